//! Boundary faces of surface groups, oriented outward from the volume they bound, and the
//! isoparametric geometry of surface elements (shape functions, area, normal).
//!
//! A surface physical group (dimension 2) lists triangles/quads; each is matched to the face of a
//! volume element with the same corner nodes, and re-ordered as that face of the volume element
//! (see [`ElementType::faces`]), so that its normal (right-hand rule on the corners) points out of
//! the volume. The orientation is confirmed geometrically (face normal against the vector from the
//! volume element's centroid to the face centroid), so inverted volume elements do not flip it.
//!
//! Reference coordinates follow Gmsh: triangles on (u, v) ∈ {u, v ≥ 0, u + v ≤ 1} with corners
//! (0,0), (1,0), (0,1); quads on [−1, 1]² with corners (−1,−1), (1,−1), (1,1), (−1,1).

use std::collections::HashMap;

use super::{ElementType, Mesh};
use crate::error::{Error, Result};

/// A face of a surface group, oriented outward from its volume element.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundaryFace {
    /// Triangle3/6 or Quad4/8/9.
    pub kind: ElementType,
    /// Node indices in Gmsh order for `kind`, outward orientation.
    pub nodes: Vec<u32>,
    /// Tag of the surface element of the group this face comes from.
    pub surface_tag: u64,
    /// Tag of the volume element it bounds.
    pub volume_tag: u64,
}

/// Sorted corner nodes: the key that identifies a face independently of its ordering.
fn face_key(kind: ElementType, nodes: &[u32]) -> Vec<u32> {
    let mut key = nodes[..kind.num_corners()].to_vec();
    key.sort_unstable();
    key
}

/// The faces of the surface group `name`, each re-ordered as the outward face of the volume
/// element it belongs to. Errors: the group does not exist, is not of dimension 2, has no face
/// elements, or has a face that bounds no volume element.
pub fn group_faces(mesh: &Mesh, name: &str) -> Result<Vec<BoundaryFace>> {
    let group = mesh.group(name)?;
    if group.dim != 2 {
        return Err(Error::input(format!(
            "{}: physical group '{name}' has dimension {}, but a surface group (dimension 2) is needed",
            mesh.source_name(),
            group.dim
        )));
    }
    let surface: Vec<(ElementType, u64, &[u32])> = mesh
        .group_blocks(group)
        .flat_map(|b| {
            b.elements()
                .enumerate()
                .map(move |(e, n)| (b.kind, b.tags.at(e), n))
        })
        .collect();
    if surface.is_empty() {
        return Err(Error::input(format!(
            "{}: surface group '{name}' has no triangle or quad elements",
            mesh.source_name()
        )));
    }
    let wanted: HashMap<Vec<u32>, usize> = surface
        .iter()
        .enumerate()
        .map(|(k, (kind, _, n))| (face_key(*kind, n), k))
        .collect();
    let mut found: Vec<Option<BoundaryFace>> = vec![None; surface.len()];
    for block in mesh.blocks.iter().filter(|b| b.kind.dim() == 3) {
        let local_faces = block.kind.faces();
        for (e, vol_nodes) in block.elements().enumerate() {
            for (face_kind, local) in &local_faces {
                let nodes: Vec<u32> = local.iter().map(|&l| vol_nodes[l]).collect();
                let Some(&k) = wanted.get(&face_key(*face_kind, &nodes)) else {
                    continue;
                };
                if found[k].is_none() {
                    let nodes = outward(mesh, *face_kind, nodes, vol_nodes);
                    found[k] = Some(BoundaryFace {
                        kind: *face_kind,
                        nodes,
                        surface_tag: surface[k].1,
                        volume_tag: block.tags.at(e),
                    });
                }
            }
        }
    }
    found
        .into_iter()
        .enumerate()
        .map(|(k, f)| {
            f.ok_or_else(|| {
                Error::input(format!(
                    "{}: element {} of surface group '{name}' is not a face of any volume element; the group must lie on the boundary of the meshed volume",
                    mesh.source_name(),
                    surface[k].1
                ))
            })
        })
        .collect()
}

