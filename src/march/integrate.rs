//! The time loop of `nlrom march`: step selection (fixed, or adaptive from the contact state,
//! Gastaldi & Berruti 2018 §4.2), the scheme's step ([`super::schemes`]), the record of every step,
//! and steady-state (periodicity) detection at the end of each excitation period.

use std::time::Instant;

use super::adaptive::AdaptiveSteps;
use super::law::{ContactState, LawSample};
use super::periodic::{self, Extremes};
use super::schemes::{
    self, Cache, Corrected, Excitation, ExcitationAt, Kinematics, Snapshot, StepContext, Workspace,
};
use super::signal::{Phase, PhaseSteps};
use super::system::{InitialCondition, MarchSystem};
use crate::case::MarchScheme;
use crate::error::{Error, Result};

/// The convergence limit Δτ/𝕋 < 1/π ≈ 0.318 of Newmark's fixed-point corrector (paper §4.2).
pub const STEP_RATIO_LIMIT: f64 = std::f64::consts::FRAC_1_PI;

/// How to march.
#[derive(Clone, Debug, PartialEq)]
pub struct MarchSettings {
    /// The scheme.
    pub scheme: MarchScheme,
    /// Excitation frequency ω (rad/s), > 0.
    pub omega: f64,
    /// Excitation periods to march, ≥ 1.
    pub periods: usize,
    /// Steps per period: the largest step is 2π/(ω·steps_per_period); the quasi-static method
    /// uses exactly this step.
    pub steps_per_period: usize,
    /// Δτ/𝕋 of the Newmark schemes, 0 < r < 1/π: the fixed step is min(r·𝕋_stick, largest step)
    /// (a step compatible with the full-stick state, paper §4.2) and the adaptive step
    /// min(r·𝕋(state), largest step).
    pub step_ratio: f64,
    /// An explicit fixed step Δτ (s) instead of the rule above (checked against the stability limit
    /// for the standard scheme).
    pub time_step: Option<f64>,
    /// Relative tolerance of the standard corrector: |Δq|_∞ < tolerance · displacement scale.
    pub tolerance: f64,
    /// Most corrector iterations per step.
    pub max_iterations: u32,
    /// Steady state: the end-of-period state repeats within this relative tolerance.
    pub steady_tolerance: f64,
    /// Stop at the first steady period.
    pub stop_at_steady: bool,
    /// Harmonics 0..=H of the last period reported per DOF.
    pub harmonics: usize,
    /// Record the velocities q̇ of every step in [`MarchHistory::v`] (n values per step; off, the
    /// record of a step holds t, q, the elements' forces and states and the iterations).
    pub record_velocities: bool,
}

impl Default for MarchSettings {
    fn default() -> Self {
        MarchSettings {
            scheme: MarchScheme::Newmark,
            omega: 1.0,
            periods: 1,
            steps_per_period: 100,
            step_ratio: 0.15,
            time_step: None,
            tolerance: 1e-8,
            max_iterations: 500,
            steady_tolerance: 1e-6,
            stop_at_steady: false,
            harmonics: 1,
            record_velocities: false,
        }
    }
}

impl MarchSettings {
    /// Checks the ranges (input errors name the setting and what to do).
    pub fn validate(&self) -> Result<()> {
        let bad = |msg: String| Err(Error::input(format!("march settings: {msg}")));
        if self.scheme.is_nonsmooth() {
            return bad(format!(
                "the scheme `{}` marches `[[obstacle]]` contacts (`march::moreau_jean`, `march::carpenter`), not friction elements",
                self.scheme
            ));
        }
        if !(self.omega.is_finite() && self.omega > 0.0) {
            return bad(format!(
                "the excitation frequency must be > 0 (found {} rad/s)",
                self.omega
            ));
        }
        if self.periods == 0 || self.steps_per_period == 0 {
            return bad("`periods` and `steps_per_period` must be ≥ 1".into());
        }
        if !(self.step_ratio > 0.0 && self.step_ratio < STEP_RATIO_LIMIT) {
            return bad(format!(
                "`step_ratio` = {} is outside 0 < Δτ/𝕋 < 1/π ≈ 0.318: Newmark's corrector does not converge beyond it (Gastaldi & Berruti 2018 §4.2)",
                self.step_ratio
            ));
        }
        if let Some(dt) = self.time_step {
            if !(dt.is_finite() && dt > 0.0) {
                return bad(format!("the time step must be > 0 (found {dt} s)"));
            }
        }
        if !(self.tolerance.is_finite() && self.tolerance > 0.0) {
            return bad(format!(
                "`tolerance` must be > 0 (found {})",
                self.tolerance
            ));
        }
        if !(self.steady_tolerance.is_finite() && self.steady_tolerance > 0.0) {
            return bad(format!(
                "`steady_tolerance` must be > 0 (found {})",
                self.steady_tolerance
            ));
        }
        if self.max_iterations == 0 {
            return bad("`max_iterations` must be ≥ 1".into());
        }
        Ok(())
    }

