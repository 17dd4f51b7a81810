//! Contact element evaluation speed (criterion).
//!
//! `element/...`: one 3-D node-to-node element (two tangential directions and the normal) in
//! partial slip with normal load variation, evaluated from its converged slider state (as Newton
//! iterations after the first call do: one period marched plus the check), forces only and
//! forces + Jacobian, for H = 3 and H = 7 at the default N_t and for H = 3 at N_t = 32.
//! `pairs/...`: a [`PairSet`] of 512 inter-sector pairs (σ = 1) evaluated with 1 and 2 rayon
//! threads (throughput in pairs). Run: `cargo bench --bench contact` (about 1 minute).
//!
//! [`PairSet`]: nlrom::contact::pairs::PairSet

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
#[path = "common/contact_input.rs"]
mod contact_input;
use contact_input::{bench_element, input, pair_set};
use nlrom::contact::aft::Aft;
use nlrom::contact::element::{evaluate, Workspace};
use nlrom::contact::law::Variant;
use nlrom::harmonics::{HarmonicForce, HarmonicLayout};

fn element(c: &mut Criterion) {
    let mut g = c.benchmark_group("element");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(1));
    for (variant, vname) in [(Variant::OneD, "1d"), (Variant::TwoD, "2d")] {
        for (h, n_t) in [(3, 16), (3, 32), (7, 32)] {
            let aft = Aft::new(HarmonicLayout::new(h, n_t).unwrap()).unwrap();
            let mut ws = Workspace::new(&aft);
            let el = bench_element(variant);
            let x = input(h);
            let mut f = vec![0.0; x.len()];
            let mut state = [0.0; 2];
            evaluate(&el, &aft, &x, &mut state, &mut f, false, &mut ws).unwrap();
            for (jac, jname) in [(false, "forces"), (true, "jacobian")] {
                g.bench_function(format!("{vname}_H{h}_Nt{n_t}_{jname}"), |b| {
                    b.iter(|| {
                        let mut s = state;
                        evaluate(&el, &aft, black_box(&x), &mut s, &mut f, jac, &mut ws).unwrap();
                        black_box(&f);
                    })
                });
            }
        }
    }
    g.finish();
}

/// 512 inter-sector pairs (σ = 1, N = 24, engine order 3) among 64 nodes (192 DOFs; a dense
/// Jacobian of 1344²); the whole
/// `HarmonicForce::evaluate` (gather, kinematics, elements, transpose, scatter) from the
/// converged state, forces only and with the dense Jacobian, with 1 and 2 rayon threads.
fn pairs(c: &mut Criterion) {
    const PAIRS: usize = 512;
    let mut g = c.benchmark_group("pairs");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2))
        .throughput(Throughput::Elements(PAIRS as u64));
    let (set, layout, q) = pair_set(PAIRS);
    let n = q.len();
    let mut state = set.initial_state();
    let mut f = vec![0.0; n];
    set.evaluate(&layout, &q, &mut state, &mut f, None).unwrap();
    let mut jac = faer::Mat::<f64>::zeros(n, n);
    for threads in [1, 2] {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        for (with_jac, jname) in [(false, "forces"), (true, "jacobian")] {
            g.bench_function(format!("H3_Nt16_{jname}_{threads}threads"), |b| {
                b.iter(|| {
                    pool.install(|| {
                        let mut s = state.clone();
                        let j = with_jac.then(|| jac.as_mut());
                        set.evaluate(&layout, black_box(&q), &mut s, &mut f, j)
                            .unwrap();
                    })
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, element, pairs);
criterion_main!(benches);
