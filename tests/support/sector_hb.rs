//! The harmonic balance of a sector problem at one frequency, as a reference for other methods.

use faer::c64;
use nlrom::harmonics::HarmonicForce;
use nlrom::hbm::{FrequencyPath, HbmSystem};
use nlrom::nonlinear::{solve_fixed, NewtonOptions};
use nlrom::problem::sector::SectorProblem;

/// Harmonic 1 of the output DOFs (m) of the HB solution at ω (rad/s), by Newton from zero
/// (tolerance 1e-10), recovered from the condensed solution (SAMA paper eq 18).
pub fn hb_outputs(problem: &SectorProblem, omega: f64) -> Vec<c64> {
    let system = HbmSystem::new(problem.layout, &problem.linear, &problem.contact).unwrap();
    let path = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let opts = NewtonOptions {
        tolerance: 1e-10,
        ..NewtonOptions::default()
    };
    let x0 = vec![0.0; system.dim()];
    let x = solve_fixed(&path, &x0, omega, &problem.contact.initial_state(), &opts)
        .expect("HB converges")
        .x;
    let nd = problem.linear.n_condensed();
    let q1: Vec<c64> = (0..nd)
        .map(|i| {
            let r = problem.layout.cos_index(1, i, nd);
            c64::new(x[r], x[r + 1])
        })
        .collect();
    problem.linear.condense(1, omega).unwrap().recover(&q1)
}