    /// The excitation period 2π/ω (s).
    pub fn period(&self) -> f64 {
        2.0 * std::f64::consts::PI / self.omega
    }

    fn dynamic(&self) -> bool {
        self.scheme != MarchScheme::QuasiStatic
    }

    fn adaptive(&self) -> bool {
        matches!(
            self.scheme,
            MarchScheme::Adaptive | MarchScheme::AdaptivePiecewiseLinear
        )
    }
}

/// Every accepted step (index 0 is the initial state at t = 0). What the result and the
/// steady-state check need: q (the harmonics of the last period, the response written by
/// `nlrom march`), the contact forces and states; the velocities only when asked for
/// ([`MarchSettings::record_velocities`]: the periodicity check compares the velocity at a
/// period's end, which the march keeps), the elements' relative displacements on demand from q
/// ([`MarchHistory::contact_displacements`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MarchHistory {
    /// Time (s), \[T\].
    pub time: Vec<f64>,
    /// Displacements, [T × n] row-major.
    pub q: Vec<f64>,
    /// Velocities, [T × n] with [`MarchSettings::record_velocities`], else empty.
    pub v: Vec<f64>,
    /// Per element (f_t, f_n) (N), [T × E × 2].
    pub force: Vec<f64>,
    /// Per element state code (0 separated, 1 stick, 2 slip+, 3 slip−), [T × E].
    pub state: Vec<u8>,
    /// Corrector iterations of each step (0 for the initial state), \[T\].
    pub iterations: Vec<u32>,
}

impl MarchHistory {
    /// Number of recorded instants T.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// Whether nothing is recorded.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// Room for `steps` more instants of `n` DOF and `ne` elements (the velocities with
    /// `velocities`).
    fn reserve(&mut self, steps: usize, n: usize, ne: usize, velocities: bool) {
        self.time.reserve(steps);
        self.q.reserve(steps * n);
        if velocities {
            self.v.reserve(steps * n);
        }
        self.force.reserve(steps * ne * 2);
        self.state.reserve(steps * ne);
        self.iterations.reserve(steps);
    }

    /// Records the instant `t` (its velocities with `velocities`).
    fn push(&mut self, t: f64, now: &Snapshot, it: u32, velocities: bool) {
        self.time.push(t);
        self.q.extend_from_slice(&now.kin.q);
        if velocities {
            self.v.extend_from_slice(&now.kin.v);
        }
        for smp in &now.samples {
            self.force.extend_from_slice(&[smp.f_t, smp.f_n]);
            self.state.push(smp.state.code());
        }
        self.iterations.push(it);
    }

    /// Per element the relative displacements (u_t, v) (m) at every recorded instant,
    /// [T × E × 2]: u_t = g_tᵀ q + p_t(t), v = g_nᵀ q + p_n(t) (Gastaldi & Berruti 2018, eq. 2;
    /// [`super::element::Element::local`]) from the recorded q of `sys` driven at `omega`
    /// (rad/s).
    pub fn contact_displacements(&self, sys: &MarchSystem, omega: f64) -> Vec<f64> {
        let n = sys.n;
        let mut out = Vec::with_capacity(self.len() * sys.elements.len() * 2);
        for (k, &t) in self.time.iter().enumerate() {
            let q = &self.q[k * n..(k + 1) * n];
            for e in &sys.elements {
                let l = e.local(q, omega, t);
                out.extend_from_slice(&[l.ut, l.v]);
            }
        }
        out
    }
}

