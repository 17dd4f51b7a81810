//! Boundary conditions: clamped nodes eliminated from the assembled matrices.

use faer::sparse::{SparseColMat, SymbolicSparseColMat};
use rayon::prelude::*;

use super::assembly::{split_at_bounds, Assembled};
use crate::case::Damping;
use crate::error::{Error, Result};
use crate::matrix_io::{DofEntry, DofMap};
use crate::mesh::Mesh;

/// The model after elimination of the clamped DOF: K and M restricted to the free DOF
/// (K_ff, M_ff), with the global DOF each row stands for.
#[derive(Clone, Debug)]
pub struct FreeModel {
    /// Stiffness K_ff (N/m), free × free, full symmetric storage.
    pub k: SparseColMat<usize, f64>,
    /// Mass M_ff (kg), free × free (its pattern a subset of `k`'s).
    pub m: SparseColMat<usize, f64>,
    /// Global DOF (3i + c) of each free row, ascending.
    pub free_dofs: Vec<usize>,
    /// Damping specification carried along for the later stages (C is not built here);
    /// `None` is undamped.
    pub damping: Option<Damping>,
}

impl FreeModel {
    /// Number of free DOF.
    pub fn n_free(&self) -> usize {
        self.free_dofs.len()
    }

    /// The DOF map of the free rows: (row, node tag, component) per row. `mesh` is the mesh the
    /// model was assembled from (rows whose node it does not have are left out).
    pub fn dof_map(&self, mesh: &Mesh) -> DofMap {
        DofMap {
            entries: self
                .free_dofs
                .iter()
                .enumerate()
                .filter_map(|(row, &d)| {
                    Some(DofEntry {
                        row,
                        node_tag: *mesh.node_tags.get(d / 3)?,
                        component: (d % 3) as u8,
                    })
                })
                .collect(),
        }
    }

    /// The same model with a damping specification attached.
    pub fn with_damping(mut self, damping: Option<Damping>) -> Self {
        self.damping = damping;
        self
    }

    /// A vector over the free DOF expanded to all `n_dofs` global DOF (zeros on clamped DOF),
    /// e.g. a mode shape for output. Errors if `x` does not have one entry per free DOF.
    pub fn expand(&self, x: &[f64], n_dofs: usize) -> Result<Vec<f64>> {
        if x.len() != self.n_free() {
            return Err(Error::input(format!(
                "a vector of {} entries cannot be expanded from {} free DOF",
                x.len(),
                self.n_free()
            )));
        }
        let mut full = vec![0.0; n_dofs];
        for (&d, &v) in self.free_dofs.iter().zip(x) {
            if let Some(slot) = full.get_mut(d) {
                *slot = v;
            }
        }
        Ok(full)
    }
}

/// Eliminates every DOF of the nodes of the physical groups `groups` (all three components fixed
/// to zero): K_ff, M_ff and the free DOF list. Errors ([`Error::Input`]) for a group that does not
/// exist or has no elements, or matrices whose size is not 3 × the mesh's node count.
pub fn clamp(assembled: &Assembled, mesh: &Mesh, groups: &[String]) -> Result<FreeModel> {
    let n = 3 * mesh.num_nodes();
    if assembled.k.nrows() != n || assembled.m.nrows() != n {
        return Err(Error::input(format!(
            "{}: the matrices have {} rows but the mesh has {} nodes ({n} DOF); assemble them from this mesh",
            mesh.source_name(),
            assembled.k.nrows(),
            mesh.num_nodes()
        )));
    }
    let mut fixed = vec![false; n];
    for name in groups {
        for node in mesh.nodes_of(name)? {
            fixed[3 * node as usize..3 * node as usize + 3].fill(true);
        }
    }
    Ok(eliminate(&assembled.k, &assembled.m, &fixed))
}

/// K and M with the DOF flagged in `fixed` removed (rows and columns): the general form of
/// [`clamp`], for any DOF layout (e.g. external matrices with a DOF map). `fixed` has one entry
/// per row of K and M.
pub fn eliminate(
    k: &SparseColMat<usize, f64>,
    m: &SparseColMat<usize, f64>,
    fixed: &[bool],
) -> FreeModel {
    let free_dofs: Vec<usize> = (0..fixed.len()).filter(|&d| !fixed[d]).collect();
    let mut new_index = vec![usize::MAX; fixed.len()];
    for (new, &old) in free_dofs.iter().enumerate() {
        new_index[old] = new;
    }
    FreeModel {
        k: restrict(k, &free_dofs, &new_index),
        m: restrict(m, &free_dofs, &new_index),
        free_dofs,
        damping: None,
    }
}

/// Columns per parallel task in [`restrict`].
const COLUMN_GROUP: usize = 4096;

/// The submatrix A[keep, keep] (`new_index[old]` = new index, `usize::MAX` when dropped).
fn restrict(
    a: &SparseColMat<usize, f64>,
    keep: &[usize],
    new_index: &[usize],
) -> SparseColMat<usize, f64> {
    let sym = a.symbolic();
    let (col_ptr, row_idx, vals) = (sym.col_ptr(), sym.row_idx(), a.val());
    let kept_rows = |old: usize| {
        row_idx[col_ptr[old]..col_ptr[old + 1]]
            .iter()
            .filter(|&&r| new_index[r] != usize::MAX)
            .count()
    };
    let counts: Vec<usize> = keep.par_iter().map(|&c| kept_rows(c)).collect();
    let mut new_ptr = Vec::with_capacity(keep.len() + 1);
    new_ptr.push(0);
    for c in &counts {
        new_ptr.push(new_ptr[new_ptr.len() - 1] + c);
    }
    let nnz = new_ptr[keep.len()];
    let mut new_rows = vec![0usize; nnz];
    let mut new_vals = vec![0.0; nnz];
    let bounds: Vec<usize> = (0..keep.len())
        .step_by(COLUMN_GROUP)
        .chain([keep.len()])
        .map(|c| new_ptr[c])
        .collect();
    split_at_bounds(&mut new_rows, &bounds)
        .into_par_iter()
        .zip(split_at_bounds(&mut new_vals, &bounds))
        .enumerate()
        .for_each(|(g, (rows, vs))| {
            let first = g * COLUMN_GROUP;
            let mut out = rows.iter_mut().zip(vs.iter_mut());
            for &old in &keep[first..(first + COLUMN_GROUP).min(keep.len())] {
                for p in col_ptr[old]..col_ptr[old + 1] {
                    let r = new_index[row_idx[p]];
                    if r != usize::MAX {
                        if let Some((ro, vo)) = out.next() {
                            *ro = r;
                            *vo = vals[p];
                        }
                    }
                }
            }
        });
    let m = keep.len();
    SparseColMat::new(
        SymbolicSparseColMat::new_checked(m, m, new_ptr, None, new_rows),
        new_vals,
    )
}
