//! `nlrom batch ... --slurm`: a Slurm job array that runs the batch, one shard per array task.
//!
//! The script (`DIR/slurm/nlrom-batch.sh`) has one `#SBATCH` line per setting (job name, array
//! `1-N`, CPUs per task, partition, time limit, log file `DIR/logs/shard-%a.log`) and runs, in
//! the directory where it was written,
//! `nlrom batch --shard $SLURM_ARRAY_TASK_ID/N --jobs $SLURM_CPUS_PER_TASK --resume INPUTS...`
//! with absolute paths for the executable, the output directory and the ROM cache, so every
//! node of the cluster finds them on the shared file system. `--resume` in the tasks makes a
//! requeued or resubmitted task skip the cases it finished. With `--submit` the script goes to
//! `sbatch --parsable` and the job id is printed; `nlrom batch merge DIR` gathers the results.
//! With `--resume`, the array holds only the shards that still have a missing or failed case.

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::json;

use super::records::{write_shared, Manifest};
use super::shard::Shard;
use super::{check_manifest, check_options, is_done, jobs_of, start_new_batch, BatchOptions};
use crate::commands::progress::Reporter;
use crate::error::{Error, Result};

/// The array size when `--array-size` is not given: one shard per case up to this many.
pub const DEFAULT_ARRAY_LIMIT: usize = 100;

/// The Slurm settings of `nlrom batch --slurm`.
#[derive(Clone, Debug, Default)]
pub struct SlurmOptions {
    /// Number of array tasks (shards); `None`: one per case, at most [`DEFAULT_ARRAY_LIMIT`].
    pub array_size: Option<usize>,
    /// `#SBATCH --partition`.
    pub partition: Option<String>,
    /// `#SBATCH --time` (Slurm's formats, e.g. `2:00:00`).
    pub time: Option<String>,
    /// `#SBATCH --cpus-per-task`: also the `--jobs` of each task.
    pub cpus: usize,
    /// Submit the script with `sbatch`.
    pub submit: bool,
}

/// What `--slurm` wrote (and submitted).
#[derive(Clone, Debug)]
pub struct SlurmPlan {
    /// The script.
    pub script: PathBuf,
    /// Number of shards N.
    pub shards: usize,
    /// The array indices (shards) to run, Slurm's syntax (`1-4`, `2,4`).
    pub array: String,
    /// Number of cases of the batch.
    pub cases: usize,
}

/// A shell word: `s` in single quotes (a quote inside as `'\''`).
pub fn shell_quote(s: &str) -> String {
    format!("'{}'", s.replace('\'', "'\\''"))
}

/// The indices (increasing) in Slurm's array syntax: runs of consecutive values as `a-b`.
pub fn array_spec(indices: &[usize]) -> String {
    let mut parts = Vec::new();
    let mut i = 0;
    while i < indices.len() {
        let mut j = i;
        while j + 1 < indices.len() && indices[j + 1] == indices[j] + 1 {
            j += 1;
        }
        parts.push(if j == i {
            indices[i].to_string()
        } else {
            format!("{}-{}", indices[i], indices[j])
        });
        i = j + 1;
    }
    parts.join(",")
}

/// A `#SBATCH` value: non-empty, without white space, quotes or control characters.
fn sbatch_value(key: &str, v: &str) -> Result<String> {
    if v.is_empty()
        || v.chars()
            .any(|c| c.is_whitespace() || c.is_control() || c == '\'' || c == '"')
    {
        return Err(Error::input(format!(
            "--{key} {v:?}: give one word without spaces or quotes"
        )));
    }
    Ok(v.to_string())
}

fn absolute(p: &Path) -> Result<PathBuf> {
    std::path::absolute(p).map_err(|e| Error::io(p, e))
}

