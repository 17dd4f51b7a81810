//! The harmonic balance problem of a reduced sector with friction contacts (SAMA paper,
//! Battiato 2021, §2 eqs 10–12; cyclic relative displacement §5 eqs 33–34; `docs/conventions.md`
//! §2–4).
//!
//! [`SectorProblem`] ties the ROM of every harmonic index k_n = n·m mod N
//! ([`crate::rom::Rom`]), the contact pairs of every `[[contact]]` ([`crate::interface`]) and the
//! engine-order excitation into the [`crate::hbm::LinearModel`] + [`PairSet`] that
//! [`crate::hbm::HbmSystem`] and [`crate::continuation`] solve. The time march of the same sector
//! ([`super::sector_march`]) reads the same excitation and output DOFs ([`SectorDofs`]).
//!
//! Temporal harmonic n = 0..H of the response of the reference sector lives on the harmonic index
//! k_n = n·m mod N (m the engine order); its linear part is the ROM of k_n,
//! D⁽ⁿ⁾(ω) = K_{k_n} − (nω)² M_{k_n} + i nω C_{k_n} (eq 12). The nonlinear DOFs are the physical ROM
//! rows (x, y, z) of every contact and target node used by a pair, in ascending node-tag order —
//! the DOF order of the [`PairSet`], whose pairs see the target displacement as
//! e^{iσφ_{k_n}} R_α^σ u_t (eq 33). The excitation of engine order m acts on harmonic n = 1: the
//! case's force on every node of the excitation group of the reference sector. In the ROM
//! coordinates of k_1 it is f_k = T_kᴴ f (`docs/conventions.md` §2), which on a physical master row
//! that is not on the (eliminated) high frontier is f itself.

use std::collections::{BTreeMap, BTreeSet};

use faer::c64;

use crate::case::{Case, ContactElement, Evaluation, ExcitationLoad};
use crate::contact::law::Variant;
use crate::contact::mapped::LinearMap;
use crate::contact::pairs::{PairSet, SectorCoupling};
use crate::cyclic::harmonic_indices;
use crate::error::{Error, Result};
use crate::harmonics::HarmonicLayout;
use crate::hbm::preload::FromStaticEquilibrium;
use crate::hbm::{HbmSystem, LinearModel, MatrixBlock};
use crate::interface::elements::VirtualNodes;
use crate::interface::ContactInterface;
use crate::mesh::Mesh;
use crate::rom::{HarmonicRom, Rom};

/// A physical DOF of the reference sector: Gmsh node tag and component 0/1/2 = x/y/z (global).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct DofLabel {
    /// Gmsh node tag.
    pub node_tag: u64,
    /// Component 0/1/2 = x/y/z in the global axes.
    pub component: u8,
}

/// The harmonic balance problem of one reduced sector (see the module documentation).
pub struct SectorProblem {
    /// Per harmonic n the dynamic stiffness of k_n, condensed on [`SectorProblem::nonlinear`],
    /// excited on n = 1.
    pub linear: LinearModel,
    /// The contact pairs of every interface on the nonlinear DOFs (same order), their forces
    /// measured from the preloaded static equilibrium (`contact.inner` is the [`PairSet`]; see
    /// [`crate::hbm::preload`]): at Q = 0 every pair with n0 > 0 is closed with its preload.
    pub contact: FromStaticEquilibrium<PairSet>,
    /// Real harmonic layout (H, AFT samples) of the case.
    pub layout: HarmonicLayout,
    /// Harmonic index k_n of each temporal harmonic n = 0..=H.
    pub harmonic_indices: Vec<usize>,
    /// Engine order m of the excitation (0 without cyclic symmetry).
    pub engine_order: usize,
    /// The nonlinear DOFs: the PairSet's DOF vector (contact and target nodes × x, y, z).
    pub nonlinear: Vec<DofLabel>,
    /// The output DOFs: `[response]` groups (else the excitation group) × x, y, z.
    pub outputs: Vec<DofLabel>,
}

