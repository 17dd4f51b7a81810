//! Stage 4 of a case, end to end: the frequency response of every sweep point (SAMA paper,
//! Battiato 2021, §2–3: harmonic balance with condensation on the contact DOFs and arc-length
//! continuation), traced in parallel (rayon) and gathered into a [`ResultsFile`]
//! (`docs/results-file.md`).
//!
//! Two kinds of case:
//! - *matrix cases* ([`CaseKind::Matrix`]: no mesh, or `[[element]]` friction elements on DOF
//!   combinations): the dense linear part of [`matrix_setup`] condensed on the rows the elements
//!   read, and the elements of [`matrix_elements`] on those rows;
//! - *sector cases* ([`CaseKind::Sector`]): the ROM of every harmonic index (read from a ROM
//!   file whose key matches, else reduced — see [`RomPolicy`]), the contact pairs of
//!   [`build_interfaces`] (SAMA or node-to-node) and [`SectorProblem`]; `/contact/<name>` gets the
//!   pairs and, per point, the fractions of the period in stick, slip and separation.
//!
//! A continuation that stops at its minimum step ([`PathEnd::Failed`]) keeps its converged
//! points: the curve is written and the failure reported (see [`SolveOutcome::failures`]).

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::{Path, PathBuf};
use std::time::Instant;

use rayon::prelude::*;
use serde_json::{json, Value};

use super::batch::records::thread_cpu_seconds;
use super::progress::Reporter;
use super::summary::{summarize, CurveSummary};
use crate::case::{Case, CaseKind};
use crate::contact::element::{ElementReport, HysteresisLoop};
use crate::contact::grounded::DofElements;
use crate::contact::pairs::PairState;
use crate::contact::slip_map::slip_map;
use crate::continuation::PathEnd;
use crate::error::{Error, Result};
use crate::harmonics::{HarmonicForce, HarmonicLayout};
use crate::hbm::frf::{frequency_response, land_at};
use crate::hbm::{HbmSystem, OutputResponse, ResponseOptions};
use crate::interface::{build_interfaces, ContactInterface};
use crate::mesh::Mesh;
use crate::model::{self, StructuralModel};
use crate::nonlinear::{linsolve, SolverChoice};
use crate::output::{
    write_results, ContactCurveDetail, ContactData, ContactMap, FileInfo, FrfData, FrfRecord,
    PointLoops, ResponseDof, ResultsFile,
};
use crate::problem::matrix_case::{matrix_elements, matrix_setup, strip_points};
use crate::problem::matrix_rom::reduced_matrix_model;
use crate::problem::modal_case::modal_setup;
use crate::problem::rom_store::{create_parent, sector_rom, RomOrigin, RomPolicy};
use crate::problem::sector::SectorProblem;
use crate::problem::settings::case_continuation;
use crate::rom::Rom;

/// How `solve` runs a case.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SolveOptions {
    /// Where the ROM of a sector case comes from.
    pub rom: RomPolicy,
    /// Fill the `stable` flag of every point (Hill's method, [`crate::hbm::stability`]; one
    /// dense eigenproblem of the uncondensed harmonic system per point).
    pub stability: bool,
}

impl SolveOptions {
    /// `rom` without stability.
    pub fn new(rom: RomPolicy) -> SolveOptions {
        SolveOptions {
            rom,
            stability: false,
        }
    }
}

/// The result of one curve (one sweep point).
#[derive(Clone, Debug)]
pub struct CurveReport {
    /// Sweep point index (the `/frf/<i>` group).
    pub sweep_point: usize,
    /// The sweep parameters and their values (empty without a sweep).
    pub params: BTreeMap<String, f64>,
    /// Converged points written.
    pub points: usize,
    /// Resonance, peak amplitude and Q-factor ([`super::summary`]); `None` without points.
    pub summary: Option<CurveSummary>,
    /// How the continuation ended: `reached_end`, `max_points`, `left_range` or `failed`.
    pub end: &'static str,
    /// Why the curve failed (no convergence), if it did.
    pub failure: Option<String>,
    /// CPU time (s) of the thread that traced the curve, from the start point to the last
    /// point's outputs: the whole CPU time of the continuation where its evaluations run on
    /// that thread (matrix blocks below 32 rows, at most 4 friction elements); the rayon
    /// workers' share of larger models is not counted. `None` where it cannot be measured (and
    /// in the records of `nlrom batch`).
    pub cpu_seconds: Option<f64>,
}

