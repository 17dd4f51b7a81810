//! The speed comparison of Gastaldi & Berruti 2018 §6 / Fig. 8 on the demonstrator
//! (cases/damper.toml, 200 Hz, one period after the static start), all in one run:
//! 1. per scheme its steps and corrector iterations relative to standard Newmark;
//! 2. wall and CPU time per march, the schemes interleaved round-robin (so a changing machine load
//!    hits them alike), minimum over the rounds, and their ratios to standard Newmark — CPU time is
//!    the thread's on-CPU time from /proc/thread-self/schedstat (ns), which a loaded machine
//!    inflates far less than the wall time;
//! 3. criterion's wall-time estimates (`damper_200hz_one_period/<scheme>`).
//!
//! `cargo bench --bench march` — the printed table is the one of docs/performance.md, next to the paper's Fig. 8.

use std::path::Path;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion};
use nlrom::case::{Case, MarchScheme};
use nlrom::march::march;
use nlrom::problem::march_case::{case_march, CaseMarch};

/// Interleaved rounds of the timing table.
const ROUNDS: usize = 40;

fn setup(scheme: MarchScheme) -> CaseMarch {
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/cases/damper.toml"));
    let case = Case::load(path).expect("bundled damper case");
    let mut cm = case_march(&case, Some(scheme), &mut |_| {}).expect("damper march");
    cm.settings.periods = 1;
    cm
}

/// On-CPU time of the calling thread (s), `None` where /proc/thread-self/schedstat is missing.
fn thread_cpu_seconds() -> Option<f64> {
    let text = std::fs::read_to_string("/proc/thread-self/schedstat").ok()?;
    let ns: f64 = text.split_whitespace().next()?.parse().ok()?;
    Some(ns * 1e-9)
}

/// Minimum wall and CPU time (s) of one march per scheme over [`ROUNDS`] interleaved rounds.
fn timing_table(cases: &[(MarchScheme, CaseMarch)]) -> Vec<(f64, f64)> {
    let mut best = vec![(f64::INFINITY, f64::INFINITY); cases.len()];
    for _ in 0..ROUNDS {
        for ((_, cm), b) in cases.iter().zip(&mut best) {
            let (c0, t0) = (thread_cpu_seconds(), Instant::now());
            let out = march(&cm.system, &cm.settings).expect("march");
            let wall = t0.elapsed().as_secs_f64();
            let cpu = match (c0, thread_cpu_seconds()) {
                (Some(a), Some(b)) => b - a,
                _ => f64::NAN,
            };
            std::hint::black_box(out.steps);
            b.0 = b.0.min(wall);
            b.1 = b.1.min(cpu);
        }
    }
    best
}

fn bench(c: &mut Criterion) {
    let cases: Vec<(MarchScheme, CaseMarch)> = MarchScheme::ALL
        .into_iter()
        .map(|s| (s, setup(s)))
        .collect();
    let outs: Vec<_> = cases
        .iter()
        .map(|(_, cm)| march(&cm.system, &cm.settings).expect("march"))
        .collect();
    let times = timing_table(&cases);
    let (r_out, r_time) = (&outs[0], times[0]);
    eprintln!("scheme | steps (ratio) | iterations (ratio) | one-iteration steps | wall ms (ratio) | CPU ms (ratio)");
    for (((s, _), out), (wall, cpu)) in cases.iter().zip(&outs).zip(&times) {
        eprintln!(
            "{s} | {} ({:.3}) | {} ({:.3}) | {:.1} % | {:.3} ({:.3}) | {:.3} ({:.3})",
            out.steps,
            out.steps as f64 / r_out.steps as f64,
            out.total_iterations,
            out.total_iterations as f64 / r_out.total_iterations as f64,
            100.0 * out.single_iteration_fraction(),
            wall * 1e3,
            wall / r_time.0,
            cpu * 1e3,
            cpu / r_time.1,
        );
    }
    let mut group = c.benchmark_group("damper_200hz_one_period");
    group.sample_size(20);
    group.measurement_time(std::time::Duration::from_secs(2));
    for (scheme, cm) in &cases {
        group.bench_function(scheme.as_str(), |b| {
            b.iter(|| march(&cm.system, &cm.settings).expect("march"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
