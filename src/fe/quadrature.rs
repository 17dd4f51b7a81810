//! Quadrature rules on the reference volume elements, chosen by polynomial degree.
//!
//! A rule of degree p integrates every polynomial of total degree ≤ p exactly on the tetrahedron;
//! on the hexahedron, every polynomial of degree ≤ p in each coordinate; on the prism, every
//! polynomial of total degree ≤ p in (u, v) times degree ≤ p in w; on the pyramid, every
//! polynomial of degree ≤ p in each collapsed coordinate (which covers all polynomials of total
//! degree ≤ p and the pyramid's rational shape-function space). All weights are positive, and they
//! sum to the reference volume (tetrahedron 1/6, hexahedron 8, prism 1, pyramid 4/3).
//!
//! The 1-D building blocks are Gauss–Legendre and Gauss–Jacobi rules (weight (1 − x)^α on [−1, 1]),
//! computed by the Golub–Welsch eigenvalue method and polished by Newton's method on the Jacobi
//! polynomial P_n^(α,0) (three-term recurrence), with the weights
//! w_i = 2^(α+1) / ((1 − x_i²) P_n'(x_i)²). An n-point rule is exact to degree 2n − 1.
//!
//! The collapsed (conical, Stroud) product rules map the cube [−1, 1]³ onto the simplex or pyramid
//! (Duffy transform) and absorb the Jacobian of the map in Gauss–Jacobi weights:
//! tetrahedron x = ¼(1+a)(1−b)(1−c)/2, y = ¼(1+b)(1−c), z = ½(1+c), dV = (1−b)(1−c)²/64 da db dc.

use crate::error::{Error, Result};
use crate::mesh::ElementType;

/// Highest polynomial degree a rule can be asked for (n = 21 points per direction).
pub const MAX_DEGREE: u32 = 41;

/// A quadrature rule on a reference element: points in reference coordinates and positive weights
/// (reference volume).
#[derive(Clone, Debug, PartialEq)]
pub struct Rule {
    /// The polynomial degree the rule is exact to (see the module documentation).
    pub degree: u32,
    /// Points (ξ, η, ζ) in the reference element.
    pub points: Vec<[f64; 3]>,
    /// Weight of each point.
    pub weights: Vec<f64>,
}

impl Rule {
    /// Number of points.
    pub fn len(&self) -> usize {
        self.points.len()
    }

    /// Whether the rule has no point (never the case for the rules built here).
    pub fn is_empty(&self) -> bool {
        self.points.is_empty()
    }
}

/// The rule of `degree` for the reference element of `kind` (any order of the shape).
///
/// | shape | degree | rule | points |
/// |---|---|---|---|
/// | tetrahedron | 0–1 | centroid | 1 |
/// | | 2 | symmetric, a = (5 − √5)/20 | 4 |
/// | | 3 | collapsed Gauss–Jacobi, n = 2 | 8 |
/// | | 4–5 | symmetric 14-point (Walkington), positive weights | 14 |
/// | | p ≥ 6 | collapsed Gauss–Jacobi, n = ⌈(p+1)/2⌉ | n³ |
/// | hexahedron | p | Gauss–Legendre n × n × n, n = ⌈(p+1)/2⌉ | n³ |
/// | prism | p | triangle rule of degree p × Gauss–Legendre n in w | 1, 3, 7 or n² (triangle) × n |
/// | pyramid | p | collapsed: Gauss–Legendre n × n × Gauss–Jacobi (α = 2) n | n³ |
///
/// Triangle rules: degree 0–1 centroid (1 point); 2: 3 points (1/6, 1/6); 3–5: Dunavant/Radon
/// 7 points, a = (6 ∓ √15)/21; p ≥ 6: collapsed Gauss–Jacobi n × n.
///
/// Errors ([`Error::Input`]) for a shape that is not a volume element or a degree above
/// [`MAX_DEGREE`].
pub fn rule(kind: ElementType, degree: u32) -> Result<Rule> {
    if degree > MAX_DEGREE {
        return Err(Error::input(format!(
            "quadrature degree {degree} for {kind} elements exceeds the maximum {MAX_DEGREE}; ask for a lower degree"
        )));
    }
    match kind.first_order() {
        ElementType::Tetra4 => Ok(tetra_rule(degree)),
        ElementType::Hexa8 => Ok(hexa_rule(degree)),
        ElementType::Prism6 => Ok(prism_rule(degree)),
        ElementType::Pyramid5 => Ok(pyramid_rule(degree)),
        _ => Err(Error::input(format!(
            "no volume quadrature rule for {kind} elements (a {}-D element)",
            kind.dim()
        ))),
    }
}

