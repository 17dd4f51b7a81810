//! The exact single-harmonic point law (`nlrom::contact::microslip`, Cigeroglu, An & Menq 2007)
//! against independent references: the time-discrete law of `nlrom::contact::law` marched over
//! N_t samples by the AFT element (harmonics, energy and every sample's state, with the error
//! falling as 1/N_t), the Jenkins closed forms, the gross-slip energy, complete stick, the closed
//! energy forms for normal motion in phase and in anti-phase with the tangential motion
//! (`docs/theory.md`), and central differences of the Jacobian and ∂/∂n0 in every regime.

use std::f64::consts::PI;

use nlrom::case::Evaluation;
use nlrom::contact::aft::Aft;
use nlrom::contact::element::{evaluate, evaluate_as, LocalElement, Workspace};
use nlrom::contact::law::{ContactParams, Regime, Variant};
use nlrom::contact::microslip::{self, CycleRegime, PhaseKind};
use nlrom::harmonics::HarmonicLayout;

fn params(kt: f64, kn: f64, mu: f64, n0: f64) -> ContactParams {
    ContactParams::new(kt, kn, mu, n0, "test").unwrap()
}

/// The paper's parametrisation (eq. 18): u = a sin τ, v = b sin(τ + φ), with the dimensionless
/// b̄ = μ k_n b/(k_t a), n̄0 = μ n0/(k_t a); k_t = 2, k_n = 5, μ = 0.4, a = 0.7. Returns the
/// parameters and (U, V) in nlrom's layout (X0, Re X1, Im X1).
fn paper_case(n0bar: f64, bbar: f64, phi: f64) -> (ContactParams, [f64; 3], [f64; 3]) {
    let (kt, kn, mu, a) = (2.0, 5.0, 0.4, 0.7);
    let b = bbar * kt * a / (mu * kn);
    let n0 = n0bar * kt * a / mu;
    // a sin τ = X1 cos τ − X2 sin τ with X1 = 0, X2 = −a; b sin(τ + φ) = b sin φ cos τ + b cos φ sin τ.
    (
        params(kt, kn, mu, n0),
        [0.0, 0.0, -a],
        [0.0, b * phi.sin(), -b * phi.cos()],
    )
}

fn element(p: ContactParams) -> LocalElement {
    LocalElement {
        params: p,
        variant: Variant::OneD,
        tangential: 1,
        normal: true,
    }
}

/// The AFT element (time-discrete law) at N_t samples: (forces [F; N], energy Σ f Δw, loop).
fn discrete(
    p: ContactParams,
    u: [f64; 3],
    v: [f64; 3],
    n_t: usize,
) -> (Vec<f64>, f64, nlrom::contact::element::HysteresisLoop) {
    let aft = Aft::new(HarmonicLayout::new(1, n_t).unwrap()).unwrap();
    let mut ws = Workspace::new(&aft);
    let x = [u, v].concat();
    let mut f = vec![0.0; 6];
    let mut w = [0.0; 2];
    evaluate(&element(p), &aft, &x, &mut w, &mut f, false, &mut ws).unwrap();
    // Once more from the periodic state (the forces of a periodic period).
    evaluate(&element(p), &aft, &x, &mut w, &mut f, false, &mut ws).unwrap();
    (f, ws.report().dissipated_energy, ws.hysteresis())
}

/// The grid of the acceptance check: n̄0 × b̄ × φ.
fn grid() -> Vec<(f64, f64, f64)> {
    let mut out = Vec::new();
    for n0bar in [-0.3, 0.0, 0.2, 0.5, 0.8, 1.2, 2.5] {
        for bbar in [0.0, 0.3, 0.8, 1.5] {
            for phi in [0.0, 0.7, PI / 2.0, 2.0, PI, 4.0, 5.5] {
                out.push((n0bar, bbar, phi));
            }
        }
    }
    out
}

