//! The solver settings of a case: the [`ContinuationOptions`] of its `[continuation]` table.

use crate::case::{Case, LinearSolverKey};
use crate::continuation::ContinuationOptions;
use crate::error::{Error, Result};
use crate::nonlinear::{NewtonOptions, SolverChoice};

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
    if let Some(n) = c.max_jumps {
        opts.max_jumps = n;
    }
    opts.newton = NewtonOptions {
        tolerance: c.tolerance.unwrap_or(opts.newton.tolerance),
        max_iterations: c.max_iterations.unwrap_or(opts.newton.max_iterations),
        linear_solver: match case.harmonic_balance.linear_solver {
            LinearSolverKey::Auto => SolverChoice::Auto,
            LinearSolverKey::Dense => SolverChoice::Dense,
            LinearSolverKey::Structured => SolverChoice::Structured,
        },
        ..opts.newton
    };
    Ok(opts)
}
