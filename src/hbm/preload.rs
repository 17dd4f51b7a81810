//! Contact forces measured from the preloaded static equilibrium.
//!
//! The SAMA paper (Battiato 2021, §6.1) computes the forced vibration *about* the static equilibrium
//! of the structure: a nonlinear static analysis (centrifugal and thermal loads, shroud
//! interference) gives the normal preload n0 of every contact, and that static state — the
//! preload in equilibrium with the pre-stress that produced it — is the configuration from which
//! the vibration starts. The contact law (eq 13) f_n = max(n0 + k_n v, 0) contains the preload,
//! so at rest (v = 0, sliders at rest) the elements exert the constant forces F_nl(0) (n0 along
//! each normal); the loads that balance them (the interference and the static loads) are not part
//! of the dynamic model. Without them, the zeroth harmonic of the harmonic balance would push the
//! contact faces apart until the preload is relieved by the structure's stiffness — a different
//! static state from the paper's.
//!
//! [`FromStaticEquilibrium`] adds the balancing load back: it evaluates
//! F̃(Q) = F_nl(Q) − F_nl(0), so that Q = 0 (the static equilibrium with the full preload) solves
//! the unexcited problem, the contacts are closed with normal force n0 at rest, and the dynamic
//! displacements Q are measured from that state. F_nl(0) is constant (zeroth harmonic only), so
//! the Jacobian is unchanged; for continuation in n0 the balancing load follows the preload
//! (the static analysis is redone for each n0): ∂F̃/∂n0 = ∂F_nl/∂n0 − ∂F_nl(0)/∂n0.
//! Elements with a gap at rest (n0 ≤ 0) exert no force at Q = 0 and are unaffected.

use faer::MatMut;

use crate::error::Result;
use crate::harmonics::{HarmonicForce, HarmonicLayout, JacobianMut};

/// A nonlinear force measured from its value at rest: F̃(Q) = F(Q) − F(0) (module documentation).
#[derive(Clone, Debug)]
pub struct FromStaticEquilibrium<F> {
    /// The force whose value at rest is subtracted (e.g. the contact [`crate::contact::pairs::PairSet`]).
    pub inner: F,
    /// F(0) in the real harmonic layout (N): the force at rest from the initial state.
    at_rest: Vec<f64>,
    /// ∂F(0)/∂p for the force's own parameter (N per unit of p), when it has one.
    at_rest_rate: Option<Vec<f64>>,
}

impl<F: HarmonicForce> FromStaticEquilibrium<F> {
    /// Evaluates `inner` at rest (Q = 0, its initial state) under `layout` and keeps that force
    /// (and its parameter derivative, when `inner` has one) to subtract.
    pub fn new(inner: F, layout: &HarmonicLayout) -> Result<Self> {
        let len = layout.len(inner.n_dofs());
        let zero = vec![0.0; len];
        let mut state = inner.initial_state();
        let mut at_rest = vec![0.0; len];
        // At rest every velocity is zero, whatever ω.
        inner.evaluate_into(layout, &zero, 0.0, &mut state, &mut at_rest, None, None)?;
        let mut rate = vec![0.0; len];
        let at_rest_rate = inner
            .parameter_derivative(layout, &zero, &inner.initial_state(), &mut rate)
            .ok()
            .map(|_| rate);
        Ok(FromStaticEquilibrium {
            inner,
            at_rest,
            at_rest_rate,
        })
    }

    /// The subtracted force F(0) (real harmonic layout, N).
    pub fn at_rest(&self) -> &[f64] {
        &self.at_rest
    }
}

impl<F: HarmonicForce> HarmonicForce for FromStaticEquilibrium<F> {
    type State = F::State;

    fn n_dofs(&self) -> usize {
        self.inner.n_dofs()
    }

    fn initial_state(&self) -> Self::State {
        self.inner.initial_state()
    }

    fn evaluate(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &mut Self::State,
        force: &mut [f64],
        jacobian: Option<MatMut<'_, f64>>,
    ) -> Result<()> {
        self.inner.evaluate(layout, q, state, force, jacobian)?;
        for (f, r) in force.iter_mut().zip(&self.at_rest) {
            *f -= r;
        }
        Ok(())
    }

    fn reads_velocity(&self) -> bool {
        self.inner.reads_velocity()
    }

    fn evaluate_into(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        omega: f64,
        state: &mut Self::State,
        force: &mut [f64],
        jacobian: Option<JacobianMut<'_>>,
        d_omega: Option<&mut [f64]>,
    ) -> Result<()> {
        self.inner
            .evaluate_into(layout, q, omega, state, force, jacobian, d_omega)?;
        for (f, r) in force.iter_mut().zip(&self.at_rest) {
            *f -= r;
        }
        Ok(())
    }

    fn parameter_derivative(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &Self::State,
        out: &mut [f64],
    ) -> Result<()> {
        self.inner.parameter_derivative(layout, q, state, out)?;
        if let Some(rate) = &self.at_rest_rate {
            for (o, r) in out.iter_mut().zip(rate) {
                *o -= r;
            }
        }
        Ok(())
    }
}