/// Per excitation period: where it ends and how far the end state is from the previous period's.
#[derive(Clone, Debug, PartialEq)]
pub struct PeriodSummary {
    /// Index into the history of the period's last instant.
    pub end_index: usize,
    /// Periodicity error max(|Δq|_∞/A, |Δq̇|_∞/(ωA)) against the previous period end, A the
    /// largest half peak-to-peak displacement of the period; `None` for the first period.
    pub periodicity_error: Option<f64>,
    /// Contact-state changes (instants where any element's state differs from the previous
    /// instant) within the period.
    pub state_changes: usize,
    /// Steps in the period.
    pub steps: usize,
}

/// The result of a march.
#[derive(Clone, Debug)]
pub struct MarchOutcome {
    /// The scheme used.
    pub scheme: MarchScheme,
    /// Every step.
    pub history: MarchHistory,
    /// One summary per marched period.
    pub periods: Vec<PeriodSummary>,
    /// The first period (1-based) whose end state repeated the previous one within the steady
    /// tolerance, if any.
    pub steady_period: Option<usize>,
    /// Harmonics n = 0..=H of each DOF over the last marched period, complex (re, im) per
    /// `docs/conventions.md` §4, \[n_dof\]\[H+1\].
    pub harmonics: Vec<Vec<(f64, f64)>>,
    /// Time steps taken (accepted).
    pub steps: usize,
    /// Steps recomputed with a smaller adaptive step.
    pub rejected_steps: usize,
    /// Sum of the corrector iterations of all steps (rejected attempts included).
    pub total_iterations: u64,
    /// Smallest and largest step used (s).
    pub step_range: (f64, f64),
    /// Step-matrix factorisations.
    pub factorisations: usize,
    /// Wall time of the time loop (s).
    pub wall_seconds: f64,
}

impl MarchOutcome {
    /// Histogram of iterations per step (paper Fig. 5): entry i counts the steps that took i
    /// iterations (index 0 unused).
    pub fn iteration_histogram(&self) -> Vec<usize> {
        let its = &self.history.iterations[1..];
        let max = its.iter().copied().max().unwrap_or(0) as usize;
        let mut h = vec![0; max + 1];
        for &i in its {
            h[i as usize] += 1;
        }
        h
    }

    /// Fraction of steps that took exactly one iteration.
    pub fn single_iteration_fraction(&self) -> f64 {
        let its = &self.history.iterations[1..];
        its.iter().filter(|&&i| i == 1).count() as f64 / its.len().max(1) as f64
    }

    /// First-harmonic amplitude |Q⁽¹⁾| of each DOF over the last period.
    pub fn first_harmonic_amplitude(&self) -> Vec<f64> {
        self.harmonics
            .iter()
            .map(|h| h.get(1).map_or(0.0, |(re, im)| re.hypot(*im)))
            .collect()
    }
}

/// A march in progress, advanced one excitation period at a time ([`Marcher::march_period`]):
/// the model, the settings, the caches of step matrices and factors, the excitation of every
/// step of a period (fixed step) and the buffers of the steps, all set up by [`Marcher::new`], so
/// that a period whose step sizes and contact states have been met allocates nothing.
pub struct Marcher<'a> {
    sys: &'a MarchSystem,
    settings: &'a MarchSettings,
    start: Instant,
    cache: Cache,
    ws: Workspace,
    cur: Snapshot,
    next: Snapshot,
    t: f64,
    /// The excitation of the current step (adaptive step) or of t = 0.
    excitation: Excitation,
    /// The phase ωt of the current state (adaptive step).
    phase: Phase,
    /// The phase of the step attempted last (adaptive step).
    next_phase: Phase,
    /// The phases of the adaptive steps, stepped per step size.
    phases: PhaseSteps,
    /// Fixed step: the steps of one period with the excitation at their ends.
    table: StepTable,
    tolerance: f64,
    /// The adaptive step of full stick, the shortest (adaptive schemes; else the largest step).
    dt_stick: f64,
    /// Adaptive step per contact-state combination (adaptive schemes).
    adaptive_dt: Option<AdaptiveSteps>,
    /// The adaptive step of the current state when the previous step found it (the state it
    /// ended in).
    next_dt: Option<f64>,
    codes: Vec<u8>,
    history: MarchHistory,
    /// The scratch of the period's amplitude.
    extremes: Extremes,
    summaries: Vec<PeriodSummary>,
    steady_period: Option<usize>,
    rejected: usize,
    total_iterations: u64,
    step_range: (f64, f64),
    prev_q: Vec<f64>,
    prev_v: Vec<f64>,
}

