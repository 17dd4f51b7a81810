//! The harmonic balance residual r(Q, ω) = D̄(ω) Q − λ F̄_e(ω) + F_nl(Q) (SAMA paper eq. 19) in
//! the real layout of `docs/conventions.md` §4, with its Jacobian ∂r/∂Q = D̄ + ∂F_nl/∂Q (eq. 21 with the
//! sign convention of [`HarmonicForce`]) and its derivative with respect to the continuation
//! parameter (ω, the excitation level λ, or the force's own parameter such as the preload n0).

use std::sync::{Arc, Mutex};

use faer::{c64, Mat, MatMut};
use rayon::prelude::*;

use super::linear::{
    Applied, Condensed, CondensedApplied, HarmonicOperator, LinearModel, SmallBuffers,
};
use crate::error::{Error, Result};
use crate::harmonics::jacobian::PendingBlocks;
use crate::harmonics::{HarmonicForce, HarmonicLayout, Jacobian};
use crate::nonlinear::{Linearization, ParameterSystem};

/// Rows of the matrix blocks from which the harmonics are condensed in parallel
/// ([`HbmSystem::per_harmonic`]): a condensation of 32 rows costs tens of µs, about what a
/// hand-over to a sleeping rayon worker costs.
const PARALLEL_ROWS: usize = 32;

/// The harmonic balance of a linear model and a nonlinear force on its condensed DOFs.
pub struct HbmSystem<'a, F: HarmonicForce> {
    layout: HarmonicLayout,
    linear: &'a LinearModel,
    force: &'a F,
    /// The buffers of the last evaluation of a small model ([`HbmSystem::evaluate_small`]),
    /// kept for the next.
    small: Mutex<Option<Box<SmallTerms>>>,
}

/// The linear terms of every harmonic of one evaluation of a small model and the buffers they
/// are formed with ([`LinearModel::condense_small`]).
struct SmallTerms {
    /// Per harmonic n: D̄⁽ⁿ⁾, F̄⁽ⁿ⁾, ∂D̄⁽ⁿ⁾/∂ω q_n, ∂F̄⁽ⁿ⁾/∂ω, and D̄⁽ⁿ⁾ q_n.
    harmonics: Vec<(CondensedApplied, Vec<c64>)>,
    /// The harmonic q_n of the evaluation.
    q_n: Vec<c64>,
    buffers: SmallBuffers,
}

impl<'a, F: HarmonicForce> HbmSystem<'a, F> {
    /// Checks that the force acts on the condensed DOFs of `linear` and that the harmonics agree.
    pub fn new(layout: HarmonicLayout, linear: &'a LinearModel, force: &'a F) -> Result<Self> {
        if force.n_dofs() != linear.n_condensed() {
            return Err(Error::input(format!(
                "the nonlinear force acts on {} DOFs but the linear model condenses on {}",
                force.n_dofs(),
                linear.n_condensed()
            )));
        }
        if layout.harmonics != linear.harmonics() {
            return Err(Error::input(format!(
                "the harmonic layout has H = {} but the linear model H = {}",
                layout.harmonics,
                linear.harmonics()
            )));
        }
        Ok(HbmSystem {
            layout,
            linear,
            force,
            small: Mutex::new(None),
        })
    }

    /// The harmonic layout.
    pub fn layout(&self) -> HarmonicLayout {
        self.layout
    }

    /// The linear model.
    pub fn linear(&self) -> &LinearModel {
        self.linear
    }

    /// The nonlinear force.
    pub fn force(&self) -> &F {
        self.force
    }

    /// The complex coefficients of harmonic n of the real harmonic vector Q (n = 0: real).
    fn harmonic_of(&self, q: &[f64], n: usize) -> Vec<c64> {
        let mut out = Vec::new();
        self.harmonic_into(q, n, &mut out);
        out
    }

