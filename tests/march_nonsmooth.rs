//! The nonsmooth schemes (Moreau–Jean θ-method, Carpenter's explicit Lagrange multipliers)
//! against closed forms, an event-driven reference, continuum solutions and Siconos' published
//! reference data.

// The Siconos reference rows are copied digit for digit as printed in the reference files.
#![allow(clippy::excessive_precision)]

mod support;

use support::cli::{json_report, nlrom};

use nlrom::march::carpenter::{carpenter, stability_limits};
use nlrom::march::moreau_jean::moreau_jean;
use nlrom::march::obstacle::{NonsmoothHistory, NonsmoothSettings, NonsmoothSystem, Obstacle};
use nlrom::march::signal::Harmonic;

fn one_dof(m: f64, c: f64, k: f64) -> NonsmoothSystem {
    NonsmoothSystem::mechanical(vec![m], vec![c], vec![k])
}

fn settings(h: f64, steps: usize, gamma: f64) -> NonsmoothSettings {
    NonsmoothSettings {
        step: h,
        steps,
        gamma,
        gamma_thermal: gamma,
        ..NonsmoothSettings::default()
    }
}

// ---------------------------------------------------------------------------------------------
// Siconos reference data (Acary et al., Siconos, INRIA, Apache-2.0): rows copied as expected
// values from kernel/swig/tests/data/BouncingBallTS.ref (commit b59f97ad, 2024) and
// Examples/Mechanics/ImpactingBar/ImpactingBar.ref (commit 9bf24ac1, 2014).
// ---------------------------------------------------------------------------------------------

/// Bouncing ball: q₀ = 1 m, m = 1 kg, f = −9.81 N, floor y = q ≥ 0, e = 0.9, γ = 1/2,
/// h = 0.005 s, 2000 steps. Rows (step, q, v, λ).
const BALL_ROWS: [(usize, f64, f64, f64); 6] = [
    (90, 6.737499999998810e-03, -4.414500000000009e+00, 0.0),
    (
        91,
        5.633874999998808e-03,
        3.973050000000009e+00,
        8.436600000000018e+00,
    ),
    (200, 7.140385000000000e-01, -1.373399999999999e+00, 0.0),
    (400, 1.059962500000670e-03, -3.585554999999998e+00, 0.0),
    (1000, 1.513536802625140e-01, -7.522581257549901e-01, 0.0),
    (
        2000,
        -2.288618090550717e-05,
        -2.775557561562891e-17,
        4.904999999999019e-02,
    ),
];

#[test]
fn bouncing_ball_reproduces_siconos_reference_rows() {
    let mut sys = one_dof(1.0, 0.0, 0.0);
    sys.force[0] = Harmonic::constant(-9.81);
    sys.x0[0] = 1.0;
    sys.obstacles
        .push(Obstacle::new("floor", vec![(0, 1.0)], 0.0, 0.9));
    let h = moreau_jean(&sys, &settings(0.005, 2000, 0.5)).unwrap();
    for (k, q, v, l) in BALL_ROWS {
        assert!((h.time[k] - 0.005 * k as f64).abs() < 1e-12);
        assert!(
            (h.x[k] - q).abs() < 1e-12,
            "q at step {k}: {} vs {q}",
            h.x[k]
        );
        assert!(
            (h.v[k] - v).abs() < 1e-12,
            "v at step {k}: {} vs {v}",
            h.v[k]
        );
        assert!((h.impulse[k] - l).abs() < 1e-12, "λ at step {k}");
    }
    // Siconos: 345 steps with an impulse, max 8.4366 N·s, impulses summing to m g T = 98.1 N·s.
    let nonzero = h.impulse.iter().filter(|&&l| l != 0.0).count();
    assert_eq!(nonzero, 345);
    let total: f64 = h.impulse.iter().sum();
    assert!((total - 98.1).abs() < 1e-9, "total impulse {total}");
    // The first impact falls in the step containing the exact time √(2/9.81) = 0.45152 s.
    let first = h.impulse.iter().position(|&l| l > 0.0).unwrap();
    let t_star = (2.0 / 9.81_f64).sqrt();
    assert!(h.time[first - 1] < t_star && t_star <= h.time[first] + 0.005);
}

/// The Siconos impacting bar: 100 nodes, 99 linear elements of length l = 0.01 m (the
/// reference's effective length 0.99 m), E = 210 GPa, ρ = 7800 kg/m³, S = 3.14e-4 m², all nodes
/// at q = 5e-5 m moving at −0.1 m/s towards a wall at node 0.
fn siconos_bar(lumped: bool) -> NonsmoothSystem {
    let n = 100;
    let (e, rho, s, l) = (210e9, 7800.0, 3.14e-4, 0.01);
    let mut m = vec![0.0; n * n];
    let mut k = vec![0.0; n * n];
    for el in 0..n - 1 {
        let (a, b) = (el, el + 1);
        let me = rho * s * l / 6.0;
        let ke = e * s / l;
        if lumped {
            m[a * n + a] += 3.0 * me;
            m[b * n + b] += 3.0 * me;
        } else {
            m[a * n + a] += 2.0 * me;
            m[b * n + b] += 2.0 * me;
            m[a * n + b] += me;
            m[b * n + a] += me;
        }
        k[a * n + a] += ke;
        k[b * n + b] += ke;
        k[a * n + b] -= ke;
        k[b * n + a] -= ke;
    }
    let mut sys = NonsmoothSystem::mechanical(m, vec![0.0; n * n], k);
    sys.x0 = vec![5e-5; n];
    sys.v0 = vec![-0.1; n];
    sys.obstacles
        .push(Obstacle::new("wall", vec![(0, 1.0)], 0.0, 0.0));
    sys
}

fn quad(a: &[f64], x: &[f64]) -> f64 {
    let n = x.len();
    (0..n)
        .map(|i| x[i] * (0..n).map(|j| a[i * n + j] * x[j]).sum::<f64>())
        .sum()
}

