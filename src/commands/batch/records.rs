//! What a batch leaves in its output directory besides the results files, so that shards run
//! on different machines can be gathered (`nlrom batch merge`) and resumed (`--resume`):
//!
//! * `DIR/batch.json`, the [`Manifest`]: every case of the batch (name and input) in order;
//! * `DIR/cases/<name>.json`, one [`CaseRecord`] per finished case (status, the summary numbers
//!   of every curve in full precision, error, wall and CPU time, shard and host), written
//!   atomically when the case ends;
//! * `DIR/shards/<I>-of-<N>.json`, one [`ShardRecord`] per shard (written when it starts and
//!   again when it ends), and `DIR/shards/<I>-of-<N>.csv`, its partial summary.
//!
//! JSON numbers are written in the shortest form that reads back to the same `f64`, so a
//! summary gathered from records equals the one the run printed, digit for digit.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use super::shard::Shard;
use super::{Job, JobResult};
use crate::commands::solve::CurveReport;
use crate::commands::summary::CurveSummary;
use crate::error::{Error, Result};
use crate::output::h5::unique_temporary_path;
use crate::problem::rom_store::create_parent;

/// The cases of a batch, in order (`DIR/batch.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Manifest {
    /// Name and input of every case.
    pub jobs: Vec<ManifestJob>,
    /// The template case of mesh inputs.
    pub template: Option<String>,
    /// The number of shards the batch was planned with (`--slurm`, `--shard`), if any.
    pub shards: Option<usize>,
}

/// One case of the manifest.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct ManifestJob {
    /// The case's name (its results file is `DIR/<name>.h5`).
    pub name: String,
    /// Its case file or mesh, as given on the command line.
    pub input: String,
}

impl Manifest {
    /// The manifest of `jobs` run with `template`.
    pub fn new(jobs: &[Job], template: Option<&Path>, shards: Option<usize>) -> Manifest {
        Manifest {
            jobs: jobs
                .iter()
                .map(|j| ManifestJob {
                    name: j.name.clone(),
                    input: j.input.display().to_string(),
                })
                .collect(),
            template: template.map(|t| t.display().to_string()),
            shards,
        }
    }

    /// Whether `other` names the same cases (the shard count may differ).
    pub fn same_cases(&self, other: &Manifest) -> bool {
        self.jobs == other.jobs && self.template == other.template
    }

    /// The jobs of the manifest.
    pub fn jobs(&self) -> Vec<Job> {
        self.jobs
            .iter()
            .map(|j| Job {
                name: j.name.clone(),
                input: PathBuf::from(&j.input),
            })
            .collect()
    }
}

/// `DIR/batch.json`.
pub fn manifest_path(dir: &Path) -> PathBuf {
    dir.join("batch.json")
}

/// `DIR/cases/<name>.json`.
pub fn case_record_path(dir: &Path, name: &str) -> PathBuf {
    dir.join("cases").join(format!("{name}.json"))
}

/// `DIR/shards/<I>-of-<N>` + `ext`.
pub fn shard_record_path(dir: &Path, shard: Shard, ext: &str) -> PathBuf {
    dir.join("shards")
        .join(format!("{}-of-{}.{ext}", shard.index, shard.count))
}

/// Reads the manifest of the batch in `dir`; a missing or unreadable one is bad input naming
/// the file.
pub fn read_manifest(dir: &Path) -> Result<Manifest> {
    let path = manifest_path(dir);
    if !path.is_file() {
        return Err(Error::input(format!(
            "{}: no batch manifest; is {} the --out directory of an `nlrom batch` run?",
            path.display(),
            dir.display()
        )));
    }
    read_json(&path)
}

/// Writes `value` as pretty JSON to `path` atomically (parent directories created).
pub fn write_json<T: Serialize>(path: &Path, value: &T) -> Result<()> {
    let text = serde_json::to_string_pretty(value)
        .map_err(|e| Error::Compute(format!("{}: cannot serialise: {e}", path.display())))?;
    write_shared(path, text.as_bytes())
}