    /// [`HbmSystem::harmonic_of`] into `out` (its length set to n_N).
    fn harmonic_into(&self, q: &[f64], n: usize, out: &mut Vec<c64>) {
        let nd = self.linear.n_condensed();
        out.clear();
        out.extend((0..nd).map(|i| {
            if n == 0 {
                c64::new(q[self.layout.static_index(i)], 0.0)
            } else {
                let c = self.layout.cos_index(n, i, nd);
                c64::new(q[c], q[c + 1])
            }
        }));
    }

    /// Every harmonic condensed at ω for an evaluation at Q (in parallel over the harmonics
    /// when the model has 32 rows or more; [`LinearModel::condense_applied`]).
    pub fn condense_all_applied(&self, q: &[f64], omega: f64) -> Result<Vec<CondensedApplied>> {
        self.per_harmonic(|n| {
            self.linear
                .condense_applied(n, omega, &self.harmonic_of(q, n))
        })
        .into_iter()
        .collect()
    }

    /// Sizes of the diagonal blocks of ∂r/∂Q over the harmonics
    /// ([`HarmonicLayout::blocks`]): D̄ is block-diagonal over them, and the contact Jacobian
    /// couples them only on the DOFs of elements whose state changes within the period (the
    /// structured solve of [`crate::nonlinear::linsolve`]). Empty (no such structure: the
    /// dense LU) for a force without [`HarmonicForce::sparse_harmonic_coupling`].
    pub fn jacobian_blocks(&self) -> Vec<usize> {
        if !self.force.sparse_harmonic_coupling() {
            return Vec::new();
        }
        self.layout.blocks(self.linear.n_condensed())
    }

    /// Number of real unknowns n_N (2H + 1).
    pub fn dim(&self) -> usize {
        self.layout.len(self.linear.n_condensed())
    }

    /// Every harmonic condensed at ω (in parallel over the harmonics when the model has 32 rows
    /// or more).
    pub fn condense_all(&self, omega: f64) -> Result<Vec<Condensed>> {
        self.per_harmonic(|n| self.linear.condense(n, omega))
            .into_iter()
            .collect()
    }

    /// `f(n)` for every harmonic n = 0..H, in order: in parallel over the harmonics when the
    /// matrix blocks have at least [`PARALLEL_ROWS`] rows, on the calling thread below. The
    /// work of a harmonic (a dense condensation, O(rows³)) must outweigh handing it to rayon's
    /// workers: on the 3-DOF chain of `cases/nlvib/chain07_jenkins.toml` the hand-overs and
    /// wake-ups cost more CPU time than the harmonic balance itself.
    fn per_harmonic<T: Send>(&self, f: impl Fn(usize) -> T + Sync + Send) -> Vec<T> {
        let harmonics = 0..=self.layout.harmonics;
        if self.linear.block_rows() < PARALLEL_ROWS {
            harmonics.map(f).collect()
        } else {
            harmonics.into_par_iter().map(f).collect()
        }
    }

    /// Evaluates at (Q, ω) with excitation factor `level`: `out.residual` = r,
    /// `out.jacobian` = ∂r/∂Q (dense or block-stored as `out` is; block-stored, its off-block
    /// entries are coalesced and D̄(ω) is left pending on the LU factors of D_LL
    /// ([`LinearModel::condense_deferred`], [`crate::harmonics::BlockJacobian::materialize`]:
    /// formed only if the matrix is factorised)), `out.d_parameter` = ∂r/∂ω (with ∂F_nl/∂ω of a force that reads
    /// velocities, [`HarmonicForce::evaluate_into`]); and `level_derivative` (if given) =
    /// ∂r/∂level = −F̄_e. Returns the end-of-period force state.
    pub fn evaluate(
        &self,
        q: &[f64],
        omega: f64,
        level: f64,
        state: &F::State,
        out: &mut Linearization,
        level_derivative: Option<&mut [f64]>,
    ) -> Result<F::State> {
        let parts = Parts {
            residual: &mut out.residual,
            jacobian: Some(&mut out.jacobian),
            d_omega: Some(&mut out.d_parameter),
            d_level: level_derivative,
            force_scale: 1.0,
            d_force: None,
        };
        self.evaluate_parts(q, omega, level, state, parts)
    }

