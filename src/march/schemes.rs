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
//!
//! A step allocates nothing once its step size and contact states have been met: the step
//! matrices and their factors are kept per step size in the [`Cache`], the excitation of the step's
//! end is evaluated once per step ([`Excitation`]), and every intermediate vector lives in the
//! [`Workspace`]; the result is written into a caller-held [`Snapshot`].

use std::collections::HashMap;

use super::dense;
use super::law::{ContactState, LawSample};
use super::lowrank::{self, ColumnTable, CompactLowRank, LowRank};
use super::signal::Harmonic;
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

impl Kinematics {
    /// Zero vectors of `n` DOF.
    pub fn zeros(n: usize) -> Self {
        Kinematics {
            q: vec![0.0; n],
            v: vec![0.0; n],
            a: vec![0.0; n],
        }
    }
}

/// The state at one instant: kinematics and the law's sample of every element (forces, states,
/// sliders).
#[derive(Clone, Debug)]
pub struct Snapshot {
    /// q, q̇, q̈.
    pub kin: Kinematics,
    /// One sample per element.
    pub samples: Vec<LawSample>,
}

impl Snapshot {
    /// Zero kinematics of `n` DOF and room for the samples of `elements` elements.
    pub fn new(n: usize, elements: usize) -> Self {
        Snapshot {
            kin: Kinematics::zeros(n),
            samples: Vec::with_capacity(elements),
        }
    }
}

/// The excitation at one instant, evaluated once per step: the force side per DOF (N; the dynamic
/// force f_e + f_d of [`MarchSystem::dynamic_force`] for the Newmark schemes, f_e alone for the
/// quasi-static method) and the prescribed parts p_t, p_n of every element (m).
#[derive(Clone, Debug, Default)]
pub struct Excitation {
    /// Force per DOF (N).
    pub force: Vec<f64>,
    /// p_t(t) per element (m).
    pub pt: Vec<f64>,
    /// p_n(t) per element (m, 0 without a normal).
    pub pn: Vec<f64>,
    /// (cos ωt, sin ωt) of the instant.
    pub phase: (f64, f64),
}

impl Excitation {
    /// Sized for `sys`, all zero.
    pub fn new(sys: &MarchSystem) -> Self {
        Excitation {
            force: vec![0.0; sys.n],
            pt: vec![0.0; sys.elements.len()],
            pn: vec![0.0; sys.elements.len()],
            phase: (1.0, 0.0),
        }
    }

    /// The excitation of `sys` at time `t` (s) for the frequency `omega` (rad/s); `dynamic`
    /// selects the dynamic force (with the damping force of prescribed velocities). One sin_cos
    /// of ωt for every signal.
    pub fn fill(&mut self, sys: &MarchSystem, omega: f64, t: f64, dynamic: bool) {
        let (s, c) = (omega * t).sin_cos();
        self.fill_at_phase(sys, c, s, dynamic);
    }

    /// The excitation of `sys` at the phase ωt of cosine `c` and sine `s` ([`Excitation::fill`]
    /// without the sin_cos; the adaptive march steps the phase, [`super::signal::PhaseSteps`]).
    #[inline]
    pub fn fill_at_phase(&mut self, sys: &MarchSystem, c: f64, s: f64, dynamic: bool) {
        self.phase = (c, s);
        for (fi, h) in self.force.iter_mut().zip(&sys.force) {
            *fi = h.at_phase(c, s);
        }
        if dynamic {
            for (fi, h) in self.force.iter_mut().zip(&sys.damping_force) {
                *fi += h.at_phase(c, s);
            }
        }
        for ((e, pt), pn) in sys.elements.iter().zip(&mut self.pt).zip(&mut self.pn) {
            *pt = e.tangential.prescribed.at_phase(c, s);
            *pn = e
                .normal
                .as_ref()
                .map_or(0.0, |d| d.prescribed.at_phase(c, s));
        }
    }

    /// The excitation as a borrowed view.
    pub fn view(&self) -> ExcitationAt<'_> {
        ExcitationAt {
            force: &self.force,
            pt: &self.pt,
            pn: &self.pn,
            phase: self.phase,
        }
    }

    /// [`Excitation::new`] then [`Excitation::fill`].
    pub fn at(sys: &MarchSystem, omega: f64, t: f64, dynamic: bool) -> Self {
        let mut e = Excitation::new(sys);
        e.fill(sys, omega, t, dynamic);
        e
    }
}

/// The excitation at one instant, borrowed (from an [`Excitation`] or a row of a precomputed
/// table of a period's steps): force per DOF (N), p_t and p_n per element (m).
#[derive(Clone, Copy, Debug)]
pub struct ExcitationAt<'a> {
    /// Force per DOF (N).
    pub force: &'a [f64],
    /// p_t(t) per element (m).
    pub pt: &'a [f64],
    /// p_n(t) per element (m, 0 without a normal).
    pub pn: &'a [f64],
    /// (cos ωt, sin ωt) of the instant (the signals' phase, [`Harmonic::at_phase`]).
    pub phase: (f64, f64),
}

/// Every intermediate vector of a step (sized once for the model).
pub struct Workspace {
    qs: Vec<f64>,
    vs: Vec<f64>,
    b: Vec<f64>,
    rhs: Vec<f64>,
    g: Vec<f64>,
    dq: Vec<f64>,
    qt: Vec<f64>,
    r: Vec<f64>,
    r_trial: Vec<f64>,
    aq: Vec<f64>,
    k: Vec<f64>,
    trial: Vec<LawSample>,
    states: Vec<ContactState>,
    codes: Vec<u8>,
    law_codes: Vec<u8>,
    seen: Vec<u8>,
    scratch: Vec<f64>,
    unused_r: Vec<f64>,
    /// y₀ = A_stick⁻¹ (b + r_ref) of the premultiplied step ([`Premultiplied`]).
    y0: Vec<f64>,
    /// [q*; v*] (2n) of the premultiplied step.
    qv: Vec<f64>,
    /// A_stick⁻¹ g_t of one element (scratch of the reference sliders' update).
    column: Vec<f64>,
    /// Whether `b` holds the Newmark right-hand side of the current step.
    b_ready: bool,
    lu: dense::ScratchLu,
    /// The standard corrector's cycle check.
    cycle: CycleCheck,
    damped: bool,
}

impl Workspace {
    /// Buffers for `sys` (the step-matrix buffer K + K_c is sized when a factor is first built).
    pub fn new(sys: &MarchSystem) -> Self {
        let (n, ne) = (sys.n, sys.elements.len());
        let v = || vec![0.0; n];
        Workspace {
            qs: v(),
            vs: v(),
            b: v(),
            rhs: v(),
            g: v(),
            dq: v(),
            qt: v(),
            r: v(),
            r_trial: v(),
            aq: v(),
            k: Vec::new(),
            trial: Vec::with_capacity(ne),
            states: Vec::with_capacity(ne),
            codes: Vec::with_capacity(ne),
            law_codes: Vec::with_capacity(ne),
            seen: Vec::with_capacity(16 * ne),
            scratch: Vec::with_capacity(4 * ne),
            unused_r: v(),
            y0: v(),
            qv: Vec::with_capacity(2 * n),
            column: v(),
            b_ready: false,
            lu: dense::ScratchLu::new(n),
            cycle: CycleCheck::new(n),
            damped: sys.damping.iter().any(|&c| c != 0.0),
        }
    }
}

