//! Model checks: volume by quadrature, total mass from M, rigid-body modes.

use faer::sparse::SparseColMat;
use faer::Mat;
use rayon::prelude::*;

use super::element::{default_degrees, unsupported, volume_of, Tabulated};
use super::Quadrature;
use crate::error::{Error, Result};
use crate::mesh::Mesh;

/// Total volume (m³) of the volume elements of `mesh`, Σₑ Σ_q w_q det J, with the mass rule of
/// `quad` (exact for straight-sided elements). Errors like [`super::assemble`] for unsupported
/// types and non-positive Jacobians (naming the element tag and file).
pub fn mesh_volume(mesh: &Mesh, quad: &Quadrature) -> Result<f64> {
    let mut total = 0.0;
    for block in mesh
        .blocks
        .iter()
        .filter(|b| b.kind.dim() == 3 && !b.is_empty())
    {
        let (_, dm) = default_degrees(block.kind).ok_or_else(|| {
            Error::input(format!(
                "{}: {}",
                mesh.source_name(),
                unsupported(block.kind)
            ))
        })?;
        let tab = Tabulated::for_degree(block.kind, quad.mass_degree.unwrap_or(dm))?;
        let n = mesh.num_nodes();
        let volumes: Vec<std::result::Result<f64, String>> = block
            .elements()
            .enumerate()
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|(e, nodes)| {
                let xs: Vec<[f64; 3]> = nodes
                    .iter()
                    .map(|&i| {
                        mesh.coords
                            .get(i as usize)
                            .copied()
                            .unwrap_or([f64::NAN; 3])
                    })
                    .collect();
                volume_of(&tab, &xs).map_err(|b| {
                    format!(
                        "{}: {} element {} has a non-positive Jacobian determinant ({}){}",
                        mesh.source_name(),
                        block.kind,
                        block.tags.at(e),
                        b.describe(),
                        if nodes.iter().any(|&i| i as usize >= n) {
                            " (node index out of range)"
                        } else {
                            ""
                        }
                    )
                })
            })
            .collect();
        for v in volumes {
            total += v.map_err(Error::Input)?;
        }
    }
    Ok(total)
}

/// The mass (kg) that M gives a rigid unit translation along x: uᵀ M u with u = 1 on every x DOF
/// (3i), i.e. the sum of the entries of M in x rows and x columns. Equals ρ·V for an assembled
/// consistent mass matrix (Σₐ Nₐ = 1). Only meaningful for the full matrices (`Assembled::m`).
pub fn total_mass(m: &SparseColMat<usize, f64>) -> f64 {
    let sym = m.symbolic();
    let (col_ptr, row_idx, vals) = (sym.col_ptr(), sym.row_idx(), m.val());
    (0..m.ncols())
        .into_par_iter()
        .step_by(3)
        .map(|c| {
            (col_ptr[c]..col_ptr[c + 1])
                .filter(|&p| row_idx[p] % 3 == 0)
                .map(|p| vals[p])
                .sum::<f64>()
        })
        .sum()
}

/// The six rigid-body modes of nodes at `coords` as the columns of a 3n × 6 matrix (DOF 3i + c):
/// unit translations along x, y, z, then rotations about the x, y, z axes through `centre`,
/// u = e × (x − centre) (m per rad). K times each column is zero for an unconstrained model.
pub fn rigid_body_modes(coords: &[[f64; 3]], centre: [f64; 3]) -> Mat<f64> {
    Mat::from_fn(3 * coords.len(), 6, |row, col| {
        let (i, c) = (row / 3, row % 3);
        if col < 3 {
            return if c == col { 1.0 } else { 0.0 };
        }
        let r = [
            coords[i][0] - centre[0],
            coords[i][1] - centre[1],
            coords[i][2] - centre[2],
        ];
        // (e_axis × r)_c
        let axis = col - 3;
        let mut e = [0.0; 3];
        e[axis] = 1.0;
        let cross = [
            e[1] * r[2] - e[2] * r[1],
            e[2] * r[0] - e[0] * r[2],
            e[0] * r[1] - e[1] * r[0],
        ];
        cross[c]
    })
}
