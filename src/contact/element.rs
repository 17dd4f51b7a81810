//! One contact element over one period: AFT evaluation of the time-discrete law of [`law`] on
//! local harmonic coefficients, periodic marching of the slider state, the analytic Jacobian and
//! the per-element state report (SAMA paper, Battiato 2021, §3 eqs 13–14 and 25; `docs/theory.md`).
//!
//! Local coefficients are stored signal by signal (each in the signal order of [`aft`]):
//! `[U1; U2; V]` (m each, m = 2H+1) where U1, U2 are the tangential relative displacements (m)
//! and V the normal approach (m). An element may have one or two tangential directions and may
//! have no normal kinematics (then v ≡ 0, f_n = max(n0, 0)); absent signals are left out of the
//! vector. The forces `[F1; F2; Fn]` (N) come in the same order, with the internal-force sign of
//! [`law`].
//!
//! The evaluated map is F(Q): the last period of the marching from the slider state at rest
//! ([`REST`]) until the end-of-period state repeats (at most [`MAX_PERIODS`]). It depends on Q
//! alone, so the harmonic balance residual is a function of the unknowns and the continuation
//! follows one curve: a slider that sticks all period (or slips one way only, a shakedown) has no
//! periodic position of its own, and one carried from point to point would make the solutions
//! depend on the path's history. The caller's slider state is a warm start, used as is where
//! it gives the same periodic state (every direction slips both ways or separates in the last
//! period: the slider is then set by the motion alone) and replaced by [`REST`] elsewhere.
//! Periods are marched from the start state until the end-of-period state repeats; the forces
//! are those of the last period. The Jacobian is the exact
//! derivative of this map F(Q; w_in) for the start state w_in used
//! (Newton needs ∂F/∂Q of exactly the map it evaluates): ∂w/∂Q is carried through the samples of
//! the last period (`docs/theory.md`) with two extra columns for ∂w_start, closed per direction:
//! * a direction that slips or separates in the last period: by periodicity w_start = w_end —
//!   a perturbed input is marched on to its own periodic state, and the 1-D end state does not
//!   depend on the start state at all (Φ = 0), so this equals the chain through the periods;
//! * a direction stuck all the last period (Φ = 1, end state = start state for every input):
//!   ∂w_start is ∂w carried through the transient periods from ∂w_in = 0
//!   (`march_transient_chain`) — zero when one period was marched (w_in already periodic:
//!   the fast path), the slip-set slider derivative after a shakedown (a transient slip set
//!   w = u − μ f_n/k_t; treating the stuck slider as fixed would give the static slope k_t
//!   where the map's is 0). The chain is marched again only in this case (rare, cheap).
//!
//! [`law`]: super::law
//! [`aft`]: super::aft

use faer::linalg::matmul::matmul;
use faer::{Accum, MatMut, MatRef, Par};

use crate::case::Evaluation;
use crate::contact::aft::{Aft, AftScratch};
use crate::contact::exact;
use crate::contact::law::{self, ContactParams, Regime, Variant};
use crate::contact::microslip;
use crate::error::{Error, Result};

/// Most periods marched before the last one is accepted without a repeated state.
pub const MAX_PERIODS: usize = 10;

/// Relative tolerance on the end-of-period slider state (relative to the largest tangential
/// displacement or slider position) for "the state repeats".
pub const STATE_TOLERANCE: f64 = 1e-13;

/// The description of one element's local kinematics and law.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LocalElement {
    /// Contact parameters.
    pub params: ContactParams,
    /// 1-D (independent directions) or 2-D (Coulomb disc) tangential law.
    pub variant: Variant,
    /// Number of tangential directions, 1 or 2 (the 2-D variant needs 2).
    pub tangential: usize,
    /// Whether the element has normal kinematics v (else v ≡ 0).
    pub normal: bool,
}

impl LocalElement {
    /// Number of local signals: tangential directions plus one if there is a normal direction.
    pub fn signals(&self) -> usize {
        self.tangential + usize::from(self.normal)
    }

    /// An input error unless the law has as many tangential directions as it needs (1 or 2 for
    /// the 1-D law, 2 for the 2-D law).
    pub(crate) fn check(&self) -> Result<()> {
        if !(1..=2).contains(&self.tangential)
            || (self.variant == Variant::TwoD && self.tangential != 2)
        {
            return Err(Error::input(format!(
                "contact element with {} tangential direction(s) and the {:?} law: the 1-D law needs 1 or 2 directions, the 2-D law exactly 2",
                self.tangential, self.variant
            )));
        }
        Ok(())
    }
}

/// How the periodic marching ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Marching {
    /// Periods marched (the forces are those of the last one).
    pub periods: usize,
    /// Whether the end-of-period state repeated within [`STATE_TOLERANCE`].
    pub converged: bool,
}

/// Per-element state over the last period (`docs/results-file.md`, `/contact/<name>/elements`).
#[derive(Clone, Debug, PartialEq)]
pub struct ElementReport {
    /// Fraction of the period's samples in stick (every tangential direction sticks).
    pub stick: f64,
    /// Fraction in slip (at least one tangential direction slips).
    pub slip: f64,
    /// Fraction in separation (f_n = 0).
    pub separation: f64,
    /// Energy dissipated per cycle W (J): the work of the tangential forces on the sliders,
    /// Σ_j f_t(τ_j)·(w_j − w_{j−1}) (exact for the time-discrete law).
    pub dissipated_energy: f64,
    /// How the marching ended.
    pub marching: Marching,
}

/// The hysteresis loop of the last period: one value per time sample τ_j = 2πj/N_t.
#[derive(Clone, Debug, PartialEq)]
pub struct HysteresisLoop {
    /// Tangential relative displacements u1, u2 (m) (u2 ≡ 0 for one direction).
    pub u: [Vec<f64>; 2],
    /// Normal approach v (m).
    pub v: Vec<f64>,
    /// Tangential forces f1, f2 (N).
    pub ft: [Vec<f64>; 2],
    /// Normal force f_n (N).
    pub fnormal: Vec<f64>,
    /// Slider positions w1, w2 (m) after each sample.
    pub w: [Vec<f64>; 2],
    /// Regime of each tangential direction per sample.
    pub regime: Vec<[Regime; 2]>,
}

/// Buffers of one thread for [`evaluate`] (reused across elements of any kind with the same
/// layout).
pub struct Workspace {
    aft_scratch: AftScratch,
    m: usize,
    n_t: usize,
    u: [Vec<f64>; 2],
    v: Vec<f64>,
    ft: [Vec<f64>; 2],
    fnormal: Vec<f64>,
    w: [Vec<f64>; 2],
    regime: Vec<[Regime; 2]>,
    marching: Marching,
    /// Local Jacobian, row-major (signals·m) × (signals·m + 1); last column ∂F/∂n0.
    jacobian: Vec<f64>,
    jacobian_cols: usize,
    /// Buffers of the Jacobian ([`march_period_differentiated`], [`finish_jacobian`]).
    derivative: DerivativeBuffers,
    /// Whether the 1-D Jacobian may come from the stored samples ([`jacobian_1d`]) where it
    /// applies (false only in the test that it equals the general differentiated march).
    samples_path: bool,
    /// The exact cycles of the last evaluation when it was analytic ([`evaluate_as`]); the
    /// report and the hysteresis loop then come from them.
    analytic: Option<AnalyticPeriod>,
}

/// The last analytic evaluation of an element ([`microslip`]): its input (the cycles are rebuilt
/// from it when a report or a loop is asked for, which keeps the evaluation free of copies).
#[derive(Clone, Debug)]
pub(crate) struct AnalyticPeriod {
    pub(crate) params: ContactParams,
    pub(crate) tangential: usize,
    pub(crate) u: [[f64; 3]; 2],
    pub(crate) v: [f64; 3],
    /// The slider state of each direction before the evaluation (m).
    pub(crate) slider: [f64; 2],
    pub(crate) energy: f64,
}

impl AnalyticPeriod {
    /// The periodic cycle of direction `d`.
    fn cycle(&self, d: usize) -> microslip::Cycle {
        microslip::cycle(&self.params, self.u[d], self.v, self.slider[d])
            .expect("the cycle of an evaluation that succeeded")
    }
}

impl Workspace {
    /// Buffers for the layout of `aft`.
    pub fn new(aft: &Aft) -> Self {
        let layout = aft.layout();
        let n_t = layout.time_samples;
        let m = layout.coefficients();
        let zeros = || vec![0.0; n_t];
        Workspace {
            aft_scratch: aft.scratch(),
            m,
            n_t,
            u: [zeros(), zeros()],
            v: zeros(),
            ft: [zeros(), zeros()],
            fnormal: zeros(),
            w: [zeros(), zeros()],
            regime: vec![[Regime::Stick; 2]; n_t],
            marching: Marching {
                periods: 0,
                converged: false,
            },
            jacobian: Vec::new(),
            jacobian_cols: 0,
            derivative: DerivativeBuffers::default(),
            samples_path: true,
            analytic: None,
        }
    }

