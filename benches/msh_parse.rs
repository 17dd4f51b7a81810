//! MSH parsing throughput (criterion): `parse_msh` on a file held in memory, per MSH variant.
//!
//! Always: the bundled conforming sector (`meshes/`), four variants. With the large generated mesh
//! present (`python3 tools/meshes/make_large_mesh.py tools/large/box`, ~1.7 M tetra10, not committed) or
//! `NLROM_BENCH_MESH=PREFIX` set, also PREFIX.{v41-binary,v41-ascii,v22-binary,v22-ascii}.msh.
//! Run: `cargo bench --bench msh_parse`. Throughput is reported in bytes of file per second.
//! `cargo bench --bench msh_parse -- float_parse` compares the two float parsers.

use std::path::{Path, PathBuf};
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use nlrom::mesh::msh::parse_msh;

const VARIANTS: [&str; 4] = ["v41-binary", "v41-ascii", "v22-binary", "v22-ascii"];

fn bundled(variant: &str) -> PathBuf {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    if variant == "v41-ascii" {
        root.join("meshes/sector_conforming.msh")
    } else {
        root.join(format!("meshes/formats/sector_conforming.{variant}.msh"))
    }
}

fn bench_files(c: &mut Criterion, group_name: &str, files: &[(String, PathBuf)], samples: usize) {
    let mut group = c.benchmark_group(group_name);
    group.sample_size(samples);
    group.measurement_time(Duration::from_secs(if samples <= 10 { 20 } else { 5 }));
    for (variant, path) in files {
        let bytes = std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        group.throughput(Throughput::Bytes(bytes.len() as u64));
        group.bench_with_input(BenchmarkId::from_parameter(variant), &bytes, |b, bytes| {
            b.iter(|| parse_msh(bytes).expect("parses"))
        });
    }
    group.finish();
}

fn msh(c: &mut Criterion) {
    let small: Vec<(String, PathBuf)> = VARIANTS
        .iter()
        .map(|v| (v.to_string(), bundled(v)))
        .collect();
    bench_files(c, "parse_msh/sector_conforming", &small, 50);

    let prefix = std::env::var("NLROM_BENCH_MESH")
        .unwrap_or_else(|_| format!("{}/tools/large/box", env!("CARGO_MANIFEST_DIR")));
    let large: Vec<(String, PathBuf)> = VARIANTS
        .iter()
        .map(|v| (v.to_string(), PathBuf::from(format!("{prefix}.{v}.msh"))))
        .filter(|(_, p)| p.exists())
        .collect();
    if large.is_empty() {
        eprintln!(
            "large mesh {prefix}.*.msh not found: run tools/meshes/make_large_mesh.py to bench it"
        );
    } else {
        bench_files(c, "parse_msh/large_tetra10", &large, 10);
    }
}

/// The float parser of the ASCII readers: `str::parse::<f64>` on the token (what the sequential
/// reader uses) against `fast_float2::parse_partial` on the bytes (what the parallel line
/// readers use), on 300 000 coordinates written as Gmsh writes them (`%.16g`).
fn floats(c: &mut Criterion) {
    let mut text = String::new();
    let mut x = 0.123_456_789_f64;
    for k in 0..300_000 {
        x = (x * 3.7 + 0.011 * k as f64).fract() - 0.5;
        text += &format!("{} ", x * 10f64.powi((k % 7) - 3));
    }
    let bytes = text.as_bytes();
    let mut group = c.benchmark_group("float_parse");
    group.throughput(Throughput::Bytes(bytes.len() as u64));
    group.bench_function("std_str_parse", |b| {
        b.iter(|| {
            bytes
                .split(|&c| c == b' ')
                .filter(|t| !t.is_empty())
                .map(|t| std::str::from_utf8(t).unwrap().parse::<f64>().unwrap())
                .sum::<f64>()
        })
    });
    group.bench_function("fast_float2", |b| {
        b.iter(|| {
            let mut i = bytes;
            let mut sum = 0.0;
            while !i.is_empty() {
                let (v, n) = fast_float2::parse_partial::<f64, _>(i).unwrap();
                sum += v;
                i = &i[n + 1..];
            }
            sum
        })
    });
    group.finish();
}

criterion_group!(benches, msh, floats);
criterion_main!(benches);