impl CurveReport {
    /// The JSON object of `nlrom solve --json`'s `frf` list.
    pub fn json(&self) -> Value {
        let s = self.summary.as_ref();
        json!({
            "sweep_point": self.sweep_point,
            "params": self.params,
            "points": self.points,
            "resonance_hz": s.map(|s| s.resonance_hz),
            "peak_amplitude": s.map(|s| s.peak_amplitude),
            "q_factor": s.and_then(|s| s.q_factor),
            "summary_response_dof": s.map(|s| s.response_dof),
            "end": self.end,
            "error": self.failure,
            "cpu_seconds": self.cpu_seconds,
        })
    }
}

/// Everything `solve` produced for a case.
#[derive(Clone, Debug)]
pub struct SolveOutcome {
    /// The results file content (written by [`solve_to_file`]).
    pub results: ResultsFile,
    /// One report per sweep point, in sweep order.
    pub curves: Vec<CurveReport>,
    /// Where the ROM came from (sector cases).
    pub rom: Option<RomOrigin>,
}

impl SolveOutcome {
    /// The failure messages of the curves that did not reach their end by convergence failure.
    pub fn failures(&self) -> Vec<String> {
        self.curves
            .iter()
            .filter_map(|c| {
                c.failure
                    .as_ref()
                    .map(|m| format!("sweep point {}: {m}", c.sweep_point))
            })
            .collect()
    }
}

/// The results file of a case: `-o` if given, else `[output] file`, else `<stem>.h5` next to
/// the case file.
pub fn default_output(case: &Case, given: Option<&Path>) -> PathBuf {
    if let Some(p) = given {
        return p.to_path_buf();
    }
    if let Some(o) = &case.output {
        return o.file.clone();
    }
    case.path.with_extension("h5")
}

/// The ROM file `nlrom run` caches a sector case's ROM in: `[rom] file`, else
/// `<results stem>.rom.h5` next to the results file.
pub fn default_rom_file(case: &Case, results: &Path) -> PathBuf {
    if let Some(r) = &case.rom {
        return r.file.clone();
    }
    let stem = results
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "nlrom".into());
    results.with_file_name(format!("{stem}.rom.h5"))
}

/// Solves `case` and writes its results to `output` (atomically; parent directories are
/// created). A failed curve is written with its converged points and listed in
/// [`SolveOutcome::failures`]; the caller decides the exit status.
pub fn solve_to_file(
    case: &Case,
    output: &Path,
    opts: &SolveOptions,
    rep: &Reporter,
) -> Result<SolveOutcome> {
    let outcome = solve_case(case, opts, rep)?;
    create_parent(output)?;
    write_results(output, &outcome.results)?;
    rep.info(&format!("wrote {}", output.display()));
    Ok(outcome)
}

/// Solves every sweep point of `case` (in parallel) and gathers the results.
pub fn solve_case(case: &Case, opts: &SolveOptions, rep: &Reporter) -> Result<SolveOutcome> {
    if case.kind() == CaseKind::Damper {
        return Err(Error::input(format!(
            "{}: a [damper] case is computed by time marching; run `nlrom march {} -o RESULT.h5`",
            case.path.display(),
            case.path.display()
        )));
    }
    case_continuation(case)?;
    let points = case.sweep_points()?;
    let (mut curves, contacts, rom) = if case.kind() == CaseKind::Matrix {
        let (curves, contacts) = solve_matrix(case, &points, opts.stability, rep)?;
        (curves, contacts, None)
    } else {
        let (rom, mesh, origin) = sector_rom(case, &opts.rom, rep)?;
        let (curves, contacts) = solve_sector(&points, &rom, &mesh, opts.stability, rep)?;
        (curves, contacts, Some(origin))
    };
    let mut maps = Vec::new();
    for (i, curve) in curves.iter_mut().enumerate() {
        for mut m in std::mem::take(&mut curve.maps) {
            m.curve = i;
            maps.push(m);
        }
    }
    maps.sort_by(|a, b| a.name.cmp(&b.name).then(a.curve.cmp(&b.curve)));
    let (frfs, reports) = curves.into_iter().map(|c| (c.frf, c.report)).unzip();
    Ok(SolveOutcome {
        results: ResultsFile {
            info: FileInfo {
                title: case.title.clone(),
                case_text: case.source_text.clone(),
            },
            frfs,
            contacts,
            march: None,
            maps,
        },
        curves: reports,
        rom,
    })
}