    /// Whether the buffers were made for the layout of `aft` (the same N_t and 2H + 1).
    pub fn fits(&self, aft: &Aft) -> bool {
        let layout = aft.layout();
        self.n_t == layout.time_samples && self.m == layout.coefficients()
    }

    /// The local Jacobian buffer of an analytic evaluation, `rows` × `cols` (row-major), zeroed.
    pub(crate) fn analytic_jacobian(&mut self, rows: usize, cols: usize) -> &mut [f64] {
        // Zeroed by one fill (a memset) once the length is set: clearing and resizing writes the
        // zeros one at a time.
        let jacobian = self.analytic_jacobian_buffer(rows, cols);
        jacobian.fill(0.0);
        jacobian
    }

    /// The local Jacobian's buffer (rows × cols, row-major) as [`Workspace::analytic_jacobian`]
    /// but not zeroed: it holds the previous evaluation's values, and the caller writes every
    /// entry.
    pub(crate) fn analytic_jacobian_buffer(&mut self, rows: usize, cols: usize) -> &mut [f64] {
        if self.jacobian.len() != rows * cols {
            self.jacobian.resize(rows * cols, 0.0);
        }
        self.jacobian_cols = cols;
        &mut self.jacobian
    }

    /// Records an analytic evaluation (its Jacobian, if any, is already in
    /// [`Workspace::analytic_jacobian`]).
    #[inline]
    pub(crate) fn set_analytic(&mut self, period: AnalyticPeriod) {
        self.marching = Marching {
            periods: 1,
            converged: true,
        };
        // in place over the previous record where there is one (no temporary of the option)
        match self.analytic.as_mut() {
            Some(last) => *last = period,
            None => self.analytic = Some(period),
        }
    }

    /// The samples τ_j = 2πj/N_t of an analytic period into the sample buffers.
    fn sample_analytic(&self) -> Option<HysteresisLoop> {
        let a = self.analytic.as_ref()?;
        let n_t = self.n_t;
        let zeros = || vec![0.0; n_t];
        let mut out = HysteresisLoop {
            u: [zeros(), zeros()],
            v: zeros(),
            ft: [zeros(), zeros()],
            fnormal: zeros(),
            w: [zeros(), zeros()],
            regime: vec![[Regime::Stick; 2]; n_t],
        };
        let cycles: Vec<microslip::Cycle> = (0..a.tangential).map(|d| a.cycle(d)).collect();
        for j in 0..n_t {
            let t = std::f64::consts::TAU * j as f64 / n_t as f64;
            let (s, c) = t.sin_cos();
            out.v[j] = a.v[0] + a.v[1] * c - a.v[2] * s;
            for (d, cycle) in cycles.iter().enumerate().take(a.tangential) {
                let u = a.u[d];
                out.u[d][j] = u[0] + u[1] * c - u[2] * s;
                let (f, n, w, kind) = microslip::state_at(&a.params, u, a.v, cycle, t);
                out.ft[d][j] = f;
                out.fnormal[j] = n;
                out.w[d][j] = w;
                out.regime[j][d] = match kind {
                    microslip::PhaseKind::Stick { .. } => Regime::Stick,
                    microslip::PhaseKind::Separation => Regime::Separation,
                    _ => Regime::Slip,
                };
            }
            if a.tangential == 1 {
                out.regime[j][1] = match out.regime[j][0] {
                    Regime::Separation => Regime::Separation,
                    _ => Regime::Stick,
                };
            }
        }
        Some(out)
    }

    /// The local Jacobian of the last [`evaluate`] with `jacobian = true`: row-major with
    /// `signals·m` rows (∂F of each local force coefficient) and `signals·m + 1` columns (∂ of each
    /// local displacement coefficient, then ∂n0). Returns (entries, number of columns).
    pub fn jacobian(&self) -> (&[f64], usize) {
        (&self.jacobian, self.jacobian_cols)
    }

    /// Stores sample j of the period.
    fn store(&mut self, j: usize, s: &law::Sample) {
        self.ft[0][j] = s.force[0];
        self.ft[1][j] = s.force[1];
        self.fnormal[j] = s.force[2];
        self.w[0][j] = s.slider[0];
        self.w[1][j] = s.slider[1];
        self.regime[j] = s.regime;
    }

    /// Stores sample j of an exact evaluation ([`super::exact`]): the motion (u1, u2, v) and the
    /// law's state there; the report and the hysteresis loop then come from the samples.
    pub(crate) fn store_exact(&mut self, j: usize, u: [f64; 2], v: f64, s: &law::Sample) {
        if j == 0 {
            self.analytic = None;
            self.marching = Marching {
                periods: 1,
                converged: true,
            };
        }
        self.u[0][j] = u[0];
        self.u[1][j] = u[1];
        self.v[j] = v;
        self.store(j, s);
    }

    /// State report of the last evaluated period.
    pub fn report(&self) -> ElementReport {
        if let Some(a) = &self.analytic {
            // Exact fractions for one direction; for two, the fractions of the samples.
            let [stick, plus, minus, separation] = a.cycle(0).fractions();
            let (stick, slip, separation) = if a.tangential == 1 {
                (stick, plus + minus, separation)
            } else {
                let l = self.sample_analytic().expect("analytic period");
                let n = self.n_t as f64;
                let count = |f: &dyn Fn(&[Regime; 2]) -> bool| {
                    l.regime.iter().filter(|r| f(r)).count() as f64 / n
                };
                (
                    count(&|r| r[0] == Regime::Stick && r[1] == Regime::Stick),
                    count(&|r| r[0] == Regime::Slip || r[1] == Regime::Slip),
                    count(&|r| r[0] == Regime::Separation),
                )
            };
            return ElementReport {
                stick,
                slip,
                separation,
                dissipated_energy: a.energy,
                marching: self.marching,
            };
        }
        let n_t = self.n_t;
        let (mut stick, mut slip, mut sep) = (0usize, 0usize, 0usize);
        for r in &self.regime {
            if r[0] == Regime::Separation {
                sep += 1;
            } else if r[0] == Regime::Slip || r[1] == Regime::Slip {
                slip += 1;
            } else {
                stick += 1;
            }
        }
        let mut energy = 0.0;
        for d in 0..2 {
            let mut prev = self.w[d][n_t - 1];
            for j in 0..n_t {
                energy += self.ft[d][j] * (self.w[d][j] - prev);
                prev = self.w[d][j];
            }
        }
        ElementReport {
            stick: stick as f64 / n_t as f64,
            slip: slip as f64 / n_t as f64,
            separation: sep as f64 / n_t as f64,
            dissipated_energy: energy,
            marching: self.marching,
        }
    }

    /// Time samples of the last evaluated period.
    pub fn hysteresis(&self) -> HysteresisLoop {
        if let Some(l) = self.sample_analytic() {
            return l;
        }
        HysteresisLoop {
            u: self.u.clone(),
            v: self.v.clone(),
            ft: self.ft.clone(),
            fnormal: self.fnormal.clone(),
            w: self.w.clone(),
            regime: self.regime.clone(),
        }
    }
}

/// Evaluates one element on its local harmonic coefficients `x` (`[U1; U2; V]`, signals·m).
///
/// `slider` holds the slider state at the start of the period on entry and the converged
/// end-of-period state on return. Writes the local force coefficients `[F1; F2; Fn]` to `force`
/// (signals·m, overwritten) and, if `jacobian`, the local Jacobian to the workspace
/// ([`Workspace::jacobian`]). The time signals are synthesised once; the forces and the
/// Jacobian are formed once, from the march that is kept.
pub fn evaluate(
    element: &LocalElement,
    aft: &Aft,
    x: &[f64],
    slider: &mut [f64; 2],
    force: &mut [f64],
    jacobian: bool,
    ws: &mut Workspace,
) -> Result<Marching> {
    element.check()?;
    ws.analytic = None;
    signals_to_time(element, aft, x, ws);
    let warm = *slider;
    let mut marched = march_periods(element, aft, slider, jacobian, ws);
    if warm != REST && !forgets_start(element, ws) {
        // The warm start gives the periodic state reached from rest only where every direction
        // forgets its start state in the last period; elsewhere march from rest.
        *slider = REST;
        marched = march_periods(element, aft, slider, jacobian, ws);
    }
    finish_period(element, aft, force, jacobian, &marched, ws);
    Ok(marched.marching)
}

/// The slider state at rest (the origin of the relative motion), from which the periodic state
/// of [`evaluate`] is defined.
pub const REST: [f64; 2] = [0.0; 2];

