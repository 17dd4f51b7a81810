//! `nlrom batch CASE_OR_MESH... [--jobs J] [--out DIR] [--case TEMPLATE]`: many cases,
//! or many meshes run with one template case (its `[model] mesh` replaced), each solved like
//! `nlrom run`, one results file `DIR/<name>.h5` each. The jobs run in a rayon pool of J
//! threads; the sweep points and the harmonic balance inside a job use the same pool (nested
//! parallelism), so `--jobs 1` runs everything on one thread. A job that fails (bad input or no
//! convergence) is reported with its message and the others go on. The summary table (case,
//! status, resonance frequency, peak amplitude, Q-factor per curve; definitions in
//! [`super::summary`]) is printed and written to `DIR/summary.csv`.
//!
//! The ROMs of sector cases go to a content-addressed cache directory (`--rom-cache`, default
//! `DIR/rom-cache`): cases with the same mesh and reduction settings reduce once, also across
//! processes and machines sharing the directory ([`RomPolicy::Shared`]).
//!
//! Beyond one machine: `--shard I/N` runs one part of the batch ([`shard`]), `--slurm` writes
//! (and with `--submit` submits) a Slurm job array running one shard per array task
//! ([`slurm`]), and `nlrom batch merge DIR` gathers the shards' records into the summary a local
//! batch writes ([`merge`]); `--resume` runs only the cases whose results are missing or failed.
//! Every case leaves a record in `DIR/cases/` ([`records`]).

pub mod merge;
pub mod records;
pub mod shard;
pub mod slurm;

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde_json::{json, Value};

use super::progress::Reporter;
use super::solve::{solve_to_file, CurveReport, SolveOptions};
use super::summary::CurveSummary;
use super::summary_cells;
use crate::case::{Case, CaseKind};
use crate::error::{Error, Result};
use crate::output::h5::host_name;
use crate::problem::rom_store::{RomOrigin, RomPolicy};
use records::{
    case_record_path, manifest_path, process_cpu_seconds, read_json, shard_record_path, slurm_job,
    write_json, write_shared, CaseRecord, Manifest, ShardRecord,
};
use shard::Shard;

/// What `nlrom batch` runs.
#[derive(Clone, Debug)]
pub struct BatchOptions {
    /// Case files, or meshes (`.msh`) when `template` is given.
    pub inputs: Vec<PathBuf>,
    /// Threads of the pool (jobs run at once), ≥ 1.
    pub jobs: usize,
    /// Output directory (results files, records, `summary.csv`).
    pub out: PathBuf,
    /// The template case for mesh inputs.
    pub template: Option<PathBuf>,
    /// The content-addressed ROM cache directory; `None`: `out/rom-cache`.
    pub rom_cache: Option<PathBuf>,
    /// Run only this shard of the batch.
    pub shard: Option<Shard>,
    /// Run only the cases whose results are missing or failed.
    pub resume: bool,
}

impl BatchOptions {
    /// `inputs` into `out` on one thread: no template, the default ROM cache, all cases.
    pub fn new(inputs: Vec<PathBuf>, out: PathBuf) -> BatchOptions {
        BatchOptions {
            inputs,
            jobs: 1,
            out,
            template: None,
            rom_cache: None,
            shard: None,
            resume: false,
        }
    }

    /// The ROM cache directory: `--rom-cache`, else `DIR/rom-cache`.
    pub fn rom_cache_dir(&self) -> PathBuf {
        self.rom_cache
            .clone()
            .unwrap_or_else(|| self.out.join("rom-cache"))
    }
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
    /// CPU time of the job (user + system, s) when the jobs run one at a time (`--jobs 1`).
    pub cpu_seconds: Option<f64>,
    /// Where the ROM of a sector case came from: `reduced`, `reused` or `raced`.
    pub rom: Option<&'static str>,
    /// No record of the job was found (`nlrom batch merge`).
    pub missing: bool,
}