#[test]
fn impacting_bar_reproduces_siconos_reference_rows() {
    let sys = siconos_bar(false);
    let s = NonsmoothSettings {
        start: 1e-8,
        ..settings(2e-6, 748, 1.0)
    };
    let h = moreau_jean(&sys, &s).unwrap();
    let n = sys.n;
    // (step, q₀, λ/h, λ): first impulse, plateau, end of the run.
    for (k, q0, p, lam) in [
        (
            251,
            2.062789924360238e-19,
            1.319080327349324e+03,
            2.638160654698648e-03,
        ),
        (
            298,
            -1.856353591158245e-07,
            1.270827478456420e+03,
            2.541654956912840e-03,
        ),
        (
            400,
            -1.856353591158252e-07,
            1.268917910729377e+03,
            2.537835821458753e-03,
        ),
    ] {
        let rel = |a: f64, b: f64| (a - b).abs() / b.abs().max(1e-300);
        assert!(
            (h.x[k * n] - q0).abs() < 1e-18,
            "q₀ at step {k}: {}",
            h.x[k * n]
        );
        assert!(rel(h.impulse[k] / 2e-6, p) < 1e-10, "λ/h at step {k}");
        assert!(rel(h.impulse[k], lam) < 1e-10, "λ at step {k}");
    }
    // Last row: q₀, v₀, qᵀKq, vᵀMv.
    let xe = &h.x[748 * n..749 * n];
    let ve = &h.v[748 * n..749 * n];
    let rel = |a: f64, b: f64| (a - b).abs() / b.abs();
    assert!(rel(xe[0], 5.442127293396990e-05) < 1e-9);
    assert!(rel(ve[0], 9.988379642872935e-02) < 1e-9);
    assert!(rel(quad(&sys.stiffness, xe), 2.596649979310149e-04) < 1e-9);
    assert!(rel(quad(&sys.mass, ve), 1.920364876961150e-02) < 1e-9);
    // 191 steps in contact, total impulse 0.456787 N·s.
    assert_eq!(h.impulse.iter().filter(|&&l| l > 0.0).count(), 191);
    let total: f64 = h.impulse.iter().sum();
    assert!((total - 0.456787).abs() < 1e-6, "total {total}");
}

/// Contact duration, plateau force and impulse of the bar against the continuum solution
/// (duration 2L/c, force E S v/c, impulse 2 m v with c = √(E/ρ)).
fn bar_continuum_checks(h: &NonsmoothHistory, dt: f64, tol: (f64, f64, f64)) {
    let (e, rho, s, len, v): (f64, f64, f64, f64, f64) = (210e9, 7800.0, 3.14e-4, 0.99, 0.1);
    let c = (e / rho).sqrt();
    let imp = h.impulses(0);
    let steps: Vec<usize> = (0..imp.len()).filter(|&k| imp[k] > 0.0).collect();
    let duration = (steps.last().unwrap() - steps.first().unwrap() + 1) as f64 * dt;
    let mut forces: Vec<f64> = steps.iter().map(|&k| imp[k] / dt).collect();
    forces.sort_by(f64::total_cmp);
    let plateau = forces[forces.len() / 2];
    let total: f64 = imp.iter().sum();
    let (d_ex, p_ex, i_ex) = (2.0 * len / c, e * s * v / c, 2.0 * rho * s * len * v);
    assert!(
        ((duration - d_ex) / d_ex).abs() < tol.0,
        "duration {duration} vs 2L/c = {d_ex}"
    );
    assert!(
        ((plateau - p_ex) / p_ex).abs() < tol.1,
        "plateau {plateau} vs ESv/c = {p_ex}"
    );
    assert!(
        ((total - i_ex) / i_ex).abs() < tol.2,
        "impulse {total} vs 2mv = {i_ex}"
    );
}

#[test]
fn impacting_bar_matches_the_continuum_solution() {
    let sys = siconos_bar(false);
    for (gamma, dt, tol) in [
        (1.0, 2e-6, (0.01, 1e-3, 0.06)),
        (0.5, 1e-6, (0.01, 1e-3, 0.015)),
    ] {
        let steps = (1.5e-3 / dt) as usize;
        let h = moreau_jean(&sys, &settings(dt, steps, gamma)).unwrap();
        bar_continuum_checks(&h, dt, tol);
    }
}

#[test]
fn carpenter_bar_matches_the_continuum_solution_below_its_limit() {
    for lumped in [false, true] {
        let sys = siconos_bar(lumped);
        let lim = stability_limits(&sys).unwrap();
        assert!(lim.thermal.is_infinite());
        let dt = 0.9 * lim.mechanical;
        let steps = (1.5e-3 / dt) as usize;
        let h = carpenter(&sys, &settings(dt, steps, 0.5)).unwrap();
        bar_continuum_checks(&h, dt, (0.02, 0.02, 0.03));
        assert!(h.lcp_residual.iter().all(|&r| r < 1e-12));
        // Carpenter enforces the gap at the end of each step: no penetration beyond round-off.
        assert!(h.max_penetration() < 1e-15, "{}", h.max_penetration());
    }
}

#[test]
fn carpenter_is_stable_below_and_unstable_above_its_limit() {
    // The bar without the wall (free flight; K, M of the bar), from a random-ish initial field.
    let mut sys = siconos_bar(false);
    sys.obstacles.clear();
    sys.v0 = (0..sys.n).map(|i| ((i * 7919) % 13) as f64 - 6.0).collect();
    // Rayleigh damping C = 1e-7 K: the centred damping leaves the limit at 2/ω_max.
    sys.damping = sys.stiffness.iter().map(|k| 1e-7 * k).collect();
    let lim = stability_limits(&sys).unwrap();
    let energy = |h: &NonsmoothHistory| {
        let n = sys.n;
        let t = h.len() - 1;
        quad(&sys.mass, &h.v[t * n..(t + 1) * n]) + quad(&sys.stiffness, &h.x[t * n..(t + 1) * n])
    };
    let e0 = quad(&sys.mass, &sys.v0);
    let stable = carpenter(&sys, &settings(0.98 * lim.mechanical, 2000, 0.5)).unwrap();
    assert!(energy(&stable) < 2.0 * e0, "{} vs {e0}", energy(&stable));
    let unstable = carpenter(&sys, &settings(1.02 * lim.mechanical, 2000, 0.5));
    match unstable {
        Ok(h) => assert!(energy(&h) > 1e6 * e0, "{}", energy(&h)),
        Err(e) => assert!(e.to_string().contains("not finite")),
    }
}

