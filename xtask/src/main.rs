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
//! * `cargo xtask check-mjcf [--reuse-venv] [ARGS…]`: verifies the MJCF export in
//!   MuJoCo itself (`docs/mjcf.md`): builds `aras`, creates a throwaway Python
//!   environment with `mujoco` and `numpy` from PyPI in `target/check-mjcf/venv`
//!   and runs `scripts/check_mjcf.py` (ARGS go to the script, e.g. `--params P.json`).
//! * `cargo xtask <command> [ARGS…]`: every other command (`pipeline`, `excite`,
//!   `simulate`, `identify`, `validate`, `predict`, `diagnose`, `--help`) is
//!   passed to the `aras` binary of the `aras-cli` package (`export-mjcf` too).

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
            "usage: cargo xtask <pipeline|excite|simulate|identify|validate|predict|diagnose|export-mjcf|check-mjcf|test|deps> [ARGS…]\n\
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
        "check-mjcf" => check_mjcf(&args[1..]),
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

/// Python packages of the MuJoCo check, pinned so that every machine checks
/// against the same MuJoCo (update both together).
const CHECK_MJCF_PACKAGES: [&str; 2] = ["mujoco==4.0.0", "numpy==2.4.6"];

/// Marker file: the venv directory was made by this command, so it may
/// remove it again.
const VENV_MARKER: &str = ".made-by-cargo-xtask-check-mjcf";

/// `cargo xtask check-mjcf`: build `aras`, make the throwaway venv, run the script.
fn check_mjcf(args: &[String]) -> ExitCode {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("xtask lives inside the workspace")
        .to_path_buf();
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let base = target.join("check-mjcf");
    let venv = base.join("venv");
    let reuse = args.iter().any(|a| a == "--reuse-venv");
    let script_args: Vec<&String> = args.iter().filter(|a| *a != "--reuse-venv").collect();

    let mut build = cargo();
    build.args([
        "build",
        "--quiet",
        "--release",
        "--package",
        "aras-cli",
        "--bin",
        "aras",
    ]);
    if run(build) != ExitCode::SUCCESS {
        return ExitCode::FAILURE;
    }
    let python = venv.join("bin").join("python");
    if !(reuse && python.exists()) {
        if venv.exists() {
            if !venv.join(VENV_MARKER).exists() {
                eprintln!(
                    "xtask: {} exists but was not made by check-mjcf; remove it or move it away",
                    venv.display()
                );
                return ExitCode::FAILURE;
            }
            if let Err(e) = std::fs::remove_dir_all(&venv) {
                eprintln!("xtask: cannot remove the old {}: {e}", venv.display());
                return ExitCode::FAILURE;
            }
        }
        eprintln!(
            "xtask: creating {} with {}…",
            venv.display(),
            CHECK_MJCF_PACKAGES.join(", ")
        );
        let mut mk = Command::new("python3");
        mk.args(["-m", "venv"]).arg(&venv);
        if run(mk) != ExitCode::SUCCESS {
            eprintln!("xtask: `python3 -m venv` failed; install python3 and python3-venv");
            return ExitCode::FAILURE;
        }
        if let Err(e) = std::fs::write(venv.join(VENV_MARKER), b"") {
            eprintln!("xtask: cannot write into {}: {e}", venv.display());
            return ExitCode::FAILURE;
        }
        let mut pip = Command::new(&python);
        pip.args([
            "-m",
            "pip",
            "install",
            "--quiet",
            "--disable-pip-version-check",
        ])
        .args(CHECK_MJCF_PACKAGES);
        if run(pip) != ExitCode::SUCCESS {
            eprintln!(
                "xtask: installing {} from PyPI failed",
                CHECK_MJCF_PACKAGES.join(" ")
            );
            return ExitCode::FAILURE;
        }
    }
    let work = base.join("work");
    if let Err(e) = std::fs::create_dir_all(&work) {
        eprintln!("xtask: cannot create {}: {e}", work.display());
        return ExitCode::FAILURE;
    }
    let mut check = Command::new(&python);
    check
        .arg(root.join("scripts").join("check_mjcf.py"))
        .arg("--aras")
        .arg(target.join("release").join("aras"))
        .arg("--work")
        .arg(&work)
        .arg("--identified")
        .args(script_args);
    run(check)
}
