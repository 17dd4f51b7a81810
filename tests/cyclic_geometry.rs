//! Cyclic-symmetry geometry (`docs/conventions.md` §2): sector rotation, frontier pairing on the bundled
//! sector models (N = 24 about z through the origin), harmonic indices.

use std::path::PathBuf;

use nlrom::case::{Axis, Cyclic};
use nlrom::cyclic::{
    check_frontier_clamps, check_harmonic_index, distinct_harmonic_indices, harmonic_indices,
    match_frontiers, phase, CyclicGeometry, FrontierPairs,
};
use nlrom::mesh::msh::read_msh;
use nlrom::mesh::Mesh;
use nlrom::Error;

type Mat = [[f64; 3]; 3];

fn mesh(name: &str) -> Mesh {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("meshes")
        .join(format!("{name}.msh"));
    read_msh(&p).unwrap()
}

fn z_axis(sectors: usize) -> CyclicGeometry {
    CyclicGeometry::from_case(&Cyclic {
        sectors,
        axis: Axis::default(),
        low: "left_frontier".into(),
        high: "right_frontier".into(),
    })
    .unwrap()
}

fn mul(a: &Mat, b: &Mat) -> Mat {
    let mut c = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            c[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    c
}

fn dist_to_identity(a: &Mat) -> f64 {
    let mut d: f64 = 0.0;
    for (i, row) in a.iter().enumerate() {
        for (j, &v) in row.iter().enumerate() {
            d = d.max((v - if i == j { 1.0 } else { 0.0 }).abs());
        }
    }
    d
}

fn dist(a: [f64; 3], b: [f64; 3]) -> f64 {
    ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2) + (a[2] - b[2]).powi(2)).sqrt()
}

/// Every pair satisfies R_α X_low = X_high to 1e-12 × model size; low ascending.
fn check_pairs(m: &Mesh, g: &CyclicGeometry, p: &FrontierPairs) {
    let size = m.size();
    assert_eq!(p.low.len(), p.high.len());
    assert!(p.low.windows(2).all(|w| w[0] < w[1]), "low not ascending");
    for (&l, &h) in p.low.iter().zip(&p.high) {
        let img = g.rotate_point(m.coords[l as usize], 1);
        let e = dist(img, m.coords[h as usize]);
        assert!(e <= 1e-12 * size, "pair {l}->{h}: error {e:e}");
    }
}

fn input_message(e: Error) -> String {
    match e {
        Error::Input(s) => s,
        other => panic!("expected Error::Input, got {other:?}"),
    }
}

#[test]
fn rotation_powers_compose_to_identity() {
    for n in [2usize, 3, 7, 24, 37] {
        let g = CyclicGeometry::new(n, [0.1, -0.2, 0.3], [1.0, 2.0, -0.5]).unwrap();
        let r = g.rotation(1);
        let mut acc = r;
        for _ in 1..n {
            acc = mul(&acc, &r);
        }
        assert!(dist_to_identity(&acc) < 1e-14, "N = {n}: R^N - I = {acc:?}");
        assert!(dist_to_identity(&g.rotation(n as i32)) == 0.0);
        for sigma in [-5i32, -1, 1, 2, 11] {
            let p = mul(&g.rotation(sigma), &g.rotation(-sigma));
            assert!(dist_to_identity(&p) < 1e-15, "N = {n}, σ = {sigma}");
            // R^σ = (R_α)^σ for positive σ
            if sigma > 0 {
                let mut acc = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
                for _ in 0..sigma {
                    acc = mul(&acc, &r);
                }
                let rs = g.rotation(sigma);
                for i in 0..3 {
                    for j in 0..3 {
                        assert!((acc[i][j] - rs[i][j]).abs() < 1e-14);
                    }
                }
            }
        }
    }
}

