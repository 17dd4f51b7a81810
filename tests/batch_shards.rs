//! `nlrom batch` beyond one process: shards (`--shard I/N`) gathered by `nlrom batch merge`
//! equal the local batch of the same cases number for number; `--resume` runs only what is
//! missing or failed; the content-addressed ROM cache shared by four processes reducing the same
//! model at once leaves one valid ROM file and four equal results; the `--slurm` script.

mod support;

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use nlrom::output::{read_results, read_rom};
use serde_json::Value;
use support::batch::{chain_case, summary_numbers};
use support::cli::{nlrom, root, stderr};

/// The chain of `cases/chain3_jenkins.toml` with H = 3, N_t = 64 and slip force n0 of element 1.
fn chain(dir: &Path, name: &str, n0: f64) -> PathBuf {
    chain_case(
        dir,
        name,
        n0,
        &[
            ("harmonics = 7", "harmonics = 3"),
            ("time_samples = 1024", "time_samples = 64"),
        ],
    )
}

fn args<'a>(head: &[&'a str], cases: &'a [PathBuf]) -> Vec<&'a str> {
    let mut v = head.to_vec();
    v.extend(cases.iter().map(|c| c.to_str().unwrap()));
    v
}

/// Seven cases in 3 shards (sizes 3, 2, 2), each shard run by its own process, merged: the
/// summary equals the local batch's (all numbers, same digits); a shard with more shards than
/// cases is empty; a lost record is reported missing, and `--resume` runs that case alone.
#[test]
fn shards_merge_into_the_local_batch() {
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<PathBuf> = (0..7)
        .map(|i| chain(dir.path(), &format!("c{i}"), 0.05 + 0.05 * i as f64))
        .collect();
    let local = dir.path().join("local");
    let o = nlrom(&args(
        &["batch", "--out", local.to_str().unwrap(), "-q"],
        &cases,
    ));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let expected = summary_numbers(&local.join("summary.csv"));
    assert_eq!(expected.len(), 7);
    assert!(expected.iter().all(|r| r[3] == "ok"), "{expected:?}");

    let sharded = dir.path().join("sharded");
    let out = sharded.to_str().unwrap();
    let mut sizes = Vec::new();
    for i in 1..=3 {
        let shard = format!("{i}/3");
        let o = nlrom(&args(
            &["batch", "--out", out, "--shard", &shard, "--json", "-q"],
            &cases,
        ));
        assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
        let report: Value = serde_json::from_slice(&o.stdout).unwrap();
        let names: Vec<&str> = report["jobs"]
            .as_array()
            .unwrap()
            .iter()
            .map(|j| j["case"].as_str().unwrap())
            .collect();
        sizes.push(names.len());
        // case p goes to shard p mod 3 + 1
        for n in &names {
            let p: usize = n[1..].parse().unwrap();
            assert_eq!(p % 3 + 1, i, "{n} in shard {i}");
        }
        assert!(sharded.join(format!("shards/{i}-of-3.csv")).is_file());
    }
    assert_eq!(sizes, [3, 2, 2]);
    let o = nlrom(&["batch", "merge", out, "--json", "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(summary_numbers(&sharded.join("summary.csv")), expected);
    let report: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["shards"].as_array().unwrap().len(), 3);
    assert!(report["missing"].as_array().unwrap().is_empty());
    for j in report["jobs"].as_array().unwrap() {
        // one case at a time: CPU time per case is measured
        assert!(j["cpu_seconds"].as_f64().unwrap() > 0.0, "{j}");
        assert!(j["wall_seconds"].as_f64().unwrap() > 0.0, "{j}");
    }
    let accounting = std::fs::read_to_string(sharded.join("accounting.csv")).unwrap();
    assert_eq!(
        accounting
            .lines()
            .filter(|l| l.starts_with("case,"))
            .count(),
        7
    );
    assert_eq!(
        accounting
            .lines()
            .filter(|l| l.starts_with("shard,"))
            .count(),
        3
    );

    // a lost case: merge lists it as missing (exit 1); --resume runs it alone
    std::fs::remove_file(sharded.join("cases/c4.json")).unwrap();
    let o = nlrom(&["batch", "merge", out, "-q"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        stderr(&o).contains("1 of 7 jobs failed or are missing"),
        "{}",
        stderr(&o)
    );
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(table.contains("c4 (sweep -): no record"), "{table}");
    let o = nlrom(&args(
        &["batch", "--out", out, "--resume", "--json", "-q"],
        &cases,
    ));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["skipped"].as_array().unwrap().len(), 6);
    assert_eq!(summary_numbers(&sharded.join("summary.csv")), expected);
    let o = nlrom(&["batch", "merge", out, "-q"]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert_eq!(summary_numbers(&sharded.join("summary.csv")), expected);

    // more shards than cases: shard 9 of 9 is empty
    let o = nlrom(&args(
        &["batch", "--out", out, "--shard", "9/9", "-q"],
        &cases,
    ));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    // other cases into the same directory are refused
    let o = nlrom(&args(
        &["batch", "--out", out, "--shard", "1/2", "-q"],
        &cases[..3],
    ));
    assert_eq!(o.status.code(), Some(2));
    assert!(
        stderr(&o).contains("batch of other cases"),
        "{}",
        stderr(&o)
    );
    // bad shard specifications
    let o = nlrom(&args(&["batch", "--out", out, "--shard", "4/3"], &cases));
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("expected I/N"), "{}", stderr(&o));
    let o = nlrom(&["batch", "merge", dir.path().to_str().unwrap()]);
    assert_eq!(o.status.code(), Some(2));
    assert!(stderr(&o).contains("no batch manifest"), "{}", stderr(&o));
}

/// The demo sector over a short frequency range, its mesh read from the repository.
fn sector_case(dir: &Path, name: &str) -> PathBuf {
    let text = std::fs::read_to_string(root().join("cases/demo.toml"))
        .unwrap()
        .replace("../meshes/", &format!("{}/meshes/", root().display()))
        .replace("end_hz = 175.0", "end_hz = 160.0")
        .replace("step_hz = 2.0", "step_hz = 2.5");
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// Four processes (one shard each) reduce the same sector model at the same time into one
/// shared ROM cache: one ROM file is left (no temporary file), it reads back with the case's
/// key, and the four results are equal point for point.
#[test]
fn four_processes_share_one_rom() {
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<PathBuf> = ["a", "b", "c", "d"]
        .iter()
        .map(|n| sector_case(dir.path(), n))
        .collect();
    let out = dir.path().join("out");
    let cache = dir.path().join("cache");
    let children: Vec<_> = (1..=4)
        .map(|i| {
            let mut cmd = Command::new(env!("CARGO_BIN_EXE_nlrom"));
            cmd.current_dir(root())
                .args(["batch", "--out", out.to_str().unwrap()])
                .args(["--rom-cache", cache.to_str().unwrap()])
                .args(["--shard", &format!("{i}/4"), "--json", "-q"])
                .args(&cases)
                .stdout(Stdio::piped())
                .stderr(Stdio::piped());
            cmd.spawn().unwrap()
        })
        .collect();
    let reports: Vec<Value> = children
        .into_iter()
        .map(|c| {
            let o = c.wait_with_output().unwrap();
            assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
            serde_json::from_slice(&o.stdout).unwrap()
        })
        .collect();
    let files: Vec<String> = std::fs::read_dir(&cache)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    assert_eq!(files.len(), 1, "{files:?}");
    assert!(files[0].ends_with(".rom.h5"), "{files:?}");
    let rom = read_rom(&cache.join(&files[0])).unwrap();
    assert_eq!(format!("{}.rom.h5", rom.key), files[0]);
    let origins: Vec<&str> = reports
        .iter()
        .map(|r| r["jobs"][0]["rom"].as_str().unwrap())
        .collect();
    // the first to publish "reduced"; the others read its file (raced or reused)
    assert_eq!(
        origins.iter().filter(|o| **o == "reduced").count(),
        1,
        "{origins:?}"
    );
    let first = read_results(&out.join("a.h5")).unwrap();
    assert!(first.frfs[0].points.len() > 3);
    for name in ["b", "c", "d"] {
        let other = read_results(&out.join(format!("{name}.h5"))).unwrap();
        assert_eq!(other.frfs[0].points, first.frfs[0].points, "{name}");
    }
    eprintln!("ROM origins of the four processes: {origins:?}");
}

/// `--slurm` without `--submit` writes the job array script: the array, the CPUs, the shard
/// command with absolute paths; `--resume` lists only the shards with missing cases, or says
/// that nothing is left.
#[test]
fn the_slurm_script_and_its_resume() {
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<PathBuf> = (0..5)
        .map(|i| chain(dir.path(), &format!("s{i}"), 0.1 + 0.05 * i as f64))
        .collect();
    let out = dir.path().join("out");
    let o_str = out.to_str().unwrap();
    let head = [
        "batch",
        "--out",
        o_str,
        "--slurm",
        "--array-size",
        "2",
        "--cpus",
        "3",
        "--partition",
        "short",
        "--time",
        "0:10:00",
        "--json",
    ];
    let o = nlrom(&args(&head, &cases));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["array"], "1-2");
    assert_eq!(report["cases"], 5);
    assert!(report["job_id"].is_null());
    let script = std::fs::read_to_string(out.join("slurm/nlrom-batch.sh")).unwrap();
    for line in [
        "#SBATCH --array=1-2",
        "#SBATCH --cpus-per-task=3",
        "#SBATCH --partition=short",
        "#SBATCH --time=0:10:00",
        &format!("#SBATCH --output={o_str}/logs/shard-%a.log"),
        &format!("batch --out '{o_str}' --rom-cache '{o_str}/rom-cache'"),
        "--shard \"${SLURM_ARRAY_TASK_ID}/2\"",
    ] {
        assert!(script.contains(line), "{line} not in\n{script}");
    }
    // the script's command runs a shard: shard 2 of 2 (cases s1, s3) as array task 2 would
    let o = Command::new("bash")
        .arg(out.join("slurm/nlrom-batch.sh"))
        .env("SLURM_ARRAY_TASK_ID", "2")
        .env("SLURM_CPUS_PER_TASK", "1")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    assert!(out.join("cases/s1.json").is_file() && out.join("cases/s3.json").is_file());
    assert!(!out.join("cases/s0.json").exists());
    // --resume: only shard 1 has work left
    let mut head = head.to_vec();
    head.push("--resume");
    let o = nlrom(&args(&head, &cases));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["array"], "1");
    let o = Command::new("bash")
        .arg(out.join("slurm/nlrom-batch.sh"))
        .env("SLURM_ARRAY_TASK_ID", "1")
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let o = nlrom(&args(&head, &cases));
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let report: Value = serde_json::from_slice(&o.stdout).unwrap();
    assert!(report["script"].is_null(), "{report}");
    // --submit without sbatch on the PATH is bad input naming sbatch
    let o = Command::new(env!("CARGO_BIN_EXE_nlrom"))
        .args(["batch", "--out", o_str, "--slurm", "--submit"])
        .args(&cases)
        .env("PATH", dir.path())
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2), "{}", stderr(&o));
    assert!(
        stderr(&o).contains("`sbatch` is not on the PATH"),
        "{}",
        stderr(&o)
    );
    // Slurm options need --slurm
    let o = nlrom(&args(&["batch", "--partition", "x"], &cases));
    assert_eq!(o.status.code(), Some(2));
}