impl SectorProblem {
    /// Builds the problem of `case` on its ROM `rom` (which must hold every k_n), the sector
    /// `mesh` (for the excitation and response groups) and the contact `interfaces` of
    /// [`crate::interface::build_interfaces`].
    ///
    /// Errors ([`Error::Input`]): no `[excitation]`, an excitation given on matrix rows, a cyclic
    /// case without engine order, a harmonic index missing from the ROM, a contact, target,
    /// excitation or response node that is not a physical master coordinate of the ROM (e.g. on
    /// the high frontier, or on the low frontier replaced by GSI), interfaces mixing 1-D and 2-D
    /// friction elements.
    pub fn build(
        case: &Case,
        rom: &Rom,
        mesh: &Mesh,
        interfaces: &[ContactInterface],
    ) -> Result<SectorProblem> {
        let dofs = SectorDofs::new(case, mesh)?;
        let harmonics = case.harmonic_balance.harmonics;
        let layout = case.harmonic_balance.layout()?;
        let (engine_order, k_n) = match &rom.cyclic {
            Some(g) => {
                let m = dofs.engine_order.ok_or_else(|| {
                    Error::input(format!(
                        "{}: [excitation] needs `engine_order` for a cyclic model",
                        case.path.display()
                    ))
                })?;
                (m, harmonic_indices(g.sectors, m, harmonics))
            }
            None => (0, vec![0; harmonics + 1]),
        };
        let nonlinear = contact_dofs(interfaces);
        let node_rows = node_row_map(&nonlinear);
        let pairs = pair_set(rom, interfaces, &node_rows, nonlinear.len(), &k_n)?;
        let contact = FromStaticEquilibrium::new(pairs, &layout)?;
        let distinct: Vec<usize> = k_n
            .iter()
            .copied()
            .collect::<BTreeSet<_>>()
            .into_iter()
            .collect();
        // the rows of every block first; its matrices are copied one block at a time as the
        // linear model splits them (one block's copy beside the model at most)
        let mut rows = Vec::with_capacity(distinct.len());
        for &k in &distinct {
            let h = rom.harmonic(k).ok_or_else(|| {
                Error::input(format!(
                    "{}: the ROM has no harmonic index k = {k} (needed by engine order {engine_order} with H = {harmonics}); rebuild it with `nlrom reduce`",
                    case.path.display()
                ))
            })?;
            rows.push((
                h,
                rows_of(h, &nonlinear, "contact/target")?,
                rows_of(h, &dofs.outputs, "response")?,
            ));
        }
        let blocks = rows.into_iter().map(|(h, nonlinear, outputs)| MatrixBlock {
            stiffness: h.stiffness.clone(),
            mass: h.mass.clone(),
            damping: h.damping.clone(),
            nonlinear,
            outputs,
        });
        let harmonic_block: Vec<usize> = k_n
            .iter()
            .map(|k| distinct.binary_search(k).unwrap_or(0))
            .collect();
        let mut forcing = vec![Vec::new(); harmonics + 1];
        if harmonics >= 1 {
            let h = rom.harmonic(k_n[1]).ok_or_else(|| {
                Error::input(format!("the ROM has no harmonic index k = {}", k_n[1]))
            })?;
            forcing[1] = dofs.excitation_vector(h)?;
        }
        let linear = LinearModel::new(blocks, harmonic_block, forcing)?;
        super::release_free_heap();
        Ok(SectorProblem {
            linear,
            contact,
            layout,
            harmonic_indices: k_n,
            engine_order,
            nonlinear,
            outputs: dofs.outputs,
        })
    }

    /// The harmonic balance system r(Q, ω) of the problem (SAMA eq 19).
    pub fn system(&self) -> Result<HbmSystem<'_, FromStaticEquilibrium<PairSet>>> {
        HbmSystem::new(self.layout, &self.linear, &self.contact)
    }
}

/// The reference-sector DOFs a sector problem reads on its ROM, for the harmonic balance
/// ([`SectorProblem`]) and the march ([`super::sector_march`]) alike: the nodes of the
/// `[excitation]` group with the force on each, and the output nodes.
#[derive(Clone, Debug)]
pub struct SectorDofs {
    /// The excitation group (`[excitation] group`).
    pub group: String,
    /// The force on every excitation node (N, x y z), `force_scale` applied.
    pub force: [f64; 3],
    /// The engine order m of the excitation, when the case gives one.
    pub engine_order: Option<usize>,
    /// Gmsh tags of the excitation nodes.
    pub excitation_nodes: Vec<u64>,
    /// The output DOFs: the nodes of the `[response]` groups (else the excitation nodes) × x, y,
    /// z, in group order, each node once.
    pub outputs: Vec<DofLabel>,
}