/// Most memory (bytes) the factors of one step size's contact states may take: a model with many
/// elements (a sector's shroud pairs) meets many state combinations during a transient; beyond
/// this the cached factors of that step are dropped and rebuilt as the states recur.
pub const MAX_CACHED_BYTES: usize = 256 << 20;

/// Most memory (bytes) the matrices and factors of all the step sizes together may take: the
/// adaptive step (paper §4.2, eq. 8) takes a few sizes of a ladder ([`super::adaptive`]), each
/// with n × n matrices (0.67 MB at n = 289) and the factors of its states. Beyond this every step
/// size but the one being entered is dropped and rebuilt on its next use (the same matrices: the
/// results do not change).
pub const MAX_CACHED_TOTAL_BYTES: usize = 1 << 30;

/// Most f64 entries of a low-rank factor kept per state (4 MiB): larger ones (a travelling wave's
/// hundreds of slipping elements on thousands of coordinates, where nearly every step meets a new
/// state) are only held as the working factor and updated from state to state.
pub const MAX_CACHED_LOW_RANK: usize = 1 << 19;

/// Which factor solves a state's step.
#[derive(Clone, Copy)]
enum Held {
    /// `factors[i]` of the step size.
    Cached(usize),
    /// The step size's working low-rank factor.
    Working,
}

/// How the step matrix of one contact state is solved.
enum StepFactor {
    /// Its inverse (n × n).
    Full(Vec<f64>),
    /// A low-rank change of the all-stick step matrix ([`LowRank`]), when the rank is below n,
    /// its Z read from the step size's [`ColumnTable`].
    LowRank(Box<CompactLowRank>),
}

impl StepFactor {
    fn entries(&self) -> usize {
        match self {
            StepFactor::Full(a) => a.len(),
            StepFactor::LowRank(l) => l.len(),
        }
    }
}

/// The all-stick operators of one step size that make a piecewise-linear Newmark step free of
/// products with the step matrix's inverse (the step is linear within a contact state, Gastaldi &
/// Berruti 2018 §4.3, eq. A15). With A_stick = M/(βΔτ²) + γC/(βΔτ) + K + K_c(stick), P =
/// M/(βΔτ²) + γC/(βΔτ) and the all-stick r_c with reference sliders w̄,
/// r_ref(t) = Σ_e [k_t (w̄_e − p_t,e(t)) g_t,e − (n0 + k_n p_n,e(t)) g_n,e],
/// a step's y₀ = A_stick⁻¹ (f(τ_{n+1}) + P q* − C v* + r_ref) =
/// (A_stick⁻¹P) q* − (A_stick⁻¹C) v* + ξ₀ + ξ_c cos ωτ + ξ_s sin ωτ + y_w:
/// one pass over [A_stick⁻¹P, −A_stick⁻¹C] (n × 2n, the entries of two n × n products) and O(n),
/// instead of P q*, C v* and a product with A_stick⁻¹. A state's q₁ then follows from y₀ by the low-rank correction of
/// its non-stick elements alone ([`LowRank::solve_shifted`]), since r_c(states) − r_ref lies in
/// the span of their columns U when w̄_e = w_e for every element in stick.
struct Premultiplied {
    /// [A_stick⁻¹P, −A_stick⁻¹C] (row-major n × 2n: row i of both in one run of 2n entries,
    /// read in one pass against [q*; v*]), or A_stick⁻¹P alone (n × n) without damping.
    h: Vec<f64>,
    /// Entries of a row of `h`: 2n, or n without damping.
    width: usize,
    /// ξ₀, ξ_c, ξ_s: A_stick⁻¹ of the mean, cosine and sine parts of f_e + f_d + r_ref − Σ k_t w̄ g_t
    /// (m).
    xi: [Vec<f64>; 3],
    /// y_w = A_stick⁻¹ Σ_e k_t w̄_e g_t,e (m).
    yw: Vec<f64>,
    /// The reference slider w̄_e of each element (m).
    wbar: Vec<f64>,
}

impl Premultiplied {
    /// The operators of the step size whose all-stick inverse is `stick` and inertia matrix
    /// M/(βΔτ²) + γC/(βΔτ) is `inertia` (row-major n × n), reference sliders at zero.
    fn new(sys: &MarchSystem, stick: &[f64], inertia: &[f64]) -> Self {
        let n = sys.n;
        let part = |h: &Harmonic, j: usize| [h.mean, h.cos, h.sin][j];
        let mut xi: [Vec<f64>; 3] = [vec![0.0; n], vec![0.0; n], vec![0.0; n]];
        for (j, x) in xi.iter_mut().enumerate() {
            let mut b = vec![0.0; n];
            for (i, bi) in b.iter_mut().enumerate() {
                *bi = part(&sys.force[i], j) + sys.damping_force.get(i).map_or(0.0, |h| part(h, j));
            }
            for e in &sys.elements {
                let p = &e.params;
                for &(i, g) in &e.tangential.weights {
                    b[i] -= p.kt * part(&e.tangential.prescribed, j) * g;
                }
                if let Some(d) = e.normal.as_ref().filter(|_| e.applies_normal) {
                    let an = p.kn * part(&d.prescribed, j) + if j == 0 { p.n0 } else { 0.0 };
                    for &(i, g) in &d.weights {
                        b[i] -= an * g;
                    }
                }
            }
            dense::matvec(stick, &b, x);
        }
        let hp = dense::product(stick, inertia, n);
        let damped = sys.damping.iter().any(|&c| c != 0.0);
        let (h, width) = if damped {
            let hc = dense::product(stick, &sys.damping, n);
            let mut h = Vec::with_capacity(2 * n * n);
            for (p, c) in hp.chunks_exact(n).zip(hc.chunks_exact(n)) {
                h.extend_from_slice(p);
                h.extend(c.iter().map(|x| -x));
            }
            (h, 2 * n)
        } else {
            (hp, n)
        };
        Premultiplied {
            h,
            width,
            xi,
            yw: vec![0.0; n],
            wbar: vec![0.0; sys.elements.len()],
        }
    }

    /// y₀ = (A_stick⁻¹P) q* − (A_stick⁻¹C) v* + ξ₀ + ξ_c c + ξ_s s + y_w into `ws.y0` (predictors
    /// in `ws.qs`, `ws.vs`, copied into `ws.qv` = [q*; v*]; (c, s) the phase of τ_{n+1}): one dot
    /// of 2n entries per row.
    fn base(&self, phase: (f64, f64), ws: &mut Workspace) {
        let n = ws.qs.len();
        let (c, s) = phase;
        let [x0, xc, xs] = &self.xi;
        ws.qv.clear();
        ws.qv.extend_from_slice(&ws.qs);
        if self.width > n {
            ws.qv.extend_from_slice(&ws.vs);
        }
        for ((i, y), row) in ws
            .y0
            .iter_mut()
            .enumerate()
            .zip(self.h.chunks_exact(self.width))
        {
            *y = dense::dot(row, &ws.qv) + x0[i] + c * xc[i] + s * xs[i] + self.yw[i];
        }
    }

    /// Memory held (f64 entries).
    fn len(&self) -> usize {
        self.h.len() + 4 * self.yw.len() + self.wbar.len()
    }
}

