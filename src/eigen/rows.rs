//! Solves and sparse products with the right-hand sides stored by rows, in the factor's row
//! order: a block of k right-hand sides X (`N_dof × k`) is held as `xt = Xᵀ`, a column-major
//! `k × N_dof` array ([`RowBlock`]), so the k values of one DOF are contiguous.
//!
//! Why: faer's supernodal solve keeps X column-major; every supernode gathers and scatters its
//! off-diagonal rows once per right-hand side (k scattered cache lines per row), and the product
//! with a sparse matrix reads every matrix entry once per right-hand side. On the 112 000-DOF
//! Craig–Bampton interior of the issue-4 benchmark that indexing and the product with M_ii took
//! as much time as the dense kernels of the solve (perf). Stored by rows, a gather or scatter
//! moves one contiguous k-vector per row and the sparse products read each entry once per block.
//!
//! Symbols: `P (K − σM) Pᵀ = L Lᵀ` ([`CholeskyFactor`], held by [`super::ShiftInvert`]), `perm`/`pinv` the permutation arrays
//! (`(P v)[a] = v[perm[a]]`, `pinv[perm[a]] = a`). "Factor order" means the rows of `P v`. For
//! supernode s (columns `c..c+w` of L, off-diagonal rows R, `L_s = [L_top; L_bot]`):
//!
//! ```text
//! forward  (L Y = B):  Y_topᵀ ← Y_topᵀ L_top⁻ᵀ,  then  Yᵀ[:, R] −= Y_topᵀ L_botᵀ
//! backward (Lᵀ X = Y): X_topᵀ −= Xᵀ[:, R] L_bot, then  X_topᵀ ← X_topᵀ L_top⁻¹
//! ```
//!
//! (the column-major algorithm of faer, transposed). The simplicial factor is handled column by
//! column the same way.

use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::{SupernodalLltRef, SupernodeRef};
use faer::sparse::linalg::cholesky::{SymbolicCholesky, SymbolicCholeskyRaw};
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use faer::{Accum, MatMut, MatRef, Par};

#[cfg(test)]
use super::ShiftInvert;
use crate::error::{Error, Result};

/// A block of k right-hand sides stored by rows: `data[k·i + c]` is row i, right-hand side c
/// (`Xᵀ`, column-major `k × n`).
#[derive(Clone, Debug)]
pub struct RowBlock {
    data: Vec<f64>,
    k: usize,
    n: usize,
}

impl RowBlock {
    /// A zero block of `k` right-hand sides with `n` rows each; [`Error::Compute`] if the
    /// memory cannot be allocated.
    pub fn zeros(k: usize, n: usize) -> Result<RowBlock> {
        let mut data = Vec::new();
        data.try_reserve_exact(k * n).map_err(|_| {
            Error::Compute(format!(
                "out of memory while allocating a {k} × {n} solve block; use a machine with more \
                 memory or a smaller model"
            ))
        })?;
        data.resize(k * n, 0.0);
        Ok(RowBlock { data, k, n })
    }

    /// Number of right-hand sides k.
    pub fn k(&self) -> usize {
        self.k
    }

    /// Number of values the block can hold without reallocating.
    pub fn capacity(&self) -> usize {
        self.data.capacity()
    }

    /// Number of rows n.
    pub fn n(&self) -> usize {
        self.n
    }

    /// Keeps the allocation and sets the shape to `k × n` (k·n must not exceed the capacity
    /// the block was created with), zero-filled.
    pub fn reset(&mut self, k: usize, n: usize) {
        assert!(
            k * n <= self.data.capacity(),
            "RowBlock::reset beyond capacity"
        );
        self.data.clear();
        self.data.resize(k * n, 0.0);
        self.k = k;
        self.n = n;
    }

    /// The k values of row i.
    pub fn row(&self, i: usize) -> &[f64] {
        &self.data[self.k * i..self.k * (i + 1)]
    }

    /// The k values of row i, mutable.
    pub fn row_mut(&mut self, i: usize) -> &mut [f64] {
        &mut self.data[self.k * i..self.k * (i + 1)]
    }

