//! Repeated evaluation of one contact element from its converged slider state, for profiling
//! the element cost with load-independent instruction counts (the element of
//! `benches/contact.rs`: 3-D, partial slip with normal load variation).
//!
//! Usage: `contact_cost <1d|2d> <H> <N_t> <forces|jacobian> <evaluations>`, e.g.
//! `valgrind --tool=callgrind --collect-atstart=no
//! --toggle-collect='nlrom::contact::element::evaluate' target/release/examples/contact_cost
//! 1d 3 32 jacobian 1000`: instructions per evaluation = Ir / (evaluations + 1). Prints the wall
//! and CPU time per evaluation (this thread's run time, `/proc/thread-self/schedstat`: not
//! inflated by other processes' load).
//!
//! `contact_cost microslip <stick|jenkins|stickslip|separation|all> <evaluations>`: the 1-D
//! element and motions of `benches/microslip.rs` evaluated with the Jacobian from the converged
//! slider state, by the exact single-harmonic cycle (`evaluation = "analytic"`) and by the AFT at
//! H = 1, N_t = 64, one after the other in this process; prints the CPU time per evaluation of
//! each and their ratio per regime. Instructions per evaluation: `valgrind --tool=callgrind
//! --collect-atstart=no --toggle-collect='nlrom::contact::element::evaluate_as'
//! target/release/examples/contact_cost microslip separation 1000`, then the inclusive Ir of
//! `nlrom::contact::microslip::evaluate_element` (analytic) and of
//! `nlrom::contact::element::evaluate` (AFT) from `callgrind_annotate --inclusive=yes`, each over
//! 1001 evaluations.
//!
//! `contact_cost pairs <threads> <forces|jacobian> <evaluations>`: the `PairSet` of 512 pairs of
//! `benches/contact.rs` (whole `HarmonicForce::evaluate` with the dense Jacobian) in a rayon pool
//! of `threads` threads; prints the wall time, the CPU time summed over the pool's threads and
//! the largest per-thread CPU time (the critical path when every thread has its own core: the
//! load-independent estimate of the parallel speedup is the 1-thread CPU time over it).

use std::hint::black_box;
use std::time::Instant;

#[path = "../../benches/common/contact_input.rs"]
mod contact_input;
#[path = "../../benches/common/microslip_input.rs"]
mod microslip_input;
use contact_input::{bench_element, input, pair_set};
use microslip_input::{microslip_element, microslip_motions};
use nlrom::case::Evaluation;
use nlrom::contact::aft::Aft;
use nlrom::contact::element::{evaluate, evaluate_as, Workspace};
use nlrom::contact::law::Variant;
use nlrom::harmonics::{HarmonicForce, HarmonicLayout};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.len() == 4 && args[0] == "pairs" {
        return pairs(args[1].parse()?, mode(&args[2])?, args[3].parse()?);
    }
    if args.len() == 3 && args[0] == "microslip" {
        return microslip(&args[1], args[2].parse()?);
    }
    if args.len() != 5 {
        return Err("usage: contact_cost <1d|2d> <H> <N_t> <forces|jacobian> <evaluations> | pairs <threads> <forces|jacobian> <evaluations> | microslip <regime|all> <evaluations>".into());
    }
    let variant = match args[0].as_str() {
        "1d" => Variant::OneD,
        "2d" => Variant::TwoD,
        v => return Err(format!("variant '{v}': expected 1d or 2d").into()),
    };
    let h: usize = args[1].parse()?;
    let n_t: usize = args[2].parse()?;
    let jacobian = mode(&args[3])?;
    let count: usize = args[4].parse()?;
    let aft = Aft::new(HarmonicLayout::new(h, n_t)?)?;
    let mut ws = Workspace::new(&aft);
    let element = bench_element(variant);
    let x = input(h);
    let mut f = vec![0.0; x.len()];
    let mut state = [0.0; 2];
    evaluate(&element, &aft, &x, &mut state, &mut f, false, &mut ws)?;
    let cpu = thread_cpu_seconds();
    let start = Instant::now();
    for _ in 0..count {
        let mut s = state;
        evaluate(
            &element,
            &aft,
            black_box(&x),
            &mut s,
            &mut f,
            jacobian,
            &mut ws,
        )?;
        black_box(&f);
    }
    let per = start.elapsed().as_secs_f64() / count.max(1) as f64;
    let cpu_per = (thread_cpu_seconds() - cpu) / count.max(1) as f64;
    println!(
        "{count} evaluations: {:.3} µs each (wall), {:.3} µs CPU",
        per * 1e6,
        cpu_per * 1e6
    );
    Ok(())
}