/// One traced curve: its results group and its report.
struct Curve {
    frf: FrfData,
    report: CurveReport,
    /// Per contact interface: the per-element detail of this curve (empty for matrix cases).
    details: Vec<ContactCurveDetail>,
    /// The stick–slip–separation maps at the curve's resonance peak (`[[strip]] map`; `curve`
    /// set by the caller).
    maps: Vec<ContactMap>,
}

/// The curves of a matrix case (no contact interfaces).
fn solve_matrix(
    case: &Case,
    points: &[Case],
    stability: bool,
    rep: &Reporter,
) -> Result<(Vec<Curve>, Vec<ContactData>)> {
    if !case.contact.is_empty() {
        return Err(Error::input(format!(
            "{}: [[contact]] interfaces need a mesh case with [reduction]; a matrix case places friction with [[element]]",
            case.path.display()
        )));
    }
    let model = model::build(case, &mut |l| rep.detail(l))?;
    let model = reduced_matrix_model(case, model, &mut |l| rep.detail(l))?;
    let curves = points
        .par_iter()
        .map(|pc| matrix_curve(pc, &model, stability, rep))
        .collect::<Result<Vec<_>>>()?;
    Ok((curves, Vec::new()))
}

/// The response at the output DOFs from the response of the solved coordinates (the modal
/// coordinates of [`modal_curve`] → the physical output rows), with the response options of the
/// curve.
type OutputMap<'a> = dyn Fn(&OutputResponse, &ResponseOptions) -> Result<OutputResponse> + 'a;

/// The curve of one sweep point of a matrix case.
fn matrix_curve(
    case: &Case,
    model: &StructuralModel,
    stability: bool,
    rep: &Reporter,
) -> Result<Curve> {
    if let Some(modes) = case.harmonic_balance.modes {
        return modal_curve(case, model, modes, stability, rep);
    }
    let setup = matrix_setup(case, model)?;
    let elements = matrix_elements(case, model, &setup.nonlinear_rows)?;
    let system = HbmSystem::new(case.harmonic_balance.layout()?, &setup.linear, &elements)?;
    let dofs = row_dofs(&setup.output_case_rows);
    let (positions, map_hz) = strip_map_parts(case, model)?;
    let maps = |q: &[f64], state: &Vec<f64>, at: Option<f64>| {
        strip_maps(case, &positions, &elements, &system.layout(), q, state, at)
    };
    let probe = ContactProbe {
        sizes: Vec::new(),
        evaluate: &|_: &[f64], _: &_, _| Ok(Vec::new()),
        maps: case.strip.iter().any(|s| s.map.is_some()).then_some(&maps),
        map_hz,
    };
    trace_curve(case, &system, dofs, &probe, None, stability, rep)
}

/// The response DOFs of the matrix rows `rows` (as written in the case).
fn row_dofs(rows: &[usize]) -> Vec<ResponseDof> {
    rows.iter().map(|&r| ResponseDof::Row(r as u64)).collect()
}

/// The positions of every `[[strip]]`'s points (per strip) and the frequencies (Hz, ascending,
/// without repeats) at which the strips with a `map` want one (`map_hz`).
fn strip_map_parts(case: &Case, model: &StructuralModel) -> Result<(Vec<Vec<f64>>, Vec<f64>)> {
    let positions = (0..case.strip.len())
        .map(|s| Ok(strip_points(case, s, model)?.iter().map(|p| p.0).collect()))
        .collect::<Result<Vec<Vec<f64>>>>()?;
    let mut map_hz: Vec<f64> = case
        .strip
        .iter()
        .filter(|s| s.map.is_some())
        .flat_map(|s| s.map_hz.iter().flatten().copied())
        .collect();
    map_hz.sort_by(f64::total_cmp);
    map_hz.dedup();
    Ok((positions, map_hz))
}

