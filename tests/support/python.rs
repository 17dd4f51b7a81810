//! Running Python + h5py from the integration tests (the independent reader of our HDF5 files).

use std::path::Path;
use std::process::Command;

/// What to do when python3 or h5py is missing.
pub const INSTALL_HINT: &str = "pip install -r tools/requirements.txt";

/// Runs `python3 -c SCRIPT ARGS...` from the crate root and returns its stdout. Panics with a
/// message naming `pip install -r tools/requirements.txt` when python3 or h5py/numpy is missing,
/// and with the script's stderr when it fails.
pub fn run_python(script: &str, args: &[&Path]) -> String {
    let root = env!("CARGO_MANIFEST_DIR");
    let probe = Command::new("python3")
        .args(["-c", "import h5py, numpy"])
        .output()
        .unwrap_or_else(|e| {
            panic!("python3 is needed for this test ({e}); install Python 3, then {INSTALL_HINT}")
        });
    assert!(
        probe.status.success(),
        "python3 cannot import h5py/numpy ({}); run: {INSTALL_HINT}",
        String::from_utf8_lossy(&probe.stderr).trim()
    );
    let output = Command::new("python3")
        .current_dir(root)
        .arg("-c")
        .arg(script)
        .args(args)
        .output()
        .expect("python3 ran a moment ago");
    assert!(
        output.status.success(),
        "python script failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    String::from_utf8(output.stdout).expect("utf-8 output")
}