    /// `Xᵀ` as a faer view (`k × n`).
    pub fn as_transposed(&self) -> MatRef<'_, f64> {
        MatRef::from_column_major_slice(&self.data, self.k, self.n)
    }

    /// `Xᵀ` as a mutable faer view (`k × n`).
    pub fn as_transposed_mut(&mut self) -> MatMut<'_, f64> {
        MatMut::from_column_major_slice_mut(&mut self.data, self.k, self.n)
    }

    /// Copies the columns of `x` (`n × k`) in, row i of `x` to row `map(i)` of the block.
    pub fn load(&mut self, x: MatRef<'_, f64>, map: impl Fn(usize) -> usize) {
        self.reset(x.ncols(), x.nrows());
        for c in 0..x.ncols() {
            let col = x.col(c);
            for i in 0..x.nrows() {
                self.data[self.k * map(i) + c] = col[i];
            }
        }
    }

    /// Copies the block out to the columns of `x` (`n × k`), row `map(i)` of the block to row i.
    pub fn store(&self, mut x: MatMut<'_, f64>, map: impl Fn(usize) -> usize) {
        for c in 0..x.ncols() {
            let mut col = x.rb_mut().col_mut(c);
            for i in 0..col.nrows() {
                col[i] = self.data[self.k * map(i) + c];
            }
        }
    }
}

/// `y += alpha · v · x` for k-vectors.
#[inline]
fn axpy(y: &mut [f64], alpha: f64, x: &[f64]) {
    for (a, b) in y.iter_mut().zip(x) {
        *a += alpha * b;
    }
}

/// A sparse Cholesky factor `P A Pᵀ = L Lᵀ` (faer's symbolic analysis and values, supernodal
/// or simplicial) with the row-stored solves of this module; owned by [`super::ShiftInvert`] and
/// detachable from it ([`super::ShiftInvert::into_factor`]).
pub struct CholeskyFactor {
    pub(super) symbolic: SymbolicCholesky<usize>,
    pub(super) l_values: Vec<f64>,
    /// Factor-order row of each original row (`pinv[perm[a]] = a`).
    pinv: Vec<usize>,
    /// Largest number of off-diagonal rows of a supernode (0 when simplicial).
    max_pattern: usize,
    /// Supernode of each factor-order row (empty when simplicial).
    supernode_of_row: Vec<usize>,
    /// Parent of each supernode in the supernodal elimination tree (`usize::MAX` at a root):
    /// the supernode of its first off-diagonal row.
    supernode_parent: Vec<usize>,
}

impl std::fmt::Debug for CholeskyFactor {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CholeskyFactor")
            .field("n_dof", &self.n_dof())
            .field("values", &self.l_values.len())
            .finish()
    }
}

impl CholeskyFactor {
    /// The factor with its symbolic analysis and numeric values.
    pub(super) fn new(symbolic: SymbolicCholesky<usize>, l_values: Vec<f64>) -> Self {
        let n = symbolic.nrows();
        let pinv = match symbolic.perm() {
            Some(p) => p.arrays().1.to_vec(),
            None => (0..n).collect(),
        };
        let mut max_pattern = 0;
        let mut supernode_of_row = Vec::new();
        let mut supernode_parent = Vec::new();
        if let SymbolicCholeskyRaw::Supernodal(s) = symbolic.raw() {
            let l = SupernodalLltRef::new(s, &l_values);
            supernode_of_row = vec![0; n];
            for sn in 0..s.n_supernodes() {
                let node = l.supernode(sn);
                let start = node.start();
                supernode_of_row[start..start + node.val().ncols()].fill(sn);
                max_pattern = max_pattern.max(node.pattern().len());
            }
            supernode_parent = (0..s.n_supernodes())
                .map(|sn| {
                    let pattern = l.supernode(sn).pattern();
                    pattern.first().map_or(usize::MAX, |&r| supernode_of_row[r])
                })
                .collect();
        }
        CholeskyFactor {
            symbolic,
            l_values,
            pinv,
            max_pattern,
            supernode_of_row,
            supernode_parent,
        }
    }

    /// The supernodes, ascending, on which `L⁻¹ b` can be nonzero when b is nonzero only in
    /// the factor-order `rows`: the union of the elimination-tree paths from the supernodes of
    /// `rows` to their roots (Gilbert and Peierls's reach, supernodal). `None` for a simplicial
    /// factor (solve over all columns).
    pub fn forward_reach(&self, rows: impl IntoIterator<Item = usize>) -> Option<Vec<usize>> {
        if self.supernode_parent.is_empty() {
            return None;
        }
        let mut marked = vec![false; self.supernode_parent.len()];
        let mut reach = Vec::new();
        for r in rows {
            let mut sn = self.supernode_of_row[r];
            while sn != usize::MAX && !marked[sn] {
                marked[sn] = true;
                reach.push(sn);
                sn = self.supernode_parent[sn];
            }
        }
        reach.sort_unstable();
        Some(reach)
    }

