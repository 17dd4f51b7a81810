//! `nlrom batch --slurm --submit` on a real single-node Slurm cluster (Debian's `slurm-wlm` and
//! `munge`): munged, slurmctld and slurmd run in the foreground as the current user from a
//! temporary directory (configuration, state, spool, logs; `proctrack/linuxproc`, `task/none`,
//! no cgroups, no accounting daemon) and are stopped when the test ends, also when it fails.
//!
//! Sixteen matrix cases go to four array tasks; `nlrom batch merge` must give the summary of the
//! local `nlrom batch` of the same cases, number for number. Then one array task is cancelled
//! while it runs: merge lists its unfinished cases as missing, and `--slurm --resume --submit`
//! resubmits only that task and completes the batch, again equal to the local one.
//!
//! Without the Slurm binaries the test is skipped with a message, except under CI (`CI` set),
//! where `.ci/run` installs them and their absence is a failure.
#![cfg(target_os = "linux")]

mod support;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

use serde_json::Value;
use support::batch::{chain_case, summary_numbers};
use support::cli::{nlrom, root, stderr};

/// The programs the test needs.
const PROGRAMS: &[&str] = &[
    "munged",
    "slurmctld",
    "slurmd",
    "sbatch",
    "squeue",
    "scancel",
    "sinfo",
];

/// `name` on the PATH or in /usr/sbin, /sbin (daemons are there on Debian).
fn find(name: &str) -> Option<PathBuf> {
    let path = std::env::var_os("PATH").unwrap_or_default();
    std::env::split_paths(&path)
        .chain(["/usr/sbin", "/sbin", "/usr/bin"].map(PathBuf::from))
        .map(|d| d.join(name))
        .find(|p| p.is_file())
}

/// The current user's name.
fn user() -> String {
    let o = Command::new("id").arg("-un").output().expect("id -un");
    String::from_utf8_lossy(&o.stdout).trim().to_string()
}

/// A free TCP port on 127.0.0.1.
fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

/// A single-node cluster in a temporary directory; dropping it cancels the jobs and stops the
/// daemons.
struct Cluster {
    dir: PathBuf,
    conf: PathBuf,
    daemons: Vec<(&'static str, Child)>,
}

impl Cluster {
    fn start(dir: &Path) -> Cluster {
        for sub in ["munge", "state", "spool", "log"] {
            std::fs::create_dir_all(dir.join(sub)).unwrap();
        }
        let mut cluster = Cluster {
            dir: dir.to_path_buf(),
            conf: dir.join("slurm.conf"),
            daemons: Vec::new(),
        };
        // munge: a fresh key readable by the current user only
        let key = dir.join("munge/munge.key");
        let mut bytes = vec![0u8; 1024];
        use std::io::Read;
        std::fs::File::open("/dev/urandom")
            .unwrap()
            .read_exact(&mut bytes)
            .unwrap();
        std::fs::write(&key, &bytes).unwrap();
        use std::os::unix::fs::PermissionsExt;
        std::fs::set_permissions(&key, std::fs::Permissions::from_mode(0o400)).unwrap();
        std::fs::set_permissions(dir.join("munge"), std::fs::Permissions::from_mode(0o700))
            .unwrap();
        let socket = dir.join("munge.socket");
        let munge = dir.join("munge");
        cluster.spawn(
            "munged",
            Command::new(find("munged").unwrap())
                .arg("--foreground")
                .arg("--force")
                .arg(format!("--socket={}", socket.display()))
                .arg(format!("--key-file={}", key.display()))
                .arg(format!("--pid-file={}", munge.join("munged.pid").display()))
                .arg(format!("--log-file={}", munge.join("munged.log").display()))
                .arg(format!(
                    "--seed-file={}",
                    munge.join("munged.seed").display()
                )),
        );
        cluster.wait_for("the munge socket", 20, || socket.exists());

        let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
            .unwrap()
            .trim()
            .split('.')
            .next()
            .unwrap()
            .to_string();
        let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
        let d = dir.display();
        let u = user();
        let conf = format!(
            "ClusterName=nlromtest
SlurmctldHost={host}(127.0.0.1)
SlurmUser={u}
SlurmdUser={u}
SlurmctldPort={}
SlurmdPort={}
AuthType=auth/munge
CredType=cred/munge
AuthInfo=socket={}
StateSaveLocation={d}/state
SlurmdSpoolDir={d}/spool
SlurmctldPidFile={d}/slurmctld.pid
SlurmdPidFile={d}/slurmd.pid
SlurmctldLogFile={d}/log/slurmctld.log
SlurmdLogFile={d}/log/slurmd.log
ProctrackType=proctrack/linuxproc
TaskPlugin=task/none
JobAcctGatherType=jobacct_gather/none
AccountingStorageType=accounting_storage/none
JobCompType=jobcomp/none
SchedulerType=sched/builtin
SelectType=select/cons_tres
SelectTypeParameters=CR_Core
MpiDefault=none
SwitchType=switch/none
ReturnToService=2
KillWait=2
MinJobAge=600
NodeName={host} NodeAddr=127.0.0.1 CPUs={cpus} State=UNKNOWN
PartitionName=test Nodes=ALL Default=YES MaxTime=INFINITE State=UP
",
            free_port(),
            free_port(),
            socket.display()
        );
        std::fs::write(&cluster.conf, conf).unwrap();
        let c = cluster.conf.clone();
        cluster.spawn(
            "slurmctld",
            Command::new(find("slurmctld").unwrap())
                .args(["-D", "-i", "-f"])
                .arg(&c),
        );
        cluster.spawn(
            "slurmd",
            Command::new(find("slurmd").unwrap())
                .args(["-D", "-f"])
                .arg(&c)
                .args(["-N", &host]),
        );
        cluster.wait_for("the node to be idle", 60, || {
            let o = cluster.run("sinfo", &["-h", "-o", "%T"]);
            String::from_utf8_lossy(&o.stdout).trim() == "idle"
        });
        cluster
    }

