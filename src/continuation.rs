//! Pseudo-arc-length continuation of the solutions of r(x, λ) = 0 (a [`ParameterSystem`]):
//! frequency responses (λ = ω) through resonances, stick–slip transitions and folds, or responses
//! to a varying excitation level at fixed ω.
//!
//! Method (`docs/theory.md`, "Continuation"; folds as in the microslip paper,
//! Cigeroglu, An & Menq 2007, §4.2):
//! - variables scaled, u = x / x_s (x_s = the largest ‖x‖₂ on the path so far, starting from the
//!   start point's) and μ = λ / λ_s (λ_s = |λ_end − λ_start|); arc length s measured in (u, μ);
//! - start: Newton at λ_start from x = 0, whose first step solves the linearised (for friction:
//!   stuck) system — the linear solution ([`trace`]); or a start solved otherwise
//!   ([`trace_from`]: a frequency response whose start Newton misses gets it by a continuation in
//!   the excitation level, `hbm::frf`);
//! - tangent predictor: t solves [∂r/∂u  ∂r/∂μ; t_prevᵀ] t = [0; 1], normalised, so that
//!   t · t_prev > 0: the orientation is carried over and folds (where dλ/ds changes sign) are
//!   passed; the orientation σ = sign det [∂r/∂u ∂r/∂μ; tᵀ] is kept with it (Allgower &
//!   Georg 1990, §2.1);
//! - corrector: Newton on the bordered system r(x, λ) = 0, t · (y − y_pred) = 0 (the
//!   hyperplane through the predicted point, orthogonal to the tangent); a corrected point
//!   farther than one step from the prediction is rejected (a jump to another branch) — except
//!   at the minimum step, where up to one initial step is accepted: the offset of the corrected
//!   point is step · tan θ at a corner turning by θ, independent of the step, so smaller steps
//!   cannot help there (a non-smooth point of contact: stick, slip or separation setting in
//!   within one AFT sample), and a segment shorter than the initial step is not skipped; above
//!   the minimum step, so is a point whose parameter lies behind the current one while the
//!   tangents at both ends point forward in it (a jump back to an earlier part of the path,
//!   which passes within one step of the later part past a resonance of high amplitude);
//! - corners: the sampled friction law is piecewise linear in the harmonics, so the path is a
//!   chain of straight segments. Where it turns by more than 60° (only accepted at the minimum
//!   step) the new tangent takes the orientation σ rather than the angle to the old one, so a
//!   fold sharper than 90° is followed instead of reversed; where the corrector fails even at
//!   the minimum step, the corner step (see `corner_step`) fixes one coordinate at a time,
//!   ahead along the secant of the last two points;
//! - step: s ← s · clamp(n_target / n_iter, ½, 2) after a converged point; on a failed
//!   corrector, a tangent turning by more than 60°, or an orientation σ that changed within the
//!   step, the step is halved and the point retried (never skipped). A change of σ above the
//!   minimum step means the angle rule was fooled: the path folded back within the step (the
//!   corrected point lies on the returning segment, its tangent oriented by angle points the
//!   wrong way) — left alone, the path runs back over itself. At the minimum step a change of σ
//!   is a branch point of the path, passed straight on. Below the minimum step the kink and
//!   corner steps are tried, and when they fail too the path stops with a reported failure and
//!   the points converged so far, each with its accepted residual;
//! - end: the first point beyond λ_end is replaced by the solution at exactly λ_end; a path that
//!   turns back by more than half the range, or reaches [`ContinuationOptions::floor`] (ω = 0
//!   for a frequency response), has left the range.

use crate::error::{Error, Result};
use crate::nonlinear::{
    linsolve, newton_core, norm, solve_fixed, Factored, Iterate, Jacobian, LinearSolver,
    Linearization, NewtonOptions, NewtonOutcome, NewtonSolution, ParameterSystem,
};

/// Continuation settings (parameter values in the parameter's unit, e.g. rad/s).
#[derive(Clone, Debug, PartialEq)]
pub struct ContinuationOptions {
    /// First parameter value λ_start.
    pub start: f64,
    /// Last parameter value λ_end (the path may run downwards).
    pub end: f64,
    /// Initial step in λ (> 0): the first predictor moves λ by about this much.
    pub initial_step: f64,
    /// Smallest step in λ units of arc length; `None`: initial step / 1000.
    pub min_step: Option<f64>,
    /// Largest step in λ units of arc length; `None`: |λ_end − λ_start| / 20 (at least the
    /// initial step).
    pub max_step: Option<f64>,
    /// Most points on the path.
    pub max_points: usize,
    /// Newton iterations per point the step adaptation aims at.
    pub target_iterations: usize,
    /// Newton settings of the start point and the corrector.
    pub newton: NewtonOptions,
    /// A bound the parameter cannot reach: a point at or beyond it ends the path with
    /// [`PathEnd::LeftRange`] (a frequency response stops at ω ≤ 0, where the harmonic balance
    /// has no physical meaning). `None`: no bound besides the range rule.
    pub floor: Option<f64>,
    /// Most jumps of a frequency sweep whose path cannot be followed to the end of its range
    /// (`hbm::frf::frequency_response`: it left the range on the start side, closed on itself,
    /// grew without bound or stalled; or no start point was found); 0: the response ends there.
    /// Not used by [`trace`].
    pub max_jumps: usize,
}

impl ContinuationOptions {
    /// Defaults for the range `start..end` with an initial step.
    pub fn new(start: f64, end: f64, initial_step: f64) -> ContinuationOptions {
        ContinuationOptions {
            start,
            end,
            initial_step,
            min_step: None,
            max_step: None,
            max_points: 20_000,
            target_iterations: 4,
            newton: NewtonOptions::default(),
            floor: None,
            max_jumps: 16,
        }
    }

    /// Checks the settings: finite start ≠ end, a step > 0, at least one point and one target
    /// iteration ([`Error::Input`] otherwise).
    pub fn validate(&self) -> Result<()> {
        let finite = [self.start, self.end, self.initial_step]
            .iter()
            .all(|v| v.is_finite());
        if !finite || self.start == self.end || self.initial_step <= 0.0 {
            return Err(Error::input(format!(
                "continuation: the range {} .. {} with step {} is invalid (need finite start ≠ end and a step > 0)",
                self.start, self.end, self.initial_step
            )));
        }
        if self.max_points == 0 || self.target_iterations == 0 {
            return Err(Error::input(
                "continuation: max_points and target_iterations must be ≥ 1",
            ));
        }
        Ok(())
    }
}

