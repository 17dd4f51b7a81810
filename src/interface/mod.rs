//! Contact pairs of a friction interface: the SAMA model for non-conforming meshes (Battiato,
//! "Self-adaptive macroslip array ...", Nonlinear Dynamics 2021, §4 eqs 28–32, Figs 5–8) and the
//! node-to-node model for conforming ones, with cyclic placement of the target (§5, eqs 33–34).
//!
//! For every `[[contact]]` of a case, [`build_interfaces`]:
//!
//! 1. **places the target surface** — the outward faces of the `target` group — in the position
//!    of the sector it belongs to: rotated by R_α^σ about the cyclic axis, σ ∈ {0, +1, −1} being
//!    the rotation under which the most contact nodes project onto it (ties: the smaller mean
//!    distance) — found from the geometry, never asked of the user (`docs/conventions.md` §3). A case
//!    without `[cyclic]` uses σ = 0. The static misalignment of the contact (`misalignment =
//!    { rotate, translate }`, paper §6.2) is applied next, to the placed surface, i.e. in the
//!    contact face's coordinates: rotation about `rotate.origin` first, then translation;
//! 2. **projects every contact node** onto it ([`project`]): the virtual node t_v, the target face
//!    containing it with its n_T nodes (mid-side nodes included), the local frame (rows t1, t2, n;
//!    n = the target face's outward normal, towards the contact body) and the signed gap. A node
//!    whose nearest surface point is not an orthogonal projection (tangential offset above the
//!    coincidence tolerance) lies outside the target's border — at a curved edge the chorded
//!    target face cuts inside the arc that the other mesh's boundary nodes sit on, by up to the
//!    chord's sagitta κh²/8. Such a node is **paired at that nearest border point** when its
//!    tangential offset is at most the edge tolerance of the border there
//!    ([`surface::edge_tolerance`]: a fraction of the edge length plus twice the sagitta of the
//!    boundary's curvature; unbounded on an edge shared by two faces, where the node is above a
//!    crease of the target), and its offset is reported ([`ContactPair::edge`]). A node farther
//!    outside — no target under it — or farther than [`MAX_DISTANCE`] × the target's mean edge
//!    is **unprojected**: listed in [`ContactInterface::unprojected`], never dropped silently;
//! 3. **weights** (SAMA), for every paired node (on the border as inside a face): w_j by inverse
//!    distance in the contact plane (eqs 28–29, [`weights`]);
//!    zero weights of eq 29's coincident case are left out of the pair. With `coupling =
//!    "interpolated"` the w_j are instead the target face's shape functions N_j at t_v (§4,
//!    Fig. 8; a coincident node still gets weight 1 alone), which may be negative (corner nodes
//!    of quadratic faces);
//! 4. **parameters** per pair c–t_j (eq 31): k_tj = w_j k_t, k_nj = w_j k_n, n0_j = w_j n0_c,
//!    where k_t, k_n are per contact node (`docs/case-file.md`) and n0_c is the contact node's share of
//!    the interface's total preload n0, in proportion to its tributary area on the contact faces
//!    (HRZ lumping, [`weights::tributary_areas`]) among the *paired* contact nodes, so that
//!    Σ_c n0_c = n0. Then eq 32 holds per contact node: Σ_j k_tj = k_t, Σ_j k_nj = k_n,
//!    Σ_j n0_j = n0_c;
//! 5. for `model = "node-to-node"`: pairs every contact node with the target node at the same
//!    position after placement (weight 1); a contact node without one is an error that lists them.
//!
//! With `coupling = "array"` (default) the harmonic balance turns each pair c–t_j into a
//! node-to-node friction element acting on the relative displacement
//! r = u_c − e^{iσφ_k} R_α^σ u_tj (eq 33 of the paper; [`crate::contact::kinematics`]), whose force
//! goes back to the target node by the adjoint map. [`ContactInterface::elements`] hands the pairs to
//! [`crate::contact::pairs::PairSet`] as such elements (weighted parameters and preload rates).
//! With `coupling = "interpolated"` each contact node becomes one element (k_t, k_n, n0_c) on
//! r = u_c − e^{iσφ_k} R_α^σ Σ_j N_j u_tj: the element reads a *virtual node* whose rows the
//! [`crate::contact::mapped::LinearMap`] fills with Σ_j N_j u_tj ([`ContactInterface::elements_with`]).
//!
//! Why the choice matters (measured on the bundled shroud, `tools/validation/stuck_frequencies.rs`): the
//! array's pairs c–t_j join points up to one target element apart, so a rigid rotation θ of both
//! faces stretches them by θ × (x_c − x_tj) and the target face's own deformation within an
//! element is resisted by Σ_j w_j k_t — spurious stiffness that raised the fully stuck frequency
//! of the non-conforming sector by 15 % over the node-to-node benchmark; the interpolated coupling
//! reproduces linear fields exactly and stays within 0.6 %.

