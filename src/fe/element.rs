//! Element matrices of 3-D isoparametric elements: stiffness Kₑ = ∫ Bᵀ D B dV and consistent mass
//! Mₑ = ∫ ρ Nᵀ N dV, by quadrature on the reference element.
//!
//! The geometry is interpolated from all nodes (x = Σ Nₐ(ξ) xₐ, so Gmsh's curved second-order
//! elements are curved here too). At each quadrature point the Jacobian J = ∂x/∂ξ gives the physical
//! gradients ∇Nₐ = J⁻ᵀ ∂Nₐ/∂ξ and dV = det J dξ; det J ≤ 0 means an inverted or degenerate element.
//!
//! DOF order inside an element: 3 per node, node-major (x, y, z of node 0, then node 1, ...).
//! For an isotropic material the 3×3 block of nodes a, b is (with gₐ = ∇Nₐ, Lamé λ, μ)
//! K_ab = ∫ (λ gₐ g_bᵀ + μ g_b gₐᵀ + μ (gₐ·g_b) I) dV, which is Bᵀ D B written out; units N/m. The
//! mass block is M_ab = ∫ ρ Nₐ N_b dV · I (kg).

use faer::Mat;

use super::material::Material;
use super::quadrature::{self, Rule};
use super::shape;
use crate::error::{Error, Result};
use crate::mesh::ElementType;

/// Default quadrature degrees (stiffness, mass) for `kind` — exact for both matrices on
/// straight-sided (affine) tetrahedra and prisms and on parallelepiped hexahedra; `None` for
/// unsupported types. See the table in [`crate::fe`].
pub fn default_degrees(kind: ElementType) -> Option<(u32, u32)> {
    use ElementType::*;
    Some(match kind {
        Tetra4 => (1, 2),
        Tetra10 => (5, 5),
        Hexa8 | Prism6 | Pyramid5 => (2, 2),
        Hexa20 | Hexa27 | Prism15 | Prism18 | Pyramid13 => (4, 4),
        _ => return None,
    })
}

/// The shape functions of one element type tabulated at the points of one rule.
#[derive(Clone, Debug)]
pub(crate) struct Tabulated {
    /// Nodes per element.
    pub nn: usize,
    /// Reference points.
    pub points: Vec<[f64; 3]>,
    /// Weights, one per point.
    pub weights: Vec<f64>,
    /// Nₐ at point q: `n[q * nn + a]`.
    pub n: Vec<f64>,
    /// ∂Nₐ/∂ξ at point q: `dn[q * nn + a]`.
    pub dn: Vec<[f64; 3]>,
}

impl Tabulated {
    /// Tabulates `kind` at the points of `rule` (`None` for unsupported types).
    pub fn new(kind: ElementType, rule: &Rule) -> Option<Tabulated> {
        let nn = kind.num_nodes();
        let mut n = Vec::with_capacity(rule.len() * nn);
        let mut dn = Vec::with_capacity(rule.len() * nn);
        for &p in &rule.points {
            let s = shape::shape(kind, p)?;
            n.extend_from_slice(&s.n);
            dn.extend_from_slice(&s.dn);
        }
        Some(Tabulated {
            nn,
            points: rule.points.clone(),
            weights: rule.weights.clone(),
            n,
            dn,
        })
    }

    /// Tabulates `kind` at the rule of `degree` (or the default for the type).
    pub fn for_degree(kind: ElementType, degree: u32) -> Result<Tabulated> {
        let rule = quadrature::rule(kind, degree)?;
        Tabulated::new(kind, &rule).ok_or_else(|| unsupported(kind))
    }

    /// Number of quadrature points.
    pub fn nq(&self) -> usize {
        self.weights.len()
    }
}

/// A non-positive Jacobian determinant found at a quadrature point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct BadJacobian {
    /// The reference point.
    pub point: [f64; 3],
    /// det J there (NaN for non-finite coordinates).
    pub det: f64,
}

impl BadJacobian {
    /// A description for messages.
    pub fn describe(&self) -> String {
        format!(
            "det J = {:.3e} at reference point ({:.4}, {:.4}, {:.4})",
            self.det, self.point[0], self.point[1], self.point[2]
        )
    }
}

