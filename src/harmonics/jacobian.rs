//! Storage of the square Jacobian of a harmonic balance system: dense, or block-stored
//! ([`BlockJacobian`]) — the diagonal blocks of a partition of the unknowns (the harmonics, whose
//! coefficients the linear part D̄(ω) does not couple), the entries outside them as a sparse list
//! (contact elements whose stick, slip or contact state changes within the period), and at most
//! one border row and column after the blocks (the arc-length equation of a continuation).
//!
//! Memory of the block storage for n_c DOFs and H harmonics: n_c²(1 + 4H) numbers for the blocks
//! and three words per off-block entry, against n_c²(2H + 1)² for the dense matrix — (1 + 4H) /
//! (2H + 1)² of it (10 % at H = 3, 5 % at H = 7).

use std::ops::{Index, IndexMut};
use std::sync::Arc;

use faer::{Mat, MatMut, MatRef};

/// The value of an entry that is not stored.
static ZERO: f64 = 0.0;

/// A matrix that is block-diagonal over the partition of a [`BlockJacobian`] and is applied to
/// vectors without being formed (e.g. the condensed dynamic stiffness D̄(ω) of the harmonic
/// balance, whose matrix costs a product of order n_N² n_L per harmonic and frequency, against
/// products of order n_N² + n_L² per vector once D_LL is factorised). A [`BlockJacobian`] holds
/// one as a pending term of its diagonal blocks ([`BlockJacobian::set_pending`]): products and
/// norms include it, and [`BlockJacobian::materialize`] adds it to the blocks before they are
/// factorised.
pub trait PendingBlocks: Send + Sync + std::fmt::Debug {
    /// y += A_b x on diagonal block `b` (`x` and `y` over the block's rows).
    fn apply(&self, b: usize, x: &[f64], y: &mut [f64]);

    /// out += A_b (the block's order).
    fn add_to(&self, b: usize, out: MatMut<'_, f64>);

    /// ‖A_b‖₁ (max column sum) or an estimate of it, for the scale of backward errors.
    fn norm_1(&self, b: usize) -> f64;
}

/// A square matrix stored as dense diagonal blocks over a partition of its leading rows and
/// columns, the entries outside the blocks as a list of (row, column, value), and at most one
/// border row and column after the blocks (module documentation); optionally a block-diagonal
/// term not yet added to the blocks ([`PendingBlocks`]).
#[derive(Clone, Debug, Default)]
pub struct BlockJacobian {
    /// First row of each block, then the number of block rows.
    starts: Vec<usize>,
    /// The diagonal blocks.
    blocks: Vec<Mat<f64>>,
    /// Off-block entries of the block rows and columns; once [`BlockJacobian::coalesce`]d sorted
    /// by (column, row), each position once and every value nonzero.
    off: Vec<(usize, usize, f64)>,
    /// Whether `off` is coalesced.
    coalesced: bool,
    /// The border: its column (length of the block rows + 1, the corner last) and its row over
    /// the block columns.
    border: Option<(Vec<f64>, Vec<f64>)>,
    /// c A of a block-diagonal term not yet in `blocks` (A and the factor c).
    pending: Option<(Arc<dyn PendingBlocks>, f64)>,
}

impl BlockJacobian {
    /// The zero matrix with diagonal blocks of the sizes `sizes` and no border.
    pub fn new(sizes: &[usize]) -> BlockJacobian {
        let mut starts = Vec::with_capacity(sizes.len() + 1);
        let mut s = 0;
        for &len in sizes {
            starts.push(s);
            s += len;
        }
        starts.push(s);
        BlockJacobian {
            starts,
            blocks: sizes.iter().map(|&m| Mat::zeros(m, m)).collect(),
            off: Vec::new(),
            coalesced: true,
            border: None,
            pending: None,
        }
    }

    /// Order of the matrix (block rows and the border).
    pub fn dim(&self) -> usize {
        self.inner() + usize::from(self.border.is_some())
    }

    /// Number of rows of the diagonal blocks together.
    pub fn inner(&self) -> usize {
        *self.starts.last().unwrap_or(&0)
    }

