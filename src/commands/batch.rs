//! `nlrom batch CASE_OR_MESH... [--jobs J] [--out DIR] [--case TEMPLATE]`: many cases,
//! or many meshes run with one template case (its `[model] mesh` replaced), each solved like
//! `nlrom run` (the ROM of a sector case cached as `DIR/<name>.rom.h5`), one results file
//! `DIR/<name>.h5` each. The jobs run in a rayon pool of J threads; the sweep points and the
//! harmonic balance inside a job use the same pool (nested parallelism), so `--jobs 1` runs
//! everything on one thread. A job that fails (bad input or no convergence) is reported with its
//! message and the others go on. The summary table (case, status, resonance frequency, peak
//! amplitude, Q-factor per curve; definitions in [`super::summary`]) is printed and written to
//! `DIR/summary.csv`.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde_json::{json, Value};

use super::progress::Reporter;
use super::solve::{default_rom_file, solve_to_file, CurveReport, SolveOptions};
use super::summary::CurveSummary;
use super::summary_cells;
use crate::case::{Case, CaseKind};
use crate::error::{Error, Result};
use crate::problem::rom_store::{create_parent, RomPolicy};

/// What `nlrom batch` runs.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    /// Case files, or meshes (`.msh`) when `template` is given.
    pub inputs: Vec<PathBuf>,
    /// Threads of the pool (jobs run at once), ≥ 1.
    pub jobs: usize,
    /// Output directory (results files, ROM files, `summary.csv`).
    pub out: PathBuf,
    /// The template case for mesh inputs.
    pub template: Option<PathBuf>,
}

/// One job: a name (unique in the batch; the stem of its input) and its input file.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Job {
    /// Name of the results file `DIR/<name>.h5`.
    pub name: String,
    /// The case file or mesh.
    pub input: PathBuf,
}

/// The outcome of one job.
#[derive(Clone, Debug)]
pub struct JobResult {
    /// The job.
    pub job: Job,
    /// The results file, when one was written.
    pub output: Option<PathBuf>,
    /// One report per sweep point (empty when the job failed before solving).
    pub curves: Vec<CurveReport>,
    /// The job's error (bad input, failed continuation), if any.
    pub error: Option<String>,
    /// Wall time of the job (s).
    pub wall_seconds: f64,
}

impl JobResult {
    /// `ok` or `failed`.
    pub fn status(&self) -> &'static str {
        if self.error.is_some() || self.curves.iter().any(|c| c.failure.is_some()) {
            "failed"
        } else {
            "ok"
        }
    }
}

/// Names the jobs after their inputs' stems, made unique with `_2`, `_3`, … in input order.
pub fn jobs_of(inputs: &[PathBuf]) -> Vec<Job> {
    let mut used = BTreeSet::new();
    inputs
        .iter()
        .map(|input| {
            let stem = input
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_else(|| "case".into());
            let mut name = stem.clone();
            let mut n = 1;
            while !used.insert(name.clone()) {
                n += 1;
                name = format!("{stem}_{n}");
            }
            Job {
                name,
                input: input.clone(),
            }
        })
        .collect()
}

/// Runs the batch and returns the job results in input order.
pub fn run_batch(opts: &BatchOptions, rep: &Reporter) -> Result<Vec<JobResult>> {
    if opts.jobs == 0 {
        return Err(Error::input("--jobs 0: give at least 1 job"));
    }
    if let Some(t) = &opts.template {
        if !t.is_file() {
            return Err(Error::input(format!(
                "--case {}: the template case file does not exist",
                t.display()
            )));
        }
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.jobs)
        .build()
        .map_err(|e| Error::Compute(format!("cannot start {} threads: {e}", opts.jobs)))?;
    let jobs = jobs_of(&opts.inputs);
    rep.info(&format!(
        "{} jobs on {} thread(s), results in {}",
        jobs.len(),
        opts.jobs,
        opts.out.display()
    ));
    Ok(pool.install(|| jobs.par_iter().map(|job| run_job(job, opts, rep)).collect()))
}