    /// Starts a daemon with its output in `log/<name>.out`.
    fn spawn(&mut self, name: &'static str, cmd: &mut Command) {
        let out = std::fs::File::create(self.dir.join(format!("log/{name}.out"))).unwrap();
        let child = cmd
            .env("SLURM_CONF", &self.conf)
            .stdin(Stdio::null())
            .stdout(out.try_clone().unwrap())
            .stderr(out)
            .spawn()
            .unwrap_or_else(|e| panic!("cannot start {name}: {e}"));
        self.daemons.push((name, child));
    }

    /// A Slurm client command with this cluster's configuration.
    fn run(&self, program: &str, args: &[&str]) -> Output {
        Command::new(find(program).unwrap())
            .args(args)
            .env("SLURM_CONF", &self.conf)
            .output()
            .unwrap()
    }

    /// `nlrom ARGS` with this cluster's configuration (so that `--submit` reaches it).
    fn nlrom(&self, args: &[&str]) -> Output {
        Command::new(env!("CARGO_BIN_EXE_nlrom"))
            .args(args)
            .current_dir(root())
            .env("SLURM_CONF", &self.conf)
            .output()
            .unwrap()
    }

    /// Polls `ready` every 0.1 s for up to `seconds`; panics with the daemons' logs.
    fn wait_for(&self, what: &str, seconds: u64, mut ready: impl FnMut() -> bool) {
        let start = Instant::now();
        while !ready() {
            if start.elapsed() > Duration::from_secs(seconds) {
                panic!(
                    "timed out after {seconds} s waiting for {what}\n{}",
                    self.logs()
                );
            }
            std::thread::sleep(Duration::from_millis(100));
        }
    }

    /// Waits until every array task of job `id` has ended (no task pending, running,
    /// completing, configuring or suspended).
    fn wait_job(&self, id: &str, seconds: u64) {
        self.wait_for(&format!("job {id} to end"), seconds, || {
            let o = self.run(
                "squeue",
                &["-h", &format!("--jobs={id}"), "-t", "all", "-o", "%T"],
            );
            o.status.success()
                && String::from_utf8_lossy(&o.stdout)
                    .split_whitespace()
                    .all(|s| {
                        !matches!(
                            s,
                            "PENDING"
                                | "RUNNING"
                                | "COMPLETING"
                                | "CONFIGURING"
                                | "SUSPENDED"
                                | "REQUEUED"
                                | "RESIZING"
                                | "SIGNALING"
                                | "STAGE_OUT"
                                | "STOPPED"
                        )
                    })
        });
    }

