//! The linear part of a matrix-defined case (`docs/case-file.md`: `[model] stiffness/mass/damping`,
//! `[excitation] dofs/force`, `[response] dofs`, `[[element]]` on DOF combinations): dense K, M,
//! C over the free rows, the excitation on harmonic 1, the nonlinear rows (every row an element
//! reads) and the output rows.
//!
//! Damping: `matrix` (read, same size as K), `rayleigh = [α, β]` (C = αM + βK) or `modal = ζ`
//! (C = M Φ diag(2ζω_j) Φᵀ M over all modes of the dense problem, Φ mass-normalised).

use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::{Mat, MatRef, Par, Side};

use super::linear::LinearModel;
use crate::case::{Case, Damping, ExcitationLoad};
use crate::eigen::self_adjoint_eigen_qr;
use crate::error::{Error, Result};
use crate::matrix_io::read_real_matrix;
use crate::model::StructuralModel;

/// Largest number of free DOF a matrix-defined case may have (the harmonic balance condenses
/// densely per frequency).
pub const MAX_DENSE_DOFS: usize = 4000;

/// The linear part of a matrix-defined case and the rows it refers to.
#[derive(Clone, Debug)]
pub struct MatrixSetup {
    /// The linear model condensed on `nonlinear_rows`.
    pub linear: LinearModel,
    /// Free-row indices of the nonlinear DOFs, ascending: the DOF order of the nonlinear force.
    pub nonlinear_rows: Vec<usize>,
    /// Free-row indices of the output DOFs.
    pub output_rows: Vec<usize>,
    /// Matrix rows (as written in the case, before clamping) of the output DOFs.
    pub output_case_rows: Vec<usize>,
}

impl MatrixSetup {
    /// Position of free row `row` among the nonlinear DOFs.
    pub fn nonlinear_position(&self, row: usize) -> Option<usize> {
        self.nonlinear_rows.binary_search(&row).ok()
    }
}

/// Builds the linear part of `case` on `model` with H harmonics.
pub fn matrix_setup(case: &Case, model: &StructuralModel) -> Result<MatrixSetup> {
    let name = case.path.display();
    let n = model.free.n_free();
    if n > MAX_DENSE_DOFS {
        return Err(Error::input(format!(
            "{name}: the model has {n} free DOF; the harmonic balance of a matrix-defined case is dense and handles up to {MAX_DENSE_DOFS} — reduce the model first (a [reduction] case)"
        )));
    }
    let free_of = free_row_map(model);
    let k = model.free.k.to_dense();
    let m = model.free.m.to_dense();
    let c = damping_matrix(case, model, &free_of, k.as_ref(), m.as_ref())?;
    let force = excitation(case, model, &free_of)?;
    let mut nonlinear_rows = Vec::new();
    for (i, e) in case.element.iter().enumerate() {
        let mut rows = vec![(format!("element[{i}].tangential.dofs"), &e.tangential.dofs)];
        if let Some(nrm) = &e.normal {
            rows.push((format!("element[{i}].normal.dofs"), &nrm.dofs));
        }
        for (key, dofs) in rows {
            for &d in dofs {
                nonlinear_rows.push(free_row(case, &free_of, &key, d)?);
            }
        }
    }
    nonlinear_rows.sort_unstable();
    nonlinear_rows.dedup();
    let output_case_rows = output_rows(case)?;
    let output_rows = output_case_rows
        .iter()
        .map(|&d| free_row(case, &free_of, "response.dofs", d))
        .collect::<Result<Vec<_>>>()?;
    let linear = LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        c.as_ref().map(|c| c.as_ref()),
        &force,
        nonlinear_rows.clone(),
        output_rows.clone(),
        case.harmonic_balance.harmonics,
    )?;
    Ok(MatrixSetup {
        linear,
        nonlinear_rows,
        output_rows,
        output_case_rows,
    })
}

/// Matrix row (before clamping) → free row, `None` for a clamped row.
fn free_row_map(model: &StructuralModel) -> Vec<Option<usize>> {
    let mut map = vec![None; model.n_dofs];
    for (i, &row) in model.free.free_dofs.iter().enumerate() {
        if row < map.len() {
            map[row] = Some(i);
        }
    }
    map
}

/// The free row of case row `d` named at `key`, or an input error.
fn free_row(case: &Case, free_of: &[Option<usize>], key: &str, d: usize) -> Result<usize> {
    match free_of.get(d) {
        Some(Some(r)) => Ok(*r),
        Some(None) => Err(Error::input(format!(
            "{}: key '{key}': row {d} is clamped; a clamped DOF cannot carry a force, an element or a response",
            case.path.display()
        ))),
        None => Err(Error::input(format!(
            "{}: key '{key}': row {d} is out of range; the matrices have {} rows (0-based rows 0..{})",
            case.path.display(),
            free_of.len(),
            free_of.len().saturating_sub(1)
        ))),
    }
}

