//! Dense symmetric / Hermitian eigenproblems.
//!
//! * [`self_adjoint_eigen_qr`]: every eigenpair of a dense self-adjoint matrix by Householder
//!   tridiagonalisation and the implicit QR algorithm. faer 0.24's default
//!   [`self_adjoint_eigen`](faer::Mat::self_adjoint_eigen) switches to divide and conquer above
//!   n = 128, which lost the orthogonality of eigenvectors of clustered eigenvalues on the
//!   projected matrices of a thick-restarted Krylov–Schur run with 100 wanted modes (the run
//!   then converged 41 of 100 modes in 200 restarts; see `lanczos.rs`) and was measured with
//!   relative residuals up to 5e-3 on a 753 × 753 graded reduced sector model, while it is
//!   accurate on random matrices (the unit test prints both). Every dense eigenproblem of nlrom's
//!   eigensolver and reduction goes through this function instead.
//! * The dense fallback of the sparse eigensolver for small problems (`N_dof` not above the
//!   Krylov basis size): the operator `A = F⁻¹ M F⁻ᵀ` is formed column by column and solved by
//!   [`self_adjoint_eigen_qr`].

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::evd::{
    self_adjoint_evd, self_adjoint_evd_scratch, ComputeEigenvectors, SelfAdjointEvdParams,
};
use faer::Mat;

use super::krylov::Operator;
use crate::error::{Error, Result};

