//! `nlrom march --scheme moreau-jean | carpenter`: the nonsmooth march of a matrix case with
//! `[[obstacle]]` contacts or of a mesh case with `[[casing]]` contacts (one obstacle per contact
//! node), written to `/march/` in the layout of `docs/results-file.md`, with
//! one "element" per obstacle: `contact_force` = (μλ/h, λ/h) (N, the mean friction and normal
//! force over the step), `contact_state` = 0 open, 2 in contact (impulse > 0). The march adds:
//!
//! | dataset | shape | unit | content |
//! |---|---|---|---|
//! | `response_names` | \[R\] | – | names of the reported rows |
//! | `impulse` | [T, E] | N·s | contact impulse λ of each step |
//! | `gap` | [T, E] | m | g(u_n) (negative: penetration) |
//! | `active` | [T, E] | – | 1 when the obstacle was in the step's active set |
//! | `lcp_residual` | \[T\] | – | complementarity residual of the step's LCP |
//! | `energy_terms` | [T, 8] | J | cumulative (kinetic, strain, damping, numerical, external, thermal, contact, residual) (`moreau-jean`) |
//! | `temperature` | [T, N] | K | temperature rise of the contact nodes, then of the other `[response]` nodes (with `[thermal]`) |
//! | `temperature_nodes` | \[N\] | – | their Gmsh node tags |
//! | `heat_terms` | [T, 4] | J | cumulative (stored, exchanged, frictional, residual) heat (with `[thermal]`) |
//!
//! and the attributes `time_step`, `gamma`, `gamma_thermal` (`moreau-jean`),
//! `stability_limit` (`carpenter`: 2/ω_max, s), `thermal_stability_limit` (`carpenter` with heat
//! rows: 2/μ_max, s), `reference_temperature` (°C, with `[thermal]`), `max_penetration` (m).
//!
//! The JSON report splits the run's wall time into the set-up (model, reduction), the march and
//! the writing of the results, gives the process's CPU time (user + system, all threads) per
//! phase and in total, and `waiting_for_cpu_seconds`: the time the command's thread was runnable
//! but waited for a core (Linux scheduler statistics), which is where the wall time beyond the
//! CPU time goes on a loaded machine.

use std::path::Path;
use std::time::Instant;

use serde_json::json;

use super::batch::records::{process_cpu_seconds, thread_cpu_wait_seconds};
use super::Reporter;
use crate::case::{Case, MarchScheme};
use crate::error::Result;
use crate::march::carpenter::{carpenter, stability_limits, StabilityLimits};
use crate::march::moreau_jean::moreau_jean;
use crate::march::obstacle::NonsmoothHistory;
use crate::model;
use crate::output::{write_results, Attr, Data, Dataset, Group, MarchData, ResultsFile};
use crate::problem::nonsmooth_case::{nonsmooth_case, NonsmoothCase};
use crate::problem::rom_store::file_info;