    /// Evaluates the homotopy r(Q, s) = D̄(ω) Q − F̄_e + s F_nl(Q) at (Q, s) for the fixed ω (rad/s)
    /// ([`FixedFrequencyParameter::ForceScale`]): `out.residual` = r, `out.jacobian` = D̄(ω) + s ∂F_nl/∂Q,
    /// `out.d_parameter` = ∂r/∂s = F_nl(Q). Returns the end-of-period force state.
    pub fn evaluate_force_scaled(
        &self,
        q: &[f64],
        omega: f64,
        force_scale: f64,
        state: &F::State,
        out: &mut Linearization,
    ) -> Result<F::State> {
        let parts = Parts {
            residual: &mut out.residual,
            jacobian: Some(&mut out.jacobian),
            d_omega: None,
            d_level: None,
            force_scale,
            d_force: Some(&mut out.d_parameter),
        };
        self.evaluate_parts(q, omega, 1.0, state, parts)
    }

    /// Fills the parts that are given (see [`HbmSystem::evaluate`]).
    fn evaluate_parts(
        &self,
        q: &[f64],
        omega: f64,
        level: f64,
        state: &F::State,
        mut out: Parts<'_>,
    ) -> Result<F::State> {
        let deferred = matches!(out.jacobian, Some(Jacobian::Blocks(_)));
        if !deferred && self.linear.block_rows() < PARALLEL_ROWS {
            return self.evaluate_small(q, omega, level, state, out);
        }
        // per harmonic: the products of the evaluation, and D̄⁽ⁿ⁾ formed (dense Jacobian) or
        // its operator (block-stored)
        let linear: Vec<(Applied, Linear)> = self
            .per_harmonic(|n| {
                let q_n = self.harmonic_of(q, n);
                if deferred {
                    let (a, op) = self.linear.condense_deferred(n, omega, &q_n)?;
                    Ok((a, Linear::Operator(Box::new(op))))
                } else {
                    let c = self.linear.condense_applied(n, omega, &q_n)?;
                    Ok((applied_of(&c, &q_n), Linear::Matrix(c.stiffness)))
                }
            })
            .into_iter()
            .collect::<Result<_>>()?;
        let end_state = self.evaluate_force(q, omega, state, &mut out)?;
        let mut operators = Vec::new();
        for (n, (a, l)) in linear.into_iter().enumerate() {
            let terms = Terms {
                stiffness_q: &a.stiffness_q,
                force: &a.force,
                stiffness_derivative_q: &a.stiffness_derivative_q,
                force_derivative: &a.force_derivative,
            };
            self.add_harmonic(n, terms, level, &mut out);
            match l {
                Linear::Matrix(d) => self.add_stiffness(n, &d, &mut out),
                Linear::Operator(op) => operators.push(*op),
            }
        }
        if let Some(Jacobian::Blocks(b)) = out.jacobian {
            b.coalesce();
            if deferred {
                b.set_pending(Arc::new(CondensedBlocks { operators }));
            }
        }
        Ok(end_state)
    }

    /// Zeroes the parts and adds the nonlinear force's (F_nl, its Jacobian, ∂F_nl/∂ω);
    /// returns the end-of-period force state.
    fn evaluate_force(
        &self,
        q: &[f64],
        omega: f64,
        state: &F::State,
        out: &mut Parts<'_>,
    ) -> Result<F::State> {
        out.residual.iter_mut().for_each(|v| *v = 0.0);
        if let Some(d) = out.d_omega.as_deref_mut() {
            d.iter_mut().for_each(|v| *v = 0.0);
        }
        if let Some(j) = out.jacobian.as_deref_mut() {
            j.clear();
        }
        let mut end_state = state.clone();
        self.force.evaluate_into(
            &self.layout,
            q,
            omega,
            &mut end_state,
            out.residual,
            out.jacobian.as_deref_mut().map(|j| j.target()),
            out.d_omega.as_deref_mut(),
        )?;
        if let Some(d) = out.d_force.as_deref_mut() {
            d.copy_from_slice(out.residual);
        }
        if out.force_scale != 1.0 {
            scale_force(out.force_scale, out);
        }
        if let Some(d) = out.d_level.as_deref_mut() {
            d.iter_mut().for_each(|v| *v = 0.0);
        }
        Ok(end_state)
    }

