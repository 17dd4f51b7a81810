//! SAMA on synthetic geometry: two hexahedral blocks touching on z = 0 (hand-computed
//! misalignment cases, rigid translation, bad input), random curved surfaces (BVH projection
//! against a brute-force search over every face), and the area lumping rule.

mod support;

use nlrom::case::{Contact, ContactElement, ContactModel, Misalignment, Rotation};
use nlrom::interface::project::closest_on_face;
use nlrom::interface::surface::{SurfaceFace, TargetSurface};
use nlrom::interface::weights::lumped_face_area;
use nlrom::interface::{build_interface, ContactInterface};
use nlrom::mesh::{ElementBlock, ElementType, Mesh, MshFormat, MshVersion, PhysicalGroup};
use support::random::SplitMix;

/// Nodes and hexa8 elements of an `n × n × 1` block over [0, 2]² × [z0, z0 + 1], with the quad4
/// faces of its bottom (`top = false`) or top layer of nodes.
struct Block {
    hexes: Vec<u32>,
    quads: Vec<u32>,
}

fn block(coords: &mut Vec<[f64; 3]>, n: usize, z0: f64, top: bool) -> Block {
    let base = coords.len() as u32;
    let h = 2.0 / n as f64;
    for k in 0..2 {
        for j in 0..=n {
            for i in 0..=n {
                coords.push([i as f64 * h, j as f64 * h, z0 + k as f64]);
            }
        }
    }
    let id = |i: usize, j: usize, k: usize| base + (k * (n + 1) * (n + 1) + j * (n + 1) + i) as u32;
    let mut hexes = Vec::new();
    let mut quads = Vec::new();
    for j in 0..n {
        for i in 0..n {
            for k in 0..2 {
                hexes.extend([
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                ]);
            }
            let k = if top { 1 } else { 0 };
            quads.extend([
                id(i, j, k),
                id(i + 1, j, k),
                id(i + 1, j + 1, k),
                id(i, j + 1, k),
            ]);
        }
    }
    Block { hexes, quads }
}

/// Lower block z ∈ [−1, 0] (`target` = its top face, `nt × nt` quads) and upper block
/// z ∈ [gap, 1 + gap] (`contact` = its bottom face, `nc × nc` quads), both over [0, 2]²; plus a
/// surface group `empty` without elements and the volume group `volume`.
fn two_blocks(nc: usize, nt: usize, gap: f64) -> Mesh {
    let mut coords = Vec::new();
    let lower = block(&mut coords, nt, -1.0, true);
    let upper = block(&mut coords, nc, gap, false);
    let mk = |kind: ElementType, phys: i32, first_tag: u64, conn: Vec<u32>| ElementBlock {
        kind,
        entity: phys,
        physicals: vec![phys],
        tags: (0..(conn.len() / kind.num_nodes()) as u64)
            .map(|t| first_tag + t)
            .collect(),
        connectivity: conn,
    };
    let group = |name: &str, dim: u8, tag: i32| PhysicalGroup {
        name: name.into(),
        dim,
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
        blocks: vec![
            mk(ElementType::Hexa8, 1, 1, lower.hexes),
            mk(ElementType::Hexa8, 1, 1001, upper.hexes),
            mk(ElementType::Quad4, 2, 2001, lower.quads),
            mk(ElementType::Quad4, 3, 3001, upper.quads),
        ],
        groups: vec![
            group("volume", 3, 1),
            group("target", 2, 2),
            group("contact", 2, 3),
            group("empty", 2, 4),
        ],
        periodic: Vec::new(),
    }
}

fn contact(model: ContactModel, misalignment: Option<Misalignment>) -> Contact {
    Contact {
        name: "joint".into(),
        contact: "contact".into(),
        target: "target".into(),
        model,
        coupling: None,
        element: ContactElement::OneD,
        mu: 0.3,
        kt: 2.0e6,
        kn: 3.0e6,
        n0: 90.0,
        misalignment,
        evaluation: Default::default(),
    }
}