impl JobResult {
    /// `ok`, `failed` or `missing`.
    pub fn status(&self) -> &'static str {
        if self.missing {
            "missing"
        } else if self.error.is_some() || self.curves.iter().any(|c| c.failure.is_some()) {
            "failed"
        } else {
            "ok"
        }
    }

    /// The result of a job without a record.
    pub fn missing(job: &Job, message: String) -> JobResult {
        JobResult {
            job: job.clone(),
            output: None,
            curves: Vec::new(),
            error: Some(message),
            wall_seconds: 0.0,
            cpu_seconds: None,
            rom: None,
            missing: true,
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

/// What one run of `nlrom batch` does: the jobs of the whole batch, the positions of this run's
/// part (the shard, or all), and which of them it runs (with `--resume`, those without a
/// finished, successful record).
#[derive(Clone, Debug)]
pub struct Plan {
    /// Every job of the batch, in input order.
    pub jobs: Vec<Job>,
    /// Positions of this run's part.
    pub part: Vec<usize>,
    /// Positions this run solves (a subset of `part`).
    pub run: Vec<usize>,
}

/// Checks the options; `--jobs 0` and a missing template are bad input.
pub fn check_options(opts: &BatchOptions) -> Result<()> {
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
    Ok(())
}

/// Prepares the output directory and plans the run. A whole batch without `--resume` starts
/// anew: the manifest is (re)written and old records are removed. A shard or a resumed run
/// keeps the records and checks that the directory's manifest lists the same cases.
pub fn plan(opts: &BatchOptions, rep: &Reporter) -> Result<Plan> {
    check_options(opts)?;
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    let jobs = jobs_of(&opts.inputs);
    let manifest = Manifest::new(&jobs, opts.template.as_deref(), opts.shard.map(|s| s.count));
    if opts.shard.is_none() && !opts.resume {
        start_new_batch(&opts.out, &manifest)?;
    } else {
        check_manifest(&opts.out, &manifest)?;
    }
    let part: Vec<usize> = match opts.shard {
        Some(s) => s.positions(jobs.len()),
        None => (0..jobs.len()).collect(),
    };
    let run: Vec<usize> = if opts.resume {
        part.iter()
            .copied()
            .filter(|&p| !is_done(&opts.out, &jobs[p]))
            .collect()
    } else {
        part.clone()
    };
    if opts.resume {
        rep.info(&format!(
            "--resume: {} of {} cases already done, {} to run",
            part.len() - run.len(),
            part.len(),
            run.len()
        ));
    }
    Ok(Plan { jobs, part, run })
}

/// Removes the records of an earlier batch in `dir` and writes the manifest.
pub fn start_new_batch(dir: &Path, manifest: &Manifest) -> Result<()> {
    for sub in ["cases", "shards"] {
        let d = dir.join(sub);
        if d.exists() {
            std::fs::remove_dir_all(&d).map_err(|e| Error::io(&d, e))?;
        }
    }
    write_json(&manifest_path(dir), manifest)
}

/// Writes the manifest if `dir` has none; else checks that it lists the same cases.
pub fn check_manifest(dir: &Path, manifest: &Manifest) -> Result<()> {
    let path = manifest_path(dir);
    if !path.exists() {
        return write_json(&path, manifest);
    }
    let existing: Manifest = read_json(&path)?;
    if existing.same_cases(manifest) {
        return Ok(());
    }
    Err(Error::input(format!(
        "{}: this directory holds a batch of other cases ({} listed, {} given); give the same inputs in the same order (and the same --case), or another --out",
        path.display(),
        existing.jobs.len(),
        manifest.jobs.len()
    )))
}

/// Whether `job` has a record with status `ok` and its results file `DIR/<name>.h5` exists.
pub fn is_done(dir: &Path, job: &Job) -> bool {
    let path = case_record_path(dir, &job.name);
    match read_json::<CaseRecord>(&path) {
        Ok(r) => r.status == "ok" && dir.join(format!("{}.h5", job.name)).is_file(),
        Err(_) => false,
    }
}

/// Runs the jobs at `positions` of `jobs` in a pool of `opts.jobs` threads, writing each
/// job's record when it ends; results in the order of `positions`.
pub fn run_jobs(
    jobs: &[Job],
    positions: &[usize],
    opts: &BatchOptions,
    rep: &Reporter,
) -> Result<Vec<JobResult>> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(opts.jobs)
        .build()
        .map_err(|e| Error::Compute(format!("cannot start {} threads: {e}", opts.jobs)))?;
    rep.info(&format!(
        "{} jobs on {} thread(s), results in {}",
        positions.len(),
        opts.jobs,
        opts.out.display()
    ));
    let host = host_name();
    Ok(pool.install(|| {
        positions
            .par_iter()
            .map(|&p| {
                let job = &jobs[p];
                let record = case_record_path(&opts.out, &job.name);
                let _ = std::fs::remove_file(&record);
                let result = run_job(job, opts, rep);
                let r = CaseRecord::of(&result, opts.shard, &host);
                if let Err(e) = write_json(&record, &r) {
                    rep.warn(&format!("{}: cannot write its record: {e}", job.name));
                }
                result
            })
            .collect()
    }))
}

/// Runs the whole batch (no shard, no resume) and returns the job results in input order.
pub fn run_batch(opts: &BatchOptions, rep: &Reporter) -> Result<Vec<JobResult>> {
    let plan = plan(opts, rep)?;
    run_jobs(&plan.jobs, &plan.run, opts, rep)
}

/// One job: load (or build from the template), solve like `nlrom run`, write `DIR/<name>.h5`.
fn run_job(job: &Job, opts: &BatchOptions, rep: &Reporter) -> JobResult {
    let start = Instant::now();
    let cpu_start = (opts.jobs == 1).then(process_cpu_seconds).flatten();
    let rep = rep.labelled(&job.name);
    let output = opts.out.join(format!("{}.h5", job.name));
    let mut written = None;
    let mut curves = Vec::new();
    let mut rom = None;
    let outcome = job_case(job, opts.template.as_deref()).and_then(|case| {
        let policy = if case.kind() == CaseKind::Matrix {
            RomPolicy::ReadIfMatching
        } else if let Some(r) = &case.rom {
            RomPolicy::Cache(r.file.clone())
        } else {
            RomPolicy::Shared(opts.rom_cache_dir())
        };
        solve_to_file(&case, &output, &SolveOptions::new(policy), &rep)
    });
    let error = match outcome {
        Ok(o) => {
            written = Some(output);
            curves = o.curves;
            rom = o.rom.as_ref().map(|r| match r {
                RomOrigin::Reused(_) => "reused",
                RomOrigin::Reduced(_) => "reduced",
                RomOrigin::Raced(_) => "raced",
            });
            None
        }
        Err(e) => Some(e.to_string()),
    };
    let cpu_seconds = cpu_start.and_then(|c0| process_cpu_seconds().map(|c1| c1 - c0));
    let result = JobResult {
        job: job.clone(),
        output: written,
        curves,
        error,
        wall_seconds: start.elapsed().as_secs_f64(),
        cpu_seconds,
        rom,
        missing: false,
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

/// `nlrom batch`: runs the jobs (of the shard, with `--shard`; those not yet done, with
/// `--resume`), prints the summary table (or `--json`) and writes `DIR/summary.csv` (a shard:
/// its record and partial summary `DIR/shards/<I>-of-<N>.{json,csv}`); fails (exit status 1)
/// when any job failed.
pub fn batch_command(opts: &BatchOptions, rep: &Reporter, as_json: bool) -> Result<()> {
    let start = Instant::now();
    let cpu_start = process_cpu_seconds();
    let plan = plan(opts, rep)?;
    let host = host_name();
    let names =
        |ps: &[usize]| -> Vec<String> { ps.iter().map(|&p| plan.jobs[p].name.clone()).collect() };
    let skipped: Vec<usize> = plan
        .part
        .iter()
        .copied()
        .filter(|p| !plan.run.contains(p))
        .collect();
    let shard_record = |finished: bool| ShardRecord {
        shard: opts.shard.map(|s| s.to_string()).unwrap_or_default(),
        host: host.clone(),
        slurm_job: slurm_job(),
        cases: names(&plan.run),
        skipped: names(&skipped),
        finished,
        wall_seconds: start.elapsed().as_secs_f64(),
        cpu_seconds: cpu_start.and_then(|c0| process_cpu_seconds().map(|c1| c1 - c0)),
    };
    if let Some(s) = opts.shard {
        write_json(
            &shard_record_path(&opts.out, s, "json"),
            &shard_record(false),
        )?;
    }
    let fresh = run_jobs(&plan.jobs, &plan.run, opts, rep)?;
    let mut by_position: BTreeMap<usize, JobResult> = plan.run.iter().copied().zip(fresh).collect();
    // the cases skipped by --resume: their records
    for &p in &skipped {
        let job = &plan.jobs[p];
        let result = read_json::<CaseRecord>(&case_record_path(&opts.out, &job.name))
            .map(|r| r.result(job))
            .unwrap_or_else(|e| JobResult::missing(job, e.to_string()));
        by_position.insert(p, result);
    }
    let results: Vec<JobResult> = by_position.into_values().collect();
    let csv_path = match opts.shard {
        Some(s) => shard_record_path(&opts.out, s, "csv"),
        None => opts.out.join("summary.csv"),
    };
    write_shared(&csv_path, summary_csv(&results).as_bytes())?;
    if let Some(s) = opts.shard {
        write_json(
            &shard_record_path(&opts.out, s, "json"),
            &shard_record(true),
        )?;
    }
    let wall = start.elapsed().as_secs_f64();
    if as_json {
        let jobs: Vec<Value> = results.iter().map(job_json).collect();
        println!(
            "{}",
            json!({
                "jobs": jobs,
                "threads": opts.jobs,
                "shard": opts.shard.map(|s| s.to_string()),
                "skipped": names(&skipped),
                "summary_csv": csv_path.display().to_string(),
                "wall_seconds": wall,
            })
        );
    } else {
        print!("{}", summary_table(&results));
        let what = match opts.shard {
            Some(s) => format!("shard {s}: "),
            None => String::new(),
        };
        println!(
            "{what}{} jobs ({} run, {} already done) in {wall:.2} s on {} thread(s); summary written to {}",
            results.len(),
            plan.run.len(),
            skipped.len(),
            opts.jobs,
            csv_path.display()
        );
        if opts.shard.is_some() {
            println!(
                "gather the shards with `nlrom batch merge {}`",
                opts.out.display()
            );
        }
    }
    fail_if_any_failed(&results, &csv_path)
}

/// Exit status 1 naming the failed (or missing) jobs, if any.
pub fn fail_if_any_failed(results: &[JobResult], csv_path: &Path) -> Result<()> {
    let failed: Vec<&JobResult> = results.iter().filter(|r| r.status() != "ok").collect();
    if failed.is_empty() {
        return Ok(());
    }
    let names: Vec<&str> = failed.iter().map(|r| r.job.name.as_str()).collect();
    let missing = failed.iter().filter(|r| r.missing).count();
    let verb = if missing == 0 {
        "failed".to_string()
    } else {
        format!("failed or are missing ({missing} missing)")
    };
    Err(Error::Compute(format!(
        "{} of {} jobs {verb} ({}); see {}",
        failed.len(),
        results.len(),
        names.join(", "),
        csv_path.display()
    )))
}

/// The JSON object of one job (`nlrom batch --json`, `merge --json`).
pub fn job_json(r: &JobResult) -> Value {
    json!({
        "case": r.job.name,
        "input": r.job.input.display().to_string(),
        "status": r.status(),
        "output": r.output.as_ref().map(|p| p.display().to_string()),
        "frf": r.curves.iter().map(CurveReport::json).collect::<Vec<_>>(),
        "error": r.error,
        "wall_seconds": r.wall_seconds,
        "cpu_seconds": r.cpu_seconds,
        "rom": r.rom,
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
                    status: if r.missing { "missing" } else { "failed" },
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
