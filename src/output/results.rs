//! The results file of `nlrom solve`, `march` and `run` (`docs/results-file.md`): plain
//! data types the solvers fill, a writer and a reader.
//!
//! The solvers fill a [`ResultsFile`]: one [`FrfData`] per sweep point (one without a sweep),
//! one [`ContactData`] per contact interface, and a [`MarchData`] for a time-marching run;
//! [`write_results`] checks the sizes and writes the layout below atomically.
//!
//! | path | type \[shape\] | unit | content |
//! |---|---|---|---|
//! | `/frf/<i>` attributes | | | `harmonics` H, `sweep_parameters` (names), one attribute per sweep parameter (its value) |
//! | `/frf/<i>/omega` | f64 \[P\] | rad/s | excitation frequency of each point, path order |
//! | `/frf/<i>/frequency_hz` | f64 \[P\] | Hz | ω/2π |
//! | `/frf/<i>/amplitude` | f64 [P, R] | m | first-harmonic amplitude abs(Q⁽¹⁾) of each response DOF |
//! | `/frf/<i>/peak` | f64 [P, R] | m | max over the period of abs(q(t)) |
//! | `/frf/<i>/harmonics` | complex [P, R, H+1] | m | Q⁽ⁿ⁾, q(τ) = Re Σ Q⁽ⁿ⁾ e^{inτ} (`docs/conventions.md` §4) |
//! | `/frf/<i>/response_dofs` | compound \[R\] {kind enum(node, row), node_tag u64, component i64} | 1 | node tag and component 0/1/2, or matrix row (component −1) |
//! | `/frf/<i>/arc_length` | f64 \[P\] | 1 | continuation arc length |
//! | `/frf/<i>/newton_iterations` | u64 \[P\] | 1 | Newton iterations of each point |
//! | `/frf/<i>/residual` | f64 \[P\] | 1 | accepted scaled residual ‖r‖₂/r_s of each point (≤ the tolerance) |
//! | `/frf/<i>/stable` | i64 \[P\] | 1 | 1 stable, 0 unstable (only when computed) |
//! | `/frf/<i>/jumps` | u64 \[J\] | 1 | index of the first point after each jump of the sweep (only when it jumped) |
//! | `/contact` attributes | | | `names`: the interfaces in the order of the points' contact fractions |
//! | `/contact/<name>` attributes | | | `model`, `coupling` (array, interpolated), `element`, `sigma`, `mu` |
//! | `/contact/<name>/pairs` | compound \[E\] {contact_node u64, target_node u64} | 1 | the node-to-node elements (c, t_j) |
//! | `/contact/<name>/weights`, `kt`, `kn`, `preload` | f64 \[E\] | 1, N/m, N/m, N | w_j, k_tj, k_nj, n0_j of each element (SAMA eq. 29–31) |
//! | `/contact/<name>/frames` | f64 [E, 3, 3] | 1 | local frame, rows t1, t2, n (global axes) |
//! | `/contact/<name>/state_fractions/<i>` | f64 [P, 3] | 1 | per point of `/frf/<i>`: fractions of the period in stick, slip, separation, averaged over the elements |
//! | `/contact/<name>/virtual_points` | f64 [E, 3] | m | virtual node t_v of each element's contact node (on the placed target surface) |
//! | `/contact/<name>/elements/<i>/fractions` | f64 [P, E, 3] | 1 | per point of `/frf/<i>` and element: stick, slip, separation fractions |
//! | `/contact/<name>/elements/<i>/dissipated_energy` | f64 [P, E] | J | energy dissipated per cycle by each element |
//! | `/contact/<name>/elements/<i>/loop_u`, `loop_force` | f64 [E, N_t, 2] | m, N | hysteresis loops at point `loop_point` (attribute; the resonance peak): u1, u2 and f1, f2 over the last period |
//! | `/contact/<name>/elements/<i>/loop_approach`, `loop_normal_force` | f64 [E, N_t] | m, N | normal approach v and normal force f_n at the same point |
//! | `/contact/<name>/map/<k>` | group | | stick–slip–separation map k of a `[[strip]]` at the peak of a curve or at a chosen frequency ([`ContactMap`]): `phase` \[N_θ\], `position` \[E\], `state` and `friction_ratio` [E, N_θ], `transition_offsets` \[E + 1\], `transition_angles` and `transition_states` \[T\] |
//! | `/march` attributes | | | `scheme`, `wall_seconds`, `omega` (rad/s), `frequency_hz`, `steps` |
//! | `/march/time` | f64 \[T\] | s | instants |
//! | `/march/response` | f64 [T, R] | m | response DOFs (`/march/response_dofs`) |
//! | `/march/response_dofs` | compound \[R\] | 1 | as `/frf/<i>/response_dofs` |
//! | `/march/contact_force` | f64 [T, E, 2] | N | per element (f_t, f_n) |
//! | `/march/contact_state` | i64 [T, E] | 1 | per element 0 separated, 1 stick, 2 slip +, 3 slip − |
//! | `/march/element_names` | strings \[E\] | 1 | the friction elements |
//! | `/march/first_harmonic_last_period` | f64 \[R\] | m | abs(Q⁽¹⁾) of each response DOF over the last period |
//! | `/march/iterations_per_step` | u64 \[T\] | 1 | corrector iterations of each step |
//! | `/march/<other>` | | | [`MarchData::extra`]: the marcher's further datasets and attributes |

use std::collections::BTreeMap;
use std::f64::consts::PI;
use std::path::Path;

use faer::c64;

use super::h5::{Attr, Column, Data, Dataset, Group, H5File, H5Reader, Records};
use super::{check_file_kind, file_attributes, FileInfo};
use crate::error::{Error, Result};

/// Root attribute `file_kind` of a results file.
pub const RESULTS_KIND: &str = "results";

/// Labels of `contact_state` codes, by code.
pub const STATE_LABELS: [&str; 4] = ["separated", "stick", "slip+", "slip-"];
/// Column labels of `state_fractions`.
pub const FRACTION_LABELS: [&str; 3] = ["stick", "slip", "separation"];
const RESPONSE_KINDS: [&str; 2] = ["node", "row"];

