//! The `/march/` group of the results file (`interface.md`, "Results (HDF5)"), written with the
//! HDF5 layer of [`crate::output`]. Every dataset carries `unit` and `description`.
//!
//! | dataset | shape | unit | content |
//! |---|---|---|---|
//! | `time` | [T] | s | instants (0 = start) |
//! | `response` | [T, R] | m (rad for a rotation) | reported DOF |
//! | `response_dofs` | [R] | – | their names |
//! | `contact_names` | [E] | – | friction elements |
//! | `contact_displacement` | [T, E, 2] | m | (u_t, v) per element: hysteresis-loop abscissae |
//! | `contact_force` | [T, E, 2] | N | (f_t, f_n) per element |
//! | `contact_state` | [T, E] | – | 0 separated, 1 stick, 2 slip +, 3 slip − |
//! | `iterations_per_step` | [T] | – | corrector iterations per step (0 at t = 0) |
//! | `iteration_histogram` | [K] | – | steps that took k iterations (paper Fig. 5) |
//! | `steps` | [1] | – | accepted time steps |
//! | `periodicity_error` | [P] | – | end-of-period state change (NaN for period 1) |
//! | `state_changes` | [P] | – | contact-state changes per period |
//! | `first_harmonic_last_period` | [R] | m | amplitude of the first harmonic over the last period |
//! | `harmonics_last_period` | [R, H+1] | m | complex harmonics 0..H (`conventions.md` §4) |
//!
//! Attributes: `scheme`, `wall_seconds`, `omega_rad_s`, `frequency_hz`, `steady_period` (−1: not
//! reached), `time_step_min`, `time_step_max`, `rejected_steps`, `total_iterations`,
//! `factorisations`.

use faer::c64;

use super::integrate::{MarchOutcome, MarchSettings};
use super::system::MarchSystem;
use crate::output::{file_attributes, Attr, Data, Dataset, FileInfo, Group, H5File};

/// The results file of a march: root attributes and the `/march/` group.
pub fn results_file(
    info: &FileInfo,
    sys: &MarchSystem,
    settings: &MarchSettings,
    out: &MarchOutcome,
    response: &[usize],
) -> H5File {
    let mut file = H5File {
        root: file_attributes(info, "results"),
    };
    *file.root.group("march") = march_group(sys, settings, out, response);
    file
}

/// The `/march/` group.
pub fn march_group(
    sys: &MarchSystem,
    settings: &MarchSettings,
    out: &MarchOutcome,
    response: &[usize],
) -> Group {
    let h = &out.history;
    let (t, n, ne, r) = (h.len(), sys.n, sys.elements.len(), response.len());
    let mut g = Group::default();
    g.add(
        "time",
        Dataset::f64s(h.time.clone(), "s", "time of each recorded instant"),
    );
    let resp: Vec<f64> = (0..t)
        .flat_map(|k| response.iter().map(move |&d| h.q[k * n + d]))
        .collect();
    g.add(
        "response",
        Dataset::new(
            &[t, r],
            Data::F64(resp),
            "m",
            "displacement of the reported DOF (rad for a rotation)",
        ),
    );
    g.add(
        "response_dofs",
        Dataset::new(
            &[r],
            Data::Strings(response.iter().map(|&d| sys.dof_names[d].clone()).collect()),
            "",
            "name of each reported DOF",
        ),
    );
    g.add(
        "contact_names",
        Dataset::new(
            &[ne],
            Data::Strings(sys.elements.iter().map(|e| e.name.clone()).collect()),
            "",
            "friction contact elements",
        ),
    );
    g.add(
        "contact_displacement",
        Dataset::new(
            &[t, ne, 2],
            Data::F64(h.local.clone()),
            "m",
            "(u_t, v): tangential relative displacement and normal approach per element",
        ),
    );
    g.add(
        "contact_force",
        Dataset::new(
            &[t, ne, 2],
            Data::F64(h.force.clone()),
            "N",
            "(f_t, f_n): friction and normal force per element",
        ),
    );
    g.add(
        "contact_state",
        Dataset::new(
            &[t, ne],
            Data::U64(h.state.iter().map(|&s| s as u64).collect()),
            "",
            "contact state per element: 0 separated, 1 stick, 2 slip +, 3 slip -",
        ),
    );
    g.add(
        "iterations_per_step",
        Dataset::u64s(
            h.iterations.iter().map(|&i| i as u64).collect(),
            "",
            "corrector iterations of each step (0 at t = 0)",
        ),
    );
    g.add(
        "iteration_histogram",
        Dataset::u64s(
            out.iteration_histogram()
                .iter()
                .map(|&c| c as u64)
                .collect(),
            "",
            "number of steps that took k iterations, k = index",
        ),
    );
    g.add(
        "steps",
        Dataset::u64s(vec![out.steps as u64], "", "accepted time steps"),
    );
    g.add(
        "periodicity_error",
        Dataset::f64s(
            out.periods
                .iter()
                .map(|p| p.periodicity_error.unwrap_or(f64::NAN))
                .collect(),
            "",
            "max(|dq|/A, |dv|/(omega A)) between consecutive period ends",
        ),
    );
    g.add(
        "state_changes",
        Dataset::u64s(
            out.periods.iter().map(|p| p.state_changes as u64).collect(),
            "",
            "instants per period where a contact state changed",
        ),
    );
    let amp = out.first_harmonic_amplitude();
    g.add(
        "first_harmonic_last_period",
        Dataset::f64s(
            response.iter().map(|&d| amp[d]).collect(),
            "m",
            "amplitude of the first harmonic over the last period",
        ),
    );
    let nh = settings.harmonics + 1;
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
    g.set_attr("scheme", Attr::Str(out.scheme.as_str().to_string()))
        .set_attr("wall_seconds", Attr::F64(out.wall_seconds))
        .set_attr("omega_rad_s", Attr::F64(settings.omega))
        .set_attr(
            "frequency_hz",
            Attr::F64(settings.omega / (2.0 * std::f64::consts::PI)),
        )
        .set_attr(
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
