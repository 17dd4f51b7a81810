//! Relative kinematics with the inter-sector rotation and phase (`nlrom::contact::kinematics`) and
//! sets of contact pairs as a `HarmonicForce` (`nlrom::contact::pairs`): complex-arithmetic
//! reference, adjointness of the force map, rigid motions giving no relative displacement, frame
//! invariance, the assembled Jacobian and ∂F/∂n0 against central finite differences, thread-count
//! independence, input errors.

use faer::Mat;
use nlrom::case::Evaluation;
use nlrom::contact::kinematics::{relative_local, relative_transpose, Phases};
use nlrom::contact::law::{ContactParams, Variant};
use nlrom::contact::pairs::{PairElement, PairSet, SectorCoupling};
use nlrom::cyclic::{harmonic_indices, CyclicGeometry};
use nlrom::harmonics::{HarmonicForce, HarmonicLayout};
use nlrom::vec3::{mat_mul, Mat3};

mod support;
use support::contact::{check_derivative, check_jacobian, forces};
use support::random::XorShift;

/// A rotation matrix from a random axis and angle (Rodrigues).
fn random_rotation(rng: &mut XorShift) -> Mat3 {
    let g = CyclicGeometry::new(
        7,
        [0.0; 3],
        [rng.uniform(), rng.uniform(), 0.5 + rng.uniform()],
    )
    .unwrap();
    // compose two different sector rotations about the random axis with a permutation-free twist
    let r = g.rotation(2);
    let h = CyclicGeometry::new(5, [0.0; 3], [1.0, rng.uniform(), rng.uniform()]).unwrap();
    mat_mul(&r, &h.rotation(1))
}

fn mat_vec(a: &Mat3, v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| a[i][0] * v[0] + a[i][1] * v[1] + a[i][2] * v[2])
}

/// Complex amplitude of harmonic n ≥ 1 of component c (signal order, 3 components × m).
fn complex(q: &[f64], m: usize, c: usize, n: usize) -> (f64, f64) {
    (q[c * m + 2 * n - 1], q[c * m + 2 * n])
}

#[test]
fn relative_kinematics_match_complex_arithmetic() {
    let mut rng = XorShift(3);
    let h = 4;
    let m = 2 * h + 1;
    let geo = CyclicGeometry::new(24, [0.0; 3], [0.0, 0.0, 1.0]).unwrap();
    let k = harmonic_indices(24, 5, h); // 0, 5, 10, 15, 20
    let frame = random_rotation(&mut rng);
    for sigma in [-1, 0, 1] {
        let r = geo.rotation(sigma);
        let ph = Phases::cyclic(sigma, &k, 24).unwrap();
        let qc = rng.vec(3 * m, 1.0);
        let qt = rng.vec(3 * m, 1.0);
        let mut out = vec![0.0; 3 * m];
        relative_local(&frame, &mat_mul(&frame, &r), &ph, &qc, Some(&qt), &mut out);
        // n = 0: F (q_c − R q_t)
        let t0 = mat_vec(&r, [qt[0], qt[m], qt[2 * m]]);
        let rel0 = mat_vec(&frame, [qc[0] - t0[0], qc[m] - t0[1], qc[2 * m] - t0[2]]);
        for a in 0..3 {
            assert!((out[a * m] - rel0[a]).abs() < 1e-14);
        }
        for n in 1..=h {
            let theta = sigma as f64 * 2.0 * std::f64::consts::PI * k[n] as f64 / 24.0;
            let (s, c) = theta.sin_cos();
            // e^{iθ} Q_t, then R, then subtract from Q_c and project.
            let tr: Vec<(f64, f64)> = (0..3)
                .map(|i| {
                    let (re, im) = complex(&qt, m, i, n);
                    (c * re - s * im, s * re + c * im)
                })
                .collect();
            let rot_re = mat_vec(&r, [tr[0].0, tr[1].0, tr[2].0]);
            let rot_im = mat_vec(&r, [tr[0].1, tr[1].1, tr[2].1]);
            let dre = [0, 1, 2].map(|i| complex(&qc, m, i, n).0 - rot_re[i]);
            let dim = [0, 1, 2].map(|i| complex(&qc, m, i, n).1 - rot_im[i]);
            let (lre, lim) = (mat_vec(&frame, dre), mat_vec(&frame, dim));
            for a in 0..3 {
                assert!(
                    (out[a * m + 2 * n - 1] - lre[a]).abs() < 1e-13,
                    "σ={sigma} n={n}"
                );
                assert!(
                    (out[a * m + 2 * n] - lim[a]).abs() < 1e-13,
                    "σ={sigma} n={n}"
                );
            }
        }
    }
}