pub mod elements;
pub mod geom;
pub mod project;
pub mod report;
pub mod surface;
pub mod weights;

use std::collections::HashMap;

use crate::case::{Case, Contact, ContactElement, ContactModel, Evaluation, SamaCoupling};
use crate::cyclic::{CyclicGeometry, MATCH_TOLERANCE};
use crate::error::{Error, Result};
use crate::mesh::faces::group_faces;
use crate::mesh::Mesh;

use crate::vec3::{norm, sub};
use geom::RigidMap;
use project::Projection;
use surface::{degeneracy, SurfaceFace, TargetSurface};

/// Largest distance from a contact node to its virtual node, as a multiple of the target faces'
/// mean edge length; a node farther away is reported as unprojected.
pub const MAX_DISTANCE: f64 = 0.5;

/// How many nodes an error message lists.
const MAX_LISTED: usize = 10;

/// One contact node and its target nodes: the parallel node-to-node elements c–t_j of the SAMA
/// array (paper Fig. 7a), or the single pair of the node-to-node model.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactPair {
    /// Gmsh tag of the contact node c.
    pub contact_node: u64,
    /// Compact node index of c.
    pub contact_index: u32,
    /// Gmsh tags of the target nodes t_j with non-zero weight.
    pub targets: Vec<u64>,
    /// Compact node indices of the t_j.
    pub target_indices: Vec<u32>,
    /// Weights w_j (eq 29), in [0, 1], Σ w_j = 1 (eq 30).
    pub weights: Vec<f64>,
    /// Local frame at t_v, rows t1, t2, n (`docs/conventions.md` §3), in the contact sector's axes.
    pub frame: [[f64; 3]; 3],
    /// Tag of the target face element that contains t_v.
    pub face: u64,
    /// Reference coordinates of t_v on that face.
    pub reference: [f64; 2],
    /// The virtual node t_v (m), on the placed target surface.
    pub virtual_point: [f64; 3],
    /// |x_c − t_v| (m).
    pub distance: f64,
    /// Signed normal gap (x_c − t_v)·n (m); negative = interpenetration.
    pub gap: f64,
    /// Tributary area of c on the contact faces (m²).
    pub area: f64,
    /// Tangential stiffness k_tj = w_j k_t of each pair (N/m), eq 31.
    pub kt: Vec<f64>,
    /// Normal stiffness k_nj = w_j k_n of each pair (N/m), eq 31.
    pub kn: Vec<f64>,
    /// Static normal preload n0_j = w_j n0_c of each pair (N), eq 31.
    pub n0: Vec<f64>,
    /// The contact node's share n0_c of the interface preload (N).
    pub n0_node: f64,
    /// Set when c projects outside the target surface, by less than the edge tolerance: t_v is
    /// then the nearest point of the target's border, not an orthogonal projection.
    pub edge: Option<EdgeOffset>,
    /// n0_c / n0: the node's fraction of the interface preload (its tributary area over the
    /// projected contact nodes' total area).
    pub preload_share: f64,
}

/// How far outside the target surface a contact node paired on the target's border lies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EdgeOffset {
    /// Length (m) of the tangential part of x_c − t_v (the node's distance outside the border,
    /// measured in the target's tangent plane at t_v).
    pub tangential_offset: f64,
    /// The edge tolerance (m) it was accepted under ([`TargetSurface::border_tolerance`] × the
    /// edge factor); +∞ on an edge shared by two faces.
    pub tolerance: f64,
}

