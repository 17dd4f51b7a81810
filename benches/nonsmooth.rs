//! The speed comparison of Thorin et al. (ASME GT2018-75959, 2018, §3.3, Fig. 16) on the blade
//! surrogate `cases/blade_casing.toml` (hexa20, 1476 displacement + 492 temperature DOF, 7 contact
//! nodes, friction and frictional heating): Moreau–Jean at h = 1e-5 s (the step of the paper's
//! accuracy) against Carpenter's explicit scheme at 0.9 times its stability limit 2/ω_max.
//!
//! Printed: the stability limits; per scheme the set-up (step matrix, its factorisation, the
//! Delassus matrix), the wall time per step measured over a contact phase from rest, the
//! projected wall time of 1 s of simulated time and the ratio; then where a step's time goes
//! (one solve with the factorised step matrix, one product with K, the rest: LCP, energy and heat
//! balances, records). Then criterion's estimate of 20 steps of each scheme.
//!
//! `cargo bench --bench nonsmooth` — the printed table is the one of docs/performance.md.

use std::path::Path;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion};
use nlrom::case::Case;
use nlrom::march::carpenter::{carpenter, stability_limits};
use nlrom::march::moreau_jean::moreau_jean;
use nlrom::march::obstacle::{NonsmoothSettings, NonsmoothSystem, SparseRows, StepLu};
use nlrom::problem::nonsmooth_case::nonsmooth_case;

fn blade() -> (NonsmoothSystem, NonsmoothSettings) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/blade_casing.toml");
    let case = Case::load(&path).expect("bundled case");
    let sm = nlrom::model::build(&case, &mut |_| {}).expect("blade model");
    let nc = nonsmooth_case(&case, &sm).expect("blade march");
    (nc.system, nc.settings)
}

/// Wall time (s) of `steps` steps and of a 1-step run (the set-up), per step.
fn per_step(run: &dyn Fn(usize) -> f64, steps: usize) -> (f64, f64) {
    let setup = run(1);
    let total = run(steps);
    (setup, (total - setup) / (steps - 1) as f64)
}

fn table() {
    let (sys, s) = blade();
    let n = sys.n;
    let t = Instant::now();
    let lim = stability_limits(&sys).expect("stability limits");
    println!(
        "blade surrogate: {n} DOF ({} displacements), {} contact nodes; stability limits: mechanical 2/ω_max = {:.3e} s, heat 2/μ_max = {:.3e} s ({:.1} s to compute)",
        sys.n_mech,
        sys.obstacles.len(),
        lim.mechanical,
        lim.thermal,
        t.elapsed().as_secs_f64()
    );
    let mj_h = 1e-5;
    let c_h = 0.9 * lim.mechanical;
    let mj = |steps: usize| -> f64 {
        let st = NonsmoothSettings {
            step: mj_h,
            steps,
            ..s.clone()
        };
        moreau_jean(&sys, &st).expect("moreau-jean").wall_seconds
    };
    let cp = |steps: usize| -> f64 {
        let st = NonsmoothSettings {
            step: c_h,
            steps,
            ..s.clone()
        };
        carpenter(&sys, &st).expect("carpenter").wall_seconds
    };
    let (mj_setup, mj_step) = per_step(&mj, 300);
    let (c_setup, c_step) = per_step(&cp, 3000);
    let (mj_1s, c_1s) = (mj_setup + mj_step / mj_h, c_setup + c_step / c_h);
    println!("| scheme | step h (s) | set-up (s) | per step (ms) | 1 s simulated (s) |");
    println!("|---|---|---|---|---|");
    println!(
        "| Moreau–Jean | {mj_h:.1e} | {mj_setup:.2} | {:.3} | {mj_1s:.0} |",
        1e3 * mj_step
    );
    println!(
        "| Carpenter | {c_h:.2e} | {c_setup:.2} | {:.3} | {c_1s:.0} |",
        1e3 * c_step
    );
    println!(
        "wall-time ratio Carpenter / Moreau–Jean for 1 s: {:.0}; step ratio {:.0}",
        c_1s / mj_1s,
        mj_h / c_h
    );
    // Where a Moreau–Jean step goes.
    let gamma = s.gamma;
    let mhat: Vec<f64> = (0..n * n)
        .map(|ij| {
            sys.mass[ij]
                + mj_h * gamma * sys.damping[ij]
                + mj_h * mj_h * gamma * gamma * sys.stiffness[ij]
        })
        .collect();
    let t = Instant::now();
    let lu = StepLu::new(&mhat, n, "M̂").expect("factorisation");
    let factor = t.elapsed().as_secs_f64();
    let k = SparseRows::new(&sys.stiffness, n, 0..n, 0..n);
    let x = vec![1e-6; n];
    let reps = 200;
    let t = Instant::now();
    for _ in 0..reps {
        std::hint::black_box(lu.solve(&x));
    }
    let solve = t.elapsed().as_secs_f64() / reps as f64;
    let t = Instant::now();
    for _ in 0..reps {
        std::hint::black_box(k.mul(&x));
    }
    let product = t.elapsed().as_secs_f64() / reps as f64;
    println!(
        "Moreau–Jean step: factorisation of M̂ {:.3} s once; per step one solve {:.3} ms, three products with K or C {:.3} ms, the rest (LCP, balances, records) {:.3} ms",
        factor,
        1e3 * solve,
        3e3 * product,
        1e3 * (mj_step - solve - 3.0 * product)
    );
}

fn bench(c: &mut Criterion) {
    table();
    let (sys, s) = blade();
    let lim = stability_limits(&sys).expect("stability limits");
    let mut g = c.benchmark_group("blade_casing_20_steps");
    g.sample_size(10);
    g.measurement_time(std::time::Duration::from_secs(5));
    let mj = NonsmoothSettings {
        step: 1e-5,
        steps: 20,
        ..s.clone()
    };
    g.bench_function("moreau_jean", |b| {
        b.iter(|| moreau_jean(&sys, &mj).unwrap())
    });
    let cp = NonsmoothSettings {
        step: 0.9 * lim.mechanical,
        steps: 20,
        ..s.clone()
    };
    g.bench_function("carpenter", |b| b.iter(|| carpenter(&sys, &cp).unwrap()));
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
