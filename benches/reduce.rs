//! Craig–Bampton reduction (criterion): `nlrom::reduction::craig_bampton` on a case's model —
//! one sparse Cholesky of K_ii, the fixed-interface modes, the streamed static modes and the
//! reduced K_cb, M_cb (model assembly excluded).
//!
//! Default: the bundled sector (cases/sector_modes.toml: 753 master DOF — both frontiers, shroud
//! contact and target, excitation — 10 878 interior DOF) with 100 interface modes. With
//! `NLROM_BENCH_REDUCE_CASE=tools/large/reduce/case.toml` (made by
//! `python3 tools/benchmarks/bench_reduce.py mesh`: ~116 000 free DOF, 2 964 master DOF, 100 interface
//! modes from its `[reduction]` table, masters from `reduction.keep`) the issue-4 benchmark.
//! Run: `cargo bench --bench reduce` (10 samples).

use std::path::PathBuf;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use nlrom::case::Case;
use nlrom::model;
use nlrom::reduction::{case_master_groups, craig_bampton, partition, CbOptions};
use nlrom::rom::MasterRole;

/// Master groups of the bundled sector (as tests/reduction_cb.rs).
fn sector_groups() -> Vec<(String, MasterRole)> {
    vec![
        ("left_frontier".into(), MasterRole::LowFrontier),
        ("right_frontier".into(), MasterRole::HighFrontier),
        ("shroud_contact".into(), MasterRole::Contact),
        ("shroud_target".into(), MasterRole::Target),
        ("excitation".into(), MasterRole::Keep),
    ]
}

fn reduce(c: &mut Criterion) {
    let root = PathBuf::from(env!("CARGO_MANIFEST_DIR"));
    let (path, from_env) = match std::env::var("NLROM_BENCH_REDUCE_CASE") {
        Ok(p) => (PathBuf::from(p), true),
        Err(_) => (root.join("cases/sector_modes.toml"), false),
    };
    let case = Case::load(&path).expect("case");
    let model = model::build(&case, &mut |_| {}).expect("model");
    let (groups, modes) = if from_env {
        let modes = case.reduction.as_ref().map_or(100, |r| r.interface_modes);
        (case_master_groups(&case), modes)
    } else {
        (sector_groups(), 100)
    };
    let part = partition(&model, &groups).expect("partition");
    let opts = CbOptions {
        interface_modes: modes,
        ..CbOptions::default()
    };
    let mut group = c.benchmark_group(format!(
        "cb_{}dof_{}masters_{}modes",
        model.free.n_free(),
        part.n_masters(),
        modes
    ));
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(60));
    group.bench_function("craig_bampton", |b| {
        b.iter(|| {
            craig_bampton(model.free.k.as_ref(), model.free.m.as_ref(), &part, &opts)
                .expect("reduces")
        })
    });
    group.finish();
}

criterion_group!(benches, reduce);
criterion_main!(benches);