#[test]
fn rotation_about_tilted_offset_axis() {
    // Axis through (1, 2, 3) along (1, 1, 1)/√3, N = 3 (α = 120°): the rotation by +120° about
    // (1,1,1) permutes the coordinate axes x → y → z → x. Relative to the origin (1,2,3), the point
    // (2,2,3) has offset (1,0,0) ↦ (0,1,0), i.e. the point (1,3,3); σ = −1: offset (0,0,1) → (1,2,4).
    let g = CyclicGeometry::new(3, [1.0, 2.0, 3.0], [2.0, 2.0, 2.0]).unwrap();
    let p = g.rotate_point([2.0, 2.0, 3.0], 1);
    assert!(dist(p, [1.0, 3.0, 3.0]) < 1e-14, "{p:?}");
    let p = g.rotate_point([2.0, 2.0, 3.0], -1);
    assert!(dist(p, [1.0, 2.0, 4.0]) < 1e-14, "{p:?}");
    let v = g.rotate_vector([0.0, 0.0, 5.0], 1);
    assert!(dist(v, [5.0, 0.0, 0.0]) < 1e-14, "{v:?}");
    // Points on the axis are fixed.
    let on = [1.0 + 0.7, 2.0 + 0.7, 3.0 + 0.7];
    assert!(dist(g.rotate_point(on, 1), on) < 1e-14);
    assert!(g.distance_to_axis(on) < 1e-15);

    // A quarter turn about -x through (0, 1, 0): (0, 2, 0) → offset (0,1,0) ↦ (0,0,-1).
    let g = CyclicGeometry::new(4, [0.0, 1.0, 0.0], [-3.0, 0.0, 0.0]).unwrap();
    let p = g.rotate_point([0.0, 2.0, 0.0], 1);
    assert!(dist(p, [0.0, 1.0, -1.0]) < 1e-15, "{p:?}");
}

#[test]
fn invalid_geometry() {
    for (n, d) in [
        (1usize, [0.0, 0.0, 1.0]),
        (0, [0.0, 0.0, 1.0]),
        (4, [0.0; 3]),
    ] {
        let msg = input_message(CyclicGeometry::new(n, [0.0; 3], d).unwrap_err());
        assert!(msg.contains("[cyclic]"), "{msg}");
    }
}

#[test]
fn conforming_frontiers_pair_up() {
    let m = mesh("sector_conforming");
    let g = z_axis(24);
    let p = match_frontiers(&m, &g, "left_frontier", "right_frontier").unwrap();
    // The axis is far from the disk (r ≥ 0.10): no axis node.
    assert!(p.axis_nodes.is_empty());
    assert_eq!(p.len(), 65);
    assert_eq!(p.low, m.nodes_of("left_frontier").unwrap());
    let mut high = p.high.clone();
    high.sort_unstable();
    assert_eq!(high, m.nodes_of("right_frontier").unwrap());
    check_pairs(&m, &g, &p);

    // Mid-edge nodes are paired too: the low frontier's triangle6 nodes 3..6 (Gmsh order) are
    // mid-edge, and each one's partner is a mid-edge node of the high frontier.
    let group = m.group("left_frontier").unwrap().clone();
    let mid: std::collections::BTreeSet<u32> = m
        .group_blocks(&group)
        .flat_map(|b| {
            b.elements()
                .flat_map(|e| e[3..6].to_vec())
                .collect::<Vec<_>>()
        })
        .collect();
    assert!(mid.len() > 30, "{} mid-edge nodes", mid.len());
    assert!(mid.iter().all(|n| p.low.binary_search(n).is_ok()));
    // $Periodic lists corners only: the position matching finds strictly more pairs.
    let periodic_pairs: usize = m
        .periodic
        .iter()
        .filter(|l| l.dim == 2)
        .map(|l| l.nodes.len())
        .max()
        .unwrap_or(0);
    assert!(periodic_pairs < 65, "{periodic_pairs}");
}

#[test]
fn conforming_shroud_faces_pair_up() {
    let m = mesh("sector_conforming");
    let g = z_axis(24);
    // shroud_target lies on θ = 0 (low), shroud_contact on θ = α (high).
    let p = match_frontiers(&m, &g, "shroud_target", "shroud_contact").unwrap();
    assert_eq!(p.len(), 65);
    assert!(p.axis_nodes.is_empty());
    check_pairs(&m, &g, &p);

    // Same faces given the wrong way round: error that says to swap them.
    let msg =
        input_message(match_frontiers(&m, &g, "shroud_contact", "shroud_target").unwrap_err());
    assert!(msg.contains("swap"), "{msg}");
}

