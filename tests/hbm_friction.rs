//! Harmonic balance with friction (contact::element through a DOF-combination wrapper) against
//! the closed forms of `docs/theory.md`: the single-DOF Jenkins oscillator (H = 1) crossing amplitude
//! 1 at ω = 0.952957 and 1.249892; Den Hartog's rigid-Coulomb amplitude ratios (H = 7, large k_t);
//! the stuck limit (μ → ∞) equal to the linear FRF.

mod support;

use faer::{c64, Mat};
use nlrom::contact::grounded::DofElements;
use nlrom::contact::law::ContactParams;
use nlrom::continuation::{trace, ContinuationOptions, PathEnd};
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::response::output_response;
use nlrom::hbm::{FrequencyPath, HbmSystem, LinearModel, ResponseOptions};
use nlrom::nonlinear::{solve_fixed, NewtonOptions};
use support::hbm::{chain4, complex_solve, friction_elements};

fn sdof(c: f64, f: f64, h: usize) -> LinearModel {
    let one = Mat::from_fn(1, 1, |_, _| 1.0);
    let cm = Mat::from_fn(1, 1, |_, _| c);
    let damping = (c > 0.0).then_some(cm.as_ref());
    LinearModel::from_real(
        one.as_ref(),
        one.as_ref(),
        damping,
        &[f],
        vec![0],
        vec![0],
        h,
    )
    .unwrap()
}

/// A Jenkins element from the DOF to the ground: stiffness k_t, slip force F_s = μ n0.
fn grounded_jenkins(kt: f64, slip_force: f64) -> DofElements {
    friction_elements(
        ContactParams::new(kt, 0.0, 1.0, slip_force, "test").unwrap(),
        vec![vec![(0, 1.0)]],
        1,
    )
}

/// The closed-form HB-1 relation (`docs/theory.md`), relative: ((k + a1/A − mω²)² + (cω + |b1|/A)²) A²
/// / F² − 1 with k = m = 1, c = 0.1, k_t = 1, F_s = 0.3, F = 0.5.
fn jenkins_relation(omega: f64, a: f64) -> f64 {
    let (kt, fs, c, f) = (1.0, 0.3, 0.1, 0.5);
    let (a1, b1) = if kt * a <= fs {
        (kt * a, 0.0)
    } else {
        let beta = (1.0 - 2.0 * fs / (kt * a)).acos();
        (
            a * kt / std::f64::consts::PI * (beta - 0.5 * (2.0 * beta).sin()),
            4.0 * fs / std::f64::consts::PI * (1.0 - fs / (kt * a)),
        )
    };
    let re = 1.0 + a1 / a - omega * omega;
    let im = c * omega + b1 / a;
    (re * re + im * im) * a * a / (f * f) - 1.0
}

#[test]
fn jenkins_oscillator_crosses_unit_amplitude_at_the_closed_form_frequencies() {
    let model = sdof(0.1, 0.5, 1);
    let force = grounded_jenkins(1.0, 0.3);
    let layout = HarmonicLayout::new(1, 2048).unwrap();
    let system = HbmSystem::new(layout, &model, &force).unwrap();
    let fp = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let path = trace(&fp, &ContinuationOptions::new(0.5, 2.0, 0.02), &mut |_| {}).unwrap();
    assert_eq!(path.end, PathEnd::ReachedEnd);
    let amplitude = |x: &[f64], w: f64| {
        output_response(&system, x, w, 1.0, &ResponseOptions::default())
            .unwrap()
            .amplitude[0]
    };
    let mut crossings = vec![];
    for pair in path.points.windows(2) {
        let (a0, a1) = (
            amplitude(&pair[0].x, pair[0].parameter),
            amplitude(&pair[1].x, pair[1].parameter),
        );
        assert!(
            jenkins_relation(pair[0].parameter, a0).abs() <= 1e-5,
            "ω {}: {}",
            pair[0].parameter,
            jenkins_relation(pair[0].parameter, a0)
        );
        if (a0 - 1.0) * (a1 - 1.0) > 0.0 {
            continue;
        }
        // secant on A(ω) = 1 with Newton at fixed ω from the bracketing point
        let (mut w0, mut w1) = (pair[0].parameter, pair[1].parameter);
        let (mut f0, mut f1) = (a0 - 1.0, a1 - 1.0);
        let mut x = pair[0].x.clone();
        for _ in 0..30 {
            if (w1 - w0).abs() < 1e-12 {
                break;
            }
            let w = w1 - f1 * (w1 - w0) / (f1 - f0);
            let sol = solve_fixed(
                &fp,
                &x,
                w,
                &pair[0].state,
                &NewtonOptions {
                    tolerance: 1e-12,
                    increment_tolerance: 1e-10,
                    ..NewtonOptions::default()
                },
            )
            .unwrap();
            x = sol.x;
            (w0, f0) = (w1, f1);
            (w1, f1) = (w, amplitude(&x, w) - 1.0);
        }
        crossings.push(w1);
    }
    assert_eq!(crossings.len(), 2, "{crossings:?}");
    assert!((crossings[0] - 0.952957).abs() <= 1e-5, "{}", crossings[0]);
    assert!((crossings[1] - 1.249892).abs() <= 1e-5, "{}", crossings[1]);
}

