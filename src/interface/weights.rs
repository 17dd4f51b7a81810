//! SAMA weights (paper eqs 28–30) and the tributary areas that share the interface preload among
//! the contact nodes.

use std::collections::BTreeMap;

use crate::mesh::faces::{area_vector, surface_quadrature, surface_shape};
use crate::mesh::ElementType;

use crate::vec3::{dot, norm, sub};

/// Inverse-distance weights of the target nodes of one contact node (SAMA paper eqs 28–29).
///
/// * `virtual_point`: the virtual node t_v (m);
/// * `frame`: the local frame at t_v (rows t1, t2, n); the distances are measured in the contact
///   plane spanned by t1, t2 (eq 28: d_j = √((x_tv − x_tj)² + (y_tv − y_tj)²) in local coordinates);
/// * `targets`: positions (m) of the n_T target nodes (all nodes of the target face);
/// * `coincident`: the distance (m) below which d_j counts as 0 (a node pair of a conforming mesh).
///
/// Returns w_j (eq 29): if some d_j = 0, w_j = 1 for the first such node and 0 for the others;
/// otherwise w_j = (d_j Σ_i 1/d_i)⁻¹, evaluated as (1/d_j)/Σ_i(1/d_i). Σ_j w_j = 1 (eq 30) to
/// round-off.
pub fn inverse_distance_weights(
    virtual_point: [f64; 3],
    frame: &[[f64; 3]; 3],
    targets: &[[f64; 3]],
    coincident: f64,
) -> Vec<f64> {
    let d: Vec<f64> = targets
        .iter()
        .map(|&x| plane_distance(virtual_point, frame, x))
        .collect();
    let mut w = vec![0.0; d.len()];
    if let Some(j) = d.iter().position(|&dj| dj <= coincident) {
        w[j] = 1.0;
        return w;
    }
    let inv_sum: f64 = d.iter().map(|dj| 1.0 / dj).sum();
    for (wj, dj) in w.iter_mut().zip(&d) {
        *wj = (1.0 / dj) / inv_sum;
    }
    w
}

/// Shape-function weights of the target nodes of one contact node (SAMA paper §4, Fig. 8: the
/// virtual node's displacement interpolated on the target face, u(t_v) = Σ_j N_j u_tj).
///
/// * `kind`, `uv`: the target face's element type and the reference coordinates of t_v on it;
/// * `virtual_point`, `frame`, `targets`, `coincident`: as for [`inverse_distance_weights`]: when a target node
///   lies within `coincident` of t_v in the contact plane, it gets weight 1 and the others 0
///   (exactly the node-to-node pair, as eq 29 does).
///
/// Otherwise returns N_j(u, v) in the face's node order: Σ_j N_j = 1 and Σ_j N_j x_tj = t_v on a
/// flat face (linear fields are reproduced, so a rigid motion gives no relative displacement);
/// the corner values of quadratic faces are negative inside the face. Values below 1e-12 in
/// magnitude (nodes of the edge t_v lies on) are set to 0, so the pair leaves them out.
pub fn interpolation_weights(
    kind: ElementType,
    uv: [f64; 2],
    virtual_point: [f64; 3],
    frame: &[[f64; 3]; 3],
    targets: &[[f64; 3]],
    coincident: f64,
) -> Vec<f64> {
    if let Some(j) = targets
        .iter()
        .position(|&x| plane_distance(virtual_point, frame, x) <= coincident)
    {
        let mut w = vec![0.0; targets.len()];
        w[j] = 1.0;
        return w;
    }
    let (n, _) = surface_shape(kind, uv[0], uv[1]);
    n.into_iter()
        .map(|nj| if nj.abs() < 1e-12 { 0.0 } else { nj })
        .collect()
}

/// Eq 28: distance (m) between t_v and a target node, measured in the contact plane (t1, t2).
pub fn plane_distance(virtual_point: [f64; 3], frame: &[[f64; 3]; 3], target: [f64; 3]) -> f64 {
    let d = sub(virtual_point, target);
    let x = dot(d, frame[0]);
    let y = dot(d, frame[1]);
    (x * x + y * y).sqrt()
}

/// Tributary areas (m²) of the nodes of a set of surface faces: each face's area is lumped to its
/// nodes in proportion to ∫ N_i² dA (the "HRZ" diagonal lumping of Hinton, Rock and Zienkiewicz,
/// 1976). The rule gives every node a positive share — also the corner nodes of quadratic faces,
/// where the consistent shares ∫ N_i dA vanish (triangle6) or turn negative (quad8) — and equal
/// shares on linear triangles (1/3) and parallelogram quads (1/4). On a flat triangle6 the
/// corner : mid-side ratio is 3 : 16 (shares 1/19 and 16/57). Σ over nodes = total area.
///
/// `faces` yields (type, node indices, node positions); returns node index → area, ascending.
pub fn tributary_areas<'a>(
    faces: impl Iterator<Item = (ElementType, &'a [u32], Vec<[f64; 3]>)>,
) -> BTreeMap<u32, f64> {
    let mut areas = BTreeMap::new();
    for (kind, nodes, xs) in faces {
        for (node, a) in nodes.iter().zip(lumped_face_area(kind, &xs)) {
            *areas.entry(*node).or_insert(0.0) += a;
        }
    }
    areas
}

/// HRZ shares of one face's area (m²) per node, in the face's node order.
pub fn lumped_face_area(kind: ElementType, xs: &[[f64; 3]]) -> Vec<f64> {
    let mut diag = vec![0.0; xs.len()];
    let mut area = 0.0;
    for (u, v, w) in surface_quadrature(kind) {
        let da = w * norm(area_vector(kind, xs, u, v));
        area += da;
        let (n, _) = surface_shape(kind, u, v);
        for (m, ni) in diag.iter_mut().zip(&n) {
            *m += ni * ni * da;
        }
    }
    let total: f64 = diag.iter().sum();
    diag.iter().map(|m| area * m / total).collect()
}
