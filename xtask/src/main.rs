//! `cargo xtask`: the thin launcher of the ARAS-Diamond toolkit.
//!
//! It has no dependencies and no mathematics. It makes sure the system
//! libraries the SDP solver links against are present (clarabel's PSD cones
//! call LAPACK; we link Debian's OpenBLAS, see `docs/blas.md`), installing
//! them with `apt-get` when it runs as root, or printing the exact command
//! when it cannot, and then builds and runs the real tools in release mode:
//!
//! * `cargo xtask test [ARGS…]`: the whole test suite (`cargo test --workspace --release`).
//! * `cargo xtask deps`: only the system-library check and install.
//! * `cargo xtask <command> [ARGS…]`: every other command (`pipeline`, `excite`,
//!   `simulate`, `identify`, `validate`, `predict`, `diagnose`, `--help`) is
//!   passed to the `aras` binary of the `aras-cli` package.

use std::path::Path;
use std::process::{Command, ExitCode};

/// Shared objects the numeric crates link against, with the Debian package
/// that provides each (the gfortran one depends on the GCC major version).
fn required_libraries() -> Vec<(&'static str, String)> {
    let gcc_major = Command::new("gcc")
        .arg("-dumpversion")
        .output()
        .ok()
        .and_then(|o| String::from_utf8(o.stdout).ok())
        .and_then(|v| v.trim().split('.').next().map(str::to_owned))
        .unwrap_or_else(|| "12".to_owned());
    vec![
        ("libopenblas.so", "libopenblas-dev".to_owned()),
        ("libgfortran.so", format!("libgfortran-{gcc_major}-dev")),
    ]
}

/// Whether the linker can find `lib` (asks the C compiler, which knows the
/// same search path the Rust linker driver uses).
fn linker_finds(lib: &str) -> bool {
    Command::new("gcc")
        .arg(format!("-print-file-name={lib}"))
        .output()
        .ok()
        .map(|o| {
            let p = String::from_utf8_lossy(&o.stdout).trim().to_owned();
            Path::new(&p).is_absolute() && Path::new(&p).exists()
        })
        .unwrap_or(false)
}

fn is_root() -> bool {
    Command::new("id")
        .arg("-u")
        .output()
        .map(|o| String::from_utf8_lossy(&o.stdout).trim() == "0")
        .unwrap_or(false)
}

fn ensure_system_libraries() -> Result<(), String> {
    let missing: Vec<String> = required_libraries()
        .into_iter()
        .filter(|(lib, _)| !linker_finds(lib))
        .map(|(_, pkg)| pkg)
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    let install = format!(
        "apt-get update && apt-get install -y --no-install-recommends {}",
        missing.join(" ")
    );
    if !is_root() || Command::new("apt-get").arg("--version").output().is_err() {
        return Err(format!(
            "the SDP solver needs system packages that are missing: {}.\n\
             Install them, then run this command again:\n    sudo sh -c '{install}'",
            missing.join(", ")
        ));
    }
    eprintln!(
        "xtask: installing {} (needed by the SDP solver)…",
        missing.join(", ")
    );
    let ok = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "DEBIAN_FRONTEND=noninteractive {install} >/dev/null"
        ))
        .status()
        .map(|s| s.success())
        .unwrap_or(false);
    if !ok
        || required_libraries()
            .iter()
            .any(|(lib, _)| !linker_finds(lib))
    {
        return Err(format!(
            "installing the system packages failed; run by hand:\n    {install}"
        ));
    }
    Ok(())
}

fn cargo() -> Command {
    Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_owned()))
}

fn run(mut cmd: Command) -> ExitCode {
    match cmd.status() {
        Ok(s) if s.success() => ExitCode::SUCCESS,
        Ok(s) => ExitCode::from(s.code().unwrap_or(1).clamp(1, 255) as u8),
        Err(e) => {
            eprintln!("xtask: could not start cargo: {e}");
            ExitCode::FAILURE
        }
    }
}

fn main() -> ExitCode {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let Some(first) = args.first().map(String::as_str) else {
        eprintln!(
            "usage: cargo xtask <pipeline|excite|simulate|identify|validate|predict|diagnose|test|deps> [ARGS…]\n\
             `cargo xtask --help` lists the commands of the toolkit."
        );
        return ExitCode::FAILURE;
    };
    if let Err(msg) = ensure_system_libraries() {
        eprintln!("xtask: {msg}");
        return ExitCode::FAILURE;
    }
    match first {
        "deps" => ExitCode::SUCCESS,
        "test" => {
            let mut cmd = cargo();
            cmd.args(["test", "--workspace", "--release"])
                .args(&args[1..]);
            run(cmd)
        }
        _ => {
            let mut cmd = cargo();
            cmd.args([
                "run",
                "--quiet",
                "--release",
                "--package",
                "aras-cli",
                "--bin",
                "aras",
                "--",
            ])
            .args(&args);
            run(cmd)
        }
    }
}
