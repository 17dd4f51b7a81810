//! Cyclic symmetry, geometry part: the sector rotation, the pairing of the low and high frontier
//! nodes, and the harmonic indices an engine-order excitation needs.
//!
//! Conventions (`docs/conventions.md` §2):
//!
//! * N identical sectors about an axis (a point `origin` on it, unit `axis` direction); the sector
//!   angle is α = 2π/N (rad) and `R_α` is the 3×3 rotation by +α about `axis` (right-hand rule).
//!   Positions rotate about the axis line through `origin`, vectors (displacements) about `axis`.
//! * The *low* frontier is the sector face at the smaller angle; every *high* frontier node is the
//!   image of one low node under `R_α`. Nodes are matched by position ([`match_frontiers`]) with the
//!   tolerance [`MATCH_TOLERANCE`] × model size ([`Mesh::size`]); an unmatched node is an error that
//!   names it.
//! * Harmonic index k ∈ {0..N-1}, inter-sector phase φ_k = 2πk/N ([`phase`]); on the frontier
//!   `u_high = e^{iφ_k} R_α u_low`. An engine-order m excitation puts temporal harmonic n on
//!   k_n = (n·m) mod N ([`harmonic_indices`]).
//!
//! * The cyclic transform ([`CyclicTransform`]) eliminates the high-frontier DOF:
//!   q = T_k q_k with q_k = {u_low, u_other}, M_k = T_kᴴ M T_k (Hermitian), likewise K_k, C_k.

use std::collections::HashMap;
use std::f64::consts::PI;

use faer::sparse::{SparseColMat, SparseColMatRef, Triplet};
use faer::{c64, Mat, MatRef};

use crate::case::Cyclic;
use crate::error::{Error, Result};
use crate::mesh::Mesh;
use crate::vec3::{dot, mat_vec, norm, rotate_about, sub};

/// Relative tolerance of the frontier matching: two positions coincide when they are closer than
/// `MATCH_TOLERANCE × mesh.size()` (the bounding-box diagonal, m). The same tolerance decides
/// whether a node lies on the symmetry axis.
pub const MATCH_TOLERANCE: f64 = 1e-6;

/// How many unmatched nodes an error message lists.
const MAX_LISTED: usize = 10;

/// The geometry of a cyclic-symmetric model (`docs/conventions.md` §2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CyclicGeometry {
    /// Number of sectors N ≥ 2.
    pub sectors: usize,
    /// A point on the symmetry axis (m).
    pub origin: [f64; 3],
    /// Unit direction of the axis; rotations are positive about it (right-hand rule).
    pub axis: [f64; 3],
    /// Sector angle α = 2π/N (rad).
    pub alpha: f64,
}

impl CyclicGeometry {
    /// Validates and builds the geometry: `sectors ≥ 2`, a finite origin and a finite, non-zero
    /// direction (normalised here).
    pub fn new(sectors: usize, origin: [f64; 3], direction: [f64; 3]) -> Result<Self> {
        if sectors < 2 {
            return Err(Error::input(format!(
                "[cyclic] sectors = {sectors}: a cyclic model needs at least 2 sectors; give the number of sectors of the full annulus (e.g. 24), or drop the [cyclic] table for a model without cyclic symmetry"
            )));
        }
        if sectors > i32::MAX as usize {
            return Err(Error::input(format!(
                "[cyclic] sectors = {sectors} is implausibly large; give the number of sectors of the full annulus"
            )));
        }
        if origin.iter().any(|c| !c.is_finite()) {
            return Err(Error::input(format!(
                "[cyclic] axis.origin = {origin:?} is not finite; give a point on the symmetry axis (m)"
            )));
        }
        let norm = norm(direction);
        if !norm.is_finite() || norm == 0.0 || direction.iter().any(|c| !c.is_finite()) {
            return Err(Error::input(format!(
                "[cyclic] axis.direction = {direction:?} must be a finite, non-zero vector (e.g. [0.0, 0.0, 1.0] for the z axis)"
            )));
        }
        Ok(CyclicGeometry {
            sectors,
            origin,
            axis: [
                direction[0] / norm,
                direction[1] / norm,
                direction[2] / norm,
            ],
            alpha: 2.0 * PI / sectors as f64,
        })
    }

    /// The geometry of the case's `[cyclic]` table.
    pub fn from_case(cyclic: &Cyclic) -> Result<Self> {
        Self::new(cyclic.sectors, cyclic.axis.origin, cyclic.axis.direction)
    }