/// J[i][k] = ∂xᵢ/∂ξₖ = Σₐ xₐ[i] ∂Nₐ/∂ξₖ.
fn jacobian(xs: &[[f64; 3]], dn: &[[f64; 3]]) -> [[f64; 3]; 3] {
    let mut j = [[0.0; 3]; 3];
    for (x, d) in xs.iter().zip(dn) {
        for (ji, xi) in j.iter_mut().zip(x) {
            for k in 0..3 {
                ji[k] += xi * d[k];
            }
        }
    }
    j
}

fn det3(j: &[[f64; 3]; 3]) -> f64 {
    j[0][0] * (j[1][1] * j[2][2] - j[1][2] * j[2][1])
        - j[0][1] * (j[1][0] * j[2][2] - j[1][2] * j[2][0])
        + j[0][2] * (j[1][0] * j[2][1] - j[1][1] * j[2][0])
}

/// det J at point `q`, or the bad point when it is not positive (or not finite).
pub(crate) fn det_at(
    tab: &Tabulated,
    q: usize,
    xs: &[[f64; 3]],
) -> std::result::Result<([[f64; 3]; 3], f64), BadJacobian> {
    let j = jacobian(xs, &tab.dn[q * tab.nn..(q + 1) * tab.nn]);
    let det = det3(&j);
    if det > 0.0 && det.is_finite() {
        Ok((j, det))
    } else {
        Err(BadJacobian {
            point: tab.points[q],
            det,
        })
    }
}

/// Physical gradients ∇Nₐ = J⁻ᵀ ∂Nₐ/∂ξ at point `q` into `grads`; returns det J.
pub(crate) fn gradients(
    tab: &Tabulated,
    q: usize,
    xs: &[[f64; 3]],
    grads: &mut [[f64; 3]],
) -> std::result::Result<f64, BadJacobian> {
    let (j, det) = det_at(tab, q, xs)?;
    // Rows of the cofactor matrix: inv[k][i] = cof[i][k] / det, and gᵢ = Σₖ inv[k][i] dNₖ.
    let cof = [
        [
            j[1][1] * j[2][2] - j[1][2] * j[2][1],
            j[1][2] * j[2][0] - j[1][0] * j[2][2],
            j[1][0] * j[2][1] - j[1][1] * j[2][0],
        ],
        [
            j[0][2] * j[2][1] - j[0][1] * j[2][2],
            j[0][0] * j[2][2] - j[0][2] * j[2][0],
            j[0][1] * j[2][0] - j[0][0] * j[2][1],
        ],
        [
            j[0][1] * j[1][2] - j[0][2] * j[1][1],
            j[0][2] * j[1][0] - j[0][0] * j[1][2],
            j[0][0] * j[1][1] - j[0][1] * j[1][0],
        ],
    ];
    let inv_det = 1.0 / det;
    for (g, d) in grads.iter_mut().zip(&tab.dn[q * tab.nn..(q + 1) * tab.nn]) {
        for (i, gi) in g.iter_mut().enumerate() {
            *gi = (cof[i][0] * d[0] + cof[i][1] * d[1] + cof[i][2] * d[2]) * inv_det;
        }
    }
    Ok(det)
}

/// Scratch buffers for [`stiffness_blocks`], sized for `nn` nodes.
#[derive(Clone, Debug, Default)]
pub(crate) struct Scratch {
    grads: Vec<[f64; 3]>,
    /// Physical gradient component p = 3a + i at the current point.
    g: Vec<f64>,
    /// A = Σ_q w_q det J_q g_q g_qᵀ (3nn × 3nn, row-major), see [`gradient_products`].
    a: Vec<f64>,
}

impl Scratch {
    /// Buffers for elements of up to `nn` nodes.
    pub fn new(nn: usize) -> Scratch {
        Scratch {
            grads: vec![[0.0; 3]; nn],
            g: vec![0.0; 3 * nn],
            a: vec![0.0; 9 * nn * nn],
        }
    }
}

