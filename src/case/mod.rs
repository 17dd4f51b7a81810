//! The TOML case file (`docs/case-file.md`): what to compute, on which model, with which parameters.
//!
//! [`Case::load`] reads, parses and validates a case; the structs below are its plain data, read
//! directly by the later stages. Units are SI (m, kg, s, N, Pa), frequencies in Hz or rad/s as the
//! key names say. Every table rejects unknown keys, so a misspelt key is an error, and every error
//! is an [`Error::Input`] of the form
//! `CASE.toml: line L, column C: key 'contact[0].mu': <what is wrong and what to do>`.
//!
//! Relative paths in the case (mesh, matrices, DOF map, damping matrix, output and ROM files) are
//! resolved against the directory of the case file when it is loaded.
//!
//! A `[sweep]` table maps parameter paths to lists of values; [`Case::sweep_points`] expands it into
//! one concrete case per value (see [`Case::sweep_points`] for the parameters that can be swept).

use std::collections::{BTreeMap, HashSet};
use std::fmt;
use std::path::{Path, PathBuf};

use serde::Deserialize;

use crate::error::{Error, Result};
use crate::harmonics::HarmonicLayout;
use crate::mesh::Mesh;
use crate::vec3::norm;

pub use casing::{Capacity, CasingGap, CasingTable, ThermalTable};
pub use obstacle::ObstacleTable;
pub use strip::{PreloadDistribution, Strip};

mod casing;
mod groups;
mod obstacle;
mod parse;
pub mod strip;
mod sweep;
mod validate;

// ---------------------------------------------------------------------------------------------
// The case and its tables
// ---------------------------------------------------------------------------------------------

/// A whole case file.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// Free text naming the case; defaults to the case file's stem.
    #[serde(default)]
    pub title: String,
    /// `[model]`: the structure (mesh or matrices), material, clamps and damping. A case with a
    /// `[damper]` table defines its model there and omits `[model]`.
    #[serde(default)]
    pub model: Model,
    /// `[cyclic]`: cyclic symmetry of a sector model; `None` for a model without it.
    #[serde(default)]
    pub cyclic: Option<Cyclic>,
    /// `[reduction]`: Craig–Bampton and interface reduction settings.
    #[serde(default)]
    pub reduction: Option<Reduction>,
    /// `[[contact]]`: friction contact interfaces between mesh node groups, in file order.
    #[serde(default)]
    pub contact: Vec<Contact>,
    /// `[excitation]`: the harmonic forcing.
    #[serde(default)]
    pub excitation: Option<Excitation>,
    /// `[response]`: which DOF to report; `None` reports the excitation nodes/DOF.
    #[serde(default)]
    pub response: Option<Response>,
    /// `[[element]]`: friction elements on DOF combinations of a matrix model, in file order.
    #[serde(default)]
    pub element: Vec<FrictionElement>,
    /// `[[strip]]`: distributed friction interfaces along lines of a matrix model (each a
    /// quadrature of friction points, [`strip`]), in file order.
    #[serde(default)]
    pub strip: Vec<Strip>,
    /// `[[obstacle]]`: rigid obstacles with unilateral contact on DOF combinations of a matrix
    /// model (the nonsmooth schemes of `nlrom march`), in file order.
    #[serde(default)]
    pub obstacle: Vec<ObstacleTable>,
    /// `[[casing]]`: rigid casings with unilateral contact, friction and frictional heating on
    /// mesh node groups (the nonsmooth schemes of `nlrom march`), in file order.
    #[serde(default)]
    pub casing: Vec<CasingTable>,
    /// `[thermal]`: thermal data of a mesh model, adding a temperature DOF per node.
    #[serde(default)]
    pub thermal: Option<ThermalTable>,
    /// `[harmonic_balance]`: number of harmonics and time samples (default: 1 harmonic).
    #[serde(default)]
    pub harmonic_balance: HarmonicBalance,
    /// `[continuation]`: the frequency range of the forced response.
    #[serde(default)]
    pub continuation: Option<Continuation>,
    /// `[march]`: time marching settings.
    #[serde(default)]
    pub march: Option<March>,
    /// `[damper]`: the rigid underplatform damper of Gastaldi & Berruti 2018 (§2, §6) driven by
    /// prescribed platform motion, marched by `nlrom march` instead of a `[model]`.
    #[serde(default)]
    pub damper: Option<Damper>,
    /// `[sweep]`: parameter path → values, one FRF per value (lists of equal length, zipped).
    /// Keys are in sorted order. Empty for a case without a sweep and for a sweep point.
    #[serde(default)]
    pub sweep: BTreeMap<String, Vec<f64>>,
    /// `[output]`: where results go.
    #[serde(default)]
    pub output: Option<Output>,
    /// `[rom]`: a stored reduced-order model to read instead of reducing again.
    #[serde(default)]
    pub rom: Option<RomFile>,
    /// The case file (as given to [`Case::load`] or [`Case::from_str`]); relative paths of the
    /// case were resolved against its directory.
    #[serde(skip)]
    pub path: PathBuf,
    /// The original text of the case file (stored in the results).
    #[serde(skip)]
    pub source_text: String,
    /// For a case made by [`Case::sweep_points`]: which point it is; `None` for a loaded case.
    #[serde(skip)]
    pub sweep_point: Option<SweepPoint>,
}