/// Analytic harmonics and energy against the time-discrete law at N_t = 8192 on the whole grid
/// (196 cases, at least 150 not stuck): harmonic coefficients within 2e-4·k_t·a, energy within
/// 2e-3·k_t·a², normal-force harmonics within 1e-6·k_t·a; the largest error at N_t = 2048 is
/// 3 to 6 times that at 8192 (first order in 1/N_t).
#[test]
fn analytic_equals_time_discrete_law_to_first_order_in_samples() {
    let (kt, a) = (2.0, 0.7);
    let mut not_stuck = 0;
    let mut worst = [0.0f64; 2];
    let mut worst_energy = 0.0f64;
    let mut worst_normal = 0.0f64;
    for (n0bar, bbar, phi) in grid() {
        let (p, u, v) = paper_case(n0bar, bbar, phi);
        let r = microslip::evaluate(&p, u, v, 0.0, false).unwrap();
        if r.cycle.regime != CycleRegime::CompleteStick {
            not_stuck += 1;
        }
        for (k, n_t) in [2048, 8192].into_iter().enumerate() {
            let (f, energy, _) = discrete(p, u, v, n_t);
            let label = format!("n̄0 = {n0bar}, b̄ = {bbar}, φ = {phi}, N_t = {n_t}");
            for c in 0..3 {
                let e = (f[c] - r.friction[c]).abs() / (kt * a);
                worst[k] = worst[k].max(e);
                if n_t == 8192 {
                    assert!(
                        e < 2e-4,
                        "{label}: F[{c}] analytic {} vs discrete {}",
                        r.friction[c],
                        f[c]
                    );
                    let en = (f[3 + c] - r.normal[c]).abs() / (kt * a);
                    worst_normal = worst_normal.max(en);
                    assert!(
                        en < 1e-6,
                        "{label}: N[{c}] analytic {} vs discrete {}",
                        r.normal[c],
                        f[3 + c]
                    );
                }
            }
            if n_t == 8192 {
                let e = (energy - r.energy).abs() / (kt * a * a);
                worst_energy = worst_energy.max(e);
                assert!(
                    e < 2e-3,
                    "{label}: W analytic {} vs discrete {energy}",
                    r.energy
                );
            }
        }
    }
    assert!(not_stuck >= 150, "{not_stuck} non-stuck cases");
    let ratio = worst[0] / worst[1];
    assert!(
        (3.0..6.0).contains(&ratio),
        "largest error {:.3e} at 2048, {:.3e} at 8192: ratio {ratio}",
        worst[0],
        worst[1]
    );
    eprintln!(
        "{not_stuck} non-stuck cases; largest harmonic error/(k_t a): {:.3e} (N_t = 2048), {:.3e} (8192); energy/(k_t a²) {worst_energy:.3e}; normal {worst_normal:.3e}",
        worst[0], worst[1]
    );
}

/// At every sample of the discrete march the state (stick, ±slip, separation) equals the
/// analytic state, except within one sample of an analytic transition angle (and at the one
/// instant where a grazing contact's normal force touches 0).
#[test]
fn discrete_transitions_lie_within_one_sample_of_the_angles() {
    let n_t = 8192;
    let dt = 2.0 * PI / n_t as f64;
    let mut transitions = 0;
    for (n0bar, bbar, phi) in grid() {
        let (p, u, v) = paper_case(n0bar, bbar, phi);
        let r = microslip::evaluate(&p, u, v, 0.0, false).unwrap();
        let angles: Vec<f64> = r.cycle.transitions().iter().map(|t| t.0).collect();
        transitions += angles.len();
        let (_, _, lp) = discrete(p, u, v, n_t);
        for j in 0..n_t {
            let t = j as f64 * dt;
            let (_, _, _, kind) = microslip::state_at(&p, u, v, &r.cycle, t);
            let discrete = match lp.regime[j][0] {
                Regime::Stick => 0,
                Regime::Separation => 2,
                Regime::Slip => lp.ft[0][j].signum() as i8,
            };
            // Grazing (n̄0 = ±b̄): n touches 0 at one instant, which the discrete law may sample
            // as a separation or as contact.
            let n_raw = p.n0 + p.kn * (v[0] + v[1] * t.cos() - v[2] * t.sin());
            if kind.code() == discrete || n_raw.abs() <= 1e-12 * p.n0.abs().max(1.0) {
                continue;
            }
            let near = angles.iter().any(|&a| {
                let d = (a - t).rem_euclid(2.0 * PI);
                d.min(2.0 * PI - d) <= 1.0 * dt + 1e-12
            });
            assert!(
                near,
                "n̄0 = {n0bar}, b̄ = {bbar}, φ = {phi}: sample {j} (τ = {t}) discrete {discrete}, analytic {} ({:?}); angles {angles:?}",
                kind.code(),
                kind
            );
        }
    }
    assert!(transitions > 400, "{transitions} transitions checked");
}

