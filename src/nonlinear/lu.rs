//! The LU factorisation with partial pivoting, P A = L U (Golub & Van Loan 2013, Algorithm
//! 3.4.1), stored packed as LAPACK's `getrf` stores it: the unit lower factor L below the
//! diagonal and the upper factor U on and above it, in one n × n matrix, with the row
//! permutation P.
//!
//! faer's `PartialPivLu` keeps L and U as two n × n matrices, twice the memory of the matrix
//! factorised (and three copies for a moment while it splits them). [`PackedLu`] runs faer's own
//! factorisation (`lu_in_place`) and triangular solves (`solve_in_place`, which read only the
//! strictly lower part as L and the upper part as U), so its solutions equal those of
//! `PartialPivLu` to the bit.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::perm::PermRef;
use faer::traits::ComplexField;
use faer::{Mat, MatMut, MatRef};

/// P A = L U of a square matrix A, L and U in one matrix.
#[derive(Clone, Debug)]
pub struct PackedLu<T> {
    /// L strictly below the diagonal (its unit diagonal not stored), U on and above it.
    lu: Mat<T>,
    /// The row permutation: row i of P A is row `forward[i]` of A.
    forward: Vec<usize>,
    /// The inverse of `forward`.
    backward: Vec<usize>,
}

impl<T: ComplexField> PackedLu<T> {
    /// The factors of the square matrix `a` (copied).
    pub fn new(a: MatRef<'_, T>) -> PackedLu<T> {
        PackedLu::in_place(a.to_owned())
    }

    /// The factors of the square matrix `a`, written over it (no copy).
    pub fn in_place(mut a: Mat<T>) -> PackedLu<T> {
        assert_eq!(a.nrows(), a.ncols(), "an LU of a square matrix");
        let n = a.nrows();
        let par = faer::get_global_parallelism();
        let mut forward = vec![0usize; n];
        let mut backward = vec![0usize; n];
        let mut scratch = MemBuffer::new(factor::lu_in_place_scratch::<usize, T>(
            n,
            n,
            par,
            Default::default(),
        ));
        factor::lu_in_place(
            a.as_mut(),
            &mut forward,
            &mut backward,
            par,
            MemStack::new(&mut scratch),
            Default::default(),
        );
        PackedLu {
            lu: a,
            forward,
            backward,
        }
    }

    /// n, the order of A.
    pub fn nrows(&self) -> usize {
        self.lu.nrows()
    }

    /// u_ii, the i-th pivot (diagonal entry of U).
    pub fn pivot(&self, i: usize) -> T {
        self.lu[(i, i)].clone()
    }

    /// The row permutation as the image of 0..n: row i of P A is row `row_order()[i]` of A.
    pub fn row_order(&self) -> &[usize] {
        &self.forward
    }

    /// X = A⁻¹ B in place of B (any number of columns).
    pub fn solve_in_place(&self, rhs: MatMut<'_, T>) {
        let n = self.nrows();
        let par = faer::get_global_parallelism();
        let mut scratch = MemBuffer::new(solve::solve_in_place_scratch::<usize, T>(
            n,
            rhs.ncols(),
            par,
        ));
        let perm = PermRef::new_checked(&self.forward, &self.backward, n);
        solve::solve_in_place(
            self.lu.as_ref(),
            self.lu.as_ref(),
            perm,
            rhs,
            par,
            MemStack::new(&mut scratch),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::c64;
    use faer::linalg::solvers::Solve;

    /// A deterministic pseudo-random number in [−1, 1).
    fn noise(seed: usize) -> f64 {
        let x = (seed as f64 * 12.9898 + 78.233).sin() * 43758.5453;
        2.0 * (x - x.floor()) - 1.0
    }

    /// The packed factors solve as faer's `PartialPivLu` does, to the bit, for real and complex
    /// matrices of orders that take faer's blocked and recursive paths (and the same pivots and
    /// row order), with several right-hand sides.
    #[test]
    fn packed_matches_faer_to_the_bit() {
        for n in [1usize, 7, 64, 150] {
            let a = Mat::from_fn(n, n, |i, j| {
                noise(i * 1000 + j) + if i == j { 0.5 } else { 0.0 }
            });
            let b = Mat::from_fn(n, 3, |i, j| noise(7 * i + 100_000 + j));
            let packed = PackedLu::new(a.as_ref());
            let faer_lu = a.partial_piv_lu();
            let mut x = b.clone();
            packed.solve_in_place(x.as_mut());
            let y = faer_lu.solve(&b);
            assert_eq!(x, y, "order {n}: real solutions differ");
            assert_eq!(packed.row_order(), faer_lu.P().arrays().0, "order {n}");
            for i in 0..n {
                assert_eq!(packed.pivot(i), faer_lu.U()[(i, i)], "order {n}, pivot {i}");
            }
            let ac = Mat::from_fn(n, n, |i, j| c64::new(a[(i, j)], noise(i + 3 * j + 55_555)));
            let bc = Mat::from_fn(n, 2, |i, j| c64::new(b[(i, j)], -b[(i, j + 1)]));
            let mut xc = bc.clone();
            PackedLu::in_place(ac.clone()).solve_in_place(xc.as_mut());
            assert_eq!(
                xc,
                ac.partial_piv_lu().solve(&bc),
                "order {n}: complex solutions differ"
            );
        }
    }

    /// A x = b to rounding (the residual is checked independently of faer's solver).
    #[test]
    fn packed_solves() {
        let n = 40;
        let a = Mat::from_fn(n, n, |i, j| {
            noise(31 * i + j) + if i == j { 3.0 } else { 0.0 }
        });
        let b = Mat::from_fn(n, 1, |i, _| noise(i + 999));
        let mut x = b.clone();
        PackedLu::new(a.as_ref()).solve_in_place(x.as_mut());
        let r = &a * &x - &b;
        let worst = (0..n).map(|i| r[(i, 0)].abs()).fold(0.0, f64::max);
        assert!(worst < 1e-13, "residual {worst:e}");
    }
}