#[test]
fn nonconforming_shroud_faces_do_not_pair() {
    let m = mesh("sector_nonconforming");
    let g = z_axis(24);
    // The disk frontiers of the non-conforming model still pair.
    let p = match_frontiers(&m, &g, "left_frontier", "right_frontier").unwrap();
    assert_eq!(p.len(), 65);
    check_pairs(&m, &g, &p);

    let msg =
        input_message(match_frontiers(&m, &g, "shroud_target", "shroud_contact").unwrap_err());
    eprintln!("{msg}");
    assert!(msg.contains("sector_nonconforming.msh"), "{msg}");
    assert!(msg.contains("'shroud_target' (213 nodes)"), "{msg}");
    assert!(msg.contains("'shroud_contact' (65 nodes)"), "{msg}");
    assert!(msg.contains("different node counts"), "{msg}");
    assert!(msg.contains("setPeriodic"), "{msg}");
    assert!(msg.contains("[cyclic] sectors"), "{msg}");
    // Names unmatched nodes by tag, at most 10 listed, then the rest counted.
    let target = m.nodes_of("shroud_target").unwrap();
    let listed = target
        .iter()
        .filter(|&&n| msg.contains(&format!("node {} (", m.node_tags[n as usize])))
        .count();
    assert!(
        (1..=10).contains(&listed),
        "{listed} target nodes listed: {msg}"
    );
    assert!(msg.contains("more)"), "{msg}");
}

#[test]
fn wrong_sector_count_is_an_error() {
    let m = mesh("sector_conforming");
    let g = z_axis(23);
    let msg =
        input_message(match_frontiers(&m, &g, "left_frontier", "right_frontier").unwrap_err());
    eprintln!("{msg}");
    assert!(msg.contains("65 node(s) of 'right_frontier'"), "{msg}");
    assert!(msg.contains("65 node(s) of 'left_frontier'"), "{msg}");
    assert!(msg.contains("N = 23"), "{msg}");
    assert!(msg.contains("tolerance"), "{msg}");
    assert!(msg.contains("[cyclic] sectors"), "{msg}");
    // Tags of unmatched nodes are named.
    let tag = m.node_tags[m.nodes_of("right_frontier").unwrap()[0] as usize];
    assert!(msg.contains(&format!("node {tag} (")), "{msg}");
}

#[test]
fn bad_groups() {
    let m = mesh("sector_conforming");
    let g = z_axis(24);
    // Same group twice: shares all its nodes.
    let msg = input_message(match_frontiers(&m, &g, "left_frontier", "left_frontier").unwrap_err());
    assert!(msg.contains("share 65 node(s)"), "{msg}");
    // Unknown group: the mesh's error names the groups there are.
    let msg = input_message(match_frontiers(&m, &g, "left", "right_frontier").unwrap_err());
    assert!(msg.contains("no physical group named 'left'"), "{msg}");
}

/// A mesh of point elements: `low` and `high` groups (dim 0) on a grid of the half-planes θ = 0
/// and θ = α about z (N sectors), `nr × nz` nodes each, with `nz` nodes on the axis shared by both.
fn synthetic_frontiers(sectors: usize, nr: usize, nz: usize) -> Mesh {
    use nlrom::mesh::{ElementBlock, ElementType, MshFormat, MshVersion, PhysicalGroup};
    let alpha = 2.0 * std::f64::consts::PI / sectors as f64;
    let (s, c) = alpha.sin_cos();
    let mut coords = Vec::new();
    let (mut low, mut high) = (Vec::new(), Vec::new());
    for iz in 0..nz {
        let z = iz as f64 * 0.01;
        coords.push([0.0, 0.0, z]); // on the axis: in both groups
        let a = (coords.len() - 1) as u32;
        low.push(a);
        high.push(a);
        for ir in 1..=nr {
            let r = ir as f64 * 0.01;
            coords.push([r, 0.0, z]);
            low.push((coords.len() - 1) as u32);
            coords.push([r * c, r * s, z]);
            high.push((coords.len() - 1) as u32);
        }
    }
    let block = |tag: i32, nodes: Vec<u32>| ElementBlock {
        kind: ElementType::Point,
        entity: tag,
        physicals: vec![tag],
        tags: (0..nodes.len() as u64)
            .map(|t| t + 1000 * tag as u64)
            .collect(),
        connectivity: nodes,
    };
    let group = |name: &str, tag: i32| PhysicalGroup {
        name: name.into(),
        dim: 0,
        tag,
    };
    Mesh {
        source: None,
        format: MshFormat {
            version: MshVersion::V41,
            binary: false,
            big_endian: false,
        },
        node_tags: (1..=coords.len() as u64).collect(),
        coords,
        blocks: vec![block(1, low), block(2, high)],
        groups: vec![group("low", 1), group("high", 2)],
        periodic: Vec::new(),
    }
}