/// Whether every tangential direction forgets its start state in the last marched period: it
/// separates at some sample (the slider follows u), or it slips both ways (the slider is set
/// by the last slip, whatever it was before). A direction that sticks all period, or slips one
/// way only (a shakedown: the loop touches μ f_n at one instant), keeps a slider position that
/// depends on where the marching started.
fn forgets_start(element: &LocalElement, ws: &Workspace) -> bool {
    (0..element.tangential).all(|d| {
        let mut slips = [false; 2];
        for (j, r) in ws.regime.iter().enumerate() {
            match r[d] {
                Regime::Separation => return true,
                Regime::Slip => {
                    slips[usize::from(ws.ft[d][j] > 0.0)] = true;
                    if slips[0] && slips[1] {
                        return true;
                    }
                }
                Regime::Stick => {}
            }
        }
        false
    })
}

/// The time signals u1, u2, v of the local coefficients `x` into the workspace (absent
/// signals zero).
fn signals_to_time(element: &LocalElement, aft: &Aft, x: &[f64], ws: &mut Workspace) {
    let m = ws.m;
    debug_assert_eq!(x.len(), element.signals() * m);
    for d in 0..2 {
        if d < element.tangential {
            aft.to_time(&x[d * m..(d + 1) * m], &mut ws.u[d], &mut ws.aft_scratch);
        } else {
            ws.u[d].fill(0.0);
        }
    }
    if element.normal {
        let o = element.tangential * m;
        aft.to_time(&x[o..o + m], &mut ws.v, &mut ws.aft_scratch);
    } else {
        ws.v.fill(0.0);
    }
}

/// What [`march_periods`] did: how the marching ended, the start states of the march and of
/// its last period, and whether its first period carried the derivative terms.
struct Marched {
    marching: Marching,
    w_in: [f64; 2],
    w_start: [f64; 2],
    differentiated: bool,
}

/// Marches periods of the time signals in the workspace from the caller's start state
/// `slider` (updated to the end state) until the end-of-period slider state repeats.
fn march_periods(
    element: &LocalElement,
    aft: &Aft,
    slider: &mut [f64; 2],
    jacobian: bool,
    ws: &mut Workspace,
) -> Marched {
    // the second direction's samples are zero without it ([`signals_to_time`])
    let scale = ws.u[..element.tangential]
        .iter()
        .fold(slider[0].abs().max(slider[1].abs()), |a, u| {
            largest_magnitude(u, a)
        });
    let tol = STATE_TOLERANCE * scale;
    let w_in = *slider;
    let mut w = w_in;
    let mut w_start = w;
    let mut marching = Marching {
        periods: 0,
        converged: false,
    };
    let mut differentiated = false;
    let mut first_differentiated = false;
    while marching.periods < MAX_PERIODS {
        w_start = w;
        // With a Jacobian of the 2-D law the first period also carries the derivative terms:
        // from a converged state (every Newton call after the first) it is the last period. The
        // 1-D law needs only the stored samples ([`jacobian_1d`]).
        differentiated = jacobian
            && marching.periods == 0
            && !(ws.samples_path && element.variant == Variant::OneD);
        if differentiated {
            march_period_differentiated(element, aft, ws, &mut w);
        } else {
            // the previous period's samples are of this motion and, for a Jenkins element
            // whose second slider starts at rest (and so stays there), of its own march
            let stored = marching.periods > 0 && !first_differentiated && w_in[1] == 0.0;
            march_period(element, ws, &mut w, stored);
        }
        first_differentiated |= differentiated;
        marching.periods += 1;
        if (w[0] - w_start[0]).abs() <= tol && (w[1] - w_start[1]).abs() <= tol {
            marching.converged = true;
            break;
        }
    }
    ws.marching = marching;
    *slider = w;
    Marched {
        marching,
        w_in,
        w_start,
        differentiated,
    }
}

/// The largest of `start` and the magnitudes of `values`, NaN ignored as by `f64::max`: in four
/// independent lanes, so that the loop vectorises (the maximum does not depend on the order).
fn largest_magnitude(values: &[f64], start: f64) -> f64 {
    let mut lanes = [start; 4];
    let chunks = values.chunks_exact(4);
    let rest = chunks.remainder();
    for chunk in chunks {
        for (lane, v) in lanes.iter_mut().zip(chunk) {
            let a = v.abs();
            if a > *lane {
                *lane = a;
            }
        }
    }
    rest.iter()
        .chain(&lanes)
        .fold(start, |largest, v| largest.max(v.abs()))
}

/// The forces of the last marched period to harmonics, and the Jacobian if asked for.
fn finish_period(
    element: &LocalElement,
    aft: &Aft,
    force: &mut [f64],
    jacobian: bool,
    marched: &Marched,
    ws: &mut Workspace,
) {
    let m = ws.m;
    debug_assert_eq!(force.len(), element.signals() * m);
    for d in 0..element.tangential {
        aft.to_harmonics(
            &ws.ft[d],
            &mut force[d * m..(d + 1) * m],
            &mut ws.aft_scratch,
        );
    }
    if element.normal {
        let o = element.tangential * m;
        aft.to_harmonics(&ws.fnormal, &mut force[o..o + m], &mut ws.aft_scratch);
    }
    if jacobian && ws.samples_path && samples_suffice(element, ws) {
        jacobian_1d(element, aft, ws);
    } else if jacobian {
        if !marched.differentiated {
            // The last period again (the same samples), now with the derivative terms.
            let mut w_again = marched.w_start;
            march_period_differentiated(element, aft, ws, &mut w_again);
        }
        let shape = Shape::new(element, ws.m);
        ws.derivative.transient.iter_mut().for_each(|t| {
            t.clear();
            t.resize(shape.cols, 0.0);
        });
        if marched.marching.periods > 1 && stuck_directions(&shape, &ws.derivative) {
            let mut w_in = marched.w_in;
            for _ in 1..marched.marching.periods {
                march_transient_chain(element, aft, ws, &shape, &mut w_in);
            }
        }
        finish_jacobian(element, aft, ws);
    }
}

/// [`evaluate`] with the chosen evaluation: `Aft` is [`evaluate`]; `Analytic` is the exact
/// single-harmonic cycle of [`microslip`] (Cigeroglu, An & Menq 2007) for the 1-D law and H = 1,
/// with the same inputs, outputs, slider state and Jacobian layout.
#[allow(clippy::too_many_arguments)]
pub fn evaluate_as(
    evaluation: Evaluation,
    element: &LocalElement,
    aft: &Aft,
    x: &[f64],
    slider: &mut [f64; 2],
    force: &mut [f64],
    jacobian: bool,
    ws: &mut Workspace,
) -> Result<Marching> {
    match evaluation {
        Evaluation::Aft => evaluate(element, aft, x, slider, force, jacobian, ws),
        Evaluation::Analytic if aft.layout().harmonics > 1 => {
            element.check()?;
            exact::evaluate_element(element, aft, x, slider, force, jacobian, ws)?;
            Ok(ws.marching)
        }
        Evaluation::Analytic => {
            // checks the element where its layout is not the one-direction fast path
            microslip::evaluate_element(
                element,
                aft.layout().harmonics,
                x,
                slider,
                force,
                jacobian,
                ws,
            )?;
            Ok(ws.marching)
        }
    }
}

/// Whether the 1-D Jacobian can be built from the stored samples of the last period
/// ([`jacobian_1d`]): the 1-D law, and either one period was marched (the caller's state was
/// periodic) or every tangential direction leaves stick in the last period (its start state is
/// then the end state, set by the last slip or separation sample; otherwise the transient
/// periods enter, [`march_transient_chain`]).
fn samples_suffice(element: &LocalElement, ws: &Workspace) -> bool {
    element.variant == Variant::OneD
        && (ws.marching.periods == 1
            || (0..element.tangential).all(|d| ws.regime.iter().any(|r| r[d] != Regime::Stick)))
}

