//! The target surface of a SAMA interface: the target group's faces in their placed position
//! (cyclic rotation R_α^σ, then the static misalignment), with a `parry3d-f64` triangle mesh and
//! its BVH for the nearest-face search.
//!
//! Quadratic faces are subdivided into flat sub-triangles through their mid-side (and centre)
//! nodes for the search only: a triangle6 into 4, a quad4 into 2, a quad8 into 6 (four corner
//! triangles and the inner quad of the mid-side nodes), a quad9 into 8 (around the centre node).
//! The exact point on the curved face is then found with the face's isoparametric map
//! ([`super::project`]). The sub-triangles use the face's own nodes as vertices, so the search
//! mesh has exactly the surface's nodes.

use std::collections::HashMap;

use parry3d_f64::math::Vector as PVec;
use parry3d_f64::shape::TriMesh;

use crate::error::{Error, Result};
use crate::mesh::faces::{area_vector, surface_quadrature};
use crate::mesh::ElementType;

use crate::vec3::{cross, dot, norm, sub};

/// One face of a surface: its type, its nodes (indices into the surface's `points`, in Gmsh order
/// and outward orientation) and the tag of the mesh element it comes from (for messages and output).
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceFace {
    /// Triangle3/6 or Quad4/8/9.
    pub kind: ElementType,
    /// Surface-local node indices in Gmsh order for `kind`, outward orientation.
    pub nodes: Vec<u32>,
    /// Tag of the surface element (Gmsh element tag).
    pub tag: u64,
}

/// A searchable surface of triangle and quad faces (linear or quadratic).
pub struct TargetSurface {
    /// Positions (m) of the surface nodes, as placed (rotated and misaligned).
    pub points: Vec<[f64; 3]>,
    /// The faces.
    pub faces: Vec<SurfaceFace>,
    /// Search mesh of flat sub-triangles with its BVH.
    trimesh: TriMesh,
    /// For every sub-triangle: its face and its local index within that face's subdivision.
    sub_of: Vec<(u32, u8)>,
    /// Node → faces adjacency (CSR): faces of node i are `node_faces[node_start[i]..node_start[i+1]]`.
    node_start: Vec<usize>,
    node_faces: Vec<u32>,
    /// Mean length (m) of the faces' corner-to-corner edges.
    pub mean_edge: f64,
    /// Edge tolerance (m) of every face edge, `edge_start[f] + k` for edge k of face f:
    /// [`edge_tolerance`] for an edge on the surface's boundary, +∞ for an edge shared by two faces.
    edge_tol: Vec<f64>,
    /// First entry of face f in `edge_tol`.
    edge_start: Vec<usize>,
    /// Per surface node: the largest edge tolerance of its boundary edges, +∞ for an interior node.
    node_tol: Vec<f64>,
}

/// Edge tolerance as a fraction of the boundary edge's length: accepts the round-off of the
/// node positions of two meshes of the same boundary (a straight boundary has no sagitta).
pub const EDGE_SIZE_FRACTION: f64 = 1e-3;

/// Multiple of the boundary's chord sagitta in the edge tolerance.
pub const EDGE_SAGITTA_FACTOR: f64 = 2.0;

/// Turning angle (rad) of the boundary polyline above which a boundary node is a corner of the
/// outline (its angle says nothing about the curvature of the sides it joins).
pub const CORNER_ANGLE: f64 = std::f64::consts::FRAC_PI_4;

/// The edge tolerance (m) of a boundary edge of length `chord` (m, corner to corner) on a
/// boundary of curvature `curvature` (1/m):
/// `EDGE_SIZE_FRACTION · L + EDGE_SAGITTA_FACTOR · κ L² / 8`.
///
/// κ L²/8 is the sagitta of a chord of length L on an arc of curvature κ: the farthest that a
/// point of the true boundary curve — a node of the other mesh of the same curved edge — lies
/// outside the chorded (linear) target face. A quadratic face follows the arc far closer, so the
/// bound holds for it too.
pub fn edge_tolerance(chord: f64, curvature: f64) -> f64 {
    EDGE_SIZE_FRACTION * chord + EDGE_SAGITTA_FACTOR * curvature * chord * chord / 8.0
}

