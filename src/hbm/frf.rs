//! A frequency response: the continuation of an [`HbmSystem`] in ω with the output DOFs'
//! response recovered at every point.

use super::response::{output_response, OutputResponse, ResponseOptions};
use super::stability::is_stable;
use super::system::{FixedFrequencyParameter, FixedFrequencyPath, FrequencyPath, HbmSystem};
use crate::continuation::{trace, trace_from, ContinuationOptions, Path, PathEnd, PathPoint};
use crate::error::{Error, Result};
use crate::harmonics::HarmonicForce;
use crate::nonlinear::{solve_fixed, NewtonOptions, NewtonSolution, ParameterSystem};

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
    /// The accepted scaled residual ‖r‖₂ / residual scale (≤ the Newton tolerance).
    pub residual: f64,
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
    /// `Some(λ₀)` when Newton from the linear solution missed the start point and it was reached
    /// by continuation in the excitation level from λ₀ × the force (see [`frequency_response`]).
    pub start_level: Option<f64>,
    /// The jumps of the sweep, in path order ([`frequency_response`]): where the path turned
    /// back out of its range and the response went on from the next frequency.
    pub jumps: Vec<Jump>,
}

/// A jump of a frequency sweep: the path could not be followed towards the end of the range
/// beyond ω = `from` (its furthest point towards the end), for the [`JumpCause`]; the response
/// goes on from the solution at ω = `to` = `from` ± the initial step, on another branch, as a
/// stepped-sine sweep jumps at a fold.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Jump {
    /// Index in [`Frf::points`] of the first point after the jump (the solution at `to`).
    pub point: usize,
    /// The furthest frequency of the path before the jump (rad/s).
    pub from: f64,
    /// The frequency the sweep went on from (rad/s).
    pub to: f64,
    /// Why the path before the jump ended.
    pub cause: JumpCause,
}

/// Why a sweep jumped ([`Jump`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum JumpCause {
    /// The path turned back and left the range on the start side.
    TurnedBack,
    /// The path came back onto itself and ran round a closed loop ([`PathEnd::Closed`]).
    Closed,
    /// The response grew without bound at a nearly fixed frequency, until the residual's
    /// round-off in double precision reached the Newton tolerance ([`residual_noise`]): the
    /// branch has no continuation that can be verified.
    Unbounded,
    /// No corrector converged beyond the path's last point, where the residual is well above
    /// its round-off ([`PathEnd::Failed`]): a corner of the sampled law (a kink of the
    /// piecewise-linear path) that no step, kink step, corner step or full Newton step passes.
    Stalled,
    /// No start point was found at the start frequency (Newton from the linear solution, the
    /// continuation in the excitation level and Newton with full steps all failed): the sweep
    /// starts at the first frequency beyond it where one is found ([`Jump::from`] is the start
    /// frequency, [`Jump::point`] 0).
    NoStart,
}

impl JumpCause {
    /// What happened, for the log.
    pub fn describe(self) -> &'static str {
        match self {
            JumpCause::TurnedBack => "the path turned back and left the range",
            JumpCause::Closed => "the path came back onto itself (a closed loop of solutions)",
            JumpCause::Unbounded => {
                "the response grew without bound (the residual's round-off reached the tolerance)"
            }
            JumpCause::Stalled => {
                "no corrector converged beyond the path's last point (a corner of the sampled law)"
            }
            JumpCause::NoStart => "no start point was found at the start frequency",
        }
    }
}

