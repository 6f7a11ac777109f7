//! `cargo xtask test`: every test of the project in one command — the Rust workspace's, the glTF files
//! checked by the Khronos validator, `anima view` driven by headless Chromium, and the Python package's
//! (pytest, a local Ray cluster among them). What a fresh machine lacks beyond the Rust toolchain,
//! Python 3 and Node.js it installs under `target/` (the validator from npm, a virtual environment with
//! the package and its test dependencies from PyPI), so that nothing outside the checkout changes;
//! the one exception is Chromium, a system package, which it installs with apt-get when run as root
//! and otherwise asks for.

use std::path::Path;
use std::process::Command;

use anyhow::{Context, Result, bail};

/// The version of the Khronos glTF validator the tests run (npm package `gltf-validator`).
const GLTF_VALIDATOR: &str = "gltf-validator@2.0.0-dev.3.10";

/// The runnable examples of what users build (issue #38): a cloth draped on the Bunny, a sheet in a
/// game loop, a walker from the shipped files.
const USER_EXAMPLES: [&str; 3] = ["drape_bunny", "sheet_game_loop", "walker"];

/// Which parts to run; all of them unless some are named.
#[derive(Debug, Clone, Copy)]
pub struct Parts {
    pub rust: bool,
    pub gltf: bool,
    pub viewer: bool,
    pub python: bool,
}

pub fn run(root: &Path, parts: Parts) -> Result<()> {
    let cargo = std::env::var_os("CARGO").unwrap_or_else(|| "cargo".into());
    let target = std::env::var_os("CARGO_TARGET_DIR").map_or_else(|| root.join("target"), Into::into);
    if parts.rust {
        step("Rust: cargo test --workspace --release");
        checked(Command::new(&cargo).args(["test", "--workspace", "--release"]).current_dir(root))?;
        // `cargo test` built every example with the workspace's features; these three, the ones a user
        // would copy, run to their end and check what they show.
        step("Examples: drape_bunny, sheet_game_loop (anima-cloth), walker (anima-run)");
        for example in USER_EXAMPLES {
            checked(Command::new(target.join("release/examples").join(example)).current_dir(root))?;
        }
    }
    if parts.gltf {
        step("glTF: every kind of file anima writes, through the Khronos validator");
        let tools = target.join("tools/gltf-validator");
        if !tools.join("node_modules/gltf-validator").is_dir() {
            std::fs::create_dir_all(&tools)?;
            checked(
                Command::new("npm")
                    .args(["install", "--no-audit", "--no-fund", "--silent", "--prefix"])
                    .arg(&tools)
                    .arg(GLTF_VALIDATOR)
                    .current_dir(root),
            )
            .context("installing the glTF validator (needs Node.js and npm)")?;
        }
        checked(
            Command::new(&cargo)
                // The workspace's own build (what the first part compiled), not `-p anima-tests`, whose
                // narrower feature set would compile the dependency tree a second time.
                .args(["test", "--workspace", "--release", "gltf", "--", "--ignored"])
                .env("ANIMA_GLTF_VALIDATOR", &tools)
                .current_dir(root),
        )?;
    }
    if parts.viewer {
        step("Viewer: anima view on a sheet, a remeshed drape and a walk, in headless Chromium");
        if chromium_ready()? {
            checked(
                Command::new(&cargo)
                    .args(["test", "--workspace", "--release", "viewer_", "--", "--ignored"])
                    .current_dir(root),
            )?;
        }
    }
    if parts.python {
        step("Python: the package built and installed into target/python, then pytest");
        let venv = target.join("python");
        let python = venv.join("bin/python");
        if !python.exists() {
            checked(Command::new("python3").args(["-m", "venv"]).arg(&venv))
                .context("making a virtual environment (needs Python 3.9 or newer with venv)")?;
        }
        // A local folder is always rebuilt and reinstalled; the test dependencies only when missing.
        checked(
            Command::new(&python)
                .args(["-m", "pip", "install", "--quiet", "--disable-pip-version-check", "./python[test]"])
                .env("CARGO_TARGET_DIR", &target)
                .current_dir(root),
        )
        .context("installing the Python package")?;
        checked(Command::new(&python).args(["-m", "pytest", "-q", "python/tests"]).current_dir(root))?;
    }
    println!("\nall tests passed");
    Ok(())
}

/// Whether Chromium can run (`ANIMA_CHROMIUM`, or Debian's `chromium`), installing the Debian package
/// when it is missing and this runs as root with apt-get. Without apt-get the viewer's tests are
/// skipped with a message; as another user, the message says what to install.
fn chromium_ready() -> Result<bool> {
    let program = std::env::var("ANIMA_CHROMIUM").unwrap_or_else(|_| "chromium".to_owned());
    let runs = |p: &str| Command::new(p).arg("--version").output().is_ok_and(|o| o.status.success());
    if runs(&program) {
        return Ok(true);
    }
    if !Command::new("apt-get").arg("--version").output().is_ok_and(|o| o.status.success()) {
        println!(
            "SKIPPED: no {program} and no apt-get to install it; set ANIMA_CHROMIUM to a Chromium binary"
        );
        return Ok(false);
    }
    let root = Command::new("id").arg("-u").output().is_ok_and(|o| o.stdout.starts_with(b"0\n"));
    if !root {
        bail!("the viewer's tests need Chromium: `sudo apt-get install chromium` (or set ANIMA_CHROMIUM)");
    }
    // The package lists may be empty on a fresh image.
    checked(Command::new("apt-get").args(["update", "-qq"]))?;
    checked(
        Command::new("apt-get")
            .args(["install", "-y", "-qq", "chromium"])
            .env("DEBIAN_FRONTEND", "noninteractive"),
    )
    .context("installing Debian's chromium")?;
    Ok(runs(&program))
}

fn step(what: &str) {
    println!("\n== {what}");
}

fn checked(cmd: &mut Command) -> Result<()> {
    let status = cmd.status().with_context(|| format!("starting {:?}", cmd.get_program()))?;
    if !status.success() {
        bail!("{:?} failed ({status})", cmd.get_program());
    }
    Ok(())
}
