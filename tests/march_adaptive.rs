//! The adaptive step of Gastaldi & Berruti 2018 (§4.2, eq. 8; src/march/adaptive.rs) against
//! dense eigenproblems written out here (faer's Cholesky and symmetric eigenvalues):
//! - the ladder's rungs lie below the step within one ratio ϱ, and are Δτ_stick ϱᵏ to the bit;
//! - the negative eigenvalues counted from the Bunch–Kaufman factorisation are those of the
//!   symmetric eigenproblem, on random symmetric matrices;
//! - on a chain of 20 masses with six friction elements (tangential and normal directions over
//!   several DOF, the slip coupling σ μ k_n g_t g_nᵀ, elements that do not apply their normal force,
//!   a largest step 8 % above the full-stick one), along a random walk through stick, slip and
//!   separation, the rung found by the inertia tests equals the ladder's rung below
//!   r 2π/√λ_max of the state's symmetric pencil (M, K + sym K_c);
//! - on the reduced sector of `cases/sector8_march.toml` (289 coordinates, 90 elements), along the
//!   contact states of a period of piecewise-linear Newmark at 170 Hz, the same, and the rung is
//!   never above the one of the spectral radius of M⁻¹(K + K_c) (eq. 8 as the dense path takes it).

mod support;

use std::path::Path;

use faer::Mat;
use nlrom::case::{Case, MarchScheme};
use nlrom::march::adaptive::{ladder_step, AdaptiveSteps, LADDER_RATIO, THRESHOLD_MARGIN};
use nlrom::march::element::{Direction, Element};
use nlrom::march::law::{ContactState, FrictionParams, LawSample, Sign};
use nlrom::march::signal::Harmonic;
use nlrom::march::{march, InitialCondition, MarchSettings, MarchSystem};
use nlrom::problem::march_case::case_march;
use support::random::Lcg;

const N: usize = 20;

fn direction(weights: &[(usize, f64)]) -> Direction {
    Direction {
        weights: weights.to_vec(),
        prescribed: Harmonic::default(),
    }
}

/// Masses 1 + 0.05 i kg on springs of 100 N/m (a chain fixed at its first end) and six friction
/// elements (k_t 60–110 N/m, k_n 40–90 N/m, μ = 0.3, n0 = 0.5 N) on pairs of DOF, the odd ones
/// without applying their normal force.
fn chain() -> MarchSystem {
    let mut k = vec![0.0; N * N];
    for (i, j, x) in support::chain::stiffness(N, 100.0, 0) {
        k[i * N + j] = x;
        k[j * N + i] = x;
    }
    let mut mass = vec![0.0; N * N];
    for i in 0..N {
        mass[i * N + i] = 1.0 + 0.05 * i as f64;
    }
    let elements = (0..6)
        .map(|j| {
            let (a, b) = (3 * j, 3 * j + 2);
            Element {
                name: format!("e{j}"),
                tangential: direction(&[(a, 1.0), (b, -1.0)]),
                normal: Some(direction(&[(a + 1, 1.0), (b, 0.5)])),
                params: FrictionParams {
                    kt: 60.0 + 10.0 * j as f64,
                    kn: 40.0 + 10.0 * j as f64,
                    mu: 0.3,
                    n0: 0.5,
                },
                applies_normal: j % 2 == 0,
            }
        })
        .collect();
    MarchSystem {
        n: N,
        mass,
        damping: vec![0.0; N * N],
        stiffness: k,
        force: vec![Harmonic::default(); N],
        damping_force: Vec::new(),
        elements,
        dof_names: (0..N).map(|i| format!("q{i}")).collect(),
        initial: InitialCondition::Rest,
        displacement_scale: 1.0,
    }
}

/// The largest eigenvalue of K φ = λ M φ with K the symmetric part of K + K_c(states) (rad²/s²):
/// M = L Lᵀ, the eigenvalues of L⁻¹ K L⁻ᵀ.
fn symmetric_top(sys: &MarchSystem, states: &[ContactState]) -> f64 {
    use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
    let n = sys.n;
    let k = sys.effective_stiffness(states);
    let m = Mat::from_fn(n, n, |i, j| sys.mass[i * n + j]);
    let l = m
        .llt(faer::Side::Lower)
        .expect("M positive definite")
        .L()
        .to_owned();
    let mut x = Mat::from_fn(n, n, |i, j| 0.5 * (k[i * n + j] + k[j * n + i]));
    solve_lower_triangular_in_place(l.as_ref(), x.as_mut(), faer::Par::Seq);
    let mut y = x.transpose().to_owned();
    solve_lower_triangular_in_place(l.as_ref(), y.as_mut(), faer::Par::Seq);
    let b = Mat::from_fn(n, n, |i, j| 0.5 * (y[(i, j)] + y[(j, i)]));
    let values = b
        .self_adjoint_eigenvalues(faer::Side::Lower)
        .expect("eigenvalues");
    values.into_iter().fold(f64::NEG_INFINITY, f64::max)
}