/// The matrices and factors of one step size Δτ (Δτ bits; 0 for the quasi-static method).
struct StepSize {
    bits: u64,
    /// M/(βΔτ²) + γC/(βΔτ) (the inertia part of every Newmark step matrix).
    inertia: Option<Vec<f64>>,
    /// (M/(βΔτ²) + γC/(βΔτ) + K)⁻¹ for the standard corrector.
    structural: Option<Vec<f64>>,
    /// Inverse of the all-stick step matrix (the base of the low-rank factors).
    stick: Option<Vec<f64>>,
    /// State codes → index into `factors`.
    index: HashMap<Vec<u8>, usize>,
    /// The factor of each state met, with its codes.
    factors: Vec<(Vec<u8>, StepFactor)>,
    /// f64 entries held by `factors`.
    held: usize,
    /// The factor used last (a step's state is most often the previous step's).
    last: Option<usize>,
    /// The low-rank factors of the state met last, moved to each new state by column updates;
    /// the factors kept in `factors` are copies of it when they are small
    /// ([`MAX_CACHED_LOW_RANK`]).
    working: Option<LowRank>,
    /// The premultiplied all-stick operators (fixed-step piecewise-linear Newmark).
    premultiplied: Option<Premultiplied>,
    /// A_stick⁻¹ g of every element direction: the Z of the cached low-rank factors.
    columns: Option<ColumnTable>,
}

impl StepSize {
    /// Memory held (bytes): the n × n matrices and the factors of the states.
    fn bytes(&self) -> usize {
        let matrices = [&self.inertia, &self.structural, &self.stick]
            .iter()
            .map(|m| m.as_ref().map_or(0, Vec::len))
            .sum::<usize>();
        let working = self.working.as_ref().map_or(0, LowRank::len);
        let premultiplied = self.premultiplied.as_ref().map_or(0, Premultiplied::len);
        let columns = self.columns.as_ref().map_or(0, ColumnTable::len);
        (matrices + self.held + working + premultiplied + columns) * std::mem::size_of::<f64>()
    }

    fn new(bits: u64) -> Self {
        StepSize {
            bits,
            inertia: None,
            structural: None,
            stick: None,
            index: HashMap::new(),
            factors: Vec::new(),
            held: 0,
            last: None,
            working: None,
            premultiplied: None,
            columns: None,
        }
    }

    /// The index of the factor of the state `codes`, if held (the last one used is checked
    /// first, without hashing).
    fn find(&mut self, codes: &[u8]) -> Option<usize> {
        if let Some(i) = self.last.filter(|&i| same_codes(&self.factors[i].0, codes)) {
            return Some(i);
        }
        let i = *self.index.get(codes)?;
        self.last = Some(i);
        Some(i)
    }
}

/// Step matrices and their factors, kept per step size (and per contact state).
#[derive(Default)]
pub struct Cache {
    /// One entry per step size met.
    sizes: Vec<StepSize>,
    /// Δτ bits → index into `sizes`.
    index: HashMap<u64, usize>,
    /// The step size used last (checked first, without hashing).
    current: Option<usize>,
    /// Number of factorisations made.
    pub factorisations: usize,
    /// Whether piecewise-linear Newmark steps use the [`Premultiplied`] operators (set by
    /// [`Cache::use_premultiplied`]).
    premultiply: bool,
    /// Most bytes all the step sizes may hold; `None`: [`MAX_CACHED_TOTAL_BYTES`].
    total_limit: Option<usize>,
}

impl Cache {
    /// A cache whose step sizes hold at most `bytes` in all (instead of
    /// [`MAX_CACHED_TOTAL_BYTES`]).
    pub fn with_total_limit(bytes: usize) -> Self {
        Cache {
            total_limit: Some(bytes),
            ..Cache::default()
        }
    }

    /// Lets the piecewise-linear Newmark steps of `sys` use the premultiplied all-stick operators
    /// (one pass over A_stick⁻¹P and A_stick⁻¹C per step instead of P q*, C v* and a product by
    /// A_stick⁻¹ per state iteration) when every contact state's step matrix is a low-rank change
    /// of the all-stick one (fewer columns than DOF, [`lowrank::max_rank`]); returns whether they
    /// do. For a fixed step: each step size holds two more n × n matrices.
    pub fn use_premultiplied(&mut self, sys: &MarchSystem, on: bool) -> bool {
        self.premultiply = on && lowrank::max_rank(&sys.elements) < sys.n;
        self.premultiply
    }

    /// Bytes held by the matrices and factors of all the step sizes.
    pub fn held_bytes(&self) -> usize {
        self.sizes.iter().map(StepSize::bytes).sum()
    }

    /// The number of step sizes held.
    pub fn step_sizes(&self) -> usize {
        self.sizes.len()
    }

    /// The index of the entry of the step size with key `bits` (made on first use).
    fn slot(&mut self, bits: u64) -> usize {
        if let Some(i) = self.current.filter(|&i| self.sizes[i].bits == bits) {
            return i;
        }
        let i = match self.index.get(&bits) {
            Some(&i) => i,
            None => {
                let limit = self.total_limit.unwrap_or(MAX_CACHED_TOTAL_BYTES);
                if self.held_bytes() > limit {
                    self.sizes.clear();
                    self.index.clear();
                }
                self.sizes.push(StepSize::new(bits));
                self.index.insert(bits, self.sizes.len() - 1);
                self.sizes.len() - 1
            }
        };
        self.current = Some(i);
        i
    }

    /// Makes sure M/(βΔτ²) + γC/(βΔτ) of the step `dt` is held; returns the step size's slot.
    fn ensure_inertia(&mut self, sys: &MarchSystem, dt: f64) -> usize {
        let i = self.slot(dt.to_bits());
        self.sizes[i].inertia.get_or_insert_with(|| {
            let cm = 1.0 / (BETA * dt * dt);
            let cc = GAMMA / (BETA * dt);
            sys.mass
                .iter()
                .zip(&sys.damping)
                .map(|(m, c)| cm * m + cc * c)
                .collect()
        });
        i
    }

    /// Makes sure the inverse of the standard corrector's S = M/(βΔτ²) + γC/(βΔτ) + K is held;
    /// returns the step size's slot.
    fn ensure_structural(&mut self, sys: &MarchSystem, dt: f64) -> Result<usize> {
        let i = self.ensure_inertia(sys, dt);
        let size = &mut self.sizes[i];
        if size.structural.is_none() {
            let s: Vec<f64> = size
                .inertia
                .as_ref()
                .expect("inertia held")
                .iter()
                .zip(&sys.stiffness)
                .map(|(p, k)| p + k)
                .collect();
            let inv = dense::inverse(&s, sys.n).ok_or_else(|| {
                Error::Compute(format!(
                    "the Newmark matrix M/(βΔτ²) + γC/(βΔτ) + K is singular (Δτ = {dt:e} s): the model needs mass"
                ))
            })?;
            self.factorisations += 1;
            size.structural = Some(inv);
        }
        Ok(i)
    }

