//! The identification core is robot-agnostic: no ARAS-Diamond crate is among
//! its dependencies, and without default features it needs no system
//! library (the SDP's OpenBLAS comes with the `sdp` feature only).
//!
//! Asks `cargo tree --offline` (nothing is downloaded: the lock file and the
//! local registry cache are enough).

use std::process::Command;

/// The package names of `aras-ident`'s normal dependency tree.
fn dependencies(extra: &[&str]) -> Vec<String> {
    let manifest = concat!(env!("CARGO_MANIFEST_DIR"), "/Cargo.toml");
    let out = Command::new(env!("CARGO"))
        .args(["tree", "--offline", "--manifest-path", manifest])
        .args(["-p", "aras-ident", "-e", "normal", "--prefix", "none"])
        .args(["--format", "{p}"])
        .args(extra)
        .output()
        .expect("cargo runs");
    assert!(
        out.status.success(),
        "cargo tree failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| l.split_whitespace().next())
        .map(str::to_owned)
        .collect()
}

#[test]
fn the_core_depends_on_no_robot_crate() {
    let deps = dependencies(&[]);
    // The listing is real: it holds the crate itself, its linear algebra and
    // (default feature `sdp`) the SDP solver.
    for present in ["aras-ident", "faer", "clarabel"] {
        assert!(
            deps.iter().any(|d| d == present),
            "{present} missing: {deps:?}"
        );
    }
    for robot in [
        "aras-kin",
        "aras-dyn",
        "aras-signal",
        "aras-excite",
        "aras-pipeline",
    ] {
        assert!(
            !deps.iter().any(|d| d == robot),
            "aras-ident depends on {robot}: {deps:?}"
        );
    }
}

#[test]
fn without_default_features_no_system_library_is_linked() {
    let deps = dependencies(&["--no-default-features"]);
    assert!(deps.iter().any(|d| d == "faer"), "{deps:?}");
    for system in [
        "clarabel",
        "openblas-src",
        "openblas-build",
        "blas-src",
        "lapack-src",
    ] {
        assert!(
            !deps.iter().any(|d| d == system),
            "aras-ident --no-default-features depends on {system}: {deps:?}"
        );
    }
}