/// Runs the nonsmooth `scheme` on `case`, writes `/march/` to `output`, prints the report.
pub fn nonsmooth_command(
    case: &Case,
    scheme: MarchScheme,
    output: &Path,
    rep: &Reporter,
    as_json: bool,
) -> Result<()> {
    let start = Instant::now();
    let (cpu0, wait0) = (process_cpu_seconds(), thread_cpu_wait_seconds());
    let structural = model::build(case, &mut |l| rep.info(l))?;
    let nc = nonsmooth_case(case, &structural)?;
    let limit = if scheme == MarchScheme::Carpenter {
        let lim = stability_limits(&nc.system)?;
        rep.info(&format!(
            "carpenter: stability limit 2/ω_max = {:.4e} s (heat rows: {:.4e} s), step {:.4e} s",
            lim.mechanical, lim.thermal, nc.settings.step
        ));
        Some(lim)
    } else {
        None
    };
    let (setup_wall, setup_cpu) = (start.elapsed().as_secs_f64(), process_cpu_seconds());
    let hist = match scheme {
        MarchScheme::Carpenter => carpenter(&nc.system, &nc.settings)?,
        _ => moreau_jean(&nc.system, &nc.settings)?,
    };
    let march_cpu = process_cpu_seconds();
    let write_start = Instant::now();
    let data = march_data(&nc, &hist, limit);
    write_results(
        output,
        &ResultsFile {
            info: file_info(case),
            march: Some(data),
            ..ResultsFile::default()
        },
    )?;
    let write_wall = write_start.elapsed().as_secs_f64();
    let cpu = process_cpu_seconds();
    let span = |a: Option<f64>, b: Option<f64>| a.zip(b).map(|(a, b)| b - a);
    let impacts = hist.impulse.iter().filter(|&&l| l > 0.0).count();
    let energy_residual = hist
        .energy
        .iter()
        .map(|e| e.residual.abs())
        .fold(0.0, f64::max);
    let r = nc.response.len();
    let max_temperature = hist
        .x
        .chunks(hist.dofs.len().max(1))
        .flat_map(|row| row[r.min(row.len())..].iter().copied())
        .fold(None, |m: Option<f64>, t| Some(m.map_or(t, |m| m.max(t))));
    let heat = hist.heat.last();
    let report = json!({
        "scheme": scheme.as_str(),
        "steps": nc.settings.steps,
        "time_step_s": nc.settings.step,
        "stability_limit_s": limit.map(|l| l.mechanical),
        "thermal_stability_limit_s": limit.map(|l| l.thermal).filter(|t| t.is_finite()),
        "max_temperature_rise_k": max_temperature,
        "frictional_heat_j": heat.map(|q| q.frictional),
        "heat_balance_residual_j": heat.map(|q| q.residual),
        "steps_with_impulse": impacts,
        "max_penetration_m": hist.max_penetration(),
        "max_energy_residual_j": energy_residual,
        "setup_wall_seconds": setup_wall,
        "setup_cpu_seconds": span(cpu0, setup_cpu),
        "march_wall_seconds": hist.wall_seconds,
        "march_cpu_seconds": span(setup_cpu, march_cpu),
        "write_wall_seconds": write_wall,
        "output": output.display().to_string(),
        "wall_seconds": start.elapsed().as_secs_f64(),
        "cpu_seconds": span(cpu0, cpu),
        "waiting_for_cpu_seconds": span(wait0, thread_cpu_wait_seconds()),
    });
    if as_json {
        println!("{report}");
    } else {
        println!(
            "{scheme} march of {}: {} steps of {:.3e} s, {} steps with a contact impulse, max penetration {:.3e} m, {:.3} s; wrote {}",
            case.path.display(),
            nc.settings.steps,
            nc.settings.step,
            impacts,
            hist.max_penetration(),
            hist.wall_seconds,
            output.display()
        );
    }
    Ok(())
}

/// |Q⁽¹⁾| of each response DOF over the last excitation period (rectangle rule on the steps).
fn first_harmonic(nc: &NonsmoothCase, h: &NonsmoothHistory) -> Vec<f64> {
    let r = h.dofs.len();
    let omega = nc.system.omega;
    let t_end = *h.time.last().unwrap_or(&0.0);
    let period = 2.0 * std::f64::consts::PI / omega;
    let idx: Vec<usize> = (1..h.len())
        .filter(|&k| h.time[k] > t_end - period * (1.0 - 1e-9))
        .collect();
    (0..nc.response.len())
        .map(|d| {
            let (mut re, mut im) = (0.0, 0.0);
            for &k in &idx {
                let (s, c) = (omega * h.time[k]).sin_cos();
                re += h.x[k * r + d] * c;
                im += h.x[k * r + d] * s;
            }
            2.0 * re.hypot(im) / idx.len().max(1) as f64
        })
        .collect()
}

