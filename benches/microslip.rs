//! The analytic single-harmonic friction point (Cigeroglu, An & Menq 2007; `evaluation =
//! "analytic"`) against the AFT evaluation of the same 1-D element at H = 1 (criterion).
//!
//! `microslip/...`: one 1-D element with one tangential direction and normal load variation,
//! evaluated with its Jacobian from its converged slider state (as in a Newton iteration), in
//! stick–slip without separation and with separation; the AFT at N_t = 64, 256, 1024 and 4096.
//! Before timing, each AFT prints its force error against the exact cycle (largest difference of
//! the harmonic coefficients over the largest coefficient), so the N_t that reaches a given
//! accuracy can be read off next to its time.
//! Run: `cargo bench --bench microslip` (about 30 s).

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nlrom::case::Evaluation;
use nlrom::contact::aft::Aft;
use nlrom::contact::element::{evaluate_as, LocalElement, Workspace};
use nlrom::contact::law::{ContactParams, Variant};
use nlrom::harmonics::HarmonicLayout;

fn microslip(c: &mut Criterion) {
    let mut g = c.benchmark_group("microslip");
    g.sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .throughput(Throughput::Elements(1));
    let el = LocalElement {
        params: ContactParams::new(2.0, 5.0, 0.4, 0.7, "bench").unwrap(),
        variant: Variant::OneD,
        tangential: 1,
        normal: true,
    };
    // u = 0.7 sin τ; v with b̄ = 0.3 (contact kept) and b̄ = 0.8 (separation), φ = 2.
    for (name, b) in [("stickslip", 0.084), ("separation", 0.224)] {
        let x = [0.0, 0.0, -0.7, 0.01, b * 2f64.sin(), -b * 2f64.cos()];
        let mut exact = [0.0; 6];
        for (evaluation, n_t, label) in [
            (Evaluation::Analytic, 64, "analytic".to_string()),
            (Evaluation::Aft, 64, "aft_Nt64".to_string()),
            (Evaluation::Aft, 256, "aft_Nt256".to_string()),
            (Evaluation::Aft, 1024, "aft_Nt1024".to_string()),
            (Evaluation::Aft, 4096, "aft_Nt4096".to_string()),
        ] {
            let aft = Aft::new(HarmonicLayout::new(1, n_t).unwrap()).unwrap();
            let mut ws = Workspace::new(&aft);
            let mut f = [0.0; 6];
            let mut state = [0.0; 2];
            evaluate_as(evaluation, &el, &aft, &x, &mut state, &mut f, true, &mut ws).unwrap();
            if evaluation == Evaluation::Analytic {
                exact = f;
            } else {
                let scale = exact.iter().fold(0.0f64, |a, v| a.max(v.abs()));
                let err = f
                    .iter()
                    .zip(&exact)
                    .fold(0.0f64, |a, (p, q)| a.max((p - q).abs()));
                eprintln!(
                    "{name} {label}: force error {:.2e} of the largest coefficient",
                    err / scale
                );
            }
            g.bench_function(format!("{name}_{label}_jacobian"), |bch| {
                bch.iter(|| {
                    let mut s = state;
                    evaluate_as(
                        evaluation,
                        &el,
                        &aft,
                        black_box(&x),
                        &mut s,
                        &mut f,
                        true,
                        &mut ws,
                    )
                    .unwrap();
                    black_box(&f);
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, microslip);
criterion_main!(benches);