impl<'a> Marcher<'a> {
    /// Checks the model and the settings, finds the initial state (at rest or in static
    /// equilibrium), prepares the step matrices of the fixed step with the excitation of every
    /// step of a period, and reserves the history of all the periods.
    pub fn new(sys: &'a MarchSystem, settings: &'a MarchSettings) -> Result<Self> {
        settings.validate()?;
        sys.validate("march model")?;
        if settings.dynamic() && !sys.mass_is_positive_definite() {
            return Err(Error::input(format!(
                "the {} scheme integrates inertia, but the model's mass matrix is not positive definite (a model without mass); use the quasi-static scheme or give the model mass",
                settings.scheme
            )));
        }
        let start = Instant::now();
        let (n, ne) = (sys.n, sys.elements.len());
        let mut cache = Cache::default();
        // piecewise-linear Newmark: two n × n products per step (schemes::Premultiplied), per
        // step size (the adaptive steps share a few rungs of the ladder, adaptive::ladder_step)
        cache.use_premultiplied(
            sys,
            matches!(
                settings.scheme,
                MarchScheme::PiecewiseLinear | MarchScheme::AdaptivePiecewiseLinear
            ),
        );
        let period = settings.period();
        let dt_max = period / settings.steps_per_period as f64;
        let cur = initial_state(sys, settings, &mut cache)?;
        let mut m = Marcher {
            sys,
            settings,
            start,
            cache,
            ws: Workspace::new(sys),
            next: cur.clone(),
            cur,
            t: 0.0,
            excitation: Excitation::at(sys, settings.omega, 0.0, settings.dynamic()),
            phase: Phase::at(settings.omega, 0.0),
            next_phase: Phase::at(settings.omega, 0.0),
            phases: PhaseSteps::new(settings.omega),
            table: StepTable::default(),
            tolerance: settings.tolerance * sys.displacement_scale,
            dt_stick: dt_max,
            adaptive_dt: None,
            next_dt: None,
            codes: Vec::with_capacity(ne),
            history: MarchHistory::default(),
            extremes: Extremes::new(n),
            summaries: Vec::with_capacity(settings.periods),
            steady_period: None,
            rejected: 0,
            total_iterations: 0,
            step_range: (f64::INFINITY, 0.0),
            prev_q: Vec::new(),
            prev_v: Vec::new(),
        };
        let steps_per_period = if settings.adaptive() {
            // the stiffest state (full stick) sets the shortest adaptive step (paper §4.2)
            let steps = AdaptiveSteps::new(sys, settings.step_ratio, dt_max);
            let dt = steps.stick();
            m.dt_stick = dt;
            m.adaptive_dt = Some(steps);
            (1.25 * period / dt).ceil() as usize + 2
        } else {
            let dt = fixed_step(sys, settings, dt_max)?;
            let mut t = 0.0;
            let mut exc = Excitation::new(sys);
            while period - t > 1e-9 * period {
                let remaining = period - t;
                let h = if dt > remaining * (1.0 - 1e-9) {
                    remaining
                } else {
                    dt
                };
                t = if h == remaining { period } else { t + h };
                exc.fill(sys, settings.omega, t, settings.dynamic());
                m.table.push(t, h, &exc);
            }
            m.table.len()
        };
        let velocities = settings.record_velocities;
        m.history
            .reserve(settings.periods * steps_per_period + 1, n, ne, velocities);
        m.history.push(0.0, &m.cur, 0, velocities);
        m.prev_q = m.cur.kin.q.clone();
        m.prev_v = m.cur.kin.v.clone();
        Ok(m)
    }

    /// Step-matrix factorisations made so far (a state or step size met for the first time).
    pub fn factorisations(&self) -> usize {
        self.cache.factorisations
    }

    /// Periods marched so far.
    pub fn periods_done(&self) -> usize {
        self.summaries.len()
    }