    /// The sizes of the diagonal blocks.
    pub fn block_sizes(&self) -> Vec<usize> {
        self.blocks.iter().map(|b| b.nrows()).collect()
    }

    /// First row of each diagonal block, then the number of block rows.
    pub fn starts(&self) -> &[usize] {
        &self.starts
    }

    /// Diagonal block `b` as stored: without a pending term ([`BlockJacobian::materialize`]
    /// first to read the whole block).
    pub fn block(&self, b: usize) -> MatRef<'_, f64> {
        self.blocks[b].as_ref()
    }

    /// Sets the block-diagonal term A, added to the diagonal blocks only by
    /// [`BlockJacobian::materialize`] (until then applied in products); replaces a pending one.
    pub fn set_pending(&mut self, a: Arc<dyn PendingBlocks>) {
        self.pending = Some((a, 1.0));
    }

    /// Drops a pending term without adding it (e.g. storage kept for reuse).
    pub fn drop_pending(&mut self) {
        self.pending = None;
    }

    /// Whether a block-diagonal term is pending.
    pub fn has_pending(&self) -> bool {
        self.pending.is_some()
    }

    /// Adds the pending block-diagonal term (if any) to the diagonal blocks, in parallel over
    /// them.
    pub fn materialize(&mut self) {
        use rayon::prelude::*;
        let Some((a, c)) = self.pending.take() else {
            return;
        };
        self.blocks.par_iter_mut().enumerate().for_each(|(b, m)| {
            if c == 1.0 {
                a.add_to(b, m.as_mut());
            } else {
                let mut t = Mat::<f64>::zeros(m.nrows(), m.ncols());
                a.add_to(b, t.as_mut());
                for j in 0..m.ncols() {
                    for i in 0..m.nrows() {
                        m[(i, j)] += c * t[(i, j)];
                    }
                }
            }
        });
    }

