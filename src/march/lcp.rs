//! The linear complementarity problem of one nonsmooth time step: find λ ∈ ℝᵐ with
//!
//! w = W λ + q ≥ 0,  λ ≥ 0,  wᵀλ = 0,
//!
//! W (m × m, row-major) the Delassus matrix of the active contacts, q the free (contact-less)
//! output. [`lemke`] is the production solver: Lemke's complementary pivoting with the covering
//! vector d = 1 and the lexicographic ratio test (Cottle, Pang & Stone, "The Linear Complementarity
//! Problem", 1992, §4.4), exact in finitely many pivots for a P-matrix W, symmetric or not.
//! [`enumerate`] tries the 2ᵐ complementary bases and serves as the oracle in tests and as the
//! fallback when Lemke ends on a ray. [`residual`] is the complementarity residual
//! ‖λ − max(0, λ − w)‖_∞ every caller reports.

use faer::linalg::solvers::Solve;

/// A solved LCP.
#[derive(Clone, Debug, PartialEq)]
pub struct LcpSolution {
    /// λ ≥ 0 (the unknown; impulses in N·s for the time steps).
    pub lambda: Vec<f64>,
    /// w = W λ + q ≥ 0.
    pub w: Vec<f64>,
    /// Pivots taken (0 when q ≥ 0).
    pub pivots: usize,
}

/// w = W λ + q for row-major W (m × m).
pub fn output(w_mat: &[f64], q: &[f64], lambda: &[f64]) -> Vec<f64> {
    let m = q.len();
    (0..m)
        .map(|i| q[i] + (0..m).map(|j| w_mat[i * m + j] * lambda[j]).sum::<f64>())
        .collect()
}

/// The complementarity residual ‖λ − max(0, λ − w)‖_∞ (zero exactly at a solution).
pub fn residual(lambda: &[f64], w: &[f64]) -> f64 {
    lambda
        .iter()
        .zip(w)
        .map(|(&l, &wi)| (l - (l - wi).max(0.0)).abs())
        .fold(0.0, f64::max)
}