/// One response DOF: a node component of a mesh model, or a row of a matrix model.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ResponseDof {
    /// Gmsh node tag and component 0/1/2 = x/y/z.
    Node { tag: u64, component: u8 },
    /// A matrix row (0-based) of a case defined by matrices.
    Row(u64),
}

/// One point of a frequency response curve.
#[derive(Clone, Debug, PartialEq)]
pub struct FrfRecord {
    /// Excitation frequency ω (rad/s).
    pub omega: f64,
    /// Harmonics Q⁽ⁿ⁾ (m), n = 0..=H, response-major: `harmonics[r * (H + 1) + n]`.
    pub harmonics: Vec<c64>,
    /// max over one period of abs(q_r(t)) (m), one per response DOF.
    pub peak: Vec<f64>,
    /// Continuation arc length at this point (dimensionless, as the continuation defines it).
    pub arc_length: f64,
    /// Newton iterations the point took.
    pub newton_iterations: u64,
    /// The accepted scaled residual ‖r‖₂ / r_s (≤ the Newton tolerance; NaN when read from a
    /// file written without it).
    pub residual: f64,
    /// Stability, when computed (the same for all points of a curve: all `Some` or all `None`).
    pub stable: Option<bool>,
    /// Per contact interface (in the order of [`ResultsFile::contacts`]): the fractions of the
    /// period in stick, slip and separation, averaged over the interface's elements.
    pub contact_fractions: Vec<[f64; 3]>,
}

/// One frequency response curve (one sweep point).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FrfData {
    /// The sweep parameters of this curve and their values (e.g. `"contact.shroud.n0"` → 113.0);
    /// empty without a sweep.
    pub sweep: BTreeMap<String, f64>,
    /// Number of harmonics H (each point has H + 1 harmonics per response DOF).
    pub harmonics: usize,
    /// The response DOFs, R of them.
    pub response_dofs: Vec<ResponseDof>,
    /// The points, in path order (ω may go back and forth at a fold).
    pub points: Vec<FrfRecord>,
    /// Indices in `points` of the first point after each jump of the sweep (where the path had
    /// left its range on the start side and went on from the next frequency); empty without.
    pub jumps: Vec<usize>,
}

/// One node-to-node friction element (c, t_j) of a contact interface.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactPairData {
    /// Gmsh tag of the contact node c.
    pub contact_node: u64,
    /// Gmsh tag of the target node t_j.
    pub target_node: u64,
    /// SAMA weight w_j (eq. 29; 1 for node-to-node).
    pub weight: f64,
    /// Local frame, rows t1, t2, n (`docs/conventions.md` §3).
    pub frame: [[f64; 3]; 3],
    /// Tangential stiffness k_tj (N/m).
    pub kt: f64,
    /// Normal stiffness k_nj (N/m).
    pub kn: f64,
    /// Static normal preload n0_j (N).
    pub preload: f64,
    /// The virtual node t_v of the contact node (m): its projection on the placed target
    /// surface, within the contact distance of the contact node (for maps of the contact face).
    pub virtual_point: [f64; 3],
}

/// Per-element detail of one contact interface on one curve (`/frf/<i>`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContactCurveDetail {
    /// Fractions of the period in stick, slip, separation, point-major: `[p * E + e]`.
    pub fractions: Vec<[f64; 3]>,
    /// Energy dissipated per cycle by each element (J), point-major: `[p * E + e]`.
    pub dissipated_energy: Vec<f64>,
    /// The hysteresis loops of every element at one point of the curve (the resonance peak).
    pub loops: Option<PointLoops>,
}

/// The hysteresis loops of the E elements of an interface at one FRF point: the last period of
/// the time-discrete law, N_t samples τ_j = 2πj/N_t (`contact::element::HysteresisLoop`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointLoops {
    /// Index of the point in `/frf/<i>`.
    pub point: usize,
    /// Samples per period N_t.
    pub samples: usize,
    /// Tangential relative displacements u1, u2 (m): `[(e * N_t + j) * 2 + d]`.
    pub u: Vec<f64>,
    /// Tangential forces f1, f2 (N), laid out as `u`.
    pub force: Vec<f64>,
    /// Normal approach v (m): `[e * N_t + j]`.
    pub approach: Vec<f64>,
    /// Normal force f_n (N), laid out as `approach`.
    pub normal_force: Vec<f64>,
}

/// One contact interface (`[[contact]]`).
#[derive(Clone, Debug, PartialEq)]
pub struct ContactData {
    /// The interface's name.
    pub name: String,
    /// `"sama"` or `"node-to-node"`.
    pub model: String,
    /// SAMA coupling: `"array"` (eq. 31, one element per c–t_j) or `"interpolated"` (one element
    /// per contact node on its interpolated virtual node).
    pub coupling: String,
    /// `"1d"` or `"2d"`.
    pub element: String,
    /// Sector offset σ of the target (`docs/conventions.md` §3).
    pub sigma: i64,
    /// Friction coefficient μ.
    pub mu: f64,
    /// The elements.
    pub pairs: Vec<ContactPairData>,
    /// Per-element detail per curve, in the order of [`ResultsFile::frfs`] (empty: not recorded).
    pub curves: Vec<ContactCurveDetail>,
}

/// A stick–slip–separation map of a friction strip at one point of a curve
/// (`/contact/<name>/map/<k>`, [`crate::contact::slip_map`]): E points, N_θ phase angles.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ContactMap {
    /// The strip's name.
    pub name: String,
    /// Friction coefficient μ.
    pub mu: f64,
    /// Index of the curve in [`ResultsFile::frfs`].
    pub curve: usize,
    /// Index of the point in that curve (the resonance peak, or a point at a chosen frequency).
    pub point: usize,
    /// Excitation frequency ω of the point (rad/s).
    pub omega: f64,
    /// Position s of each point along the strip (m), \[E\].
    pub position: Vec<f64>,
    /// Phase angles τ_j = 2πj/N_θ of the excitation F cos τ (rad), \[N_θ\].
    pub phase: Vec<f64>,
    /// State per point and angle, `[e * N_θ + j]`: 0 stick, 1 positive slip, −1 negative slip,
    /// 2 separation.
    pub state: Vec<i64>,
    /// f/(μn) per point and angle, laid out as `state`; NaN where μn = 0.
    pub friction_ratio: Vec<f64>,
    /// Point e's transitions are entries `transition_offsets[e]..transition_offsets[e + 1]` of
    /// `transition_angles` and `transition_states` (E + 1 offsets).
    pub transition_offsets: Vec<u64>,
    /// Transition angles τ (rad, in [0, 2π), ascending per point).
    pub transition_angles: Vec<f64>,
    /// The state entered at each transition (codes of `state`).
    pub transition_states: Vec<i64>,
}