#[test]
fn force_map_is_the_transpose_of_the_kinematic_map() {
    let mut rng = XorShift(11);
    let h = 3;
    let m = 2 * h + 1;
    let frame = random_rotation(&mut rng);
    let target_frame = mat_mul(&frame, &random_rotation(&mut rng));
    let ph = Phases::cyclic(1, &[0, 3, 6, 9], 10).unwrap();
    let (qc, qt, g) = (
        rng.vec(3 * m, 1.0),
        rng.vec(3 * m, 1.0),
        rng.vec(3 * m, 1.0),
    );
    let mut r = vec![0.0; 3 * m];
    relative_local(&frame, &target_frame, &ph, &qc, Some(&qt), &mut r);
    let (mut fc, mut ft) = (vec![0.0; 3 * m], vec![0.0; 3 * m]);
    relative_transpose(&frame, &target_frame, &ph, &g, &mut fc, Some(&mut ft));
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let lhs = dot(&g, &r);
    let rhs = dot(&fc, &qc) + dot(&ft, &qt);
    assert!(
        (lhs - rhs).abs() < 1e-13 * lhs.abs().max(1.0),
        "{lhs} vs {rhs}"
    );
}

/// At k = 0 a rigid rotation of the whole disk (every sector alike) moves a contact node and the
/// image R_α^σ X_t of its target identically: zero relative displacement in every harmonic.
#[test]
fn rigid_disk_rotation_gives_no_relative_motion_at_k0() {
    let geo = CyclicGeometry::new(24, [0.0; 3], [0.0, 0.0, 1.0]).unwrap();
    let h = 3;
    let m = 2 * h + 1;
    let k = harmonic_indices(24, 0, h); // all zero
    let x_t = [0.2, 0.013, 0.01];
    let frame = [[0.0, 0.0, 1.0], [0.6, -0.8, 0.0], [0.8, 0.6, 0.0]];
    let mut rng = XorShift(17);
    for sigma in [-1, 1] {
        let r = geo.rotation(sigma);
        let x_c = mat_vec(&r, x_t); // the contact node sits on the target's image
                                    // Rigid rotation about z with angle amplitudes ε_l per coefficient: u = ε_l (ẑ × X).
        let eps = rng.vec(m, 1e-3);
        let field = |x: [f64; 3]| {
            let mut q = vec![0.0; 3 * m];
            for (l, e) in eps.iter().enumerate() {
                q[l] = -e * x[1];
                q[m + l] = e * x[0];
            }
            q
        };
        let (qc, qt) = (field(x_c), field(x_t));
        let ph = Phases::cyclic(sigma, &k, 24).unwrap();
        let mut out = vec![1.0; 3 * m];
        relative_local(&frame, &mat_mul(&frame, &r), &ph, &qc, Some(&qt), &mut out);
        assert!(out.iter().all(|v| v.abs() < 1e-17), "σ={sigma}: {out:?}");
        // With k ≠ 0 the same motion does produce relative motion (the phase matters).
        let ph5 = Phases::cyclic(sigma, &harmonic_indices(24, 5, h), 24).unwrap();
        relative_local(&frame, &mat_mul(&frame, &r), &ph5, &qc, Some(&qt), &mut out);
        assert!(out.iter().any(|v| v.abs() > 1e-6));
    }
}

fn params(n0: f64) -> ContactParams {
    ContactParams::new(10.0, 20.0, 0.5, n0, "test").unwrap()
}

/// Two inter-sector pairs (σ = +1 and −1) between nodes 0/1 and 2/3 and one grounded pair on
/// node 4; 15 DOFs.
fn pair_set(variant: Variant, rot: &Mat3, axis: [f64; 3], h: usize) -> PairSet {
    let geo = CyclicGeometry::new(12, [0.0; 3], axis).unwrap();
    let f0 = [[0.0, 0.0, 1.0], [0.6, -0.8, 0.0], [0.8, 0.6, 0.0]];
    let f1 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    let rotate_frame = |f: Mat3| [0, 1, 2].map(|i| mat_vec(rot, f[i]));
    let pairs = vec![
        PairElement {
            contact: [0, 1, 2],
            target: Some([3, 4, 5]),
            frame: rotate_frame(f0),
            sigma: 1,
            params: params(1.0),
            preload_rate: 0.7,
        },
        PairElement {
            contact: [6, 7, 8],
            target: Some([9, 10, 11]),
            frame: rotate_frame(f1),
            sigma: -1,
            params: params(0.5),
            preload_rate: 0.3,
        },
        PairElement {
            contact: [12, 13, 14],
            target: None,
            frame: rotate_frame(f1),
            sigma: 0,
            params: params(0.8),
            preload_rate: 1.0,
        },
    ];
    let coupling = SectorCoupling {
        sectors: 12,
        rotation: geo.rotation(1),
        harmonic_indices: harmonic_indices(12, 1, h),
    };
    PairSet::new(15, variant, pairs, Some(coupling)).unwrap()
}