    /// [`HbmSystem::evaluate_parts`] with a dense (or no) Jacobian for a model of fewer than
    /// [`PARALLEL_ROWS`] rows: the harmonics condensed by [`LinearModel::condense_small`] into
    /// the buffers of the previous evaluation (made on the first), so that an evaluation makes
    /// no matrix or vector of the linear part. The terms are added in the same order as
    /// [`HbmSystem::evaluate_parts`] adds its own.
    fn evaluate_small(
        &self,
        q: &[f64],
        omega: f64,
        level: f64,
        state: &F::State,
        mut out: Parts<'_>,
    ) -> Result<F::State> {
        let kept = self.small.lock().ok().and_then(|mut s| s.take());
        let mut terms = kept.unwrap_or_else(|| {
            Box::new(SmallTerms {
                harmonics: Vec::new(),
                q_n: Vec::new(),
                buffers: SmallBuffers::default(),
            })
        });
        let SmallTerms {
            harmonics,
            q_n,
            buffers,
        } = &mut *terms;
        let nd = self.linear.n_condensed();
        harmonics.resize_with(self.layout.harmonics + 1, || {
            let c = CondensedApplied {
                stiffness: Mat::zeros(nd, nd),
                force: Vec::new(),
                stiffness_derivative_q: Vec::new(),
                force_derivative: Vec::new(),
            };
            (c, Vec::new())
        });
        for (n, (c, dq)) in harmonics.iter_mut().enumerate() {
            self.harmonic_into(q, n, q_n);
            self.linear.condense_small(n, omega, q_n, c, buffers)?;
            dq.resize(nd, c64::new(0.0, 0.0));
            stiffness_times(&c.stiffness, q_n, dq);
        }
        let end_state = self.evaluate_force(q, omega, state, &mut out)?;
        for (n, (c, dq)) in harmonics.iter().enumerate() {
            let t = Terms {
                stiffness_q: dq,
                force: &c.force,
                stiffness_derivative_q: &c.stiffness_derivative_q,
                force_derivative: &c.force_derivative,
            };
            self.add_harmonic(n, t, level, &mut out);
            self.add_stiffness(n, &c.stiffness, &mut out);
        }
        if let Ok(mut s) = self.small.lock() {
            *s = Some(terms);
        }
        Ok(end_state)
    }

    /// The residual r alone at (Q, ω) with excitation factor `level` (no Jacobian, no
    /// derivatives): the linear part by [`LinearModel::condensed_residual`] (no condensed
    /// matrix), in parallel over the harmonics of a large model, plus the nonlinear force.
    /// Returns the end-of-period force state.
    pub fn evaluate_residual(
        &self,
        q: &[f64],
        omega: f64,
        level: f64,
        state: &F::State,
        residual: &mut [f64],
    ) -> Result<F::State> {
        self.residual_force_scaled(q, omega, level, 1.0, state, residual)
    }