/// One converged point of the path.
#[derive(Clone, Debug)]
pub struct PathPoint<S> {
    /// The unknowns x (the harmonic vector of the condensed DOFs).
    pub x: Vec<f64>,
    /// The parameter λ (ω in rad/s for a frequency response).
    pub parameter: f64,
    /// Arc length from the start, in the scaled variables.
    pub arc_length: f64,
    /// Newton iterations of this point.
    pub iterations: usize,
    /// dλ/ds of the unit tangent (scaled): its sign changes at a fold.
    pub tangent_parameter: f64,
    /// The accepted scaled residual ‖r‖₂ / residual scale (≤ the Newton tolerance).
    pub residual: f64,
    /// The force memory at the end of the converged period.
    pub state: S,
}

/// Why the path ended.
#[derive(Clone, Debug, PartialEq)]
pub enum PathEnd {
    /// The end parameter value was reached (the last point is at exactly λ_end).
    ReachedEnd,
    /// `max_points` points were computed first.
    MaxPoints,
    /// The path turned back and left the range on the start side (or reached the parameter's
    /// bound, [`ContinuationOptions::floor`]).
    LeftRange,
    /// The corrector failed at the minimum step; the message says where and why.
    Failed(String),
    /// The path came back onto itself, going the same way: it runs round a closed loop
    /// (`LoopWatch`) and would never reach the end.
    Closed,
}

/// A traced path: the converged points in path order and how it ended.
#[derive(Clone, Debug)]
pub struct Path<S> {
    /// Points in path order (λ goes back and forth at folds).
    pub points: Vec<PathPoint<S>>,
    /// How the path ended.
    pub end: PathEnd,
    /// Steps that were rejected and retried with half the step.
    pub retries: usize,
    /// Points found by the corner step (see [`trace_from`]) after the corrector failed at the
    /// minimum step.
    pub corner_steps: usize,
}

/// Scaling of the unknowns and the parameter.
#[derive(Clone, Copy, Debug)]
struct Scales {
    x: f64,
    lambda: f64,
    residual: f64,
}

/// Traces the path of `system` from `opts.start` to `opts.end`, the start point solved by Newton
/// from x = 0 (whose first step is the linear solution). `on_point` is called for every
/// converged point (progress reports). Fails only when the start point does not converge.
pub fn trace<S: ParameterSystem>(
    system: &S,
    opts: &ContinuationOptions,
    on_point: &mut dyn FnMut(&PathPoint<S::State>),
) -> Result<Path<S::State>> {
    opts.validate()?;
    let state0 = system.initial_state();
    let x0 = vec![0.0; system.dim()];
    let start = solve_fixed(system, &x0, opts.start, &state0, &opts.newton).map_err(|f| {
        Error::Compute(format!(
            "the start point at parameter {} did not converge from the linear solution: {} — try another start value, a smaller excitation or more damping",
            opts.start, f.message
        ))
    })?;
    trace_from(system, opts, start, on_point)
}

