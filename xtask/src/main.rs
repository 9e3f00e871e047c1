//! `cargo xtask`: the thin launcher of the ARAS-Diamond toolkit.
//!
//! It has no dependencies and no mathematics. It makes sure the system
//! libraries the SDP solver links against are present (clarabel's PSD cones
//! call LAPACK; we link Debian's OpenBLAS, see `docs/blas.md`), and then
//! builds and runs the real tools in release mode:
//!
//! * `cargo xtask test [ARGS…]`: the whole test suite (`cargo test --workspace --release`).
//! * `cargo xtask deps`: only the system-library check and install.
//! * `cargo xtask check-mjcf [--reuse-venv] [--no-build] [ARGS…]`: verifies the MJCF
//!   export in MuJoCo itself (`docs/mjcf.md`): builds `aras` (`--no-build`: use the
//!   `target/release/aras` a test run left), creates a throwaway Python environment
//!   with `mujoco` and `numpy` from PyPI in `target/check-mjcf/venv` (`--reuse-venv`:
//!   keep an existing one) and runs `scripts/check_mjcf.py` (ARGS go to the script,
//!   e.g. `--params P.json`).
//! * `cargo xtask check-urdf [--reuse-venv]`: cross-checks `aras-urdf` against Pinocchio
//!   and its MJCF export in MuJoCo (`docs/urdf.md`): builds its `urdf_torques` example,
//!   creates a throwaway environment with `pin`, `example-robot-data`, `mujoco` and `numpy`
//!   in `target/check-urdf/venv` and runs `scripts/check_urdf.py`.
//! * `cargo xtask <command> [ARGS…]`: every other command (`pipeline`, `excite`,
//!   `simulate`, `identify`, `validate`, `predict`, `diagnose`, `friction`, `--help`) is
//!   passed to the `aras` binary of the `aras-cli` package (`export-mjcf` too).
//!
//! When a library is missing it says which, why, and the exact command that
//! installs it. It runs that command itself only with `apt-get` (the one
//! package manager it recognises), as root, and unless declined with
//! `--no-install` (before the command: `cargo xtask --no-install test`) or
//! `ARAS_NO_INSTALL=1`; at a terminal it asks first. The package manager's
//! own output is shown (on stderr, so a command's stdout stays clean).

use std::io::{IsTerminal, Write};
use std::path::{Path, PathBuf};
use std::process::{Command, ExitCode, Stdio};

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

/// Whether `apt-get` is there to run (Debian and its derivatives).
fn has_apt_get() -> bool {
    Command::new("apt-get")
        .arg("--version")
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success())
}

/// How the user chose to handle a missing library.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Install {
    /// Install with apt-get when possible (the default).
    Allowed,
    /// `--no-install` or `ARAS_NO_INSTALL=1`: never run a package manager.
    Declined,
}

/// `ARAS_NO_INSTALL` set to anything but empty, `0` or `false` declines.
fn declined_by_env() -> bool {
    std::env::var("ARAS_NO_INSTALL")
        .map(|v| !matches!(v.trim(), "" | "0" | "false"))
        .unwrap_or(false)
}

/// At a terminal, asks before installing; elsewhere (CI) proceeds.
fn confirmed() -> bool {
    if !std::io::stdin().is_terminal() {
        return true;
    }
    eprint!("xtask: install them now? [Y/n] ");
    let _ = std::io::stderr().flush();
    let mut answer = String::new();
    if std::io::stdin().read_line(&mut answer).is_err() {
        return false;
    }
    matches!(answer.trim().to_lowercase().as_str(), "" | "y" | "yes")
}

/// Runs apt-get with `args`, its output on our stderr.
fn apt_get(args: &[&str]) -> bool {
    eprintln!("xtask: running: apt-get {}", args.join(" "));
    Command::new("apt-get")
        .args(args)
        .env("DEBIAN_FRONTEND", "noninteractive")
        .stdout(Stdio::from(std::io::stderr()))
        .status()
        .is_ok_and(|s| s.success())
}

/// What to do about missing libraries.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Plan {
    /// Run apt-get (as root, not declined).
    AptGet,
    /// Print the command for the user, with the reason.
    ByHand(&'static str),
}