    /// Diagonal block `b`, to write.
    pub fn block_mut(&mut self, b: usize) -> MatMut<'_, f64> {
        self.blocks[b].as_mut()
    }

    /// The block of row (or column) `i` of the block rows.
    fn block_of(&self, i: usize) -> usize {
        self.starts.partition_point(|&s| s <= i) - 1
    }

    /// Sets every entry to zero and removes the border and any pending term.
    pub fn clear(&mut self) {
        self.blocks.iter_mut().for_each(|b| b.fill(0.0));
        self.off.clear();
        self.coalesced = true;
        self.border = None;
        self.pending = None;
    }

    /// Adds `v` at (i, j) of the block rows and columns.
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        let (bi, bj) = (self.block_of(i), self.block_of(j));
        if bi == bj {
            let s = self.starts[bi];
            self.blocks[bi][(i - s, j - s)] += v;
        } else if v != 0.0 {
            self.off.push((i, j, v));
            self.coalesced = false;
        }
    }

    /// Adds the l × l matrix `values` (column-major) at the rows and columns `index` (all in
    /// the block rows): the Jacobian of one element on its DOFs.
    pub fn add_patch(&mut self, index: &[usize], values: &[f64]) {
        let l = index.len();
        let blocks: Vec<usize> = index.iter().map(|&i| self.block_of(i)).collect();
        for (c, (&gc, &bc)) in index.iter().zip(&blocks).enumerate() {
            let col = &values[c * l..(c + 1) * l];
            for ((&gr, &br), &v) in index.iter().zip(&blocks).zip(col) {
                if br == bc {
                    let s = self.starts[br];
                    self.blocks[br][(gr - s, gc - s)] += v;
                } else if v != 0.0 {
                    self.off.push((gr, gc, v));
                    self.coalesced = false;
                }
            }
        }
    }

    /// Adds the dense matrix `a` (square, of the block rows' order).
    pub fn add_dense(&mut self, a: MatRef<'_, f64>) {
        for j in 0..a.ncols() {
            for i in 0..a.nrows() {
                let v = a[(i, j)];
                if v != 0.0 {
                    self.add(i, j, v);
                }
            }
        }
    }

    /// Sorts the off-block entries by (column, row), sums repeated positions and drops exact
    /// zeros, in place: no second list and no sort buffer (an unstable sort, so repeated
    /// positions are summed in an order fixed by the list but not the order they were added).
    pub fn coalesce(&mut self) {
        if self.coalesced {
            return;
        }
        self.off.sort_unstable_by_key(|&(i, j, _)| (j, i));
        let mut kept = 0;
        for k in 0..self.off.len() {
            let (i, j, v) = self.off[k];
            if kept > 0 && self.off[kept - 1].0 == i && self.off[kept - 1].1 == j {
                self.off[kept - 1].2 += v;
            } else {
                self.off[kept] = (i, j, v);
                kept += 1;
            }
        }
        self.off.truncate(kept);
        self.off.retain(|e| e.2 != 0.0);
        self.coalesced = true;
    }

    /// The off-block entries (row, column, value), coalesced.
    pub fn off_block(&mut self) -> &[(usize, usize, f64)] {
        self.coalesce();
        &self.off
    }

    /// The off-block entries as stored (coalesced if [`BlockJacobian::coalesce`] ran since the
    /// last addition).
    pub fn off_block_stored(&self) -> (&[(usize, usize, f64)], bool) {
        (&self.off, self.coalesced)
    }

    /// Multiplies every entry of the block rows and columns by `c` (the border is unchanged).
    pub fn scale(&mut self, c: f64) {
        for b in &mut self.blocks {
            for j in 0..b.ncols() {
                b.col_mut(j).iter_mut().for_each(|v| *v *= c);
            }
        }
        self.off.iter_mut().for_each(|e| e.2 *= c);
        if let Some(p) = &mut self.pending {
            p.1 *= c;
        }
    }

    /// Appends the border: `column` (length [`BlockJacobian::inner`] + 1, the corner last) and
    /// `row` (length [`BlockJacobian::inner`]), replacing any border.
    pub fn set_border(&mut self, column: Vec<f64>, row: Vec<f64>) {
        assert!(
            column.len() == self.inner() + 1 && row.len() == self.inner(),
            "border of {} and {} entries for {} block rows",
            column.len(),
            row.len(),
            self.inner()
        );
        self.border = Some((column, row));
    }

    /// Removes and returns the border (column, row).
    pub fn take_border(&mut self) -> Option<(Vec<f64>, Vec<f64>)> {
        self.border.take()
    }

    /// The border (column, row), if any.
    pub fn border(&self) -> Option<(&[f64], &[f64])> {
        self.border.as_ref().map(|(c, r)| (&c[..], &r[..]))
    }

    /// y = A x.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        let inner = self.inner();
        let mut y = vec![0.0; self.dim()];
        for (b, w) in self.blocks.iter().zip(self.starts.windows(2)) {
            let xs = faer::ColRef::from_slice(&x[w[0]..w[1]]);
            let ys = faer::ColMut::from_slice_mut(&mut y[w[0]..w[1]]);
            faer::linalg::matmul::matmul(
                ys,
                faer::Accum::Replace,
                b.as_ref(),
                xs,
                1.0,
                faer::get_global_parallelism(),
            );
        }
        if let Some((a, c)) = &self.pending {
            for (b, w) in self.starts.windows(2).enumerate() {
                let mut t = vec![0.0; w[1] - w[0]];
                a.apply(b, &x[w[0]..w[1]], &mut t);
                y[w[0]..w[1]]
                    .iter_mut()
                    .zip(t)
                    .for_each(|(y, t)| *y += c * t);
            }
        }
        for &(i, j, v) in &self.off {
            y[i] += v * x[j];
        }
        if let Some((col, row)) = &self.border {
            let xb = x[inner];
            for (yi, c) in y.iter_mut().zip(col) {
                *yi += c * xb;
            }
            y[inner] += row.iter().zip(x).map(|(r, x)| r * x).sum::<f64>();
        }
        y
    }

    /// max_j Σ_i |a_ij|; with a pending term c A, the bound from the triangle inequality
    /// (the stored entries' column sums plus |c| ‖A_b‖₁ of the column's block, or its
    /// estimate, [`PendingBlocks::norm_1`]).
    pub fn norm_1(&self) -> f64 {
        let mut sums = vec![0.0; self.dim()];
        for (b, w) in self.blocks.iter().zip(self.starts.windows(2)) {
            for j in 0..b.ncols() {
                sums[w[0] + j] = b.col(j).iter().map(|v| v.abs()).sum();
            }
        }
        if let Some((a, c)) = &self.pending {
            for (b, w) in self.starts.windows(2).enumerate() {
                let add = c.abs() * a.norm_1(b);
                sums[w[0]..w[1]].iter_mut().for_each(|s| *s += add);
            }
        }
        for &(_, j, v) in &self.off {
            sums[j] += v.abs();
        }
        if let Some((col, row)) = &self.border {
            let inner = self.inner();
            sums[inner] = col.iter().map(|v| v.abs()).sum();
            for (s, r) in sums.iter_mut().zip(row) {
                *s += r.abs();
            }
        }
        sums.into_iter().fold(0.0, f64::max)
    }

    /// The dense matrix (with the pending term).
    pub fn to_dense(&self) -> Mat<f64> {
        let n = self.dim();
        let mut a = Mat::<f64>::zeros(n, n);
        for (k, (b, w)) in self.blocks.iter().zip(self.starts.windows(2)).enumerate() {
            let mut sub = a.as_mut().submatrix_mut(w[0], w[0], b.nrows(), b.ncols());
            if let Some((p, c)) = &self.pending {
                p.add_to(k, sub.as_mut());
                for j in 0..b.ncols() {
                    for i in 0..b.nrows() {
                        sub[(i, j)] = c * sub[(i, j)] + b[(i, j)];
                    }
                }
            } else {
                sub.copy_from(b);
            }
        }
        for &(i, j, v) in &self.off {
            a[(i, j)] += v;
        }
        if let Some((col, row)) = &self.border {
            let inner = self.inner();
            for (i, c) in col.iter().enumerate() {
                a[(i, inner)] = *c;
            }
            for (j, r) in row.iter().enumerate() {
                a[(inner, j)] = *r;
            }
        }
        a
    }

    /// A reference to entry (i, j): stored, or [`ZERO`]. Off-block entries are found by binary
    /// search once coalesced (by a scan for the first match otherwise). A pending term is not
    /// included ([`BlockJacobian::materialize`] first).
    fn entry(&self, i: usize, j: usize) -> &f64 {
        let inner = self.inner();
        if let Some((col, row)) = &self.border {
            if j == inner {
                return &col[i];
            }
            if i == inner {
                return &row[j];
            }
        }
        let (bi, bj) = (self.block_of(i), self.block_of(j));
        if bi == bj {
            let s = self.starts[bi];
            return &self.blocks[bi][(i - s, j - s)];
        }
        let found = if self.coalesced {
            self.off
                .binary_search_by_key(&(j, i), |&(r, c, _)| (c, r))
                .ok()
        } else {
            self.off.iter().position(|&(r, c, _)| r == i && c == j)
        };
        found.map_or(&ZERO, |k| &self.off[k].2)
    }
}

