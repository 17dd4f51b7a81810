//! The harmonic balance of a model on matrix rows on the modal coordinates of its lowest modes
//! (`[harmonic_balance] modes = m`): the m lowest modes of (K, M) over the free rows, their
//! modal damping ratios, and their mass-normalised shapes at the rows the elements read, the
//! forced rows and the output rows, as a [`ModalModel`]
//! ([`crate::hbm::modal`]: u(t) = Φ q(t), Craig & Kurdila 2006, mode-superposition method).
//! The unknowns are the m(2H + 1) modal harmonics whatever the number of contact DOFs; nothing
//! of size n × n is formed when the modes come from the sparse eigensolver, so the dense limit
//! of [`super::matrix_case::matrix_setup`] does not apply.
//!
//! Modal damping ratios ζ_r of the case's damping, exact on the modes of (K, M): `modal = ζ`
//! gives ζ on every mode; `rayleigh = [α, β]` (C = αM + βK) gives ζ_r = α/(2ω_r) + βω_r/2;
//! undamped gives 0. An external damping matrix is not diagonal on the modes in general and is
//! refused.

use faer::Mat;

use crate::case::{Case, Damping};
use crate::eigen::{lowest_modes, symmetric_modes, EigenOptions};
use crate::error::{Error, Result};
use crate::hbm::modal::ModalModel;
use crate::model::StructuralModel;

use super::matrix_case::{matrix_rows, MatrixRows};

/// Up to this many free rows the modes come from the dense pencil (every mode, O(n³): about a
/// second at 2000 rows); above it from the sparse shift-invert eigensolver (the m lowest),
/// unless m exceeds half the rows.
const DENSE_MODES_UP_TO: usize = 2000;

/// A matrix case's linear part on its lowest modes, and the rows it refers to.
#[derive(Clone, Debug)]
pub struct ModalSetup {
    /// The modal model: ω_r, ζ_r and Φ at the element, forced and output rows.
    pub modal: ModalModel,
    /// The rows of the case (free-row indices, the order of [`ModalModel::contact_shapes`]) and
    /// its outputs.
    pub rows: MatrixRows,
    /// The natural frequencies of the modes (Hz), ascending.
    pub frequencies_hz: Vec<f64>,
}

/// The modal model of the `modes` lowest modes of the matrix case `case` on `model`.
///
/// Errors name the key: `harmonic_balance.modes` beyond the number of free rows, an external
/// damping matrix, a mode at zero frequency (a free–free model: clamp it), and the rows' errors
/// of [`matrix_rows`].
pub fn modal_setup(case: &Case, model: &StructuralModel, modes: usize) -> Result<ModalSetup> {
    let file = case.path.display();
    let n = model.free.n_free();
    if modes == 0 || modes > n {
        return Err(Error::input(format!(
            "{file}: key 'harmonic_balance.modes': {modes} modes for a model of {n} free DOF; give 1 to {n}"
        )));
    }
    let rows = matrix_rows(case, model)?;
    let (eigenvalues, shapes) = lowest(case, model, modes)?;
    let mut frequencies = Vec::with_capacity(modes);
    for (r, &lambda) in eigenvalues.iter().enumerate() {
        if !(lambda > 0.0 && lambda.is_finite()) {
            return Err(Error::input(format!(
                "{file}: key 'harmonic_balance.modes': mode {} has λ = {lambda:e} rad²/s² (a rigid-body mode); modal coordinates need a clamped model ([model] clamp)",
                r + 1
            )));
        }
        frequencies.push(lambda.sqrt());
    }
    let ratios = damping_ratios(case, &frequencies)?;
    let at = |rows: &[usize]| Mat::from_fn(rows.len(), modes, |i, r| shapes[(rows[i], r)]);
    let forced: Vec<usize> = (0..n).filter(|&i| rows.force[i] != 0.0).collect();
    let modal = ModalModel::new(
        frequencies.clone(),
        ratios,
        at(&rows.nonlinear_rows),
        at(&forced),
        forced.iter().map(|&i| rows.force[i]).collect(),
        at(&rows.output_rows),
    )?;
    let frequencies_hz = frequencies
        .iter()
        .map(|w| w / (2.0 * std::f64::consts::PI))
        .collect();
    Ok(ModalSetup {
        modal,
        rows,
        frequencies_hz,
    })
}

/// The `modes` lowest eigenvalues λ_r (rad²/s², ascending) and mass-normalised modes (n × m)
/// of the free (K, M): every mode of the dense pencil for small models or when m is more than
/// half the rows, else the sparse shift-invert eigensolver at shift 0.
fn lowest(case: &Case, model: &StructuralModel, modes: usize) -> Result<(Vec<f64>, Mat<f64>)> {
    let n = model.free.n_free();
    let keyed = |e: Error| {
        Error::Compute(format!(
            "{}: key 'harmonic_balance.modes': the {modes} lowest modes of the model: {e}",
            case.path.display()
        ))
    };
    if n <= DENSE_MODES_UP_TO || 2 * modes > n {
        let k = model.free.k.to_dense();
        let m = model.free.m.to_dense();
        let (values, vectors) = symmetric_modes(k.as_ref(), m.as_ref()).map_err(keyed)?;
        let first = vectors.as_ref().subcols(0, modes).to_owned();
        return Ok((values[..modes].to_vec(), first));
    }
    let found = lowest_modes(
        model.free.k.as_ref(),
        model.free.m.as_ref(),
        modes,
        &EigenOptions::default(),
    )
    .map_err(keyed)?;
    Ok((found.eigenvalues, found.vectors))
}

/// ζ_r of the case's damping on modes of natural frequencies ω_r (rad/s) (module
/// documentation).
fn damping_ratios(case: &Case, frequencies: &[f64]) -> Result<Vec<f64>> {
    Ok(match &case.model.damping {
        None => vec![0.0; frequencies.len()],
        Some(Damping::Modal(zeta)) => vec![*zeta; frequencies.len()],
        Some(Damping::Rayleigh { alpha, beta }) => frequencies
            .iter()
            .map(|w| alpha / (2.0 * w) + beta * w / 2.0)
            .collect(),
        Some(Damping::Matrix(_)) => {
            return Err(Error::input(format!(
                "{}: key 'model.damping.matrix': an external damping matrix is not diagonal on the modes; with `harmonic_balance.modes` give `modal` or `rayleigh` damping",
                case.path.display()
            )))
        }
    })
}
