//! The analytic single-harmonic friction point (Cigeroglu, An & Menq 2007; `evaluation =
//! "analytic"`) against the AFT evaluation of the same 1-D element at H = 1 (criterion).
//!
//! `microslip/...`: one 1-D element with one tangential direction and normal load variation
//! (`common/microslip_input.rs`), evaluated with its Jacobian (forces, end slider state and the
//! local Jacobian with the ∂n0 column) from its converged slider state, as in a Newton iteration,
//! by both paths on the same element and the same motion, in four regimes of the paper (§2.2):
//! complete stick, stick–slip at constant load (Jenkins), stick–slip with normal load variation
//! and stick–slip–separation; the AFT at N_t = 64, 256, 1024 and 4096. Before timing, each case
//! prints the regime of its exact cycle and each AFT its force error against it (largest
//! difference of the harmonic coefficients over the largest coefficient), so the N_t that reaches
//! a given accuracy can be read off next to its time.
//! Run: `cargo bench --bench microslip` (about 1 min). Load-independent instruction counts and
//! CPU times of the same evaluations: `tools/benchmarks/contact_cost.rs` (`microslip`).

use std::hint::black_box;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use nlrom::case::Evaluation;
use nlrom::contact::aft::Aft;
use nlrom::contact::element::{evaluate_as, Workspace};
use nlrom::contact::microslip;
use nlrom::harmonics::HarmonicLayout;

#[path = "common/microslip_input.rs"]
mod microslip_input;
use microslip_input::{microslip_element, microslip_motions};

fn microslip(c: &mut Criterion) {
    let mut g = c.benchmark_group("microslip");
    g.sample_size(20)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(1))
        .throughput(Throughput::Elements(1));
    let el = microslip_element();
    for (name, x) in microslip_motions() {
        let cycle = microslip::cycle(&el.params, [x[0], x[1], x[2]], [x[3], x[4], x[5]], 0.0);
        eprintln!("{name}: {}", cycle.unwrap().regime.name());
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
