//! `nlrom march`: time marching of a `[damper]`, matrix-defined or sector ROM case (the
//! nonsmooth schemes on `[[obstacle]]` contacts in [`super::nonsmooth`]), and the
//! `/march/` group of the results file it writes (`docs/results-file.md`): a march as the
//! [`MarchData`] of [`crate::output::results`], whose [`write_results`] owns the file. The layout's
//! datasets (`time`, `response` [T, R], `response_dofs`, `contact_force` [T, E, 2] and
//! `contact_state` [T, E] per element, `element_names`, `first_harmonic_last_period` \[R\],
//! `iterations_per_step` \[T\]; attributes `scheme`, `wall_seconds`, `omega`, `frequency_hz`, `steps`)
//! are `MarchData`'s fields; the march adds, in [`MarchData::extra`]:
//!
//! | dataset | shape | unit | content |
//! |---|---|---|---|
//! | `response_names` | \[R\] | – | names of the reported DOF (`u`, `w`, `phi` for the damper) |
//! | `contact_displacement` | [T, E, 2] | m | (u_t, v) per element: hysteresis-loop abscissae |
//! | `iteration_histogram` | \[K\] | – | steps that took k iterations (paper Fig. 5) |
//! | `periodicity_error` | \[P\] | – | end-of-period state change (NaN for period 1) |
//! | `state_changes` | \[P\] | – | instants per period at which a contact state changed |
//! | `harmonics_last_period` | [R, H+1] | m | complex harmonics 0..H (`docs/conventions.md` §4) |
//!
//! and the attributes `steady_period` (−1: not reached), `time_step_min`, `time_step_max` (s),
//! `rejected_steps`, `total_iterations`, `factorisations`.

use std::path::Path;
use std::time::Instant;

use faer::c64;

use serde_json::json;

use super::nonsmooth::nonsmooth_command;
use super::Reporter;
use crate::case::{Case, MarchScheme};
use crate::error::{Error, Result};
use crate::march::{march, MarchOutcome};
use crate::output::{write_results, Attr, Data, Dataset, FileInfo, Group, MarchData, ResultsFile};
use crate::problem::march_case::{case_march, CaseMarch};
use crate::problem::rom_store::file_info;

/// `nlrom march`: time marching of a `[damper]`, matrix-defined or sector ROM case; writes `/march/` and
/// reports the counts (steps, iterations per step, state changes, wall time).
pub fn march_command(
    case_path: &Path,
    output: &Path,
    scheme: Option<MarchScheme>,
    rep: &Reporter,
    as_json: bool,
) -> Result<()> {
    let start = Instant::now();
    let case = Case::load(case_path)?;
    let chosen = scheme.or(case.march.as_ref().map(|m| m.scheme));
    if let Some(s) = chosen.filter(|s| s.is_nonsmooth()) {
        return nonsmooth_command(&case, s, output, rep, as_json);
    }
    if !case.obstacle.is_empty() || !case.casing.is_empty() {
        let key = if case.obstacle.is_empty() {
            "casing"
        } else {
            "obstacle"
        };
        return Err(Error::input(format!(
            "{}: key '{key}': `[[{key}]]` contacts are marched by `--scheme moreau-jean` or `--scheme carpenter` (or `scheme` in [march])",
            case_path.display()
        )));
    }
    let cm = case_march(&case, scheme, &mut |l| rep.info(l))?;
    let out = march(&cm.system, &cm.settings)?;
    write_march_results(output, &file_info(&case), &cm, &out)?;
    let last = out.periods.last();
    let report = json!({
        "scheme": out.scheme.as_str(),
        "steps": out.steps,
        "rejected_steps": out.rejected_steps,
        "total_iterations": out.total_iterations,
        "iteration_histogram": out.iteration_histogram(),
        "single_iteration_fraction": out.single_iteration_fraction(),
        "state_changes_last_period": last.map(|p| p.state_changes),
        "periodicity_error_last_period": last.and_then(|p| p.periodicity_error),
        "steady_period": out.steady_period,
        "time_step_range_s": [out.step_range.0, out.step_range.1],
        "first_harmonic_last_period": cm.response.iter().map(|&d| out.first_harmonic_amplitude()[d]).collect::<Vec<_>>(),
        "response_dofs": cm.response.iter().map(|&d| cm.system.dof_names[d].clone()).collect::<Vec<_>>(),
        "march_wall_seconds": out.wall_seconds,
        "output": output.display().to_string(),
        "wall_seconds": start.elapsed().as_secs_f64(),
    });
    if as_json {
        println!("{report}");
    } else {
        println!(
            "{} march of {}: {} steps ({} iterations, {:.1} % single-iteration steps), {} state changes in the last period, steady {}, {:.3} s; wrote {}",
            out.scheme,
            case_path.display(),
            out.steps,
            out.total_iterations,
            100.0 * out.single_iteration_fraction(),
            last.map_or(0, |p| p.state_changes),
            out.steady_period.map_or("not reached".to_string(), |p| format!("after {p} periods")),
            out.wall_seconds,
            output.display()
        );
    }
    Ok(())
}

