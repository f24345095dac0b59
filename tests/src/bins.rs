//! The command-line binaries end-to-end tests run: built by cargo once per test process (a
//! no-op when up to date), so a binary left from an older checkout is never the one tested.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// target/<profile>/, where cargo puts the binaries (a test runs from target/<profile>/deps).
pub fn bin_dir() -> PathBuf {
    let exe = std::env::current_exe().expect("test executable path");
    exe.parent()
        .and_then(Path::parent)
        .expect("target/<profile>/deps/<test>")
        .to_path_buf()
}

/// Builds `bin` with `args` (packages and binaries) and returns its path.
fn built(args: &[&str], bin: &str) -> PathBuf {
    let status = Command::new(env!("CARGO"))
        .arg("build")
        .args(args)
        .current_dir(crate::repo_root())
        .status()
        .expect("run cargo build");
    assert!(status.success(), "cargo build of {bin} failed");
    bin_dir().join(bin)
}

/// The `aerie` binary.
pub fn aerie_bin() -> &'static PathBuf {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| built(&["-p", "aerie", "--bin", "aerie"], "aerie"))
}

/// The `aerie-send` binary (the test sender of the simulator bridge), built together with
/// `aerie`: cargo unifies the features of the packages of one build, so building the bridge
/// alone would compile its dependencies a second time with other features (2 minutes on 2
/// cores).
pub fn aerie_send_bin() -> &'static PathBuf {
    static BIN: OnceLock<PathBuf> = OnceLock::new();
    BIN.get_or_init(|| {
        built(
            &[
                "-p",
                "aerie",
                "--bin",
                "aerie",
                "-p",
                "aerie-sim-bridge",
                "--bin",
                "aerie-send",
            ],
            "aerie-send",
        )
    })
}