/// The local Jacobian of the 1-D law ([`finish_jacobian`]: the same matrix up to rounding) from
/// the regimes and forces of the last period alone, in O(N_t + J·H + R·H²) for J changes of
/// regime or slip direction and R stick runs: the samples are visited once, to find the runs
/// ([`class_runs`]).
///
/// Per sample the 1-D law has piecewise-constant weights (SAMA paper eqs 13–14): stick
/// ∂f_d = k_t (∂u_d − ∂w_d), slip ∂f_d = σ μ (k_n ∂v + ∂n0) with σ = sgn f_d, and
/// ∂f_n = k_n ∂v + ∂n0 in contact. So the fixed-w part is k_t M(χ_stick) on (F_d, U_d),
/// μ k_n M(σ χ_slip) on (F_d, V) and k_n M(χ_contact) on (F_n, V), M(a) the harmonic
/// multiplication matrix ([`add_multiplication_block`]) from the Fourier sums of the indicator
/// sequences (from their jumps, [`Aft::jump_fourier_sums`]); the n0 column is M(a)'s first column (∂n0 acts as a
/// constant signal), with the factors μ and 1.
///
/// Memory: a slip or separation sample j0 resets the slider, ∂w_d = E_j0 ∂U_d
/// − (σ μ/k_t)(k_n E_j0 ∂V + ∂n0) (the second term only in slip), which then holds over the stick
/// run R that follows; the run adds −k_t β_R ⊗ ∂w_d with β_R = Σ_{j∈R} B_·j (from the
/// cumulative sums of the analysis columns, [`Aft::add_analysis_sum`]). The period is
/// cyclic: the run before the first reset follows the last one (w_start = w_end); a direction
/// stuck all period marched once has ∂w_start = 0 (the caller's state is a parameter).
fn jacobian_1d(element: &LocalElement, aft: &Aft, ws: &mut Workspace) {
    let m = ws.m;
    let h = (m - 1) / 2;
    let shape = Shape::new(element, m);
    let (cols, n0_col) = (shape.cols, shape.n0_col);
    let p = element.params;
    let Workspace {
        jacobian,
        jacobian_cols,
        derivative: b,
        regime,
        ft,
        fnormal,
        ..
    } = ws;
    // zeroed by one fill (a memset) once the length is set
    jacobian.resize(element.signals() * m * cols, 0.0);
    jacobian.fill(0.0);
    *jacobian_cols = cols;
    b.sequence.resize(regime.len(), 0.0);
    b.sums.resize(2 * m, 0.0);
    b.beta[0].resize(m, 0.0);
    let normal = shape.offsets.of(2);
    if let Some(vo) = normal {
        if fnormal.iter().all(|&f| f > 0.0) {
            // In contact all period: M(1) = I, so k_n I and the n0 column e_0.
            for k in 0..m {
                jacobian[(vo + k) * cols + vo + k] += p.kn;
            }
            jacobian[vo * cols + n0_col] += 1.0;
        } else {
            for (s, &f) in b.sequence.iter_mut().zip(fnormal.iter()) {
                *s = if f > 0.0 { 1.0 } else { 0.0 };
            }
            if aft.step_fourier_sums(&b.sequence, &mut b.sums) {
                add_first_column(h, &b.sums, 1.0, jacobian, cols, vo, n0_col);
                scale_sums(&mut b.sums, p.kn);
                add_multiplication_block(h, &b.sums, &mut b.signed, jacobian, cols, vo, vo);
            }
        }
    }
    for (d, force) in ft.iter().enumerate().take(element.tangential) {
        let row0 = d * m;
        let n_t = regime.len();
        let whole = class_runs(regime, force, d, &mut b.runs);
        let runs = &b.runs;
        // Stick indicator χ_stick and slip sign σ χ_slip, from their jumps.
        if run_fourier_sums(aft, runs, whole, n_t, SampleClass::stick, &mut b.sums) {
            scale_sums(&mut b.sums, p.kt);
            add_multiplication_block(h, &b.sums, &mut b.signed, jacobian, cols, row0, row0);
        }
        if run_fourier_sums(aft, runs, whole, n_t, SampleClass::slip, &mut b.sums) {
            add_first_column(h, &b.sums, p.mu, jacobian, cols, row0, n0_col);
            if let Some(vo) = normal {
                scale_sums(&mut b.sums, p.mu * p.kn);
                add_multiplication_block(h, &b.sums, &mut b.signed, jacobian, cols, row0, vo);
            }
        }
        let mut memory = StickRuns {
            jac: jacobian,
            cols,
            row0,
            normal,
            n0_col,
            params: p,
            beta: &mut b.beta[0],
        };
        memory.add(aft, runs, n_t);
    }
}

/// What the 1-D law's Jacobian needs of one sample of one direction ([`jacobian_1d`]): its
/// regime and, in slip, the sign σ of its force.
#[derive(Clone, Copy, Debug, PartialEq)]
enum SampleClass {
    Stick,
    /// Slip with f_d > 0 (σ = +1).
    SlipUp,
    /// Slip with f_d < 0 (σ = −1).
    SlipDown,
    Separation,
}

impl SampleClass {
    /// The class of a sample in `regime` with the force `f` (N).
    fn of(regime: Regime, f: f64) -> SampleClass {
        match regime {
            Regime::Stick => SampleClass::Stick,
            Regime::Slip if f.is_sign_negative() => SampleClass::SlipDown,
            Regime::Slip => SampleClass::SlipUp,
            Regime::Separation => SampleClass::Separation,
        }
    }

    /// The stick indicator χ_stick (1 or 0).
    fn stick(self) -> f64 {
        if self == SampleClass::Stick {
            1.0
        } else {
            0.0
        }
    }

    /// σ χ_slip: the sign of the force in slip, else 0.
    fn slip(self) -> f64 {
        self.sigma().unwrap_or(0.0)
    }

    /// σ of a slip sample, None otherwise.
    fn sigma(self) -> Option<f64> {
        match self {
            SampleClass::SlipUp => Some(1.0),
            SampleClass::SlipDown => Some(-1.0),
            SampleClass::Stick | SampleClass::Separation => None,
        }
    }
}

/// The maximal runs of samples of one class of direction `d` over the period, cyclically: into
/// `runs` the first sample and class of each run, in increasing sample order (empty when the
/// whole period is one class); returns the class of the last sample (the whole period's class
/// when `runs` is empty).
fn class_runs(
    regime: &[[Regime; 2]],
    f: &[f64],
    d: usize,
    runs: &mut Vec<(usize, SampleClass)>,
) -> SampleClass {
    runs.clear();
    let n_t = regime.len();
    let last = SampleClass::of(regime[n_t - 1][d], f[n_t - 1]);
    let mut previous = last;
    for (j, (r, &fj)) in regime.iter().zip(f).enumerate() {
        let class = SampleClass::of(r[d], fj);
        if class != previous {
            runs.push((j, class));
            previous = class;
        }
    }
    last
}

/// The length (samples) of run `r` of the cyclic runs `runs` over `n_t` samples.
fn run_length(runs: &[(usize, SampleClass)], r: usize, n_t: usize) -> usize {
    match runs.get(r + 1) {
        Some(&(next, _)) => next - runs[r].0,
        None => n_t - runs[r].0 + runs[0].0,
    }
}

/// The Fourier sums ([`Aft::jump_fourier_sums`]) of the weight sequence `value`(class) of the
/// samples, from the runs of [`class_runs`] (`whole`: its returned class); the same values as
/// [`Aft::step_fourier_sums`] on the sequence. Returns false if the sequence is all zero.
fn run_fourier_sums(
    aft: &Aft,
    runs: &[(usize, SampleClass)],
    whole: SampleClass,
    n_t: usize,
    value: fn(SampleClass) -> f64,
    sums: &mut [f64],
) -> bool {
    if runs.is_empty() {
        return aft.jump_fourier_sums(std::iter::empty(), n_t as f64 * value(whole), sums);
    }
    let total: f64 = (0..runs.len())
        .map(|r| value(runs[r].1) * run_length(runs, r, n_t) as f64)
        .sum();
    let before = |r: usize| runs[(r + runs.len() - 1) % runs.len()].1;
    let jumps = (0..runs.len()).filter_map(|r| {
        let delta = value(runs[r].1) - value(before(r));
        (delta != 0.0).then_some((runs[r].0, delta))
    });
    aft.jump_fourier_sums(jumps, total, sums)
}

/// Multiplies Fourier sums by `factor`.
fn scale_sums(sums: &mut [f64], factor: f64) {
    sums.iter_mut().for_each(|s| *s *= factor);
}

/// Adds `factor` × the harmonics of a weight sequence, i.e. the first column of its
/// multiplication matrix (Q_0 = c_0, Re Q_κ = 2c_κ, Im Q_κ = −2s_κ from its Fourier sums
/// `sums`, [`add_multiplication_block`]), to column `col` of rows `row0..row0 + 2H + 1`.
fn add_first_column(
    h: usize,
    sums: &[f64],
    factor: f64,
    jac: &mut [f64],
    cols: usize,
    row0: usize,
    col: usize,
) {
    jac[row0 * cols + col] += factor * sums[0];
    for k in 1..=h {
        jac[(row0 + 2 * k - 1) * cols + col] += 2.0 * factor * sums[2 * k];
        jac[(row0 + 2 * k) * cols + col] -= 2.0 * factor * sums[2 * k + 1];
    }
}

/// The slider-memory terms of one direction of the 1-D law ([`jacobian_1d`]) into the rows
/// `row0..row0 + m` of the local Jacobian.
struct StickRuns<'a> {
    jac: &'a mut [f64],
    cols: usize,
    row0: usize,
    /// Offset of the V coefficients (None without normal kinematics).
    normal: Option<usize>,
    n0_col: usize,
    params: ContactParams,
    /// β_R accumulator (m).
    beta: &'a mut Vec<f64>,
}