/// What a case describes; the one rule every command dispatches on ([`Case::kind`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CaseKind {
    /// `[damper]`: the underplatform damper of Gastaldi & Berruti 2018, computed by time
    /// marching only.
    Damper,
    /// A model on matrix rows: matrices without a mesh, or any model (also one assembled from a
    /// mesh) with `[[element]]` friction elements on DOF combinations or `[[strip]]` entries.
    /// Solved on the dense free rows; a mesh model with `[reduction]` on its Craig–Bampton model,
    /// whose masters keep the rows the elements and strips read.
    Matrix,
    /// A mesh model with `[reduction]` (optionally `[cyclic]`) and `[[contact]]` interfaces
    /// between node groups: solved on the reduced sector.
    Sector,
}

impl Case {
    /// The kind of the case: `[damper]` → [`CaseKind::Damper`]; no mesh, or any `[[element]]`
    /// or `[[strip]]` → [`CaseKind::Matrix`] (elements act on matrix rows: the unreduced model's,
    /// or with `[reduction]` the master rows of its Craig–Bampton model);
    /// else [`CaseKind::Sector`].
    pub fn kind(&self) -> CaseKind {
        if self.damper.is_some() {
            CaseKind::Damper
        } else if self.model.mesh.is_none() || !self.element.is_empty() || !self.strip.is_empty() {
            CaseKind::Matrix
        } else {
            CaseKind::Sector
        }
    }
}

/// One point of a parameter sweep.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SweepPoint {
    /// 0-based index of the point in sweep order (the `<sweep-point>` group of the results).
    pub index: usize,
    /// The swept parameters (paths as in `[sweep]`) and their values at this point.
    pub values: Vec<(String, f64)>,
}

/// `[model]`: the structure.
#[derive(Clone, Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Model {
    /// Gmsh mesh file: geometry, groups and (without `stiffness`/`mass`) the FE model.
    #[serde(default)]
    pub mesh: Option<PathBuf>,
    /// Material of every volume not listed in `materials`.
    #[serde(default)]
    pub material: Option<Material>,
    /// Per-volume-group materials, overriding `material` on those groups.
    #[serde(default)]
    pub materials: Vec<GroupMaterial>,
    /// Physical groups whose nodes are fixed (all three components).
    #[serde(default)]
    pub clamp: Vec<String>,
    /// Damping model; `None` is undamped.
    #[serde(default)]
    pub damping: Option<Damping>,
    /// External stiffness matrix (Matrix Market, N/m) instead of assembling from the mesh.
    #[serde(default)]
    pub stiffness: Option<PathBuf>,
    /// External mass matrix (Matrix Market, kg), given together with `stiffness`.
    #[serde(default)]
    pub mass: Option<PathBuf>,
    /// DOF map (`dofs.csv`) relating the rows of external matrices to mesh nodes; without it, row
    /// `3*i + c` is component `c` of node index `i` (`docs/conventions.md` §1).
    #[serde(default)]
    pub dofs: Option<PathBuf>,
    /// Quadrature of the element matrices (`quadrature = { stiffness = 5, mass = 5 }`: polynomial
    /// degrees the rules integrate exactly); omitted keys use each element type's default rule.
    #[serde(default)]
    pub quadrature: QuadratureDegrees,
}

/// `[model] quadrature`: the polynomial degrees of the stiffness and mass rules (`docs/theory.md`: match
/// the other code's rule when comparing against it).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct QuadratureDegrees {
    /// Degree of the stiffness rule; `None` = the element type's default.
    #[serde(default)]
    pub stiffness: Option<u32>,
    /// Degree of the mass rule; `None` = the element type's default.
    #[serde(default)]
    pub mass: Option<u32>,
}

/// An isotropic linear elastic material (its elasticity law is in [`crate::fe::material`]).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Young's modulus E (Pa), > 0.
    pub young: f64,
    /// Poisson's ratio ν (dimensionless), −1 < ν < 0.5.
    pub poisson: f64,
    /// Density ρ (kg/m³), > 0.
    pub density: f64,
}

/// A material on one volume group (`materials = [{ group = "...", young = ..., ... }]`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GroupMaterial {
    /// Physical volume group the material applies to.
    pub group: String,
    /// Young's modulus (Pa), > 0.
    pub young: f64,
    /// Poisson's ratio, −1 < ν < 0.5.
    pub poisson: f64,
    /// Density (kg/m³), > 0.
    pub density: f64,
}

impl GroupMaterial {
    /// The material itself.
    pub fn material(&self) -> Material {
        Material {
            young: self.young,
            poisson: self.poisson,
            density: self.density,
        }
    }
}

/// `model.damping`: exactly one of `modal = ζ`, `rayleigh = [α, β]`, `matrix = "D.mtx"`.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(try_from = "DampingSpec")]
pub enum Damping {
    /// The same modal damping ratio ζ (dimensionless) on every mode.
    Modal(f64),
    /// C = α M + β K, α in 1/s, β in s.
    Rayleigh {
        /// Mass-proportional coefficient α (1/s).
        alpha: f64,
        /// Stiffness-proportional coefficient β (s).
        beta: f64,
    },
    /// An external damping matrix (Matrix Market, N·s/m).
    Matrix(PathBuf),
}

/// The damping table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct DampingSpec {
    modal: Option<f64>,
    rayleigh: Option<[f64; 2]>,
    matrix: Option<PathBuf>,
}