/// One job: load (or build from the template), solve like `nlrom run`, write `DIR/<name>.h5`.
fn run_job(job: &Job, opts: &BatchOptions, rep: &Reporter) -> JobResult {
    let start = Instant::now();
    let rep = rep.labelled(&job.name);
    let output = opts.out.join(format!("{}.h5", job.name));
    let mut written = None;
    let mut curves = Vec::new();
    let outcome = job_case(job, opts.template.as_deref()).and_then(|case| {
        let policy = if case.kind() == CaseKind::Matrix {
            RomPolicy::ReadIfMatching
        } else {
            RomPolicy::Cache(default_rom_file(&case, &output))
        };
        solve_to_file(&case, &output, &SolveOptions::new(policy), &rep)
    });
    let error = match outcome {
        Ok(o) => {
            written = Some(output);
            curves = o.curves;
            None
        }
        Err(e) => Some(e.to_string()),
    };
    let result = JobResult {
        job: job.clone(),
        output: written,
        curves,
        error,
        wall_seconds: start.elapsed().as_secs_f64(),
    };
    if let Some(e) = &result.error {
        rep.warn(&format!("failed: {e}"));
    } else if result.status() == "failed" {
        rep.warn("a curve failed to converge (its converged points are written)");
    }
    result
}

/// The case of a job: the case file itself, or the template with the mesh replaced (its `[rom]
/// file` dropped so that every mesh gets its own ROM file).
fn job_case(job: &Job, template: Option<&Path>) -> Result<Case> {
    let is_mesh = job
        .input
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("msh"));
    if !is_mesh {
        return Case::load(&job.input);
    }
    let Some(template) = template else {
        return Err(Error::input(format!(
            "{}: a mesh needs a template case: pass `--case TEMPLATE.toml` (its [model] mesh is replaced by each mesh)",
            job.input.display()
        )));
    };
    if !job.input.is_file() {
        return Err(Error::input(format!(
            "{}: the mesh file does not exist",
            job.input.display()
        )));
    }
    let mut case = Case::load(template)?;
    if case.model.mesh.is_none() {
        return Err(Error::input(format!(
            "{}: the template case has no `[model] mesh` to replace by {}",
            template.display(),
            job.input.display()
        )));
    }
    case.model.mesh = Some(job.input.clone());
    case.rom = None;
    case.title = format!("{} ({})", case.title, job.name);
    case.source_text += &format!(
        "\n# nlrom batch: [model] mesh replaced by \"{}\"\n",
        job.input.display()
    );
    Ok(case)
}

/// `nlrom batch`: runs the jobs, prints the summary table (or `--json`), writes
/// `DIR/summary.csv`; fails (exit status 1) when any job failed.
pub fn batch_command(opts: &BatchOptions, rep: &Reporter, as_json: bool) -> Result<()> {
    let start = Instant::now();
    let results = run_batch(opts, rep)?;
    let csv_path = opts.out.join("summary.csv");
    write_atomic(&csv_path, &summary_csv(&results))?;
    if as_json {
        let jobs: Vec<Value> = results.iter().map(job_json).collect();
        println!(
            "{}",
            json!({
                "jobs": jobs,
                "threads": opts.jobs,
                "summary_csv": csv_path.display().to_string(),
                "wall_seconds": start.elapsed().as_secs_f64(),
            })
        );
    } else {
        print!("{}", summary_table(&results));
        println!(
            "{} jobs in {:.2} s on {} thread(s); summary written to {}",
            results.len(),
            start.elapsed().as_secs_f64(),
            opts.jobs,
            csv_path.display()
        );
    }
    let failed: Vec<&JobResult> = results.iter().filter(|r| r.status() == "failed").collect();
    if failed.is_empty() {
        return Ok(());
    }
    let names: Vec<&str> = failed.iter().map(|r| r.job.name.as_str()).collect();
    Err(Error::Compute(format!(
        "{} of {} jobs failed ({}); see {}",
        failed.len(),
        results.len(),
        names.join(", "),
        csv_path.display()
    )))
}

fn job_json(r: &JobResult) -> Value {
    json!({
        "case": r.job.name,
        "input": r.job.input.display().to_string(),
        "status": r.status(),
        "output": r.output.as_ref().map(|p| p.display().to_string()),
        "frf": r.curves.iter().map(CurveReport::json).collect::<Vec<_>>(),
        "error": r.error,
        "wall_seconds": r.wall_seconds,
    })
}

/// One row per curve (one per job that failed before solving): the cells of the table and CSV.
struct Row {
    case: String,
    sweep: String,
    status: &'static str,
    summary: Option<CurveSummary>,
    points: String,
    message: String,
}