// ---------------------------------------------------------------------------------------------
// Closed forms
// ---------------------------------------------------------------------------------------------

#[test]
fn free_mass_against_a_wall_rebounds_at_minus_e_v() {
    let (mass, vel, d) = (2.0, 3.0, 0.0123);
    for gamma in [0.5, 0.75, 1.0] {
        for e in [0.0, 0.5, 1.0] {
            let mut sys = one_dof(mass, 0.0, 0.0);
            sys.x0[0] = d;
            sys.v0[0] = -vel;
            sys.obstacles
                .push(Obstacle::new("wall", vec![(0, 1.0)], 0.0, e));
            let dt = 1e-3;
            let h = moreau_jean(&sys, &settings(dt, 20, gamma)).unwrap();
            let k = h.impulse.iter().position(|&l| l > 0.0).unwrap();
            // One impulse m(1 + e)V, in the step whose predicted gap is the first ≤ 0.
            assert!((h.impulse[k] - mass * (1.0 + e) * vel).abs() < 1e-12);
            assert_eq!(h.impulse.iter().filter(|&&l| l > 0.0).count(), 1);
            let mid = |j: usize| h.x[j] + 0.5 * dt * h.v[j];
            assert!(mid(k - 1) <= 0.0 && mid(k - 2) > 0.0);
            assert!((h.v[k] - e * vel).abs() < 1e-12, "rebound {}", h.v[k]);
            // Penetration bound: the activation puts g_{k−1} + hV/2 in (0, hV], and the step moves
            // the mass by hV(γ(1 + e) − 1), so g_k ∈ (−hV(3/2 − γ(1 + e)), hV(γ(1 + e) − 1/2)];
            // for e = 0, (−hV(3/2 − γ), hV(γ − 1/2)]: penetration ≤ hV at γ = 1/2.
            let g = h.x[k];
            let shift = gamma * (1.0 + e);
            assert!(g > -dt * vel * (1.5 - shift) - 1e-15 && g <= dt * vel * (shift - 0.5) + 1e-15);
            // Energy: ½mV² lost for e = 0, ½m(1 − e²)V² in general (kinetic after = ½m e²V²).
            let last = h.energy.last().unwrap();
            assert!((last.kinetic - 0.5 * mass * e * e * vel * vel).abs() < 1e-12);
            assert!(last.residual.abs() < 1e-12);
            // Contact work: −½m(1 − e²)V² at γ = 1/2.
            if gamma == 0.5 {
                assert!((last.contact + 0.5 * mass * (1.0 - e * e) * vel * vel).abs() < 1e-12);
            }
        }
    }
}

#[test]
fn oscillator_single_impact_matches_the_closed_form() {
    // m ü + k u = 0, u(0) = 0, u̇(0) = V towards a wall at u = g0 (g = g0 − u).
    let (m, w0, vel) = (1.0, 2.0 * std::f64::consts::PI * 10.0, 1.0);
    let k = m * w0 * w0;
    let g0 = 0.6 * vel / w0;
    let t_star = (g0 * w0 / vel).asin() / w0;
    let v_star = (vel * vel - w0 * w0 * g0 * g0).sqrt();
    // Up to half a period after the impact: before the grazing return (e = 0) and the second
    // impact (e = 1, at t* + 2t* + π/ω₀).
    let t_end = t_star + std::f64::consts::PI / w0;
    for e in [0.0, 1.0] {
        let exact = |t: f64| {
            if t <= t_star {
                vel / w0 * (w0 * t).sin()
            } else {
                let s = t - t_star;
                g0 * (w0 * s).cos() - e * v_star / w0 * (w0 * s).sin()
            }
        };
        let mut errors = Vec::new();
        for dt in [1e-4, 3e-5, 1e-5, 3e-6, 1e-6] {
            let mut sys = one_dof(m, 0.0, k);
            sys.v0[0] = vel;
            sys.obstacles
                .push(Obstacle::new("wall", vec![(0, -1.0)], g0, e));
            let steps = (t_end / dt).round() as usize;
            let h = moreau_jean(&sys, &settings(dt, steps, 0.5)).unwrap();
            let first = h.impulse.iter().position(|&l| l > 0.0).unwrap();
            assert!(
                (h.time[first] - t_star).abs() <= 1.5 * dt,
                "impact at {}",
                h.time[first]
            );
            // Rebound velocity −e V* (the ODE's direction: u̇ = −e V*).
            assert!(
                (h.v[first] + e * v_star).abs() < 20.0 * dt * w0 * vel,
                "rebound {} vs {}",
                h.v[first],
                -e * v_star
            );
            let num: f64 = (0..h.len())
                .map(|i| (h.x[i] - exact(h.time[i])).abs())
                .sum();
            let den: f64 = (0..h.len()).map(|i| exact(h.time[i]).abs()).sum();
            // The impact is resolved to within a step: a time shift in [0, 2h) after the impact
            // (e = 1) or a penetration below hV (e = 0); either way |u − u_exact| < 2hV.
            let worst = (0..h.len())
                .map(|i| (h.x[i] - exact(h.time[i])).abs())
                .fold(0.0, f64::max);
            assert!(worst < 2.0 * dt * vel, "h = {dt}: max error {worst}");
            errors.push(num / den);
            // Energy after the impact: ½k g0² + ½m e²V*², at O(h).
            let last = h.energy.last().unwrap();
            let after = 0.5 * k * g0 * g0 + 0.5 * m * e * e * v_star * v_star;
            assert!(
                ((last.kinetic + last.strain) - after).abs() < 50.0 * dt * w0 * after,
                "energy {} vs {after}",
                last.kinetic + last.strain
            );
            assert!(h
                .energy
                .iter()
                .all(|t| t.residual.abs() < 1e-12 * (0.5 * m * vel * vel)));
        }
        println!("single impact, e = {e}: L1 errors at h = 1e-4 .. 1e-6: {errors:?}");
        assert!(errors[0] < 0.01 && errors[4] < 2e-4, "{errors:?}");
        if e == 0.0 {
            // First order per decade (for e = 1 the time shift's fraction of h varies with h,
            // so only the bound above holds step by step).
            assert!(errors[2] < errors[0] / 5.0, "e = {e}: {errors:?}");
            assert!(errors[4] < errors[2] / 5.0, "e = {e}: {errors:?}");
        }
    }
}