impl TryFrom<DampingSpec> for Damping {
    type Error = String;

    fn try_from(s: DampingSpec) -> std::result::Result<Self, String> {
        match (s.modal, s.rayleigh, s.matrix) {
            (Some(z), None, None) => Ok(Damping::Modal(z)),
            (None, Some([alpha, beta]), None) => Ok(Damping::Rayleigh { alpha, beta }),
            (None, None, Some(p)) => Ok(Damping::Matrix(p)),
            _ => Err(
                "give exactly one of `modal = ζ`, `rayleigh = [α, β]` or `matrix = \"D.mtx\"`"
                    .into(),
            ),
        }
    }
}

/// `[cyclic]`: N identical sectors about an axis (`docs/conventions.md` §2).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Cyclic {
    /// Number of sectors N ≥ 2.
    pub sectors: usize,
    /// The symmetry axis; default z through the origin.
    #[serde(default)]
    pub axis: Axis,
    /// Group of the low frontier (the face at the smaller angle).
    pub low: String,
    /// Group of the high frontier (the image of `low` under the sector rotation).
    pub high: String,
}

/// An axis: a point on it and its direction (need not be normalised).
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Axis {
    /// A point on the axis (m); default the origin.
    #[serde(default)]
    pub origin: [f64; 3],
    /// Direction (any non-zero length); default +z.
    #[serde(default = "z_direction")]
    pub direction: [f64; 3],
}

fn z_direction() -> [f64; 3] {
    [0.0, 0.0, 1.0]
}

impl Default for Axis {
    fn default() -> Self {
        Axis {
            origin: [0.0; 3],
            direction: z_direction(),
        }
    }
}

/// `[reduction]`: Craig–Bampton and interface (GSI) reduction.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Reduction {
    /// Number of fixed-interface (Craig–Bampton) modes kept.
    pub interface_modes: usize,
    /// Number of interface (GSI) modes for the frontier; `None` keeps all frontier DOF.
    #[serde(default)]
    pub gsi_modes: Option<usize>,
    /// Extra groups whose nodes stay master nodes (response, excitation).
    #[serde(default)]
    pub keep: Vec<String>,
}

/// `[[contact]]`: a friction contact interface between mesh groups.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Contact {
    /// Unique name (used in sweep paths and results).
    pub name: String,
    /// Group of the contact nodes.
    pub contact: String,
    /// Group whose faces form the target surface.
    pub target: String,
    /// How contact nodes are paired with the target; default `sama`.
    #[serde(default)]
    pub model: ContactModel,
    /// SAMA only: how a contact node is coupled to the target face around its virtual node:
    /// `array` (the paper's eq 31; the default when absent) or `interpolated` (shape functions,
    /// paper Fig. 8). Giving it with `model = "node-to-node"` is an input error.
    #[serde(default)]
    pub coupling: Option<SamaCoupling>,
    /// Friction element: independent (`1d`, default) or coupled (`2d`) tangential directions.
    #[serde(default)]
    pub element: ContactElement,
    /// Friction coefficient μ ≥ 0.
    pub mu: f64,
    /// Tangential contact stiffness (N/m per contact node), ≥ 0.
    pub kt: f64,
    /// Normal contact stiffness (N/m per contact node), ≥ 0.
    pub kn: f64,
    /// Total static normal preload (N), shared by tributary area; negative: initial gap.
    pub n0: f64,
    /// Static offset of the target face.
    #[serde(default)]
    pub misalignment: Option<Misalignment>,
    /// How the friction elements are evaluated on harmonic vectors (as `[[element]]
    /// evaluation`): `aft` (default) or `analytic`, the exact single-harmonic cycle of the 1-D
    /// law (Cigeroglu, An & Menq 2007), which needs `element = "1d"` and H = 1.
    #[serde(default)]
    pub evaluation: Evaluation,
}

/// How contact nodes are paired with the target surface.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum ContactModel {
    /// Surface-to-surface projection with area weights (SAMA).
    #[default]
    #[serde(rename = "sama")]
    Sama,
    /// Coincident node pairs.
    #[serde(rename = "node-to-node")]
    NodeToNode,
}

/// How SAMA couples a contact node c to the n_T nodes t_j of the target face that contains its
/// virtual node t_v (Battiato 2021, §4).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum SamaCoupling {
    /// The self-adaptive macroslip array of eq 31 (Fig. 7a): one friction element per pair c–t_j
    /// on u_c − u_tj with the inverse-distance weights w_j of eq 29 scaling k_t, k_n and n0.
    #[default]
    #[serde(rename = "array")]
    Array,
    /// One friction element per contact node on u_c − u(t_v), u(t_v) = Σ_j N_j(t_v) u_tj
    /// interpolated by the target face's shape functions (the alternative of §4, Fig. 8); its
    /// force goes back to the t_j by the same N_j. Unlike the array it gives no force under a
    /// rigid rotation of both faces and adds no stiffness to the target face's own deformation.
    #[serde(rename = "interpolated")]
    Interpolated,
}

/// The friction element used per contact pair.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
pub enum ContactElement {
    /// Two independent 1D friction elements along t1 and t2.
    #[default]
    #[serde(rename = "1d")]
    OneD,
    /// A coupled 2D friction element in the tangent plane.
    #[serde(rename = "2d")]
    TwoD,
}