/// A contact node that could not be projected onto the target surface.
#[derive(Clone, Debug, PartialEq)]
pub struct Unprojected {
    /// Gmsh tag of the contact node.
    pub node: u64,
    /// Distance (m) to the nearest point of the target surface within the search radius, if any.
    pub distance: Option<f64>,
    /// Tangential part (m) of the offset to that point (> 0: outside the target surface).
    pub tangential_offset: Option<f64>,
}

/// One friction interface (`[[contact]]`) with its pairs.
#[derive(Clone, Debug, PartialEq)]
pub struct ContactInterface {
    /// The contact's name.
    pub name: String,
    /// SAMA or node-to-node.
    pub model: ContactModel,
    /// SAMA coupling of a contact node to its target nodes (array of eq 31, or interpolated);
    /// irrelevant for pairs with a single target (weight 1).
    pub coupling: SamaCoupling,
    /// 1-D or 2-D friction element per pair.
    pub element: ContactElement,
    /// How the pairs' friction elements are evaluated (AFT or the exact single-harmonic cycle).
    pub evaluation: Evaluation,
    /// Friction coefficient μ of every pair.
    pub mu: f64,
    /// Sector offset σ of the target surface (0 within one sector).
    pub sigma: i32,
    /// R_α^σ (row-major), the rotation that placed the target; the identity for σ = 0.
    pub rotation: [[f64; 3]; 3],
    /// Number of contact nodes (projected or not).
    pub contact_nodes: usize,
    /// Pairs, in ascending contact-node tag order.
    pub pairs: Vec<ContactPair>,
    /// Contact nodes without a projection, ascending.
    pub unprojected: Vec<Unprojected>,
    /// Σ over all pairs of k_tj (N/m) = k_t × number of projected contact nodes.
    pub sum_kt: f64,
    /// Σ over all pairs of k_nj (N/m).
    pub sum_kn: f64,
    /// Σ over all pairs of n0_j (N) = n0 when any node is projected.
    pub sum_n0: f64,
    /// The coincidence tolerance used (m).
    pub coincident_tolerance: f64,
    /// The largest accepted projection distance (m).
    pub max_distance: f64,
}

impl ContactInterface {
    /// The pairs whose contact node lies outside the target surface and was paired at the nearest
    /// point of its border ([`ContactPair::edge`]).
    pub fn edge_pairs(&self) -> impl Iterator<Item = &ContactPair> {
        self.pairs.iter().filter(|p| p.edge.is_some())
    }
}

/// The pairs of every `[[contact]]` of `case` on `mesh`. `cyclic`: the sector geometry for
/// inter-sector contact (σ = ±1 candidates); `None` allows σ = 0 only.
///
/// Errors ([`Error::Input`], each naming the contact and group): a group that is missing, not a
/// surface group, empty or without faces; a degenerate face; contact and target that do not face
/// each other under any candidate rotation (no node projects); non-coincident nodes for the
/// node-to-node model.
pub fn build_interfaces(
    case: &Case,
    mesh: &Mesh,
    cyclic: Option<&CyclicGeometry>,
) -> Result<Vec<ContactInterface>> {
    case.contact
        .iter()
        .map(|c| build_interface(c, mesh, cyclic))
        .collect()
}

/// The contact nodes of an interface with their tributary areas.
struct ContactSide {
    /// Node indices, ascending.
    nodes: Vec<u32>,
    /// Tributary area (m²) of each node.
    areas: Vec<f64>,
}

/// [`build_interfaces`] with the edge tolerances scaled by `edge_factor` (1 in
/// [`build_interfaces`]; 0 pairs only the nodes that project orthogonally inside a face).
pub fn build_interfaces_with(
    case: &Case,
    mesh: &Mesh,
    cyclic: Option<&CyclicGeometry>,
    edge_factor: f64,
) -> Result<Vec<ContactInterface>> {
    case.contact
        .iter()
        .map(|c| build_interface_with(c, mesh, cyclic, edge_factor))
        .collect()
}

