//! Harmonic balance speed (criterion) on the 3-DOF chain with two Jenkins elements of
//! `cases/chain3_jenkins.toml`: ground –k– m1 –k– m2 –k– m3 (k = 1 N/m, m = 1 kg, Rayleigh
//! C = 0.02 K), Jenkins elements m1–ground and m2–m3 (k_t = 1 N/m, μ n0 = 0.2 N), force 0.5 N on
//! m3, H = 7, N_t = 1024.
//!
//! Benchmarks: `newton_iteration` (one residual + analytic Jacobian evaluation and one dense LU
//! solve of the 45 unknowns) and `frf` (the whole continuation 0.2 → 2.2 rad/s; the time per point
//! is this divided by the number of points, printed once). Run: `cargo bench --bench hbm`.
//! The friction elements come from `contact::element` through the test wrapper of
//! `tests/support/hbm.rs` (the same law and Jacobian as the `[[element]]` force).

#[path = "../tests/support/hbm.rs"]
mod hbm_support;

use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use faer::Mat;
use hbm_support::friction_elements;
use nlrom::contact::grounded::DofElements;
use nlrom::contact::law::ContactParams;
use nlrom::continuation::{trace, ContinuationOptions};
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::{FrequencyPath, HbmSystem, LinearModel};
use nlrom::nonlinear::{solve_dense, Linearization, ParameterSystem};

fn chain() -> (LinearModel, DofElements) {
    let k = Mat::from_fn(3, 3, |i, j| match (i, j) {
        (0, 0) | (1, 1) => 2.0,
        (2, 2) => 1.0,
        (a, b) if a.abs_diff(b) == 1 => -1.0,
        _ => 0.0,
    });
    let m = Mat::<f64>::identity(3, 3);
    let c = Mat::from_fn(3, 3, |i, j| 0.02 * k[(i, j)]);
    let linear = LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        Some(c.as_ref()),
        &[0.0, 0.0, 0.5],
        vec![0, 1, 2],
        vec![2],
        7,
    )
    .unwrap();
    let params = ContactParams::new(1.0, 0.0, 1.0, 0.2, "bench").unwrap();
    let elements = friction_elements(params, vec![vec![(0, 1.0)], vec![(1, -1.0), (2, 1.0)]], 3);
    (linear, elements)
}

fn hbm(c: &mut Criterion) {
    let (linear, pair) = chain();
    let layout = HarmonicLayout::new(7, 1024).unwrap();
    let system = HbmSystem::new(layout, &linear, &pair).unwrap();
    let fp = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let opts = ContinuationOptions::new(0.2, 2.2, 0.02);
    let path = trace(&fp, &opts, &mut |_| {}).unwrap();
    let n_points = path.points.len();
    let iterations: usize = path.points.iter().map(|p| p.iterations).sum();
    eprintln!("chain3_jenkins: {n_points} points, {iterations} Newton iterations ({:.2} per point), end {:?}", iterations as f64 / n_points as f64, path.end);
    let mid = &path.points[n_points / 2];
    let mut group = c.benchmark_group("hbm_chain3_jenkins_h7_nt1024");
    group
        .sample_size(10)
        .measurement_time(Duration::from_secs(5));
    group.bench_function("newton_iteration", |bench| {
        bench.iter(|| {
            let mut lin = Linearization::zeros(fp.dim());
            fp.evaluate(&mid.x, mid.parameter, &mid.state, &mut lin)
                .unwrap();
            solve_dense(
                lin.jacobian.as_dense().expect("a dense Jacobian"),
                &lin.residual,
            )
            .unwrap()
        })
    });
    group.bench_function("frf", |bench| {
        bench.iter(|| trace(&fp, &opts, &mut |_| {}).unwrap().points.len())
    });
    group.finish();
}

criterion_group!(benches, hbm);
criterion_main!(benches);
