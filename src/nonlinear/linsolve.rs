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
//! for a contact interface, groups of neighbouring elements in transition), each component's
//! rows into the diagonal blocks they lie in, and each such dense part E_kb (rows R_kb of block b,
//! columns C_k) is compressed by a column-pivoted QR to E_kb = Q_kb (Q_kbᵀ E_kb) of rank r_kb
//! (the columns of R with |r_ii| > 1e-13 max |r_ii|). With U = (Q_kb), Vᵀ = (Q_kbᵀ E_kb), the
//! parts side by side (r = Σ r_kb columns),
//!
//!   A⁻¹ b = P⁻¹ b − P⁻¹U (I_r + Vᵀ P⁻¹ U)⁻¹ Vᵀ P⁻¹ b,   det A = det P · det(I_r + Vᵀ P⁻¹ U)
//!
//! (the matrix determinant lemma). Each column of U lies in one diagonal block, and so does its
//! column of X = P⁻¹U: X is formed and stored block by block (P_b⁻¹ on the r_b columns of block
//! b: 2 s_b² r_b flops and s_b r_b numbers, against 2 n s_b r and n r for columns that span
//! every block). A contact element's Jacobian is Bᵀ K(t) B (B its interpolation of the
//! element's DOFs to the contact point's three directions; SAMA paper eq. 26), so its rows in one
//! harmonic have at most the rank of B's, and Σ_b r_kb stays close to rank E_k (4–10 % above it
//! on the bundled sector, `docs/performance.md`). Each solve is checked by its backward error
//! ‖b − A x‖∞ / (‖A‖∞ ‖x‖∞ + ‖b‖∞) and refined; a solve that stays above
//! [`BACKWARD_ERROR`] goes to the dense LU.
//!
//! The matrix is either dense or block-stored ([`crate::harmonics::BlockJacobian`]: the
//! diagonal blocks, the off-block entries as a list, the border as a row and a column); the
//! structured path reads the blocks and E's entries directly from the block storage, so that
//! no n × n matrix is formed (the dense LU of a block-stored matrix works on a dense copy).
//! [`LinearSolver::factor_solve`] returns the factors, and [`LinearSolver::solve_near`] solves
//! a nearby matrix on them by iterative refinement (the continuation tangent at a converged
//! point on the factors of the last Newton step). [`LinearSolver::solve_krylov`] solves a
//! nearby matrix A by GMRES (Saad & Schultz 1986; Saad 2003, "Iterative methods for sparse
//! linear systems", Alg. 9.5) right-preconditioned by the factors F of an earlier one: when A
//! differs from F by the stiffness of the few contact elements that changed regime, F⁻¹A is the
//! identity plus a matrix of low rank and GMRES converges in about as many iterations as that
//! rank; each costs one solve on F and one product with A (the block-stored A is not factorised
//! again). Newton ([`super::newton_core`]) solves its steps after the first this way (a
//! continuation corrector its first as well, on the factors of the previous point's tangent
//! system) and factorises again only when GMRES needs more than [`KRYLOV_ITERATIONS`] iterations (or more than
//! [`KRYLOV_REFRESH`] at the step before); every Krylov solution is checked by the same backward
//! error as a direct one. [`LinearSolver::solve_krylov_signed`] adds the sign of det A from
//! the Hessenberg matrix of the GMRES cycle (the continuation tangent where the refinement of
//! [`LinearSolver::solve_near`] does not converge).
//!
//! Cost for n unknowns, blocks s_b, r_b columns of U in block b, r = Σ_b r_b (flops): dense LU
//! (2/3)n³; structured Σ_b (2/3)s_b³ + 2 Σ_b s_b² r_b + 2 Σ_kb r_kb Σ_b' |C_k ∩ b'| r_b' +
//! (2/3) r³ (block LUs, P⁻¹U, Vᵀ X and the capacitance LU), plus the QRs
//! (Σ_kb 2|R_kb||C_k| min(|R_kb|, |C_k|)); a border column adds 2 Σ_b s_b² to P⁻¹U. Fully stuck
//! (E = 0) it is the blocks alone, (8H + 1) / (2H + 1)³ of the dense LU. [`SolverChoice::Auto`]
//! takes the cheaper path by this flop count for every matrix it sees.

use std::cell::Cell;
use std::sync::Mutex;

use faer::{Accum, Mat, MatRef};
use rayon::prelude::*;

use super::lu::PackedLu;
use super::{permutation_sign, solve_dense_signed_ref, Linearization};
use crate::harmonics::{BlockJacobian, Jacobian};

/// Which linear solver the Newton steps and tangents use (`harmonic_balance.linear_solver`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SolverChoice {
    /// The dense LU always, on a dense Jacobian.
    Dense,
    /// The cheaper of the dense LU and the block Woodbury solve by the flop model of the module
    /// documentation, per matrix; systems of at least [`AUTO_MIN_UNKNOWNS`] unknowns with a
    /// block partition store their Jacobian by blocks ([`BlockJacobian`]), smaller ones dense
    /// (and are solved by the dense LU).
    #[default]
    Auto,
    /// The block Woodbury solve whenever a block partition is known, on a block-stored Jacobian
    /// (the dense LU when a block is singular or the backward error is too large).
    Structured,
}

/// Smallest system that [`SolverChoice::Auto`] analyses: below, the dense LU costs less than a
/// millisecond.
pub const AUTO_MIN_UNKNOWNS: usize = 400;

/// Largest backward error ‖b − A x‖∞ / (‖A‖₁ ‖x‖∞ + ‖b‖∞) of an accepted structured solve
/// (after at most [`REFINEMENTS`] steps of iterative refinement on the same factors), and of a
/// solve on the factors of a nearby matrix ([`LinearSolver::solve_near`]).
pub const BACKWARD_ERROR: f64 = 1e-12;

/// Most steps of iterative refinement of a structured solve.
pub const REFINEMENTS: usize = 2;

/// Most steps of iterative refinement of a solve on the factors of a nearby matrix.
pub const NEAR_REFINEMENTS: usize = 4;

/// Most GMRES iterations of a solve on the factors of a nearby matrix
/// ([`LinearSolver::solve_krylov`]): beyond, the matrix is factorised.
pub const KRYLOV_ITERATIONS: usize = 30;

/// A Krylov solve of more GMRES iterations than this tells Newton to factorise at its next
/// step (the factors have drifted from the matrices).
pub const KRYLOV_REFRESH: usize = 10;

/// Relative threshold of the rank of a component of E (|r_ii| of its column-pivoted QR against
/// the largest).
const RANK_TOLERANCE: f64 = 1e-13;

/// Counts of the solves of a thread (all [`LinearSolver`]s), for reports and benchmarks.
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
    /// Factorisations (dense LUs and block factorisations with their capacitance matrix);
    /// the solves beyond them reused factors ([`LinearSolver::solve_near`],
    /// [`LinearSolver::solve_krylov`]).
    pub factorizations: usize,
    /// Solves by GMRES on the factors of an earlier matrix ([`LinearSolver::solve_krylov`]).
    pub krylov: usize,
    /// GMRES iterations of those solves.
    pub krylov_iterations: usize,
}

thread_local! {
    static STATS: Cell<SolverStats> = const { Cell::new(SolverStats {
        dense: 0,
        structured: 0,
        fallbacks: 0,
        rank_sum: 0,
        size_sum: 0,
        factorizations: 0,
        krylov: 0,
        krylov_iterations: 0,
    }) };
}

