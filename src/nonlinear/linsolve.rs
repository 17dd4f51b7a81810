//! The linear solve of a Newton step or continuation tangent, A x = b with A stored dense, and the
//! sign of det A (the orientation of a continuation tangent): either faer's dense LU with partial
//! pivoting, or — when A has a known partition into diagonal blocks whose off-block part is
//! sparse and of low rank — an exact Woodbury solve (Woodbury 1950; Hager 1989, "Updating the
//! inverse of a matrix", SIAM Review 31, eq. 1.1) on the LU factors of the diagonal blocks.
//!
//! For the harmonic balance the diagonal blocks are the harmonics (the static block of n_c rows,
//! then one block of 2n_c rows per harmonic, `docs/conventions.md` §4): the condensed dynamic
//! stiffness D̄(ω) is block-diagonal over the harmonics, and a contact element couples harmonics
//! only when its stick, slip or contact state changes within the period — an element that sticks
//! all period adds its constant stiffness to every harmonic's block, one that is open all period
//! adds nothing. So A = P + E, P the diagonal blocks, E nonzero only on the rows and columns of
//! the elements in transition. A continuation's bordered matrix [J c; bᵀ β] adds a border of k
//! rows and columns after the blocks; it is held as an identity block in P and a rank-2k term in
//! E, so the bordered matrix is solved exactly, at folds too (where J is singular but A is not).
//!
//! E is split into the connected components of its graph (rows and columns linked by an entry:
//! for a contact interface, groups of neighbouring elements in transition), and each component's
//! dense block E_k (rows R_k, columns C_k) is compressed by a column-pivoted QR to E_k = Q_k (Q_kᵀ
//! E_k) of rank r_k (the columns of R with |r_ii| > 1e-13 max |r_ii|). With U = (Q_k)_k, Vᵀ = (Q_kᵀ
//! E_k)_k, the components side by side (r = Σ r_k columns),
//!
//!   A⁻¹ b = P⁻¹ b − P⁻¹U (I_r + Vᵀ P⁻¹ U)⁻¹ Vᵀ P⁻¹ b,   det A = det P · det(I_r + Vᵀ P⁻¹ U)
//!
//! (the matrix determinant lemma), each solve checked by its backward error
//! ‖b − A x‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞) and refined; a solve that stays above
//! [`BACKWARD_ERROR`] goes to the dense LU.
//!
//! Cost for n unknowns, blocks s_b, rank r (flops): dense LU (2/3)n³; structured
//! Σ_b (2/3)s_b³ + 2 Σ_b s_b² r + 2 r Σ_k r_k |C_k| + (2/3) r³, plus the QRs (Σ_k 2|R_k||C_k|²).
//! At n_c = 690, H = 3 (n = 4830) in microslip (r ≈ 13 % of n) that is about 5× fewer; fully stuck
//! (E = 0) it is the blocks alone, (8H + 1) / (2H + 1)³ of the dense LU. [`SolverChoice::Auto`]
//! takes the cheaper path by this flop count for every matrix it sees.

use std::sync::atomic::{AtomicUsize, Ordering};

use faer::linalg::solvers::{PartialPivLu, Solve};
use faer::{Accum, Mat, MatRef};
use rayon::prelude::*;

use super::{permutation_sign, solve_dense_signed_ref};

/// Which linear solver the Newton steps and tangents use (`harmonic_balance.linear_solver`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SolverChoice {
    /// The dense LU always.
    #[default]
    Dense,
    /// The cheaper of the dense LU and the block Woodbury solve by the flop model of the module
    /// documentation, per matrix (the dense LU for systems below [`AUTO_MIN_UNKNOWNS`]).
    Auto,
    /// The block Woodbury solve whenever a block partition is known (the dense LU when a block
    /// is singular or the backward error is too large).
    Structured,
}

/// Smallest system that [`SolverChoice::Auto`] analyses: below, the dense LU costs less than a
/// millisecond.
pub const AUTO_MIN_UNKNOWNS: usize = 400;

/// Largest backward error ‖b − A x‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞) of an accepted structured solve
/// (after at most [`REFINEMENTS`] steps of iterative refinement on the same factors).
pub const BACKWARD_ERROR: f64 = 1e-12;

/// Most steps of iterative refinement of a structured solve.
pub const REFINEMENTS: usize = 2;

/// Relative threshold of the rank of a component of E (|r_ii| of its column-pivoted QR against
/// the largest).
const RANK_TOLERANCE: f64 = 1e-13;