/// The curve of one sweep point of a matrix case on the modal coordinates of its `modes` lowest
/// modes ([`modal_setup`]): the friction elements projected on the modes, the response at the
/// output rows Φ_o Q per harmonic, the strips' maps from the elements' motion Φ_c Q.
fn modal_curve(
    case: &Case,
    model: &StructuralModel,
    modes: usize,
    stability: bool,
    rep: &Reporter,
) -> Result<Curve> {
    let setup = modal_setup(case, model, modes)?;
    let (first, last) = (setup.frequencies_hz[0], setup.frequencies_hz[modes - 1]);
    rep.detail(&format!(
        "harmonic balance on {modes} modal coordinates (modes at {first:.6}–{last:.6} Hz) for {} element DOF of {} free DOF",
        setup.rows.nonlinear_rows.len(),
        model.free.n_free()
    ));
    let range = case_continuation(case)?;
    let highest_swept =
        range.start.max(range.end) * case.harmonic_balance.harmonics as f64 / (2.0 * PI);
    if modes < model.free.n_free() && last < 2.0 * highest_swept {
        rep.warn(&format!(
            "harmonic_balance.modes = {modes}: the highest mode ({last:.6} Hz) is below twice the highest harmonic swept ({highest_swept:.6} Hz = H × the highest frequency); the truncated basis may miss the response there: check by raising `modes`"
        ));
    }
    let elements = matrix_elements(case, model, &setup.rows.nonlinear_rows)?;
    let layout = case.harmonic_balance.layout()?;
    let linear = setup.modal.linear_model(case.harmonic_balance.harmonics)?;
    let force = setup.modal.project(elements)?;
    let system = HbmSystem::new(layout, &linear, &force)?;
    let dofs = row_dofs(&setup.rows.output_case_rows);
    let (positions, map_hz) = strip_map_parts(case, model)?;
    let maps = |q: &[f64], state: &Vec<f64>, at: Option<f64>| {
        let u = force.to_physical(&layout, q)?;
        strip_maps(case, &positions, force.inner(), &layout, &u, state, at)
    };
    let probe = ContactProbe {
        sizes: Vec::new(),
        evaluate: &|_: &[f64], _: &_, _| Ok(Vec::new()),
        maps: case.strip.iter().any(|s| s.map.is_some()).then_some(&maps),
        map_hz,
    };
    let physical =
        |modal: &OutputResponse, opts: &ResponseOptions| setup.modal.physical_response(modal, opts);
    trace_curve(case, &system, dofs, &probe, Some(&physical), stability, rep)
}

/// The maps of the `[[strip]]` entries that ask for one (`map = N_θ`), at the harmonics `q` with
/// slider states `state` of the friction elements `elements` (the strips' points follow the
/// friction `[[element]]` entries, in file order; `positions[s]` are the positions of strip s's
/// points): with `at` = None the strips without `map_hz` (a resonance peak), with `at` = Some(f)
/// those whose `map_hz` lists f (Hz).
fn strip_maps(
    case: &Case,
    positions: &[Vec<f64>],
    elements: &DofElements,
    layout: &HarmonicLayout,
    q: &[f64],
    state: &[f64],
    at: Option<f64>,
) -> Result<Vec<ContactMap>> {
    let mut start = case
        .element
        .iter()
        .filter(|e| e.kind == crate::case::ElementKind::Friction)
        .count();
    let mut maps = Vec::new();
    for (s, strip) in case.strip.iter().enumerate() {
        let points = &positions[s];
        let range = start..start + points.len();
        start = range.end;
        let Some(phases) = strip.map else { continue };
        let wanted = match (at, &strip.map_hz) {
            (None, None) => true,
            (Some(f), Some(hz)) => hz.contains(&f),
            _ => false,
        };
        if !wanted {
            continue;
        }
        let map = slip_map(&elements.map_points(layout, q, state, range)?, phases)?;
        maps.push(ContactMap {
            name: strip.label(s),
            mu: strip.mu,
            position: points.clone(),
            phase: map.phases,
            state: map.state.into_iter().map(i64::from).collect(),
            friction_ratio: map.friction_ratio,
            transition_offsets: map.transition_offsets.iter().map(|&o| o as u64).collect(),
            transition_angles: map.transition_angles,
            transition_states: map.transition_states.into_iter().map(i64::from).collect(),
            ..ContactMap::default()
        });
    }
    Ok(maps)
}

