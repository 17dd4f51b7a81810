//! The harmonic balance residual r(Q, ω) = D̄(ω) Q − λ F̄_e(ω) + F_nl(Q) (SAMA paper eq. 19) in
//! the real layout of `docs/conventions.md` §4, with its Jacobian ∂r/∂Q = D̄ + ∂F_nl/∂Q (eq. 21 with the
//! sign convention of [`HarmonicForce`]) and its derivative with respect to the continuation
//! parameter (ω, the excitation level λ, or the force's own parameter such as the preload n0).

use faer::{c64, MatMut};
use rayon::prelude::*;

use super::linear::{Condensed, CondensedApplied, LinearModel};
use crate::error::{Error, Result};
use crate::harmonics::{HarmonicForce, HarmonicLayout, Jacobian};
use crate::nonlinear::{Linearization, ParameterSystem};

/// The harmonic balance of a linear model and a nonlinear force on its condensed DOFs.
pub struct HbmSystem<'a, F: HarmonicForce> {
    layout: HarmonicLayout,
    linear: &'a LinearModel,
    force: &'a F,
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
        let nd = self.linear.n_condensed();
        (0..nd)
            .map(|i| {
                if n == 0 {
                    c64::new(q[self.layout.static_index(i)], 0.0)
                } else {
                    let c = self.layout.cos_index(n, i, nd);
                    c64::new(q[c], q[c + 1])
                }
            })
            .collect()
    }

    /// Every harmonic condensed at ω for an evaluation at Q (in parallel over the harmonics;
    /// [`LinearModel::condense_applied`]).
    pub fn condense_all_applied(&self, q: &[f64], omega: f64) -> Result<Vec<CondensedApplied>> {
        (0..=self.layout.harmonics)
            .into_par_iter()
            .map(|n| {
                self.linear
                    .condense_applied(n, omega, &self.harmonic_of(q, n))
            })
            .collect()
    }

    /// Sizes of the diagonal blocks of ∂r/∂Q over the harmonics
    /// ([`HarmonicLayout::blocks`]): D̄ is block-diagonal over them, and the contact Jacobian
    /// couples them only on the DOFs of elements whose state changes within the period (the
    /// structured solve of [`crate::nonlinear::linsolve`]).
    pub fn jacobian_blocks(&self) -> Vec<usize> {
        self.layout.blocks(self.linear.n_condensed())
    }

    /// Number of real unknowns n_N (2H + 1).
    pub fn dim(&self) -> usize {
        self.layout.len(self.linear.n_condensed())
    }

    /// Every harmonic condensed at ω (in parallel over the harmonics).
    pub fn condense_all(&self, omega: f64) -> Result<Vec<Condensed>> {
        (0..=self.layout.harmonics)
            .into_par_iter()
            .map(|n| self.linear.condense(n, omega))
            .collect()
    }

    /// Evaluates at (Q, ω) with excitation factor `level`: `out.residual` = r,
    /// `out.jacobian` = ∂r/∂Q (dense or block-stored as `out` is; block-stored, its off-block
    /// entries are coalesced), `out.d_parameter` = ∂r/∂ω (with ∂F_nl/∂ω of a force that reads
    /// velocities, [`HarmonicForce::evaluate_at`]); and `level_derivative` (if given) =
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
        };
        self.evaluate_parts(q, omega, level, state, parts)
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
        let condensed = self.condense_all_applied(q, omega)?;
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
        if let Some(d) = out.d_level.as_deref_mut() {
            d.iter_mut().for_each(|v| *v = 0.0);
        }
        for (n, c) in condensed.iter().enumerate() {
            self.add_harmonic(n, c, q, level, &mut out);
        }
        if let Some(Jacobian::Blocks(b)) = out.jacobian {
            b.coalesce();
        }
        Ok(end_state)
    }

    /// The residual r alone at (Q, ω) with excitation factor `level` (no Jacobian, no
    /// derivatives): the linear part by [`LinearModel::condensed_residual`] (no condensed
    /// matrix), in parallel over the harmonics, plus the nonlinear force. Returns the
    /// end-of-period force state.
    pub fn evaluate_residual(
        &self,
        q: &[f64],
        omega: f64,
        level: f64,
        state: &F::State,
        residual: &mut [f64],
    ) -> Result<F::State> {
        let nd = self.linear.n_condensed();
        let layout = self.layout;
        let linear: Vec<Vec<c64>> = (0..=layout.harmonics)
            .into_par_iter()
            .map(|n| {
                self.linear
                    .condensed_residual(n, omega, &self.harmonic_of(q, n), level)
            })
            .collect::<Result<_>>()?;
        residual.iter_mut().for_each(|v| *v = 0.0);
        let mut end_state = state.clone();
        self.force
            .evaluate_into(&layout, q, omega, &mut end_state, residual, None, None)?;
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

    /// Adds harmonic n's linear terms: D̄ Q − level·F̄ to the residual, D̄ to the Jacobian,
    /// D̄' Q − level·F̄' to ∂r/∂ω (real 2×2 blocks of eq. 24), −F̄ to ∂r/∂level.
    fn add_harmonic(
        &self,
        n: usize,
        c: &CondensedApplied,
        q: &[f64],
        level: f64,
        out: &mut Parts<'_>,
    ) {
        let nd = self.linear.n_condensed();
        // D̄ is written into its harmonic's diagonal block: `jac` and the offset of its rows
        let (mut jac, offset): (Option<MatMut<'_, f64>>, usize) = match out.jacobian.as_deref_mut()
        {
            None => (None, 0),
            Some(Jacobian::Dense(a)) => (Some(a.as_mut()), 0),
            Some(Jacobian::Blocks(b)) => {
                let offset = b.starts()[n];
                (Some(b.block_mut(n)), offset)
            }
        };
        if n == 0 {
            for i in 0..nd {
                let ri = self.layout.static_index(i);
                for j in 0..nd {
                    let cj = self.layout.static_index(j);
                    if let Some(a) = jac.as_mut() {
                        a[(ri - offset, cj - offset)] += c.stiffness[(i, j)].re;
                    }
                    out.residual[ri] += c.stiffness[(i, j)].re * q[cj];
                }
                if let Some(d) = out.d_omega.as_deref_mut() {
                    d[ri] += c.stiffness_derivative_q[i].re;
                    d[ri] -= level * c.force_derivative[i].re;
                }
                out.residual[ri] -= level * c.force[i].re;
            }
            if let Some(d) = out.d_level.as_deref_mut() {
                for i in 0..nd {
                    d[self.layout.static_index(i)] -= c.force[i].re;
                }
            }
            return;
        }
        for i in 0..nd {
            let ri = self.layout.cos_index(n, i, nd);
            let mut dq = c64::new(0.0, 0.0);
            let ddq = c.stiffness_derivative_q[i];
            for j in 0..nd {
                let cj = self.layout.cos_index(n, j, nd);
                let d = c.stiffness[(i, j)];
                if let Some(a) = jac.as_mut() {
                    let (r, k) = (ri - offset, cj - offset);
                    a[(r, k)] += d.re;
                    a[(r, k + 1)] -= d.im;
                    a[(r + 1, k)] += d.im;
                    a[(r + 1, k + 1)] += d.re;
                }
                let qj = c64::new(q[cj], q[cj + 1]);
                dq += d * qj;
            }
            let f = c.force[i] * level;
            let df = c.force_derivative[i] * level;
            out.residual[ri] += dq.re - f.re;
            out.residual[ri + 1] += dq.im - f.im;
            if let Some(d) = out.d_omega.as_deref_mut() {
                d[ri] += ddq.re - df.re;
                d[ri + 1] += ddq.im - df.im;
            }
        }
        if let Some(d) = out.d_level.as_deref_mut() {
            for i in 0..nd {
                let ri = self.layout.cos_index(n, i, nd);
                d[ri] -= c.force[i].re;
                d[ri + 1] -= c.force[i].im;
            }
        }
    }
}

/// The outputs of one evaluation of [`HbmSystem`] (each but the residual optional).
struct Parts<'o> {
    residual: &'o mut [f64],
    jacobian: Option<&'o mut Jacobian>,
    d_omega: Option<&'o mut [f64]>,
    d_level: Option<&'o mut [f64]>,
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

/// Response to a varying excitation level λ (factor on the case's force) at fixed ω (rad/s).
pub struct LevelPath<'s, 'a, F: HarmonicForce> {
    /// The harmonic balance system.
    pub system: &'s HbmSystem<'a, F>,
    /// The fixed excitation frequency (rad/s).
    pub omega: f64,
}

impl<F: HarmonicForce> ParameterSystem for LevelPath<'_, '_, F> {
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
        level: f64,
        state: &F::State,
        out: &mut Linearization,
    ) -> Result<F::State> {
        let mut d_level = vec![0.0; x.len()];
        let end = self
            .system
            .evaluate(x, self.omega, level, state, out, Some(&mut d_level))?;
        out.d_parameter = d_level;
        Ok(end)
    }

    fn evaluate_residual(
        &self,
        x: &[f64],
        level: f64,
        state: &F::State,
        residual: &mut [f64],
    ) -> Result<F::State> {
        self.system
            .evaluate_residual(x, self.omega, level, state, residual)
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