/// Labels of the map state codes −1, 0, 1, 2 (attribute `labels` of `state`, in code order).
pub const MAP_STATE_LABELS: [&str; 4] = ["slip-", "stick", "slip+", "separated"];

/// A time-marching run.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MarchData {
    /// The scheme (`newmark`, `adaptive`, `piecewise-linear`, `quasi-static`).
    pub scheme: String,
    /// Wall time of the march (s).
    pub wall_seconds: f64,
    /// Excitation frequency ω (rad/s).
    pub omega: f64,
    /// Accepted time steps.
    pub steps: u64,
    /// The response DOFs, R of them.
    pub response_dofs: Vec<ResponseDof>,
    /// Instants (s), T of them.
    pub time: Vec<f64>,
    /// Responses (m), [T × R] row-major.
    pub response: Vec<f64>,
    /// Names of the friction elements, E of them.
    pub element_names: Vec<String>,
    /// Per element (f_t, f_n) (N), [T × E × 2] row-major.
    pub contact_force: Vec<f64>,
    /// Per element state code (0 separated, 1 stick, 2 slip+, 3 slip−), [T × E].
    pub contact_state: Vec<u8>,
    /// abs(Q⁽¹⁾) of each response DOF over the last period (m), \[R\].
    pub first_harmonic_last_period: Vec<f64>,
    /// Corrector iterations of each step, \[T\].
    pub iterations_per_step: Vec<u64>,
    /// Further datasets and attributes of `/march` beyond the layout above (the marcher's loops,
    /// histograms, periodicity record, …), written and read back verbatim; their names must not
    /// clash with the layout's.
    pub extra: Group,
}

/// Everything a results file holds.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ResultsFile {
    /// Case title and text (root attributes).
    pub info: FileInfo,
    /// Frequency responses, `/frf/0`, `/frf/1`, … in sweep order.
    pub frfs: Vec<FrfData>,
    /// Contact interfaces, `/contact/<name>`.
    pub contacts: Vec<ContactData>,
    /// The time-marching run, `/march`.
    pub march: Option<MarchData>,
    /// Stick–slip–separation maps of friction strips, `/contact/<name>/map/<k>` (read back
    /// sorted by name, then curve).
    pub maps: Vec<ContactMap>,
}

/// Writes `results` to `path` atomically. Fails (exit status 1, naming the curve or element) when
/// the sizes are inconsistent.
pub fn write_results(path: &Path, results: &ResultsFile) -> Result<()> {
    results_file(results)?.write(path)
}

/// The in-memory HDF5 file of `results`.
pub fn results_file(results: &ResultsFile) -> Result<H5File> {
    let mut file = H5File {
        root: file_attributes(&results.info, RESULTS_KIND),
    };
    for (i, frf) in results.frfs.iter().enumerate() {
        check_frf(frf, i, results.contacts.len())?;
        frf_group(file.root.group("frf").group(&i.to_string()), frf);
    }
    for contact in &results.contacts {
        contact_group(file.root.group("contact"), contact, &results.frfs)?;
    }
    if !results.contacts.is_empty() {
        let names = results.contacts.iter().map(|c| c.name.clone()).collect();
        file.root
            .group("contact")
            .set_attr("names", Attr::Strs(names));
    }
    for map in &results.maps {
        map_group(file.root.group("contact"), map, &results.frfs)?;
    }
    if !results.maps.is_empty() {
        let mut names: Vec<String> = results.maps.iter().map(|m| m.name.clone()).collect();
        names.sort();
        names.dedup();
        file.root
            .group("contact")
            .set_attr("maps", Attr::Strs(names));
    }
    if let Some(march) = &results.march {
        check_march(march)?;
        march_group(file.root.group("march"), march);
    }
    Ok(file)
}

fn size_error(what: String) -> Error {
    Error::Compute(format!("results file: {what}"))
}

fn check_frf(frf: &FrfData, i: usize, contacts: usize) -> Result<()> {
    let r = frf.response_dofs.len();
    let per_point = r * (frf.harmonics + 1);
    let some_stable = frf.points.iter().filter(|p| p.stable.is_some()).count();
    if some_stable != 0 && some_stable != frf.points.len() {
        return Err(size_error(format!(
            "/frf/{i}: stability is given for {some_stable} of {} points (all or none)",
            frf.points.len()
        )));
    }
    let ordered = frf.jumps.windows(2).all(|w| w[0] < w[1]);
    if !ordered || frf.jumps.iter().any(|&j| j == 0 || j >= frf.points.len()) {
        return Err(size_error(format!(
            "/frf/{i}: jumps at points {:?} of {} (increasing, each after the first point)",
            frf.jumps,
            frf.points.len()
        )));
    }
    for (p, point) in frf.points.iter().enumerate() {
        if point.harmonics.len() != per_point || point.peak.len() != r {
            return Err(size_error(format!(
                "/frf/{i} point {p}: {} harmonics and {} peaks, expected {per_point} (R = {r}, H = {}) and {r}",
                point.harmonics.len(),
                point.peak.len(),
                frf.harmonics
            )));
        }
        if point.contact_fractions.len() != contacts {
            return Err(size_error(format!(
                "/frf/{i} point {p}: contact fractions for {} interfaces, the file has {contacts}",
                point.contact_fractions.len()
            )));
        }
    }
    Ok(())
}

