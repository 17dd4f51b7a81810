//! Time-marching schemes (src/march) against closed forms and against each other on single-DOF
//! systems: linear steady state, Jenkins-element energy per cycle, a harmonic-balance reference
//! (H = 7, computed here independently), piecewise-linear = standard Newmark at the same step,
//! quasi-static = a direct static hysteresis computation, second-order step convergence, bad input.

use nlrom::case::MarchScheme;
use nlrom::march::element::{Direction, Element};
use nlrom::march::law::FrictionParams;
use nlrom::march::signal::Harmonic;
use nlrom::march::{march, InitialCondition, MarchSettings, MarchSystem};
use nlrom::Error;

/// m q̈ + c q̇ + k q + f_t = F cos ωt with a Jenkins element (k_t, slip limit F_s = μ n0) on q.
fn sdof(m: f64, c: f64, k: f64, f: f64, kt: f64, fs: f64) -> MarchSystem {
    let mut sys = MarchSystem {
        n: 1,
        mass: vec![m],
        damping: vec![c],
        stiffness: vec![k],
        force: vec![Harmonic {
            mean: 0.0,
            cos: f,
            sin: 0.0,
        }],
        damping_force: Vec::new(),
        elements: vec![Element {
            name: "jenkins".into(),
            tangential: Direction {
                weights: vec![(0, 1.0)],
                prescribed: Harmonic::default(),
            },
            normal: None,
            params: FrictionParams {
                kt,
                kn: 0.0,
                mu: 1.0,
                n0: fs,
            },
            applies_normal: true,
        }],
        dof_names: vec!["q".into()],
        initial: InitialCondition::Rest,
        displacement_scale: 1.0,
    };
    sys.displacement_scale = sys.default_displacement_scale();
    sys
}

fn settings(scheme: MarchScheme, omega: f64, periods: usize, spp: usize) -> MarchSettings {
    MarchSettings {
        scheme,
        omega,
        periods,
        steps_per_period: spp,
        ..MarchSettings::default()
    }
}

/// A friction element that never slips (F_s huge) makes the system linear with stiffness k + k_t:
/// every dynamic scheme's steady first harmonic matches the exact F/(k + k_t − mω² + icω).
#[test]
fn linear_sdof_reaches_the_exact_steady_state() {
    let (m, c, k, kt, f, omega) = (1.0, 0.1, 1.0, 0.5, 0.3, 1.1);
    let sys = sdof(m, c, k, f, kt, 1e9);
    let (dr, di) = (k + kt - m * omega * omega, c * omega);
    let den = dr * dr + di * di;
    let exact = (f * dr / den, -f * di / den); // Q = F / (dr + i di)
    for scheme in [
        MarchScheme::Newmark,
        MarchScheme::Adaptive,
        MarchScheme::PiecewiseLinear,
        MarchScheme::AdaptivePiecewiseLinear,
    ] {
        let mut s = settings(scheme, omega, 80, 400);
        s.stop_at_steady = true;
        s.steady_tolerance = 1e-7;
        let out = march(&sys, &s).unwrap();
        assert!(out.steady_period.is_some(), "{scheme}: not steady");
        let (re, im) = out.harmonics[0][1];
        let err = (re - exact.0).hypot(im - exact.1) / exact.0.hypot(exact.1);
        assert!(
            err < 2e-4,
            "{scheme}: first harmonic ({re}, {im}) vs {exact:?}: {err}"
        );
    }
}

/// One sample of a Jenkins element written out here (independent of src/march/law.rs): force and
/// the new slider.
fn jenkins(kt: f64, fs: f64, u: f64, w: f64) -> (f64, f64) {
    let trial = kt * (u - w);
    if trial.abs() <= fs {
        (trial, w)
    } else {
        let f = fs * trial.signum();
        (f, u - f / kt)
    }
}

// The harmonic-balance cross-check is tests/march_hbm.rs (against nlrom::hbm).

/// Energy per cycle at steady state: the friction work ∮ f_t du over the last period equals the
/// Jenkins closed form W = 4F_s(A − F_s/k_t) for the element's half peak-to-peak travel A, and the
/// input work ∮ F cos ωt q̇ dt equals viscous plus friction dissipation.
#[test]
fn jenkins_energy_per_cycle_and_energy_balance() {
    let (m, c, k, f, kt, fs) = (1.0, 0.1, 1.0, 0.5, 1.0, 0.3);
    let omega = 0.9;
    let sys = sdof(m, c, k, f, kt, fs);
    let mut s = settings(MarchScheme::PiecewiseLinear, omega, 200, 2000);
    s.stop_at_steady = true;
    s.steady_tolerance = 1e-9;
    s.record_velocities = true;
    let out = march(&sys, &s).unwrap();
    assert!(out.steady_period.is_some());
    let h = &out.history;
    let local = h.contact_displacements(&sys, omega);
    let np = out.periods.len();
    let (first, last) = (out.periods[np - 2].end_index, out.periods[np - 1].end_index);
    let (mut w_fric, mut w_in, mut w_visc) = (0.0, 0.0, 0.0);
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for i in first..last {
        let dt = h.time[i + 1] - h.time[i];
        let du = local[2 * (i + 1)] - local[2 * i];
        w_fric += 0.5 * (h.force[2 * i] + h.force[2 * (i + 1)]) * du;
        let p = |j: usize| f * (omega * h.time[j]).cos() * h.v[j];
        w_in += 0.5 * dt * (p(i) + p(i + 1));
        w_visc += 0.5 * dt * c * (h.v[i].powi(2) + h.v[i + 1].powi(2));
        lo = lo.min(local[2 * i]);
        hi = hi.max(local[2 * i]);
    }
    let a = 0.5 * (hi - lo);
    let closed = 4.0 * fs * (a - fs / kt);
    eprintln!("A = {a:.6}, W_fric = {w_fric:.6}, closed form {closed:.6}, W_in = {w_in:.6}, W_visc = {w_visc:.6}");
    assert!(
        (w_fric - closed).abs() < 2e-3 * closed,
        "{w_fric} vs {closed}"
    );
    assert!(
        (w_in - w_visc - w_fric).abs() < 2e-3 * w_in,
        "balance {w_in} vs {}",
        w_visc + w_fric
    );
}

