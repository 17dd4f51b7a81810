//! Pseudo-arc-length continuation through folds: the Duffing oscillator
//! m q̈ + c q̇ + k q + k3 q³ = F cos ωt against its one-harmonic frequency–amplitude relation
//! ((k − mω² + ¾ k3 A²)² + (cω)²) A² = F², both turning points traced, no skipped segment;
//! level continuation of a linear system; a failing corrector is reported with the points kept.

mod support;

use faer::Mat;
use nlrom::continuation::{trace, ContinuationOptions, PathEnd, PathPoint};
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::frf::frequency_response;
use nlrom::hbm::response::output_response;
use nlrom::hbm::{
    FixedFrequencyParameter, FixedFrequencyPath, FrequencyPath, HbmSystem, LinearModel,
    ResponseOptions,
};
use nlrom::nonlinear::{Linearization, ParameterSystem};
use nlrom::{Error, Result};
use support::hbm::{chain4, PolynomialSprings};

const K: f64 = 1.0;
const M: f64 = 1.0;
const C: f64 = 0.05;
const K3: f64 = 0.5;
const F: f64 = 0.1;

/// The residual of the HB-1 relation, relative to F².
fn hb1_residual(omega: f64, a: f64) -> f64 {
    let re = K - M * omega * omega + 0.75 * K3 * a * a;
    ((re * re + (C * omega).powi(2)) * a * a - F * F) / (F * F)
}

/// The upper root ω₊(A) of the HB-1 relation (a quadratic in ω²), if real.
fn omega_plus(a: f64) -> Option<f64> {
    let alpha = K + 0.75 * K3 * a * a;
    let b = 2.0 * alpha - C * C;
    let disc = b * b - 4.0 * (alpha * alpha - F * F / (a * a));
    (disc >= 0.0).then(|| ((b + disc.sqrt()) / 2.0).sqrt())
}

/// The two fold frequencies of the HB-1 curve: the local maximum and minimum of ω₊(A).
fn analytic_folds() -> (f64, f64) {
    let samples: Vec<(f64, f64)> = (1..200_000)
        .map(|i| 0.05 + i as f64 * 2e-5)
        .filter_map(|a| omega_plus(a).map(|w| (a, w)))
        .collect();
    let mut max: f64 = 0.0;
    let mut min = f64::INFINITY;
    for w in samples.windows(3) {
        let (p, c, n) = (w[0].1, w[1].1, w[2].1);
        if c >= p && c >= n {
            max = max.max(c);
        }
        if c <= p && c <= n {
            min = min.min(c);
        }
    }
    (max, min)
}

/// The peak of the HB-1 curve: the largest A with a real ω (to 1e-5).
fn analytic_peak() -> f64 {
    (1..400_000)
        .map(|i| i as f64 * 1e-5)
        .filter(|a| omega_plus(*a).is_some())
        .fold(0.0, f64::max)
}

fn duffing_model(h: usize) -> LinearModel {
    let k = Mat::from_fn(1, 1, |_, _| K);
    let m = Mat::from_fn(1, 1, |_, _| M);
    let c = Mat::from_fn(1, 1, |_, _| C);
    LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        Some(c.as_ref()),
        &[F],
        vec![0],
        vec![0],
        h,
    )
    .unwrap()
}

fn cubic() -> PolynomialSprings {
    PolynomialSprings {
        k1: vec![0.0],
        k3: vec![K3],
    }
}

/// Frequencies of the path points where dω/ds changes sign (interpolated between the two
/// points around it by the sign change of the tangent's ω component).
fn fold_frequencies<S>(points: &[PathPoint<S>]) -> Vec<f64> {
    points
        .windows(2)
        .filter(|w| w[0].tangent_parameter * w[1].tangent_parameter < 0.0)
        .map(|w| {
            if w[0].tangent_parameter > 0.0 {
                w[0].parameter.max(w[1].parameter)
            } else {
                w[0].parameter.min(w[1].parameter)
            }
        })
        .collect()
}