fn node_at(m: &Mesh, x: [f64; 3], lower: bool) -> u64 {
    let half = m.num_nodes() / 2;
    let range = if lower { 0..half } else { half..m.num_nodes() };
    let i = range
        .into_iter()
        .find(|&i| (0..3).all(|c| (m.coords[i][c] - x[c]).abs() < 1e-12))
        .unwrap();
    m.node_tags[i]
}

fn pair_of(iface: &ContactInterface, node: u64) -> &nlrom::interface::ContactPair {
    iface.pairs.iter().find(|p| p.contact_node == node).unwrap()
}

#[test]
fn conforming_blocks_pair_node_to_node() {
    let m = two_blocks(2, 2, 0.0);
    for model in [ContactModel::NodeToNode, ContactModel::Sama] {
        let iface = build_interface(&contact(model, None), &m, None).unwrap();
        assert_eq!(iface.sigma, 0);
        assert_eq!(iface.pairs.len(), 9);
        for p in &iface.pairs {
            let x = m.coords[p.contact_index as usize];
            assert_eq!(p.targets, vec![node_at(&m, x, true)]);
            assert_eq!(p.weights, vec![1.0]);
            // Outward normal of the lower block's top face: +z, towards the contact body.
            assert_eq!(p.frame[2], [0.0, 0.0, 1.0]);
        }
        // Tributary areas of the 3×3 grid of unit quads: corners 1/4, edges 1/2, centre 1.
        let centre = pair_of(&iface, node_at(&m, [1.0, 1.0, 0.0], false));
        assert!((centre.area - 1.0).abs() < 1e-14);
        assert!((centre.n0_node - 90.0 / 4.0).abs() < 1e-12);
    }
}

