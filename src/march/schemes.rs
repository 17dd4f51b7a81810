//! One time step of each scheme of Gastaldi & Berruti 2018:
//! - [`standard_step`]: Newmark-β (β = 1/4, γ = 1/2) with the predictor–corrector of Appendix A.3
//!   (constant-displacement predictor, fixed-point corrector on the unbalanced force);
//! - [`piecewise_linear_step`]: the piecewise-linear Newmark of §4.3 / Appendix A.4 (predict the
//!   contact states unchanged, solve the linear step, verify the states with the law, re-solve only
//!   at a transition);
//! - [`quasi_static_step`]: the quasi-static method of §5.2 / eq. 10 / Appendix B (no inertia).
//!
//! Symbols: q, q̇, q̈ at τ_n (the [`Kinematics`]), Δτ the step (s), w the sliders at τ_n (m).
//! Newmark's relations (eq. A7) in displacement form: q̈₁ = (q₁ − q*)/(βΔτ²), q̇₁ = v* + γΔτ q̈₁ with
//! q* = q + Δτ q̇ + Δτ²(½ − β) q̈ and v* = q̇ + Δτ(1 − γ) q̈.

use std::collections::HashMap;

use super::dense;
use super::law::{ContactState, LawSample};
use super::lowrank::{self, LowRank};
use super::system::MarchSystem;
use crate::error::{Error, Result};

/// Newmark's β (constant average acceleration).
pub const BETA: f64 = 0.25;
/// Newmark's γ.
pub const GAMMA: f64 = 0.5;

/// Displacement (m), velocity (m/s), acceleration (m/s²) vectors at one instant.
#[derive(Clone, Debug, PartialEq)]
pub struct Kinematics {
    /// q.
    pub q: Vec<f64>,
    /// q̇.
    pub v: Vec<f64>,
    /// q̈.
    pub a: Vec<f64>,
}

/// The converged end of a step.
#[derive(Clone, Debug)]
pub struct StepOutcome {
    /// q, q̇, q̈ at τ_{n+1}.
    pub kin: Kinematics,
    /// The law's sample of every element at τ_{n+1} (forces, states, updated sliders).
    pub samples: Vec<LawSample>,
    /// Corrector iterations (contact-law evaluations of the whole system) the step took.
    pub iterations: u32,
}

/// Most memory (bytes) the factors of one step size's contact states may take: a model with many
/// elements (a sector's shroud pairs) meets many state combinations during a transient; beyond
/// this the cached factors of that step are dropped and rebuilt as the states recur.
pub const MAX_CACHED_BYTES: usize = 256 << 20;

/// How the step matrix of one contact state is solved.
enum StepFactor {
    /// Its inverse (n × n).
    Full(Vec<f64>),
    /// A low-rank change of the all-stick step matrix ([`LowRank`]), when the rank is below n/2.
    LowRank(LowRank),
}

impl StepFactor {
    fn entries(&self) -> usize {
        match self {
            StepFactor::Full(a) => a.len(),
            StepFactor::LowRank(l) => l.len(),
        }
    }
}

/// Factors of the step matrices, kept while the step and the contact states repeat.
#[derive(Default)]
pub struct Cache {
    /// Δτ bits → (M/(βΔτ²) + γC/(βΔτ) + K)⁻¹ for the standard corrector.
    structural: HashMap<u64, Vec<f64>>,
    /// Δτ bits (0 for the quasi-static method) → state codes → factor of the step matrix, with
    /// the f64 entries held.
    piecewise: HashMap<u64, (HashMap<Vec<u8>, StepFactor>, usize)>,
    /// Δτ bits (0 for the quasi-static method) → inverse of the all-stick step matrix.
    stick: HashMap<u64, Vec<f64>>,
    /// Number of factorisations made.
    pub factorisations: usize,
}

