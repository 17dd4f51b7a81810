//! Helpers of the full-annulus cyclic-symmetry tests (tests/cyclic_annulus.rs,
//! tests/cyclic_axis.rs): the full model made of N merged sector copies, the per-k sparse sector
//! frequencies and their union.
#![allow(dead_code)]

use nlrom::case::Case;
use nlrom::cyclic::{match_frontiers, CyclicGeometry, CyclicTransform};
use nlrom::eigen::{lowest_modes, EigenOptions};
use nlrom::fe::{assemble, clamp, Material, Materials, Quadrature};
use nlrom::mesh::{ElementBlock, Mesh};
use nlrom::model::StructuralModel;
use nlrom::reduction::free_frontier_pairs;

/// The material of the sector models of these tests (steel, SI units).
pub const STEEL: Material = Material {
    young: 210e9,
    poisson: 0.3,
    density: 7800.0,
};

/// The `n` lowest natural frequencies (Hz) of `mesh` (steel) assembled by nlrom as an ordinary
/// model and clamped on the group `clamp_group`: the full-model reference of the union over k.
pub fn full_model_frequencies(mesh: &Mesh, clamp_group: &str, n: usize) -> Vec<f64> {
    let full = assemble(mesh, &Materials::uniform(STEEL), &Quadrature::default()).unwrap();
    let free = clamp(&full, mesh, &[clamp_group.to_string()]).unwrap();
    let modes = lowest_modes(
        free.k.as_ref(),
        free.m.as_ref(),
        n,
        &EigenOptions::default(),
    )
    .expect("full-model modes");
    modes.frequencies_hz()
}

/// N rotated copies of `sector` about the z axis, each `high` node merged with the `low` node of
/// the next copy and the nodes on the axis shared by all copies; only the volume elements and
/// the 2-D elements of the group `boundary` (the clamp) are kept.
pub fn merge_sectors(sector: &Mesh, n: usize, low: &str, high: &str, boundary: &str) -> Mesh {
    let geom = CyclicGeometry::new(n, [0.0; 3], [0.0, 0.0, 1.0]).unwrap();
    let pairs = match_frontiers(sector, &geom, low, high).unwrap();
    let nn = sector.num_nodes();
    let mut low_of_high = vec![u32::MAX; nn];
    for (&l, &h) in pairs.low.iter().zip(&pairs.high) {
        low_of_high[h as usize] = l;
    }
    let mut on_axis = vec![false; nn];
    for &a in &pairs.axis_nodes {
        on_axis[a as usize] = true;
    }
    // Global id of node m of copy s (before compaction).
    let id = |s: usize, m: u32| -> usize {
        if on_axis[m as usize] {
            return m as usize;
        }
        match low_of_high[m as usize] {
            u32::MAX => s * nn + m as usize,
            l => ((s + 1) % n) * nn + l as usize,
        }
    };
    let mut index = vec![u32::MAX; n * nn];
    let mut coords = Vec::new();
    for s in 0..n {
        for m in 0..nn as u32 {
            if low_of_high[m as usize] == u32::MAX && (s == 0 || !on_axis[m as usize]) {
                index[id(s, m)] = coords.len() as u32;
                coords.push(geom.rotate_point(sector.coords[m as usize], s as i32));
            }
        }
    }
    let clamp = sector.group(boundary).unwrap().clone();
    let mut blocks = Vec::new();
    for s in 0..n {
        for b in &sector.blocks {
            let keep = b.kind.dim() == 3 || (b.kind.dim() == 2 && b.physicals.contains(&clamp.tag));
            if !keep {
                continue;
            }
            blocks.push(ElementBlock {
                kind: b.kind,
                entity: b.entity,
                physicals: b.physicals.clone(),
                tags: b.tags.iter().map(|t| t + (s as u64) * 1_000_000).collect(),
                connectivity: b.connectivity.iter().map(|&m| index[id(s, m)]).collect(),
            });
        }
    }
    Mesh {
        source: None,
        format: sector.format,
        node_tags: (1..=coords.len() as u64).collect(),
        coords,
        blocks,
        groups: sector.groups.clone(),
        periodic: Vec::new(),
    }
}

/// Frequencies (Hz) of the sparse sector model of harmonic index k (T_kᴴ K T_k, no CB): the
/// lowest `n` distinct ones (the real embedding of a complex k doubles every eigenvalue).
pub fn sparse_sector_frequencies(
    model: &StructuralModel,
    case: &Case,
    k: usize,
    n: usize,
) -> Vec<f64> {
    let (geom, pairs) = free_frontier_pairs(case, model).unwrap();
    let t = CyclicTransform::new(&geom, k, model.free.n_free(), &pairs).unwrap();
    let kk = t.project_sparse_embedded(model.free.k.as_ref()).unwrap();
    let mk = t.project_sparse_embedded(model.free.m.as_ref()).unwrap();
    let copies = if t.real { 1 } else { 2 };
    let modes = lowest_modes(
        kk.as_ref(),
        mk.as_ref(),
        copies * n,
        &EigenOptions::default(),
    )
    .expect("sector modes");
    let f = modes.frequencies_hz();
    if copies == 2 {
        for p in f.chunks(2) {
            assert!(
                (p[0] / p[1] - 1.0).abs() < 1e-9,
                "k = {k}: embedding pair {p:?}"
            );
        }
    }
    f.iter().step_by(copies).copied().collect()
}

/// Union over k of per-k frequencies, cut below the smallest per-k maximum (so no frequency of
/// any k is missing below the cut), sorted.
pub fn union_below_cut(per_k: &[Vec<f64>]) -> Vec<f64> {
    let cut = per_k
        .iter()
        .map(|f| *f.last().unwrap())
        .fold(f64::INFINITY, f64::min);
    let mut all: Vec<f64> = per_k
        .iter()
        .flatten()
        .copied()
        .filter(|&f| f < cut)
        .collect();
    all.sort_by(f64::total_cmp);
    all
}

/// Largest |a_i / b_i − 1|.
pub fn max_rel_error(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x / y - 1.0).abs())
        .fold(0.0, f64::max)
}

/// The cyclic-symmetry check: the union over k of the sector frequencies `per_k` (Hz) below the
/// common cut against the lowest frequencies of the full model, `full(n)` giving its lowest n.
/// Asserts at least `min_count` frequencies, agreement to 1e-8 relative, and that the next full
/// frequency lies above the cut (no mode of the full model missed). Returns (union, reference).
pub fn check_union_against_full(
    per_k: &[Vec<f64>],
    full: impl Fn(usize) -> Vec<f64>,
    min_count: usize,
    label: &str,
) -> (Vec<f64>, Vec<f64>) {
    let union = union_below_cut(per_k);
    let reference = full(union.len() + 2);
    println!("full model (Hz): {:?}", &reference[..union.len()]);
    println!("union over k of the sector (Hz): {union:?}");
    let err = max_rel_error(&union, &reference);
    println!(
        "{label}: {} frequencies, max relative error {err:.2e}",
        union.len()
    );
    assert!(union.len() >= min_count, "{}", union.len());
    assert!(err < 1e-8, "{err:e}");
    assert!(reference[union.len()] >= union[union.len() - 1] * (1.0 - 1e-8));
    (union, reference)
}
