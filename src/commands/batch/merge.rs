//! `nlrom batch merge DIR`: gathers the records the shards of a batch left in `DIR`
//! ([`super::records`]) into `DIR/summary.csv` — the file a local `nlrom batch` of the same
//! cases writes, row for row and number for number — lists the missing and failed cases with
//! their errors, and reports wall and CPU time per case and per shard (also written to
//! `DIR/accounting.csv`). Exit status 1 when a case is missing or failed.

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

use super::records::{case_record_path, read_json, read_manifest, write_shared};
use super::records::{CaseRecord, ShardRecord};
use super::shard::Shard;
use super::{fail_if_any_failed, job_json, summary_csv, summary_table, JobResult};
use crate::commands::progress::Reporter;
use crate::error::{Error, Result};

/// What the merge found: the results in the manifest's order, with each case's record when
/// there is one, and the shard records (ordered by N, then I).
#[derive(Clone, Debug)]
pub struct Merged {
    /// One result per case of the manifest (`missing` when there is no record).
    pub results: Vec<JobResult>,
    /// The record of each case, if any.
    pub records: Vec<Option<CaseRecord>>,
    /// The shard records found in `DIR/shards/`.
    pub shards: Vec<ShardRecord>,
}

/// Reads the manifest, the case records and the shard records of the batch in `dir`.
pub fn gather(dir: &Path) -> Result<Merged> {
    let manifest = read_manifest(dir)?;
    let jobs = manifest.jobs();
    let mut results = Vec::with_capacity(jobs.len());
    let mut records = Vec::with_capacity(jobs.len());
    for (p, job) in jobs.iter().enumerate() {
        let path = case_record_path(dir, &job.name);
        if path.exists() {
            match read_json::<CaseRecord>(&path) {
                Ok(r) => {
                    results.push(r.result(job));
                    records.push(Some(r));
                }
                Err(e) => {
                    results.push(JobResult::missing(job, format!("unreadable record: {e}")));
                    records.push(None);
                }
            }
            continue;
        }
        let mut message = "no record: the case has not run to its end".to_string();
        if let Some(n) = manifest.shards {
            let shard = Shard::of_position(p, n);
            message += &format!(" (shard {shard}");
            let log = dir.join("logs").join(format!("shard-{}.log", shard.index));
            if log.is_file() {
                message += &format!(", log {}", log.display());
            }
            message += ")";
        }
        results.push(JobResult::missing(job, message));
        records.push(None);
    }
    Ok(Merged {
        results,
        records,
        shards: shard_records(dir)?,
    })
}

/// The shard records in `dir/shards/` ordered by N, then I.
fn shard_records(dir: &Path) -> Result<Vec<ShardRecord>> {
    let sdir = dir.join("shards");
    if !sdir.is_dir() {
        return Ok(Vec::new());
    }
    let mut files: Vec<PathBuf> = std::fs::read_dir(&sdir)
        .map_err(|e| Error::io(&sdir, e))?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "json"))
        .collect();
    files.sort();
    let mut shards = Vec::new();
    for f in files {
        shards.push(read_json::<ShardRecord>(&f)?);
    }
    let order = |r: &ShardRecord| {
        r.shard
            .parse::<Shard>()
            .map_or((usize::MAX, usize::MAX), |s| (s.count, s.index))
    };
    shards.sort_by_key(order);
    Ok(shards)
}

/// `DIR/accounting.csv`: one row per case (`scope` = `case`) and per shard (`shard`) with wall
/// and CPU time (s).
pub fn accounting_csv(m: &Merged) -> String {
    let mut s = String::from("scope,name,shard,host,status,wall_seconds,cpu_seconds,rom\n");
    let num = |v: Option<f64>| v.map_or(String::new(), |x| format!("{x:.3}"));
    for (r, rec) in m.results.iter().zip(&m.records) {
        let shard = rec
            .as_ref()
            .and_then(|r| r.shard.clone())
            .unwrap_or_default();
        let host = rec.as_ref().map(|r| r.host.clone()).unwrap_or_default();
        s += &format!(
            "case,{},{shard},{host},{},{},{},{}\n",
            r.job.name,
            r.status(),
            if r.missing {
                String::new()
            } else {
                format!("{:.3}", r.wall_seconds)
            },
            num(r.cpu_seconds),
            r.rom.unwrap_or("")
        );
    }
    for sh in &m.shards {
        s += &format!(
            "shard,{},{},{},{},{:.3},{},\n",
            sh.shard,
            sh.shard,
            sh.host,
            if sh.finished {
                "finished"
            } else {
                "unfinished"
            },
            sh.wall_seconds,
            num(sh.cpu_seconds)
        );
    }
    s
}