/// A Jacobian, dense or block-stored.
#[derive(Clone, Debug)]
pub enum Jacobian {
    /// Every entry stored.
    Dense(Mat<f64>),
    /// Diagonal blocks, sparse off-block entries and a border ([`BlockJacobian`]).
    Blocks(BlockJacobian),
}

impl Default for Jacobian {
    fn default() -> Jacobian {
        Jacobian::Dense(Mat::zeros(0, 0))
    }
}

impl Jacobian {
    /// Order of the matrix.
    pub fn dim(&self) -> usize {
        match self {
            Jacobian::Dense(a) => a.nrows(),
            Jacobian::Blocks(b) => b.dim(),
        }
    }

    /// The dense matrix, if stored so.
    pub fn as_dense(&self) -> Option<&Mat<f64>> {
        match self {
            Jacobian::Dense(a) => Some(a),
            Jacobian::Blocks(_) => None,
        }
    }

    /// The dense matrix (a copy).
    pub fn to_dense(&self) -> Mat<f64> {
        match self {
            Jacobian::Dense(a) => a.clone(),
            Jacobian::Blocks(b) => b.to_dense(),
        }
    }

    /// Adds a block-stored matrix's pending term to its blocks
    /// ([`BlockJacobian::materialize`]); nothing for a dense one.
    pub fn materialize(&mut self) {
        if let Jacobian::Blocks(b) = self {
            b.materialize();
        }
    }