    /// x = A⁻¹ b for the piecewise-linear step matrix A of the contact `states` (codes `codes`;
    /// A = K + K_c(states), plus M/(βΔτ²) + γC/(βΔτ) when `dynamic`): its factor is built on the
    /// first visit of the state (into `k`, the n × n buffer) and cached per step size (key Δτ bits,
    /// 0 for the quasi-static method) within [`MAX_CACHED_BYTES`], as the inverse, or as a low-rank
    /// change of the all-stick inverse when the states differ from full stick by a rank below n/2
    /// ([`super::lowrank`]).
    #[allow(clippy::too_many_arguments)]
    fn step_solve(
        &mut self,
        ctx: &StepContext,
        dynamic: bool,
        states: &[ContactState],
        codes: &[u8],
        b: &[f64],
        x: &mut [f64],
        k: &mut Vec<f64>,
        scratch: &mut Vec<f64>,
        one_off: Option<(&mut dense::ScratchLu, &mut Vec<f64>)>,
    ) -> Result<()> {
        if let (true, Some((lu, unused_r))) = (dynamic, one_off) {
            let sys = ctx.sys;
            one_off_matrix(sys, ctx.dt, states, k, unused_r);
            if !lu.factor(k) {
                return Err(singular(sys, step_name(dynamic), ctx.t1, codes));
            }
            lu.solve(b, x);
            return Ok(());
        }
        let slot = self.slot(if dynamic { ctx.dt.to_bits() } else { 0 });
        let held = self.held_factor(ctx, dynamic, slot, states, codes, k)?;
        let size = &self.sizes[slot];
        let factor = match held {
            Held::Cached(f) => &size.factors[f].1,
            Held::Working => {
                let w = size.working.as_ref().expect("working factor held");
                w.solve_with(size.stick.as_ref().expect("stick held"), b, x, scratch);
                return Ok(());
            }
        };
        match factor {
            StepFactor::Full(inv) => dense::matvec(inv, b, x),
            StepFactor::LowRank(l) => l.solve_with(
                size.stick.as_ref().expect("stick held"),
                size.columns.as_ref().expect("columns held"),
                b,
                x,
                scratch,
            ),
        }
        Ok(())
    }

    /// Where the factor of the state `codes` of the step size in `slot` is held: cached, the
    /// working factor, or built now ([`Cache::build_factor`]).
    fn held_factor(
        &mut self,
        ctx: &StepContext,
        dynamic: bool,
        slot: usize,
        states: &[ContactState],
        codes: &[u8],
        k: &mut Vec<f64>,
    ) -> Result<Held> {
        let size = &mut self.sizes[slot];
        Ok(match size.find(codes) {
            Some(f) => Held::Cached(f),
            None if size.working.as_ref().is_some_and(|w| w.states() == states) => Held::Working,
            None => self.build_factor(ctx, dynamic, slot, states, codes, k)?,
        })
    }

    /// Makes sure the inverse of the all-stick step matrix of the step size in `slot` is held
    /// (with its inertia part when `dynamic`, which must be held then); returns the
    /// factorisations made (0 or 1; none when the matrix is singular).
    fn ensure_stick(
        &mut self,
        sys: &MarchSystem,
        slot: usize,
        dynamic: bool,
        k: &mut Vec<f64>,
    ) -> usize {
        let size = &mut self.sizes[slot];
        if size.stick.is_some() {
            return 0;
        }
        let inertia = size.inertia.as_deref().filter(|_| dynamic);
        step_matrix(sys, inertia, &sys.stick_states(), k);
        size.stick = dense::inverse(k, sys.n);
        usize::from(size.stick.is_some())
    }

    /// Makes sure the [`Premultiplied`] operators of the step `dt` are held, when enabled
    /// ([`Cache::use_premultiplied`]) and the all-stick step matrix is regular; returns the step
    /// size's slot.
    fn ensure_premultiplied(
        &mut self,
        sys: &MarchSystem,
        dt: f64,
        k: &mut Vec<f64>,
    ) -> Option<usize> {
        if !self.premultiply {
            return None;
        }
        let slot = self.ensure_inertia(sys, dt);
        if self.sizes[slot].premultiplied.is_none() {
            self.factorisations += self.ensure_stick(sys, slot, true, k);
            let size = &mut self.sizes[slot];
            match (size.stick.as_ref(), size.inertia.as_ref()) {
                (Some(stick), Some(inertia)) => {
                    size.premultiplied = Some(Premultiplied::new(sys, stick, inertia));
                }
                _ => {
                    self.premultiply = false;
                    return None;
                }
            }
        }
        Some(slot)
    }

    /// q₁ of the contact `states` (codes `codes`) from y₀ (`y0`, [`Premultiplied::base`]) of the
    /// step size in `slot` into `x`: first the reference sliders of the elements in stick are
    /// brought to their sliders w at τ_n (`start`; y_w and y₀ updated by O(n) per element that
    /// changed), then x = y₀ + Z B (δ − Vᵀ y₀) ([`LowRank::solve_shifted`]) with δ the columns'
    /// share of r_c(states) − r_ref: n0 + k_n p_n for a separated element's normal column; for its
    /// tangential column k_t (p_t − w̄), minus s μ (n0 + k_n p_n) in slip of sign s (paper Table 1,
    /// [`super::element::Element::add_linear_piece`]). Returns false, solving nothing, when the
    /// state's factor is a full inverse (a change of rank n or more).
    #[allow(clippy::too_many_arguments)]
    fn premultiplied_solve(
        &mut self,
        ctx: &StepContext,
        slot: usize,
        start: &[LawSample],
        states: &[ContactState],
        codes: &[u8],
        ws_y0: &mut [f64],
        x: &mut [f64],
        k: &mut Vec<f64>,
        scratch: &mut Vec<f64>,
        column: &mut [f64],
    ) -> Result<bool> {
        let (sys, n, exc) = (ctx.sys, ctx.sys.n, ctx.excitation);
        {
            let size = &mut self.sizes[slot];
            let stick = size.stick.as_ref().expect("stick held");
            let pm = size.premultiplied.as_mut().expect("premultiplied held");
            for (i, (e, &s)) in sys.elements.iter().zip(states).enumerate() {
                let w = start[i].slider;
                if s != ContactState::Stick || w.to_bits() == pm.wbar[i].to_bits() {
                    continue;
                }
                let d = e.params.kt * (w - pm.wbar[i]);
                lowrank::solve_sparse(stick, n, &e.tangential.weights, column);
                for ((yw, y), c) in pm.yw.iter_mut().zip(ws_y0.iter_mut()).zip(column.iter()) {
                    *yw += d * c;
                    *y += d * c;
                }
                pm.wbar[i] = w;
            }
        }
        let held = self.held_factor(ctx, true, slot, states, codes, k)?;
        let size = &self.sizes[slot];
        let wbar = &size
            .premultiplied
            .as_ref()
            .expect("premultiplied held")
            .wbar;
        let delta = |i: usize, normal: bool| -> f64 {
            let (e, p) = (&sys.elements[i], &sys.elements[i].params);
            let an = match e.normal {
                Some(_) => p.n0 + p.kn * exc.pn[i],
                None => p.n0,
            };
            if normal {
                return an;
            }
            let stick = p.kt * (exc.pt[i] - wbar[i]);
            match states[i] {
                ContactState::Slip(sign) => stick - sign.value() * p.mu * an,
                _ => stick,
            }
        };
        match held {
            Held::Cached(f) => match &size.factors[f].1 {
                StepFactor::LowRank(l) => {
                    let table = size.columns.as_ref().expect("columns held");
                    l.solve_shifted(table, ws_y0, delta, x, scratch);
                }
                StepFactor::Full(_) => return Ok(false),
            },
            Held::Working => {
                let w = size.working.as_ref().expect("working factor held");
                w.solve_shifted(ws_y0, delta, x, scratch);
            }
        }
        Ok(true)
    }