/// Points per direction of a Gauss rule exact to `degree`: ⌈(p + 1)/2⌉, at least 1.
fn points_for(degree: u32) -> usize {
    (degree as usize + 2) / 2
}

/// The tetrahedron rule of `degree` (see [`rule`]) on the reference tetrahedron (0,0,0), (1,0,0),
/// (0,1,0), (0,0,1).
pub fn tetra_rule(degree: u32) -> Rule {
    match degree {
        0 | 1 => Rule {
            degree: 1,
            points: vec![[0.25; 3]],
            weights: vec![1.0 / 6.0],
        },
        2 => tetra4_points(),
        4 | 5 => tetra14_points(),
        _ => tetra_conical(points_for(degree)),
    }
}

/// The 4-point degree-2 rule: the orbit of (a, a, a) with a = (5 − √5)/20, weights 1/24.
fn tetra4_points() -> Rule {
    let (a, b) = (0.138_196_601_125_010_5, 0.585_410_196_624_968_5);
    Rule {
        degree: 2,
        points: orbit31(a, b).to_vec(),
        weights: vec![1.0 / 24.0; 4],
    }
}

/// The four points with barycentric coordinates (a, a, a, b), b = 1 − 3a.
fn orbit31(a: f64, b: f64) -> [[f64; 3]; 4] {
    [[a, a, a], [b, a, a], [a, b, a], [a, a, b]]
}

/// The 14-point degree-5 rule with positive weights (Walkington, "Quadrature on simplices of
/// arbitrary dimension", 2000): two (a, a, a, 1 − 3a) orbits and one (b, b, ½ − b, ½ − b) orbit.
/// Coefficients solved to 40 digits from the moment equations (mpmath), rounded to f64.
fn tetra14_points() -> Rule {
    let groups: [(f64, f64); 2] = [
        (0.310_885_919_263_300_6, 0.018_781_320_953_002_643),
        (0.092_735_250_310_891_22, 0.012_248_840_519_393_659),
    ];
    let mut points = Vec::with_capacity(14);
    let mut weights = Vec::with_capacity(14);
    for (a, w) in groups {
        points.extend_from_slice(&orbit31(a, 1.0 - 3.0 * a));
        weights.extend_from_slice(&[w; 4]);
    }
    let b = 0.045_503_704_125_649_65;
    let c = 0.5 - b;
    points.extend_from_slice(&[
        [b, b, c],
        [b, c, b],
        [c, b, b],
        [c, c, b],
        [c, b, c],
        [b, c, c],
    ]);
    weights.extend_from_slice(&[0.007_091_003_462_846_911; 6]);
    Rule {
        degree: 5,
        points,
        weights,
    }
}