/// b̄ = 0 (Jenkins): the closed forms of `docs/theory.md` (k_t = 1, μ n0 = 0.3, A = 1:
/// Re F1 = 0.2523158, Im F1 = 0.2673803, W = 0.84 = 4 μ n0 (A − μ n0/k_t)) to round-off, and the
/// gross-slip energy 4 μ N (A − μ N/k_t) over a range of amplitudes; complete stick below
/// μ N/k_t: F = k_t U, W = 0.
#[test]
fn jenkins_gross_slip_and_stick_closed_forms() {
    let p = params(1.0, 0.0, 0.3, 1.0);
    let r = microslip::evaluate(&p, [0.0, 1.0, 0.0], [0.0; 3], 0.0, false).unwrap();
    let beta = (1.0f64 - 2.0 * 0.3).acos();
    let fs = (beta - 0.5 * (2.0 * beta).sin()) / PI;
    let fc = 4.0 / PI * 0.3 * 0.7;
    assert!((r.friction[1] - fs).abs() < 1e-14, "{:?}", r.friction);
    assert!((r.friction[2] - fc).abs() < 1e-14, "{:?}", r.friction);
    assert!((r.friction[1] - 0.2523158).abs() < 1e-7);
    assert!((r.friction[2] - 0.2673803).abs() < 1e-7);
    assert!((r.energy - 0.84).abs() < 1e-14);
    assert!(r.friction[0].abs() < 1e-15);
    assert_eq!(r.cycle.regime, CycleRegime::StickSlip);
    for (kt, mu, n, amp, phase) in [
        (3.0, 0.2, 5.0, 0.4, 0.3),
        (1e6, 0.5, 200.0, 2e-4, 2.0),
        (10.0, 0.1, 1.0, 0.0101, -1.0),
    ] {
        let p = params(kt, 7.0, mu, n);
        let u = [0.25 * amp, amp * f64::cos(phase), amp * f64::sin(phase)];
        let r = microslip::evaluate(&p, u, [0.0; 3], 0.0, true).unwrap();
        let want = 4.0 * mu * n * (amp - mu * n / kt);
        assert!(
            (r.energy - want).abs() < 1e-12 * want.abs().max(mu * n * amp),
            "W = {} vs 4μN(A − μN/k) = {want}",
            r.energy
        );
        // Complete stick: the amplitude below μN/k_t, slider 0 admissible.
        let small = 0.9 * mu * n / kt;
        let us = [0.0, small * phase.cos(), small * phase.sin()];
        let r = microslip::evaluate(&p, us, [0.0; 3], 0.0, true).unwrap();
        assert_eq!(r.cycle.regime, CycleRegime::CompleteStick);
        assert!(r.energy.abs() < 1e-15 * kt * small * small);
        for (f, x) in r.friction.iter().zip(&us) {
            assert!((f - kt * x).abs() < 1e-12 * kt * small);
        }
        let j = r.friction_jacobian.unwrap();
        for (k, row) in j.iter().enumerate() {
            for (x, value) in row.iter().enumerate() {
                let want = if x == k { kt } else { 0.0 };
                assert!((value - want).abs() < 1e-12 * kt, "∂F{k}/∂x{x} = {value}");
            }
        }
    }
}

/// φ = 0 and φ = π: the energy per cycle in closed form (`docs/theory.md`, "Exact
/// single-harmonic evaluation") over b̄ ∈ {0.1, 0.3, 0.6, 0.9}, n̄0 ∈ [−0.2, 1.1], to 1e-12·k_t a².
#[test]
fn in_phase_normal_motion_energy_closed_forms() {
    let (kt, a) = (2.0, 0.7);
    let mut checked = 0;
    for bbar in [0.1, 0.3, 0.6, 0.9] {
        for i in 0..=26 {
            let n0bar = -0.2 + 0.05 * i as f64;
            let want = if n0bar <= -bbar {
                0.0
            } else if n0bar < bbar {
                kt * a * a * (1.0 - bbar) * (bbar + n0bar).powi(2) / (bbar * (1.0 + bbar))
            } else if n0bar < 1.0 {
                kt * a * a * 4.0 * (1.0 - n0bar) * (n0bar - bbar * bbar) / (1.0 - bbar * bbar)
            } else {
                0.0
            };
            for phi in [0.0, PI] {
                let (p, u, v) = paper_case(n0bar, bbar, phi);
                let r = microslip::evaluate(&p, u, v, 0.0, false).unwrap();
                assert!(
                    (r.energy - want).abs() < 1e-12 * kt * a * a,
                    "b̄ = {bbar}, n̄0 = {n0bar}, φ = {phi}: W = {} vs {want}",
                    r.energy
                );
                checked += 1;
            }
        }
    }
    assert_eq!(checked, 4 * 27 * 2);
}

