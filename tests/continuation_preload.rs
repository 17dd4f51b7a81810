//! Continuation in the static normal load n0 at fixed ω ([`nlrom::hbm::PreloadPath`], ∂r/∂n0 from
//! `HarmonicForce::parameter_derivative`) against independent fixed-ω Newton solves, each from
//! the linear start x = 0 and sliders at rest, at the same n0 values (1e-8 relative), and the
//! parameter derivative against central finite differences of the residual.

mod support;

use nlrom::contact::grounded::DofElements;
use nlrom::continuation::{trace, ContinuationOptions, PathEnd};
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::{FrequencyPath, HbmSystem, LinearModel, PreloadPath};
use nlrom::nonlinear::{norm, solve_fixed, Linearization, NewtonOptions, ParameterSystem};
use nlrom::Result;
use support::hbm::{tangential_normal_element, two_oscillators};

const OMEGA: f64 = 1.0;

/// Two oscillators (x tangential, y normal) joined by one friction element with normal load
/// variation (k_t = 1, k_n = 3, μ = 0.3), both excited; at ω = 1 the x oscillator slips over
/// part of every period for n0 in 0.15..0.6 (so the periodic solution is unique).
fn model() -> LinearModel {
    two_oscillators(0.02, [0.05, 0.03], 5)
}

fn contact(n0: f64) -> Result<DofElements> {
    tangential_normal_element(n0)
}

fn tight() -> NewtonOptions {
    NewtonOptions {
        tolerance: 1e-12,
        increment_tolerance: 1e-11,
        max_iterations: 60,
        ..NewtonOptions::default()
    }
}

#[test]
fn preload_path_matches_independent_fixed_frequency_solves() {
    let linear = model();
    let layout = HarmonicLayout::new(5, 256).unwrap();
    let path_system = PreloadPath {
        layout,
        linear: &linear,
        build: contact,
        omega: OMEGA,
        level: 1.0,
        initial: vec![0.0],
    };
    let mut opts = ContinuationOptions::new(0.15, 0.6, 0.02);
    opts.newton = tight();
    let path = trace(&path_system, &opts, &mut |_| {}).unwrap();
    assert_eq!(path.end, PathEnd::ReachedEnd);
    assert!(path.points.len() >= 10, "{} points", path.points.len());
    let mut worst: f64 = 0.0;
    for p in &path.points {
        let force = contact(p.parameter).unwrap();
        let system = HbmSystem::new(layout, &linear, &force).unwrap();
        let fp = FrequencyPath {
            system: &system,
            level: 1.0,
        };
        let zero = vec![0.0; fp.dim()];
        let direct = solve_fixed(&fp, &zero, OMEGA, &vec![0.0], &tight()).unwrap();
        let diff: Vec<f64> = p.x.iter().zip(&direct.x).map(|(a, b)| a - b).collect();
        worst = worst.max(norm(&diff) / norm(&direct.x));
    }
    println!(
        "{} points, largest relative difference {worst:.3e}",
        path.points.len()
    );
    assert!(worst <= 1e-8, "largest relative difference {worst:.3e}");
    // the load actually changes the response (not a trivially constant path)
    let first = &path.points[0].x;
    let last = &path.points.last().unwrap().x;
    let change: Vec<f64> = first.iter().zip(last).map(|(a, b)| a - b).collect();
    assert!(norm(&change) > 0.1 * norm(first));
}

#[test]
fn preload_derivative_matches_finite_differences() {
    let linear = model();
    let layout = HarmonicLayout::new(5, 256).unwrap();
    let path_system = PreloadPath {
        layout,
        linear: &linear,
        build: contact,
        omega: OMEGA,
        level: 1.0,
        initial: vec![0.0],
    };
    // a slipping periodic solution at n0 = 0.3 and its own slider state
    let force = contact(0.3).unwrap();
    let system = HbmSystem::new(layout, &linear, &force).unwrap();
    let fp = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let sol = solve_fixed(&fp, &vec![0.0; fp.dim()], OMEGA, &vec![0.0], &tight()).unwrap();
    let residual_at = |p: f64| {
        let mut lin = Linearization::zeros(path_system.dim());
        path_system
            .evaluate(&sol.x, p, &sol.state, &mut lin)
            .unwrap();
        lin
    };
    let at = residual_at(0.3);
    let h = 1e-6;
    let (plus, minus) = (residual_at(0.3 + h), residual_at(0.3 - h));
    let fd: Vec<f64> = plus
        .residual
        .iter()
        .zip(&minus.residual)
        .map(|(a, b)| (a - b) / (2.0 * h))
        .collect();
    let err: Vec<f64> = fd.iter().zip(&at.d_parameter).map(|(a, b)| a - b).collect();
    assert!(norm(&at.d_parameter) > 1e-3);
    assert!(
        norm(&err) <= 1e-6 * norm(&at.d_parameter),
        "FD {fd:?} vs analytic {:?}",
        at.d_parameter
    );
}
