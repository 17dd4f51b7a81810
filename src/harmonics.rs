//! Harmonic vectors in the real layout of `docs/conventions.md` §4, and the interface every nonlinear
//! force of the harmonic balance implements.
//!
//! A periodic signal of the normalised time τ = ω t (one period = 2π) is
//! q(τ) = Re Σ_{n=0..H} Q⁽ⁿ⁾ e^{i n τ} = Q⁽⁰⁾ + Σ_{n≥1} (Re Q⁽ⁿ⁾ cos nτ − Im Q⁽ⁿ⁾ sin nτ).
//! The real unknown vector of `n_dof` such signals is harmonic-major (SAMA paper, eq. 22):
//! `[Q⁽⁰⁾ of every DOF; for n = 1..H, for every DOF: Re Q⁽ⁿ⁾, Im Q⁽ⁿ⁾]`, length `n_dof·(2H+1)`.
//!
//! This module is the contract between the contact elements (which evaluate forces and Jacobians in
//! this layout) and the harmonic-balance solver (which assembles and solves in it).

use faer::{Mat, MatMut};

use crate::error::{Error, Result};

pub mod jacobian;

pub use jacobian::{BlockJacobian, Jacobian, JacobianMut, JacobianSink};

/// Number of harmonics H and time samples N_t per period used by the alternating
/// frequency/time (AFT) evaluation of nonlinear forces.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HarmonicLayout {
    /// Highest temporal harmonic H ≥ 0 (n = 0 is the static part).
    pub harmonics: usize,
    /// Samples per period N_t ≥ 2H + 2 (`docs/conventions.md` §4).
    pub time_samples: usize,
}

impl HarmonicLayout {
    /// Validates `time_samples ≥ 2H + 2`.
    pub fn new(harmonics: usize, time_samples: usize) -> Result<Self> {
        if time_samples < 2 * harmonics + 2 {
            return Err(Error::input(format!(
                "[harmonic_balance] time_samples = {time_samples} is too small for harmonics = {harmonics}: the AFT needs N_t ≥ 2H + 2 = {} samples per period (the default is the smallest power of two ≥ 4(H+1) = {})",
                2 * harmonics + 2,
                Self::default_samples(harmonics)
            )));
        }
        Ok(HarmonicLayout {
            harmonics,
            time_samples,
        })
    }

    /// The layout with the default number of samples, the smallest power of two ≥ 4(H+1).
    pub fn with_default_samples(harmonics: usize) -> Self {
        HarmonicLayout {
            harmonics,
            time_samples: Self::default_samples(harmonics),
        }
    }

    /// The smallest power of two ≥ 4(H+1) (`docs/conventions.md` §4).
    pub fn default_samples(harmonics: usize) -> usize {
        (4 * (harmonics + 1)).next_power_of_two()
    }

    /// Real coefficients per DOF, 2H + 1.
    pub fn coefficients(&self) -> usize {
        2 * self.harmonics + 1
    }

    /// Length of the real harmonic vector of `n_dof` DOFs, `n_dof·(2H+1)`.
    pub fn len(&self, n_dof: usize) -> usize {
        n_dof * self.coefficients()
    }

    /// Index of the static coefficient Q⁽⁰⁾ of `dof` in a vector of `n_dof` DOFs.
    pub fn static_index(&self, dof: usize) -> usize {
        dof
    }

    /// Index of Re Q⁽ⁿ⁾ of `dof` (n ≥ 1) in a vector of `n_dof` DOFs; Im Q⁽ⁿ⁾ follows at `+1`.
    pub fn cos_index(&self, n: usize, dof: usize, n_dof: usize) -> usize {
        debug_assert!(n >= 1 && n <= self.harmonics && dof < n_dof);
        n_dof + 2 * ((n - 1) * n_dof + dof)
    }

    /// Sizes of the harmonic blocks of a vector of `n_dof` DOFs: `n_dof` static coefficients,
    /// then `2 n_dof` (Re, Im interleaved) per harmonic. A linear operator that does not mix
    /// harmonics is block-diagonal over them.
    pub fn blocks(&self, n_dof: usize) -> Vec<usize> {
        std::iter::once(n_dof)
            .chain(std::iter::repeat_n(2 * n_dof, self.harmonics))
            .collect()
    }
}