    /// Marches one excitation period; returns whether its end state repeated the previous
    /// period's within the steady tolerance.
    pub fn march_period(&mut self) -> Result<bool> {
        let (sys, s) = (self.sys, self.settings);
        let p = self.summaries.len();
        let period = s.period();
        let t0 = p as f64 * period;
        let t_end = t0 + period;
        let first_index = self.history.len() - 1;
        if !s.adaptive() {
            for j in 0..self.table.len() {
                let (t_rel, dt, exc) = self.table.get(j);
                let t1 = if t_rel == period { t_end } else { t0 + t_rel };
                let ctx = context(sys, s, self.tolerance, t1, dt, exc, false);
                let its = step(
                    s,
                    &ctx,
                    &self.cur,
                    &mut self.cache,
                    &mut self.ws,
                    &mut self.next,
                )?
                .map_err(|why| why.error(&ctx))?;
                self.total_iterations += its as u64;
                self.step_range = (self.step_range.0.min(dt), self.step_range.1.max(dt));
                std::mem::swap(&mut self.cur, &mut self.next);
                self.t = t1;
                self.history.push(t1, &self.cur, its, s.record_velocities);
            }
        } else {
            while t_end - self.t > 1e-9 * period {
                let remaining = t_end - self.t;
                // the step of the current state, found as the previous step ended
                let mut dt = match self.next_dt.take() {
                    Some(dt) => dt,
                    None => self.step_of_current(),
                };
                // the step closing the period (shortened to its end) is a one-off size
                let end_time = |dt: f64, t: f64| {
                    if dt > remaining * (1.0 - 1e-9) {
                        (remaining, t_end, true)
                    } else {
                        (dt, t + dt, false)
                    }
                };
                let (h, mut t1, mut one_off) = end_time(dt, self.t);
                dt = h;
                let mut its = match self.attempt(t1, dt, one_off) {
                    Ok(Ok(its)) => its as u64,
                    // the standard corrector diverges when the state stiffens within a long
                    // step (Δτ/𝕋 beyond 1/π): re-run with the full-stick step, the shortest
                    Ok(Err(_)) | Err(_) if dt > self.dt_stick * (1.0 + 1e-12) => {
                        (dt, t1, one_off) = end_time(self.dt_stick, self.t);
                        self.rejected += 1;
                        self.converged(t1, dt, one_off)? as u64
                    }
                    Ok(Err(why)) => return Err(self.unconverged(why, t1, dt, one_off)),
                    Err(e) => return Err(e),
                };
                // paper §4.2: re-run with the smaller step the new state asks for
                for _ in 0..8 {
                    let dt_new = self.step_of_next();
                    let (h, t_new, one) = end_time(dt_new, self.t);
                    // a step closing the period is the same step at the smaller size
                    if dt_new >= dt * (1.0 - 1e-12) || h.to_bits() == dt.to_bits() {
                        self.next_dt = Some(dt_new);
                        break;
                    }
                    (dt, t1, one_off) = (h, t_new, one);
                    self.rejected += 1;
                    its += self.converged(t1, dt, one_off)? as u64;
                }
                self.total_iterations += its;
                self.step_range = (self.step_range.0.min(dt), self.step_range.1.max(dt));
                std::mem::swap(&mut self.cur, &mut self.next);
                self.t = t1;
                self.phase = self.next_phase;
                self.history.push(
                    t1,
                    &self.cur,
                    its.min(u32::MAX as u64) as u32,
                    s.record_velocities,
                );
            }
        }
        let end_index = self.history.len() - 1;
        let summary = periodic::summarize(
            &self.history,
            sys,
            &mut self.extremes,
            s.omega,
            first_index,
            end_index,
            (&self.prev_q, &self.prev_v),
            &self.cur.kin.v,
            p > 0,
        );
        self.prev_q.copy_from_slice(&self.cur.kin.q);
        self.prev_v.copy_from_slice(&self.cur.kin.v);
        let steady = summary
            .periodicity_error
            .is_some_and(|e| e < s.steady_tolerance);
        self.summaries.push(summary);
        if steady && self.steady_period.is_none() {
            self.steady_period = Some(p + 1);
        }
        Ok(steady)
    }

    /// The adaptive step (s) of the contact state of the current snapshot.
    fn step_of_current(&mut self) -> f64 {
        let steps = self.adaptive_dt.as_mut().expect("adaptive steps set up");
        steps.step_of(self.sys, &self.cur.samples, &mut self.codes)
    }

    /// The adaptive step (s) of the contact state an attempted step ended in (the next snapshot).
    fn step_of_next(&mut self) -> f64 {
        let steps = self.adaptive_dt.as_mut().expect("adaptive steps set up");
        steps.step_of(self.sys, &self.next.samples, &mut self.codes)
    }