impl SectorDofs {
    /// The excitation and output DOFs of the mesh case `case` on its sector `mesh`.
    ///
    /// Errors ([`Error::Input`]): no `[excitation]`, an excitation on matrix rows (`dofs`), a
    /// group missing from the mesh.
    pub fn new(case: &Case, mesh: &Mesh) -> Result<SectorDofs> {
        let excitation = case.excitation.as_ref().ok_or_else(|| {
            Error::input(format!(
                "{}: the case has no [excitation]; add `[excitation] engine_order = .., group = .., force = [..]`",
                case.path.display()
            ))
        })?;
        let (group, force) = match &excitation.load {
            ExcitationLoad::Group { group, force } => {
                (group.clone(), force.map(|f| f * excitation.force_scale))
            }
            ExcitationLoad::Dofs { .. } => {
                return Err(Error::input(format!(
                    "{}: [excitation] gives matrix rows (`dofs`), but a mesh case needs `group` and `force` (N per node, x y z)",
                    case.path.display()
                )))
            }
        };
        let excitation_nodes = tags_of(mesh, &group)?;
        let outputs = output_dofs(case, mesh, &excitation_nodes)?;
        Ok(SectorDofs {
            group,
            force,
            engine_order: excitation.engine_order,
            excitation_nodes,
            outputs,
        })
    }

    /// F_e⁽¹⁾ in the ROM coordinates of `h`: the force (N, x y z) at the physical rows of every
    /// excitation node of the reference sector (f_k = T_kᴴ f = f there, `docs/conventions.md`
    /// §2).
    ///
    /// Errors ([`Error::Input`]): an excitation node without a physical ROM coordinate.
    pub fn excitation_vector(&self, h: &HarmonicRom) -> Result<Vec<c64>> {
        let mut f = vec![c64::new(0.0, 0.0); h.len()];
        for &tag in &self.excitation_nodes {
            for (c, &value) in self.force.iter().enumerate() {
                let row = h.row_of(tag, c as u8).ok_or_else(|| {
                    missing_node(h, tag, &format!("excitation ('{}')", self.group))
                })?;
                f[row] += c64::new(value, 0.0);
            }
        }
        Ok(f)
    }

    /// The ROM rows of the output DOFs in `h`.
    ///
    /// Errors ([`Error::Input`]): an output node without a physical ROM coordinate.
    pub fn output_rows(&self, h: &HarmonicRom) -> Result<Vec<usize>> {
        rows_of(h, &self.outputs, "response")
    }
}

/// Every contact and target node of the pairs, ascending tag, × x, y, z.
fn contact_dofs(interfaces: &[ContactInterface]) -> Vec<DofLabel> {
    let mut tags = BTreeSet::new();
    for iface in interfaces {
        for p in &iface.pairs {
            tags.insert(p.contact_node);
            tags.extend(p.targets.iter().copied());
        }
    }
    tags.into_iter().flat_map(node_dofs).collect()
}

/// The x, y, z DOFs of a node.
fn node_dofs(tag: u64) -> [DofLabel; 3] {
    [0u8, 1, 2].map(|component| DofLabel {
        node_tag: tag,
        component,
    })
}

/// Node tag → its three rows in `dofs` (which lists nodes × x, y, z).
fn node_row_map(dofs: &[DofLabel]) -> BTreeMap<u64, [usize; 3]> {
    dofs.chunks(3)
        .enumerate()
        .map(|(i, d)| (d[0].node_tag, [3 * i, 3 * i + 1, 3 * i + 2]))
        .collect()
}

