//! `hbm::preload::FromStaticEquilibrium`: contact forces measured from the preloaded static
//! equilibrium (SAMA paper §6.1, uncoupled static/dynamic approach). Checked against the inner
//! force it wraps: zero force at rest, F̃(Q) = F(Q) − F(0) with the same Jacobian, the n0
//! derivative against central differences of the balanced force in n0, and an element with a
//! gap at rest (n0 < 0) left unchanged.

use std::path::Path;

use faer::Mat;
use nlrom::case::{Case, FrictionElement};
use nlrom::contact::grounded::DofElements;
use nlrom::harmonics::{HarmonicForce, HarmonicLayout};
use nlrom::hbm::preload::FromStaticEquilibrium;

/// One element on DOFs 0 (tangential) and 1 (normal, normal load variation), preload `n0`.
fn elements(n0: f64) -> Vec<FrictionElement> {
    let text = format!(
        "[model]\nstiffness = \"K.mtx\"\nmass = \"M.mtx\"\n\n[excitation]\ndofs = [0]\nforce = [1.0]\n\n\
         [[element]]\nkind = \"friction\"\ntangential = {{ dofs = [0], weights = [1.0] }}\n\
         normal = {{ dofs = [1], weights = [1.0] }}\nkt = 2.0\nkn = 3.0\nmu = 0.4\nn0 = {n0}\n"
    );
    Case::from_str(&text, Path::new("/tmp/case.toml"))
        .unwrap()
        .element
}

fn force<F: HarmonicForce>(f: &F, layout: &HarmonicLayout, q: &[f64]) -> (Vec<f64>, Mat<f64>) {
    let mut state = f.initial_state();
    let mut out = vec![0.0; q.len()];
    let mut jac = Mat::<f64>::zeros(q.len(), q.len());
    f.evaluate(layout, q, &mut state, &mut out, Some(jac.as_mut()))
        .unwrap();
    (out, jac)
}

/// A partial-slip, intermittently separating input (H = 3, DOFs 0 and 1).
fn input(layout: &HarmonicLayout) -> Vec<f64> {
    (0..layout.len(2))
        .map(|i| 0.3 * ((i as f64) * 1.7).sin() + if i == 1 { 0.05 } else { 0.0 })
        .collect()
}

#[test]
fn zero_at_rest_and_inner_minus_rest_elsewhere() {
    let layout = HarmonicLayout::new(3, 64).unwrap();
    let inner = DofElements::from_case(&elements(1.0), 2).unwrap();
    let wrapped = DofElements::from_case(&elements(1.0), 2).unwrap();
    let balanced = FromStaticEquilibrium::new(wrapped, &layout).unwrap();
    let zero = vec![0.0; layout.len(2)];
    let (f0, _) = force(&balanced, &layout, &zero);
    assert!(f0.iter().all(|v| v.abs() < 1e-14), "{f0:?}");
    // At rest the element pushes along its normal with n0 = 1 (zeroth harmonic of DOF 1).
    let rest = balanced.at_rest();
    assert!(
        (rest[layout.static_index(1)] - 1.0).abs() < 1e-14,
        "{rest:?}"
    );
    let q = input(&layout);
    let (fi, ji) = force(&inner, &layout, &q);
    let (fb, jb) = force(&balanced, &layout, &q);
    for i in 0..q.len() {
        assert!((fb[i] - (fi[i] - rest[i])).abs() < 1e-14);
        for j in 0..q.len() {
            assert_eq!(jb[(i, j)], ji[(i, j)]);
        }
    }
}

/// ∂F̃/∂n0 of the wrapper against central differences of F̃ rebuilt at n0 ± h (each with its own
/// static balance): the balancing load follows the preload.
#[test]
fn preload_derivative_matches_central_differences() {
    let layout = HarmonicLayout::new(3, 64).unwrap();
    let q = input(&layout);
    let n0 = 1.0;
    let h = 1e-6;
    let balanced = |n: f64| {
        FromStaticEquilibrium::new(DofElements::from_case(&elements(n), 2).unwrap(), &layout)
            .unwrap()
    };
    let b = balanced(n0);
    let mut state = b.initial_state();
    let mut scratch = vec![0.0; q.len()];
    b.evaluate(&layout, &q, &mut state, &mut scratch, None)
        .unwrap();
    let mut d = vec![0.0; q.len()];
    b.parameter_derivative(&layout, &q, &state, &mut d).unwrap();
    let (fp, _) = force(&balanced(n0 + h), &layout, &q);
    let (fm, _) = force(&balanced(n0 - h), &layout, &q);
    let scale = d.iter().fold(1e-12_f64, |a, v| a.max(v.abs()));
    for i in 0..q.len() {
        let fd = (fp[i] - fm[i]) / (2.0 * h);
        assert!(
            (fd - d[i]).abs() <= 1e-6 * scale,
            "row {i}: {} vs {fd}",
            d[i]
        );
    }
}

/// With a gap at rest (n0 < 0: g0 = −n0/k_n) the element exerts no force at Q = 0, and the
/// wrapper changes nothing.
#[test]
fn open_gap_at_rest_is_unchanged() {
    let layout = HarmonicLayout::new(3, 64).unwrap();
    let inner = DofElements::from_case(&elements(-0.2), 2).unwrap();
    let wrapped = DofElements::from_case(&elements(-0.2), 2).unwrap();
    let balanced = FromStaticEquilibrium::new(wrapped, &layout).unwrap();
    assert!(balanced.at_rest().iter().all(|v| *v == 0.0));
    let q = input(&layout);
    assert_eq!(
        force(&balanced, &layout, &q).0,
        force(&inner, &layout, &q).0
    );
}