/// As [`trace`] from a start point already solved at `opts.start` (its linearization must be
/// that of `system`: ∂r/∂λ is the tangent's parameter column).
pub fn trace_from<S: ParameterSystem>(
    system: &S,
    opts: &ContinuationOptions,
    mut start: NewtonSolution<S::State>,
    on_point: &mut dyn FnMut(&PathPoint<S::State>),
) -> Result<Path<S::State>> {
    opts.validate()?;
    if start.x.len() != system.dim() || start.parameter != opts.start {
        return Err(Error::input(format!(
            "continuation: the start point has {} unknowns at parameter {}; the system has {} and the path starts at {}",
            start.x.len(),
            start.parameter,
            system.dim(),
            opts.start
        )));
    }
    let range = (opts.end - opts.start).abs();
    let direction = (opts.end - opts.start).signum();
    let x_norm = norm(&start.x);
    let mut scales = Scales {
        x: if x_norm > 0.0 { x_norm } else { 1.0 },
        lambda: range,
        residual: system.residual_scale(),
    };
    let solver = LinearSolver::new(system.jacobian_blocks(), opts.newton.linear_solver);
    let first = initial_tangent(&mut start.linearization, &scales, direction, &solver).ok_or_else(
        || {
            Error::Compute(format!(
            "the Jacobian at the start point (parameter {}) is singular; try another start value",
            opts.start
        ))
        },
    )?;
    let mut orientation = first.orientation;
    // the factors of the current point's tangent system: the next corrector starts on them
    let mut carried = first.factors;
    let mut tangent = first.t;
    let mut step = opts.initial_step / range / tangent[tangent.len() - 1].abs().max(1e-3);
    let min_step = opts.min_step.map_or(step / 1000.0, |m| m / range);
    let max_step = opts
        .max_step
        .map_or((step).max(1.0 / 20.0), |m| m / range)
        .max(min_step);
    step = step.clamp(min_step, max_step);
    let initial_step = step;
    let mut path = Path {
        points: vec![],
        end: PathEnd::MaxPoints,
        retries: 0,
        corner_steps: 0,
    };
    let mut current = point_from(start, 0.0, tangent[tangent.len() - 1]);
    on_point(&current);
    path.points.push(current.clone());
    let mut watch = LoopWatch::default();
    while path.points.len() < opts.max_points {
        let y = scaled(&current, &scales);
        let predicted: Vec<f64> = y.iter().zip(&tangent).map(|(y, t)| y + step * t).collect();
        // the corrector's largest offset from the prediction in steps: one, or at the minimum
        // step (a corner) one initial step
        let at_min = step <= 2.0 * min_step;
        let allowance = if at_min {
            (initial_step / step).max(1.0)
        } else {
            1.0
        };
        let outcome = correct(
            system,
            &current.state,
            &predicted,
            &tangent,
            (step, allowance),
            &scales,
            opts,
            &solver,
            // moved, so that the new point's factors replace them without both held; a
            // retried step factorises again
            carried.take(),
        );
        let (sol, mut new_tangent, length) = match outcome {
            // a forward turn by less than 60° that keeps the orientation σ; at the minimum
            // step σ may change (a branch point, passed straight on)
            Ok((sol, Some(t)))
                if dot(&t.t, &tangent) >= 0.5 && (t.orientation == orientation || at_min) =>
            {
                (sol, t, step)
            }
            // a sharp turn at the minimum step: a corner of the piecewise-linear path, the
            // forward direction from the orientation (at a fold of more than 90° the new
            // tangent points back against the old one)
            Ok((sol, Some(t))) if at_min => (sol, t.oriented(orientation), step),
            other => {
                let why = match other {
                    Err(f) => f,
                    Ok((_, None)) => "singular bordered Jacobian at the corrected point".into(),
                    Ok((_, Some(t))) if dot(&t.t, &tangent) >= 0.5 => {
                        "the orientation of the path changed within the step".into()
                    }
                    Ok(_) => "the tangent turned by more than 60°".into(),
                };
                step *= 0.5;
                path.retries += 1;
                if step >= min_step {
                    continue;
                }
                if let Some(t) = shrink_scale(&tangent, &mut scales, norm(&current.x)) {
                    // the scale of a passed resonance made the minimum step large against the
                    // present amplitude: retry from the initial step in the present scale
                    tangent = t;
                    step = initial_step;
                    continue;
                }
                let before = path.points.len().checked_sub(2).map(|i| &path.points[i]);
                let corner = kink_step(
                    system,
                    &current,
                    (&tangent, orientation),
                    &scales,
                    min_step,
                    (opts, &solver),
                )
                .or_else(|| {
                    corner_step(
                        system,
                        (before, &current),
                        (&tangent, orientation),
                        &scales,
                        min_step,
                        (opts, &solver),
                    )
                })
                .or_else(|| {
                    full_step(
                        system,
                        &current,
                        (&tangent, orientation),
                        &scales,
                        min_step,
                        (opts, &solver),
                    )
                });
                let Some(found) = corner else {
                    path.end = PathEnd::Failed(format!(
                        "continuation stopped after the point at parameter {:.9e}: {why} even with the minimum step {:.3e} (λ units), and no corner step converged; the {} points converged so far are kept",
                        current.parameter,
                        min_step * range,
                        path.points.len()
                    ));
                    return Ok(path);
                };
                path.corner_steps += 1;
                step = (2.0 * found.2).clamp(min_step, max_step);
                found
            }
        };
        orientation = new_tangent.orientation;
        carried = new_tangent.factors.take();
        let iterations = sol.iterations;
        let arc = current.arc_length + length;
        let mut next = point_from(sol, arc, new_tangent.t[new_tangent.t.len() - 1]);
        if direction * (next.parameter - opts.end) >= 0.0 {
            // the end point is solved afresh: the factors and the stored matrix are not needed
            drop(carried.take());
            solver.release_storage();
            next = end_point(system, &current, next, opts).unwrap_or_else(|p| p);
            on_point(&next);
            path.points.push(next);
            path.end = PathEnd::ReachedEnd;
            return Ok(path);
        }
        if opts.floor.is_some_and(|f| next.parameter <= f) {
            // the point beyond the bound is not kept
            path.end = PathEnd::LeftRange;
            return Ok(path);
        }
        if direction * (opts.start - next.parameter) > 0.5 * range {
            on_point(&next);
            path.points.push(next);
            path.end = PathEnd::LeftRange;
            return Ok(path);
        }
        on_point(&next);
        path.points.push(next.clone());
        if watch.closes(&path.points, &scales) {
            path.end = PathEnd::Closed;
            return Ok(path);
        }
        current = next;
        tangent = rescale(new_tangent.t, &mut scales, norm(&current.x));
        let factor = (opts.target_iterations as f64 / iterations.max(1) as f64).clamp(0.5, 2.0);
        step = (step * factor).clamp(min_step, max_step);
    }
    Ok(path)
}

/// Detection of a path that runs round a closed loop (Brent's cycle detection, Brent 1980): the
/// point at index 2^j is kept as a mark; a later step (8 or more points on) whose segment passes
/// through the mark — within 1e-3 of the segment's length, in the current scales — going the
/// same way as the mark's own step (cosine > 0.9) closes the loop. The sampled friction law is
/// piecewise linear, so a path round a loop passes through its earlier points, not merely near
/// them. It can hold closed loops of solutions; a path that reaches one through a branch point
/// of the law circles it for ever.
#[derive(Default)]
struct LoopWatch {
    /// The mark: its index in the path, its (x, λ) and its last step (unscaled).
    mark: Option<(usize, Vec<f64>, Vec<f64>)>,
}

impl LoopWatch {
    /// Whether the last point of `points` closes a loop; moves the mark to it at powers of two.
    fn closes<T>(&mut self, points: &[PathPoint<T>], s: &Scales) -> bool {
        let n = points.len();
        if n < 2 {
            return false;
        }
        let (prev, last) = (unscaled(&points[n - 2]), unscaled(&points[n - 1]));
        let step = difference(&last, &prev);
        let closed = self.mark.as_ref().is_some_and(|(at, mark, mark_step)| {
            // the mark relative to the point before the last, and the last step, scaled
            let (m, d) = (
                scaled_difference(&difference(mark, &prev), s),
                scaled_difference(&step, s),
            );
            let length = norm(&d);
            if n - 1 < at + 8 || length == 0.0 {
                return false;
            }
            // the mark's distance from the last step's segment
            let along = (dot(&m, &d) / (length * length)).clamp(0.0, 1.0);
            let off: Vec<f64> = m.iter().zip(&d).map(|(m, d)| m - along * d).collect();
            let unit: Vec<f64> = d.iter().map(|v| v / length).collect();
            let same_way = dot(&unit, &scaled_unit(mark_step, s)) > 0.9;
            norm(&off) <= 1e-3 * length && same_way
        });
        if n.is_power_of_two() {
            self.mark = Some((n - 1, last, step));
        }
        closed
    }
}

/// (x, λ) of a path point, unscaled.
fn unscaled<T>(p: &PathPoint<T>) -> Vec<f64> {
    p.x.iter()
        .copied()
        .chain(std::iter::once(p.parameter))
        .collect()
}