impl StickRuns<'_> {
    /// Adds the terms of every stick run of the cyclic runs `runs` of a period of `n_t`
    /// samples ([`class_runs`]): the sample before a stick run resets the slider (slip or
    /// separation), and β_R is the sum of the run's analysis columns. A direction of one class
    /// all period has none (stuck all period: ∂w_start = 0, one period marched,
    /// [`samples_suffice`]).
    fn add(&mut self, aft: &Aft, runs: &[(usize, SampleClass)], n_t: usize) {
        // from the run after the period's last reset: the last run first if it sticks
        let count = runs.len();
        let first_run = match runs.last() {
            Some(&(_, SampleClass::Stick)) => count - 1,
            _ => 0,
        };
        for r in (first_run..count).chain(0..first_run) {
            let (first, class) = runs[r];
            if class != SampleClass::Stick {
                continue;
            }
            let reset = runs[(r + count - 1) % count].1;
            self.beta.fill(0.0);
            aft.add_analysis_sum(first, run_length(runs, r, n_t), self.beta);
            self.emit(aft.synthesis_row((first + n_t - 1) % n_t), reset.sigma());
        }
    }

    /// Adds −k_t β ⊗ ∂w for the reset ∂w = E ∂U_d − (σ μ/k_t)(k_n E ∂V + ∂n0) (synthesis row
    /// `e`; `sigma` None for a separation reset, ∂w = E ∂U_d).
    fn emit(&mut self, e: &[f64], sigma: Option<f64>) {
        let p = self.params;
        add_outer(
            self.jac, self.cols, self.row0, self.row0, -p.kt, self.beta, e,
        );
        let Some(sigma) = sigma else { return };
        if let Some(vo) = self.normal {
            add_outer(
                self.jac,
                self.cols,
                self.row0,
                vo,
                sigma * p.mu * p.kn,
                self.beta,
                e,
            );
        }
        for (k, bk) in self.beta.iter().enumerate() {
            self.jac[(self.row0 + k) * self.cols + self.n0_col] += sigma * p.mu * bk;
        }
    }
}

/// `jac[row0 + k][col0 + l]` += alpha · left_k · right_l (row-major, `cols` columns).
fn add_outer(
    jac: &mut [f64],
    cols: usize,
    row0: usize,
    col0: usize,
    alpha: f64,
    left: &[f64],
    right: &[f64],
) {
    for (k, lk) in left.iter().enumerate() {
        let a = alpha * lk;
        let row = &mut jac[(row0 + k) * cols + col0..(row0 + k) * cols + col0 + right.len()];
        for (r, rv) in row.iter_mut().zip(right) {
            *r += a * rv;
        }
    }
}

/// One period of the law from the slider state `w` (updated to the end state); fills the force,
/// slider and regime samples of the workspace. `stored`: the samples of the previous period of
/// the same motion are in the workspace, marched by this function from a second slider at rest.
fn march_period(element: &LocalElement, ws: &mut Workspace, w: &mut [f64; 2], stored: bool) {
    if element.variant == Variant::OneD && element.tangential == 1 && !element.normal && w[1] == 0.0
    {
        march_period_one_direction(&element.params, ws, w, stored);
    } else {
        march_period_samples(element, ws, w);
    }
}

/// [`march_period`] by the general law, sample by sample.
fn march_period_samples(element: &LocalElement, ws: &mut Workspace, w: &mut [f64; 2]) {
    let p = &element.params;
    for j in 0..ws.n_t {
        let s = law::sample(element.variant, p, [ws.u[0][j], ws.u[1][j]], ws.v[j], *w);
        ws.store(j, &s);
        *w = s.slider;
    }
}

/// [`march_period`] of a 1-D element with one tangential direction and no normal kinematics
/// (a Jenkins element: v ≡ 0, so f_n = max(n0, 0) and the slip limit μ f_n are constant) whose
/// second slider is at rest: the second direction (u2 ≡ 0, w2 = 0) has the trial force 0 and
/// sticks with f2 = 0 (or separates, f_n = 0) all period, so only the first is marched.
///
/// After a `stored` period of the same motion, the samples are marched until the first that
/// slips or separates; where it does so as the stored sample did (same regime and force), the
/// slider after it is the stored one (a slip sets it to u − f/k_t, a separation to u, from the
/// motion alone), and so is every later sample: the stored samples from there on are this
/// period's, and it ends where the previous one ended. The samples are those of the general
/// loop, value for value.
fn march_period_one_direction(
    p: &ContactParams,
    ws: &mut Workspace,
    w: &mut [f64; 2],
    stored: bool,
) {
    let fnormal = law::normal_force(p, 0.0);
    let separated = fnormal <= 0.0;
    let limit = p.mu * fnormal;
    let reach = limit / p.kt;
    let (_, _, idle) = law::tangential_1d(p.kt, limit, separated, 0.0, 0.0);
    let mut slider = w[0];
    for j in 0..ws.n_t {
        let (f, next, regime) =
            law::tangential_1d_reach(p.kt, limit, reach, separated, ws.u[0][j], slider);
        if stored && regime != Regime::Stick && regime == ws.regime[j][0] && f == ws.ft[0][j] {
            w[0] = ws.w[0][ws.n_t - 1];
            return;
        }
        ws.ft[0][j] = f;
        ws.w[0][j] = next;
        ws.regime[j] = [regime, idle];
        slider = next;
    }
    ws.ft[1].fill(0.0);
    ws.w[1].fill(0.0);
    ws.fnormal.fill(fnormal);
    w[0] = slider;
}

/// [`march_period`] with the law's tangents, also collecting the slider-memory and fixed-w
/// terms of the Jacobian ([`derivative_step`]; finished by [`finish_jacobian`]).
fn march_period_differentiated(
    element: &LocalElement,
    aft: &Aft,
    ws: &mut Workspace,
    w: &mut [f64; 2],
) {
    let p = &element.params;
    let shape = Shape::new(element, ws.m);
    ws.derivative.reset(ws.m, ws.n_t, shape.cols);
    for j in 0..ws.n_t {
        let t = law::sample_with_tangent(element.variant, p, [ws.u[0][j], ws.u[1][j]], ws.v[j], *w);
        ws.store(j, &t.sample);
        *w = t.sample.slider;
        derivative_step(&shape, aft, j, &t, &mut ws.derivative);
    }
}

/// Buffers of the Jacobian ([`derivative_step`], [`finish_jacobian`]; one set per thread, reused across elements).
#[derive(Default)]
struct DerivativeBuffers {
    /// ∂w_d (d = 1, 2) after the current sample: rows of length `ext` = local inputs, n0, and
    /// the two columns ∂/∂w_start (the unknown derivative of the starting state).
    dw: [Vec<f64>; 2],
    /// s = vᵀ ∂w of a 2-D slip sample (length `ext`).
    s: Vec<f64>,
    /// β_d = Σ_j (∂f_j,d/∂w_d) B_·j over the samples since ∂w_d last changed (length m).
    beta: [Vec<f64>; 2],
    /// Whether β_d holds a contribution.
    live: [bool; 2],
    /// Memory terms of force d as rank-one products left_r ⊗ right_r: left vectors (m each).
    left: [Vec<f64>; 2],
    /// Right rows (`ext` each).
    right: [Vec<f64>; 2],
    /// ∂(f1, f2, f_n)/∂(u1, u2, v, n0) at fixed w of each sample.
    weights: Vec<[[f64; 4]; 3]>,
    /// One weight sequence (f, c) over the samples (N_t).
    sequence: Vec<f64>,
    /// Fourier sums of one weight sequence (2(2H+1)).
    sums: Vec<f64>,
    /// The runs of one class of a direction of the 1-D law ([`class_runs`]).
    runs: Vec<(usize, SampleClass)>,
    /// Scratch of [`add_multiplication_block`] (4H+1).
    signed: Vec<[f64; 2]>,
    /// Harmonics of one n0 weight sequence (m).
    column: Vec<f64>,
    /// Σ_r left_r ⊗ right_r on the two ∂w_start columns (m × 2).
    start_coef: Vec<f64>,
    /// ∂w_start from the periodicity condition (two rows of length cols).
    start: [Vec<f64>; 2],
    /// ∂w at the start of the last period carried through the transient periods from the
    /// given start state (∂w_in = 0; two rows of length cols; [`march_transient_chain`]).
    transient: [Vec<f64>; 2],
}

impl DerivativeBuffers {
    fn reset(&mut self, m: usize, n_t: usize, cols: usize) {
        let ext = cols + 2;
        for d in 0..2 {
            self.dw[d].clear();
            self.dw[d].resize(ext, 0.0);
            self.dw[d][cols + d] = 1.0;
            self.beta[d].clear();
            self.beta[d].resize(m, 0.0);
            self.live[d] = false;
            self.left[d].clear();
            self.right[d].clear();
            self.start[d].clear();
            self.start[d].resize(cols, 0.0);
        }
        self.s.clear();
        self.s.resize(ext, 0.0);
        self.weights.clear();
        self.weights.resize(n_t, [[0.0; 4]; 3]);
        self.sequence.resize(n_t, 0.0);
        self.sums.resize(4 * m, 0.0);
        self.column.resize(m, 0.0);
        self.start_coef.resize(2 * m, 0.0);
    }