/// Traces the frequency response of `system` (excitation level 1) and recovers the outputs.
/// `on_point` sees every converged point (for progress). The start point is solved by Newton
/// from the linear solution or, when that does not converge, reached by continuation in the
/// excitation level at the start frequency (from λ₀ = ½, ¼, … 2⁻¹⁰ × the force up to 1; the
/// λ₀ used is [`Frf::start_level`]); when that fails too, by Newton from the linear solution
/// with every step taken in full, and last by continuation in a factor on the nonlinear force
/// from the linear response without it ([`FixedFrequencyParameter::ForceScale`]).
///
/// A path that cannot be followed to the end of the range does not cover it: it turns back and
/// leaves the range on the start side ([`PathEnd::LeftRange`]: the branch through the start
/// folds back, e.g. a superharmonic resonance met at the start), comes back onto itself
/// ([`PathEnd::Closed`]), or grows without bound until its residual's round-off reaches the
/// tolerance ([`JumpCause::Unbounded`]), or stops where no corrector converges
/// ([`JumpCause::Stalled`]). The sweep then jumps, at most
/// [`ContinuationOptions::max_jumps`] times ([`Jump`]): from the path's furthest point towards
/// the end, ω_f, to ω_f ± the initial step (or 2, 4, 8, … steps, within the range, where no
/// solution is found there), where the solution is found by Newton from the furthest point's or, failing that,
/// as a start point; the path goes on from there, and its points follow the earlier ones. A
/// jump that finds no solution ends the response as the path before it ended. Where no start
/// point is found at all, the sweep starts at the first of ω_start ± 1, 2, 4, … initial steps
/// where one is found, and that counts as its first jump ([`JumpCause::NoStart`]).
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
    opts.validate()?;
    let fp = FrequencyPath { system, level: 1.0 };
    let frequency_opts = ContinuationOptions {
        floor: Some(0.0),
        ..opts.clone()
    };
    let mut jumps = Vec::new();
    let (start, start_level, first) = match start_point(&fp, opts) {
        Ok((start, level)) => (start, level, opts.start),
        Err(e) if opts.max_jumps == 0 => return Err(e),
        Err(e) => match later_start(&fp, opts) {
            Some((start, to)) => {
                jumps.push(Jump {
                    point: 0,
                    from: opts.start,
                    to,
                    cause: JumpCause::NoStart,
                });
                (start, None, to)
            }
            None => return Err(e),
        },
    };
    let first_opts = ContinuationOptions {
        start: first,
        ..frequency_opts.clone()
    };
    let mut path = trace_from(&fp, &first_opts, start, on_point)?;
    while jumps.len() < opts.max_jumps {
        let Some(cause) = jump_cause(&fp, &path, opts.newton.tolerance)? else {
            break;
        };
        if cause == JumpCause::Unbounded {
            // the last point's noise was measured by jump_cause
            if path.points.len() > 1 {
                path.points.pop();
            }
            drop_unverifiable(&fp, &mut path, opts.newton.tolerance)?;
        }
        let Some((jump, segment)) = jump_on(&fp, &frequency_opts, &path, cause, on_point)? else {
            break;
        };
        jumps.push(jump);
        let offset = path.points.last().map_or(0.0, |p| p.arc_length);
        path.points.extend(segment.points.into_iter().map(|mut p| {
            p.arc_length += offset;
            p
        }));
        path.end = segment.end;
        path.retries += segment.retries;
        path.corner_steps += segment.corner_steps;
    }
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
                residual: p.residual,
                q: p.x,
                state: p.state,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    Ok(Frf {
        points,
        end: path.end,
        retries: path.retries,
        start_level,
        jumps,
    })
}

/// Where [`start_point`] finds no solution at ω_start: the first of ω_start ± 1, 2, 4, 8, …
/// initial steps (within the range) where it finds one, with that frequency; `None` when there
/// is none.
fn later_start<F: HarmonicForce>(
    fp: &FrequencyPath<'_, '_, F>,
    opts: &ContinuationOptions,
) -> Option<(NewtonSolution<F::State>, f64)> {
    jump_targets(opts.start, opts).find_map(|to| {
        let shifted = ContinuationOptions {
            start: to,
            ..opts.clone()
        };
        start_point(fp, &shifted).ok().map(|(sol, _)| (sol, to))
    })
}

/// The frequencies (rad/s) a sweep tries beyond ω = `from` when it jumps ([`jump_on`]) or
/// looks for a later start ([`later_start`]): `from` ± 1, 2, 4, 8, … initial steps towards the
/// end of the range, while they lie within it.
fn jump_targets(from: f64, opts: &ContinuationOptions) -> impl Iterator<Item = f64> {
    let direction = (opts.end - opts.start).signum();
    let (end, step) = (opts.end, opts.initial_step);
    std::iter::successors(Some(1.0_f64), |steps| Some(2.0 * steps))
        .map(move |steps| from + direction * steps * step)
        .take_while(move |to| direction * (end - to) > 0.0)
}