fn response_dofs_dataset(dofs: &[ResponseDof]) -> Dataset {
    let mut kind = Vec::with_capacity(dofs.len());
    let mut tag = Vec::with_capacity(dofs.len());
    let mut component = Vec::with_capacity(dofs.len());
    for dof in dofs {
        let (k, t, c) = match *dof {
            ResponseDof::Node { tag, component } => (0, tag, i64::from(component)),
            ResponseDof::Row(row) => (1, row, -1),
        };
        kind.push(k);
        tag.push(t);
        component.push(c);
    }
    let records = Records::new()
        .column(
            "kind",
            Column::Enum {
                labels: RESPONSE_KINDS.iter().map(|s| s.to_string()).collect(),
                codes: kind,
            },
        )
        .column("node_tag", Column::U64(tag))
        .column("component", Column::I64(component));
    Dataset::records(
        records,
        "1",
        "response DOFs: kind node (node_tag = Gmsh tag, component 0/1/2 = x/y/z) or row (node_tag = matrix row, component -1)",
    )
}

fn frf_group(group: &mut Group, frf: &FrfData) {
    let p = frf.points.len();
    let r = frf.response_dofs.len();
    let h1 = frf.harmonics + 1;
    group
        .set_attr("harmonics", Attr::U64(frf.harmonics as u64))
        .set_attr(
            "sweep_parameters",
            Attr::Strs(frf.sweep.keys().cloned().collect()),
        );
    for (name, value) in &frf.sweep {
        group.set_attr(name, Attr::F64(*value));
    }
    let omega: Vec<f64> = frf.points.iter().map(|q| q.omega).collect();
    let hz = omega.iter().map(|w| w / (2.0 * PI)).collect();
    group.add(
        "omega",
        Dataset::f64s(omega, "rad/s", "excitation frequency, path order"),
    );
    group.add(
        "frequency_hz",
        Dataset::f64s(hz, "Hz", "excitation frequency omega/(2 pi)"),
    );
    let amplitude = frf
        .points
        .iter()
        .flat_map(|q| (0..r).map(move |j| first_harmonic(&q.harmonics, j, h1)))
        .collect();
    group.add(
        "amplitude",
        Dataset::new(
            &[p, r],
            Data::F64(amplitude),
            "m",
            "first-harmonic amplitude abs(Q1) of each response DOF",
        ),
    );
    let peak = frf.points.iter().flat_map(|q| q.peak.clone()).collect();
    group.add(
        "peak",
        Dataset::new(
            &[p, r],
            Data::F64(peak),
            "m",
            "max over the period of abs(q(t)) of each response DOF",
        ),
    );
    let harmonics = frf
        .points
        .iter()
        .flat_map(|q| q.harmonics.clone())
        .collect();
    group.add(
        "harmonics",
        Dataset::new(
            &[p, r, h1],
            Data::Complex(harmonics),
            "m",
            "harmonics Q_n, n = 0..H: q(tau) = Re sum Q_n exp(i n tau), tau = omega t",
        ),
    );
    group.add("response_dofs", response_dofs_dataset(&frf.response_dofs));
    group.add(
        "arc_length",
        Dataset::f64s(
            frf.points.iter().map(|q| q.arc_length).collect(),
            "1",
            "continuation arc length",
        ),
    );
    group.add(
        "newton_iterations",
        Dataset::u64s(
            frf.points.iter().map(|q| q.newton_iterations).collect(),
            "1",
            "Newton iterations of each point",
        ),
    );
    group.add(
        "residual",
        Dataset::f64s(
            frf.points.iter().map(|q| q.residual).collect(),
            "1",
            "accepted scaled residual of each point",
        ),
    );
    let stable: Option<Vec<i64>> = frf.points.iter().map(|q| q.stable.map(i64::from)).collect();
    if let (Some(stable), false) = (stable, frf.points.is_empty()) {
        group.add("stable", Dataset::i64s(stable, "1", "1 stable, 0 unstable"));
    }
    if !frf.jumps.is_empty() {
        group.add(
            "jumps",
            Dataset::u64s(
                frf.jumps.iter().map(|&j| j as u64).collect(),
                "1",
                "index of the first point after each jump of the sweep",
            ),
        );
    }
}

/// abs(Q⁽¹⁾) of response DOF `j` (0 when H = 0).
fn first_harmonic(harmonics: &[c64], j: usize, h1: usize) -> f64 {
    if h1 < 2 {
        return 0.0;
    }
    harmonics[j * h1 + 1].norm()
}

fn contact_group(parent: &mut Group, contact: &ContactData, frfs: &[FrfData]) -> Result<()> {
    if parent.groups.contains_key(&contact.name) {
        return Err(size_error(format!(
            "two contact interfaces named {:?}",
            contact.name
        )));
    }
    let index = parent.groups.len();
    let group = parent.group(&contact.name);
    group
        .set_attr("model", Attr::Str(contact.model.clone()))
        .set_attr("coupling", Attr::Str(contact.coupling.clone()))
        .set_attr("element", Attr::Str(contact.element.clone()))
        .set_attr("sigma", Attr::I64(contact.sigma))
        .set_attr("mu", Attr::F64(contact.mu));
    let pairs = &contact.pairs;
    let records = Records::new()
        .column(
            "contact_node",
            Column::U64(pairs.iter().map(|p| p.contact_node).collect()),
        )
        .column(
            "target_node",
            Column::U64(pairs.iter().map(|p| p.target_node).collect()),
        );
    group.add(
        "pairs",
        Dataset::records(
            records,
            "1",
            "node-to-node elements: Gmsh tags of the contact node c and the target node t_j",
        ),
    );
    let column = |f: fn(&ContactPairData) -> f64| pairs.iter().map(f).collect::<Vec<f64>>();
    group.add(
        "weights",
        Dataset::f64s(column(|p| p.weight), "1", "SAMA weight w_j (eq. 29)"),
    );
    group.add(
        "kt",
        Dataset::f64s(column(|p| p.kt), "N/m", "tangential stiffness k_tj"),
    );
    group.add(
        "kn",
        Dataset::f64s(column(|p| p.kn), "N/m", "normal stiffness k_nj"),
    );
    group.add(
        "preload",
        Dataset::f64s(column(|p| p.preload), "N", "static normal preload n0_j"),
    );
    let frames = pairs
        .iter()
        .flat_map(|p| p.frame.iter().flatten().copied())
        .collect();
    group.add(
        "frames",
        Dataset::new(
            &[pairs.len(), 3, 3],
            Data::F64(frames),
            "1",
            "local frame of each element, rows t1, t2, n (global axes)",
        ),
    );
    let points = pairs
        .iter()
        .flat_map(|p| p.virtual_point.iter().copied())
        .collect();
    group.add(
        "virtual_points",
        Dataset::new(
            &[pairs.len(), 3],
            Data::F64(points),
            "m",
            "virtual node t_v of each element's contact node (its projection on the placed target surface)",
        ),
    );
    for (i, detail) in contact.curves.iter().enumerate() {
        let p = frfs.get(i).map_or(0, |f| f.points.len());
        check_detail(contact, detail, i, p)?;
        detail_group(
            group.group("elements").group(&i.to_string()),
            detail,
            p,
            pairs.len(),
        );
    }
    for (i, frf) in frfs.iter().enumerate() {
        let fractions = frf
            .points
            .iter()
            .flat_map(|p| p.contact_fractions[index])
            .collect();
        group.group("state_fractions").add(
            &i.to_string(),
            Dataset::new(
                &[frf.points.len(), 3],
                Data::F64(fractions),
                "1",
                "per point of /frf/<i>: fractions of the period in stick, slip, separation",
            )
            .with_attr(
                "columns",
                Attr::Strs(FRACTION_LABELS.iter().map(|s| s.to_string()).collect()),
            ),
        );
    }
    Ok(())
}

