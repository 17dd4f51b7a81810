//! `[[strip]]`: a distributed friction interface — the contact area of Cigeroglu, An & Menq
//! 2007 (§2, eqs 4–17 at every point; eq 38 for the modal forces) as a quadrature of point
//! elements, either along a line of a matrix model or on a face group of a mesh.
//!
//! **On matrix rows** (`dofs`, `stations`, `tangential`): the strip has stations s_0 < s_1 < …
//! (m) along the line; at each station the tangential relative displacement is
//! u(s_j) = Σ_k T_jk q(dofs_k) (and the normal approach v(s_j) = Σ_k N_jk q(dofs_k)), with weights
//! that are the nodes' shape-function values (a nodal model) or the mode-shape values φ_k(s_j) (a
//! modal model). Between stations the weights are interpolated linearly. The integration points
//! are the Gauss–Legendre points of every segment [s_j, s_{j+1}]; a point of weight dA (m) is one
//! friction element of the 1-D law with k_t = k_u dA, k_n = k_v dA, μ and the preload
//! n0 = q(s) dA, where the preload per length q(s) has the chosen shape and integrates (by the
//! same rule) to the strip's total preload.
//!
//! **On a mesh face** (`face`, `direction`): the points are the Gauss points of the faces of a
//! surface group against rigid ground, with k_u, k_v per unit area and dA the point's area
//! (`crate::problem::face_strip` builds them).

use serde::Deserialize;

use super::Evaluation;

/// How the total preload is distributed along a strip.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PreloadDistribution {
    /// q(s) constant.
    #[default]
    Uniform,
    /// q(s) ∝ 1 + c (2ξ − 1)², ξ = (s − s_0)/(s_last − s_0): c > 0 smallest at the centre, c < 0
    /// largest at the centre (c ≥ −1, so that q does not change sign).
    Quadratic,
    /// q(s) ∝ the `values` given at the stations, interpolated linearly (each ≥ 0).
    Stations,
}

impl PreloadDistribution {
    /// The name used in case files.
    pub fn name(self) -> &'static str {
        match self {
            PreloadDistribution::Uniform => "uniform",
            PreloadDistribution::Quadratic => "quadratic",
            PreloadDistribution::Stations => "stations",
        }
    }
}