#[test]
fn duffing_one_harmonic_matches_the_analytic_curve_through_both_folds() {
    let model = duffing_model(1);
    let force = cubic();
    let system = HbmSystem::new(HarmonicLayout::new(1, 8).unwrap(), &model, &force).unwrap();
    let path_system = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let mut opts = ContinuationOptions::new(0.5, 2.0, 0.01);
    opts.max_step = Some(0.02);
    let mut seen = 0;
    let path = trace(&path_system, &opts, &mut |_| seen += 1).unwrap();
    assert_eq!(path.end, PathEnd::ReachedEnd);
    assert_eq!(seen, path.points.len());
    let last = path.points.last().unwrap();
    assert!((last.parameter - 2.0).abs() <= 1e-12);
    let amps: Vec<f64> = path
        .points
        .iter()
        .map(|p| {
            output_response(&system, &p.x, p.parameter, 1.0, &ResponseOptions::default())
                .unwrap()
                .amplitude[0]
        })
        .collect();
    // every point on the analytic HB-1 curve
    for (p, a) in path.points.iter().zip(&amps) {
        let r = hb1_residual(p.parameter, *a);
        assert!(
            r.abs() <= 1e-6,
            "ω = {}, A = {a}: relation residual {r:e}",
            p.parameter
        );
    }
    // both turning points, at the analytic fold frequencies
    let folds = fold_frequencies(&path.points);
    let (w_max, w_min) = analytic_folds();
    assert_eq!(folds.len(), 2, "folds at {folds:?}");
    assert!(
        (folds[0] - w_max).abs() <= 2e-3 * w_max,
        "upper fold {} vs {w_max}",
        folds[0]
    );
    assert!(
        (folds[1] - w_min).abs() <= 2e-3 * w_min,
        "lower fold {} vs {w_min}",
        folds[1]
    );
    // no skipped segment: amplitude rises to the peak and then falls, in small steps
    let peak = amps.iter().cloned().fold(0.0, f64::max);
    let ip = amps.iter().position(|a| *a == peak).unwrap();
    assert!(amps[..=ip].windows(2).all(|w| w[1] > w[0]));
    assert!(amps[ip..].windows(2).all(|w| w[1] < w[0]));
    assert!(amps.windows(2).all(|w| (w[1] - w[0]).abs() <= 0.1 * peak));
    // the analytic peak: the largest A with a real ω
    let a_max = analytic_peak();
    assert!(
        (peak - a_max).abs() <= 5e-3 * a_max,
        "peak {peak} vs {a_max}"
    );
    // the three branches: between the folds three solutions at one frequency
    let mid = 0.5 * (w_max + w_min);
    let crossings = path
        .points
        .windows(2)
        .filter(|w| (w[0].parameter - mid) * (w[1].parameter - mid) <= 0.0)
        .count();
    assert_eq!(crossings, 3);
}

/// With 5 harmonics the third harmonic appears; the first-harmonic amplitude stays within 2 % of
/// the HB-1 curve's peak and both folds are still passed.
#[test]
fn duffing_five_harmonics_passes_the_folds() {
    let model = duffing_model(5);
    let force = cubic();
    let system = HbmSystem::new(HarmonicLayout::new(5, 32).unwrap(), &model, &force).unwrap();
    let path_system = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let mut opts = ContinuationOptions::new(0.5, 2.0, 0.01);
    opts.max_step = Some(0.02);
    let path = trace(&path_system, &opts, &mut |_| {}).unwrap();
    assert_eq!(path.end, PathEnd::ReachedEnd);
    assert_eq!(fold_frequencies(&path.points).len(), 2);
    let responses: Vec<_> = path
        .points
        .iter()
        .map(|p| {
            output_response(&system, &p.x, p.parameter, 1.0, &ResponseOptions::default()).unwrap()
        })
        .collect();
    let peak = responses.iter().map(|r| r.amplitude[0]).fold(0.0, f64::max);
    let a_max = analytic_peak();
    assert!(
        (peak - a_max).abs() <= 0.02 * a_max,
        "peak {peak} vs HB-1 {a_max}"
    );
    let h3 = responses
        .iter()
        .map(|r| r.harmonics[0][3].norm())
        .fold(0.0, f64::max);
    assert!(h3 > 1e-3 * peak && h3 < 0.1 * peak, "third harmonic {h3}");
}