/// a − b.
fn difference(a: &[f64], b: &[f64]) -> Vec<f64> {
    a.iter().zip(b).map(|(p, q)| p - q).collect()
}

/// The unit vector of an unscaled difference in the scaled variables (zero for a zero one).
fn scaled_unit(d: &[f64], s: &Scales) -> Vec<f64> {
    let v = scaled_difference(d, s);
    let len = norm(&v);
    if len > 0.0 {
        v.iter().map(|a| a / len).collect()
    } else {
        v
    }
}

/// (Δx / x_s, Δλ / λ_s).
fn scaled_difference(d: &[f64], s: &Scales) -> Vec<f64> {
    let last = d.len() - 1;
    d.iter()
        .enumerate()
        .map(|(i, v)| if i == last { v / s.lambda } else { v / s.x })
        .collect()
}

/// The point at exactly λ_end, by Newton at fixed λ from the linear interpolation between the
/// last point before the end and the first beyond it. `Err(beyond)` if that fails.
fn end_point<S: ParameterSystem>(
    system: &S,
    before: &PathPoint<S::State>,
    beyond: PathPoint<S::State>,
    opts: &ContinuationOptions,
) -> std::result::Result<PathPoint<S::State>, PathPoint<S::State>> {
    let span = beyond.parameter - before.parameter;
    let w = if span != 0.0 {
        ((opts.end - before.parameter) / span).clamp(0.0, 1.0)
    } else {
        1.0
    };
    let guess: Vec<f64> = before
        .x
        .iter()
        .zip(&beyond.x)
        .map(|(a, b)| a + w * (b - a))
        .collect();
    match solve_fixed(system, &guess, opts.end, &before.state, &opts.newton) {
        Ok(sol) => {
            let arc = before.arc_length + w * (beyond.arc_length - before.arc_length);
            Ok(point_from(sol, arc, beyond.tangent_parameter))
        }
        Err(_) => Err(beyond),
    }
}

fn point_from<T>(sol: NewtonSolution<T>, arc_length: f64, tangent_parameter: f64) -> PathPoint<T> {
    PathPoint {
        x: sol.x,
        parameter: sol.parameter,
        arc_length,
        iterations: sol.iterations,
        tangent_parameter,
        residual: sol.residual,
        state: sol.state,
    }
}

/// Raises the unknowns' scale x_s to ‖x‖ when the path has grown beyond it (so that the arc
/// length keeps weighing amplitude and parameter alike through a resonance) and converts the
/// unit tangent to the new scale.
fn rescale(tangent: Vec<f64>, scales: &mut Scales, x_norm: f64) -> Vec<f64> {
    if x_norm <= scales.x {
        return tangent;
    }
    to_scale(&tangent, scales, x_norm)
}

/// Lowers the unknowns' scale x_s to ‖x‖ when it exceeds ‖x‖ by more than
/// [`SHRINK_RATIO`], returning the tangent in the new scale; `None` otherwise.
///
/// x_s only grows along a path ([`rescale`]): past a resonance of high amplitude it stays at
/// the peak, and the minimum step, a length in units of x_s, can then move x by more than
/// the present amplitude. A strongly curved stretch of the path beyond the resonance cannot
/// be followed at such a step, so this is tried once the step has fallen below its minimum.
fn shrink_scale(tangent: &[f64], scales: &mut Scales, x_norm: f64) -> Option<Vec<f64>> {
    if x_norm > 0.0 && scales.x > SHRINK_RATIO * x_norm {
        Some(to_scale(tangent, scales, x_norm))
    } else {
        None
    }
}

/// The ratio x_s / ‖x‖ above which a stalled path lowers x_s ([`shrink_scale`]).
const SHRINK_RATIO: f64 = 4.0;

/// Sets x_s to `x_scale` and converts the unit tangent in (u, μ) = (x / x_s, λ / λ_s) to it:
/// the same direction in (x, λ), normalised again.
fn to_scale(tangent: &[f64], scales: &mut Scales, x_scale: f64) -> Vec<f64> {
    let ratio = scales.x / x_scale;
    scales.x = x_scale;
    let n = tangent.len() - 1;
    let t: Vec<f64> = tangent
        .iter()
        .enumerate()
        .map(|(i, v)| if i < n { v * ratio } else { *v })
        .collect();
    let len = norm(&t);
    t.iter().map(|v| v / len).collect()
}

/// (u, μ) = (x / x_s, λ / λ_s) of a path point.
fn scaled<T>(p: &PathPoint<T>, s: &Scales) -> Vec<f64> {
    scaled_xy(&p.x, p.parameter, s)
}

/// (u, μ) = (x / x_s, λ / λ_s) for the unknowns `x` and the parameter λ.
fn scaled_xy(x: &[f64], parameter: f64, s: &Scales) -> Vec<f64> {
    let mut y: Vec<f64> = x.iter().map(|x| x / s.x).collect();
    y.push(parameter / s.lambda);
    y
}

/// The scaled Jacobian [∂r/∂u  ∂r/∂μ] / r_s (`jacobian` = ∂r/∂x, `d_parameter` = ∂r/∂λ) as
/// the first `dim` rows of a (dim+1)² matrix whose last row is `border`, stored as `jacobian`
/// is (block-stored: scaled in place, with the border; dense: in a matrix of `solver`'s, to
/// which `jacobian` is handed back, [`LinearSolver::recycle`]).
fn bordered(
    jacobian: Jacobian,
    d_parameter: &[f64],
    s: &Scales,
    border: &[f64],
    solver: &LinearSolver,
) -> Jacobian {
    let n = d_parameter.len();
    let cx = s.x / s.residual;
    let cl = s.lambda / s.residual;
    match jacobian {
        Jacobian::Dense(j) => {
            let mut a = solver.dense_matrix(n + 1, n + 1);
            for k in 0..n {
                for i in 0..n {
                    a[(i, k)] = j[(i, k)] * cx;
                }
            }
            for i in 0..n {
                a[(i, n)] = d_parameter[i] * cl;
            }
            for (k, b) in border.iter().enumerate() {
                a[(n, k)] = *b;
            }
            solver.recycle(Jacobian::Dense(j));
            Jacobian::Dense(a)
        }
        Jacobian::Blocks(mut b) => {
            b.scale(cx);
            let column = d_parameter
                .iter()
                .map(|d| d * cl)
                .chain(std::iter::once(border[n]))
                .collect();
            b.set_border(column, border[..n].to_vec());
            Jacobian::Blocks(b)
        }
    }
}