    /// `R_α^σ`: the rotation by σ·α about the axis (Rodrigues' formula), row-major; σ may be
    /// negative. σ is reduced modulo N first, so `rotation(N)` is exactly the identity.
    pub fn rotation(&self, sigma: i32) -> [[f64; 3]; 3] {
        let n = self.sectors as i64;
        let mut s = (sigma as i64).rem_euclid(n);
        if 2 * s > n {
            s -= n; // smallest angle: |θ| ≤ π, for accuracy
        }
        let theta = 2.0 * PI * s as f64 / n as f64;
        let (sin, cos) = if s == 0 { (0.0, 1.0) } else { theta.sin_cos() };
        let a = self.axis;
        let c1 = 1.0 - cos;
        // R = cos θ I + sin θ [a]× + (1 − cos θ) a aᵀ
        [
            [
                cos + c1 * a[0] * a[0],
                c1 * a[0] * a[1] - sin * a[2],
                c1 * a[0] * a[2] + sin * a[1],
            ],
            [
                c1 * a[1] * a[0] + sin * a[2],
                cos + c1 * a[1] * a[1],
                c1 * a[1] * a[2] - sin * a[0],
            ],
            [
                c1 * a[2] * a[0] - sin * a[1],
                c1 * a[2] * a[1] + sin * a[0],
                cos + c1 * a[2] * a[2],
            ],
        ]
    }

    /// The vector `v` rotated by σ·α about the axis direction (for displacements, forces).
    pub fn rotate_vector(&self, v: [f64; 3], sigma: i32) -> [f64; 3] {
        mat_vec(&self.rotation(sigma), v)
    }

    /// The point `p` (m) rotated by σ·α about the axis line through `origin`.
    pub fn rotate_point(&self, p: [f64; 3], sigma: i32) -> [f64; 3] {
        rotate_about(&self.rotation(sigma), self.origin, p)
    }

    /// Distance (m) of the point `p` to the axis line.
    pub fn distance_to_axis(&self, p: [f64; 3]) -> f64 {
        let v = sub(p, self.origin);
        let t = dot(v, self.axis);
        norm([
            v[0] - t * self.axis[0],
            v[1] - t * self.axis[1],
            v[2] - t * self.axis[2],
        ])
    }
}

/// The node pairing of the two frontiers (`docs/conventions.md` §2).
///
/// `high[i]` is the image of `low[i]` under `R_α`: `R_α X_low[i] = X_high[i]` within the matching
/// tolerance. Pairs are in ascending `low` order; all entries are compact node indices.
///
/// Nodes on the axis (closer to it than the tolerance) map to themselves and belong to both
/// frontiers; they are not part of the pairs but listed in `axis_nodes`. Later stages must not
/// eliminate them as high nodes: the cyclic constraint reads `u = e^{iφ_k} R_α u` for them, and
/// R_α has the eigenvalues 1 (axial direction) and e^{±iα} (the two circular in-plane
/// directions). So for k = 0 only the axial component survives, for k = 1 and k = N−1 only one
/// circularly polarised in-plane component each (both in-plane components when N = 2), and for
/// every other k the node is fixed. The transform stage applies this constraint explicitly
/// ([`DofPair::on_axis`], [`axis_basis`], [`CyclicTransform`]).
#[derive(Clone, Debug, PartialEq, Eq, Default)]
pub struct FrontierPairs {
    /// Low-frontier node indices, ascending.
    pub low: Vec<u32>,
    /// High-frontier node indices: `high[i]` is the image of `low[i]`.
    pub high: Vec<u32>,
    /// Nodes of either frontier that lie on the axis (ascending), excluded from the pairs.
    pub axis_nodes: Vec<u32>,
}

impl FrontierPairs {
    /// Number of pairs.
    pub fn len(&self) -> usize {
        self.low.len()
    }

    /// Whether there is no pair.
    pub fn is_empty(&self) -> bool {
        self.low.is_empty()
    }
}