/// A static rigid offset of a contact's target face.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Misalignment {
    /// Translation (m) of the target face.
    #[serde(default)]
    pub translate: [f64; 3],
    /// Rotation of the target face, applied before the translation.
    #[serde(default)]
    pub rotate: Option<Rotation>,
}

/// A rotation about an axis through a point.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Rotation {
    /// Axis direction (any non-zero length).
    pub axis: [f64; 3],
    /// Angle (degrees, right-hand rule about `axis`).
    pub angle_deg: f64,
    /// A point on the axis (m); default the origin.
    #[serde(default)]
    pub origin: [f64; 3],
}

/// `[excitation]`: a harmonic force f·cos(ωt).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(try_from = "ExcitationSpec")]
pub struct Excitation {
    /// Engine order m of a cyclic model (required with `[cyclic]`).
    pub engine_order: Option<usize>,
    /// Where the force acts.
    pub load: ExcitationLoad,
    /// Factor on every force value (key `force_scale`, default 1; sweepable as
    /// `excitation.force_scale`).
    pub force_scale: f64,
}

/// Where an excitation acts.
#[derive(Clone, Debug, PartialEq)]
pub enum ExcitationLoad {
    /// The same force vector (N, global frame, per node) on every node of a group.
    Group {
        /// The group's name.
        group: String,
        /// Force per node (N), x, y, z.
        force: [f64; 3],
    },
    /// Forces (N) on matrix rows (0-based) of a matrix model.
    Dofs {
        /// Matrix rows.
        dofs: Vec<usize>,
        /// One force per row (N).
        force: Vec<f64>,
    },
}

/// The excitation table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ExcitationSpec {
    engine_order: Option<usize>,
    group: Option<String>,
    dofs: Option<Vec<usize>>,
    force: Vec<f64>,
    #[serde(default = "one")]
    force_scale: f64,
}

fn one() -> f64 {
    1.0
}

const EXCITATION_HELP: &str = "give either `group` and `force = [fx, fy, fz]` (mesh models) or `dofs` and `force` lists of equal length (matrix models)";

impl TryFrom<ExcitationSpec> for Excitation {
    type Error = String;

    fn try_from(s: ExcitationSpec) -> std::result::Result<Self, String> {
        let load = match (s.group, s.dofs) {
            (Some(group), None) => {
                let force: [f64; 3] = s.force.as_slice().try_into().map_err(|_| {
                    format!(
                        "`force` has {} values; with `group` it is the force per node [fx, fy, fz]",
                        s.force.len()
                    )
                })?;
                ExcitationLoad::Group { group, force }
            }
            (None, Some(dofs)) if dofs.len() == s.force.len() && !dofs.is_empty() => {
                ExcitationLoad::Dofs {
                    dofs,
                    force: s.force,
                }
            }
            (None, Some(dofs)) => {
                return Err(format!(
                    "`dofs` has {} entries and `force` {}; {EXCITATION_HELP}",
                    dofs.len(),
                    s.force.len()
                ))
            }
            _ => return Err(EXCITATION_HELP.into()),
        };
        Ok(Excitation {
            engine_order: s.engine_order,
            load,
            force_scale: s.force_scale,
        })
    }
}

/// `[response]`: the DOF whose response is reported (give one of the two lists).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Response {
    /// Groups whose nodes are reported (all three components).
    #[serde(default)]
    pub groups: Vec<String>,
    /// Matrix rows (0-based) reported, for matrix models.
    #[serde(default)]
    pub dofs: Vec<usize>,
}

/// `[[element]]`: a nonlinear element on DOF combinations of a matrix model. Which keys an
/// element takes depends on its `kind` ([`ElementKind`]); a key of another kind is an error.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrictionElement {
    /// The element kind.
    pub kind: ElementKind,
    /// The coordinate the element reads, x = Σ weights·q\[dofs\] (m); its force acts back along
    /// the same weights. `tangential` for the friction kinds, `displacement` (an alias) for the
    /// spring and damper kinds.
    #[serde(alias = "displacement")]
    pub tangential: WeightedDofs,
    /// Normal relative displacement v = Σ weights·q\[dofs\] (optional normal load variation;
    /// `friction` only).
    #[serde(default)]
    pub normal: Option<WeightedDofs>,
    /// Tangential stiffness (N/m), ≥ 0 (`friction`, required).
    #[serde(default)]
    pub kt: Option<f64>,
    /// Normal stiffness (N/m), ≥ 0; default 0 (used only with `normal`).
    #[serde(default)]
    pub kn: f64,
    /// Friction coefficient μ ≥ 0 (`friction`, `tanh_friction`, required).
    #[serde(default)]
    pub mu: Option<f64>,
    /// Static normal load (N); without `normal` the slip limit is μ·n0 (`friction`,
    /// `tanh_friction`, required).
    #[serde(default)]
    pub n0: Option<f64>,
    /// Regularising velocity ε (m/s) > 0 of `tanh_friction`: f = μ n0 tanh(ẋ/ε).
    #[serde(default)]
    pub eps: Option<f64>,
    /// Cubic stiffness k3 (N/m³) of `cubic_spring`: f = k3 x³.
    #[serde(default)]
    pub k3: Option<f64>,
    /// Coefficients c_p (N/m^p) of `polynomial_spring`: f = Σ c_p x^p.
    #[serde(default)]
    pub coefficients: Option<Vec<f64>>,
    /// Integer exponents p ≥ 1 of `polynomial_spring`, one per coefficient.
    #[serde(default)]
    pub exponents: Option<Vec<u32>>,
    /// Stiffness k (N/m) ≥ 0 of `unilateral_spring`: f = k max(x − gap, 0).
    #[serde(default)]
    pub k: Option<f64>,
    /// Gap (m) of `unilateral_spring`: contact while x ≥ gap; default 0.
    #[serde(default)]
    pub gap: Option<f64>,
    /// Damping coefficient c (N·s²/m²) of `quadratic_damper`: f = c ẋ|ẋ|.
    #[serde(default)]
    pub c: Option<f64>,
    /// How a `friction` element is evaluated on harmonic vectors: `aft` (default, any H) or
    /// `analytic` (exact single-harmonic cycle, Cigeroglu, An & Menq 2007; needs H = 1).
    #[serde(default)]
    pub evaluation: Evaluation,
}