/// The curves of a sector case; `/contact/` holds the interfaces of sweep point 0 (the sweep
/// values of the others are attributes of their `/frf/<i>`).
fn solve_sector(
    points: &[Case],
    rom: &Rom,
    mesh: &Mesh,
    stability: bool,
    rep: &Reporter,
) -> Result<(Vec<Curve>, Vec<ContactData>)> {
    let solved = points
        .par_iter()
        .map(|pc| sector_curve(pc, rom, mesh, stability, rep))
        .collect::<Result<Vec<_>>>()?;
    let mut contacts = Vec::new();
    let mut curves = Vec::with_capacity(solved.len());
    for (i, (mut curve, interfaces)) in solved.into_iter().enumerate() {
        if i == 0 {
            contacts = interfaces.iter().map(ContactData::from_interface).collect();
        }
        for (contact, detail) in contacts.iter_mut().zip(std::mem::take(&mut curve.details)) {
            contact.curves.push(detail);
        }
        curves.push(curve);
    }
    Ok((curves, contacts))
}

/// The curve of one sweep point of a sector case and its contact interfaces.
fn sector_curve(
    case: &Case,
    rom: &Rom,
    mesh: &Mesh,
    stability: bool,
    rep: &Reporter,
) -> Result<(Curve, Vec<ContactInterface>)> {
    let interfaces = build_interfaces(case, mesh, rom.cyclic.as_ref())?;
    for iface in &interfaces {
        rep.detail(&projection_line(iface));
        if let Some(w) = unprojected_warning(iface, "see `nlrom contact`") {
            rep.warn(&w);
        }
    }
    let problem = SectorProblem::build(case, rom, mesh, &interfaces)?;
    let system = problem.system()?;
    let sizes: Vec<usize> = interfaces
        .iter()
        .map(ContactInterface::element_count)
        .collect();
    let evaluate = |q: &[f64], state: &PairState, loops: bool| {
        problem
            .contact
            .inner
            .reports(&problem.layout, q, state, loops)
    };
    let probe = ContactProbe {
        sizes,
        evaluate: &evaluate,
        maps: None,
        map_hz: Vec::new(),
    };
    let dofs = problem
        .outputs
        .iter()
        .map(|o| ResponseDof::Node {
            tag: o.node_tag,
            component: o.component,
        })
        .collect();
    let curve = trace_curve(case, &system, dofs, &probe, None, stability, rep)?;
    Ok((curve, interfaces))
}

/// "contact 'NAME': σ = S, P of C contact nodes projected", followed by "(E on the target's
/// edge, outside by at most D m)" when nodes were paired on the target's border.
pub fn projection_line(iface: &ContactInterface) -> String {
    let mut line = format!(
        "contact '{}': σ = {}, {} of {} contact nodes projected",
        iface.name,
        iface.sigma,
        iface.pairs.len(),
        iface.contact_nodes
    );
    let offsets: Vec<f64> = iface
        .edge_pairs()
        .filter_map(|p| p.edge.map(|e| e.tangential_offset))
        .collect();
    if !offsets.is_empty() {
        line += &format!(
            " ({} on the target's edge, outside by at most {:.3e} m)",
            offsets.len(),
            offsets.iter().copied().fold(0.0, f64::max)
        );
    }
    line
}

