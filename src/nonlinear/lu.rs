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

use std::mem::MaybeUninit;

use faer::dyn_stack::{MemStack, StackReq};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::perm::PermRef;
use faer::traits::ComplexField;
use faer::{Mat, MatMut, MatRef, Par};

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

/// Bytes of scratch for faer's LU of an n × n matrix and for its solves with up to `columns`
/// right-hand sides on `par`, at any alignment.
fn scratch_bytes<T: ComplexField>(n: usize, columns: usize, par: Par) -> usize {
    let req = StackReq::any_of(&[
        factor::lu_in_place_scratch::<usize, T>(n, n, par, Default::default()),
        solve::solve_in_place_scratch::<usize, T>(n, columns, par),
    ]);
    req.size_bytes() + req.align_bytes()
}

/// `scratch` grown to at least `bytes` (never shrunk, so a buffer reused from one factorisation
/// to the next is allocated once).
fn grown(scratch: &mut Vec<MaybeUninit<u8>>, bytes: usize) -> &mut [MaybeUninit<u8>] {
    if scratch.len() < bytes {
        scratch.resize(bytes, MaybeUninit::uninit());
    }
    scratch.as_mut_slice()
}

impl<T: ComplexField> PackedLu<T> {
    /// The factors of the square matrix `a` (copied).
    pub fn new(a: MatRef<'_, T>) -> PackedLu<T> {
        PackedLu::in_place(a.to_owned())
    }

    /// The factors of the square matrix `a`, written over it (no copy).
    pub fn in_place(a: Mat<T>) -> PackedLu<T> {
        assert_eq!(a.nrows(), a.ncols(), "an LU of a square matrix");
        let n = a.nrows();
        let mut lu = PackedLu {
            lu: a,
            forward: vec![0usize; n],
            backward: vec![0usize; n],
        };
        lu.factor_held(faer::get_global_parallelism(), &mut Vec::new());
        lu
    }

    /// An empty (0 × 0) factorisation whose storage [`PackedLu::refactor`] sizes and reuses.
    pub fn empty() -> PackedLu<T> {
        PackedLu {
            lu: Mat::zeros(0, 0),
            forward: Vec::new(),
            backward: Vec::new(),
        }
    }

    /// Factors, over the storage of the previous factors, the n × n matrix that `fill` writes
    /// into it (its entries are those of the previous factors, or zeros when n changed), on
    /// `par` with the scratch `scratch` (grown when too small). Nothing is allocated when n is
    /// that of the previous call and `scratch` is large enough: for factorisations repeated
    /// in a loop. The factors equal [`PackedLu::new`]'s of the same matrix on the same `par`.
    pub fn refactor(
        &mut self,
        n: usize,
        par: Par,
        scratch: &mut Vec<MaybeUninit<u8>>,
        fill: impl FnOnce(&mut Mat<T>),
    ) {
        if self.lu.nrows() != n || self.lu.ncols() != n {
            self.lu = Mat::zeros(n, n);
            self.forward.resize(n, 0);
            self.backward.resize(n, 0);
        }
        fill(&mut self.lu);
        self.factor_held(par, scratch);
    }

    /// faer's LU of the held matrix, over it.
    fn factor_held(&mut self, par: Par, scratch: &mut Vec<MaybeUninit<u8>>) {
        let n = self.lu.nrows();
        let stack = grown(scratch, scratch_bytes::<T>(n, 1, par));
        factor::lu_in_place(
            self.lu.as_mut(),
            &mut self.forward,
            &mut self.backward,
            par,
            MemStack::new(stack),
            Default::default(),
        );
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
        self.solve_in_place_with(rhs, faer::get_global_parallelism(), &mut Vec::new());
    }

    /// [`PackedLu::solve_in_place`] on `par` with the scratch `scratch` (grown when too small;
    /// nothing allocated when it is large enough).
    pub fn solve_in_place_with(
        &self,
        rhs: MatMut<'_, T>,
        par: Par,
        scratch: &mut Vec<MaybeUninit<u8>>,
    ) {
        let n = self.nrows();
        let stack = grown(scratch, scratch_bytes::<T>(n, rhs.ncols(), par));
        let perm = PermRef::new_checked(&self.forward, &self.backward, n);
        solve::solve_in_place(
            self.lu.as_ref(),
            self.lu.as_ref(),
            perm,
            rhs,
            par,
            MemStack::new(stack),
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

    /// Factors refactored over reused storage (after a matrix of another order, then of the
    /// same order) and solved with reused scratch equal [`PackedLu::new`]'s to the bit, on the
    /// calling thread and on the global parallelism.
    #[test]
    fn refactored_storage_gives_the_same_factors() {
        let mut lu = PackedLu::empty();
        let mut scratch = Vec::new();
        for (round, n) in [5usize, 40, 40, 7].into_iter().enumerate() {
            let a = Mat::from_fn(n, n, |i, j| {
                noise(round * 7919 + i * 100 + j) + if i == j { 0.3 } else { 0.0 }
            });
            let b = Mat::from_fn(n, 2, |i, j| noise(31 * i + j + round));
            for par in [Par::Seq, faer::get_global_parallelism()] {
                lu.refactor(n, par, &mut scratch, |m| m.copy_from(&a));
                let mut x = b.clone();
                lu.solve_in_place_with(x.as_mut(), par, &mut scratch);
                let fresh = PackedLu::new(a.as_ref());
                let mut y = b.clone();
                fresh.solve_in_place(y.as_mut());
                assert_eq!(x, y, "order {n}, round {round}: solutions differ");
                assert_eq!(lu.row_order(), fresh.row_order(), "order {n}");
                for i in 0..n {
                    assert_eq!(lu.pivot(i), fresh.pivot(i), "order {n}, pivot {i}");
                }
            }
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