/// The pairs of one `[[contact]]` (see the module documentation for the steps).
pub fn build_interface(
    c: &Contact,
    mesh: &Mesh,
    cyclic: Option<&CyclicGeometry>,
) -> Result<ContactInterface> {
    build_interface_with(c, mesh, cyclic, 1.0)
}

/// [`build_interface`] with the edge tolerances ([`TargetSurface::border_tolerance`]) scaled by
/// `edge_factor` ≥ 0.
pub fn build_interface_with(
    c: &Contact,
    mesh: &Mesh,
    cyclic: Option<&CyclicGeometry>,
    edge_factor: f64,
) -> Result<ContactInterface> {
    let label = format!("[[contact]] '{}'", c.name);
    let side = contact_side(c, mesh, &label)?;
    let (target_nodes, faces) = target_faces(c, mesh, &label)?;
    let coincident = MATCH_TOLERANCE * mesh.size();
    let misalign = c
        .misalignment
        .as_ref()
        .map(RigidMap::misalignment)
        .unwrap_or_else(RigidMap::identity);
    let candidates: Vec<i32> = match cyclic {
        Some(g) if g.sectors > 2 => vec![0, 1, -1],
        Some(_) => vec![0, 1],
        None => vec![0],
    };
    let mut trials = Vec::with_capacity(candidates.len());
    for &sigma in &candidates {
        let place = match cyclic {
            Some(g) => misalign.after(&RigidMap::rotation(g.rotation(sigma), g.origin)),
            None => misalign,
        };
        let points: Vec<[f64; 3]> = target_nodes
            .iter()
            .map(|&n| place.apply(mesh.coords[n as usize]))
            .collect();
        let surface = TargetSurface::new(points, faces.clone(), &target_label(&label, c))?;
        let max_distance = MAX_DISTANCE * surface.mean_edge;
        let limits = Limits {
            max_distance,
            coincident,
            edge_factor,
        };
        let projections = project_nodes(&surface, mesh, &side.nodes, &limits);
        trials.push(Trial {
            sigma,
            surface,
            projections,
            max_distance,
        });
    }
    let best = choose_placement(&trials, c, mesh, &label)?;
    let trial = &trials[best];
    let rotation = match cyclic {
        Some(g) => g.rotation(trial.sigma),
        None => RigidMap::identity().rotation,
    };
    let mut iface = ContactInterface {
        name: c.name.clone(),
        model: c.model,
        coupling: c.coupling.unwrap_or_default(),
        element: c.element,
        evaluation: c.evaluation,
        mu: c.mu,
        sigma: trial.sigma,
        rotation,
        contact_nodes: side.nodes.len(),
        pairs: Vec::new(),
        unprojected: Vec::new(),
        sum_kt: 0.0,
        sum_kn: 0.0,
        sum_n0: 0.0,
        coincident_tolerance: coincident,
        max_distance: trial.max_distance,
    };
    let geometry = PairGeometry {
        mesh,
        surface: &trial.surface,
        target_nodes: &target_nodes,
        coincident,
    };
    fill_pairs(&mut iface, c, &side, &trial.projections, &geometry, &label)?;
    Ok(iface)
}

fn target_label(label: &str, c: &Contact) -> String {
    format!("{label}: target group '{}'", c.target)
}

/// The contact group's nodes and tributary areas. Errors: not a surface group, no faces,
/// degenerate faces.
fn contact_side(c: &Contact, mesh: &Mesh, label: &str) -> Result<ContactSide> {
    let faces = group_faces(mesh, &c.contact).map_err(|e| {
        Error::input(format!(
            "{label}: contact group '{}': {e}; the contact group must be a surface group whose faces give the nodes' tributary areas",
            c.contact
        ))
    })?;
    for f in &faces {
        let xs: Vec<[f64; 3]> = f.nodes.iter().map(|&n| mesh.coords[n as usize]).collect();
        if let Some(why) = degeneracy(f.kind, &xs) {
            return Err(Error::input(format!(
                "{label}: contact group '{}' of {}: face element {} is degenerate: {why}; fix the mesh of that surface",
                c.contact,
                mesh.source_name(),
                f.surface_tag
            )));
        }
    }
    let areas = weights::tributary_areas(faces.iter().map(|f| {
        let xs: Vec<[f64; 3]> = f.nodes.iter().map(|&n| mesh.coords[n as usize]).collect();
        (f.kind, f.nodes.as_slice(), xs)
    }));
    Ok(ContactSide {
        nodes: areas.keys().copied().collect(),
        areas: areas.values().copied().collect(),
    })
}