/// Pairs the nodes of the groups `low` and `high`: for every high node, the low node q with
/// `R_α X_q = X_high` within `MATCH_TOLERANCE × mesh.size()` (see [`FrontierPairs`]).
///
/// Uses a spatial hash of the rotated low nodes (cell = the tolerance; each query looks at the
/// 27 neighbouring cells), so it is linear in the number of nodes for a mesh without clusters of
/// coincident nodes. Gmsh's `$Periodic` section is not used (it lists only corner nodes).
///
/// Errors (all [`Error::Input`], naming the file and the groups): a missing or empty group; nodes
/// shared by the two groups other than axis nodes; high nodes without a low preimage or low nodes
/// without a high image (the message lists up to 10 node tags with their coordinates, the count,
/// the tolerance, and what to check); groups with different node counts.
pub fn match_frontiers(
    mesh: &Mesh,
    geom: &CyclicGeometry,
    low: &str,
    high: &str,
) -> Result<FrontierPairs> {
    let low_nodes = mesh.nodes_of(low)?;
    let high_nodes = mesh.nodes_of(high)?;
    let size = mesh.size();
    let tol = MATCH_TOLERANCE * size;
    if !(tol > 0.0 && tol.is_finite()) {
        return Err(Error::input(format!(
            "{}: the model size (bounding-box diagonal) is {size} m, so frontier nodes cannot be matched; check the mesh coordinates",
            mesh.source_name()
        )));
    }

    let on_axis = |n: u32| geom.distance_to_axis(mesh.coords[n as usize]) < tol;
    let mut axis_nodes: Vec<u32> = low_nodes
        .iter()
        .chain(high_nodes.iter())
        .copied()
        .filter(|&n| on_axis(n))
        .collect();
    axis_nodes.sort_unstable();
    axis_nodes.dedup();
    let low_off: Vec<u32> = low_nodes.iter().copied().filter(|&n| !on_axis(n)).collect();
    let high_off: Vec<u32> = high_nodes
        .iter()
        .copied()
        .filter(|&n| !on_axis(n))
        .collect();

    let shared = intersect_sorted(&low_off, &high_off);
    if !shared.is_empty() {
        return Err(Error::input(format!(
            "{}: the cyclic frontiers '{low}' and '{high}' share {} node(s) off the axis: {}. \
             The low and high frontiers must be the two opposite faces of the sector (only nodes on the symmetry axis may belong to both); check `[cyclic] low`/`high` and the physical groups",
            mesh.source_name(),
            shared.len(),
            list_nodes(mesh, &shared)
        )));
    }

    let m = pair_nodes(mesh, geom, 1, &low_off, &high_off, tol);
    if m.unmatched_high.is_empty() && m.unmatched_low.is_empty() {
        if low_nodes.len() != high_nodes.len() {
            // Only possible with axis nodes in one group but not the other.
            return Err(Error::input(format!(
                "{}: the cyclic frontiers '{low}' ({} nodes) and '{high}' ({} nodes) have different node counts although all off-axis nodes pair up: a node on the axis belongs to one frontier only ({} axis node(s): {}); mesh the frontiers periodically so that they share their axis nodes",
                mesh.source_name(),
                low_nodes.len(),
                high_nodes.len(),
                axis_nodes.len(),
                list_nodes(mesh, &axis_nodes)
            )));
        }
        return Ok(FrontierPairs {
            low: m.low,
            high: m.high,
            axis_nodes,
        });
    }

    let mut msg = format!(
        "{}: the cyclic frontiers '{low}' ({} nodes) and '{high}' ({} nodes) do not match under the sector rotation R_α (N = {}, α = {:.6}°, axis through {:?} along {:?}); matching tolerance {:.3e} m ({MATCH_TOLERANCE:e} × model size {:.6e} m).",
        mesh.source_name(),
        low_nodes.len(),
        high_nodes.len(),
        geom.sectors,
        geom.alpha.to_degrees(),
        geom.origin,
        geom.axis,
        tol,
        size
    );
    if low_nodes.len() != high_nodes.len() {
        msg.push_str(" The two groups have different node counts.");
    }
    if !m.unmatched_high.is_empty() {
        msg.push_str(&format!(
            " {} node(s) of '{high}' are not the image R_α X of any node of '{low}': {}.",
            m.unmatched_high.len(),
            list_nodes(mesh, &m.unmatched_high)
        ));
    }
    if !m.unmatched_low.is_empty() {
        msg.push_str(&format!(
            " {} node(s) of '{low}' have no image R_α X on '{high}': {}.",
            m.unmatched_low.len(),
            list_nodes(mesh, &m.unmatched_low)
        ));
    }
    let swapped = pair_nodes(mesh, geom, -1, &low_off, &high_off, tol);
    if swapped.unmatched_high.is_empty() && swapped.unmatched_low.is_empty() {
        msg.push_str(&format!(
            " The groups do match under R_α⁻¹: '{high}' is the face at the smaller angle, so swap `[cyclic] low` and `high` (or reverse `[cyclic] axis.direction`)."
        ));
    } else {
        msg.push_str(
            " Check `[cyclic] sectors` (α = 2π/N), `[cyclic] axis` (origin and direction; the rotation is +α about the direction, right-hand rule, from the low to the high frontier), that `low`/`high` name the two opposite sector faces, and that the mesh was meshed periodically (Gmsh `setPeriodic(2, [high], [low], R_α)`) so that every high node, mid-edge nodes included, is the rotation of a low node.",
        );
    }
    Err(Error::input(msg))
}