/// The output rows as written in the case: `[response] dofs`, else the excitation rows.
fn output_rows(case: &Case) -> Result<Vec<usize>> {
    if let Some(r) = case.response.as_ref().filter(|r| !r.dofs.is_empty()) {
        return Ok(r.dofs.clone());
    }
    match case.excitation.as_ref().map(|e| &e.load) {
        Some(ExcitationLoad::Dofs { dofs, .. }) => Ok(dofs.clone()),
        _ => Err(Error::input(format!(
            "{}: key 'response': a matrix-defined case needs `[response] dofs = [...]` or `[excitation] dofs`",
            case.path.display()
        ))),
    }
}

/// The excitation amplitude per free row (N), f = force·cos(ωt) (times `force_scale`).
fn excitation(case: &Case, model: &StructuralModel, free_of: &[Option<usize>]) -> Result<Vec<f64>> {
    let mut f = vec![0.0; model.free.n_free()];
    let Some(e) = &case.excitation else {
        return Err(Error::input(format!(
            "{}: key 'excitation': a forced response needs `[excitation] dofs = [...]` and `force = [...]`",
            case.path.display()
        )));
    };
    match &e.load {
        ExcitationLoad::Dofs { dofs, force } => {
            for (&d, &v) in dofs.iter().zip(force) {
                f[free_row(case, free_of, "excitation.dofs", d)?] += v * e.force_scale;
            }
        }
        ExcitationLoad::Group { group, .. } => {
            return Err(Error::input(format!(
                "{}: key 'excitation.group': the group '{group}' cannot load a matrix-defined model in the direct harmonic balance; give `dofs` and `force` (matrix rows)",
                case.path.display()
            )))
        }
    }
    Ok(f)
}

/// The dense damping matrix over the free rows, `None` when undamped.
fn damping_matrix(
    case: &Case,
    model: &StructuralModel,
    free_of: &[Option<usize>],
    k: MatRef<'_, f64>,
    m: MatRef<'_, f64>,
) -> Result<Option<Mat<f64>>> {
    let n = k.nrows();
    match &case.model.damping {
        None => Ok(None),
        Some(Damping::Rayleigh { alpha, beta }) => Ok(Some(Mat::from_fn(n, n, |i, j| {
            alpha * m[(i, j)] + beta * k[(i, j)]
        }))),
        Some(Damping::Matrix(path)) => {
            let c = read_real_matrix(path)?;
            if c.nrows() != model.n_dofs || c.ncols() != model.n_dofs {
                return Err(Error::input(format!(
                    "{}: a {}×{} damping matrix for K of {} rows (key 'model.damping.matrix' of {})",
                    path.display(),
                    c.nrows(),
                    c.ncols(),
                    model.n_dofs,
                    case.path.display()
                )));
            }
            let full = c.to_dense();
            let rows: Vec<usize> = (0..model.n_dofs)
                .filter(|&r| free_of[r].is_some())
                .collect();
            Ok(Some(Mat::from_fn(n, n, |i, j| full[(rows[i], rows[j])])))
        }
        Some(Damping::Modal(zeta)) => modal_damping(k, m, *zeta).map(Some).map_err(|e| {
            Error::input(format!(
                "{}: key 'model.damping.modal': {e}",
                case.path.display()
            ))
        }),
    }
}

/// C = M Φ diag(2ζω_j) Φᵀ M with Φ the mass-normalised modes of (K, M): with M = L Lᵀ and
/// L⁻¹ K L⁻ᵀ = U Λ Uᵀ, C = (L U) diag(2ζ√λ_j) (L U)ᵀ. The dense eigenproblem is solved by the
/// implicit QR algorithm ([`crate::eigen::self_adjoint_eigen_qr`]): faer's default divide and
/// conquer loses orthogonality on clustered eigenvalues above 128 × 128.
pub fn modal_damping(k: MatRef<'_, f64>, m: MatRef<'_, f64>, zeta: f64) -> Result<Mat<f64>> {
    let n = k.nrows();
    let llt = m
        .llt(Side::Lower)
        .map_err(|_| Error::input("modal damping needs a positive definite mass matrix M"))?;
    let l = llt.L().to_owned();
    let mut x = k.to_owned();
    solve_lower_triangular_in_place(l.as_ref(), x.as_mut(), Par::Seq);
    let mut a = x.transpose().to_owned();
    solve_lower_triangular_in_place(l.as_ref(), a.as_mut(), Par::Seq);
    let sym = Mat::from_fn(n, n, |i, j| 0.5 * (a[(i, j)] + a[(j, i)]));
    let (lambda, u) = self_adjoint_eigen_qr(sym.as_ref())
        .map_err(|e| Error::Compute(format!("modal damping: {e}")))?;
    let lu = &l * &u;
    let scaled = Mat::from_fn(n, n, |i, r| {
        lu[(i, r)] * 2.0 * zeta * lambda[r].max(0.0).sqrt()
    });
    Ok(&scaled * lu.transpose())
}
