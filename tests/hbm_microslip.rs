//! The analytic single-harmonic friction elements (`evaluation = "analytic"`, Cigeroglu, An &
//! Menq 2007) inside the harmonic balance at H = 1, on the 3-DOF chain of
//! `cases/chain3_jenkins.toml` with one element carrying normal load variation: the frequency
//! response equals the AFT one to first order in 1/N_t, and at every point the excitation's
//! work per cycle equals the viscous plus the friction dissipation.

mod support;

use std::path::Path;

use nlrom::case::{Case, Evaluation};
use nlrom::contact::grounded::DofElements;
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::frf::{frequency_response, Frf};
use nlrom::hbm::system::FrequencyPath;
use nlrom::hbm::{HbmSystem, ResponseOptions};
use nlrom::model;
use nlrom::nonlinear::{solve_fixed, NewtonOptions};
use nlrom::problem::matrix_case::matrix_setup;
use nlrom::problem::settings::case_continuation;
use support::cli::root;

fn case_text(evaluation: &str) -> String {
    let m = root().join("cases/chain3");
    format!(
        r#"title = "chain, {evaluation}"
[model]
stiffness = "{k}"
mass = "{mm}"
damping = {{ rayleigh = [0.0, 0.02] }}

[excitation]
dofs = [2]
force = [0.5]

[response]
dofs = [0, 1, 2]

[[element]]
kind = "friction"
tangential = {{ dofs = [0], weights = [1.0] }}
kt = 1.0
mu = 1.0
n0 = 0.2
evaluation = "{evaluation}"

[[element]]
kind = "friction"
tangential = {{ dofs = [1, 2], weights = [-1.0, 1.0] }}
normal = {{ dofs = [0], weights = [0.5] }}
kt = 1.0
kn = 0.8
mu = 1.0
n0 = 0.15
evaluation = "{evaluation}"

[harmonic_balance]
harmonics = 1

[continuation]
start_rad_s = 0.3
end_rad_s = 2.0
step_rad_s = 0.02
"#,
        k = m.join("K.mtx").display(),
        mm = m.join("M.mtx").display(),
    )
}

fn response(evaluation: &str, n_t: usize) -> (Case, Frf<Vec<f64>>, DofElements, HarmonicLayout) {
    let case = Case::from_str(&case_text(evaluation), Path::new("/tmp/chain.toml")).unwrap();
    let model = model::build(&case, &mut |_| {}).unwrap();
    let setup = matrix_setup(&case, &model).unwrap();
    let elements = DofElements::from_case(&case.element, 3).unwrap();
    let layout = HarmonicLayout::new(1, n_t).unwrap();
    let system = HbmSystem::new(layout, &setup.linear, &elements).unwrap();
    let opts = case_continuation(&case).unwrap();
    let frf = frequency_response(&system, &opts, &ResponseOptions::default(), &mut |_| {}).unwrap();
    (case, frf, elements, layout)
}

/// Newton at the fixed ω from `q0` on the system of `evaluation` with N_t samples, to 1e-12.
fn solve_at(evaluation: &str, n_t: usize, omega: f64, q0: &[f64], state: &Vec<f64>) -> Vec<f64> {
    let case = Case::from_str(&case_text(evaluation), Path::new("/tmp/chain.toml")).unwrap();
    let model = model::build(&case, &mut |_| {}).unwrap();
    let setup = matrix_setup(&case, &model).unwrap();
    let elements = DofElements::from_case(&case.element, 3).unwrap();
    let system = HbmSystem::new(
        HarmonicLayout::new(1, n_t).unwrap(),
        &setup.linear,
        &elements,
    )
    .unwrap();
    let path = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let opts = NewtonOptions {
        tolerance: 1e-12,
        increment_tolerance: 1e-10,
        max_iterations: 40,
        ..NewtonOptions::default()
    };
    solve_fixed(&path, q0, omega, state, &opts).unwrap().x
}

/// At twelve points of the analytic frequency response (H = 1), Newton on the AFT system from the
/// analytic solution: the solutions differ by less than 5e-3 of |Q| at N_t = 1024 (near the resonance) and the
/// largest difference falls by a factor 3 to 6 from 256 to 1024 samples (first order in
/// 1/N_t). The evaluation choice is read from the case file.
#[test]
fn analytic_and_aft_solutions_agree_to_first_order() {
    let (case, analytic, elements, _) = response("analytic", 64);
    assert_eq!(elements.evaluations(), &[Evaluation::Analytic; 2]);
    assert_eq!(case.element[1].evaluation, Evaluation::Analytic);
    let stride = analytic.points.len() / 12;
    let mut worst = [0.0f64; 2];
    for p in analytic.points.iter().step_by(stride) {
        let reference = solve_at("analytic", 64, p.omega, &p.q, &p.state);
        let size = reference.iter().map(|x| x * x).sum::<f64>().sqrt();
        for (k, n_t) in [256, 1024].into_iter().enumerate() {
            let q = solve_at("aft", n_t, p.omega, &reference, &p.state);
            let d = q
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).powi(2))
                .sum::<f64>()
                .sqrt();
            worst[k] = worst[k].max(d / size);
        }
    }
    eprintln!("largest relative difference AFT − analytic at N_t = 256, 1024: {worst:?}");
    assert!(worst[1] < 5e-3, "{worst:?}");
    let ratio = worst[0] / worst[1];
    assert!((3.0..6.0).contains(&ratio), "{worst:?}: ratio {ratio}");
}

/// Energy balance at every point of the analytic response: the work of the excitation per
/// cycle, −π f Im X₂, equals the viscous dissipation π ω Re(Xᴴ C X) plus the energy the two
/// friction elements dissipate (their exact cycles), to 1e-6 of the excitation work (the
/// continuation's Newton tolerance is 1e-8 of the force).
#[test]
fn energy_balance_at_every_point() {
    let (_, frf, elements, layout) = response("analytic", 64);
    // K of the chain: ground–k–m1–k–m2–k–m3 with k = 1; C = 0.02 K.
    let k = [[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]];
    let mut checked = 0;
    for p in &frf.points {
        // q: [Q0 of the 3 DOFs; Re Q1, Im Q1 per DOF].
        let x: Vec<(f64, f64)> = (0..3).map(|d| (p.q[3 + 2 * d], p.q[4 + 2 * d])).collect();
        let work = -std::f64::consts::PI * 0.5 * x[2].1;
        let mut viscous = 0.0;
        for r in 0..3 {
            for c in 0..3 {
                viscous += 0.02 * k[r][c] * (x[r].0 * x[c].0 + x[r].1 * x[c].1);
            }
        }
        viscous *= std::f64::consts::PI * p.omega;
        let reports = elements.reports(&layout, &p.q, &p.state, false).unwrap();
        let friction: f64 = reports.iter().map(|r| r.0.dissipated_energy).sum();
        assert!(
            (work - viscous - friction).abs() <= 1e-6 * work.abs(),
            "ω = {}: excitation {work}, viscous {viscous}, friction {friction}",
            p.omega
        );
        checked += 1;
    }
    assert!(checked > 50, "{checked} points");
}
