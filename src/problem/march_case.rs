//! A case file as a march, by [`Case::kind`]: the [`MarchSystem`] of a `[damper]` table
//! ([`super::damper`]), of a model on matrix rows (`[model]` matrices or mesh, damping,
//! `[excitation]` rows, `[[element]]` friction elements; [`super::matrix_case::matrix_march`]) or
//! of a sector's reduced model ([`super::sector_march`]), the [`MarchSettings`] of its `[march]`
//! table, and the reported DOF.

use super::damper::damper_system;
use super::matrix_case::matrix_march;
use super::matrix_rom::reduced_matrix_model;
use super::sector_march::sector_march;
use crate::case::{Case, CaseKind, MarchScheme};
use crate::error::{Error, Result};
use crate::march::{MarchSettings, MarchSystem};
use crate::model;
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
    if let (CaseKind::Damper, Some(d)) = (case.kind(), &case.damper) {
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
    if case.kind() == CaseKind::Sector {
        let sm = sector_march(case, log)?;
        return Ok(CaseMarch {
            system: sm.system,
            response: sm.response,
            response_dofs: sm.response_dofs,
            settings,
        });
    }
    let structural = model::build(case, log)?;
    let structural = reduced_matrix_model(case, structural, log)?;
    let (system, response) = matrix_march(case, &structural)?;
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
