//! The Craig–Bampton model of a matrix case on a mesh (`[model] mesh` with a `[[strip]]` on a
//! face group, `[[element]]` entries or a line `[[strip]]`) that has `[reduction]`: the free
//! model x = T_CB x_r (Craig & Bampton, AIAA J. 6, 1968; [`crate::reduction::craig_bampton()`])
//! with the nodes of the strips' face groups, the excitation and response groups and
//! `reduction.keep` as masters and `reduction.interface_modes` fixed-interface modes, so that a
//! model beyond the dense limit of a matrix case ([`super::matrix_case::MAX_DENSE_DOFS`] free
//! DOF) is solved on n_b + n_m coordinates.
//!
//! The reduced model is a [`StructuralModel`] like the unreduced one: its free rows are the
//! master DOF, which keep their case rows (node, component) in ascending order, then the modal
//! coordinates, numbered from the model's row count on so that no case row names them. Every
//! row a strip point, an `[[element]]`, the excitation or the response reads is a master, so
//! the strips' point weights (shape-function values on the face's nodes) and the other rows map
//! onto the ROM's physical coordinates unchanged, and [`super::matrix_case`] builds the
//! harmonic balance and the march from it as from the full model. A load on the masters is
//! applied exactly (T_CBᵀ f = f on the master rows), and the model is exact statically at the
//! masters (K_cb's master block is the static condensation K_bb + K_bi Ψ); at a frequency ω the
//! difference from the full model is the truncation of the fixed-interface modes above the
//! kept ones. Damping: `rayleigh` is projected exactly, `modal = ζ` is applied to every mode of
//! the reduced model (as for a sector ROM, [`crate::reduction`]); an external damping matrix is
//! not projected (an input error).

use faer::sparse::{SparseColMat, Triplet};
use faer::Mat;

use crate::case::{Case, Damping, ExcitationLoad};
use crate::error::{Error, Result};
use crate::fe::bc::FreeModel;
use crate::model::StructuralModel;
use crate::reduction::{case_master_groups, craig_bampton, partition, CbOptions, Partition};
use crate::rom::MasterRole;

use super::matrix_case::{case_elements, free_row_map};

/// The master groups of a matrix case: those of every case ([`case_master_groups`]: excitation
/// and response groups, `reduction.keep`) and the face group of every `[[strip]]` on a face.
pub fn matrix_master_groups(case: &Case) -> Vec<(String, MasterRole)> {
    let mut groups = case_master_groups(case);
    for strip in &case.strip {
        if let Some(face) = &strip.face {
            groups.push((face.clone(), MasterRole::Contact));
        }
    }
    groups
}