/// Lemke's algorithm with the lexicographic ratio test; `None` on ray termination (W not
/// a P-matrix, or degenerate beyond the lexicographic rule) or after 50·(m + 1) pivots.
///
/// Tableau: w − W z − d z₀ = q with basis w; z₀ enters at the row of min q, then the
/// complement of each leaving variable enters, until z₀ leaves. Ties in the ratio test are
/// broken by the rows of the current basis inverse (the w-columns of the tableau).
pub fn lemke(w_mat: &[f64], q: &[f64]) -> Option<LcpSolution> {
    let m = q.len();
    if q.iter().all(|&v| v >= 0.0) {
        return Some(LcpSolution {
            lambda: vec![0.0; m],
            w: q.to_vec(),
            pivots: 0,
        });
    }
    // Columns: 0..m w, m..2m z, 2m z0, 2m+1 rhs.
    let nc = 2 * m + 2;
    let mut t = vec![0.0; m * nc];
    for i in 0..m {
        t[i * nc + i] = 1.0;
        for j in 0..m {
            t[i * nc + m + j] = -w_mat[i * m + j];
        }
        t[i * nc + 2 * m] = -1.0;
        t[i * nc + 2 * m + 1] = q[i];
    }
    let mut basis: Vec<usize> = (0..m).collect();
    let scale = q.iter().chain(w_mat).fold(1.0_f64, |a, &b| a.max(b.abs()));
    let eps = 1e-13 * scale;
    let pivot = |t: &mut Vec<f64>, r: usize, c: usize| {
        let p = t[r * nc + c];
        for k in 0..nc {
            t[r * nc + k] /= p;
        }
        for i in 0..m {
            if i != r {
                let f = t[i * nc + c];
                if f != 0.0 {
                    for k in 0..nc {
                        t[i * nc + k] -= f * t[r * nc + k];
                    }
                }
            }
        }
    };
    // z0 enters at the most negative q (lexicographic: the smallest row of [q, B⁻¹] / 1).
    let mut r = 0;
    for i in 1..m {
        if q[i] < q[r] {
            r = i;
        }
    }
    pivot(&mut t, r, 2 * m);
    let mut leaving = basis[r];
    basis[r] = 2 * m;
    let mut pivots = 1;
    while pivots < 50 * (m + 1) {
        let enter = if leaving < m {
            leaving + m
        } else {
            leaving - m
        };
        // Lexicographic minimum ratio over rows with a positive entry in the entering column.
        let mut best: Option<usize> = None;
        for i in 0..m {
            let a = t[i * nc + enter];
            if a <= eps {
                continue;
            }
            best = Some(match best {
                None => i,
                Some(b) => {
                    let ab = t[b * nc + enter];
                    let key = |row: usize, piv: f64, k: usize| -> f64 {
                        if k == 0 {
                            t[row * nc + 2 * m + 1] / piv
                        } else {
                            t[row * nc + k - 1] / piv
                        }
                    };
                    let mut choice = b;
                    for k in 0..=m {
                        let (ki, kb) = (key(i, a, k), key(b, ab, k));
                        let tol = 1e-12 * (1.0 + ki.abs().max(kb.abs()));
                        if ki < kb - tol {
                            choice = i;
                            break;
                        }
                        if ki > kb + tol {
                            break;
                        }
                        if k == m && basis[i] == 2 * m {
                            choice = i;
                        }
                    }
                    choice
                }
            });
        }
        let r = best?;
        // Prefer z0 leaving among exact ties on the ratio.
        let r = {
            let ratio = t[r * nc + 2 * m + 1] / t[r * nc + enter];
            (0..m)
                .find(|&i| {
                    basis[i] == 2 * m
                        && t[i * nc + enter] > eps
                        && (t[i * nc + 2 * m + 1] / t[i * nc + enter] - ratio).abs()
                            <= 1e-12 * (1.0 + ratio.abs())
                })
                .unwrap_or(r)
        };
        pivot(&mut t, r, enter);
        leaving = basis[r];
        basis[r] = enter;
        pivots += 1;
        if leaving == 2 * m {
            let mut lambda = vec![0.0; m];
            for (i, &b) in basis.iter().enumerate() {
                if (m..2 * m).contains(&b) {
                    lambda[b - m] = t[i * nc + 2 * m + 1].max(0.0);
                }
            }
            let w = output(w_mat, q, &lambda);
            return Some(LcpSolution { lambda, w, pivots });
        }
    }
    None
}

/// Solves the LCP by enumerating the 2ᵐ complementary index sets S (λ_S = −W_SS⁻¹ q_S, λ = 0
/// off S) and keeping the first with λ ≥ −tol and w ≥ −tol (tol = 1e-12·max(1, ‖q‖_∞)); the
/// test oracle and the fallback of [`lemke`]. m ≤ 20.
pub fn enumerate(w_mat: &[f64], q: &[f64]) -> Option<LcpSolution> {
    let m = q.len();
    assert!(m <= 20, "enumeration of an LCP of size {m}");
    let tol = 1e-12 * q.iter().fold(1.0_f64, |a, &b| a.max(b.abs()));
    for mask in 0u32..(1u32 << m) {
        let s: Vec<usize> = (0..m).filter(|&i| mask & (1 << i) != 0).collect();
        let k = s.len();
        let mut lambda = vec![0.0; m];
        if k > 0 {
            let a = faer::Mat::from_fn(k, k, |i, j| w_mat[s[i] * m + s[j]]);
            let b: Vec<f64> = s.iter().map(|&i| -q[i]).collect();
            let Some(x) = solve_small(&a, &b) else {
                continue;
            };
            for (&i, &v) in s.iter().zip(&x) {
                lambda[i] = v;
            }
        }
        if lambda.iter().any(|&l| l < -tol) {
            continue;
        }
        let w = output(w_mat, q, &lambda);
        if w.iter().any(|&v| v < -tol) {
            continue;
        }
        for l in &mut lambda {
            *l = l.max(0.0);
        }
        return Some(LcpSolution {
            lambda,
            w,
            pivots: 0,
        });
    }
    None
}