/// Writes `bytes` to `path` through a temporary file whose name no other process or machine
/// uses ([`unique_temporary_path`]), then renames it: readers on a shared file system see the
/// old or the new file, whole, even when several shards write the same path.
pub fn write_shared(path: &Path, bytes: &[u8]) -> Result<()> {
    create_parent(path)?;
    let tmp = unique_temporary_path(path);
    let written = std::fs::write(&tmp, bytes).and_then(|()| std::fs::rename(&tmp, path));
    if let Err(e) = written {
        let _ = std::fs::remove_file(&tmp);
        return Err(Error::io(path, e));
    }
    Ok(())
}

/// Reads a JSON file; a malformed one is bad input naming the file, line and column.
pub fn read_json<T: for<'de> Deserialize<'de>>(path: &Path) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    serde_json::from_str(&text).map_err(|e| Error::input(format!("{}: {e}", path.display())))
}

/// The record of one finished case (`DIR/cases/<name>.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CaseRecord {
    /// The case's name.
    pub case: String,
    /// Its input file.
    pub input: String,
    /// `ok` or `failed`.
    pub status: String,
    /// The results file, when one was written.
    pub output: Option<String>,
    /// One entry per curve.
    pub curves: Vec<CurveRecord>,
    /// The case's error (bad input, failed continuation), if any.
    pub error: Option<String>,
    /// Wall time of the case (s).
    pub wall_seconds: f64,
    /// CPU time of the case (user + system, s): measured when the shard runs one case at a time
    /// (`--jobs 1`), `None` otherwise (concurrent cases share the process's threads).
    pub cpu_seconds: Option<f64>,
    /// Where the ROM of a sector case came from: `reduced`, `reused` or `raced` (reduced, but
    /// another task published the same ROM first and its file was read).
    pub rom: Option<String>,
    /// The shard that ran the case (`I/N`), `None` for an unsharded batch.
    pub shard: Option<String>,
    /// The machine that ran it.
    pub host: String,
}

/// One curve of a [`CaseRecord`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CurveRecord {
    /// Sweep point index.
    pub sweep_point: usize,
    /// The sweep parameters.
    pub params: BTreeMap<String, f64>,
    /// Converged points.
    pub points: usize,
    /// Resonance frequency (Hz).
    pub resonance_hz: Option<f64>,
    /// Peak first-harmonic amplitude (m).
    pub peak_amplitude: Option<f64>,
    /// Half-power Q-factor.
    pub q_factor: Option<f64>,
    /// The response DOF of the summary.
    pub response_dof: Option<usize>,
    /// The peak point's index.
    pub peak_point: Option<usize>,
    /// How the continuation ended.
    pub end: String,
    /// Why the curve failed, if it did.
    pub failure: Option<String>,
}

impl CaseRecord {
    /// The record of `result`, run by `shard` on `host`.
    pub fn of(result: &JobResult, shard: Option<Shard>, host: &str) -> CaseRecord {
        CaseRecord {
            case: result.job.name.clone(),
            input: result.job.input.display().to_string(),
            status: result.status().to_string(),
            output: result.output.as_ref().map(|p| p.display().to_string()),
            curves: result
                .curves
                .iter()
                .map(|c| CurveRecord {
                    sweep_point: c.sweep_point,
                    params: c.params.clone(),
                    points: c.points,
                    resonance_hz: c.summary.map(|s| s.resonance_hz),
                    peak_amplitude: c.summary.map(|s| s.peak_amplitude),
                    q_factor: c.summary.and_then(|s| s.q_factor),
                    response_dof: c.summary.map(|s| s.response_dof),
                    peak_point: c.summary.map(|s| s.peak_point),
                    end: c.end.to_string(),
                    failure: c.failure.clone(),
                })
                .collect(),
            error: result.error.clone(),
            wall_seconds: result.wall_seconds,
            cpu_seconds: result.cpu_seconds,
            rom: result.rom.map(str::to_string),
            shard: shard.map(|s| s.to_string()),
            host: host.to_string(),
        }
    }

