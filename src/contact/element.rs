//! One contact element over one period: AFT evaluation of the time-discrete law of [`law`] on
//! local harmonic coefficients, periodic marching of the slider state, the analytic Jacobian and
//! the per-element state report (SAMA paper, Battiato 2021, §3 eqs 13–14 and 25; `methods.md`).
//!
//! Local coefficients are stored signal by signal (each in the signal order of [`aft`]):
//! `[U1; U2; V]` (m each, m = 2H+1) where U1, U2 are the tangential relative displacements (m)
//! and V the normal approach (m). An element may have one or two tangential directions and may
//! have no normal kinematics (then v ≡ 0, f_n = max(n0, 0)); absent signals are left out of the
//! vector. The forces `[F1; F2; Fn]` (N) come in the same order, with the internal-force sign of
//! [`law`].
//!
//! Periods are marched from the given slider state until the end-of-period state repeats (at most
//! [`MAX_PERIODS`]); the forces are those of the last period. The Jacobian is the derivative of
//! this periodic solution: ∂w/∂Q is carried through the samples (`methods.md`), and the
//! dependence of the starting slider state on Q is closed by the periodicity condition
//! w_start = w_end. A direction that never slips or separates during the period keeps its given
//! slider (∂w_start = 0): the stuck solution is not unique and the state comes from the caller.
//!
//! [`law`]: super::law
//! [`aft`]: super::aft

use crate::contact::aft::{Aft, AftScratch};
use crate::contact::law::{self, ContactParams, Regime, Variant};
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

    fn check(&self) -> Result<()> {
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

/// Per-element state over the last period (`interface.md` contact-state output).
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
    // derivative carriers
    grad_w: [Vec<f64>; 2],
    grad_tmp: [Vec<f64>; 2],
    dforce: Vec<f64>,
    periodic: Vec<f64>,
    tangents: Vec<law::SampleTangent>,
    weights: Vec<f64>,
    sums: Vec<f64>,
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
            grad_w: [Vec::new(), Vec::new()],
            grad_tmp: [Vec::new(), Vec::new()],
            dforce: Vec::new(),
            periodic: Vec::new(),
            tangents: Vec::with_capacity(n_t),
            weights: Vec::with_capacity(n_t),
            sums: Vec::new(),
        }
    }

    /// The local Jacobian of the last [`evaluate`] with `jacobian = true`: row-major with
    /// `signals·m` rows (∂F of each local force coefficient) and `signals·m + 1` columns (∂ of each
    /// local displacement coefficient, then ∂n0). Returns (entries, number of columns).
    pub fn jacobian(&self) -> (&[f64], usize) {
        (&self.jacobian, self.jacobian_cols)
    }

    /// State report of the last evaluated period.
    pub fn report(&self) -> ElementReport {
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
/// ([`Workspace::jacobian`]).
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
    let m = ws.m;
    let nsig = element.signals();
    debug_assert_eq!(x.len(), nsig * m);
    debug_assert_eq!(force.len(), nsig * m);
    // Time signals.
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
    // March periods until the end-of-period slider state repeats.
    let scale = ws.u[0]
        .iter()
        .chain(ws.u[1].iter())
        .fold(slider[0].abs().max(slider[1].abs()), |a, b| a.max(b.abs()));
    let tol = STATE_TOLERANCE * scale;
    let mut w = *slider;
    let mut w_start = w;
    let mut marching = Marching {
        periods: 0,
        converged: false,
    };
    while marching.periods < MAX_PERIODS {
        w_start = w;
        march_period(element, ws, &mut w);
        marching.periods += 1;
        if (w[0] - w_start[0]).abs() <= tol && (w[1] - w_start[1]).abs() <= tol {
            marching.converged = true;
            break;
        }
    }
    ws.marching = marching;
    *slider = w;
    // Forces to harmonics.
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
    if jacobian {
        match element.variant {
            Variant::OneD => differentiate_one_d(element, aft, w_start, ws),
            Variant::TwoD => differentiate(element, aft, w_start, ws),
        }
    }
    Ok(marching)
}

