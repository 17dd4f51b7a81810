//! Small dense row-major matrices of the march (the damper has 3 DOF, matrix-defined systems and
//! reduced models a few hundred at most): matrix–vector products, inverses and spectral radii.
//! Factorisations and eigenvalues use faer.

use faer::linalg::solvers::DenseSolveCore;
use faer::Mat;

/// y = A x for row-major `a` (n×n).
pub fn matvec(a: &[f64], x: &[f64], y: &mut [f64]) {
    let n = x.len();
    for (i, yi) in y.iter_mut().enumerate() {
        let row = &a[i * n..(i + 1) * n];
        *yi = row.iter().zip(x).map(|(aij, xj)| aij * xj).sum();
    }
}

/// y += A x for row-major `a` (n×n).
pub fn matvec_add(a: &[f64], x: &[f64], y: &mut [f64]) {
    let n = x.len();
    for (i, yi) in y.iter_mut().enumerate() {
        let row = &a[i * n..(i + 1) * n];
        *yi += row.iter().zip(x).map(|(aij, xj)| aij * xj).sum::<f64>();
    }
}

/// y += α A x for row-major `a` (n×n).
pub fn matvec_scaled_add(alpha: f64, a: &[f64], x: &[f64], y: &mut [f64]) {
    let n = x.len();
    for (i, yi) in y.iter_mut().enumerate() {
        let row = &a[i * n..(i + 1) * n];
        *yi += alpha * row.iter().zip(x).map(|(aij, xj)| aij * xj).sum::<f64>();
    }
}

fn to_faer(a: &[f64], n: usize) -> Mat<f64> {
    Mat::from_fn(n, n, |i, j| a[i * n + j])
}

/// The inverse of row-major `a` (n×n) by LU with partial pivoting, or `None` when `a` is singular
/// to working precision (‖A·A⁻¹ − I‖_∞ > 1e-8 or non-finite entries).
pub fn inverse(a: &[f64], n: usize) -> Option<Vec<f64>> {
    if n == 0 {
        return Some(Vec::new());
    }
    let m = to_faer(a, n);
    let inv = m.partial_piv_lu().inverse();
    let mut out: Vec<f64> = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            out[i * n + j] = inv[(i, j)];
        }
    }
    if out.iter().any(|x| !x.is_finite()) {
        return None;
    }
    // residual check A·A⁻¹ = I
    let mut worst: f64 = 0.0;
    for i in 0..n {
        for j in 0..n {
            let s: f64 = (0..n).map(|k| a[i * n + k] * out[k * n + j]).sum();
            let target = if i == j { 1.0 } else { 0.0 };
            worst = worst.max((s - target).abs());
        }
    }
    (worst <= 1e-8).then_some(out)
}

/// An LU factorisation (partial pivoting, faer) held in buffers sized once, for a step matrix
/// factored and used within one step only (the closing step of a period in the adaptive march):
/// [`ScratchLu::factor`] and [`ScratchLu::solve`] allocate nothing.
pub struct ScratchLu {
    lu: Mat<f64>,
    rhs: Mat<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    stack: faer::dyn_stack::MemBuffer,
}

impl ScratchLu {
    /// Buffers for n × n matrices.
    pub fn new(n: usize) -> Self {
        use faer::linalg::lu::partial_pivoting::{factor, solve};
        let par = faer::Par::Seq;
        let req = factor::lu_in_place_scratch::<usize, f64>(n, n, par, Default::default())
            .or(solve::solve_in_place_scratch::<usize, f64>(n, 1, par));
        ScratchLu {
            lu: Mat::zeros(n, n),
            rhs: Mat::zeros(n, 1),
            perm: vec![0; n],
            perm_inv: vec![0; n],
            stack: faer::dyn_stack::MemBuffer::new(req),
        }
    }

    /// Factors row-major `a` (n×n); false when a pivot is zero or not finite (singular).
    pub fn factor(&mut self, a: &[f64]) -> bool {
        use faer::linalg::lu::partial_pivoting::factor;
        let n = self.lu.nrows();
        for j in 0..n {
            for i in 0..n {
                self.lu[(i, j)] = a[i * n + j];
            }
        }
        factor::lu_in_place(
            self.lu.as_mut(),
            &mut self.perm,
            &mut self.perm_inv,
            faer::Par::Seq,
            faer::dyn_stack::MemStack::new(&mut self.stack),
            Default::default(),
        );
        (0..n).all(|i| {
            let d = self.lu[(i, i)];
            d.is_finite() && d != 0.0
        })
    }

    /// x = A⁻¹ b with the last factored A.
    pub fn solve(&mut self, b: &[f64], x: &mut [f64]) {
        use faer::linalg::lu::partial_pivoting::solve;
        let n = self.lu.nrows();
        for (i, &bi) in b.iter().enumerate() {
            self.rhs[(i, 0)] = bi;
        }
        let perm = faer::perm::PermRef::new_checked(&self.perm, &self.perm_inv, n);
        solve::solve_in_place(
            self.lu.as_ref(),
            self.lu.as_ref(),
            perm,
            self.rhs.as_mut(),
            faer::Par::Seq,
            faer::dyn_stack::MemStack::new(&mut self.stack),
        );
        for (i, xi) in x.iter_mut().enumerate() {
            *xi = self.rhs[(i, 0)];
        }
    }
}

/// The spectral radius max |λ| of row-major `a` (n×n, not necessarily symmetric).
pub fn spectral_radius(a: &[f64], n: usize) -> Option<f64> {
    if n == 0 {
        return Some(0.0);
    }
    let m = to_faer(a, n);
    let ev = m.eigenvalues().ok()?;
    Some(ev.iter().map(|z| z.norm()).fold(0.0, f64::max))
}

/// The product A B of row-major n×n matrices.
pub fn matmul(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut c = vec![0.0; n * n];
    for i in 0..n {
        for k in 0..n {
            let aik = a[i * n + k];
            if aik != 0.0 {
                for j in 0..n {
                    c[i * n + j] += aik * b[k * n + j];
                }
            }
        }
    }
    c
}

/// ‖x‖_∞.
pub fn norm_inf(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_and_spectral_radius_of_small_matrices() {
        let a = [4.0, 1.0, 0.0, 2.0, 3.0, 1.0, 0.0, 1.0, 2.0];
        let inv = inverse(&a, 3).unwrap();
        let id = matmul(&a, &inv, 3);
        for i in 0..3 {
            for j in 0..3 {
                let t = if i == j { 1.0 } else { 0.0 };
                assert!((id[i * 3 + j] - t).abs() < 1e-14);
            }
        }
        assert!(inverse(&[1.0, 2.0, 2.0, 4.0], 2).is_none());
        // the scratch LU solves like the inverse
        let mut lu = ScratchLu::new(3);
        assert!(lu.factor(&a));
        let b = [1.0, -2.0, 0.5];
        let (mut x, mut y) = ([0.0; 3], [0.0; 3]);
        lu.solve(&b, &mut x);
        matvec(&inv, &b, &mut y);
        for (p, q) in x.iter().zip(&y) {
            assert!((p - q).abs() < 1e-14);
        }
        assert!(!lu.factor(&[1.0, 2.0, 0.0, 2.0, 4.0, 0.0, 0.0, 0.0, 1.0]));
        // rotation-like matrix: eigenvalues ±2i, spectral radius 2
        let r = spectral_radius(&[0.0, -2.0, 2.0, 0.0], 2).unwrap();
        assert!((r - 2.0).abs() < 1e-12);
    }
}