    /// Number of rows and columns of the factorised matrix.
    pub fn n_dof(&self) -> usize {
        self.pinv.len()
    }

    /// `pinv`: the factor-order row of each original row (`pinv[perm[a]] = a`; identity
    /// without an ordering).
    pub fn factor_rows(&self) -> &[usize] {
        &self.pinv
    }

    /// Scratch for [`Self::forward_rows`] / [`Self::backward_rows`] with k right-hand sides.
    pub fn row_scratch(&self, k: usize) -> Vec<f64> {
        vec![0.0; k * self.max_pattern]
    }

    /// `x ← L⁻¹ x` for a block in factor order (sequential). `scratch` from
    /// [`Self::row_scratch`] with at least `x.k()` right-hand sides.
    pub fn forward_rows(&self, x: &mut RowBlock, scratch: &mut [f64]) {
        self.forward_rows_in(x, None, scratch);
    }

    /// [`Self::forward_rows`] restricted to the supernodes `reach` (ascending, from
    /// [`Self::forward_reach`] of the rows where x is nonzero; all supernodes with `None`). The
    /// other rows of x must be zero on entry and stay zero: L⁻¹ b vanishes outside the reach of b.
    pub fn forward_rows_in(&self, x: &mut RowBlock, reach: Option<&[usize]>, scratch: &mut [f64]) {
        let k = x.k;
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let l = SparseColMatRef::new(s.factor(), &self.l_values);
                for j in 0..l.ncols() {
                    let (rows, vals) = (l.row_idx_of_col_raw(j), l.val_of_col(j));
                    let (head, tail) = x.data.split_at_mut(k * (j + 1));
                    let xj = &mut head[k * j..];
                    let d = vals[0].recip();
                    xj.iter_mut().for_each(|v| *v *= d);
                    for (&i, &v) in rows[1..].iter().zip(&vals[1..]) {
                        let off = k * (i - j - 1);
                        axpy(&mut tail[off..off + k], -v, xj);
                    }
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let l = SupernodalLltRef::new(s, &self.l_values);
                let mut forward = |sn: usize| forward_supernode(l.supernode(sn), x, scratch);
                match reach {
                    Some(r) => r.iter().for_each(|&sn| forward(sn)),
                    None => (0..s.n_supernodes()).for_each(forward),
                }
            }
        }
    }

    /// `x ← L⁻ᵀ x` for a block in factor order (sequential); `scratch` as for
    /// [`Self::forward_rows`].
    pub fn backward_rows(&self, x: &mut RowBlock, scratch: &mut [f64]) {
        self.backward_rows_in(x, None, scratch);
    }

    /// [`Self::backward_rows`] computed only on the supernodes `reach` (ascending, closed under
    /// ancestors, e.g. from [`Self::forward_reach`]; all with `None`): the rows of `L⁻ᵀ x` in
    /// those supernodes are exact (each depends only on its ancestors), the other rows keep
    /// their input values.
    pub fn backward_rows_in(&self, x: &mut RowBlock, reach: Option<&[usize]>, scratch: &mut [f64]) {
        let k = x.k;
        match self.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let l = SparseColMatRef::new(s.factor(), &self.l_values);
                for j in (0..l.ncols()).rev() {
                    let (rows, vals) = (l.row_idx_of_col_raw(j), l.val_of_col(j));
                    let (head, tail) = x.data.split_at_mut(k * (j + 1));
                    let xj = &mut head[k * j..];
                    for (&i, &v) in rows[1..].iter().zip(&vals[1..]) {
                        let off = k * (i - j - 1);
                        axpy(xj, -v, &tail[off..off + k]);
                    }
                    let d = vals[0].recip();
                    xj.iter_mut().for_each(|v| *v *= d);
                }
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let l = SupernodalLltRef::new(s, &self.l_values);
                let mut backward = |sn: usize| backward_supernode(l.supernode(sn), x, scratch);
                match reach {
                    Some(r) => r.iter().rev().for_each(|&sn| backward(sn)),
                    None => (0..s.n_supernodes()).rev().for_each(backward),
                }
            }
        }
    }

    /// `x ← (L Lᵀ)⁻¹ x = P (K − σM)⁻¹ Pᵀ x` for a block in factor order (sequential).
    pub fn solve_rows(&self, x: &mut RowBlock, scratch: &mut [f64]) {
        self.forward_rows(x, scratch);
        self.backward_rows(x, scratch);
    }
}

