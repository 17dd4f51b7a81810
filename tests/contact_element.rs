//! One contact element over a period (`nlrom::contact::{aft, element}`): AFT round trip, the
//! Jenkins closed forms (`docs/theory.md`, "The friction contact element"), energy per cycle against the loop area, the separation
//! fraction under harmonic normal motion, and the analytic Jacobian against central finite
//! differences in every contact regime, for both variants and H ∈ {1, 3, 7}.

use nlrom::contact::aft::Aft;
use nlrom::contact::element::{evaluate, LocalElement, Workspace};
use nlrom::contact::law::{ContactParams, Variant};
use nlrom::harmonics::HarmonicLayout;

mod support;
use support::random::XorShift;

fn params(kt: f64, kn: f64, mu: f64, n0: f64) -> ContactParams {
    ContactParams::new(kt, kn, mu, n0, "test").unwrap()
}

#[test]
fn aft_round_trip_is_exact_for_band_limited_signals() {
    let mut rng = XorShift(7);
    for (h, n_t) in [(1, 4), (3, 16), (3, 13), (7, 32), (7, 100)] {
        let aft = Aft::new(HarmonicLayout::new(h, n_t).unwrap()).unwrap();
        let mut s = aft.scratch();
        let q: Vec<f64> = (0..2 * h + 1).map(|_| rng.uniform()).collect();
        let mut x = vec![0.0; n_t];
        aft.to_time(&q, &mut x, &mut s);
        for (j, xj) in x.iter().enumerate() {
            let tau = 2.0 * std::f64::consts::PI * j as f64 / n_t as f64;
            let mut direct = q[0];
            for n in 1..=h {
                let a = n as f64 * tau;
                direct += q[2 * n - 1] * a.cos() - q[2 * n] * a.sin();
            }
            assert!((xj - direct).abs() < 1e-13, "H={h} N_t={n_t} sample {j}");
        }
        let mut back = vec![0.0; 2 * h + 1];
        aft.to_harmonics(&x, &mut back, &mut s);
        for (a, b) in q.iter().zip(&back) {
            assert!((a - b).abs() < 1e-13, "H={h} N_t={n_t}: {a} vs {b}");
        }
    }
    assert!(Aft::new(HarmonicLayout {
        harmonics: 3,
        time_samples: 6
    })
    .is_err());
}

/// The Jenkins element (k_t, slip force F_s = μ n0) under u = A cos τ (`docs/theory.md`).
#[test]
fn jenkins_closed_forms() {
    let aft = Aft::new(HarmonicLayout::new(1, 4096).unwrap()).unwrap();
    let mut ws = Workspace::new(&aft);
    for (kt, fs, amp) in [(1.0, 0.3, 1.0), (2.5, 0.4, 0.5), (1.0, 0.3, 0.31)] {
        let el = LocalElement {
            params: params(kt, 0.0, fs / 2.0, 2.0),
            variant: Variant::OneD,
            tangential: 1,
            normal: false,
        };
        let mut slider = [0.0; 2];
        let mut f = [0.0; 3];
        let marching = evaluate(
            &el,
            &aft,
            &[0.0, amp, 0.0],
            &mut slider,
            &mut f,
            false,
            &mut ws,
        )
        .unwrap();
        assert!(marching.converged && marching.periods <= 3, "{marching:?}");
        let beta = (1.0 - 2.0 * fs / (kt * amp)).acos();
        let a1 = amp * kt / std::f64::consts::PI * (beta - 0.5 * (2.0 * beta).sin());
        let b1 = 4.0 * fs / std::f64::consts::PI * (1.0 - fs / (kt * amp));
        let w = 4.0 * fs * (amp - fs / kt);
        if (kt, fs, amp) == (1.0, 0.3, 1.0) {
            assert!((a1 - 0.2523158).abs() < 1e-7 && (b1 - 0.2673803).abs() < 1e-7);
            assert!((w - 0.84).abs() < 1e-12);
        }
        assert!((f[1] - a1).abs() <= 1e-6 * a1, "a1 {} vs {a1}", f[1]);
        // Friction lags: f = a1 cos τ − Im F sin τ with Im F = +|b1| (energy is dissipated).
        assert!((f[2] - b1).abs() <= 1e-6 * b1, "b1 {} vs {b1}", f[2]);
        let report = ws.report();
        assert!(
            (report.dissipated_energy - w).abs() <= 1e-6 * w,
            "W {} vs {w}",
            report.dissipated_energy
        );
        // The energy also follows from the harmonics: W = π A Im F⁽¹⁾ for u = A cos τ.
        assert!((std::f64::consts::PI * amp * f[2] - w).abs() <= 1e-6 * w);
    }
}