impl Cache {
    /// x = A⁻¹ b for the piecewise-linear step matrix A of the contact `states` (codes `codes`;
    /// `k` = K + K_c(states); A adds M/(βΔτ²) + γC/(βΔτ) when `dynamic`): its factor is cached per
    /// step size (key Δτ bits, 0 for the quasi-static method) within [`MAX_CACHED_BYTES`], as
    /// the inverse, or as a low-rank change of the all-stick inverse when the states differ from
    /// full stick by a rank below n/2 ([`super::lowrank`]).
    #[allow(clippy::too_many_arguments)]
    fn step_solve(
        &mut self,
        ctx: &StepContext,
        dynamic: bool,
        states: &[ContactState],
        codes: &[u8],
        k: &[f64],
        b: &[f64],
        x: &mut [f64],
    ) -> Result<()> {
        let (sys, n) = (ctx.sys, ctx.sys.n);
        let dt_key = if dynamic { ctx.dt.to_bits() } else { 0 };
        let step_matrix = |k: &[f64]| {
            if dynamic {
                dynamic_matrix(sys, ctx.dt, k)
            } else {
                k.to_vec()
            }
        };
        let (per, held) = self.piecewise.entry(dt_key).or_default();
        if !per.contains_key(codes) {
            let cols = lowrank::columns(&sys.elements, states);
            let mut factor = None;
            if 2 * cols.len() < n {
                if let std::collections::hash_map::Entry::Vacant(e) = self.stick.entry(dt_key) {
                    let a = step_matrix(&sys.effective_stiffness(&sys.stick_states()));
                    if let Some(inv) = dense::inverse(&a, n) {
                        e.insert(inv);
                        self.factorisations += 1;
                    }
                }
                factor = self
                    .stick
                    .get(&dt_key)
                    .and_then(|inv| LowRank::new(inv, n, cols).map(StepFactor::LowRank));
            }
            let factor = match factor {
                Some(f) => f,
                None => StepFactor::Full(
                    dense::inverse(&step_matrix(k), n)
                        .ok_or_else(|| singular(sys, step_name(dynamic), ctx.t1, codes))?,
                ),
            };
            if (*held + factor.entries()) * std::mem::size_of::<f64>() > MAX_CACHED_BYTES {
                per.clear();
                *held = 0;
            }
            *held += factor.entries();
            per.insert(codes.to_vec(), factor);
            self.factorisations += 1;
        }
        match &per[codes] {
            StepFactor::Full(inv) => dense::matvec(inv, b, x),
            StepFactor::LowRank(l) => l.solve(&self.stick[&dt_key], b, x),
        }
        Ok(())
    }
}

/// The name of the piecewise-linear step in messages.
fn step_name(dynamic: bool) -> &'static str {
    if dynamic {
        "piecewise-linear Newmark"
    } else {
        "quasi-static (K + K_c)"
    }
}

/// Where and when a step is taken.
#[derive(Clone, Copy, Debug)]
pub struct StepContext<'a> {
    /// The model.
    pub sys: &'a MarchSystem,
    /// Excitation frequency ω (rad/s).
    pub omega: f64,
    /// τ_{n+1} (s).
    pub t1: f64,
    /// Δτ (s).
    pub dt: f64,
    /// Absolute displacement tolerance of the standard corrector (m).
    pub tolerance: f64,
    /// Most corrector iterations.
    pub max_iterations: u32,
}

/// The law at q for every element, from the sliders `w` at τ_n.
pub fn evaluate_law(
    sys: &MarchSystem,
    omega: f64,
    t: f64,
    q: &[f64],
    w: &[f64],
    out: &mut Vec<LawSample>,
) {
    out.clear();
    out.extend(
        sys.elements
            .iter()
            .zip(w)
            .map(|(e, &wi)| e.sample(e.local(q, omega, t), wi)),
    );
}

/// The contact force f_c = Σ −g_t f_t − g_n f_n of the samples, added to `f`.
pub fn add_contact_force(sys: &MarchSystem, samples: &[LawSample], f: &mut [f64]) {
    for (e, s) in sys.elements.iter().zip(samples) {
        e.add_force(s.f_t, s.f_n, f);
    }
}

/// State codes of the samples (the cache key and the state comparison).
pub fn state_codes(samples: &[LawSample], out: &mut Vec<u8>) {
    out.clear();
    out.extend(samples.iter().map(|s| s.state.code()));
}

