//! A case file as a march: the [`MarchSystem`] of a `[damper]` table, of a matrix-defined model
//! (`[model]` stiffness/mass, damping, `[excitation]` rows, `[[element]]` friction elements) or of
//! a sector's reduced model ([`super::sector`]), the
//! [`MarchSettings`] of its `[march]` table, and the reported DOF.

use std::collections::HashMap;

use faer::Mat;

use super::damper::damper_system;
use super::element::{Direction, Element};
use super::integrate::MarchSettings;
use super::law::FrictionParams;
use super::sector::sector_march;
use super::signal::Harmonic;
use super::system::{InitialCondition, MarchSystem};
use crate::case::{Case, Damping, ElementKind, ExcitationLoad, MarchScheme, WeightedDofs};
use crate::error::{Error, Result};
use crate::hbm::setup::modal_damping;
use crate::matrix_io::read_real_matrix;
use crate::model::{self, StructuralModel};
use crate::output::ResponseDof;

/// The marched model of a case and the DOF indices it reports.
pub struct CaseMarch {
    /// The model.
    pub system: MarchSystem,
    /// Reported DOF (indices into the system's DOF).
    pub response: Vec<usize>,
    /// The reported DOF as results-file response DOFs: the matrix row of a matrix-defined case,
    /// the DOF index (0 u, 1 w, 2 φ) of a damper.
    pub response_dofs: Vec<ResponseDof>,
    /// How to march.
    pub settings: MarchSettings,
}

/// Builds the march of `case` with the scheme `scheme` (default: the case's). `log` receives
/// progress lines.
pub fn case_march(
    case: &Case,
    scheme: Option<MarchScheme>,
    log: &mut dyn FnMut(&str),
) -> Result<CaseMarch> {
    let m = case.march.as_ref().ok_or_else(|| {
        Error::input(format!(
            "{}: `nlrom march` needs a [march] table (frequency_hz, periods, steps_per_period)",
            case.path.display()
        ))
    })?;
    let settings = MarchSettings {
        scheme: scheme.unwrap_or(m.scheme),
        omega: m.omega(),
        periods: m.periods,
        steps_per_period: m.steps_per_period,
        step_ratio: m.step_ratio.unwrap_or(MarchSettings::default().step_ratio),
        time_step: m.time_step,
        tolerance: m.tolerance.unwrap_or(MarchSettings::default().tolerance),
        steady_tolerance: m
            .steady_tolerance
            .unwrap_or(MarchSettings::default().steady_tolerance),
        stop_at_steady: m.stop_at_steady,
        harmonics: case.harmonic_balance.harmonics,
        ..MarchSettings::default()
    };
    if let Some(d) = &case.damper {
        let system = damper_system(d, settings.omega)?;
        log(&format!(
            "damper: {} contact points, {} platforms",
            d.contact.len(),
            d.platform.len()
        ));
        return Ok(CaseMarch {
            response: (0..system.n).collect(),
            response_dofs: (0..system.n as u64).map(ResponseDof::Row).collect(),
            system,
            settings,
        });
    }
    if case.model.mesh.is_some() || case.rom.is_some() || case.cyclic.is_some() {
        let sm = sector_march(case, log)?;
        return Ok(CaseMarch {
            system: sm.system,
            response: sm.response,
            response_dofs: sm.response_dofs,
            settings,
        });
    }
    let structural = model::build(case, log)?;
    let (system, response) = matrix_system(case, &structural)?;
    let response_dofs = response
        .iter()
        .map(|&i| ResponseDof::Row(structural.free.free_dofs[i] as u64))
        .collect();
    Ok(CaseMarch {
        system,
        response,
        response_dofs,
        settings,
    })
}

/// Dense row-major copy of a sparse matrix.
fn dense(a: faer::sparse::SparseColMatRef<'_, usize, f64>) -> Vec<f64> {
    let n = a.nrows();
    let mut out = vec![0.0; n * n];
    for j in 0..a.ncols() {
        for (i, v) in a.row_idx_of_col(j).zip(a.val_of_col(j)) {
            out[i * n + j] += *v;
        }
    }
    out
}

