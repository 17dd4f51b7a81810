//! Running the `nlrom` binary from the integration tests.

use std::path::{Path, PathBuf};
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

/// `nlrom COMMAND CASE -o OUT --json -q EXTRA...` (`solve`, `run` or `march`): asserts exit
/// status 0, returns the JSON report.
pub fn json_report(command: &str, case: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        command,
        case.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--json",
        "-q",
    ];
    args.extend_from_slice(extra);
    let o = nlrom(&args);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    serde_json::from_slice(&o.stdout).expect("one JSON object on stdout")
}