    /// One adaptive step from the current state to `t1` (step `dt`; `one_off`: a size met once)
    /// into the next state, with the excitation at `t1` (its phase stepped from the current one,
    /// [`PhaseSteps::advance`]; from sin_cos for a one-off step); returns the iterations, or why
    /// the standard corrector did not converge.
    fn attempt(&mut self, t1: f64, dt: f64, one_off: bool) -> Result<Corrected> {
        let (sys, s) = (self.sys, self.settings);
        let phase = if one_off {
            Phase::at(s.omega, t1)
        } else {
            self.phases.advance(self.phase, self.t, dt, t1)
        };
        self.next_phase = phase;
        self.excitation
            .fill_at_phase(sys, phase.cos, phase.sin, true);
        let ctx = context(
            sys,
            s,
            self.tolerance,
            t1,
            dt,
            self.excitation.view(),
            one_off,
        );
        step(
            s,
            &ctx,
            &self.cur,
            &mut self.cache,
            &mut self.ws,
            &mut self.next,
        )
    }

    /// [`Marcher::attempt`], its non-convergence as an error.
    fn converged(&mut self, t1: f64, dt: f64, one_off: bool) -> Result<u32> {
        match self.attempt(t1, dt, one_off)? {
            Ok(its) => Ok(its),
            Err(why) => Err(self.unconverged(why, t1, dt, one_off)),
        }
    }

    /// The error of an adaptive step to `t1` (step `dt`) whose corrector did not converge.
    fn unconverged(&self, why: schemes::Unconverged, t1: f64, dt: f64, one_off: bool) -> Error {
        let ctx = context(
            self.sys,
            self.settings,
            self.tolerance,
            t1,
            dt,
            self.excitation.view(),
            one_off,
        );
        why.error(&ctx)
    }

    /// The outcome: the history, the period summaries and the harmonics of the last period.
    pub fn finish(self) -> MarchOutcome {
        let summaries = self.summaries;
        let history = self.history;
        let last_end = summaries.last().map_or(0, |p| p.end_index);
        let first_of_last = if summaries.len() >= 2 {
            summaries[summaries.len() - 2].end_index
        } else {
            0
        };
        let harmonics = if last_end > first_of_last {
            periodic::harmonics(
                &history,
                self.sys.n,
                self.settings.omega,
                first_of_last,
                last_end,
                self.settings.harmonics,
            )
        } else {
            vec![vec![(0.0, 0.0); self.settings.harmonics + 1]; self.sys.n]
        };
        let steps = history.len() - 1;
        MarchOutcome {
            scheme: self.settings.scheme,
            history,
            periods: summaries,
            steady_period: self.steady_period,
            harmonics,
            steps,
            rejected_steps: self.rejected,
            total_iterations: self.total_iterations,
            step_range: self.step_range,
            factorisations: self.cache.factorisations,
            wall_seconds: self.start.elapsed().as_secs_f64(),
        }
    }
}

/// The steps of one period of the fixed-step march, with the excitation at their ends, in flat
/// arrays (filled once by [`Marcher::new`]).
#[derive(Default)]
struct StepTable {
    /// DOF n and elements E of a row (kept, instead of dividing the lengths by the step count
    /// at every step).
    n: usize,
    ne: usize,
    /// End time of each step within the period (s).
    t: Vec<f64>,
    /// Step size (s).
    dt: Vec<f64>,
    /// Force per DOF at each step's end, [steps × n].
    force: Vec<f64>,
    /// p_t per element, [steps × E].
    pt: Vec<f64>,
    /// p_n per element, [steps × E].
    pn: Vec<f64>,
    /// (cos ωt, sin ωt) at each step's end.
    phase: Vec<(f64, f64)>,
}

impl StepTable {
    fn push(&mut self, t: f64, dt: f64, exc: &Excitation) {
        self.n = exc.force.len();
        self.ne = exc.pt.len();
        self.t.push(t);
        self.dt.push(dt);
        self.force.extend_from_slice(&exc.force);
        self.pt.extend_from_slice(&exc.pt);
        self.pn.extend_from_slice(&exc.pn);
        self.phase.push(exc.phase);
    }

    fn len(&self) -> usize {
        self.t.len()
    }

