//! Harmonic balance speed on the bundled sector and on a large synthetic contact model (the
//! numbers of docs/performance.md, "Harmonic balance").
//!
//! ```text
//! cargo run --release --example hbm_speed -- sector CASE.toml [H] [POINTS] [KEY=VALUE ...]
//! cargo run --release --example hbm_speed -- synthetic [CONTACT_DOFS] [H] [SAMPLES] [EVERY] [nodense]
//! cargo run --release --example hbm_speed -- modal [CONTACT_DOFS] [H] [MODES] [SAMPLES] [EVERY] [newton]
//! ```
//!
//! `sector`: the case's sector problem (reduction, SAMA interfaces, preload balance) with H
//! harmonics (default 3; the case's AFT samples), a continuation of POINTS points (default 8) from
//! the case's start frequency: wall time per point and per Newton iteration (corrector
//! iterations; the predictor's tangent solves are included in the per-point time), the linear
//! solves by path (dense LU or structured, with the mean rank of the low-rank correction), the
//! peak resident memory and the system time's share of the CPU time, then the split of one
//! Newton iteration at the last point. KEY=VALUE overrides the case:
//! `solver=dense|auto|structured[,...]` (`harmonic_balance.linear_solver`), `n0=N` (every contact's
//! preload), `start=F` (`continuation.start`, in the case's unit); `split=no` leaves out the split
//! of one Newton iteration.
//!
//! `synthetic`: CONTACT_DOFS / 6 node-to-node pairs (frames along x, y, z; k_t = k_n = 1 N/m,
//! μ = 0.5, n0 = 1 N, 1-D friction) on a chain of CONTACT_DOFS unit masses and unit springs
//! (C = 0.01 K), every DOF nonlinear, forced on harmonic 1 so that the pairs stick, slip and
//! separate; H (default 3) and SAMPLES (default 4(H+1) rounded up to a power of two): the split
//! of one Newton iteration. With EVERY > 1 only one pair in EVERY moves that much, the others 50
//! times less and stick all period (microslip of the interface). `nodense` leaves out the dense
//! Jacobian and its LU (whose n² memory and n³ time are out of reach beyond about 15 000 unknowns).
//!
//! `modal`: the harmonic balance on modal coordinates (`nlrom::hbm::modal`) of a synthetic
//! modal interface (`synthetic_modal_interface` of `tests/support/hbm.rs`): CONTACT_DOFS / 6
//! node-to-node pairs along a strip seen by MODES smooth mode shapes (default 1 500 contact DOF,
//! H = 5, 300 modes, 32 samples), one pair in EVERY (default 8) with a small preload so that it
//! slips and separates at the state timed, the others stuck all period; MODES·(2H + 1) unknowns.
//! The split of one Newton iteration at that state (ω = 0.8 rad/s): the contact forces alone
//! (U = Φ_c Q, the physical AFT, Φ_cᵀ F), the forces with the projected Jacobian, the whole
//! evaluation (linear part, forces, Jacobian into a dense matrix), the residual alone and the
//! dense LU and solve; the heap's high-water mark above the heap before the split and the peak
//! resident memory. `newton` adds a Newton solve from that state (dense LU): iterations and CPU
//! time per iteration.
//!
//! The split (best of `HBM_SPEED_REPEAT` runs, default 2, wall clock,
//! `faer::get_global_parallelism` threads):
//! condensation of the linear part at ω; AFT = contact forces alone (inverse DFT, contact law
//! march, DFT); contact Jacobian = forces with the analytic Jacobian minus forces alone, into a
//! dense matrix and into the block storage of `harmonics::BlockJacobian`; linear assembly = the
//! whole dense residual + Jacobian evaluation minus the contact part and the condensation; linear
//! part, block-stored = the block-stored evaluation minus its contact part (D̄ left pending: the
//! LU of D_LL and matrix–vector products); D̄ formed = adding the pending D̄ to the blocks, as a
//! factorisation does (timed on a copy); the residual alone (what a
//! damping trial evaluates); dense LU = faer's partial-pivoting LU and solve of the Jacobian
//! (`nonlinear::solve_dense`); structured solve = the block LUs and low-rank correction of
//! `nonlinear::linsolve` on the block-stored Jacobian; and the path the automatic choice takes.
//!
//! `solver=` takes a comma-separated list (e.g. `solver=auto,dense`): the continuation is traced
//! once per solver in the same process, each with its own peak memory (the peak is reset before
//! each, `/proc/self/clear_refs`), and the points are compared with the previous solver's. With
//! `HBM_SPEED_POINTS` set, every point's iterations, factorisations, GMRES solves and CPU time are
//! printed as it converges.
//!
//! After each continuation the live heap bytes (a counting global allocator, `heap_peak.rs`)
//! before it and their high-water mark during it are printed; with `HBM_SPEED_HEAP` set, also
//! the allocations of 256 kB or more live at that mark, by call site.