/// `/contact/<name>/map/<k>` of one map, k the number of maps of `<name>` written before it
/// (with `model = "strip"` and `mu` on a new `/contact/<name>`).
fn map_group(parent: &mut Group, m: &ContactMap, frfs: &[FrfData]) -> Result<()> {
    let (e, n) = (m.position.len(), m.phase.len());
    let k = parent
        .groups
        .get(&m.name)
        .and_then(|g| g.groups.get("map"))
        .map_or(0, |g| g.groups.len());
    let what = format!("/contact/{}/map/{k} (curve {})", m.name, m.curve);
    let points = frfs.get(m.curve).map(|f| f.points.len());
    if points.is_none_or(|p| m.point >= p) {
        return Err(size_error(format!(
            "{what}: point {} of a curve with {points:?} points",
            m.point
        )));
    }
    let transitions = m.transition_angles.len();
    if m.state.len() != e * n
        || m.friction_ratio.len() != e * n
        || m.transition_offsets.len() != e + 1
        || m.transition_offsets.last().copied() != Some(transitions as u64)
        || m.transition_offsets.windows(2).any(|w| w[1] < w[0])
        || m.transition_states.len() != transitions
    {
        return Err(size_error(format!(
            "{what}: inconsistent sizes for {e} points and {n} phase angles"
        )));
    }
    let fresh = !parent.groups.contains_key(&m.name);
    let group = parent.group(&m.name);
    if fresh {
        group
            .set_attr("model", Attr::Str("strip".into()))
            .set_attr("mu", Attr::F64(m.mu));
    }
    let g = group.group("map").group(&k.to_string());
    g.set_attr("curve", Attr::U64(m.curve as u64))
        .set_attr("point", Attr::U64(m.point as u64))
        .set_attr("omega", Attr::F64(m.omega));
    g.add(
        "phase",
        Dataset::f64s(
            m.phase.clone(),
            "rad",
            "phase angles τ_j = 2πj/N_θ of the excitation F cos τ",
        ),
    );
    g.add(
        "position",
        Dataset::f64s(
            m.position.clone(),
            "m",
            "position s of each point along the strip",
        ),
    );
    g.add(
        "state",
        Dataset::new(
            &[e, n],
            Data::I64(m.state.clone()),
            "1",
            "state per point and phase angle: -1 negative slip, 0 stick, 1 positive slip, 2 separation",
        )
        .with_attr(
            "labels",
            Attr::Strs(MAP_STATE_LABELS.iter().map(|s| s.to_string()).collect()),
        ),
    );
    g.add(
        "friction_ratio",
        Dataset::new(
            &[e, n],
            Data::F64(m.friction_ratio.clone()),
            "1",
            "friction force over its limit f/(μn) per point and phase angle (NaN where μn = 0)",
        ),
    );
    g.add(
        "transition_offsets",
        Dataset::u64s(
            m.transition_offsets.clone(),
            "1",
            "point e's transitions are entries offsets[e]..offsets[e+1] of transition_angles and transition_states",
        ),
    );
    g.add(
        "transition_angles",
        Dataset::f64s(
            m.transition_angles.clone(),
            "rad",
            "exact transition angles of each point's cycle, ascending per point, in [0, 2π)",
        ),
    );
    g.add(
        "transition_states",
        Dataset::i64s(
            m.transition_states.clone(),
            "1",
            "the state entered at each transition (codes of state)",
        ),
    );
    Ok(())
}

fn check_detail(contact: &ContactData, d: &ContactCurveDetail, i: usize, p: usize) -> Result<()> {
    let e = contact.pairs.len();
    let what = format!("/contact/{}/elements/{i}", contact.name);
    if d.fractions.len() != p * e || d.dissipated_energy.len() != p * e {
        return Err(size_error(format!(
            "{what}: {} fractions and {} energies, expected P × E = {p} × {e}",
            d.fractions.len(),
            d.dissipated_energy.len()
        )));
    }
    if let Some(l) = &d.loops {
        let n = e * l.samples;
        if l.point >= p
            || l.u.len() != 2 * n
            || l.force.len() != 2 * n
            || l.approach.len() != n
            || l.normal_force.len() != n
        {
            return Err(size_error(format!(
                "{what}: loops at point {} of {p} with sizes {}/{}/{}/{}, expected E × N_t = {e} × {}",
                l.point,
                l.u.len(),
                l.force.len(),
                l.approach.len(),
                l.normal_force.len(),
                l.samples
            )));
        }
    }
    Ok(())
}