    /// The job result this record describes (for the job `job` of the manifest).
    pub fn result(&self, job: &Job) -> JobResult {
        let curves = self
            .curves
            .iter()
            .map(|c| {
                let summary = match (c.resonance_hz, c.peak_amplitude) {
                    (Some(resonance_hz), Some(peak_amplitude)) => Some(CurveSummary {
                        resonance_hz,
                        peak_amplitude,
                        response_dof: c.response_dof.unwrap_or(0),
                        peak_point: c.peak_point.unwrap_or(0),
                        q_factor: c.q_factor,
                    }),
                    _ => None,
                };
                CurveReport {
                    sweep_point: c.sweep_point,
                    params: c.params.clone(),
                    points: c.points,
                    summary,
                    end: end_label(&c.end),
                    failure: c.failure.clone(),
                    cpu_seconds: None,
                }
            })
            .collect();
        JobResult {
            job: job.clone(),
            output: self.output.as_ref().map(PathBuf::from),
            curves,
            error: self.error.clone(),
            wall_seconds: self.wall_seconds,
            cpu_seconds: self.cpu_seconds,
            rom: self.rom.as_deref().map(rom_label),
            missing: false,
        }
    }
}

/// The static label of a continuation end read from a record.
fn end_label(end: &str) -> &'static str {
    match end {
        "reached_end" => "reached_end",
        "max_points" => "max_points",
        "left_range" => "left_range",
        _ => "failed",
    }
}

/// The static label of a ROM origin read from a record.
fn rom_label(rom: &str) -> &'static str {
    match rom {
        "reused" => "reused",
        "raced" => "raced",
        _ => "reduced",
    }
}

/// The record of one shard (`DIR/shards/<I>-of-<N>.json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ShardRecord {
    /// `I/N`.
    pub shard: String,
    /// The machine.
    pub host: String,
    /// The Slurm job and array task (`$SLURM_ARRAY_JOB_ID_$SLURM_ARRAY_TASK_ID`), if any.
    pub slurm_job: Option<String>,
    /// The cases of the shard.
    pub cases: Vec<String>,
    /// The cases skipped by `--resume` (their results were there).
    pub skipped: Vec<String>,
    /// Whether the shard ran to its end (`false` while running, or when it was killed).
    pub finished: bool,
    /// Wall time of the shard so far (s).
    pub wall_seconds: f64,
    /// CPU time of the shard's process (user + system, all threads, s), if measurable.
    pub cpu_seconds: Option<f64>,
}

/// The CPU time (user + system) of this process so far, all threads (s); `None` where it
/// cannot be measured.
pub fn process_cpu_seconds() -> Option<f64> {
    #[cfg(target_os = "linux")]
    {
        let mut usage = std::mem::MaybeUninit::<libc::rusage>::zeroed();
        // SAFETY: getrusage writes a complete `rusage` into the pointer it is given.
        let rc = unsafe { libc::getrusage(libc::RUSAGE_SELF, usage.as_mut_ptr()) };
        if rc != 0 {
            return None;
        }
        // SAFETY: initialised by the successful call above.
        let u = unsafe { usage.assume_init() };
        let t = |tv: libc::timeval| tv.tv_sec as f64 + tv.tv_usec as f64 * 1e-6;
        Some(t(u.ru_utime) + t(u.ru_stime))
    }
    #[cfg(not(target_os = "linux"))]
    {
        None
    }
}

/// The CPU time (user + system) of the calling thread so far (s; `CLOCK_THREAD_CPUTIME_ID`);
/// `None` where it cannot be measured.
pub fn thread_cpu_seconds() -> Option<f64> {
    #[cfg(target_os = "linux")]
    {
        let mut t = libc::timespec {
            tv_sec: 0,
            tv_nsec: 0,
        };
        // SAFETY: clock_gettime writes a complete `timespec` into the pointer it is given.
        let rc = unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut t) };
        (rc == 0).then_some(t.tv_sec as f64 + t.tv_nsec as f64 * 1e-9)
    }
    #[cfg(not(target_os = "linux"))]
    {
        None
    }
}