/// Trapezoidal loop area ∮ f_t · du_t from the hysteresis samples.
fn loop_area(ws: &Workspace) -> f64 {
    let l = ws.hysteresis();
    let n = l.v.len();
    let mut area = 0.0;
    for d in 0..2 {
        for j in 0..n {
            let p = (j + n - 1) % n;
            area += 0.5 * (l.ft[d][j] + l.ft[d][p]) * (l.u[d][j] - l.u[d][p]);
        }
    }
    area
}

/// The dissipated energy (slider work, exact for the time-discrete law) against the trapezoidal
/// loop area ∮ f_t·du_t of the samples: both converge to the continuous cycle's energy, their
/// difference falls like 1/N_t (4× per 4× samples when slip or separation dominate; it is zero for the Jenkins element, whose slip force is constant).
#[test]
fn dissipated_energy_equals_loop_area() {
    let mut rng = XorShift(99);
    for variant in [Variant::OneD, Variant::TwoD] {
        for trial in 0..3 {
            let el = LocalElement {
                params: params(10.0, 20.0, 0.5, 1.0),
                variant,
                tangential: 2,
                normal: true,
            };
            let vamp = [0.0, 0.02, 0.08][trial];
            let x = random_input(&mut rng, 3, [0.2, 0.15, vamp]);
            let mut rel = Vec::new();
            for n_t in [1024, 4096, 16384] {
                let aft = Aft::new(HarmonicLayout::new(3, n_t).unwrap()).unwrap();
                let mut ws = Workspace::new(&aft);
                let mut slider = [0.0; 2];
                let mut f = vec![0.0; 21];
                evaluate(&el, &aft, &x, &mut slider, &mut f, false, &mut ws).unwrap();
                let w = ws.report().dissipated_energy;
                assert!(w > 0.0);
                rel.push(((w - loop_area(&ws)) / w).abs());
            }
            assert!(
                rel[2] <= 3e-4 && rel[0] >= 3.0 * rel[2],
                "{variant:?} trial {trial}: relative differences at N_t = 1024, 4096, 16384: {rel:?}"
            );
        }
    }
}

#[test]
fn separation_fraction_under_harmonic_normal_motion() {
    let n_t = 4096;
    let aft = Aft::new(HarmonicLayout::new(1, n_t).unwrap()).unwrap();
    let mut ws = Workspace::new(&aft);
    for (n0, kn, amp) in [(1.0, 20.0, 0.1), (1.0, 20.0, 0.06), (0.5, 100.0, 0.2)] {
        let el = LocalElement {
            params: params(10.0, kn, 0.5, n0),
            variant: Variant::OneD,
            tangential: 1,
            normal: true,
        };
        // u = 0.05 sin τ, v = amp cos τ
        let x = [0.0, 0.0, -0.05, 0.0, amp, 0.0];
        let mut slider = [0.0; 2];
        let mut f = [0.0; 6];
        evaluate(&el, &aft, &x, &mut slider, &mut f, false, &mut ws).unwrap();
        // f_n = 0 where cos τ ≤ −n0/(k_n A): a fraction acos(n0/(k_n A))/π of the period.
        let expected = (n0 / (kn * amp)).acos() / std::f64::consts::PI;
        let r = ws.report();
        assert!(
            (r.separation - expected).abs() <= 1.0 / n_t as f64,
            "separation {} vs {expected}",
            r.separation
        );
        assert!((r.stick + r.slip + r.separation - 1.0).abs() < 1e-12);
    }
}

/// Random local coefficients of three signals with amplitudes `amp`, decaying as 1/n.
fn random_input(rng: &mut XorShift, h: usize, amp: [f64; 3]) -> Vec<f64> {
    let m = 2 * h + 1;
    let mut x = vec![0.0; 3 * m];
    for (c, a) in amp.iter().enumerate() {
        x[c * m] = 0.3 * a * rng.uniform();
        for n in 1..=h {
            x[c * m + 2 * n - 1] = a * rng.uniform() / n as f64;
            x[c * m + 2 * n] = a * rng.uniform() / n as f64;
        }
    }
    x
}