    /// (end time within the period, step, excitation at the end) of step `j`.
    fn get(&self, j: usize) -> (f64, f64, ExcitationAt<'_>) {
        let (n, ne) = (self.n, self.ne);
        (
            self.t[j],
            self.dt[j],
            ExcitationAt {
                force: &self.force[j * n..(j + 1) * n],
                pt: &self.pt[j * ne..(j + 1) * ne],
                pn: &self.pn[j * ne..(j + 1) * ne],
                phase: self.phase[j],
            },
        )
    }
}

/// The context of a step ending at `t1` after `dt` with the excitation `excitation` there.
fn context<'b>(
    sys: &'b MarchSystem,
    s: &MarchSettings,
    tolerance: f64,
    t1: f64,
    dt: f64,
    excitation: ExcitationAt<'b>,
    one_off: bool,
) -> StepContext<'b> {
    StepContext {
        sys,
        omega: s.omega,
        t1,
        dt,
        tolerance,
        max_iterations: s.max_iterations,
        excitation,
        one_off,
    }
}

/// Marches `sys` with `settings`: [`Marcher::march_period`] for each of the settings' periods,
/// stopping at the first steady period when asked.
pub fn march(sys: &MarchSystem, settings: &MarchSettings) -> Result<MarchOutcome> {
    let mut m = Marcher::new(sys, settings)?;
    for _ in 0..settings.periods {
        let steady = m.march_period()?;
        if steady && settings.stop_at_steady {
            break;
        }
    }
    Ok(m.finish())
}

/// The fixed step of the non-adaptive schemes: the explicit `time_step` (checked for the standard
/// scheme against Δτ/𝕋_stick < 1/π), else min(r·𝕋_stick, largest step) for the Newmark schemes and
/// the largest step for the quasi-static method; shortened so a period holds a whole number of steps.
fn fixed_step(sys: &MarchSystem, s: &MarchSettings, dt_max: f64) -> Result<f64> {
    let period = s.period();
    // the shortest full-stick period (an eigenvalue problem of the model), only where it is used
    let t_stick = || {
        if s.dynamic() {
            sys.shortest_period(&sys.stick_states())
        } else {
            None
        }
    };
    match s.time_step {
        Some(dt) => {
            let checked = (s.scheme == MarchScheme::Newmark).then(t_stick).flatten();
            if let Some(t) = checked {
                if dt / t >= STEP_RATIO_LIMIT {
                    return Err(Error::input(format!(
                        "march settings: the time step {dt:e} s is {:.3} of the shortest natural period 𝕋 = {t:e} s in full stick; standard Newmark's corrector needs Δτ/𝕋 < 1/π ≈ 0.318 (Gastaldi & Berruti 2018 §4.2): use a step below {:e} s",
                        dt / t,
                        STEP_RATIO_LIMIT * t
                    )));
                }
            }
            Ok(dt)
        }
        None => {
            let dt = t_stick().map_or(dt_max, |t| (s.step_ratio * t).min(dt_max));
            let n = (period / dt - 1e-9).ceil().max(1.0);
            Ok(period / n)
        }
    }
}

/// One step of the chosen scheme from `cur` into `next`; returns the iterations, or why the
/// standard corrector did not converge.
fn step(
    s: &MarchSettings,
    ctx: &StepContext,
    cur: &Snapshot,
    cache: &mut Cache,
    ws: &mut Workspace,
    next: &mut Snapshot,
) -> Result<Corrected> {
    match s.scheme {
        MarchScheme::Newmark | MarchScheme::Adaptive => {
            schemes::standard_corrector(ctx, cur, cache, ws, next)
        }
        MarchScheme::PiecewiseLinear | MarchScheme::AdaptivePiecewiseLinear => {
            schemes::piecewise_linear_step(ctx, cur, cache, ws, next).map(Ok)
        }
        MarchScheme::QuasiStatic => schemes::quasi_static_step(ctx, cur, cache, ws, next).map(Ok),
        MarchScheme::MoreauJean | MarchScheme::Carpenter => Err(Error::input(format!(
            "the scheme `{}` does not march friction elements",
            s.scheme
        ))),
    }
}

/// Increments of the prescribed motion from its mean to its value at t = 0 in [`static_start`].
const STATIC_LOAD_STEPS: usize = 20;