/// Counts of the solves of the process (all [`LinearSolver`]s), for reports and benchmarks.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SolverStats {
    /// Solves by the dense LU (including fallbacks).
    pub dense: usize,
    /// Solves by the block Woodbury path.
    pub structured: usize,
    /// Structured attempts that went to the dense LU (singular block or capacitance matrix,
    /// backward error too large).
    pub fallbacks: usize,
    /// Sum of the ranks r of E over the structured solves.
    pub rank_sum: usize,
    /// Sum of the sizes of the structured systems (to compare with `rank_sum`).
    pub size_sum: usize,
}

static DENSE: AtomicUsize = AtomicUsize::new(0);
static STRUCTURED: AtomicUsize = AtomicUsize::new(0);
static FALLBACKS: AtomicUsize = AtomicUsize::new(0);
static RANK_SUM: AtomicUsize = AtomicUsize::new(0);
static SIZE_SUM: AtomicUsize = AtomicUsize::new(0);

/// The counts of every solve of this process so far.
pub fn stats() -> SolverStats {
    SolverStats {
        dense: DENSE.load(Ordering::Relaxed),
        structured: STRUCTURED.load(Ordering::Relaxed),
        fallbacks: FALLBACKS.load(Ordering::Relaxed),
        rank_sum: RANK_SUM.load(Ordering::Relaxed),
        size_sum: SIZE_SUM.load(Ordering::Relaxed),
    }
}

/// The linear solver of Newton steps and tangents: the block partition of the matrices it will
/// see (see the module documentation) and the choice of path.
#[derive(Clone, Debug, Default)]
pub struct LinearSolver {
    blocks: Vec<usize>,
    choice: SolverChoice,
}

impl LinearSolver {
    /// A solver that always uses the dense LU.
    pub fn dense() -> LinearSolver {
        LinearSolver::default()
    }

    /// A solver for matrices whose leading diagonal blocks have the sizes `blocks` (in order;
    /// rows and columns after them are a border, e.g. of a bordered continuation system; empty:
    /// no partition, dense LU).
    pub fn new(blocks: Vec<usize>, choice: SolverChoice) -> LinearSolver {
        LinearSolver { blocks, choice }
    }

    /// Solves A x = b; `None` when A is (numerically) singular or x is not finite.
    pub fn solve(&self, a: MatRef<'_, f64>, b: &[f64]) -> Option<Vec<f64>> {
        self.solve_signed(a, b).map(|(x, _)| x)
    }

    /// Solves A x = b and returns the sign (±1) of det A too.
    pub fn solve_signed(&self, a: MatRef<'_, f64>, b: &[f64]) -> Option<(Vec<f64>, f64)> {
        self.solve_path(a, b).0
    }

    /// [`LinearSolver::solve_signed`] and the path that solved (or failed).
    pub fn solve_path(
        &self,
        a: MatRef<'_, f64>,
        b: &[f64],
    ) -> (Option<(Vec<f64>, f64)>, SolvePath) {
        let n = b.len();
        let inner: usize = self.blocks.iter().sum();
        let partitioned = !self.blocks.is_empty() && inner <= n && n - inner <= 4;
        let try_structured = partitioned
            && match self.choice {
                SolverChoice::Dense => false,
                SolverChoice::Structured => true,
                SolverChoice::Auto => n >= AUTO_MIN_UNKNOWNS,
            };
        if try_structured {
            match Woodbury::factor(a, &self.blocks, self.choice == SolverChoice::Auto) {
                Decision::Dense => {}
                Decision::Failed => {
                    FALLBACKS.fetch_add(1, Ordering::Relaxed);
                }
                Decision::Structured(w) => {
                    if let Some(x) = w.solve_checked(a, b) {
                        STRUCTURED.fetch_add(1, Ordering::Relaxed);
                        RANK_SUM.fetch_add(w.rank(), Ordering::Relaxed);
                        SIZE_SUM.fetch_add(n, Ordering::Relaxed);
                        return (Some((x, w.sign)), SolvePath::Structured { rank: w.rank() });
                    }
                    FALLBACKS.fetch_add(1, Ordering::Relaxed);
                }
            }
        }
        DENSE.fetch_add(1, Ordering::Relaxed);
        (solve_dense_signed_ref(a, b), SolvePath::Dense)
    }
}