/// The counts of the solves run on this thread so far (a Newton iteration solves on the thread
/// that runs it; a curve traced beside others in a rayon pool may include theirs when its
/// thread helps with them while waiting).
pub fn stats() -> SolverStats {
    STATS.with(Cell::get)
}

/// Changes this thread's counts.
fn record(f: impl FnOnce(&mut SolverStats)) {
    STATS.with(|s| {
        let mut v = s.get();
        f(&mut v);
        s.set(v);
    });
}

/// Counts one solve on `path` of a system of `n` unknowns.
fn count(path: SolvePath, n: usize) {
    record(|s| match path {
        SolvePath::Dense => s.dense += 1,
        SolvePath::Structured { rank } => {
            s.structured += 1;
            s.rank_sum += rank;
            s.size_sum += n;
        }
    });
}

/// The linear solver of Newton steps and tangents: the block partition of the matrices it will
/// see (see the module documentation) and the choice of path; it keeps one block-stored matrix
/// and up to two dense ones handed back by [`LinearSolver::recycle`] for the next
/// [`LinearSolver::linearization`] or [`LinearSolver::dense_matrix`] (no allocation of the
/// matrices per evaluation).
#[derive(Debug, Default)]
pub struct LinearSolver {
    blocks: Vec<usize>,
    choice: SolverChoice,
    spare: Mutex<Option<BlockJacobian>>,
    /// Dense matrices handed back ([`LinearSolver::recycle`]), at most `SPARE_DENSE`, for
    /// the next [`LinearSolver::linearization`] or [`LinearSolver::dense_matrix`].
    spare_dense: Mutex<Vec<Mat<f64>>>,
}

/// Most dense matrices a [`LinearSolver`] keeps for reuse: a Newton step of a continuation
/// corrector holds two (the Jacobian and its bordered matrix).
const SPARE_DENSE: usize = 2;

impl Clone for LinearSolver {
    /// The same partition and choice (without the spare storage).
    fn clone(&self) -> LinearSolver {
        LinearSolver::new(self.blocks.clone(), self.choice)
    }
}

/// Factors of a matrix from [`LinearSolver::factor_solve`], to solve further right-hand sides
/// with ([`Factored::solve`], [`LinearSolver::solve_near`], [`LinearSolver::solve_krylov`]).
/// A clone shares the factors.
#[derive(Clone)]
pub struct Factored {
    kind: std::sync::Arc<FactorKind>,
    n: usize,
}

enum FactorKind {
    Dense { lu: PackedLu<f64>, sign: f64 },
    Structured(Box<Woodbury>),
}

impl Factored {
    /// sign det A (±1).
    pub fn sign(&self) -> f64 {
        match self.kind.as_ref() {
            FactorKind::Dense { sign, .. } => *sign,
            FactorKind::Structured(w) => w.sign,
        }
    }

    /// The path of these factors.
    pub fn path(&self) -> SolvePath {
        match self.kind.as_ref() {
            FactorKind::Dense { .. } => SolvePath::Dense,
            FactorKind::Structured(w) => SolvePath::Structured { rank: w.rank() },
        }
    }

    /// x = A⁻¹ b on the factors (no refinement); `None` if x is not finite.
    pub fn solve(&self, b: &[f64]) -> Option<Vec<f64>> {
        let x = match self.kind.as_ref() {
            FactorKind::Dense { lu, .. } => {
                let mut x = Mat::from_fn(b.len(), 1, |i, _| b[i]);
                lu.solve_in_place(x.as_mut());
                x.col(0).iter().copied().collect::<Vec<f64>>()
            }
            FactorKind::Structured(w) => w.apply(b),
        };
        x.iter().all(|v| v.is_finite()).then_some(x)
    }
}