/// The target group's nodes (ascending mesh indices) and faces in surface-local numbering.
fn target_faces(c: &Contact, mesh: &Mesh, label: &str) -> Result<(Vec<u32>, Vec<SurfaceFace>)> {
    let faces = group_faces(mesh, &c.target).map_err(|e| {
        Error::input(format!(
            "{label}: target group '{}': {e}; the target must be a surface group (triangles or quads on the boundary of the meshed volume)",
            c.target
        ))
    })?;
    let mut nodes: Vec<u32> = faces.iter().flat_map(|f| f.nodes.iter().copied()).collect();
    nodes.sort_unstable();
    nodes.dedup();
    let local: HashMap<u32, u32> = nodes
        .iter()
        .enumerate()
        .map(|(i, &n)| (n, i as u32))
        .collect();
    let faces = faces
        .iter()
        .map(|f| SurfaceFace {
            kind: f.kind,
            nodes: f.nodes.iter().map(|n| local[n]).collect(),
            tag: f.surface_tag,
        })
        .collect();
    Ok((nodes, faces))
}

/// The outcome of projecting one contact node.
#[derive(Clone, Copy, Debug)]
enum NodeProjection {
    /// An orthogonal projection inside a face, within the distance limit.
    Inside(Projection),
    /// The nearest point of the surface is on a face's border and the node is off it by more than
    /// the coincidence tolerance but at most the edge tolerance (second field, m): paired there.
    Edge(Projection, f64),
    /// The nearest surface point (within the search radius) is not inside a face, or too far.
    Outside(Projection),
    /// No surface point within the search radius.
    Far,
}

/// The acceptance limits of a projection.
struct Limits {
    /// Largest distance |x_c − t_v| (m).
    max_distance: f64,
    /// Tangential offset (m) up to which t_v counts as an orthogonal projection.
    coincident: f64,
    /// Scale of the edge tolerances (1 by default, 0 = no pairing on the border).
    edge_factor: f64,
}

/// Projects the contact nodes (in parallel) and classifies the results.
fn project_nodes(
    surface: &TargetSurface,
    mesh: &Mesh,
    nodes: &[u32],
    limits: &Limits,
) -> Vec<NodeProjection> {
    let points: Vec<[f64; 3]> = nodes.iter().map(|&n| mesh.coords[n as usize]).collect();
    surface
        .project_many(&points, limits.max_distance)
        .into_iter()
        .map(|p| match p {
            None => NodeProjection::Far,
            Some(p) if p.distance > limits.max_distance => NodeProjection::Outside(p),
            Some(p) if p.tangential_offset <= limits.coincident => NodeProjection::Inside(p),
            Some(p) if limits.edge_factor > 0.0 => {
                let tol = limits.edge_factor * surface.border_tolerance(p.face, p.uv);
                if p.tangential_offset <= tol {
                    NodeProjection::Edge(p, tol)
                } else {
                    NodeProjection::Outside(p)
                }
            }
            Some(p) => NodeProjection::Outside(p),
        })
        .collect()
}

impl NodeProjection {
    /// The projection of a paired node (inside a face or on its border).
    fn paired(&self) -> Option<&Projection> {
        match self {
            NodeProjection::Inside(p) | NodeProjection::Edge(p, _) => Some(p),
            _ => None,
        }
    }
}

/// The projections of the contact nodes for one candidate σ.
struct Trial {
    sigma: i32,
    surface: TargetSurface,
    projections: Vec<NodeProjection>,
    max_distance: f64,
}

impl Trial {
    /// Number of projected nodes and their mean distance.
    fn score(&self) -> (usize, f64) {
        let d: Vec<f64> = self
            .projections
            .iter()
            .filter_map(|p| p.paired().map(|p| p.distance))
            .collect();
        let mean = if d.is_empty() {
            f64::INFINITY
        } else {
            d.iter().sum::<f64>() / d.len() as f64
        };
        (d.len(), mean)
    }
}