    /// The factor of a state met for the first time ([`Cache::step_solve`]): the working low-rank
    /// factor moved to the state by column updates (or built anew), kept as a copy when small, or
    /// the inverse when the rank is not below n. Returns where it is held.
    fn build_factor(
        &mut self,
        ctx: &StepContext,
        dynamic: bool,
        slot: usize,
        states: &[ContactState],
        codes: &[u8],
        k: &mut Vec<f64>,
    ) -> Result<Held> {
        let (sys, n) = (ctx.sys, ctx.sys.n);
        if dynamic {
            self.ensure_inertia(sys, ctx.dt);
        }
        let mut factor = None;
        let mut made = 0;
        let low_rank = lowrank::rank(&sys.elements, states) < n;
        if low_rank {
            made = self.ensure_stick(sys, slot, dynamic, k);
        }
        let size = &mut self.sizes[slot];
        if low_rank {
            if let Some(inv) = size.stick.as_ref() {
                let updated = size
                    .working
                    .as_mut()
                    .is_some_and(|w| w.update(inv, &sys.elements, states));
                if !updated {
                    size.working = LowRank::new(inv, n, &sys.elements, states);
                }
                if let Some(w) = size.working.as_ref() {
                    if w.len() > MAX_CACHED_LOW_RANK {
                        self.factorisations += made + 1;
                        return Ok(Held::Working);
                    }
                    if size.columns.is_none() {
                        size.columns = Some(ColumnTable::new(inv, n, &sys.elements));
                    }
                    factor = Some(StepFactor::LowRank(Box::new(w.compact())));
                }
            }
        }
        let factor = match factor {
            Some(f) => f,
            None => {
                let inertia = size.inertia.as_deref().filter(|_| dynamic);
                step_matrix(sys, inertia, states, k);
                StepFactor::Full(
                    dense::inverse(k, n)
                        .ok_or_else(|| singular(sys, step_name(dynamic), ctx.t1, codes))?,
                )
            }
        };
        if (size.held + factor.entries()) * std::mem::size_of::<f64>() > MAX_CACHED_BYTES {
            size.factors.clear();
            size.index.clear();
            size.held = 0;
        }
        size.held += factor.entries();
        size.factors.push((codes.to_vec(), factor));
        let i = size.factors.len() - 1;
        size.index.insert(codes.to_vec(), i);
        size.last = Some(i);
        self.factorisations += made + 1;
        Ok(Held::Cached(i))
    }
}

/// The step matrix K + K_c(states) + `inertia` (M/(βΔτ²) + γC/(βΔτ), none for the quasi-static
/// method; row-major) into `k`.
fn step_matrix(
    sys: &MarchSystem,
    inertia: Option<&[f64]>,
    states: &[ContactState],
    k: &mut Vec<f64>,
) {
    k.clear();
    k.extend_from_slice(&sys.stiffness);
    for (e, &s) in sys.elements.iter().zip(states) {
        e.add_stiffness(s, k, sys.n);
    }
    if let Some(p) = inertia {
        k.iter_mut().zip(p).for_each(|(a, b)| *a += b);
    }
}

/// The step matrix M/(βΔτ²) + γC/(βΔτ) + K + K_c(states) (row-major) into `k` (resized to n²
/// on first use), `r` an n-vector of scratch.
fn one_off_matrix(
    sys: &MarchSystem,
    dt: f64,
    states: &[ContactState],
    k: &mut Vec<f64>,
    r: &mut [f64],
) {
    let cm = 1.0 / (BETA * dt * dt);
    let cc = GAMMA / (BETA * dt);
    k.clear();
    k.extend(
        sys.stiffness
            .iter()
            .zip(&sys.mass)
            .zip(&sys.damping)
            .map(|((k, m), c)| k + cm * m + cc * c),
    );
    for (e, &s) in sys.elements.iter().zip(states) {
        e.add_linear_piece_with(s, 0.0, 0.0, 0.0, Some(k), r);
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
    /// The excitation at τ_{n+1} (dynamic force for the Newmark schemes, f_e for the
    /// quasi-static method).
    pub excitation: ExcitationAt<'a>,
    /// A step size met once (the adaptive march's step closing a period): its step matrices
    /// are factored in the [`Workspace`] and not cached.
    pub one_off: bool,
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

/// The law at q for every element with the prescribed parts of `exc` and the sliders of `prev`
/// (the samples at τ_n).
pub fn evaluate_law_with(
    sys: &MarchSystem,
    exc: ExcitationAt,
    q: &[f64],
    prev: &[LawSample],
    out: &mut Vec<LawSample>,
) {
    out.clear();
    out.extend(
        sys.elements
            .iter()
            .zip(prev)
            .zip(exc.pt.iter().zip(exc.pn))
            .map(|((e, p), (&pt, &pn))| e.sample(e.local_with(q, pt, pn), p.slider)),
    );
}

/// The contact force f_c = Σ −g_t f_t − g_n f_n of the samples, added to `f`.
pub fn add_contact_force(sys: &MarchSystem, samples: &[LawSample], f: &mut [f64]) {
    for (e, s) in sys.elements.iter().zip(samples) {
        e.add_force(s.f_t, s.f_n, f);
    }
}

/// Whether two state-code lists are equal, compared inline (a library `memcmp` call costs more
/// than the comparison for the few elements of small models).
fn same_codes(a: &[u8], b: &[u8]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x == y)
}

/// State codes of the samples (the cache key and the state comparison).
pub fn state_codes(samples: &[LawSample], out: &mut Vec<u8>) {
    out.clear();
    out.extend(samples.iter().map(|s| s.state.code()));
}

/// q* and v* of Newmark's relations into `qs`, `vs`.
fn newmark_predictors(k: &Kinematics, dt: f64, qs: &mut [f64], vs: &mut [f64]) {
    for i in 0..k.q.len() {
        qs[i] = k.q[i] + dt * k.v[i] + dt * dt * (0.5 - BETA) * k.a[i];
        vs[i] = k.v[i] + dt * (1.0 - GAMMA) * k.a[i];
    }
}

/// q̈₁, q̇₁ of `kin` from its q₁ by Newmark's relations.
fn newmark_rates(kin: &mut Kinematics, qs: &[f64], vs: &[f64], dt: f64) {
    for i in 0..kin.q.len() {
        kin.a[i] = (kin.q[i] - qs[i]) / (BETA * dt * dt);
        kin.v[i] = vs[i] + GAMMA * dt * kin.a[i];
    }
}

/// The Newmark right-hand side b = f + M q*/(βΔτ²) + C (γ q*/(βΔτ) − v*) =
/// f + P q* − C v* with P = M/(βΔτ²) + γC/(βΔτ), into `ws.b` (predictors in `ws.qs`, `ws.vs`).
fn newmark_rhs(sys: &MarchSystem, p: &[f64], force: &[f64], ws: &mut Workspace) {
    let n = ws.qs.len();
    if ws.damped {
        // row by row over P and C
        for (i, bi) in ws.b.iter_mut().enumerate() {
            let (pr, cr) = (&p[i * n..(i + 1) * n], &sys.damping[i * n..(i + 1) * n]);
            *bi = force[i] + dense::dot(pr, &ws.qs) - dense::dot(cr, &ws.vs);
        }
    } else {
        dense::matvec(p, &ws.qs, &mut ws.b);
        ws.b.iter_mut().zip(force).for_each(|(b, f)| *b += f);
    }
}

/// [`newmark_rhs`] without the cached P: b = f + (M/(βΔτ²) + γC/(βΔτ)) q* − C v*.
fn newmark_rhs_direct(sys: &MarchSystem, dt: f64, force: &[f64], ws: &mut Workspace) {
    let cm = 1.0 / (BETA * dt * dt);
    let cc = GAMMA / (BETA * dt);
    ws.b.copy_from_slice(force);
    dense::matvec_scaled_add(cm, &sys.mass, &ws.qs, &mut ws.b);
    if ws.damped {
        dense::matvec_scaled_add(cc, &sys.damping, &ws.qs, &mut ws.b);
        dense::matvec_scaled_add(-1.0, &sys.damping, &ws.vs, &mut ws.b);
    }
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

/// The first corrector iteration at which [`standard_corrector`] compares its iterates for a cycle
/// (Brent 1980): the standard steps of the damper and the one-DOF oscillators of
/// `benches/march.rs` converge in at most 17 iterations, so a converging step hardly ever pays
/// for the comparison.
pub const CYCLE_CHECK_FROM: u32 = 16;

/// Why the standard corrector stopped without converging. No message is formed here: the adaptive
/// march re-runs such a step with the full-stick step, and a step must not allocate
/// ([`Unconverged::error`] forms the message).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Unconverged {
    /// The iteration limit was reached.
    Limit(u32),
    /// Iterate `repeat` equals iterate `first` bit for bit: the iterates cycle from there on, and
    /// since none of the cycle's iterates converged none ever will (the slip of a one-DOF Jenkins
    /// element alternating between its two signs, each iterate the other's exact image).
    Cycle {
        /// The earlier iterate.
        first: u32,
        /// The iterate that repeats it.
        repeat: u32,
    },
}

impl Unconverged {
    /// The error of a step of `ctx` that did not converge.
    pub fn error(self, ctx: &StepContext) -> Error {
        let how = match self {
            Unconverged::Limit(n) => format!("did not converge in {n} iterations"),
            Unconverged::Cycle { first, repeat } => format!(
                "cycles (iterate {repeat} repeats iterate {first} bit for bit, so it cannot converge)"
            ),
        };
        Error::Compute(format!(
            "standard Newmark: the corrector {how} at t = {:.6e} s (Δτ = {:e} s); the fixed point needs Δτ/𝕋 < 1/π — lower `step_ratio` or the time step",
            ctx.t1, ctx.dt
        ))
    }
}

/// The result of [`standard_corrector`]: the iterations, or why it did not converge.
pub type Corrected = std::result::Result<u32, Unconverged>;

/// Brent's cycle detection (Brent 1980, "An improved Monte Carlo factorization algorithm", BIT 20,
/// §2) on the iterates q̃_k of the standard corrector, a map q̃_{k+1} = F(q̃_k) that depends on q̃_k
/// alone within a step: one saved iterate, moved to the current one whenever the distance to it
/// reaches a power of two, so a cycle of length L entered at iterate μ is found by iterate
/// 2 max(μ, L) or so, with one comparison of n values per iteration and no allocation.
struct CycleCheck {
    /// The saved iterate.
    saved: Vec<f64>,
    /// Its index k.
    saved_at: u32,
    /// The distance at which the saved iterate moves on.
    power: u32,
}

impl CycleCheck {
    /// Room for iterates of `n` DOF.
    fn new(n: usize) -> Self {
        CycleCheck {
            saved: Vec::with_capacity(n),
            saved_at: 0,
            power: 1,
        }
    }

    /// Iterate `it` is `q`: the index of an earlier iterate it equals bit for bit, if any. The
    /// comparisons start at [`CYCLE_CHECK_FROM`] (that iterate is saved).
    fn repeat_of(&mut self, it: u32, q: &[f64]) -> Option<u32> {
        if it < CYCLE_CHECK_FROM {
            return None;
        }
        if it > CYCLE_CHECK_FROM && same_bits(&self.saved, q) {
            return Some(self.saved_at);
        }
        if it == CYCLE_CHECK_FROM || it - self.saved_at == self.power {
            self.power = if it == CYCLE_CHECK_FROM {
                1
            } else {
                2 * self.power
            };
            self.saved.clear();
            self.saved.extend_from_slice(q);
            self.saved_at = it;
        }
        None
    }
}

/// Whether `a` and `b` hold the same values bit for bit.
fn same_bits(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| x.to_bits() == y.to_bits())
}

