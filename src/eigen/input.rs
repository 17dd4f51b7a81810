//! Checks of the pencil (K, M) before anything is factorised: shapes, storage, finiteness,
//! symmetry and the signs of the diagonals. Every failure is an [`Error::Input`] that names the
//! matrix and the entry (0-based row, column) and says what to do.

use faer::sparse::SparseColMatRef;

use crate::error::{Error, Result};

/// Largest accepted `|a_ij − a_ji|`, relative to the largest `|a_ij|` of the matrix.
pub(super) const SYMMETRY_TOLERANCE: f64 = 1e-10;

/// Checks K (`k`) and M (`m`): square, same size, not empty, sorted row indices without
/// duplicates, finite values, symmetric (both triangles stored), diagonals not negative.
pub(super) fn check_pencil(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
) -> Result<()> {
    check_square("K", k)?;
    check_square("M", m)?;
    if k.nrows() != m.nrows() {
        return Err(Error::input(format!(
            "K is {0}×{0} but M is {1}×{1}; they must have the same size (the same DOF numbering)",
            k.nrows(),
            m.nrows()
        )));
    }
    if k.nrows() == 0 {
        return Err(Error::input(
            "K and M are empty (0 DOF); there is nothing to solve",
        ));
    }
    for (name, a) in [("K", k), ("M", m)] {
        check_storage(name, a)?;
        check_finite(name, a)?;
        check_symmetric(name, a)?;
        check_diagonal(name, a)?;
    }
    Ok(())
}

/// `a` must be square.
fn check_square(name: &str, a: SparseColMatRef<'_, usize, f64>) -> Result<()> {
    if a.nrows() != a.ncols() {
        return Err(Error::input(format!(
            "{name} is {}×{}; it must be square",
            a.nrows(),
            a.ncols()
        )));
    }
    Ok(())
}

/// Row indices strictly increasing in every column (sorted, no duplicates).
fn check_storage(name: &str, a: SparseColMatRef<'_, usize, f64>) -> Result<()> {
    for j in 0..a.ncols() {
        let rows = a.row_idx_of_col_raw(j);
        if let Some(w) = rows.windows(2).find(|w| w[0] >= w[1]) {
            return Err(Error::input(format!(
                "{name}: column {j} has unsorted or duplicate row indices ({} then {}); build the \
                 matrix with SparseColMat::try_new_from_triplets, which sorts and sums duplicates",
                w[0], w[1]
            )));
        }
    }
    Ok(())
}

/// No NaN or infinite entry.
fn check_finite(name: &str, a: SparseColMatRef<'_, usize, f64>) -> Result<()> {
    for j in 0..a.ncols() {
        let rows = a.row_idx_of_col_raw(j);
        let vals = a.val_of_col(j);
        if let Some((i, v)) = rows.iter().zip(vals).find(|(_, v)| !v.is_finite()) {
            return Err(Error::input(format!(
                "{name}[{i},{j}] = {v} is not a finite number; check the assembly or the file"
            )));
        }
    }
    Ok(())
}

/// Value of the stored entry (i, j), 0 if absent (`a` has sorted columns).
fn entry(a: SparseColMatRef<'_, usize, f64>, i: usize, j: usize) -> f64 {
    let rows = a.row_idx_of_col_raw(j);
    match rows.binary_search(&i) {
        Ok(p) => a.val_of_col(j)[p],
        Err(_) => 0.0,
    }
}

/// `|a_ij − a_ji| ≤ SYMMETRY_TOLERANCE · max|a|` for every stored off-diagonal entry.
fn check_symmetric(name: &str, a: SparseColMatRef<'_, usize, f64>) -> Result<()> {
    let max_abs = (0..a.ncols())
        .flat_map(|j| a.val_of_col(j).iter())
        .fold(0.0_f64, |acc, v| acc.max(v.abs()));
    let tol = SYMMETRY_TOLERANCE * max_abs;
    for j in 0..a.ncols() {
        let rows = a.row_idx_of_col_raw(j);
        let vals = a.val_of_col(j);
        for (&i, &v) in rows.iter().zip(vals) {
            if i == j {
                continue;
            }
            let w = entry(a, j, i);
            if (v - w).abs() > tol {
                return Err(Error::input(format!(
                    "{name} is not symmetric: {name}[{i},{j}] = {v:e} but {name}[{j},{i}] = {w:e} \
                     (0-based); store both triangles of a symmetric matrix (Matrix Market files \
                     with the `symmetric` qualifier are expanded on reading)"
                )));
            }
        }
    }
    Ok(())
}

/// Diagonal entries not negative (necessary for a positive semi-definite matrix).
fn check_diagonal(name: &str, a: SparseColMatRef<'_, usize, f64>) -> Result<()> {
    for j in 0..a.ncols() {
        let d = entry(a, j, j);
        if d < 0.0 {
            return Err(Error::input(format!(
                "{name}[{j},{j}] = {d:e} is negative, so {name} is not positive semi-definite; \
                 check the sign convention of the assembly"
            )));
        }
    }
    Ok(())
}