/// Solves the LCP by [`lemke`], falling back to [`enumerate`] (m ≤ 16) on ray termination.
pub fn solve(w_mat: &[f64], q: &[f64]) -> Option<LcpSolution> {
    lemke(w_mat, q).or_else(|| (q.len() <= 16).then(|| enumerate(w_mat, q)).flatten())
}

/// A x = b by dense LU; `None` when A is numerically singular.
fn solve_small(a: &faer::Mat<f64>, b: &[f64]) -> Option<Vec<f64>> {
    let lu = a.partial_piv_lu();
    let u = lu.U();
    let (lo, hi) = (0..u.nrows())
        .map(|i| u[(i, i)].abs())
        .fold((f64::INFINITY, 0.0_f64), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        });
    if lo <= 1e-14 * hi {
        return None;
    }
    let mut x = faer::Col::from_fn(b.len(), |i| b[i]);
    lu.solve_in_place(x.as_mut());
    Some((0..b.len()).map(|i| x[i]).collect())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A small deterministic generator (xorshift) for random test matrices.
    fn rng(seed: &mut u64) -> f64 {
        *seed ^= *seed << 13;
        *seed ^= *seed >> 7;
        *seed ^= *seed << 17;
        (*seed >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn componentwise_counterexample_is_solved_as_an_lcp() {
        // W = [[2,1],[1,2]], q = (−1, 0.5): λ = (1/2, 0), w = (0, 1).
        let s = lemke(&[2.0, 1.0, 1.0, 2.0], &[-1.0, 0.5]).unwrap();
        assert!((s.lambda[0] - 0.5).abs() < 1e-15 && s.lambda[1] == 0.0);
        assert!(s.w[0].abs() < 1e-15 && (s.w[1] - 1.0).abs() < 1e-15);
    }

    #[test]
    fn lemke_equals_enumeration_on_random_p_matrices() {
        let mut seed = 0x9e37_79b9_7f4a_7c15_u64;
        for trial in 0..400 {
            let m = 1 + trial % 10;
            // W = A Aᵀ + m I (SPD) plus a skew part (still a P-matrix: positive definite).
            let a: Vec<f64> = (0..m * m).map(|_| rng(&mut seed) - 0.5).collect();
            let mut w = vec![0.0; m * m];
            for i in 0..m {
                for j in 0..m {
                    let aat: f64 = (0..m).map(|k| a[i * m + k] * a[j * m + k]).sum();
                    let skew = if trial % 2 == 1 {
                        0.3 * (a[i * m + j] - a[j * m + i])
                    } else {
                        0.0
                    };
                    w[i * m + j] = aat + skew + if i == j { 0.2 } else { 0.0 };
                }
            }
            let q: Vec<f64> = (0..m).map(|_| 2.0 * rng(&mut seed) - 1.0).collect();
            let l = lemke(&w, &q).expect("Lemke on a P-matrix");
            let e = enumerate(&w, &q).expect("enumeration on a P-matrix");
            for i in 0..m {
                assert!((l.lambda[i] - e.lambda[i]).abs() < 1e-10, "trial {trial}");
            }
            assert!(residual(&l.lambda, &l.w) < 1e-12, "trial {trial}");
        }
    }

    #[test]
    fn degenerate_q_terminates() {
        // q with zeros and W with two equal rows (still P on the principal minors used).
        let w = [2.0, 1.0, 0.0, 1.0, 2.0, 0.0, 0.0, 0.0, 1.0];
        for q in [[0.0, -1.0, 0.0], [-1.0, -1.0, 0.0], [0.0, 0.0, -2.0]] {
            let s = lemke(&w, &q).unwrap();
            assert!(residual(&s.lambda, &s.w) < 1e-13, "{q:?}");
            assert!(s.lambda.iter().all(|&l| l >= 0.0));
        }
        let s = lemke(&[1.0, 1.0, 1.0, 1.0], &[-1.0, -1.0]).unwrap();
        assert!(residual(&s.lambda, &s.w) < 1e-13);
    }

    #[test]
    fn nonnegative_q_needs_no_pivot() {
        let s = lemke(&[1.0, 0.0, 0.0, 1.0], &[0.0, 3.0]).unwrap();
        assert_eq!((s.pivots, s.lambda.clone()), (0, vec![0.0, 0.0]));
    }
}
