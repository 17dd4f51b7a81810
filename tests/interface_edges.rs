//! SAMA at the edges of curved, tilted, non-conforming interfaces.
//!
//! The interface is a Z-shroud-like contact face generated here: the plane through the radial
//! direction x, tilted by β about it, cut by the cylinders r = 0.09 m and r = 0.1 m (an arc of an
//! ellipse in the plane, of curvature up to sin²β / r: straight at β = 0) and by two straight
//! lines, optionally bulged into a cylindrical surface. A block of tetrahedra (tetra4, or tetra10
//! with its mid-side nodes on the curved geometry) is meshed on either side with different,
//! graded node spacings, so the meshes do not conform and the contact nodes on the outer curved
//! edge lie outside the chorded target faces, by up to the chord's sagitta.
//!
//! Checked: every contact node is paired; the sums of eq 32 (Battiato 2021) to 1e-12; the
//! weights of the nodes on the face's boundary equal those at the nearest target point found by
//! brute force (dense sampling of every target face, then a derivative-free pattern search),
//! for both couplings; a contact row beyond the target (no overlap) stays unprojected; and on the
//! bundled non-conforming models the nodes that project inside a face keep exactly the weights
//! they have with the edge tolerance set to zero.

use std::path::Path;

use nlrom::case::{Case, Contact, ContactElement, ContactModel, Misalignment, SamaCoupling};
use nlrom::cyclic::CyclicGeometry;
use nlrom::interface::{build_interface_with, build_interfaces_with, ContactInterface};
use nlrom::mesh::msh::read_msh;
use nlrom::mesh::{ElementBlock, ElementType, Mesh, MshFormat, MshVersion, PhysicalGroup};

const R_IN: f64 = 0.09;
const R_OUT: f64 = 0.1;
const HALF_SPAN: f64 = 0.03;
const THICKNESS: f64 = 0.004;
const KT: f64 = 2.0e6;
const KN: f64 = 3.0e6;
const N0: f64 = 90.0;

/// The interface geometry: tilt β (rad) and bulge radius ρ (m, 0 = flat).
#[derive(Clone, Copy)]
struct Shape {
    tilt: f64,
    bulge: f64,
}

impl Shape {
    /// In-plane axes e1 = x, e2 (the tilted axial direction) and the plane normal n = e1 × e2.
    fn axes(self) -> ([f64; 3], [f64; 3], [f64; 3]) {
        let (s, c) = self.tilt.sin_cos();
        ([1.0, 0.0, 0.0], [0.0, -s, c], [0.0, -c, -s])
    }

    /// The point of the interface at (ξ, η) ∈ [0, 1]², moved by `offset` (m) along n.
    fn point(self, xi: f64, eta: f64, offset: f64) -> [f64; 3] {
        let s = HALF_SPAN * (2.0 * eta - 1.0);
        let sb2 = (s * self.tilt.sin()).powi(2);
        let (a_in, a_out) = ((R_IN * R_IN - sb2).sqrt(), (R_OUT * R_OUT - sb2).sqrt());
        let a = a_in + xi * (a_out - a_in);
        let w = if self.bulge > 0.0 {
            self.bulge - (self.bulge * self.bulge - s * s).sqrt()
        } else {
            0.0
        };
        let (e1, e2, n) = self.axes();
        std::array::from_fn(|c| a * e1[c] + s * e2[c] + (w + offset) * n[c])
    }
}

/// One meshed block: cells along ξ and η, a grading of η, and its side of the interface.
#[derive(Clone, Copy)]
struct Grid {
    nx: usize,
    ny: usize,
    /// Amplitude of the η grading (0 = uniform).
    grade: f64,
}