/// The march as the results file's [`MarchData`] (module doc).
fn march_data(
    nc: &NonsmoothCase,
    h: &NonsmoothHistory,
    limit: Option<StabilityLimits>,
) -> MarchData {
    let sys = &nc.system;
    let (t, e, dt) = (h.len(), sys.obstacles.len(), nc.settings.step);
    let (recorded, r) = (h.dofs.len(), nc.response.len());
    let columns = |range: std::ops::Range<usize>| -> Vec<f64> {
        h.x.chunks(recorded.max(1))
            .take(t)
            .flat_map(|row| row[range.clone()].iter().copied())
            .collect()
    };
    let mut force = Vec::with_capacity(t * e * 2);
    for k in 0..t {
        for (i, o) in sys.obstacles.iter().enumerate() {
            let l = h.impulse[k * e + i] / dt;
            force.extend([o.mu * l, l]);
        }
    }
    let mut g = Group::default();
    g.add(
        "response_names",
        Dataset::new(
            &[r],
            Data::Strings(
                h.dofs[..r]
                    .iter()
                    .map(|&d| sys.dof_names[d].clone())
                    .collect(),
            ),
            "1",
            "name of each reported row",
        ),
    );
    g.add(
        "impulse",
        Dataset::new(
            &[t, e],
            Data::F64(h.impulse.clone()),
            "N s",
            "contact impulse of each step",
        ),
    );
    g.add(
        "gap",
        Dataset::new(
            &[t, e],
            Data::F64(h.gap.clone()),
            "m",
            "gap g(u_n); negative is a penetration",
        ),
    );
    g.add(
        "active",
        Dataset::new(
            &[t, e],
            Data::U64(h.active.iter().map(|&a| u64::from(a)).collect()),
            "1",
            "1 when the obstacle was in the active set of the step",
        ),
    );
    g.add(
        "lcp_residual",
        Dataset::f64s(
            h.lcp_residual.clone(),
            "1",
            "complementarity residual of the step's LCP",
        ),
    );
    if !h.energy.is_empty() {
        let terms: Vec<f64> = h
            .energy
            .iter()
            .flat_map(|q| {
                [
                    q.kinetic,
                    q.strain,
                    q.damping,
                    q.numerical,
                    q.external,
                    q.thermal,
                    q.contact,
                    q.residual,
                ]
            })
            .collect();
        g.add(
            "energy_terms",
            Dataset::new(
                &[t, 8],
                Data::F64(terms),
                "J",
                "cumulative kinetic, strain, damping, numerical, external, thermal, contact, residual",
            ),
        );
        g.set_attr("gamma", Attr::F64(nc.settings.gamma))
            .set_attr("gamma_thermal", Attr::F64(nc.settings.gamma_thermal));
    }
    if !nc.temperature_nodes.is_empty() {
        let nt = recorded - r;
        g.add(
            "temperature",
            Dataset::new(
                &[t, nt],
                Data::F64(columns(r..recorded)),
                "K",
                "temperature rise above the reference temperature of the contact nodes, then of the other response nodes",
            ),
        );
        g.add(
            "temperature_nodes",
            Dataset::new(
                &[nt],
                Data::U64(nc.temperature_nodes.clone()),
                "1",
                "Gmsh tags of the nodes of `temperature`",
            ),
        );
    }
    if let Some(t0) = nc.reference_temperature {
        g.set_attr("reference_temperature", Attr::F64(t0));
    }
    if !h.heat.is_empty() {
        let terms: Vec<f64> = h
            .heat
            .iter()
            .flat_map(|q| [q.stored, q.exchanged, q.frictional, q.residual])
            .collect();
        g.add(
            "heat_terms",
            Dataset::new(
                &[h.heat.len(), 4],
                Data::F64(terms),
                "J",
                "cumulative stored, exchanged, frictional heat and the balance residual",
            ),
        );
    }
    if let Some(l) = limit {
        g.set_attr("stability_limit", Attr::F64(l.mechanical));
        if l.thermal.is_finite() {
            g.set_attr("thermal_stability_limit", Attr::F64(l.thermal));
        }
    }
    g.set_attr("time_step", Attr::F64(dt))
        .set_attr("max_penetration", Attr::F64(h.max_penetration()));
    MarchData {
        scheme: h.scheme.to_string(),
        wall_seconds: h.wall_seconds,
        omega: sys.omega,
        steps: nc.settings.steps as u64,
        response_dofs: nc.response.clone(),
        time: h.time.clone(),
        response: columns(0..r),
        element_names: sys.obstacles.iter().map(|o| o.name.clone()).collect(),
        contact_force: force,
        contact_state: h
            .impulse
            .iter()
            .map(|&l| if l > 0.0 { 2 } else { 0 })
            .collect(),
        first_harmonic_last_period: first_harmonic(nc, h),
        iterations_per_step: h.pivots.iter().map(|&p| u64::from(p)).collect(),
        extra: g,
    }
}