    /// Sets every entry to zero (and removes a block-stored border).
    pub fn clear(&mut self) {
        match self {
            Jacobian::Dense(a) => a.fill(0.0),
            Jacobian::Blocks(b) => b.clear(),
        }
    }

    /// Multiplies every entry by `c` (a block-stored border is unchanged).
    pub fn scale(&mut self, c: f64) {
        match self {
            Jacobian::Dense(a) => {
                for j in 0..a.ncols() {
                    a.col_mut(j).iter_mut().for_each(|v| *v *= c);
                }
            }
            Jacobian::Blocks(b) => b.scale(c),
        }
    }

    /// y = A x.
    pub fn mul_vec(&self, x: &[f64]) -> Vec<f64> {
        match self {
            Jacobian::Dense(a) => {
                let mut y = faer::Col::<f64>::zeros(a.nrows());
                faer::linalg::matmul::matmul(
                    y.as_mut(),
                    faer::Accum::Replace,
                    a.as_ref(),
                    faer::ColRef::from_slice(x),
                    1.0,
                    faer::get_global_parallelism(),
                );
                y.iter().copied().collect()
            }
            Jacobian::Blocks(b) => b.mul_vec(x),
        }
    }

    /// Where a force adds its Jacobian.
    pub fn target(&mut self) -> JacobianMut<'_> {
        match self {
            Jacobian::Dense(a) => JacobianMut::Dense(a.as_mut()),
            Jacobian::Blocks(b) => JacobianMut::Blocks(b),
        }
    }
}

impl Index<(usize, usize)> for Jacobian {
    type Output = f64;

    fn index(&self, (i, j): (usize, usize)) -> &f64 {
        match self {
            Jacobian::Dense(a) => &a[(i, j)],
            Jacobian::Blocks(b) => b.entry(i, j),
        }
    }
}

impl IndexMut<(usize, usize)> for Jacobian {
    /// Dense: any entry. Block-stored: entries of the diagonal blocks and of the border only
    /// (an off-block position has no storage of its own: add with [`BlockJacobian::add`]).
    fn index_mut(&mut self, (i, j): (usize, usize)) -> &mut f64 {
        match self {
            Jacobian::Dense(a) => &mut a[(i, j)],
            Jacobian::Blocks(b) => {
                let inner = b.inner();
                let (bi, bj) = (b.block_of(i.min(inner)), b.block_of(j.min(inner)));
                if let Some((col, row)) = &mut b.border {
                    if j == inner {
                        return &mut col[i];
                    }
                    if i == inner {
                        return &mut row[j];
                    }
                }
                assert!(
                    bi == bj,
                    "({i}, {j}) is outside the diagonal blocks of a block-stored Jacobian"
                );
                let s = b.starts[bi];
                &mut b.blocks[bi][(i - s, j - s)]
            }
        }
    }
}

/// A receiver of a force's Jacobian, element by element, that stores or transforms the
/// contributions itself instead of adding them into a matrix of the force's order (e.g. the
/// projection on modal coordinates of `hbm::modal`, which never forms the physical matrix).
pub trait JacobianSink: Send {
    /// Adds the l × l matrix `values` (column-major: entry (r, c) at `c·l + r`) at the rows and
    /// columns `index` (one element's Jacobian on its DOFs' coefficients).
    fn add_patch(&mut self, index: &[usize], values: &[f64]);

    /// Adds `v` at (i, j).
    fn add_entry(&mut self, i: usize, j: usize, v: f64);
}

/// Where a force adds its Jacobian: a dense matrix, a block-stored one, or a
/// [`JacobianSink`].
pub enum JacobianMut<'a> {
    /// A dense matrix.
    Dense(MatMut<'a, f64>),
    /// A block-stored matrix.
    Blocks(&'a mut BlockJacobian),
    /// A receiver of element Jacobians.
    Sink(&'a mut (dyn JacobianSink + 'static)),
}