#[path = "../../tests/support/hbm.rs"]
mod hbm_support;

#[path = "heap_peak.rs"]
mod heap_peak;

/// Counts the live heap bytes and their high-water mark (printed after each continuation).
#[global_allocator]
static HEAP: heap_peak::Counting = heap_peak::Counting;

use std::f64::consts::PI;
use std::path::Path;
use std::time::Instant;

use hbm_support::{synthetic_interface, synthetic_modal_interface};

use faer::Mat;
use nlrom::case::{Case, LinearSolverKey};
use nlrom::continuation::trace;
use nlrom::harmonics::{HarmonicForce, JacobianMut};
use nlrom::hbm::{FrequencyPath, HbmSystem};
use nlrom::interface::build_interfaces;
use nlrom::nonlinear::{
    linsolve, solve_dense, solve_fixed, LinearSolver, Linearization, NewtonOptions,
    ParameterSystem, SolverChoice,
};
use nlrom::problem::sector::SectorProblem;
use nlrom::problem::settings::case_continuation;
use nlrom::reduction::reduce;
use nlrom::{model, Result};

/// Runs of each timed part of the split (`HBM_SPEED_REPEAT`, default 2).
fn repeat() -> usize {
    std::env::var("HBM_SPEED_REPEAT")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(2)
        .max(1)
}

fn main() -> Result<()> {
    nlrom::problem::use_one_heap_arena();
    let args: Vec<String> = std::env::args().skip(1).collect();
    let num = |i: usize, default: usize| {
        args.get(i)
            .map(|s| s.parse().expect("a number"))
            .unwrap_or(default)
    };
    eprintln!(
        "faer parallelism: {:?}; rayon threads: {}",
        faer::get_global_parallelism(),
        rayon::current_num_threads()
    );
    match args.first().map(String::as_str) {
        Some("sector") => sector(
            Path::new(&args[1]),
            num(2, 3),
            num(3, 8),
            args.get(4..).unwrap_or_default(),
        ),
        Some("synthetic") => {
            let h = num(2, 3);
            let samples = num(3, (4 * (h + 1)).next_power_of_two());
            let dense = args.get(5).map(String::as_str) != Some("nodense");
            synthetic(num(1, 1500), h, samples, num(4, 1), dense)
        }
        Some("modal") => {
            let newton = args.get(6).map(String::as_str) == Some("newton");
            modal(
                num(1, 1500),
                num(2, 5),
                num(3, 300),
                num(4, 32),
                num(5, 8),
                newton,
            )
        }
        _ => {
            eprintln!("usage: hbm_speed sector CASE.toml [H] [POINTS] | synthetic [CONTACT_DOFS] [H] [SAMPLES] [EVERY] [nodense] | modal [CONTACT_DOFS] [H] [MODES] [SAMPLES] [EVERY] [newton]");
            Ok(())
        }
    }
}

/// CPU time (user + system, all threads) of this process so far (s), from /proc/self/stat
/// (clock ticks of 10 ms); 0 where unavailable.
fn cpu_seconds() -> f64 {
    let (user, system) = cpu_split();
    user + system
}

