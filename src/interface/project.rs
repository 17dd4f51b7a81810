//! Projection of a contact node onto the target surface (SAMA paper §4, step 1; Fig. 6): the
//! virtual node t_v, the target face containing it, and the local frame there (`docs/conventions.md` §3).
//!
//! The BVH of the flat search mesh gives the nearest sub-triangle; its barycentric coordinates give
//! a first (u, v) on the face, refined on the face's isoparametric map x(u, v) = Σ N_i(u, v) x_i by
//! Gauss–Newton on ½|x_c − x(u, v)|², with (u, v) kept in the reference element. When the result
//! is on the face's border (the nearest point may then lie on a neighbouring curved face), the
//! faces sharing a node with it are tried too and the nearest point wins.

use parry3d_f64::math::Vector as PVec;
use parry3d_f64::query::PointQueryWithLocation;
use rayon::prelude::*;

use crate::mesh::faces::surface_shape;
use crate::mesh::ElementType;

use super::surface::{is_triangle, reference_node, subdivision, TargetSurface};
use crate::vec3::{cross, dot, norm, scale, sub, unit};

/// The projection of a point onto the target surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Projection {
    /// Index of the target face (into [`TargetSurface::faces`]).
    pub face: usize,
    /// Reference coordinates (u, v) of t_v on that face (inside the reference element).
    pub uv: [f64; 2],
    /// The virtual node t_v (m), a point of the face.
    pub point: [f64; 3],
    /// Local frame at t_v, rows t1, t2, n: n = the face's outward unit normal (towards the contact
    /// body), t1 = the face's first edge (corner 1 − corner 0) projected on the tangent plane and
    /// normalised, t2 = n × t1 (right-handed).
    pub frame: [[f64; 3]; 3],
    /// Signed normal gap (x_c − t_v)·n (m): positive = the contact node is outside the target body
    /// (open gap), negative = interpenetration.
    pub gap: f64,
    /// Distance |x_c − t_v| (m).
    pub distance: f64,
    /// Length (m) of the tangential part of x_c − t_v: zero (to round-off) when t_v is the
    /// orthogonal projection inside the face, positive when the node projects outside the surface.
    pub tangential_offset: f64,
}

/// Largest number of Gauss–Newton iterations on one face.
const MAX_ITERATIONS: usize = 40;

/// The reference point (u, v) moved into the reference element (triangle or [−1, 1]²).
fn clamp_reference(kind: ElementType, uv: [f64; 2]) -> [f64; 2] {
    if is_triangle(kind) {
        let (mut u, mut v) = (uv[0].max(0.0), uv[1].max(0.0));
        if u + v > 1.0 {
            // nearest point of the hypotenuse u + v = 1
            let s = (0.5 * (1.0 + u - v)).clamp(0.0, 1.0);
            u = s;
            v = 1.0 - s;
        }
        [u, v]
    } else {
        [uv[0].clamp(-1.0, 1.0), uv[1].clamp(-1.0, 1.0)]
    }
}

/// Position x(u, v) and tangents ∂x/∂u, ∂x/∂v of a face with node positions `xs`.
fn evaluate(kind: ElementType, xs: &[[f64; 3]], uv: [f64; 2]) -> [[f64; 3]; 3] {
    let (n, d) = surface_shape(kind, uv[0], uv[1]);
    let mut out = [[0.0; 3]; 3];
    for ((x, nk), dk) in xs.iter().zip(&n).zip(&d) {
        for c in 0..3 {
            out[0][c] += nk * x[c];
            out[1][c] += dk[0] * x[c];
            out[2][c] += dk[1] * x[c];
        }
    }
    out
}

/// The point of the face (node positions `xs`) nearest to `x`, by Gauss–Newton from `uv0` with
/// the iterate kept inside the reference element; returns its reference coordinates.
pub fn closest_on_face(kind: ElementType, xs: &[[f64; 3]], x: [f64; 3], uv0: [f64; 2]) -> [f64; 2] {
    let mut uv = clamp_reference(kind, uv0);
    for _ in 0..MAX_ITERATIONS {
        let [p, xu, xv] = evaluate(kind, xs, uv);
        let r = sub(x, p);
        let (a, b, c) = (dot(xu, xu), dot(xu, xv), dot(xv, xv));
        let det = a * c - b * b;
        if det.is_nan() || det <= 0.0 {
            break;
        }
        let (gu, gv) = (dot(xu, r), dot(xv, r));
        let du = (c * gu - b * gv) / det;
        let dv = (a * gv - b * gu) / det;
        let next = clamp_reference(kind, [uv[0] + du, uv[1] + dv]);
        let step = (next[0] - uv[0]).abs() + (next[1] - uv[1]).abs();
        uv = next;
        if step < 1e-15 {
            break;
        }
    }
    along_border(kind, xs, x, uv)
}

