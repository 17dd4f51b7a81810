//! Master (boundary) and interior DOF of the Craig–Bampton partition (`docs/theory.md`, "Craig–Bampton reduction").
//!
//! Masters are the free DOF of the nodes of: the low and high cyclic frontiers, the contact and
//! target groups of every `[[contact]]`, the `reduction.keep` groups, and — so that the solver can
//! apply the force and report the response on physical DOF — the excitation group and the
//! `[response]` groups. Everything else that is free after clamping is interior.
//!
//! Order of the master rows (the physical reduced coordinates of [`crate::rom`]): by role
//! (low frontier, high frontier, contact, target, keep — the first matching role wins), then by
//! node (ascending Gmsh tag), then by component x, y, z. The order is the same for every harmonic
//! index k; the cyclic transform only removes the high-frontier rows.

use std::collections::BTreeMap;

use crate::case::{Case, Excitation, ExcitationLoad};
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::model::StructuralModel;
use crate::rom::MasterRole;

/// A physical master DOF.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MasterDof {
    /// Row of the DOF in the free (clamped) model.
    pub free_row: usize,
    /// Compact mesh node index.
    pub node: u32,
    /// Gmsh node tag.
    pub node_tag: u64,
    /// Component 0/1/2 = x/y/z (global frame).
    pub component: u8,
    /// Why it is a master.
    pub role: MasterRole,
}

/// The partition of the free DOF into masters (b) and interior (i).
#[derive(Clone, Debug, PartialEq)]
pub struct Partition {
    /// Master DOF in reduced-coordinate order (see the module documentation).
    pub masters: Vec<MasterDof>,
    /// Free rows of the interior DOF, ascending.
    pub interior: Vec<usize>,
    /// Number of free DOF (masters + interior).
    pub n_free: usize,
    /// Master node indices per group name, for the ROM file.
    pub groups: BTreeMap<String, Vec<u32>>,
}

impl Partition {
    /// Number of master DOF n_b.
    pub fn n_masters(&self) -> usize {
        self.masters.len()
    }

    /// Free rows of the masters, in reduced-coordinate order.
    pub fn master_rows(&self) -> Vec<usize> {
        self.masters.iter().map(|d| d.free_row).collect()
    }

    /// Every master node index, ascending, without repetition.
    pub fn master_nodes(&self) -> Vec<u32> {
        let mut n: Vec<u32> = self.masters.iter().map(|d| d.node).collect();
        n.sort_unstable();
        n.dedup();
        n
    }

    /// The master rows (positions in `masters`) of node `node`, component order.
    pub fn rows_of_node(&self, node: u32) -> Vec<usize> {
        self.masters
            .iter()
            .enumerate()
            .filter_map(|(r, d)| (d.node == node).then_some(r))
            .collect()
    }
}

/// The master groups a case names, with their roles: `[cyclic] low`/`high`, every contact's
/// `contact` and `target`, `reduction.keep`, the excitation group and the response groups.
pub fn case_master_groups(case: &Case) -> Vec<(String, MasterRole)> {
    let mut groups = Vec::new();
    if let Some(c) = &case.cyclic {
        groups.push((c.low.clone(), MasterRole::LowFrontier));
        groups.push((c.high.clone(), MasterRole::HighFrontier));
    }
    for c in &case.contact {
        groups.push((c.contact.clone(), MasterRole::Contact));
        groups.push((c.target.clone(), MasterRole::Target));
    }
    for g in case.reduction.iter().flat_map(|r| r.keep.iter()) {
        groups.push((g.clone(), MasterRole::Keep));
    }
    if let Some(Excitation {
        load: ExcitationLoad::Group { group, .. },
        ..
    }) = &case.excitation
    {
        groups.push((group.clone(), MasterRole::Keep));
    }
    for g in case.response.iter().flat_map(|r| r.groups.iter()) {
        groups.push((g.clone(), MasterRole::Keep));
    }
    groups
}

/// The partition of `model`'s free DOF with the nodes of `groups` (name, role) as masters.
///
/// Errors ([`Error::Input`]): a model without a mesh (groups need one), an unknown or empty group,
/// no free master DOF at all (every master node clamped), or no interior DOF.
pub fn partition(model: &StructuralModel, groups: &[(String, MasterRole)]) -> Result<Partition> {
    let mesh = model.mesh.as_ref().ok_or_else(|| {
        Error::input(
            "the reduction needs a mesh: master nodes (frontiers, contact, keep groups) are \
             physical groups; give `[model] mesh`",
        )
    })?;
    let role_of = node_roles(mesh, groups)?;
    let n_free = model.free.n_free();
    let map = model.free_dof_map().ok_or_else(|| {
        Error::input("the model has no DOF map: give `[model] dofs = \"dofs.csv\"`")
    })?;
    let mut masters = Vec::new();
    let mut interior = Vec::new();
    let mut is_master = vec![false; n_free];
    for e in &map.entries {
        let node = mesh.node_index(e.node_tag);
        if let Some(role) = node.and_then(|n| role_of[n as usize]) {
            masters.push(MasterDof {
                free_row: e.row,
                node: node.unwrap_or(0),
                node_tag: e.node_tag,
                component: e.component,
                role,
            });
            is_master[e.row] = true;
        }
    }
    interior.extend((0..n_free).filter(|&r| !is_master[r]));
    masters.sort_by_key(|d| (d.role, d.node, d.component));
    if masters.is_empty() {
        return Err(Error::input(format!(
            "{}: no free master DOF: the master groups ({}) are empty or entirely clamped; name \
             the frontier, contact or keep groups in the case",
            mesh.source_name(),
            group_names(groups)
        )));
    }
    if interior.is_empty() {
        return Err(Error::input(format!(
            "{}: every free DOF is a master ({} DOF), so there is nothing to reduce; the master \
             groups ({}) cover the whole model",
            mesh.source_name(),
            masters.len(),
            group_names(groups)
        )));
    }
    let mut free_master = vec![false; mesh.num_nodes()];
    for d in &masters {
        free_master[d.node as usize] = true;
    }
    let mut by_group: BTreeMap<String, Vec<u32>> = BTreeMap::new();
    for (name, _) in groups {
        let nodes: Vec<u32> = mesh
            .nodes_of(name)?
            .into_iter()
            .filter(|&n| free_master[n as usize])
            .collect();
        by_group.insert(name.clone(), nodes);
    }
    Ok(Partition {
        masters,
        interior,
        n_free,
        groups: by_group,
    })
}

/// For every mesh node, the first role (in [`MasterRole`] order) of a group holding it.
fn node_roles(mesh: &Mesh, groups: &[(String, MasterRole)]) -> Result<Vec<Option<MasterRole>>> {
    let mut role_of: Vec<Option<MasterRole>> = vec![None; mesh.num_nodes()];
    for (name, role) in groups {
        for n in mesh.nodes_of(name)? {
            let slot = &mut role_of[n as usize];
            *slot = Some(slot.map_or(*role, |r| r.min(*role)));
        }
    }
    Ok(role_of)
}

fn group_names(groups: &[(String, MasterRole)]) -> String {
    if groups.is_empty() {
        return "none".into();
    }
    groups
        .iter()
        .map(|(g, _)| format!("'{g}'"))
        .collect::<Vec<_>>()
        .join(", ")
}