#[test]
fn energy_balance_closes_every_step_for_any_gamma() {
    // A damped, forced two-DOF chain with a wall under the second mass.
    for gamma in [0.5, 0.6, 1.0] {
        let k = [2000.0, -1000.0, -1000.0, 1000.0];
        let c: Vec<f64> = k.iter().map(|v| 1e-3 * v).collect();
        let mut sys = NonsmoothSystem::mechanical(vec![1.0, 0.0, 0.0, 0.5], c, k.to_vec());
        sys.omega = 20.0;
        sys.force[1] = Harmonic {
            mean: -2.0,
            cos: 0.0,
            sin: 30.0,
        };
        sys.obstacles
            .push(Obstacle::new("wall", vec![(1, 1.0)], 0.01, 0.3));
        let h = moreau_jean(&sys, &settings(1e-3, 5000, gamma)).unwrap();
        let scale = h
            .energy
            .iter()
            .map(|e| e.external.abs().max(e.kinetic + e.strain))
            .fold(0.0, f64::max);
        let worst = h
            .energy
            .iter()
            .map(|e| e.residual.abs())
            .fold(0.0, f64::max);
        assert!(
            worst < 1e-11 * scale,
            "γ = {gamma}: residual {worst} of {scale}"
        );
        assert!(h.impulse.iter().filter(|&&l| l > 0.0).count() > 50);
        // The θ-method dissipates (numerical ≥ 0); at γ = 1/2 the impacts do (contact work
        // λ(y_{n+1} + y_n)/2 = λ(1 − e)y_n/2 ≤ 0).
        let last = h.energy.last().unwrap();
        assert!(last.numerical >= -1e-12);
        if gamma == 0.5 {
            assert!(last.contact < 0.0);
        }
    }
}

#[test]
fn without_contact_gamma_half_conserves_energy() {
    let k = vec![2000.0, -1000.0, -1000.0, 1000.0];
    let mut sys = NonsmoothSystem::mechanical(vec![1.0, 0.0, 0.0, 0.5], vec![0.0; 4], k);
    sys.v0 = vec![1.0, -0.3];
    let e0 = 0.5 * (1.0 + 0.5 * 0.09);
    let h = moreau_jean(&sys, &settings(1e-2, 10000, 0.5)).unwrap();
    for e in &h.energy {
        assert!(((e.kinetic + e.strain) - e0).abs() < 1e-12 * e0);
    }
    let h = moreau_jean(&sys, &settings(1e-2, 1000, 0.7)).unwrap();
    for w in h.energy.windows(2) {
        assert!(w[1].kinetic + w[1].strain <= w[0].kinetic + w[0].strain + 1e-15);
    }
}

// ---------------------------------------------------------------------------------------------
// The forced one-DOF oscillator against a wall (the paper's simple model in one DOF) against an
// exact event-driven reference.
// ---------------------------------------------------------------------------------------------

/// m ü + c u̇ + k u = F sin Ωt, wall u ≤ g0, e = 0: closed-form free flight between events,
/// bisection on u = g0 for impacts (impulse m u̇⁻), persistent contact while
/// λ(t) = F sin Ωt − k g0 ≥ 0, release with zero velocity.
struct EventDriven {
    m: f64,
    c: f64,
    k: f64,
    f: f64,
    big_omega: f64,
    g0: f64,
    /// Free flights: (start time, u, v) with the flight valid until the next event.
    flights: Vec<(f64, f64, f64)>,
    /// Contact intervals [a, b].
    contacts: Vec<(f64, f64)>,
    /// Impacts (time, impulse).
    impacts: Vec<(f64, f64)>,
}

impl EventDriven {
    fn free(&self, (t0, u0, v0): (f64, f64, f64), t: f64) -> (f64, f64) {
        let (m, c, k, w) = (self.m, self.c, self.k, self.big_omega);
        let a11 = k - m * w * w;
        let det = a11 * a11 + (c * w) * (c * w);
        let (pa, pb) = (self.f * a11 / det, -self.f * c * w / det);
        let up = |t: f64| pa * (w * t).sin() + pb * (w * t).cos();
        let vp = |t: f64| w * (pa * (w * t).cos() - pb * (w * t).sin());
        let zw = c / (2.0 * m);
        let wd = (k / m - zw * zw).sqrt();
        let c1 = u0 - up(t0);
        let c2 = (v0 - vp(t0) + zw * c1) / wd;
        let s = t - t0;
        let ex = (-zw * s).exp();
        let (sn, cs) = (wd * s).sin_cos();
        let u = up(t) + ex * (c1 * cs + c2 * sn);
        let v = vp(t) + ex * (-zw * (c1 * cs + c2 * sn) + wd * (-c1 * sn + c2 * cs));
        (u, v)
    }