/// The pairs of `set` (built by [`pair_set`] with the identity and the z axis) with every preload
/// shifted by rate·p, evaluated by `evaluation`.
fn preload_shifted(
    set: &PairSet,
    variant: Variant,
    h: usize,
    p: f64,
    evaluation: Evaluation,
) -> PairSet {
    let mut pairs = set.pairs().to_vec();
    for pr in pairs.iter_mut() {
        pr.params.n0 += pr.preload_rate * p;
    }
    let geo = CyclicGeometry::new(12, [0.0; 3], [0.0, 0.0, 1.0]).unwrap();
    let coupling = SectorCoupling {
        sectors: 12,
        rotation: geo.rotation(1),
        harmonic_indices: harmonic_indices(12, 1, h),
    };
    let count = pairs.len();
    PairSet::new(15, variant, pairs, Some(coupling))
        .unwrap()
        .with_evaluations(vec![evaluation; count])
        .unwrap()
}

const IDENTITY: Mat3 = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];

/// q with node displacements of amplitude ~0.1 (tangential stick limit 0.05) and small normal parts.
fn random_q(rng: &mut XorShift, layout: &HarmonicLayout) -> Vec<f64> {
    let mut q = rng.vec(layout.len(15), 0.08);
    // a static normal offset keeps the pairs mostly closed
    for v in q.iter_mut().take(15) {
        *v *= 0.1;
    }
    q
}

#[test]
fn assembled_jacobian_and_preload_derivative_match_finite_differences() {
    for variant in [Variant::OneD, Variant::TwoD] {
        for h in [1, 3] {
            let layout = HarmonicLayout::with_default_samples(h);
            let set = pair_set(variant, &IDENTITY, [0.0, 0.0, 1.0], h);
            let n = layout.len(15);
            let mut rng = XorShift(23 + h as u64);
            let q = random_q(&mut rng, &layout);
            let mut state = set.initial_state();
            let mut f = vec![0.0; n];
            let mut jac = Mat::<f64>::zeros(n, n);
            set.evaluate(&layout, &q, &mut state, &mut f, Some(jac.as_mut()))
                .unwrap();
            let reports = set.reports(&layout, &q, &state, false).unwrap();
            assert!(reports.iter().any(|(r, _)| r.slip > 0.0), "{reports:?}");
            check_jacobian(
                &set,
                &layout,
                &q,
                &state,
                &jac,
                &format!("{variant:?} H={h}"),
            );
            let step = 1e-6;
            // ∂F/∂p with n0_j = n0_j + rate_j p.
            let mut dp = vec![0.0; n];
            set.parameter_derivative(&layout, &q, &state, &mut dp)
                .unwrap();
            let shifted = |p: f64| {
                let s2 = preload_shifted(&set, variant, h, p, Evaluation::Aft);
                forces(&s2, &layout, &q, &state)
            };
            check_derivative(&dp, &shifted(step), &shifted(-step), "∂F/∂p");
        }
    }
}