    /// Copies the weight sequence ∂f_f/∂x_c into `sequence`; false if it is zero.
    fn gather(&mut self, f: usize, c: usize) -> bool {
        let mut nonzero = false;
        for (s, w) in self.sequence.iter_mut().zip(&self.weights) {
            *s = w[f][c];
            nonzero |= *s != 0.0;
        }
        nonzero
    }

    /// Ends the stick accumulation of direction d (before ∂w_d changes): emits β_d ⊗ ∂w_d.
    fn flush(&mut self, d: usize) {
        if self.live[d] {
            self.left[d].extend_from_slice(&self.beta[d]);
            self.right[d].extend_from_slice(&self.dw[d]);
            self.beta[d].fill(0.0);
            self.live[d] = false;
        }
    }
}

/// Which local signal (u1, u2, v) sits at which offset of the local coefficient vector.
#[derive(Clone, Copy)]
struct Offsets {
    m: usize,
    tangential: usize,
    normal: bool,
}

impl Offsets {
    /// Offset of the coefficients of signal c ∈ {0: u1, 1: u2, 2: v}; None if absent. The same
    /// offsets index the force rows (f1, f2, f_n).
    fn of(&self, c: usize) -> Option<usize> {
        match c {
            0 => Some(0),
            1 if self.tangential == 2 => Some(self.m),
            2 if self.normal => Some(self.tangential * self.m),
            _ => None,
        }
    }
}

#[inline]
/// `row` += Σ_c g_c E_j (in the coefficients of input c) + g_n0 e_n0 for the partial
/// derivatives g = ∂(·)/∂(u1, u2, v, n0) of one sample with synthesis row `e` = E_j.
fn add_input_row(row: &mut [f64], g: &[f64; 4], e: &[f64], offsets: Offsets, n0_col: usize) {
    for (c, &gc) in g.iter().enumerate().take(3) {
        if gc == 0.0 {
            continue;
        }
        if let Some(o) = offsets.of(c) {
            for (r, ev) in row[o..o + e.len()].iter_mut().zip(e) {
                *r += gc * ev;
            }
        }
    }
    row[n0_col] += g[3];
}

/// Sizes and signal offsets of an element's local Jacobian.
#[derive(Clone, Copy)]
struct Shape {
    /// Tangential directions.
    tangential: usize,
    /// Columns: local inputs, then n0.
    cols: usize,
    /// The n0 column.
    n0_col: usize,
    offsets: Offsets,
    /// 2-D law.
    two_d: bool,
    /// k_t (N/m).
    kt: f64,
}

impl Shape {
    fn new(element: &LocalElement, m: usize) -> Self {
        let nsig = element.signals();
        Shape {
            tangential: element.tangential,
            cols: nsig * m + 1,
            n0_col: nsig * m,
            offsets: Offsets {
                m,
                tangential: element.tangential,
                normal: element.normal,
            },
            two_d: element.variant == Variant::TwoD,
            kt: element.params.kt,
        }
    }
}

/// The Jacobian terms of sample j with the law's tangent `t` (see [`finish_jacobian`]): its
/// fixed-w weights, its slider-memory term and the update of ∂w.
fn derivative_step(
    shape: &Shape,
    aft: &Aft,
    j: usize,
    t: &law::SampleTangent,
    b: &mut DerivativeBuffers,
) {
    b.weights[j] = t.dforce_dx;
    let e = aft.synthesis_row(j);
    let bj = aft.analysis_column(j);
    if shape.two_d && t.sample.regime[0] == Regime::Slip {
        slip_2d(t, shape.kt, e, bj, shape.offsets, shape.n0_col, b);
        return;
    }
    // A_j, W_j diagonal.
    for d in 0..shape.tangential {
        let g = t.dforce_dw[d][d];
        if g != 0.0 {
            for (bk, bv) in b.beta[d].iter_mut().zip(bj) {
                *bk += g * bv;
            }
            b.live[d] = true;
        }
        if keeps_slider(t, d) {
            continue;
        }
        b.flush(d);
        update_diagonal(&mut b.dw[d], t, d, e, shape);
    }
}

/// Whether sample `t` leaves ∂w_d unchanged (A_dd = 1 and C_d = 0: stick).
#[inline]
fn keeps_slider(t: &law::SampleTangent, d: usize) -> bool {
    t.dslider_dw[d][d] == 1.0 && t.dslider_dx[d].iter().all(|&x| x == 0.0)
}

/// ∂w_d ← A_dd ∂w_d + C_d E_j for a sample with diagonal A (synthesis row `e` = E_j).
fn update_diagonal(row: &mut [f64], t: &law::SampleTangent, d: usize, e: &[f64], shape: &Shape) {
    let a = t.dslider_dw[d][d];
    if a == 0.0 {
        row.fill(0.0);
    } else if a != 1.0 {
        for r in row.iter_mut() {
            *r *= a;
        }
    }
    add_input_row(row, &t.dslider_dx[d], e, shape.offsets, shape.n0_col);
}

/// The radial-return direction v of a 2-D slip sample, A = ∂w'/∂w = v vᵀ (rank one); None if
/// A = 0.
fn slip_direction(a: [[f64; 2]; 2]) -> Option<[f64; 2]> {
    let k = if a[0][0] >= a[1][1] { 0 } else { 1 };
    let pivot = a[k][k];
    (pivot > 0.0).then(|| {
        let root = pivot.sqrt();
        [a[0][k] / root, a[1][k] / root]
    })
}

/// Whether the last period (differentiated in `b`) leaves a tangential direction stuck all
/// period (Φ_dd = 1 of the 1-D law; Φ = I of the 2-D law): the only case in which the
/// transient periods enter the Jacobian ([`finish_jacobian`]).
fn stuck_directions(shape: &Shape, b: &DerivativeBuffers) -> bool {
    let phi = |d: usize, e: usize| b.dw[d][shape.cols + e];
    match shape.two_d {
        false => (0..shape.tangential).any(|d| phi(d, d) == 1.0),
        true => phi(0, 0) == 1.0 && phi(1, 1) == 1.0 && phi(0, 1) == 0.0 && phi(1, 0) == 0.0,
    }
}

/// One transient period from the slider state `w` (updated to the end state), carrying only
/// ∂w (`transient` of the buffers, from ∂w = 0 at the caller's start state) through the
/// samples: ∂w_j = C_j ∂x_j + A_j ∂w_{j−1}. The workspace's stored samples are not touched.
fn march_transient_chain(
    element: &LocalElement,
    aft: &Aft,
    ws: &mut Workspace,
    shape: &Shape,
    w: &mut [f64; 2],
) {
    let p = &element.params;
    let b = &mut ws.derivative;
    for j in 0..ws.n_t {
        let t = law::sample_with_tangent(element.variant, p, [ws.u[0][j], ws.u[1][j]], ws.v[j], *w);
        *w = t.sample.slider;
        let e = aft.synthesis_row(j);
        if shape.two_d && t.sample.regime[0] == Regime::Slip {
            let [t0, t1] = &mut b.transient;
            match slip_direction(t.dslider_dw) {
                Some(v) => {
                    for (r0, r1) in t0.iter_mut().zip(t1.iter_mut()) {
                        let s = v[0] * *r0 + v[1] * *r1;
                        *r0 = v[0] * s;
                        *r1 = v[1] * s;
                    }
                }
                None => {
                    t0.fill(0.0);
                    t1.fill(0.0);
                }
            }
            for (d, row) in b.transient.iter_mut().enumerate() {
                add_input_row(row, &t.dslider_dx[d], e, shape.offsets, shape.n0_col);
            }
            continue;
        }
        for d in 0..shape.tangential {
            if !keeps_slider(&t, d) {
                update_diagonal(&mut b.transient[d], &t, d, e, shape);
            }
        }
    }
}