/// How a 1-D friction element is evaluated on harmonic vectors.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Evaluation {
    /// Alternating frequency/time: the time-discrete law marched over N_t samples (any H).
    #[default]
    Aft,
    /// The exact continuous-time stick–slip–separation cycle under single-harmonic motion
    /// (Cigeroglu, An & Menq 2007, eqs 4–29): no sampling error; only with H = 1.
    Analytic,
}

impl Evaluation {
    /// The name used in case files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Evaluation::Aft => "aft",
            Evaluation::Analytic => "analytic",
        }
    }
}

/// The largest exponent of a `polynomial_spring`.
pub const MAX_EXPONENT: u32 = 15;

/// Kinds of `[[element]]` (the element library of Krack & Gross 2019, NLvib, on DOF
/// combinations x = Σ wᵢ q_{dᵢ}).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ElementKind {
    /// A 1D friction element (Jenkins element with optional normal load variation).
    #[default]
    Friction,
    /// f = k3 x³.
    CubicSpring,
    /// f = Σ c_p x^p.
    PolynomialSpring,
    /// f = k max(x − gap, 0) (normal-only penalty contact).
    UnilateralSpring,
    /// f = c ẋ|ẋ|.
    QuadraticDamper,
    /// f = μ n0 tanh(ẋ/ε) (regularised Coulomb friction).
    TanhFriction,
}

impl ElementKind {
    /// The name used in case files.
    pub fn name(self) -> &'static str {
        match self {
            ElementKind::Friction => "friction",
            ElementKind::CubicSpring => "cubic_spring",
            ElementKind::PolynomialSpring => "polynomial_spring",
            ElementKind::UnilateralSpring => "unilateral_spring",
            ElementKind::QuadraticDamper => "quadratic_damper",
            ElementKind::TanhFriction => "tanh_friction",
        }
    }

    /// The keys of this kind besides `kind` and the coordinate: (required, optional).
    pub fn keys(self) -> (&'static [&'static str], &'static [&'static str]) {
        match self {
            ElementKind::Friction => (&["kt", "mu", "n0"], &["normal", "kn", "evaluation"]),
            ElementKind::CubicSpring => (&["k3"], &[]),
            ElementKind::PolynomialSpring => (&["coefficients", "exponents"], &[]),
            ElementKind::UnilateralSpring => (&["k"], &["gap"]),
            ElementKind::QuadraticDamper => (&["c"], &[]),
            ElementKind::TanhFriction => (&["mu", "n0", "eps"], &[]),
        }
    }
}

impl FrictionElement {
    /// Whether the friction parameter `p` (`mu`, `kt`, `kn`, `n0`) belongs to this kind.
    fn sweepable(&self, p: &str) -> bool {
        let (required, optional) = self.kind.keys();
        required.contains(&p) || optional.contains(&p)
    }

    /// The kind-specific keys given in the case (`kn` counts when nonzero).
    pub fn given_keys(&self) -> Vec<&'static str> {
        let mut out = Vec::new();
        let mut add = |name, given: bool| {
            if given {
                out.push(name);
            }
        };
        add("normal", self.normal.is_some());
        add("kt", self.kt.is_some());
        add("kn", self.kn != 0.0);
        add("mu", self.mu.is_some());
        add("n0", self.n0.is_some());
        add("eps", self.eps.is_some());
        add("k3", self.k3.is_some());
        add("coefficients", self.coefficients.is_some());
        add("exponents", self.exponents.is_some());
        add("k", self.k.is_some());
        add("gap", self.gap.is_some());
        add("c", self.c.is_some());
        add("evaluation", self.evaluation != Evaluation::Aft);
        out
    }
}

/// A linear combination Σ weights\[i\]·q\[dofs\[i\]\] of matrix rows.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WeightedDofs {
    /// Matrix rows (0-based).
    pub dofs: Vec<usize>,
    /// One weight per row (dimensionless).
    pub weights: Vec<f64>,
}