/// `[[strip]]`: friction points on DOF combinations of a matrix model (a line: `dofs`,
/// `stations`, `tangential`) or on a face group of a mesh model (`face`, `direction`).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Strip {
    /// The matrix rows (0-based) the strip's kinematics read (a strip on matrix rows).
    #[serde(default)]
    pub dofs: Vec<usize>,
    /// Station positions s_j (m), strictly increasing, at least two (a strip on matrix rows).
    #[serde(default)]
    pub stations: Vec<f64>,
    /// Per station, one weight per entry of `dofs`: u(s_j) = Σ_k tangential\[j\]\[k\]·q[dofs\[k\]]
    /// (a strip on matrix rows).
    #[serde(default)]
    pub tangential: Vec<Vec<f64>>,
    /// Per station, the weights of the normal approach v(s_j) (v > 0 loads the contact); none:
    /// no normal motion (constant preload).
    #[serde(default)]
    pub normal: Option<Vec<Vec<f64>>>,
    /// A surface physical group of the mesh in contact with rigid ground: the strip's points are
    /// the Gauss points of its faces (instead of `dofs`, `stations`, `tangential`, `normal`).
    #[serde(default)]
    pub face: Option<String>,
    /// With `face`: the slip direction p (global frame, any non-zero length), projected on the
    /// face's tangent plane at every point; positions along the strip are measured along it.
    #[serde(default)]
    pub direction: Option<[f64; 3]>,
    /// Gauss–Legendre points per segment (1 to 8; default 2); with `face`: per direction of a
    /// quadrilateral (g × g points), and triangles take a rule exact to degree 2g − 1.
    #[serde(default = "default_gauss")]
    pub gauss: usize,
    /// Tangential contact stiffness k_u ≥ 0 per unit length (N/m²), or per unit area with `face`
    /// (N/m³).
    pub kt: f64,
    /// Normal contact stiffness k_v ≥ 0 per unit length (N/m²), or per unit area with `face`
    /// (N/m³); default 0. With `face`, kn > 0 adds the normal motion (normal load variation).
    #[serde(default)]
    pub kn: f64,
    /// Friction coefficient μ ≥ 0.
    pub mu: f64,
    /// Total normal preload ∫ q ds (N) (∫ q dA with `face`); negative: an initial gap,
    /// n0 = −k_v g0 per length or area (needs the normal motion: `normal` weights, or `face`, and
    /// `kn` > 0).
    pub preload: f64,
    /// The shape of q(s) along the strip (default uniform; with `face`, s is the position along
    /// `direction` and ξ runs over the face group's extent along it).
    #[serde(default)]
    pub distribution: PreloadDistribution,
    /// The coefficient c of the quadratic distribution.
    #[serde(default)]
    pub c: Option<f64>,
    /// The relative preload at each station, for `distribution = "stations"`.
    #[serde(default)]
    pub values: Option<Vec<f64>>,
    /// How the points are evaluated on harmonic vectors (as `[[element]] evaluation`).
    #[serde(default)]
    pub evaluation: Evaluation,
    /// The strip's name in the results file (`/contact/<name>`); default `strip<s>` with s its
    /// index in file order.
    #[serde(default)]
    pub name: Option<String>,
    /// Phase angles N_θ of a stick–slip–separation map (`/contact/<name>/map/<k>`) at the
    /// resonance peak of every curve, or at `map_hz`; none: no map. Needs H = 1 (the map is built
    /// from the exact single-harmonic cycle, [`crate::contact::slip_map`]).
    #[serde(default)]
    pub map: Option<usize>,
    /// Excitation frequencies (Hz) at which to take the maps instead of the resonance peak: one
    /// map at every crossing of each curve with each frequency (one per branch inside a fold),
    /// at a solution added to the curve there ([`crate::hbm::frf::land_at`]).
    #[serde(default)]
    pub map_hz: Option<Vec<f64>>,
}

fn default_gauss() -> usize {
    2
}

/// The largest number of Gauss points per segment.
pub const MAX_GAUSS: usize = 8;

/// The most phase angles of a map.
pub const MAX_MAP_PHASES: usize = 100_000;

/// The most frequencies of `map_hz`.
pub const MAX_MAP_FREQUENCIES: usize = 100;

impl Strip {
    /// The strip's name: `name`, else `strip<index>`.
    pub fn label(&self, index: usize) -> String {
        self.name.clone().unwrap_or_else(|| format!("strip{index}"))
    }

    /// The relative preload per length at s (the shape of q, not normalised) of a strip on
    /// matrix rows; valid after validation (stations increasing, `c` and `values` present when
    /// their distribution needs them).
    pub fn shape(&self, s: f64) -> f64 {
        self.shape_on(s, self.stations[0], self.stations[self.stations.len() - 1])
    }

    /// The relative preload at position s of a strip that spans [s0, s1] (for `stations`, the
    /// stations' values interpolated at s).
    pub fn shape_on(&self, s: f64, s0: f64, s1: f64) -> f64 {
        match self.distribution {
            PreloadDistribution::Uniform => 1.0,
            PreloadDistribution::Quadratic => {
                let x = 2.0 * (s - s0) / (s1 - s0) - 1.0;
                1.0 + self.c.unwrap_or(0.0) * x * x
            }
            PreloadDistribution::Stations => {
                let v = self.values.as_deref().unwrap_or_default();
                let j = self
                    .stations
                    .windows(2)
                    .position(|w| s <= w[1])
                    .unwrap_or(self.stations.len() - 2);
                let eta = (s - self.stations[j]) / (self.stations[j + 1] - self.stations[j]);
                (1.0 - eta) * v[j] + eta * v[j + 1]
            }
        }
    }
}