/// `nodes` (a face of the volume element `vol_nodes`, in the element's outward ordering) flipped
/// if the geometry says it points inward (an inverted volume element).
fn outward(mesh: &Mesh, kind: ElementType, nodes: Vec<u32>, vol_nodes: &[u32]) -> Vec<u32> {
    let centroid = |ids: &[u32]| {
        let mut c = [0.0; 3];
        for &i in ids {
            for (a, x) in c.iter_mut().zip(mesh.coords[i as usize]) {
                *a += x / ids.len() as f64;
            }
        }
        c
    };
    let xs: Vec<[f64; 3]> = nodes.iter().map(|&i| mesh.coords[i as usize]).collect();
    let (u, v) = reference_centre(kind);
    let n = area_vector(kind, &xs, u, v);
    let fc = centroid(&nodes[..kind.num_corners()]);
    let vc = centroid(vol_nodes);
    let d = [fc[0] - vc[0], fc[1] - vc[1], fc[2] - vc[2]];
    if n[0] * d[0] + n[1] * d[1] + n[2] * d[2] >= 0.0 {
        nodes
    } else {
        flip(kind, &nodes)
    }
}

/// The same face with the opposite orientation (corner 0 kept, the others reversed, mid-edge
/// nodes permuted to match).
pub fn flip(kind: ElementType, nodes: &[u32]) -> Vec<u32> {
    let order: &[usize] = match kind {
        ElementType::Triangle3 => &[0, 2, 1],
        ElementType::Triangle6 => &[0, 2, 1, 5, 4, 3],
        ElementType::Quad4 => &[0, 3, 2, 1],
        ElementType::Quad8 => &[0, 3, 2, 1, 7, 6, 5, 4],
        ElementType::Quad9 => &[0, 3, 2, 1, 7, 6, 5, 4, 8],
        _ => return nodes.to_vec(),
    };
    order.iter().map(|&k| nodes[k]).collect()
}

/// The reference-coordinate centre of a surface element.
fn reference_centre(kind: ElementType) -> (f64, f64) {
    match kind.first_order() {
        ElementType::Triangle3 => (1.0 / 3.0, 1.0 / 3.0),
        _ => (0.0, 0.0),
    }
}

/// Shape functions and their derivatives (∂/∂u, ∂/∂v) of a surface element at (u, v), in Gmsh
/// node order. Triangles: linear and quadratic Lagrange; quads: bilinear, 8-node serendipity and
/// 9-node Lagrange. Panics on non-surface types (a programming error, not an input error).
pub fn surface_shape(kind: ElementType, u: f64, v: f64) -> (Vec<f64>, Vec<[f64; 2]>) {
    match kind {
        ElementType::Triangle3 => (
            vec![1.0 - u - v, u, v],
            vec![[-1.0, -1.0], [1.0, 0.0], [0.0, 1.0]],
        ),
        ElementType::Triangle6 => {
            let l = [1.0 - u - v, u, v];
            let n = vec![
                l[0] * (2.0 * l[0] - 1.0),
                l[1] * (2.0 * l[1] - 1.0),
                l[2] * (2.0 * l[2] - 1.0),
                4.0 * l[0] * l[1],
                4.0 * l[1] * l[2],
                4.0 * l[2] * l[0],
            ];
            let d = vec![
                [1.0 - 4.0 * l[0], 1.0 - 4.0 * l[0]],
                [4.0 * l[1] - 1.0, 0.0],
                [0.0, 4.0 * l[2] - 1.0],
                [4.0 * (l[0] - l[1]), -4.0 * l[1]],
                [4.0 * l[2], 4.0 * l[1]],
                [-4.0 * l[2], 4.0 * (l[0] - l[2])],
            ];
            (n, d)
        }
        ElementType::Quad4 => {
            let c = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
            let n = c
                .iter()
                .map(|(a, b)| 0.25 * (1.0 + a * u) * (1.0 + b * v))
                .collect();
            let d = c
                .iter()
                .map(|(a, b)| [0.25 * a * (1.0 + b * v), 0.25 * b * (1.0 + a * u)])
                .collect();
            (n, d)
        }
        ElementType::Quad8 => quad8_shape(u, v),
        ElementType::Quad9 => quad9_shape(u, v),
        other => panic!("surface_shape called for a {other} element"),
    }
}

/// Reference positions of the 9 quad nodes in Gmsh order (corners, mid-edges, centre).
const QUAD_NODES: [(f64, f64); 9] = [
    (-1.0, -1.0),
    (1.0, -1.0),
    (1.0, 1.0),
    (-1.0, 1.0),
    (0.0, -1.0),
    (1.0, 0.0),
    (0.0, 1.0),
    (-1.0, 0.0),
    (0.0, 0.0),
];

