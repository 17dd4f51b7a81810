//! The commands of the command line (`docs/user-guide.md`), one module each, all reporting
//! through one [`Reporter`] (`--quiet`, `-v`) and printing one JSON object with `--json`:
//!
//! * [`mesh_info`]: `nlrom mesh info`, a mesh's summary;
//! * [`modes`]: `nlrom modes`, natural frequencies at a stage of the reduction;
//! * [`export`]: `nlrom export`, K, M and the DOF map as files;
//! * [`reduce`]: `nlrom reduce`, the ROM file of a mesh case;
//! * [`contact`]: `nlrom contact`, the contact pairs of a case;
//! * [`march`]: `nlrom march`, time marching and the `/march/` results;
//! * [`solve`]: `nlrom solve` and `run`, one case end to end — the ROM (read when its key
//!   matches, else reduced), the contact pairs, the harmonic balance problem and the frequency
//!   response of every sweep point (in parallel), gathered into a results file; [`RomPolicy`]
//!   says whether the ROM is cached in a file (`run`) or only read (`solve`).
//! * [`summary`]: resonance frequency, peak amplitude and half-power Q-factor of a curve.
//! * [`batch`]: `nlrom batch`, many cases (or many meshes with one template case) in a rayon
//!   pool of `--jobs` threads, one results file each and a summary table (`summary.csv`); shards,
//!   the Slurm job array (`--slurm`), `batch merge`, `--resume` and the shared ROM cache.
//! * [`demo`]: `nlrom demo`, the bundled demo case end to end, then the plots.
//! * [`law`]: `nlrom law`, one friction contact point under a prescribed harmonic motion.
//! * [`progress`]: log lines (`--quiet`, `-v`) and indicatif progress bars on stderr.
//!
//! Exit status (`crate::error::Error::exit_code`): 0 success, 1 a failed computation (a
//! continuation that did not converge: its converged points are written first), 2 bad input.

pub mod batch;
pub mod contact;
pub mod demo;
pub mod export;
pub mod law;
pub mod march;
pub mod mesh_info;
pub mod modes;
pub mod nonsmooth;
pub mod progress;
pub mod reduce;
pub mod solve;
pub mod summary;

use std::path::Path;
use std::time::Instant;

use serde_json::{json, Value};

pub use crate::problem::rom_store::{RomOrigin, RomPolicy};
pub use contact::contact_command;
pub use demo::demo_command;
pub use export::export_command;
pub use march::march_command;
pub use mesh_info::mesh_info_command;
pub use modes::modes_command;
pub use progress::Reporter;
pub use reduce::reduce_command;
pub use solve::{
    default_output, default_rom_file, solve_case, solve_to_file, CurveReport, SolveOptions,
    SolveOutcome,
};
pub use summary::{summarize, CurveSummary};

use crate::case::{Case, CaseKind};
use crate::error::{Error, Result};

/// `nlrom solve` (`cache_rom = false`) and `nlrom run` (`cache_rom = true`, the ROM is kept in
/// [`default_rom_file`] and reused while its key matches): solves the case (with the `stable`
/// flag of every point when `stability`), writes the results file and prints the summary (text
/// or `--json`). A failed curve makes the command fail (exit
/// status 1) after the file with its converged points is written.
pub fn solve_command(
    case_path: &Path,
    output: Option<&Path>,
    cache_rom: bool,
    stability: bool,
    rep: &Reporter,
    as_json: bool,
) -> Result<()> {
    let start = Instant::now();
    let case = Case::load(case_path)?;
    let output = default_output(&case, output);
    let policy = if cache_rom && case.kind() != CaseKind::Matrix {
        RomPolicy::Cache(default_rom_file(&case, &output))
    } else {
        RomPolicy::ReadIfMatching
    };
    let opts = SolveOptions {
        rom: policy,
        stability,
    };
    let outcome = solve_to_file(&case, &output, &opts, rep)?;
    if as_json {
        println!("{}", outcome_json(&outcome, &output, start));
    } else {
        print!("{}", outcome_text(case_path, &outcome, &output));
    }
    let failures = outcome.failures();
    if failures.is_empty() {
        Ok(())
    } else {
        Err(Error::Compute(format!(
            "{}: {}; {} holds the converged points",
            case_path.display(),
            failures.join("; "),
            output.display()
        )))
    }
}

/// The JSON report of `nlrom solve|run --json`: `frf` (one object per sweep point, see
/// [`CurveReport::json`]), `output`, `rom` (sector cases: `file`, `reused`), `wall_seconds`.
pub fn outcome_json(outcome: &SolveOutcome, output: &Path, start: Instant) -> Value {
    let rom = outcome.rom.as_ref().map(|o| match o {
        RomOrigin::Reused(p) => json!({"file": p.display().to_string(), "reused": true}),
        RomOrigin::Raced(p) => {
            json!({"file": p.display().to_string(), "reused": false, "raced": true})
        }
        RomOrigin::Reduced(p) => {
            json!({"file": p.as_ref().map(|p| p.display().to_string()), "reused": false})
        }
    });
    json!({
        "frf": outcome.curves.iter().map(CurveReport::json).collect::<Vec<_>>(),
        "output": output.display().to_string(),
        "rom": rom,
        "wall_seconds": start.elapsed().as_secs_f64(),
    })
}

/// The text report: one line per curve.
pub fn outcome_text(case_path: &Path, outcome: &SolveOutcome, output: &Path) -> String {
    let mut s = format!(
        "frequency response of {} written to {}\n",
        case_path.display(),
        output.display()
    );
    s += &format!(
        "{:>5} {:<28} {:>7} {:>15} {:>15} {:>9}  {}\n",
        "sweep", "parameters", "points", "resonance (Hz)", "peak ampl. (m)", "Q", "end"
    );
    for c in &outcome.curves {
        let params: Vec<String> = c.params.iter().map(|(k, v)| format!("{k}={v}")).collect();
        let params = if params.is_empty() {
            "-".to_string()
        } else {
            params.join(" ")
        };
        let (f, a, q) = summary_cells(c.summary.as_ref());
        s += &format!(
            "{:>5} {:<28} {:>7} {:>15} {:>15} {:>9}  {}\n",
            c.sweep_point, params, c.points, f, a, q, c.end
        );
    }
    s
}

/// Resonance (Hz), peak amplitude (m) and Q as table cells ("-" when missing).
pub fn summary_cells(s: Option<&CurveSummary>) -> (String, String, String) {
    match s {
        None => ("-".into(), "-".into(), "-".into()),
        Some(s) => (
            format!("{:.6}", s.resonance_hz),
            format!("{:.6e}", s.peak_amplitude),
            s.q_factor.map_or("-".into(), |q| format!("{q:.2}")),
        ),
    }
}
