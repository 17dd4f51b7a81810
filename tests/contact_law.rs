//! The single-sample contact law (`nlrom::contact::law`): regimes against hand values, the
//! partial derivatives against central finite differences, the 2-D disc against the 1-D law on a
//! straight path, and parameter validation.

use nlrom::contact::law::{
    normal_force, sample, sample_with_tangent, ContactParams, Regime, Variant,
};

fn params(kt: f64, kn: f64, mu: f64, n0: f64) -> ContactParams {
    ContactParams::new(kt, kn, mu, n0, "test").unwrap()
}

#[test]
fn normal_force_and_separation() {
    let p = params(10.0, 100.0, 0.4, 2.0);
    assert_eq!(normal_force(&p, 0.01), 3.0);
    assert_eq!(normal_force(&p, -0.05), 0.0);
    // Separation: no force, the slider follows u.
    let s = sample(Variant::OneD, &p, [0.3, -0.1], -0.05, [1.0, 1.0]);
    assert_eq!(s.force, [0.0, 0.0, 0.0]);
    assert_eq!(s.slider, [0.3, -0.1]);
    assert_eq!(s.regime, [Regime::Separation; 2]);
    // Initial gap n0 < 0: contact only once k_n v > −n0.
    let gap = params(10.0, 100.0, 0.4, -1.0);
    assert_eq!(normal_force(&gap, 0.005), 0.0);
    assert!((normal_force(&gap, 0.02) - 1.0).abs() < 1e-14);
}

#[test]
fn two_d_radial_return_stays_on_the_disc() {
    let p = params(10.0, 0.0, 0.5, 2.0); // limit μ n0 = 1 N
    let u = [0.3, 0.4]; // |k_t u| = 5 N
    let s = sample(Variant::TwoD, &p, u, 0.0, [0.0, 0.0]);
    assert_eq!(s.regime, [Regime::Slip; 2]);
    assert!((s.force[0] - 0.6).abs() < 1e-14 && (s.force[1] - 0.8).abs() < 1e-14);
    // After the return the trial force from the new slider is exactly on the disc.
    let tr = [10.0 * (u[0] - s.slider[0]), 10.0 * (u[1] - s.slider[1])];
    assert!((tr[0].hypot(tr[1]) - 1.0).abs() < 1e-14);
    // The 1-D law clips each component separately (larger force than the disc).
    let s1 = sample(Variant::OneD, &p, u, 0.0, [0.0, 0.0]);
    assert_eq!([s1.force[0], s1.force[1]], [1.0, 1.0]);
}

#[test]
fn two_d_equals_one_d_on_a_straight_path() {
    let p = params(3.0, 50.0, 0.3, 1.0);
    let mut w1 = [0.0; 2];
    let mut w2 = [0.0; 2];
    for j in 0..200 {
        let s = (j as f64 * 0.1).sin();
        let u = [s, 0.0];
        let v = 0.01 * (j as f64 * 0.07).cos();
        let a = sample(Variant::OneD, &p, u, v, w1);
        let b = sample(Variant::TwoD, &p, u, v, w2);
        assert!((a.force[0] - b.force[0]).abs() < 1e-14);
        assert_eq!(a.regime[0], b.regime[0]);
        w1 = a.slider;
        w2 = b.slider;
    }
}

/// Central finite difference of every output of `sample` with respect to (u1, u2, v, n0, w1, w2).
fn check_tangent(variant: Variant, p: ContactParams, u: [f64; 2], v: f64, w: [f64; 2]) -> Regime {
    let t = sample_with_tangent(variant, &p, u, v, w);
    let h = 1e-7;
    let eval = |x: [f64; 6]| {
        let q = ContactParams { n0: x[3], ..p };
        let s = sample(variant, &q, [x[0], x[1]], x[2], [x[4], x[5]]);
        [s.force[0], s.force[1], s.force[2], s.slider[0], s.slider[1]]
    };
    let x0 = [u[0], u[1], v, p.n0, w[0], w[1]];
    for c in 0..6 {
        let mut xp = x0;
        let mut xm = x0;
        xp[c] += h;
        xm[c] -= h;
        let (fp, fm) = (eval(xp), eval(xm));
        for o in 0..5 {
            let fd = (fp[o] - fm[o]) / (2.0 * h);
            let an = match (o, c) {
                (0..=2, 0..=3) => t.dforce_dx[o][c],
                (0..=1, 4..=5) => t.dforce_dw[o][c - 4],
                (2, 4..=5) => 0.0,
                (3..=4, 0..=3) => t.dslider_dx[o - 3][c],
                (3..=4, 4..=5) => t.dslider_dw[o - 3][c - 4],
                _ => unreachable!(),
            };
            assert!(
                (fd - an).abs() <= 1e-6 * (1.0 + an.abs()),
                "{variant:?} output {o} input {c}: analytic {an}, finite difference {fd}"
            );
        }
    }
    t.sample.regime[0]
}

#[test]
fn tangents_match_finite_differences() {
    let p = params(7.0, 40.0, 0.35, 1.5);
    for variant in [Variant::OneD, Variant::TwoD] {
        // stick, slip (both signs, oblique), separation
        assert_eq!(
            check_tangent(variant, p, [0.01, -0.02], 0.01, [0.0, 0.0]),
            Regime::Stick
        );
        assert_eq!(
            check_tangent(variant, p, [0.5, -0.3], 0.02, [0.1, 0.05]),
            Regime::Slip
        );
        assert_eq!(
            check_tangent(variant, p, [-0.4, 0.2], -0.01, [0.1, 0.0]),
            Regime::Slip
        );
        assert_eq!(
            check_tangent(variant, p, [0.2, 0.1], -0.1, [0.0, 0.0]),
            Regime::Separation
        );
    }
}

#[test]
fn invalid_parameters_are_named() {
    for (kt, kn, mu, n0, key) in [
        (-1.0, 0.0, 0.1, 1.0, "kt"),
        (1.0, -2.0, 0.1, 1.0, "kn"),
        (1.0, 0.0, -0.1, 1.0, "mu"),
        (f64::NAN, 0.0, 0.1, 1.0, "kt"),
        (1.0, 0.0, 0.1, f64::INFINITY, "n0"),
    ] {
        let err = ContactParams::new(kt, kn, mu, n0, "[[element]] 2").unwrap_err();
        let msg = err.to_string();
        assert!(msg.contains("[[element]] 2") && msg.contains(key), "{msg}");
        assert_eq!(err.exit_code(), 2);
    }
}