/// The candidate σ under which most contact nodes project (ties: the smaller mean distance).
/// Error when no node projects under any candidate.
fn choose_placement(trials: &[Trial], c: &Contact, mesh: &Mesh, label: &str) -> Result<usize> {
    let mut best = 0;
    for (i, t) in trials.iter().enumerate().skip(1) {
        let (n, d) = t.score();
        let (nb, db) = trials[best].score();
        if n > nb || (n == nb && d < db) {
            best = i;
        }
    }
    if trials[best].score().0 > 0 {
        return Ok(best);
    }
    let detail: Vec<String> = trials
        .iter()
        .map(|t| {
            let nearest = t
                .projections
                .iter()
                .filter_map(|p| match p {
                    NodeProjection::Outside(p)
                    | NodeProjection::Inside(p)
                    | NodeProjection::Edge(p, _) => Some(p.distance),
                    NodeProjection::Far => None,
                })
                .fold(f64::INFINITY, f64::min);
            let nearest = if nearest.is_finite() {
                format!("nearest projection {nearest:.3e} m")
            } else {
                "no target face within the search radius".to_string()
            };
            format!("σ = {}: {nearest}", t.sigma)
        })
        .collect();
    Err(Error::input(format!(
        "{label}: the contact group '{}' and the target group '{}' of {} do not face each other: no contact node projects inside a target face within {:.3e} m ({} × the target's mean edge) under any sector rotation tried ({}). Check the group names, the [cyclic] axis, and the misalignment",
        c.contact,
        c.target,
        mesh.source_name(),
        trials[best].max_distance,
        MAX_DISTANCE,
        detail.join("; ")
    )))
}

/// What the pair construction needs of the placed target.
struct PairGeometry<'a> {
    mesh: &'a Mesh,
    surface: &'a TargetSurface,
    /// Mesh node index of each surface-local node.
    target_nodes: &'a [u32],
    coincident: f64,
}

/// Builds the pairs (SAMA weights or node-to-node matches), the preload shares and the sums.
fn fill_pairs(
    iface: &mut ContactInterface,
    c: &Contact,
    side: &ContactSide,
    projections: &[NodeProjection],
    geo: &PairGeometry,
    label: &str,
) -> Result<()> {
    let mesh = geo.mesh;
    let projected_area: f64 = side
        .areas
        .iter()
        .zip(projections)
        .filter(|(_, p)| p.paired().is_some())
        .map(|(a, _)| a)
        .sum();
    let matches = match c.model {
        ContactModel::NodeToNode => Some(coincident_targets(iface, side, projections, geo, label)?),
        ContactModel::Sama => None,
    };
    for (i, (&node, p)) in side.nodes.iter().zip(projections).enumerate() {
        let (p, edge) = match p {
            NodeProjection::Inside(p) => (p, None),
            NodeProjection::Edge(p, tol) => (
                p,
                Some(EdgeOffset {
                    tangential_offset: p.tangential_offset,
                    tolerance: *tol,
                }),
            ),
            NodeProjection::Outside(p) => {
                iface.unprojected.push(Unprojected {
                    node: mesh.node_tags[node as usize],
                    distance: Some(p.distance),
                    tangential_offset: Some(p.tangential_offset),
                });
                continue;
            }
            NodeProjection::Far => {
                iface.unprojected.push(Unprojected {
                    node: mesh.node_tags[node as usize],
                    distance: None,
                    tangential_offset: None,
                });
                continue;
            }
        };
        let face = &geo.surface.faces[p.face];
        let (locals, w): (Vec<u32>, Vec<f64>) = match &matches {
            Some(m) => (vec![m[i]], vec![1.0]),
            None => {
                let xs = geo.surface.face_points(p.face);
                let w = match c.coupling.unwrap_or_default() {
                    SamaCoupling::Array => {
                        weights::inverse_distance_weights(p.point, &p.frame, &xs, geo.coincident)
                    }
                    SamaCoupling::Interpolated => weights::interpolation_weights(
                        face.kind,
                        p.uv,
                        p.point,
                        &p.frame,
                        &xs,
                        geo.coincident,
                    ),
                };
                face.nodes
                    .iter()
                    .zip(w)
                    .filter(|(_, w)| *w != 0.0)
                    .map(|(&n, w)| (n, w))
                    .unzip()
            }
        };
        let target_indices: Vec<u32> = locals
            .iter()
            .map(|&l| geo.target_nodes[l as usize])
            .collect();
        let preload_share = side.areas[i] / projected_area;
        let n0_node = c.n0 * preload_share;
        iface.pairs.push(ContactPair {
            contact_node: mesh.node_tags[node as usize],
            contact_index: node,
            targets: target_indices
                .iter()
                .map(|&t| mesh.node_tags[t as usize])
                .collect(),
            target_indices,
            kt: w.iter().map(|w| w * c.kt).collect(),
            kn: w.iter().map(|w| w * c.kn).collect(),
            n0: w.iter().map(|w| w * n0_node).collect(),
            weights: w,
            frame: p.frame,
            face: face.tag,
            reference: p.uv,
            virtual_point: p.point,
            distance: p.distance,
            gap: p.gap,
            area: side.areas[i],
            n0_node,
            preload_share,
            edge,
        });
    }
    iface.sum_kt = iface.pairs.iter().flat_map(|p| &p.kt).sum();
    iface.sum_kn = iface.pairs.iter().flat_map(|p| &p.kn).sum();
    iface.sum_n0 = iface.pairs.iter().flat_map(|p| &p.n0).sum();
    Ok(())
}