/// Reference coordinates of the corners of a triangle (unit triangle) or quad ([−1, 1]²), in
/// Gmsh order.
fn reference_corners(kind: ElementType) -> &'static [[f64; 2]] {
    if is_triangle(kind) {
        &[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]
    } else {
        &[[-1.0, -1.0], [1.0, -1.0], [1.0, 1.0], [-1.0, 1.0]]
    }
}

/// The minimiser of |x − x(u, v)| when the Gauss–Newton iterate `uv` stopped on the border of
/// the reference element. The clamped step stops where the *unconstrained* step points out of
/// the element, which is the constrained minimum only when ∂x/∂u ⊥ ∂x/∂v; so from there each
/// edge the point lies on is searched by Gauss–Newton along the edge (parameter t ∈ [0, 1]),
/// and the nearest of these points and `uv` is returned. An interior `uv`, or one where x − x(u, v)
/// is already normal to the face (tangential part below 1e-9 of the face's size), is returned as is.
fn along_border(kind: ElementType, xs: &[[f64; 3]], x: [f64; 3], uv: [f64; 2]) -> [f64; 2] {
    const EPS: f64 = 1e-12;
    let [p, xu, xv] = evaluate(kind, xs, uv);
    let r = sub(x, p);
    let n = cross(xu, xv);
    let nn = dot(n, n);
    if nn > 0.0 {
        let tangential = norm(sub(r, scale(dot(r, n) / nn, n)));
        if tangential <= 1e-9 * norm(xu).max(norm(xv)) {
            return uv;
        }
    }
    let corners = reference_corners(kind);
    let dist2 = |uv: [f64; 2]| {
        let d = sub(x, evaluate(kind, xs, uv)[0]);
        dot(d, d)
    };
    let mut best = (dist2(uv), uv);
    for k in 0..corners.len() {
        let (a, b) = (corners[k], corners[(k + 1) % corners.len()]);
        let e = [b[0] - a[0], b[1] - a[1]];
        let len2 = e[0] * e[0] + e[1] * e[1];
        let mut t = ((uv[0] - a[0]) * e[0] + (uv[1] - a[1]) * e[1]) / len2;
        let off = [a[0] + t * e[0] - uv[0], a[1] + t * e[1] - uv[1]];
        if off[0].abs() > EPS || off[1].abs() > EPS || !(-EPS..=1.0 + EPS).contains(&t) {
            continue; // uv is not on this edge
        }
        for _ in 0..MAX_ITERATIONS {
            let at = [a[0] + t * e[0], a[1] + t * e[1]];
            let [p, xu, xv] = evaluate(kind, xs, at);
            let xt = [0, 1, 2].map(|c| xu[c] * e[0] + xv[c] * e[1]);
            let g = dot(xt, xt);
            if g.is_nan() || g <= 0.0 {
                break;
            }
            let next = (t + dot(sub(x, p), xt) / g).clamp(0.0, 1.0);
            let step = (next - t).abs();
            t = next;
            if step < 1e-15 {
                break;
            }
        }
        // Exactly on the edge's line: the other coordinate from the corners, not from t·e.
        let on = match (e[0] == 0.0, e[1] == 0.0) {
            (true, _) => [a[0], a[1] + t * e[1]],
            (_, true) => [a[0] + t * e[0], a[1]],
            _ => [a[0] + t * e[0], b[1] + (1.0 - t) * (a[1] - b[1])],
        };
        let d = dist2(on);
        if d < best.0 * (1.0 - 1e-12) {
            best = (d, on);
        }
    }
    best.1
}

/// The local frame (rows t1, t2, n) of a face at reference point `uv` (`docs/conventions.md` §3).
pub fn local_frame(kind: ElementType, xs: &[[f64; 3]], uv: [f64; 2]) -> [[f64; 3]; 3] {
    let [_, xu, xv] = evaluate(kind, xs, uv);
    frame_from_tangents(xu, xv, sub(xs[1], xs[0]))
}

/// The frame with n = unit(x_u × x_v) and t1 = `edge` projected on the tangent plane.
fn frame_from_tangents(xu: [f64; 3], xv: [f64; 3], edge: [f64; 3]) -> [[f64; 3]; 3] {
    let n = unit(cross(xu, xv));
    let t1 = unit(sub(edge, scale(dot(edge, n), n)));
    let t2 = cross(n, t1);
    [t1, t2, n]
}

