//! Small matrix cases for the `nlrom batch` tests and the numbers of a `summary.csv`.

use std::path::{Path, PathBuf};

use super::cli::root;

/// `cases/chain3_jenkins.toml` written to `DIR/<name>.toml`: its matrices read from the
/// repository, element 1's slip force `n0`, then each `(from, to)` text replacement applied
/// (e.g. `("harmonics = 7", "harmonics = 3")`).
pub fn chain_case(dir: &Path, name: &str, n0: f64, replacements: &[(&str, &str)]) -> PathBuf {
    let mut text = std::fs::read_to_string(root().join("cases/chain3_jenkins.toml"))
        .unwrap()
        .replace(
            "\"chain3/",
            &format!("\"{}/cases/chain3/", root().display()),
        )
        .replace(
            "kt = 1.0\nmu = 1.0\nn0 = 0.2\n\n[harmonic_balance]",
            &format!("kt = 1.0\nmu = 1.0\nn0 = {n0}\n\n[harmonic_balance]"),
        );
    for (from, to) in replacements {
        assert!(text.contains(from), "{from:?} is not in the chain case");
        text = text.replace(from, to);
    }
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// The rows of a batch's `summary.csv` (header excluded) as its 11 cells; no cell holds a
/// quoted comma except the message, the last column.
pub fn summary_rows(csv: &Path) -> Vec<Vec<String>> {
    let text = std::fs::read_to_string(csv).unwrap();
    let mut lines = text.lines();
    assert!(lines
        .next()
        .unwrap()
        .starts_with("case,input,sweep_point,status,resonance_hz"));
    lines
        .map(|l| l.splitn(11, ',').map(str::to_string).collect())
        .collect()
}

/// The rows of a batch's `summary.csv` without the columns that name the run (output path,
/// wall time): case, input, sweep point, status, resonance, peak amplitude, Q, points, message.
pub fn summary_numbers(csv: &Path) -> Vec<Vec<String>> {
    summary_rows(csv)
        .into_iter()
        .map(|c| {
            let mut keep = c[..8].to_vec();
            keep.push(c[10].clone());
            keep
        })
        .collect()
}