/// `[harmonic_balance]`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HarmonicBalance {
    /// Number of harmonics H ≥ 1 (the forcing is on harmonic 1); 1 when the key is omitted.
    #[serde(default = "one_harmonic")]
    pub harmonics: usize,
    /// Time samples per period for the AFT, ≥ 2H+2; `None`: see [`HarmonicBalance::samples`].
    #[serde(default)]
    pub time_samples: Option<usize>,
    /// The linear solver of the Newton steps and continuation tangents (`linear_solver`).
    #[serde(default)]
    pub linear_solver: LinearSolverKey,
    /// On a model on matrix rows: solve on the modal coordinates of its m lowest modes
    /// (`modes`, [`crate::problem::modal_case`]); `None`: on the physical rows.
    #[serde(default)]
    pub modes: Option<usize>,
}

/// `harmonic_balance.linear_solver`: how the Newton steps and tangents are solved
/// ([`crate::nonlinear::linsolve`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum LinearSolverKey {
    /// The cheaper of `dense` and `structured` by their flop counts, per solve, with the
    /// Jacobian stored by harmonic blocks from 400 unknowns on (the default).
    #[default]
    Auto,
    /// Dense LU of the whole Jacobian, stored dense.
    Dense,
    /// Block LUs per harmonic plus an exact low-rank (Woodbury) correction for the contact
    /// elements that couple harmonics.
    Structured,
}

/// The default `harmonic_balance.harmonics`: H = 1.
fn one_harmonic() -> usize {
    1
}

impl Default for HarmonicBalance {
    fn default() -> Self {
        HarmonicBalance {
            harmonics: 1,
            time_samples: None,
            linear_solver: LinearSolverKey::Auto,
            modes: None,
        }
    }
}

impl HarmonicBalance {
    /// The number of AFT time samples: `time_samples` if given, else the smallest power of two
    /// ≥ 4(H+1) (`docs/conventions.md` §4).
    pub fn samples(&self) -> usize {
        self.time_samples
            .unwrap_or_else(|| (4 * (self.harmonics + 1)).next_power_of_two())
    }

    /// The harmonic layout of H = `harmonics` with [`HarmonicBalance::samples`] AFT samples.
    pub fn layout(&self) -> Result<HarmonicLayout> {
        HarmonicLayout::new(self.harmonics, self.samples())
    }
}

/// The unit a frequency was given in.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum FrequencyUnit {
    /// Hertz (`_hz` keys).
    #[default]
    Hz,
    /// Radians per second (`_rad_s` keys).
    RadPerSecond,
}

impl FrequencyUnit {
    /// Converts a frequency in this unit to rad/s.
    pub fn to_rad_s(self, value: f64) -> f64 {
        match self {
            FrequencyUnit::Hz => 2.0 * std::f64::consts::PI * value,
            FrequencyUnit::RadPerSecond => value,
        }
    }

    /// The key suffix: `hz` or `rad_s`.
    pub fn suffix(self) -> &'static str {
        match self {
            FrequencyUnit::Hz => "hz",
            FrequencyUnit::RadPerSecond => "rad_s",
        }
    }
}

/// `[continuation]`: the frequency range, either `start_hz`/`end_hz`/`step_hz` or
/// `start_rad_s`/`end_rad_s`/`step_rad_s`; the optional step bounds use the same unit suffix.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(try_from = "ContinuationSpec")]
pub struct Continuation {
    /// The unit of `start`, `end`, `step`, `min_step`, `max_step`.
    pub unit: FrequencyUnit,
    /// First frequency (> 0).
    pub start: f64,
    /// Last frequency (> 0, ≠ start); the path may run downwards.
    pub end: f64,
    /// Initial step (> 0), adapted afterwards.
    pub step: f64,
    /// Smallest step the adaptation may take (`min_step_hz`/`min_step_rad_s`); `None`: solver default.
    pub min_step: Option<f64>,
    /// Largest step (`max_step_hz`/`max_step_rad_s`); `None`: solver default.
    pub max_step: Option<f64>,
    /// Most points on the path (`max_points`); `None`: solver default.
    pub max_points: Option<usize>,
    /// Relative residual tolerance of the corrector (`tolerance`); `None`: solver default.
    pub tolerance: Option<f64>,
    /// Most corrector iterations per point (`max_iterations`); `None`: solver default.
    pub max_iterations: Option<usize>,
    /// Most jumps of the sweep where its path cannot be followed to the end of the range
    /// (`max_jumps`); `None`: solver default (16).
    pub max_jumps: Option<usize>,
}

impl Continuation {
    /// (start, end, initial step) in rad/s, whichever unit the case used.
    pub fn omega_range(&self) -> (f64, f64, f64) {
        let u = self.unit;
        (
            u.to_rad_s(self.start),
            u.to_rad_s(self.end),
            u.to_rad_s(self.step),
        )
    }

    /// (min step, max step) in rad/s, if given.
    pub fn step_bounds_rad_s(&self) -> (Option<f64>, Option<f64>) {
        let u = self.unit;
        (
            self.min_step.map(|s| u.to_rad_s(s)),
            self.max_step.map(|s| u.to_rad_s(s)),
        )
    }
}

/// The continuation table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ContinuationSpec {
    start_hz: Option<f64>,
    end_hz: Option<f64>,
    step_hz: Option<f64>,
    min_step_hz: Option<f64>,
    max_step_hz: Option<f64>,
    start_rad_s: Option<f64>,
    end_rad_s: Option<f64>,
    step_rad_s: Option<f64>,
    min_step_rad_s: Option<f64>,
    max_step_rad_s: Option<f64>,
    max_points: Option<usize>,
    tolerance: Option<f64>,
    max_iterations: Option<usize>,
    max_jumps: Option<usize>,
}