/// The regimes a test case must produce.
#[derive(Clone, Copy, Debug)]
enum Case {
    FullStick,
    GrossSlip,
    PartialSlip,
    IntermittentSeparation,
    OpenGap,
}

/// Checks the analytic Jacobian against central differences for one random input of `case`.
///
/// A periodic state reached by *shakedown* (a direction slipped while marching, then sticks with
/// its trial force exactly on the limit) is a kink of the periodic solution: its one-sided
/// derivatives differ. Such draws are recognised by forward and backward differences that
/// disagree and replaced by a new draw (the analytic Jacobian returns the stick side there).
fn check_jacobian(variant: Variant, h: usize, case: Case, seed: u64) {
    let aft = Aft::new(HarmonicLayout::with_default_samples(h)).unwrap();
    let mut ws = Workspace::new(&aft);
    let mut rng = XorShift(seed);
    // k_t = 10, μ n0 = 0.5: sticks for |u − w| ≤ 0.05; k_n v = n0 at |v| = 0.05.
    let (n0, amp) = match case {
        Case::FullStick => (1.0, [0.01, 0.008, 0.01]),
        Case::GrossSlip => (1.0, [1.0, 0.8, 0.01]),
        Case::PartialSlip => (1.0, [0.12, 0.1, 0.01]),
        Case::IntermittentSeparation => (1.0, [0.2, 0.15, 0.1]),
        Case::OpenGap => (-1.0, [0.2, 0.15, 0.02]),
    };
    let el = LocalElement {
        params: params(10.0, 20.0, 0.5, n0),
        variant,
        tangential: 2,
        normal: true,
    };
    let m = 2 * h + 1;
    let cols = 3 * m + 1;
    for _draw in 0..20 {
        let x = random_input(&mut rng, h, amp);
        let mut slider = [0.0; 2];
        let mut f = vec![0.0; 3 * m];
        let marching = evaluate(&el, &aft, &x, &mut slider, &mut f, true, &mut ws).unwrap();
        assert!(
            marching.converged,
            "{variant:?} H={h} {case:?}: {marching:?}"
        );
        let r = ws.report();
        let regimes_ok = match case {
            Case::FullStick => r.stick == 1.0,
            Case::GrossSlip => r.slip > 0.6 && r.separation == 0.0,
            Case::PartialSlip => r.slip > 0.0 && r.stick > 0.2 && r.separation == 0.0,
            Case::IntermittentSeparation => r.separation > 0.0 && r.separation < 1.0,
            Case::OpenGap => r.separation == 1.0,
        };
        if !regimes_ok {
            continue;
        }
        let (jac, jcols) = ws.jacobian();
        assert_eq!(jcols, cols);
        let jac = jac.to_vec();
        let scale = jac.iter().fold(0.0f64, |a, b| a.max(b.abs()));
        // Differences from the converged state (as a continuation calls the element).
        let hstep = 1e-6;
        let mut fd = vec![0.0; 3 * m * cols];
        let mut kink = 0.0f64;
        let mut f0 = vec![0.0; 3 * m];
        let mut s0 = slider;
        evaluate(&el, &aft, &x, &mut s0, &mut f0, false, &mut ws).unwrap();
        for c in 0..cols {
            let mut out = [vec![0.0; 3 * m], vec![0.0; 3 * m]];
            for (k, sign) in [1.0, -1.0].into_iter().enumerate() {
                let mut xs = x.clone();
                let mut e = el;
                if c < 3 * m {
                    xs[c] += sign * hstep;
                } else {
                    e.params.n0 += sign * hstep;
                }
                let mut s = slider;
                evaluate(&e, &aft, &xs, &mut s, &mut out[k], false, &mut ws).unwrap();
            }
            for r in 0..3 * m {
                fd[r * cols + c] = (out[0][r] - out[1][r]) / (2.0 * hstep);
                let forward = (out[0][r] - f0[r]) / hstep;
                let backward = (f0[r] - out[1][r]) / hstep;
                kink = kink.max((forward - backward).abs());
            }
        }
        if kink > 1e-3 * scale.max(1.0) {
            continue;
        }
        for r in 0..3 * m {
            for c in 0..cols {
                let an = jac[r * cols + c];
                assert!(
                    (fd[r * cols + c] - an).abs() <= 1e-6 * scale.max(1e-300),
                    "{variant:?} H={h} {case:?}: ∂F[{r}]/∂x[{c}] analytic {an} vs FD {} (scale {scale})",
                    fd[r * cols + c]
                );
            }
        }
        if let Case::OpenGap = case {
            assert_eq!(scale, 0.0, "an open gap has no force and a zero Jacobian");
            assert!(f.iter().all(|&v| v == 0.0));
        } else {
            assert!(scale > 1.0);
        }
        return;
    }
    panic!(
        "{variant:?} H={h} {case:?}: no differentiable random input with these regimes in 20 draws"
    );
}