/// `/contact/<name>/elements/<i>`: per-element fractions and energies per point, the loops.
fn detail_group(group: &mut Group, d: &ContactCurveDetail, p: usize, e: usize) {
    let fractions = d.fractions.iter().flatten().copied().collect();
    group.add(
        "fractions",
        Dataset::new(
            &[p, e, 3],
            Data::F64(fractions),
            "1",
            "per point of /frf/<i> and element: fractions of the period in stick, slip, separation",
        )
        .with_attr(
            "columns",
            Attr::Strs(FRACTION_LABELS.iter().map(|s| s.to_string()).collect()),
        ),
    );
    group.add(
        "dissipated_energy",
        Dataset::new(
            &[p, e],
            Data::F64(d.dissipated_energy.clone()),
            "J",
            "energy dissipated per cycle by each element",
        ),
    );
    let Some(l) = &d.loops else { return };
    let n_t = l.samples;
    group.set_attr("loop_point", Attr::U64(l.point as u64));
    let datasets = [
        (
            "loop_u",
            &l.u,
            2,
            "m",
            "tangential relative displacements u1, u2 over the last period",
        ),
        (
            "loop_force",
            &l.force,
            2,
            "N",
            "tangential forces f1, f2 over the last period",
        ),
        (
            "loop_approach",
            &l.approach,
            1,
            "m",
            "normal approach v over the last period",
        ),
        (
            "loop_normal_force",
            &l.normal_force,
            1,
            "N",
            "normal force f_n over the last period",
        ),
    ];
    for (name, values, dirs, unit, what) in datasets {
        let shape: Vec<usize> = if dirs == 2 {
            vec![e, n_t, 2]
        } else {
            vec![e, n_t]
        };
        group.add(
            name,
            Dataset::new(&shape, Data::F64(values.clone()), unit, what)
                .with_attr("point", Attr::U64(l.point as u64)),
        );
    }
}

/// Dataset and attribute names of `/march` that [`MarchData`]'s typed fields own.
const MARCH_DATASETS: [&str; 8] = [
    "time",
    "iterations_per_step",
    "response",
    "response_dofs",
    "contact_force",
    "contact_state",
    "element_names",
    "first_harmonic_last_period",
];
const MARCH_ATTRS: [&str; 5] = ["scheme", "wall_seconds", "omega", "frequency_hz", "steps"];

fn check_march(m: &MarchData) -> Result<()> {
    let owned = |name: &String| {
        MARCH_DATASETS.contains(&name.as_str()) || MARCH_ATTRS.contains(&name.as_str())
    };
    if let Some(name) = m
        .extra
        .datasets
        .keys()
        .chain(m.extra.attrs.keys())
        .find(|n| owned(n))
    {
        return Err(size_error(format!(
            "/march/{name}: an extra dataset or attribute takes the name of a layout one"
        )));
    }
    if let Some(name) = m.extra.groups.keys().next() {
        return Err(size_error(format!(
            "/march/{name}: extra sub-groups are not written"
        )));
    }
    let t = m.time.len();
    let r = m.response_dofs.len();
    let e = m.element_names.len();
    let checks = [
        ("response", m.response.len(), t * r),
        ("contact_force", m.contact_force.len(), t * e * 2),
        ("contact_state", m.contact_state.len(), t * e),
        (
            "first_harmonic_last_period",
            m.first_harmonic_last_period.len(),
            r,
        ),
        ("iterations_per_step", m.iterations_per_step.len(), t),
    ];
    for (name, got, expected) in checks {
        if got != expected {
            return Err(size_error(format!(
                "/march/{name}: {got} values, expected {expected} (T = {t}, R = {r}, E = {e})"
            )));
        }
    }
    Ok(())
}

fn march_group(group: &mut Group, m: &MarchData) {
    let t = m.time.len();
    let r = m.response_dofs.len();
    let e = m.element_names.len();
    for (name, d) in &m.extra.datasets {
        group.add(name, d.clone());
    }
    for (name, a) in &m.extra.attrs {
        group.set_attr(name, a.clone());
    }
    group
        .set_attr("scheme", Attr::Str(m.scheme.clone()))
        .set_attr("wall_seconds", Attr::F64(m.wall_seconds))
        .set_attr("omega", Attr::F64(m.omega))
        .set_attr("frequency_hz", Attr::F64(m.omega / (2.0 * PI)))
        .set_attr("steps", Attr::U64(m.steps));
    group.add("time", Dataset::f64s(m.time.clone(), "s", "instants"));
    group.add(
        "response",
        Dataset::new(
            &[t, r],
            Data::F64(m.response.clone()),
            "m",
            "displacement of each response DOF",
        ),
    );
    group.add("response_dofs", response_dofs_dataset(&m.response_dofs));
    group.add(
        "contact_force",
        Dataset::new(
            &[t, e, 2],
            Data::F64(m.contact_force.clone()),
            "N",
            "per friction element (f_t, f_n)",
        ),
    );
    group.add(
        "contact_state",
        Dataset::new(
            &[t, e],
            Data::I64(m.contact_state.iter().map(|&s| i64::from(s)).collect()),
            "1",
            "per friction element: 0 separated, 1 stick, 2 slip +, 3 slip -",
        )
        .with_attr(
            "labels",
            Attr::Strs(STATE_LABELS.iter().map(|s| s.to_string()).collect()),
        ),
    );
    group.add(
        "element_names",
        Dataset::new(
            &[e],
            Data::Strings(m.element_names.clone()),
            "1",
            "friction elements",
        ),
    );
    group.add(
        "first_harmonic_last_period",
        Dataset::f64s(
            m.first_harmonic_last_period.clone(),
            "m",
            "abs(Q1) of each response DOF over the last period",
        ),
    );
    group.add(
        "iterations_per_step",
        Dataset::u64s(
            m.iterations_per_step.clone(),
            "1",
            "corrector iterations of each step",
        ),
    );
}

// ---------------------------------------------------------------------------------------------
// Reading