    /// As [`HbmSystem::evaluate_residual`] with the nonlinear force multiplied by `force_scale`
    /// (the homotopy of [`FixedFrequencyParameter::ForceScale`]).
    fn residual_force_scaled(
        &self,
        q: &[f64],
        omega: f64,
        level: f64,
        force_scale: f64,
        state: &F::State,
        residual: &mut [f64],
    ) -> Result<F::State> {
        let nd = self.linear.n_condensed();
        let layout = self.layout;
        let linear: Vec<Vec<c64>> = self
            .per_harmonic(|n| {
                self.linear
                    .condensed_residual(n, omega, &self.harmonic_of(q, n), level)
            })
            .into_iter()
            .collect::<Result<_>>()?;
        residual.iter_mut().for_each(|v| *v = 0.0);
        let mut end_state = state.clone();
        self.force
            .evaluate_into(&layout, q, omega, &mut end_state, residual, None, None)?;
        if force_scale != 1.0 {
            residual.iter_mut().for_each(|v| *v *= force_scale);
        }
        for (n, r) in linear.iter().enumerate() {
            for (i, v) in r.iter().enumerate() {
                if n == 0 {
                    residual[layout.static_index(i)] += v.re;
                } else {
                    let ri = layout.cos_index(n, i, nd);
                    residual[ri] += v.re;
                    residual[ri + 1] += v.im;
                }
            }
        }
        Ok(end_state)
    }

    /// Adds harmonic n's linear terms: D̄ Q − level·F̄ to the residual, D̄' Q − level·F̄' to
    /// ∂r/∂ω (real 2×2 blocks of eq. 24), −F̄ to ∂r/∂level.
    fn add_harmonic(&self, n: usize, c: Terms<'_>, level: f64, out: &mut Parts<'_>) {
        let nd = self.linear.n_condensed();
        for i in 0..nd {
            let f = c.force[i] * level;
            let r = c.stiffness_q[i] - f;
            let d = c.stiffness_derivative_q[i] - c.force_derivative[i] * level;
            if n == 0 {
                let ri = self.layout.static_index(i);
                out.residual[ri] += r.re;
                if let Some(dw) = out.d_omega.as_deref_mut() {
                    dw[ri] += d.re;
                }
                if let Some(dl) = out.d_level.as_deref_mut() {
                    dl[ri] -= c.force[i].re;
                }
            } else {
                let ri = self.layout.cos_index(n, i, nd);
                out.residual[ri] += r.re;
                out.residual[ri + 1] += r.im;
                if let Some(dw) = out.d_omega.as_deref_mut() {
                    dw[ri] += d.re;
                    dw[ri + 1] += d.im;
                }
                if let Some(dl) = out.d_level.as_deref_mut() {
                    dl[ri] -= c.force[i].re;
                    dl[ri + 1] -= c.force[i].im;
                }
            }
        }
    }

    /// Adds D̄⁽ⁿ⁾ to the Jacobian (real 2×2 blocks of eq. 24 for n ≥ 1) on harmonic n's
    /// diagonal block.
    fn add_stiffness(&self, n: usize, d: &Mat<c64>, out: &mut Parts<'_>) {
        let nd = self.linear.n_condensed();
        let block = match out.jacobian.as_deref_mut() {
            None => return,
            Some(Jacobian::Dense(a)) => {
                let (start, size) = if n == 0 {
                    (0, nd)
                } else {
                    (self.layout.cos_index(n, 0, nd), 2 * nd)
                };
                a.as_mut().submatrix_mut(start, start, size, size)
            }
            Some(Jacobian::Blocks(b)) => b.block_mut(n),
        };
        add_block(n == 0, d, block);
    }
}

/// Adds the complex n_N × n_N matrix `d` to a diagonal block of the real layout: the static
/// block (`real`: Re d) or a harmonic's (rows and columns Re, Im interleaved per DOF: the real
/// 2×2 block [Re −Im; Im Re] of each entry).
fn add_block(real: bool, d: &Mat<c64>, mut a: MatMut<'_, f64>) {
    let nd = d.nrows();
    for j in 0..nd {
        for i in 0..nd {
            let v = d[(i, j)];
            if real {
                a[(i, j)] += v.re;
            } else {
                let (r, k) = (2 * i, 2 * j);
                a[(r, k)] += v.re;
                a[(r, k + 1)] -= v.im;
                a[(r + 1, k)] += v.im;
                a[(r + 1, k + 1)] += v.re;
            }
        }
    }
}

