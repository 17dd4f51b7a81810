//! `nlrom demo [--out DIR]`: the bundled demo case (`cases/demo.toml`) end to end — reduction
//! (cached in `DIR/demo.rom.h5`), contact pairs, harmonic balance with continuation — written to
//! `DIR/demo.h5`, then `python3 tools/post/plot_frf.py DIR/demo.h5 --out DIR` (the FRF) and
//! `python3 tools/post/plot_contact.py DIR/demo.h5 --out DIR` (hysteresis loops and the shroud's
//! contact-state map at the resonance) when python3 and the scripts exist (skipped with a note
//! otherwise); prints where the results and plots are.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use super::progress::Reporter;
use super::solve::{solve_to_file, SolveOptions};
use super::{outcome_json, outcome_text};
use crate::case::Case;
use crate::error::{Error, Result};
use crate::problem::rom_store::RomPolicy;

/// The demo case, relative to the crate root.
pub const DEMO_CASE: &str = "cases/demo.toml";
/// The plotting scripts, relative to the crate root, each run as `python3 SCRIPT RESULT --out DIR`.
pub const PLOT_SCRIPTS: [&str; 2] = ["tools/post/plot_frf.py", "tools/post/plot_contact.py"];

/// The crate root (where `cases/` and `tools/` are): the current directory when it holds the
/// demo case (a clone run with `cargo run`), else the directory the binary was built from.
pub fn crate_root() -> PathBuf {
    if Path::new(DEMO_CASE).is_file() {
        PathBuf::new()
    } else {
        PathBuf::from(env!("CARGO_MANIFEST_DIR"))
    }
}

/// What happened to the plots.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Plots {
    /// The script ran and wrote its PNG files into the directory.
    Written(PathBuf),
    /// Not made; the note says why.
    Skipped(String),
}

/// Runs the demo into `out`.
pub fn demo_command(out: &Path, rep: &Reporter, as_json: bool) -> Result<()> {
    let start = Instant::now();
    let root = crate_root();
    let case_path = root.join(DEMO_CASE);
    if !case_path.is_file() {
        return Err(Error::input(format!(
            "{}: the demo case is missing; run `nlrom demo` from the nlrom source tree",
            case_path.display()
        )));
    }
    let case = Case::load(&case_path)?;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let output = out.join("demo.h5");
    let opts = SolveOptions::new(RomPolicy::Cache(out.join("demo.rom.h5")));
    rep.info(&format!(
        "demo case: {} ({})",
        case.title,
        case_path.display()
    ));
    let outcome = solve_to_file(&case, &output, &opts, rep)?;
    let plots = PLOT_SCRIPTS
        .iter()
        .map(|script| plot(&root.join(script), &output, out, rep))
        .find(|p| matches!(p, Plots::Skipped(_)))
        .unwrap_or_else(|| Plots::Written(out.to_path_buf()));
    if as_json {
        let mut report = outcome_json(&outcome, &output, start);
        report["plots"] = match &plots {
            Plots::Written(d) => serde_json::json!({"dir": d.display().to_string()}),
            Plots::Skipped(note) => serde_json::json!({"skipped": note}),
        };
        println!("{report}");
    } else {
        print!("{}", outcome_text(&case_path, &outcome, &output));
        println!("results: {}", output.display());
        match &plots {
            Plots::Written(d) => println!("plots:   {}", d.display()),
            Plots::Skipped(note) => println!("plots:   not made ({note})"),
        }
        println!(
            "read it in Python: python3 tools/post/nlrom_results.py {}",
            output.display()
        );
    }
    let failures = outcome.failures();
    if failures.is_empty() {
        Ok(())
    } else {
        Err(Error::Compute(format!(
            "demo: {}; the converged points are in {}",
            failures.join("; "),
            output.display()
        )))
    }
}

/// Runs `python3 SCRIPT RESULT --out DIR` when the script exists and python3 runs; the script's
/// output goes to stderr (stdout carries the demo's report, JSON with `--json`).
fn plot(script: &Path, result: &Path, dir: &Path, rep: &Reporter) -> Plots {
    if !script.is_file() {
        return Plots::Skipped(format!("{} is not there", script.display()));
    }
    let status = Command::new("python3")
        .arg(script)
        .arg(result)
        .arg("--out")
        .arg(dir)
        .stdout(std::process::Stdio::from(std::io::stderr()))
        .status();
    match status {
        Ok(s) if s.success() => Plots::Written(dir.to_path_buf()),
        Ok(s) => {
            rep.warn(&format!("{} exited with {s}", script.display()));
            Plots::Skipped(format!("{} failed ({s})", script.display()))
        }
        Err(e) => Plots::Skipped(format!("python3 could not be started: {e}")),
    }
}
