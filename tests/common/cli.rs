//! Running the `nlrom` binary from the integration tests.

use std::path::PathBuf;
use std::process::{Command, Output};

/// The crate root (where `cases/`, `meshes/` are).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Runs `nlrom ARGS` in the crate root.
pub fn nlrom(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_nlrom"))
        .args(args)
        .current_dir(root())
        .output()
        .expect("runs")
}

/// The stderr of a run as text.
pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}