impl TryFrom<ContinuationSpec> for Continuation {
    type Error = String;

    fn try_from(s: ContinuationSpec) -> std::result::Result<Self, String> {
        let hz = [
            s.start_hz,
            s.end_hz,
            s.step_hz,
            s.min_step_hz,
            s.max_step_hz,
        ];
        let rad = [
            s.start_rad_s,
            s.end_rad_s,
            s.step_rad_s,
            s.min_step_rad_s,
            s.max_step_rad_s,
        ];
        let any = |v: &[Option<f64>; 5]| v.iter().any(Option::is_some);
        let (unit, v) = match (any(&hz), any(&rad)) {
            (true, true) => {
                return Err(
                    "mixes `_hz` and `_rad_s` keys; use one unit for all frequencies".into(),
                )
            }
            (false, true) => (FrequencyUnit::RadPerSecond, rad),
            _ => (FrequencyUnit::Hz, hz),
        };
        let sfx = unit.suffix();
        let need = |x: Option<f64>, key: &str| {
            x.ok_or_else(|| format!("missing `{key}_{sfx}`; give start_{sfx}, end_{sfx} and step_{sfx} (or the same keys in {})", if sfx == "hz" { "rad/s: start_rad_s, ..." } else { "Hz: start_hz, ..." }))
        };
        Ok(Continuation {
            unit,
            start: need(v[0], "start")?,
            end: need(v[1], "end")?,
            step: need(v[2], "step")?,
            min_step: v[3],
            max_step: v[4],
            max_points: s.max_points,
            tolerance: s.tolerance,
            max_iterations: s.max_iterations,
            max_jumps: s.max_jumps,
        })
    }
}

/// `[march]`: time marching at one excitation frequency.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(try_from = "MarchSpec")]
pub struct March {
    /// Excitation frequency in `unit` (`frequency_hz` or `frequency_rad_s`), > 0.
    pub frequency: f64,
    /// The unit of `frequency`.
    pub unit: FrequencyUnit,
    /// Number of excitation periods simulated, ≥ 1.
    pub periods: usize,
    /// Time steps per period (the fixed step; the adaptive scheme starts from it), ≥ 1.
    pub steps_per_period: usize,
    /// The integration scheme; default `newmark`.
    pub scheme: MarchScheme,
    /// Δτ/𝕋 of the Newmark schemes (0 < r < 1/π; `None`: the march default 0.15): the fixed step
    /// is min(r·𝕋_stick, period/steps_per_period), the adaptive one uses 𝕋 of the current state.
    pub step_ratio: Option<f64>,
    /// An explicit fixed time step (s) instead (`time_step_s`).
    pub time_step: Option<f64>,
    /// Relative displacement tolerance of the standard Newmark corrector (`None`: 1e-8).
    pub tolerance: Option<f64>,
    /// Relative tolerance of the periodicity check (`None`: 1e-6).
    pub steady_tolerance: Option<f64>,
    /// Stop at the first period whose end state repeats the previous one (default false).
    pub stop_at_steady: bool,
    /// θ-method parameter γ ∈ [1/2, 1] of the `moreau-jean` scheme (`None`: 1/2).
    pub gamma: Option<f64>,
    /// γ_θ ∈ [1/2, 1] of the heat rows of `moreau-jean` (`None`: = γ).
    pub gamma_thermal: Option<f64>,
    /// Activation tolerance ε_g (m) of `moreau-jean`: an obstacle is active when its predicted
    /// gap is ≤ ε_g (`None`: 0).
    pub activation_tolerance: Option<f64>,
}

impl March {
    /// The excitation frequency in rad/s.
    pub fn omega(&self) -> f64 {
        self.unit.to_rad_s(self.frequency)
    }
}

/// The march table as written.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct MarchSpec {
    frequency_hz: Option<f64>,
    frequency_rad_s: Option<f64>,
    periods: usize,
    steps_per_period: usize,
    #[serde(default)]
    scheme: MarchScheme,
    step_ratio: Option<f64>,
    time_step_s: Option<f64>,
    tolerance: Option<f64>,
    steady_tolerance: Option<f64>,
    #[serde(default)]
    stop_at_steady: bool,
    gamma: Option<f64>,
    gamma_thermal: Option<f64>,
    activation_tolerance: Option<f64>,
}

impl TryFrom<MarchSpec> for March {
    type Error = String;

    fn try_from(s: MarchSpec) -> std::result::Result<Self, String> {
        let (frequency, unit) = match (s.frequency_hz, s.frequency_rad_s) {
            (Some(f), None) => (f, FrequencyUnit::Hz),
            (None, Some(w)) => (w, FrequencyUnit::RadPerSecond),
            _ => return Err("give exactly one of `frequency_hz` and `frequency_rad_s`".into()),
        };
        Ok(March {
            frequency,
            unit,
            periods: s.periods,
            steps_per_period: s.steps_per_period,
            scheme: s.scheme,
            step_ratio: s.step_ratio,
            time_step: s.time_step_s,
            tolerance: s.tolerance,
            steady_tolerance: s.steady_tolerance,
            stop_at_steady: s.stop_at_steady,
            gamma: s.gamma,
            gamma_thermal: s.gamma_thermal,
            activation_tolerance: s.activation_tolerance,
        })
    }
}

