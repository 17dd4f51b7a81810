//! The contact element's analytic Jacobian when the periodic marching passes through a
//! transient (`nlrom::contact::element`): from a fixed start state the first period slips and the
//! later periods stick (shakedown), so the returned force depends on the input through the slider
//! position the transient left. The Jacobian must be the derivative of exactly this map (the
//! start state is a parameter): checked against central finite differences from the same start
//! state for every evaluation, for the 1-D and 2-D laws, to 1e-6 relative.

use nlrom::contact::aft::Aft;
use nlrom::contact::element::{evaluate, LocalElement, Workspace};
use nlrom::contact::law::{ContactParams, Variant};
use nlrom::harmonics::HarmonicLayout;

/// u1 = u0 + A cos τ (+ small higher harmonics), u2 = 0.005 sin τ, v = small harmonic normal
/// motion; k_t = 10, μ n0 = 0.5 (stick for |u − w| ≤ 0.05), u0 = 0.1, A = 0.02: from w = 0 the
/// first sample slips (k_t |u0 + A| = 1.2 > 0.5) and after it the element sticks (k_t 2A = 0.4
/// < 2 μ n0 = 1).
fn shakedown_input(h: usize) -> Vec<f64> {
    let m = 2 * h + 1;
    let mut x = vec![0.0; 3 * m];
    x[0] = 0.1;
    x[1] = 0.02;
    x[3] = 1e-3; // cos 2τ of u1
    x[m + 2] = -0.005; // u2 = 0.005 sin τ (u = Re U − Im U sin τ convention)
    x[2 * m] = 1e-3; // static normal approach
    x[2 * m + 1] = 2e-3; // cos τ of v
    x
}

fn check(variant: Variant, h: usize) {
    let aft = Aft::new(HarmonicLayout::with_default_samples(h)).unwrap();
    let mut ws = Workspace::new(&aft);
    let el = LocalElement {
        params: ContactParams::new(10.0, 20.0, 0.5, 1.0, "test").unwrap(),
        variant,
        tangential: 2,
        normal: true,
    };
    let m = 2 * h + 1;
    let cols = 3 * m + 1;
    let x = shakedown_input(h);
    let start = [0.0; 2];
    let mut slider = start;
    let mut f = vec![0.0; 3 * m];
    let marching = evaluate(&el, &aft, &x, &mut slider, &mut f, true, &mut ws).unwrap();
    let report = ws.report();
    // The transient: more than one period, the last one fully stuck, the slider moved.
    assert!(
        marching.converged && marching.periods >= 2,
        "{variant:?}: {marching:?}"
    );
    assert_eq!(report.stick, 1.0, "{variant:?}: last period must stick");
    assert!(slider[0] > 0.05, "{variant:?}: slider {slider:?}");
    let jac = ws.jacobian().0.to_vec();
    let scale = jac.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    let step = 1e-7;
    let mut worst = 0.0f64;
    for c in 0..cols {
        let mut out = [vec![0.0; 3 * m], vec![0.0; 3 * m]];
        for (k, sign) in [1.0, -1.0].into_iter().enumerate() {
            let mut xs = x.clone();
            let mut e = el;
            if c < 3 * m {
                xs[c] += sign * step;
            } else {
                e.params.n0 += sign * step;
            }
            let mut s = start;
            evaluate(&e, &aft, &xs, &mut s, &mut out[k], false, &mut ws).unwrap();
        }
        for r in 0..3 * m {
            let fd = (out[0][r] - out[1][r]) / (2.0 * step);
            let an = jac[r * cols + c];
            worst = worst.max((fd - an).abs() / scale);
        }
    }
    assert!(
        worst <= 1e-6,
        "{variant:?} H={h}: largest |FD − analytic| / max|J| = {worst:e} (scale {scale})"
    );
    // The static tangential column: the transient set w = u − μ f_n/k_t at the slip instant,
    // so the static tangential force does not depend on the static displacement u0: slope 0 for
    // the 1-D law (nearly 0 for the 2-D disc, whose slip direction depends on u2), not the
    // stuck stiffness k_t = 10 of a slider that stays where the caller left it.
    let bound = match variant {
        Variant::OneD => 1e-9,
        Variant::TwoD => 1e-2,
    };
    assert!(
        jac[0].abs() <= bound * el.params.kt,
        "{variant:?}: ∂F1_0/∂U1_0 = {}",
        jac[0]
    );
}

#[test]
fn jacobian_through_a_shakedown_transient_matches_finite_differences() {
    for h in [1, 3] {
        check(Variant::OneD, h);
        check(Variant::TwoD, h);
    }
}