fn quad8_shape(u: f64, v: f64) -> (Vec<f64>, Vec<[f64; 2]>) {
    let mut n = Vec::with_capacity(8);
    let mut d = Vec::with_capacity(8);
    for &(a, b) in &QUAD_NODES[..8] {
        if a != 0.0 && b != 0.0 {
            let s = a * u + b * v - 1.0;
            n.push(0.25 * (1.0 + a * u) * (1.0 + b * v) * s);
            d.push([
                0.25 * a * (1.0 + b * v) * (s + 1.0 + a * u),
                0.25 * b * (1.0 + a * u) * (s + 1.0 + b * v),
            ]);
        } else if a == 0.0 {
            n.push(0.5 * (1.0 - u * u) * (1.0 + b * v));
            d.push([-u * (1.0 + b * v), 0.5 * b * (1.0 - u * u)]);
        } else {
            n.push(0.5 * (1.0 + a * u) * (1.0 - v * v));
            d.push([0.5 * a * (1.0 - v * v), -v * (1.0 + a * u)]);
        }
    }
    (n, d)
}

/// 1-D quadratic Lagrange polynomial through −1, 0, 1 for the node at `a`, and its derivative.
fn lagrange2(a: f64, x: f64) -> (f64, f64) {
    if a < 0.0 {
        (0.5 * x * (x - 1.0), x - 0.5)
    } else if a > 0.0 {
        (0.5 * x * (x + 1.0), x + 0.5)
    } else {
        (1.0 - x * x, -2.0 * x)
    }
}

fn quad9_shape(u: f64, v: f64) -> (Vec<f64>, Vec<[f64; 2]>) {
    QUAD_NODES
        .iter()
        .map(|&(a, b)| {
            let (la, da) = lagrange2(a, u);
            let (lb, db) = lagrange2(b, v);
            (la * lb, [da * lb, la * db])
        })
        .unzip()
}

