//! What the command line's test binaries share: the binary, and a fresh temporary folder per test.

use std::path::PathBuf;
use std::process::Command;

/// The `anima` binary this package builds.
pub fn anima() -> Command {
    Command::new(env!("CARGO_BIN_EXE_anima"))
}

/// The empty folder `anima-<test binary>-<name>-<process id>` in the system's temporary folder, emptied
/// first when an earlier run left it.
pub fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "anima-{}-{name}-{}",
        env!("CARGO_CRATE_NAME"),
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}