/// The paper's regimes (§2.2, with the corrected no-separation bound n̄0 ≥ b̄ of eq. 20): complete
/// stick iff 2 n̄0 > ℓ1 + ℓ2 (eq. 19), separation iff −b̄ < n̄0 < b̄; and the transition angles
/// of eqs 21–26 (paper form, 0 < φ < π or π < φ < 2π) equal the analytic cycle's to 1e-12 after
/// the phase shift θ = τ + θ_u.
#[test]
fn regimes_and_transition_angles_match_the_paper_formulas() {
    let mut compared = 0;
    for (n0bar, bbar, phi) in grid() {
        let (p, u, v) = paper_case(n0bar, bbar, phi);
        let r = microslip::evaluate(&p, u, v, 0.0, false).unwrap();
        let l1 = (1.0 + bbar * bbar - 2.0 * bbar * phi.cos()).sqrt();
        let l2 = (1.0 + bbar * bbar + 2.0 * bbar * phi.cos()).sqrt();
        if (n0bar + bbar).abs() < 1e-12 {
            continue; // the boundary n̄0 = −b̄: contact at a single instant
        }
        let want = if n0bar + bbar <= 0.0 {
            CycleRegime::AlwaysSeparated
        } else if n0bar < bbar {
            CycleRegime::Separation
        } else if 2.0 * n0bar > l1 + l2 {
            CycleRegime::CompleteStick
        } else {
            CycleRegime::StickSlip
        };
        assert_eq!(r.cycle.regime, want, "n̄0 = {n0bar}, b̄ = {bbar}, φ = {phi}");
        // u = a sin τ here, so θ = τ (θ_u = 0).
        let s = phi.sin();
        if bbar == 0.0 || s.abs() < 1e-9 || want == CycleRegime::CompleteStick {
            continue;
        }
        let psi = if s > 0.0 { 0.0 } else { PI };
        let at1 = ((1.0 - bbar * phi.cos()) / (bbar * s)).atan();
        let at2 = ((1.0 + bbar * phi.cos()) / (bbar * s)).atan();
        let mut paper: Vec<(&str, f64)> = vec![("P", PI - psi - at1), ("N", PI - psi + at2)];
        if want == CycleRegime::StickSlip {
            paper.push(("StP", psi + ((l2 - 2.0 * n0bar) / l1).acos() - at1));
            paper.push(("StN", psi + ((l1 - 2.0 * n0bar) / l2).acos() + at2));
        }
        if want == CycleRegime::Separation {
            paper.push(("Sp1", PI + (n0bar / bbar).asin() - phi));
            paper.push(("Sp2", -(n0bar / bbar).asin() - phi));
        }
        let ours = r.cycle.transitions();
        for (name, angle) in paper {
            let Some(found) = ours.iter().find(|t| t.1 == name) else {
                // P or N need not occur with separation (a slip may end in separation).
                assert!(
                    want == CycleRegime::Separation && (name == "P" || name == "N"),
                    "n̄0 = {n0bar}, b̄ = {bbar}, φ = {phi}: no {name} in {ours:?}"
                );
                continue;
            };
            let d = (found.0 - angle).rem_euclid(2.0 * PI);
            assert!(
                d.min(2.0 * PI - d) < 1e-12,
                "n̄0 = {n0bar}, b̄ = {bbar}, φ = {phi}: θ_{name} paper {angle}, ours {}",
                found.0
            );
            compared += 1;
        }
    }
    assert!(compared > 100, "{compared} angles compared");
}