/// Result of one matching pass.
struct Matching {
    low: Vec<u32>,
    high: Vec<u32>,
    unmatched_low: Vec<u32>,
    unmatched_high: Vec<u32>,
}

/// Matches `R_α^σ X_low` to `X_high` with a spatial hash of cell size `tol`.
fn pair_nodes(
    mesh: &Mesh,
    geom: &CyclicGeometry,
    sigma: i32,
    low: &[u32],
    high: &[u32],
    tol: f64,
) -> Matching {
    let r = geom.rotation(sigma);
    let cell = |p: [f64; 3]| -> [i64; 3] {
        // `as` saturates (NaN → 0): no panic on odd coordinates, they just do not match.
        [
            (p[0] / tol).floor() as i64,
            (p[1] / tol).floor() as i64,
            (p[2] / tol).floor() as i64,
        ]
    };
    let images: Vec<[f64; 3]> = low
        .iter()
        .map(|&q| rotate_about(&r, geom.origin, mesh.coords[q as usize]))
        .collect();
    let mut grid: HashMap<[i64; 3], Vec<u32>> = HashMap::with_capacity(low.len());
    for (i, &p) in images.iter().enumerate() {
        grid.entry(cell(p)).or_default().push(i as u32);
    }

    let mut low_used = vec![false; low.len()];
    let mut pairs: Vec<(u32, u32)> = Vec::with_capacity(high.len());
    let mut unmatched_high = Vec::new();
    for &h in high {
        let x = mesh.coords[h as usize];
        let c = cell(x);
        let mut best: Option<(f64, usize)> = None;
        for dx in -1..=1i64 {
            for dy in -1..=1i64 {
                for dz in -1..=1i64 {
                    let key = [
                        c[0].saturating_add(dx),
                        c[1].saturating_add(dy),
                        c[2].saturating_add(dz),
                    ];
                    for &i in grid.get(&key).map(Vec::as_slice).unwrap_or(&[]) {
                        let d = norm(sub(images[i as usize], x));
                        if d < tol && best.is_none_or(|(bd, _)| d < bd) {
                            best = Some((d, i as usize));
                        }
                    }
                }
            }
        }
        match best {
            Some((_, i)) if !low_used[i] => {
                low_used[i] = true;
                pairs.push((low[i], h));
            }
            // No preimage, or a preimage already taken by a coincident high node.
            _ => unmatched_high.push(h),
        }
    }
    pairs.sort_unstable();
    let unmatched_low = low
        .iter()
        .zip(&low_used)
        .filter_map(|(&q, &used)| (!used).then_some(q))
        .collect();
    Matching {
        low: pairs.iter().map(|p| p.0).collect(),
        high: pairs.iter().map(|p| p.1).collect(),
        unmatched_low,
        unmatched_high,
    }
}

/// Checks the clamps against the frontier pairing: a pair whose low node is clamped but whose high
/// node is not (or the reverse) is an error naming the frontier and clamp groups, since the cyclic
/// constraint `u_high = e^{iφ_k} R_α u_low` would tie a fixed node to a free one.
///
/// A pair with both nodes clamped is consistent (the usual case: a clamped hub meets both
/// frontiers along its edges) and is returned, as indices into `pairs.low`/`pairs.high`, so that
/// later stages drop it from the frontier masters; clamped axis nodes need nothing.
pub fn check_frontier_clamps(
    mesh: &Mesh,
    pairs: &FrontierPairs,
    low: &str,
    high: &str,
    clamps: &[String],
) -> Result<Vec<usize>> {
    // For every node, the first clamp group that fixes it.
    let mut clamped_by: Vec<Option<usize>> = vec![None; mesh.num_nodes()];
    for (g, name) in clamps.iter().enumerate() {
        for n in mesh.nodes_of(name)? {
            clamped_by[n as usize].get_or_insert(g);
        }
    }
    let mut both = Vec::new();
    let mut bad: Vec<(u32, &str, usize)> = Vec::new(); // (clamped node, its frontier, clamp group)
    for (i, (&l, &h)) in pairs.low.iter().zip(&pairs.high).enumerate() {
        match (clamped_by[l as usize], clamped_by[h as usize]) {
            (Some(_), Some(_)) => both.push(i),
            (Some(g), None) => bad.push((l, low, g)),
            (None, Some(g)) => bad.push((h, high, g)),
            (None, None) => {}
        }
    }
    if let Some(&(_, frontier, g)) = bad.first() {
        let listed: Vec<String> = bad
            .iter()
            .take(MAX_LISTED)
            .map(|&(n, f, g)| {
                let p = mesh.coords[n as usize];
                format!(
                    "node {} ({:.9e}, {:.9e}, {:.9e}) of '{f}' clamped by '{}'",
                    mesh.node_tags[n as usize], p[0], p[1], p[2], clamps[g]
                )
            })
            .collect();
        return Err(Error::input(format!(
            "{}: the cyclic frontier '{frontier}' touches the clamp group '{}': {} frontier node(s) are clamped while their cyclic partner on the other frontier is free ({}{}). \
             A clamp that meets the frontiers must fix the same nodes on '{low}' and '{high}' (cyclically symmetric); correct `[model] clamp` or the physical groups",
            mesh.source_name(),
            clamps[g],
            bad.len(),
            listed.join("; "),
            if bad.len() > MAX_LISTED { "; ..." } else { "" }
        )));
    }
    Ok(both)
}