/// Element stiffness into `out` as nn × nn blocks of 3×3: block (a, b) at `(a * nn + b) * 9`,
/// entry `3i + j` = K[3a + i][3b + j] (N/m).
///
/// With A_ab[i][j] = ∫ ∂ᵢNₐ ∂ⱼN_b dV (see [`gradient_products`]),
/// K_ab = λ A_ab + μ A_abᵀ + μ tr(A_ab) I — the isotropic Bᵀ D B. The result is exactly symmetric.
pub(crate) fn stiffness_blocks(
    tab: &Tabulated,
    xs: &[[f64; 3]],
    (lambda, mu): (f64, f64),
    s: &mut Scratch,
    out: &mut [f64],
) -> std::result::Result<(), BadJacobian> {
    let nn = tab.nn;
    let n3 = 3 * nn;
    gradient_products(tab, xs, s)?;
    let a_at = |p: usize, r: usize| s.a[p * n3 + r];
    for a in 0..nn {
        for b in a..nn {
            let (pa, pb) = (3 * a, 3 * b);
            let trace = a_at(pa, pb) + a_at(pa + 1, pb + 1) + a_at(pa + 2, pb + 2);
            let blk = &mut out[(a * nn + b) * 9..(a * nn + b + 1) * 9];
            for i in 0..3 {
                for j in 0..3 {
                    blk[3 * i + j] = lambda * a_at(pa + i, pb + j) + mu * a_at(pa + j, pb + i);
                }
                blk[4 * i] += mu * trace;
            }
        }
    }
    mirror_blocks(nn, out);
    Ok(())
}

/// A = Σ_q w_q det J_q g_q g_qᵀ into `s.a` (3nn × 3nn, row-major, exactly symmetric), g_q the
/// physical gradients at point q stacked node-major (3a + i): A[3a+i][3b+j] = ∫ ∂ᵢNₐ ∂ⱼN_b dV.
/// Rank-one updates of the upper triangle, then mirrored.
fn gradient_products(
    tab: &Tabulated,
    xs: &[[f64; 3]],
    s: &mut Scratch,
) -> std::result::Result<(), BadJacobian> {
    let n3 = 3 * tab.nn;
    s.a[..n3 * n3].fill(0.0);
    for q in 0..tab.nq() {
        let w = tab.weights[q] * gradients(tab, q, xs, &mut s.grads[..tab.nn])?;
        for (a, g) in s.grads[..tab.nn].iter().enumerate() {
            s.g[3 * a..3 * a + 3].copy_from_slice(g);
        }
        let g = &s.g[..n3];
        for (p, row) in s.a[..n3 * n3].chunks_exact_mut(n3).enumerate() {
            let wp = w * g[p];
            let (row, gs) = (&mut row[p..], &g[p..]);
            for k in 0..row.len().min(gs.len()) {
                row[k] += wp * gs[k];
            }
        }
    }
    for p in 0..n3 {
        for r in 0..p {
            s.a[p * n3 + r] = s.a[r * n3 + p];
        }
    }
    Ok(())
}

/// Fills the blocks below the block diagonal: K_ba = K_abᵀ.
fn mirror_blocks(nn: usize, out: &mut [f64]) {
    for a in 0..nn {
        for b in 0..a {
            for i in 0..3 {
                for j in 0..3 {
                    out[(a * nn + b) * 9 + 3 * i + j] = out[(b * nn + a) * 9 + 3 * j + i];
                }
            }
        }
    }
}

/// Scalar consistent mass ∫ ρ Nₐ N_b dV into `out` (nn × nn, row-major, kg); the element mass
/// matrix is this ⊗ I₃.
pub(crate) fn mass_scalar(
    tab: &Tabulated,
    xs: &[[f64; 3]],
    rho: f64,
    out: &mut [f64],
) -> std::result::Result<(), BadJacobian> {
    let nn = tab.nn;
    out[..nn * nn].fill(0.0);
    for q in 0..tab.nq() {
        let (_, det) = det_at(tab, q, xs)?;
        let w = rho * tab.weights[q] * det;
        let n = &tab.n[q * nn..(q + 1) * nn];
        for a in 0..nn {
            let wa = w * n[a];
            for b in a..nn {
                out[a * nn + b] += wa * n[b];
            }
        }
    }
    for a in 0..nn {
        for b in 0..a {
            out[a * nn + b] = out[b * nn + a];
        }
    }
    Ok(())
}

/// ∫ dV = Σ_q w_q det J(ξ_q) (m³).
pub(crate) fn volume_of(tab: &Tabulated, xs: &[[f64; 3]]) -> std::result::Result<f64, BadJacobian> {
    (0..tab.nq()).try_fold(0.0, |v, q| Ok(v + tab.weights[q] * det_at(tab, q, xs)?.1))
}