/// A bordered matrix of [`bordered`] with its last row replaced by `border`.
fn rebordered(matrix: Jacobian, border: &[f64]) -> Jacobian {
    match matrix {
        Jacobian::Dense(mut a) => {
            let n = a.nrows() - 1;
            for (k, b) in border.iter().enumerate() {
                a[(n, k)] = *b;
            }
            Jacobian::Dense(a)
        }
        Jacobian::Blocks(mut b) => {
            let n = b.inner();
            if let Some((mut column, _)) = b.take_border() {
                column[n] = border[n];
                b.set_border(column, border[..n].to_vec());
            }
            Jacobian::Blocks(b)
        }
    }
}

/// The unit tangent at the start, oriented so that λ moves towards the end (the start's
/// Jacobian is moved out of `lin`).
fn initial_tangent(
    lin: &mut Linearization,
    s: &Scales,
    direction: f64,
    solver: &LinearSolver,
) -> Option<Tangent> {
    let n = lin.residual.len();
    let mut border = vec![0.0; n + 1];
    border[n] = direction;
    let jacobian = std::mem::take(&mut lin.jacobian);
    tangent_of(
        &mut bordered(jacobian, &lin.d_parameter, s, &border, solver),
        solver,
    )
}

/// A unit tangent and its orientation: the sign (±1) of det [∂r/∂u ∂r/∂μ; tᵀ].
///
/// The orientation is constant along a regular path, through folds and across the corners of
/// a piecewise-linear path, however sharp (Allgower & Georg 1990, §2.1 and §12.1): it tells the
/// forward direction where the angle to the previous tangent cannot.
#[derive(Clone)]
struct Tangent {
    t: Vec<f64>,
    orientation: f64,
    /// The factors the tangent was solved on (of its bordered matrix or a nearby one), for the
    /// next corrector to start from.
    factors: Option<Factored>,
}

impl Tangent {
    /// The tangent reversed (its orientation changes sign with it).
    fn reversed(self) -> Tangent {
        Tangent {
            t: self.t.iter().map(|v| -v).collect(),
            orientation: -self.orientation,
            factors: self.factors,
        }
    }

    /// The tangent oriented as `orientation`.
    fn oriented(self, orientation: f64) -> Tangent {
        if self.orientation == orientation {
            self
        } else {
            self.reversed()
        }
    }
}

/// Solves [∂r/∂u ∂r/∂μ; bᵀ] t = [0; 1] (`matrix`, from [`bordered`]) and normalises t (so
/// that t·b > 0). det [J; tᵀ] has the sign of det [J; bᵀ]: with c the cofactor vector of J
/// (J c = 0), det [J; vᵀ] = v · c and t ∥ c / (b · c).
fn tangent_of(matrix: &mut Jacobian, solver: &LinearSolver) -> Option<Tangent> {
    let mut rhs = vec![0.0; matrix.dim()];
    rhs[matrix.dim() - 1] = 1.0;
    let (t, f) = solver.factor_solve(matrix, &rhs)?;
    let sign = f.sign();
    unit_tangent(t, sign, Some(f))
}

/// t / ‖t‖ with its orientation and the factors it was solved on.
fn unit_tangent(t: Vec<f64>, orientation: f64, factors: Option<Factored>) -> Option<Tangent> {
    let len = norm(&t);
    (len > 0.0 && len.is_finite()).then(|| Tangent {
        t: t.iter().map(|v| v / len).collect(),
        orientation,
        factors,
    })
}

/// The corrector from the predicted point; returns the solution and the new tangent (oriented
/// along `tangent`).
///
/// The corrected point must lie within `allowance` steps of the prediction (`(step,
/// allowance)`; see the module documentation): the hyperplane
/// t · (y − y_pred) = 0 reaches arbitrarily far, and near a sharp fold (e.g. where contact
/// separation sets in within a few AFT samples) Newton can converge on it to a point of another
/// branch — a jump that would skip the segment in between. Such a point is rejected like a failed
/// corrector (the step is halved). Above the minimum step, so is a point whose parameter lies
/// behind the current one although the tangents at both ends point forward in it: between them
/// the parameter would have to turn twice within one step. This is the jump back to an earlier
/// part of the same path across a resonance of high amplitude, where the unknowns' scale x_s is
/// the peak and the path before and after the resonance pass close to each other in (u, μ).
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn correct<S: ParameterSystem>(
    system: &S,
    state: &S::State,
    predicted: &[f64],
    tangent: &[f64],
    (step, allowance): (f64, f64),
    s: &Scales,
    opts: &ContinuationOptions,
    solver: &LinearSolver,
    initial: Option<Factored>,
) -> std::result::Result<(NewtonSolution<S::State>, Option<Tangent>), String> {
    let done = correct_on(
        system, state, predicted, tangent, tangent, s, opts, solver, initial,
    )?;
    let y = scaled_xy(&done.0.x, done.0.parameter, s);
    let off: Vec<f64> = y.iter().zip(predicted).map(|(a, b)| a - b).collect();
    let last = y.len() - 1;
    let went_back = (y[last] - (predicted[last] - step * tangent[last])) * tangent[last] < 0.0;
    let kept_direction = done
        .1
        .as_ref()
        .is_some_and(|t| t.t[last] * tangent[last] > 0.0);
    if allowance <= 1.0 && went_back && kept_direction {
        Err("the parameter went back within the step although the path's direction in it did not change (a jump to an earlier part of the path)".into())
    } else if norm(&off) <= allowance * step {
        Ok(done)
    } else {
        Err(format!(
            "the corrector moved {:.3e} from the prediction, farther than {:.3e} (towards another branch)",
            norm(&off),
            allowance * step
        ))
    }
}