/// One jump of [`frequency_response`] after `path` left the range: the jump and the path traced
/// from where it lands (its points not yet appended), or `None` when no solution was found
/// there (or the furthest point is already at the end).
fn jump_on<F: HarmonicForce>(
    fp: &FrequencyPath<'_, '_, F>,
    opts: &ContinuationOptions,
    path: &Path<F::State>,
    cause: JumpCause,
    on_point: &mut dyn FnMut(&PathPoint<F::State>),
) -> Result<Option<(Jump, Path<F::State>)>> {
    let direction = (opts.end - opts.start).signum();
    let progress = |p: &PathPoint<F::State>| direction * (p.parameter - opts.start);
    let Some(furthest) = path
        .points
        .iter()
        .max_by(|a, b| progress(a).total_cmp(&progress(b)))
    else {
        return Ok(None);
    };
    let from = furthest.parameter;
    let remaining = opts.max_points.saturating_sub(path.points.len());
    if remaining == 0 {
        return Ok(None);
    }
    // one initial step on; where no solution is found there, 2, 4, 8, … steps within the range
    let found = jump_targets(from, opts).find_map(|to| {
        let segment_opts = ContinuationOptions {
            start: to,
            max_points: remaining,
            ..opts.clone()
        };
        let landed = match solve_fixed(fp, &furthest.x, to, &furthest.state, &opts.newton) {
            Ok(sol) => Some(sol),
            Err(_) => start_point(fp, &segment_opts).ok().map(|(sol, _)| sol),
        };
        landed.map(|sol| (to, segment_opts, sol))
    });
    let Some((to, segment_opts, landed)) = found else {
        return Ok(None);
    };
    let segment = trace_from(fp, &segment_opts, landed, on_point)?;
    let jump = Jump {
        point: path.points.len(),
        from,
        to,
        cause,
    };
    Ok(Some((jump, segment)))
}

/// Whether the sweep jumps at the end of `path`, and why: a path that left its range on the
/// start side ([`JumpCause::TurnedBack`]), one that closed on itself ([`JumpCause::Closed`]),
/// one that stopped (failed or ran out of points) where the residual's round-off noise at its
/// last point is at least a quarter of the Newton `tolerance` ([`JumpCause::Unbounded`]), and
/// one that failed where the noise is below that ([`JumpCause::Stalled`]).
fn jump_cause<F: HarmonicForce>(
    fp: &FrequencyPath<'_, '_, F>,
    path: &Path<F::State>,
    tolerance: f64,
) -> Result<Option<JumpCause>> {
    match path.end {
        PathEnd::LeftRange => Ok(Some(JumpCause::TurnedBack)),
        PathEnd::Closed => Ok(Some(JumpCause::Closed)),
        PathEnd::ReachedEnd => Ok(None),
        PathEnd::MaxPoints | PathEnd::Failed(_) => {
            let Some(last) = path.points.last() else {
                return Ok(None);
            };
            let noise = residual_noise(fp, &last.x, last.parameter, &last.state)?;
            if noise >= 0.25 * tolerance {
                Ok(Some(JumpCause::Unbounded))
            } else if matches!(path.end, PathEnd::Failed(_)) {
                Ok(Some(JumpCause::Stalled))
            } else {
                Ok(None)
            }
        }
    }
}

/// Removes from the end of a path that grew without bound the points that double precision
/// cannot verify: those whose residual noise ([`residual_noise`]) is at least a quarter of the
/// Newton `tolerance` (their accepted residual is within the noise). The first point is kept.
fn drop_unverifiable<F: HarmonicForce>(
    fp: &FrequencyPath<'_, '_, F>,
    path: &mut Path<F::State>,
    tolerance: f64,
) -> Result<()> {
    while path.points.len() > 1 {
        let Some(last) = path.points.last() else {
            break;
        };
        if residual_noise(fp, &last.x, last.parameter, &last.state)? < 0.25 * tolerance {
            break;
        }
        path.points.pop();
    }
    Ok(())
}