impl JacobianMut<'_> {
    /// A shorter-lived view of the same target.
    pub fn rb_mut(&mut self) -> JacobianMut<'_> {
        match self {
            JacobianMut::Dense(a) => JacobianMut::Dense(a.as_mut()),
            JacobianMut::Blocks(b) => JacobianMut::Blocks(b),
            JacobianMut::Sink(s) => JacobianMut::Sink(&mut **s),
        }
    }

    /// Adds `v` at (i, j).
    pub fn add(&mut self, i: usize, j: usize, v: f64) {
        match self {
            JacobianMut::Dense(a) => a[(i, j)] += v,
            JacobianMut::Blocks(b) => b.add(i, j, v),
            JacobianMut::Sink(s) => s.add_entry(i, j, v),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Block storage gives the entries, product, norm and dense copy of the same matrix
    /// assembled densely, from patches that overlap and straddle blocks.
    #[test]
    fn block_storage_matches_dense_assembly() {
        let sizes = [2, 4, 4];
        let mut b = BlockJacobian::new(&sizes);
        let mut d = Mat::<f64>::zeros(10, 10);
        let patches: [&[usize]; 3] = [&[0, 3, 7], &[1, 2, 3], &[3, 8, 9, 0]];
        for (p, idx) in patches.iter().enumerate() {
            let l = idx.len();
            let vals: Vec<f64> = (0..l * l)
                .map(|k| {
                    if k % 5 == 3 {
                        0.0
                    } else {
                        (k + 7 * p) as f64 - 4.5
                    }
                })
                .collect();
            b.add_patch(idx, &vals);
            for (c, &gc) in idx.iter().enumerate() {
                for (r, &gr) in idx.iter().enumerate() {
                    d[(gr, gc)] += vals[c * l + r];
                }
            }
        }
        b.coalesce();
        let x: Vec<f64> = (0..10).map(|i| 1.0 / (1.0 + i as f64)).collect();
        b.set_border(
            (0..11).map(|i| 0.1 * i as f64).collect(),
            (0..10).map(|j| 1.0 - 0.2 * j as f64).collect(),
        );
        let mut full = Mat::<f64>::zeros(11, 11);
        full.as_mut().submatrix_mut(0, 0, 10, 10).copy_from(&d);
        for i in 0..11 {
            full[(i, 10)] = 0.1 * i as f64;
        }
        for j in 0..10 {
            full[(10, j)] = 1.0 - 0.2 * j as f64;
        }
        let mut x11 = x.clone();
        x11.push(0.7);
        let jb = Jacobian::Blocks(b.clone());
        for i in 0..11 {
            for j in 0..11 {
                assert_eq!(jb[(i, j)], full[(i, j)], "({i}, {j})");
            }
        }
        assert_eq!(b.to_dense(), full);
        let y = b.mul_vec(&x11);
        let norm1 = (0..11)
            .map(|j| (0..11).map(|i| full[(i, j)].abs()).sum::<f64>())
            .fold(0.0, f64::max);
        assert!((b.norm_1() - norm1).abs() <= 1e-12 * norm1);
        for (i, yi) in y.iter().enumerate() {
            let e: f64 = (0..11).map(|j| full[(i, j)] * x11[j]).sum();
            assert!(
                (yi - e).abs() <= 1e-12 * (1.0 + e.abs()),
                "{i}: {yi} vs {e}"
            );
        }
        // the off-block list holds each straddling position once, none in a block
        let off = b.off_block();
        assert!(off.windows(2).all(|w| (w[0].1, w[0].0) < (w[1].1, w[1].0)));
        assert!(off
            .iter()
            .all(|&(i, j, v)| v != 0.0 && b_of(&sizes, i) != b_of(&sizes, j)));
    }

    fn b_of(sizes: &[usize], i: usize) -> usize {
        let mut s = 0;
        for (k, &len) in sizes.iter().enumerate() {
            s += len;
            if i < s {
                return k;
            }
        }
        sizes.len()
    }
}