/// The [`PairSet`] of all interfaces on the contact DOF vector, with the cyclic coupling
/// (R_α, k_n) when the ROM is cyclic; interpolated SAMA couplings read virtual nodes
/// (Σ_j N_j u_tj) through a [`LinearMap`] appended after the physical rows.
fn pair_set(
    rom: &Rom,
    interfaces: &[ContactInterface],
    node_rows: &BTreeMap<u64, [usize; 3]>,
    n_dofs: usize,
    k_n: &[usize],
) -> Result<PairSet> {
    let mut pairs = Vec::new();
    let mut virtuals = VirtualNodes::new(n_dofs);
    for iface in interfaces {
        pairs.extend(iface.elements_with(|tag| node_rows.get(&tag).copied(), &mut virtuals)?);
    }
    let variant = friction_variant(interfaces)?;
    let coupling = rom.cyclic.as_ref().map(|g| SectorCoupling {
        sectors: g.sectors,
        rotation: g.rotation(1),
        harmonic_indices: k_n.to_vec(),
    });
    let evaluations: Vec<Evaluation> = interfaces
        .iter()
        .flat_map(|iface| std::iter::repeat_n(iface.evaluation, iface.element_count()))
        .collect();
    if virtuals.rows.is_empty() {
        return PairSet::new(n_dofs, variant, pairs, coupling)?.with_evaluations(evaluations);
    }
    let inner = n_dofs + virtuals.rows.len();
    PairSet::new(inner, variant, pairs, coupling)?
        .with_evaluations(evaluations)?
        .with_map(LinearMap::identity_and(n_dofs, virtuals.rows)?)
}

/// The one friction element variant of all interfaces (the PairSet has one).
fn friction_variant(interfaces: &[ContactInterface]) -> Result<Variant> {
    let variant_of = |e: ContactElement| match e {
        ContactElement::OneD => Variant::OneD,
        ContactElement::TwoD => Variant::TwoD,
    };
    let first = interfaces
        .first()
        .map(|i| variant_of(i.element))
        .unwrap_or(Variant::OneD);
    if let Some(other) = interfaces.iter().find(|i| variant_of(i.element) != first) {
        return Err(Error::input(format!(
            "contact '{}' uses a different friction element (`element`) than contact '{}'; use the same `element` (\"1d\" or \"2d\") for every [[contact]]",
            other.name, interfaces[0].name
        )));
    }
    Ok(first)
}

/// Gmsh tags of the nodes of a group.
fn tags_of(mesh: &Mesh, group: &str) -> Result<Vec<u64>> {
    Ok(mesh
        .nodes_of(group)?
        .into_iter()
        .map(|n| mesh.node_tags[n as usize])
        .collect())
}

/// Output DOFs: the nodes of the `[response]` groups (else the excitation nodes) × x, y, z, in
/// group order, each node once.
fn output_dofs(case: &Case, mesh: &Mesh, excitation_nodes: &[u64]) -> Result<Vec<DofLabel>> {
    let groups: &[String] = case
        .response
        .as_ref()
        .map(|r| r.groups.as_slice())
        .unwrap_or(&[]);
    let mut tags: Vec<u64> = Vec::new();
    if groups.is_empty() {
        tags.extend_from_slice(excitation_nodes);
    }
    for g in groups {
        tags.extend(tags_of(mesh, g)?);
    }
    let mut seen = BTreeSet::new();
    tags.retain(|t| seen.insert(*t));
    Ok(tags.into_iter().flat_map(node_dofs).collect())
}

/// The ROM row of every DOF, or an error naming the first one that is not a physical master.
fn rows_of(h: &HarmonicRom, dofs: &[DofLabel], what: &str) -> Result<Vec<usize>> {
    dofs.iter()
        .map(|d| {
            h.row_of(d.node_tag, d.component)
                .ok_or_else(|| missing_node(h, d.node_tag, what))
        })
        .collect()
}

/// The error for a node without a physical ROM coordinate.
fn missing_node(h: &HarmonicRom, tag: u64, what: &str) -> Error {
    Error::input(format!(
        "{what} node {tag} is not a physical coordinate of the ROM of harmonic index k = {}; \
         list its group in `[reduction] keep` (a node on the high cyclic frontier, or on the low \
         frontier when `gsi_modes` reduces it, has no physical coordinate: choose nodes off the frontiers)",
        h.harmonic_index
    ))
}