/// Newton on r(x, λ) = 0, `border` · (y − y_pred) = 0 from the predicted point, its first
/// step on the factors `initial` of a nearby bordered matrix when given ([`newton_core`]); the
/// new tangent is oriented along `tangent`.
#[allow(clippy::type_complexity, clippy::too_many_arguments)]
fn correct_on<S: ParameterSystem>(
    system: &S,
    state: &S::State,
    predicted: &[f64],
    border: &[f64],
    tangent: &[f64],
    s: &Scales,
    opts: &ContinuationOptions,
    solver: &LinearSolver,
    initial: Option<Factored>,
) -> std::result::Result<(NewtonSolution<S::State>, Option<Tangent>), String> {
    let n = system.dim();
    let mut eval = |z: &[f64], with_matrix: bool| -> Result<Iterate<(Linearization, S::State)>> {
        let x: Vec<f64> = z[..n].iter().map(|u| u * s.x).collect();
        let lambda = z[n] * s.lambda;
        let (mut lin, end) = if with_matrix {
            let mut lin = solver.linearization(n);
            let end = system.evaluate(&x, lambda, state, &mut lin)?;
            (lin, end)
        } else {
            let mut residual = vec![0.0; n];
            let end = system.evaluate_residual(&x, lambda, state, &mut residual)?;
            let lin = Linearization {
                residual,
                jacobian: Jacobian::default(),
                d_parameter: Vec::new(),
            };
            (lin, end)
        };
        let mut g: Vec<f64> = lin.residual.iter().map(|r| r / s.residual).collect();
        g.push(dot(
            border,
            &z.iter()
                .zip(predicted)
                .map(|(a, b)| a - b)
                .collect::<Vec<_>>(),
        ));
        let matrix = with_matrix.then(|| {
            let jacobian = std::mem::take(&mut lin.jacobian);
            bordered(jacobian, &lin.d_parameter, s, border, solver)
        });
        Ok(Iterate {
            z: z.to_vec(),
            g,
            matrix,
            g_scale: 1.0,
            extra: (lin, end),
        })
    };
    // a corrector that needs far more iterations than the target is better retried with a
    // smaller step than pushed on
    let newton = NewtonOptions {
        max_iterations: opts.newton.max_iterations.min(3 * opts.target_iterations),
        max_halvings: opts.newton.max_halvings.min(2),
        ..opts.newton
    };
    let NewtonOutcome {
        iterate: it,
        iterations,
        factors,
    } = newton_core(predicted.to_vec(), &mut eval, 1.0, &newton, solver, initial)
        .map_err(|f| f.message)?;
    let residual = norm(&it.g[..n]);
    // the tangent system [G; tangentᵀ] at the solution: the corrector's matrix there with its
    // last row replaced; solved on the factors of the last step's matrix when they are close
    // enough to it (refined to the backward error of a direct solve, or by GMRES on them),
    // factorised otherwise
    let matrix = match it.matrix {
        Some(m) => Some(m),
        None => eval(&it.z, true).ok().and_then(|e| e.matrix),
    };
    let new_tangent = matrix.and_then(|m| {
        let mut m = if border == tangent {
            m
        } else {
            rebordered(m, tangent)
        };
        let mut rhs = vec![0.0; n + 1];
        rhs[n] = 1.0;
        let near = (border == tangent)
            .then(|| {
                solver.solve_near(&factors, &m, &rhs).or_else(|| {
                    // GMRES on the same factors, with the sign of det from its Hessenberg
                    // matrix; a solve that needs many iterations factorises, so that the
                    // next corrector starts on fresh factors
                    solver
                        .reuses_factors(n + 1)
                        .then(|| solver.solve_krylov_signed(&factors, &m, &rhs))
                        .flatten()
                        .filter(|(_, k, _)| *k <= linsolve::KRYLOV_REFRESH)
                        .map(|(t, _, sign)| (t, sign))
                })
            })
            .flatten();
        match near {
            Some((t, sign)) => unit_tangent(t, sign, Some(factors)),
            None => {
                // the new factors replace the old ones, which are dropped first
                drop(factors);
                tangent_of(&mut m, solver)
            }
        }
    });
    let z = it.z;
    let (lin, end) = it.extra;
    let sol = NewtonSolution {
        x: z[..n].iter().map(|u| u * s.x).collect(),
        parameter: z[n] * s.lambda,
        state: end,
        iterations,
        residual,
        linearization: lin,
    };
    Ok((sol, new_tangent))
}

