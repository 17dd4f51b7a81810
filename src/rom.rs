//! The reduced-order model (ROM): per harmonic index k, the Craig–Bampton + cyclic (+ GSI)
//! matrices of one sector and the description of every reduced coordinate.
//!
//! This is the data contract between the reduction (`nlrom reduce`, [`crate::reduction`]), the ROM
//! file (`/rom/k<K>/` of `docs/results-file.md`) and the solver. Conventions: `docs/conventions.md` §1–2.
//!
//! Reduced coordinates of harmonic index k, in order:
//! 1. physical master DOFs kept as they are (node-major, components x, y, z): the low frontier
//!    (unless GSI replaced it), contact, target and `keep` nodes; without a cyclic constraint (the
//!    `cb` stage) also the high frontier;
//! 2. GSI interface coordinates η_f (when `gsi_modes` is set; they replace the low frontier);
//! 3. Craig–Bampton fixed-interface modal coordinates.
//!
//! Physical displacements of the reference sector at a physical master DOF are read directly
//! (`q_k` at its row); for k ≠ 0, N/2 the coordinates are complex and the physical field of the
//! reference sector at temporal harmonic n is Re(Q e^{inτ}) (`docs/conventions.md` §2, §4).

use std::collections::BTreeMap;

use faer::{c64, Mat};

use crate::cyclic::CyclicGeometry;

/// Why a physical DOF is a master (the first matching role in this order wins).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum MasterRole {
    /// Low cyclic frontier.
    LowFrontier,
    /// High cyclic frontier (present only in the unconstrained CB model).
    HighFrontier,
    /// Contact node of a contact interface.
    Contact,
    /// Node of a target surface.
    Target,
    /// Node of a `reduction.keep` group (excitation, response).
    Keep,
}

/// What one reduced coordinate is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ReducedDof {
    /// A physical DOF: Gmsh node tag, component 0/1/2 = x/y/z (global frame), and its role.
    Physical {
        node_tag: u64,
        component: u8,
        role: MasterRole,
    },
    /// GSI interface coordinate number `index` (0-based) of the low frontier.
    Interface { index: usize },
    /// Craig–Bampton fixed-interface mode number `mode` (0-based, ascending frequency).
    Modal { mode: usize },
}

/// What the GSI reduction of one harmonic index kept and dropped (`docs/theory.md`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct GsiReport {
    /// Number of CB+CS modes used to build the basis (n_g).
    pub modes_used: usize,
    /// Interface vectors retained after Gram–Schmidt.
    pub retained: usize,
    /// 0-based indices of the mode vectors dropped as linearly dependent.
    pub dropped: Vec<usize>,
}

/// The reduced matrices of one harmonic index k.
#[derive(Clone, Debug)]
pub struct HarmonicRom {
    /// Harmonic index k (0 for a model without cyclic symmetry).
    pub harmonic_index: usize,
    /// True when the matrices are real (k = 0, k = N/2, or no cyclic symmetry); the imaginary
    /// parts are then exactly zero.
    pub real: bool,
    /// K_k (N/m), Hermitian, n × n.
    pub stiffness: Mat<c64>,
    /// M_k (kg), Hermitian, n × n.
    pub mass: Mat<c64>,
    /// C_k (N·s/m), Hermitian, n × n, when the case defines damping.
    pub damping: Option<Mat<c64>>,
    /// Description of each of the n reduced coordinates.
    pub dofs: Vec<ReducedDof>,
    /// Lowest eigenfrequencies (Hz) of (K_k, M_k), ascending.
    pub frequencies_hz: Vec<f64>,
    /// GSI report, when the interface was reduced.
    pub gsi: Option<GsiReport>,
}

impl HarmonicRom {
    /// Number of reduced coordinates n.
    pub fn len(&self) -> usize {
        self.dofs.len()
    }

    /// True when there are no reduced coordinates.
    pub fn is_empty(&self) -> bool {
        self.dofs.is_empty()
    }

    /// Row of the physical DOF (node tag, component), if it is a reduced coordinate.
    pub fn row_of(&self, node_tag: u64, component: u8) -> Option<usize> {
        self.dofs.iter().position(|d| {
            matches!(d, ReducedDof::Physical { node_tag: t, component: c, .. } if *t == node_tag && *c == component)
        })
    }
}

/// A master node: Gmsh tag and position (m).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MasterNode {
    pub tag: u64,
    pub position: [f64; 3],
}

/// The ROM of a case: one [`HarmonicRom`] per harmonic index the case needs.
#[derive(Clone, Debug)]
pub struct Rom {
    /// Cyclic geometry; `None` for a model without cyclic symmetry.
    pub cyclic: Option<CyclicGeometry>,
    /// Number of free (unclamped) DOFs of the full sector model.
    pub full_dofs: usize,
    /// Every physical master node, ascending tag.
    pub nodes: Vec<MasterNode>,
    /// Master node tags per group name (frontiers, contact, target and keep groups).
    pub groups: BTreeMap<String, Vec<u64>>,
    /// Number of CB fixed-interface modes.
    pub interface_modes: usize,
    /// Eigenfrequencies (Hz) of the fixed-interface modes.
    pub interface_frequencies_hz: Vec<f64>,
    /// ROMs per harmonic index, ascending k.
    pub harmonics: Vec<HarmonicRom>,
    /// Hex digest of the inputs the ROM depends on (mesh, material, clamps, cyclic, reduction,
    /// contact groups); `nlrom run` reuses a ROM file whose key matches.
    pub key: String,
}

impl Rom {
    /// The ROM of harmonic index k, if it was built.
    pub fn harmonic(&self, k: usize) -> Option<&HarmonicRom> {
        self.harmonics.iter().find(|h| h.harmonic_index == k)
    }
}
