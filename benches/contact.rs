//! Contact element evaluation speed (criterion).
//!
//! `element/...`: one 3-D node-to-node element (two tangential directions and the normal) in
//! partial slip with normal load variation, evaluated from its converged slider state (as Newton
//! iterations after the first call do: one period marched plus the check), forces only and
//! forces + Jacobian, for H = 3 and H = 7 at the default N_t and for H = 3 at N_t = 32.
//! `pairs/...`: a [`PairSet`] of 512 inter-sector pairs (σ = 1) evaluated with 1 and 2 rayon
//! threads. Run: `cargo bench --bench contact` (about 1 minute).
//!
//! [`PairSet`]: nlrom::contact::pairs::PairSet

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nlrom::contact::aft::Aft;
use nlrom::contact::element::{evaluate, LocalElement, Workspace};
use nlrom::contact::law::{ContactParams, Variant};
use nlrom::harmonics::HarmonicLayout;

/// Local input of a 3-D element: u1, u2 of amplitude ~0.1 (stick limit 0.05), v of 0.01.
fn input(h: usize) -> Vec<f64> {
    let m = 2 * h + 1;
    let mut x = vec![0.0; 3 * m];
    for (c, a) in [0.1, 0.08, 0.01].into_iter().enumerate() {
        x[c * m + 1] = a;
        x[c * m + 2] = 0.3 * a * (c as f64 - 1.0);
        for n in 2..=h {
            x[c * m + 2 * n - 1] = 0.1 * a / n as f64;
        }
    }
    x
}

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
            let el = LocalElement {
                params: ContactParams::new(10.0, 20.0, 0.5, 1.0, "bench").unwrap(),
                variant,
                tangential: 2,
                normal: true,
            };
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

criterion_group!(benches, element);
criterion_main!(benches);