/// Corner positions (in the face's node list) of edge k of a face, and its mid-side node if any.
pub fn face_edge(kind: ElementType, k: usize) -> (usize, usize, Option<usize>) {
    let corners = kind.num_corners();
    let mid = match kind {
        ElementType::Triangle6 => Some(3 + k),
        ElementType::Quad8 | ElementType::Quad9 => Some(4 + k),
        _ => None,
    };
    (k, (k + 1) % corners, mid)
}

/// Sub-triangles of a face for the search, as triples of positions in the face's node list.
pub fn subdivision(kind: ElementType) -> &'static [[usize; 3]] {
    match kind {
        ElementType::Triangle3 => &[[0, 1, 2]],
        ElementType::Triangle6 => &[[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]],
        ElementType::Quad4 => &[[0, 1, 2], [0, 2, 3]],
        ElementType::Quad8 => &[
            [0, 4, 7],
            [4, 1, 5],
            [5, 2, 6],
            [7, 6, 3],
            [4, 5, 6],
            [4, 6, 7],
        ],
        ElementType::Quad9 => &[
            [0, 4, 8],
            [0, 8, 7],
            [4, 1, 5],
            [4, 5, 8],
            [8, 5, 2],
            [8, 2, 6],
            [7, 8, 6],
            [7, 6, 3],
        ],
        _ => &[],
    }
}

/// Reference coordinates (u, v) of the nodes of a surface element in Gmsh order (triangles on
/// the unit triangle, quads on [−1, 1]², see [`crate::mesh::faces`]).
pub fn reference_node(kind: ElementType, local: usize) -> [f64; 2] {
    const TRI: [[f64; 2]; 6] = [
        [0.0, 0.0],
        [1.0, 0.0],
        [0.0, 1.0],
        [0.5, 0.0],
        [0.5, 0.5],
        [0.0, 0.5],
    ];
    const QUAD: [[f64; 2]; 9] = [
        [-1.0, -1.0],
        [1.0, -1.0],
        [1.0, 1.0],
        [-1.0, 1.0],
        [0.0, -1.0],
        [1.0, 0.0],
        [0.0, 1.0],
        [-1.0, 0.0],
        [0.0, 0.0],
    ];
    if is_triangle(kind) {
        TRI[local]
    } else {
        QUAD[local]
    }
}

/// Whether a surface element type is a triangle (else a quad).
pub fn is_triangle(kind: ElementType) -> bool {
    kind.first_order() == ElementType::Triangle3
}

/// Why the face with node positions `xs` is degenerate, if it is: an area vector that vanishes
/// (relative to the longest corner edge squared) or reverses direction at a quadrature point or at
/// a node (a collapsed or folded face).
pub fn degeneracy(kind: ElementType, xs: &[[f64; 3]]) -> Option<String> {
    let corners = kind.num_corners();
    let longest = (0..corners)
        .map(|k| norm(sub(xs[(k + 1) % corners], xs[k])))
        .fold(0.0, f64::max);
    if !longest.is_finite() || longest <= 0.0 {
        return Some("its corner nodes coincide".into());
    }
    let centre = if is_triangle(kind) {
        [1.0 / 3.0, 1.0 / 3.0]
    } else {
        [0.0, 0.0]
    };
    let a0 = if kind == ElementType::Triangle3 {
        cross(sub(xs[1], xs[0]), sub(xs[2], xs[0]))
    } else {
        area_vector(kind, xs, centre[0], centre[1])
    };
    let floor = 1e-10 * longest * longest;
    if norm(a0) <= floor {
        return Some("its area is zero (collinear or coincident nodes)".into());
    }
    if kind == ElementType::Triangle3 {
        return None; // constant area vector
    }
    let mut samples: Vec<[f64; 2]> = surface_quadrature(kind)
        .iter()
        .map(|&(u, v, _)| [u, v])
        .collect();
    samples.extend((0..kind.num_nodes()).map(|k| reference_node(kind, k)));
    for [u, v] in samples {
        let a = area_vector(kind, xs, u, v);
        if dot(a, a0) <= floor * norm(a0) {
            return Some(format!(
                "its area vector vanishes or reverses at reference point ({u:.3}, {v:.3}) (a folded or badly curved face)"
            ));
        }
    }
    None
}

