//! The time loop of `nlrom march`: step selection (fixed, or adaptive from the contact state,
//! Gastaldi & Berruti 2018 §4.2), the scheme's step ([`super::schemes`]), the record of every step,
//! and steady-state (periodicity) detection at the end of each excitation period.

use std::collections::HashMap;
use std::time::Instant;

use super::law::{ContactState, LawSample};
use super::periodic;
use super::schemes::{self, Cache, Kinematics, StepContext, StepOutcome};
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

/// Every accepted step (index 0 is the initial state at t = 0).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MarchHistory {
    /// Time (s), \[T\].
    pub time: Vec<f64>,
    /// Displacements, [T × n] row-major.
    pub q: Vec<f64>,
    /// Velocities, [T × n].
    pub v: Vec<f64>,
    /// Per element (u_t, v) relative displacements (m), [T × E × 2].
    pub local: Vec<f64>,
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

    fn push(
        &mut self,
        sys: &MarchSystem,
        omega: f64,
        t: f64,
        kin: &Kinematics,
        s: &[LawSample],
        it: u32,
    ) {
        self.time.push(t);
        self.q.extend_from_slice(&kin.q);
        self.v.extend_from_slice(&kin.v);
        for (e, smp) in sys.elements.iter().zip(s) {
            let l = e.local(&kin.q, omega, t);
            self.local.extend_from_slice(&[l.ut, l.v]);
            self.force.extend_from_slice(&[smp.f_t, smp.f_n]);
            self.state.push(smp.state.code());
        }
        self.iterations.push(it);
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

/// The state the loop carries from one step to the next.
struct Current {
    t: f64,
    kin: Kinematics,
    samples: Vec<LawSample>,
}

impl Current {
    fn states(&self) -> Vec<ContactState> {
        self.samples.iter().map(|s| s.state).collect()
    }

    fn sliders(&self) -> Vec<f64> {
        self.samples.iter().map(|s| s.slider).collect()
    }
}

/// Marches `sys` with `settings`.
pub fn march(sys: &MarchSystem, settings: &MarchSettings) -> Result<MarchOutcome> {
    settings.validate()?;
    sys.validate("march model")?;
    if settings.dynamic() && !sys.mass_is_positive_definite() {
        return Err(Error::input(format!(
            "the {} scheme integrates inertia, but the model's mass matrix is not positive definite (a model without mass); use the quasi-static scheme or give the model mass",
            settings.scheme
        )));
    }
    let start = Instant::now();
    let mut cache = Cache::default();
    let tol = settings.tolerance * sys.displacement_scale;
    let period = settings.period();
    let dt_max = period / settings.steps_per_period as f64;
    let fixed_dt = fixed_step(sys, settings, dt_max)?;
    let mut periods_dt: HashMap<Vec<u8>, f64> = HashMap::new();
    let mut dt_for = |states: &[ContactState]| -> f64 {
        let key: Vec<u8> = states.iter().map(|s| s.code()).collect();
        *periods_dt.entry(key).or_insert_with(|| {
            sys.shortest_period(states)
                .map_or(dt_max, |t| (settings.step_ratio * t).min(dt_max))
        })
    };

    let mut cur = initial_state(sys, settings, &mut cache)?;
    let mut history = MarchHistory::default();
    history.push(sys, settings.omega, 0.0, &cur.kin, &cur.samples, 0);
    let mut summaries = Vec::new();
    let mut steady_period = None;
    let (mut rejected, mut total_it) = (0usize, 0u64);
    let (mut dt_min, mut dt_maxu) = (f64::INFINITY, 0.0f64);
    let mut prev_end = (cur.kin.q.clone(), cur.kin.v.clone());
    for p in 0..settings.periods {
        let t_end = (p + 1) as f64 * period;
        let first_index = history.len() - 1;
        while t_end - cur.t > 1e-9 * period {
            let remaining = t_end - cur.t;
            let mut dt = if settings.adaptive() {
                dt_for(&cur.states())
            } else {
                fixed_dt
            };
            if dt > remaining * (1.0 - 1e-9) {
                dt = remaining;
            }
            let mut out = step(sys, settings, &cur, dt, tol, &mut cache)?;
            let mut its = out.iterations as u64;
            if settings.adaptive() {
                // paper §4.2: re-run with the smaller step the new state asks for
                for _ in 0..8 {
                    let states: Vec<ContactState> = out.samples.iter().map(|s| s.state).collect();
                    let dt_new = dt_for(&states);
                    if dt_new >= dt * (1.0 - 1e-12) {
                        break;
                    }
                    dt = dt_new;
                    rejected += 1;
                    out = step(sys, settings, &cur, dt, tol, &mut cache)?;
                    its += out.iterations as u64;
                }
            }
            total_it += its;
            dt_min = dt_min.min(dt);
            dt_maxu = dt_maxu.max(dt);
            cur = Current {
                t: if dt == remaining { t_end } else { cur.t + dt },
                kin: out.kin,
                samples: out.samples,
            };
            history.push(
                sys,
                settings.omega,
                cur.t,
                &cur.kin,
                &cur.samples,
                its.min(u32::MAX as u64) as u32,
            );
        }
        let end_index = history.len() - 1;
        let summary = periodic::summarize(
            &history,
            sys,
            settings.omega,
            first_index,
            end_index,
            &prev_end,
            p > 0,
        );
        prev_end = (cur.kin.q.clone(), cur.kin.v.clone());
        let steady = summary
            .periodicity_error
            .is_some_and(|e| e < settings.steady_tolerance);
        summaries.push(summary);
        if steady && steady_period.is_none() {
            steady_period = Some(p + 1);
            if settings.stop_at_steady {
                break;
            }
        }
    }
    let last = summaries.last().expect("at least one period");
    let first_of_last = if summaries.len() >= 2 {
        summaries[summaries.len() - 2].end_index
    } else {
        0
    };
    let harmonics = periodic::harmonics(
        &history,
        sys.n,
        settings.omega,
        first_of_last,
        last.end_index,
        settings.harmonics,
    );
    let steps = history.len() - 1;
    Ok(MarchOutcome {
        scheme: settings.scheme,
        history,
        periods: summaries,
        steady_period,
        harmonics,
        steps,
        rejected_steps: rejected,
        total_iterations: total_it,
        step_range: (dt_min, dt_maxu),
        factorisations: cache.factorisations,
        wall_seconds: start.elapsed().as_secs_f64(),
    })
}

/// The fixed step of the non-adaptive schemes: the explicit `time_step` (checked for the standard
/// scheme against Δτ/𝕋_stick < 1/π), else min(r·𝕋_stick, largest step) for the Newmark schemes and
/// the largest step for the quasi-static method; shortened so a period holds a whole number of steps.
fn fixed_step(sys: &MarchSystem, s: &MarchSettings, dt_max: f64) -> Result<f64> {
    let period = s.period();
    let t_stick = if s.dynamic() {
        sys.shortest_period(&sys.stick_states())
    } else {
        None
    };
    match s.time_step {
        Some(dt) => {
            if let (MarchScheme::Newmark, Some(t)) = (s.scheme, t_stick) {
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
            let dt = t_stick.map_or(dt_max, |t| (s.step_ratio * t).min(dt_max));
            let n = (period / dt - 1e-9).ceil().max(1.0);
            Ok(period / n)
        }
    }
}

/// One step of the chosen scheme from `cur` over `dt`.
fn step(
    sys: &MarchSystem,
    s: &MarchSettings,
    cur: &Current,
    dt: f64,
    tol: f64,
    cache: &mut Cache,
) -> Result<StepOutcome> {
    let ctx = StepContext {
        sys,
        omega: s.omega,
        t1: cur.t + dt,
        dt,
        tolerance: tol,
        max_iterations: s.max_iterations,
    };
    let sliders = cur.sliders();
    match s.scheme {
        MarchScheme::Newmark | MarchScheme::Adaptive => {
            schemes::standard_step(&ctx, &cur.kin, &sliders, cache)
        }
        MarchScheme::PiecewiseLinear | MarchScheme::AdaptivePiecewiseLinear => {
            schemes::piecewise_linear_step(&ctx, &cur.kin, &cur.states(), &sliders, cache)
        }
        MarchScheme::QuasiStatic => {
            schemes::quasi_static_step(&ctx, &cur.kin, &cur.states(), &sliders, cache)
        }
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
/// Returns q at t = 0 with the sliders of the path's end in `sliders`.
fn static_start(
    sys: &MarchSystem,
    s: &MarchSettings,
    cache: &mut Cache,
) -> Result<(Vec<f64>, Vec<f64>)> {
    let n = sys.n;
    let mut kin = Kinematics {
        q: vec![0.0; n],
        v: vec![0.0; n],
        a: vec![0.0; n],
    };
    let mut states = sys.stick_states();
    let mut sliders = vec![0.0; sys.elements.len()];
    for j in 0..=STATIC_LOAD_STEPS {
        let scale = j as f64 / STATIC_LOAD_STEPS as f64;
        let mut scaled = sys.clone();
        for e in &mut scaled.elements {
            for d in std::iter::once(&mut e.tangential).chain(e.normal.as_mut()) {
                d.prescribed.cos *= scale;
                d.prescribed.sin *= scale;
            }
        }
        let ctx = StepContext {
            sys: &scaled,
            omega: s.omega,
            t1: 0.0,
            dt: 1.0,
            tolerance: 0.0,
            max_iterations: s.max_iterations,
        };
        let mut fresh = Cache::default();
        let out = schemes::quasi_static_step(&ctx, &kin, &states, &sliders, &mut fresh)
            .map_err(|e| Error::Compute(format!("initial static equilibrium: {e}")))?;
        cache.factorisations += fresh.factorisations;
        states = out.samples.iter().map(|x| x.state).collect();
        sliders = out.samples.iter().map(|x| x.slider).collect();
        kin.q = out.kin.q;
    }
    Ok((kin.q, sliders))
}

/// The state at t = 0: at rest (q = 0) or in static equilibrium; the acceleration from the
/// equation of motion, M q̈ = f_e + f_c − K q − C q̇.
fn initial_state(sys: &MarchSystem, s: &MarchSettings, cache: &mut Cache) -> Result<Current> {
    let n = sys.n;
    let mut samples = Vec::new();
    let (q, sliders) = match sys.initial {
        InitialCondition::Rest => (vec![0.0; n], vec![0.0; sys.elements.len()]),
        InitialCondition::Static => static_start(sys, s, cache)?,
    };
    schemes::evaluate_law(sys, s.omega, 0.0, &q, &sliders, &mut samples);
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
    Ok(Current {
        t: 0.0,
        kin: Kinematics { q, v, a },
        samples,
    })
}