/// The path of one solve.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SolvePath {
    /// The dense LU.
    Dense,
    /// The block Woodbury solve with E of rank `rank`.
    Structured {
        /// r, the columns of U.
        rank: usize,
    },
}

/// What [`Woodbury::factor`] found.
enum Decision {
    /// The dense LU is cheaper (automatic choice).
    Dense,
    /// A block or the capacitance matrix is singular.
    Failed,
    /// The factors.
    Structured(Box<Woodbury>),
}

/// One component of E: rows, columns, and E_k = U_k V_kᵀ.
struct Piece {
    rows: Vec<usize>,
    cols: Vec<usize>,
    /// |rows| × r_k, orthonormal columns.
    u: Mat<f64>,
    /// r_k × |cols|.
    vt: Mat<f64>,
}

/// The factors of A = P + U Vᵀ (module documentation).
struct Woodbury {
    n: usize,
    /// First row of each diagonal block, then the border's.
    starts: Vec<usize>,
    /// LU of each diagonal block (the border's block is the identity).
    blocks: Vec<PartialPivLu<f64>>,
    /// The components of E and the border terms as pieces (the border's column pieces have all
    /// rows, its row pieces one row).
    pieces: Vec<Piece>,
    /// First column of each piece in U.
    offsets: Vec<usize>,
    /// X = P⁻¹ U, n × r.
    x: Mat<f64>,
    /// LU of the capacitance matrix I + Vᵀ X.
    capacitance: PartialPivLu<f64>,
    /// sign det A.
    sign: f64,
}

/// Flops of (2/3) m³ (an LU of order m).
fn lu_flops(m: usize) -> f64 {
    2.0 / 3.0 * (m as f64).powi(3)
}

/// sign det of a regular LU (sign det P · Π sign u_ii), `None` if the smallest |u_ii| ≤ 1e-15
/// max |u_ii|.
pub(crate) fn lu_sign(lu: &PartialPivLu<f64>) -> Option<f64> {
    let u = lu.U();
    let m = u.nrows();
    let (min, max) = (0..m)
        .map(|i| u[(i, i)].abs())
        .fold((f64::INFINITY, 0.0_f64), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        });
    if m > 0 && min <= 1e-15 * max {
        return None;
    }
    let negative = (0..m).filter(|&i| u[(i, i)] < 0.0).count();
    let sign = permutation_sign(lu.P().arrays().0);
    Some(if negative.is_multiple_of(2) {
        sign
    } else {
        -sign
    })
}

