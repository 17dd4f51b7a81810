//! The speed comparison of Thorin et al. (ASME GT2018-75959, 2018, §3.3, Fig. 16) on the blade
//! surrogate `cases/blade_casing.toml` (hexa20, 1476 displacement + 492 temperature DOF, 7 contact
//! nodes, friction and frictional heating) and on its Craig–Bampton model (`[reduction]
//! interface_modes = 20`: the 21 contact-node DOF, 20 fixed-interface modes and the heat rows in
//! contact temperatures and every conduction mode, 533 coordinates): Moreau–Jean at h = 1e-5 s
//! (the step of the paper's accuracy) against Carpenter's explicit scheme at 0.9 times its
//! stability limit 2/ω_max of the same model.
//!
//! Printed: the load average; per model its construction time and stability limits; per model
//! and scheme the set-up (step matrix, its factorisation, the Delassus matrix), the wall and CPU
//! time per step measured over a contact phase from rest, the projected wall and CPU time of 1 s
//! of simulated time; the reduced Moreau–Jean march is also run over the whole second. Then
//! where a Moreau–Jean step goes: one solve with the factors of the step matrix M̂, one product
//! with K, and the contact's share (a step in contact against the same step with the casing out
//! of reach). Then criterion's estimate of 20 steps of each scheme on both models.
//!
//! `cargo bench --bench nonsmooth` — the printed tables are those of docs/performance.md.

use std::path::Path;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion};
use nlrom::case::Case;
use nlrom::march::carpenter::{carpenter, stability_limits};
use nlrom::march::moreau_jean::moreau_jean;
use nlrom::march::obstacle::{NonsmoothSettings, NonsmoothSystem, SparseRows, StepLu};
use nlrom::problem::nonsmooth_case::nonsmooth_case;

/// The bundled surrogate with `extra` appended to its case text.
fn blade(extra: &str) -> (NonsmoothSystem, NonsmoothSettings) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/blade_casing.toml");
    let text = std::fs::read_to_string(&path).expect("bundled case") + extra;
    let case = Case::from_str(&text, &path).expect("bundled case");
    let sm = nlrom::model::build(&case, &mut |_| {}).expect("blade model");
    let nc = nonsmooth_case(&case, &sm).expect("blade march");
    (nc.system, nc.settings)
}

const REDUCED: &str = "\n[reduction]\ninterface_modes = 20\n";

/// CPU time (user + system, all threads) of this process so far (s), from /proc/self/stat
/// (clock ticks of 10 ms); 0 where it cannot be read.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the command name in parentheses: utime and stime are the 12th and 13th.
    let rest = stat.rsplit(')').next().unwrap_or("");
    let f: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |k: usize| f.get(k).and_then(|v| v.parse::<f64>().ok()).unwrap_or(0.0);
    (ticks(11) + ticks(12)) / 100.0
}

/// The 1-, 5- and 15-minute load averages.
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

/// Wall and CPU time (s) of `f`.
fn timed<T>(f: impl FnOnce() -> T) -> (T, f64, f64) {
    let (w, c) = (Instant::now(), cpu_seconds());
    let out = f();
    (out, w.elapsed().as_secs_f64(), cpu_seconds() - c)
}

/// One scheme on one model: set-up (a 1-step run) and the wall and CPU time per step over
/// `steps` steps.
struct Timing {
    setup: f64,
    wall: f64,
    cpu: f64,
}

fn per_step(run: &dyn Fn(usize), steps: usize) -> Timing {
    let ((), setup, _) = timed(|| run(1));
    let ((), wall, cpu) = timed(|| run(steps));
    Timing {
        setup,
        wall: (wall - setup) / (steps - 1) as f64,
        cpu: cpu / steps as f64,
    }
}

fn moreau_jean_run(sys: &NonsmoothSystem, s: &NonsmoothSettings, h: f64, steps: usize) {
    let st = NonsmoothSettings {
        step: h,
        steps,
        ..s.clone()
    };
    std::hint::black_box(moreau_jean(sys, &st).expect("moreau-jean"));
}

fn carpenter_run(sys: &NonsmoothSystem, s: &NonsmoothSettings, h: f64, steps: usize) {
    let st = NonsmoothSettings {
        step: h,
        steps,
        ..s.clone()
    };
    std::hint::black_box(carpenter(sys, &st).expect("carpenter"));
}

