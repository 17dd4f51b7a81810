//! Dense fallback for small problems (`N_dof` not above the Krylov subspace dimension, where
//! faer's Krylov–Schur does not apply): the operator `A = F⁻¹ M F⁻ᵀ` is formed column by column
//! and handed to faer's dense self-adjoint eigensolver (Householder tridiagonalisation + divide
//! and conquer).

use faer::{Mat, Side};

use super::krylov::Operator;
use crate::error::{Error, Result};

/// The `n` largest eigenpairs (θ, y) of the operator, θ descending, `‖y‖₂ = 1`.
pub(super) fn largest_eigenpairs(op: &Operator<'_, '_>, n: usize) -> Result<(Vec<f64>, Mat<f64>)> {
    let n_dof = op.n_dof();
    let identity = Mat::<f64>::identity(n_dof, n_dof);
    let mut a = Mat::<f64>::zeros(n_dof, n_dof);
    op.apply(a.as_mut(), identity.as_ref())?;
    let sym = Mat::from_fn(n_dof, n_dof, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let evd = sym.self_adjoint_eigen(Side::Lower).map_err(|e| {
        Error::Compute(format!(
            "the dense symmetric eigensolver did not converge ({e:?}); check K and M for \
             extreme values"
        ))
    })?;
    let (s, u) = (evd.S(), evd.U());
    let cols: Vec<usize> = (0..n).map(|c| n_dof - 1 - c).collect();
    let theta = cols.iter().map(|&c| s[c]).collect();
    let y = Mat::from_fn(n_dof, n, |i, c| u[(i, cols[c])]);
    Ok((theta, y))
}