/// Static equilibrium at t = 0 along a loading path: first the external force f_e(0) with the
/// prescribed motions at their mean (every contact predicted in stick, sliders at zero), then the
/// prescribed motions brought to their t = 0 values in [`STATIC_LOAD_STEPS`] quasi-static
/// increments, the sliders carried along (friction makes the static state path-dependent).
/// Returns q at t = 0 with the samples of the path's end.
fn static_start(
    sys: &MarchSystem,
    s: &MarchSettings,
    cache: &mut Cache,
) -> Result<(Vec<f64>, Vec<LawSample>)> {
    let (n, ne) = (sys.n, sys.elements.len());
    let mut cur = Snapshot::new(n, ne);
    cur.samples.extend(sys.elements.iter().map(|_| LawSample {
        f_t: 0.0,
        f_n: 0.0,
        state: ContactState::Stick,
        slider: 0.0,
    }));
    let mut next = Snapshot::new(n, ne);
    // the step matrices K + K_c do not depend on the prescribed motions: one cache for the path
    let full = Excitation::at(sys, s.omega, 0.0, false);
    let mut exc = full.clone();
    let mut ws = Workspace::new(sys);
    for j in 0..=STATIC_LOAD_STEPS {
        let scale = j as f64 / STATIC_LOAD_STEPS as f64;
        for (i, e) in sys.elements.iter().enumerate() {
            let mean_t = e.tangential.prescribed.mean;
            let mean_n = e.normal.as_ref().map_or(0.0, |d| d.prescribed.mean);
            exc.pt[i] = mean_t + scale * (full.pt[i] - mean_t);
            exc.pn[i] = mean_n + scale * (full.pn[i] - mean_n);
        }
        let ctx = StepContext {
            sys,
            omega: s.omega,
            t1: 0.0,
            dt: 1.0,
            tolerance: 0.0,
            max_iterations: s.max_iterations,
            excitation: exc.view(),
            one_off: false,
        };
        schemes::quasi_static_step(&ctx, &cur, cache, &mut ws, &mut next)
            .map_err(|e| Error::Compute(format!("initial static equilibrium: {e}")))?;
        std::mem::swap(&mut cur, &mut next);
        cur.kin.v.iter_mut().for_each(|x| *x = 0.0);
    }
    Ok((cur.kin.q, cur.samples))
}

/// The state at t = 0: at rest (q = 0) or in static equilibrium; the acceleration from the
/// equation of motion, M q̈ = f_e + f_c − K q − C q̇.
fn initial_state(sys: &MarchSystem, s: &MarchSettings, cache: &mut Cache) -> Result<Snapshot> {
    let n = sys.n;
    let mut samples = Vec::with_capacity(sys.elements.len());
    let (q, sliders) = match sys.initial {
        InitialCondition::Rest => (vec![0.0; n], vec![0.0; sys.elements.len()]),
        InitialCondition::Static => {
            let (q, path) = static_start(sys, s, cache)?;
            (q, path.iter().map(|x| x.slider).collect())
        }
    };
    schemes::evaluate_law(sys, s.omega, 0.0, &q, &sliders, &mut samples);
    finish_initial(sys, s, q, samples)
}

/// The initial snapshot from q (q̇ = 0) and its samples: q̈ = M⁻¹(f_e + f_c − K q) for the
/// dynamic schemes, 0 for the quasi-static one.
fn finish_initial(
    sys: &MarchSystem,
    s: &MarchSettings,
    q: Vec<f64>,
    samples: Vec<LawSample>,
) -> Result<Snapshot> {
    let n = sys.n;
    let v = vec![0.0; n];
    let mut a = vec![0.0; n];
    if s.dynamic() {
        let mut f = vec![0.0; n];
        sys.external_force(s.omega, 0.0, &mut f);
        schemes::add_contact_force(sys, &samples, &mut f);
        let mut kq = vec![0.0; n];
        super::dense::matvec(&sys.stiffness, &q, &mut kq);
        f.iter_mut().zip(&kq).for_each(|(fi, k)| *fi -= k);
        let minv = super::dense::inverse(&sys.mass, n)
            .ok_or_else(|| Error::input("the mass matrix is singular"))?;
        super::dense::matvec(&minv, &f, &mut a);
    }
    Ok(Snapshot {
        kin: Kinematics { q, v, a },
        samples,
    })
}