/// Harmonic index of each temporal harmonic n = 0..=H under engine order m:
/// k_n = (n·m) mod N (`docs/conventions.md` §2). Entry n is k_n; n = 0 always gives k = 0.
pub fn harmonic_indices(sectors: usize, engine_order: usize, harmonics: usize) -> Vec<usize> {
    if sectors == 0 {
        return vec![0; harmonics + 1];
    }
    let m = engine_order % sectors;
    (0..=harmonics)
        .map(|n| (n % sectors) * m % sectors)
        .collect()
}

/// The distinct harmonic indices of [`harmonic_indices`], ascending: one ROM is built for each.
pub fn distinct_harmonic_indices(
    sectors: usize,
    engine_order: usize,
    harmonics: usize,
) -> Vec<usize> {
    let mut k = harmonic_indices(sectors, engine_order, harmonics);
    k.sort_unstable();
    k.dedup();
    k
}

/// Inter-sector phase φ_k = 2πk/N (rad).
pub fn phase(k: usize, sectors: usize) -> f64 {
    2.0 * PI * k as f64 / sectors as f64
}

/// Error unless 0 ≤ k < N.
pub fn check_harmonic_index(k: usize, sectors: usize) -> Result<()> {
    if k < sectors {
        Ok(())
    } else {
        Err(Error::input(format!(
            "harmonic index k = {k} is out of range for N = {sectors} sectors: k must be in 0..={} (conventions §2; k and N − k are the two travelling-wave directions of the same nodal diameter)",
            sectors.saturating_sub(1)
        )))
    }
}

/// e^{iφ_k}, φ_k = 2πk/N: exactly 1 for k = 0 and exactly −1 for k = N/2 (so that those
/// transforms are real to the bit).
pub fn phase_factor(k: usize, sectors: usize) -> c64 {
    if k == 0 {
        c64::new(1.0, 0.0)
    } else if 2 * k == sectors {
        c64::new(-1.0, 0.0)
    } else {
        let (s, c) = phase(k, sectors).sin_cos();
        c64::new(c, s)
    }
}

/// Whether harmonic index k gives real matrices (k = 0, or k = N/2 for even N).
pub fn is_real_harmonic(k: usize, sectors: usize) -> bool {
    k == 0 || 2 * k == sectors
}

/// A cyclic frontier pair expressed in rows of the matrices the transform acts on: the x, y, z
/// rows of a low-frontier node and of its image on the high frontier. A node on the symmetry
/// axis (its own image, see [`FrontierPairs`]) is the pair with `low == high`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DofPair {
    /// Rows of u_low (components x, y, z).
    pub low: [usize; 3],
    /// Rows of u_high (components x, y, z); equal to `low` for a node on the axis.
    pub high: [usize; 3],
}

impl DofPair {
    /// The pair of a node on the axis (rows x, y, z): its own image.
    pub fn on_axis(rows: [usize; 3]) -> Self {
        DofPair {
            low: rows,
            high: rows,
        }
    }

    /// Whether this is a node on the axis (`low == high`).
    pub fn is_axis(&self) -> bool {
        self.low == self.high
    }
}

