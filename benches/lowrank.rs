//! Column updates against new builds of the low-rank step factors (`src/march/lowrank.rs`), at the
//! size of the travelling-wave march on `sector8` (2312 coordinates, 720 friction elements, each
//! direction on 6 coordinates), for factors of rank r = 100…700 (r slipping elements).
//!
//! Per rank: the wall time of a new build ([`LowRank::new`]), of one changed column by updates
//! ([`LowRank::update`], 4 and 16 elements reversing their slip: 8 and 32 columns), and the
//! crossover, the number of changed columns whose updates cost one build, also as a fraction of r
//! (the rule [`UPDATE_FRACTION`] builds anew above it). Minimum over 7 repetitions each. Then
//! criterion's estimates of the build and of an 8-column update at r = 400.
//!
//! `cargo bench --bench lowrank` (about 30 s).

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion};
use nlrom::march::element::{Direction, Element};
use nlrom::march::law::{ContactState, FrictionParams, Sign};
use nlrom::march::lowrank::{LowRank, UPDATE_FRACTION};
use nlrom::march::signal::Harmonic;

const N: usize = 2312;
const ELEMENTS: usize = 720;

/// A linear congruential sequence in [0, 1).
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (self.0 >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// The elements (pairs sharing a normal force) and a dense stand-in for the all-stick inverse,
/// 0.1 (I + 0.01 R) with R of entries in [−1, 1).
fn model() -> (Vec<Element>, Vec<f64>) {
    let mut rng = Lcg(2024);
    let direction = |rng: &mut Lcg| Direction {
        weights: (0..6)
            .map(|_| ((rng.next() * N as f64) as usize, rng.next() - 0.5))
            .collect(),
        prescribed: Harmonic::default(),
    };
    let elements = (0..ELEMENTS)
        .map(|e| Element {
            name: format!("e{e}"),
            tangential: direction(&mut rng),
            normal: Some(direction(&mut rng)),
            params: FrictionParams {
                kt: 1.0,
                kn: 1.0,
                mu: 0.3,
                n0: 1.0,
            },
            applies_normal: e % 2 == 0,
        })
        .collect();
    let inverse = (0..N * N)
        .map(|ij| 0.1 * (f64::from(u8::from(ij / N == ij % N)) + 0.02 * (rng.next() - 0.5)))
        .collect();
    (elements, inverse)
}

/// The first `r` elements slipping, the rest stuck (rank r).
fn slipping(r: usize) -> Vec<ContactState> {
    (0..ELEMENTS)
        .map(|e| {
            if e < r {
                ContactState::Slip(Sign::Positive)
            } else {
                ContactState::Stick
            }
        })
        .collect()
}

/// `states` with the slip of the first `m` elements reversed (2 m changed columns).
fn reversed(states: &[ContactState], m: usize) -> Vec<ContactState> {
    let mut out = states.to_vec();
    out[..m].fill(ContactState::Slip(Sign::Negative));
    out
}

/// Minimum wall time (s) of `f` over 7 calls, each after `prepare`.
fn best<T>(mut prepare: impl FnMut() -> T, mut f: impl FnMut(T)) -> f64 {
    (0..7)
        .map(|_| {
            let x = prepare();
            let t0 = Instant::now();
            f(x);
            t0.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

fn table(elements: &[Element], inverse: &[f64]) {
    eprintln!("\nlow-rank factors, n = {N}, {ELEMENTS} elements: build against column updates");
    eprintln!(
        "rank r | build ms | per column µs (8 / 32 columns) | crossover columns | crossover / r"
    );
    for r in [100, 200, 400, 700] {
        let states = slipping(r);
        let build = best(
            || (),
            |_| {
                black_box(LowRank::new(inverse, N, elements, &states).expect("factors"));
            },
        );
        let base = LowRank::new(inverse, N, elements, &states).expect("factors");
        let per_column = |m: usize| {
            let target = reversed(&states, m);
            if base.changed_columns(elements, &target) as f64 > UPDATE_FRACTION * r as f64 {
                return f64::NAN;
            }
            best(
                || base.clone(),
                |mut lr| assert!(lr.update(inverse, elements, &target), "update refused"),
            ) / (2 * m) as f64
        };
        let (c8, c32) = (per_column(4), per_column(16));
        let crossover = build / c8;
        eprintln!(
            "{r} | {:.2} | {:.1} / {:.1} | {crossover:.0} | {:.3}",
            build * 1e3,
            c8 * 1e6,
            c32 * 1e6,
            crossover / r as f64
        );
    }
}

fn bench(c: &mut Criterion) {
    let (elements, inverse) = model();
    table(&elements, &inverse);
    let states = slipping(400);
    let target = reversed(&states, 4);
    let base = LowRank::new(&inverse, N, &elements, &states).expect("factors");
    let mut g = c.benchmark_group("lowrank_r400");
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(300))
        .measurement_time(Duration::from_secs(2));
    g.bench_function("build", |b| {
        b.iter(|| LowRank::new(&inverse, N, &elements, &states).expect("factors"))
    });
    g.bench_function("update_8_columns", |b| {
        b.iter_batched(
            || base.clone(),
            |mut lr| lr.update(&inverse, &elements, &target),
            criterion::BatchSize::LargeInput,
        )
    });
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
