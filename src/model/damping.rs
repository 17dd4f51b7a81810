//! The viscous damping matrix C (N·s/m) of a model from its `[model] damping` specification
//! (`docs/case-file.md`; `docs/theory.md`, Damping), for any dense model: the free rows of a
//! matrix case (real, T = f64) and the reduced model of each harmonic index (T = c64, Hermitian).
//!
//! * `rayleigh = [α, β]`: C = αM + βK (α in 1/s, β in s). On a ROM this is the exact projection
//!   of αM + βK, since every reduction step is linear.
//! * `modal = ζ`: C = M X diag(2ζω_j) Xᴴ M, X the mass-normalised modes of (K, M) (K x_j = ω_j² M x_j,
//!   Xᴴ M X = I, every mode of the dense model), so that Xᴴ C X = diag(2ζω_j): every mode has the
//!   damping ratio ζ exactly.
//! * `matrix = "D.mtx"`: read by the caller, which knows the rows of the model (the `external`
//!   argument of [`damping_matrix`]).

use std::path::Path;

use faer::traits::math_utils::mul_real;
use faer::traits::ComplexField;
use faer::{Mat, MatRef};

use crate::case::Damping;
use crate::eigen::pencil::pencil_modes;
use crate::error::Result;

/// The damping matrix C over the rows of the dense K (N/m) and M (kg), both n × n self-adjoint,
/// or `None` when `damping` is `None` (undamped). `external` reads a `matrix = "D.mtx"`
/// specification (or refuses it with an input error).
///
/// Errors: those of `external`, and for modal damping those of [`modal_damping`].
pub fn damping_matrix<T>(
    damping: Option<&Damping>,
    k: MatRef<'_, T>,
    m: MatRef<'_, T>,
    external: impl FnOnce(&Path) -> Result<Mat<T>>,
) -> Result<Option<Mat<T>>>
where
    T: ComplexField<Real = f64>,
{
    match damping {
        None => Ok(None),
        Some(Damping::Rayleigh { alpha, beta }) => {
            Ok(Some(Mat::from_fn(m.nrows(), m.ncols(), |i, j| {
                mul_real(&m[(i, j)], alpha) + mul_real(&k[(i, j)], beta)
            })))
        }
        Some(Damping::Modal(zeta)) => modal_damping(k, m, *zeta).map(Some),
        Some(Damping::Matrix(path)) => external(path).map(Some),
    }
}

/// Modal damping C = (M X) diag(2ζω_j) (M X)ᴴ with ω_j = √max(λ_j, 0) (rad/s) and X the
/// mass-normalised modes of (K, M) ([`pencil_modes`]: inverse form when K is positive definite,
/// direct form for a model with rigid-body modes, which get no damping).
///
/// Errors ([`crate::Error::Compute`]): M is not positive definite, or the eigensolver fails.
pub fn modal_damping<T>(k: MatRef<'_, T>, m: MatRef<'_, T>, zeta: f64) -> Result<Mat<T>>
where
    T: ComplexField<Real = f64>,
{
    let (lambda, x) = pencil_modes(k, m)?;
    let mx = m * &x;
    let d: Vec<f64> = lambda
        .iter()
        .map(|&l| 2.0 * zeta * l.max(0.0).sqrt())
        .collect();
    let scaled = Mat::from_fn(mx.nrows(), mx.ncols(), |i, j| mul_real(&mx[(i, j)], &d[j]));
    Ok(&scaled * mx.adjoint())
}