/// Reads a results file written by [`write_results`]. Errors (exit status 2) name the file and the
/// dataset.
pub fn read_results(path: &Path) -> Result<ResultsFile> {
    let reader = H5Reader::open(path)?;
    let info = check_file_kind(&reader, RESULTS_KIND)?;
    let contact_attrs = if reader.has_group("/contact") {
        reader.attrs("/contact")?
    } else {
        BTreeMap::new()
    };
    let names_attr = |name: &str| match contact_attrs.get(name) {
        None => Ok(Vec::new()),
        Some(Attr::Strs(names)) => Ok(names.clone()),
        Some(other) => Err(reader.error(
            "/contact",
            format!("attribute {name:?} should be strings, found {other:?}"),
        )),
    };
    let contact_names = names_attr("names")?;
    let map_names = names_attr("maps")?;
    if reader.has_group("/contact") && contact_names.is_empty() && map_names.is_empty() {
        return Err(reader.error("/contact", "attribute \"names\" missing"));
    }
    let mut frfs = Vec::new();
    if reader.has_group("/frf") {
        let count = reader.group_names("/frf")?.len();
        for i in 0..count {
            frfs.push(read_frf(&reader, i, &contact_names)?);
        }
    }
    let mut contacts = Vec::new();
    let frf_points: Vec<usize> = frfs.iter().map(|f| f.points.len()).collect();
    for name in &contact_names {
        contacts.push(read_contact(&reader, name, &frf_points)?);
    }
    let march = if reader.has_group("/march") {
        Some(read_march(&reader)?)
    } else {
        None
    };
    let mut maps = Vec::new();
    for name in &map_names {
        let mut keys: Vec<usize> = reader
            .group_names(&format!("/contact/{name}/map"))?
            .iter()
            .filter_map(|c| c.parse().ok())
            .collect();
        keys.sort_unstable();
        for k in keys {
            maps.push(read_map(&reader, name, k)?);
        }
    }
    Ok(ResultsFile {
        info,
        frfs,
        contacts,
        march,
        maps,
    })
}

/// `/contact/<name>/map/<k>`; its curve is the attribute `curve` (files without it have one map
/// per curve, k = the curve).
fn read_map(reader: &H5Reader, name: &str, k: usize) -> Result<ContactMap> {
    let base = format!("/contact/{name}/map/{k}");
    let curve = if reader.attrs(&base)?.contains_key("curve") {
        reader.attr_u64(&base, "curve")? as usize
    } else {
        k
    };
    let at = |n: &str| format!("{base}/{n}");
    let position = reader.f64_vector(&at("position"))?;
    let phase = reader.f64_vector(&at("phase"))?;
    let (e, n) = (position.len(), phase.len());
    let transition_angles = reader.f64_vector(&at("transition_angles"))?;
    let t = transition_angles.len();
    Ok(ContactMap {
        name: name.to_string(),
        mu: reader.attr_f64(&format!("/contact/{name}"), "mu")?,
        curve,
        point: reader.attr_u64(&base, "point")? as usize,
        omega: reader.attr_f64(&base, "omega")?,
        state: reader.i64s(&at("state"), &[e, n])?,
        friction_ratio: reader.f64s(&at("friction_ratio"), &[e, n])?,
        transition_offsets: reader.u64s(&at("transition_offsets"), &[e + 1])?,
        transition_states: reader.i64s(&at("transition_states"), &[t])?,
        transition_angles,
        position,
        phase,
    })
}

fn read_response_dofs(reader: &H5Reader, path: &str) -> Result<Vec<ResponseDof>> {
    let records = reader.records(path, None, &["kind", "node_tag", "component"])?;
    let tags = reader.column(path, &records, "node_tag", Column::as_u64, "u64")?;
    let components = reader.column(path, &records, "component", Column::as_i64, "i64")?;
    let Some(Column::Enum { codes, .. }) = records.get("kind") else {
        return Err(reader.error(path, "field \"kind\" should be an enumeration"));
    };
    let mut dofs = Vec::with_capacity(records.len());
    for j in 0..records.len() {
        dofs.push(match (codes[j], u8::try_from(components[j])) {
            (0, Ok(component)) if component < 3 => ResponseDof::Node {
                tag: tags[j],
                component,
            },
            (1, _) => ResponseDof::Row(tags[j]),
            _ => {
                return Err(reader.error(
                    path,
                    format!("record {j}: node DOF with component {}", components[j]),
                ))
            }
        });
    }
    Ok(dofs)
}

fn read_frf(reader: &H5Reader, i: usize, contact_names: &[String]) -> Result<FrfData> {
    let base = format!("/frf/{i}");
    let harmonics = reader.attr_u64(&base, "harmonics")? as usize;
    let mut sweep = BTreeMap::new();
    if let Attr::Strs(names) = reader.attr(&base, "sweep_parameters")? {
        for name in names {
            let value = reader.attr_f64(&base, &name)?;
            sweep.insert(name, value);
        }
    }
    let response_dofs = read_response_dofs(reader, &format!("{base}/response_dofs"))?;
    let omega = reader.f64_vector(&format!("{base}/omega"))?;
    let (p, r, h1) = (omega.len(), response_dofs.len(), harmonics + 1);
    let values = reader.complexes(&format!("{base}/harmonics"), &[p, r, h1])?;
    let peak = reader.f64s(&format!("{base}/peak"), &[p, r])?;
    let arc = reader.f64s(&format!("{base}/arc_length"), &[p])?;
    let newton = reader.u64s(&format!("{base}/newton_iterations"), &[p])?;
    let residual = if reader.group(&base)?.datasets.contains_key("residual") {
        reader.f64s(&format!("{base}/residual"), &[p])?
    } else {
        vec![f64::NAN; p]
    };
    let stable = if reader.group(&base)?.datasets.contains_key("stable") {
        Some(reader.i64s(&format!("{base}/stable"), &[p])?)
    } else {
        None
    };
    let jumps = match reader.group(&base)?.datasets.get("jumps") {
        Some(d) => {
            let jumps = reader.u64s(&format!("{base}/jumps"), &[d.shape[0]])?;
            if let Some(bad) = jumps.iter().find(|&&j| j == 0 || j as usize >= p) {
                return Err(reader.error(
                    &format!("{base}/jumps"),
                    format!("jump at point {bad}: not a point after the first of {p}"),
                ));
            }
            jumps.into_iter().map(|j| j as usize).collect()
        }
        None => Vec::new(),
    };
    let mut fractions = Vec::with_capacity(contact_names.len());
    for name in contact_names {
        fractions.push(reader.f64s(&format!("/contact/{name}/state_fractions/{i}"), &[p, 3])?);
    }
    let points = (0..p)
        .map(|q| FrfRecord {
            omega: omega[q],
            harmonics: values[q * r * h1..(q + 1) * r * h1].to_vec(),
            peak: peak[q * r..(q + 1) * r].to_vec(),
            arc_length: arc[q],
            newton_iterations: newton[q],
            residual: residual[q],
            stable: stable.as_ref().map(|s| s[q] != 0),
            contact_fractions: fractions
                .iter()
                .map(|f| [f[3 * q], f[3 * q + 1], f[3 * q + 2]])
                .collect(),
        })
        .collect();
    Ok(FrfData {
        sweep,
        harmonics,
        response_dofs,
        points,
        jumps,
    })
}