/// Rotating positions, frames, the cyclic axis and all displacements by one rotation G rotates
/// every node force by G; a translation common to both nodes of a same-sector pair changes nothing.
#[test]
fn frame_invariance_and_rigid_motion() {
    let h = 3;
    let layout = HarmonicLayout::with_default_samples(h);
    let m = layout.coefficients();
    let n = layout.len(15);
    let mut rng = XorShift(31);
    let g = random_rotation(&mut rng);
    let q = random_q(&mut rng, &layout);
    // q rotated node by node, coefficient by coefficient.
    let rotate_q = |q: &[f64]| {
        let mut out = vec![0.0; n];
        for node in 0..5 {
            for l in 0..m {
                let idx =
                    |c: usize| nlrom::contact::aft::global_index(&layout, l, 3 * node + c, 15);
                let v = mat_vec(&g, [q[idx(0)], q[idx(1)], q[idx(2)]]);
                for c in 0..3 {
                    out[idx(c)] = v[c];
                }
            }
        }
        out
    };
    for variant in [Variant::OneD, Variant::TwoD] {
        let a = pair_set(variant, &IDENTITY, [0.0, 0.0, 1.0], h);
        let b = pair_set(variant, &g, mat_vec(&g, [0.0, 0.0, 1.0]), h);
        let (mut sa, mut sb) = (a.initial_state(), b.initial_state());
        let (mut fa, mut fb) = (vec![0.0; n], vec![0.0; n]);
        a.evaluate(&layout, &q, &mut sa, &mut fa, None).unwrap();
        b.evaluate(&layout, &rotate_q(&q), &mut sb, &mut fb, None)
            .unwrap();
        let fa_rot = rotate_q(&fa);
        let scale = fa.iter().fold(0.0f64, |x, y| x.max(y.abs()));
        assert!(scale > 0.1);
        for (x, y) in fa_rot.iter().zip(&fb) {
            assert!((x - y).abs() < 1e-12 * scale, "{variant:?}: {x} vs {y}");
        }
        for (x, y) in sa.iter().zip(&sb) {
            assert!((x[0] - y[0]).abs() < 1e-12 && (x[1] - y[1]).abs() < 1e-12);
        }
    }
    // Common translation of both nodes of a same-sector pair.
    let pair = PairElement {
        contact: [0, 1, 2],
        target: Some([3, 4, 5]),
        frame: [[0.0, 0.0, 1.0], [0.6, -0.8, 0.0], [0.8, 0.6, 0.0]],
        sigma: 0,
        params: params(1.0),
        preload_rate: 1.0,
    };
    let set = PairSet::new(6, Variant::TwoD, vec![pair], None).unwrap();
    let n6 = layout.len(6);
    let q6 = rng.vec(n6, 0.08);
    let mut moved = q6.clone();
    for l in 0..m {
        let d = rng.vec(3, 0.5);
        for c in 0..3 {
            moved[nlrom::contact::aft::global_index(&layout, l, c, 6)] += d[c];
            moved[nlrom::contact::aft::global_index(&layout, l, 3 + c, 6)] += d[c];
        }
    }
    let (mut s1, mut s2) = (set.initial_state(), set.initial_state());
    let (mut f1, mut f2) = (vec![0.0; n6], vec![0.0; n6]);
    set.evaluate(&layout, &q6, &mut s1, &mut f1, None).unwrap();
    set.evaluate(&layout, &moved, &mut s2, &mut f2, None)
        .unwrap();
    for (x, y) in f1.iter().zip(&f2) {
        assert!((x - y).abs() < 1e-12, "{x} vs {y}");
    }
}

#[test]
fn result_does_not_depend_on_the_thread_count() {
    let h = 3;
    let layout = HarmonicLayout::with_default_samples(h);
    let n = layout.len(15);
    let mut rng = XorShift(41);
    let q = random_q(&mut rng, &layout);
    let set = pair_set(Variant::OneD, &IDENTITY, [0.0, 0.0, 1.0], h);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| {
            let mut s = set.initial_state();
            let mut f = vec![0.0; n];
            let mut j = Mat::<f64>::zeros(n, n);
            set.evaluate(&layout, &q, &mut s, &mut f, Some(j.as_mut()))
                .unwrap();
            (f, j, s)
        })
    };
    let (f1, j1, s1) = run(1);
    let (f2, j2, s2) = run(2);
    assert_eq!(f1, f2);
    assert_eq!(s1, s2);
    assert!(j1 == j2);
}

#[test]
fn bad_pairs_and_inputs_are_reported() {
    let good = PairElement {
        contact: [0, 1, 2],
        target: Some([3, 4, 5]),
        frame: IDENTITY,
        sigma: 0,
        params: params(1.0),
        preload_rate: 1.0,
    };
    let err = |p: PairElement| {
        PairSet::new(6, Variant::OneD, vec![good.clone(), p], None)
            .unwrap_err()
            .to_string()
    };
    let msg = err(PairElement {
        target: Some([3, 4, 6]),
        ..good.clone()
    });
    assert!(
        msg.contains("contact pair 1") && msg.contains("row 6"),
        "{msg}"
    );
    let msg = err(PairElement {
        frame: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, -1.0]],
        ..good.clone()
    });
    assert!(msg.contains("right-handed"), "{msg}");
    let msg = err(PairElement {
        sigma: 1,
        ..good.clone()
    });
    assert!(msg.contains("σ = 1"), "{msg}");
    let msg = err(PairElement {
        params: ContactParams {
            mu: -0.1,
            ..good.params
        },
        ..good.clone()
    });
    assert!(msg.contains("mu"), "{msg}");
    let set = PairSet::new(6, Variant::OneD, vec![good], None).unwrap();
    let layout = HarmonicLayout::with_default_samples(1);
    let mut q = vec![0.0; layout.len(6)];
    q[4] = f64::NAN;
    let mut s = set.initial_state();
    let mut f = vec![0.0; q.len()];
    let e = set.evaluate(&layout, &q, &mut s, &mut f, None).unwrap_err();
    assert_eq!(e.exit_code(), 1);
    assert!(e.to_string().contains("not finite"));
    q[4] = 0.0;
    let bad_layout = HarmonicLayout {
        harmonics: 3,
        time_samples: 6,
    };
    let mut q = vec![0.0; bad_layout.len(6)];
    let e = set
        .evaluate(&bad_layout, &q.clone(), &mut s, &mut q, None)
        .unwrap_err();
    assert!(e.to_string().contains("time_samples"), "{e}");
}