/// The projection record of `x` at the point `point` of face `f` with reference coordinates `uv`
/// and frame `frame`.
fn projection_at(
    f: usize,
    x: [f64; 3],
    uv: [f64; 2],
    point: [f64; 3],
    frame: [[f64; 3]; 3],
) -> Projection {
    let d = sub(x, point);
    let gap = dot(d, frame[2]);
    Projection {
        face: f,
        uv,
        point,
        frame,
        gap,
        distance: norm(d),
        tangential_offset: norm(sub(d, scale(gap, frame[2]))),
    }
}

impl TargetSurface {
    /// The projection of `x` onto face `f`, starting the search at reference point `uv0`.
    pub fn project_on_face(&self, f: usize, x: [f64; 3], uv0: [f64; 2]) -> Projection {
        let kind = self.faces[f].kind;
        let xs = self.face_points(f);
        let uv = closest_on_face(kind, &xs, x, uv0);
        let [point, _, _] = evaluate(kind, &xs, uv);
        projection_at(f, x, uv, point, local_frame(kind, &xs, uv))
    }

    /// A flat triangle3 face: the search already found the exact nearest point, with barycentric
    /// coordinates `bary` (of corners 0, 1, 2), so (u, v) = (b1, b2) and the frame is constant.
    fn project_on_flat_triangle(&self, f: usize, x: [f64; 3], bary: [f64; 3]) -> Projection {
        let nodes = &self.faces[f].nodes;
        let [x0, x1, x2] = [0, 1, 2].map(|k| self.points[nodes[k] as usize]);
        let point: [f64; 3] =
            std::array::from_fn(|c| bary[0] * x0[c] + bary[1] * x1[c] + bary[2] * x2[c]);
        let (e1, e2) = (sub(x1, x0), sub(x2, x0));
        projection_at(
            f,
            x,
            [bary[1], bary[2]],
            point,
            frame_from_tangents(e1, e2, e1),
        )
    }

    /// The projection of `x` onto the surface, or `None` when no face comes closer than
    /// `search_radius` (m). The BVH gives the nearest flat sub-triangle; the point is refined on
    /// the curved face; if it lands on the face's border, the neighbouring faces are tried too.
    pub fn project(&self, x: [f64; 3], search_radius: f64) -> Option<Projection> {
        let (_, (tri, location)) = self
            .trimesh()
            .project_local_point_and_get_location_with_max_dist(
                PVec::new(x[0], x[1], x[2]),
                false,
                search_radius,
            )?;
        let (f, s) = self.sub_triangle(tri);
        let bary = location.barycentric_coordinates()?;
        let kind = self.faces[f].kind;
        if kind == ElementType::Triangle3 {
            let best = self.project_on_flat_triangle(f, x, bary);
            if best.tangential_offset <= 1e-9 * self.mean_edge {
                return Some(best);
            }
            return Some(self.best_among_neighbours(f, x, best));
        }
        let corners = subdivision(kind)[s];
        let mut uv0 = [0.0; 2];
        for (b, &local) in bary.iter().zip(&corners) {
            let r = reference_node(kind, local);
            uv0[0] += b * r[0];
            uv0[1] += b * r[1];
        }
        let best = self.project_on_face(f, x, uv0);
        if best.tangential_offset <= 1e-9 * self.mean_edge {
            return Some(best);
        }
        Some(self.best_among_neighbours(f, x, best))
    }

    /// [`TargetSurface::project`] for many points, in parallel (rayon), in the order given.
    pub fn project_many(&self, points: &[[f64; 3]], search_radius: f64) -> Vec<Option<Projection>> {
        points
            .par_iter()
            .map(|&x| self.project(x, search_radius))
            .collect()
    }

    /// The nearest of `first` and the projections onto the faces sharing a node with face `f`
    /// (ties in distance, within 1e-12 of the mean edge, go to the smaller tangential offset).
    fn best_among_neighbours(&self, f: usize, x: [f64; 3], first: Projection) -> Projection {
        let tie = 1e-12 * self.mean_edge;
        let mut best = first;
        for g in self.neighbours(f) {
            if g == f {
                continue;
            }
            let kind = self.faces[g].kind;
            let centre = if is_triangle(kind) {
                [1.0 / 3.0, 1.0 / 3.0]
            } else {
                [0.0, 0.0]
            };
            let p = self.project_on_face(g, x, centre);
            let closer = p.distance < best.distance - tie;
            let tied = (p.distance - best.distance).abs() <= tie;
            if closer || (tied && p.tangential_offset < best.tangential_offset) {
                best = p;
            }
        }
        best
    }
}
