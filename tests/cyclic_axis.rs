//! Cyclic symmetry with nodes on the axis: a sector of a solid disk without a
//! hole (meshes/disk8.msh, `tools/meshes/make_disk_mesh.py`: N = 8, radius 0.1 m, thickness 0.01 m,
//! tetra10, rim clamped), whose z-axis edge belongs to both frontiers. Each axis node obeys
//! `u = e^{iφ_k} R_α u` (`nlrom::cyclic::axis_basis`). Reference: the full disk — 8 rotated
//! copies merged at the frontiers, the axis nodes once — assembled and clamped by nlrom as an
//! ordinary model; the union over k = 0..7 of the sector frequencies must equal its spectrum to
//! 1e-8 (sparse sector T_kᴴ K T_k; measured 3.6e-14), and CB + CS must follow it to the CB
//! accuracy (1e-3). Plate theory as a sanity check: the lowest k = 0 mode, 2516 Hz, against
//! 2554 Hz for a clamped thin circular plate (λ² = 10.22).

mod support;

use std::path::PathBuf;

use nlrom::case::Case;
use nlrom::cyclic::{axis_basis, match_frontiers, CyclicGeometry};
use nlrom::eigen::hermitian_modes;
use nlrom::mesh::msh::read_msh;
use nlrom::model::{self, StructuralModel};
use nlrom::reduction::{free_frontier_pairs, Sector};
use support::cyclic::{
    check_union_against_full, full_model_frequencies, max_rel_error, merge_sectors,
    sparse_sector_frequencies,
};

const N: usize = 8;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn sector_case() -> (Case, StructuralModel) {
    let text = format!(
        r#"
[model]
mesh = "../meshes/disk8.msh"
material = {{ young = 210e9, poisson = 0.3, density = 7800.0 }}
clamp = ["rim"]

[cyclic]
sectors = {N}
low = "low"
high = "high"

[reduction]
interface_modes = 60
"#
    );
    let case = Case::from_str(&text, &root().join("cases/test_disk.toml")).expect("case");
    let model = model::build(&case, &mut |_| {}).expect("model");
    (case, model)
}

/// The lowest `n` frequencies (Hz) of the full disk, rim clamped.
fn disk_frequencies(n: usize) -> Vec<f64> {
    let sector = read_msh(&root().join("meshes/disk8.msh")).unwrap();
    let geom = CyclicGeometry::new(N, [0.0; 3], [0.0, 0.0, 1.0]).unwrap();
    let pairs = match_frontiers(&sector, &geom, "low", "high").unwrap();
    assert!(pairs.axis_nodes.len() >= 3, "{:?}", pairs.axis_nodes);
    let mesh = merge_sectors(&sector, N, "low", "high", "rim");
    full_model_frequencies(&mesh, "rim", n)
}

// The basis vectors satisfy u = e^{iφ_k} R_α u and are orthonormal; k = 2..6 leave none.
#[test]
fn axis_basis_satisfies_the_constraint() {
    for n in [2usize, 3, 8] {
        let geom = CyclicGeometry::new(n, [0.1, -0.2, 0.3], [1.0, 2.0, 2.0]).unwrap();
        let r = geom.rotation(1);
        for k in 0..n {
            let basis = axis_basis(&geom, k);
            let expected = match (n, k) {
                (_, 0) => 1,
                (2, 1) => 2,
                (_, k) if k == 1 || k == n - 1 => 1,
                _ => 0,
            };
            assert_eq!(basis.len(), expected, "N = {n}, k = {k}");
            let e = nlrom::cyclic::phase_factor(k, n);
            for (i, b) in basis.iter().enumerate() {
                for c in 0..3 {
                    let rb: faer::c64 = (0..3).map(|d| b[d] * r[c][d]).sum();
                    assert!((e * rb - b[c]).norm() < 1e-15, "N = {n}, k = {k}");
                }
                for (j, o) in basis.iter().enumerate() {
                    let dot: faer::c64 = (0..3).map(|c| b[c].conj() * o[c]).sum();
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((dot - want).norm() < 1e-15, "N = {n}, k = {k}");
                }
            }
        }
    }
}

#[test]
fn disk_with_axis_nodes_union_of_sector_frequencies_is_the_full_spectrum() {
    let (case, model) = sector_case();
    let per_k = 4;
    let (_, pairs) = free_frontier_pairs(&case, &model).unwrap();
    assert!(pairs.iter().any(|p| p.is_axis()));
    let sparse: Vec<Vec<f64>> = (0..N)
        .map(|k| sparse_sector_frequencies(&model, &case, k, per_k))
        .collect();
    check_union_against_full(&sparse, disk_frequencies, 16, "axis nodes, cs without CB");

    // CB + CS with the axis nodes as masters (60 interface modes): the CB truncation error,
    // measured 4.2e-4..7.0e-4 for every k (with or without axis coordinates).
    let sector = Sector::build(&case, &model, &mut |_| {}).unwrap();
    let cb: Vec<Vec<f64>> = (0..N)
        .map(|k| {
            let h = sector.harmonic(k, None).unwrap();
            hermitian_modes(h.stiffness.as_ref(), h.mass.as_ref(), h.real)
                .unwrap()
                .frequencies_hz(per_k)
        })
        .collect();
    let per_k: Vec<f64> = (0..N).map(|k| max_rel_error(&cb[k], &sparse[k])).collect();
    let listed: Vec<String> = per_k.iter().map(|e| format!("{e:.1e}")).collect();
    println!(
        "axis nodes, CB+CS vs sparse cs, max relative error per k: {}",
        listed.join(" ")
    );
    let err_cb = per_k.iter().copied().fold(0.0, f64::max);
    assert!(err_cb < 1e-3, "{err_cb:e}");
}