/// The local Jacobian of the periodic solution (SAMA paper eq. 25 in
/// local coordinates, plus the column ∂F/∂n0), in O(N_t·H + N_mem·H²) with N_mem the number of
/// slider-memory terms (stick runs, and 2-D slip samples).
///
/// With x = (local coefficients, n0), E_j the synthesis row and B_·j the analysis column of
/// sample j, the law gives ∂f_j = D_j ∂x_j + W_j ∂w_{j−1} and ∂w_j = C_j ∂x_j + A_j ∂w_{j−1}
/// (∂x_j = E_j ⊗ ·; [`law::sample_with_tangent`]), and ∂F = Σ_j B_·j ∂f_j:
/// * the fixed-w part Σ_j B_·j D_j E_j is, per (force, input) pair, the harmonic matrix of
///   multiplication by the sampled weight (D_j)_fc, built from its Fourier sums
///   ([`add_multiplication_block`]); the n0 column is the harmonics of (D_j)_f,n0;
/// * the memory part Σ_j B_·j W_j ∂w_{j−1}: where A_j, W_j are diagonal (stick: A = 1,
///   W = −k_t; slip of the 1-D law and separation: A = W = 0) ∂w_d stays constant over a stick
///   run and the run contributes the rank-one product (Σ_run W B_·j) ⊗ ∂w_d; a 2-D slip sample
///   has A = v vᵀ (rank one, the radial-return projection) and W = −k_t A, one rank-one product
///   (−k_t v B_·j) ⊗ (vᵀ ∂w_{j−1}). The products are summed at the end ([`add_products`]).
///
/// ∂w is carried with two extra columns for ∂w_start, so that ∂w_end = G + Φ ∂w_start; the
/// periodicity w_start = w_end gives ∂w_start = (I − Φ)⁻¹ G ([`periodic_start`]; a direction
/// that never leaves stick keeps ∂w_start = 0), which closes the extra columns.
fn finish_jacobian(element: &LocalElement, aft: &Aft, ws: &mut Workspace) {
    let m = ws.m;
    let h = (m - 1) / 2;
    let shape = Shape::new(element, m);
    let (nt, cols, n0_col, offsets) = (element.tangential, shape.cols, shape.n0_col, shape.offsets);
    let Workspace {
        jacobian,
        jacobian_cols,
        derivative: b,
        aft_scratch,
        ..
    } = ws;
    jacobian.clear();
    jacobian.resize(element.signals() * m * cols, 0.0);
    *jacobian_cols = cols;
    for d in 0..nt {
        b.flush(d);
    }
    // Periodic closure.
    let phi = [
        [b.dw[0][cols], b.dw[0][cols + 1]],
        [b.dw[1][cols], b.dw[1][cols + 1]],
    ];
    periodic_start(
        element.variant,
        phi,
        &b.dw,
        &b.transient,
        cols,
        &mut b.start,
    );
    // Fixed-w part.
    for f in 0..3 {
        let Some(fb) = offsets.of(f) else { continue };
        for c in 0..3 {
            let Some(cb) = offsets.of(c) else { continue };
            if !b.gather(f, c) {
                continue;
            }
            aft.fourier_sums(&b.sequence, &mut b.sums, aft_scratch);
            add_multiplication_block(h, &b.sums, &mut b.signed, jacobian, cols, fb, cb);
        }
        if b.gather(f, 3) {
            aft.to_harmonics(&b.sequence, &mut b.column, aft_scratch);
            for (k, ck) in b.column.iter().enumerate() {
                jacobian[(fb + k) * cols + n0_col] += ck;
            }
        }
    }
    // Memory part, closed with ∂w_start.
    for d in 0..nt {
        let rows = &mut jacobian[d * m * cols..(d + 1) * m * cols];
        add_products(&b.left[d], &b.right[d], m, cols, rows, &mut b.start_coef);
        for (k, row) in rows.chunks_exact_mut(cols).enumerate() {
            let (c0, c1) = (b.start_coef[2 * k], b.start_coef[2 * k + 1]);
            if c0 == 0.0 && c1 == 0.0 {
                continue;
            }
            for ((r, s0), s1) in row.iter_mut().zip(&b.start[0]).zip(&b.start[1]) {
                *r += c0 * s0 + c1 * s1;
            }
        }
    }
}

/// Memory and ∂w update of a 2-D slip sample: A = ∂w'/∂w = v vᵀ (rank one, symmetric, from
/// the radial return) and ∂f/∂w = −k_t A, so ∂f_j gains −k_t v (vᵀ ∂w_{j−1}) and
/// ∂w_j = v (vᵀ ∂w_{j−1}) + C_j ∂x_j.
fn slip_2d(
    t: &law::SampleTangent,
    kt: f64,
    e: &[f64],
    bj: &[f64],
    offsets: Offsets,
    n0_col: usize,
    b: &mut DerivativeBuffers,
) {
    b.flush(0);
    b.flush(1);
    if let Some(vv) = slip_direction(t.dslider_dw) {
        for ((s, d0), d1) in b.s.iter_mut().zip(&b.dw[0]).zip(&b.dw[1]) {
            *s = vv[0] * d0 + vv[1] * d1;
        }
        for (d, vd) in vv.into_iter().enumerate() {
            b.left[d].extend(bj.iter().map(|bv| -kt * vd * bv));
            b.right[d].extend_from_slice(&b.s);
            for (r, s) in b.dw[d].iter_mut().zip(&b.s) {
                *r = vd * s;
            }
        }
    } else {
        b.dw[0].fill(0.0);
        b.dw[1].fill(0.0);
    }
    for d in 0..2 {
        add_input_row(&mut b.dw[d], &t.dslider_dx[d], e, offsets, n0_col);
    }
}

/// `rows` (m × cols, row-major) += Σ_r left_r ⊗ right_r[..cols] and `coef` (m × 2) =
/// Σ_r left_r ⊗ right_r[cols..cols+2], for left vectors of length m and right rows of length
/// cols + 2: one matrix product (faer, SIMD) of the m × R and R × (cols + 2) factors.
fn add_products(
    left: &[f64],
    right: &[f64],
    m: usize,
    cols: usize,
    rows: &mut [f64],
    coef: &mut [f64],
) {
    coef.fill(0.0);
    let r = left.len() / m;
    if r == 0 {
        return;
    }
    let lhs = MatRef::from_column_major_slice(left, m, r);
    let rhs = MatRef::from_row_major_slice(right, r, cols + 2);
    let dst = MatMut::from_row_major_slice_mut(rows, m, cols);
    matmul(dst, Accum::Add, lhs, rhs.subcols(0, cols), 1.0, Par::Seq);
    let start = MatMut::from_row_major_slice_mut(coef, m, 2);
    matmul(
        start,
        Accum::Replace,
        lhs,
        rhs.subcols(cols, 2),
        1.0,
        Par::Seq,
    );
}

/// ∂w_start of the last period into `start` (two rows of length `cols`). Where the last period
/// slips or separates, from the periodicity w_start = w_end = Φ w_start + G (per derivative
/// column; G is the first `cols` entries of the rows of `g`): a perturbed input is marched to
/// its own periodic state. Where a direction sticks all period (Φ = 1), the end state equals
/// the start state for every input and the start state is whatever the transient periods left:
/// `transient` (zero when no transient period was marched: the caller's state is a parameter).
fn periodic_start(
    variant: Variant,
    phi: [[f64; 2]; 2],
    g: &[Vec<f64>; 2],
    transient: &[Vec<f64>; 2],
    cols: usize,
    start: &mut [Vec<f64>; 2],
) {
    start[0].fill(0.0);
    start[1].fill(0.0);
    match variant {
        Variant::OneD => {
            // Φ is diagonal with entries exactly 1 (stuck all period) or 0 (slider reset).
            for d in 0..2 {
                if phi[d][d] == 1.0 {
                    start[d].copy_from_slice(&transient[d][..cols]);
                } else {
                    let s = 1.0 / (1.0 - phi[d][d]);
                    for (o, gv) in start[d].iter_mut().zip(&g[d][..cols]) {
                        *o = s * gv;
                    }
                }
            }
        }
        Variant::TwoD => {
            if phi == [[1.0, 0.0], [0.0, 1.0]] {
                start[0].copy_from_slice(&transient[0][..cols]);
                start[1].copy_from_slice(&transient[1][..cols]);
                return;
            }
            let a = [[1.0 - phi[0][0], -phi[0][1]], [-phi[1][0], 1.0 - phi[1][1]]];
            let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            let inv = [
                [a[1][1] / det, -a[0][1] / det],
                [-a[1][0] / det, a[0][0] / det],
            ];
            for k in 0..cols {
                let (g0, g1) = (g[0][k], g[1][k]);
                start[0][k] = inv[0][0] * g0 + inv[0][1] * g1;
                start[1][k] = inv[1][0] * g0 + inv[1][1] * g1;
            }
        }
    }
}

