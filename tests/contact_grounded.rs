//! Friction elements on DOF combinations (`nlrom::contact::grounded`, `[[element]]` of
//! `docs/case-file.md`): the Jenkins closed forms through a case file, the two-DOF element against the
//! grounded one, the single-DOF oscillator's closed-form amplitude solved by Newton with the
//! analytic Jacobian, the Jacobian and ∂F/∂n0 against central differences, input errors.

use std::path::Path;

use faer::linalg::solvers::Solve;
use faer::Mat;
use nlrom::case::{Case, FrictionElement, WeightedDofs};
use nlrom::contact::aft::global_index;
use nlrom::contact::grounded::DofElements;
use nlrom::harmonics::{HarmonicForce, HarmonicLayout};

mod support;
use support::contact::{check_derivative, check_jacobian, forces};
use support::random::XorShift;

fn case_elements(elements: &str) -> Vec<FrictionElement> {
    let text = format!(
        "[model]\nstiffness = \"K.mtx\"\nmass = \"M.mtx\"\n\n[excitation]\ndofs = [0]\nforce = [1.0]\n\n{elements}"
    );
    Case::from_str(&text, Path::new("/tmp/case.toml"))
        .unwrap()
        .element
}

/// Jenkins element k_t = 1, F_s = μ n0 = 0.3 to the ground under q = A cos τ (`docs/theory.md`).
#[test]
fn jenkins_from_a_case_file() {
    let els = case_elements(
        "[[element]]\nkind = \"friction\"\ntangential = { dofs = [0], weights = [1.0] }\nkt = 1.0\nmu = 0.3\nn0 = 1.0\n",
    );
    let set = DofElements::from_case(&els, 1).unwrap();
    let layout = HarmonicLayout::new(1, 4096).unwrap();
    let q = [0.0, 1.0, 0.0];
    let mut state = set.initial_state();
    let mut f = [0.0; 3];
    set.evaluate(&layout, &q, &mut state, &mut f, None).unwrap();
    assert!((f[1] - 0.2523158).abs() < 1e-6, "a1 = {}", f[1]);
    assert!((f[2] - 0.2673803).abs() < 1e-6, "b1 = {}", f[2]);
    let reports = set.reports(&layout, &q, &state, true).unwrap();
    assert!((reports[0].0.dissipated_energy - 0.84).abs() < 1e-9);
    assert_eq!(reports[0].1.as_ref().unwrap().v.len(), 4096);
}

/// An element between DOFs 0 and 1 (weights −1, 1) acts as the grounded element on
/// u = q1 − q0, with opposite forces on the two DOFs.
#[test]
fn two_dof_element_equals_grounded_element_on_the_difference() {
    let two = DofElements::from_case(
        &case_elements("[[element]]\nkind = \"friction\"\ntangential = { dofs = [0, 1], weights = [-1.0, 1.0] }\nkt = 20.0\nmu = 1.0\nn0 = 1.0\n"),
        2,
    )
    .unwrap();
    let one = DofElements::from_case(
        &case_elements("[[element]]\nkind = \"friction\"\ntangential = { dofs = [0], weights = [1.0] }\nkt = 20.0\nmu = 1.0\nn0 = 1.0\n"),
        1,
    )
    .unwrap();
    let layout = HarmonicLayout::with_default_samples(3);
    let mut rng = XorShift(5);
    let q2 = rng.vec(layout.len(2), 0.1);
    let q1: Vec<f64> = (0..7)
        .map(|l| q2[global_index(&layout, l, 1, 2)] - q2[global_index(&layout, l, 0, 2)])
        .collect();
    let (mut s2, mut s1) = (two.initial_state(), one.initial_state());
    let (mut f2, mut f1) = (vec![0.0; layout.len(2)], vec![0.0; 7]);
    two.evaluate(&layout, &q2, &mut s2, &mut f2, None).unwrap();
    one.evaluate(&layout, &q1, &mut s1, &mut f1, None).unwrap();
    assert!(f1.iter().any(|v| v.abs() > 0.1));
    for l in 0..7 {
        assert!((f2[global_index(&layout, l, 1, 2)] - f1[l]).abs() < 1e-14);
        assert!((f2[global_index(&layout, l, 0, 2)] + f1[l]).abs() < 1e-14);
    }
}