/// Basis (orthonormal, global x, y, z components) of the displacements u of a node on the axis
/// that satisfy the cyclic constraint `u = e^{iφ_k} R_α u` of harmonic index k: the eigenvectors
/// of R_α for the eigenvalue e^{−iφ_k}. With the axis a and the in-plane pair e₁ ⟂ a,
/// e₂ = a × e₁ (R_α e₁ = cos α e₁ + sin α e₂): k = 0 → {a}; N = 2, k = 1 → {e₁, e₂} (R_α = −1 in
/// the plane); k = 1 → {(e₁ + i e₂)/√2} (R_α v = e^{−iα} v); k = N − 1 → {(e₁ − i e₂)/√2};
/// any other k → {} (the node does not move).
pub fn axis_basis(geom: &CyclicGeometry, k: usize) -> Vec<[c64; 3]> {
    let a = geom.axis;
    let real = |v: [f64; 3]| v.map(|x| c64::new(x, 0.0));
    // e₁: the coordinate direction least aligned with the axis, made orthogonal to it.
    let c = (0..3)
        .min_by(|&i, &j| a[i].abs().total_cmp(&a[j].abs()))
        .unwrap_or(0);
    let mut e1 = [0.0; 3];
    e1[c] = 1.0;
    let e1 = {
        let v = [
            e1[0] - a[c] * a[0],
            e1[1] - a[c] * a[1],
            e1[2] - a[c] * a[2],
        ];
        let n = norm(v);
        [v[0] / n, v[1] / n, v[2] / n]
    };
    let e2 = [
        a[1] * e1[2] - a[2] * e1[1],
        a[2] * e1[0] - a[0] * e1[2],
        a[0] * e1[1] - a[1] * e1[0],
    ];
    let n = geom.sectors;
    let circular = |sign: f64| -> [c64; 3] {
        let h = std::f64::consts::FRAC_1_SQRT_2;
        [0, 1, 2].map(|i| c64::new(h * e1[i], sign * h * e2[i]))
    };
    if k == 0 {
        vec![real(a)]
    } else if n == 2 && k == 1 {
        vec![real(e1), real(e2)]
    } else if k == 1 {
        vec![circular(1.0)]
    } else if k == n - 1 {
        vec![circular(-1.0)]
    } else {
        Vec::new()
    }
}

/// The cyclic transform of harmonic index k (`docs/conventions.md` §2): q = T_k q_k, where q holds
/// all `n_full` rows of a sector model and q_k all rows except the high-frontier ones (same order),
/// and every high row is `u_high = e^{iφ_k} R_α u_low`:
/// `T_k[high_c, low_d] = e^{iφ_k} R_α[c][d]`, identity on the kept rows.
///
/// A node on the axis (a pair with `low == high`) keeps, instead of its 3 rows, the amplitudes
/// of the [`axis_basis`] vectors b_j (0, 1 or 2 coordinates): `T_k[row_c, j] = b_j[c]`. Each
/// such coordinate takes the place (in `kept`) of the node's row of the largest |b_j\[c\]|, so
/// that its label is that component.
#[derive(Clone, Debug, PartialEq)]
pub struct CyclicTransform {
    /// Harmonic index k.
    pub harmonic_index: usize,
    /// Number of sectors N.
    pub sectors: usize,
    /// Whether T_k is real (k = 0 or N/2): the imaginary parts are then exactly zero.
    pub real: bool,
    /// Full row of each reduced coordinate (every row that is not a high-frontier row, or the
    /// label row of an axis coordinate), ascending.
    pub kept: Vec<usize>,
    /// Per full row, the nonzero entries (reduced column, value) of T_k.
    rows: Vec<Vec<(usize, c64)>>,
}