/// The area vector ∂x/∂u × ∂x/∂v at (u, v) of a surface element with node positions `xs` (m²
/// per unit reference area; it points along the face's right-hand normal).
pub fn area_vector(kind: ElementType, xs: &[[f64; 3]], u: f64, v: f64) -> [f64; 3] {
    let (_, d) = surface_shape(kind, u, v);
    let mut a = [0.0; 3];
    let mut b = [0.0; 3];
    for (x, dn) in xs.iter().zip(&d) {
        for c in 0..3 {
            a[c] += x[c] * dn[0];
            b[c] += x[c] * dn[1];
        }
    }
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// Quadrature points (u, v, weight) on the reference surface element: 7-point degree-5 rule on
/// triangles (Dunavant), 3×3 Gauss–Legendre on quads.
pub fn surface_quadrature(kind: ElementType) -> Vec<(f64, f64, f64)> {
    if kind.first_order() == ElementType::Triangle3 {
        let a1 = 0.059_715_871_789_770;
        let b1 = 0.470_142_064_105_115;
        let a2 = 0.797_426_985_353_087;
        let b2 = 0.101_286_507_323_456;
        let w0 = 0.225 / 2.0;
        let w1 = 0.132_394_152_788_506 / 2.0;
        let w2 = 0.125_939_180_544_827 / 2.0;
        vec![
            (1.0 / 3.0, 1.0 / 3.0, w0),
            (b1, b1, w1),
            (a1, b1, w1),
            (b1, a1, w1),
            (b2, b2, w2),
            (a2, b2, w2),
            (b2, a2, w2),
        ]
    } else {
        let g = (0.6f64).sqrt();
        let pts = [(-g, 5.0 / 9.0), (0.0, 8.0 / 9.0), (g, 5.0 / 9.0)];
        let mut q = Vec::with_capacity(9);
        for &(x, wx) in &pts {
            for &(y, wy) in &pts {
                q.push((x, y, wx * wy));
            }
        }
        q
    }
}

/// Area (m²) of a surface element with node positions `xs`, by quadrature of |∂x/∂u × ∂x/∂v|
/// (exact for flat straight-sided faces, accurate to the rule's order for curved ones).
pub fn face_area(kind: ElementType, xs: &[[f64; 3]]) -> f64 {
    surface_quadrature(kind)
        .iter()
        .map(|&(u, v, w)| {
            let a = area_vector(kind, xs, u, v);
            w * (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    const SURFACES: [ElementType; 5] = [
        ElementType::Triangle3,
        ElementType::Triangle6,
        ElementType::Quad4,
        ElementType::Quad8,
        ElementType::Quad9,
    ];

    fn reference_nodes(kind: ElementType) -> Vec<(f64, f64)> {
        match kind {
            ElementType::Triangle3 => vec![(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)],
            ElementType::Triangle6 => vec![
                (0.0, 0.0),
                (1.0, 0.0),
                (0.0, 1.0),
                (0.5, 0.0),
                (0.5, 0.5),
                (0.0, 0.5),
            ],
            k => QUAD_NODES[..k.num_nodes()].to_vec(),
        }
    }

    #[test]
    fn shape_functions_interpolate_and_sum_to_one() {
        for kind in SURFACES {
            for (i, &(u, v)) in reference_nodes(kind).iter().enumerate() {
                let (n, d) = surface_shape(kind, u, v);
                for (j, nj) in n.iter().enumerate() {
                    let expected = if i == j { 1.0 } else { 0.0 };
                    assert!((nj - expected).abs() < 1e-14, "{kind} N{j} at node {i}");
                }
                let sum_du: f64 = d.iter().map(|x| x[0]).sum();
                let sum_dv: f64 = d.iter().map(|x| x[1]).sum();
                assert!(sum_du.abs() < 1e-13 && sum_dv.abs() < 1e-13, "{kind}");
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let h = 1e-6;
        for kind in SURFACES {
            let (u, v) = (0.21, 0.17);
            let (_, d) = surface_shape(kind, u, v);
            let (np, _) = surface_shape(kind, u + h, v);
            let (nm, _) = surface_shape(kind, u - h, v);
            let (nvp, _) = surface_shape(kind, u, v + h);
            let (nvm, _) = surface_shape(kind, u, v - h);
            for j in 0..d.len() {
                assert!(
                    (d[j][0] - (np[j] - nm[j]) / (2.0 * h)).abs() < 1e-8,
                    "{kind} dN{j}/du"
                );
                assert!(
                    (d[j][1] - (nvp[j] - nvm[j]) / (2.0 * h)).abs() < 1e-8,
                    "{kind} dN{j}/dv"
                );
            }
        }
    }

    #[test]
    fn area_of_mapped_faces() {
        // Reference nodes scaled by 2 in x and 3 in y: area = 6 × reference area.
        for kind in SURFACES {
            let xs: Vec<[f64; 3]> = reference_nodes(kind)
                .iter()
                .map(|&(u, v)| [2.0 * u, 3.0 * v, 1.0])
                .collect();
            let reference = if kind.first_order() == ElementType::Triangle3 {
                0.5
            } else {
                4.0
            };
            assert!(
                (face_area(kind, &xs) - 6.0 * reference).abs() < 1e-13,
                "{kind}"
            );
            let flipped: Vec<[f64; 3]> = flip(kind, &(0..xs.len() as u32).collect::<Vec<_>>())
                .iter()
                .map(|&k| xs[k as usize])
                .collect();
            let (u, v) = reference_centre(kind);
            assert!(area_vector(kind, &xs, u, v)[2] > 0.0);
            assert!(area_vector(kind, &flipped, u, v)[2] < 0.0, "{kind} flip");
        }
    }

    #[test]
    fn curved_triangle6_area_of_an_exact_parabolic_patch() {
        // x = (u, v, u²) is exactly quadratic, so a triangle6 with nodes on it is the patch itself.
        // Its area is ∫₀¹ √(1 + 4x²)(1 − x) dx; reference by composite Simpson with 20 000 panels.
        let nodes = reference_nodes(ElementType::Triangle6);
        let xs: Vec<[f64; 3]> = nodes.iter().map(|&(u, v)| [u, v, u * u]).collect();
        let f = |x: f64| (1.0 + 4.0 * x * x).sqrt() * (1.0 - x);
        let m = 20_000;
        let h = 1.0 / m as f64;
        let simpson: f64 = (0..m)
            .map(|k| {
                let a = k as f64 * h;
                h / 6.0 * (f(a) + 4.0 * f(a + 0.5 * h) + f(a + h))
            })
            .sum();
        let a = face_area(ElementType::Triangle6, &xs);
        assert!((a - simpson).abs() / simpson < 1e-4, "{a} vs {simpson}");
    }
}