/// Level continuation of a linear system at fixed ω: the response is proportional to the level.
#[test]
fn level_continuation_of_a_linear_system_is_proportional() {
    let (k, m, c) = chain4();
    let model = LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        Some(c.as_ref()),
        &[0.0, 1.0, 0.0, 0.0],
        vec![0, 3],
        vec![1],
        2,
    )
    .unwrap();
    let springs = PolynomialSprings {
        k1: vec![0.5, 0.5],
        k3: vec![0.0, 0.0],
    };
    let system = HbmSystem::new(HarmonicLayout::new(2, 8).unwrap(), &model, &springs).unwrap();
    let omega = 0.77;
    let level_path = FixedFrequencyPath {
        system: &system,
        omega,
        parameter: FixedFrequencyParameter::Level,
    };
    let path = trace(
        &level_path,
        &ContinuationOptions::new(0.5, 3.0, 0.1),
        &mut |_| {},
    )
    .unwrap();
    assert_eq!(path.end, PathEnd::ReachedEnd);
    let unit = output_response(
        &system,
        &path.points[0].x,
        omega,
        0.5,
        &ResponseOptions::default(),
    )
    .unwrap()
    .amplitude[0]
        / 0.5;
    for p in &path.points {
        let a = output_response(
            &system,
            &p.x,
            omega,
            p.parameter,
            &ResponseOptions::default(),
        )
        .unwrap()
        .amplitude[0];
        assert!((a - unit * p.parameter).abs() <= 1e-9 * unit * p.parameter);
    }
    assert!((path.points.last().unwrap().parameter - 3.0).abs() < 1e-12);
}

/// r(x, λ) = x − λ whose evaluation fails for λ > 1.2: the path stops with a failure naming the
/// last converged parameter, keeping every point before it, after halving the step.
struct FailsBeyond;

impl ParameterSystem for FailsBeyond {
    type State = ();
    fn dim(&self) -> usize {
        1
    }
    fn residual_scale(&self) -> f64 {
        1.0
    }
    fn initial_state(&self) {}
    fn evaluate(&self, x: &[f64], lambda: f64, _: &(), out: &mut Linearization) -> Result<()> {
        if lambda > 1.2 {
            return Err(Error::Compute("contact state did not converge".into()));
        }
        out.residual[0] = x[0] - lambda;
        out.jacobian[(0, 0)] = 1.0;
        out.d_parameter[0] = -1.0;
        Ok(())
    }
}

#[test]
fn failed_corrector_is_reported_with_the_points_kept() {
    let path = trace(
        &FailsBeyond,
        &ContinuationOptions::new(1.0, 2.0, 0.05),
        &mut |_| {},
    )
    .unwrap();
    let PathEnd::Failed(msg) = &path.end else {
        panic!("expected a failure, got {:?}", path.end)
    };
    let last = path.points.last().unwrap();
    assert!(
        last.parameter <= 1.2 && last.parameter > 1.19,
        "last {}",
        last.parameter
    );
    assert!(msg.contains("contact state did not converge"), "{msg}");
    assert!(msg.contains("minimum step"), "{msg}");
    assert!(path.retries >= 5);
    // the points are consecutive: no gap larger than the initial step
    assert!(path
        .points
        .windows(2)
        .all(|w| w[1].parameter - w[0].parameter <= 0.05 * 2.0 + 1e-12));
    // a start that cannot be solved is an error
    let e = trace(
        &FailsBeyond,
        &ContinuationOptions::new(1.5, 2.0, 0.05),
        &mut |_| {},
    )
    .err()
    .unwrap();
    assert!(e.to_string().contains("start point"), "{e}");
}

/// The unit circle (x − 1)² + λ² = 1 traced from λ = 0.6 upwards: it turns at λ = 1 and comes back.
/// With a floor at λ = 0.3 the path ends (left the range) before reaching it, every point kept
/// above it; without it, the path runs on until the range rule (start − ½ range = 0.1).
struct Circle;