impl CyclicTransform {
    /// Builds T_k for a model of `n_full` rows with the frontier `pairs`.
    ///
    /// Errors ([`Error::Input`]): k ≥ N, a row out of range, or a row used twice (a high row that
    /// is also a low row or listed in two pairs).
    pub fn new(geom: &CyclicGeometry, k: usize, n_full: usize, pairs: &[DofPair]) -> Result<Self> {
        check_harmonic_index(k, geom.sectors)?;
        let mut is_high = vec![false; n_full];
        let mut is_low = vec![false; n_full];
        for p in pairs {
            for &r in p.low.iter().chain(&p.high) {
                if r >= n_full {
                    return Err(Error::input(format!(
                        "cyclic transform: row {r} of a frontier pair is out of range (the model has {n_full} rows)"
                    )));
                }
            }
            for &r in &p.high {
                if is_high[r] || is_low[r] {
                    return Err(Error::input(format!(
                        "cyclic transform: row {r} appears in two frontier pairs; every high-frontier DOF must be the image of exactly one low-frontier DOF"
                    )));
                }
                is_high[r] = true;
            }
            for &r in &p.low {
                if is_high[r] && !p.is_axis() {
                    return Err(Error::input(format!(
                        "cyclic transform: row {r} is both a low- and a high-frontier DOF"
                    )));
                }
                is_low[r] = true;
            }
        }
        // Axis nodes: their rows are "high" (replaced); their coordinates take label rows.
        let basis = axis_basis(geom, k);
        let mut label: Vec<Option<[c64; 3]>> = vec![None; n_full];
        for p in pairs.iter().filter(|p| p.is_axis()) {
            let mut taken = [false; 3];
            for b in &basis {
                let c = (0..3)
                    .filter(|&c| !taken[c])
                    .max_by(|&i, &j| b[i].norm().total_cmp(&b[j].norm()))
                    .unwrap_or(0);
                taken[c] = true;
                label[p.low[c]] = Some(*b);
            }
        }
        let kept: Vec<usize> = (0..n_full)
            .filter(|&r| !is_high[r] || label[r].is_some())
            .collect();
        let mut column = vec![usize::MAX; n_full];
        for (j, &r) in kept.iter().enumerate() {
            column[r] = j;
        }
        let mut rows: Vec<Vec<(usize, c64)>> = vec![Vec::new(); n_full];
        for &r in kept.iter().filter(|&&r| !is_high[r]) {
            rows[r].push((column[r], c64::new(1.0, 0.0)));
        }
        let e = phase_factor(k, geom.sectors);
        let rot = geom.rotation(1);
        for p in pairs {
            if p.is_axis() {
                for &l in &p.low {
                    if let Some(b) = label[l] {
                        for c in 0..3 {
                            if b[c] != c64::new(0.0, 0.0) {
                                rows[p.low[c]].push((column[l], b[c]));
                            }
                        }
                    }
                }
                continue;
            }
            for c in 0..3 {
                rows[p.high[c]] = (0..3)
                    .filter(|&d| rot[c][d] != 0.0)
                    .map(|d| (column[p.low[d]], e * rot[c][d]))
                    .collect();
            }
        }
        Ok(CyclicTransform {
            harmonic_index: k,
            sectors: geom.sectors,
            real: is_real_harmonic(k, geom.sectors),
            kept,
            rows,
        })
    }

    /// Number of rows of the full sector model.
    pub fn n_full(&self) -> usize {
        self.rows.len()
    }

    /// Number of reduced coordinates (rows of q_k).
    pub fn n_reduced(&self) -> usize {
        self.kept.len()
    }

    /// The nonzero entries (reduced column j, value T_k[r, j]) of row `r` of T_k: q\[r\] =
    /// Σ value · q_k\[j\] (one unit entry for a kept row, e^{iφ_k} R_α\[c\]\[d\] for a high row).
    pub fn row(&self, r: usize) -> &[(usize, c64)] {
        &self.rows[r]
    }

    /// T_kᴴ A T_k for a dense real symmetric `a` (n_full²): Hermitian, n_reduced².
    pub fn project(&self, a: MatRef<'_, f64>) -> Mat<c64> {
        let (n, m) = (self.n_full(), self.n_reduced());
        // B = A T (n × m)
        let mut b = Mat::<c64>::zeros(n, m);
        for (r, entries) in self.rows.iter().enumerate() {
            for &(j, t) in entries {
                let mut bj = b.col_mut(j);
                let ar = a.col(r);
                for i in 0..n {
                    bj[i] += t * ar[i];
                }
            }
        }
        // C = Tᴴ B (m × m)
        let mut out = Mat::<c64>::zeros(m, m);
        for col in 0..m {
            let bc = b.col(col);
            let mut oc = out.col_mut(col);
            for (r, entries) in self.rows.iter().enumerate() {
                for &(j, t) in entries {
                    oc[j] += t.conj() * bc[r];
                }
            }
        }
        out
    }

    /// q = T_k q_k: the full sector field from the reduced coordinates.
    pub fn expand(&self, q_k: &[c64]) -> Vec<c64> {
        self.rows
            .iter()
            .map(|entries| entries.iter().map(|&(j, t)| t * q_k[j]).sum())
            .collect()
    }