/// Piecewise-linear Newmark solves the same implicit step as standard Newmark: at the same step
/// the two histories agree to the standard corrector's tolerance, and > 90 % of the piecewise-linear
/// steps take one iteration (paper §4.3).
#[test]
fn piecewise_linear_equals_standard_newmark_at_the_same_step() {
    let sys = sdof(1.0, 0.05, 1.0, 0.5, 2.0, 0.3);
    let omega = 1.2;
    let mut runs = Vec::new();
    for scheme in [MarchScheme::Newmark, MarchScheme::PiecewiseLinear] {
        let mut s = settings(scheme, omega, 10, 300);
        s.time_step = Some(2.0 * std::f64::consts::PI / omega / 300.0);
        s.tolerance = 1e-13;
        runs.push(march(&sys, &s).unwrap());
    }
    let (a, b) = (&runs[0].history, &runs[1].history);
    assert_eq!(a.len(), b.len());
    let scale = a.q.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let diff =
        a.q.iter()
            .zip(&b.q)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
    eprintln!("max |q_std − q_pl| / max|q| = {:.2e}", diff / scale);
    assert!(diff < 1e-9 * scale, "{diff} vs scale {scale}");
    assert_eq!(a.state, b.state, "the contact states differ");
    let frac = runs[1].single_iteration_fraction();
    let changes: usize = runs[1].periods.iter().map(|p| p.state_changes).sum();
    assert!(
        changes >= 20,
        "the run should cross many transitions, saw {changes}"
    );
    eprintln!(
        "iterations: standard {}, piecewise-linear {} (single-iteration steps {:.1} %)",
        runs[0].total_iterations,
        runs[1].total_iterations,
        100.0 * frac
    );
    assert!(frac > 0.9, "single-iteration fraction {frac}");
    assert!(runs[0].total_iterations > runs[1].total_iterations);
}

/// Quasi-static method on a massless system k q + f_t(q) = F cos ωt equals a direct static
/// hysteresis computation (bisection of the monotone scalar equation at every instant, with the
/// slider carried along), and its force harmonics under a prescribed u = A cos ωt equal the
/// Jenkins closed form of `docs/theory.md` (a1 = 0.2523158, |b1| = 0.2673803 for k_t = 1, F_s = 0.3, A = 1).
#[test]
fn quasi_static_equals_direct_static_hysteresis() {
    let (k, kt, fs, f, omega) = (0.5, 1.0, 0.3, 1.0, 3.0);
    let mut sys = sdof(0.0, 0.0, k, f, kt, fs);
    sys.mass = vec![0.0];
    let n_steps = 300;
    let mut s = settings(MarchScheme::QuasiStatic, omega, 2, n_steps);
    s.harmonics = 1;
    let out = march(&sys, &s).unwrap();
    let h = &out.history;
    assert_eq!(h.len(), 2 * n_steps + 1);
    let mut w = 0.0;
    let mut worst: f64 = 0.0;
    for (i, &t) in h.time.iter().enumerate().skip(1) {
        let target = f * (omega * t).cos();
        let g = |q: f64| k * q + jenkins(kt, fs, q, w).0 - target;
        let (mut lo, mut hi) = (-10.0, 10.0);
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if g(mid) > 0.0 {
                hi = mid
            } else {
                lo = mid
            }
        }
        let q = 0.5 * (lo + hi);
        w = jenkins(kt, fs, q, w).1;
        worst = worst.max((q - h.q[i]).abs());
    }
    assert!(worst < 1e-12, "quasi-static vs direct: {worst}");
    // dynamic schemes are refused on a massless model
    let e = march(&sys, &settings(MarchScheme::Newmark, omega, 1, 100)).unwrap_err();
    assert!(matches!(e, Error::Input(_)), "{e}");
    assert!(e.to_string().contains("mass"), "{e}");

    // prescribed u = cos ωt on an element acting on nothing
    let mut sys = sdof(0.0, 0.0, 1.0, 0.0, kt, fs);
    sys.mass = vec![0.0];
    sys.elements[0].tangential = Direction {
        weights: vec![],
        prescribed: Harmonic::cosine(1.0, 0.0),
    };
    let out = march(&sys, &settings(MarchScheme::QuasiStatic, omega, 2, 4000)).unwrap();
    let h = &out.history;
    let local = h.contact_displacements(&sys, omega);
    let (first, last) = (out.periods[0].end_index, out.periods[1].end_index);
    let (mut a1, mut b1, mut work) = (0.0, 0.0, 0.0);
    let period = 2.0 * std::f64::consts::PI / omega;
    for i in first..last {
        let dt = h.time[i + 1] - h.time[i];
        let fc = |j: usize| h.force[2 * j] * (omega * h.time[j]).cos();
        let fsn = |j: usize| h.force[2 * j] * (omega * h.time[j]).sin();
        a1 += 0.5 * dt * (fc(i) + fc(i + 1)) * 2.0 / period;
        b1 += 0.5 * dt * (fsn(i) + fsn(i + 1)) * 2.0 / period;
        work += 0.5 * (h.force[2 * i] + h.force[2 * i + 2]) * (local[2 * i + 2] - local[2 * i]);
    }
    eprintln!("a1 = {a1:.7}, b1 = {b1:.7}, W = {work:.7}");
    assert!((a1 - 0.2523158).abs() < 2e-4, "a1 {a1}");
    assert!((b1.abs() - 0.2673803).abs() < 2e-4, "b1 {b1}");
    assert!((work - 0.84).abs() < 1e-3, "W {work}");
}