/// User and system CPU time of this process so far (s), fields 14 and 15 of /proc/self/stat.
fn cpu_split() -> (f64, f64) {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let after = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<f64> = after
        .split_whitespace()
        .map(|v| v.parse().unwrap_or(0.0))
        .collect();
    // fields 14 (utime) and 15 (stime) of proc(5); `after` starts at field 3
    f.get(11)
        .zip(f.get(12))
        .map_or((0.0, 0.0), |(u, s)| (u / 100.0, s / 100.0))
}

/// Peak resident memory of this process so far (GB), from /proc/self/status (VmHWM); 0 where
/// unavailable.
fn peak_rss_gb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |kb| kb / 1024.0 / 1024.0)
}

/// Best wall time (s) of [`repeat`] runs of `f`, and the CPU time of that run.
fn best<T>(mut f: impl FnMut() -> T) -> (f64, f64) {
    (0..repeat())
        .map(|_| {
            let (t, c) = (Instant::now(), cpu_seconds());
            std::hint::black_box(f());
            (t.elapsed().as_secs_f64(), cpu_seconds() - c)
        })
        .fold((f64::INFINITY, 0.0), |a, b| if b.0 < a.0 { b } else { a })
}

fn sector(path: &Path, h: usize, points: usize, overrides: &[String]) -> Result<()> {
    let mut case = Case::load(path)?;
    case.harmonic_balance.harmonics = h;
    let mut solvers = vec![case.harmonic_balance.linear_solver];
    let mut with_split = true;
    for o in overrides {
        let (key, value) = o.split_once('=').expect("KEY=VALUE");
        match key {
            "solver" => {
                solvers = value
                    .split(',')
                    .map(|v| match v {
                        "dense" => LinearSolverKey::Dense,
                        "auto" => LinearSolverKey::Auto,
                        "structured" => LinearSolverKey::Structured,
                        other => {
                            panic!("solver={other}: dense, auto or structured (comma-separated)")
                        }
                    })
                    .collect()
            }
            "n0" => {
                let n0: f64 = value.parse().expect("n0=NUMBER");
                case.contact.iter_mut().for_each(|c| c.n0 = n0);
            }
            "start" => {
                let c = case.continuation.as_mut().expect("a [continuation] table");
                c.start = value.parse().expect("start=NUMBER");
            }
            "split" => with_split = value != "no",
            other => panic!("unknown override {other}: solver, n0, start, split"),
        }
    }
    let t = Instant::now();
    let sm = model::build(&case, &mut |_| {})?;
    let rom = reduce(&case, &sm, &mut |_| {})?;
    let rss_rom = rss_gb();
    let mesh = sm.mesh.as_ref().expect("a sector case has a mesh");
    let interfaces = build_interfaces(&case, mesh, rom.cyclic.as_ref())?;
    let problem = SectorProblem::build(&case, &rom, mesh, &interfaces)?;
    let rss_problem = rss_gb();
    let system = problem.system()?;
    drop((sm, rom, interfaces));
    nlrom::problem::release_free_heap();
    eprintln!(
        "resident: {rss_rom:.2} GB after the reduction, {rss_problem:.2} GB with the problem, {:.2} GB after dropping the model and ROM; {} rows per harmonic ({} condensed)",
        rss_gb(),
        problem.linear.uncondensed(0).stiffness.nrows(),
        problem.linear.n_condensed()
    );
    eprintln!(
        "setup (model, reduction, interfaces) {:.1} s, peak RSS {:.2} GB; H = {h}, N_t = {}, {} contact DOF, {} unknowns",
        t.elapsed().as_secs_f64(),
        peak_rss_gb(),
        problem.layout.time_samples,
        problem.linear.n_condensed(),
        system.dim()
    );
    let fp = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let mut last: Option<Vec<(f64, Vec<f64>)>> = None;
    for solver in solvers {
        case.harmonic_balance.linear_solver = solver;
        let mut opts = case_continuation(&case)?;
        opts.max_points = points;
        let rss_before = reset_peak_rss();
        let heap_before = heap_peak::live_bytes();
        heap_peak::trace_from_env();
        heap_peak::reset();
        let (t, c, split0) = (Instant::now(), cpu_seconds(), cpu_split());
        let before = linsolve::stats();
        let mut mark = (linsolve::stats(), cpu_seconds());
        let verbose = std::env::var_os("HBM_SPEED_POINTS").is_some();
        let path = trace(&fp, &opts, &mut |p| {
            let (s, c) = (linsolve::stats(), cpu_seconds());
            if verbose {
                eprintln!(
                    "  point {:.4} Hz: {} iterations, {} factorisations, {} GMRES solves ({} iterations), CPU {:.2} s, heap mark {:.1} MB",
                    p.parameter / (2.0 * PI),
                    p.iterations,
                    s.factorizations - mark.0.factorizations,
                    s.krylov - mark.0.krylov,
                    s.krylov_iterations - mark.0.krylov_iterations,
                    c - mark.1,
                    heap_peak::peak_bytes() as f64 / 1e6
                );
            }
            mark = (s, c);
        })?;
        let (wall, cpu) = (t.elapsed().as_secs_f64(), cpu_seconds() - c);
        heap_peak::report(heap_before, 12);
        heap_peak::stop();
        let system_share = (cpu_split().1 - split0.1) / cpu.max(1e-9);
        let after = linsolve::stats();
        let iterations: usize = path.points.iter().map(|p| p.iterations).sum();
        let n = path.points.len();
        println!(
            "sector, {:?}: {n} points ({:.2} → {:.2} Hz, {} retries), {iterations} Newton iterations, {:.3} s per point, {:.4} s per iteration (whole continuation {wall:.2} s, CPU {cpu:.2} s: {:.2} s per point, {:.2} s per iteration)",
            opts.newton.linear_solver,
            path.points[0].parameter / (2.0 * PI),
            path.points[n - 1].parameter / (2.0 * PI),
            path.retries,
            wall / n as f64,
            wall / iterations.max(1) as f64,
            cpu / n as f64,
            cpu / iterations.max(1) as f64
        );
        let structured = after.structured - before.structured;
        let krylov = after.krylov - before.krylov;
        println!(
            "  linear solves: {} dense LU, {structured} structured (mean rank {:.0} = {:.1} % of the unknowns), {} fallbacks to the dense LU, {} factorisations ({:.2} per point), {krylov} by GMRES on earlier factors ({:.1} iterations each); peak RSS of the continuation {:.2} GB (resident before it {rss_before:.2} GB); system time {:.1} % of the continuation's CPU",
            after.dense - before.dense,
            (after.rank_sum - before.rank_sum) as f64 / structured.max(1) as f64,
            100.0 * (after.rank_sum - before.rank_sum) as f64
                / (after.size_sum - before.size_sum).max(1) as f64,
            after.fallbacks - before.fallbacks,
            after.factorizations - before.factorizations,
            (after.factorizations - before.factorizations) as f64 / n as f64,
            (after.krylov_iterations - before.krylov_iterations) as f64 / krylov.max(1) as f64,
            peak_rss_gb(),
            100.0 * system_share
        );
        let points: Vec<(f64, Vec<f64>)> = path
            .points
            .iter()
            .map(|p| (p.parameter, p.x.clone()))
            .collect();
        if let Some(previous) = &last {
            print_difference(previous, &points);
        }
        last = Some(points);
        if let Some(p) = path.points.last().filter(|_| with_split) {
            split(&fp, &system, &p.x, p.parameter, &p.state, true)?;
        }
    }
    Ok(())
}