/// A nonlinear force acting on `n_dofs()` DOFs, evaluated on harmonic vectors
/// (real layout above, length `layout.len(n_dofs())`).
///
/// The harmonic balance residual is r(Q, ω) = D̄(ω) Q − F̄_e + F_nl(Q) (SAMA paper eq. 19): the
/// force returned here is the force the element exerts *on the structure with a minus sign*, i.e.
/// the internal force that appears on the left-hand side with the elastic forces (a linear spring k
/// gives F_nl = k Q).
pub trait HarmonicForce: Send + Sync {
    /// Memory carried from one evaluation to the next (e.g. the slider positions at the start of
    /// the period, from the previous converged continuation point).
    type State: Clone + Send + Sync + std::fmt::Debug;

    /// Number of DOFs the force reads and acts on.
    fn n_dofs(&self) -> usize;

    /// The state for the first evaluation (e.g. sliders at rest, from the static solution).
    fn initial_state(&self) -> Self::State;

    /// Adds the harmonic coefficients F_nl(Q) to `force` and, when given, ∂F_nl/∂Q to
    /// `jacobian` (square, `layout.len(n_dofs())`). `state` holds the starting memory on entry
    /// and the converged end-of-period memory on return.
    fn evaluate(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &mut Self::State,
        force: &mut [f64],
        jacobian: Option<MatMut<'_, f64>>,
    ) -> Result<()>;

    /// Whether ∂F_nl/∂Q couples different harmonics only on the DOFs of a few elements (those
    /// whose state changes within the period), so that a harmonic balance Jacobian is its
    /// harmonic blocks plus a sparse term of low rank (the structured solve). Default: true;
    /// false for a force whose every DOF is coupled across harmonics as soon as one element is
    /// (a contact force projected on modes): its Jacobian is solved by the dense LU.
    fn sparse_harmonic_coupling(&self) -> bool {
        true
    }

    /// Whether F_nl reads velocities q̇ = ω ∂q/∂τ and so depends on the frequency ω (then it is
    /// evaluated with [`HarmonicForce::evaluate_into`]). Default: false.
    fn reads_velocity(&self) -> bool {
        false
    }

    /// As [`HarmonicForce::evaluate`] at the fundamental frequency `omega` (rad/s), with the
    /// Jacobian added into a dense or a block-stored matrix or a [`JacobianSink`]
    /// ([`JacobianMut`]), and ∂F_nl/∂ω added to `d_omega` when given. The default is for forces
    /// of displacements only: it calls `evaluate`, adds nothing to `d_omega`, and evaluates a
    /// block-stored or sunk Jacobian through a dense temporary of the force's order; forces that
    /// read velocities, and forces with many DOFs (which add their Jacobians element by
    /// element), implement it.
    #[allow(clippy::too_many_arguments)]
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
        let _ = (omega, d_omega);
        match jacobian {
            None => self.evaluate(layout, q, state, force, None),
            Some(JacobianMut::Dense(j)) => self.evaluate(layout, q, state, force, Some(j)),
            Some(mut target) => {
                let mut dense = Mat::<f64>::zeros(q.len(), q.len());
                self.evaluate(layout, q, state, force, Some(dense.as_mut()))?;
                match target {
                    JacobianMut::Blocks(b) => b.add_dense(dense.as_ref()),
                    _ => {
                        for j in 0..dense.ncols() {
                            for i in 0..dense.nrows() {
                                if dense[(i, j)] != 0.0 {
                                    target.add(i, j, dense[(i, j)]);
                                }
                            }
                        }
                    }
                }
                Ok(())
            }
        }
    }

    /// Adds ∂F_nl/∂p to `out` (length `layout.len(n_dofs())`) for the force's own scalar
    /// parameter p (for the contact elements: the static normal load n0, see the implementor),
    /// at the periodic solution reached from `state` (which is not changed). The default reports
    /// that the force has no such parameter.
    fn parameter_derivative(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &Self::State,
        out: &mut [f64],
    ) -> Result<()> {
        let _ = (layout, q, state, out);
        Err(Error::Compute(
            "this nonlinear force has no parameter derivative (∂F/∂p)".into(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn layout_indices_are_harmonic_major() {
        let layout = HarmonicLayout::new(2, 8).unwrap();
        assert_eq!(layout.len(3), 15);
        assert_eq!(layout.static_index(2), 2);
        assert_eq!(layout.cos_index(1, 0, 3), 3);
        assert_eq!(layout.cos_index(1, 2, 3), 7);
        assert_eq!(layout.cos_index(2, 0, 3), 9);
        assert_eq!(layout.cos_index(2, 2, 3), 13);
        assert_eq!(HarmonicLayout::default_samples(3), 16);
        assert_eq!(HarmonicLayout::default_samples(7), 32);
        assert!(HarmonicLayout::new(3, 7).is_err());
        assert!(HarmonicLayout::new(3, 8).is_ok());
    }
}