/// One period of the law from the slider state `w` (updated to the end state); fills the force,
/// slider and regime samples of the workspace.
fn march_period(element: &LocalElement, ws: &mut Workspace, w: &mut [f64; 2]) {
    let p = &element.params;
    for j in 0..ws.n_t {
        let s = law::sample(element.variant, p, [ws.u[0][j], ws.u[1][j]], ws.v[j], *w);
        ws.ft[0][j] = s.force[0];
        ws.ft[1][j] = s.force[1];
        ws.fnormal[j] = s.force[2];
        ws.w[0][j] = s.slider[0];
        ws.w[1][j] = s.slider[1];
        ws.regime[j] = s.regime;
        *w = s.slider;
    }
}

/// The local Jacobian of the periodic solution starting from `w_start` (SAMA paper eq. 25 in
/// local coordinates, plus the column ∂F/∂n0).
///
/// With x = (local coefficients, n0) and E_j the synthesis row of sample j, each sample gives
/// ∂f_j = (∂f/∂x)(E_j ⊗ ·) + (∂f/∂w) ∂w_{j−1} and ∂w_j = (∂w'/∂x)(E_j ⊗ ·) + (∂w'/∂w) ∂w_{j−1}.
/// ∂w is split as G_j + Φ_j ∂w_start (G carried from ∂w_start = 0, Φ_j = ∂w_j/∂w_start); the
/// periodicity w_end = w_start then gives ∂w_start = (I − Φ_end)⁻¹ G_end, and
/// ∂F_k = Σ_j B_kj ∂f_j with B the analysis table.
fn differentiate(element: &LocalElement, aft: &Aft, w_start: [f64; 2], ws: &mut Workspace) {
    let p = &element.params;
    let m = ws.m;
    let n_t = ws.n_t;
    let nt = element.tangential;
    let nsig = element.signals();
    let cols = nsig * m + 1;
    let rows = nsig * m;
    let n0_col = nsig * m;
    ws.jacobian.clear();
    ws.jacobian.resize(rows * cols, 0.0);
    ws.jacobian_cols = cols;
    for d in 0..2 {
        ws.grad_w[d].clear();
        ws.grad_w[d].resize(cols, 0.0);
        ws.grad_tmp[d].clear();
        ws.grad_tmp[d].resize(cols, 0.0);
    }
    ws.dforce.clear();
    ws.dforce.resize(nsig * cols, 0.0);
    // periodic[(row) * 2 + a]: Σ_j B ∂f/∂w Φ_j, the coefficient of ∂w_start.
    ws.periodic.clear();
    ws.periodic.resize(rows * 2, 0.0);
    // Local input component c ∈ {u1, u2, v} → offset of its coefficients in x (None if absent).
    let offset = |c: usize| -> Option<usize> {
        match c {
            0 => Some(0),
            1 if nt == 2 => Some(m),
            2 if element.normal => Some(nt * m),
            _ => None,
        }
    };
    // Local force f ∈ {f1, f2, fn} → row block.
    let force_block = offset;
    let mut phi = [[1.0, 0.0], [0.0, 1.0]];
    let mut w = w_start;
    let analysis = aft.analysis_table();
    for j in 0..n_t {
        let t = law::sample_with_tangent(element.variant, p, [ws.u[0][j], ws.u[1][j]], ws.v[j], w);
        w = t.sample.slider;
        let e = aft.synthesis_row(j);
        // ∂f_j for every present force, as rows of length `cols`.
        for f in 0..3 {
            let Some(fb) = force_block(f) else { continue };
            let row_index = fb / m;
            let row = &mut ws.dforce[row_index * cols..(row_index + 1) * cols];
            row.fill(0.0);
            for c in 0..3 {
                let g = t.dforce_dx[f][c];
                if g != 0.0 {
                    if let Some(o) = offset(c) {
                        for (r, ev) in row[o..o + m].iter_mut().zip(e) {
                            *r += g * ev;
                        }
                    }
                }
            }
            row[n0_col] += t.dforce_dx[f][3];
            if f < 2 {
                for a in 0..2 {
                    let g = t.dforce_dw[f][a];
                    if g != 0.0 {
                        for (r, gw) in row.iter_mut().zip(&ws.grad_w[a]) {
                            *r += g * gw;
                        }
                    }
                }
            }
            // Accumulate the forward transform and the periodic coupling.
            let dfphi = if f < 2 {
                [
                    t.dforce_dw[f][0] * phi[0][0] + t.dforce_dw[f][1] * phi[1][0],
                    t.dforce_dw[f][0] * phi[0][1] + t.dforce_dw[f][1] * phi[1][1],
                ]
            } else {
                [0.0, 0.0]
            };
            let row_is_zero = row.iter().all(|&r| r == 0.0);
            for k in 0..m {
                let b = analysis[k * n_t + j];
                let out = (fb + k) * cols;
                if !row_is_zero {
                    for (jv, r) in ws.jacobian[out..out + cols].iter_mut().zip(row.iter()) {
                        *jv += b * r;
                    }
                }
                ws.periodic[(fb + k) * 2] += b * dfphi[0];
                ws.periodic[(fb + k) * 2 + 1] += b * dfphi[1];
            }
        }
        // ∂w_j and Φ_j.
        for a in 0..2 {
            let tmp = &mut ws.grad_tmp[a];
            tmp.fill(0.0);
            for c in 0..3 {
                let g = t.dslider_dx[a][c];
                if g != 0.0 {
                    if let Some(o) = offset(c) {
                        for (r, ev) in tmp[o..o + m].iter_mut().zip(e) {
                            *r += g * ev;
                        }
                    }
                }
            }
            tmp[n0_col] += t.dslider_dx[a][3];
            for b in 0..2 {
                let g = t.dslider_dw[a][b];
                if g != 0.0 {
                    for (r, gw) in tmp.iter_mut().zip(&ws.grad_w[b]) {
                        *r += g * gw;
                    }
                }
            }
        }
        std::mem::swap(&mut ws.grad_w, &mut ws.grad_tmp);
        let dw = t.dslider_dw;
        phi = [
            [
                dw[0][0] * phi[0][0] + dw[0][1] * phi[1][0],
                dw[0][0] * phi[0][1] + dw[0][1] * phi[1][1],
            ],
            [
                dw[1][0] * phi[0][0] + dw[1][1] * phi[1][0],
                dw[1][0] * phi[0][1] + dw[1][1] * phi[1][1],
            ],
        ];
    }
    // Periodicity: ∂w_start = (I − Φ)⁻¹ G_end; directions that never left stick keep ∂w_start = 0.
    let start = periodic_start(element.variant, phi, &ws.grad_w, cols);
    for r in 0..rows {
        let (c0, c1) = (ws.periodic[r * 2], ws.periodic[r * 2 + 1]);
        if c0 == 0.0 && c1 == 0.0 {
            continue;
        }
        let out = &mut ws.jacobian[r * cols..(r + 1) * cols];
        for (k, o) in out.iter_mut().enumerate() {
            *o += c0 * start[0][k] + c1 * start[1][k];
        }
    }
}