/// m q̈ + c q̇ + k q + f_J(q) = F cos ωt with one harmonic: the closed form (`docs/theory.md`) gives
/// amplitude 1 at ω = 0.952957 and 1.249892 (k = m = 1, c = 0.1, k_t = 1, F_s = 0.3, F = 0.5),
/// with Q = F / (k − mω² + a1/A + i(cω + |b1|/A)). The harmonic-balance residual with the element
/// vanishes there, and Newton with the element's analytic Jacobian, started 10 % away, converges
/// back to it quadratically.
#[test]
fn single_dof_oscillator_closed_form_amplitude() {
    let set = DofElements::from_case(
        &case_elements("[[element]]\nkind = \"friction\"\ntangential = { dofs = [0], weights = [1.0] }\nkt = 1.0\nmu = 0.3\nn0 = 1.0\n"),
        1,
    )
    .unwrap();
    let layout = HarmonicLayout::new(1, 2048).unwrap();
    let (a1, b1): (f64, f64) = (0.2523158, 0.2673803); // Jenkins coefficients at A = 1
    for omega in [0.952957, 1.249892] {
        // D(ω) in the real layout: static k; first harmonic [[k − ω², −cω], [cω, k − ω²]].
        let (re, im) = (1.0 - omega * omega, 0.1 * omega);
        let (dr, di) = (re + a1, im + b1);
        let den = dr * dr + di * di;
        let exact = [0.0, 0.5 * dr / den, -0.5 * di / den];
        assert!((exact[1].hypot(exact[2]) - 1.0).abs() < 2e-6);
        let residual = |q: &[f64], state: &mut Vec<f64>, jac: Option<&mut Mat<f64>>| {
            let mut f = vec![0.0; 3];
            set.evaluate(&layout, q, state, &mut f, jac.map(|j| j.as_mut()))
                .unwrap();
            [
                q[0] + f[0],
                re * q[1] - im * q[2] + f[1] - 0.5,
                im * q[1] + re * q[2] + f[2],
            ]
        };
        let mut state = set.initial_state();
        let r = residual(&exact, &mut state, None);
        assert!(
            r.iter().all(|v| v.abs() < 2e-6),
            "ω = {omega}: residual {r:?}"
        );
        let mut q = vec![0.02, 1.1 * exact[1], 0.9 * exact[2]];
        let mut history = Vec::new();
        for _ in 0..20 {
            let mut j = Mat::<f64>::zeros(3, 3);
            let r = residual(&q, &mut state, Some(&mut j));
            history.push(r.iter().map(|v| v.abs()).fold(0.0, f64::max));
            if history.last().unwrap() < &1e-14 {
                break;
            }
            j[(0, 0)] += 1.0;
            j[(1, 1)] += re;
            j[(1, 2)] -= im;
            j[(2, 1)] += im;
            j[(2, 2)] += re;
            let dq = j.partial_piv_lu().solve(Mat::from_fn(3, 1, |i, _| -r[i]));
            for (i, v) in q.iter_mut().enumerate() {
                *v += dq[(i, 0)];
            }
        }
        assert!(
            history.len() <= 8,
            "ω = {omega}: residual history {history:?}"
        );
        let amplitude = q[1].hypot(q[2]);
        assert!(
            (amplitude - 1.0).abs() < 2e-6,
            "ω = {omega}: amplitude {amplitude}"
        );
    }
}