/// The products of a harmonic condensed with its matrix: D̄ q_n by a matrix–vector product.
fn applied_of(c: &CondensedApplied, q_n: &[c64]) -> Applied {
    let mut stiffness_q = vec![c64::new(0.0, 0.0); q_n.len()];
    stiffness_times(&c.stiffness, q_n, &mut stiffness_q);
    Applied {
        stiffness_q,
        force: c.force.clone(),
        stiffness_derivative_q: c.stiffness_derivative_q.clone(),
        force_derivative: c.force_derivative.clone(),
    }
}

/// D̄ q_n into `out` (faer's product, as `&D̄ * q`).
fn stiffness_times(d: &Mat<c64>, q_n: &[c64], out: &mut [c64]) {
    let q = faer::MatRef::from_column_major_slice(q_n, q_n.len(), 1);
    let out = faer::MatMut::from_column_major_slice_mut(out, q_n.len(), 1);
    let one = c64::new(1.0, 0.0);
    let par = faer::get_global_parallelism();
    faer::linalg::matmul::matmul(out, faer::Accum::Replace, d.as_ref(), q, one, par);
}

/// The linear terms of harmonic n of one evaluation (length n_N each): D̄⁽ⁿ⁾ q_n, F̄⁽ⁿ⁾,
/// ∂D̄⁽ⁿ⁾/∂ω q_n, ∂F̄⁽ⁿ⁾/∂ω.
struct Terms<'t> {
    stiffness_q: &'t [c64],
    force: &'t [c64],
    stiffness_derivative_q: &'t [c64],
    force_derivative: &'t [c64],
}

/// The linear part of one harmonic for the Jacobian: formed, or as an operator.
enum Linear {
    Matrix(Mat<c64>),
    Operator(Box<HarmonicOperator>),
}

/// D̄(ω) of every harmonic as the pending term of a block-stored Jacobian (block n = harmonic n;
/// the static block over the n_N static coefficients, harmonic n ≥ 1 over Re, Im interleaved:
/// [`HarmonicLayout`]).
#[derive(Debug)]
struct CondensedBlocks {
    operators: Vec<HarmonicOperator>,
}

impl PendingBlocks for CondensedBlocks {
    fn apply(&self, b: usize, x: &[f64], y: &mut [f64]) {
        let op = &self.operators[b];
        if b == 0 {
            let q: Vec<c64> = x.iter().map(|&v| c64::new(v, 0.0)).collect();
            for (y, v) in y.iter_mut().zip(op.apply(&q)) {
                *y += v.re;
            }
        } else {
            let q: Vec<c64> = x.chunks_exact(2).map(|p| c64::new(p[0], p[1])).collect();
            for (y, v) in y.chunks_exact_mut(2).zip(op.apply(&q)) {
                y[0] += v.re;
                y[1] += v.im;
            }
        }
    }

    fn add_to(&self, b: usize, out: MatMut<'_, f64>) {
        add_block(b == 0, &self.operators[b].matrix(), out);
    }

    fn norm_1(&self, b: usize) -> f64 {
        self.operators[b].norm_1()
    }
}

/// The outputs of one evaluation of [`HbmSystem`] (each but the residual optional).
struct Parts<'o> {
    residual: &'o mut [f64],
    jacobian: Option<&'o mut Jacobian>,
    d_omega: Option<&'o mut [f64]>,
    d_level: Option<&'o mut [f64]>,
    /// Factor s on the nonlinear force (1 outside the homotopy of
    /// [`FixedFrequencyParameter::ForceScale`]).
    force_scale: f64,
    /// ∂r/∂s = F_nl(Q), if wanted.
    d_force: Option<&'o mut [f64]>,
}