impl ParameterSystem for Circle {
    type State = ();
    fn dim(&self) -> usize {
        1
    }
    fn residual_scale(&self) -> f64 {
        1.0
    }
    fn initial_state(&self) {}
    fn evaluate(&self, x: &[f64], lambda: f64, _: &(), out: &mut Linearization) -> Result<()> {
        out.residual[0] = (x[0] - 1.0).powi(2) + lambda * lambda - 1.0;
        out.jacobian[(0, 0)] = 2.0 * (x[0] - 1.0);
        out.d_parameter[0] = 2.0 * lambda;
        Ok(())
    }
}

#[test]
fn a_path_that_reaches_the_parameter_floor_ends_there() {
    let mut opts = ContinuationOptions::new(0.6, 1.6, 0.02);
    let free = trace(&Circle, &opts, &mut |_| {}).unwrap();
    assert_eq!(free.end, PathEnd::LeftRange);
    let lowest = free.points.last().unwrap().parameter;
    assert!(lowest < 0.1, "without a floor the path ends at {lowest}");
    opts.floor = Some(0.3);
    let bounded = trace(&Circle, &opts, &mut |_| {}).unwrap();
    assert_eq!(bounded.end, PathEnd::LeftRange);
    let last = bounded.points.last().unwrap();
    assert!(bounded.points.iter().all(|p| p.parameter > 0.3));
    assert!(last.parameter < 0.35, "last point at {}", last.parameter);
    // the turning point at λ = 1 was passed: x − 1 changed sign
    assert!((last.x[0] - 1.0) * (bounded.points[0].x[0] - 1.0) < 0.0);
}

/// A downward sweep started on the lower branch inside the bistable range: the path folds at the
/// lower fold ω₋, runs back up the middle branch past the start by more than half the range and
/// leaves it. The sweep jumps from ω₋ one initial step down to the upper branch, the only
/// solution there, and reaches the end. Checked against the HB-1 relation: the jump's origin at
/// the analytic fold frequency (2e-3), every point on the curve (1e-6), the point after the
/// jump on the upper branch. With `max_jumps = 0` the same sweep ends where it left the range.
#[test]
fn a_sweep_that_leaves_its_range_jumps_at_the_fold() {
    let model = duffing_model(1);
    let force = cubic();
    let system = HbmSystem::new(HarmonicLayout::new(1, 8).unwrap(), &model, &force).unwrap();
    let mut opts = ContinuationOptions::new(1.2, 1.0, 0.01);
    opts.max_step = Some(0.005);
    let frf = frequency_response(&system, &opts, &ResponseOptions::default(), &mut |_| {}).unwrap();
    assert_eq!(frf.end, PathEnd::ReachedEnd);
    assert_eq!(frf.jumps.len(), 1, "jumps {:?}", frf.jumps);
    let jump = frf.jumps[0];
    let (_, w_min) = analytic_folds();
    assert!(
        (jump.from - w_min).abs() <= 2e-3 * w_min,
        "jump from {} vs the fold {w_min}",
        jump.from
    );
    assert!((jump.to - (jump.from - 0.01)).abs() <= 1e-12);
    // before the jump the path ran back up the middle branch beyond the start
    assert!(frf.points[..jump.point].iter().any(|p| p.omega > 1.3));
    for p in &frf.points {
        let r = hb1_residual(p.omega, p.response.amplitude[0]);
        assert!(r.abs() <= 1e-6, "ω = {}: relation residual {r:e}", p.omega);
    }
    let landed = &frf.points[jump.point];
    assert!((landed.omega - jump.to).abs() <= 1e-12);
    // the upper branch (the single real root of the relation at ω = 1.1236 is A = 0.9654)
    assert!(
        landed.response.amplitude[0] > 0.9,
        "{}",
        landed.response.amplitude[0]
    );
    assert!((frf.points.last().unwrap().omega - 1.0).abs() <= 1e-12);

    opts.max_jumps = 0;
    let stopped =
        frequency_response(&system, &opts, &ResponseOptions::default(), &mut |_| {}).unwrap();
    assert_eq!(stopped.end, PathEnd::LeftRange);
    assert!(stopped.jumps.is_empty());
    assert_eq!(stopped.points.len(), jump.point);
}