/// The Jacobian ∂(F, N)/∂(U, V, n0) against central differences (relative step 1e-6 of the
/// input scale) to 1e-6 of its largest entry, in complete stick (kept slider), stick–slip,
/// separation with re-contact in stick and in ±slip, and near grazing.
#[test]
fn jacobian_and_preload_derivative_match_central_differences() {
    let cases = [
        ("complete stick", 2.5, 0.3, 0.7),
        ("stick-slip", 0.5, 0.3, 2.0),
        ("stick-slip, in phase", 0.5, 0.3, 0.0),
        ("jenkins", 0.3, 0.0, 0.0),
        ("separation", 0.2, 0.8, 0.7),
        ("separation, anti-phase", 0.2, 0.8, PI),
        ("separation, re-contact in stick", 0.5, 1.5, 2.0),
        ("separation, gap", -0.3, 1.5, 4.0),
        ("near grazing", 0.79, 0.8, 5.5),
    ];
    let mut regimes = std::collections::BTreeSet::new();
    for (label, n0bar, bbar, phi) in cases {
        let (p, u, v) = paper_case(n0bar, bbar, phi);
        // Mean parts, so that the static columns are exercised.
        let u = [0.05, u[1] + 0.01, u[2]];
        let v = [0.02 * v[1].abs().max(0.1), v[1], v[2]];
        let r = microslip::evaluate(&p, u, v, 0.0, true).unwrap();
        let slider = r.slider;
        let r = microslip::evaluate(&p, u, v, slider, true).unwrap();
        for ph in r.cycle.phases() {
            if let PhaseKind::Stick { origin, .. } = ph.kind {
                regimes.insert(format!("{origin:?}").split('(').next().unwrap().to_string());
            }
        }
        let (fj, nj) = (r.friction_jacobian.unwrap(), r.normal_jacobian.unwrap());
        let scale = fj
            .iter()
            .chain(&nj)
            .flatten()
            .fold(0.0f64, |m, x| m.max(x.abs()));
        let x0: Vec<f64> = u.iter().chain(&v).copied().chain([p.n0]).collect();
        let xscale = [0.7, 0.7, 0.7, 0.3, 0.3, 0.3, p.n0.abs().max(1.0)];
        for c in 0..7 {
            let h = 1e-6 * xscale[c];
            let eval = |s: f64| {
                let mut x = x0.clone();
                x[c] += s * h;
                let q = params(p.kt, p.kn, p.mu, x[6]);
                let r =
                    microslip::evaluate(&q, [x[0], x[1], x[2]], [x[3], x[4], x[5]], slider, false)
                        .unwrap();
                (r.friction, r.normal)
            };
            let (fp, np) = eval(1.0);
            let (fm, nm) = eval(-1.0);
            for k in 0..3 {
                let dfd = (fp[k] - fm[k]) / (2.0 * h);
                let dnd = (np[k] - nm[k]) / (2.0 * h);
                assert!(
                    (dfd - fj[k][c]).abs() <= 1e-6 * scale,
                    "{label}: ∂F{k}/∂x{c} analytic {} vs central {dfd} (scale {scale})",
                    fj[k][c]
                );
                assert!(
                    (dnd - nj[k][c]).abs() <= 1e-6 * scale,
                    "{label}: ∂N{k}/∂x{c} analytic {} vs central {dnd}",
                    nj[k][c]
                );
            }
        }
    }
    for origin in [
        "Carried",
        "AfterPositiveSlip",
        "AfterNegativeSlip",
        "Recontact",
    ] {
        assert!(
            regimes.contains(origin),
            "no stick phase of origin {origin}: {regimes:?}"
        );
    }
}