/// q* and v* of Newmark's relations.
fn newmark_predictors(k: &Kinematics, dt: f64) -> (Vec<f64>, Vec<f64>) {
    let qs = (0..k.q.len())
        .map(|i| k.q[i] + dt * k.v[i] + dt * dt * (0.5 - BETA) * k.a[i])
        .collect();
    let vs = (0..k.q.len())
        .map(|i| k.v[i] + dt * (1.0 - GAMMA) * k.a[i])
        .collect();
    (qs, vs)
}

/// q̈₁, q̇₁ from q₁ by Newmark's relations.
fn newmark_rates(q1: &[f64], qs: &[f64], vs: &[f64], dt: f64) -> (Vec<f64>, Vec<f64>) {
    let a1: Vec<f64> = q1
        .iter()
        .zip(qs)
        .map(|(q, s)| (q - s) / (BETA * dt * dt))
        .collect();
    let v1 = vs
        .iter()
        .zip(&a1)
        .map(|(v, a)| v + GAMMA * dt * a)
        .collect();
    (a1, v1)
}

/// The step matrix M/(βΔτ²) + γC/(βΔτ) + K_eff (row-major) for a stiffness `k_eff`.
fn dynamic_matrix(sys: &MarchSystem, dt: f64, k_eff: &[f64]) -> Vec<f64> {
    let cm = 1.0 / (BETA * dt * dt);
    let cc = GAMMA / (BETA * dt);
    k_eff
        .iter()
        .zip(&sys.mass)
        .zip(&sys.damping)
        .map(|((k, m), c)| k + cm * m + cc * c)
        .collect()
}

fn singular(sys: &MarchSystem, what: &str, t: f64, states: &[u8]) -> Error {
    let names: Vec<String> = sys
        .elements
        .iter()
        .zip(states)
        .map(|(e, s)| format!("{}={}", e.name, state_name(*s)))
        .collect();
    Error::Compute(format!(
        "the {what} matrix is singular at t = {t:.6e} s with contact states [{}]: the model has an unrestrained motion in this state (e.g. every contact separated and no structural stiffness)",
        names.join(", ")
    ))
}

/// A state code's name: separated, stick, slip+, slip−.
pub fn state_name(code: u8) -> &'static str {
    match code {
        0 => "separated",
        1 => "stick",
        2 => "slip+",
        _ => "slip-",
    }
}