/// The error for an element type the FE assembly does not handle.
pub(crate) fn unsupported(kind: ElementType) -> Error {
    let names: Vec<&str> = shape::SUPPORTED.iter().map(|k| k.name()).collect();
    Error::input(format!(
        "{kind} elements are not supported by the FE assembly (supported: {}); remesh (Gmsh: Mesh.SecondOrderIncomplete = 1 gives pyramid13 instead of pyramid14)",
        names.join(", ")
    ))
}

/// Tabulation of the rule of `degree` (or the type's default for the matrix `which`).
pub(crate) fn table(
    kind: ElementType,
    xs: &[[f64; 3]],
    degree: Option<u32>,
    stiffness: bool,
) -> Result<Tabulated> {
    let (ds, dm) = default_degrees(kind).ok_or_else(|| unsupported(kind))?;
    if xs.len() != kind.num_nodes() {
        return Err(Error::input(format!(
            "a {kind} element has {} nodes, {} coordinates given",
            kind.num_nodes(),
            xs.len()
        )));
    }
    let d = degree.unwrap_or(if stiffness { ds } else { dm });
    Tabulated::for_degree(kind, d)
}

pub(crate) fn bad_element(kind: ElementType, b: BadJacobian) -> Error {
    Error::input(format!(
        "{kind} element with a non-positive Jacobian determinant ({}): it is inverted or degenerate",
        b.describe()
    ))
}

/// The 3n × 3n stiffness matrix Kₑ = ∫ Bᵀ D B dV (N/m) of one element with node coordinates `xs`
/// (m, Gmsh order), node-major DOF, with the quadrature rule of `degree` (default:
/// [`default_degrees`]). Errors: unsupported type, wrong node count, det J ≤ 0, invalid material.
pub fn element_stiffness(
    kind: ElementType,
    xs: &[[f64; 3]],
    material: &Material,
    degree: Option<u32>,
) -> Result<Mat<f64>> {
    material.validate("element material")?;
    let tab = table(kind, xs, degree, true)?;
    let nn = tab.nn;
    let mut blocks = vec![0.0; nn * nn * 9];
    let mut scratch = Scratch::new(nn);
    stiffness_blocks(&tab, xs, material.lame(), &mut scratch, &mut blocks)
        .map_err(|b| bad_element(kind, b))?;
    Ok(Mat::from_fn(3 * nn, 3 * nn, |r, c| {
        blocks[((r / 3) * nn + c / 3) * 9 + 3 * (r % 3) + c % 3]
    }))
}

/// The 3n × 3n consistent mass matrix Mₑ = ∫ ρ Nᵀ N dV (kg) of one element, node-major DOF, with
/// the rule of `degree` (default: [`default_degrees`]).
pub fn element_mass(
    kind: ElementType,
    xs: &[[f64; 3]],
    density: f64,
    degree: Option<u32>,
) -> Result<Mat<f64>> {
    let tab = table(kind, xs, degree, false)?;
    let nn = tab.nn;
    let mut m = vec![0.0; nn * nn];
    mass_scalar(&tab, xs, density, &mut m).map_err(|b| bad_element(kind, b))?;
    Ok(Mat::from_fn(3 * nn, 3 * nn, |r, c| {
        if r % 3 == c % 3 {
            m[(r / 3) * nn + c / 3]
        } else {
            0.0
        }
    }))
}