/// The time (s) the calling thread has spent runnable but waiting for a CPU (the run-queue
/// delay, second field of `/proc/thread-self/schedstat`, ns): on a loaded machine, the part of
/// its wall time that other processes took. `None` where it cannot be read (not Linux, or a
/// kernel without scheduler statistics).
pub fn thread_cpu_wait_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let delay: f64 = stat.split_whitespace().nth(1)?.parse().ok()?;
    Some(delay * 1e-9)
}

/// `$SLURM_ARRAY_JOB_ID_$SLURM_ARRAY_TASK_ID` (or `$SLURM_JOB_ID`) inside a Slurm job.
pub fn slurm_job() -> Option<String> {
    let var = |k: &str| std::env::var(k).ok().filter(|v| !v.is_empty());
    match (var("SLURM_ARRAY_JOB_ID"), var("SLURM_ARRAY_TASK_ID")) {
        (Some(j), Some(t)) => Some(format!("{j}_{t}")),
        _ => var("SLURM_JOB_ID"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_record_reads_back_to_the_same_numbers() {
        let job = Job {
            name: "a".into(),
            input: PathBuf::from("cases/a.toml"),
        };
        let result = JobResult {
            job: job.clone(),
            output: Some(PathBuf::from("out/a.h5")),
            curves: vec![CurveReport {
                sweep_point: 0,
                params: BTreeMap::from([("n0".to_string(), 0.1)]),
                points: 17,
                summary: Some(CurveSummary {
                    resonance_hz: 0.1 + 0.2,
                    peak_amplitude: 1.0 / 3.0,
                    response_dof: 1,
                    peak_point: 5,
                    q_factor: Some(std::f64::consts::PI * 1e7),
                }),
                end: "reached_end",
                failure: None,
                cpu_seconds: None,
            }],
            error: None,
            wall_seconds: 0.123456789,
            cpu_seconds: Some(2.5e-3),
            rom: None,
            missing: false,
        };
        let record = CaseRecord::of(&result, Some(Shard { index: 2, count: 3 }), "node1");
        let text = serde_json::to_string(&record).unwrap();
        let back: CaseRecord = serde_json::from_str(&text).unwrap();
        assert_eq!(back, record);
        let r = back.result(&job);
        let (a, b) = (
            r.curves[0].summary.unwrap(),
            result.curves[0].summary.unwrap(),
        );
        assert_eq!(a, b);
        assert_eq!(r.wall_seconds.to_bits(), result.wall_seconds.to_bits());
        assert_eq!(back.shard.as_deref(), Some("2/3"));
    }

    /// Every f64 reads back from a record bit for bit (serde_json's `float_roundtrip` parser; its
    /// default parser may be one unit in the last place off).
    #[test]
    fn numbers_round_trip_bit_for_bit() {
        let mut state: u64 = 0x9e37_79b9_7f4a_7c15;
        let mut off = 0;
        for _ in 0..20_000 {
            // xorshift64 bit patterns, finite values of every magnitude
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            let x = f64::from_bits(state);
            if !x.is_finite() {
                continue;
            }
            let curve = CurveRecord {
                sweep_point: 0,
                params: BTreeMap::new(),
                points: 1,
                resonance_hz: Some(x),
                peak_amplitude: Some(x.abs().sqrt()),
                q_factor: None,
                response_dof: Some(0),
                peak_point: Some(0),
                end: "reached_end".into(),
                failure: None,
            };
            let back: CurveRecord =
                serde_json::from_str(&serde_json::to_string(&curve).unwrap()).unwrap();
            if back != curve {
                off += 1;
            }
        }
        assert_eq!(off, 0, "{off} numbers did not read back exactly");
    }
}