/// The kink step: the next point when the pseudo-arc-length corrector fails even at the minimum
/// step h_min because the path turns sharply at a kink just ahead.
///
/// The sampled friction force is piecewise linear in the harmonics, so the path is piecewise
/// straight in u: on the far side of a kink (a sample changing stick, slip or contact) the path
/// follows the null direction t_B of that facet's Jacobian, oriented by the path's orientation σ
/// (Allgower & Georg 1990, §12.1: sign det [G; tᵀ] is the same on both sides of a facet). At a
/// sharp fold t_B points back against the incoming tangent t, and no hyperplane ahead along t
/// meets the outgoing segment — Newton then cycles between the two facets at any step size.
///
/// The facet beyond is found by linearising g (the scaled residual) at y_p = y_c + s_p t,
/// s_p = 1, 2, 4 h_min. The kink on the incoming line is where that facet's linearisation
/// vanishes best along t: s_c = s_p − (g_p · Gt)/(Gt · Gt), clamped to [0, s_p]; the next
/// point is then sought on the hyperplane through c + h t_B orthogonal to t_B (h = 1, 4,
/// 16 h_min), accepted within h of that prediction and ahead of the current point (its
/// σ-oriented tangent points away from it). Returns as [`corner_step`].
#[allow(clippy::type_complexity)]
fn kink_step<S: ParameterSystem>(
    system: &S,
    current: &PathPoint<S::State>,
    (tangent, orientation): (&[f64], f64),
    s: &Scales,
    min_step: f64,
    (opts, solver): (&ContinuationOptions, &LinearSolver),
) -> Option<(NewtonSolution<S::State>, Tangent, f64)> {
    let n = system.dim();
    let y_c = scaled(current, s);
    for factor in [1.0, 2.0, 4.0] {
        let s_p = factor * min_step;
        let y_p: Vec<f64> = y_c.iter().zip(tangent).map(|(y, t)| y + s_p * t).collect();
        let x: Vec<f64> = y_p[..n].iter().map(|u| u * s.x).collect();
        let mut lin = solver.linearization(n);
        system
            .evaluate(&x, y_p[n] * s.lambda, &current.state, &mut lin)
            .ok()?;
        let along = scaled_jacobian_times(&lin, s, tangent);
        let jacobian = std::mem::take(&mut lin.jacobian);
        let Some(beyond) = tangent_of(
            &mut bordered(jacobian, &lin.d_parameter, s, tangent, solver),
            solver,
        ) else {
            continue;
        };
        let mut beyond = beyond.oriented(orientation);
        // the correctors below factorise afresh
        drop(beyond.factors.take());
        if dot(&beyond.t, tangent) > 0.99 {
            continue;
        }
        let g_p: Vec<f64> = lin.residual.iter().map(|r| r / s.residual).collect();
        let s_c = (s_p - dot(&g_p, &along) / dot(&along, &along)).clamp(0.0, s_p);
        if !s_c.is_finite() {
            continue;
        }
        let corner: Vec<f64> = y_c.iter().zip(tangent).map(|(y, t)| y + s_c * t).collect();
        for h in [1.0, 4.0, 16.0].map(|f| f * min_step) {
            let predicted: Vec<f64> = corner
                .iter()
                .zip(&beyond.t)
                .map(|(c, t)| c + h * t)
                .collect();
            let Ok((sol, Some(t))) = correct_on(
                system,
                &current.state,
                &predicted,
                &beyond.t,
                &beyond.t,
                s,
                opts,
                solver,
                None,
            ) else {
                continue;
            };
            let y = scaled_xy(&sol.x, sol.parameter, s);
            let off: Vec<f64> = y.iter().zip(&predicted).map(|(a, b)| a - b).collect();
            let moved: Vec<f64> = y.iter().zip(&y_c).map(|(a, b)| a - b).collect();
            let t = t.oriented(orientation);
            if dot(&moved, &t.t) > 0.0 && norm(&off) <= h {
                let length = norm(&moved);
                return Some((sol, t, length));
            }
        }
    }
    None
}

/// G v for the scaled Jacobian G = [∂r/∂u ∂r/∂μ] / r_s (the first rows of [`bordered`]).
fn scaled_jacobian_times(lin: &Linearization, s: &Scales, v: &[f64]) -> Vec<f64> {
    let n = lin.residual.len();
    let cx = s.x / s.residual;
    let cl = s.lambda / s.residual;
    let jv = lin.jacobian.mul_vec(&v[..n]);
    (0..n)
        .map(|i| jv[i] * cx + lin.d_parameter[i] * cl * v[n])
        .collect()
}

/// The corner step: the next point when the pseudo-arc-length corrector fails even at the minimum
/// step h_min.
///
/// The sampled friction force is piecewise linear in the harmonics (a stick–slip or separation
/// instant moves by whole AFT samples), so the solution path is a chain of straight segments with
/// corners. At a corner the predictor along the incoming tangent lands off the outgoing segment,
/// and Newton on the hyperplane orthogonal to that tangent can cycle between two facets of the
/// law, neither of whose linearisations has its root inside itself — at any step size. A
/// hyperplane of another orientation crosses the outgoing segment where Newton converges at
/// once. This is the local parametrisation of Rheinboldt (1986): the path is parametrised by
/// one coordinate of y = (u, μ) at a time, fixed at its predicted value,
/// e_k · (y − y_pred) = 0, with y_pred = y_c + h·d along the secant d of the last two points
/// (the unit tangent at the start). The coordinates k are tried in the order of |d_k|, largest
/// first (the coordinate that varies most along the path, so the hyperplane is never tangent to
/// it at a fold), up to three of them, each at h = 1, 4 and 16 h_min.
///
/// A point is accepted only if it lies ahead of the current one — its tangent, oriented as the
/// path, points away from the current point — and within 4h of it (no jump to another
/// branch). Returns the solution, its unit tangent (with the path's orientation,
/// which tells the forward direction also where the path folds back at the corner) and the arc
/// length to it; `None` if no candidate converged.
#[allow(clippy::type_complexity)]
fn corner_step<S: ParameterSystem>(
    system: &S,
    (before, current): (Option<&PathPoint<S::State>>, &PathPoint<S::State>),
    (tangent, orientation): (&[f64], f64),
    s: &Scales,
    min_step: f64,
    (opts, solver): (&ContinuationOptions, &LinearSolver),
) -> Option<(NewtonSolution<S::State>, Tangent, f64)> {
    let y_c = scaled(current, s);
    let secant = before.and_then(|b| {
        let d: Vec<f64> = y_c.iter().zip(scaled(b, s)).map(|(c, b)| c - b).collect();
        let len = norm(&d);
        (len > 0.0 && len.is_finite()).then(|| d.iter().map(|v| v / len).collect::<Vec<f64>>())
    });
    let direction = secant.unwrap_or_else(|| tangent.to_vec());
    let mut order: Vec<usize> = (0..direction.len()).collect();
    order.sort_by(|&a, &b| direction[b].abs().total_cmp(&direction[a].abs()));
    for &k in order.iter().take(3) {
        let mut border = vec![0.0; direction.len()];
        border[k] = 1.0;
        for factor in [1.0, 4.0, 16.0] {
            let h = factor * min_step;
            let predicted: Vec<f64> = y_c.iter().zip(&direction).map(|(y, d)| y + h * d).collect();
            let Ok((sol, Some(t))) = correct_on(
                system,
                &current.state,
                &predicted,
                &border,
                &direction,
                s,
                opts,
                solver,
                None,
            ) else {
                continue;
            };
            let y = scaled_xy(&sol.x, sol.parameter, s);
            let moved: Vec<f64> = y.iter().zip(&y_c).map(|(a, b)| a - b).collect();
            let length = norm(&moved);
            let t = t.oriented(orientation);
            // ahead of the current point: the path leaves it towards the candidate, whose
            // oriented tangent points away from it (a point of the incoming segment has its
            // tangent pointing back at the current point)
            if dot(&moved, &t.t) > 0.0 && length <= 4.0 * h {
                return Some((sol, t, length));
            }
        }
    }
    None
}