/// The job array script for `opts` (the inputs as given, relative to `cwd`), `shards` shards,
/// array indices `array`.
pub fn script_text(
    opts: &BatchOptions,
    slurm: &SlurmOptions,
    exe: &Path,
    cwd: &Path,
    shards: usize,
    array: &str,
) -> Result<String> {
    let out = absolute(&opts.out)?;
    let cache = absolute(&opts.rom_cache_dir())?;
    let q = |p: &Path| shell_quote(&p.display().to_string());
    let mut s = String::from("#!/bin/bash\n");
    s += "# nlrom batch as a Slurm job array: array task I runs shard I of the batch.\n";
    s +=
        "# Written by `nlrom batch --slurm`; adapt the #SBATCH lines to the cluster, submit with\n";
    s += &format!(
        "# `sbatch {}`, then gather the results with `nlrom batch merge {}`.\n",
        out.join("slurm/nlrom-batch.sh").display(),
        out.display()
    );
    s += "#SBATCH --job-name=nlrom-batch\n";
    s += &format!("#SBATCH --array={array}\n");
    s += &format!("#SBATCH --cpus-per-task={}\n", slurm.cpus);
    s += "#SBATCH --ntasks=1\n";
    if let Some(p) = &slurm.partition {
        s += &format!("#SBATCH --partition={}\n", sbatch_value("partition", p)?);
    }
    if let Some(t) = &slurm.time {
        s += &format!("#SBATCH --time={}\n", sbatch_value("time", t)?);
    }
    s += &format!(
        "#SBATCH --output={}\n",
        out.join("logs").join("shard-%a.log").display()
    );
    s += "set -eu\n";
    s += &format!("cd {}\n", q(cwd));
    s += &format!(
        "exec {} batch --out {} --rom-cache {} \\\n  --shard \"${{SLURM_ARRAY_TASK_ID}}/{shards}\" --jobs \"${{SLURM_CPUS_PER_TASK:-1}}\" --resume \\\n",
        q(exe),
        q(&out),
        q(&cache)
    );
    if let Some(t) = &opts.template {
        s += &format!("  --case {} \\\n", q(t));
    }
    s += "  --";
    for input in &opts.inputs {
        s += &format!(" \\\n  {}", q(input));
    }
    s.push('\n');
    Ok(s)
}

/// Writes the job array script of the batch (a new batch, or with `--resume` the shards that
/// still have work) and the manifest; `None` when `--resume` finds nothing to run.
pub fn write_script(
    opts: &BatchOptions,
    slurm: &SlurmOptions,
    rep: &Reporter,
) -> Result<Option<SlurmPlan>> {
    check_options(opts)?;
    if slurm.cpus == 0 {
        return Err(Error::input("--cpus 0: give at least 1 CPU per task"));
    }
    let jobs = jobs_of(&opts.inputs);
    let mut shards = slurm
        .array_size
        .unwrap_or(jobs.len().min(DEFAULT_ARRAY_LIMIT));
    if shards == 0 {
        return Err(Error::input("--array-size 0: give at least 1 array task"));
    }
    if shards > jobs.len() {
        rep.info(&format!(
            "--array-size {shards} > {} cases: {} array tasks",
            jobs.len(),
            jobs.len()
        ));
        shards = jobs.len();
    }
    std::fs::create_dir_all(&opts.out).map_err(|e| Error::io(&opts.out, e))?;
    let manifest = Manifest::new(&jobs, opts.template.as_deref(), Some(shards));
    let indices: Vec<usize> = if opts.resume {
        check_manifest(&opts.out, &manifest)?;
        let mut todo: Vec<usize> = jobs
            .iter()
            .enumerate()
            .filter(|(_, j)| !is_done(&opts.out, j))
            .map(|(p, _)| Shard::of_position(p, shards).index)
            .collect();
        todo.sort_unstable();
        todo.dedup();
        todo
    } else {
        start_new_batch(&opts.out, &manifest)?;
        (1..=shards).collect()
    };
    if indices.is_empty() {
        return Ok(None);
    }
    let logs = opts.out.join("logs");
    std::fs::create_dir_all(&logs).map_err(|e| Error::io(&logs, e))?;
    let array = array_spec(&indices);
    let exe = std::env::current_exe().map_err(|e| Error::io(Path::new("nlrom"), e))?;
    let cwd = std::env::current_dir().map_err(|e| Error::io(Path::new("."), e))?;
    let text = script_text(opts, slurm, &exe, &cwd, shards, &array)?;
    let script = opts.out.join("slurm").join("nlrom-batch.sh");
    write_shared(&script, text.as_bytes())?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        let _ = std::fs::set_permissions(&script, std::fs::Permissions::from_mode(0o755));
    }
    Ok(Some(SlurmPlan {
        script,
        shards,
        array,
        cases: jobs.len(),
    }))
}