/// The largest relative difference of two paths' points (unknowns and parameter).
fn print_difference(a: &[(f64, Vec<f64>)], b: &[(f64, Vec<f64>)]) {
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    let worst = a
        .iter()
        .zip(b)
        .map(|((pa, xa), (pb, xb))| {
            let dx: Vec<f64> = xa.iter().zip(xb).map(|(p, q)| p - q).collect();
            (norm(&dx) / norm(xa)).max((pa - pb).abs() / pa.abs())
        })
        .fold(0.0, f64::max);
    println!(
        "  same points as the previous solver: {} and {} points, largest relative difference {worst:.1e}",
        a.len(),
        b.len()
    );
}

/// Resident memory of this process now (GB), from /proc/self/status (VmRSS); 0 where
/// unavailable.
fn rss_gb() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.split_whitespace().next()?.parse::<f64>().ok())
        .map_or(0.0, |kb| kb / 1024.0 / 1024.0)
}

/// Resets the peak resident memory of this process to the current one (Linux: `5` to
/// /proc/self/clear_refs) and returns the current one (GB).
fn reset_peak_rss() -> f64 {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
    rss_gb()
}

/// Times the parts of one Newton iteration at (x, ω) and prints them.
fn split<F: HarmonicForce>(
    fp: &FrequencyPath<'_, '_, F>,
    system: &HbmSystem<'_, F>,
    x: &[f64],
    omega: f64,
    state: &F::State,
    dense: bool,
) -> Result<()> {
    let layout = system.layout();
    let force = system.force();
    let nf = x.len();
    let condense = best(|| system.condense_all_applied(x, omega).unwrap());
    let aft = best(|| {
        let mut s = state.clone();
        let mut f = vec![0.0; nf];
        force.evaluate(&layout, x, &mut s, &mut f, None).unwrap();
    });
    let structured = LinearSolver::new(fp.jacobian_blocks(), SolverChoice::Structured);
    let auto = LinearSolver::new(fp.jacobian_blocks(), SolverChoice::Auto);
    let mut blocks = structured.linearization(nf).jacobian;
    let aft_blocks = best(|| {
        let mut s = state.clone();
        let mut f = vec![0.0; nf];
        blocks.clear();
        force
            .evaluate_into(
                &layout,
                x,
                omega,
                &mut s,
                &mut f,
                Some(blocks.target()),
                None,
            )
            .unwrap();
    });
    // one block storage at a time (each is (2 n_c)² H values)
    drop(blocks);
    let mut lin_blocks = structured.linearization(nf);
    let whole_blocks = best(|| fp.evaluate(x, omega, state, &mut lin_blocks).unwrap());
    let residual = best(|| {
        let mut r = vec![0.0; nf];
        fp.evaluate_residual(x, omega, state, &mut r).unwrap();
    });
    // D̄(ω) is left pending by the block-stored evaluation: formed when the matrix is factorised
    let formed = best(|| {
        let mut j = lin_blocks.jacobian.clone();
        j.materialize();
        j
    });
    lin_blocks.jacobian.materialize();
    let mut path = None;
    let structured_solve = best(|| {
        let (x, f) = structured
            .factor_solve(&mut lin_blocks.jacobian, &lin_blocks.residual)
            .unwrap();
        path = Some(f.path());
        x
    });
    let mut auto_path = None;
    let auto_solve = best(|| {
        let (x, f) = auto
            .factor_solve(&mut lin_blocks.jacobian, &lin_blocks.residual)
            .unwrap();
        auto_path = Some(f.path());
        x
    });
    drop(lin_blocks);
    let row = |what: &str, t: (f64, f64), total: f64| {
        println!(
            "  {what:<52} {:>9.4} s {:>5.1} %  (CPU {:.2} s)",
            t.0,
            100.0 * t.0 / total,
            t.1
        )
    };
    let minus = |a: (f64, f64), b: (f64, f64)| (a.0 - b.0, a.1 - b.1);
    if !dense {
        let total = whole_blocks.0 + formed.0 + structured_solve.0;
        println!("one Newton iteration, {nf} unknowns (best of {}, wall; % of the block-stored + structured iteration {total:.4} s):", repeat());
        row("condensation of the linear part", condense, total);
        row("AFT: contact forces", aft, total);
        row(
            "contact Jacobian, block-stored",
            minus(aft_blocks, aft),
            total,
        );
        row(
            "linear part, block-stored (D̄ pending)",
            minus(whole_blocks, aft_blocks),
            total,
        );
        row("D̄ formed at a factorisation (with a copy)", formed, total);
        row("residual alone (a damping trial)", residual, total);
        row(
            "structured factorisation + solve (block-stored)",
            structured_solve,
            total,
        );
        row("automatic choice: factorisation + solve", auto_solve, total);
        println!("  structured path: {path:?}; automatic choice: {auto_path:?}");
        println!(
            "  iteration: block-stored + structured {total:.4} s (CPU {:.2} s)",
            whole_blocks.1 + formed.1 + structured_solve.1
        );
        return Ok(());
    }
    let mut jac = Mat::<f64>::zeros(nf, nf);
    let aft_jac = best(|| {
        let mut s = state.clone();
        let mut f = vec![0.0; nf];
        jac.fill(0.0);
        force
            .evaluate(&layout, x, &mut s, &mut f, Some(jac.as_mut()))
            .unwrap();
    });
    drop(jac);
    let mut lin = Linearization::zeros(fp.dim());
    let whole = best(|| fp.evaluate(x, omega, state, &mut lin).unwrap());
    let dense = lin.jacobian.as_dense().expect("a dense Jacobian");
    let lu = best(|| solve_dense(dense, &lin.residual).unwrap());
    let total = whole.0 + lu.0;
    let row = |what: &str, t: (f64, f64)| row(what, t, total);
    println!("one Newton iteration, {nf} unknowns (best of {}, wall; % of the dense iteration {total:.4} s):", repeat());
    row("condensation of the linear part", condense);
    row("AFT: contact forces", aft);
    row(
        "contact Jacobian, dense (forces + Jacobian − forces)",
        minus(aft_jac, aft),
    );
    row("contact Jacobian, block-stored", minus(aft_blocks, aft));
    row(
        "linear assembly, dense (evaluation − contact − cond.)",
        minus(minus(whole, aft_jac), condense),
    );
    row(
        "linear part, block-stored (D̄ pending)",
        minus(whole_blocks, aft_blocks),
    );
    row("D̄ formed at a factorisation (with a copy)", formed);
    row("residual alone (a damping trial)", residual);
    row("dense LU + solve", lu);
    row(
        "structured factorisation + solve (block-stored)",
        structured_solve,
    );
    row("automatic choice: factorisation + solve", auto_solve);
    println!("  structured path: {path:?}; automatic choice: {auto_path:?}");
    let structured_iteration = whole_blocks.0 + formed.0 + structured_solve.0;
    println!(
        "  iteration: dense {total:.4} s, block-stored + structured {structured_iteration:.4} s ({:.1}×)",
        total / structured_iteration
    );
    Ok(())
}

