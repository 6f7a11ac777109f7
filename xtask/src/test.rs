//! `cargo xtask test`: every test of the project in one command — the Rust workspace's, the glTF files
//! checked by the Khronos validator, and the Python package's (pytest, a local Ray cluster among them).
//! What a fresh machine lacks beyond the Rust toolchain, Python 3 and Node.js it installs under
//! `target/` (the validator from npm, a virtual environment with the package and its test
//! dependencies from PyPI), so that nothing outside the checkout changes.

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