fn rows(results: &[JobResult]) -> Vec<(Row, &JobResult)> {
    let mut out = Vec::new();
    for r in results {
        if r.curves.is_empty() {
            out.push((
                Row {
                    case: r.job.name.clone(),
                    sweep: "-".into(),
                    status: "failed",
                    summary: None,
                    points: "0".into(),
                    message: r.error.clone().unwrap_or_default(),
                },
                r,
            ));
            continue;
        }
        for c in &r.curves {
            let message = c.failure.clone().or_else(|| r.error.clone());
            out.push((
                Row {
                    case: r.job.name.clone(),
                    sweep: c.sweep_point.to_string(),
                    status: if message.is_some() { "failed" } else { "ok" },
                    summary: c.summary,
                    points: c.points.to_string(),
                    message: message.unwrap_or_default(),
                },
                r,
            ));
        }
    }
    out
}

/// The printed summary table; failure messages follow the table.
pub fn summary_table(results: &[JobResult]) -> String {
    let rows = rows(results);
    let width = rows
        .iter()
        .map(|(r, _)| r.case.chars().count())
        .max()
        .unwrap_or(4)
        .max(4);
    let mut s = format!(
        "{:<width$} {:>5} {:>7} {:>16} {:>15} {:>9} {:>7}\n",
        "case", "sweep", "status", "resonance (Hz)", "peak ampl. (m)", "Q", "points"
    );
    for (r, _) in &rows {
        let (resonance, peak, q) = summary_cells(r.summary.as_ref());
        s += &format!(
            "{:<width$} {:>5} {:>7} {:>16} {:>15} {:>9} {:>7}\n",
            r.case, r.sweep, r.status, resonance, peak, q, r.points
        );
    }
    for (r, _) in rows.iter().filter(|(r, _)| !r.message.is_empty()) {
        s += &format!("{} (sweep {}): {}\n", r.case, r.sweep, r.message);
    }
    s
}

/// `summary.csv`: case, input, sweep_point, status, resonance_hz, peak_amplitude_m, q_factor,
/// points, output, wall_seconds, message (numbers in full precision, empty cells for missing
/// values).
pub fn summary_csv(results: &[JobResult]) -> String {
    let mut s = String::from(
        "case,input,sweep_point,status,resonance_hz,peak_amplitude_m,q_factor,points,output,wall_seconds,message\n",
    );
    let blank = |v: &str| {
        if v == "-" {
            String::new()
        } else {
            v.to_string()
        }
    };
    let number = |v: Option<f64>| v.map_or(String::new(), |x| x.to_string());
    for (r, job) in rows(results) {
        let summary = r.summary.as_ref();
        let cells = [
            r.case.clone(),
            job.job.input.display().to_string(),
            blank(&r.sweep),
            r.status.to_string(),
            number(summary.map(|x| x.resonance_hz)),
            number(summary.map(|x| x.peak_amplitude)),
            number(summary.and_then(|x| x.q_factor)),
            r.points.clone(),
            job.output
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_default(),
            format!("{:.3}", job.wall_seconds),
            r.message.clone(),
        ];
        let line: Vec<String> = cells.iter().map(|c| csv_cell(c)).collect();
        s += &line.join(",");
        s.push('\n');
    }
    s
}

/// A CSV cell, quoted (RFC 4180) when it holds a comma, quote or line break.
fn csv_cell(v: &str) -> String {
    if v.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", v.replace('"', "\"\""))
    } else {
        v.to_string()
    }
}

/// Writes `text` to `path` through a temporary file in the same directory, then renames it.
pub fn write_atomic(path: &Path, text: &str) -> Result<()> {
    create_parent(path)?;
    let tmp = path.with_extension(format!("tmp-{}", std::process::id()));
    std::fs::write(&tmp, text).map_err(|e| Error::io(&tmp, e))?;
    std::fs::rename(&tmp, path).map_err(|e| Error::io(path, e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn job_names_are_unique_stems() {
        let jobs = jobs_of(&[
            PathBuf::from("a/case.toml"),
            PathBuf::from("b/case.toml"),
            PathBuf::from("m/blade.msh"),
            PathBuf::from("c/case.toml"),
        ]);
        let names: Vec<&str> = jobs.iter().map(|j| j.name.as_str()).collect();
        assert_eq!(names, ["case", "case_2", "blade", "case_3"]);
    }

    #[test]
    fn csv_cells_are_quoted_when_needed() {
        assert_eq!(csv_cell("plain"), "plain");
        assert_eq!(csv_cell("a, b"), "\"a, b\"");
        assert_eq!(csv_cell("say \"x\""), "\"say \"\"x\"\"\"");
    }
}