    fn build(m: f64, c: f64, k: f64, f: f64, big_omega: f64, g0: f64, t_end: f64) -> Self {
        let mut r = EventDriven {
            m,
            c,
            k,
            f,
            big_omega,
            g0,
            flights: Vec::new(),
            contacts: Vec::new(),
            impacts: Vec::new(),
        };
        let mut state = (0.0, 0.0, 0.0);
        let scan = 2e-7;
        let lam = |t: f64| f * (big_omega * t).sin() - k * g0;
        loop {
            r.flights.push(state);
            // Find the first t > t0 with u(t) > g0.
            let mut t = state.0;
            let hit = loop {
                let tn = t + scan;
                if tn > t_end {
                    break None;
                }
                if r.free(state, tn).0 > g0 {
                    break Some((t, tn));
                }
                t = tn;
            };
            let Some((mut a, mut b)) = hit else { break };
            for _ in 0..80 {
                let mid = 0.5 * (a + b);
                if r.free(state, mid).0 > g0 {
                    b = mid;
                } else {
                    a = mid;
                }
            }
            let ti = 0.5 * (a + b);
            let vi = r.free(state, ti).1;
            r.impacts.push((ti, m * vi));
            // Persistent contact while λ ≥ 0; else leave at once with zero velocity.
            let mut tl = ti;
            if lam(ti) >= 0.0 {
                // λ(t) = F sin Ωt − k g0 becomes negative where sin Ωt = k g0 / F, decreasing.
                let phase = (k * g0 / f).asin();
                let period = 2.0 * std::f64::consts::PI / big_omega;
                let base = (ti / period).floor() * period;
                let mut t_out = base + (std::f64::consts::PI - phase) / big_omega;
                while t_out < ti {
                    t_out += period;
                }
                tl = t_out.min(t_end);
                r.contacts.push((ti, tl));
            }
            if tl >= t_end {
                break;
            }
            state = (tl, g0, 0.0);
        }
        r
    }

    fn u(&self, t: f64) -> f64 {
        if self.contacts.iter().any(|&(a, b)| t >= a && t <= b) {
            return self.g0;
        }
        let fl = self
            .flights
            .iter()
            .rev()
            .find(|f| f.0 <= t)
            .copied()
            .unwrap();
        self.free(fl, t).0.min(self.g0)
    }

    /// Total contact impulse over (a, b] (N·s): persistent-contact force plus impacts.
    fn impulse(&self, a: f64, b: f64) -> f64 {
        let (f, w, kg) = (self.f, self.big_omega, self.k * self.g0);
        let mut total = 0.0;
        for &(ca, cb) in &self.contacts {
            let (lo, hi) = (ca.max(a), cb.min(b));
            if hi > lo {
                total += f / w * ((w * lo).cos() - (w * hi).cos()) - kg * (hi - lo);
            }
        }
        for &(ti, p) in &self.impacts {
            if ti > a && ti <= b {
                total += p;
            }
        }
        total
    }
}

fn forced_oscillator() -> (NonsmoothSystem, f64) {
    let m = 1.0;
    let w0 = 2.0 * std::f64::consts::PI * 1300.0;
    let k = m * w0 * w0;
    let mut sys = one_dof(m, 1e-5 * k, k);
    sys.omega = 2.0 * std::f64::consts::PI * 100.0 / 3.0;
    sys.force[0] = Harmonic {
        mean: 0.0,
        cos: 0.0,
        sin: 100.0,
    };
    let g0 = 100.0 / (2.0 * k);
    sys.obstacles
        .push(Obstacle::new("wall", vec![(0, -1.0)], g0, 0.0));
    (sys, g0)
}

/// L1 errors (paper eq. 19, trapezoid on the coarse grid) of u and of the contact force per step.
fn errors_against(reference: &EventDriven, h: &NonsmoothHistory, dt: f64) -> (f64, f64) {
    let n = h.len();
    let u_ref: Vec<f64> = h.time.iter().map(|&t| reference.u(t)).collect();
    let trap = |f: &dyn Fn(usize) -> f64| -> f64 {
        (0..n)
            .map(|i| {
                let w = if i == 0 || i == n - 1 { 0.5 } else { 1.0 };
                w * f(i)
            })
            .sum::<f64>()
    };
    let eu = trap(&|i| (h.x[i] - u_ref[i]).abs()) / trap(&|i| u_ref[i].abs());
    let f_ref: Vec<f64> = (0..n)
        .map(|i| {
            if i == 0 {
                0.0
            } else {
                reference.impulse(h.time[i - 1], h.time[i]) / dt
            }
        })
        .collect();
    let ef = trap(&|i| (h.impulse[i] / dt - f_ref[i]).abs()) / trap(&|i| f_ref[i].abs());
    (eu, ef)
}

#[test]
fn forced_oscillator_error_falls_at_first_order() {
    let (sys, g0) = forced_oscillator();
    let t_end = 0.1;
    let k = sys.stiffness[0];
    let reference = EventDriven::build(1.0, sys.damping[0], k, 100.0, sys.omega, g0, t_end);
    assert!(reference.impacts.len() >= 3 && !reference.contacts.is_empty());
    let mut errs = Vec::new();
    for dt in [1e-4, 1e-5, 1e-6] {
        let steps = (t_end / dt).round() as usize;
        let h = moreau_jean(&sys, &settings(dt, steps, 0.5)).unwrap();
        errs.push(errors_against(&reference, &h, dt));
    }
    println!("forced oscillator L1 errors (u, λ/h) at h = 1e-4, 1e-5, 1e-6: {errs:?}");
    // First order: ≥ 5× per decade of h on both (the expected order of a nonsmooth solution).
    for w in errs.windows(2) {
        assert!(w[1].0 < w[0].0 / 5.0, "{errs:?}");
        assert!(w[1].1 < w[0].1 / 5.0, "{errs:?}");
    }
    assert!(errs[2].0 < 1e-3 && errs[2].1 < 1e-2, "{errs:?}");
}