/// The warning for contact nodes that did not project onto the target, if any (`hint` says
/// where to find them).
pub fn unprojected_warning(iface: &ContactInterface, hint: &str) -> Option<String> {
    (!iface.unprojected.is_empty()).then(|| {
        format!(
            "contact '{}': {} contact node(s) do not project onto the target surface ({hint})",
            iface.name,
            iface.unprojected.len()
        )
    })
}

/// The per-element state of the contact elements at a solution (harmonic vector `q`, force
/// memory `state`): [`crate::contact::pairs::PairSet::reports`] with the hysteresis loops when asked.
type ElementReports<'a, S> =
    dyn Fn(&[f64], &S, bool) -> Result<Vec<(ElementReport, Option<HysteresisLoop>)>> + Sync + 'a;

/// The stick–slip–separation maps at a solution (harmonic vector `q`, force memory `state`): at a
/// resonance peak (None) or at a chosen frequency (Some(f), Hz).
type PeakMaps<'a, S> = dyn Fn(&[f64], &S, Option<f64>) -> Result<Vec<ContactMap>> + Sync + 'a;

/// How the contact state of a curve's points is recorded: the element reports, and the number of
/// elements of each interface (consecutive in the pair set; empty without contact interfaces),
/// and the maps taken at the resonance peak or at the frequencies `map_hz` (Hz), if any.
struct ContactProbe<'a, S> {
    sizes: Vec<usize>,
    evaluate: &'a ElementReports<'a, S>,
    maps: Option<&'a PeakMaps<'a, S>>,
    map_hz: Vec<f64>,
}

impl<S> ContactProbe<'_, S> {
    /// Per interface: the fractions of the period in stick, slip and separation averaged over
    /// its elements, and each element's fractions and dissipated energy appended to `details`.
    fn record_point(
        &self,
        q: &[f64],
        state: &S,
        details: &mut [ContactCurveDetail],
    ) -> Result<Vec<[f64; 3]>> {
        let reports = (self.evaluate)(q, state, false)?;
        let mut averages = Vec::with_capacity(self.sizes.len());
        let mut start = 0;
        for (&n, detail) in self.sizes.iter().zip(details.iter_mut()) {
            let mut sum = [0.0; 3];
            for (r, _) in &reports[start..start + n] {
                let f = [r.stick, r.slip, r.separation];
                sum.iter_mut().zip(f).for_each(|(s, v)| *s += v);
                detail.fractions.push(f);
                detail.dissipated_energy.push(r.dissipated_energy);
            }
            let scale = if n > 0 { 1.0 / n as f64 } else { 0.0 };
            averages.push(sum.map(|s| s * scale));
            start += n;
        }
        Ok(averages)
    }

    /// The hysteresis loops of every element at point `point` (harmonics `q`, memory `state`),
    /// stored in each interface's detail.
    fn record_loops(
        &self,
        point: usize,
        q: &[f64],
        state: &S,
        details: &mut [ContactCurveDetail],
    ) -> Result<()> {
        let reports = (self.evaluate)(q, state, true)?;
        let mut elements = reports.into_iter().filter_map(|(_, l)| l);
        for (&n, detail) in self.sizes.iter().zip(details.iter_mut()) {
            let mut loops = PointLoops {
                point,
                ..PointLoops::default()
            };
            for l in elements.by_ref().take(n) {
                loops.samples = l.v.len();
                for j in 0..l.v.len() {
                    loops.u.extend([l.u[0][j], l.u[1][j]]);
                    loops.force.extend([l.ft[0][j], l.ft[1][j]]);
                }
                loops.approach.extend_from_slice(&l.v);
                loops.normal_force.extend_from_slice(&l.fnormal);
            }
            detail.loops = Some(loops);
        }
        Ok(())
    }
}