    /// The tails of the daemons' logs.
    fn logs(&self) -> String {
        let mut s = String::new();
        for f in [
            "log/munged.out",
            "log/slurmctld.out",
            "log/slurmd.out",
            "log/slurmctld.log",
            "log/slurmd.log",
        ] {
            let text = std::fs::read_to_string(self.dir.join(f)).unwrap_or_default();
            let lines: Vec<&str> = text.lines().collect();
            s += &format!(
                "--- {f}\n{}\n",
                lines[lines.len().saturating_sub(15)..].join("\n")
            );
        }
        s
    }
}

impl Drop for Cluster {
    fn drop(&mut self) {
        // cancel what is left, give the steps a moment to end, then stop the daemons, newest first
        let o = self.run("squeue", &["-h", "-o", "%A"]);
        for id in String::from_utf8_lossy(&o.stdout).split_whitespace() {
            let _ = self.run("scancel", &[id]);
        }
        let start = Instant::now();
        while start.elapsed() < Duration::from_secs(10) {
            let o = self.run("squeue", &["-h"]);
            if String::from_utf8_lossy(&o.stdout).trim().is_empty() {
                break;
            }
            std::thread::sleep(Duration::from_millis(200));
        }
        while let Some((name, mut child)) = self.daemons.pop() {
            // SAFETY: kill(2) on the pid of a child this process started and has not reaped
            unsafe {
                libc::kill(child.id() as libc::pid_t, libc::SIGTERM);
            }
            let start = Instant::now();
            loop {
                match child.try_wait() {
                    Ok(Some(_)) => break,
                    _ if start.elapsed() > Duration::from_secs(5) => {
                        eprintln!("{name} did not stop on SIGTERM; killing it");
                        let _ = child.kill();
                        let _ = child.wait();
                        break;
                    }
                    _ => std::thread::sleep(Duration::from_millis(50)),
                }
            }
        }
    }
}

/// The chain of `cases/chain3_jenkins.toml` with slip force n0 of element 1 and force `f` (N),
/// in steps of at most 0.01 rad/s (about 1500 points, a fraction of a second each: long enough
/// to cancel an array task between two of its cases).
fn chain(dir: &Path, name: &str, n0: f64, f: f64) -> PathBuf {
    let force = format!("force = [{f}]");
    chain_case(
        dir,
        name,
        n0,
        &[
            (
                "step_rad_s = 0.02",
                "step_rad_s = 0.004\nmax_step_rad_s = 0.01",
            ),
            ("force = [0.5]", &force),
        ],
    )
}

fn json(o: &Output) -> Value {
    serde_json::from_slice(&o.stdout)
        .unwrap_or_else(|e| panic!("{e}: {}\n{}", String::from_utf8_lossy(&o.stdout), stderr(o)))
}

/// The record of shard `name` (`I/N`) in a merge report.
fn shard<'a>(merged: &'a Value, name: &str) -> &'a Value {
    merged["shards"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["shard"] == name)
        .unwrap_or_else(|| panic!("no shard {name} in {merged}"))
}