/// Submits `script` with `sbatch --parsable`; returns the job id.
pub fn submit(script: &Path) -> Result<String> {
    let out = Command::new("sbatch")
        .arg("--parsable")
        .arg(script)
        .output()
        .map_err(|e| {
            if e.kind() == std::io::ErrorKind::NotFound {
                Error::input(format!(
                    "--submit: `sbatch` is not on the PATH (run on a Slurm login node, or submit {} there)",
                    script.display()
                ))
            } else {
                Error::io(Path::new("sbatch"), e)
            }
        })?;
    if !out.status.success() {
        return Err(Error::Compute(format!(
            "sbatch {} failed ({}): {}",
            script.display(),
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        )));
    }
    let stdout = String::from_utf8_lossy(&out.stdout);
    let id = stdout
        .lines()
        .next()
        .and_then(|l| l.split(';').next())
        .map(str::trim)
        .filter(|id| !id.is_empty())
        .ok_or_else(|| {
            Error::Compute(format!(
                "sbatch {} printed no job id: {stdout:?}",
                script.display()
            ))
        })?;
    Ok(id.to_string())
}

/// `nlrom batch ... --slurm`: writes the script, submits it with `--submit`, prints what to do
/// next (or one JSON object: `script`, `array`, `shards`, `cases`, `job_id`, `out`).
pub fn slurm_command(
    opts: &BatchOptions,
    slurm: &SlurmOptions,
    rep: &Reporter,
    as_json: bool,
) -> Result<()> {
    let Some(plan) = write_script(opts, slurm, rep)? else {
        if as_json {
            println!("{}", json!({"script": null, "job_id": null, "array": null}));
        } else {
            println!(
                "--resume: every case of {} is done; nothing to submit",
                opts.out.display()
            );
        }
        return Ok(());
    };
    let job_id = if slurm.submit {
        Some(submit(&plan.script)?)
    } else {
        None
    };
    if as_json {
        println!(
            "{}",
            json!({
                "script": plan.script.display().to_string(),
                "array": plan.array,
                "shards": plan.shards,
                "cases": plan.cases,
                "job_id": job_id,
                "out": opts.out.display().to_string(),
            })
        );
        return Ok(());
    }
    println!(
        "wrote {} ({} cases in {} shards; array {})",
        plan.script.display(),
        plan.cases,
        plan.shards,
        plan.array
    );
    match job_id {
        Some(id) => println!(
            "submitted job {id}; follow it with `squeue -j {id}`, then gather: nlrom batch merge {}",
            opts.out.display()
        ),
        None => println!(
            "submit it with `sbatch {}`, then gather: nlrom batch merge {}",
            plan.script.display(),
            opts.out.display()
        ),
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn array_specs_compress_runs() {
        assert_eq!(array_spec(&[1, 2, 3, 4]), "1-4");
        assert_eq!(array_spec(&[2, 4]), "2,4");
        assert_eq!(array_spec(&[1, 3, 4, 5, 8]), "1,3-5,8");
        assert_eq!(array_spec(&[7]), "7");
    }

    #[test]
    fn shell_words_are_quoted() {
        assert_eq!(shell_quote("a b"), "'a b'");
        assert_eq!(shell_quote("it's"), "'it'\\''s'");
    }

    #[test]
    fn the_script_runs_one_shard_per_array_task() {
        let mut opts = BatchOptions::new(
            vec![PathBuf::from("cases/a.toml"), PathBuf::from("my case.toml")],
            PathBuf::from("/scratch/out"),
        );
        opts.template = None;
        let slurm = SlurmOptions {
            array_size: Some(2),
            partition: Some("short".into()),
            time: Some("0:30:00".into()),
            cpus: 4,
            submit: false,
        };
        let s = script_text(
            &opts,
            &slurm,
            Path::new("/opt/nlrom"),
            Path::new("/home/u/study"),
            2,
            "1-2",
        )
        .unwrap();
        for line in [
            "#SBATCH --array=1-2\n",
            "#SBATCH --cpus-per-task=4\n",
            "#SBATCH --partition=short\n",
            "#SBATCH --time=0:30:00\n",
            "#SBATCH --output=/scratch/out/logs/shard-%a.log\n",
            "cd '/home/u/study'\n",
            "exec '/opt/nlrom' batch --out '/scratch/out' --rom-cache '/scratch/out/rom-cache'",
            "--shard \"${SLURM_ARRAY_TASK_ID}/2\" --jobs \"${SLURM_CPUS_PER_TASK:-1}\" --resume",
            "  'cases/a.toml' \\\n  'my case.toml'\n",
        ] {
            assert!(s.contains(line), "{line:?} not in\n{s}");
        }
        let bad = SlurmOptions {
            partition: Some("a b".into()),
            ..slurm
        };
        let e = script_text(&opts, &bad, Path::new("/x"), Path::new("/y"), 2, "1-2").unwrap_err();
        assert!(e.to_string().contains("--partition"), "{e}");
    }
}