/// Traces the frequency response of one sweep point with a progress bar and converts it to the
/// results layout. A start that does not converge, or a continuation that fails later, gives a
/// curve with the converged points and a failure message; bad input is an error.
fn trace_curve<F: HarmonicForce>(
    case: &Case,
    system: &HbmSystem<'_, F>,
    response_dofs: Vec<ResponseDof>,
    contact: &ContactProbe<'_, F::State>,
    outputs: Option<&OutputMap<'_>>,
    stability: bool,
    rep: &Reporter,
) -> Result<Curve> {
    let opts = case_continuation(case)?;
    let params: BTreeMap<String, f64> = case
        .sweep_point
        .as_ref()
        .map(|s| s.values.iter().cloned().collect())
        .unwrap_or_default();
    let index = case.sweep_point.as_ref().map_or(0, |s| s.index);
    let label = curve_label(index, &params);
    let t = Instant::now();
    let mut bar = rep.curve_bar(&label, opts.start / (2.0 * PI), opts.end / (2.0 * PI));
    let response = ResponseOptions {
        stability,
        ..ResponseOptions::default()
    };
    let solves_before = linsolve::stats();
    let cpu_before = thread_cpu_seconds();
    let traced = frequency_response(system, &opts, &response, &mut |p| {
        bar.point(p.parameter, p.iterations)
    });
    let cpu_seconds = cpu_before.zip(thread_cpu_seconds()).map(|(a, b)| b - a);
    bar.finish();
    rep.info(&format!(
        "{label}: {}",
        solves_line(opts.newton.linear_solver, solves_before, linsolve::stats())
    ));
    let mut frf = FrfData {
        sweep: params.clone(),
        harmonics: system.layout().harmonics,
        response_dofs,
        points: Vec::new(),
        jumps: Vec::new(),
    };
    let mut details = vec![ContactCurveDetail::default(); contact.sizes.len()];
    let mut maps = Vec::new();
    let (end, failure) = match traced {
        Err(e @ (Error::Input(_) | Error::Io { .. } | Error::Msh(_))) => return Err(e),
        Err(e) => (
            "failed",
            Some(format!(
                "the start point at {:.6} Hz did not converge: {e}",
                opts.start / (2.0 * PI)
            )),
        ),
        Ok(mut traced) => {
            let landed = land_at(
                system,
                &mut traced,
                &contact
                    .map_hz
                    .iter()
                    .map(|f| 2.0 * PI * f)
                    .collect::<Vec<_>>(),
                &opts.newton,
                &response,
            )?;
            for (w, why) in &landed.failed {
                rep.warn(&format!(
                    "{label}: no map at {:.6} Hz: Newton at that frequency failed from the neighbouring points ({why})",
                    w / (2.0 * PI)
                ));
            }
            if let Some(level) = traced.start_level {
                rep.info(&format!(
                    "{label}: Newton from the linear solution missed the start point at {:.6} Hz; it was reached by continuation in the excitation level from {level} × the force",
                    opts.start / (2.0 * PI)
                ));
            }
            for jump in &traced.jumps {
                rep.warn(&format!(
                    "{label}: at {:.6} Hz {}; the sweep jumped to {:.6} Hz and went on from there (point {})",
                    jump.from / (2.0 * PI),
                    jump.cause.describe(),
                    jump.to / (2.0 * PI),
                    jump.point
                ));
            }
            frf.jumps = traced.jumps.iter().map(|j| j.point).collect();
            for p in &traced.points {
                let mapped;
                let at_dofs = match outputs {
                    Some(map) => {
                        mapped = map(&p.response, &response)?;
                        &mapped
                    }
                    None => &p.response,
                };
                frf.points.push(FrfRecord {
                    omega: p.omega,
                    harmonics: at_dofs.harmonics.concat(),
                    peak: at_dofs.peak.clone(),
                    arc_length: p.arc_length,
                    newton_iterations: p.iterations as u64,
                    residual: p.residual,
                    stable: p.stable,
                    contact_fractions: contact.record_point(&p.q, &p.state, &mut details)?,
                });
            }
            if !contact.sizes.is_empty() || contact.maps.is_some() {
                let (hz, amplitude) = curve_amplitudes(&frf);
                if let Some(peak) = summarize(&hz, &amplitude) {
                    let p = &traced.points[peak.peak_point];
                    if !contact.sizes.is_empty() {
                        contact.record_loops(peak.peak_point, &p.q, &p.state, &mut details)?;
                    }
                    if let Some(at_peak) = contact.maps {
                        for mut m in at_peak(&p.q, &p.state, None)? {
                            m.point = peak.peak_point;
                            m.omega = p.omega;
                            maps.push(m);
                        }
                    }
                }
            }
            if let Some(at) = contact.maps {
                for (&f, points) in contact.map_hz.iter().zip(&landed.points) {
                    if points.is_empty() {
                        rep.warn(&format!(
                            "{label}: the curve does not reach {f} Hz: no map there"
                        ));
                    }
                    for &k in points {
                        let p = &traced.points[k];
                        for mut m in at(&p.q, &p.state, Some(f))? {
                            m.point = k;
                            m.omega = p.omega;
                            maps.push(m);
                        }
                    }
                }
            }
            match traced.end {
                PathEnd::ReachedEnd => ("reached_end", None),
                PathEnd::MaxPoints => {
                    rep.warn(&format!(
                        "{label}: stopped after max_points = {} points before the end frequency (raise `[continuation] max_points`)",
                        opts.max_points
                    ));
                    ("max_points", None)
                }
                PathEnd::LeftRange => ("left_range", None),
                PathEnd::Closed => ("closed", None),
                PathEnd::Failed(msg) => {
                    let last = frf.points.last().map_or(opts.start, |p| p.omega);
                    (
                        "failed",
                        Some(format!(
                            "the continuation failed after {} converged points (last at {:.6} Hz): {msg}",
                            frf.points.len(),
                            last / (2.0 * PI)
                        )),
                    )
                }
            }
        }
    };
    let (hz, amplitude) = curve_amplitudes(&frf);
    rep.info(&format!(
        "{label}: {} points in {:.2} s ({end})",
        frf.points.len(),
        t.elapsed().as_secs_f64()
    ));
    let report = CurveReport {
        sweep_point: index,
        params,
        points: frf.points.len(),
        summary: summarize(&hz, &amplitude),
        end,
        failure,
        cpu_seconds,
    };
    Ok(Curve {
        frf,
        report,
        details,
        maps,
    })
}

