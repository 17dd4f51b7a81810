//! The speed comparison of Gastaldi & Berruti 2018 §6 / Fig. 8 on the demonstrator
//! (cases/damper.toml, 200 Hz, one period after the static start): wall time of each scheme
//! (criterion) and, printed once, its steps and corrector iterations relative to standard Newmark.
//!
//! `cargo bench --bench march` — ratios of the criterion means against `newmark` go in the README.

use std::path::Path;

use criterion::{criterion_group, criterion_main, Criterion};
use nlrom::case::{Case, MarchScheme};
use nlrom::march::from_case::{case_march, CaseMarch};
use nlrom::march::march;

fn setup(scheme: MarchScheme) -> CaseMarch {
    let path = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/cases/damper.toml"));
    let case = Case::load(path).expect("bundled damper case");
    let mut cm = case_march(&case, Some(scheme), &mut |_| {}).expect("damper march");
    cm.settings.periods = 1;
    cm
}

fn bench(c: &mut Criterion) {
    let reference = {
        let cm = setup(MarchScheme::Newmark);
        march(&cm.system, &cm.settings).expect("standard march")
    };
    for scheme in MarchScheme::ALL {
        let cm = setup(scheme);
        let out = march(&cm.system, &cm.settings).expect("march");
        eprintln!(
            "{scheme:>26}: {:>5} steps ({:.3} of standard), {:>6} iterations ({:.3} of standard), {:.1} % single-iteration steps",
            out.steps,
            out.steps as f64 / reference.steps as f64,
            out.total_iterations,
            out.total_iterations as f64 / reference.total_iterations as f64,
            100.0 * out.single_iteration_fraction()
        );
    }
    let mut group = c.benchmark_group("damper_200hz_one_period");
    group.sample_size(20);
    group.measurement_time(std::time::Duration::from_secs(2));
    for scheme in MarchScheme::ALL {
        let cm = setup(scheme);
        group.bench_function(scheme.as_str(), |b| {
            b.iter(|| march(&cm.system, &cm.settings).expect("march"))
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