/// [`standard_corrector`], its non-convergence as an error ([`Unconverged::error`]).
pub fn standard_step(
    ctx: &StepContext,
    start: &Snapshot,
    cache: &mut Cache,
    ws: &mut Workspace,
    out: &mut Snapshot,
) -> Result<u32> {
    standard_corrector(ctx, start, cache, ws, out)?.map_err(|why| why.error(ctx))
}

/// Standard Newmark-β step, Appendix A.3 generalised to C, K ≠ 0: predictor q̃ = q_n; then repeat
/// (A9) R = M q̈̃ + C q̇̃ + K q̃ − f_e(τ_{n+1}) − f_c(q̃), (A10) Δq = −S⁻¹ R with
/// S = M/(βΔτ²) + γC/(βΔτ) + K (the paper's M/(βΔτ²) for the rigid damper), (A11) q̃ += Δq, until
/// |Δq|_∞ < tol. The contact force is the law's, from the sliders at τ_n. The fixed point
/// converges for Δτ/𝕋 < 1/π (paper §4.2, 0.318).
///
/// With R = S q̃ − b − f_c(q̃) (b = f + M q*/(βΔτ²) + C(γ q*/(βΔτ) − v*), the part of R that does
/// not change within the step), the update is q̃ ← S⁻¹ b + S⁻¹ f_c(q̃): S⁻¹ b is computed once per
/// step and an iteration costs one law evaluation and one product with S⁻¹ (the same iterates).
/// The iterates are checked for an exact cycle from [`CYCLE_CHECK_FROM`] on (Brent 1980): a
/// cycle stops the corrector with the outcome the iteration limit would give, without the
/// iterations up to the limit. Writes the step's end into `out`; returns the iterations, or why
/// the corrector did not converge (errors: a singular Newmark matrix).
pub fn standard_corrector(
    ctx: &StepContext,
    start: &Snapshot,
    cache: &mut Cache,
    ws: &mut Workspace,
    out: &mut Snapshot,
) -> Result<Corrected> {
    let sys = ctx.sys;
    let dt = ctx.dt;
    newmark_predictors(&start.kin, dt, &mut ws.qs, &mut ws.vs);
    let sinv = if ctx.one_off {
        newmark_rhs_direct(sys, dt, ctx.excitation.force, ws);
        one_off_matrix(sys, dt, &[], &mut ws.k, &mut ws.unused_r);
        if !ws.lu.factor(&ws.k) {
            return Err(Error::Compute(format!(
                "the Newmark matrix M/(βΔτ²) + γC/(βΔτ) + K is singular (Δτ = {dt:e} s): the model needs mass"
            )));
        }
        None
    } else {
        let i = cache.ensure_structural(sys, dt)?;
        let size = &cache.sizes[i];
        newmark_rhs(
            sys,
            size.inertia.as_ref().expect("inertia held"),
            ctx.excitation.force,
            ws,
        );
        size.structural.as_ref()
    };
    // S⁻¹ x into y
    let solve = |lu: &mut dense::ScratchLu, x: &[f64], y: &mut [f64]| match sinv {
        Some(inv) => dense::matvec(inv, x, y),
        None => lu.solve(x, y),
    };
    // y0 = S⁻¹ b
    solve(&mut ws.lu, &ws.b, &mut ws.rhs);
    let q = &mut out.kin.q;
    q.copy_from_slice(&start.kin.q);
    for it in 1..=ctx.max_iterations {
        evaluate_law_with(sys, ctx.excitation, q, &start.samples, &mut out.samples);
        ws.g.iter_mut().for_each(|x| *x = 0.0);
        add_contact_force(sys, &out.samples, &mut ws.g);
        solve(&mut ws.lu, &ws.g, &mut ws.dq);
        let mut change: f64 = 0.0;
        for ((qi, y), d) in q.iter_mut().zip(&ws.rhs).zip(&ws.dq) {
            let new = y + d;
            change = change.max((new - *qi).abs());
            *qi = new;
        }
        if change < ctx.tolerance {
            newmark_rates(&mut out.kin, &ws.qs, &ws.vs, dt);
            evaluate_law_with(
                sys,
                ctx.excitation,
                &out.kin.q,
                &start.samples,
                &mut out.samples,
            );
            return Ok(Ok(it));
        }
        if let Some(first) = ws.cycle.repeat_of(it, q) {
            return Ok(Err(Unconverged::Cycle { first, repeat: it }));
        }
    }
    Ok(Err(Unconverged::Limit(ctx.max_iterations)))
}