/// One supernode of the forward sweep: `Y_topᵀ ← Y_topᵀ L_top⁻ᵀ`, then
/// `Yᵀ[:, R] −= Y_topᵀ L_botᵀ`. The update is formed as `L_bot Y_top` (|R| × k, column-major in
/// `scratch`): with the long dimension |R| as the product's row count it runs about 1.6× faster
/// than `Y_topᵀ L_botᵀ` (k × |R|) for k = 64 (measured on the issue-4 benchmark).
fn forward_supernode(node: SupernodeRef<'_, usize, f64>, x: &mut RowBlock, scratch: &mut [f64]) {
    let k = x.k;
    let (start, pattern, ls) = (node.start(), node.pattern(), node.val());
    let w = ls.ncols();
    let (top, bot) = ls.split_at_row(w);
    let mut xt = x.as_transposed_mut();
    let mut x_top = xt.rb_mut().subcols_mut(start, w);
    solve_lower_triangular_in_place(top, x_top.rb_mut().transpose_mut(), Par::Seq);
    let p = pattern.len();
    if p == 0 {
        return;
    }
    let tmp = &mut scratch[..k * p];
    matmul(
        MatMut::from_column_major_slice_mut(tmp, p, k),
        Accum::Replace,
        bot,
        x_top.rb().transpose(),
        1.0,
        Par::Seq,
    );
    for (idx, &i) in pattern.iter().enumerate() {
        let xi = &mut x.data[k * i..k * (i + 1)];
        for (v, t) in xi.iter_mut().zip(tmp[idx..].iter().step_by(p)) {
            *v -= t;
        }
    }
}

/// One supernode of the backward sweep: `X_topᵀ −= Xᵀ[:, R] L_bot`, then
/// `X_topᵀ ← X_topᵀ L_top⁻¹`.
fn backward_supernode(node: SupernodeRef<'_, usize, f64>, x: &mut RowBlock, scratch: &mut [f64]) {
    let k = x.k;
    let (start, pattern, ls) = (node.start(), node.pattern(), node.val());
    let w = ls.ncols();
    let (top, bot) = ls.split_at_row(w);
    if !pattern.is_empty() {
        let tmp = &mut scratch[..k * pattern.len()];
        for (idx, &i) in pattern.iter().enumerate() {
            tmp[k * idx..k * (idx + 1)].copy_from_slice(&x.data[k * i..k * (i + 1)]);
        }
        let tmp_mat = MatRef::from_column_major_slice(tmp, k, pattern.len());
        let mut xt = x.as_transposed_mut();
        matmul(
            xt.rb_mut().subcols_mut(start, w),
            Accum::Add,
            tmp_mat,
            bot,
            -1.0,
            Par::Seq,
        );
    }
    let mut xt = x.as_transposed_mut();
    let x_top = xt.rb_mut().subcols_mut(start, w);
    solve_upper_triangular_in_place(top.transpose(), x_top.transpose_mut(), Par::Seq);
}

/// `y += alpha · (P A Pᵀ) x` for a symmetric sparse `a` (both triangles stored, original row
/// order) and blocks x, y in factor order (`pinv` from [`CholeskyFactor::factor_rows`]): row
/// `pinv[j]` of y gathers column j of `a`. Reads each entry of `a` once for the whole block.
pub fn symmetric_product_rows(
    y: &mut RowBlock,
    a: SparseColMatRef<'_, usize, f64>,
    pinv: &[usize],
    x: &RowBlock,
    alpha: f64,
) {
    let k = x.k;
    for j in 0..a.ncols() {
        let yj = y.row_mut(pinv[j]);
        for (&i, &v) in a.row_idx_of_col_raw(j).iter().zip(a.val_of_col(j)) {
            axpy(yj, alpha * v, &x.data[k * pinv[i]..k * (pinv[i] + 1)]);
        }
    }
    debug_assert_eq!(y.k, k);
}

/// `out += alpha · aᵀ X` for a sparse `a` (`n × m`) whose rows are already in the block's row
/// order, X stored by rows (`n × k`), `out` dense `m × k`.
pub fn transpose_product_rows(
    mut out: MatMut<'_, f64>,
    a: SparseColMatRef<'_, usize, f64>,
    x: &RowBlock,
    alpha: f64,
) {
    let k = x.k;
    let mut acc = vec![0.0; k];
    for r in 0..a.ncols() {
        acc.fill(0.0);
        for (&i, &v) in a.row_idx_of_col_raw(r).iter().zip(a.val_of_col(r)) {
            axpy(&mut acc, v, x.row(i));
        }
        for (c, &s) in acc.iter().enumerate() {
            out[(r, c)] += alpha * s;
        }
    }
}