#[test]
fn a_job_array_on_a_single_node_cluster_equals_the_local_batch() {
    let missing: Vec<&str> = PROGRAMS
        .iter()
        .copied()
        .filter(|p| find(p).is_none())
        .collect();
    if !missing.is_empty() {
        let ci = std::env::var("CI").is_ok_and(|v| !v.is_empty() && v != "false");
        assert!(
            !ci,
            "CI must run the Slurm test, but {missing:?} are missing: .ci/run installs slurm-wlm and munge"
        );
        eprintln!(
            "SKIPPED: the Slurm cluster test needs {missing:?} (Debian: apt-get install slurm-wlm munge)"
        );
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let cases_dir = dir.path().join("cases");
    std::fs::create_dir(&cases_dir).unwrap();
    // 16 cases: 4 slip forces × 4 excitation levels
    let cases: Vec<String> = (0..16)
        .map(|i| {
            let n0 = 0.1 + 0.05 * (i % 4) as f64;
            let f = 0.3 + 0.1 * (i / 4) as f64;
            let path = chain(&cases_dir, &format!("c{i:02}"), n0, f);
            path.display().to_string()
        })
        .collect();
    let with_cases = |head: &[&str]| -> Vec<String> {
        head.iter()
            .map(|s| s.to_string())
            .chain(cases.iter().cloned())
            .collect()
    };

    // the reference: the local batch, one case at a time
    let local = dir.path().join("local");
    let args = with_cases(&["batch", "--out", local.to_str().unwrap(), "-q"]);
    let t = Instant::now();
    let o = nlrom(&args.iter().map(String::as_str).collect::<Vec<_>>());
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let local_seconds = t.elapsed().as_secs_f64();
    let expected = summary_numbers(&local.join("summary.csv"));
    assert_eq!(expected.len(), 16);
    assert!(expected.iter().all(|r| r[3] == "ok"), "{expected:?}");
    let distinct: std::collections::BTreeSet<&String> = expected.iter().map(|r| &r[5]).collect();
    assert_eq!(distinct.len(), 16, "every case has its own peak amplitude");

    let cluster = Cluster::start(&dir.path().join("slurm"));
    // `nlrom batch CASES --out OUT --slurm --array-size 4 --submit [--resume]`: the report
    let submit = |out: &Path, resume: bool| -> Value {
        let mut args = with_cases(&[
            "batch",
            "--out",
            out.to_str().unwrap(),
            "--slurm",
            "--array-size",
            "4",
            "--submit",
            "--json",
        ]);
        if resume {
            args.insert(1, "--resume".into());
        }
        let o = cluster.nlrom(&args.iter().map(String::as_str).collect::<Vec<_>>());
        assert_eq!(
            o.status.code(),
            Some(0),
            "{}\n{}",
            stderr(&o),
            cluster.logs()
        );
        json(&o)
    };
    // `nlrom batch merge OUT --json`: exit status and report
    let merge = |out: &Path| -> (Option<i32>, Value) {
        let o = cluster.nlrom(&["batch", "merge", out.to_str().unwrap(), "--json", "-q"]);
        (o.status.code(), json(&o))
    };

    // 1. the whole batch as a job array of 4 tasks
    let out = dir.path().join("cluster");
    let t = Instant::now();
    let report = submit(&out, false);
    let job = report["job_id"].as_str().unwrap().to_string();
    assert_eq!(report["array"], "1-4");
    cluster.wait_job(&job, 300);
    let cluster_seconds = t.elapsed().as_secs_f64();
    let (code, merged) = merge(&out);
    assert_eq!(
        code,
        Some(0),
        "{merged}\nshard 1 log:\n{}",
        std::fs::read_to_string(out.join("logs/shard-1.log")).unwrap_or_default()
    );
    assert_eq!(summary_numbers(&out.join("summary.csv")), expected);
    assert_eq!(merged["shards"].as_array().unwrap().len(), 4);
    for i in 1..=4 {
        let s = shard(&merged, &format!("{i}/4"));
        assert_eq!(s["finished"], true);
        assert_eq!(s["cases"].as_array().unwrap().len(), 4);
        assert_eq!(s["slurm_job"], format!("{job}_{i}"));
        assert!(s["cpu_seconds"].as_f64().unwrap() > 0.0);
        assert!(out.join(format!("logs/shard-{i}.log")).is_file());
    }
    eprintln!(
        "16 cases: local batch {local_seconds:.1} s, job array of 4 tasks {cluster_seconds:.1} s (submit to end)"
    );

    // 2. cancel array task 1 once its first case is done; merge reports the rest missing
    let out = dir.path().join("cancelled");
    let job = submit(&out, false)["job_id"].as_str().unwrap().to_string();
    // shard 1 holds the cases at positions 0, 4, 8, 12
    cluster.wait_for("the first case of shard 1", 120, || {
        out.join("cases/c00.json").is_file()
    });
    let o = cluster.run("scancel", &[&format!("{job}_1")]);
    assert!(o.status.success(), "{}", stderr(&o));
    cluster.wait_job(&job, 300);
    let (code, merged) = merge(&out);
    assert_eq!(code, Some(1), "{merged}");
    let missing: Vec<&str> = merged["missing"]
        .as_array()
        .unwrap()
        .iter()
        .map(|m| m.as_str().unwrap())
        .collect();
    assert!(
        !missing.is_empty(),
        "array task 1 finished all its cases before it was cancelled: nothing to resume"
    );
    for m in &missing {
        assert!(["c04", "c08", "c12"].contains(m), "{m} is not in shard 1");
    }
    assert_eq!(shard(&merged, "1/4")["finished"], false);
    let message = merged["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .find(|j| j["case"] == missing[0])
        .unwrap()["error"]
        .as_str()
        .unwrap()
        .to_string();
    assert!(message.contains("shard 1/4"), "{message}");

    // 3. --resume resubmits array task 1 only, and the batch is complete
    let report = submit(&out, true);
    assert_eq!(report["array"], "1");
    cluster.wait_job(report["job_id"].as_str().unwrap(), 300);
    let (code, merged) = merge(&out);
    assert_eq!(code, Some(0), "{merged}");
    assert!(merged["missing"].as_array().unwrap().is_empty());
    assert_eq!(summary_numbers(&out.join("summary.csv")), expected);
    let s1 = shard(&merged, "1/4");
    assert_eq!(s1["finished"], true);
    assert_eq!(s1["cases"].as_array().unwrap().len(), missing.len());
    assert_eq!(s1["skipped"].as_array().unwrap().len(), 4 - missing.len());
    eprintln!(
        "cancelled array task 1 with {} of its 4 cases unfinished; --resume ran them",
        missing.len()
    );
}
