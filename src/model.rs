//! The structural model a case describes (stage 1): K and M assembled from the case's mesh by
//! [`crate::fe`], or read from external Matrix Market files; clamped DOF eliminated.
//!
//! External matrices relate to the mesh through the DOF map (`dofs.csv`, row → node tag and
//! component); without one, row `3i + c` is component `c` of node index `i` (`docs/conventions.md` §1).
//! A model defined by matrices alone (no mesh) has no groups and therefore no clamp.
//!
//! [`damping`] builds the damping matrix C of any dense model (matrix case or ROM) from the
//! case's damping specification.

pub mod damping;

use std::path::Path;
use std::time::Instant;

use crate::case::Case;
use crate::error::{Error, Result};
use crate::fe::{self, FreeModel, Materials, Quadrature};
use crate::matrix_io::{read_dof_map, read_real_matrix, DofEntry, DofMap};
use crate::mesh::msh::read_msh;
use crate::mesh::Mesh;

/// The structural model of a case after clamping.
#[derive(Clone, Debug)]
pub struct StructuralModel {
    /// The mesh, when the case names one.
    pub mesh: Option<Mesh>,
    /// K_ff (N/m), M_ff (kg) over the free DOF, the free DOF list and the damping specification.
    pub free: FreeModel,
    /// Number of DOF before clamping (rows of the assembled or imported matrices).
    pub n_dofs: usize,
    /// Row → (node tag, component) of the matrices before clamping; `None` for a matrix-only
    /// model without `dofs.csv`.
    pub dofs: Option<DofMap>,
}

impl StructuralModel {
    /// The DOF map of the free rows (row = free DOF index), when the model has one.
    pub fn free_dof_map(&self) -> Option<DofMap> {
        let dofs = self.dofs.as_ref()?;
        let entries = self
            .free
            .free_dofs
            .iter()
            .enumerate()
            .filter_map(|(row, &old)| {
                dofs.entries.get(old).map(|e| DofEntry {
                    row,
                    node_tag: e.node_tag,
                    component: e.component,
                })
            })
            .collect();
        Some(DofMap { entries })
    }
}

/// Builds the structural model of `case`: reads the mesh (checking every group the case names),
/// assembles K and M from it or reads the external matrices, and eliminates the clamped nodes.
/// `log` receives one line per step (for progress on stderr).
pub fn build(case: &Case, log: &mut dyn FnMut(&str)) -> Result<StructuralModel> {
    let start = Instant::now();
    let mesh = match &case.model.mesh {
        Some(path) => {
            let mesh = read_msh(path)?;
            case.check_groups(&mesh)?;
            log(&format!(
                "read {} ({} nodes, {} elements) in {:.2} s",
                path.display(),
                mesh.num_nodes(),
                mesh.num_elements(),
                start.elapsed().as_secs_f64()
            ));
            Some(mesh)
        }
        None => None,
    };
    let model = match (&case.model.stiffness, &case.model.mass) {
        (Some(k), Some(m)) => external(case, mesh, k, m, log)?,
        _ => assembled(case, mesh, log)?,
    };
    log(&format!(
        "model: {} DOF, {} free after clamping ({:.2} s)",
        model.n_dofs,
        model.free.n_free(),
        start.elapsed().as_secs_f64()
    ));
    Ok(model)
}

/// K and M assembled from the mesh with the case's materials and quadrature, then clamped.
fn assembled(
    case: &Case,
    mesh: Option<Mesh>,
    log: &mut dyn FnMut(&str),
) -> Result<StructuralModel> {
    let mesh = mesh.ok_or_else(|| {
        Error::input(format!(
            "{}: [model] needs `mesh` or both `stiffness` and `mass`",
            case.path.display()
        ))
    })?;
    let t = Instant::now();
    let quad = Quadrature {
        stiffness_degree: case.model.quadrature.stiffness,
        mass_degree: case.model.quadrature.mass,
    };
    let full = fe::assemble(&mesh, &Materials::from_case(&case.model), &quad)?;
    log(&format!(
        "assembled K and M ({} DOF) in {:.2} s",
        full.n_dofs(),
        t.elapsed().as_secs_f64()
    ));
    let free = fe::clamp(&full, &mesh, &case.model.clamp)?.with_damping(case.model.damping.clone());
    Ok(StructuralModel {
        n_dofs: full.n_dofs(),
        dofs: Some(full.dof_map(&mesh)),
        mesh: Some(mesh),
        free,
    })
}

/// K and M read from Matrix Market files; the clamp (if any) through the DOF map.
fn external(
    case: &Case,
    mesh: Option<Mesh>,
    k_path: &Path,
    m_path: &Path,
    log: &mut dyn FnMut(&str),
) -> Result<StructuralModel> {
    let k = read_real_matrix(k_path)?;
    let m = read_real_matrix(m_path)?;
    let n = k.nrows();
    for (path, a) in [(k_path, &k), (m_path, &m)] {
        if a.nrows() != a.ncols() || a.nrows() != n {
            return Err(Error::input(format!(
                "{}: a {}×{} matrix, but K ({}) is {n}×{n}: K and M must be square and of the same size",
                path.display(),
                a.nrows(),
                a.ncols(),
                k_path.display()
            )));
        }
    }
    log(&format!("read K and M ({n} DOF)"));
    let dofs = match (&case.model.dofs, &mesh) {
        (Some(path), _) => Some(read_dof_map(path)?),
        (None, Some(mesh)) => Some(DofMap::structural(&mesh.node_tags)),
        (None, None) => None,
    };
    if let Some(map) = &dofs {
        check_dof_map(case, map, n)?;
    }
    let mut fixed = vec![false; n];
    if let (Some(mesh), Some(map)) = (&mesh, &dofs) {
        for name in &case.model.clamp {
            let tags: std::collections::HashSet<u64> = mesh
                .nodes_of(name)?
                .iter()
                .map(|&i| mesh.node_tags[i as usize])
                .collect();
            for e in &map.entries {
                if tags.contains(&e.node_tag) {
                    fixed[e.row] = true;
                }
            }
        }
    }
    let free = fe::eliminate(&k, &m, &fixed).with_damping(case.model.damping.clone());
    Ok(StructuralModel {
        mesh,
        free,
        n_dofs: n,
        dofs,
    })
}

/// The DOF map must have exactly one entry per matrix row, row `r` at position `r`.
fn check_dof_map(case: &Case, map: &DofMap, n: usize) -> Result<()> {
    let consistent =
        map.entries.len() == n && map.entries.iter().enumerate().all(|(i, e)| e.row == i);
    if consistent {
        return Ok(());
    }
    let source = case
        .model
        .dofs
        .as_ref()
        .map(|p| p.display().to_string())
        .unwrap_or_else(|| "the mesh's node list (3 DOF per node)".to_string());
    Err(Error::input(format!(
        "{source}: the DOF map has {} entries for matrices of {n} rows; it needs one line per row, rows 0..{n} in order",
        map.entries.len()
    )))
}