impl TargetSurface {
    /// Builds the surface from node positions and faces. `label` names the surface in messages
    /// (e.g. "target group 'shroud_target' of contact 'shroud'").
    ///
    /// Errors ([`Error::Input`]): no faces, a face that is not a triangle or quad, a node index out
    /// of range, a degenerate face (named by its element tag, see [`degeneracy`]).
    pub fn new(points: Vec<[f64; 3]>, faces: Vec<SurfaceFace>, label: &str) -> Result<Self> {
        if faces.is_empty() {
            return Err(Error::input(format!(
                "{label} has no faces; the target must be a surface group (triangles or quads on the boundary of the meshed volume)"
            )));
        }
        let mut indices: Vec<[u32; 3]> = Vec::new();
        let mut sub_of: Vec<(u32, u8)> = Vec::new();
        let mut edge_sum = 0.0;
        let mut edge_count = 0usize;
        for (f, face) in faces.iter().enumerate() {
            let sub = subdivision(face.kind);
            if sub.is_empty() || face.nodes.len() != face.kind.num_nodes() {
                return Err(Error::input(format!(
                    "{label}: element {} is a {} with {} nodes; surfaces need triangles or quads (linear or quadratic)",
                    face.tag,
                    face.kind,
                    face.nodes.len()
                )));
            }
            if let Some(&bad) = face.nodes.iter().find(|&&n| n as usize >= points.len()) {
                return Err(Error::input(format!(
                    "{label}: element {} refers to node index {bad}, but the surface has {} nodes",
                    face.tag,
                    points.len()
                )));
            }
            let xs: Vec<[f64; 3]> = face.nodes.iter().map(|&n| points[n as usize]).collect();
            if let Some(why) = degeneracy(face.kind, &xs) {
                return Err(Error::input(format!(
                    "{label}: face element {} is degenerate: {why}; fix the mesh of that surface",
                    face.tag
                )));
            }
            let corners = face.kind.num_corners();
            for k in 0..corners {
                edge_sum += norm(sub_pts(&xs, (k + 1) % corners, k));
                edge_count += 1;
            }
            for (s, tri) in sub.iter().enumerate() {
                indices.push([face.nodes[tri[0]], face.nodes[tri[1]], face.nodes[tri[2]]]);
                sub_of.push((f as u32, s as u8));
            }
        }
        let vertices: Vec<PVec> = points.iter().map(|p| PVec::new(p[0], p[1], p[2])).collect();
        let trimesh = TriMesh::new(vertices, indices)
            .map_err(|e| Error::input(format!("{label}: cannot build its search mesh: {e}")))?;
        let (node_start, node_faces) = adjacency(points.len(), &faces);
        let (edge_tol, edge_start, node_tol) = boundary_tolerances(&points, &faces);
        Ok(TargetSurface {
            points,
            faces,
            trimesh,
            sub_of,
            node_start,
            node_faces,
            mean_edge: edge_sum / edge_count as f64,
            edge_tol,
            edge_start,
            node_tol,
        })
    }

    /// The search mesh (flat sub-triangles with their BVH).
    pub fn trimesh(&self) -> &TriMesh {
        &self.trimesh
    }