/// Appends the nodes and elements of one block (one layer of Kuhn-split cells, 6 tets each) to
/// the mesh under construction. `below` = the target (ζ ∈ [−1, 0], face at ζ = 0), else the
/// contact block (ζ ∈ [0, 1] shifted by `gap`, face at ζ = 0). Returns (tets, face triangles).
fn block(
    coords: &mut Vec<[f64; 3]>,
    shape: Shape,
    g: Grid,
    order: usize,
    below: bool,
    gap: f64,
) -> (Vec<u32>, Vec<u32>) {
    let base = coords.len() as u32;
    let (mx, my, mz) = (order * g.nx, order * g.ny, order);
    let eta = |t: f64| {
        t + g.grade * (2.0 * std::f64::consts::PI * t).sin() / (2.0 * std::f64::consts::PI)
    };
    for k in 0..=mz {
        for j in 0..=my {
            for i in 0..=mx {
                let zeta = k as f64 / mz as f64 - if below { 1.0 } else { 0.0 };
                let off = zeta * THICKNESS + if below { 0.0 } else { gap };
                coords.push(shape.point(i as f64 / mx as f64, eta(j as f64 / my as f64), off));
            }
        }
    }
    // Fine-lattice node id; corners of cell (i, j, k) are at order × (i + a, j + b, k + c).
    let id = |p: [usize; 3]| base + (p[2] * (my + 1) * (mx + 1) + p[1] * (mx + 1) + p[0]) as u32;
    let corner = |c: [usize; 3]| c.map(|v| v * order);
    let mid = |a: [usize; 3], b: [usize; 3]| -> [usize; 3] { std::array::from_fn(|d| a[d] + b[d]) };
    let mut tets = Vec::new();
    let mut tris = Vec::new();
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    for j in 0..g.ny {
        for i in 0..g.nx {
            for perm in perms {
                let mut c = [[i, j, 0]; 4];
                for s in 0..3 {
                    c[s + 1] = c[s];
                    c[s + 1][perm[s]] += 1;
                }
                let mut v = c.map(&corner);
                let x = v.map(|p| coords[id(p) as usize]);
                let e = |a: usize| std::array::from_fn::<f64, 3, _>(|d| x[a][d] - x[0][d]);
                let (a, b, cc) = (e(1), e(2), e(3));
                let vol = a[0] * (b[1] * cc[2] - b[2] * cc[1])
                    - a[1] * (b[0] * cc[2] - b[2] * cc[0])
                    + a[2] * (b[0] * cc[1] - b[1] * cc[0]);
                if vol < 0.0 {
                    v.swap(1, 2);
                }
                tets.extend(v.map(&id));
                if order == 2 {
                    let half = |a: usize, b: usize| id(mid(v[a], v[b]).map(|x| x / 2));
                    // Gmsh tetra10 mid-side nodes: (0,1) (1,2) (2,0) (3,0) (3,2) (3,1).
                    tets.extend([
                        half(0, 1),
                        half(1, 2),
                        half(2, 0),
                        half(3, 0),
                        half(3, 2),
                        half(3, 1),
                    ]);
                }
            }
            // The face layer: ζ = 0 is k = 1 for the target, k = 0 for the contact block.
            let k = usize::from(below);
            for t in [[[0, 0], [1, 0], [1, 1]], [[0, 0], [1, 1], [0, 1]]] {
                let v = t.map(|[a, b]| corner([i + a, j + b, k]));
                tris.extend(v.map(&id));
                if order == 2 {
                    let half = |a: usize, b: usize| id(mid(v[a], v[b]).map(|x| x / 2));
                    tris.extend([half(0, 1), half(1, 2), half(2, 0)]);
                }
            }
        }
    }
    (tets, tris)
}

/// The two blocks as a mesh with surface groups `target` and `contact`.
fn interface_mesh(shape: Shape, target: Grid, contact: Grid, order: usize, gap: f64) -> Mesh {
    let mut coords = Vec::new();
    let (t_tets, t_tris) = block(&mut coords, shape, target, order, true, gap);
    let (c_tets, c_tris) = block(&mut coords, shape, contact, order, false, gap);
    let (tet, tri) = if order == 1 {
        (ElementType::Tetra4, ElementType::Triangle3)
    } else {
        (ElementType::Tetra10, ElementType::Triangle6)
    };
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
            mk(tet, 1, 1, t_tets),
            mk(tet, 1, 100_001, c_tets),
            mk(tri, 2, 200_001, t_tris),
            mk(tri, 3, 300_001, c_tris),
        ],
        groups: vec![
            group("volume", 3, 1),
            group("target", 2, 2),
            group("contact", 2, 3),
        ],
        periodic: Vec::new(),
    }
}

fn contact(coupling: SamaCoupling, misalignment: Option<Misalignment>) -> Contact {
    Contact {
        name: "shroud".into(),
        contact: "contact".into(),
        target: "target".into(),
        model: ContactModel::Sama,
        coupling: Some(coupling),
        element: ContactElement::OneD,
        mu: 0.3,
        kt: KT,
        kn: KN,
        n0: N0,
        misalignment,
        evaluation: Default::default(),
    }
}