fn synthetic(
    contact_dofs: usize,
    h: usize,
    samples: usize,
    every: usize,
    dense: bool,
) -> Result<()> {
    let slipping = (every > 1).then(|| 1.0 / every as f64);
    let (linear, set, layout, x) = synthetic_interface(contact_dofs, h, samples, slipping)?;
    let n = linear.n_condensed();
    let pairs = n / 6;
    let system = HbmSystem::new(layout, &linear, &set)?;
    let fp = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    println!(
        "synthetic: {pairs} pairs ({} moving), {n} contact DOF, H = {h}, N_t = {samples}",
        pairs.div_ceil(every.max(1))
    );
    split(&fp, &system, &x, 0.8, &set.initial_state(), dense)
}

/// The split of one Newton iteration of the harmonic balance on modal coordinates (module
/// documentation, `modal`).
fn modal(
    contact_dofs: usize,
    h: usize,
    modes: usize,
    samples: usize,
    every: usize,
    newton: bool,
) -> Result<()> {
    let (model, set, layout, q) =
        synthetic_modal_interface(contact_dofs, modes, h, samples, every)?;
    let pairs = contact_dofs / 6;
    let linear = model.linear_model(h)?;
    let force = model.project(set)?;
    let system = HbmSystem::new(layout, &linear, &force)?;
    let fp = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let n = fp.dim();
    let state = force.initial_state();
    let omega = 0.8;
    println!(
        "modal: {pairs} pairs ({} with n0 = 0.2 N), {} contact DOF, {modes} modes, H = {h}, N_t = {samples}: {n} unknowns",
        pairs.div_ceil(every.max(1)),
        6 * pairs
    );
    let heap_before = heap_peak::live_bytes();
    heap_peak::reset();
    let rss_before = reset_peak_rss();
    let forces = best(|| {
        let mut s = state.clone();
        let mut f = vec![0.0; n];
        force
            .evaluate_into(&layout, &q, omega, &mut s, &mut f, None, None)
            .unwrap();
    });
    let mut jac = Mat::<f64>::zeros(n, n);
    let projected = best(|| {
        let mut s = state.clone();
        let mut f = vec![0.0; n];
        jac.fill(0.0);
        let target = Some(JacobianMut::Dense(jac.as_mut()));
        force
            .evaluate_into(&layout, &q, omega, &mut s, &mut f, target, None)
            .unwrap();
    });
    let (constant, coupled) = force.last_split();
    drop(jac);
    let mut lin = Linearization::zeros(n);
    let whole = best(|| fp.evaluate(&q, omega, &state, &mut lin).unwrap());
    let residual = best(|| {
        let mut r = vec![0.0; n];
        fp.evaluate_residual(&q, omega, &state, &mut r).unwrap();
    });
    let dense = lin.jacobian.as_dense().expect("a dense Jacobian");
    let lu = best(|| solve_dense(dense, &lin.residual).unwrap());
    let total = whole.0 + lu.0;
    let row = |what: &str, t: (f64, f64)| {
        println!(
            "  {what:<52} {:>9.4} s {:>5.1} %  (CPU {:.2} s)",
            t.0,
            100.0 * t.0 / total,
            t.1
        )
    };
    println!(
        "one Newton iteration, {n} unknowns (best of {}, wall; % of the iteration {total:.4} s):",
        repeat()
    );
    row("contact forces (Φ_c Q, AFT, Φ_cᵀ F)", forces);
    row(
        "projected contact Jacobian (forces + Jacobian − forces)",
        (projected.0 - forces.0, projected.1 - forces.1),
    );
    row("whole evaluation (linear part, forces, Jacobian)", whole);
    row("residual alone (a damping trial)", residual);
    row("dense LU + solve", lu);
    println!(
        "  pairs projected as constant {constant}, in transition {coupled}; iteration CPU {:.2} s; heap mark {:.1} MB above the {:.1} MB before; peak resident {:.2} GB ({:.2} GB before)",
        whole.1 + lu.1,
        heap_peak::peak_bytes().saturating_sub(heap_before) as f64 / 1e6,
        heap_before as f64 / 1e6,
        peak_rss_gb(),
        rss_before
    );
    drop(lin);
    if newton {
        let opts = NewtonOptions {
            linear_solver: SolverChoice::Dense,
            ..NewtonOptions::default()
        };
        let cpu = cpu_seconds();
        match solve_fixed(&fp, &q, omega, &state, &opts) {
            Ok(sol) => {
                let spent = cpu_seconds() - cpu;
                println!(
                    "  Newton from that state: {} iterations, {spent:.2} CPU s, {:.2} CPU s per iteration; pairs at the solution: {:?} (constant, in transition)",
                    sol.iterations,
                    spent / sol.iterations.max(1) as f64,
                    force.last_split()
                );
            }
            Err(e) => println!("  Newton from that state failed: {}", e.message),
        }
    }
    Ok(())
}