/// Den Hartog (1931): X/(F0/k) = 2.71142 (r = 0.8, μN/F0 = 0.2), 1.70822 (r = 1.25, 0.2),
/// 4.91194 (r = 0.9, 0.3), approached with k_t = 500 k, H = 7, within 1 %.
#[test]
fn den_hartog_rigid_coulomb_ratios() {
    for (r, ratio, expected) in [
        (0.8, 0.2, 2.71142),
        (1.25, 0.2, 1.70822),
        (0.9, 0.3, 4.91194),
    ] {
        let model = sdof(0.0, 1.0, 7);
        let force = grounded_jenkins(500.0, ratio);
        let system = HbmSystem::new(HarmonicLayout::new(7, 1024).unwrap(), &model, &force).unwrap();
        let fp = FrequencyPath {
            system: &system,
            level: 1.0,
        };
        let start = if r < 1.0 { 0.5 } else { 2.0 };
        let path = trace(&fp, &ContinuationOptions::new(start, r, 0.02), &mut |_| {}).unwrap();
        assert_eq!(path.end, PathEnd::ReachedEnd, "r = {r}");
        let last = path.points.last().unwrap();
        assert!((last.parameter - r).abs() < 1e-12);
        let peak = output_response(
            &system,
            &last.x,
            r,
            1.0,
            &ResponseOptions {
                peak_samples: 4096,
                ..ResponseOptions::default()
            },
        )
        .unwrap()
        .peak[0];
        let err = (peak - expected).abs() / expected;
        assert!(
            err <= 0.01,
            "r = {r}, μN/F0 = {ratio}: X k/F0 = {peak}, Den Hartog {expected} ({:.2} %)",
            100.0 * err
        );
    }
}

/// μ → ∞: the element never slips and the FRF equals the linear FRF with k_t between DOFs 0 and
/// 2 (direct complex solve) at every path point, to 1e-8.
#[test]
fn stuck_limit_equals_the_linear_frf() {
    let (k, m, c) = chain4();
    let force = [0.0, 1.0, 0.0, 0.0];
    let kt = 0.8;
    let model = LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        Some(c.as_ref()),
        &force,
        vec![0, 2],
        vec![0, 1, 2, 3],
        3,
    )
    .unwrap();
    let element = friction_elements(
        ContactParams::new(kt, 0.0, 1.0, 1e9, "test").unwrap(),
        vec![vec![(0, -1.0), (1, 1.0)]],
        2,
    );
    let system = HbmSystem::new(HarmonicLayout::new(3, 64).unwrap(), &model, &element).unwrap();
    let fp = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let path = trace(&fp, &ContinuationOptions::new(0.2, 2.5, 0.05), &mut |_| {}).unwrap();
    assert_eq!(path.end, PathEnd::ReachedEnd);
    assert!(path.points.len() > 10);
    for p in &path.points {
        let w = p.parameter;
        let mut d = Mat::from_fn(4, 4, |i, j| {
            c64::new(k[(i, j)] - w * w * m[(i, j)], w * c[(i, j)])
        });
        for (i, j, s) in [(0, 0, 1.0), (2, 2, 1.0), (0, 2, -1.0), (2, 0, -1.0)] {
            d[(i, j)] += c64::new(s * kt, 0.0);
        }
        let x = complex_solve(&d, &force.map(|f| c64::new(f, 0.0)));
        let resp = output_response(&system, &p.x, w, 1.0, &ResponseOptions::default()).unwrap();
        let scale = x.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for (dof, xd) in x.iter().enumerate() {
            assert!(
                (resp.harmonics[dof][1] - xd).norm() <= 1e-8 * scale,
                "ω {w} dof {dof}"
            );
        }
    }
}
