//! Gram–Schmidt interface (GSI) reduction of the low cyclic frontier (`docs/theory.md`, "Gram–Schmidt
//! interface (GSI) reduction"; the recipe adopted in place of Battiato et al., CMAME 2018).
//!
//! For one harmonic index k, with the CB+CS model (K_k, M_k) whose first `n_f` coordinates are the
//! low-frontier DOF:
//! 1. the lowest n_g modes of (K_k, M_k) (contact/target DOF free);
//! 2. their low-frontier partitions (complex columns of length n_f);
//! 3. modified Gram–Schmidt with re-orthogonalisation (two passes, inner product aᴴb), a column
//!    dropped when its residual norm falls below [`DROP_TOLERANCE`] × its original norm → V_k
//!    (n_f × m, orthonormal columns);
//! 4. u_low = V_k η_f; the other coordinates unchanged: q_k = G η with G = blockdiag(V_k, I) up to
//!    the column order, and K_g = Gᴴ K_k G, M_g = Gᴴ M_k G (Hermitian).
//!
//! The n_g modes lie in the range of G (their frontier part is in span V_k), so they are
//! eigenpairs of the reduced model exactly; higher modes are approximated.
//!
//! Column order of the result (`crate::rom`): the remaining physical DOF, then η_f, then the CB
//! modal coordinates.

use faer::{c64, Mat, MatRef};

use crate::eigen::hermitian_modes;
use crate::error::{Error, Result};
use crate::rom::GsiReport;

/// Relative residual norm below which a frontier vector counts as linearly dependent.
pub const DROP_TOLERANCE: f64 = 1e-8;

/// The GSI-reduced matrices of one harmonic index.
#[derive(Clone, Debug)]
pub struct Gsi {
    /// V_k: orthonormal frontier basis (n_f × m).
    pub basis: Mat<c64>,
    /// Gᴴ K_k G (N/m).
    pub stiffness: Mat<c64>,
    /// Gᴴ M_k G (kg).
    pub mass: Mat<c64>,
    /// Retained count and dropped vectors.
    pub report: GsiReport,
}

/// Orthonormalises the columns of `a` by modified Gram–Schmidt with one re-orthogonalisation
/// pass, dropping columns whose residual norm is below `DROP_TOLERANCE` × their norm. Returns the
/// basis and the indices of the dropped columns.
pub fn orthonormalise(a: MatRef<'_, c64>) -> (Mat<c64>, Vec<usize>) {
    let n = a.nrows();
    let mut basis: Vec<Vec<c64>> = Vec::new();
    let mut dropped = Vec::new();
    for j in 0..a.ncols() {
        let mut v: Vec<c64> = (0..n).map(|i| a[(i, j)]).collect();
        let norm0 = norm(&v);
        if norm0 > 0.0 {
            for _pass in 0..2 {
                for q in &basis {
                    let proj: c64 = q.iter().zip(&v).map(|(qi, vi)| qi.conj() * vi).sum();
                    for (vi, qi) in v.iter_mut().zip(q) {
                        *vi -= proj * qi;
                    }
                }
            }
        }
        let r = norm(&v);
        if norm0 == 0.0 || r < DROP_TOLERANCE * norm0 {
            dropped.push(j);
            continue;
        }
        for vi in &mut v {
            *vi /= r;
        }
        basis.push(v);
    }
    let out = Mat::from_fn(n, basis.len(), |i, j| basis[j][i]);
    (out, dropped)
}

fn norm(v: &[c64]) -> f64 {
    v.iter().map(|x| x.norm_sqr()).sum::<f64>().sqrt()
}

/// The GSI reduction of (K_k, M_k) (see the module documentation): `n_frontier` first
/// coordinates are the low frontier, the next `n_other_physical` the remaining physical DOF,
/// the rest modal; `n_g` modes build the basis. `real`: K_k, M_k are real (k = 0, N/2), and so
/// is V_k.
///
/// Errors: [`Error::Input`] when n_g is 0 or exceeds the model size, or the model has no
/// frontier; [`Error::Compute`] from the eigensolver.
pub fn gsi(
    k: MatRef<'_, c64>,
    m: MatRef<'_, c64>,
    real: bool,
    n_frontier: usize,
    n_other_physical: usize,
    n_g: usize,
) -> Result<Gsi> {
    let n = k.nrows();
    if n_frontier == 0 {
        return Err(Error::input(
            "[reduction] gsi_modes: the model has no free low-frontier DOF to reduce; drop \
             `gsi_modes` or define `[cyclic]` frontiers",
        ));
    }
    if n_g == 0 || n_g > n {
        return Err(Error::input(format!(
            "[reduction] gsi_modes = {n_g}: give 1 to {n} modes (the CB+CS model has {n} \
             coordinates)"
        )));
    }
    let modes = hermitian_modes(k, m, real)?;
    let frontier = modes.vectors.as_ref().submatrix(0, 0, n_frontier, n_g);
    let (v, dropped) = orthonormalise(frontier);
    let n_eta = v.ncols();
    // Internal order: [η (n_eta), rows n_frontier.. unchanged]; G = blockdiag(V, I).
    let rest = n - n_frontier;
    let internal = |a: MatRef<'_, c64>| -> Mat<c64> {
        let a_ff = a.submatrix(0, 0, n_frontier, n_frontier);
        let a_fr = a.submatrix(0, n_frontier, n_frontier, rest);
        let a_rr = a.submatrix(n_frontier, n_frontier, rest, rest);
        let mut out = Mat::<c64>::zeros(n_eta + rest, n_eta + rest);
        let vh = v.adjoint();
        let top = vh * a_ff * &v;
        let cross = vh * a_fr;
        out.as_mut()
            .submatrix_mut(0, 0, n_eta, n_eta)
            .copy_from(&top);
        out.as_mut()
            .submatrix_mut(0, n_eta, n_eta, rest)
            .copy_from(&cross);
        out.as_mut()
            .submatrix_mut(n_eta, 0, rest, n_eta)
            .copy_from(cross.adjoint());
        out.as_mut()
            .submatrix_mut(n_eta, n_eta, rest, rest)
            .copy_from(a_rr);
        out
    };
    // Final order: other physical, η, modal.
    let size = n_eta + rest;
    let from_internal = |f: usize| -> usize {
        if f < n_other_physical {
            n_eta + f
        } else if f < n_other_physical + n_eta {
            f - n_other_physical
        } else {
            f
        }
    };
    let reorder =
        |a: Mat<c64>| Mat::from_fn(size, size, |i, j| a[(from_internal(i), from_internal(j))]);
    Ok(Gsi {
        stiffness: reorder(internal(k)),
        mass: reorder(internal(m)),
        report: GsiReport {
            modes_used: n_g,
            retained: n_eta,
            dropped,
        },
        basis: v,
    })
}