/// The linear solves between two counts of [`linsolve::stats`], for the log: which path the
/// `harmonic_balance.linear_solver` choice took.
fn solves_line(
    choice: SolverChoice,
    before: linsolve::SolverStats,
    after: linsolve::SolverStats,
) -> String {
    let structured = after.structured - before.structured;
    let rank = after.rank_sum - before.rank_sum;
    let size = after.size_sum - before.size_sum;
    let mut line = format!(
        "linear solver {choice:?}: {} solves by the dense LU, {structured} structured",
        after.dense - before.dense
    );
    if structured > 0 {
        line += &format!(
            " (block LUs per harmonic, low-rank correction of mean rank {:.1} % of the unknowns)",
            100.0 * rank as f64 / size.max(1) as f64
        );
    }
    let fallbacks = after.fallbacks - before.fallbacks;
    if fallbacks > 0 {
        line += &format!(", {fallbacks} structured attempts fell back to the dense LU");
    }
    line + &format!(
        "; {} factorisations",
        after.factorizations - before.factorizations
    )
}

/// The frequencies (Hz) of a curve's points and the first-harmonic amplitudes abs(Q⁽¹⁾) of its
/// response DOFs, `amplitude[p][r]` (0 when H = 0).
fn curve_amplitudes(frf: &FrfData) -> (Vec<f64>, Vec<Vec<f64>>) {
    let hz = frf.points.iter().map(|p| p.omega / (2.0 * PI)).collect();
    let h1 = frf.harmonics + 1;
    let amplitude = frf
        .points
        .iter()
        .map(|p| {
            p.harmonics
                .chunks(h1)
                .map(|hs| hs.get(1).map_or(0.0, |h| h.norm()))
                .collect()
        })
        .collect();
    (hz, amplitude)
}

/// "FRF" or "sweep 2 (contact.shroud.n0 = 150)".
fn curve_label(index: usize, params: &BTreeMap<String, f64>) -> String {
    if params.is_empty() {
        return "FRF".into();
    }
    let values: Vec<String> = params.iter().map(|(k, v)| format!("{k} = {v}")).collect();
    format!("sweep {index} ({})", values.join(", "))
}