/// ∂w_start from the periodicity w_start = w_end = Φ w_start + G (per derivative column).
fn periodic_start(
    variant: Variant,
    phi: [[f64; 2]; 2],
    g: &[Vec<f64>; 2],
    cols: usize,
) -> [Vec<f64>; 2] {
    let mut start = [vec![0.0; cols], vec![0.0; cols]];
    match variant {
        Variant::OneD => {
            // Φ is diagonal with entries exactly 1 (stuck all period) or 0 (slider reset).
            for d in 0..2 {
                if phi[d][d] != 1.0 {
                    let s = 1.0 / (1.0 - phi[d][d]);
                    for (o, gv) in start[d].iter_mut().zip(&g[d]) {
                        *o = s * gv;
                    }
                }
            }
        }
        Variant::TwoD => {
            if phi == [[1.0, 0.0], [0.0, 1.0]] {
                return start;
            }
            let a = [[1.0 - phi[0][0], -phi[0][1]], [-phi[1][0], 1.0 - phi[1][1]]];
            let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
            let inv = [
                [a[1][1] / det, -a[0][1] / det],
                [-a[1][0] / det, a[0][0] / det],
            ];
            for k in 0..cols {
                start[0][k] = inv[0][0] * g[0][k] + inv[0][1] * g[1][k];
                start[1][k] = inv[1][0] * g[0][k] + inv[1][1] * g[1][k];
            }
        }
    }
    start
}