/// Standard Newmark-β step, Appendix A.3 generalised to C, K ≠ 0: predictor q̃ = q_n; then repeat
/// (A9) R = M q̈̃ + C q̇̃ + K q̃ − f_e(τ_{n+1}) − f_c(q̃), (A10) Δq = −S⁻¹ R with
/// S = M/(βΔτ²) + γC/(βΔτ) + K (the paper's M/(βΔτ²) for the rigid damper), (A11) q̃ += Δq, until
/// |Δq|_∞ < tol. The contact force is the law's, from the sliders at τ_n. The fixed point
/// converges for Δτ/𝕋 < 1/π (paper §4.2, 0.318).
pub fn standard_step(
    ctx: &StepContext,
    start: &Kinematics,
    sliders: &[f64],
    cache: &mut Cache,
) -> Result<StepOutcome> {
    let sys = ctx.sys;
    let (n, dt) = (sys.n, ctx.dt);
    let key = dt.to_bits();
    let sinv = match cache.structural.entry(key) {
        std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
        std::collections::hash_map::Entry::Vacant(e) => {
            let s = dynamic_matrix(sys, dt, &sys.stiffness);
            let inv = dense::inverse(&s, n).ok_or_else(|| {
                Error::Compute(format!(
                    "the Newmark matrix M/(βΔτ²) + γC/(βΔτ) + K is singular (Δτ = {dt:e} s): the model needs mass"
                ))
            })?;
            cache.factorisations += 1;
            e.insert(inv)
        }
    };
    let (qs, vs) = newmark_predictors(start, dt);
    let mut q = start.q.clone();
    let mut f = vec![0.0; n];
    let mut r = vec![0.0; n];
    let mut dq = vec![0.0; n];
    let mut samples = Vec::with_capacity(sys.elements.len());
    for it in 1..=ctx.max_iterations {
        let (a1, v1) = newmark_rates(&q, &qs, &vs, dt);
        evaluate_law(sys, ctx.omega, ctx.t1, &q, sliders, &mut samples);
        sys.dynamic_force(ctx.omega, ctx.t1, &mut f);
        add_contact_force(sys, &samples, &mut f);
        // R = M a + C v + K q − f
        dense::matvec(&sys.mass, &a1, &mut r);
        dense::matvec_add(&sys.damping, &v1, &mut r);
        dense::matvec_add(&sys.stiffness, &q, &mut r);
        r.iter_mut().zip(&f).for_each(|(ri, fi)| *ri -= fi);
        dense::matvec(sinv, &r, &mut dq);
        q.iter_mut().zip(&dq).for_each(|(qi, d)| *qi -= d);
        if dense::norm_inf(&dq) < ctx.tolerance {
            let (a1, v1) = newmark_rates(&q, &qs, &vs, dt);
            evaluate_law(sys, ctx.omega, ctx.t1, &q, sliders, &mut samples);
            return Ok(StepOutcome {
                kin: Kinematics { q, v: v1, a: a1 },
                samples,
                iterations: it,
            });
        }
    }
    Err(Error::Compute(format!(
        "standard Newmark: the corrector did not converge in {} iterations at t = {:.6e} s (Δτ = {dt:e} s); the fixed point needs Δτ/𝕋 < 1/π — lower `step_ratio` or the time step",
        ctx.max_iterations, ctx.t1
    )))
}

/// The piecewise-linear solve shared by the dynamic and the quasi-static methods: with the states
/// predicted unchanged from `states0`, solve A(states) q₁ = b(states) with
/// A = `mass_term` + K + K_c(states) (`mass_term` adds M/(βΔτ²) + γC/(βΔτ) for Newmark, nothing for
/// the quasi-static method) and b = f_e + r_c(states, w) + `b_extra`; verify the states with the
/// law at q₁; re-solve with the law's states until they agree (Appendix A.4 steps 2–6, Appendix B).
/// Returns `Err(iterations)` if the state iteration cycles or exceeds the iteration limit.
#[allow(clippy::type_complexity)]
fn state_iteration(
    ctx: &StepContext,
    dynamic: bool,
    states0: &[ContactState],
    sliders: &[f64],
    b_extra: &[f64],
    cache: &mut Cache,
) -> Result<std::result::Result<(Vec<f64>, Vec<LawSample>, u32), u32>> {
    let sys = ctx.sys;
    let n = sys.n;
    let mut states: Vec<ContactState> = states0.to_vec();
    let mut codes: Vec<u8> = states.iter().map(|s| s.code()).collect();
    let mut seen: Vec<Vec<u8>> = Vec::new();
    let mut k = vec![0.0; n * n];
    let mut rc = vec![0.0; n];
    let mut f = vec![0.0; n];
    let mut q1 = vec![0.0; n];
    let mut samples = Vec::with_capacity(states.len());
    let mut law_codes = Vec::with_capacity(states.len());
    for it in 1..=ctx.max_iterations {
        sys.linear_piece(&states, sliders, ctx.omega, ctx.t1, &mut k, &mut rc);
        if dynamic {
            sys.dynamic_force(ctx.omega, ctx.t1, &mut f);
        } else {
            sys.external_force(ctx.omega, ctx.t1, &mut f);
        }
        for i in 0..n {
            f[i] += rc[i] + b_extra[i];
        }
        cache.step_solve(ctx, dynamic, &states, &codes, &k, &f, &mut q1)?;
        evaluate_law(sys, ctx.omega, ctx.t1, &q1, sliders, &mut samples);
        state_codes(&samples, &mut law_codes);
        if law_codes == codes {
            return Ok(Ok((q1, samples, it)));
        }
        seen.push(std::mem::replace(&mut codes, law_codes.clone()));
        if seen.contains(&codes) {
            return Ok(Err(it));
        }
        states.clear();
        states.extend(samples.iter().map(|s| s.state));
    }
    Ok(Err(ctx.max_iterations))
}