impl Woodbury {
    /// Splits `a` over `blocks` (and the border after them), compresses E and factorises; with
    /// `auto`, returns [`Decision::Dense`] as soon as the flop model says the dense LU is
    /// cheaper.
    fn factor(a: MatRef<'_, f64>, blocks: &[usize], auto: bool) -> Decision {
        let n = a.nrows();
        let inner: usize = blocks.iter().sum();
        let mut starts: Vec<usize> = blocks
            .iter()
            .scan(0, |s, &len| {
                let start = *s;
                *s += len;
                Some(start)
            })
            .collect();
        starts.push(inner);
        let block_of = {
            let mut b = vec![0usize; inner];
            for (k, w) in starts.windows(2).enumerate() {
                b[w[0]..w[1]].iter_mut().for_each(|v| *v = k);
            }
            b
        };
        // off-block entries of the inner part, column by column (in parallel)
        let entries: Vec<Vec<(usize, f64)>> = (0..inner)
            .into_par_iter()
            .map(|j| {
                let col = a.col(j);
                let (s, e) = (starts[block_of[j]], starts[block_of[j] + 1]);
                (0..s)
                    .chain(e..inner)
                    .filter_map(|i| (col[i] != 0.0).then_some((i, col[i])))
                    .collect()
            })
            .collect();
        // connected components: rows are nodes 0..inner, columns inner..2 inner
        let mut parent: Vec<usize> = (0..2 * inner).collect();
        fn find(p: &mut [usize], mut i: usize) -> usize {
            while p[i] != i {
                p[i] = p[p[i]];
                i = p[i];
            }
            i
        }
        for (j, col) in entries.iter().enumerate() {
            for &(i, _) in col {
                let (ri, rj) = (find(&mut parent, i), find(&mut parent, inner + j));
                if ri != rj {
                    parent[ri] = rj;
                }
            }
        }
        let mut index = vec![usize::MAX; 2 * inner];
        let mut groups: Vec<(Vec<usize>, Vec<usize>)> = Vec::new();
        let mut touched = vec![false; 2 * inner];
        for (j, col) in entries.iter().enumerate() {
            for &(i, _) in col {
                touched[i] = true;
                touched[inner + j] = true;
            }
        }
        for (node, _) in touched.iter().enumerate().filter(|(_, &t)| t) {
            let root = find(&mut parent, node);
            if index[root] == usize::MAX {
                index[root] = groups.len();
                groups.push((Vec::new(), Vec::new()));
            }
            let g = &mut groups[index[root]];
            if node < inner {
                g.0.push(node);
            } else {
                g.1.push(node - inner);
            }
        }
        let border = n - inner;
        let dense_flops = lu_flops(n);
        let blocks_flops: f64 = blocks.iter().map(|&s| lu_flops(s)).sum();
        let sq: f64 = blocks.iter().map(|&s| (s * s) as f64).sum();
        let qr_flops: f64 = groups
            .iter()
            .map(|(r, c)| 2.0 * r.len() as f64 * (c.len().min(r.len()) as f64).powi(2))
            .sum();
        if auto && blocks_flops + qr_flops > 0.5 * dense_flops {
            return Decision::Dense;
        }
        // compress each component: E_k = Q (Qᵀ E_k)
        let mut pieces: Vec<Piece> = groups
            .into_par_iter()
            .map(|(rows, cols)| {
                let mut pos = vec![usize::MAX; inner];
                rows.iter().enumerate().for_each(|(p, &i)| pos[i] = p);
                let mut e = Mat::<f64>::zeros(rows.len(), cols.len());
                for (q, &j) in cols.iter().enumerate() {
                    for &(i, v) in &entries[j] {
                        e[(pos[i], q)] = v;
                    }
                }
                let qr = e.col_piv_qr();
                let r = qr.thin_R();
                let d = r.nrows().min(r.ncols());
                let max = (0..d).map(|i| r[(i, i)].abs()).fold(0.0, f64::max);
                let rank = (0..d)
                    .filter(|&i| r[(i, i)].abs() > RANK_TOLERANCE * max)
                    .count();
                let q = qr.compute_thin_Q();
                let u = q.get(.., ..rank).to_owned();
                let vt = u.transpose() * &e;
                Piece { rows, cols, u, vt }
            })
            .collect();
        // the border: columns inner.. (minus the identity block) and rows inner.. (inner columns)
        for t in 0..border {
            let c = inner + t;
            let mut u = Mat::<f64>::zeros(n, 1);
            for i in 0..n {
                u[(i, 0)] = a[(i, c)];
            }
            u[(c, 0)] -= 1.0;
            pieces.push(Piece {
                rows: (0..n).collect(),
                cols: vec![c],
                u,
                vt: Mat::from_fn(1, 1, |_, _| 1.0),
            });
            pieces.push(Piece {
                rows: vec![c],
                cols: (0..inner).collect(),
                u: Mat::from_fn(1, 1, |_, _| 1.0),
                vt: Mat::from_fn(1, inner, |_, j| a[(c, j)]),
            });
        }
        let offsets: Vec<usize> = pieces
            .iter()
            .scan(0, |s, p| {
                let o = *s;
                *s += p.u.ncols();
                Some(o)
            })
            .collect();
        let rank: usize = pieces.iter().map(|p| p.u.ncols()).sum();
        let vx_flops: f64 = pieces
            .iter()
            .map(|p| 2.0 * (p.u.ncols() * p.cols.len() * rank) as f64)
            .sum();
        let structured_flops = blocks_flops + 2.0 * sq * rank as f64 + vx_flops + lu_flops(rank);
        if auto && structured_flops > 0.5 * dense_flops {
            return Decision::Dense;
        }
        // block factors
        let lus: Vec<Option<PartialPivLu<f64>>> = starts
            .windows(2)
            .map(|w| {
                let lu = a
                    .submatrix(w[0], w[0], w[1] - w[0], w[1] - w[0])
                    .partial_piv_lu();
                lu_sign(&lu).is_some().then_some(lu)
            })
            .collect();
        let Some(lus) = lus.into_iter().collect::<Option<Vec<_>>>() else {
            return Decision::Failed;
        };
        let mut sign: f64 = lus.iter().map(|lu| lu_sign(lu).unwrap_or(1.0)).product();
        // X = P⁻¹ U
        let mut x = Mat::<f64>::zeros(n, rank);
        for (p, &o) in pieces.iter().zip(&offsets) {
            for (q, &i) in p.rows.iter().enumerate() {
                for l in 0..p.u.ncols() {
                    x[(i, o + l)] = p.u[(q, l)];
                }
            }
        }
        for (w, lu) in starts.windows(2).zip(&lus) {
            lu.solve_in_place(x.as_mut().subrows_mut(w[0], w[1] - w[0]));
        }
        // capacitance I + Vᵀ X
        let mut c = Mat::<f64>::identity(rank, rank);
        for (p, &o) in pieces.iter().zip(&offsets) {
            let gathered = Mat::from_fn(p.cols.len(), rank, |q, l| x[(p.cols[q], l)]);
            faer::linalg::matmul::matmul(
                c.as_mut().subrows_mut(o, p.u.ncols()),
                Accum::Add,
                p.vt.as_ref(),
                gathered.as_ref(),
                1.0,
                faer::get_global_parallelism(),
            );
        }
        let capacitance = c.partial_piv_lu();
        match lu_sign(&capacitance) {
            Some(s) => sign *= s,
            None => return Decision::Failed,
        }
        Decision::Structured(Box::new(Woodbury {
            n,
            starts,
            blocks: lus,
            pieces,
            offsets,
            x,
            capacitance,
            sign,
        }))
    }