/// A matrix as the checks read it.
#[derive(Clone, Copy)]
enum View<'a> {
    Dense(MatRef<'a, f64>),
    Blocks(&'a BlockJacobian),
}

impl<'a> View<'a> {
    fn of(a: &'a Jacobian) -> View<'a> {
        match a {
            Jacobian::Dense(m) => View::Dense(m.as_ref()),
            Jacobian::Blocks(b) => View::Blocks(b),
        }
    }

    /// A x.
    fn mul_vec(self, x: &[f64]) -> Vec<f64> {
        match self {
            View::Dense(m) => {
                let mut y = faer::Col::<f64>::zeros(m.nrows());
                faer::linalg::matmul::matmul(
                    y.as_mut(),
                    Accum::Replace,
                    m,
                    faer::ColRef::from_slice(x),
                    1.0,
                    faer::get_global_parallelism(),
                );
                y.iter().copied().collect()
            }
            View::Blocks(b) => b.mul_vec(x),
        }
    }

    /// ‖A‖₁ (max column sum); in parallel over the columns from [`PARALLEL_NORM_ENTRIES`]
    /// entries.
    fn norm_1(self) -> f64 {
        match self {
            View::Dense(m) => {
                let column_sum = |j: usize| m.col(j).iter().map(|v| v.abs()).sum::<f64>();
                if m.nrows() * m.ncols() < PARALLEL_NORM_ENTRIES {
                    (0..m.ncols()).map(column_sum).fold(0.0, f64::max)
                } else {
                    (0..m.ncols())
                        .into_par_iter()
                        .map(column_sum)
                        .reduce(|| 0.0, f64::max)
                }
            }
            View::Blocks(b) => b.norm_1(),
        }
    }
}

/// Entries of a dense matrix from which its 1-norm is summed in parallel: a smaller sum costs
/// less than handing its columns to rayon's workers.
const PARALLEL_NORM_ENTRIES: usize = 1 << 16;

/// ‖b − A x‖∞ / (‖A‖ ‖x‖∞ + ‖b‖∞) and b − A x.
fn backward_error(a: View<'_>, norm_a: f64, x: &[f64], b: &[f64]) -> (f64, Vec<f64>) {
    let inf = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
    let ax = a.mul_vec(x);
    let r: Vec<f64> = b.iter().zip(&ax).map(|(b, a)| b - a).collect();
    let scale = norm_a * inf(x) + inf(b);
    let eta = if scale > 0.0 { inf(&r) / scale } else { 0.0 };
    (eta, r)
}

impl LinearSolver {
    /// A solver that always uses the dense LU.
    pub fn dense() -> LinearSolver {
        LinearSolver::new(Vec::new(), SolverChoice::Dense)
    }

    /// A solver for matrices whose leading diagonal blocks have the sizes `blocks` (in order;
    /// rows and columns after them are a border, e.g. of a bordered continuation system; empty:
    /// no partition, dense LU).
    pub fn new(blocks: Vec<usize>, choice: SolverChoice) -> LinearSolver {
        LinearSolver {
            blocks,
            choice,
            spare: Mutex::new(None),
            spare_dense: Mutex::new(Vec::new()),
        }
    }

    /// Whether Newton solves the steps after its first on earlier factors by GMRES
    /// ([`LinearSolver::solve_krylov`]) for systems of `dim` unknowns: with the structured choice,
    /// or the automatic one from [`AUTO_MIN_UNKNOWNS`] unknowns on (never with the dense choice,
    /// which is the reference path).
    pub fn reuses_factors(&self, dim: usize) -> bool {
        match self.choice {
            SolverChoice::Dense => false,
            SolverChoice::Structured => true,
            SolverChoice::Auto => dim >= AUTO_MIN_UNKNOWNS,
        }
    }

    /// Hands a matrix that is no longer needed back for the next
    /// [`LinearSolver::linearization`] (kept when it is block-stored over this solver's blocks).
    pub fn recycle(&self, matrix: Jacobian) {
        match matrix {
            Jacobian::Blocks(mut b) => {
                b.drop_pending();
                if b.block_sizes() == self.blocks {
                    if let Ok(mut spare) = self.spare.lock() {
                        *spare = Some(b);
                    }
                }
            }
            Jacobian::Dense(m) => {
                if let Ok(mut spare) = self.spare_dense.lock() {
                    if spare.len() < SPARE_DENSE {
                        spare.push(m);
                    }
                }
            }
        }
    }

    /// A zeroed `rows` × `cols` dense matrix: a recycled one of that size
    /// ([`LinearSolver::recycle`]) or a new one.
    pub fn dense_matrix(&self, rows: usize, cols: usize) -> Mat<f64> {
        let kept = self.spare_dense.lock().ok().and_then(|mut spare| {
            let i = spare
                .iter()
                .position(|m| m.nrows() == rows && m.ncols() == cols)?;
            Some(spare.swap_remove(i))
        });
        match kept {
            Some(mut m) => {
                m.fill(0.0);
                m
            }
            None => Mat::zeros(rows, cols),
        }
    }

    /// Drops the block-stored matrix kept for reuse (e.g. before work that allocates its own).
    pub fn release_storage(&self) {
        if let Ok(mut spare) = self.spare.lock() {
            *spare = None;
        }
    }

    /// Whether the Jacobians of `dim` unknowns are stored by blocks: a partition of `dim` is
    /// known and the choice is [`SolverChoice::Structured`], or [`SolverChoice::Auto`] at
    /// [`AUTO_MIN_UNKNOWNS`] unknowns or more.
    pub fn stores_blocks(&self, dim: usize) -> bool {
        let known = !self.blocks.is_empty() && self.blocks.iter().sum::<usize>() == dim;
        known
            && match self.choice {
                SolverChoice::Dense => false,
                SolverChoice::Structured => true,
                SolverChoice::Auto => dim >= AUTO_MIN_UNKNOWNS,
            }
    }

    /// Zeroed storage for the linearization of a system of `dim` unknowns: the Jacobian
    /// block-stored when [`LinearSolver::stores_blocks`], dense otherwise.
    pub fn linearization(&self, dim: usize) -> Linearization {
        if self.stores_blocks(dim) {
            let spare = self.spare.lock().ok().and_then(|mut s| s.take());
            let blocks = match spare {
                Some(mut b) => {
                    b.clear();
                    b
                }
                None => BlockJacobian::new(&self.blocks),
            };
            Linearization {
                residual: vec![0.0; dim],
                jacobian: Jacobian::Blocks(blocks),
                d_parameter: vec![0.0; dim],
            }
        } else {
            Linearization {
                residual: vec![0.0; dim],
                jacobian: Jacobian::Dense(self.dense_matrix(dim, dim)),
                d_parameter: vec![0.0; dim],
            }
        }
    }

    /// Solves A x = b; `None` when A is (numerically) singular or x is not finite.
    pub fn solve(&self, a: MatRef<'_, f64>, b: &[f64]) -> Option<Vec<f64>> {
        self.solve_signed(a, b).map(|(x, _)| x)
    }

    /// Solves A x = b and returns the sign (±1) of det A too.
    pub fn solve_signed(&self, a: MatRef<'_, f64>, b: &[f64]) -> Option<(Vec<f64>, f64)> {
        self.solve_path(a, b).0
    }

    /// Whether a dense matrix of order `n` is tried on the structured path: its blocks are
    /// known (up to a border of at most 4 rows) and the choice is structured, or automatic from
    /// [`AUTO_MIN_UNKNOWNS`] on.
    fn splits_dense(&self, n: usize) -> bool {
        let inner: usize = self.blocks.iter().sum();
        let partitioned = !self.blocks.is_empty() && inner <= n && n - inner <= 4;
        partitioned
            && match self.choice {
                SolverChoice::Dense => false,
                SolverChoice::Structured => true,
                SolverChoice::Auto => n >= AUTO_MIN_UNKNOWNS,
            }
    }

    /// [`LinearSolver::solve_signed`] and the path that solved (or failed), A stored dense.
    pub fn solve_path(
        &self,
        a: MatRef<'_, f64>,
        b: &[f64],
    ) -> (Option<(Vec<f64>, f64)>, SolvePath) {
        let n = b.len();
        if self.splits_dense(n) {
            let split = Split::dense(a, &self.blocks);
            match Woodbury::factor(split, self.choice == SolverChoice::Auto) {
                Decision::Dense => {}
                Decision::Failed => {
                    record(|s| s.fallbacks += 1);
                }
                Decision::Structured(w) => {
                    let a = View::Dense(a);
                    if let Some(x) = w.solve_checked(a, a.norm_1(), b) {
                        let path = SolvePath::Structured { rank: w.rank() };
                        count(path, n);
                        return (Some((x, w.sign)), path);
                    }
                    record(|s| s.fallbacks += 1);
                }
            }
        }
        record(|s| s.factorizations += 1);
        count(SolvePath::Dense, n);
        (solve_dense_signed_ref(a, b), SolvePath::Dense)
    }

    /// Factorises A (dense or block-stored) by the chosen path and solves A x = b (a structured
    /// solve checked by its backward error, [`BACKWARD_ERROR`], and refined; the dense LU when
    /// that fails). Returns x and the factors; `None` when A is (numerically) singular or x is
    /// not finite. A pending term of a block-stored A is first added to its blocks
    /// ([`Jacobian::materialize`]).
    pub fn factor_solve(&self, a: &mut Jacobian, b: &[f64]) -> Option<(Vec<f64>, Factored)> {
        a.materialize();
        let a = &*a;
        let n = b.len();
        let split = match a {
            Jacobian::Blocks(m) if self.choice != SolverChoice::Dense => Some(Split::blocks(m)),
            Jacobian::Dense(m) => self
                .splits_dense(n)
                .then(|| Split::dense(m.as_ref(), &self.blocks)),
            Jacobian::Blocks(_) => None,
        };
        if let Some(split) = split {
            match Woodbury::factor(split, self.choice == SolverChoice::Auto) {
                Decision::Dense => {}
                Decision::Failed => {
                    record(|s| s.fallbacks += 1);
                }
                Decision::Structured(w) => {
                    record(|s| s.factorizations += 1);
                    let view = View::of(a);
                    if let Some(x) = w.solve_checked(view, view.norm_1(), b) {
                        let f = Factored {
                            kind: std::sync::Arc::new(FactorKind::Structured(w)),
                            n,
                        };
                        count(f.path(), n);
                        return Some((x, f));
                    }
                    record(|s| s.fallbacks += 1);
                }
            }
        }
        record(|s| s.factorizations += 1);
        count(SolvePath::Dense, n);
        let lu = match a {
            Jacobian::Dense(m) => PackedLu::new(m.as_ref()),
            Jacobian::Blocks(m) => PackedLu::in_place(m.to_dense()),
        };
        let sign = lu_sign(&lu)?;
        let f = Factored {
            kind: std::sync::Arc::new(FactorKind::Dense { lu, sign }),
            n,
        };
        let x = f.solve(b)?;
        Some((x, f))
    }

    /// Solves A x = b with the factors `near` of a nearby matrix of the same order (e.g. the
    /// Jacobian of the previous Newton iterate), refined on A by at most [`NEAR_REFINEMENTS`]
    /// steps until the backward error is at most [`BACKWARD_ERROR`]; then sign det A = sign det
    /// of the nearby matrix, returned as well (the refinement contracts: I − F⁻¹A has norm
    /// below 1 on the iterates, so F⁻¹A has no eigenvalue on the negative real axis). `None`
    /// when the refinement does not reach the threshold (factorise A instead).
    pub fn solve_near(&self, near: &Factored, a: &Jacobian, b: &[f64]) -> Option<(Vec<f64>, f64)> {
        if near.n != a.dim() || b.len() != a.dim() {
            return None;
        }
        let a = View::of(a);
        let norm_a = a.norm_1();
        let mut x = near.solve(b)?;
        let mut previous = f64::INFINITY;
        for _ in 0..=NEAR_REFINEMENTS {
            let (eta, r) = backward_error(a, norm_a, &x, b);
            if !eta.is_finite() || eta > 0.5 * previous {
                return None;
            }
            if eta <= BACKWARD_ERROR {
                count(near.path(), b.len());
                return Some((x, near.sign()));
            }
            previous = eta;
            let dx = near.solve(&r)?;
            x.iter_mut().zip(dx).for_each(|(xi, d)| *xi += d);
        }
        None
    }

    /// Solves A x = b by GMRES right-preconditioned by the factors `near` of a nearby matrix of
    /// the same order (module documentation; Saad 2003, Alg. 9.5, modified Gram–Schmidt and
    /// Givens rotations), from x₀ = F⁻¹ b, restarted from the current x whenever the Arnoldi
    /// residual estimate says the backward error ‖b − A x‖∞ / (‖A‖₁ ‖x‖∞ + ‖b‖∞) should be
    /// below [`BACKWARD_ERROR`], which is then checked on the true residual. Returns x and the
    /// GMRES iterations; `None` when that is not reached within [`KRYLOV_ITERATIONS`] iterations
    /// (factorise A instead). The sign of det A is not known from this solve.
    pub fn solve_krylov(
        &self,
        near: &Factored,
        a: &Jacobian,
        b: &[f64],
    ) -> Option<(Vec<f64>, usize)> {
        self.krylov(near, a, b).map(|(x, k, _)| (x, k))
    }

    /// [`LinearSolver::solve_krylov`] with the sign of det A: sign det F · sign det H_k, H_k
    /// = V_kᵀ A F⁻¹ V_k the square Hessenberg matrix of the GMRES cycle that converged (V_k its
    /// Arnoldi basis). With A F⁻¹ = I + L, L = V_k V_kᵀ L when the Krylov space holds the range
    /// of L, and then det(A F⁻¹) = det(I_k + V_kᵀ L V_k) = det H_k (Sylvester's determinant
    /// identity); GMRES converges to the backward error of a direct solve in k ≪ n
    /// iterations only when A F⁻¹ is the identity plus such a term of low rank and a
    /// remainder clustered at 1, whose eigenvalues lie off the negative real axis (the
    /// argument of [`LinearSolver::solve_near`]). Returns x, the GMRES iterations and sign det
    /// A; `None` when GMRES does not converge within one cycle of at most
    /// [`KRYLOV_ITERATIONS`] iterations, or H_k is singular (factorise A instead).
    pub fn solve_krylov_signed(
        &self,
        near: &Factored,
        a: &Jacobian,
        b: &[f64],
    ) -> Option<(Vec<f64>, usize, f64)> {
        let (x, k, sign) = self.krylov(near, a, b)?;
        Some((x, k, sign?))
    }

    /// GMRES of [`LinearSolver::solve_krylov`]; the sign of det A when at most one cycle ran
    /// ([`LinearSolver::solve_krylov_signed`]).
    fn krylov(
        &self,
        near: &Factored,
        a: &Jacobian,
        b: &[f64],
    ) -> Option<(Vec<f64>, usize, Option<f64>)> {
        let n = b.len();
        if near.n != n || a.dim() != n {
            return None;
        }
        let inf = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let view = View::of(a);
        let norm_a = view.norm_1();
        let norm_b = inf(b);
        let mut x = near.solve(b)?;
        let mut used = 0;
        // sign det (A F⁻¹): +1 while no cycle ran (x = F⁻¹ b solves A to the threshold, the
        // case of `solve_near`), that of the only cycle's H_k, unknown after a restart
        let mut cycles = 0;
        let mut relative: Option<f64> = Some(1.0);
        loop {
            let (eta, r) = backward_error(view, norm_a, &x, b);
            if !eta.is_finite() {
                return None;
            }
            if eta <= BACKWARD_ERROR || norm_b == 0.0 {
                record(|s| {
                    s.krylov += 1;
                    s.krylov_iterations += used;
                });
                return Some((x, used, relative.map(|s| s * near.sign())));
            }
            if used >= KRYLOV_ITERATIONS {
                return None;
            }
            // ‖r‖₂ that makes the backward error at most half the threshold
            let target = 0.5 * BACKWARD_ERROR * (norm_a * inf(&x) + norm_b);
            let (dx, k, sign) = gmres_cycle(near, view, r, target, KRYLOV_ITERATIONS - used)?;
            if k == 0 {
                return None;
            }
            cycles += 1;
            relative = if cycles == 1 { sign } else { None };
            used += k;
            x.iter_mut().zip(dx).for_each(|(xi, d)| *xi += d);
        }
    }
}

/// One cycle of right-preconditioned GMRES on A d = r (at most `max` iterations, until the
/// residual estimate is at most `target`): d = F⁻¹ V_k y_k with y_k minimising ‖β e₁ − H̄_k y‖
/// (Saad 2003, Alg. 9.5). Returns d, k and the sign of det H_k (H_k = V_kᵀ A F⁻¹ V_k, the
/// square part of the Hessenberg matrix before its rotations; `None` if it is singular).
fn gmres_cycle(
    near: &Factored,
    a: View<'_>,
    r: Vec<f64>,
    target: f64,
    max: usize,
) -> Option<(Vec<f64>, usize, Option<f64>)> {
    let dot = |u: &[f64], v: &[f64]| u.iter().zip(v).map(|(a, b)| a * b).sum::<f64>();
    let beta = super::norm(&r);
    if beta == 0.0 || !beta.is_finite() {
        return Some((vec![0.0; r.len()], 0, Some(1.0)));
    }
    // the Hessenberg columns as computed (for det H_k)
    let mut hessenberg: Vec<Vec<f64>> = Vec::new();
    let mut basis: Vec<Vec<f64>> = vec![r.iter().map(|v| v / beta).collect()];
    // columns of the rotated Hessenberg matrix (the upper triangle R), the rotations, and g
    let mut columns: Vec<Vec<f64>> = Vec::new();
    let mut rotations: Vec<(f64, f64)> = Vec::new();
    let mut g = vec![beta];
    while columns.len() < max {
        let k = columns.len();
        let mut w = a.mul_vec(&near.solve(&basis[k])?);
        let mut h = vec![0.0; k + 2];
        for (i, v) in basis.iter().enumerate() {
            let hi = dot(&w, v);
            h[i] = hi;
            w.iter_mut().zip(v).for_each(|(w, v)| *w -= hi * v);
        }
        let next = super::norm(&w);
        h[k + 1] = next;
        hessenberg.push(h.clone());
        for (i, &(c, s)) in rotations.iter().enumerate() {
            let (p, q) = (h[i], h[i + 1]);
            h[i] = c * p + s * q;
            h[i + 1] = -s * p + c * q;
        }
        let d = h[k].hypot(h[k + 1]);
        if d == 0.0 || !d.is_finite() {
            break;
        }
        let (c, s) = (h[k] / d, h[k + 1] / d);
        h[k] = d;
        h[k + 1] = 0.0;
        rotations.push((c, s));
        g.push(-s * g[k]);
        g[k] *= c;
        columns.push(h);
        if next == 0.0 || g[k + 1].abs() <= target {
            break;
        }
        basis.push(w.iter().map(|v| v / next).collect());
    }
    let k = columns.len();
    // R y = g, back substitution
    let mut y = vec![0.0; k];
    for i in (0..k).rev() {
        let sum: f64 = (i + 1..k).map(|j| columns[j][i] * y[j]).sum();
        y[i] = (g[i] - sum) / columns[i][i];
    }
    let mut u = vec![0.0; r.len()];
    for (yj, v) in y.iter().zip(&basis) {
        u.iter_mut().zip(v).for_each(|(u, v)| *u += yj * v);
    }
    let square = Mat::from_fn(k, k, |i, j| hessenberg[j].get(i).copied().unwrap_or(0.0));
    let sign = lu_sign(&PackedLu::in_place(square));
    Some((near.solve(&u)?, k, sign))
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

/// A matrix split into the parts of the Woodbury solve.
struct Split<'a> {
    n: usize,
    /// First row of each diagonal block, then the number of block rows.
    starts: Vec<usize>,
    /// The diagonal blocks.
    blocks: Vec<MatRef<'a, f64>>,
    /// The off-block entries of each block column (row, value).
    entries: Vec<Vec<(usize, f64)>>,
    /// The border's columns (all n rows) and rows (the block columns).
    border_cols: Vec<Vec<f64>>,
    border_rows: Vec<Vec<f64>>,
}

impl<'a> Split<'a> {
    /// A dense matrix over the blocks `blocks` (the rows and columns after them a border).
    fn dense(a: MatRef<'a, f64>, blocks: &[usize]) -> Split<'a> {
        let n = a.nrows();
        let starts = starts_of(blocks);
        let inner = starts[starts.len() - 1];
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
        let blocks = starts
            .windows(2)
            .map(|w| a.submatrix(w[0], w[0], w[1] - w[0], w[1] - w[0]))
            .collect();
        let border_cols = (inner..n)
            .map(|c| (0..n).map(|i| a[(i, c)]).collect())
            .collect();
        let border_rows = (inner..n)
            .map(|r| (0..inner).map(|j| a[(r, j)]).collect())
            .collect();
        Split {
            n,
            starts,
            blocks,
            entries,
            border_cols,
            border_rows,
        }
    }

    /// A block-stored matrix (without a pending term).
    fn blocks(m: &'a BlockJacobian) -> Split<'a> {
        debug_assert!(!m.has_pending(), "a pending term is not in the blocks");
        let starts = m.starts().to_vec();
        let inner = m.inner();
        let mut entries: Vec<Vec<(usize, f64)>> = vec![Vec::new(); inner];
        let (off, coalesced) = m.off_block_stored();
        for &(i, j, v) in off {
            entries[j].push((i, v));
        }
        if !coalesced {
            for col in &mut entries {
                col.sort_by_key(|e| e.0);
                let mut merged: Vec<(usize, f64)> = Vec::with_capacity(col.len());
                for &(i, v) in col.iter() {
                    match merged.last_mut() {
                        Some(last) if last.0 == i => last.1 += v,
                        _ => merged.push((i, v)),
                    }
                }
                merged.retain(|e| e.1 != 0.0);
                *col = merged;
            }
        }
        let (border_cols, border_rows) = match m.border() {
            Some((c, r)) => (vec![c.to_vec()], vec![r.to_vec()]),
            None => (Vec::new(), Vec::new()),
        };
        Split {
            n: m.dim(),
            starts,
            blocks: (0..m.block_sizes().len()).map(|b| m.block(b)).collect(),
            entries,
            border_cols,
            border_rows,
        }
    }
}

/// First row of each block of sizes `blocks`, then their sum.
fn starts_of(blocks: &[usize]) -> Vec<usize> {
    let mut starts: Vec<usize> = blocks
        .iter()
        .scan(0, |s, &len| {
            let start = *s;
            *s += len;
            Some(start)
        })
        .collect();
    starts.push(blocks.iter().sum());
    starts
}

/// One piece of E = Σ_p U_p V_pᵀ: the rows of U_p lie inside one diagonal block (a component of
/// E restricted to that block's rows), or it is a border term.
struct Piece {
    /// The diagonal block of the rows (`None`: a border term).
    block: Option<usize>,
    rows: Vec<usize>,
    /// Ascending.
    cols: Vec<usize>,
    /// |rows| × r_p (orthonormal columns for a block piece).
    u: Mat<f64>,
    /// r_p × |cols|.
    vt: Mat<f64>,
}

/// V_pᵀ of a [`Piece`] once X = P⁻¹U is formed (U_p is no longer needed).
struct Coupling {
    /// Ascending.
    cols: Vec<usize>,
    /// r_p × |cols|.
    vt: Mat<f64>,
}

/// The columns `first`..`first + x.ncols()` of X = P⁻¹U on the rows `start`..`start +
/// x.nrows()`, zero elsewhere: the pieces of one diagonal block (P⁻¹ keeps them in it), or a
/// border term.
struct Segment {
    start: usize,
    first: usize,
    x: Mat<f64>,
}

/// The factors of A = P + U Vᵀ (module documentation).
struct Woodbury {
    n: usize,
    /// First row of each diagonal block, then the border's.
    starts: Vec<usize>,
    /// LU of each diagonal block (the border's block is the identity).
    blocks: Vec<PackedLu<f64>>,
    /// V_pᵀ of each piece, in the order of U's columns.
    couplings: Vec<Coupling>,
    /// First column of each piece in U.
    offsets: Vec<usize>,
    /// X = P⁻¹ U by row ranges (Σ_b s_b r_b numbers, not n r).
    segments: Vec<Segment>,
    /// LU of the capacitance matrix I + Vᵀ X.
    capacitance: PackedLu<f64>,
    /// sign det A.
    sign: f64,
}

/// Flops of (2/3) m³ (an LU of order m).
fn lu_flops(m: usize) -> f64 {
    2.0 / 3.0 * (m as f64).powi(3)
}

/// sign det of a regular LU (sign det P · Π sign u_ii), `None` if the smallest |u_ii| ≤ 1e-15
/// max |u_ii|.
pub(crate) fn lu_sign(lu: &PackedLu<f64>) -> Option<f64> {
    let m = lu.nrows();
    let (min, max) = (0..m)
        .map(|i| lu.pivot(i).abs())
        .fold((f64::INFINITY, 0.0_f64), |(lo, hi), d| {
            (lo.min(d), hi.max(d))
        });
    if m > 0 && min <= 1e-15 * max {
        return None;
    }
    let negative = (0..m).filter(|&i| lu.pivot(i) < 0.0).count();
    let sign = permutation_sign(lu.row_order());
    Some(if negative.is_multiple_of(2) {
        sign
    } else {
        -sign
    })
}

/// The connected components of the graph of E (rows 0..inner and columns linked by an entry;
/// `entries` per column): (rows, columns) of each, both ascending.
fn components(entries: &[Vec<(usize, f64)>]) -> Vec<(Vec<usize>, Vec<usize>)> {
    let inner = entries.len();
    // rows are nodes 0..inner, columns inner..2 inner
    let mut parent: Vec<usize> = (0..2 * inner).collect();
    fn find(p: &mut [usize], mut i: usize) -> usize {
        while p[i] != i {
            p[i] = p[p[i]];
            i = p[i];
        }
        i
    }
    let mut touched = vec![false; 2 * inner];
    for (j, col) in entries.iter().enumerate() {
        for &(i, _) in col {
            touched[i] = true;
            touched[inner + j] = true;
            let (ri, rj) = (find(&mut parent, i), find(&mut parent, inner + j));
            if ri != rj {
                parent[ri] = rj;
            }
        }
    }
    let mut index = vec![usize::MAX; 2 * inner];
    let mut groups: Vec<(Vec<usize>, Vec<usize>)> = Vec::new();
    for node in (0..2 * inner).filter(|&v| touched[v]) {
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
    groups
}

/// The rows of each component of E split by diagonal block: (block, rows, columns of the
/// component), ordered by block.
fn block_parts(
    groups: Vec<(Vec<usize>, Vec<usize>)>,
    starts: &[usize],
) -> Vec<(usize, Vec<usize>, Vec<usize>)> {
    let mut parts: Vec<(usize, Vec<usize>, Vec<usize>)> = Vec::new();
    for (rows, cols) in groups {
        for b in 0..starts.len() - 1 {
            let (lo, hi) = (
                rows.partition_point(|&i| i < starts[b]),
                rows.partition_point(|&i| i < starts[b + 1]),
            );
            if lo < hi {
                parts.push((b, rows[lo..hi].to_vec(), cols.clone()));
            }
        }
    }
    parts.sort_by_key(|p| p.0);
    parts
}

/// E restricted to `rows` × `cols` (`entries` per column) compressed by a column-pivoted QR
/// to U Vᵀ, U = Q of rank r (|r_ii| > [`RANK_TOLERANCE`] max |r_ii|), Vᵀ = Qᵀ E.
fn compress(entries: &[Vec<(usize, f64)>], rows: &[usize], cols: &[usize]) -> (Mat<f64>, Mat<f64>) {
    let mut e = Mat::<f64>::zeros(rows.len(), cols.len());
    for (q, &j) in cols.iter().enumerate() {
        for &(i, v) in &entries[j] {
            if let Ok(p) = rows.binary_search(&i) {
                e[(p, q)] = v;
            }
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
    (u, vt)
}

/// The border terms of a bordered matrix as pieces: for border index c, the column (minus the
/// identity block's 1) as a piece of all `n` rows, and the row over the `inner` block columns as
/// a piece of row c.
fn border_pieces(
    n: usize,
    inner: usize,
    border_cols: &[Vec<f64>],
    border_rows: &[Vec<f64>],
) -> Vec<Piece> {
    let mut pieces = Vec::new();
    for (t, (col, row)) in border_cols.iter().zip(border_rows).enumerate() {
        let c = inner + t;
        let mut u = Mat::<f64>::from_fn(n, 1, |i, _| col[i]);
        u[(c, 0)] -= 1.0;
        pieces.push(Piece {
            block: None,
            rows: (0..n).collect(),
            cols: vec![c],
            u,
            vt: Mat::from_fn(1, 1, |_, _| 1.0),
        });
        pieces.push(Piece {
            block: None,
            rows: vec![c],
            cols: (0..inner).collect(),
            u: Mat::from_fn(1, 1, |_, _| 1.0),
            vt: Mat::from_fn(1, inner, |_, j| row[j]),
        });
    }
    pieces
}

/// Flops of Vᵀ X on the segments of [`solve_segments`]: 2 r_p times the columns of X that
/// piece p meets, each once per row of V_pᵀ in the segment's rows (a block's pieces meet only
/// that block's columns of X).
fn product_flops(pieces: &[Piece], starts: &[usize]) -> f64 {
    let mut widths = vec![0usize; starts.len() - 1];
    let mut ranges: Vec<(usize, usize, usize)> = Vec::new();
    for p in pieces {
        match p.block {
            Some(b) => widths[b] += p.u.ncols(),
            None => ranges.push((p.rows[0], p.rows[0] + p.rows.len(), p.u.ncols())),
        }
    }
    for (b, w) in starts.windows(2).enumerate() {
        ranges.push((w[0], w[1], widths[b]));
    }
    pieces
        .iter()
        .map(|p| {
            let met: usize = ranges
                .iter()
                .map(|&(lo, hi, width)| {
                    let n =
                        p.cols.partition_point(|&j| j < hi) - p.cols.partition_point(|&j| j < lo);
                    n * width
                })
                .sum();
            2.0 * (p.u.ncols() * met) as f64
        })
        .sum()
}

/// X = P⁻¹ U by segments: one per diagonal block holding pieces (P_b⁻¹ of their U_p, side by
/// side, in parallel over the blocks), one per border piece (its rows: all for a border column
/// — whose block rows P⁻¹ solves —, row c for a border row, where P is the identity).
fn solve_segments(
    pieces: &[Piece],
    offsets: &[usize],
    starts: &[usize],
    lus: &[PackedLu<f64>],
) -> Vec<Segment> {
    let mut ranges: Vec<(Option<usize>, usize, usize)> = Vec::new();
    for (k, p) in pieces.iter().enumerate() {
        match ranges.last_mut() {
            Some(last) if p.block.is_some() && last.0 == p.block => last.2 = k + 1,
            _ => ranges.push((p.block, k, k + 1)),
        }
    }
    ranges
        .into_par_iter()
        .map(|(block, k0, k1)| {
            let first = offsets[k0];
            let width: usize = pieces[k0..k1].iter().map(|p| p.u.ncols()).sum();
            let start = match block {
                Some(b) => starts[b],
                None => pieces[k0].rows[0],
            };
            let height = match block {
                Some(b) => starts[b + 1] - starts[b],
                None => pieces[k0].rows.len(),
            };
            let mut x = Mat::<f64>::zeros(height, width);
            for (p, &o) in pieces[k0..k1].iter().zip(&offsets[k0..k1]) {
                for (q, &i) in p.rows.iter().enumerate() {
                    for l in 0..p.u.ncols() {
                        x[(i - start, o - first + l)] = p.u[(q, l)];
                    }
                }
            }
            match block {
                Some(b) => lus[b].solve_in_place(x.as_mut()),
                None if height > 1 => {
                    for (w, lu) in starts.windows(2).zip(lus) {
                        lu.solve_in_place(x.as_mut().subrows_mut(w[0], w[1] - w[0]));
                    }
                }
                None => {}
            }
            Segment { start, first, x }
        })
        .collect()
}

/// The rows of the capacitance matrix I + Vᵀ X of one coupling (at column offset `offset`, of
/// `m` columns): V_pᵀ times the rows of X at its columns, segment by segment.
fn capacitance_rows(c: &Coupling, offset: usize, m: usize, segments: &[Segment]) -> Mat<f64> {
    let r = c.vt.nrows();
    let mut out = Mat::<f64>::zeros(r, m);
    for l in 0..r {
        out[(l, offset + l)] = 1.0;
    }
    for s in segments {
        let (lo, hi) = (
            c.cols.partition_point(|&j| j < s.start),
            c.cols.partition_point(|&j| j < s.start + s.x.nrows()),
        );
        if lo == hi {
            continue;
        }
        let gathered = Mat::from_fn(hi - lo, s.x.ncols(), |q, l| {
            s.x[(c.cols[lo + q] - s.start, l)]
        });
        faer::linalg::matmul::matmul(
            out.as_mut().subcols_mut(s.first, s.x.ncols()),
            Accum::Add,
            c.vt.get(.., lo..hi),
            gathered.as_ref(),
            1.0,
            faer::Par::Seq,
        );
    }
    out
}

impl Woodbury {
    /// Compresses E of `split` and factorises; with `auto`, returns [`Decision::Dense`] as soon
    /// as the flop model says the dense LU is cheaper.
    fn factor(split: Split<'_>, auto: bool) -> Decision {
        let Split {
            n,
            starts,
            blocks,
            entries,
            border_cols,
            border_rows,
        } = split;
        let inner = starts[starts.len() - 1];
        let parts = block_parts(components(&entries), &starts);
        let dense_flops = lu_flops(n);
        let blocks_flops: f64 = blocks.iter().map(|b| lu_flops(b.nrows())).sum();
        let qr_flops: f64 = parts
            .iter()
            .map(|(_, r, c)| 2.0 * (r.len() * c.len() * c.len().min(r.len())) as f64)
            .sum();
        if auto && blocks_flops + qr_flops > 0.5 * dense_flops {
            return Decision::Dense;
        }
        // compress each component's rows in each block: E_kb = Q (Qᵀ E_kb)
        let mut pieces: Vec<Piece> = parts
            .into_par_iter()
            .map(|(b, rows, cols)| {
                let (u, vt) = compress(&entries, &rows, &cols);
                Piece {
                    block: Some(b),
                    rows,
                    cols,
                    u,
                    vt,
                }
            })
            .collect();
        drop(entries);
        pieces.extend(border_pieces(n, inner, &border_cols, &border_rows));
        let offsets: Vec<usize> = pieces
            .iter()
            .scan(0, |s, p| {
                let o = *s;
                *s += p.u.ncols();
                Some(o)
            })
            .collect();
        let rank: usize = pieces.iter().map(|p| p.u.ncols()).sum();
        // P⁻¹U: 2 s_b² per column of a block piece, 2 Σ_b s_b² per border column
        let sq: f64 = blocks.iter().map(|b| (b.nrows() * b.nrows()) as f64).sum();
        let solve_flops: f64 = pieces
            .iter()
            .map(|p| {
                let s = p.block.map_or(sq, |b| (blocks[b].nrows().pow(2)) as f64);
                2.0 * s * p.u.ncols() as f64
            })
            .sum();
        let vx_flops = product_flops(&pieces, &starts);
        let structured_flops = blocks_flops + solve_flops + vx_flops + lu_flops(rank);
        if auto && structured_flops > 0.5 * dense_flops {
            return Decision::Dense;
        }
        // block factors (in parallel over the blocks)
        let lus: Vec<Option<PackedLu<f64>>> = blocks
            .par_iter()
            .map(|b| {
                let lu = PackedLu::new(*b);
                lu_sign(&lu).is_some().then_some(lu)
            })
            .collect();
        let Some(lus) = lus.into_iter().collect::<Option<Vec<_>>>() else {
            return Decision::Failed;
        };
        let mut sign: f64 = lus.iter().map(|lu| lu_sign(lu).unwrap_or(1.0)).product();
        let segments = solve_segments(&pieces, &offsets, &starts, &lus);
        let couplings: Vec<Coupling> = pieces
            .into_iter()
            .map(|p| Coupling {
                cols: p.cols,
                vt: p.vt,
            })
            .collect();
        // capacitance I + Vᵀ X, by the rows of each coupling (in parallel)
        let rows: Vec<Mat<f64>> = couplings
            .par_iter()
            .zip(&offsets)
            .map(|(c, &o)| capacitance_rows(c, o, rank, &segments))
            .collect();
        let mut c = Mat::<f64>::zeros(rank, rank);
        for (part, &o) in rows.iter().zip(&offsets) {
            c.as_mut()
                .subrows_mut(o, part.nrows())
                .copy_from(part.as_ref());
        }
        drop(rows);
        let capacitance = PackedLu::in_place(c);
        match lu_sign(&capacitance) {
            Some(s) => sign *= s,
            None => return Decision::Failed,
        }
        Decision::Structured(Box::new(Woodbury {
            n,
            starts,
            blocks: lus,
            couplings,
            offsets,
            segments,
            capacitance,
            sign,
        }))
    }

    /// r, the number of columns of U.
    fn rank(&self) -> usize {
        self.capacitance.nrows()
    }

    /// x = A⁻¹ b by the Woodbury formula.
    fn apply(&self, b: &[f64]) -> Vec<f64> {
        let mut y = Mat::from_fn(self.n, 1, |i, _| b[i]);
        for (w, lu) in self.starts.windows(2).zip(&self.blocks) {
            lu.solve_in_place(y.as_mut().subrows_mut(w[0], w[1] - w[0]));
        }
        let mut s = Mat::<f64>::zeros(self.rank(), 1);
        for (c, &o) in self.couplings.iter().zip(&self.offsets) {
            for l in 0..c.vt.nrows() {
                s[(o + l, 0)] = c
                    .cols
                    .iter()
                    .enumerate()
                    .map(|(q, &j)| c.vt[(l, q)] * y[(j, 0)])
                    .sum();
            }
        }
        self.capacitance.solve_in_place(s.as_mut());
        for seg in &self.segments {
            faer::linalg::matmul::matmul(
                y.as_mut().subrows_mut(seg.start, seg.x.nrows()),
                Accum::Add,
                seg.x.as_ref(),
                s.as_ref().subrows(seg.first, seg.x.ncols()),
                -1.0,
                faer::Par::Seq,
            );
        }
        (0..self.n).map(|i| y[(i, 0)]).collect()
    }

    /// x = A⁻¹ b refined until its backward error is at most [`BACKWARD_ERROR`]; `None` if it
    /// is not within [`REFINEMENTS`] steps or x is not finite. `norm_a` is ‖A‖₁ (in place of
    /// ‖A‖∞: a threshold, not a bound).
    fn solve_checked(&self, a: View<'_>, norm_a: f64, b: &[f64]) -> Option<Vec<f64>> {
        let inf = |v: &[f64]| v.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        let norm_b = inf(b);
        let mut x = self.apply(b);
        for step in 0..=REFINEMENTS {
            if !x.iter().all(|v| v.is_finite()) {
                return None;
            }
            let (eta, r) = backward_error(a, norm_a, &x, b);
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
    /// `a` with its diagonal entry (20, 20) moved across the sign change of det A (det is
    /// linear in it): the first of −20, −5, −1, 7, 20 whose determinant sign differs from `sd`.
    fn other_sign(a: &Mat<f64>, b: &[f64], sd: f64) -> Mat<f64> {
        [-20.0, -5.0, -1.0, 7.0, 20.0]
            .iter()
            .map(|&v| {
                let mut m = a.clone();
                m[(20, 20)] = v;
                m
            })
            .find(|m| solve_dense_signed_ref(m.as_ref(), b).unwrap().1 != sd)
            .expect("a matrix with the other determinant sign")
    }

    /// max_i |x_i − y_i|.
    fn max_difference(x: &[f64], y: &[f64]) -> f64 {
        x.iter()
            .zip(y)
            .map(|(p, q)| (p - q).abs())
            .fold(0.0, f64::max)
    }

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
                let err = max_difference(&xs, &xd);
                let scale = xd.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
                assert!(
                    err <= 1e-12 * scale,
                    "border {border} coupling {coupling}: {err:e}"
                );
                assert_eq!(ss, sd, "border {border} coupling {coupling}");
            }
        }
    }

    /// GMRES on the factors of a matrix that differs by the stiffness of one "element" (rank 3,
    /// on rows and columns {4, 15, 40} in three blocks, bordered) gives the dense solution in
    /// at most rank + 2 iterations; from unrelated factors (every diagonal entry moved) it either
    /// gives the dense solution too or reports that it did not converge — never another x.
    #[test]
    fn krylov_on_nearby_factors() {
        let (a, blocks) = example(true, 0.5);
        let n = a.nrows();
        let b: Vec<f64> = (0..n).map(|i| noise(4000 + i)).collect();
        let (xd, _) = solve_dense_signed_ref(a.as_ref(), &b).unwrap();
        let scale = xd.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let err = |x: &[f64]| max_difference(x, &xd);
        let el = [4usize, 15, 40];
        for choice in [SolverChoice::Dense, SolverChoice::Structured] {
            let solver = LinearSolver::new(blocks.clone(), choice);
            let mut near = a.clone();
            for (p, &i) in el.iter().enumerate() {
                for (q, &j) in el.iter().enumerate() {
                    near[(i, j)] += 0.8 * noise(5000 + 3 * p + q) + if p == q { 0.5 } else { 0.0 };
                }
            }
            let (_, f) = solver.factor_solve(&mut Jacobian::Dense(near), &b).unwrap();
            let before = stats();
            let (x, iterations) = solver
                .solve_krylov(&f, &Jacobian::Dense(a.clone()), &b)
                .unwrap();
            assert!(err(&x) <= 1e-11 * scale, "{choice:?}: {:e}", err(&x));
            assert!((1..=5).contains(&iterations), "{choice:?}: {iterations}");
            let after = stats();
            assert_eq!(after.krylov - before.krylov, 1);
            assert_eq!(
                after.krylov_iterations - before.krylov_iterations,
                iterations
            );
            let far = Mat::from_fn(n, n, |i, j| {
                a[(i, j)] + if i == j { 4.0 * noise(6000 + i) } else { 0.0 }
            });
            let (_, f) = solver.factor_solve(&mut Jacobian::Dense(far), &b).unwrap();
            if let Some((x, iterations)) = solver.solve_krylov(&f, &Jacobian::Dense(a.clone()), &b)
            {
                assert!(err(&x) <= 1e-10 * scale, "{choice:?} far: {:e}", err(&x));
                assert!(iterations <= KRYLOV_ITERATIONS);
            }
        }
    }

    /// GMRES on the factors of a nearby matrix (A plus the stiffness of one "element", rank 3)
    /// and of a matrix whose determinant has the other sign (one diagonal entry of A moved
    /// across det = 0, rank 1) gives the dense solution of A and the dense LU's sign of det A.
    #[test]
    fn krylov_sign_matches_dense() {
        let (a, blocks) = example(true, 0.5);
        let n = a.nrows();
        let b: Vec<f64> = (0..n).map(|i| noise(7000 + i)).collect();
        let (xd, sd) = solve_dense_signed_ref(a.as_ref(), &b).unwrap();
        let scale = xd.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        let mut near = a.clone();
        let el = [4usize, 15, 40];
        for (p, &i) in el.iter().enumerate() {
            for (q, &j) in el.iter().enumerate() {
                near[(i, j)] += 0.8 * noise(5000 + 3 * p + q) + if p == q { 0.5 } else { 0.0 };
            }
        }
        let far = other_sign(&a, &b, sd);
        for choice in [SolverChoice::Dense, SolverChoice::Structured] {
            let solver = LinearSolver::new(blocks.clone(), choice);
            for (what, m) in [("near", &near), ("other sign", &far)] {
                let (_, f) = solver
                    .factor_solve(&mut Jacobian::Dense(m.clone()), &b)
                    .unwrap();
                if what == "other sign" {
                    assert_ne!(f.sign(), sd);
                }
                let (x, k, sign) = solver
                    .solve_krylov_signed(&f, &Jacobian::Dense(a.clone()), &b)
                    .unwrap();
                let err = max_difference(&x, &xd);
                assert!(err <= 1e-10 * scale, "{choice:?} {what}: {err:e}");
                assert!((1..=5).contains(&k), "{choice:?} {what}: {k}");
                assert_eq!(sign, sd, "{choice:?} {what}");
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

    /// A solve on the factors of a nearby matrix (A with one block entry moved by 1e-4) gives
    /// the dense solution of A and its determinant sign; from the factors of a matrix whose
    /// determinant has the other sign the refinement does not converge and `None` tells the
    /// caller to factorise.
    #[test]
    fn solve_near_refines_on_nearby_factors() {
        let (a, blocks) = example(true, 0.5);
        let n = a.nrows();
        let b: Vec<f64> = (0..n).map(|i| noise(3000 + i)).collect();
        let (xd, sd) = solve_dense_signed_ref(a.as_ref(), &b).unwrap();
        let scale = xd.iter().fold(0.0_f64, |m, v| m.max(v.abs()));
        for choice in [SolverChoice::Dense, SolverChoice::Structured] {
            let solver = LinearSolver::new(blocks.clone(), choice);
            let mut near = a.clone();
            near[(20, 20)] += 1e-4;
            let (_, f) = solver
                .factor_solve(&mut Jacobian::Dense(near.clone()), &b)
                .unwrap();
            let (x, sign) = solver
                .solve_near(&f, &Jacobian::Dense(a.clone()), &b)
                .unwrap();
            let err = max_difference(&x, &xd);
            assert!(err <= 1e-11 * scale, "{choice:?}: {err:e}");
            assert_eq!(sign, sd, "{choice:?}");
            // far: the diagonal entry moved across the sign change of det A (det is linear in
            // it; `sign_and_auto` finds both signs between −5 and 7)
            let far = other_sign(&a, &b, sd);
            let (_, f) = solver.factor_solve(&mut Jacobian::Dense(far), &b).unwrap();
            assert!(solver
                .solve_near(&f, &Jacobian::Dense(a.clone()), &b)
                .is_none());
        }
    }
}