/// Where a Moreau–Jean step of `sys` at step `h` goes: the step in contact (`in_contact`)
/// against the same step with the casing 1 m away (the smooth part: products, block solves,
/// balances, records), the difference being the contact (active set, Delassus rows, LCP,
/// correction); with `parts`, one solve with the sparse LU of the whole M̂ and three products
/// with K or C.
fn breakdown(
    sys: &NonsmoothSystem,
    s: &NonsmoothSettings,
    h: f64,
    in_contact: &Timing,
    steps: usize,
    parts: bool,
) -> String {
    let mut free = sys.clone();
    for o in &mut free.obstacles {
        o.gap = 1.0;
    }
    let smooth = per_step(&|k| moreau_jean_run(&free, s, h, k), steps);
    let mut out = format!(
        "per step {:.4} ms wall / {:.4} ms CPU; out of contact {:.4} / {:.4} ms, so the contact {:.4} / {:.4} ms",
        1e3 * in_contact.wall,
        1e3 * in_contact.cpu,
        1e3 * smooth.wall,
        1e3 * smooth.cpu,
        1e3 * (in_contact.wall - smooth.wall),
        1e3 * (in_contact.cpu - smooth.cpu)
    );
    if parts {
        let n = sys.n;
        let gamma = s.gamma;
        let mhat: Vec<f64> = (0..n * n)
            .map(|ij| {
                sys.mass[ij]
                    + h * gamma * sys.damping[ij]
                    + h * h * gamma * gamma * sys.stiffness[ij]
            })
            .collect();
        let (lu, factor, _) = timed(|| StepLu::new(&mhat, n, "M̂").expect("factorisation"));
        let k = SparseRows::new(&sys.stiffness, n, 0..n, 0..n);
        let x = vec![1e-6; n];
        let reps = 200;
        let ((), solve, _) = timed(|| {
            for _ in 0..reps {
                std::hint::black_box(lu.solve(&x));
            }
        });
        let ((), product, _) = timed(|| {
            for _ in 0..reps {
                std::hint::black_box(k.mul(&x));
            }
        });
        out += &format!(
            "; sparse LU of the whole M̂ {factor:.3} s, one solve with it {:.3} ms, three products with K or C {:.3} ms (wall)",
            1e3 * solve / reps as f64,
            3e3 * product / reps as f64
        );
    }
    out
}

fn table() {
    println!("load average {}", load_average());
    println!("| model | scheme | step h (s) | set-up (s) | per step wall (ms) | per step CPU (ms) | 1 s simulated, wall (s) | 1 s simulated, CPU (s) |");
    println!("|---|---|---|---|---|---|---|---|");
    let mut notes = Vec::new();
    for (label, extra, mj_steps, c_steps) in
        [("full", "", 300, 3000), ("reduced", REDUCED, 10000, 20000)]
    {
        let ((sys, s), build_wall, build_cpu) = timed(|| blade(extra));
        let lim = stability_limits(&sys).expect("stability limits");
        let mj_h = 1e-5;
        let c_h = 0.9 * lim.mechanical;
        let mj = per_step(&|k| moreau_jean_run(&sys, &s, mj_h, k), mj_steps);
        let cp = per_step(&|k| carpenter_run(&sys, &s, c_h, k), c_steps);
        for (scheme, h, t) in [("Moreau–Jean", mj_h, &mj), ("Carpenter", c_h, &cp)] {
            println!(
                "| {label} ({} DOF) | {scheme} | {h:.2e} | {:.2} | {:.4} | {:.4} | {:.1} | {:.1} |",
                sys.n,
                t.setup,
                1e3 * t.wall,
                1e3 * t.cpu,
                t.setup + t.wall / h,
                t.cpu / h
            );
        }
        notes.push(format!(
            "{label}: model built in {build_wall:.2} s wall, {build_cpu:.2} s CPU; limits 2/ω_max = {:.3e} s, heat 2/μ_max = {:.3e} s; Carpenter / Moreau–Jean for 1 s: wall {:.0}, CPU {:.0}, steps {:.0}",
            lim.mechanical,
            lim.thermal,
            (cp.setup + cp.wall / c_h) / (mj.setup + mj.wall / mj_h),
            (cp.cpu / c_h) / (mj.cpu / mj_h),
            mj_h / c_h
        ));
        notes.push(format!(
            "{label} Moreau–Jean step: {}",
            breakdown(&sys, &s, mj_h, &mj, mj_steps, label == "full")
        ));
        if label == "reduced" {
            let steps = (1.0 / mj_h).round() as usize;
            let ((), wall, cpu) = timed(|| moreau_jean_run(&sys, &s, mj_h, steps));
            notes.push(format!(
                "reduced Moreau–Jean over the whole second ({steps} steps): {wall:.2} s wall, {cpu:.2} s CPU; with the model's construction {:.2} s wall, {:.2} s CPU",
                wall + build_wall,
                cpu + build_cpu
            ));
        }
    }
    for n in notes {
        println!("{n}");
    }
    println!("load average {}", load_average());
}

fn bench(c: &mut Criterion) {
    table();
    let mut g = c.benchmark_group("blade_casing_20_steps");
    g.sample_size(10);
    g.measurement_time(std::time::Duration::from_secs(5));
    for (label, extra) in [("full", ""), ("reduced", REDUCED)] {
        let (sys, s) = blade(extra);
        let lim = stability_limits(&sys).expect("stability limits");
        let mj = NonsmoothSettings {
            step: 1e-5,
            steps: 20,
            ..s.clone()
        };
        g.bench_function(format!("moreau_jean_{label}"), |b| {
            b.iter(|| moreau_jean(&sys, &mj).unwrap())
        });
        let cp = NonsmoothSettings {
            step: 0.9 * lim.mechanical,
            steps: 20,
            ..s.clone()
        };
        g.bench_function(format!("carpenter_{label}"), |b| {
            b.iter(|| carpenter(&sys, &cp).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