/// Multiplies the nonlinear force's terms already in `out` (residual, Jacobian, ∂r/∂ω) by `s`:
/// called right after the force is evaluated into the cleared parts, before the linear terms.
fn scale_force(s: f64, out: &mut Parts<'_>) {
    out.residual.iter_mut().for_each(|v| *v *= s);
    if let Some(j) = out.jacobian.as_deref_mut() {
        j.scale(s);
    }
    if let Some(d) = out.d_omega.as_deref_mut() {
        d.iter_mut().for_each(|v| *v *= s);
    }
}

/// Frequency response: the unknowns are Q, the parameter is ω (rad/s), the excitation level is
/// fixed.
pub struct FrequencyPath<'s, 'a, F: HarmonicForce> {
    /// The harmonic balance system.
    pub system: &'s HbmSystem<'a, F>,
    /// Factor on the excitation (1 for the case's force).
    pub level: f64,
}

impl<F: HarmonicForce> ParameterSystem for FrequencyPath<'_, '_, F> {
    type State = F::State;

    fn jacobian_blocks(&self) -> Vec<usize> {
        self.system.jacobian_blocks()
    }

    fn dim(&self) -> usize {
        self.system.dim()
    }

    fn residual_scale(&self) -> f64 {
        residual_scale(self.system.linear.force_norm() * self.level.abs())
    }

    fn initial_state(&self) -> F::State {
        self.system.force.initial_state()
    }

    fn evaluate(
        &self,
        x: &[f64],
        omega: f64,
        state: &F::State,
        out: &mut Linearization,
    ) -> Result<F::State> {
        self.system.evaluate(x, omega, self.level, state, out, None)
    }

    fn evaluate_residual(
        &self,
        x: &[f64],
        omega: f64,
        state: &F::State,
        residual: &mut [f64],
    ) -> Result<F::State> {
        self.system
            .evaluate_residual(x, omega, self.level, state, residual)
    }
}

/// The factor a [`FixedFrequencyPath`] continues in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FixedFrequencyParameter {
    /// The excitation level λ (factor on the case's force): r(Q, λ) = D̄(ω) Q − λ F̄_e + F_nl(Q),
    /// ∂r/∂λ = −F̄_e.
    Level,
    /// The factor s on the nonlinear force, the homotopy from the underlying linear system to the
    /// full one: r(Q, s) = D̄(ω) Q − F̄_e + s F_nl(Q), ∂r/∂s = F_nl(Q), s from 0 (the linear
    /// response without the nonlinear elements) to 1 (the frequency response's equation at ω).
    /// A start-point method of [`crate::hbm::frf::frequency_response`] for strong excitation,
    /// where the response is far from the stuck, linearised solution and close to the one without
    /// the elements (gross slip, separation), and the continuation in the excitation level meets
    /// folds.
    ForceScale,
}

/// The harmonic balance system at a fixed frequency ω (rad/s), continued in the excitation level
/// or in the factor on the nonlinear force ([`FixedFrequencyParameter`]).
pub struct FixedFrequencyPath<'s, 'a, F: HarmonicForce> {
    /// The harmonic balance system.
    pub system: &'s HbmSystem<'a, F>,
    /// The fixed excitation frequency ω (rad/s).
    pub omega: f64,
    /// What the path's parameter multiplies.
    pub parameter: FixedFrequencyParameter,
}

impl<F: HarmonicForce> ParameterSystem for FixedFrequencyPath<'_, '_, F> {
    type State = F::State;

    fn jacobian_blocks(&self) -> Vec<usize> {
        self.system.jacobian_blocks()
    }

    fn dim(&self) -> usize {
        self.system.dim()
    }

    fn residual_scale(&self) -> f64 {
        residual_scale(self.system.linear.force_norm())
    }

    fn initial_state(&self) -> F::State {
        self.system.force.initial_state()
    }