    /// r, the number of columns of U.
    fn rank(&self) -> usize {
        self.x.ncols()
    }

    /// x = A⁻¹ b by the Woodbury formula.
    fn apply(&self, b: &[f64]) -> Vec<f64> {
        let mut y = Mat::from_fn(self.n, 1, |i, _| b[i]);
        for (w, lu) in self.starts.windows(2).zip(&self.blocks) {
            lu.solve_in_place(y.as_mut().subrows_mut(w[0], w[1] - w[0]));
        }
        let mut s = Mat::<f64>::zeros(self.rank(), 1);
        for (p, &o) in self.pieces.iter().zip(&self.offsets) {
            for l in 0..p.vt.nrows() {
                s[(o + l, 0)] = p
                    .cols
                    .iter()
                    .enumerate()
                    .map(|(q, &j)| p.vt[(l, q)] * y[(j, 0)])
                    .sum();
            }
        }
        self.capacitance.solve_in_place(s.as_mut());
        faer::linalg::matmul::matmul(
            y.as_mut(),
            Accum::Add,
            self.x.as_ref(),
            s.as_ref(),
            -1.0,
            faer::get_global_parallelism(),
        );
        (0..self.n).map(|i| y[(i, 0)]).collect()
    }

    /// x = A⁻¹ b refined until its backward error is at most [`BACKWARD_ERROR`]; `None` if it
    /// is not within [`REFINEMENTS`] steps or x is not finite.
    fn solve_checked(&self, a: MatRef<'_, f64>, b: &[f64]) -> Option<Vec<f64>> {
        // ‖A‖₁ (A is read by columns) in place of ‖A‖∞: a threshold, not a bound
        let norm_a = (0..self.n)
            .into_par_iter()
            .map(|j| a.col(j).iter().map(|v| v.abs()).sum::<f64>())
            .reduce(|| 0.0, f64::max);
        let inf = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let norm_b = inf(b);
        let mut x = self.apply(b);
        for step in 0..=REFINEMENTS {
            if !x.iter().all(|v| v.is_finite()) {
                return None;
            }
            let xm = faer::ColRef::from_slice(&x);
            let mut r = faer::Col::from_fn(self.n, |i| b[i]);
            faer::linalg::matmul::matmul(
                r.as_mut(),
                Accum::Add,
                a,
                xm,
                -1.0,
                faer::get_global_parallelism(),
            );
            let r: Vec<f64> = r.iter().copied().collect();
            let eta = inf(&r) / (norm_a * inf(&x) + norm_b);
            if eta <= BACKWARD_ERROR || norm_b == 0.0 {
                return Some(x);
            }
            if step == REFINEMENTS {
                break;
            }
            let dx = self.apply(&r);
            x.iter_mut().zip(dx).for_each(|(xi, d)| *xi += d);
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Deterministic numbers in [−0.5, 0.5).
    fn noise(seed: usize) -> f64 {
        let s = (seed as u64)
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    }

    /// Blocks 6, 12, 12, 12 with a sparse coupling between two groups of rows and columns of
    /// low rank, and a border of one row and column.
    fn example(border: bool, coupling: f64) -> (Mat<f64>, Vec<usize>) {
        let blocks = vec![6, 12, 12, 12];
        let inner: usize = blocks.iter().sum();
        let n = inner + usize::from(border);
        let block_of = |i: usize| [6, 18, 30, 42].iter().position(|&e| i < e).unwrap_or(4);
        let a = Mat::from_fn(n, n, |i, j| {
            if i >= inner || j >= inner {
                return if i == j { 0.0 } else { noise(7 * i + 3 * j) };
            }
            let mut v = 0.0;
            if block_of(i) == block_of(j) {
                v += noise(i * 97 + j) + if i == j { 3.0 } else { 0.0 };
            }
            // an "element" on rows/columns {2, 9, 20, 33} coupling all blocks (rank ≤ 4)
            let el = [2usize, 9, 20, 33];
            if let (Some(p), Some(q)) = (
                el.iter().position(|&e| e == i),
                el.iter().position(|&e| e == j),
            ) {
                v += coupling * (1.0 + p as f64) * (2.0 - q as f64);
            }
            // a second, rank-2 one on {4, 15, 40}
            let el2 = [4usize, 15, 40];
            if let (Some(p), Some(q)) = (
                el2.iter().position(|&e| e == i),
                el2.iter().position(|&e| e == j),
            ) {
                v += coupling * (noise(p) * noise(q + 5) + noise(p + 9) * noise(q + 11));
            }
            v
        });
        (a, blocks)
    }

    /// The structured path gives the dense LU's solution and determinant sign (with and without
    /// a border whose corner is zero, as at a fold), with E of rank 3 + 2 (+2 for the border).
    #[test]
    fn woodbury_matches_dense() {
        for border in [false, true] {
            for coupling in [0.0, 0.3, 2.0] {
                let (a, blocks) = example(border, coupling);
                let n = a.nrows();
                let b: Vec<f64> = (0..n).map(|i| noise(1000 + i)).collect();
                let (xd, sd) = solve_dense_signed_ref(a.as_ref(), &b).unwrap();
                let solver = LinearSolver::new(blocks.clone(), SolverChoice::Structured);
                let (solved, path) = solver.solve_path(a.as_ref(), &b);
                let (xs, ss) = solved.unwrap();
                let rank = match path {
                    SolvePath::Structured { rank } => rank,
                    SolvePath::Dense => panic!("dense"),
                };
                // E's off-block part: the first element's 4 rows are in 4 blocks (its outer
                // product less the in-block diagonal has rank ≤ 4), the second's 3 (rank ≤ 3)
                let border_rank = 2 * usize::from(border);
                if coupling == 0.0 {
                    assert_eq!(rank, border_rank);
                } else {
                    assert!(rank > border_rank && rank <= 7 + border_rank, "{rank}");
                }
                let err = xs
                    .iter()
                    .zip(&xd)
                    .map(|(p, q)| (p - q).abs())
                    .fold(0.0, f64::max);
                let scale = xd.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                assert!(
                    err <= 1e-12 * scale,
                    "border {border} coupling {coupling}: {err:e}"
                );
                assert_eq!(ss, sd, "border {border} coupling {coupling}");
            }
        }
    }

    /// A matrix whose determinant changes sign as a diagonal entry crosses a threshold: the
    /// structured sign follows the dense one on both sides; Auto keeps a small system dense.
    #[test]
    fn sign_and_auto() {
        let (mut a, blocks) = example(true, 0.5);
        let n = a.nrows();
        let b: Vec<f64> = (0..n).map(|i| noise(2000 + i)).collect();
        let solver = LinearSolver::new(blocks.clone(), SolverChoice::Structured);
        let mut signs = Vec::new();
        for shift in [-8.0, -4.0, 0.0, 4.0] {
            a[(20, 20)] = 3.0 + shift;
            let (_, sd) = solve_dense_signed_ref(a.as_ref(), &b).unwrap();
            let (_, ss) = solver.solve_signed(a.as_ref(), &b).unwrap();
            assert_eq!(ss, sd, "shift {shift}");
            signs.push(sd);
        }
        assert!(signs.contains(&1.0) && signs.contains(&-1.0), "{signs:?}");
        let (solved, path) =
            LinearSolver::new(blocks, SolverChoice::Auto).solve_path(a.as_ref(), &b);
        assert!(solved.is_some());
        assert_eq!(path, SolvePath::Dense);
    }
}