/// Eqs 30–32 for every pair, to 1e-12: Σ w_j = 1, Σ k_tj = k_t, Σ k_nj = k_n, Σ n0_j = n0_c, and
/// Σ over the interface of n0_j = n0.
fn check_sums(iface: &ContactInterface) {
    for p in &iface.pairs {
        let sum = |v: &[f64]| v.iter().sum::<f64>();
        assert!((sum(&p.weights) - 1.0).abs() < 1e-12, "{p:?}");
        assert!((sum(&p.kt) - KT).abs() < 1e-12 * KT, "{p:?}");
        assert!((sum(&p.kn) - KN).abs() < 1e-12 * KN, "{p:?}");
        assert!((sum(&p.n0) - p.n0_node).abs() < 1e-12 * N0, "{p:?}");
    }
    assert!((iface.sum_n0 - N0).abs() < 1e-12 * N0, "{}", iface.sum_n0);
    let n = iface.pairs.len() as f64;
    assert!((iface.sum_kt - n * KT).abs() < 1e-12 * n * KT);
    assert!((iface.sum_kn - n * KN).abs() < 1e-12 * n * KN);
}

/// Shape functions of a triangle3/6 at (u, v) and their derivatives (Gmsh node order).
fn shape(order: usize, u: f64, v: f64) -> (Vec<f64>, Vec<[f64; 2]>) {
    let l = 1.0 - u - v;
    if order == 1 {
        return (vec![l, u, v], vec![[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]]);
    }
    (
        vec![
            l * (2.0 * l - 1.0),
            u * (2.0 * u - 1.0),
            v * (2.0 * v - 1.0),
            4.0 * u * l,
            4.0 * u * v,
            4.0 * v * l,
        ],
        vec![
            [1.0 - 4.0 * l, 1.0 - 4.0 * l],
            [4.0 * u - 1.0, 0.0],
            [0.0, 4.0 * v - 1.0],
            [4.0 * (l - u), -4.0 * u],
            [4.0 * v, 4.0 * u],
            [-4.0 * v, 4.0 * (l - v)],
        ],
    )
}

fn eval(order: usize, xs: &[[f64; 3]], u: f64, v: f64) -> [[f64; 3]; 3] {
    let (n, d) = shape(order, u, v);
    let mut out = [[0.0; 3]; 3];
    for k in 0..xs.len() {
        for c in 0..3 {
            out[0][c] += n[k] * xs[k][c];
            out[1][c] += d[k][0] * xs[k][c];
            out[2][c] += d[k][1] * xs[k][c];
        }
    }
    out
}

fn d2(a: [f64; 3], b: [f64; 3]) -> f64 {
    (0..3).map(|c| (a[c] - b[c]).powi(2)).sum()
}

/// The nearest point of one triangle face to `x` without the library's projection: the best of
/// a 40 × 40 sampling of the reference triangle, refined by a compass search over the directions
/// ±u, ±v, ±(u − v) (the last ones slide along the hypotenuse) with the step halved down to 1e-15.
/// Returns ((u, v), squared distance).
fn nearest_on_face(order: usize, xs: &[[f64; 3]], x: [f64; 3]) -> ([f64; 2], f64) {
    if order == 1 {
        return nearest_on_flat_triangle(xs, x);
    }
    let f = |uv: [f64; 2]| d2(eval(order, xs, uv[0], uv[1])[0], x);
    let inside = |uv: [f64; 2]| uv[0] >= 0.0 && uv[1] >= 0.0 && uv[0] + uv[1] <= 1.0;
    let m = 40;
    let mut best = ([0.0, 0.0], f64::INFINITY);
    for a in 0..=m {
        for b in 0..=m - a {
            let uv = [a as f64 / m as f64, b as f64 / m as f64];
            let d = f(uv);
            if d < best.1 {
                best = (uv, d);
            }
        }
    }
    let mut step = 1.0 / m as f64;
    let dirs = [
        [1.0, 0.0],
        [-1.0, 0.0],
        [0.0, 1.0],
        [0.0, -1.0],
        [1.0, -1.0],
        [-1.0, 1.0],
    ];
    while step > 1e-15 {
        let mut moved = false;
        for d in dirs {
            let mut uv = [best.0[0] + step * d[0], best.0[1] + step * d[1]];
            // Land exactly on the border when the step would cross it.
            uv = [uv[0].max(0.0), uv[1].max(0.0)];
            if uv[0] + uv[1] > 1.0 {
                continue;
            }
            if inside(uv) {
                let v = f(uv);
                if v < best.1 {
                    best = (uv, v);
                    moved = true;
                }
            }
        }
        if !moved {
            step *= 0.5;
        }
    }
    best
}