/// How the state iteration solves a state's linear step.
#[derive(Clone, Copy)]
enum Solver {
    /// A(states)⁻¹ (b + r_c(states, w)) with b in `ws.b`.
    RightHandSide,
    /// From y₀ in `ws.y0` with the [`Premultiplied`] operators of the step size in the slot
    /// ([`Cache::premultiplied_solve`]).
    Premultiplied(usize),
}

/// The piecewise-linear solve shared by the dynamic and the quasi-static methods: with the states
/// predicted unchanged from `start`, solve A(states) q₁ = b + r_c(states, w) with
/// A = K + K_c(states) (+ M/(βΔτ²) + γC/(βΔτ) for Newmark) and b (the force and, for Newmark,
/// the predictor terms) in `ws.b`, or from the premultiplied y₀ (`solver`); verify the states with
/// the law at q₁; re-solve with the law's states until they agree (Appendix A.4 steps 2–6,
/// Appendix B). q₁ and the samples go to `out`. Returns `Err(iterations)` if the state iteration
/// cycles or exceeds the iteration limit.
fn state_iteration(
    ctx: &StepContext,
    dynamic: bool,
    solver: Solver,
    start: &Snapshot,
    cache: &mut Cache,
    ws: &mut Workspace,
    out: &mut Snapshot,
) -> Result<std::result::Result<u32, u32>> {
    let sys = ctx.sys;
    let exc = ctx.excitation;
    let ne = sys.elements.len();
    ws.states.clear();
    ws.states.extend(start.samples.iter().map(|s| s.state));
    state_codes(&start.samples, &mut ws.codes);
    ws.seen.clear();
    for it in 1..=ctx.max_iterations {
        let solved = match solver {
            Solver::Premultiplied(slot) => cache.premultiplied_solve(
                ctx,
                slot,
                &start.samples,
                &ws.states,
                &ws.codes,
                &mut ws.y0,
                &mut out.kin.q,
                &mut ws.k,
                &mut ws.scratch,
                &mut ws.column,
            )?,
            Solver::RightHandSide => false,
        };
        if !solved {
            ensure_newmark_rhs(ctx, dynamic, cache, ws);
            ws.rhs.copy_from_slice(&ws.b);
            for (i, e) in sys.elements.iter().enumerate() {
                let w = start.samples[i].slider;
                e.add_linear_piece_with(ws.states[i], w, exc.pt[i], exc.pn[i], None, &mut ws.rhs);
            }
            cache.step_solve(
                ctx,
                dynamic,
                &ws.states,
                &ws.codes,
                &ws.rhs,
                &mut out.kin.q,
                &mut ws.k,
                &mut ws.scratch,
                ctx.one_off.then_some((&mut ws.lu, &mut ws.unused_r)),
            )?;
        }
        evaluate_law_with(sys, exc, &out.kin.q, &start.samples, &mut out.samples);
        state_codes(&out.samples, &mut ws.law_codes);
        if same_codes(&ws.law_codes, &ws.codes) {
            return Ok(Ok(it));
        }
        ws.seen.extend_from_slice(&ws.codes);
        std::mem::swap(&mut ws.codes, &mut ws.law_codes);
        if ws.seen.chunks_exact(ne).any(|c| c == ws.codes.as_slice()) {
            return Ok(Err(it));
        }
        ws.states.clear();
        ws.states.extend(out.samples.iter().map(|s| s.state));
    }
    Ok(Err(ctx.max_iterations))
}

/// Makes sure `ws.b` holds the right-hand side of the step (`ws.b_ready`): for Newmark (`dynamic`)
/// b = f + P q* − C v* ([`newmark_rhs`]; predictors in `ws.qs`, `ws.vs`), for the quasi-static
/// method it is set by the step.
fn ensure_newmark_rhs(ctx: &StepContext, dynamic: bool, cache: &mut Cache, ws: &mut Workspace) {
    if ws.b_ready || !dynamic {
        return;
    }
    let (sys, dt) = (ctx.sys, ctx.dt);
    if ctx.one_off {
        newmark_rhs_direct(sys, dt, ctx.excitation.force, ws);
    } else {
        let i = cache.ensure_inertia(sys, dt);
        newmark_rhs(
            sys,
            cache.sizes[i].inertia.as_ref().expect("inertia held"),
            ctx.excitation.force,
            ws,
        );
    }
    ws.b_ready = true;
}

/// Piecewise-linear Newmark step (paper §4.3, Appendix A.4, eqs A12–A16): the contact states at
/// τ_{n+1} are predicted equal to those at τ_n, the linear Newmark step of eq. A13/A15 is solved, the
/// states are verified by the law and the step re-solved only at a transition. If the state
/// iteration cycles (a tie at a stick/slip boundary; frequent with many elements) the step falls
/// back to damped Newton on the same piecewise-linear equation (unlike the standard corrector it
/// needs no step limit), and the iterations of both are counted. With the premultiplied all-stick
/// operators ([`Cache::use_premultiplied`], not for a one-off step) the linear step is solved from
/// y₀ = A_stick⁻¹ (b + r_ref) (two n × n products) by the low-rank correction of the non-stick
/// elements instead of b = f + P q* − C v* and a product with A_stick⁻¹:
/// the same q₁ to rounding. Writes the step's end into `out`; returns the iterations.
pub fn piecewise_linear_step(
    ctx: &StepContext,
    start: &Snapshot,
    cache: &mut Cache,
    ws: &mut Workspace,
    out: &mut Snapshot,
) -> Result<u32> {
    let sys = ctx.sys;
    let dt = ctx.dt;
    newmark_predictors(&start.kin, dt, &mut ws.qs, &mut ws.vs);
    ws.b_ready = false;
    let premultiplied = if ctx.one_off {
        None
    } else {
        cache.ensure_premultiplied(sys, dt, &mut ws.k)
    };
    let solver = match premultiplied {
        Some(slot) => {
            let pm = cache.sizes[slot].premultiplied.as_ref();
            pm.expect("premultiplied held")
                .base(ctx.excitation.phase, ws);
            Solver::Premultiplied(slot)
        }
        None => {
            ensure_newmark_rhs(ctx, true, cache, ws);
            Solver::RightHandSide
        }
    };
    let iterations = match state_iteration(ctx, true, solver, start, cache, ws, out)? {
        Ok(it) => it,
        Err(tried) => {
            ensure_newmark_rhs(ctx, true, cache, ws);
            tried + damped_newton(ctx, true, start, cache, ws, out)?
        }
    };
    newmark_rates(&mut out.kin, &ws.qs, &ws.vs, dt);
    Ok(iterations)
}