fn read_contact(reader: &H5Reader, name: &str, frf_points: &[usize]) -> Result<ContactData> {
    let base = format!("/contact/{name}");
    let path = format!("{base}/pairs");
    let records = reader.records(&path, None, &["contact_node", "target_node"])?;
    let e = records.len();
    let contact = reader.column(&path, &records, "contact_node", Column::as_u64, "u64")?;
    let target = reader.column(&path, &records, "target_node", Column::as_u64, "u64")?;
    let column = |n: &str| reader.f64s(&format!("{base}/{n}"), &[e]);
    let (weight, kt, kn, preload) = (
        column("weights")?,
        column("kt")?,
        column("kn")?,
        column("preload")?,
    );
    let frames = reader.f64s(&format!("{base}/frames"), &[e, 3, 3])?;
    let points = reader.f64s(&format!("{base}/virtual_points"), &[e, 3])?;
    let pairs = (0..e)
        .map(|j| {
            let f = &frames[9 * j..9 * j + 9];
            ContactPairData {
                contact_node: contact[j],
                target_node: target[j],
                weight: weight[j],
                frame: [[f[0], f[1], f[2]], [f[3], f[4], f[5]], [f[6], f[7], f[8]]],
                kt: kt[j],
                kn: kn[j],
                preload: preload[j],
                virtual_point: [points[3 * j], points[3 * j + 1], points[3 * j + 2]],
            }
        })
        .collect();
    let mut curves = Vec::new();
    for (i, p) in frf_points.iter().enumerate() {
        let path = format!("{base}/elements/{i}");
        if !reader.has_group(&path) {
            break;
        }
        curves.push(read_detail(reader, &path, *p, e)?);
    }
    Ok(ContactData {
        name: name.to_string(),
        model: reader.attr_str(&base, "model")?,
        coupling: reader.attr_str(&base, "coupling")?,
        element: reader.attr_str(&base, "element")?,
        sigma: reader.attr_i64(&base, "sigma")?,
        mu: reader.attr_f64(&base, "mu")?,
        pairs,
        curves,
    })
}

/// `/contact/<name>/elements/<i>` of a curve of `p` points and `e` elements.
fn read_detail(reader: &H5Reader, path: &str, p: usize, e: usize) -> Result<ContactCurveDetail> {
    let fractions = reader.f64s(&format!("{path}/fractions"), &[p, e, 3])?;
    let fractions = fractions.chunks(3).map(|f| [f[0], f[1], f[2]]).collect();
    let dissipated_energy = reader.f64s(&format!("{path}/dissipated_energy"), &[p, e])?;
    let loops = if reader.attrs(path)?.contains_key("loop_point") {
        let point = reader.attr_u64(path, "loop_point")? as usize;
        let u = reader.dataset(&format!("{path}/loop_u"))?;
        let samples = u.shape.get(1).copied().unwrap_or(0);
        let pair = [e, samples, 2];
        let single = [e, samples];
        Some(PointLoops {
            point,
            samples,
            u: reader.f64s(&format!("{path}/loop_u"), &pair)?,
            force: reader.f64s(&format!("{path}/loop_force"), &pair)?,
            approach: reader.f64s(&format!("{path}/loop_approach"), &single)?,
            normal_force: reader.f64s(&format!("{path}/loop_normal_force"), &single)?,
        })
    } else {
        None
    };
    Ok(ContactCurveDetail {
        fractions,
        dissipated_energy,
        loops,
    })
}

/// The datasets and attributes of `/march` beyond the layout ([`MarchData::extra`]).
fn march_extra(reader: &H5Reader) -> Result<Group> {
    let mut g = reader.group("/march")?;
    g.datasets
        .retain(|name, _| !MARCH_DATASETS.contains(&name.as_str()));
    g.attrs
        .retain(|name, _| !MARCH_ATTRS.contains(&name.as_str()));
    g.groups.clear();
    Ok(g)
}

fn read_march(reader: &H5Reader) -> Result<MarchData> {
    let response_dofs = read_response_dofs(reader, "/march/response_dofs")?;
    let time = reader.f64_vector("/march/time")?;
    let names = match reader.dataset("/march/element_names")?.data {
        Data::Strings(v) => v,
        other => {
            return Err(reader.error(
                "/march/element_names",
                format!("element type {}, expected strings", other.type_name()),
            ))
        }
    };
    let (t, r, e) = (time.len(), response_dofs.len(), names.len());
    let state = reader.i64s("/march/contact_state", &[t, e])?;
    let state = state
        .iter()
        .map(|&s| {
            u8::try_from(s)
                .ok()
                .filter(|&c| (c as usize) < STATE_LABELS.len())
        })
        .collect::<Option<Vec<u8>>>()
        .ok_or_else(|| reader.error("/march/contact_state", "state code outside 0..=3"))?;
    Ok(MarchData {
        scheme: reader.attr_str("/march", "scheme")?,
        wall_seconds: reader.attr_f64("/march", "wall_seconds")?,
        omega: reader.attr_f64("/march", "omega")?,
        steps: reader.attr_u64("/march", "steps")?,
        response: reader.f64s("/march/response", &[t, r])?,
        contact_force: reader.f64s("/march/contact_force", &[t, e, 2])?,
        contact_state: state,
        first_harmonic_last_period: reader.f64s("/march/first_harmonic_last_period", &[r])?,
        iterations_per_step: reader.u64s("/march/iterations_per_step", &[t])?,
        response_dofs,
        time,
        element_names: names,
        extra: march_extra(reader)?,
    })
}