/// The local Jacobian of the 1-D variant in O(N_t·H + runs·H²) instead of O(N_t·H²).
///
/// In the 1-D law the slider memory is reset at every slip or separation sample (∂w'/∂w = 0
/// there) and frozen during stick (∂w'/∂w = 1, ∂w'/∂x = 0), so ∂w during a stick run equals
/// ∂w' of the run's *anchor* (its last slip/separation sample, wrapping around the period: the
/// periodic closure of [`differentiate`]). ∂F therefore splits into
/// * Σ_j B_kj a_j E_jl for each weight sequence a_j = ∂f_j/∂x_c (fixed w): the harmonic
///   multiplication matrix of a, built from its discrete Fourier sums of orders 0..2H
///   ([`add_multiplication_block`]);
/// * per stick run, (Σ_{j∈run} B_kj ∂f_j/∂w) ⊗ ∂w'_anchor, a rank-one update;
/// * the column ∂/∂n0, Σ_j B_kj ∂f_j/∂n0.
///
/// A direction that never slips or separates has no anchor and keeps ∂w_start = 0.
fn differentiate_one_d(element: &LocalElement, aft: &Aft, w_start: [f64; 2], ws: &mut Workspace) {
    let p = &element.params;
    let m = ws.m;
    let n_t = ws.n_t;
    let nt = element.tangential;
    let nsig = element.signals();
    let cols = nsig * m + 1;
    let n0_col = nsig * m;
    ws.jacobian.clear();
    ws.jacobian.resize(nsig * m * cols, 0.0);
    ws.jacobian_cols = cols;
    let offset = |c: usize| -> Option<usize> {
        match c {
            0 => Some(0),
            1 if nt == 2 => Some(m),
            2 if element.normal => Some(nt * m),
            _ => None,
        }
    };
    ws.tangents.clear();
    let mut w = w_start;
    for j in 0..n_t {
        let t = law::sample_with_tangent(element.variant, p, [ws.u[0][j], ws.u[1][j]], ws.v[j], w);
        w = t.sample.slider;
        ws.tangents.push(t);
    }
    let analysis = aft.analysis_table();
    // Fixed-w terms: multiplication blocks and the n0 column.
    for f in 0..3 {
        let Some(fb) = offset(f) else { continue };
        for c in 0..3 {
            let Some(cb) = offset(c) else { continue };
            ws.weights.clear();
            ws.weights
                .extend(ws.tangents.iter().map(|t| t.dforce_dx[f][c]));
            if ws.weights.iter().all(|&a| a == 0.0) {
                continue;
            }
            add_multiplication_block(
                aft,
                &ws.weights,
                &mut ws.jacobian,
                cols,
                fb,
                cb,
                &mut ws.sums,
            );
        }
        for (j, t) in ws.tangents.iter().enumerate() {
            let a = t.dforce_dx[f][3];
            if a != 0.0 {
                for k in 0..m {
                    ws.jacobian[(fb + k) * cols + n0_col] += analysis[k * n_t + j] * a;
                }
            }
        }
    }
    // Slider memory: one rank-one update per stick run.
    for d in 0..nt {
        let is_anchor = |t: &law::SampleTangent| t.dslider_dw[d][d] == 0.0;
        let Some(last) = ws.tangents.iter().rposition(is_anchor) else {
            continue;
        };
        let fb = d * m;
        let mut anchor = last;
        let mut beta = vec![0.0; m];
        let flush =
            |anchor: usize, beta: &mut [f64], jac: &mut [f64], tangents: &[law::SampleTangent]| {
                let ta = &tangents[anchor];
                let e = aft.synthesis_row(anchor);
                for (k, bk) in beta.iter_mut().enumerate() {
                    if *bk == 0.0 {
                        continue;
                    }
                    let row = &mut jac[(fb + k) * cols..(fb + k + 1) * cols];
                    for c in [d, 2] {
                        let g = ta.dslider_dx[d][c];
                        if let (Some(o), true) = (offset(c), g != 0.0) {
                            for (r, ev) in row[o..o + m].iter_mut().zip(e) {
                                *r += *bk * g * ev;
                            }
                        }
                    }
                    row[n0_col] += *bk * ta.dslider_dx[d][3];
                    *bk = 0.0;
                }
            };
        for j in 0..n_t {
            let t = &ws.tangents[j];
            if is_anchor(t) {
                flush(anchor, &mut beta, &mut ws.jacobian, &ws.tangents);
                anchor = j;
            } else {
                let g = t.dforce_dw[d][d];
                if g != 0.0 {
                    for (k, b) in beta.iter_mut().enumerate() {
                        *b += analysis[k * n_t + j] * g;
                    }
                }
            }
        }
        flush(anchor, &mut beta, &mut ws.jacobian, &ws.tangents);
    }
}