    /// Face and sub-triangle index of search triangle `t`.
    pub fn sub_triangle(&self, t: u32) -> (usize, usize) {
        let (f, s) = self.sub_of[t as usize];
        (f as usize, s as usize)
    }

    /// Faces that share at least one node with face `f` (including `f`), ascending, distinct.
    pub fn neighbours(&self, f: usize) -> Vec<usize> {
        let mut out: Vec<usize> = self.faces[f]
            .nodes
            .iter()
            .flat_map(|&n| {
                let n = n as usize;
                self.node_faces[self.node_start[n]..self.node_start[n + 1]]
                    .iter()
                    .map(|&g| g as usize)
            })
            .collect();
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Node positions of face `f`.
    pub fn face_points(&self, f: usize) -> Vec<[f64; 3]> {
        self.faces[f]
            .nodes
            .iter()
            .map(|&n| self.points[n as usize])
            .collect()
    }

    /// The edge tolerance (m) at the reference point `uv` of face `f` (a point of the face's
    /// border, as the nearest point of a node outside the surface is): on a corner, the largest
    /// [`edge_tolerance`] of the surface boundary edges at that node; on an edge, that edge's
    /// tolerance. +∞ where the point is on an edge or node shared with other faces (a node above a
    /// crease of the chorded surface has the target under it). Inside the face (not expected for
    /// a point with a tangential offset): [`EDGE_SIZE_FRACTION`] × the mean edge.
    pub fn border_tolerance(&self, f: usize, uv: [f64; 2]) -> f64 {
        let face = &self.faces[f];
        let on = border_edges(face.kind, uv);
        match on.as_slice() {
            [] => EDGE_SIZE_FRACTION * self.mean_edge,
            [k] => self.edge_tol[self.edge_start[f] + k],
            [a, b, ..] => {
                // The corner shared by edges a and b: edge a's end is edge b's start or vice versa.
                let (a0, a1, _) = face_edge(face.kind, *a);
                let (b0, _, _) = face_edge(face.kind, *b);
                let corner = if a1 == b0 { a1 } else { a0 };
                self.node_tol[face.nodes[corner] as usize]
            }
        }
    }

    /// Length (m) of the diagonal of the surface's bounding box.
    pub fn diagonal(&self) -> f64 {
        let [lo, hi] = crate::mesh::bbox_of(self.points.iter());
        norm(sub(hi, lo))
    }
}

fn sub_pts(xs: &[[f64; 3]], a: usize, b: usize) -> [f64; 3] {
    sub(xs[a], xs[b])
}

/// The edges (indices k of [`face_edge`]) of the reference element on which `uv` lies (within
/// 1e-9), ascending.
fn border_edges(kind: ElementType, uv: [f64; 2]) -> Vec<usize> {
    const EPS: f64 = 1e-9;
    let [u, v] = uv;
    let on: Vec<bool> = if is_triangle(kind) {
        vec![v.abs() <= EPS, (u + v - 1.0).abs() <= EPS, u.abs() <= EPS]
    } else {
        vec![
            (v + 1.0).abs() <= EPS,
            (u - 1.0).abs() <= EPS,
            (v - 1.0).abs() <= EPS,
            (u + 1.0).abs() <= EPS,
        ]
    };
    on.iter()
        .enumerate()
        .filter(|(_, &b)| b)
        .map(|(k, _)| k)
        .collect()
}

/// Edge tolerances of a surface's faces (see [`TargetSurface::border_tolerance`]).
///
/// The boundary edges are the face edges (corner pairs) that belong to one face only. They form
/// the boundary polyline through their corner and mid-side nodes; at a node joining two segments
/// of lengths l1, l2 that turn by θ < [`CORNER_ANGLE`], the boundary curvature is
/// κ = θ / ((l1 + l2)/2) (exact for a circle sampled by equal chords, to O(θ²)). An edge's κ is
/// the largest at its nodes (0 when all are corners), and its tolerance [`edge_tolerance`].
///
/// Returns (tolerance per face edge, first edge of each face, tolerance per node).
fn boundary_tolerances(
    points: &[[f64; 3]],
    faces: &[SurfaceFace],
) -> (Vec<f64>, Vec<usize>, Vec<f64>) {
    let key = |a: u32, b: u32| (a.min(b), a.max(b));
    let mut count: HashMap<(u32, u32), u32> = HashMap::new();
    for face in faces {
        for k in 0..face.kind.num_corners() {
            let (a, b, _) = face_edge(face.kind, k);
            *count.entry(key(face.nodes[a], face.nodes[b])).or_default() += 1;
        }
    }
    // Boundary segments at each node: the neighbouring node along the boundary polyline.
    let mut along: HashMap<u32, Vec<u32>> = HashMap::new();
    let mut link = |p: u32, q: u32| {
        along.entry(p).or_default().push(q);
        along.entry(q).or_default().push(p);
    };
    for face in faces {
        for k in 0..face.kind.num_corners() {
            let (a, b, mid) = face_edge(face.kind, k);
            let (na, nb) = (face.nodes[a], face.nodes[b]);
            if count[&key(na, nb)] != 1 {
                continue;
            }
            match mid {
                Some(m) => {
                    link(na, face.nodes[m]);
                    link(face.nodes[m], nb);
                }
                None => link(na, nb),
            }
        }
    }
    let curvature = |n: u32| -> f64 {
        let Some(nb) = along.get(&n) else { return 0.0 };
        let [p, q] = nb.as_slice() else { return 0.0 };
        let x = points[n as usize];
        let (d1, d2) = (sub(x, points[*p as usize]), sub(points[*q as usize], x));
        let (l1, l2) = (norm(d1), norm(d2));
        if l1 <= 0.0 || l2 <= 0.0 {
            return 0.0;
        }
        let theta = (dot(d1, d2) / (l1 * l2)).clamp(-1.0, 1.0).acos();
        if theta < CORNER_ANGLE {
            theta / (0.5 * (l1 + l2))
        } else {
            0.0
        }
    };
    let mut edge_tol = Vec::new();
    let mut edge_start = Vec::with_capacity(faces.len());
    let mut node_tol = vec![f64::INFINITY; points.len()];
    let mut on_boundary = vec![false; points.len()];
    for face in faces {
        edge_start.push(edge_tol.len());
        for k in 0..face.kind.num_corners() {
            let (a, b, mid) = face_edge(face.kind, k);
            let (na, nb) = (face.nodes[a], face.nodes[b]);
            if count[&key(na, nb)] != 1 {
                edge_tol.push(f64::INFINITY);
                continue;
            }
            let kappa = [Some(na), mid.map(|m| face.nodes[m]), Some(nb)]
                .into_iter()
                .flatten()
                .map(curvature)
                .fold(0.0, f64::max);
            let tol = edge_tolerance(norm(sub(points[nb as usize], points[na as usize])), kappa);
            edge_tol.push(tol);
            for n in [na, nb] {
                let n = n as usize;
                node_tol[n] = if on_boundary[n] {
                    node_tol[n].max(tol)
                } else {
                    tol
                };
                on_boundary[n] = true;
            }
        }
    }
    (edge_tol, edge_start, node_tol)
}

/// Node → faces adjacency in CSR form.
fn adjacency(num_points: usize, faces: &[SurfaceFace]) -> (Vec<usize>, Vec<u32>) {
    let mut count = vec![0usize; num_points + 1];
    for face in faces {
        for &n in &face.nodes {
            count[n as usize + 1] += 1;
        }
    }
    for i in 0..num_points {
        count[i + 1] += count[i];
    }
    let mut fill = count.clone();
    let mut list = vec![0u32; count[num_points]];
    for (f, face) in faces.iter().enumerate() {
        for &n in &face.nodes {
            list[fill[n as usize]] = f as u32;
            fill[n as usize] += 1;
        }
    }
    (count, list)
}