#[test]
fn tangential_misalignment_changes_the_pairing_as_computed_by_hand() {
    // Target shifted by (0.25, 0.5, 0): a quarter and a half of its 1 × 1 elements.
    let m = two_blocks(2, 2, 0.0);
    let mis = Misalignment {
        translate: [0.25, 0.5, 0.0],
        rotate: None,
    };
    let iface = build_interface(&contact(ContactModel::Sama, Some(mis)), &m, None).unwrap();
    // Contact nodes with x < 0.25 or y < 0.5 lie outside the shifted target.
    let mut unprojected: Vec<u64> = iface.unprojected.iter().map(|u| u.node).collect();
    unprojected.sort_unstable();
    let mut expected: Vec<u64> = [[0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [0.0, 1.0], [0.0, 2.0]]
        .iter()
        .map(|&[x, y]| node_at(&m, [x, y, 0.0], false))
        .collect();
    expected.sort_unstable();
    assert_eq!(unprojected, expected);
    assert_eq!(iface.pairs.len(), 4);
    // Each is either beyond the search radius (0.5 × mean edge 1) or has a tangential offset.
    for u in &iface.unprojected {
        assert!(
            u.tangential_offset.is_none_or(|t| t > 0.2) && u.distance.is_none_or(|d| d <= 0.5),
            "{u:?}"
        );
    }

    // Contact node (1, 1) in the shifted face of the target nodes (0,0), (1,0), (1,1), (0,1),
    // now at (0.25,0.5), (1.25,0.5), (1.25,1.5), (0.25,1.5): plane distances √0.8125, √0.3125,
    // √0.3125, √0.8125; eq 29: w_j = (1/d_j) / Σ 1/d_i.
    let p = pair_of(&iface, node_at(&m, [1.0, 1.0, 0.0], false));
    let (far, near) = (1.0 / 0.8125f64.sqrt(), 1.0 / 0.3125f64.sqrt());
    let s = 2.0 * far + 2.0 * near;
    let expect = [
        ([0.0, 0.0], far / s),
        ([1.0, 0.0], near / s),
        ([1.0, 1.0], near / s),
        ([0.0, 1.0], far / s),
    ];
    assert_eq!(p.targets.len(), 4);
    for (xy, w) in expect {
        let t = node_at(&m, [xy[0], xy[1], 0.0], true);
        let j = p.targets.iter().position(|&x| x == t).unwrap();
        assert!((p.weights[j] - w).abs() < 1e-15, "{:?} vs {w}", p.weights);
        assert!((p.kt[j] - w * 2.0e6).abs() < 1e-15 * 2.0e6);
    }
    assert_eq!(p.virtual_point, [1.0, 1.0, 0.0]);
    // Preload shared by the projected nodes' tributary areas: (1,1) 1, (2,1) ½, (1,2) ½, (2,2) ¼.
    assert!((p.n0_node - 90.0 / 2.25).abs() < 1e-12);
    let corner = pair_of(&iface, node_at(&m, [2.0, 2.0, 0.0], false));
    assert!((corner.n0_node - 90.0 * 0.25 / 2.25).abs() < 1e-12);
    assert!((iface.sum_n0 - 90.0).abs() < 1e-12);
    assert!((iface.sum_kt - 4.0 * 2.0e6).abs() < 1e-12 * 8e6);
}

#[test]
fn rotational_misalignment_permutes_the_node_pairs() {
    // 90° about the vertical line through (1, 1): the target grid maps onto itself, node (x, y)
    // going to (2 − y, x). Node-to-node pairs follow.
    let m = two_blocks(2, 2, 0.0);
    let mis = Misalignment {
        translate: [0.0; 3],
        rotate: Some(Rotation {
            axis: [0.0, 0.0, 2.0],
            angle_deg: 90.0,
            origin: [1.0, 1.0, -3.0],
        }),
    };
    let iface = build_interface(&contact(ContactModel::NodeToNode, Some(mis)), &m, None).unwrap();
    assert_eq!(iface.pairs.len(), 9);
    for p in &iface.pairs {
        let [x, y, _] = m.coords[p.contact_index as usize];
        // contact (x, y) = image of target (y', ...) with 2 − y' = x, x' = y → target (y, 2 − x)
        assert_eq!(p.targets, vec![node_at(&m, [y, 2.0 - x, 0.0], true)]);
        // t1 = the rotated first edge of the target face: along ±x or ±y, in plane.
        assert!(p.frame[0][2].abs() < 1e-15 && (p.frame[2][2] - 1.0).abs() < 1e-15);
    }
}

#[test]
fn normal_offset_is_the_gap_and_far_targets_are_unprojected() {
    // The upper block 0.1 above: gap 0.1 everywhere (limit 0.5 × mean edge 1 = 0.5).
    let m = two_blocks(3, 2, 0.1);
    let iface = build_interface(&contact(ContactModel::Sama, None), &m, None).unwrap();
    assert_eq!(iface.pairs.len(), 16);
    for p in &iface.pairs {
        assert!((p.gap - 0.1).abs() < 1e-14 && (p.distance - 0.1).abs() < 1e-14);
    }
    // A misalignment pushing the target 0.05 into the contact body: gap −0.05 (interpenetration).
    let mis = Misalignment {
        translate: [0.0, 0.0, 0.15],
        rotate: None,
    };
    let iface = build_interface(&contact(ContactModel::Sama, Some(mis)), &m, None).unwrap();
    assert!(iface.pairs.iter().all(|p| (p.gap + 0.05).abs() < 1e-14));
}

#[test]
fn uniform_translation_of_both_surfaces_changes_nothing() {
    let m = two_blocks(3, 2, 0.0);
    let mut moved = m.clone();
    let d = [0.37, -1.2, 0.05];
    for x in &mut moved.coords {
        for c in 0..3 {
            x[c] += d[c];
        }
    }
    let a = build_interface(&contact(ContactModel::Sama, None), &m, None).unwrap();
    let b = build_interface(&contact(ContactModel::Sama, None), &moved, None).unwrap();
    assert_eq!(a.pairs.len(), 16);
    assert_eq!(a.pairs.len(), b.pairs.len());
    for (p, q) in a.pairs.iter().zip(&b.pairs) {
        assert_eq!(p.targets, q.targets);
        for (x, y) in p.weights.iter().zip(&q.weights) {
            assert!((x - y).abs() < 1e-12);
        }
        assert!(p.gap.abs() < 1e-14 && q.gap.abs() < 1e-14);
    }
}

#[test]
fn bad_input_gives_clear_errors() {
    let m = two_blocks(2, 2, 0.0);
    let msg = |c: Contact, m: &Mesh| {
        let e = build_interface(&c, m, None).unwrap_err();
        assert_eq!(e.exit_code(), 2);
        e.to_string()
    };
    // Empty target group.
    let mut c = contact(ContactModel::Sama, None);
    c.target = "empty".into();
    let s = msg(c, &m);
    assert!(
        s.contains("'joint'") && s.contains("'empty'") && s.contains("no triangle or quad"),
        "{s}"
    );
    // Empty contact group.
    let mut c = contact(ContactModel::Sama, None);
    c.contact = "empty".into();
    let s = msg(c, &m);
    assert!(s.contains("contact group 'empty'"), "{s}");
    // A target group without faces (a volume group).
    let mut c = contact(ContactModel::Sama, None);
    c.target = "volume".into();
    let s = msg(c, &m);
    assert!(
        s.contains("target group 'volume'") && s.contains("dimension 3"),
        "{s}"
    );
    // Unknown group.
    let mut c = contact(ContactModel::Sama, None);
    c.target = "nope".into();
    assert!(msg(c, &m).contains("no physical group named 'nope'"));
    // Groups that do not face each other: upper block 5 above.
    let far = two_blocks(2, 2, 5.0);
    let s = msg(contact(ContactModel::Sama, None), &far);
    assert!(
        s.contains("do not face each other") && s.contains("σ = 0"),
        "{s}"
    );
    // Degenerate target face: collapse the corner (2, 2, 0) of the lower block onto (1, 2, 0).
    let mut bad = m.clone();
    let i = bad.node_index(node_at(&m, [2.0, 2.0, 0.0], true)).unwrap() as usize;
    bad.coords[i] = [1.0, 2.0, 0.0];
    let s = msg(contact(ContactModel::Sama, None), &bad);
    assert!(
        s.contains("degenerate") && s.contains("element 2004"),
        "{s}"
    );
    // Degenerate contact face.
    let mut bad = m.clone();
    let i = bad.node_index(node_at(&m, [2.0, 2.0, 0.0], false)).unwrap() as usize;
    bad.coords[i] = [1.0, 1.0, 0.0];
    let s = msg(contact(ContactModel::Sama, None), &bad);
    assert!(
        s.contains("contact group 'contact'") && s.contains("degenerate"),
        "{s}"
    );
}

// ---------------------------------------------------------------------------------------------
// Random curved surfaces: BVH projection against brute force
// ---------------------------------------------------------------------------------------------

/// A curved height field z = f(x, y) over [0, 1]², `n × n` cells of faces (triangle3/6 pairs or
/// quad8/quad9), nodes (mid-side included) jittered in x, y and lying exactly on the surface
/// (triangle3 faces use the corner nodes only: a faceted surface).
fn curved_surface(kind: ElementType, n: usize, rng: &mut SplitMix) -> TargetSurface {
    let f = |x: f64, y: f64| 0.15 * (3.0 * x).sin() * (2.0 * y).cos() + 0.1 * x * y;
    let m = 2 * n + 1; // nodes per row on the half-step grid
    let h = 0.5 / n as f64;
    let mut points = Vec::new();
    for j in 0..m {
        for i in 0..m {
            let jit = |r: &mut SplitMix, k: usize| {
                if k == 0 || k == m - 1 {
                    0.0
                } else {
                    0.15 * h * (r.next() - 0.5)
                }
            };
            let x = i as f64 * h + jit(rng, i);
            let y = j as f64 * h + jit(rng, j);
            points.push([x, y, f(x, y)]);
        }
    }
    let id = |i: usize, j: usize| (j * m + i) as u32;
    let mut faces = Vec::new();
    for cj in 0..n {
        for ci in 0..n {
            let (i, j) = (2 * ci, 2 * cj);
            let nodes = match kind {
                ElementType::Triangle6 | ElementType::Triangle3 => {
                    let mut first = vec![
                        id(i, j),
                        id(i + 2, j),
                        id(i + 2, j + 2),
                        id(i + 1, j),
                        id(i + 2, j + 1),
                        id(i + 1, j + 1),
                    ];
                    let mut second = vec![
                        id(i, j),
                        id(i + 2, j + 2),
                        id(i, j + 2),
                        id(i + 1, j + 1),
                        id(i + 1, j + 2),
                        id(i, j + 1),
                    ];
                    first.truncate(kind.num_nodes());
                    second.truncate(kind.num_nodes());
                    faces.push(SurfaceFace {
                        kind,
                        nodes: first,
                        tag: faces.len() as u64 + 1,
                    });
                    second
                }
                _ => {
                    let mut v = vec![
                        id(i, j),
                        id(i + 2, j),
                        id(i + 2, j + 2),
                        id(i, j + 2),
                        id(i + 1, j),
                        id(i + 2, j + 1),
                        id(i + 1, j + 2),
                        id(i, j + 1),
                    ];
                    if kind == ElementType::Quad9 {
                        v.push(id(i + 1, j + 1));
                    }
                    v
                }
            };
            faces.push(SurfaceFace {
                kind,
                nodes,
                tag: faces.len() as u64 + 1,
            });
        }
    }
    TargetSurface::new(points, faces, "random surface").unwrap()
}

/// Brute force, no BVH: the nearest point over every face, by Gauss–Newton from 9 starts per face.
fn brute_force(s: &TargetSurface, x: [f64; 3]) -> (usize, f64) {
    let mut best = (usize::MAX, f64::INFINITY);
    for (f, face) in s.faces.iter().enumerate() {
        let xs = s.face_points(f);
        for a in 0..3 {
            for b in 0..3 {
                let uv0 = if face.kind.first_order() == ElementType::Triangle3 {
                    [a as f64 / 3.0, b as f64 / 3.0 * (1.0 - a as f64 / 3.0)]
                } else {
                    [a as f64 - 1.0, b as f64 - 1.0]
                };
                let uv = closest_on_face(face.kind, &xs, x, uv0);
                let (n, _) = nlrom::mesh::faces::surface_shape(face.kind, uv[0], uv[1]);
                let mut p = [0.0; 3];
                for (k, xk) in xs.iter().enumerate() {
                    for c in 0..3 {
                        p[c] += n[k] * xk[c];
                    }
                }
                let d =
                    ((p[0] - x[0]).powi(2) + (p[1] - x[1]).powi(2) + (p[2] - x[2]).powi(2)).sqrt();
                if d < best.1 {
                    best = (f, d);
                }
            }
        }
    }
    best
}

/// Dense sampling of every face (61 × 61 reference points): an upper bound of the distance that
/// does not use the projection code at all.
fn sampled_distance(s: &TargetSurface, x: [f64; 3]) -> f64 {
    let mut best = f64::INFINITY;
    for (f, face) in s.faces.iter().enumerate() {
        let xs = s.face_points(f);
        for a in 0..=60 {
            for b in 0..=60 {
                let (u, v) = if face.kind.first_order() == ElementType::Triangle3 {
                    if a + b > 60 {
                        continue;
                    }
                    (a as f64 / 60.0, b as f64 / 60.0)
                } else {
                    (a as f64 / 30.0 - 1.0, b as f64 / 30.0 - 1.0)
                };
                let (n, _) = nlrom::mesh::faces::surface_shape(face.kind, u, v);
                let mut d2 = 0.0;
                for c in 0..3 {
                    let p: f64 = xs.iter().zip(&n).map(|(xk, nk)| nk * xk[c]).sum();
                    d2 += (p - x[c]).powi(2);
                }
                best = best.min(d2.sqrt());
            }
        }
    }
    best
}

#[test]
fn bvh_projection_matches_brute_force_on_random_curved_surfaces() {
    let mut rng = SplitMix(7);
    for kind in [
        ElementType::Triangle6,
        ElementType::Quad8,
        ElementType::Quad9,
    ] {
        let s = curved_surface(kind, 6, &mut rng);
        let mut checked = 0;
        for _ in 0..150 {
            let (x, y) = (0.03 + 0.94 * rng.next(), 0.03 + 0.94 * rng.next());
            let z = 0.15 * (3.0 * x).sin() * (2.0 * y).cos() + 0.1 * x * y;
            let q = [x, y, z + 0.08 * (rng.next() - 0.5)];
            let p = s.project(q, 1.0).expect("within the search radius");
            let (bf, bd) = brute_force(&s, q);
            assert!(
                (p.distance - bd).abs() < 1e-12,
                "{kind}: {} vs {bd}",
                p.distance
            );
            if p.face != bf {
                // Only on a shared edge: both faces contain the nearest point.
                let other = s.project_on_face(bf, q, [0.2, 0.2]);
                assert!((other.distance - p.distance).abs() < 1e-12);
            }
            // The projection is orthogonal (interior nearest point) and consistent with dense
            // sampling: no sample is nearer, and the nearest sample is within the sampling
            // spacing δ (≤ 0.003 m here: cell 1/6, 60 steps, slopes < 0.6) of the exact foot.
            assert!(
                p.tangential_offset < 1e-10,
                "{kind}: {}",
                p.tangential_offset
            );
            if checked % 10 != 0 {
                checked += 1;
                continue;
            }
            let sampled = sampled_distance(&s, q);
            assert!(
                p.distance <= sampled + 1e-13 && sampled.powi(2) <= p.distance.powi(2) + 9e-6,
                "{kind}: {} vs sampled {sampled}",
                p.distance
            );
            checked += 1;
        }
        assert_eq!(checked, 150);
    }
}

#[test]
fn points_beyond_the_border_have_a_tangential_offset() {
    let mut rng = SplitMix(11);
    let s = curved_surface(ElementType::Quad8, 4, &mut rng);
    // Beyond the edge x = 1 of the surface: the nearest point is on the border, not orthogonal.
    let p = s.project([1.2, 0.5, 0.0], 2.0).unwrap();
    assert!(p.tangential_offset > 0.1, "{p:?}");
    assert!(s.project([5.0, 5.0, 5.0], 0.5).is_none());
}

#[test]
fn hrz_area_lumping_of_quadratic_faces() {
    // Flat triangle6 of area 1/2: corners 1/19 of the area each, mid-sides 16/57.
    let tri: Vec<[f64; 3]> = [
        [0.0, 0.0],
        [1.0, 0.0],
        [0.0, 1.0],
        [0.5, 0.0],
        [0.5, 0.5],
        [0.0, 0.5],
    ]
    .iter()
    .map(|&[u, v]| [u, v, 0.0])
    .collect();
    let a = lumped_face_area(ElementType::Triangle6, &tri);
    for (k, ak) in a.iter().enumerate() {
        let share = if k < 3 { 1.0 / 19.0 } else { 16.0 / 57.0 };
        assert!((ak - 0.5 * share).abs() < 1e-15, "{a:?}");
    }
    // Unit quad4: equal quarters; quad8: all positive (consistent corner loads would be −1/12).
    let quad: Vec<[f64; 3]> = [
        [-1.0, -1.0],
        [1.0, -1.0],
        [1.0, 1.0],
        [-1.0, 1.0],
        [0.0, -1.0],
        [1.0, 0.0],
        [0.0, 1.0],
        [-1.0, 0.0],
    ]
    .iter()
    .map(|&[u, v]| [0.5 * u, 0.5 * v, 0.0])
    .collect();
    let a4 = lumped_face_area(ElementType::Quad4, &quad[..4]);
    assert!(a4.iter().all(|a| (a - 0.25).abs() < 1e-15), "{a4:?}");
    let a8 = lumped_face_area(ElementType::Quad8, &quad);
    assert!(a8.iter().all(|&a| a > 0.0));
    assert!((a8.iter().sum::<f64>() - 1.0).abs() < 1e-14);
}