/// Adds M(a)_kl = Σ_j B_kj a_j E_jl (the harmonic matrix of multiplication by the sampled
/// weight a) to the block at (`row0`, `col0`) of `jac` (row-major, `cols` columns), from the
/// discrete Fourier sums c_p = Σ_j a_j cos(pτ_j)/N_t, s_p = Σ_j a_j sin(pτ_j)/N_t, p = 0..2H:
/// M_00 = c_0, M_0,ν = (c_ν, −s_ν), M_κ,0 = (2c_κ, −2s_κ),
/// M_κν = [[c_{κ−ν} + c_{κ+ν}, −(s_{κ+ν} + s_{ν−κ})], [−(s_{κ+ν} + s_{κ−ν}), c_{κ−ν} − c_{κ+ν}]]
/// (2×2 blocks of (Re, Im) rows and columns; s_{−p} = −s_p).
fn add_multiplication_block(
    aft: &Aft,
    a: &[f64],
    jac: &mut [f64],
    cols: usize,
    row0: usize,
    col0: usize,
    sums: &mut Vec<f64>,
) {
    let h = aft.layout().harmonics;
    let n_t = a.len();
    let (cos, sin) = aft.unit_circle();
    sums.clear();
    sums.resize(2 * (2 * h + 1), 0.0);
    for p in 0..=2 * h {
        let (mut c, mut s) = (0.0, 0.0);
        let mut q = 0;
        for &aj in a {
            c += aj * cos[q];
            s += aj * sin[q];
            q += p;
            if q >= n_t {
                q -= n_t;
            }
        }
        sums[2 * p] = c / n_t as f64;
        sums[2 * p + 1] = s / n_t as f64;
    }
    let cp = |p: isize| sums[2 * p.unsigned_abs()];
    let sp = |p: isize| p.signum() as f64 * sums[2 * p.unsigned_abs() + 1];
    let mut add = |r: usize, c: usize, v: f64| jac[(row0 + r) * cols + col0 + c] += v;
    add(0, 0, cp(0));
    for nu in 1..=h as isize {
        let l = 2 * nu as usize;
        add(0, l - 1, cp(nu));
        add(0, l, -sp(nu));
    }
    for ka in 1..=h as isize {
        let k = 2 * ka as usize;
        add(k - 1, 0, 2.0 * cp(ka));
        add(k, 0, -2.0 * sp(ka));
        for nu in 1..=h as isize {
            let l = 2 * nu as usize;
            add(k - 1, l - 1, cp(ka - nu) + cp(ka + nu));
            add(k - 1, l, -(sp(ka + nu) + sp(nu - ka)));
            add(k, l - 1, -(sp(ka + nu) + sp(ka - nu)));
            add(k, l, cp(ka - nu) - cp(ka + nu));
        }
    }
}