/// The nearest point of a flat triangle, in closed form: the orthogonal foot from the 2 × 2
/// normal equations if it is inside, else the nearest of the feet on the three edge segments.
fn nearest_on_flat_triangle(xs: &[[f64; 3]], x: [f64; 3]) -> ([f64; 2], f64) {
    let sub = |a: [f64; 3], b: [f64; 3]| -> [f64; 3] { std::array::from_fn(|c| a[c] - b[c]) };
    let dot = |a: [f64; 3], b: [f64; 3]| (0..3).map(|c| a[c] * b[c]).sum::<f64>();
    let (e1, e2, r) = (sub(xs[1], xs[0]), sub(xs[2], xs[0]), sub(x, xs[0]));
    let (a, b, c) = (dot(e1, e1), dot(e1, e2), dot(e2, e2));
    let (g1, g2) = (dot(e1, r), dot(e2, r));
    let det = a * c - b * b;
    let (u, v) = ((c * g1 - b * g2) / det, (a * g2 - b * g1) / det);
    let at = |u: f64, v: f64| d2(eval(1, xs, u, v)[0], x);
    if u >= 0.0 && v >= 0.0 && u + v <= 1.0 {
        return ([u, v], at(u, v));
    }
    // Edges in reference coordinates: from corner p to corner q.
    let corners = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
    let mut best = ([0.0, 0.0], f64::INFINITY);
    for (p, q) in [(0, 1), (1, 2), (2, 0)] {
        let (xp, xq) = (xs[p], xs[q]);
        let d = sub(xq, xp);
        let t = (dot(sub(x, xp), d) / dot(d, d)).clamp(0.0, 1.0);
        let uv = [
            corners[p][0] + t * (corners[q][0] - corners[p][0]),
            corners[p][1] + t * (corners[q][1] - corners[p][1]),
        ];
        let dd = at(uv[0], uv[1]);
        if dd < best.1 {
            best = (uv, dd);
        }
    }
    best
}

/// The brute-force nearest points of the target to a contact node at `x`.
struct BruteForce {
    /// The smallest distance (m) over all target faces.
    distance: f64,
    /// The distance (m) to the face the pair chose.
    face_distance: f64,
    /// Eq 29 weights (target node tag, weight) at the nearest point of that face: the
    /// interpolated coupling's shape functions N_j and the array coupling's inverse distances in
    /// the tangent plane (weight 1 alone on a node within `coincident`).
    interpolated: Vec<(u64, f64)>,
    array: Vec<(u64, f64)>,
}