/// The round-off noise of the scaled residual ‖r‖₂ / r_s at the harmonics `x` and frequency
/// `omega` (rad/s), from the force memory `state`: the larger change of it
/// when every unknown is moved by 4 units of round-off (relative 4ε, ε = 2.2e-16), with two
/// patterns of signs. r = D̄(ω) Q − F̄_e + F̄_nl(Q) sums terms that cancel; where ‖Q‖ has grown
/// so large that ε ‖D̄‖ ‖Q‖ reaches the tolerance times the force level, no point can be
/// verified to the tolerance any more, whatever the corrector does.
pub fn residual_noise<F: HarmonicForce>(
    fp: &FrequencyPath<'_, '_, F>,
    x: &[f64],
    omega: f64,
    state: &F::State,
) -> Result<f64> {
    let n = fp.dim();
    let scale = fp.residual_scale();
    let mut base = vec![0.0; n];
    fp.evaluate_residual(x, omega, state, &mut base)?;
    let mut noise: f64 = 0.0;
    for pattern in [1usize, 2] {
        let moved: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, x)| {
                let sign = if (i / pattern) % 2 == 0 { 1.0 } else { -1.0 };
                x * (1.0 + sign * 4.0 * f64::EPSILON)
            })
            .collect();
        let mut r = vec![0.0; n];
        fp.evaluate_residual(&moved, omega, state, &mut r)?;
        let change: f64 = r
            .iter()
            .zip(&base)
            .map(|(a, b)| (a - b) * (a - b))
            .sum::<f64>()
            .sqrt();
        noise = noise.max(change / scale);
    }
    Ok(noise)
}

/// The points of a traced response at chosen frequencies ([`land_at`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Landed {
    /// Per requested frequency, the indices in [`Frf::points`] of the points at exactly that ω,
    /// in path order (several inside a fold, none where the path does not reach it).
    pub points: Vec<Vec<usize>>,
    /// Crossings where Newton at the fixed frequency did not converge (ω in rad/s, why).
    pub failed: Vec<(f64, String)>,
}

/// Adds to `frf` a point at every crossing of its path with each of the frequencies `omegas`
/// (rad/s), so that a traced response has exact solutions there (inside a fold, one per branch).
///
/// Where ω* lies strictly between the frequencies of consecutive points i and i + 1, Newton at
/// the fixed ω* starts from Q interpolated linearly in ω between them, with the force memory of
/// point i; the solution is inserted between them, its arc length interpolated the same way and
/// its outputs (and Hill stability when `response.stability`) recovered as for the traced points.
/// A point already at ω* is kept as it is; a jump ([`Frf::jumps`]) is no crossing (its two points
/// lie on different branches), and the jumps' point indices follow the inserted points. A
/// crossing whose Newton fails is left out and listed in
/// [`Landed::failed`].
pub fn land_at<F: HarmonicForce>(
    system: &HbmSystem<'_, F>,
    frf: &mut Frf<F::State>,
    omegas: &[f64],
    newton: &NewtonOptions,
    response: &ResponseOptions,
) -> Result<Landed> {
    let fp = FrequencyPath { system, level: 1.0 };
    let mut failed = Vec::new();
    // (insert after point i, the new point), in path order
    let mut inserted: Vec<(usize, FrfPoint<F::State>)> = Vec::new();
    for i in 0..frf.points.len().saturating_sub(1) {
        if frf.jumps.iter().any(|j| j.point == i + 1) {
            // a jump: the two points lie on different branches
            continue;
        }
        let (a, b) = (&frf.points[i], &frf.points[i + 1]);
        let mut between: Vec<f64> = omegas
            .iter()
            .copied()
            .filter(|&w| (a.omega - w) * (b.omega - w) < 0.0)
            .collect();
        // in path order between the two points
        between.sort_by(|x, y| ((x - a.omega).abs()).total_cmp(&(y - a.omega).abs()));
        between.dedup();
        for w in between {
            let t = (w - a.omega) / (b.omega - a.omega);
            let x0: Vec<f64> = a.q.iter().zip(&b.q).map(|(p, q)| p + t * (q - p)).collect();
            match solve_fixed(&fp, &x0, w, &a.state, newton) {
                Ok(sol) => {
                    let stable = if response.stability {
                        Some(is_stable(system, &sol.x, w, &sol.state)?)
                    } else {
                        None
                    };
                    inserted.push((
                        i,
                        FrfPoint {
                            omega: w,
                            response: output_response(system, &sol.x, w, 1.0, response)?,
                            arc_length: a.arc_length + t * (b.arc_length - a.arc_length),
                            iterations: sol.iterations,
                            residual: sol.residual,
                            q: sol.x,
                            state: sol.state,
                            stable,
                        },
                    ))
                }
                Err(f) => failed.push((w, f.message)),
            }
        }
    }
    if !inserted.is_empty() {
        for jump in &mut frf.jumps {
            jump.point += inserted.iter().filter(|(i, _)| *i < jump.point).count();
        }
        let old = std::mem::take(&mut frf.points);
        let mut extra = inserted.into_iter().peekable();
        for (i, p) in old.into_iter().enumerate() {
            frf.points.push(p);
            while let Some((_, q)) = extra.next_if(|(j, _)| *j == i) {
                frf.points.push(q);
            }
        }
    }
    let points = omegas
        .iter()
        .map(|&w| {
            (0..frf.points.len())
                .filter(|&k| frf.points[k].omega == w)
                .collect()
        })
        .collect();
    Ok(Landed { points, failed })
}