#[test]
fn jacobian_and_preload_derivative_match_finite_differences() {
    let els = case_elements(
        "[[element]]\nkind = \"friction\"\ntangential = { dofs = [0, 1], weights = [-1.0, 1.0] }\nnormal = { dofs = [2, 1], weights = [1.0, 0.5] }\nkt = 10.0\nkn = 20.0\nmu = 0.5\nn0 = 0.3\n\n[[element]]\nkind = \"friction\"\ntangential = { dofs = [2], weights = [2.0] }\nkt = 5.0\nmu = 0.4\nn0 = 0.5\n",
    );
    let set = DofElements::from_case(&els, 3).unwrap();
    for h in [1, 3, 7] {
        let layout = HarmonicLayout::with_default_samples(h);
        let n = layout.len(3);
        let mut rng = XorShift(13 + h as u64);
        let q = rng.vec(n, 0.1);
        let mut state = set.initial_state();
        let mut f = vec![0.0; n];
        let mut jac = Mat::<f64>::zeros(n, n);
        set.evaluate(&layout, &q, &mut state, &mut f, Some(jac.as_mut()))
            .unwrap();
        let reports = set.reports(&layout, &q, &state, false).unwrap();
        assert!(
            reports[0].0.separation > 0.0 && reports[0].0.slip > 0.0,
            "{reports:?}"
        );
        check_jacobian(&set, &layout, &q, &state, &jac, &format!("H={h}"));
        let step = 1e-6;
        let mut dp = vec![0.0; n];
        set.parameter_derivative(&layout, &q, &state, &mut dp)
            .unwrap();
        let shifted = |d: f64| {
            let mut e = els.clone();
            for x in e.iter_mut() {
                x.n0 = x.n0.map(|n| n + d);
            }
            forces(&DofElements::from_case(&e, 3).unwrap(), &layout, &q, &state)
        };
        check_derivative(
            &dp,
            &shifted(step),
            &shifted(-step),
            &format!("H={h} ∂/∂n0"),
        );
    }
}

#[test]
fn bad_elements_are_reported() {
    let base = FrictionElement {
        kind: nlrom::case::ElementKind::Friction,
        tangential: WeightedDofs {
            dofs: vec![0, 1],
            weights: vec![-1.0, 1.0],
        },
        normal: None,
        kt: Some(1.0),
        kn: 0.0,
        mu: Some(0.3),
        n0: Some(1.0),
        ..FrictionElement::default()
    };
    let err = |e: FrictionElement| {
        DofElements::from_case(&[base.clone(), e], 2)
            .unwrap_err()
            .to_string()
    };
    let msg = err(FrictionElement {
        tangential: WeightedDofs {
            dofs: vec![0, 2],
            weights: vec![1.0, 1.0],
        },
        ..base.clone()
    });
    assert!(
        msg.contains("element[1].tangential.dofs") && msg.contains("row 2"),
        "{msg}"
    );
    let msg = err(FrictionElement {
        normal: Some(WeightedDofs {
            dofs: vec![0],
            weights: vec![],
        }),
        ..base.clone()
    });
    assert!(msg.contains("element[1].normal"), "{msg}");
    let msg = err(FrictionElement {
        kt: Some(-1.0),
        ..base.clone()
    });
    assert!(msg.contains("element[1]") && msg.contains("kt"), "{msg}");
    let msg = err(FrictionElement {
        mu: Some(f64::NAN),
        ..base.clone()
    });
    assert!(msg.contains("mu"), "{msg}");
    let msg = err(FrictionElement {
        tangential: WeightedDofs {
            dofs: vec![0],
            weights: vec![f64::INFINITY],
        },
        ..base.clone()
    });
    assert!(msg.contains("weights"), "{msg}");
    // N_t ≤ 2H and non-finite harmonics.
    let set = DofElements::from_case(&[base], 2).unwrap();
    let mut s = set.initial_state();
    let bad = HarmonicLayout {
        harmonics: 2,
        time_samples: 4,
    };
    let mut f = vec![0.0; bad.len(2)];
    let e = set
        .evaluate(&bad, &f.clone(), &mut s, &mut f, None)
        .unwrap_err();
    assert!(
        e.to_string().contains("time_samples") && e.exit_code() == 2,
        "{e}"
    );
    let layout = HarmonicLayout::with_default_samples(1);
    let mut q = vec![0.0; layout.len(2)];
    q[0] = f64::INFINITY;
    let mut f = vec![0.0; q.len()];
    assert!(set.evaluate(&layout, &q, &mut s, &mut f, None).is_err());
}