/// [`BruteForce`] for the contact node at `x` paired on the target face element `face` (its
/// tag): the nearest point of every face is searched ([`nearest_on_face`]); the weights are those
/// at the nearest point of `face`, which must be a nearest face (ties between faces happen where
/// two faces' borders are equally near).
fn brute_force(mesh: &Mesh, order: usize, x: [f64; 3], coincident: f64, face: u64) -> BruteForce {
    let tris = &mesh.blocks[2];
    let nn = tris.kind.num_nodes();
    let mut distance = f64::INFINITY;
    let mut chosen = None;
    for e in 0..tris.tags.len() {
        let conn = &tris.connectivity[e * nn..(e + 1) * nn];
        let xs: Vec<[f64; 3]> = conn.iter().map(|&n| mesh.coords[n as usize]).collect();
        let (uv, d) = nearest_on_face(order, &xs, x);
        distance = distance.min(d.sqrt());
        if tris.tags.at(e) == face {
            chosen = Some((e, uv, d));
        }
    }
    let (e, [u, v], dd) = chosen.expect("the pair's face is a target face");
    let conn = &tris.connectivity[e * nn..(e + 1) * nn];
    let xs: Vec<[f64; 3]> = conn.iter().map(|&n| mesh.coords[n as usize]).collect();
    let tags: Vec<u64> = conn.iter().map(|&n| mesh.node_tags[n as usize]).collect();
    let (n, _) = shape(order, u, v);
    // Tangent plane at the point: t1 along ∂x/∂u, t2 ⊥ t1 in the plane of ∂x/∂u, ∂x/∂v.
    let [p, xu, xv] = eval(order, &xs, u, v);
    let unit = |a: [f64; 3]| {
        let l = a.iter().map(|c| c * c).sum::<f64>().sqrt();
        a.map(|c| c / l)
    };
    let t1 = unit(xu);
    let dot = |a: [f64; 3], b: [f64; 3]| (0..3).map(|c| a[c] * b[c]).sum::<f64>();
    let t2 = unit(std::array::from_fn(|c| xv[c] - dot(xv, t1) * t1[c]));
    let dist: Vec<f64> = xs
        .iter()
        .map(|&xj| {
            let r: [f64; 3] = std::array::from_fn(|c| p[c] - xj[c]);
            (dot(r, t1).powi(2) + dot(r, t2).powi(2)).sqrt()
        })
        .collect();
    // Eq 29's coincident case (both couplings): a target node at t_v takes the whole weight.
    let (interpolated, array) = match dist.iter().position(|&dj| dj <= coincident) {
        Some(j) => (vec![(tags[j], 1.0)], vec![(tags[j], 1.0)]),
        None => {
            let inv: f64 = dist.iter().map(|d| 1.0 / d).sum();
            (
                tags.iter().copied().zip(n).collect(),
                tags.iter()
                    .zip(&dist)
                    .map(|(&t, &d)| (t, (1.0 / d) / inv))
                    .collect(),
            )
        }
    };
    BruteForce {
        distance,
        face_distance: dd.sqrt(),
        interpolated,
        array,
    }
}

/// The pair's weights equal the brute force's per target node (a node missing on one side has
/// weight 0 there: the pairs leave out weights below 1e-12).
fn assert_weights(what: &str, got: &[(u64, f64)], want: &[(u64, f64)], tol: f64) {
    let weight = |list: &[(u64, f64)], t: u64| list.iter().find(|w| w.0 == t).map_or(0.0, |w| w.1);
    for &(t, _) in got.iter().chain(want) {
        assert!(
            (weight(got, t) - weight(want, t)).abs() <= tol,
            "{what}: {got:?} vs brute force {want:?}"
        );
    }
}

/// Coarse and fine grids of the two sides: different cell counts and gradings.
fn grids(fine: bool) -> (Grid, Grid) {
    let k = if fine { 2 } else { 1 };
    (
        Grid {
            nx: 2 * k,
            ny: 4 * k,
            grade: 0.15,
        },
        Grid {
            nx: 3 * k,
            ny: 5 * k + 1,
            grade: -0.1,
        },
    )
}

/// Whether the contact node at `x` lies on the boundary of the generated face: found by
/// comparing with the face's own boundary nodes (ξ or η at 0 or 1) of the contact grid.
fn on_boundary(shape: Shape, g: Grid, order: usize, gap: f64, x: [f64; 3]) -> bool {
    let (mx, my) = (order * g.nx, order * g.ny);
    let eta = |t: f64| {
        t + g.grade * (2.0 * std::f64::consts::PI * t).sin() / (2.0 * std::f64::consts::PI)
    };
    for j in 0..=my {
        for i in 0..=mx {
            if i != 0 && i != mx && j != 0 && j != my {
                continue;
            }
            let p = shape.point(i as f64 / mx as f64, eta(j as f64 / my as f64), gap);
            if d2(p, x) < 1e-24 {
                return true;
            }
        }
    }
    false
}