/// ρ(M⁻¹(K + K_c(states))), the spectral radius (rad²/s²).
fn spectral_radius(sys: &MarchSystem, states: &[ContactState]) -> f64 {
    let t = sys.shortest_period(states).expect("a period");
    (2.0 * std::f64::consts::PI / t).powi(2)
}

/// Samples in `states` (the adaptive step reads their states).
fn samples(states: &[ContactState]) -> Vec<LawSample> {
    states
        .iter()
        .map(|&state| LawSample {
            f_t: 0.0,
            f_n: 0.0,
            state,
            slider: 0.0,
        })
        .collect()
}

fn codes(states: &[ContactState]) -> Vec<u8> {
    states.iter().map(|s| s.code()).collect()
}

/// The ladder's rung below eq. 8 for ρ (rad²/s²), a state within `THRESHOLD_MARGIN` of a rung's
/// threshold taking it (as the full-stick state takes rung 0 whatever the rounding of its ρ).
fn rung_of(rho: f64, ratio: f64, dt_stick: f64, dt_max: f64) -> f64 {
    let rho = rho / (1.0 + THRESHOLD_MARGIN);
    let dt = ratio * 2.0 * std::f64::consts::PI / rho.sqrt();
    ladder_step(dt.min(dt_max), dt_stick, dt_max)
}

#[test]
fn inertia_tests_find_the_rung_of_the_symmetric_pencil_on_a_chain() {
    let sys = chain();
    let all = [
        ContactState::Stick,
        ContactState::Slip(Sign::Positive),
        ContactState::Slip(Sign::Negative),
        ContactState::Separated,
    ];
    let ratio = 0.15;
    let dt_stick = ratio * sys.shortest_period(&sys.stick_states()).expect("period");
    let dt_max = 1.08 * dt_stick;
    let mut steps = AdaptiveSteps::new(&sys, ratio, dt_max);
    assert_eq!(steps.stick(), dt_stick);
    let mut states = sys.stick_states();
    // a deterministic walk: one or two elements change per state
    let mut random = Lcg(12345);
    let mut rungs = std::collections::BTreeMap::new();
    let elements: Vec<usize> = (0..states.len()).collect();
    for step in 0..300 {
        for _ in 0..1 + step % 2 {
            let e = random.pick(&elements);
            states[e] = random.pick(&all);
        }
        let dt = steps.step(&sys, &codes(&states), &samples(&states));
        let expected = rung_of(symmetric_top(&sys, &states), ratio, dt_stick, dt_max);
        assert_eq!(dt, expected, "step {step}: states {:?}", codes(&states));
        let eq8 = ratio * sys.shortest_period(&states).expect("period");
        assert!(dt <= eq8.min(dt_max) * (1.0 + 1e-6), "{dt} above {eq8}");
        *rungs
            .entry((dt / dt_stick * 1e4).round() as i64)
            .or_insert(0) += 1;
    }
    let (met, tests, bound, dense) = steps.counts();
    eprintln!(
        "chain: {met} states, {tests} inertia tests, {bound} rungs excluded by the bound, {dense} dense eigenproblems; steps (Δτ/Δτ_stick × 1e4: count) {rungs:?}"
    );
    assert_eq!(dense, 0);
    // the walk meets the largest step, rungs between, and full stick
    assert!(rungs.len() >= 4, "{rungs:?}");
}

