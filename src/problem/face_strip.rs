//! The integration points of a `[[strip]]` on a mesh face group (`face`, `direction`): the
//! distributed contact area D of Cigeroglu, An & Menq 2007 (§2) on the faces of a surface group
//! of the FE model, pressed against rigid ground.
//!
//! Kinematics (the paper's eqs 1–3 with the contact frame taken per point): at a point x of a
//! face, n is the face's unit outward normal (out of the body, towards the ground) and t the slip
//! direction p projected on the tangent plane, t = (p − (p·n) n)/|p − (p·n) n|. With the ground
//! rigid (d_B = 0) the relative motion of eq 3 is
//!
//! u(x) = t · Σ_a N_a(ξ) d_a  (tangential, m),  v(x) = n · Σ_a N_a(ξ) d_a  (normal approach, m),
//!
//! d_a the displacements of the face's nodes and N_a its shape functions at the point's reference
//! coordinates ξ (`crate::mesh::faces::surface_shape`): v > 0 moves the face into the ground and
//! raises the normal load (eq 4). The paper's w (the second tangent) is not used: the points slip
//! along t only, as in the paper's 2-D law.
//!
//! Quadrature of eq 38, Q = ∬_D [φ_u f_u + φ_v f_v] dA: the Gauss points of every face — g × g
//! Gauss–Legendre points on a quadrilateral, a rule exact to degree 2g − 1 on a triangle — with
//! area weights dA = w |∂x/∂ξ₁ × ∂x/∂ξ₂| (m²). Each point is one element of the 1-D law (eqs
//! 4–17) with k_t = k_u dA, k_n = k_v dA (k_u, k_v per unit area, N/m³), μ, and the preload
//! n0 = P q(s) dA / Σ q dA, so the points' preloads add up to the total P (N) exactly; q is the
//! strip's distribution at the point's position s = p̂ · x − min_a p̂ · x_a (m) along the
//! direction, over the group's extent [0, ℓ] along it. On a flat face whose direction lies in its
//! plane, the points at one position s form the line strip of the same length with
//! k_u(line) = k_u × width.

use crate::error::{Error, Result};
use crate::fe::quadrature::{gauss_legendre, triangle_rule};
use crate::mesh::faces::{area_vector, group_faces, surface_shape};
use crate::mesh::{ElementType, Mesh};
use crate::vec3::{dot, norm};

/// The largest |p̂ · n| between the unit slip direction and a face's unit normal: the direction
/// must lie at most 30° off the face's plane (at least 60° from its normal).
pub const MAX_NORMAL_COSINE: f64 = 0.5;

/// One integration point of a face strip.
#[derive(Clone, Debug, PartialEq)]
pub struct FacePoint {
    /// Position s along the direction, from the group's smallest p̂ · x (m).
    pub position: f64,
    /// The point x (m, global frame).
    pub x: [f64; 3],
    /// The unit slip direction t in the face's tangent plane.
    pub tangent: [f64; 3],
    /// The face's unit outward normal n.
    pub normal: [f64; 3],
    /// The area weight dA (m²).
    pub area: f64,
    /// The face's nodes (indices into the mesh) with their shape-function values N_a at the point.
    pub nodes: Vec<(u32, f64)>,
    /// Tag of the surface element the point lies on.
    pub surface_tag: u64,
}

/// The points of a face group and the group's extent along the direction.
#[derive(Clone, Debug, PartialEq)]
pub struct FacePoints {
    /// The points, face by face in group order, Gauss points in rule order within a face.
    pub points: Vec<FacePoint>,
    /// The length ℓ (m) of the group along the direction: positions lie in [0, ℓ].
    pub length: f64,
}

/// The Gauss points of the faces of the surface group `group` of `mesh` for the slip direction
/// `direction` and `gauss` points per direction (see the module documentation).
///
/// Errors ([`Error::Input`], naming the mesh file, the group and the face element): the group
/// is missing, not a surface group or not on the boundary of a volume; a face of zero area at a
/// point; a direction within 60° of a face's normal (|p̂ · n| > [`MAX_NORMAL_COSINE`]).
pub fn face_points(
    mesh: &Mesh,
    group: &str,
    direction: [f64; 3],
    gauss: usize,
) -> Result<FacePoints> {
    let faces = group_faces(mesh, group)?;
    let len = norm(direction);
    let p = direction.map(|c| c / len);
    let along = |i: u32| dot(p, mesh.coords[i as usize]);
    let s_min = faces
        .iter()
        .flat_map(|f| f.nodes.iter().map(|&i| along(i)))
        .fold(f64::INFINITY, f64::min);
    let s_max = faces
        .iter()
        .flat_map(|f| f.nodes.iter().map(|&i| along(i)))
        .fold(f64::NEG_INFINITY, f64::max);
    let mut points = Vec::new();
    for face in &faces {
        let xs: Vec<[f64; 3]> = face
            .nodes
            .iter()
            .map(|&i| mesh.coords[i as usize])
            .collect();
        for (u, v, w) in rule(face.kind, gauss) {
            let (shape, _) = surface_shape(face.kind, u, v);
            let a = area_vector(face.kind, &xs, u, v);
            let jac = norm(a);
            let place = || {
                format!(
                    "{}: face element {} of group '{group}'",
                    mesh.source_name(),
                    face.surface_tag
                )
            };
            if jac.is_nan() || jac <= 0.0 {
                return Err(Error::input(format!(
                    "{}: the face has zero area at a Gauss point (a degenerate element)",
                    place()
                )));
            }
            let n = a.map(|c| c / jac);
            let pn = dot(p, n);
            if pn.abs() > MAX_NORMAL_COSINE {
                return Err(Error::input(format!(
                    "{}: the strip's direction [{}, {}, {}] makes {:.1}° with the face's normal [{:.3}, {:.3}, {:.3}]; the slip direction must lie in (or near, at most 30° off) the face's plane",
                    place(),
                    direction[0],
                    direction[1],
                    direction[2],
                    pn.abs().acos().to_degrees(),
                    n[0],
                    n[1],
                    n[2]
                )));
            }
            let tp = [p[0] - pn * n[0], p[1] - pn * n[1], p[2] - pn * n[2]];
            let tl = norm(tp);
            let mut x = [0.0; 3];
            for (xa, na) in xs.iter().zip(&shape) {
                for c in 0..3 {
                    x[c] += na * xa[c];
                }
            }
            points.push(FacePoint {
                position: dot(p, x) - s_min,
                x,
                tangent: tp.map(|c| c / tl),
                normal: n,
                area: w * jac,
                nodes: face.nodes.iter().copied().zip(shape).collect(),
                surface_tag: face.surface_tag,
            });
        }
    }
    Ok(FacePoints {
        points,
        length: s_max - s_min,
    })
}

/// The rule (u, v, weight) of `gauss` points per direction on a surface element: g × g
/// Gauss–Legendre on the quadrilateral [−1, 1]², exact to degree 2g − 1 on the triangle.
fn rule(kind: ElementType, gauss: usize) -> Vec<(f64, f64, f64)> {
    if kind.first_order() == ElementType::Triangle3 {
        let (pts, wts) = triangle_rule((2 * gauss - 1) as u32);
        pts.iter()
            .zip(&wts)
            .map(|(q, &w)| (q[0], q[1], w))
            .collect()
    } else {
        let (x, w) = gauss_legendre(gauss);
        let mut out = Vec::with_capacity(gauss * gauss);
        for (xu, wu) in x.iter().zip(&w) {
            for (xv, wv) in x.iter().zip(&w) {
                out.push((*xu, *xv, wu * wv));
            }
        }
        out
    }
}
