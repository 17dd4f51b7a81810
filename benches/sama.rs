//! SAMA projection speed (criterion): 100 000 contact points projected onto a target surface of
//! about one million flat triangles (goal: under 2 s on 2 cores).
//!
//! The target is a wavy height field z = 0.02 sin(7x) cos(5y) over [0, 1]², 708 × 708 cells of two
//! triangle3 faces each (1 002 528 triangles, jittered vertices); the points are uniformly random
//! over the square, 0–5 mm off the surface. Benchmarks: `build_1M_triangles` (the surface with its
//! degeneracy checks and BVH, [`TargetSurface::new`]) and `project_100k` (the parallel projection,
//! [`TargetSurface::project_many`]: BVH search + Newton refinement + frame). Run:
//! `cargo bench --bench sama` (10 samples each, about a minute on 2 cores).

use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use nlrom::interface::surface::{SurfaceFace, TargetSurface};
use nlrom::mesh::ElementType;

/// Cells per side: 2 × 708² = 1 002 528 triangles.
const CELLS: usize = 708;
/// Number of projected points.
const POINTS: usize = 100_000;

/// Deterministic uniform numbers in [0, 1) (SplitMix64).
fn uniform(state: &mut u64) -> f64 {
    *state = state.wrapping_add(0x9E37_79B9_7F4A_7C15);
    let mut z = *state;
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    ((z ^ (z >> 31)) >> 11) as f64 / (1u64 << 53) as f64
}

fn height(x: f64, y: f64) -> f64 {
    0.02 * (7.0 * x).sin() * (5.0 * y).cos()
}

/// Vertices and triangle faces of the wavy grid.
fn grid(state: &mut u64) -> (Vec<[f64; 3]>, Vec<SurfaceFace>) {
    let n = CELLS;
    let h = 1.0 / n as f64;
    let mut points = Vec::with_capacity((n + 1) * (n + 1));
    for j in 0..=n {
        for i in 0..=n {
            let jitter = |s: &mut u64, k: usize| {
                if k == 0 || k == n {
                    0.0
                } else {
                    0.2 * h * (uniform(s) - 0.5)
                }
            };
            let x = i as f64 * h + jitter(state, i);
            let y = j as f64 * h + jitter(state, j);
            points.push([x, y, height(x, y)]);
        }
    }
    let id = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    let mut faces = Vec::with_capacity(2 * n * n);
    for j in 0..n {
        for i in 0..n {
            for nodes in [
                vec![id(i, j), id(i + 1, j), id(i + 1, j + 1)],
                vec![id(i, j), id(i + 1, j + 1), id(i, j + 1)],
            ] {
                faces.push(SurfaceFace {
                    kind: ElementType::Triangle3,
                    nodes,
                    tag: faces.len() as u64 + 1,
                });
            }
        }
    }
    (points, faces)
}

fn bench(c: &mut Criterion) {
    let mut state = 42u64;
    let (points, faces) = grid(&mut state);
    let queries: Vec<[f64; 3]> = (0..POINTS)
        .map(|_| {
            let (x, y) = (uniform(&mut state), uniform(&mut state));
            [x, y, height(x, y) + 0.005 * uniform(&mut state)]
        })
        .collect();
    let mut group = c.benchmark_group("sama");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(20));
    group.bench_function("build_1M_triangles", |b| {
        b.iter(|| TargetSurface::new(points.clone(), faces.clone(), "bench").unwrap())
    });
    let surface = TargetSurface::new(points, faces, "bench").unwrap();
    group.bench_function("project_100k", |b| {
        b.iter(|| {
            let p = surface.project_many(&queries, 0.01);
            assert!(p.iter().all(Option::is_some));
            p
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