/// Second-order convergence of every Newmark scheme where no state transition falls inside a step:
/// from rest, the oscillator stays in stick up to t_w; the error at t_w against a Δτ/16 reference
/// drops by 4 ± 0.4 when Δτ halves.
#[test]
fn newmark_schemes_converge_at_second_order_between_transitions() {
    let sys = sdof(1.0, 0.1, 1.0, 0.5, 1.0, 10.0);
    let omega = 0.7;
    let t_w = 3.0; // |k_t q| stays far below F_s = 10: no transition
    let run = |scheme: MarchScheme, dt: f64| -> f64 {
        let mut s = settings(scheme, omega, 1, 10);
        s.time_step = Some(dt);
        s.tolerance = 1e-14;
        let out = march(&sys, &s).unwrap();
        let h = &out.history;
        let i = h
            .time
            .iter()
            .position(|&t| (t - t_w).abs() < 1e-9)
            .expect("t_w on the grid");
        assert!(h.state.iter().all(|&c| c == 1), "left stick");
        h.q[i]
    };
    for scheme in [MarchScheme::Newmark, MarchScheme::PiecewiseLinear] {
        let dt = t_w / 15.0;
        let reference = run(scheme, dt / 16.0);
        let e1 = (run(scheme, dt) - reference).abs();
        let e2 = (run(scheme, dt / 2.0) - reference).abs();
        let e4 = (run(scheme, dt / 4.0) - reference).abs();
        eprintln!(
            "{scheme}: errors {e1:.3e} {e2:.3e} {e4:.3e}, ratios {:.3} {:.3}",
            e1 / e2,
            e2 / e4
        );
        assert!((e1 / e2 - 4.0).abs() < 0.4 && (e2 / e4 - 4.0).abs() < 0.4);
    }
}

/// Bad settings are input errors that say what to change.
#[test]
fn bad_settings_are_input_errors() {
    let sys = sdof(1.0, 0.1, 1.0, 0.5, 1.0, 0.3);
    let check = |s: MarchSettings, needle: &str| {
        let e = march(&sys, &s).unwrap_err();
        assert!(matches!(e, Error::Input(_)), "{e}");
        assert!(e.to_string().contains(needle), "{e} lacks '{needle}'");
    };
    let base = settings(MarchScheme::Newmark, 1.0, 1, 100);
    check(
        MarchSettings {
            time_step: Some(0.0),
            ..base.clone()
        },
        "time step must be > 0",
    );
    check(
        MarchSettings {
            time_step: Some(-1e-3),
            ..base.clone()
        },
        "time step must be > 0",
    );
    check(
        MarchSettings {
            step_ratio: 0.4,
            ..base.clone()
        },
        "1/π",
    );
    // 𝕋_stick = 2π/√2 ≈ 4.44 s: Δτ = 2 s is Δτ/𝕋 = 0.45 > 1/π
    check(
        MarchSettings {
            time_step: Some(2.0),
            ..base.clone()
        },
        "0.318",
    );
    check(
        MarchSettings {
            omega: 0.0,
            ..base.clone()
        },
        "frequency",
    );
    check(
        MarchSettings {
            periods: 0,
            ..base.clone()
        },
        "periods",
    );
    // the piecewise-linear scheme is not bound by the corrector's limit
    assert!(march(
        &sys,
        &MarchSettings {
            time_step: Some(2.0),
            scheme: MarchScheme::PiecewiseLinear,
            ..base
        }
    )
    .is_ok());
}