#[test]
fn inertia_tests_follow_the_sector_states_like_the_dense_eigenproblems() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/sector8_march.toml");
    let case = Case::load(&path).expect("bundled case");
    let cm = case_march(&case, Some(MarchScheme::PiecewiseLinear), &mut |_| {}).expect("march");
    let sys = &cm.system;
    let settings = MarchSettings {
        periods: 1,
        steps_per_period: 300,
        time_step: None,
        stop_at_steady: false,
        ..cm.settings.clone()
    };
    let out = march(sys, &settings).expect("march");
    let ne = sys.elements.len();
    // the sequence of states met, each once, in the march's order
    let mut sequence: Vec<&[u8]> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for row in out.history.state.chunks_exact(ne) {
        if seen.insert(row) {
            sequence.push(row);
        }
    }
    let to_states = |codes: &[u8]| -> Vec<ContactState> {
        codes
            .iter()
            .map(|&c| match c {
                0 => ContactState::Separated,
                1 => ContactState::Stick,
                2 => ContactState::Slip(Sign::Positive),
                _ => ContactState::Slip(Sign::Negative),
            })
            .collect()
    };
    let ratio = settings.step_ratio;
    let dt_max = settings.period() / settings.steps_per_period as f64;
    let mut steps = AdaptiveSteps::new(sys, ratio, dt_max);
    let dt_stick = steps.stick();
    let every = (sequence.len() / 40).max(1);
    let (mut compared, mut worst) = (0, 0.0f64);
    let mut rungs = std::collections::BTreeMap::new();
    let mut cpu = std::time::Duration::ZERO;
    for (j, codes) in sequence.iter().enumerate() {
        let states = to_states(codes);
        let smp = samples(&states);
        let t0 = std::time::Instant::now();
        let dt = steps.step(sys, codes, &smp);
        cpu += t0.elapsed();
        *rungs
            .entry((dt / dt_stick * 1e4).round() as i64)
            .or_insert(0) += 1;
        if j % every != 0 {
            continue;
        }
        compared += 1;
        let (top, rho) = (symmetric_top(sys, &states), spectral_radius(sys, &states));
        assert_eq!(dt, rung_of(top, ratio, dt_stick, dt_max), "state {j}");
        assert!(dt <= rung_of(rho, ratio, dt_stick, dt_max), "state {j}");
        worst = worst.max((top - rho) / rho);
    }
    let (met, tests, bound, dense) = steps.counts();
    eprintln!(
        "sector: {met} states met, {tests} inertia tests, {bound} rungs excluded by the bound, {dense} dense eigenproblems, {:.3} ms per state; steps (Δτ/Δτ_stick × 1e4: count) {rungs:?}; {compared} compared with the dense eigenproblems: λ_max of the symmetric pencil above ρ by at most {worst:.2e} of it",
        cpu.as_secs_f64() * 1e3 / sequence.len() as f64
    );
    assert!(compared >= 30, "{compared}");
    assert_eq!(dense, 0);
    assert!(worst < 5e-3, "{worst}");
}

#[test]
fn ladder_rungs_lie_below_the_step_within_one_ratio() {
    let (stick, max) = (1.0e-6, 3.0e-6);
    assert_eq!(ladder_step(stick, stick, max), stick);
    assert_eq!(ladder_step(5.0e-6, stick, max), max);
    assert_eq!(ladder_step(max, stick, max), max);
    for j in 0..2000 {
        let dt = stick * (0.8 + 2.2 * j as f64 / 2000.0);
        if dt >= max {
            continue;
        }
        let r = ladder_step(dt, stick, max);
        assert!(r <= dt, "{r} above {dt}");
        assert!(r * LADDER_RATIO > dt, "{r} more than one rung below {dt}");
        // a rung is Δτ_stick ϱᵏ to the bit, whatever step led to it
        let k = (r / stick).ln() / LADDER_RATIO.ln();
        assert_eq!(r, stick * LADDER_RATIO.powi(k.round() as i32));
    }
}

#[test]
fn inertia_counts_the_negative_eigenvalues() {
    let mut random = Lcg(987654321);
    for n in 1..40 {
        let mut a = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..=i {
                // some zero diagonals, to force 2 × 2 pivots
                let x = if i == j && i % 3 == 0 {
                    0.0
                } else {
                    random.next() - 0.5
                };
                a[i * n + j] = x;
                a[j * n + i] = x;
            }
        }
        let m = Mat::from_fn(n, n, |i, j| a[i * n + j]);
        let values = m
            .self_adjoint_eigenvalues(faer::Side::Lower)
            .expect("eigenvalues");
        let expected = values.iter().filter(|&&v| v < 0.0).count();
        assert_eq!(
            nlrom::march::dense::negative_eigenvalues(&a, n),
            expected,
            "n = {n}"
        );
    }
}
