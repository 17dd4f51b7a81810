//! Shape functions of the volume elements: values and derivatives with respect to the reference
//! coordinates, in Gmsh node order ([`crate::mesh::element`]).
//!
//! Reference elements (as Gmsh):
//!
//! | shape | reference domain | corners |
//! |---|---|---|
//! | tetrahedron | u, v, w ≥ 0, u + v + w ≤ 1 | (0,0,0) (1,0,0) (0,1,0) (0,0,1) |
//! | hexahedron | [−1, 1]³ | (−1,−1,−1) (1,−1,−1) (1,1,−1) (−1,1,−1), then the same at w = +1 |
//! | prism | triangle (u, v) × w ∈ [−1, 1] | (0,0,−1) (1,0,−1) (0,1,−1) (0,0,1) (1,0,1) (0,1,1) |
//! | pyramid | base [−1, 1]² at w = 0, apex (0, 0, 1) | (−1,−1,0) (1,−1,0) (1,1,0) (−1,1,0) (0,0,1) |
//!
//! Higher-order nodes sit at the mid-points of the edges listed in [`crate::mesh::element`] (then
//! the face centres and the body centre for hexa27 / prism18).
//!
//! | type | functions |
//! |---|---|
//! | tetra4, tetra10 | barycentric λ: λᵢ; corners λᵢ(2λᵢ − 1), edges 4λᵢλⱼ |
//! | hexa8 | ⅛(1 + ξᵢξ)(1 + ηᵢη)(1 + ζᵢζ) |
//! | hexa20 | serendipity: corners ⅛(1+ξᵢξ)(1+ηᵢη)(1+ζᵢζ)(ξᵢξ + ηᵢη + ζᵢζ − 2), edges ¼(1 − ξ²)(1+ηᵢη)(1+ζᵢζ) |
//! | hexa27 | triquadratic Lagrange |
//! | prism6 | λᵢ · ½(1 + wᵢw) |
//! | prism15 | corners ½λᵢ(2λᵢ−1)(1+wᵢw) − ½λᵢ(1−w²); triangle edges 2λᵢλⱼ(1+wᵢw); vertical edges λᵢ(1−w²) |
//! | prism18 | triangle6 × 1-D quadratic Lagrange in w |
//! | pyramid5 | base ¼(1+ξᵢξ−ζ)(1+ηᵢη−ζ)/(1−ζ), apex ζ (rational) |
//! | pyramid13 | rational serendipity (Bedrosian 1992): base corners ¼(1+ξᵢξ−ζ)(1+ηᵢη−ζ)(ξᵢξ+ηᵢη−1)/(1−ζ), base edges ½(1+ξ−ζ)(1−ξ−ζ)(1+ηᵢη−ζ)/(1−ζ) (and ξ ↔ η), apex ζ(2ζ−1), apex edges ζ(1+ξᵢξ−ζ)(1+ηᵢη−ζ)/(1−ζ) (ξᵢ, ηᵢ the base corner's) |
//!
//! Every basis here reproduces linear fields (all quadratic ones for the second-order types), which
//! is what the patch test needs. The pyramid bases are rational and undefined at the apex itself
//! (ζ = 1); quadrature points never lie there. Derivatives are computed by forward-mode automatic
//! differentiation of these expressions (a value–gradient pair), so they are exact.

use std::ops::{Add, Div, Mul, Sub};

use crate::mesh::ElementType;

/// Shape-function values and their derivatives ∂Nₐ/∂(ξ, η, ζ) at one reference point.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapeValues {
    /// Nₐ, one per node in Gmsh order.
    pub n: Vec<f64>,
    /// (∂Nₐ/∂ξ, ∂Nₐ/∂η, ∂Nₐ/∂ζ), one per node.
    pub dn: Vec<[f64; 3]>,
}

/// The volume element types the FE assembly supports (every 3-D type nlrom reads but pyramid14).
pub const SUPPORTED: [ElementType; 10] = [
    ElementType::Tetra4,
    ElementType::Tetra10,
    ElementType::Hexa8,
    ElementType::Hexa20,
    ElementType::Hexa27,
    ElementType::Prism6,
    ElementType::Prism15,
    ElementType::Prism18,
    ElementType::Pyramid5,
    ElementType::Pyramid13,
];

/// Whether [`shape`] (and so the assembly) supports `kind`.
pub fn is_supported(kind: ElementType) -> bool {
    SUPPORTED.contains(&kind)
}