/// The smallest fraction of the excitation the level continuation of [`start_point`] starts from
/// (2⁻¹⁰).
const SMALLEST_START_LEVEL: f64 = 1.0 / 1024.0;

/// The start point of a frequency response at ω_start = `opts.start`.
///
/// Newton from the linear solution (Q = 0: its first step solves the stuck, linearised system)
/// usually converges. When the excitation is strong enough for friction to slip or contacts to
/// separate far from that solution, it may not; the start is then reached by continuation in the
/// excitation level λ at the fixed ω_start ([`FixedFrequencyParameter::Level`], the residual
/// D̄(ω) Q − λ F̄_e + F_c(Q)) from λ₀ up to λ = 1, through any fold in λ. λ₀ = ½, halved down
/// to 2⁻¹⁰ while the start at λ₀ does not converge, and down to ⅛ while the path turns back far
/// below λ₀ (by more than half its range: a path from ⅛ may go back to λ < 0); a path that stops
/// on the way is not retried (a smaller λ₀ would meet the same point). Newton at λ = 1 from
/// the end of that path then gives the start point with the frequency path's linearization.
/// Where that fails too: Newton from the linear solution with every step taken in full, and
/// last the continuation in the force scale ([`force_scale_start`]).
///
/// Returns the start point and, when the level continuation gave it, λ₀.
///
/// Errors ([`Error::Compute`]): neither way reaches λ = 1; the message gives both reasons.
fn start_point<F: HarmonicForce>(
    fp: &FrequencyPath<'_, '_, F>,
    opts: &ContinuationOptions,
) -> Result<(NewtonSolution<F::State>, Option<f64>)> {
    let x0 = vec![0.0; fp.dim()];
    let direct = match solve_fixed(fp, &x0, opts.start, &fp.initial_state(), &opts.newton) {
        Ok(sol) => return Ok((sol, None)),
        Err(f) => f.message,
    };
    let fail = |why: String, from: f64, homotopy: String| {
        Error::Compute(format!(
            "Newton from the linear solution failed ({direct}), and so did the continuation in the \
             excitation level from {from:.3e} × the force up to 1 at that frequency ({why}) and \
             the continuation from the linear system without the nonlinear force ({homotopy}) — \
             try another start frequency, a smaller excitation or more damping"
        ))
    };
    let level = level_continuation(fp.system, opts);
    let from = level.from;
    let why = match level.end {
        Ok((x, state)) => match solve_fixed(fp, &x, opts.start, &state, &opts.newton) {
            Ok(sol) => return Ok((sol, Some(from))),
            Err(f) => format!(
                "Newton at the full force from the end of that path: {}",
                f.message
            ),
        },
        Err(why) => why,
    };
    // last, Newton from the linear solution with every step taken in full (as the
    // continuation's full-step corrector): on the piecewise-linear sampled law a damped step
    // can stall on a facet that does not hold the root
    let undamped = NewtonOptions {
        max_halvings: 0,
        max_iterations: 2 * opts.newton.max_iterations,
        ..opts.newton
    };
    if let Ok(sol) = solve_fixed(fp, &x0, opts.start, &fp.initial_state(), &undamped) {
        return Ok((sol, None));
    }
    force_scale_start(fp, opts)
        .map(|sol| (sol, None))
        .map_err(|homotopy| fail(why, from, homotopy))
}