#[test]
fn curved_tilted_nonconforming_interfaces_pair_every_contact_node() {
    let gap = 2e-5;
    let mut edge_total = 0;
    for order in [1, 2] {
        for fine in [false, true] {
            for tilt_deg in [0.0f64, 15.0, 30.0, 45.0] {
                for bulge in [0.0, 0.25] {
                    let shape = Shape {
                        tilt: tilt_deg.to_radians(),
                        bulge,
                    };
                    let (tg, cg) = grids(fine);
                    let mesh = interface_mesh(shape, tg, cg, order, gap);
                    let label =
                        format!("order {order}, fine {fine}, tilt {tilt_deg}°, bulge {bulge}");
                    let c = contact(SamaCoupling::Interpolated, None);
                    let iface = build_interface_with(&c, &mesh, None, 1.0).unwrap();
                    let strict = build_interface_with(&c, &mesh, None, 0.0).unwrap();
                    let array =
                        build_interface_with(&contact(SamaCoupling::Array, None), &mesh, None, 1.0)
                            .unwrap();
                    assert!(
                        iface.unprojected.is_empty(),
                        "{label}: {:?}",
                        iface.unprojected
                    );
                    assert_eq!(iface.pairs.len(), iface.contact_nodes, "{label}");
                    assert_eq!(array.pairs.len(), iface.contact_nodes, "{label}");
                    check_sums(&iface);
                    check_sums(&array);
                    // Without the edge tolerance, exactly the edge-paired nodes are unprojected
                    // (only on a curved edge of chorded faces) and the others keep their weights.
                    let mut lost: Vec<u64> = strict.unprojected.iter().map(|u| u.node).collect();
                    let mut edge: Vec<u64> = iface.edge_pairs().map(|p| p.contact_node).collect();
                    lost.sort_unstable();
                    edge.sort_unstable();
                    assert_eq!(lost, edge, "{label}");
                    if order == 1 && tilt_deg >= 30.0 && bulge == 0.0 {
                        assert!(
                            !edge.is_empty(),
                            "{label}: the curved edge should need the tolerance"
                        );
                    }
                    edge_total += edge.len();
                    for p in &strict.pairs {
                        let q = iface
                            .pairs
                            .iter()
                            .find(|q| q.contact_node == p.contact_node)
                            .unwrap();
                        assert_eq!(
                            (&q.targets, &q.weights),
                            (&p.targets, &p.weights),
                            "{label}"
                        );
                        assert!(q.edge.is_none());
                    }
                    for p in iface.edge_pairs() {
                        let e = p.edge.unwrap();
                        assert!(e.tangential_offset <= e.tolerance, "{label}: {e:?}");
                        // Outside by at most the sagitta of a target chord (cells ≤ 15 mm,
                        // curvature ≤ sin²β/r + 1/ρ ≤ 9 /m): κh²/8 < 0.26 mm.
                        assert!(e.tangential_offset < 2.6e-4, "{label}: {e:?}");
                    }
                    // Boundary nodes (and every edge-paired node) against the brute force.
                    let coincident = iface.coincident_tolerance;
                    let tol = if order == 1 { 1e-9 } else { 1e-7 };
                    let mut checked = 0;
                    for (p, q) in iface.pairs.iter().zip(&array.pairs) {
                        assert_eq!(p.contact_node, q.contact_node);
                        let x = mesh.coords[p.contact_index as usize];
                        if p.edge.is_none() && !on_boundary(shape, cg, order, gap, x) {
                            continue;
                        }
                        let bf = brute_force(&mesh, order, x, coincident, p.face);
                        assert!(
                            (p.distance - bf.distance).abs() < 1e-12
                                && (bf.face_distance - bf.distance).abs() < 1e-12,
                            "{label}: node {} distance {} vs brute force {} (on its face {})",
                            p.contact_node,
                            p.distance,
                            bf.distance,
                            bf.face_distance
                        );
                        assert_eq!(p.face, q.face);
                        let got = |pp: &nlrom::interface::ContactPair| -> Vec<(u64, f64)> {
                            pp.targets
                                .iter()
                                .copied()
                                .zip(pp.weights.iter().copied())
                                .collect()
                        };
                        let what = format!("{label}: node {}", p.contact_node);
                        assert_weights(
                            &format!("{what} interpolated"),
                            &got(p),
                            &bf.interpolated,
                            tol,
                        );
                        assert_weights(&format!("{what} array"), &got(q), &bf.array, tol);
                        checked += 1;
                    }
                    assert!(
                        checked >= 2 * (order * cg.ny + 1),
                        "{label}: {checked} boundary nodes"
                    );
                }
            }
        }
    }
    assert!(
        edge_total > 50,
        "{edge_total} edge-paired nodes over all cases"
    );
}