/// The collapsed (conical product) rule with `n` points per direction on the tetrahedron: exact to
/// degree 2n − 1, n³ points, positive weights.
pub fn tetra_conical(n: usize) -> Rule {
    let (xa, wa) = gauss_jacobi(n, 0);
    let (xb, wb) = gauss_jacobi(n, 1);
    let (xc, wc) = gauss_jacobi(n, 2);
    let mut points = Vec::with_capacity(n * n * n);
    let mut weights = Vec::with_capacity(n * n * n);
    for (c, wc) in xc.iter().zip(&wc) {
        for (b, wb) in xb.iter().zip(&wb) {
            for (a, wa) in xa.iter().zip(&wa) {
                let z = 0.5 * (1.0 + c);
                let y = 0.25 * (1.0 + b) * (1.0 - c);
                let x = 0.125 * (1.0 + a) * (1.0 - b) * (1.0 - c);
                points.push([x, y, z]);
                weights.push(wa * wb * wc / 64.0);
            }
        }
    }
    Rule {
        degree: (2 * n - 1) as u32,
        points,
        weights,
    }
}

/// A rule on the reference triangle (0,0), (1,0), (0,1): points (u, v) and weights (sum 1/2).
pub fn triangle_rule(degree: u32) -> (Vec<[f64; 2]>, Vec<f64>) {
    match degree {
        0 | 1 => (vec![[1.0 / 3.0; 2]], vec![0.5]),
        2 => {
            let (a, b) = (1.0 / 6.0, 2.0 / 3.0);
            (vec![[a, a], [b, a], [a, b]], vec![1.0 / 6.0; 3])
        }
        3..=5 => triangle7(),
        _ => triangle_conical(points_for(degree)),
    }
}

/// The 7-point degree-5 rule (Radon 1948; Dunavant 1985 #5) in closed form.
fn triangle7() -> (Vec<[f64; 2]>, Vec<f64>) {
    let s = 15f64.sqrt();
    let (a1, a2) = ((6.0 - s) / 21.0, (6.0 + s) / 21.0);
    let (w1, w2) = ((155.0 - s) / 2400.0, (155.0 + s) / 2400.0);
    let mut pts = vec![[1.0 / 3.0; 2]];
    let mut wts = vec![9.0 / 80.0];
    for (a, w) in [(a1, w1), (a2, w2)] {
        let b = 1.0 - 2.0 * a;
        pts.extend_from_slice(&[[a, a], [b, a], [a, b]]);
        wts.extend_from_slice(&[w; 3]);
    }
    (pts, wts)
}

/// The collapsed Gauss–Jacobi rule with `n` points per direction on the triangle (exact to 2n − 1):
/// u = ¼(1+a)(1−b), v = ½(1+b), dA = (1−b)/8 da db.
fn triangle_conical(n: usize) -> (Vec<[f64; 2]>, Vec<f64>) {
    let (xa, wa) = gauss_jacobi(n, 0);
    let (xb, wb) = gauss_jacobi(n, 1);
    let mut pts = Vec::with_capacity(n * n);
    let mut wts = Vec::with_capacity(n * n);
    for (b, wb) in xb.iter().zip(&wb) {
        for (a, wa) in xa.iter().zip(&wa) {
            pts.push([0.25 * (1.0 + a) * (1.0 - b), 0.5 * (1.0 + b)]);
            wts.push(wa * wb / 8.0);
        }
    }
    (pts, wts)
}

/// The n × n × n Gauss–Legendre rule on [−1, 1]³ with n = ⌈(p+1)/2⌉.
pub fn hexa_rule(degree: u32) -> Rule {
    let (x, w) = gauss_legendre(points_for(degree));
    let mut points = Vec::with_capacity(x.len().pow(3));
    let mut weights = Vec::with_capacity(x.len().pow(3));
    for (z, wz) in x.iter().zip(&w) {
        for (y, wy) in x.iter().zip(&w) {
            for (xx, wx) in x.iter().zip(&w) {
                points.push([*xx, *y, *z]);
                weights.push(wx * wy * wz);
            }
        }
    }
    Rule {
        degree: (2 * x.len() - 1) as u32,
        points,
        weights,
    }
}