#[test]
fn carpenter_and_moreau_jean_agree_at_carpenters_step() {
    let (sys, g0) = forced_oscillator();
    let t_end = 0.05;
    let reference = EventDriven::build(
        1.0,
        sys.damping[0],
        sys.stiffness[0],
        100.0,
        sys.omega,
        g0,
        t_end,
    );
    let lim = stability_limits(&sys).unwrap();
    let dt = 1e-6;
    assert!(dt < lim.mechanical);
    let steps = (t_end / dt).round() as usize;
    let c = carpenter(&sys, &settings(dt, steps, 0.5)).unwrap();
    let mj = moreau_jean(&sys, &settings(dt, steps, 0.5)).unwrap();
    let (ec, fc) = errors_against(&reference, &c, dt);
    let (em, fm) = errors_against(&reference, &mj, dt);
    println!("h = 1e-6: carpenter (u {ec:.3e}, λ {fc:.3e}), moreau-jean (u {em:.3e}, λ {fm:.3e})");
    assert!(ec < 2e-3 && em < 2e-3 && fc < 2e-2 && fm < 2e-2);
    // The two agree to within their errors against the exact solution.
    let diff: f64 = (0..c.len()).map(|i| (c.x[i] - mj.x[i]).abs()).sum::<f64>()
        / (0..c.len()).map(|i| mj.x[i].abs()).sum::<f64>();
    assert!(diff < ec + em + 1e-12, "{diff}");
}

// ---------------------------------------------------------------------------------------------
// Thermo-mechanical coupling in persistent contact (closed form of the discrete scheme).
// ---------------------------------------------------------------------------------------------

/// m ü + c_u u̇ + k u + k_uθ θ = F − λ, c_θ θ̇ + κ θ = α λ, wall g = −u ≥ 0. In persistent
/// contact the heat rows are the θ-method for c_θ θ̇ + κ_eff θ = α(F − k u₀),
/// κ_eff = κ + α k_uθ, and λ/h = F − k u₀ − k_uθ θ_{n+γ}.
fn coupled(k_ut: f64) -> NonsmoothSystem {
    let (m, k, cu, ct, kappa, alpha, f) = (1.0, 1000.0, 0.01, 1.0, 0.5, 0.1, 10.0);
    let mut sys = NonsmoothSystem {
        n: 2,
        n_mech: 1,
        mass: vec![m, 0.0, 0.0, 0.0],
        damping: vec![cu, 0.0, 0.0, ct],
        stiffness: vec![k, k_ut, 0.0, kappa],
        force: vec![Harmonic::constant(f), Harmonic::default()],
        omega: 0.0,
        obstacles: Vec::new(),
        dof_names: vec!["u".into(), "theta".into()],
        x0: vec![1e-9, 0.0],
        v0: vec![0.0, 0.0],
        heat_weights: Vec::new(),
    };
    let mut o = Obstacle::new("wall", vec![(0, -1.0)], 0.0, 0.0);
    o.heating = alpha;
    o.heated = vec![(1, 1.0)];
    sys.obstacles.push(o);
    sys
}

#[test]
fn coupled_persistent_contact_matches_the_discrete_closed_form() {
    for (k_ut, expected) in [(-2.0, 3.3250704939), (-10.0, 44050.936362)] {
        let sys = coupled(k_ut);
        let (k, f, ct, kappa, alpha, u0) = (1000.0, 10.0, 1.0, 0.5, 0.1, 1e-9);
        let dt = 1e-3;
        let gamma = 0.5;
        let h = moreau_jean(&sys, &settings(dt, 20000, gamma)).unwrap();
        let k_eff = kappa + alpha * k_ut;
        let mut theta = 0.0_f64;
        let mut worst = 0.0_f64;
        let mut worst_force = 0.0_f64;
        for step in 1..h.len() {
            let next = ((ct - (1.0 - gamma) * dt * k_eff) * theta + dt * alpha * (f - k * u0))
                / (ct + gamma * dt * k_eff);
            let force = f - k * u0 - k_ut * (theta + gamma * (next - theta));
            theta = next;
            worst = worst.max((h.x[step * 2 + 1] - theta).abs() / theta.abs());
            worst_force = worst_force.max((h.impulse[step] / dt - force).abs() / force.abs());
            assert!(
                (h.x[step * 2] - u0).abs() < 1e-6 * u0,
                "u = {}",
                h.x[step * 2]
            );
        }
        assert!(worst < 1e-10, "θ relative error {worst}");
        assert!(worst_force < 1e-10, "λ/h relative error {worst_force}");
        let last = h.x[(h.len() - 1) * 2 + 1];
        assert!(
            (last - expected).abs() < 1e-9 * expected.abs(),
            "θ(20 s) = {last}"
        );
        // The heat balance closes: stored = α Σλ − conducted.
        let q = h.heat.last().unwrap();
        assert!(q.residual.abs() < 1e-10 * q.frictional.abs(), "{q:?}");
    }
}

#[test]
fn moreau_jean_does_not_depend_on_the_initial_temperature_rate() {
    let sys = coupled(-2.0);
    let a = moreau_jean(&sys, &settings(1e-3, 500, 0.5)).unwrap();
    let mut other = sys.clone();
    other.v0[1] = 37.0;
    let b = moreau_jean(&other, &settings(1e-3, 500, 0.5)).unwrap();
    for (x, y) in a.x.iter().zip(&b.x) {
        assert!((x - y).abs() <= 1e-13 * x.abs().max(1e-9));
    }
}

// ---------------------------------------------------------------------------------------------
// Bad input
// ---------------------------------------------------------------------------------------------

#[test]
fn bad_step_and_gamma_are_errors_naming_the_key() {
    let (sys, _) = forced_oscillator();
    let e = moreau_jean(&sys, &settings(0.0, 10, 0.5)).unwrap_err();
    assert!(e.to_string().contains("march.time_step_s"), "{e}");
    for gamma in [0.4, 1.01, f64::NAN] {
        let e = moreau_jean(&sys, &settings(1e-5, 10, gamma)).unwrap_err();
        assert!(e.to_string().contains("march.gamma"), "γ = {gamma}: {e}");
    }
    let mut s = settings(1e-5, 10, 0.5);
    s.gamma_thermal = 1.2;
    let e = moreau_jean(&sys, &s).unwrap_err();
    assert!(e.to_string().contains("march.gamma_thermal"), "{e}");
    let e = carpenter(&sys, &settings(-1e-5, 10, 0.5)).unwrap_err();
    assert!(e.to_string().contains("march.time_step_s"), "{e}");
}