/// Quasi-static step (paper §5.2, eq. 10, Appendix B, eqs A17–A20): (K + K_c) q₁ = f_e + r_c with
/// the states predicted unchanged and verified by the law. q̇₁ = (q₁ − q_n)/Δτ, q̈₁ = 0. Writes
/// the step's end into `out`; returns the iterations.
pub fn quasi_static_step(
    ctx: &StepContext,
    start: &Snapshot,
    cache: &mut Cache,
    ws: &mut Workspace,
    out: &mut Snapshot,
) -> Result<u32> {
    ws.b.copy_from_slice(ctx.excitation.force);
    let solver = Solver::RightHandSide;
    let iterations = match state_iteration(ctx, false, solver, start, cache, ws, out)? {
        Ok(it) => it,
        Err(tried) => tried + damped_newton(ctx, false, start, cache, ws, out)?,
    };
    let kin = &mut out.kin;
    for i in 0..kin.q.len() {
        kin.v[i] = (kin.q[i] - start.kin.q[i]) / ctx.dt;
        kin.a[i] = 0.0;
    }
    Ok(iterations)
}

/// ‖b + f_c(q) − A q‖_∞ with the law's forces from the sliders of `prev`: the residual of the
/// piecewise-linear step, A = M/(βΔτ²) + γC/(βΔτ) + K when `dynamic` (Newmark, eq. A13 with q̈₁,
/// q̇₁ from q₁), else A = K (quasi-static); `b` holds the force and the predictor terms. The
/// residual goes to `r`, the samples to `samples`; `aq`, `cq` are scratch.
#[allow(clippy::too_many_arguments)]
fn step_residual(
    ctx: &StepContext,
    dynamic: bool,
    q: &[f64],
    prev: &[LawSample],
    b: &[f64],
    r: &mut [f64],
    aq: &mut [f64],
    cq: &mut [f64],
    samples: &mut Vec<LawSample>,
) -> f64 {
    let sys = ctx.sys;
    evaluate_law_with(sys, ctx.excitation, q, prev, samples);
    r.copy_from_slice(b);
    dense::matvec(&sys.stiffness, q, aq);
    if dynamic {
        let cm = 1.0 / (BETA * ctx.dt * ctx.dt);
        let cc = GAMMA / (BETA * ctx.dt);
        dense::matvec_scaled_add(cm, &sys.mass, q, aq);
        dense::matvec(&sys.damping, q, cq);
        aq.iter_mut().zip(cq.iter()).for_each(|(a, c)| *a += cc * c);
    }
    add_contact_force(sys, samples, r);
    r.iter_mut().zip(aq.iter()).for_each(|(ri, a)| *ri -= a);
    dense::norm_inf(r)
}

/// Fallback of the piecewise-linear and quasi-static steps when the state iteration cycles (the
/// solution sits on a stick/slip or slip-sign boundary, frequent with many elements): Newton on
/// the continuous piecewise-linear residual of [`step_residual`] with the state's tangent
/// A + K_c and a backtracking line search on ‖r‖_∞, from q_n, until the update is below the
/// tolerance (or 1e-9 of the displacement scale). q₁ and its samples go to `out`.
fn damped_newton(
    ctx: &StepContext,
    dynamic: bool,
    start: &Snapshot,
    cache: &mut Cache,
    ws: &mut Workspace,
    out: &mut Snapshot,
) -> Result<u32> {
    let sys = ctx.sys;
    let tol = ctx.tolerance.max(1e-9 * sys.displacement_scale);
    out.kin.q.copy_from_slice(&start.kin.q);
    let mut norm = step_residual(
        ctx,
        dynamic,
        &out.kin.q,
        &start.samples,
        &ws.b,
        &mut ws.r,
        &mut ws.aq,
        &mut ws.g,
        &mut out.samples,
    );
    for it in 1..=ctx.max_iterations {
        ws.states.clear();
        ws.states.extend(out.samples.iter().map(|s| s.state));
        state_codes(&out.samples, &mut ws.codes);
        cache.step_solve(
            ctx,
            dynamic,
            &ws.states,
            &ws.codes,
            &ws.r,
            &mut ws.dq,
            &mut ws.k,
            &mut ws.scratch,
            ctx.one_off.then_some((&mut ws.lu, &mut ws.unused_r)),
        )?;
        let mut lambda = 1.0;
        loop {
            for ((t, q), d) in ws.qt.iter_mut().zip(&out.kin.q).zip(&ws.dq) {
                *t = q + lambda * d;
            }
            let nt = step_residual(
                ctx,
                dynamic,
                &ws.qt,
                &start.samples,
                &ws.b,
                &mut ws.r_trial,
                &mut ws.aq,
                &mut ws.g,
                &mut ws.trial,
            );
            if nt < (1.0 - 1e-4 * lambda) * norm || lambda < 1e-6 {
                std::mem::swap(&mut out.kin.q, &mut ws.qt);
                norm = nt;
                std::mem::swap(&mut ws.r, &mut ws.r_trial);
                std::mem::swap(&mut out.samples, &mut ws.trial);
                break;
            }
            lambda *= 0.5;
        }
        if lambda * dense::norm_inf(&ws.dq) < tol {
            return Ok(it);
        }
    }
    Err(Error::Compute(format!(
        "{}: no solution of the step found at t = {:.6e} s in {} Newton iterations (the contact states cycle); try another number of steps per period",
        step_name(dynamic),
        ctx.t1,
        ctx.max_iterations
    )))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The iterate of Brent's check at which `sequence` (iterate k at index k − 1) is found to
    /// repeat an earlier iterate, with that iterate's index.
    fn detection(sequence: &[f64]) -> Option<(u32, u32)> {
        let mut check = CycleCheck::new(1);
        (1..=sequence.len() as u32).find_map(|it| {
            check
                .repeat_of(it, &sequence[it as usize - 1..it as usize])
                .map(|f| (f, it))
        })
    }

    #[test]
    fn brent_check_finds_exact_cycles_soon_after_they_start_and_nothing_else() {
        // distinct iterates up to k = 20, then the cycle A, B (the Jenkins slip signs)
        let two: Vec<f64> = (1..=500)
            .map(|k| match k {
                k if k < 20 => k as f64,
                k if k % 2 == 0 => 0.699586488238333,
                _ => 0.7022815566695447,
            })
            .collect();
        let (first, repeat) = detection(&two).expect("2-cycle found");
        assert_eq!(
            two[first as usize - 1].to_bits(),
            two[repeat as usize - 1].to_bits()
        );
        assert_eq!((repeat - first) % 2, 0);
        assert!(repeat <= 20 + 8, "2-cycle entered at 20 found at {repeat}");
        // a 3-cycle from the first compared iterate on
        let three: Vec<f64> = (1..=500).map(|k| [1.0, 2.0, 3.0][k % 3]).collect();
        let (first, repeat) = detection(&three).expect("3-cycle found");
        assert_eq!((repeat - first) % 3, 0);
        assert!(repeat <= CYCLE_CHECK_FROM + 8, "found at {repeat}");
        // iterates that never repeat (alternating about a limit they approach slowly): no cycle
        let distinct: Vec<f64> = (1..=500)
            .map(|k| 1.0 + (-0.5f64).powi(k % 2) / k as f64)
            .collect();
        assert_eq!(detection(&distinct), None);
        // a value seen before the comparisons start is not a cycle of the compared iterates
        let mut early: Vec<f64> = (1..=500).map(|k| k as f64).collect();
        early[CYCLE_CHECK_FROM as usize + 3] = early[2];
        assert_eq!(detection(&early), None);
    }
}