    /// T_kᴴ A T_k for a sparse real symmetric `a` (n_full², e.g. the whole sector's K or M) in
    /// the real embedding used by the real sparse eigensolver: for a real transform (k = 0, N/2)
    /// T_kᵀ A T_k itself (n_reduced²); otherwise, with T_kᴴ A T_k = X + iY,
    /// `[[X, −Y], [Y, X]]` (2 n_reduced², symmetric; the complex vector a + ib maps to [a; b],
    /// so every eigenvalue of the Hermitian pencil appears twice). Rows sorted.
    pub fn project_sparse_embedded(
        &self,
        a: SparseColMatRef<'_, usize, f64>,
    ) -> Result<SparseColMat<usize, f64>> {
        let m = self.n_reduced();
        let mut trip: Vec<Triplet<usize, usize, f64>> = Vec::new();
        for c in 0..a.ncols() {
            for (r, &v) in a.row_idx_of_col(c).zip(a.val_of_col(c)) {
                for &(jr, tr) in &self.rows[r] {
                    for &(jc, tc) in &self.rows[c] {
                        let h = tr.conj() * tc * v;
                        trip.push(Triplet::new(jr, jc, h.re));
                        if !self.real {
                            trip.push(Triplet::new(m + jr, m + jc, h.re));
                            if h.im != 0.0 {
                                trip.push(Triplet::new(jr, m + jc, -h.im));
                                trip.push(Triplet::new(m + jr, jc, h.im));
                            }
                        }
                    }
                }
            }
        }
        let size = if self.real { m } else { 2 * m };
        SparseColMat::try_new_from_triplets(size, size, &trip).map_err(|e| {
            Error::Compute(format!(
                "cyclic transform: assembling the projected sparse matrix failed ({e:?})"
            ))
        })
    }
}

/// Up to [`MAX_LISTED`] nodes as `tag (x, y, z)`, then `...` when there are more.
fn list_nodes(mesh: &Mesh, nodes: &[u32]) -> String {
    let mut parts: Vec<String> = nodes
        .iter()
        .take(MAX_LISTED)
        .map(|&n| {
            let p = mesh.coords[n as usize];
            format!(
                "node {} ({:.9e}, {:.9e}, {:.9e})",
                mesh.node_tags[n as usize], p[0], p[1], p[2]
            )
        })
        .collect();
    if nodes.len() > MAX_LISTED {
        parts.push(format!("... ({} more)", nodes.len() - MAX_LISTED));
    }
    parts.join(", ")
}

/// Elements common to two ascending slices.
fn intersect_sorted(a: &[u32], b: &[u32]) -> Vec<u32> {
    let (mut i, mut j, mut out) = (0, 0, Vec::new());
    while i < a.len() && j < b.len() {
        match a[i].cmp(&b[j]) {
            std::cmp::Ordering::Less => i += 1,
            std::cmp::Ordering::Greater => j += 1,
            std::cmp::Ordering::Equal => {
                out.push(a[i]);
                i += 1;
                j += 1;
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn z_geom(n: usize) -> CyclicGeometry {
        CyclicGeometry::new(n, [0.0; 3], [0.0, 0.0, 2.0]).unwrap()
    }

    #[test]
    fn validation() {
        assert!(CyclicGeometry::new(1, [0.0; 3], [0.0, 0.0, 1.0]).is_err());
        assert!(CyclicGeometry::new(4, [0.0; 3], [0.0; 3]).is_err());
        assert!(CyclicGeometry::new(4, [0.0; 3], [f64::NAN, 0.0, 1.0]).is_err());
        assert!(CyclicGeometry::new(4, [f64::INFINITY, 0.0, 0.0], [0.0, 0.0, 1.0]).is_err());
        let g = z_geom(4);
        assert_eq!(g.axis, [0.0, 0.0, 1.0]);
        assert!((g.alpha - PI / 2.0).abs() < 1e-15);
    }

    #[test]
    fn quarter_turn_about_z() {
        let g = z_geom(4);
        let p = g.rotate_point([1.0, 0.0, 0.5], 1);
        assert!(norm(sub(p, [0.0, 1.0, 0.5])) < 1e-15, "{p:?}");
        let p = g.rotate_point([1.0, 0.0, 0.5], -1);
        assert!(norm(sub(p, [0.0, -1.0, 0.5])) < 1e-15, "{p:?}");
        assert_eq!(g.rotation(4), g.rotation(0));
        assert_eq!(
            g.rotation(0),
            [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]]
        );
    }

    #[test]
    fn harmonic_index_helpers() {
        assert_eq!(harmonic_indices(8, 3, 4), vec![0, 3, 6, 1, 4]);
        assert_eq!(distinct_harmonic_indices(8, 3, 4), vec![0, 1, 3, 4, 6]);
        assert!(check_harmonic_index(7, 8).is_ok());
        assert!(check_harmonic_index(8, 8).is_err());
        assert!((phase(2, 8) - PI / 2.0).abs() < 1e-15);
    }

    #[test]
    fn intersection() {
        assert_eq!(intersect_sorted(&[1, 3, 5, 7], &[2, 3, 7, 9]), vec![3, 7]);
        assert!(intersect_sorted(&[], &[1]).is_empty());
    }
}