// ---------------------------------------------------------------------------------------------
// The command line on the bundled case
// ---------------------------------------------------------------------------------------------

#[test]
fn nlrom_march_runs_both_nonsmooth_schemes_on_the_bundled_wall_case() {
    let case = std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/oscillator_wall.toml"
    ));
    let dir = std::env::temp_dir().join(format!("nlrom_wall_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mj_out = dir.join("mj.h5");
    let r = json_report("march", case, &mj_out, &[]);
    assert_eq!(r["scheme"], "moreau-jean");
    assert_eq!(r["steps"], 9000);
    assert!(r["steps_with_impulse"].as_u64().unwrap() > 100);
    assert!(r["max_energy_residual_j"].as_f64().unwrap() < 1e-12);
    let c_out = dir.join("c.h5");
    let rc = json_report("march", case, &c_out, &["--scheme", "carpenter"]);
    assert_eq!(rc["scheme"], "carpenter");
    // 2/ω = 2/(2π·1300) = 2.449e-4 s.
    let limit = rc["stability_limit_s"].as_f64().unwrap();
    assert!((limit - 2.0 / (2.0 * std::f64::consts::PI * 1300.0)).abs() < 1e-9 * limit);
    let a = nlrom::output::read_results(&mj_out).unwrap().march.unwrap();
    let b = nlrom::output::read_results(&c_out).unwrap().march.unwrap();
    assert_eq!(a.time.len(), 9001);
    assert_eq!(a.element_names, ["wall"]);
    // The two schemes agree on the displacement to within their O(h) errors (h = 1e-5 s).
    let num: f64 = a
        .response
        .iter()
        .zip(&b.response)
        .map(|(x, y)| (x - y).abs())
        .sum();
    let den: f64 = a.response.iter().map(|x| x.abs()).sum();
    assert!(num / den < 0.02, "{}", num / den);
    // The mean contact force over the run: the same to within a few per cent.
    let fa: f64 = a.contact_force.iter().skip(1).step_by(2).sum();
    let fb: f64 = b.contact_force.iter().skip(1).step_by(2).sum();
    assert!((fa - fb).abs() < 0.05 * fa, "{fa} vs {fb}");
    // An obstacle case marched by a smooth scheme is refused, naming the key.
    let res = nlrom(&[
        "march",
        case.to_str().unwrap(),
        "-o",
        dir.join("x.h5").to_str().unwrap(),
        "--scheme",
        "newmark",
    ]);
    assert_eq!(res.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&res.stderr).contains("obstacle"));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn bad_obstacle_and_gamma_keys_are_reported_with_their_path() {
    let dir = std::env::temp_dir().join(format!("nlrom_wall_bad_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let base = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/oscillator_wall.toml"
    ))
    .unwrap()
    .replace(
        "\"wall/",
        &format!("\"{}/cases/wall/", env!("CARGO_MANIFEST_DIR")),
    );
    for (from, to, key) in [
        ("gamma = 0.5", "gamma = 0.4", "march.gamma"),
        ("gamma = 0.5", "gamma = 1.2", "march.gamma"),
        (
            "time_step_s = 1e-5",
            "time_step_s = 0.0",
            "march.time_step_s",
        ),
        (
            "time_step_s = 1e-5",
            "time_step_s = -1e-5",
            "march.time_step_s",
        ),
        (
            "restitution = 0.0",
            "restitution = 1.5",
            "obstacle[0].restitution",
        ),
        (
            "weights = [-1.0] }",
            "weights = [-1.0, 2.0] }",
            "obstacle[0].normal.weights",
        ),
        (
            "dofs = [0], weights = [-1.0]",
            "dofs = [3], weights = [-1.0]",
            "obstacle[0].normal.dofs",
        ),
        (
            "restitution = 0.0",
            "restitution = 0.0\nmu = 0.2",
            "obstacle[0].mu",
        ),
    ] {
        let path = dir.join("bad.toml");
        std::fs::write(&path, base.replace(from, to)).unwrap();
        let res = nlrom(&[
            "march",
            path.to_str().unwrap(),
            "-o",
            dir.join("bad.h5").to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&res.stderr);
        assert_eq!(res.status.code(), Some(2), "{to}: {err}");
        assert!(err.contains(key), "{to}: {err}");
    }
    std::fs::remove_dir_all(&dir).ok();
}

// ---------------------------------------------------------------------------------------------
// A thermoelastic FE bar (fe::thermal) against a wall with frictional heating
// ---------------------------------------------------------------------------------------------

#[test]
fn thermoelastic_fe_bar_hitting_a_wall_closes_its_energy_and_heat_balances() {
    use nlrom::fe::structured::StructuredBox;
    use nlrom::fe::thermal::{assemble_thermal, Capacity, ThermalMaterial};
    use nlrom::fe::{assemble, Material, Materials, Quadrature};
    use nlrom::mesh::ElementType;
    let size = [0.05, 0.01, 0.01];
    let mesh = StructuredBox::new(ElementType::Hexa8, [4, 1, 1], size)
        .build()
        .unwrap();
    let mat = Material {
        young: 110e9,
        poisson: 0.3,
        density: 4430.0,
    };
    let th = ThermalMaterial {
        conductivity: 6.7,
        specific_heat: 520.0,
        expansion: 9e-6,
        capacity: Capacity::Consistent,
    };
    let quad = Quadrature::default();
    let mech = assemble(&mesh, &Materials::uniform(mat), &quad).unwrap();
    let therm = assemble_thermal(&mesh, &Materials::uniform(mat), &th, &quad).unwrap();
    let nodes = mesh.coords.len();
    // Mechanical DOF: every node off the clamped face x = 0; thermal DOF: every node (insulated).
    let free: Vec<usize> = (0..3 * nodes)
        .filter(|&p| mesh.coords[p / 3][0] > 1e-12)
        .collect();
    let (nu, nt) = (free.len(), nodes);
    let n = nu + nt;
    let (k, m) = (mech.k.to_dense(), mech.m.to_dense());
    let (kt, ct, ku) = (
        therm.conductance.to_dense(),
        therm.capacity.to_dense(),
        therm.coupling.to_dense(),
    );
    let mut kk = vec![0.0; n * n];
    let mut mm = vec![0.0; n * n];
    let mut cc = vec![0.0; n * n];
    for (i, &p) in free.iter().enumerate() {
        for (j, &q) in free.iter().enumerate() {
            kk[i * n + j] = k[(p, q)];
            mm[i * n + j] = m[(p, q)];
            cc[i * n + j] = 1e-6 * k[(p, q)];
        }
        for b in 0..nt {
            kk[i * n + nu + b] = ku[(p, b)];
        }
    }
    for a in 0..nt {
        for b in 0..nt {
            kk[(nu + a) * n + nu + b] = kt[(a, b)];
            cc[(nu + a) * n + nu + b] = ct[(a, b)];
        }
    }
    let mut sys = NonsmoothSystem {
        n,
        n_mech: nu,
        mass: mm,
        damping: cc,
        stiffness: kk,
        force: vec![Harmonic::default(); n],
        omega: 2.0 * std::f64::consts::PI * 2000.0,
        obstacles: Vec::new(),
        dof_names: (0..n).map(|i| format!("dof {i}")).collect(),
        x0: vec![0.0; n],
        v0: vec![0.0; n],
        heat_weights: Vec::new(),
    };
    // The four tip nodes pushed along +x by 200 N at 2 kHz against a wall 0.1 µm away, with
    // friction along +y (μ = 0.15) and the frictional heat α λ into each tip node.
    let alpha = 0.1;
    for (node, x) in mesh.coords.iter().enumerate() {
        if (x[0] - size[0]).abs() < 1e-12 {
            let ux = free.iter().position(|&p| p == 3 * node).unwrap();
            let uy = free.iter().position(|&p| p == 3 * node + 1).unwrap();
            sys.force[ux] = Harmonic {
                mean: 0.0,
                cos: 0.0,
                sin: 200.0,
            };
            let mut o = Obstacle::new(&format!("tip {node}"), vec![(ux, -1.0)], 1e-7, 0.0);
            o.mu = 0.15;
            o.tangential = vec![(uy, 1.0)];
            o.heating = alpha;
            o.heated = vec![(nu + node, 1.0)];
            sys.obstacles.push(o);
        }
    }
    assert_eq!(sys.obstacles.len(), 4);
    let h = moreau_jean(&sys, &settings(1e-6, 1000, 0.5)).unwrap();
    let total_impulse: f64 = h.impulse.iter().sum();
    assert!(total_impulse > 0.0 && h.impulse.iter().all(|&l| l >= 0.0));
    // Energy balance every step (friction and heat included in the terms).
    let scale = h
        .energy
        .iter()
        .map(|e| e.external.abs().max(e.kinetic + e.strain))
        .fold(0.0, f64::max);
    let worst = h
        .energy
        .iter()
        .map(|e| e.residual.abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-10 * scale, "energy residual {worst} of {scale}");
    // Insulated body: the stored heat equals α Σλ (K^θθ 1 = 0), and the capacity-weighted mean
    // temperature rise is α Σλ / (ρ c_p V).
    let q = h.heat.last().unwrap();
    assert!((q.frictional - alpha * total_impulse).abs() < 1e-12 * q.frictional);
    assert!(
        (q.stored - q.frictional).abs() < 1e-9 * q.frictional,
        "{q:?}"
    );
    let theta = &h.x_final[nu..];
    let c1: Vec<f64> = (0..nt).map(|a| (0..nt).map(|b| ct[(a, b)]).sum()).collect();
    let mean = c1.iter().zip(theta).map(|(c, t)| c * t).sum::<f64>() / c1.iter().sum::<f64>();
    let volume: f64 = size.iter().product();
    let expected = alpha * total_impulse / (mat.density * th.specific_heat * volume);
    assert!(
        (mean - expected).abs() < 1e-9 * expected,
        "{mean} vs {expected}"
    );
}

#[test]
fn sparse_rows_products_equal_the_dense_products() {
    // SparseRows::row_dot (consecutive columns as a slice dot product, scattered ones gathered,
    // both with partial sums) against the plain row-major product, on rows of every length
    // 0–13 with consecutive, scattered and empty patterns.
    use nlrom::march::obstacle::SparseRows;
    let (rows, n) = (42, 17);
    let mut a = vec![0.0; rows * n];
    for r in 0..rows {
        let len = r % 14;
        for k in 0..len {
            // Even rows: a consecutive block; odd rows: every other column (mod 17) from the end.
            let c = if r % 2 == 0 {
                (r / 2) % (n - len + 1) + k
            } else {
                (3 * n - 1 - 2 * k) % n
            };
            a[r * n + c] = 0.5 + ((r * n + c) as f64 * 0.37) % 5.3;
        }
    }
    let x: Vec<f64> = (0..n).map(|i| (0.7 * i as f64).sin() + 0.1).collect();
    let s = SparseRows::new(&a, n, 0..rows, 0..n);
    let y = s.mul(&x);
    for r in 0..rows {
        let exact: f64 = (0..n).map(|c| a[r * n + c] * x[c]).sum();
        let scale: f64 = (0..n)
            .map(|c| (a[r * n + c] * x[c]).abs())
            .sum::<f64>()
            .max(1.0);
        assert!(
            (y[r] - exact).abs() < 1e-14 * scale,
            "row {r}: {} vs {exact}",
            y[r]
        );
    }
    let z: Vec<f64> = (0..rows.min(n)).map(|i| x[i] - 0.3).collect();
    let sq = SparseRows::new(&a, n, 0..n, 0..n);
    let quad: f64 = (0..n)
        .map(|r| z[r] * (0..n).map(|c| a[r * n + c] * z[c]).sum::<f64>())
        .sum();
    assert!((sq.quad(&z) - quad).abs() < 1e-13 * quad.abs().max(1.0));
}