const TET_CORNERS: [[f64; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];
const HEX_CORNERS: [[f64; 3]; 8] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
];
const PRISM_CORNERS: [[f64; 3]; 6] = [
    [0.0, 0.0, -1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, -1.0],
    [0.0, 0.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
];
const PYRAMID_CORNERS: [[f64; 3]; 5] = [
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];
/// Gmsh edge orders (`mesh::element`): mid-edge node k + corners is on edge k.
const TET_EDGES: [[usize; 2]; 6] = [[0, 1], [1, 2], [2, 0], [3, 0], [3, 2], [3, 1]];
const HEX_EDGES: [[usize; 2]; 12] = [
    [0, 1],
    [0, 3],
    [0, 4],
    [1, 2],
    [1, 5],
    [2, 3],
    [2, 6],
    [3, 7],
    [4, 5],
    [4, 7],
    [5, 6],
    [6, 7],
];
const PRISM_EDGES: [[usize; 2]; 9] = [
    [0, 1],
    [0, 2],
    [0, 3],
    [1, 2],
    [1, 4],
    [2, 5],
    [3, 4],
    [3, 5],
    [4, 5],
];
const PYRAMID_EDGES: [[usize; 2]; 8] = [
    [0, 1],
    [0, 3],
    [0, 4],
    [1, 2],
    [1, 4],
    [2, 3],
    [2, 4],
    [3, 4],
];
/// Face-centre nodes of hexa27 (nodes 20..25) and prism18 (15..17), by face corners.
const HEX_FACES: [[usize; 4]; 6] = [
    [0, 3, 2, 1],
    [0, 1, 5, 4],
    [0, 4, 7, 3],
    [1, 2, 6, 5],
    [2, 3, 7, 6],
    [4, 5, 6, 7],
];
const PRISM_QUAD_FACES: [[usize; 4]; 3] = [[0, 1, 4, 3], [0, 3, 5, 2], [1, 2, 5, 4]];

/// For each node of `kind` in Gmsh order, the corners it is the average of: itself for a corner,
/// the two ends of its edge, the four corners of its face, or all corners for a body centre.
/// `None` for unsupported types.
pub fn node_parents(kind: ElementType) -> Option<Vec<Vec<usize>>> {
    use ElementType::*;
    if !is_supported(kind) {
        return None;
    }
    let corners = kind.num_corners();
    let mut parents: Vec<Vec<usize>> = (0..corners).map(|c| vec![c]).collect();
    let (edges, faces): (&[[usize; 2]], &[[usize; 4]]) = match kind {
        Tetra10 => (&TET_EDGES, &[]),
        Hexa20 => (&HEX_EDGES, &[]),
        Hexa27 => (&HEX_EDGES, &HEX_FACES),
        Prism15 => (&PRISM_EDGES, &[]),
        Prism18 => (&PRISM_EDGES, &PRISM_QUAD_FACES),
        Pyramid13 => (&PYRAMID_EDGES, &[]),
        _ => (&[], &[]),
    };
    parents.extend(edges.iter().map(|e| e.to_vec()));
    parents.extend(faces.iter().map(|f| f.to_vec()));
    if kind == Hexa27 {
        parents.push((0..8).collect());
    }
    Some(parents)
}

/// Reference coordinates of the nodes of `kind` in Gmsh order (`None` for unsupported types).
pub fn reference_nodes(kind: ElementType) -> Option<Vec<[f64; 3]>> {
    let corners: &[[f64; 3]] = match kind.first_order() {
        ElementType::Tetra4 => &TET_CORNERS,
        ElementType::Hexa8 => &HEX_CORNERS,
        ElementType::Prism6 => &PRISM_CORNERS,
        ElementType::Pyramid5 => &PYRAMID_CORNERS,
        _ => return None,
    };
    let parents = node_parents(kind)?;
    Some(
        parents
            .iter()
            .map(|p| {
                let mut x = [0.0; 3];
                for &c in p {
                    for k in 0..3 {
                        x[k] += corners[c][k] / p.len() as f64;
                    }
                }
                x
            })
            .collect(),
    )
}

/// Shape functions of `kind` at the reference point `xi` (Gmsh node order); `None` for types the
/// assembly does not support (see [`SUPPORTED`]).
pub fn shape(kind: ElementType, xi: [f64; 3]) -> Option<ShapeValues> {
    let x = [
        Dual::var(xi[0], 0),
        Dual::var(xi[1], 1),
        Dual::var(xi[2], 2),
    ];
    let nodes = reference_nodes(kind)?;
    let duals: Vec<Dual> = match kind.first_order() {
        ElementType::Tetra4 => tet(kind, x),
        ElementType::Hexa8 => nodes.iter().map(|c| hex_node(kind, *c, x)).collect(),
        ElementType::Prism6 => nodes.iter().map(|c| prism_node(kind, *c, x)).collect(),
        _ => nodes.iter().map(|c| pyramid_node(kind, *c, x)).collect(),
    };
    Some(ShapeValues {
        n: duals.iter().map(|d| d.v).collect(),
        dn: duals.iter().map(|d| d.d).collect(),
    })
}

/// Tetrahedra: barycentric coordinates λ = (1 − u − v − w, u, v, w).
fn tet(kind: ElementType, [u, v, w]: [Dual; 3]) -> Vec<Dual> {
    let l = [1.0 - u - v - w, u, v, w];
    if kind == ElementType::Tetra4 {
        return l.to_vec();
    }
    let mut n: Vec<Dual> = l.iter().map(|&li| li * (2.0 * li - 1.0)).collect();
    n.extend(TET_EDGES.iter().map(|&[i, j]| 4.0 * l[i] * l[j]));
    n
}

/// 1-D quadratic Lagrange polynomial through −1, 0, 1 for the node at `a`.
fn lagrange2(a: f64, x: Dual) -> Dual {
    if a < 0.0 {
        0.5 * x * (x - 1.0)
    } else if a > 0.0 {
        0.5 * x * (x + 1.0)
    } else {
        1.0 - x * x
    }
}

/// Hexahedra: the function of the node at reference position `c`.
fn hex_node(kind: ElementType, c: [f64; 3], x: [Dual; 3]) -> Dual {
    match kind {
        ElementType::Hexa27 => {
            lagrange2(c[0], x[0]) * lagrange2(c[1], x[1]) * lagrange2(c[2], x[2])
        }
        _ => {
            // (1 + cₖxₖ) along a corner's coordinates, (1 − xₖ²) along a mid-edge node's zero one.
            let f = |k: usize| {
                if c[k] == 0.0 {
                    1.0 - x[k] * x[k]
                } else {
                    1.0 + c[k] * x[k]
                }
            };
            let product = f(0) * f(1) * f(2);
            let is_corner = c.iter().all(|&ck| ck != 0.0);
            match (kind, is_corner) {
                (ElementType::Hexa8, _) => 0.125 * product,
                (_, true) => 0.125 * product * (c[0] * x[0] + c[1] * x[1] + c[2] * x[2] - 2.0),
                (_, false) => 0.25 * product,
            }
        }
    }
}

/// Prisms: the function of the node at reference position `c` = (uₐ, vₐ, wₐ).
fn prism_node(kind: ElementType, c: [f64; 3], [u, v, w]: [Dual; 3]) -> Dual {
    let l = [1.0 - u - v, u, v];
    let la = [1.0 - c[0] - c[1], c[0], c[1]];
    // The node's position in the triangle: a corner (one λ = 1) or an edge mid-point (two ½).
    let ones: Vec<usize> = (0..3).filter(|&i| la[i] > 0.75).collect();
    let halves: Vec<usize> = (0..3).filter(|&i| (la[i] - 0.5).abs() < 0.25).collect();
    let wa = c[2];
    let lin = 1.0 + wa * w;
    let bubble = 1.0 - w * w;
    match (kind, ones.as_slice(), halves.as_slice()) {
        (ElementType::Prism6, [i], _) => 0.5 * l[*i] * lin,
        (ElementType::Prism15, [i], _) if wa != 0.0 => {
            0.5 * l[*i] * (2.0 * l[*i] - 1.0) * lin - 0.5 * l[*i] * bubble
        }
        (ElementType::Prism15, [i], _) => l[*i] * bubble,
        (ElementType::Prism15, [], [i, j]) => 2.0 * l[*i] * l[*j] * lin,
        (_, [i], _) => l[*i] * (2.0 * l[*i] - 1.0) * lagrange2(wa, w),
        (_, _, [i, j]) => 4.0 * l[*i] * l[*j] * lagrange2(wa, w),
        _ => Dual::cst(f64::NAN),
    }
}

/// Pyramids: the rational function of the node at reference position `c`.
fn pyramid_node(kind: ElementType, c: [f64; 3], [x, y, z]: [Dual; 3]) -> Dual {
    let top = 1.0 - z;
    if c[2] == 1.0 {
        return if kind == ElementType::Pyramid5 {
            z
        } else {
            z * (2.0 * z - 1.0)
        };
    }
    if c[2] == 0.5 {
        // Apex edge of the base corner (2cₓ, 2c_y).
        let (xi, yi) = (2.0 * c[0], 2.0 * c[1]);
        return z * (1.0 + xi * x - z) * (1.0 + yi * y - z) / top;
    }
    let fx = 1.0 + c[0] * x - z;
    let fy = 1.0 + c[1] * y - z;
    match (kind, c[0] == 0.0, c[1] == 0.0) {
        (ElementType::Pyramid5, _, _) => 0.25 * fx * fy / top,
        (_, false, false) => 0.25 * fx * fy * (c[0] * x + c[1] * y - 1.0) / top,
        (_, true, _) => 0.5 * (1.0 + x - z) * (1.0 - x - z) * fy / top,
        (_, _, true) => 0.5 * (1.0 + y - z) * (1.0 - y - z) * fx / top,
    }
}

/// A value with its gradient with respect to the three reference coordinates (forward-mode
/// automatic differentiation).
#[derive(Clone, Copy, Debug)]
struct Dual {
    v: f64,
    d: [f64; 3],
}

impl Dual {
    /// A constant.
    fn cst(v: f64) -> Dual {
        Dual { v, d: [0.0; 3] }
    }

    /// The reference coordinate number `k` with value `v`.
    fn var(v: f64, k: usize) -> Dual {
        let mut d = [0.0; 3];
        d[k] = 1.0;
        Dual { v, d }
    }

    fn map(self, other: Dual, v: f64, f: impl Fn(f64, f64) -> f64) -> Dual {
        Dual {
            v,
            d: [
                f(self.d[0], other.d[0]),
                f(self.d[1], other.d[1]),
                f(self.d[2], other.d[2]),
            ],
        }
    }
}

impl Add for Dual {
    type Output = Dual;
    fn add(self, o: Dual) -> Dual {
        self.map(o, self.v + o.v, |a, b| a + b)
    }
}

impl Sub for Dual {
    type Output = Dual;
    fn sub(self, o: Dual) -> Dual {
        self.map(o, self.v - o.v, |a, b| a - b)
    }
}

#[allow(clippy::suspicious_arithmetic_impl)] // the product rule
impl Mul for Dual {
    type Output = Dual;
    fn mul(self, o: Dual) -> Dual {
        let (a, b) = (self.v, o.v);
        self.map(o, a * b, |da, db| da * b + a * db)
    }
}

#[allow(clippy::suspicious_arithmetic_impl)] // the quotient rule
impl Div for Dual {
    type Output = Dual;
    fn div(self, o: Dual) -> Dual {
        let (a, b) = (self.v, o.v);
        self.map(o, a / b, |da, db| (da * b - a * db) / (b * b))
    }
}

impl Add<f64> for Dual {
    type Output = Dual;
    fn add(self, c: f64) -> Dual {
        self + Dual::cst(c)
    }
}

impl Sub<f64> for Dual {
    type Output = Dual;
    fn sub(self, c: f64) -> Dual {
        self - Dual::cst(c)
    }
}

impl Add<Dual> for f64 {
    type Output = Dual;
    fn add(self, d: Dual) -> Dual {
        Dual::cst(self) + d
    }
}

impl Sub<Dual> for f64 {
    type Output = Dual;
    fn sub(self, d: Dual) -> Dual {
        Dual::cst(self) - d
    }
}

impl Mul<Dual> for f64 {
    type Output = Dual;
    fn mul(self, d: Dual) -> Dual {
        Dual::cst(self) * d
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A reference point inside every element (pyramid included).
    const INSIDE: [f64; 3] = [0.13, 0.21, 0.17];

    #[test]
    fn kronecker_property_at_the_nodes() {
        for kind in SUPPORTED {
            let nodes = reference_nodes(kind).unwrap();
            assert_eq!(nodes.len(), kind.num_nodes(), "{kind}");
            for (i, &x) in nodes.iter().enumerate() {
                // The pyramid bases are rational with a removable singularity at the apex.
                let apex = kind.first_order() == ElementType::Pyramid5 && x[2] == 1.0;
                let x = if apex { [0.0, 0.0, 1.0 - 1e-13] } else { x };
                let s = shape(kind, x).unwrap();
                for (j, nj) in s.n.iter().enumerate() {
                    let expected = if i == j { 1.0 } else { 0.0 };
                    assert!(
                        (nj - expected).abs() < 1e-11,
                        "{kind} N{j} at node {i}: {nj}"
                    );
                }
            }
        }
    }

    #[test]
    fn partition_of_unity_and_polynomial_completeness() {
        // Σ Nₐ f(Xₐ) = f(x) for f = 1, x, y, z (and all quadratics for second-order types).
        let monomials: [[i32; 3]; 10] = [
            [0, 0, 0],
            [1, 0, 0],
            [0, 1, 0],
            [0, 0, 1],
            [2, 0, 0],
            [0, 2, 0],
            [0, 0, 2],
            [1, 1, 0],
            [1, 0, 1],
            [0, 1, 1],
        ];
        for kind in SUPPORTED {
            let nodes = reference_nodes(kind).unwrap();
            let s = shape(kind, INSIDE).unwrap();
            let count = if kind.order() == 1 { 4 } else { 10 };
            for m in &monomials[..count] {
                let f = |x: [f64; 3]| x[0].powi(m[0]) * x[1].powi(m[1]) * x[2].powi(m[2]);
                let interp: f64 = s.n.iter().zip(&nodes).map(|(n, x)| n * f(*x)).sum();
                assert!((interp - f(INSIDE)).abs() < 1e-14, "{kind} monomial {m:?}");
                // Derivatives reproduce ∇f.
                for k in 0..3 {
                    let d: f64 = s.dn.iter().zip(&nodes).map(|(dn, x)| dn[k] * f(*x)).sum();
                    let mut e = m[k] as f64;
                    let mut mm = *m;
                    mm[k] -= 1;
                    if mm[k] >= 0 {
                        e *= INSIDE[0].powi(mm[0]) * INSIDE[1].powi(mm[1]) * INSIDE[2].powi(mm[2]);
                    } else {
                        e = 0.0;
                    }
                    assert!((d - e).abs() < 1e-13, "{kind} d/dx{k} of {m:?}: {d} vs {e}");
                }
            }
        }
    }

    #[test]
    fn derivatives_match_finite_differences() {
        let h = 1e-6;
        for kind in SUPPORTED {
            let s = shape(kind, INSIDE).unwrap();
            for k in 0..3 {
                let mut xp = INSIDE;
                let mut xm = INSIDE;
                xp[k] += h;
                xm[k] -= h;
                let np = shape(kind, xp).unwrap().n;
                let nm = shape(kind, xm).unwrap().n;
                for a in 0..s.n.len() {
                    let fd = (np[a] - nm[a]) / (2.0 * h);
                    assert!(
                        (s.dn[a][k] - fd).abs() < 1e-8,
                        "{kind} dN{a}/dξ{k}: {} vs {fd}",
                        s.dn[a][k]
                    );
                }
            }
        }
    }

    #[test]
    fn mid_edge_nodes_follow_the_gmsh_edge_lists() {
        // tetra10 node 8 is on edge (3, 2), node 9 on (3, 1): the ones that differ from VTK.
        let t = reference_nodes(ElementType::Tetra10).unwrap();
        assert_eq!(t[8], [0.0, 0.5, 0.5]);
        assert_eq!(t[9], [0.5, 0.0, 0.5]);
        let h = reference_nodes(ElementType::Hexa27).unwrap();
        assert_eq!(h[9], [-1.0, 0.0, -1.0]);
        assert_eq!(h[20], [0.0, 0.0, -1.0]);
        assert_eq!(h[22], [-1.0, 0.0, 0.0]);
        assert_eq!(h[26], [0.0, 0.0, 0.0]);
        let p = reference_nodes(ElementType::Prism18).unwrap();
        assert_eq!(p[8], [0.0, 0.0, 0.0]);
        assert_eq!(p[16], [0.0, 0.5, 0.0]);
        assert!(shape(ElementType::Pyramid14, INSIDE).is_none());
        assert!(shape(ElementType::Triangle3, INSIDE).is_none());
    }
}