#[test]
fn jacobian_matches_finite_differences_in_every_regime() {
    let mut seed = 1;
    for variant in [Variant::OneD, Variant::TwoD] {
        for h in [1, 3, 7] {
            for case in [
                Case::FullStick,
                Case::GrossSlip,
                Case::PartialSlip,
                Case::IntermittentSeparation,
                Case::OpenGap,
            ] {
                seed += 1;
                check_jacobian(variant, h, case, seed);
            }
        }
    }
}

#[test]
fn returned_state_is_periodic() {
    let aft = Aft::new(HarmonicLayout::with_default_samples(3)).unwrap();
    let mut ws = Workspace::new(&aft);
    let mut rng = XorShift(5);
    let el = LocalElement {
        params: params(10.0, 20.0, 0.5, 1.0),
        variant: Variant::TwoD,
        tangential: 2,
        normal: true,
    };
    let x = random_input(&mut rng, 3, [0.2, 0.15, 0.03]);
    let mut slider = [0.0; 2];
    let mut f1 = vec![0.0; 21];
    evaluate(&el, &aft, &x, &mut slider, &mut f1, false, &mut ws).unwrap();
    let mut f2 = vec![0.0; 21];
    let again = evaluate(&el, &aft, &x, &mut slider, &mut f2, false, &mut ws).unwrap();
    assert_eq!(again.periods, 1);
    for (a, b) in f1.iter().zip(&f2) {
        assert!((a - b).abs() < 1e-12);
    }
}

/// The forces are those of the periodic state marched from the sliders at rest, whatever slider
/// state the caller passes (a warm start): closed forms for u = U0 + A cos τ on a Jenkins element
/// (k_t, slip force F_s) — stuck (k_t (|U0| + A) < F_s: f = k_t u), a one-way shakedown
/// (k_t (U0 + A) > F_s but k_t A < F_s: slip at τ = 0 sets the slider to U0 + A − F_s/k_t, then
/// stick: F⁽⁰⁾ = F_s − k_t A, F⁽¹⁾ = k_t A) and two-way slip (the first harmonic of
/// `jenkins_closed_forms`, independent of U0).
#[test]
fn forces_do_not_depend_on_the_callers_slider_state() {
    let aft = Aft::new(HarmonicLayout::new(1, 4096).unwrap()).unwrap();
    let mut ws = Workspace::new(&aft);
    let (kt, fs) = (2.0, 0.5);
    let el = LocalElement {
        params: params(kt, 0.0, fs / 2.0, 2.0),
        variant: Variant::OneD,
        tangential: 1,
        normal: false,
    };
    let two_way = |amp: f64| {
        let beta = (1.0 - 2.0 * fs / (kt * amp)).acos();
        amp * kt / std::f64::consts::PI * (beta - 0.5 * (2.0 * beta).sin())
    };
    // (U0, A, expected F⁽⁰⁾ or None when not in closed form, expected Re F⁽¹⁾)
    let cases = [
        (0.05, 0.1, Some(kt * 0.05), kt * 0.1),
        (0.2, 0.1, Some(fs - kt * 0.1), kt * 0.1),
        (0.0, 1.0, Some(0.0), two_way(1.0)),
    ];
    for (u0, amp, f0, f1) in cases {
        for warm in [0.0, 0.3, -0.17, 0.12] {
            let mut slider = [warm, 0.0];
            let mut f = [0.0; 3];
            evaluate(
                &el,
                &aft,
                &[u0, amp, 0.0],
                &mut slider,
                &mut f,
                false,
                &mut ws,
            )
            .unwrap();
            if let Some(f0) = f0 {
                assert!(
                    (f[0] - f0).abs() <= 1e-9,
                    "U0 {u0} A {amp} warm {warm}: F0 {} vs {f0}",
                    f[0]
                );
            }
            let tol = if f0 == Some(0.0) { 1e-6 * f1 } else { 1e-9 };
            assert!(
                (f[1] - f1).abs() <= tol,
                "U0 {u0} A {amp} warm {warm}: Re F1 {} vs {f1}",
                f[1]
            );
        }
    }
}