/// Piecewise-linear Newmark step (paper §4.3, Appendix A.4, eqs A12–A16): the contact states at
/// τ_{n+1} are predicted equal to those at τ_n, the linear Newmark step of eq. A13/A15 is solved, the
/// states are verified by the law and the step re-solved only at a transition. If the state
/// iteration cycles (a tie at a stick/slip boundary; frequent with many elements) the step falls
/// back to damped Newton on the same piecewise-linear equation (unlike the standard corrector it
/// needs no step limit), and the iterations of both are counted.
pub fn piecewise_linear_step(
    ctx: &StepContext,
    start: &Kinematics,
    states: &[ContactState],
    sliders: &[f64],
    cache: &mut Cache,
) -> Result<StepOutcome> {
    let sys = ctx.sys;
    let dt = ctx.dt;
    let (qs, vs) = newmark_predictors(start, dt);
    // b_extra = M q*/(βΔτ²) + C (γ q*/(βΔτ) − v*)
    let cm = 1.0 / (BETA * dt * dt);
    let cc = GAMMA / (BETA * dt);
    let mq: Vec<f64> = qs.iter().map(|x| cm * x).collect();
    let cq: Vec<f64> = qs.iter().zip(&vs).map(|(q, v)| cc * q - v).collect();
    let mut extra = vec![0.0; sys.n];
    dense::matvec(&sys.mass, &mq, &mut extra);
    dense::matvec_add(&sys.damping, &cq, &mut extra);
    let (q1, samples, iterations) =
        match state_iteration(ctx, true, states, sliders, &extra, cache)? {
            Ok(solved) => solved,
            Err(tried) => {
                let (q1, samples, its) =
                    damped_newton(ctx, true, &start.q, sliders, &extra, cache)?;
                (q1, samples, tried + its)
            }
        };
    let (a1, v1) = newmark_rates(&q1, &qs, &vs, dt);
    Ok(StepOutcome {
        kin: Kinematics {
            q: q1,
            v: v1,
            a: a1,
        },
        samples,
        iterations,
    })
}

/// Quasi-static step (paper §5.2, eq. 10, Appendix B, eqs A17–A20): (K + K_c) q₁ = f_e + r_c with
/// the states predicted unchanged and verified by the law. q̇₁ = (q₁ − q_n)/Δτ, q̈₁ = 0.
pub fn quasi_static_step(
    ctx: &StepContext,
    start: &Kinematics,
    states: &[ContactState],
    sliders: &[f64],
    cache: &mut Cache,
) -> Result<StepOutcome> {
    let extra = vec![0.0; ctx.sys.n];
    let (q1, samples, iterations) =
        match state_iteration(ctx, false, states, sliders, &extra, cache)? {
            Ok(found) => found,
            Err(tried) => {
                let (q, s, its) = damped_newton(ctx, false, &start.q, sliders, &extra, cache)?;
                (q, s, tried + its)
            }
        };
    let v1 = q1
        .iter()
        .zip(&start.q)
        .map(|(a, b)| (a - b) / ctx.dt)
        .collect();
    Ok(StepOutcome {
        kin: Kinematics {
            q: q1,
            v: v1,
            a: vec![0.0; ctx.sys.n],
        },
        samples,
        iterations,
    })
}