/// The prism rule: the triangle rule of degree p in (u, v) times Gauss–Legendre with ⌈(p+1)/2⌉
/// points in w ∈ [−1, 1].
pub fn prism_rule(degree: u32) -> Rule {
    let (tri, tw) = triangle_rule(degree);
    let (x, w) = gauss_legendre(points_for(degree));
    let mut points = Vec::with_capacity(tri.len() * x.len());
    let mut weights = Vec::with_capacity(tri.len() * x.len());
    for (z, wz) in x.iter().zip(&w) {
        for (p, wp) in tri.iter().zip(&tw) {
            points.push([p[0], p[1], *z]);
            weights.push(wp * wz);
        }
    }
    Rule {
        degree,
        points,
        weights,
    }
}

/// The collapsed rule on the reference pyramid (base [−1, 1]² at ζ = 0, apex (0, 0, 1)):
/// ξ = a(1 − ζ), η = b(1 − ζ), ζ = ½(1 + c), dV = (1 − c)²/8 da db dc; Gauss–Legendre in a and b,
/// Gauss–Jacobi (α = 2) in c, n = ⌈(p+1)/2⌉ points each.
pub fn pyramid_rule(degree: u32) -> Rule {
    let n = points_for(degree);
    let (xa, wa) = gauss_legendre(n);
    let (xc, wc) = gauss_jacobi(n, 2);
    let mut points = Vec::with_capacity(n * n * n);
    let mut weights = Vec::with_capacity(n * n * n);
    for (c, wc) in xc.iter().zip(&wc) {
        let z = 0.5 * (1.0 + c);
        for (b, wb) in xa.iter().zip(&wa) {
            for (a, w) in xa.iter().zip(&wa) {
                points.push([a * (1.0 - z), b * (1.0 - z), z]);
                weights.push(w * wb * wc / 8.0);
            }
        }
    }
    Rule {
        degree: (2 * n - 1) as u32,
        points,
        weights,
    }
}

/// The n-point Gauss–Legendre rule on [−1, 1] (nodes ascending).
pub fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    gauss_jacobi(n, 0)
}

/// The n-point Gauss–Jacobi rule for ∫₋₁¹ (1 − x)^α f(x) dx (nodes ascending, n ≥ 1; α = 0 is
/// Gauss–Legendre). Exact for polynomials f of degree ≤ 2n − 1.
pub fn gauss_jacobi(n: usize, alpha: u32) -> (Vec<f64>, Vec<f64>) {
    let n = n.max(1);
    let a = f64::from(alpha);
    let mut nodes = golub_welsch_nodes(n, a);
    let mut weights = Vec::with_capacity(n);
    for x in nodes.iter_mut() {
        for _ in 0..3 {
            let (p, dp) = jacobi_and_derivative(n, a, *x);
            *x -= p / dp;
        }
        let (_, dp) = jacobi_and_derivative(n, a, *x);
        weights.push(2f64.powi(alpha as i32 + 1) / ((1.0 - *x * *x) * dp * dp));
    }
    if alpha == 0 {
        symmetrise(&mut nodes, &mut weights);
    }
    (nodes, weights)
}

/// Makes a rule for an even weight exactly symmetric about 0 (x_i = −x_{n−1−i}, equal weights).
fn symmetrise(nodes: &mut [f64], weights: &mut [f64]) {
    let n = nodes.len();
    for i in 0..n / 2 {
        let x = 0.5 * (nodes[n - 1 - i] - nodes[i]);
        let w = 0.5 * (weights[i] + weights[n - 1 - i]);
        (nodes[i], nodes[n - 1 - i]) = (-x, x);
        (weights[i], weights[n - 1 - i]) = (w, w);
    }
    if n % 2 == 1 {
        nodes[n / 2] = 0.0;
    }
}