    fn evaluate(
        &self,
        x: &[f64],
        parameter: f64,
        state: &F::State,
        out: &mut Linearization,
    ) -> Result<F::State> {
        match self.parameter {
            FixedFrequencyParameter::Level => {
                let mut d_level = vec![0.0; x.len()];
                let end = self.system.evaluate(
                    x,
                    self.omega,
                    parameter,
                    state,
                    out,
                    Some(&mut d_level),
                )?;
                out.d_parameter = d_level;
                Ok(end)
            }
            FixedFrequencyParameter::ForceScale => self
                .system
                .evaluate_force_scaled(x, self.omega, parameter, state, out),
        }
    }

    fn evaluate_residual(
        &self,
        x: &[f64],
        parameter: f64,
        state: &F::State,
        residual: &mut [f64],
    ) -> Result<F::State> {
        let (level, force_scale) = match self.parameter {
            FixedFrequencyParameter::Level => (parameter, 1.0),
            FixedFrequencyParameter::ForceScale => (1.0, parameter),
        };
        self.system
            .residual_force_scaled(x, self.omega, level, force_scale, state, residual)
    }
}

/// The force level used to scale residuals; 1 N when there is no excitation.
fn residual_scale(force_norm: f64) -> f64 {
    if force_norm > 0.0 && force_norm.is_finite() {
        force_norm
    } else {
        1.0
    }
}

/// Response to the nonlinear force's own parameter p (for the contact elements the static
/// normal load n0) at fixed ω (rad/s) and excitation level: r(Q, p) = D̄(ω) Q − level·F̄_e +
/// F_nl(Q; p), ∂r/∂p = ∂F_nl/∂p from [`HarmonicForce::parameter_derivative`].
///
/// `build(p)` makes the force at parameter p; it must move the force's parameters the way its
/// `parameter_derivative` assumes (e.g. [`crate::contact::grounded::DofElements`]: every
/// element's n0 = p; [`crate::contact::pairs::PairSet`]: each pair's n0 = preload_rate · p).
/// The force is rebuilt at every evaluation (cheap for the contact forces: the AFT plan is made
/// on first use).
pub struct PreloadPath<'a, F: HarmonicForce, B: Fn(f64) -> Result<F> + Sync> {
    /// Real harmonic layout.
    pub layout: HarmonicLayout,
    /// The linear part (condensed on the force's DOFs).
    pub linear: &'a LinearModel,
    /// The force at parameter p.
    pub build: B,
    /// The fixed excitation frequency ω (rad/s).
    pub omega: f64,
    /// Factor on the excitation (1 for the case's force).
    pub level: f64,
    /// The force memory before the first point.
    pub initial: F::State,
}

impl<F: HarmonicForce, B: Fn(f64) -> Result<F> + Sync> ParameterSystem for PreloadPath<'_, F, B> {
    type State = F::State;

    fn jacobian_blocks(&self) -> Vec<usize> {
        self.layout.blocks(self.linear.n_condensed())
    }

    fn dim(&self) -> usize {
        self.layout.len(self.linear.n_condensed())
    }

    fn residual_scale(&self) -> f64 {
        residual_scale(self.linear.force_norm() * self.level.abs())
    }

    fn initial_state(&self) -> F::State {
        self.initial.clone()
    }

    fn evaluate(
        &self,
        x: &[f64],
        p: f64,
        state: &F::State,
        out: &mut Linearization,
    ) -> Result<F::State> {
        let force = (self.build)(p)?;
        let system = HbmSystem::new(self.layout, self.linear, &force)?;
        let end = system.evaluate(x, self.omega, self.level, state, out, None)?;
        out.d_parameter.iter_mut().for_each(|v| *v = 0.0);
        force.parameter_derivative(&self.layout, x, state, &mut out.d_parameter)?;
        Ok(end)
    }

    fn evaluate_residual(
        &self,
        x: &[f64],
        p: f64,
        state: &F::State,
        residual: &mut [f64],
    ) -> Result<F::State> {
        let force = (self.build)(p)?;
        let system = HbmSystem::new(self.layout, self.linear, &force)?;
        system.evaluate_residual(x, self.omega, self.level, state, residual)
    }
}