#[test]
fn a_contact_row_beyond_the_target_stays_unprojected() {
    // The target moved inward along the plane by 0.3 of its cell width across the face: the
    // contact nodes of the outer edge have no target under them (offset ≫ the edge tolerance).
    for order in [1, 2] {
        let shape = Shape {
            tilt: 30f64.to_radians(),
            bulge: 0.0,
        };
        let (tg, cg) = grids(false);
        let mesh = interface_mesh(shape, tg, cg, order, 0.0);
        let shift = 0.3 * (R_OUT - R_IN) / tg.nx as f64;
        let m = Misalignment {
            translate: [-shift, 0.0, 0.0],
            rotate: None,
        };
        let iface = build_interface_with(
            &contact(SamaCoupling::Interpolated, Some(m)),
            &mesh,
            None,
            1.0,
        )
        .unwrap();
        let mut unprojected: Vec<u64> = iface.unprojected.iter().map(|u| u.node).collect();
        unprojected.sort_unstable();
        // The outer edge ξ = 1 of the contact face.
        let mut outer: Vec<u64> = mesh
            .nodes_of("contact")
            .unwrap()
            .into_iter()
            .map(|i| i as usize)
            .filter(|&i| {
                let x = mesh.coords[i];
                (0..=order * cg.ny).any(|j| {
                    let t = j as f64 / (order * cg.ny) as f64;
                    let eta = t + cg.grade * (2.0 * std::f64::consts::PI * t).sin()
                        / (2.0 * std::f64::consts::PI);
                    d2(shape.point(1.0, eta, 0.0), x) < 1e-24
                })
            })
            .map(|i| mesh.node_tags[i])
            .collect();
        outer.sort_unstable();
        assert_eq!(unprojected, outer, "order {order}");
        for u in &iface.unprojected {
            assert!(u.tangential_offset.unwrap() > 0.5 * shift, "{u:?}");
        }
        assert_eq!(iface.pairs.len() + outer.len(), iface.contact_nodes);
        check_sums(&iface);
    }
}

fn bundled(name: &str) -> (Case, Mesh, Option<CyclicGeometry>) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join(format!("cases/{name}.toml"));
    let case = Case::load(&path).unwrap();
    let mesh = read_msh(case.model.mesh.as_ref().unwrap()).unwrap();
    let geom = case
        .cyclic
        .as_ref()
        .map(|c| CyclicGeometry::from_case(c).unwrap());
    (case, mesh, geom)
}

#[test]
fn bundled_models_keep_the_weights_of_nodes_that_project_inside() {
    for name in [
        "shroud_nonconforming",
        "paper/m1_nonconforming",
        "paper/m2_nonconforming",
        "paper/m1_fine_target",
        "paper/m1_misaligned",
        "paper/m2_misaligned",
    ] {
        let (case, mesh, geom) = bundled(name);
        let strict = build_interfaces_with(&case, &mesh, geom.as_ref(), 0.0).unwrap();
        let paired = build_interfaces_with(&case, &mesh, geom.as_ref(), 1.0).unwrap();
        for (s, p) in strict.iter().zip(&paired) {
            assert_eq!(s.sigma, p.sigma, "{name}");
            for sp in &s.pairs {
                let pp = p
                    .pairs
                    .iter()
                    .find(|q| q.contact_node == sp.contact_node)
                    .unwrap_or_else(|| panic!("{name}: node {} lost", sp.contact_node));
                assert_eq!(pp.targets, sp.targets, "{name}");
                assert_eq!(pp.weights, sp.weights, "{name}");
                assert_eq!(pp.virtual_point, sp.virtual_point, "{name}");
                assert!(pp.edge.is_none());
            }
            // The others are either paired on the edge or still unprojected.
            assert_eq!(
                p.pairs.len() + p.unprojected.len(),
                s.pairs.len() + s.unprojected.len()
            );
            assert_eq!(
                p.pairs.len() - s.pairs.len(),
                p.edge_pairs().count(),
                "{name}"
            );
            check_sums_scaled(p);
        }
    }
}

/// Eq 32 on a bundled model (its own k_t, k_n): Σ w_j = 1 per pair and the interface sums.
fn check_sums_scaled(iface: &ContactInterface) {
    for p in &iface.pairs {
        assert!((p.weights.iter().sum::<f64>() - 1.0).abs() < 1e-12, "{p:?}");
        assert!(
            (p.n0.iter().sum::<f64>() - p.n0_node).abs() <= 1e-12 * p.n0_node.abs().max(1e-300)
        );
    }
}
