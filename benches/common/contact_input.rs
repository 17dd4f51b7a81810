//! The inputs of the contact benchmarks, shared by `benches/contact.rs` and
//! `tools/benchmarks/contact_cost.rs`.

use nlrom::contact::element::LocalElement;
use nlrom::contact::law::{ContactParams, Variant};
use nlrom::contact::pairs::{PairElement, PairSet, SectorCoupling};
use nlrom::cyclic::{harmonic_indices, CyclicGeometry};
use nlrom::harmonics::HarmonicLayout;

/// The benchmark element: k_t = 10, k_n = 20, μ = 0.5, n0 = 1, two tangential directions and
/// the normal, law `variant`.
pub fn bench_element(variant: Variant) -> LocalElement {
    LocalElement {
        params: ContactParams::new(10.0, 20.0, 0.5, 1.0, "bench").unwrap(),
        variant,
        tangential: 2,
        normal: true,
    }
}

/// Local input of a 3-D element: u1, u2 of amplitude ~0.1 (stick limit 0.05), v of 0.01.
pub fn input(h: usize) -> Vec<f64> {
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

/// `pairs` inter-sector pairs (σ = 1, N = 24, engine order 3, 1-D law) among 64 nodes (192 DOFs;
/// H = 3 at the default N_t = 16: a dense Jacobian of 1344²) and a displacement vector that
/// puts them in partial slip. Returns (pair set, layout, q).
pub fn pair_set(pairs: usize) -> (PairSet, HarmonicLayout, Vec<f64>) {
    let geo = CyclicGeometry::new(24, [0.0; 3], [0.0, 0.0, 1.0]).unwrap();
    let h = 3;
    let layout = HarmonicLayout::with_default_samples(h);
    let list: Vec<PairElement> = (0..pairs)
        .map(|i| PairElement {
            contact: [0, 1, 2].map(|c| 3 * (i % 32) + c),
            target: Some([0, 1, 2].map(|c| 3 * (32 + (7 * i) % 32) + c)),
            frame: [[0.0, 0.0, 1.0], [0.6, -0.8, 0.0], [0.8, 0.6, 0.0]],
            sigma: 1,
            params: ContactParams::new(10.0, 20.0, 0.5, 1.0, "bench").unwrap(),
            preload_rate: 1.0,
        })
        .collect();
    let coupling = SectorCoupling {
        sectors: 24,
        rotation: geo.rotation(1),
        harmonic_indices: harmonic_indices(24, 3, h),
    };
    let set = PairSet::new(192, Variant::OneD, list, Some(coupling)).unwrap();
    let q: Vec<f64> = (0..layout.len(192))
        .map(|i| 0.05 * ((i * 7919 % 1000) as f64 / 500.0 - 1.0))
        .collect();
    (set, layout, q)
}