/// Every eigenpair of the self-adjoint `a` (n × n, only the lower triangle is read): eigenvalues
/// ascending (real) and the orthonormal eigenvectors as columns, by Householder
/// tridiagonalisation and the implicit QR algorithm (faer's divide and conquer is disabled, see
/// the module documentation). Cost O(n³), memory n² values plus workspace.
///
/// Errors ([`Error::Compute`]): out of memory for the workspace, or the QR iteration does not
/// converge (NaN or infinite entries).
pub fn self_adjoint_eigen_qr<T>(a: faer::MatRef<'_, T>) -> Result<(Vec<f64>, Mat<T>)>
where
    T: faer::traits::ComplexField<Real = f64>,
{
    let mut u = Mat::<T>::zeros(a.nrows(), a.nrows());
    let values = evd_qr(a, Some(u.as_mut()))?;
    Ok((values, u))
}

/// The eigenvalues of the self-adjoint `a` (ascending), as [`self_adjoint_eigen_qr`] without
/// the eigenvectors: the tridiagonalisation (4n³/3 flops) and the QR iteration on the
/// tridiagonal matrix (O(n²)) instead of about 9n³ flops, and no n × n output.
pub fn self_adjoint_eigenvalues_qr<T>(a: faer::MatRef<'_, T>) -> Result<Vec<f64>>
where
    T: faer::traits::ComplexField<Real = f64>,
{
    evd_qr(a, None)
}

/// faer's self-adjoint eigendecomposition with the QR algorithm; eigenvectors into `u` if given.
fn evd_qr<T>(a: faer::MatRef<'_, T>, u: Option<faer::MatMut<'_, T>>) -> Result<Vec<f64>>
where
    T: faer::traits::ComplexField<Real = f64>,
{
    let n = a.nrows();
    let mut params: SelfAdjointEvdParams = <SelfAdjointEvdParams as faer::Auto<T>>::auto();
    params.recursion_threshold = usize::MAX;
    let par = faer::get_global_parallelism();
    let vectors = if u.is_some() {
        ComputeEigenvectors::Yes
    } else {
        ComputeEigenvectors::No
    };
    let req = self_adjoint_evd_scratch::<T>(n, vectors, par, params.into());
    let mut mem = MemBuffer::try_new(req).map_err(|_| {
        Error::Compute(format!(
            "out of memory for the dense eigensolver workspace ({n} × {n})"
        ))
    })?;
    let mut s = faer::diag::Diag::<T>::zeros(n);
    self_adjoint_evd(
        a,
        s.as_mut(),
        u,
        par,
        MemStack::new(&mut mem),
        params.into(),
    )
    .map_err(|e| {
        Error::Compute(format!(
            "the dense self-adjoint eigensolver ({n} × {n}) did not converge ({e:?}); check \
                 the matrices for NaN or extreme values"
        ))
    })?;
    Ok((0..n)
        .map(|i| faer::traits::math_utils::real(&s[i]))
        .collect())
}

/// The `n` largest eigenpairs (θ, y) of the operator, θ descending, `‖y‖₂ = 1`.
pub(super) fn largest_eigenpairs(op: &Operator<'_, '_>, n: usize) -> Result<(Vec<f64>, Mat<f64>)> {
    let n_dof = op.n_dof();
    let identity = Mat::<f64>::identity(n_dof, n_dof);
    let mut a = Mat::<f64>::zeros(n_dof, n_dof);
    op.apply(a.as_mut(), identity.as_ref())?;
    let sym = Mat::from_fn(n_dof, n_dof, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let (s, u) = self_adjoint_eigen_qr(sym.as_ref())?;
    let cols: Vec<usize> = (0..n).map(|c| n_dof - 1 - c).collect();
    let theta = cols.iter().map(|&c| s[c]).collect();
    let y = Mat::from_fn(n_dof, n, |i, c| u[(i, cols[c])]);
    Ok((theta, y))
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::c64;

    /// A random Hermitian n × n matrix with eigenvalues graded over `decades` orders of
    /// magnitude: Q diag(10^(−decades·j/n)) Qᴴ with Q unitary (QR of a random complex matrix).
    fn graded_hermitian(n: usize, decades: f64, seed: u64) -> Mat<c64> {
        let mut rng = super::super::lanczos::SplitMix(seed);
        let g = Mat::<c64>::from_fn(n, n, |_, _| c64::new(rng.uniform(), rng.uniform()));
        let q = g.qr().compute_Q();
        let d = Mat::<c64>::from_fn(n, n, |i, j| {
            if i == j {
                c64::new(10f64.powf(-decades * i as f64 / n as f64), 0.0)
            } else {
                c64::new(0.0, 0.0)
            }
        });
        let a = &q * &d * q.adjoint();
        Mat::from_fn(n, n, |i, j| (a[(i, j)] + a[(j, i)].conj()) * 0.5)
    }

    /// max_j ‖A u_j − s_j u_j‖₂ / ‖A‖_F.
    fn worst_residual(a: &Mat<c64>, s: &[f64], u: &Mat<c64>) -> f64 {
        let au = a * u;
        let norm = a.norm_l2();
        (0..s.len())
            .map(|j| {
                let r = au.col(j) - u.col(j) * faer::Scale(c64::new(s[j], 0.0));
                r.norm_l2() / norm
            })
            .fold(0.0, f64::max)
    }

    // 300 × 300 random Hermitian matrices (eigenvalues graded over 0 and 12 decades): every
    // eigenpair has a residual below 1e-13 ‖A‖, eigenvalues ascending, U unitary to 1e-12.
    #[test]
    fn qr_eigensolver_is_accurate_above_128() {
        for (decades, seed) in [(0.0, 7), (12.0, 11)] {
            let a = graded_hermitian(300, decades, seed);
            let (s, u) = self_adjoint_eigen_qr(a.as_ref()).unwrap();
            assert!(s.windows(2).all(|w| w[0] <= w[1]));
            let r = worst_residual(&a, &s, &u);
            assert!(r < 1e-13, "decades {decades}: residual {r:e}");
            let g = u.adjoint() * &u - Mat::<c64>::identity(300, 300);
            assert!(
                g.norm_max() < 1e-12,
                "decades {decades}: {:e}",
                g.norm_max()
            );
            // For the record: faer's default (divide and conquer above 128).
            let evd = a.self_adjoint_eigen(faer::Side::Lower).unwrap();
            let s_dc: Vec<f64> = (0..300).map(|i| evd.S()[i].re).collect();
            let u_dc = evd.U().to_owned();
            println!(
                "decades {decades}: QR residual {r:.1e}, faer default {:.1e}",
                worst_residual(&a, &s_dc, &u_dc)
            );
        }
    }
}