/// Writes the results file of a march (root attributes from `info`, `/march/`) atomically.
pub fn write_march_results(
    path: &Path,
    info: &FileInfo,
    cm: &CaseMarch,
    out: &MarchOutcome,
) -> Result<()> {
    let results = ResultsFile {
        info: info.clone(),
        march: Some(march_data(cm, out)),
        ..ResultsFile::default()
    };
    write_results(path, &results)
}

/// The march as the results file's [`MarchData`].
pub fn march_data(cm: &CaseMarch, out: &MarchOutcome) -> MarchData {
    let (sys, response) = (&cm.system, &cm.response);
    let h = &out.history;
    let (t, n) = (h.len(), sys.n);
    let amp = out.first_harmonic_amplitude();
    MarchData {
        scheme: out.scheme.as_str().to_string(),
        wall_seconds: out.wall_seconds,
        omega: cm.settings.omega,
        steps: out.steps as u64,
        response_dofs: cm.response_dofs.clone(),
        time: h.time.clone(),
        response: (0..t)
            .flat_map(|k| response.iter().map(move |&d| h.q[k * n + d]))
            .collect(),
        element_names: sys.elements.iter().map(|e| e.name.clone()).collect(),
        contact_force: h.force.clone(),
        contact_state: h.state.clone(),
        first_harmonic_last_period: response.iter().map(|&d| amp[d]).collect(),
        iterations_per_step: h.iterations.iter().map(|&i| u64::from(i)).collect(),
        extra: march_extra(cm, out),
    }
}

/// The datasets and attributes the march adds to the layout (module doc).
fn march_extra(cm: &CaseMarch, out: &MarchOutcome) -> Group {
    let (sys, response) = (&cm.system, &cm.response);
    let h = &out.history;
    let (t, ne, r) = (h.len(), sys.elements.len(), response.len());
    let mut g = Group::default();
    g.add(
        "response_names",
        Dataset::new(
            &[r],
            Data::Strings(response.iter().map(|&d| sys.dof_names[d].clone()).collect()),
            "1",
            "name of each reported DOF",
        ),
    );
    g.add(
        "contact_displacement",
        Dataset::new(
            &[t, ne, 2],
            Data::F64(h.contact_displacements(sys, cm.settings.omega)),
            "m",
            "(u_t, v): tangential relative displacement and normal approach per element",
        ),
    );
    g.add(
        "iteration_histogram",
        Dataset::u64s(
            out.iteration_histogram()
                .iter()
                .map(|&c| c as u64)
                .collect(),
            "1",
            "number of steps that took k iterations, k = index",
        ),
    );
    g.add(
        "periodicity_error",
        Dataset::f64s(
            out.periods
                .iter()
                .map(|p| p.periodicity_error.unwrap_or(f64::NAN))
                .collect(),
            "1",
            "max(|dq|/A, |dv|/(omega A)) between consecutive period ends",
        ),
    );
    g.add(
        "state_changes",
        Dataset::u64s(
            out.periods.iter().map(|p| p.state_changes as u64).collect(),
            "1",
            "instants per period at which a contact state changed",
        ),
    );
    let nh = cm.settings.harmonics + 1;
    let harm: Vec<c64> = response
        .iter()
        .flat_map(|&d| out.harmonics[d].iter().map(|&(re, im)| c64::new(re, im)))
        .collect();
    g.add(
        "harmonics_last_period",
        Dataset::new(
            &[r, nh],
            Data::Complex(harm),
            "m",
            "harmonics 0..H over the last period, q = Re sum Q_n exp(i n omega t)",
        ),
    );
    g.set_attr(
        "steady_period",
        Attr::I64(out.steady_period.map_or(-1, |p| p as i64)),
    )
    .set_attr("time_step_min", Attr::F64(out.step_range.0))
    .set_attr("time_step_max", Attr::F64(out.step_range.1))
    .set_attr("rejected_steps", Attr::U64(out.rejected_steps as u64))
    .set_attr("total_iterations", Attr::U64(out.total_iterations))
    .set_attr("factorisations", Attr::U64(out.factorisations as u64));
    g
}