/// The volume ∫ dV (m³) of one element by quadrature (rule of `degree`, default the mass rule of
/// the type; exact for straight-sided elements).
pub fn element_volume(kind: ElementType, xs: &[[f64; 3]], degree: Option<u32>) -> Result<f64> {
    let tab = table(kind, xs, degree, false)?;
    volume_of(&tab, xs).map_err(|b| bad_element(kind, b))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn steel() -> Material {
        Material {
            young: 200e9,
            poisson: 0.3,
            density: 7850.0,
        }
    }

    /// The reference nodes mapped by x = A ξ + t (A with positive determinant).
    fn affine_nodes(kind: ElementType) -> (Vec<[f64; 3]>, f64) {
        let a = [[1.1, 0.2, 0.1], [-0.1, 0.9, 0.3], [0.05, -0.2, 1.3]];
        let det = det3(&a);
        let xs = shape::reference_nodes(kind)
            .unwrap()
            .iter()
            .map(|p| {
                let mut x = [0.3, -0.2, 0.5];
                for i in 0..3 {
                    for k in 0..3 {
                        x[i] += a[i][k] * p[k];
                    }
                }
                x
            })
            .collect();
        (xs, det)
    }

    fn reference_volume(kind: ElementType) -> f64 {
        match kind.first_order() {
            ElementType::Tetra4 => 1.0 / 6.0,
            ElementType::Hexa8 => 8.0,
            ElementType::Prism6 => 1.0,
            _ => 4.0 / 3.0,
        }
    }

    #[test]
    fn volume_and_mass_of_affine_elements() {
        for kind in shape::SUPPORTED {
            let (xs, det) = affine_nodes(kind);
            let v = element_volume(kind, &xs, None).unwrap();
            let exact = det * reference_volume(kind);
            assert!((v - exact).abs() < 1e-14 * exact, "{kind}: {v} vs {exact}");
            // Σ of all x-x entries of Mₑ = ρ V (a rigid x translation).
            let m = element_mass(kind, &xs, 2.0, None).unwrap();
            let total: f64 = (0..m.nrows())
                .step_by(3)
                .flat_map(|r| (0..m.ncols()).step_by(3).map(move |c| (r, c)))
                .map(|(r, c)| m[(r, c)])
                .sum();
            assert!((total - 2.0 * exact).abs() < 1e-13 * exact, "{kind} mass");
        }
    }

    #[test]
    fn stiffness_is_symmetric_and_annihilates_rigid_motions() {
        for kind in shape::SUPPORTED {
            let (xs, _) = affine_nodes(kind);
            let k = element_stiffness(kind, &xs, &steel(), None).unwrap();
            let n = k.nrows();
            let norm = (0..n).map(|i| k[(i, i)].abs()).fold(0.0, f64::max);
            for r in 0..n {
                for c in 0..n {
                    assert!(
                        (k[(r, c)] - k[(c, r)]).abs() <= 1e-13 * norm,
                        "{kind} symmetry"
                    );
                }
            }
            // Rigid rotation about z: u = (−y, x, 0).
            let u: Vec<f64> = xs.iter().flat_map(|x| [-x[1], x[0], 0.0]).collect();
            for r in 0..n {
                let f: f64 = (0..n).map(|c| k[(r, c)] * u[c]).sum();
                assert!(f.abs() <= 1e-11 * norm, "{kind} K·rotation row {r}: {f}");
            }
        }
    }

    #[test]
    fn unit_cube_hexa8_stiffness_entry_closed_form() {
        // Hexa8 on the unit cube: K[0][0] = (λ + 2μ)/9 + 2μ/9 ... computed by hand:
        // K_aa[x][x] = ∫ (λ+2μ) (∂N/∂x)² + μ ((∂N/∂y)² + (∂N/∂z)²) dV, with ∫(∂N/∂x)² = 1/9 per
        // direction for the corner function of the unit cube, so K = (λ + 4μ)/9.
        let xs: Vec<[f64; 3]> = shape::reference_nodes(ElementType::Hexa8)
            .unwrap()
            .iter()
            .map(|p| [0.5 * (p[0] + 1.0), 0.5 * (p[1] + 1.0), 0.5 * (p[2] + 1.0)])
            .collect();
        let m = steel();
        let (l, mu) = m.lame();
        let k = element_stiffness(ElementType::Hexa8, &xs, &m, None).unwrap();
        let expected = (l + 4.0 * mu) / 9.0;
        assert!(
            (k[(0, 0)] - expected).abs() < 1e-12 * expected,
            "{} vs {expected}",
            k[(0, 0)]
        );
    }

    #[test]
    fn inverted_and_malformed_elements_are_errors() {
        let (mut xs, _) = affine_nodes(ElementType::Tetra4);
        xs.swap(1, 2);
        let e = element_volume(ElementType::Tetra4, &xs, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("non-positive Jacobian"), "{e}");
        let e = element_volume(ElementType::Tetra10, &xs, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("10 nodes, 4 coordinates"), "{e}");
        let e = element_volume(ElementType::Pyramid14, &xs, None)
            .unwrap_err()
            .to_string();
        assert!(e.contains("not supported"), "{e}");
        xs[0][0] = f64::NAN;
        assert!(element_volume(ElementType::Tetra4, &xs, None).is_err());
    }
}