/// The Craig–Bampton model of the matrix case `case` on its full model `model` (see the module
/// documentation); `log` receives the reduction's progress lines.
///
/// Errors ([`Error::Input`], naming the case file and the key): `[cyclic]` or
/// `reduction.gsi_modes` (a matrix case has no frontier), an external damping matrix, a row of
/// an `[[element]]`, a line strip, the excitation or the response that is an interior DOF, and
/// the errors of [`partition`] and [`craig_bampton()`].
pub fn reduced_matrix_model(
    case: &Case,
    model: StructuralModel,
    log: &mut dyn FnMut(&str),
) -> Result<StructuralModel> {
    let file = case.path.display();
    let refuse = |key: &str, why: &str| Error::input(format!("{file}: key '{key}': {why}"));
    let Some(reduction) = &case.reduction else {
        return Ok(model);
    };
    if case.cyclic.is_some() {
        return Err(refuse(
            "cyclic",
            "a matrix case (with [[element]] or [[strip]]) is reduced without cyclic symmetry; remove [cyclic] or model the contacts as [[contact]] interfaces",
        ));
    }
    if reduction.gsi_modes.is_some() {
        return Err(refuse(
            "reduction.gsi_modes",
            "a matrix case has no cyclic frontier to reduce; remove gsi_modes",
        ));
    }
    if matches!(case.model.damping, Some(Damping::Matrix(_))) {
        return Err(refuse(
            "model.damping.matrix",
            "an external damping matrix is not projected on the Craig–Bampton model; give `modal` or `rayleigh` damping with [reduction]",
        ));
    }
    let parts = partition(&model, &matrix_master_groups(case))?;
    check_rows_are_masters(case, &model, &parts)?;
    let cb = craig_bampton(
        model.free.k.as_ref(),
        model.free.m.as_ref(),
        &parts,
        &CbOptions {
            interface_modes: reduction.interface_modes,
            ..CbOptions::default()
        },
    )?;
    log(&format!(
        "Craig–Bampton: {} free DOF → {} masters + {} fixed-interface modes (factorisation {:.2} s, modes {:.2} s, static modes {:.2} s)",
        model.free.n_free(),
        cb.n_masters,
        cb.n_modes(),
        cb.timings.factor_s,
        cb.timings.modes_s,
        cb.timings.static_s
    ));
    // masters by ascending case row, then the modes
    let mut order: Vec<usize> = (0..cb.n_masters).collect();
    order.sort_by_key(|&c| parts.masters[c].free_row);
    order.extend(cb.n_masters..cb.len());
    let mut free_dofs: Vec<usize> = order[..cb.n_masters]
        .iter()
        .map(|&c| model.free.free_dofs[parts.masters[c].free_row])
        .collect();
    free_dofs.extend((0..cb.n_modes()).map(|j| model.n_dofs + j));
    Ok(StructuralModel {
        free: FreeModel {
            k: sparse_permuted(&cb.stiffness, &order)?,
            m: sparse_permuted(&cb.mass, &order)?,
            free_dofs,
            damping: model.free.damping.clone(),
        },
        mesh: model.mesh,
        n_dofs: model.n_dofs,
        dofs: model.dofs,
    })
}

/// Every row the case's elements and strips (also on faces), its excitation `dofs` and its
/// response `dofs` read must be a master: an interior row is an input error naming the key.
fn check_rows_are_masters(case: &Case, model: &StructuralModel, parts: &Partition) -> Result<()> {
    let free_of = free_row_map(model);
    let mut master = vec![false; parts.n_free];
    for d in &parts.masters {
        master[d.free_row] = true;
    }
    let mut rows: Vec<(String, usize)> = Vec::new();
    for (name, e) in case_elements(case, model)? {
        let mut read = vec![("tangential", &e.tangential)];
        if let Some(n) = &e.normal {
            read.push(("normal", n));
        }
        for (what, w) in read {
            rows.extend(w.dofs.iter().map(|&d| (format!("{name}.{what}.dofs"), d)));
        }
    }
    if let Some(ExcitationLoad::Dofs { dofs, .. }) = case.excitation.as_ref().map(|e| &e.load) {
        rows.extend(dofs.iter().map(|&d| ("excitation.dofs".to_string(), d)));
    }
    if let Some(r) = &case.response {
        rows.extend(r.dofs.iter().map(|&d| ("response.dofs".to_string(), d)));
    }
    for (key, d) in rows {
        if let Some(Some(r)) = free_of.get(d) {
            if !master[*r] {
                return Err(Error::input(format!(
                    "{}: key '{key}': row {d} is an interior DOF of the Craig–Bampton reduction ([reduction]); name a group holding its node in `reduction.keep` so that it stays a physical coordinate",
                    case.path.display()
                )));
            }
        }
    }
    Ok(())
}

/// The dense symmetric `a` with rows and columns taken in `order`, as a sparse matrix of its
/// non-zero entries (full storage, the form of [`FreeModel`]).
fn sparse_permuted(a: &Mat<f64>, order: &[usize]) -> Result<SparseColMat<usize, f64>> {
    let n = order.len();
    let mut triplets = Vec::new();
    for (j, &cj) in order.iter().enumerate() {
        for (i, &ci) in order.iter().enumerate() {
            let v = a[(ci, cj)];
            if v != 0.0 {
                triplets.push(Triplet::new(i, j, v));
            }
        }
    }
    SparseColMat::try_new_from_triplets(n, n, &triplets)
        .map_err(|e| Error::Compute(format!("Craig–Bampton model as a sparse matrix: {e:?}")))
}