/// The march system of a matrix-defined case: dense K, M, C over the free DOF, the excitation
/// f = force·cos ωt on its rows, the `[[element]]` friction elements; starts at rest.
fn matrix_system(case: &Case, sm: &StructuralModel) -> Result<(MarchSystem, Vec<usize>)> {
    let file = case.path.display().to_string();
    let n = sm.free.n_free();
    let index: HashMap<usize, usize> = sm
        .free
        .free_dofs
        .iter()
        .enumerate()
        .map(|(i, &d)| (d, i))
        .collect();
    let row = |r: usize, key: &str| -> Result<usize> {
        index.get(&r).copied().ok_or_else(|| {
            Error::input(format!(
                "{file}: {key} names matrix row {r}, but the model's free rows are 0..{} (clamped rows cannot be used)",
                sm.n_dofs
            ))
        })
    };
    let k = dense(sm.free.k.as_ref());
    let m = dense(sm.free.m.as_ref());
    let c = damping_matrix(case, sm, &k, &m)?;
    let mut force = vec![Harmonic::default(); n];
    let mut response = Vec::new();
    if let Some(e) = &case.excitation {
        match &e.load {
            ExcitationLoad::Dofs { dofs, force: f } => {
                for (&d, &fv) in dofs.iter().zip(f) {
                    let i = row(d, "excitation.dofs")?;
                    force[i].cos += fv * e.force_scale;
                    response.push(i);
                }
            }
            ExcitationLoad::Group { .. } => {
                return Err(Error::input(format!(
                    "{file}: excitation.group needs a mesh; a matrix model gives `dofs` and `force`"
                )))
            }
        }
    }
    if let Some(r) = &case.response {
        if !r.dofs.is_empty() {
            response = r
                .dofs
                .iter()
                .map(|&d| row(d, "response.dofs"))
                .collect::<Result<_>>()?;
        }
    }
    let direction = |w: &WeightedDofs, key: &str| -> Result<Direction> {
        Ok(Direction {
            weights: w
                .dofs
                .iter()
                .zip(&w.weights)
                .map(|(&d, &x)| Ok((row(d, key)?, x)))
                .collect::<Result<_>>()?,
            prescribed: Harmonic::default(),
        })
    };
    let mut elements = Vec::new();
    for (i, e) in case.element.iter().enumerate() {
        let name = format!("element[{i}]");
        if e.kind != ElementKind::Friction {
            return Err(Error::input(format!(
                "{file}: {name}: kind = \"{}\" is computed by the harmonic balance (`nlrom solve`); time marching takes `friction` elements only",
                e.kind.name()
            )));
        }
        let value = |v: Option<f64>| v.unwrap_or(0.0);
        elements.push(Element {
            tangential: direction(&e.tangential, &format!("{name}.tangential"))?,
            normal: e
                .normal
                .as_ref()
                .map(|w| direction(w, &format!("{name}.normal")))
                .transpose()?,
            params: FrictionParams::new(
                value(e.kt),
                e.kn,
                value(e.mu),
                value(e.n0),
                &format!("{file}: {name}"),
            )?,
            name,
            applies_normal: true,
        });
    }
    if response.is_empty() {
        response = (0..n.min(3)).collect();
    }
    let mut sys = MarchSystem {
        n,
        mass: m,
        damping: c,
        stiffness: k,
        force,
        damping_force: Vec::new(),
        elements,
        dof_names: sm
            .free
            .free_dofs
            .iter()
            .map(|d| format!("row {d}"))
            .collect(),
        initial: InitialCondition::Rest,
        displacement_scale: 1.0,
    };
    sys.displacement_scale = sys.default_displacement_scale();
    sys.validate(&file)?;
    Ok((sys, response))
}

/// C of the case's damping: Rayleigh αM + βK, an external matrix, or modal damping ζ on every
/// mode of (K, M): C = M Φ diag(2ζω_i) Φᵀ M with M-normalised modes Φ.
fn damping_matrix(case: &Case, sm: &StructuralModel, k: &[f64], m: &[f64]) -> Result<Vec<f64>> {
    let n = sm.free.n_free();
    match &case.model.damping {
        None => Ok(vec![0.0; n * n]),
        Some(Damping::Rayleigh { alpha, beta }) => Ok(m
            .iter()
            .zip(k)
            .map(|(mi, ki)| alpha * mi + beta * ki)
            .collect()),
        Some(Damping::Matrix(path)) => {
            let c = read_real_matrix(path)?;
            if c.nrows() != sm.n_dofs || c.ncols() != sm.n_dofs {
                return Err(Error::input(format!(
                    "{}: a {}×{} damping matrix for a model of {} rows",
                    path.display(),
                    c.nrows(),
                    c.ncols(),
                    sm.n_dofs
                )));
            }
            let full = dense(c.as_ref());
            let f = &sm.free.free_dofs;
            Ok((0..n * n)
                .map(|ij| full[f[ij / n] * sm.n_dofs + f[ij % n]])
                .collect())
        }
        Some(Damping::Modal(zeta)) => {
            let km = Mat::from_fn(n, n, |i, j| k[i * n + j]);
            let mm = Mat::from_fn(n, n, |i, j| m[i * n + j]);
            let c = modal_damping(km.as_ref(), mm.as_ref(), *zeta)?;
            Ok((0..n * n).map(|ij| c[(ij / n, ij % n)]).collect())
        }
    }
}