/// Eigenvalues of the symmetric tridiagonal Jacobi matrix of the weight (1 − x)^α (Golub–Welsch),
/// ascending: the nodes to machine precision, before the Newton polish.
fn golub_welsch_nodes(n: usize, a: f64) -> Vec<f64> {
    let mut t = nalgebra::DMatrix::<f64>::zeros(n, n);
    for k in 0..n {
        let kf = k as f64;
        t[(k, k)] = if k == 0 {
            -a / (a + 2.0)
        } else {
            -a * a / ((2.0 * kf + a) * (2.0 * kf + a + 2.0))
        };
        if k + 1 < n {
            let m = kf + 1.0;
            let s = 2.0 * m + a;
            let b2 = 4.0 * m * (m + a) * m * (m + a) / (s * s * (s + 1.0) * (s - 1.0));
            t[(k, k + 1)] = b2.sqrt();
            t[(k + 1, k)] = b2.sqrt();
        }
    }
    let mut x: Vec<f64> = nalgebra::SymmetricEigen::new(t)
        .eigenvalues
        .iter()
        .copied()
        .collect();
    x.sort_by(f64::total_cmp);
    x
}

/// P_n^(α,0)(x) and its derivative, by the three-term recurrence and
/// (2n+α)(1−x²) P_n' = n(α − (2n+α)x) P_n + 2(n+α) n P_{n−1}.
fn jacobi_and_derivative(n: usize, a: f64, x: f64) -> (f64, f64) {
    let mut p0 = 1.0;
    let mut p1 = (a + 1.0) + (a + 2.0) * (x - 1.0) / 2.0;
    for k in 2..=n {
        let k = k as f64;
        let s = 2.0 * k + a;
        let c1 = 2.0 * k * (k + a) * (s - 2.0);
        let c2 = (s - 1.0) * (s * (s - 2.0) * x + a * a);
        let c3 = 2.0 * (k + a - 1.0) * (k - 1.0) * s;
        let p2 = (c2 * p1 - c3 * p0) / c1;
        p0 = p1;
        p1 = p2;
    }
    let nf = n as f64;
    let s = 2.0 * nf + a;
    let dp = (nf * (a - s * x) * p1 + 2.0 * (nf + a) * nf * p0) / (s * (1.0 - x * x));
    (p1, dp)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// n! as f64.
    fn fact(n: u32) -> f64 {
        (1..=n).map(f64::from).product()
    }

    /// ∫₋₁¹ x^k dx.
    fn line_moment(k: u32) -> f64 {
        if k % 2 == 1 {
            0.0
        } else {
            2.0 / f64::from(k + 1)
        }
    }

    fn check(
        rule: &Rule,
        exact: impl Fn(u32, u32, u32) -> f64,
        admissible: impl Fn(u32, u32, u32) -> bool,
        what: &str,
    ) {
        let p = rule.degree;
        for i in 0..=p {
            for j in 0..=p {
                for k in 0..=p {
                    if !admissible(i, j, k) {
                        continue;
                    }
                    let q: f64 = rule
                        .points
                        .iter()
                        .zip(&rule.weights)
                        .map(|(x, w)| {
                            w * x[0].powi(i as i32) * x[1].powi(j as i32) * x[2].powi(k as i32)
                        })
                        .sum();
                    let e = exact(i, j, k);
                    // Relative for non-zero moments, absolute for the odd ones that vanish by symmetry.
                    let tol = if e == 0.0 { 1e-15 } else { 1e-13 * e.abs() };
                    assert!(
                        (q - e).abs() <= tol,
                        "{what} degree {p}: x^{i} y^{j} z^{k}: {q} vs {e}"
                    );
                }
            }
        }
        assert!(
            rule.weights.iter().all(|&w| w > 0.0),
            "{what}: positive weights"
        );
    }

    #[test]
    fn gauss_jacobi_is_exact_to_2n_minus_1() {
        for alpha in 0..=2u32 {
            for n in 1..=12 {
                let (x, w) = gauss_jacobi(n, alpha);
                for k in 0..(2 * n as u32) {
                    // ∫ (1−x)^α x^k dx by expanding with the binomial theorem in (1 − x).
                    let q: f64 = x.iter().zip(&w).map(|(x, w)| w * x.powi(k as i32)).sum();
                    let e: f64 = (0..=alpha)
                        .map(|m| {
                            let binom = fact(alpha) / (fact(m) * fact(alpha - m));
                            binom * (-1f64).powi(m as i32) * line_moment(k + m)
                        })
                        .sum();
                    assert!(
                        (q - e).abs() < 1e-14 * 8.0,
                        "alpha {alpha} n {n} k {k}: {q} vs {e}"
                    );
                }
            }
        }
    }

    #[test]
    fn gauss_legendre_three_points_closed_form() {
        let (x, w) = gauss_legendre(3);
        let g = 0.6f64.sqrt();
        for (a, b) in x.iter().zip([-g, 0.0, g]) {
            assert!((a - b).abs() < 1e-15);
        }
        for (a, b) in w.iter().zip([5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0]) {
            assert!((a - b).abs() < 1e-15);
        }
    }

    #[test]
    fn tetra_rules_exact_on_monomials() {
        // ∫ over the unit tetrahedron of x^a y^b z^c = a! b! c! / (a+b+c+3)!.
        for degree in 0..=12 {
            let r = tetra_rule(degree);
            assert!(r.degree >= degree.max(1));
            check(
                &r,
                |a, b, c| fact(a) * fact(b) * fact(c) / fact(a + b + c + 3),
                |a, b, c| a + b + c <= r.degree,
                "tetra",
            );
        }
        assert_eq!(tetra_rule(5).len(), 14);
        assert_eq!(tetra_rule(2).len(), 4);
    }

    #[test]
    fn tetra14_is_not_exact_at_degree_6() {
        // A check that the monomial test can fail: the 14-point rule misses x^6.
        let r = tetra_rule(5);
        let q: f64 = r
            .points
            .iter()
            .zip(&r.weights)
            .map(|(x, w)| w * x[0].powi(6))
            .sum();
        let e = fact(6) / fact(9);
        assert!((q - e).abs() > 1e-6 * e);
    }

    #[test]
    fn hexa_rules_exact_per_coordinate() {
        for degree in 0..=9 {
            let r = hexa_rule(degree);
            check(
                &r,
                |a, b, c| line_moment(a) * line_moment(b) * line_moment(c),
                |a, b, c| a.max(b).max(c) <= degree,
                "hexa",
            );
        }
    }

    #[test]
    fn prism_rules_exact() {
        // ∫ over triangle × [−1, 1] of u^a v^b w^c = a! b! / (a+b+2)! × ∫ w^c.
        for degree in 0..=9 {
            let r = prism_rule(degree);
            check(
                &r,
                |a, b, c| fact(a) * fact(b) / fact(a + b + 2) * line_moment(c),
                |a, b, c| a + b <= degree && c <= degree,
                "prism",
            );
        }
    }

    #[test]
    fn pyramid_rules_exact() {
        // ∫ over the pyramid of x^a y^b z^c = ∫x^a ∫y^b (over [−1,1]) × c! (a+b+2)! / (a+b+c+3)!.
        for degree in 0..=9 {
            let r = pyramid_rule(degree);
            check(
                &r,
                |a, b, c| {
                    line_moment(a) * line_moment(b) * fact(c) * fact(a + b + 2)
                        / fact(a + b + c + 3)
                },
                |a, b, c| a + b + c <= degree,
                "pyramid",
            );
        }
    }

    #[test]
    fn rule_dispatch_and_limits() {
        assert_eq!(rule(ElementType::Tetra10, 5).unwrap().len(), 14);
        assert_eq!(rule(ElementType::Hexa20, 4).unwrap().len(), 27);
        assert_eq!(rule(ElementType::Prism15, 4).unwrap().len(), 21);
        assert_eq!(rule(ElementType::Pyramid13, 4).unwrap().len(), 27);
        assert!(rule(ElementType::Triangle3, 2).is_err());
        let e = rule(ElementType::Hexa8, MAX_DEGREE + 1)
            .unwrap_err()
            .to_string();
        assert!(e.contains("exceeds the maximum"), "{e}");
    }
}
