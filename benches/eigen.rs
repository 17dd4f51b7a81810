//! Sparse eigensolver (criterion): the lowest 20 modes of the 7-point Laplacian stiffness on a
//! 3-D grid of masses with clamped outside neighbours (spring 1e6 N/m, mass 0.5 kg), 50×50×48 =
//! 120 000 DOF by default (`NLROM_BENCH_EIGEN_GRID=NX,NY,NZ` overrides).
//!
//! Benchmarks: `factorise` (sparse Cholesky of K, [`ShiftInvert::new`]) and `lowest_20` (block
//! Krylov–Schur on a prebuilt factorisation, [`ShiftInvert::lowest_modes`]); their sum is the
//! cost of [`nlrom::eigen::lowest_modes`]. Run: `cargo bench --bench eigen` (10 samples each,
//! about 5 minutes on 2 cores).

use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use faer::sparse::{SparseColMat, Triplet};
use nlrom::eigen::{EigenOptions, ShiftInvert};

/// Spring stiffness (N/m) and point mass (kg) of the lattice.
const SPRING: f64 = 1.0e6;
const MASS: f64 = 0.5;

/// The grid size from `NLROM_BENCH_EIGEN_GRID` or 50×50×48.
fn grid() -> (usize, usize, usize) {
    let parsed = std::env::var("NLROM_BENCH_EIGEN_GRID").ok().and_then(|s| {
        let v: Vec<usize> = s.split(',').filter_map(|x| x.trim().parse().ok()).collect();
        (v.len() == 3).then(|| (v[0], v[1], v[2]))
    });
    parsed.unwrap_or((50, 50, 48))
}

/// K (7-point Laplacian, Dirichlet outside) and lumped M of an `nx × ny × nz` grid.
fn lattice(
    nx: usize,
    ny: usize,
    nz: usize,
) -> (SparseColMat<usize, f64>, SparseColMat<usize, f64>) {
    let id = |i: usize, j: usize, k: usize| i + nx * (j + ny * k);
    let mut t = Vec::with_capacity(7 * nx * ny * nz);
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let p = id(i, j, k);
                t.push(Triplet::new(p, p, 6.0 * SPRING));
                let neighbours = [
                    (i + 1 < nx).then(|| id(i + 1, j, k)),
                    (j + 1 < ny).then(|| id(i, j + 1, k)),
                    (k + 1 < nz).then(|| id(i, j, k + 1)),
                ];
                for q in neighbours.into_iter().flatten() {
                    t.push(Triplet::new(p, q, -SPRING));
                    t.push(Triplet::new(q, p, -SPRING));
                }
            }
        }
    }
    let n = nx * ny * nz;
    let m: Vec<_> = (0..n).map(|i| Triplet::new(i, i, MASS)).collect();
    (
        SparseColMat::try_new_from_triplets(n, n, &t).expect("valid lattice"),
        SparseColMat::try_new_from_triplets(n, n, &m).expect("valid mass"),
    )
}

fn eigen(c: &mut Criterion) {
    let (nx, ny, nz) = grid();
    let (k, m) = lattice(nx, ny, nz);
    let opts = EigenOptions::default();
    let mut group = c.benchmark_group(format!("eigen_lattice_{}", nx * ny * nz));
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(90));
    group.bench_function("factorise", |b| {
        b.iter(|| ShiftInvert::new(k.as_ref(), m.as_ref(), 0.0).expect("factorises"))
    });
    let si = ShiftInvert::new(k.as_ref(), m.as_ref(), 0.0).expect("factorises");
    group.bench_function("lowest_20", |b| {
        b.iter(|| si.lowest_modes(20, &opts).expect("converges"))
    });
    group.finish();
}

criterion_group!(benches, eigen);
criterion_main!(benches);
