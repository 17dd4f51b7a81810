//! Helpers shared by the contact tests.

use faer::Mat;
use nlrom::harmonics::{HarmonicForce, HarmonicLayout};

/// Forces of `force` at `q` from a copy of `state`.
#[allow(dead_code)]
pub fn forces<F: HarmonicForce>(
    force: &F,
    layout: &HarmonicLayout,
    q: &[f64],
    state: &F::State,
) -> Vec<f64> {
    let mut s = state.clone();
    let mut out = vec![0.0; q.len()];
    force.evaluate(layout, q, &mut s, &mut out, None).unwrap();
    out
}

/// Asserts that the analytic Jacobian `jac` of `force` at (`q`, converged `state`) equals central
/// differences (step 1e-6) to 1e-6 relative to its largest entry; returns that entry.
#[allow(dead_code)]
pub fn check_jacobian<F: HarmonicForce>(
    force: &F,
    layout: &HarmonicLayout,
    q: &[f64],
    state: &F::State,
    jac: &Mat<f64>,
    label: &str,
) -> f64 {
    let n = q.len();
    let mut scale: f64 = 0.0;
    for r in 0..n {
        for c in 0..n {
            scale = scale.max(jac[(r, c)].abs());
        }
    }
    let step = 1e-6;
    for c in 0..n {
        let (mut qp, mut qm) = (q.to_vec(), q.to_vec());
        qp[c] += step;
        qm[c] -= step;
        let (fp, fm) = (
            forces(force, layout, &qp, state),
            forces(force, layout, &qm, state),
        );
        for r in 0..n {
            let fd = (fp[r] - fm[r]) / (2.0 * step);
            assert!(
                (fd - jac[(r, c)]).abs() <= 1e-6 * scale,
                "{label}: J[{r},{c}] = {} vs central difference {fd}",
                jac[(r, c)]
            );
        }
    }
    scale
}

/// Asserts that `analytic` = (`plus` − `minus`)/(2·1e-6) to 1e-6 relative to its largest entry.
#[allow(dead_code)]
pub fn check_derivative(analytic: &[f64], plus: &[f64], minus: &[f64], label: &str) {
    let scale = analytic.iter().fold(0.0f64, |a, b| a.max(b.abs()));
    assert!(scale > 0.1, "{label}: derivative is (nearly) zero");
    for (r, a) in analytic.iter().enumerate() {
        let fd = (plus[r] - minus[r]) / 2e-6;
        assert!(
            (fd - a).abs() <= 1e-6 * scale,
            "{label}: ∂F[{r}] = {a} vs central difference {fd}"
        );
    }
}