/// Whether the mode argument asks for the Jacobian.
fn mode(arg: &str) -> Result<bool, Box<dyn std::error::Error>> {
    match arg {
        "forces" => Ok(false),
        "jacobian" => Ok(true),
        v => Err(format!("mode '{v}': expected forces or jacobian").into()),
    }
}

/// CPU time per evaluation (s) of the microslip element with its Jacobian on the local input
/// `x` by `evaluation` at H = 1 and N_t = `n_t`, from the converged slider state, over `count`
/// evaluations (after one that converges the state).
fn microslip_time(
    evaluation: Evaluation,
    n_t: usize,
    x: &[f64; 6],
    count: usize,
) -> Result<f64, Box<dyn std::error::Error>> {
    let element = microslip_element();
    let aft = Aft::new(HarmonicLayout::new(1, n_t)?)?;
    let mut ws = Workspace::new(&aft);
    let mut f = [0.0; 6];
    let mut state = [0.0; 2];
    evaluate_as(
        evaluation, &element, &aft, x, &mut state, &mut f, true, &mut ws,
    )?;
    let cpu = thread_cpu_seconds();
    for _ in 0..count {
        let mut s = state;
        evaluate_as(
            evaluation,
            &element,
            &aft,
            black_box(x),
            &mut s,
            &mut f,
            true,
            &mut ws,
        )?;
        black_box(&f);
    }
    Ok((thread_cpu_seconds() - cpu) / count.max(1) as f64)
}

/// The analytic and AFT (N_t = 64) evaluations of the microslip element in the regime `which`
/// (or `all`): CPU time per evaluation of each and their ratio.
fn microslip(which: &str, count: usize) -> Result<(), Box<dyn std::error::Error>> {
    let motions = microslip_motions();
    if which != "all" && !motions.iter().any(|(name, _)| *name == which) {
        return Err(format!(
            "regime '{which}': expected stick, jenkins, stickslip, separation or all"
        )
        .into());
    }
    println!("regime | analytic (µs CPU) | AFT N_t = 64 (µs CPU) | AFT / analytic");
    for (name, x) in motions
        .iter()
        .filter(|(n, _)| which == "all" || *n == which)
    {
        let analytic = microslip_time(Evaluation::Analytic, 64, x, count)?;
        let aft = microslip_time(Evaluation::Aft, 64, x, count)?;
        println!(
            "{name} | {:.3} | {:.3} | {:.1}",
            analytic * 1e6,
            aft * 1e6,
            aft / analytic
        );
    }
    Ok(())
}

/// Evaluates the pair set `count` times in a pool of `threads` threads and prints the times.
fn pairs(threads: usize, jacobian: bool, count: usize) -> Result<(), Box<dyn std::error::Error>> {
    let (set, layout, q) = pair_set(512);
    let n = q.len();
    let mut state = set.initial_state();
    let mut f = vec![0.0; n];
    set.evaluate(&layout, &q, &mut state, &mut f, None)?;
    let mut jac = faer::Mat::<f64>::zeros(n, n);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    let cpu = pool.broadcast(|_| thread_cpu_seconds());
    let start = Instant::now();
    for _ in 0..count {
        pool.install(|| {
            let mut s = state.clone();
            let j = jacobian.then(|| jac.as_mut());
            set.evaluate(&layout, black_box(&q), &mut s, &mut f, j)
        })?;
    }
    let wall = start.elapsed().as_secs_f64();
    let used: Vec<f64> = pool
        .broadcast(|_| thread_cpu_seconds())
        .iter()
        .zip(&cpu)
        .map(|(b, a)| b - a)
        .collect();
    let per = |t: f64| t / count.max(1) as f64 * 1e3;
    println!(
        "{threads} thread(s), {count} evaluations: {:.3} ms each (wall), CPU {:.3} ms summed over threads, largest thread {:.3} ms",
        per(wall),
        per(used.iter().sum()),
        per(used.iter().fold(0.0, |a: f64, &b| a.max(b)))
    );
    Ok(())
}

/// Run time of this thread (s) from `/proc/thread-self/schedstat` (first field, ns); NaN where
/// unavailable.
fn thread_cpu_seconds() -> f64 {
    std::fs::read_to_string("/proc/thread-self/schedstat")
        .ok()
        .and_then(|s| s.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(f64::NAN, |ns| ns * 1e-9)
}
