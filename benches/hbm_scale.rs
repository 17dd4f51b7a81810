//! The linear solve of a harmonic balance Newton step at interface scale (criterion): the
//! Jacobian of a synthetic contact interface — a chain of unit masses and springs whose every DOF
//! belongs to a node-to-node friction pair (k_t = k_n = 1 N/m, μ = 0.5, n0 = 1 N; the
//! `synthetic_interface` of `tests/support/hbm.rs`) — at a harmonic-1 state where one pair in
//! `EVERY` slips and separates and the others stick, solved by the dense LU and by the
//! structured path of `nlrom::nonlinear::linsolve` (block LUs per harmonic and the exact
//! Woodbury correction for the pairs that couple harmonics) on the block-stored Jacobian, and by
//! the automatic choice; and the evaluation of residual and Jacobian into dense and into block
//! storage. The rank of the correction and the ratio of the two solve times are printed once.
//!
//! Group `hbm_scale_modal`: the harmonic balance on modal coordinates (`nlrom::hbm::modal`) of
//! the synthetic modal interface of `tests/support/hbm.rs` (`MODAL_CONTACT_DOFS` contact DOF,
//! `MODES` modes, one pair in 8 slipping and separating, H = 5): one evaluation of the residual
//! and the projected Jacobian into a dense matrix, and its dense LU and solve.
//!
//! Run: `cargo bench --bench hbm_scale` (about a minute).

#[path = "../tests/support/hbm.rs"]
mod hbm_support;

use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use hbm_support::{synthetic_interface, synthetic_modal_interface};
use nlrom::hbm::{FrequencyPath, HbmSystem};
use nlrom::nonlinear::linsolve::SolvePath;
use nlrom::nonlinear::{LinearSolver, Linearization, ParameterSystem, SolverChoice};

/// Contact DOF of the interface (a multiple of 6).
const CONTACT_DOFS: usize = 480;
/// Harmonics.
const H: usize = 3;
/// One pair in `EVERY` moves enough to slip and separate (≈ 12 % of the pairs).
const EVERY: f64 = 8.0;

fn scale(c: &mut Criterion) {
    let (linear, set, layout, x) =
        synthetic_interface(CONTACT_DOFS, H, 32, Some(1.0 / EVERY)).unwrap();
    let system = HbmSystem::new(layout, &linear, &set).unwrap();
    let fp = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let dense = LinearSolver::dense();
    let structured = LinearSolver::new(fp.jacobian_blocks(), SolverChoice::Structured);
    let auto = LinearSolver::new(fp.jacobian_blocks(), SolverChoice::Auto);
    // the same Jacobian stored dense (for the dense LU) and by blocks (for the others)
    let mut lin = Linearization::zeros(fp.dim());
    fp.evaluate(&x, 0.8, &fp.initial_state(), &mut lin).unwrap();
    let mut lin_blocks = structured.linearization(fp.dim());
    fp.evaluate(&x, 0.8, &fp.initial_state(), &mut lin_blocks)
        .unwrap();
    let b = lin.residual.clone();
    let time = |s: &LinearSolver, a: &mut Linearization| {
        let t = Instant::now();
        let (x, f) = s.factor_solve(&mut a.jacobian, &b).unwrap();
        (t.elapsed().as_secs_f64(), x, f.path())
    };
    let (td, xd, _) = time(&dense, &mut lin);
    let (ts, xs, path) = time(&structured, &mut lin_blocks);
    let (_, _, auto_path) = time(&auto, &mut lin_blocks);
    let diff = xd
        .iter()
        .zip(&xs)
        .map(|(p, q)| (p - q).abs())
        .fold(0.0, f64::max);
    let rank = match path {
        SolvePath::Structured { rank } => rank,
        SolvePath::Dense => 0,
    };
    println!(
        "{CONTACT_DOFS} contact DOF, H = {H}, {} unknowns: rank of the correction {rank} ({:.1} %), auto takes {auto_path:?}; one solve dense {td:.3} s, structured {ts:.3} s ({:.1}×); max |x_s − x_d| {diff:.1e}",
        b.len(),
        100.0 * rank as f64 / b.len() as f64,
        td / ts
    );
    let mut g = c.benchmark_group("hbm_scale");
    g.sample_size(10).measurement_time(Duration::from_secs(8));
    g.bench_function("dense_lu", |bench| {
        bench.iter(|| dense.factor_solve(&mut lin.jacobian, &b).unwrap())
    });
    g.bench_function("structured", |bench| {
        bench.iter(|| {
            structured
                .factor_solve(&mut lin_blocks.jacobian, &b)
                .unwrap()
        })
    });
    g.bench_function("auto", |bench| {
        bench.iter(|| auto.factor_solve(&mut lin_blocks.jacobian, &b).unwrap())
    });
    g.bench_function("evaluate_dense", |bench| {
        bench.iter(|| fp.evaluate(&x, 0.8, &fp.initial_state(), &mut lin).unwrap())
    });
    g.bench_function("evaluate_blocks", |bench| {
        bench.iter(|| {
            fp.evaluate(&x, 0.8, &fp.initial_state(), &mut lin_blocks)
                .unwrap()
        })
    });
    g.finish();
}

/// Contact DOF of the modal interface.
const MODAL_CONTACT_DOFS: usize = 1200;
/// Modes of the modal interface.
const MODES: usize = 60;

fn modal(c: &mut Criterion) {
    let (model, set, layout, q) =
        synthetic_modal_interface(MODAL_CONTACT_DOFS, MODES, 5, 32, 8).unwrap();
    let linear = model.linear_model(5).unwrap();
    let force = model.project(set).unwrap();
    let system = HbmSystem::new(layout, &linear, &force).unwrap();
    let fp = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let dense = LinearSolver::dense();
    let mut lin = Linearization::zeros(fp.dim());
    fp.evaluate(&q, 0.8, &fp.initial_state(), &mut lin).unwrap();
    let b = lin.residual.clone();
    let mut g = c.benchmark_group("hbm_scale_modal");
    g.sample_size(10).measurement_time(Duration::from_secs(5));
    g.bench_function("evaluate", |bench| {
        bench.iter(|| fp.evaluate(&q, 0.8, &fp.initial_state(), &mut lin).unwrap())
    });
    g.bench_function("dense_lu", |bench| {
        bench.iter(|| dense.factor_solve(&mut lin.jacobian, &b).unwrap())
    });
    g.finish();
}

criterion_group!(benches, scale, modal);
criterion_main!(benches);