/// The full-step corrector: the next point when the damped corrector, the kink step and the
/// corner step all fail at the minimum step h_min.
///
/// On a piecewise-linear residual (the sampled friction law) Newton's full step from one facet
/// lands on the facet that holds the root, and the next step finds it exactly; a step damped
/// until the residual decreases stays on the first facet, where the residual's local minimum is
/// not a root, and stalls there. Here every step is taken in full and the residual may grow on
/// the way, as in Newton's method for piecewise-differentiable equations (Kojima & Shindo
/// 1986), which on a piecewise-linear map ends as soon as an iterate's facet holds the root
/// (its linearisation is the map there).
///
/// From the prediction y_p = y_c + h t (h = 1, 4, 16 h_min) the point is sought on three
/// hyperplanes through y_p: the one orthogonal to the tangent t (pseudo-arc length); the one of
/// fixed parameter λ = λ_p (the frequency response's own parametrisation, whose Jacobian ∂r/∂x
/// alone is regular off folds); and the one of fixed u_k = (y_p)_k, k the unknown along which
/// t moves most (regular at a fold in λ; Rheinboldt 1986). A point is accepted within 4h of
/// the current one and ahead of it: on the first hyperplane its tangent, oriented as the path,
/// points away from it; on the others it lies ahead in the fixed coordinate, and its tangent is
/// directed onwards in that coordinate ([`onward_along`]). Returns as [`corner_step`].
#[allow(clippy::type_complexity)]
fn full_step<S: ParameterSystem>(
    system: &S,
    current: &PathPoint<S::State>,
    (tangent, orientation): (&[f64], f64),
    s: &Scales,
    min_step: f64,
    (opts, solver): (&ContinuationOptions, &LinearSolver),
) -> Option<(NewtonSolution<S::State>, Tangent, f64)> {
    let undamped = ContinuationOptions {
        newton: NewtonOptions {
            max_halvings: 0,
            ..opts.newton
        },
        ..opts.clone()
    };
    let y_c = scaled(current, s);
    let last = y_c.len() - 1;
    // the coordinate along which the path moves most (an unknown at a fold in λ)
    let k = (0..last)
        .max_by(|&a, &b| tangent[a].abs().total_cmp(&tangent[b].abs()))
        .unwrap_or(last);
    let axis = |i: usize| -> Vec<f64> {
        let mut e = vec![0.0; y_c.len()];
        e[i] = 1.0;
        e
    };
    let (fixed_parameter, fixed_unknown) = (axis(last), axis(k));
    for h in [1.0, 4.0, 16.0].map(|f| f * min_step) {
        let predicted: Vec<f64> = y_c.iter().zip(tangent).map(|(y, t)| y + h * t).collect();
        for (border, along) in [
            (tangent, None),
            (fixed_parameter.as_slice(), Some(last)),
            (fixed_unknown.as_slice(), Some(k)),
        ] {
            let Ok((sol, Some(t))) = correct_on(
                system,
                &current.state,
                &predicted,
                border,
                tangent,
                s,
                &undamped,
                solver,
                None,
            ) else {
                continue;
            };
            let y = scaled_xy(&sol.x, sol.parameter, s);
            let moved: Vec<f64> = y.iter().zip(&y_c).map(|(a, b)| a - b).collect();
            let length = norm(&moved);
            if length > 4.0 * h {
                continue;
            }
            match along {
                None => {
                    let t = t.oriented(orientation);
                    if dot(&moved, &t.t) > 0.0 {
                        return Some((sol, t, length));
                    }
                }
                Some(i) => {
                    if let Some(t) = onward_along(t, tangent, moved[i], i) {
                        return Some((sol, t, length));
                    }
                }
            }
        }
    }
    None
}

/// The tangent at a point found with the coordinate i of y = (u, μ) fixed ahead of the current
/// point ([`full_step`]), directed as the path goes on: with its component i of the sign of the
/// incoming tangent's, when both are clearly non-zero (> 1e-6) and the point lies ahead in
/// that coordinate (`moved_i` of that sign too). The orientation σ is then the one of that
/// direction: at a corner where several facets of the sampled law meet, σ can change (a
/// branch point of the piecewise-linear path), while the coordinate keeps its sense of travel.
/// `None` where the point is not ahead or the path turns in that coordinate.
fn onward_along(t: Tangent, incoming: &[f64], moved_i: f64, i: usize) -> Option<Tangent> {
    let sense = incoming[i];
    let ahead = moved_i * sense > 0.0;
    let clear = sense.abs() > 1e-6 && t.t[i].abs() > 1e-6;
    if !(ahead && clear) {
        return None;
    }
    Some(if t.t[i] * sense > 0.0 {
        t
    } else {
        t.reversed()
    })
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A tangent converted to another x_s keeps its direction in (x, λ) and unit length; a
    /// stalled path lowers x_s only when it exceeds ‖x‖ by more than the ratio.
    #[test]
    fn a_lowered_scale_keeps_the_tangent_direction() {
        let mut s = Scales {
            x: 100.0,
            lambda: 2.0,
            residual: 1.0,
        };
        // (u, μ) = (x / x_s, λ / λ_s): raw direction (dx, dλ) = (t_u x_s, t_μ λ_s)
        let t = [0.6, 0.0, 0.8];
        let raw = |t: &[f64], s: &Scales| [t[0] * s.x, t[1] * s.x, t[2] * s.lambda];
        let before = raw(&t, &s);
        assert!(
            shrink_scale(&t, &mut s, 30.0).is_none(),
            "x_s = 100 ≤ 4 · 30"
        );
        assert_eq!(s.x, 100.0);
        let u = shrink_scale(&t, &mut s, 10.0).expect("x_s = 100 > 4 · 10");
        assert_eq!(s.x, 10.0);
        assert!((norm(&u) - 1.0).abs() < 1e-15);
        let after = raw(&u, &s);
        // parallel: the cross product of the (x, λ) parts vanishes, and the same sense
        let cross = before[0] * after[2] - before[2] * after[0];
        assert!(cross.abs() < 1e-12 * norm(&before) * norm(&after));
        assert!(dot(&before, &after) > 0.0);
        // the x part's share grows by the ratio 10: t_u / t_μ = 0.6 / 0.8 · 10
        assert!((u[0] / u[2] - 7.5).abs() < 1e-12);
    }
}