/// Adds M(a)_kl = Σ_j B_kj a_j E_jl (the harmonic matrix of multiplication by a sampled weight
/// a) to the block at (`row0`, `col0`) of `jac` (row-major, `cols` columns), from the discrete
/// Fourier sums c_p = `sums[2p]`, s_p = `sums[2p+1]`, p = 0..2H ([`Aft::fourier_sums`]):
/// M_00 = c_0, M_0,ν = (c_ν, −s_ν), M_κ,0 = (2c_κ, −2s_κ),
/// M_κν = [[c_{κ−ν} + c_{κ+ν}, −(s_{κ+ν} + s_{ν−κ})], [−(s_{κ+ν} + s_{κ−ν}), c_{κ−ν} − c_{κ+ν}]]
/// (2×2 blocks of (Re, Im) rows and columns; c_{−p} = c_p, s_{−p} = −s_p). `signed` is scratch
/// for the sums of orders q = −2H..=2H, (c_q, s_q) at index q + 2H, so that a block row reads
/// contiguous runs of orders. A constant weight (s_p = c_p = 0 for p ≥ 1) adds c_0 I.
pub(crate) fn add_multiplication_block(
    h: usize,
    sums: &[f64],
    signed: &mut Vec<[f64; 2]>,
    jac: &mut [f64],
    cols: usize,
    row0: usize,
    col0: usize,
) {
    let m = 2 * h + 1;
    if sums[2..2 * m].iter().all(|&x| x == 0.0) {
        // A constant weight (e.g. stuck or in contact all period): M = c_0 I.
        for k in 0..m {
            jac[(row0 + k) * cols + col0 + k] += sums[0];
        }
        return;
    }
    let zero = 2 * h;
    signed.resize(4 * h + 1, [0.0; 2]);
    for p in 0..=2 * h {
        let (c, s) = (sums[2 * p], sums[2 * p + 1]);
        signed[zero + p] = [c, s];
        signed[zero - p] = [c, -s];
    }
    {
        let row = &mut jac[row0 * cols + col0..row0 * cols + col0 + m];
        row[0] += sums[0];
        for (pair, cs) in row[1..]
            .chunks_exact_mut(2)
            .zip(&signed[zero + 1..=zero + h])
        {
            pair[0] += cs[0];
            pair[1] -= cs[1];
        }
    }
    for ka in 1..=h {
        let two = &mut jac[(row0 + 2 * ka - 1) * cols..(row0 + 2 * ka + 1) * cols];
        let (re, im) = two.split_at_mut(cols);
        re[col0] += 2.0 * sums[2 * ka];
        im[col0] -= 2.0 * sums[2 * ka + 1];
        let re = &mut re[col0 + 1..col0 + m];
        let im = &mut im[col0 + 1..col0 + m];
        // Orders κ + ν (ν = 1..H, increasing) and κ − ν (decreasing).
        let plus = &signed[zero + ka + 1..zero + ka + 1 + h];
        let minus = &signed[zero + ka - h..zero + ka];
        for nu in 0..h {
            let (p, n) = (plus[nu], minus[h - 1 - nu]);
            re[2 * nu] += n[0] + p[0];
            re[2 * nu + 1] -= p[1] - n[1];
            im[2 * nu] -= p[1] + n[1];
            im[2 * nu + 1] += n[0] - p[0];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::harmonics::HarmonicLayout;

    /// Local coefficients of `signals` signals with amplitudes `amp`, decaying as 1/n, from a
    /// fixed pseudo-random sequence.
    fn input(seed: &mut u64, h: usize, signals: usize, amp: [f64; 3]) -> Vec<f64> {
        let m = 2 * h + 1;
        let mut uniform = || {
            *seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (*seed >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
        };
        let mut x = vec![0.0; signals * m];
        for (c, a) in amp.iter().enumerate().take(signals) {
            x[c * m] = 0.3 * a * uniform();
            for n in 1..=h {
                x[c * m + 2 * n - 1] = a * uniform() / n as f64;
                x[c * m + 2 * n] = a * uniform() / n as f64;
            }
        }
        x
    }

    /// The 1-D Jacobian from the stored samples ([`jacobian_1d`]) equals the general
    /// differentiated march ([`finish_jacobian`]) to 1e-12 of its largest entry: every regime
    /// (all stuck, where it is k_t I on the tangential blocks; gross and partial slip;
    /// intermittent and permanent separation), H = 1, 3, 7, from the zero state (transient
    /// periods) and from the converged state, for 1 or 2 directions with and without normal
    /// kinematics; also checks the all-stuck closed form.
    #[test]
    fn samples_jacobian_equals_general_path() {
        let mut seed = 7;
        let mut compared = 0;
        for h in [1, 3, 7] {
            let aft = Aft::new(HarmonicLayout::with_default_samples(h)).unwrap();
            let m = 2 * h + 1;
            let mut ws = Workspace::new(&aft);
            for (tangential, normal) in [(2, true), (1, true), (2, false)] {
                for (n0, amp) in [
                    (1.0, [0.01, 0.008, 0.01]),
                    (1.0, [1.0, 0.8, 0.01]),
                    (1.0, [0.12, 0.1, 0.01]),
                    (1.0, [0.2, 0.15, 0.1]),
                    (-1.0, [0.2, 0.15, 0.02]),
                ] {
                    let el = LocalElement {
                        params: ContactParams::new(10.0, 20.0, 0.5, n0, "test").unwrap(),
                        variant: Variant::OneD,
                        tangential,
                        normal,
                    };
                    let nsig = el.signals();
                    let x = input(&mut seed, h, nsig, amp);
                    let mut f = vec![0.0; nsig * m];
                    let mut converged = [0.0; 2];
                    evaluate(&el, &aft, &x, &mut converged, &mut f, false, &mut ws).unwrap();
                    for start in [[0.0; 2], converged] {
                        let mut jac = [Vec::new(), Vec::new()];
                        let mut periods = [0; 2];
                        for (k, samples_path) in [true, false].into_iter().enumerate() {
                            let mut s = start;
                            ws.samples_path = samples_path;
                            let marching =
                                evaluate(&el, &aft, &x, &mut s, &mut f, true, &mut ws).unwrap();
                            ws.samples_path = true;
                            periods[k] = marching.periods;
                            jac[k] = ws.jacobian().0.to_vec();
                        }
                        assert_eq!(periods[0], periods[1]);
                        let scale = jac[1].iter().fold(0.0f64, |a, b| a.max(b.abs()));
                        for (i, (a, g)) in jac[0].iter().zip(&jac[1]).enumerate() {
                            assert!(
                                (a - g).abs() <= 1e-12 * scale,
                                "H={h} {tangential} dir normal={normal} n0={n0} amp={amp:?} start={start:?}: entry {i}: samples {a} vs general {g}"
                            );
                        }
                        compared += 1;
                        let r = ws.report();
                        if r.stick == 1.0 && periods[0] == 1 {
                            // All stuck from a periodic state: k_t I on the tangential blocks.
                            let cols = nsig * m + 1;
                            for d in 0..tangential {
                                for k in 0..m {
                                    for l in 0..cols {
                                        let want = if l == d * m + k { 10.0 } else { 0.0 };
                                        let got = jac[0][(d * m + k) * cols + l];
                                        assert!(
                                            (got - want).abs() <= 1e-12 * 10.0,
                                            "all stuck H={h}: [{k}][{l}] = {got}"
                                        );
                                    }
                                }
                            }
                        }
                    }
                }
            }
        }
        assert_eq!(compared, 3 * 3 * 5 * 2);
    }

    /// The march of a Jenkins element (one direction, no normal kinematics), whole or after a
    /// stored period of the same motion, gives the samples of the general
    /// law value for value: stuck all period, partial and gross slip, n0 = 0 (no limit) and
    /// n0 < 0 (separated all period), from rest and from a displaced slider, over three
    /// periods.
    #[test]
    fn one_direction_march_equals_the_general_law() {
        let mut seed = 11;
        let h = 7;
        let aft = Aft::new(HarmonicLayout::new(h, 1024).unwrap()).unwrap();
        let mut fast = Workspace::new(&aft);
        let mut again = Workspace::new(&aft);
        let mut general = Workspace::new(&aft);
        let mut marched = 0;
        for n0 in [1.0, 0.0, -1.0] {
            let el = LocalElement {
                params: ContactParams::new(20.0, 0.0, 1.0, n0, "test").unwrap(),
                variant: Variant::OneD,
                tangential: 1,
                normal: false,
            };
            for amp in [0.01, 0.12, 1.0] {
                let x = input(&mut seed, h, 1, [amp, 0.0, 0.0]);
                for start in [0.0, 0.03] {
                    let mut w = [[start, 0.0]; 3];
                    for ws in [&mut fast, &mut again, &mut general] {
                        aft.to_time(&x, &mut ws.u[0], &mut ws.aft_scratch);
                        ws.u[1].fill(0.0);
                        ws.v.fill(0.0);
                    }
                    for period in 0..3 {
                        march_period_one_direction(&el.params, &mut fast, &mut w[0], false);
                        march_period(&el, &mut again, &mut w[1], period > 0);
                        march_period_samples(&el, &mut general, &mut w[2]);
                        for (k, ws) in [&fast, &again].into_iter().enumerate() {
                            let what = format!("n0={n0} amp={amp} start={start} period {period}");
                            assert_eq!(w[k], w[2], "{what}");
                            assert_eq!(ws.ft, general.ft, "{what}");
                            assert_eq!(ws.w, general.w, "{what}");
                            assert_eq!(ws.fnormal, general.fnormal, "{what}");
                            assert_eq!(ws.regime, general.regime, "{what}");
                        }
                        marched += 1;
                    }
                }
            }
        }
        assert_eq!(marched, 3 * 3 * 2 * 3);
    }
}
