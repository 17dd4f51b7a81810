//! A frequency response: the continuation of an [`HbmSystem`] in ω with the output DOFs'
//! response recovered at every point, and the continuation settings of a case's
//! `[continuation]` table.

use super::newton::NewtonOptions;
use super::response::{output_response, OutputResponse, ResponseOptions};
use super::stability::is_stable;
use super::system::{FrequencyPath, HbmSystem};
use crate::case::Case;
use crate::continuation::{trace, ContinuationOptions, PathEnd, PathPoint};
use crate::error::{Error, Result};
use crate::harmonics::HarmonicForce;

/// One point of a frequency response.
#[derive(Clone, Debug)]
pub struct FrfPoint<S> {
    /// Excitation frequency ω (rad/s).
    pub omega: f64,
    /// The output DOFs' harmonics, amplitude and peak.
    pub response: OutputResponse,
    /// Arc length from the start (scaled variables).
    pub arc_length: f64,
    /// Newton iterations of the point.
    pub iterations: usize,
    /// The condensed harmonic vector Q_N (real layout).
    pub q: Vec<f64>,
    /// The nonlinear force's memory at the point.
    pub state: S,
    /// Stable by Hill's method ([`super::stability::is_stable`]); `None` unless
    /// `ResponseOptions::stability` asked for it.
    pub stable: Option<bool>,
}

/// A traced frequency response.
#[derive(Clone, Debug)]
pub struct Frf<S> {
    /// Points in path order.
    pub points: Vec<FrfPoint<S>>,
    /// How the path ended ([`PathEnd::Failed`] keeps the points converged before the failure).
    pub end: PathEnd,
    /// Steps rejected and retried with half the step.
    pub retries: usize,
}

/// Traces the frequency response of `system` (excitation level 1) and recovers the outputs.
/// `on_point` sees every converged point (for progress).
pub fn frequency_response<F: HarmonicForce>(
    system: &HbmSystem<'_, F>,
    opts: &ContinuationOptions,
    response: &ResponseOptions,
    on_point: &mut dyn FnMut(&PathPoint<F::State>),
) -> Result<Frf<F::State>> {
    if opts.start <= 0.0 || opts.end <= 0.0 {
        return Err(Error::input(format!(
            "the frequency range {} .. {} rad/s must lie above zero (both ends > 0); the response at ω ≤ 0 is not a forced vibration",
            opts.start, opts.end
        )));
    }
    let fp = FrequencyPath { system, level: 1.0 };
    let path = trace(&fp, opts, on_point)?;
    let points = path
        .points
        .into_iter()
        .map(|p| {
            let stable = if response.stability {
                Some(is_stable(system, &p.x, p.parameter, &p.state)?)
            } else {
                None
            };
            Ok(FrfPoint {
                stable,
                omega: p.parameter,
                response: output_response(system, &p.x, p.parameter, 1.0, response)?,
                arc_length: p.arc_length,
                iterations: p.iterations,
                q: p.x,
                state: p.state,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Frf {
        points,
        end: path.end,
        retries: path.retries,
    })
}

/// The continuation settings of a case's `[continuation]` table (rad/s).
pub fn case_continuation(case: &Case) -> Result<ContinuationOptions> {
    let c = case.continuation.as_ref().ok_or_else(|| {
        Error::input(format!(
            "{}: key 'continuation': a forced response needs `[continuation] start_hz, end_hz, step_hz` (or the _rad_s keys)",
            case.path.display()
        ))
    })?;
    let (start, end, step) = c.omega_range();
    let (min_step, max_step) = c.step_bounds_rad_s();
    let mut opts = ContinuationOptions::new(start, end, step);
    opts.min_step = min_step;
    opts.max_step = max_step;
    if let Some(n) = c.max_points {
        opts.max_points = n;
    }
    opts.newton = NewtonOptions {
        tolerance: c.tolerance.unwrap_or(opts.newton.tolerance),
        max_iterations: c.max_iterations.unwrap_or(opts.newton.max_iterations),
        ..opts.newton
    };
    Ok(opts)
}