/// The last start-point method of [`start_point`]: the continuation in the factor s on the
/// nonlinear force at the fixed ω_start ([`FixedFrequencyParameter::ForceScale`]: r = D̄ Q − F̄_e + s F_nl(Q)) from the
/// linear response without the nonlinear force (s = 0) to s = 1, then Newton on the frequency
/// path from its end. Under strong excitation (gross slip, separation) that response is near the
/// solution, and the path in s meets no fold where the one in the excitation level does (the
/// branch at the full force is then not connected to the small-force one at that frequency).
/// Err: why it failed.
fn force_scale_start<F: HarmonicForce>(
    fp: &FrequencyPath<'_, '_, F>,
    opts: &ContinuationOptions,
) -> std::result::Result<NewtonSolution<F::State>, String> {
    let path = FixedFrequencyPath {
        system: fp.system,
        omega: opts.start,
        parameter: FixedFrequencyParameter::ForceScale,
    };
    let sopts = fixed_frequency_options(0.0, opts);
    let traced = trace(&path, &sopts, &mut |_| {}).map_err(|e| e.to_string())?;
    let reached = traced.points.last().map_or(0.0, |p| p.parameter);
    let ended = match traced.end {
        PathEnd::ReachedEnd => None,
        PathEnd::LeftRange => Some("turned back below s = 0".to_string()),
        PathEnd::Closed => Some("came back onto itself".to_string()),
        PathEnd::MaxPoints => Some(format!("took more than {} points", sopts.max_points)),
        PathEnd::Failed(m) => Some(m),
    };
    if let Some(why) = ended {
        return Err(format!(
            "the path in s {why} (last point at s = {reached:.4})"
        ));
    }
    let last = traced
        .points
        .last()
        .ok_or_else(|| "the path in s has no points".to_string())?;
    solve_fixed(fp, &last.x, opts.start, &last.state, &opts.newton).map_err(|f| {
        format!(
            "Newton at the full force from the end of that path: {}",
            f.message
        )
    })
}

/// How the continuation in the excitation level of [`start_point`] ended.
struct LevelEnd<S> {
    /// At λ = 1: the end (Q, force memory); else why the last attempt failed.
    end: std::result::Result<(Vec<f64>, S), String>,
    /// The start level λ₀ of the last attempt.
    from: f64,
}

/// The options of the start procedure's continuations at the fixed ω_start (in the excitation
/// level, [`level_continuation`], and in the force scale, [`force_scale_start`]): from `from` to
/// 1 in 20 initial steps, at most 5 and at least 2·10⁴ steps over the range, 2000 points, the
/// sweep's Newton options. The minimum step is explicit: the default (initial step / 1000 in
/// scaled arc length) is inflated when ‖Q‖ at a small start makes the first tangent nearly
/// parallel to Q.
fn fixed_frequency_options(from: f64, opts: &ContinuationOptions) -> ContinuationOptions {
    let range = 1.0 - from;
    let mut fixed = ContinuationOptions::new(from, 1.0, range / 20.0);
    fixed.max_step = Some(range / 5.0);
    fixed.min_step = Some(range / 2e4);
    fixed.max_points = 2000;
    fixed.newton = opts.newton;
    fixed
}

/// The continuation in the excitation level of [`start_point`].
fn level_continuation<F: HarmonicForce>(
    system: &HbmSystem<'_, F>,
    opts: &ContinuationOptions,
) -> LevelEnd<F::State> {
    let lp = FixedFrequencyPath {
        system,
        omega: opts.start,
        parameter: FixedFrequencyParameter::Level,
    };
    let mut level = 0.5;
    let mut tried = level;
    let mut why = String::new();
    while level >= SMALLEST_START_LEVEL {
        tried = level;
        let lopts = fixed_frequency_options(level, opts);
        match trace(&lp, &lopts, &mut |_| {}) {
            Ok(path) => match path.end {
                PathEnd::ReachedEnd => match path.points.into_iter().last() {
                    Some(last) => {
                        return LevelEnd {
                            end: Ok((last.x, last.state)),
                            from: level,
                        }
                    }
                    None => why = "the level path has no points".into(),
                },
                // a smaller start level lets the path go further back through a fold in λ; below
                // λ₀ = ⅛ it may already go back to λ < 0, so a smaller one would not help
                PathEnd::LeftRange => {
                    why = "the level path turned back below its start".into();
                    if level <= 0.125 {
                        break;
                    }
                }
                // the obstacle lies on the path itself: a smaller start level meets it again
                PathEnd::Failed(m) => {
                    why = m;
                    break;
                }
                PathEnd::MaxPoints => {
                    why = format!("the level path took more than {} points", lopts.max_points);
                    break;
                }
                PathEnd::Closed => {
                    why = "the level path came back onto itself (a closed loop)".into();
                    break;
                }
            },
            // the start did not converge: a smaller level is nearer the linear solution
            Err(e) => why = e.to_string(),
        }
        level *= 0.5;
    }
    LevelEnd {
        end: Err(why),
        from: tried,
    }
}