/// The pairs evaluated by the exact single-harmonic cycle (`with_evaluations`, Cigeroglu, An &
/// Menq 2007) at H = 1: the node forces equal the AFT's to first order in 1/N_t (the largest
/// difference falls by more than 5 from N_t = 256 to 4096 and is below 1e-4 of the largest force
/// there), the assembled Jacobian and ∂F/∂p equal central differences, and the 2-D
/// (Coulomb disc) variant refuses it.
#[test]
fn analytic_pairs_agree_with_the_aft_and_finite_differences() {
    let analytic = |variant| {
        pair_set(variant, &IDENTITY, [0.0, 0.0, 1.0], 1)
            .with_evaluations(vec![Evaluation::Analytic; 3])
    };
    let set = analytic(Variant::OneD).unwrap();
    let layout = HarmonicLayout::new(1, 64).unwrap();
    let n = layout.len(15);
    let mut rng = XorShift(41);
    let q = random_q(&mut rng, &layout);
    let state = set.initial_state();
    let exact = forces(&set, &layout, &q, &state);
    let reports = set.reports(&layout, &q, &state, false).unwrap();
    assert!(reports.iter().any(|(r, _)| r.slip > 0.0), "{reports:?}");
    let scale = exact.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let diffs: Vec<f64> = [256, 4096]
        .iter()
        .map(|&nt| {
            let aft = pair_set(Variant::OneD, &IDENTITY, [0.0, 0.0, 1.0], 1);
            let f = forces(&aft, &HarmonicLayout::new(1, nt).unwrap(), &q, &state);
            f.iter()
                .zip(&exact)
                .fold(0.0f64, |a, (x, y)| a.max((x - y).abs()))
        })
        .collect();
    eprintln!("analytic − AFT at N_t = 256, 4096: {diffs:?} (largest force {scale})");
    assert!(diffs[1] < 1e-4 * scale, "{diffs:?}");
    assert!(diffs[0] / diffs[1] > 5.0, "{diffs:?}");
    let mut s = state.clone();
    let mut f = vec![0.0; n];
    let mut jac = Mat::<f64>::zeros(n, n);
    set.evaluate(&layout, &q, &mut s, &mut f, Some(jac.as_mut()))
        .unwrap();
    check_jacobian(&set, &layout, &q, &state, &jac, "analytic pairs");
    let mut dp = vec![0.0; n];
    set.parameter_derivative(&layout, &q, &state, &mut dp)
        .unwrap();
    let shifted = |p: f64| {
        let s2 = preload_shifted(&set, Variant::OneD, 1, p, Evaluation::Analytic);
        forces(&s2, &layout, &q, &state)
    };
    check_derivative(&dp, &shifted(1e-6), &shifted(-1e-6), "analytic ∂F/∂p");
    let e = analytic(Variant::TwoD).unwrap_err().to_string();
    assert!(e.contains("2-D") && e.contains("analytic"), "{e}");
    // H = 3 is refused at evaluation.
    let layout3 = HarmonicLayout::new(3, 64).unwrap();
    let set3 = pair_set(Variant::OneD, &IDENTITY, [0.0, 0.0, 1.0], 3)
        .with_evaluations(vec![Evaluation::Analytic; 3])
        .unwrap();
    let mut s3 = set3.initial_state();
    let mut f3 = vec![0.0; layout3.len(15)];
    let e = set3
        .evaluate(
            &layout3,
            &vec![0.01; layout3.len(15)],
            &mut s3,
            &mut f3,
            None,
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("harmonics = 1"), "{e}");
}
