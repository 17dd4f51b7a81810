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
use crate::mesh::Mesh;

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
    pub rom: Option<Rom>,
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
    /// mesh) with `[[element]]` friction elements on DOF combinations. Solved on the dense free
    /// rows, without reduction.
    Matrix,
    /// A mesh model with `[reduction]` (optionally `[cyclic]`) and `[[contact]]` interfaces
    /// between node groups: solved on the reduced sector.
    Sector,
}

impl Case {
    /// The kind of the case: `[damper]` → [`CaseKind::Damper`]; no mesh, or any `[[element]]`
    /// → [`CaseKind::Matrix`] (elements act on matrix rows, which only the unreduced model has);
    /// else [`CaseKind::Sector`].
    pub fn kind(&self) -> CaseKind {
        if self.damper.is_some() {
            CaseKind::Damper
        } else if self.model.mesh.is_none() || !self.element.is_empty() {
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

/// An isotropic linear elastic material.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Young's modulus (Pa), > 0.
    pub young: f64,
    /// Poisson's ratio, −1 < ν < 0.5.
    pub poisson: f64,
    /// Density (kg/m³), > 0.
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
            ElementKind::Friction => (&["kt", "mu", "n0"], &["normal", "kn"]),
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
    /// Number of harmonics H ≥ 1 (the forcing is on harmonic 1).
    pub harmonics: usize,
    /// Time samples per period for the AFT, ≥ 2H+2; `None`: see [`HarmonicBalance::samples`].
    #[serde(default)]
    pub time_samples: Option<usize>,
}

impl Default for HarmonicBalance {
    fn default() -> Self {
        HarmonicBalance {
            harmonics: 1,
            time_samples: None,
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
}

impl MarchScheme {
    /// All schemes, in documentation order.
    pub const ALL: [MarchScheme; 5] = [
        MarchScheme::Newmark,
        MarchScheme::Adaptive,
        MarchScheme::PiecewiseLinear,
        MarchScheme::AdaptivePiecewiseLinear,
        MarchScheme::QuasiStatic,
    ];

    /// The spelling in the case file and on the command line.
    pub fn as_str(self) -> &'static str {
        match self {
            MarchScheme::Newmark => "newmark",
            MarchScheme::Adaptive => "adaptive",
            MarchScheme::PiecewiseLinear => "piecewise-linear",
            MarchScheme::AdaptivePiecewiseLinear => "adaptive-piecewise-linear",
            MarchScheme::QuasiStatic => "quasi-static",
        }
    }
}

impl std::str::FromStr for MarchScheme {
    type Err = String;

    fn from_str(s: &str) -> std::result::Result<Self, String> {
        MarchScheme::ALL
            .into_iter()
            .find(|m| m.as_str() == s)
            .ok_or_else(|| {
                format!("unknown scheme '{s}'; expected newmark, adaptive, piecewise-linear, adaptive-piecewise-linear or quasi-static")
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
pub struct Rom {
    /// The ROM file (HDF5); `nlrom solve` reads it instead of reducing again.
    pub file: PathBuf,
}

// ---------------------------------------------------------------------------------------------
// Key paths and error messages
// ---------------------------------------------------------------------------------------------

/// One step of a key path: a table key or an array index.
#[derive(Clone, Debug, PartialEq)]
enum Seg {
    Key(String),
    Index(usize),
}

/// A path to a value in the case file, displayed as `contact[0].mu` or `sweep."contact.a.n0"[2]`.
#[derive(Clone, Debug, Default, PartialEq)]
struct KeyPath(Vec<Seg>);

impl KeyPath {
    /// Parses `a.b[2].c` (keys without dots).
    fn parse(s: &str) -> KeyPath {
        let mut segs = Vec::new();
        for part in s.split('.').filter(|p| !p.is_empty()) {
            let mut pieces = part.split('[');
            if let Some(key) = pieces.next().filter(|k| !k.is_empty()) {
                segs.push(Seg::Key(key.to_string()));
            }
            for idx in pieces {
                if let Ok(i) = idx.trim_end_matches(']').parse() {
                    segs.push(Seg::Index(i));
                }
            }
        }
        KeyPath(segs)
    }

    /// The path of a sweep value: `sweep."<key>"[index]`.
    fn sweep(key: &str, index: Option<usize>) -> KeyPath {
        let mut segs = vec![Seg::Key("sweep".into()), Seg::Key(key.into())];
        segs.extend(index.map(Seg::Index));
        KeyPath(segs)
    }

    /// Converts a `serde_path_to_error` path.
    fn from_serde(p: &serde_path_to_error::Path) -> KeyPath {
        use serde_path_to_error::Segment;
        KeyPath(
            p.iter()
                .filter_map(|s| match s {
                    Segment::Seq { index } => Some(Seg::Index(*index)),
                    Segment::Map { key } => Some(Seg::Key(key.clone())),
                    Segment::Enum { variant } => Some(Seg::Key(variant.clone())),
                    _ => None,
                })
                .collect(),
        )
    }
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, s) in self.0.iter().enumerate() {
            match s {
                Seg::Index(n) => write!(f, "[{n}]")?,
                Seg::Key(k) => {
                    if i > 0 {
                        f.write_str(".")?;
                    }
                    let bare = !k.is_empty()
                        && k.chars()
                            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
                    if bare {
                        f.write_str(k)?
                    } else {
                        write!(f, "\"{k}\"")?
                    }
                }
            }
        }
        Ok(())
    }
}

/// 1-based (line, column) of byte `offset` in `text`.
fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// Byte span of the value at `path` in the TOML `text` (of the deepest part of the path found).
fn locate(text: &str, path: &KeyPath) -> Option<std::ops::Range<usize>> {
    let root = toml::de::DeTable::parse(text).ok()?;
    let mut span = root.span();
    let root = toml::de::DeValue::Table(root.into_inner());
    let mut cur = &root;
    for seg in &path.0 {
        let next = match seg {
            Seg::Key(k) => cur.get(k.as_str()),
            Seg::Index(i) => cur.get(*i),
        };
        let Some(next) = next else { break };
        span = next.span();
        cur = next.get_ref();
    }
    Some(span)
}

/// `file: line L, column C: key 'path': message`, leaving out what is unknown.
fn format_error(
    file: &Path,
    text: &str,
    path: &KeyPath,
    span: Option<std::ops::Range<usize>>,
    with_column: bool,
    msg: &str,
) -> Error {
    let mut s = file.display().to_string();
    if let Some(span) = span {
        let (line, col) = line_col(text, span.start);
        s += &format!(": line {line}");
        if with_column {
            s += &format!(", column {col}");
        }
    }
    if !path.0.is_empty() {
        s += &format!(": key '{path}'");
    }
    Error::input(format!("{s}: {msg}"))
}

/// Parses the TOML text into a [`Case`] (no path resolution, no validation).
fn parse_toml(text: &str, file: &Path) -> Result<Case> {
    let de = toml::de::Deserializer::parse(text).map_err(|e| {
        format_error(
            file,
            text,
            &KeyPath::default(),
            e.span(),
            true,
            e.message().trim(),
        )
    })?;
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = KeyPath::from_serde(e.path());
        let inner = e.inner();
        let span = inner.span().or_else(|| locate(text, &path));
        format_error(file, text, &path, span, true, inner.message().trim())
    })
}

// ---------------------------------------------------------------------------------------------
// Loading
// ---------------------------------------------------------------------------------------------

impl Case {
    /// Reads, parses and validates the case file at `path`; relative paths in it are resolved
    /// against its directory.
    pub fn load(path: &Path) -> Result<Case> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Case::from_str(&text, path)
    }

    /// Parses and validates case text as if read from `path` (used in messages and as the base
    /// of relative paths).
    pub fn from_str(text: &str, path: &Path) -> Result<Case> {
        let mut case = parse_toml(text, path)?;
        case.path = path.to_path_buf();
        case.source_text = text.to_string();
        if case.title.is_empty() {
            case.title = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
        }
        case.resolve_paths();
        case.validate()?;
        case.sweep_points()?;
        Ok(case)
    }

    /// The directory relative paths of the case refer to.
    pub fn base_dir(&self) -> PathBuf {
        self.path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default()
    }

    /// Joins every relative path of the case to [`Case::base_dir`].
    fn resolve_paths(&mut self) {
        let dir = self.base_dir();
        let fix = |p: &mut PathBuf| {
            if p.is_relative() {
                *p = dir.join(&*p);
            }
        };
        let m = &mut self.model;
        m.mesh.iter_mut().for_each(fix);
        m.stiffness.iter_mut().for_each(fix);
        m.mass.iter_mut().for_each(fix);
        m.dofs.iter_mut().for_each(fix);
        if let Some(Damping::Matrix(p)) = &mut m.damping {
            fix(p);
        }
        if let Some(o) = &mut self.output {
            fix(&mut o.file);
        }
        if let Some(r) = &mut self.rom {
            fix(&mut r.file);
        }
    }

    /// An input error at `key` (its line found in the source text).
    fn key_error(&self, key: &KeyPath, msg: impl fmt::Display) -> Error {
        let span = locate(&self.source_text, key);
        format_error(
            &self.path,
            &self.source_text,
            key,
            span,
            false,
            &msg.to_string(),
        )
    }

    /// `Ok(())` if `ok`, else an input error at `key` with the message `msg()`.
    fn require<M: fmt::Display>(&self, ok: bool, key: &str, msg: impl FnOnce() -> M) -> Result<()> {
        if ok {
            Ok(())
        } else {
            Err(self.key_error(&KeyPath::parse(key), msg()))
        }
    }

    /// Error unless `v` is finite and > 0.
    fn positive(&self, key: &str, v: f64) -> Result<()> {
        self.require(v.is_finite() && v > 0.0, key, || {
            format!("must be a finite number > 0 (found {v})")
        })
    }

    /// Error unless `v` is finite and ≥ 0.
    fn non_negative(&self, key: &str, v: f64) -> Result<()> {
        self.require(v.is_finite() && v >= 0.0, key, || {
            format!("must be a finite number ≥ 0 (found {v})")
        })
    }

    /// Error unless every value is finite.
    fn finite(&self, key: &str, v: &[f64]) -> Result<()> {
        match v.iter().find(|x| !x.is_finite()) {
            None => Ok(()),
            Some(x) => {
                Err(self.key_error(&KeyPath::parse(key), format!("must be finite (found {x})")))
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Validation
// ---------------------------------------------------------------------------------------------

impl Case {
    /// Checks ranges and the consistency of the tables (everything that needs no mesh or matrix).
    pub fn validate(&self) -> Result<()> {
        self.validate_model()?;
        self.validate_damping()?;
        self.validate_cyclic()?;
        self.validate_reduction()?;
        self.validate_contacts()?;
        self.validate_excitation()?;
        self.validate_response()?;
        self.validate_elements()?;
        self.validate_harmonic_balance()?;
        self.validate_continuation()?;
        self.validate_march()?;
        self.validate_damper()
    }

    fn validate_model(&self) -> Result<()> {
        let m = &self.model;
        if self.damper.is_some() {
            let empty = m.mesh.is_none() && m.stiffness.is_none() && m.mass.is_none();
            return self.require(empty, "model", || {
                "a case with [damper] defines its model there; remove `mesh`/`stiffness`/`mass` from [model]"
            });
        }
        match (&m.stiffness, &m.mass) {
            (Some(_), None) => {
                return Err(self.key_error(
                    &KeyPath::parse("model.stiffness"),
                    "`stiffness` needs `mass` too (both Matrix Market files)",
                ))
            }
            (None, Some(_)) => {
                return Err(self.key_error(
                    &KeyPath::parse("model.mass"),
                    "`mass` needs `stiffness` too (both Matrix Market files)",
                ))
            }
            _ => {}
        }
        let matrices = m.stiffness.is_some();
        if m.mesh.is_none() && !matrices {
            return Err(self.key_error(
                &KeyPath::parse("model"),
                "give `mesh = \"FILE.msh\"` or both `stiffness` and `mass` (Matrix Market files)",
            ));
        }
        if m.mesh.is_some() && !matrices && m.material.is_none() && m.materials.is_empty() {
            return Err(self.key_error(&KeyPath::parse("model"), "a model assembled from the mesh needs `material = { young = ..., poisson = ..., density = ... }`"));
        }
        if let Some(mat) = &m.material {
            self.check_material("model.material", mat)?;
        }
        for (i, gm) in m.materials.iter().enumerate() {
            self.check_material(&format!("model.materials[{i}]"), &gm.material())?;
        }
        for (key, degree) in [
            ("stiffness", m.quadrature.stiffness),
            ("mass", m.quadrature.mass),
        ] {
            if let Some(d) = degree {
                self.require(
                    (1..=20).contains(&d),
                    &format!("model.quadrature.{key}"),
                    || format!("the rule's polynomial degree must be 1..=20 (found {d})"),
                )?;
            }
        }
        if m.mesh.is_none() {
            self.check_matrix_model()?;
        }
        Ok(())
    }

    fn check_material(&self, key: &str, m: &Material) -> Result<()> {
        self.positive(&format!("{key}.young"), m.young)?;
        self.positive(&format!("{key}.density"), m.density)?;
        let nu = m.poisson;
        self.require(
            nu.is_finite() && nu > -1.0 && nu < 0.5,
            &format!("{key}.poisson"),
            || format!("Poisson's ratio must satisfy -1 < ν < 0.5 (found {nu})"),
        )
    }

    /// A model without a mesh has no groups: nothing may name one.
    fn check_matrix_model(&self) -> Result<()> {
        let no_mesh = "needs `model.mesh`; a model given by matrices alone has no groups";
        let mut uses: Vec<&str> = Vec::new();
        if !self.model.clamp.is_empty() {
            uses.push("model.clamp");
        }
        if !self.model.materials.is_empty() {
            uses.push("model.materials");
        }
        if self.cyclic.is_some() {
            uses.push("cyclic");
        }
        if !self.contact.is_empty() {
            uses.push("contact");
        }
        if matches!(
            self.excitation,
            Some(Excitation {
                load: ExcitationLoad::Group { .. },
                ..
            })
        ) {
            uses.push("excitation.group");
        }
        if self.response.as_ref().is_some_and(|r| !r.groups.is_empty()) {
            uses.push("response.groups");
        }
        if self.reduction.as_ref().is_some_and(|r| !r.keep.is_empty()) {
            uses.push("reduction.keep");
        }
        match uses.first() {
            None => Ok(()),
            Some(k) => Err(self.key_error(&KeyPath::parse(k), no_mesh)),
        }
    }

    fn validate_damping(&self) -> Result<()> {
        match &self.model.damping {
            Some(Damping::Modal(z)) => {
                let ok = z.is_finite() && (0.0..1.0).contains(z);
                self.require(ok, "model.damping.modal", || {
                    format!("the modal damping ratio must satisfy 0 ≤ ζ < 1 (found {z})")
                })
            }
            Some(Damping::Rayleigh { alpha, beta }) => {
                self.non_negative("model.damping.rayleigh[0]", *alpha)?;
                self.non_negative("model.damping.rayleigh[1]", *beta)
            }
            _ => Ok(()),
        }
    }

    fn validate_cyclic(&self) -> Result<()> {
        let Some(c) = &self.cyclic else { return Ok(()) };
        self.require(c.sectors >= 2, "cyclic.sectors", || {
            format!("needs at least 2 sectors (found {})", c.sectors)
        })?;
        self.finite("cyclic.axis.origin", &c.axis.origin)?;
        self.finite("cyclic.axis.direction", &c.axis.direction)?;
        self.require(
            norm(&c.axis.direction) > 0.0,
            "cyclic.axis.direction",
            || "the axis direction must not be zero",
        )?;
        self.require(c.low != c.high, "cyclic.high", || {
            format!("the low and high frontiers are the same group '{}'", c.low)
        })?;
        let needs_eo = self
            .excitation
            .as_ref()
            .is_some_and(|e| e.engine_order.is_none());
        self.require(!needs_eo, "excitation", || {
            "a cyclic model needs `engine_order` (the excitation's engine order m)"
        })
    }

    fn validate_reduction(&self) -> Result<()> {
        let Some(r) = &self.reduction else {
            return Ok(());
        };
        self.require(r.gsi_modes != Some(0), "reduction.gsi_modes", || {
            "must be ≥ 1; omit it to keep all frontier DOF"
        })
    }

    fn validate_contacts(&self) -> Result<()> {
        let mut names = HashSet::new();
        for (i, c) in self.contact.iter().enumerate() {
            let key = format!("contact[{i}]");
            let ok_name = !c.name.trim().is_empty() && !c.name.contains('.');
            self.require(ok_name, &format!("{key}.name"), || format!("'{}' is not a usable name: it must be non-empty and contain no '.' (sweep paths are contact.<name>.<field>)", c.name))?;
            self.require(
                names.insert(c.name.as_str()),
                &format!("{key}.name"),
                || {
                    format!(
                        "contact name '{}' is used twice; names must be unique",
                        c.name
                    )
                },
            )?;
            self.check_friction(&key, c.mu, c.kt, c.kn, c.n0, true)?;
            self.require(
                c.coupling.is_none() || c.model == ContactModel::Sama,
                &format!("{key}.coupling"),
                || {
                    "`coupling` applies to `model = \"sama\"` only (node-to-node pairs have one \
                     target node each); remove it or set `model = \"sama\"`"
                },
            )?;
            if let Some(m) = &c.misalignment {
                self.check_misalignment(&format!("{key}.misalignment"), m)?;
            }
        }
        Ok(())
    }

    /// Ranges of friction parameters; `normal`: whether the element has a normal direction.
    fn check_friction(
        &self,
        key: &str,
        mu: f64,
        kt: f64,
        kn: f64,
        n0: f64,
        normal: bool,
    ) -> Result<()> {
        self.non_negative(&format!("{key}.mu"), mu)?;
        self.non_negative(&format!("{key}.kt"), kt)?;
        self.non_negative(&format!("{key}.kn"), kn)?;
        self.finite(&format!("{key}.n0"), &[n0])?;
        let n0_key = format!("{key}.n0");
        if !normal {
            return self.require(n0 >= 0.0, &n0_key, || {
                format!("without a `normal` direction the slip limit is mu·n0, so n0 must be ≥ 0 (found {n0})")
            });
        }
        self.require(n0 >= 0.0 || kn > 0.0, &n0_key, || {
            format!("n0 = {n0} < 0 means an initial gap -n0/kn, which needs kn > 0")
        })
    }

    fn check_misalignment(&self, key: &str, m: &Misalignment) -> Result<()> {
        self.finite(&format!("{key}.translate"), &m.translate)?;
        let Some(r) = &m.rotate else { return Ok(()) };
        self.finite(&format!("{key}.rotate.axis"), &r.axis)?;
        self.finite(&format!("{key}.rotate.origin"), &r.origin)?;
        self.finite(&format!("{key}.rotate.angle_deg"), &[r.angle_deg])?;
        self.require(norm(&r.axis) > 0.0, &format!("{key}.rotate.axis"), || {
            "the rotation axis must not be zero"
        })
    }

    fn validate_excitation(&self) -> Result<()> {
        let Some(e) = &self.excitation else {
            return Ok(());
        };
        self.finite("excitation.force_scale", &[e.force_scale])?;
        match &e.load {
            ExcitationLoad::Group { force, .. } => self.finite("excitation.force", force),
            ExcitationLoad::Dofs { force, .. } => self.finite("excitation.force", force),
        }
    }

    fn validate_response(&self) -> Result<()> {
        let Some(r) = &self.response else {
            return Ok(());
        };
        self.require(r.groups.is_empty() || r.dofs.is_empty(), "response", || {
            "give either `groups` (mesh models) or `dofs` (matrix rows), not both"
        })
    }

    fn validate_elements(&self) -> Result<()> {
        for (i, e) in self.element.iter().enumerate() {
            let key = format!("element[{i}]");
            self.check_weighted(&format!("{key}.tangential"), &e.tangential)?;
            self.check_element_keys(&key, e)?;
            if let Some(n) = &e.normal {
                self.check_weighted(&format!("{key}.normal"), n)?;
            }
            self.check_element_values(&key, e)?;
        }
        Ok(())
    }

    /// The keys of `e` fit its kind: every required key given, no key of another kind.
    fn check_element_keys(&self, key: &str, e: &FrictionElement) -> Result<()> {
        let (required, optional) = e.kind.keys();
        let given = e.given_keys();
        let kind = e.kind.name();
        if let Some(k) = required.iter().find(|k| !given.contains(k)) {
            return Err(self.key_error(
                &KeyPath::parse(&format!("{key}.kind")),
                format!(
                    "an element of kind = \"{kind}\" needs the key `{k}` (its keys: {})",
                    required.join(", ")
                ),
            ));
        }
        if let Some(k) = given
            .iter()
            .find(|k| !required.contains(k) && !optional.contains(k))
        {
            return Err(self.key_error(
                &KeyPath::parse(&format!("{key}.{k}")),
                format!(
                    "`{k}` is not a key of kind = \"{kind}\" (its keys: {})",
                    required
                        .iter()
                        .chain(optional)
                        .copied()
                        .collect::<Vec<_>>()
                        .join(", ")
                ),
            ));
        }
        Ok(())
    }

    /// Ranges of the kind's parameters (the keys are known to be present).
    fn check_element_values(&self, key: &str, e: &FrictionElement) -> Result<()> {
        let val = |v: Option<f64>| v.unwrap_or(0.0);
        match e.kind {
            ElementKind::Friction => self.check_friction(
                key,
                val(e.mu),
                val(e.kt),
                e.kn,
                val(e.n0),
                e.normal.is_some(),
            ),
            ElementKind::CubicSpring => self.finite(&format!("{key}.k3"), &[val(e.k3)]),
            ElementKind::PolynomialSpring => {
                let c = e.coefficients.as_deref().unwrap_or_default();
                let p = e.exponents.as_deref().unwrap_or_default();
                self.finite(&format!("{key}.coefficients"), c)?;
                self.require(!c.is_empty() && c.len() == p.len(), &format!("{key}.exponents"), || {
                    format!(
                        "`coefficients` ({} entries) and `exponents` ({} entries) must be non-empty lists of equal length",
                        c.len(),
                        p.len()
                    )
                })?;
                self.require(
                    p.iter().all(|&x| (1..=MAX_EXPONENT).contains(&x)),
                    &format!("{key}.exponents"),
                    || format!("exponents must be integers from 1 to {MAX_EXPONENT} (found {p:?})"),
                )
            }
            ElementKind::UnilateralSpring => {
                self.non_negative(&format!("{key}.k"), val(e.k))?;
                self.finite(&format!("{key}.gap"), &[val(e.gap)])
            }
            ElementKind::QuadraticDamper => self.finite(&format!("{key}.c"), &[val(e.c)]),
            ElementKind::TanhFriction => {
                self.non_negative(&format!("{key}.mu"), val(e.mu))?;
                self.non_negative(&format!("{key}.n0"), val(e.n0))?;
                self.positive(&format!("{key}.eps"), val(e.eps))
            }
        }
    }

    fn check_weighted(&self, key: &str, w: &WeightedDofs) -> Result<()> {
        let ok = !w.dofs.is_empty() && w.dofs.len() == w.weights.len();
        self.require(ok, key, || {
            format!(
                "`dofs` ({} entries) and `weights` ({} entries) must be non-empty lists of equal length",
                w.dofs.len(),
                w.weights.len()
            )
        })?;
        self.finite(&format!("{key}.weights"), &w.weights)
    }

    fn validate_harmonic_balance(&self) -> Result<()> {
        let hb = &self.harmonic_balance;
        let h = hb.harmonics;
        self.require(h >= 1, "harmonic_balance.harmonics", || {
            "needs at least 1 harmonic (the forcing is on harmonic 1)"
        })?;
        let n = hb.samples();
        let default = HarmonicBalance {
            harmonics: h,
            time_samples: None,
        }
        .samples();
        self.require(n >= 2 * h + 2, "harmonic_balance.time_samples", || {
            format!(
                "{n} samples cannot resolve {h} harmonics without aliasing; use at least 2H+2 = {} (or omit it for the default {default})",
                2 * h + 2
            )
        })
    }

    fn validate_continuation(&self) -> Result<()> {
        let Some(c) = &self.continuation else {
            return Ok(());
        };
        let k = |name: &str| format!("continuation.{name}_{}", c.unit.suffix());
        self.positive(&k("start"), c.start)?;
        self.positive(&k("end"), c.end)?;
        self.positive(&k("step"), c.step)?;
        self.require(c.start != c.end, &k("end"), || {
            "the range is empty: end equals start"
        })?;
        if let Some(s) = c.min_step {
            self.positive(&k("min_step"), s)?;
        }
        if let Some(s) = c.max_step {
            self.positive(&k("max_step"), s)?;
        }
        if let (Some(lo), Some(hi)) = (c.min_step, c.max_step) {
            self.require(lo <= hi, &k("min_step"), || {
                format!("min step {lo} exceeds max step {hi}")
            })?;
        }
        if let Some(t) = c.tolerance {
            self.positive("continuation.tolerance", t)?;
        }
        self.require(c.max_points != Some(0), "continuation.max_points", || {
            "must be ≥ 1"
        })?;
        self.require(
            c.max_iterations != Some(0),
            "continuation.max_iterations",
            || "must be ≥ 1",
        )
    }

    fn validate_march(&self) -> Result<()> {
        let Some(m) = &self.march else { return Ok(()) };
        self.positive(&format!("march.frequency_{}", m.unit.suffix()), m.frequency)?;
        self.require(m.periods >= 1, "march.periods", || "must be ≥ 1")?;
        self.require(m.steps_per_period >= 1, "march.steps_per_period", || {
            "must be ≥ 1"
        })?;
        if let Some(r) = m.step_ratio {
            self.require(
                r > 0.0 && r < std::f64::consts::FRAC_1_PI,
                "march.step_ratio",
                || format!("Δτ/𝕋 must satisfy 0 < r < 1/π ≈ 0.318, the convergence limit of Newmark's corrector (found {r})"),
            )?;
        }
        if let Some(dt) = m.time_step {
            self.positive("march.time_step_s", dt)?;
        }
        if let Some(t) = m.tolerance {
            self.positive("march.tolerance", t)?;
        }
        if let Some(t) = m.steady_tolerance {
            self.positive("march.steady_tolerance", t)?;
        }
        Ok(())
    }

    fn validate_damper(&self) -> Result<()> {
        let Some(d) = &self.damper else { return Ok(()) };
        self.positive("damper.mass", d.mass)?;
        self.positive("damper.inertia", d.inertia)?;
        self.non_negative("damper.centrifugal_force", d.centrifugal_force)?;
        self.non_negative("damper.damping_ratio", d.damping_ratio)?;
        self.require(d.damping_ratio < 1.0, "damper.damping_ratio", || {
            "must be below 1 (a modal damping ratio; 0.05 damps the damper's inner oscillation)"
        })?;
        self.require(!d.contact.is_empty(), "damper", || {
            "needs at least one [[damper.contact]]"
        })?;
        for (i, p) in d.platform.iter().enumerate() {
            let key = format!("damper.platform[{i}]");
            self.finite(&format!("{key}.amplitude"), &p.amplitude)?;
            self.finite(&format!("{key}.phase_deg"), &[p.phase_deg])?;
        }
        for (i, c) in d.contact.iter().enumerate() {
            let key = format!("damper.contact[{i}]");
            let known = d.platform.iter().any(|p| p.name == c.platform);
            self.require(known, &format!("{key}.platform"), || {
                let names: Vec<&str> = d.platform.iter().map(|p| p.name.as_str()).collect();
                format!(
                    "no [[damper.platform]] is named '{}'; the platforms are: {}",
                    c.platform,
                    names.join(", ")
                )
            })?;
            self.finite(&format!("{key}.point"), &c.point)?;
            self.finite(&format!("{key}.normal"), &c.normal)?;
            self.require(
                c.normal[0].hypot(c.normal[1]) > 0.0,
                &format!("{key}.normal"),
                || "the contact normal must not be zero",
            )?;
            self.check_friction(&key, c.mu, c.kt, c.kn, c.n0, true)?;
        }
        Ok(())
    }
}

/// Euclidean norm of a 3-vector.
fn norm(v: &[f64; 3]) -> f64 {
    (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()
}

// ---------------------------------------------------------------------------------------------
// Groups
// ---------------------------------------------------------------------------------------------

impl Case {
    /// Every group the case names, with the key that names it, in file order.
    pub fn group_references(&self) -> Vec<(String, String)> {
        let mut refs = Vec::new();
        let mut add = |key: String, g: &str| refs.push((key, g.to_string()));
        for (i, g) in self.model.clamp.iter().enumerate() {
            add(format!("model.clamp[{i}]"), g);
        }
        for (i, m) in self.model.materials.iter().enumerate() {
            add(format!("model.materials[{i}].group"), &m.group);
        }
        if let Some(c) = &self.cyclic {
            add("cyclic.low".into(), &c.low);
            add("cyclic.high".into(), &c.high);
        }
        for (i, g) in self
            .reduction
            .iter()
            .flat_map(|r| r.keep.iter())
            .enumerate()
        {
            add(format!("reduction.keep[{i}]"), g);
        }
        for (i, c) in self.contact.iter().enumerate() {
            add(format!("contact[{i}].contact"), &c.contact);
            add(format!("contact[{i}].target"), &c.target);
        }
        if let Some(Excitation {
            load: ExcitationLoad::Group { group, .. },
            ..
        }) = &self.excitation
        {
            add("excitation.group".into(), group);
        }
        for (i, g) in self
            .response
            .iter()
            .flat_map(|r| r.groups.iter())
            .enumerate()
        {
            add(format!("response.groups[{i}]"), g);
        }
        refs
    }

    /// Checks that every group the case names exists in `mesh` and has elements, and that
    /// per-group materials name volume (dim 3) groups. The error lists every problem, each with the
    /// case file, line and key, and the groups the mesh has.
    pub fn check_groups(&self, mesh: &Mesh) -> Result<()> {
        let problems: Vec<String> = self
            .group_references()
            .iter()
            .filter_map(|(key, name)| self.group_problem(mesh, key, name))
            .collect();
        if problems.is_empty() {
            return Ok(());
        }
        Err(Error::input(format!(
            "{}\nthe mesh {} has: {}",
            problems.join("\n"),
            mesh.source_name(),
            describe_groups(mesh)
        )))
    }

    /// What is wrong with the group `name` named at `key`, if anything.
    fn group_problem(&self, mesh: &Mesh, key: &str, name: &str) -> Option<String> {
        let path = KeyPath::parse(key);
        let Some(g) = mesh.groups.iter().find(|g| g.name == name) else {
            let hint = closest_group(mesh, name)
                .map(|c| format!("; did you mean '{c}'?"))
                .unwrap_or_default();
            let msg = format!(
                "the mesh {} has no physical group '{name}'{hint}",
                mesh.source_name()
            );
            return Some(self.key_error(&path, msg).to_string());
        };
        if mesh.group_element_count(g) == 0 {
            let msg = format!(
                "physical group '{name}' (dim {}, tag {}) of {} has no elements",
                g.dim,
                g.tag,
                mesh.source_name()
            );
            return Some(self.key_error(&path, msg).to_string());
        }
        if key.starts_with("model.materials") && g.dim != 3 {
            let msg = format!(
                "a material needs a volume group (dim 3), but '{name}' has dim {}",
                g.dim
            );
            return Some(self.key_error(&path, msg).to_string());
        }
        None
    }
}

/// `name (dim D, tag T, E elements), ...` for the groups of a mesh.
fn describe_groups(mesh: &Mesh) -> String {
    if mesh.groups.is_empty() {
        return "no physical groups; define them in Gmsh (Physical Point/Curve/Surface/Volume)"
            .into();
    }
    mesh.groups
        .iter()
        .map(|g| {
            format!(
                "'{}' (dim {}, tag {}, {} elements)",
                g.name,
                g.dim,
                g.tag,
                mesh.group_element_count(g)
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The mesh group whose name is closest to `name` (case-insensitive edit distance ≤ 2).
fn closest_group<'a>(mesh: &'a Mesh, name: &str) -> Option<&'a str> {
    let lower = name.to_lowercase();
    mesh.groups
        .iter()
        .map(|g| {
            (
                edit_distance(&g.name.to_lowercase(), &lower),
                g.name.as_str(),
            )
        })
        .filter(|(d, _)| *d <= 2)
        .min_by_key(|(d, _)| *d)
        .map(|(_, n)| n)
}

/// Levenshtein distance between two strings (by chars).
fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != *cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}

// ---------------------------------------------------------------------------------------------
// Sweeps
// ---------------------------------------------------------------------------------------------

/// A friction parameter that can be swept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum FrictionParam {
    Mu,
    Kt,
    Kn,
    N0,
}

const FRICTION_PARAMS: [(&str, FrictionParam); 4] = [
    ("mu", FrictionParam::Mu),
    ("kt", FrictionParam::Kt),
    ("kn", FrictionParam::Kn),
    ("n0", FrictionParam::N0),
];

/// What a sweep path sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum SweepTarget {
    Contact(usize, FrictionParam),
    Element(usize, FrictionParam),
    DampingModal,
    ForceScale,
}

impl Case {
    /// One case per sweep point, with the swept parameters applied (a case without a sweep gives
    /// one point: itself). Several sweep keys are zipped: their lists must have equal lengths.
    ///
    /// Sweepable parameter paths:
    /// - `contact.<name>.mu|kt|kn|n0` — a `[[contact]]` by name;
    /// - `element.<index>.mu|kt|kn|n0` — an `[[element]]` by 0-based index (the parameters of
    ///   its kind: all four for `friction`, `mu` and `n0` for `tanh_friction`);
    /// - `model.damping.modal` — the modal damping ratio (the case must use modal damping);
    /// - `excitation.force_scale` — a factor on the excitation forces.
    ///
    /// Each point has an empty `sweep` table and its [`SweepPoint`] set; its values are validated
    /// like the case file's.
    pub fn sweep_points(&self) -> Result<Vec<Case>> {
        let n = self.sweep_length()?;
        let targets: Vec<(&String, &Vec<f64>, SweepTarget)> = self
            .sweep
            .iter()
            .map(|(k, v)| self.sweep_target(k).map(|t| (k, v, t)))
            .collect::<Result<_>>()?;
        (0..n)
            .map(|i| {
                let mut point = self.clone();
                point.sweep.clear();
                let mut values = Vec::with_capacity(targets.len());
                for (key, list, target) in &targets {
                    point.apply_sweep(*target, list[i]);
                    values.push(((*key).clone(), list[i]));
                }
                point.sweep_point = Some(SweepPoint { index: i, values });
                point.validate_sweep_point(&targets, i)?;
                Ok(point)
            })
            .collect()
    }

    /// The number of sweep points (1 without a sweep); errors on empty or unequal lists.
    fn sweep_length(&self) -> Result<usize> {
        let mut lens = self.sweep.iter().map(|(k, v)| (k, v.len()));
        let Some((first_key, n)) = lens.next() else {
            return Ok(1);
        };
        if n == 0 {
            return Err(self.key_error(
                &KeyPath::sweep(first_key, None),
                "the list of values is empty",
            ));
        }
        match lens.find(|(_, m)| *m != n) {
            None => Ok(n),
            Some((k, m)) => Err(self.key_error(
                &KeyPath::sweep(k, None),
                format!("has {m} values but '{first_key}' has {n}; several sweep keys are zipped point by point, so their lists need equal lengths"),
            )),
        }
    }

    /// Parses a sweep path against this case's contacts and elements.
    fn sweep_target(&self, path: &str) -> Result<SweepTarget> {
        let parts: Vec<&str> = path.split('.').collect();
        let param = |p: &str| {
            FRICTION_PARAMS
                .iter()
                .find(|(n, _)| *n == p)
                .map(|(_, f)| *f)
        };
        let target = match parts.as_slice() {
            ["contact", name, p] => self
                .contact
                .iter()
                .position(|c| c.name == *name)
                .zip(param(p))
                .map(|(i, f)| SweepTarget::Contact(i, f)),
            ["element", idx, p] => idx
                .parse::<usize>()
                .ok()
                .filter(|i| *i < self.element.len() && self.element[*i].sweepable(p))
                .zip(param(p))
                .map(|(i, f)| SweepTarget::Element(i, f)),
            ["model", "damping", "modal"]
                if matches!(self.model.damping, Some(Damping::Modal(_))) =>
            {
                Some(SweepTarget::DampingModal)
            }
            ["excitation", "force_scale"] if self.excitation.is_some() => {
                Some(SweepTarget::ForceScale)
            }
            _ => None,
        };
        target.ok_or_else(|| {
            self.key_error(
                &KeyPath::sweep(path, None),
                format!(
                    "unknown sweep parameter '{path}'; this case can sweep: {}",
                    self.sweep_paths().join(", ")
                ),
            )
        })
    }

    /// The sweep paths valid for this case.
    pub fn sweep_paths(&self) -> Vec<String> {
        let mut out = Vec::new();
        for c in &self.contact {
            out.extend(
                FRICTION_PARAMS
                    .iter()
                    .map(|(p, _)| format!("contact.{}.{p}", c.name)),
            );
        }
        for (i, e) in self.element.iter().enumerate() {
            out.extend(
                FRICTION_PARAMS
                    .iter()
                    .filter(|(p, _)| e.sweepable(p))
                    .map(|(p, _)| format!("element.{i}.{p}")),
            );
        }
        if matches!(self.model.damping, Some(Damping::Modal(_))) {
            out.push("model.damping.modal".into());
        }
        if self.excitation.is_some() {
            out.push("excitation.force_scale".into());
        }
        if out.is_empty() {
            out.push("none (the case has no contact, element, modal damping or excitation)".into());
        }
        out
    }

    /// Sets the swept parameter to `v`.
    fn apply_sweep(&mut self, target: SweepTarget, v: f64) {
        let set = |f: FrictionParam, mu: &mut f64, kt: &mut f64, kn: &mut f64, n0: &mut f64| match f
        {
            FrictionParam::Mu => *mu = v,
            FrictionParam::Kt => *kt = v,
            FrictionParam::Kn => *kn = v,
            FrictionParam::N0 => *n0 = v,
        };
        match target {
            SweepTarget::Contact(i, f) => {
                let c = &mut self.contact[i];
                set(f, &mut c.mu, &mut c.kt, &mut c.kn, &mut c.n0);
            }
            SweepTarget::Element(i, f) => {
                let e = &mut self.element[i];
                match f {
                    FrictionParam::Mu => e.mu = Some(v),
                    FrictionParam::Kt => e.kt = Some(v),
                    FrictionParam::Kn => e.kn = v,
                    FrictionParam::N0 => e.n0 = Some(v),
                }
            }
            SweepTarget::DampingModal => self.model.damping = Some(Damping::Modal(v)),
            SweepTarget::ForceScale => {
                if let Some(e) = &mut self.excitation {
                    e.force_scale = v;
                }
            }
        }
    }

    /// Validates a sweep point; an error names the sweep value that caused it.
    fn validate_sweep_point(
        &self,
        targets: &[(&String, &Vec<f64>, SweepTarget)],
        i: usize,
    ) -> Result<()> {
        if targets.is_empty() {
            return Ok(());
        }
        self.validate().map_err(|e| {
            let key = targets[0].0;
            let values: Vec<String> = targets
                .iter()
                .map(|(k, l, _)| format!("{k} = {}", l[i]))
                .collect();
            let what = format!("sweep point {i} ({}) is invalid: {e}", values.join(", "));
            self.key_error(&KeyPath::sweep(key, Some(i)), what)
        })
    }
}