/// `x[i, c] = alpha · a[i, first + c]` for the k columns `first..first + k` of a sparse `a`
/// whose rows are in the block's row order (x zero on entry).
pub fn scatter_rows(
    x: &mut RowBlock,
    a: SparseColMatRef<'_, usize, f64>,
    first: usize,
    alpha: f64,
) {
    let k = x.k;
    for c in 0..k {
        for (&i, &v) in a
            .row_idx_of_col_raw(first + c)
            .iter()
            .zip(a.val_of_col(first + c))
        {
            x.data[k * i + c] = alpha * v;
        }
    }
}

/// `a` with row i moved to row `new_row[i]` (rows sorted again within each column).
pub fn renumber_rows(
    a: SparseColMatRef<'_, usize, f64>,
    new_row: &[usize],
) -> SparseColMat<usize, f64> {
    let mut col_ptr = Vec::with_capacity(a.ncols() + 1);
    col_ptr.push(0usize);
    let mut rows = Vec::with_capacity(a.compute_nnz());
    let mut vals = Vec::with_capacity(a.compute_nnz());
    let mut entries: Vec<(usize, f64)> = Vec::new();
    for j in 0..a.ncols() {
        entries.clear();
        entries.extend(
            a.row_idx_of_col_raw(j)
                .iter()
                .zip(a.val_of_col(j))
                .map(|(&i, &v)| (new_row[i], v)),
        );
        entries.sort_unstable_by_key(|e| e.0);
        rows.extend(entries.iter().map(|e| e.0));
        vals.extend(entries.iter().map(|e| e.1));
        col_ptr.push(rows.len());
    }
    SparseColMat::new(
        SymbolicSparseColMat::new_checked(a.nrows(), a.ncols(), col_ptr, None, rows),
        vals,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::eigen::shift_invert::tests::lattice;
    use faer::sparse::linalg::matmul::sparse_dense_matmul;
    use faer::Mat;

    fn pseudo_random(rows: usize, cols: usize) -> Mat<f64> {
        Mat::from_fn(rows, cols, |i, j| ((i * 7 + j * 13) % 17) as f64 - 8.0)
    }

    /// solve_rows against faer's column-major solve (and the identity K X = B), for a simplicial
    /// (small) and a supernodal (larger) factor; forward then backward must equal the full solve.
    fn check_solve(n: usize, supernodal: bool) {
        const COLS: usize = 5;
        let k = lattice(n, 0.5);
        let si = ShiftInvert::new(k.as_ref(), k.as_ref(), 0.0).unwrap();
        assert_eq!(
            matches!(
                si.factor().symbolic.raw(),
                SymbolicCholeskyRaw::Supernodal(_)
            ),
            supernodal,
            "n = {n}: unexpected factor type"
        );
        let b = pseudo_random(k.nrows(), COLS);
        let mut reference = b.clone();
        si.solve_in_place(reference.as_mut()).unwrap();
        let pinv = si.factor().factor_rows().to_vec();
        let mut x = RowBlock::zeros(COLS, k.nrows()).unwrap();
        x.load(b.as_ref(), |i| pinv[i]);
        let factor = si.into_factor();
        let mut scratch = factor.row_scratch(COLS);
        factor.solve_rows(&mut x, &mut scratch);
        let mut got = Mat::<f64>::zeros(k.nrows(), COLS);
        x.store(got.as_mut(), |i| pinv[i]);
        let scale = reference.norm_max();
        assert!((&got - &reference).norm_max() <= 1e-13 * scale, "n = {n}");
        let residual = &k * &got - &b;
        assert!(residual.norm_max() <= 1e-10 * b.norm_max(), "n = {n}");
    }

    #[test]
    fn row_solves_match_column_solves_simplicial() {
        check_solve(4, false);
    }

    #[test]
    fn row_solves_match_column_solves_supernodal() {
        check_solve(16, true);
    }

    // A forward sweep restricted to the reach of a sparse right-hand side equals the full sweep
    // bit for bit (the skipped supernodes would only add zeros) and is nonzero only on the reach.
    #[test]
    fn forward_sweep_on_the_reach_equals_the_full_sweep() {
        let a = lattice(16, 0.5);
        let factor = ShiftInvert::new(a.as_ref(), a.as_ref(), 0.0)
            .unwrap()
            .into_factor();
        let n = factor.n_dof();
        let rows = [3usize, 17, 400].map(|i| factor.factor_rows()[i]);
        let mut full = RowBlock::zeros(2, n).unwrap();
        for (c, &r) in rows.iter().enumerate() {
            full.row_mut(r)[c % 2] = 1.0 + c as f64;
        }
        let mut part = full.clone();
        let reach = factor.forward_reach(rows).expect("supernodal factor");
        assert!(!reach.is_empty() && reach.len() < factor.supernode_parent.len());
        assert!(reach.windows(2).all(|w| w[0] < w[1]));
        let mut scratch = factor.row_scratch(2);
        factor.forward_rows(&mut full, &mut scratch);
        factor.forward_rows_in(&mut part, Some(&reach), &mut scratch);
        assert_eq!(full.data, part.data);
        let nonzero = (0..n)
            .filter(|&i| full.row(i).iter().any(|&v| v != 0.0))
            .count();
        let in_reach = reach_rows(&factor, &reach);
        assert!(
            nonzero <= in_reach && in_reach < n,
            "{nonzero} {in_reach} {n}"
        );
    }

    /// Number of factor rows (columns of L) in the supernodes `reach` of a supernodal factor.
    fn reach_rows(factor: &CholeskyFactor, reach: &[usize]) -> usize {
        match factor.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(_) => factor.n_dof(),
            SymbolicCholeskyRaw::Supernodal(s) => {
                let l = SupernodalLltRef::new(s, &factor.l_values);
                reach.iter().map(|&sn| l.supernode(sn).val().ncols()).sum()
            }
        }
    }

    // (P A Pᵀ) X in factor order against faer's sparse × dense product in the original order.
    #[test]
    fn symmetric_product_in_factor_order() {
        let a = lattice(6, 1.5);
        let si = ShiftInvert::new(a.as_ref(), a.as_ref(), 0.0).unwrap();
        let pinv = si.factor().factor_rows().to_vec();
        let x = pseudo_random(a.nrows(), 3);
        let mut reference = Mat::<f64>::zeros(a.nrows(), 3);
        sparse_dense_matmul(
            reference.as_mut(),
            Accum::Replace,
            a.as_ref(),
            x.as_ref(),
            2.0,
            Par::Seq,
        );
        let mut xr = RowBlock::zeros(3, a.nrows()).unwrap();
        xr.load(x.as_ref(), |i| pinv[i]);
        let mut y = RowBlock::zeros(3, a.nrows()).unwrap();
        symmetric_product_rows(&mut y, a.as_ref(), &pinv, &xr, 2.0);
        let mut got = Mat::<f64>::zeros(a.nrows(), 3);
        y.store(got.as_mut(), |i| pinv[i]);
        assert!((&got - &reference).norm_max() <= 1e-13 * reference.norm_max());
    }

    // aᵀ X and the scattered columns of a, with a's rows renumbered, against dense products.
    #[test]
    fn transpose_product_and_scatter_with_renumbered_rows() {
        let a = lattice(3, 0.0); // 27 × 27, used as a rectangular 27 × 27 block
        let new_row: Vec<usize> = (0..27).map(|i| (i * 5) % 27).collect();
        let ar = renumber_rows(a.as_ref(), &new_row);
        let x = pseudo_random(27, 4);
        let mut xr = RowBlock::zeros(4, 27).unwrap();
        xr.load(x.as_ref(), |i| new_row[i]);
        let mut got = Mat::<f64>::from_fn(27, 4, |_, _| 1.0);
        transpose_product_rows(got.as_mut(), ar.as_ref(), &xr, -2.0);
        let dense = a.to_dense();
        let reference = Mat::<f64>::from_fn(27, 4, |_, _| 1.0) - 2.0 * dense.transpose() * &x;
        assert!((&got - &reference).norm_max() <= 1e-13 * reference.norm_max());
        let mut s = RowBlock::zeros(4, 27).unwrap();
        scatter_rows(&mut s, ar.as_ref(), 10, 3.0);
        let mut back = Mat::<f64>::zeros(27, 4);
        s.store(back.as_mut(), |i| new_row[i]);
        let expected = 3.0 * dense.get(.., 10..14);
        assert_eq!((&back - &expected).norm_max(), 0.0);
    }
}