/// The element path (`evaluate_as`): the analytic evaluation of a two-direction element with
/// normal kinematics equals the point evaluation per direction (to round-off: the element path
/// evaluates the separating point in closed form, the point evaluation by the event march);
/// with H = 3 it is an input error that names the remedy; the 2-D law is refused.
#[test]
fn element_path_and_its_errors() {
    let aft = Aft::new(HarmonicLayout::new(1, 64).unwrap()).unwrap();
    let mut ws = Workspace::new(&aft);
    let p = params(2.0, 5.0, 0.4, 1.0);
    let el = LocalElement {
        params: p,
        variant: Variant::OneD,
        tangential: 2,
        normal: true,
    };
    let (u1, u2, v) = ([0.1, 0.5, -0.2], [0.0, -0.3, 0.4], [0.01, 0.2, 0.1]);
    let x: Vec<f64> = u1.iter().chain(&u2).chain(&v).copied().collect();
    let mut f = vec![0.0; 9];
    let mut w = [0.0; 2];
    evaluate_as(
        Evaluation::Analytic,
        &el,
        &aft,
        &x,
        &mut w,
        &mut f,
        true,
        &mut ws,
    )
    .unwrap();
    let r1 = microslip::evaluate(&p, u1, v, 0.0, true).unwrap();
    let r2 = microslip::evaluate(&p, u2, v, 0.0, true).unwrap();
    // the point separates: the element path takes the closed form, the point evaluation the event
    // march, equal to round-off (1e-13 of the force scale k_t |U1| + |n0e| + k_n |V1|, of
    // k_t + k_n for the Jacobian)
    let scale = p.kt * u1[1].hypot(u1[2]).max(u2[1].hypot(u2[2]))
        + (p.n0 + p.kn * v[0]).abs()
        + p.kn * v[1].hypot(v[2]);
    let near = |a: f64, b: f64, unit: f64| (a - b).abs() <= 1e-13 * unit;
    let all_near = |a: &[f64], b: &[f64]| a.iter().zip(b).all(|(x, y)| near(*x, *y, scale));
    assert!(
        all_near(&f[0..3], &r1.friction),
        "{:?} {:?}",
        &f[0..3],
        r1.friction
    );
    assert!(
        all_near(&f[3..6], &r2.friction),
        "{:?} {:?}",
        &f[3..6],
        r2.friction
    );
    assert!(
        all_near(&f[6..9], &r1.normal),
        "{:?} {:?}",
        &f[6..9],
        r1.normal
    );
    let sliders = [r1.slider * p.kt, r2.slider * p.kt];
    assert!(
        all_near(&[w[0] * p.kt, w[1] * p.kt], &sliders),
        "{w:?} {sliders:?}"
    );
    let (jac, cols) = ws.jacobian();
    assert_eq!(cols, 10);
    let jac_scale = p.kt + p.kn;
    assert!(near(
        jac[cols + 1],
        r1.friction_jacobian.unwrap()[1][1],
        jac_scale
    ));
    assert!(near(
        jac[4 * cols + 7],
        r2.friction_jacobian.unwrap()[1][4],
        jac_scale
    ));
    assert!(near(
        jac[7 * cols + 9],
        r1.normal_jacobian.unwrap()[1][6],
        jac_scale
    ));
    assert_eq!(jac[cols + 4], 0.0, "direction 1 does not depend on U2");
    let rep = ws.report();
    assert!((rep.dissipated_energy - r1.energy - r2.energy).abs() < 1e-15);
    assert!((rep.stick + rep.slip + rep.separation - 1.0).abs() < 1e-12);
    let lp = ws.hysteresis();
    assert_eq!(lp.ft[0].len(), 64);

    // H = 3: the exact cycle with transitions located as roots (`contact::exact`); a motion
    // whose second and third harmonics are zero gives the closed-form cycle's mean and first
    // harmonic (the force's higher harmonics are not zero: the closed form leaves them out)
    let aft3 = Aft::new(HarmonicLayout::new(3, 64).unwrap()).unwrap();
    let mut ws3 = Workspace::new(&aft3);
    let widen = |s: &[f64; 3]| [s[0], s[1], s[2], 0.0, 0.0, 0.0, 0.0];
    let x3: Vec<f64> = [widen(&u1), widen(&u2), widen(&v)].concat();
    let mut f3 = vec![0.0; 21];
    let mut w3 = [0.0; 2];
    evaluate_as(
        Evaluation::Analytic,
        &el,
        &aft3,
        &x3,
        &mut w3,
        &mut f3,
        false,
        &mut ws3,
    )
    .unwrap();
    for (signal, closed) in [&r1.friction, &r2.friction, &r1.normal].iter().enumerate() {
        for (k, expected) in closed.iter().enumerate() {
            assert!(
                (f3[signal * 7 + k] - expected).abs() < 1e-12,
                "signal {signal} coefficient {k}: {} vs {expected}",
                f3[signal * 7 + k]
            );
        }
    }
    let el2 = LocalElement {
        variant: Variant::TwoD,
        ..el
    };
    let err = evaluate_as(
        Evaluation::Analytic,
        &el2,
        &aft,
        &x,
        &mut w,
        &mut f,
        false,
        &mut ws,
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("2-D"), "{err}");
}
