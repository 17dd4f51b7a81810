//! A case as the model of the nonsmooth schemes ([`crate::march::moreau_jean`],
//! [`crate::march::carpenter`]): a matrix-defined case with `[[obstacle]]` tables (dense K, M, C
//! over the free rows of [`super::matrix_case`], the excitation f = force·cos ωt, the obstacles on
//! free rows), or a mesh case with `[[casing]]` tables ([`super::casing_case`]); and the step,
//! step count, γ and recorded rows of the `[march]` table.

use super::matrix_case::{damping_matrix, free_row, free_row_map};
use crate::case::{Case, CaseKind, ExcitationLoad, WeightedDofs};
use crate::error::{Error, Result};
use crate::march::obstacle::{NonsmoothSettings, NonsmoothSystem, Obstacle};
use crate::march::signal::Harmonic;
use crate::model::StructuralModel;
use crate::output::ResponseDof;

/// The nonsmooth march of a case: model, settings and the recorded rows.
pub struct NonsmoothCase {
    /// The model.
    pub system: NonsmoothSystem,
    /// Steps, step size, γ; `record` holds the reported DOF: first the mechanical response
    /// (`response`), then the temperature rows of `temperature_nodes`.
    pub settings: NonsmoothSettings,
    /// The reported mechanical DOF (matrix rows before clamping, or node tag and component).
    pub response: Vec<ResponseDof>,
    /// Gmsh tags of the nodes whose temperature rise is recorded (after the response in
    /// `settings.record`); empty without thermal DOF.
    pub temperature_nodes: Vec<u64>,
    /// The stress-free temperature θ = 0 stands for (°C), with thermal DOF.
    pub reference_temperature: Option<f64>,
}

/// The `[march]` settings of a nonsmooth march: the step `time_step_s`, else the period over
/// `steps_per_period`, for `periods` excitation periods; γ (default 1/2), γ_θ (default γ), ε_g.
pub(crate) fn march_settings(case: &Case, record: Vec<usize>) -> Result<NonsmoothSettings> {
    let m = case.march.as_ref().ok_or_else(|| {
        Error::input(format!(
            "{}: `nlrom march` needs a [march] table (frequency_hz, periods, steps_per_period)",
            case.path.display()
        ))
    })?;
    let period = 2.0 * std::f64::consts::PI / m.omega();
    let step = m.time_step.unwrap_or(period / m.steps_per_period as f64);
    let steps = ((m.periods as f64 * period) / step).round().max(1.0) as usize;
    let gamma = m.gamma.unwrap_or(0.5);
    let settings = NonsmoothSettings {
        step,
        steps,
        start: 0.0,
        gamma,
        gamma_thermal: m.gamma_thermal.unwrap_or(gamma),
        activation_tolerance: m.activation_tolerance.unwrap_or(0.0),
        record: Some(record),
    };
    settings.validate()?;
    Ok(settings)
}

/// Builds the nonsmooth march of `case` on its structural model `sm`: [`super::casing_case`]
/// for a mesh case with `[[casing]]`, else the matrix-defined case with `[[obstacle]]` (below).
pub fn nonsmooth_case(case: &Case, sm: &StructuralModel) -> Result<NonsmoothCase> {
    if !case.casing.is_empty() || case.thermal.is_some() {
        return super::casing_case::casing_case(case, sm);
    }
    let file = case.path.display().to_string();
    if case.kind() != CaseKind::Matrix || case.model.mesh.is_some() {
        return Err(Error::input(format!(
            "{file}: key 'obstacle': the nonsmooth schemes march a model on matrix rows (`[model] stiffness`/`mass`) with `[[obstacle]]` tables, or a mesh model with `[[casing]]` tables"
        )));
    }
    if !case.element.is_empty() {
        return Err(Error::input(format!(
            "{file}: key 'element': the nonsmooth schemes take `[[obstacle]]` contacts, not `[[element]]` friction elements; march those with newmark, adaptive, piecewise-linear or quasi-static"
        )));
    }
    let m = case.march.as_ref().ok_or_else(|| {
        Error::input(format!(
            "{file}: `nlrom march` needs a [march] table (frequency_hz, periods, steps_per_period)"
        ))
    })?;
    let n = sm.free.n_free();
    let free_of = free_row_map(sm);
    let row = |r: usize, key: &str| free_row(case, &free_of, key, r);
    let k = sm.free.k.to_dense();
    let mass = sm.free.m.to_dense();
    let c = damping_matrix(case, sm, k.as_ref(), mass.as_ref())?;
    let dense =
        |a: &faer::Mat<f64>| -> Vec<f64> { (0..n * n).map(|ij| a[(ij / n, ij % n)]).collect() };
    let mut sys = NonsmoothSystem::mechanical(
        dense(&mass),
        c.as_ref().map_or_else(|| vec![0.0; n * n], dense),
        dense(&k),
    );
    sys.omega = m.omega();
    sys.dof_names = sm
        .free
        .free_dofs
        .iter()
        .map(|d| format!("row {d}"))
        .collect();
    let mut response = Vec::new();
    let mut response_rows = Vec::new();
    if let Some(e) = &case.excitation {
        match &e.load {
            ExcitationLoad::Dofs { dofs, force } => {
                for (&d, &f) in dofs.iter().zip(force) {
                    let i = row(d, "excitation.dofs")?;
                    sys.force[i] = Harmonic {
                        cos: sys.force[i].cos + f * e.force_scale,
                        ..sys.force[i]
                    };
                    response.push(i);
                    response_rows.push(d);
                }
            }
            ExcitationLoad::Group { .. } => {
                return Err(Error::input(format!(
                    "{file}: key 'excitation.group': a matrix model gives `dofs` and `force`"
                )))
            }
        }
    }
    if let Some(r) = case.response.as_ref().filter(|r| !r.dofs.is_empty()) {
        response = r
            .dofs
            .iter()
            .map(|&d| row(d, "response.dofs"))
            .collect::<Result<_>>()?;
        response_rows = r.dofs.clone();
    }
    let combination = |w: &WeightedDofs, key: &str| -> Result<Vec<(usize, f64)>> {
        w.dofs
            .iter()
            .zip(&w.weights)
            .map(|(&d, &x)| Ok((row(d, key)?, x)))
            .collect()
    };
    for (i, o) in case.obstacle.iter().enumerate() {
        let key = format!("obstacle[{i}]");
        let mut ob = Obstacle::new(
            &o.label(i),
            combination(&o.normal, &format!("{key}.normal.dofs"))?,
            o.gap,
            o.restitution,
        );
        ob.mu = o.mu;
        if let Some(s) = &o.sliding {
            ob.tangential = combination(s, &format!("{key}.sliding.dofs"))?;
        }
        for &(j, _) in &ob.normal {
            if !response.contains(&j) {
                response.push(j);
                response_rows.push(sm.free.free_dofs[j]);
            }
        }
        sys.obstacles.push(ob);
    }
    if response.is_empty() {
        response = (0..n.min(3)).collect();
        response_rows = response.iter().map(|&j| sm.free.free_dofs[j]).collect();
    }
    sys.validate(&file)?;
    Ok(NonsmoothCase {
        system: sys,
        settings: march_settings(case, response)?,
        response: response_rows
            .iter()
            .map(|&r| ResponseDof::Row(r as u64))
            .collect(),
        temperature_nodes: Vec::new(),
        reference_temperature: None,
    })
}