/// The printed accounting: per case and per shard wall and CPU time.
pub fn accounting_table(m: &Merged) -> String {
    let width = m
        .results
        .iter()
        .map(|r| r.job.name.chars().count())
        .max()
        .unwrap_or(4)
        .max(5);
    let num = |v: Option<f64>| v.map_or("-".to_string(), |x| format!("{x:.2}"));
    let mut s = format!(
        "{:<width$} {:>7} {:>12} {:>8} {:>8} {:>7}\n",
        "case", "shard", "host", "wall (s)", "CPU (s)", "ROM"
    );
    for (r, rec) in m.results.iter().zip(&m.records) {
        let (shard, host) = rec.as_ref().map_or(("-".into(), "-".into()), |x| {
            (x.shard.clone().unwrap_or("-".into()), x.host.clone())
        });
        let wall = if r.missing {
            "-".into()
        } else {
            format!("{:.2}", r.wall_seconds)
        };
        s += &format!(
            "{:<width$} {:>7} {:>12} {:>8} {:>8} {:>7}\n",
            r.job.name,
            shard,
            host,
            wall,
            num(r.cpu_seconds),
            r.rom.unwrap_or("-")
        );
    }
    if !m.shards.is_empty() {
        s += &format!(
            "{:>7} {:>12} {:>14} {:>6} {:>7} {:>8} {:>8}\n",
            "shard", "host", "slurm job", "cases", "skipped", "wall (s)", "CPU (s)"
        );
        for sh in &m.shards {
            s += &format!(
                "{:>7} {:>12} {:>14} {:>6} {:>7} {:>8.2} {:>8}{}\n",
                sh.shard,
                sh.host,
                sh.slurm_job.as_deref().unwrap_or("-"),
                sh.cases.len(),
                sh.skipped.len(),
                sh.wall_seconds,
                num(sh.cpu_seconds),
                if sh.finished {
                    ""
                } else {
                    "  (did not finish)"
                }
            );
        }
    }
    s
}

/// `nlrom batch merge DIR`: writes `DIR/summary.csv` and `DIR/accounting.csv`, prints the
/// summary table and the accounting (or one JSON object); exit status 1 when a case is missing
/// or failed.
pub fn merge_command(dir: &Path, rep: &Reporter, as_json: bool) -> Result<()> {
    let m = gather(dir)?;
    let csv_path = dir.join("summary.csv");
    write_shared(&csv_path, summary_csv(&m.results).as_bytes())?;
    let acc_path = dir.join("accounting.csv");
    write_shared(&acc_path, accounting_csv(&m).as_bytes())?;
    let names = |status: &str| -> Vec<String> {
        m.results
            .iter()
            .filter(|r| r.status() == status)
            .map(|r| r.job.name.clone())
            .collect()
    };
    let case_wall = m.results.iter().fold(0.0, |s, r| s + r.wall_seconds);
    let shard_cpu = m
        .shards
        .iter()
        .filter_map(|s| s.cpu_seconds)
        .fold(0.0, |a, b| a + b);
    rep.info(&format!(
        "{} cases in the manifest of {}, {} shard records",
        m.results.len(),
        dir.display(),
        m.shards.len()
    ));
    if as_json {
        let jobs: Vec<Value> = m
            .results
            .iter()
            .zip(&m.records)
            .map(|(r, rec)| {
                let mut j = job_json(r);
                j["shard"] = json!(rec.as_ref().and_then(|x| x.shard.clone()));
                j["host"] = json!(rec.as_ref().map(|x| x.host.clone()));
                j
            })
            .collect();
        println!(
            "{}",
            json!({
                "jobs": jobs,
                "shards": m.shards,
                "missing": names("missing"),
                "failed": names("failed"),
                "summary_csv": csv_path.display().to_string(),
                "accounting_csv": acc_path.display().to_string(),
                "case_wall_seconds": case_wall,
                "shard_cpu_seconds": shard_cpu,
            })
        );
    } else {
        print!("{}", summary_table(&m.results));
        print!("{}", accounting_table(&m));
        println!(
            "{} cases: {} ok, {} failed, {} missing; {:.2} s of case wall time, {:.2} s of shard CPU time; summary written to {}",
            m.results.len(),
            names("ok").len(),
            names("failed").len(),
            names("missing").len(),
            case_wall,
            shard_cpu,
            csv_path.display()
        );
        if !names("missing").is_empty() || !names("failed").is_empty() {
            println!("run the missing and failed cases again with --resume");
        }
    }
    fail_if_any_failed(&m.results, &csv_path)
}