/// Installs only when allowed, with apt-get, as root; otherwise the user
/// gets the command.
fn plan(install: Install, apt_get: bool, root: bool) -> Plan {
    if install == Install::Declined {
        Plan::ByHand("not installing (--no-install or ARAS_NO_INSTALL is set)")
    } else if !apt_get {
        Plan::ByHand("apt-get is not available here, and no other package manager is run")
    } else if !root {
        Plan::ByHand("installing needs root")
    } else {
        Plan::AptGet
    }
}

fn ensure_system_libraries(install: Install) -> Result<(), String> {
    let missing: Vec<(&str, String)> = required_libraries()
        .into_iter()
        .filter(|(lib, _)| !linker_finds(lib))
        .collect();
    if missing.is_empty() {
        return Ok(());
    }
    let packages: Vec<&str> = missing.iter().map(|(_, p)| p.as_str()).collect();
    let libs: Vec<String> = missing
        .iter()
        .map(|(lib, pkg)| format!("{lib} (Debian package {pkg})"))
        .collect();
    let command = format!(
        "apt-get update && apt-get install -y --no-install-recommends {}",
        packages.join(" ")
    );
    eprintln!(
        "xtask: the linker cannot find {}.\n\
         xtask: why: the physically consistent identification is a semidefinite program; its \
         solver (clarabel) calls LAPACK for the PSD cones, and this workspace links the \
         system's OpenBLAS and the gfortran runtime it needs (docs/blas.md).",
        libs.join(" and ")
    );
    let by_hand = |why: &str| {
        format!(
            "{why}. Install the packages, then run this command again:\n    \
             sudo sh -c '{command}'\n\
             (other systems: install OpenBLAS with LAPACK and the gfortran runtime with your \
             package manager; docs/blas.md)"
        )
    };
    match plan(install, has_apt_get(), is_root()) {
        Plan::ByHand(why) => return Err(by_hand(why)),
        Plan::AptGet => {}
    }
    eprintln!(
        "xtask: will run `{command}` (decline with `cargo xtask --no-install …` or ARAS_NO_INSTALL=1)"
    );
    if !confirmed() {
        return Err(by_hand("not installing (declined)"));
    }
    let ok = apt_get(&["update"]) && {
        let mut args = vec!["install", "-y", "--no-install-recommends"];
        args.extend(&packages);
        apt_get(&args)
    };
    if !ok
        || required_libraries()
            .iter()
            .any(|(lib, _)| !linker_finds(lib))
    {
        return Err(format!(
            "installing the system packages failed (apt-get's output is above); run by hand:\n    {command}"
        ));
    }
    eprintln!("xtask: installed {}", packages.join(", "));
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
    let mut args: Vec<String> = std::env::args().skip(1).collect();
    // The launcher's own option comes before the command.
    let mut install = if declined_by_env() {
        Install::Declined
    } else {
        Install::Allowed
    };
    while args.first().map(String::as_str) == Some("--no-install") {
        install = Install::Declined;
        args.remove(0);
    }
    let Some(first) = args.first().map(String::as_str) else {
        eprintln!(
            "usage: cargo xtask [--no-install] <pipeline|excite|simulate|identify|validate|predict|diagnose|friction|export-mjcf|check-mjcf|check-urdf|test|deps> [ARGS…]\n\
             `cargo xtask --help` lists the commands of the toolkit; --no-install (or\n\
             ARAS_NO_INSTALL=1) never installs missing system libraries, it prints the command."
        );
        return ExitCode::FAILURE;
    };
    if let Err(msg) = ensure_system_libraries(install) {
        eprintln!("xtask: {msg}");
        return ExitCode::FAILURE;
    }
    match first {
        "deps" => ExitCode::SUCCESS,
        "check-mjcf" => check_mjcf(&args[1..]),
        "check-urdf" => check_urdf(&args[1..]),
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

/// Marker file: the venv (or scratch) directory was made by this command,
/// so it may remove it again.
const VENV_MARKER: &str = ".made-by-cargo-xtask-check-mjcf";

/// Removes `dir` if it exists and holds [`VENV_MARKER`] (this command made
/// it); a directory without the marker is never touched.
fn remove_own_dir(dir: &Path) -> Result<(), String> {
    if !dir.exists() {
        return Ok(());
    }
    if !dir.join(VENV_MARKER).exists() {
        return Err(format!(
            "{} exists but was not made by check-mjcf; remove it or move it away",
            dir.display()
        ));
    }
    std::fs::remove_dir_all(dir)
        .map_err(|e| format!("cannot remove the old {}: {e}", dir.display()))
}

/// The workspace this run belongs to, found at run time (a copied or moved
/// checkout runs its own tree): the parent of `manifest_dir` (the
/// `CARGO_MANIFEST_DIR` cargo sets for `cargo run`, the xtask package) when
/// it holds a workspace manifest, else the nearest directory at or above
/// `start` whose `Cargo.toml` declares `[workspace]`.
fn workspace_root(manifest_dir: Option<&Path>, start: &Path) -> Option<PathBuf> {
    let is_workspace = |d: &Path| {
        std::fs::read_to_string(d.join("Cargo.toml"))
            .is_ok_and(|t| t.lines().any(|l| l.trim() == "[workspace]"))
    };
    if let Some(parent) = manifest_dir.and_then(Path::parent)
        && is_workspace(parent)
    {
        return Some(parent.to_path_buf());
    }
    start
        .ancestors()
        .find(|d| is_workspace(d))
        .map(Path::to_path_buf)
}

/// `cargo xtask check-mjcf`: build `aras`, make the throwaway venv, run the script.
fn check_mjcf(args: &[String]) -> ExitCode {
    let here = std::env::current_dir().unwrap_or_else(|_| ".".into());
    let manifest = std::env::var_os("CARGO_MANIFEST_DIR").map(PathBuf::from);
    let Some(root) = workspace_root(manifest.as_deref(), &here) else {
        eprintln!(
            "xtask: no Cargo workspace above {}; run `cargo xtask check-mjcf` inside the checkout",
            here.display()
        );
        return ExitCode::FAILURE;
    };
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(std::path::PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let base = target.join("check-mjcf");
    let venv = base.join("venv");
    let reuse = args.iter().any(|a| a == "--reuse-venv");
    let no_build = args.iter().any(|a| a == "--no-build");
    let script_args: Vec<&String> = args
        .iter()
        .filter(|a| *a != "--reuse-venv" && *a != "--no-build")
        .collect();
    let aras = target.join("release").join("aras");

    if no_build {
        if !aras.is_file() {
            eprintln!(
                "xtask: --no-build, but {} does not exist; build it (cargo build --release -p aras-cli) or drop --no-build",
                aras.display()
            );
            return ExitCode::FAILURE;
        }
    } else if run({
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
        build
    }) != ExitCode::SUCCESS
    {
        return ExitCode::FAILURE;
    }
    let python = venv.join("bin").join("python");
    if !(reuse && python.exists()) {
        if let Err(msg) = remove_own_dir(&venv) {
            eprintln!("xtask: {msg}");
            return ExitCode::FAILURE;
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
    // A fresh scratch directory each run (only one this command made is removed).
    let work = base.join("work");
    if let Err(msg) = remove_own_dir(&work) {
        eprintln!("xtask: {msg}");
        return ExitCode::FAILURE;
    }
    if let Err(e) =
        std::fs::create_dir_all(&work).and_then(|()| std::fs::write(work.join(VENV_MARKER), b""))
    {
        eprintln!("xtask: cannot create {}: {e}", work.display());
        return ExitCode::FAILURE;
    }
    let mut check = Command::new(&python);
    check
        .arg(root.join("scripts").join("check_mjcf.py"))
        .arg("--aras")
        .arg(&aras)
        .arg("--work")
        .arg(&work)
        .arg("--identified")
        .args(script_args);
    run(check)
}

/// Python packages of the URDF check, pinned so that every machine checks
/// against the same Pinocchio (update together).
const CHECK_URDF_PACKAGES: [&str; 4] = [
    "pin==4.1.0",
    "example-robot-data==6.0.0",
    "mujoco==4.0.0",
    "numpy==2.4.6",
];

/// `cargo xtask check-urdf`: build the example, make the throwaway venv, run the script.
fn check_urdf(args: &[String]) -> ExitCode {
    let here = std::env::current_dir().unwrap_or_else(|_| ".".into());
    let manifest = std::env::var_os("CARGO_MANIFEST_DIR").map(PathBuf::from);
    let Some(root) = workspace_root(manifest.as_deref(), &here) else {
        eprintln!(
            "xtask: no Cargo workspace above {}; run `cargo xtask check-urdf` inside the checkout",
            here.display()
        );
        return ExitCode::FAILURE;
    };
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| root.join("target"));
    let base = target.join("check-urdf");
    let venv = base.join("venv");
    let reuse = args.iter().any(|a| a == "--reuse-venv");
    let mut build = cargo();
    build.args([
        "build",
        "--quiet",
        "--release",
        "--package",
        "aras-urdf",
        "--example",
        "urdf_torques",
    ]);
    if run(build) != ExitCode::SUCCESS {
        return ExitCode::FAILURE;
    }
    let python = venv.join("bin").join("python");
    if !(reuse && python.exists()) {
        if let Err(msg) = remove_own_dir(&venv) {
            eprintln!("xtask: {msg}");
            return ExitCode::FAILURE;
        }
        eprintln!(
            "xtask: creating {} with {}…",
            venv.display(),
            CHECK_URDF_PACKAGES.join(", ")
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
        .args(CHECK_URDF_PACKAGES);
        if run(pip) != ExitCode::SUCCESS {
            eprintln!(
                "xtask: installing {} from PyPI failed",
                CHECK_URDF_PACKAGES.join(" ")
            );
            return ExitCode::FAILURE;
        }
    }
    let work = base.join("work");
    if let Err(msg) = remove_own_dir(&work) {
        eprintln!("xtask: {msg}");
        return ExitCode::FAILURE;
    }
    if let Err(e) =
        std::fs::create_dir_all(&work).and_then(|()| std::fs::write(work.join(VENV_MARKER), b""))
    {
        eprintln!("xtask: cannot create {}: {e}", work.display());
        return ExitCode::FAILURE;
    }
    let mut check = Command::new(&python);
    check
        .arg(root.join("scripts").join("check_urdf.py"))
        .arg("--ours")
        .arg(target.join("release").join("examples").join("urdf_torques"))
        .arg("--work")
        .arg(&work);
    run(check)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A checkout copied elsewhere is located where it now is: from the
    /// run-time manifest directory or by walking up from the current one.
    #[test]
    fn workspace_is_located_at_run_time() {
        let tmp = std::env::temp_dir().join(format!("xtask-root-{}", std::process::id()));
        let copy = tmp.join("copy");
        let sub = copy.join("crates").join("x");
        std::fs::create_dir_all(copy.join("xtask")).unwrap();
        std::fs::create_dir_all(&sub).unwrap();
        std::fs::write(copy.join("Cargo.toml"), "[workspace]\nmembers = []\n").unwrap();
        std::fs::write(sub.join("Cargo.toml"), "[package]\nname = \"x\"\n").unwrap();
        let xtask = copy.join("xtask");
        assert_eq!(
            workspace_root(Some(&xtask), Path::new("/")),
            Some(copy.clone())
        );
        assert_eq!(workspace_root(None, &sub), Some(copy.clone()));
        // A manifest directory outside any workspace falls back to the walk.
        assert_eq!(workspace_root(Some(&sub), &sub), Some(copy.clone()));
        assert_eq!(workspace_root(None, &tmp), None);
        std::fs::remove_dir_all(&tmp).unwrap();
    }

    #[test]
    fn installs_only_with_apt_get_as_root_when_not_declined() {
        assert_eq!(plan(Install::Allowed, true, true), Plan::AptGet);
        for (install, apt, root) in [
            (Install::Declined, true, true),
            (Install::Allowed, false, true),
            (Install::Allowed, true, false),
            (Install::Declined, false, false),
        ] {
            assert!(
                matches!(plan(install, apt, root), Plan::ByHand(_)),
                "{install:?} apt-get={apt} root={root}"
            );
        }
    }
}