#[test]
fn axis_nodes_are_reported_separately() {
    let m = synthetic_frontiers(6, 3, 4);
    let g = CyclicGeometry::new(6, [0.0; 3], [0.0, 0.0, 1.0]).unwrap();
    let p = match_frontiers(&m, &g, "low", "high").unwrap();
    assert_eq!(p.len(), 12);
    assert_eq!(p.axis_nodes, vec![0, 7, 14, 21]);
    assert!(p
        .axis_nodes
        .iter()
        .all(|a| !p.low.contains(a) && !p.high.contains(a)));
    check_pairs(&m, &g, &p);
}

#[test]
fn large_frontiers_match_quickly() {
    // 2 × 20 100 nodes (the quadratic search would need 4e8 distance evaluations).
    let m = synthetic_frontiers(24, 200, 100);
    let g = z_axis(24);
    let t = std::time::Instant::now();
    let p = match_frontiers(&m, &g, "low", "high").unwrap();
    let dt = t.elapsed();
    assert_eq!(p.len(), 20_000);
    assert_eq!(p.axis_nodes.len(), 100);
    check_pairs(&m, &g, &p);
    assert!(dt.as_secs_f64() < 2.0, "matching took {dt:?}");
}

#[test]
fn clamp_consistency() {
    let m = mesh("sector_conforming");
    let g = z_axis(24);
    let p = match_frontiers(&m, &g, "left_frontier", "right_frontier").unwrap();
    // The hub meets both frontiers along its edges: a consistent clamp, the clamped pairs come back.
    let hub = m.nodes_of("hub").unwrap();
    let both =
        check_frontier_clamps(&m, &p, "left_frontier", "right_frontier", &["hub".into()]).unwrap();
    assert!(!both.is_empty());
    for &i in &both {
        assert!(hub.binary_search(&p.low[i]).is_ok() && hub.binary_search(&p.high[i]).is_ok());
    }
    // Clamping one frontier only: error naming the frontier and the clamp group.
    let msg = input_message(
        check_frontier_clamps(
            &m,
            &p,
            "left_frontier",
            "right_frontier",
            &["hub".into(), "left_frontier".into()],
        )
        .unwrap_err(),
    );
    assert!(
        msg.contains("frontier 'left_frontier' touches the clamp group 'left_frontier'"),
        "{msg}"
    );
    let n_bad = 65 - both.len();
    assert!(msg.contains(&format!("{n_bad} frontier node(s)")), "{msg}");
    // No clamp at all: nothing to report.
    assert!(
        check_frontier_clamps(&m, &p, "left_frontier", "right_frontier", &[])
            .unwrap()
            .is_empty()
    );
}

#[test]
fn harmonic_indices_of_engine_orders() {
    assert_eq!(harmonic_indices(24, 3, 5), vec![0, 3, 6, 9, 12, 15]);
    assert_eq!(harmonic_indices(8, 3, 4), vec![0, 3, 6, 1, 4]);
    assert_eq!(distinct_harmonic_indices(8, 3, 4), vec![0, 1, 3, 4, 6]);
    assert_eq!(
        distinct_harmonic_indices(24, 3, 5),
        vec![0, 3, 6, 9, 12, 15]
    );
    // Wrap-around and repeats: N = 6, m = 4 → 0, 4, 2, 0, 4.
    assert_eq!(harmonic_indices(6, 4, 4), vec![0, 4, 2, 0, 4]);
    assert_eq!(distinct_harmonic_indices(6, 4, 4), vec![0, 2, 4]);
    // Engine order ≥ N behaves like m mod N.
    assert_eq!(harmonic_indices(8, 11, 4), harmonic_indices(8, 3, 4));
    assert!((phase(6, 24) - std::f64::consts::FRAC_PI_2).abs() < 1e-15);
    assert!(check_harmonic_index(23, 24).is_ok());
    let msg = input_message(check_harmonic_index(24, 24).unwrap_err());
    assert!(msg.contains("k = 24") && msg.contains("N = 24"), "{msg}");
}