/// Time integration schemes of `nlrom march`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum MarchScheme {
    /// Newmark average acceleration with a fixed step.
    #[default]
    Newmark,
    /// Newmark with an adaptive step.
    Adaptive,
    /// Piecewise-linear Newmark: contact states predicted unchanged, verified, corrected at
    /// transitions (Gastaldi & Berruti 2018, Appendix A.4).
    PiecewiseLinear,
    /// Piecewise-linear Newmark with the adaptive step.
    AdaptivePiecewiseLinear,
    /// Quasi-static stepping (no inertia).
    QuasiStatic,
    /// The Moreau–Jean θ-method on `[[obstacle]]` unilateral contacts (Thorin et al. 2018).
    MoreauJean,
    /// Carpenter's explicit forward-increment Lagrange multipliers on `[[obstacle]]` contacts
    /// (Carpenter, Taylor & Katona 1991).
    Carpenter,
}

impl MarchScheme {
    /// All schemes, in documentation order.
    pub const ALL: [MarchScheme; 7] = [
        MarchScheme::Newmark,
        MarchScheme::Adaptive,
        MarchScheme::PiecewiseLinear,
        MarchScheme::AdaptivePiecewiseLinear,
        MarchScheme::QuasiStatic,
        MarchScheme::MoreauJean,
        MarchScheme::Carpenter,
    ];

    /// The spelling in the case file and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            MarchScheme::Newmark => "newmark",
            MarchScheme::Adaptive => "adaptive",
            MarchScheme::PiecewiseLinear => "piecewise-linear",
            MarchScheme::AdaptivePiecewiseLinear => "adaptive-piecewise-linear",
            MarchScheme::QuasiStatic => "quasi-static",
            MarchScheme::MoreauJean => "moreau-jean",
            MarchScheme::Carpenter => "carpenter",
        }
    }

    /// Whether the scheme is one of the nonsmooth (unilateral contact) schemes.
    pub fn is_nonsmooth(self) -> bool {
        matches!(self, MarchScheme::MoreauJean | MarchScheme::Carpenter)
    }
}

impl std::str::FromStr for MarchScheme {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        MarchScheme::ALL
            .into_iter()
            .find(|m| m.as_str() == s)
            .ok_or_else(|| {
                format!("unknown scheme '{s}'; expected newmark, adaptive, piecewise-linear, adaptive-piecewise-linear, quasi-static, moreau-jean or carpenter")
            })
    }
}

impl fmt::Display for MarchScheme {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// `[damper]`: a rigid 2-D underplatform damper (DOF u, w along x, y at the centre of mass and
/// the rotation φ about z) between blade platforms whose motion is prescribed (Gastaldi & Berruti
/// 2018 eqs 2–4). The centrifugal load acts along −y.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Damper {
    /// Damper mass m_D (kg), > 0.
    pub mass: f64,
    /// Moment of inertia I_z about the centre of mass (kg·m²), > 0.
    pub inertia: f64,
    /// |CF| (N), ≥ 0: f_ED = (0, −|CF|, 0).
    pub centrifugal_force: f64,
    /// Damping ratio ζ (0 ≤ ζ < 1, default 0) for the vibration of the damper on its contact springs
    /// (the ≈ 10 kHz "inner resonance" of the paper's §5.1): normal contact dashpots c = 2ζ k_n/ω_1,
    /// ω_1 the lowest full-stick natural frequency (`march::damper`). The paper has no C_D and filters these oscillations a
    /// posteriori (Fig. 6b).
    #[serde(default)]
    pub damping_ratio: f64,
    /// `[[damper.platform]]`: the platforms and their prescribed motion.
    pub platform: Vec<DamperPlatform>,
    /// `[[damper.contact]]`: the contact points.
    pub contact: Vec<DamperContact>,
}

/// `[[damper.platform]]`: a rigidly translating platform, u_P(t) = amplitude·cos(ωt + phase).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DamperPlatform {
    /// Name the contacts refer to.
    pub name: String,
    /// Displacement amplitudes (x, y) (m).
    pub amplitude: [f64; 2],
    /// Phase (degrees), default 0.
    #[serde(default)]
    pub phase_deg: f64,
}

/// `[[damper.contact]]`: a contact point between the damper and a platform.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DamperContact {
    /// Name (results).
    pub name: String,
    /// The platform's name.
    pub platform: String,
    /// Position of the contact point relative to the damper's centre of mass (x, y) (m).
    pub point: [f64; 2],
    /// Contact normal (x, y) pointing from the platform into the damper (any non-zero length).
    pub normal: [f64; 2],
    /// Tangential contact stiffness (N/m), ≥ 0.
    pub kt: f64,
    /// Normal contact stiffness (N/m), ≥ 0.
    pub kn: f64,
    /// Friction coefficient μ ≥ 0.
    pub mu: f64,
    /// Normal preload (N), default 0 (the centrifugal load closes the contacts).
    #[serde(default)]
    pub n0: f64,
}

/// `[output]`.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Output {
    /// The results file (HDF5).
    pub file: PathBuf,
}

/// `[rom]`: a stored reduced-order model (written by `nlrom reduce`).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RomFile {
    /// The ROM file (HDF5); `nlrom solve` reads it instead of reducing again.
    pub file: PathBuf,
}