/// ‖f + b_extra + f_c(q) − A q‖_∞ with the law's forces from the sliders `w`: the residual of
/// the piecewise-linear step, A = M/(βΔτ²) + γC/(βΔτ) + K and f the dynamic force when
/// `dynamic` (Newmark, eq. A13 with q̈₁, q̇₁ from q₁), else A = K and f = f_e (quasi-static).
#[allow(clippy::too_many_arguments)]
fn step_residual(
    ctx: &StepContext,
    dynamic: bool,
    q: &[f64],
    w: &[f64],
    b_extra: &[f64],
    r: &mut [f64],
    aq: &mut [f64],
    samples: &mut Vec<LawSample>,
) -> f64 {
    let sys = ctx.sys;
    evaluate_law(sys, ctx.omega, ctx.t1, q, w, samples);
    if dynamic {
        sys.dynamic_force(ctx.omega, ctx.t1, r);
        let cm = 1.0 / (BETA * ctx.dt * ctx.dt);
        let cc = GAMMA / (BETA * ctx.dt);
        dense::matvec(&sys.mass, q, aq);
        aq.iter_mut().for_each(|x| *x *= cm);
        let mut cq = vec![0.0; sys.n];
        dense::matvec(&sys.damping, q, &mut cq);
        aq.iter_mut().zip(&cq).for_each(|(a, c)| *a += cc * c);
        dense::matvec_add(&sys.stiffness, q, aq);
    } else {
        sys.external_force(ctx.omega, ctx.t1, r);
        dense::matvec(&sys.stiffness, q, aq);
    }
    add_contact_force(sys, samples, r);
    r.iter_mut()
        .zip(aq.iter().zip(b_extra))
        .for_each(|(ri, (a, b))| *ri += b - a);
    dense::norm_inf(r)
}

/// Fallback of the piecewise-linear and quasi-static steps when the state iteration cycles (the
/// solution sits on a stick/slip or slip-sign boundary, frequent with many elements): Newton on
/// the continuous piecewise-linear residual of [`step_residual`] with the state's tangent
/// A + K_c and a backtracking line search on ‖r‖_∞, from `q0`, until the update is below the
/// tolerance (or 1e-9 of the displacement scale).
fn damped_newton(
    ctx: &StepContext,
    dynamic: bool,
    q0: &[f64],
    sliders: &[f64],
    b_extra: &[f64],
    cache: &mut Cache,
) -> Result<(Vec<f64>, Vec<LawSample>, u32)> {
    let sys = ctx.sys;
    let n = sys.n;
    let tol = ctx.tolerance.max(1e-9 * sys.displacement_scale);
    let mut q = q0.to_vec();
    let mut samples = Vec::new();
    let mut trial_samples = Vec::new();
    let mut r = vec![0.0; n];
    let mut r_trial = vec![0.0; n];
    let mut aq = vec![0.0; n];
    let mut k = vec![0.0; n * n];
    let mut rc = vec![0.0; n];
    let mut codes = Vec::new();
    let mut norm = step_residual(
        ctx,
        dynamic,
        &q,
        sliders,
        b_extra,
        &mut r,
        &mut aq,
        &mut samples,
    );
    for it in 1..=ctx.max_iterations {
        let states: Vec<ContactState> = samples.iter().map(|s| s.state).collect();
        state_codes(&samples, &mut codes);
        sys.linear_piece(&states, sliders, ctx.omega, ctx.t1, &mut k, &mut rc);
        let mut dq = vec![0.0; n];
        cache.step_solve(ctx, dynamic, &states, &codes, &k, &r, &mut dq)?;
        let mut lambda = 1.0;
        loop {
            let qt: Vec<f64> = q.iter().zip(&dq).map(|(a, d)| a + lambda * d).collect();
            let nt = step_residual(
                ctx,
                dynamic,
                &qt,
                sliders,
                b_extra,
                &mut r_trial,
                &mut aq,
                &mut trial_samples,
            );
            if nt < (1.0 - 1e-4 * lambda) * norm || lambda < 1e-6 {
                q = qt;
                norm = nt;
                std::mem::swap(&mut r, &mut r_trial);
                std::mem::swap(&mut samples, &mut trial_samples);
                break;
            }
            lambda *= 0.5;
        }
        if lambda * dense::norm_inf(&dq) < tol {
            return Ok((q, samples, it));
        }
    }
    Err(Error::Compute(format!(
        "{}: no solution of the step found at t = {:.6e} s in {} Newton iterations (the contact states cycle); try another number of steps per period",
        step_name(dynamic),
        ctx.t1,
        ctx.max_iterations
    )))
}