/// Node-to-node model: for every projected contact node, the surface-local target node at the
/// same position (within the coincidence tolerance) after placement. Error listing the contact
/// nodes without one (including unprojected ones: a conforming interface has none).
fn coincident_targets(
    iface: &ContactInterface,
    side: &ContactSide,
    projections: &[NodeProjection],
    geo: &PairGeometry,
    label: &str,
) -> Result<Vec<u32>> {
    let tol = geo.coincident;
    let cell = |x: [f64; 3]| -> [i64; 3] { x.map(|c| (c / tol).floor() as i64) };
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::new();
    for (l, &x) in geo.surface.points.iter().enumerate() {
        grid.entry(cell(x)).or_default().push(l as u32);
    }
    let find = |x: [f64; 3]| -> Option<u32> {
        let k = cell(x);
        let mut best: Option<(f64, u32)> = None;
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    let Some(list) = grid.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) else {
                        continue;
                    };
                    for &l in list {
                        let d = norm(sub(geo.surface.points[l as usize], x));
                        if d <= tol && best.is_none_or(|(bd, _)| d < bd) {
                            best = Some((d, l));
                        }
                    }
                }
            }
        }
        best.map(|(_, l)| l)
    };
    let mut matched = vec![0u32; side.nodes.len()];
    let mut missing = Vec::new();
    for (i, (&node, p)) in side.nodes.iter().zip(projections).enumerate() {
        let x = geo.mesh.coords[node as usize];
        match (p, find(x)) {
            (NodeProjection::Inside(_) | NodeProjection::Edge(..), Some(l)) => matched[i] = l,
            _ => missing.push(node),
        }
    }
    if missing.is_empty() {
        return Ok(matched);
    }
    let listed: Vec<String> = missing
        .iter()
        .take(MAX_LISTED)
        .map(|&n| {
            let x = geo.mesh.coords[n as usize];
            format!(
                "{} at ({:.6e}, {:.6e}, {:.6e})",
                geo.mesh.node_tags[n as usize], x[0], x[1], x[2]
            )
        })
        .collect();
    Err(Error::input(format!(
        "{label}: model = \"node-to-node\" needs a target node at the position of every contact node (after the sector rotation σ = {} and the misalignment), within {:.3e} m; {} of {} contact nodes have none: {}{}. The meshes do not conform: use model = \"sama\"",
        iface.sigma,
        tol,
        missing.len(),
        side.nodes.len(),
        listed.join(", "),
        if missing.len() > MAX_LISTED { ", ..." } else { "" }
    )))
}
