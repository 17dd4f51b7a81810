//! FE assembly throughput (criterion): `fe::assemble` (K and M) on structured tetra10 boxes of
//! n × n × n cells (6 tetrahedra per cell), from ~25 k to ~1.05 M DOF, plus a hexa20 box.
//!
//! Run: `cargo bench --bench fe_assembly`. `NLROM_BENCH_FE_SIZES=10,20` picks the tetra10 sizes
//! (default 10, 20, 35; 35 gives 1.05 M DOF). Before each size the DOF count, the number of stored
//! entries, the bytes of the two matrices and the process's peak resident memory (VmHWM) after
//! one assembly are printed to stderr.

use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use nlrom::fe::structured::StructuredBox;
use nlrom::fe::{assemble, Material, Materials, Quadrature};
use nlrom::mesh::{ElementType, Mesh};

const STEEL: Material = Material {
    young: 210e9,
    poisson: 0.3,
    density: 7800.0,
};

/// Peak resident set size of this process (kB), from /proc (Linux only; 0 elsewhere).
fn peak_rss_kb() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1).and_then(|v| v.parse().ok()))
        })
        .unwrap_or(0)
}

/// Assembles once and reports size, time and memory.
fn report(label: &str, mesh: &Mesh) {
    let t = Instant::now();
    let a = assemble(mesh, &Materials::uniform(STEEL), &Quadrature::default()).expect("assembles");
    let secs = t.elapsed().as_secs_f64();
    let (nnz_k, nnz_m) = (a.k.val().len(), a.m.val().len());
    // Values (8 B) + row indices (8 B) per entry, plus column pointers, two matrices.
    let bytes = 16 * (nnz_k + nnz_m) + 16 * (a.n_dofs() + 1);
    eprintln!(
        "{label}: {} elements, {} DOF, {nnz_k} entries in K, {nnz_m} in M, K+M {:.2} GB, first assembly {secs:.2} s, peak RSS {:.2} GB",
        mesh.num_elements(),
        a.n_dofs(),
        bytes as f64 / 1e9,
        peak_rss_kb() as f64 / 1e6
    );
}

fn bench_box(c: &mut Criterion, kind: ElementType, sizes: &[usize]) {
    let mut group = c.benchmark_group(format!("fe_assembly/{kind}"));
    for &n in sizes {
        let mesh = StructuredBox::new(kind, [n; 3], [1.0; 3])
            .distorted(0.1, 1)
            .build()
            .expect("box mesh");
        report(&format!("{kind} {n}³"), &mesh);
        let dofs = 3 * mesh.num_nodes() as u64;
        group.sample_size(10);
        group.measurement_time(Duration::from_secs(match dofs {
            d if d > 500_000 => 90,
            d if d > 100_000 => 20,
            _ => 15,
        }));
        group.throughput(Throughput::Elements(dofs));
        group.bench_with_input(
            BenchmarkId::from_parameter(format!("{n}^3 ({dofs} DOF)")),
            &mesh,
            |b, mesh| {
                b.iter(|| {
                    assemble(mesh, &Materials::uniform(STEEL), &Quadrature::default())
                        .expect("assembles")
                })
            },
        );
    }
    group.finish();
}

fn fe(c: &mut Criterion) {
    let sizes: Vec<usize> = std::env::var("NLROM_BENCH_FE_SIZES")
        .ok()
        .map(|s| s.split(',').filter_map(|v| v.trim().parse().ok()).collect())
        .unwrap_or_else(|| vec![10, 20, 35]);
    bench_box(c, ElementType::Tetra10, &sizes);
    bench_box(c, ElementType::Hexa20, &[12]);
}

criterion_group!(benches, fe);
criterion_main!(benches);
