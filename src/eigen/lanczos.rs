//! Block Krylov–Schur (thick-restart block Lanczos with full re-orthogonalisation) for the
//! largest eigenpairs (θ, y) of the symmetric positive semi-definite operator `A = F⁻¹ M F⁻ᵀ`.
//!
//! One cycle: starting from `k` kept Ritz vectors and the next block `V_next` (b orthonormal
//! columns), the basis `V` grows by blocks: `W = A V_j` (one multi-column shift-invert
//! application), the projection `H[:, j] = Vᵀ W` is computed explicitly against the whole basis,
//! `W` is orthogonalised by classical Gram–Schmidt done twice (BLAS-3) and QR-factorised into the
//! next block (`W − V H[:, j] = V_next B`). At `m` columns, the Rayleigh–Ritz step diagonalises
//! `H = S Θ Sᵀ` (faer's dense self-adjoint eigensolver); the residual of Ritz pair i is
//! `‖A x_i − θ_i x_i‖₂ = ‖B S[last block, i]‖₂`, exact in exact arithmetic because only the last
//! block's image leaves span(V). The cycle ends when the wanted pairs satisfy
//! `‖A x_i − θ_i x_i‖₂ ≤ tol · θ_i + 1e3·ε·θ_max`; otherwise the basis is compressed to the `k` leading Ritz
//! vectors (thick restart, `H ← diag(θ_1..θ_k)`) and `V_next` is kept as the next block.
//!
//! A block of b vectors captures up to b copies of a repeated eigenvalue in exact arithmetic (a
//! single-vector Krylov space holds only one), so multiplicities up to b are found reliably;
//! higher ones usually too (round-off feeds the missing directions in over the restarts), but
//! without a guarantee — there is no Sturm-sequence count.

use faer::linalg::matmul::matmul;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::{Accum, ColMut, ColRef, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

use super::dense::self_adjoint_eigen_qr;
use super::krylov::Operator;
use crate::error::{Error, Result};

/// A new direction whose norm after orthogonalisation is below this fraction of its norm before
/// is treated as lost to round-off (rank-deficient block) and replaced by a random direction.
const DEFLATION_RATIO: f64 = 1e-10;
/// Round-off floor of the Ritz residuals, relative to the largest Ritz value (≈ ‖A‖₂): a pair
/// counts as converged once `‖A x − θ x‖₂ ≤ tol · θ + NOISE_FLOOR · θ_max`. Round-off in the
/// applications of A keeps the residual estimates at about ε θ_max, so without the floor a pair
/// with θ ≪ θ_max (an elastic mode next to rigid-body modes with a shift very close to 0) would
/// never converge; the residual check after the back-transformation judges it instead.
const NOISE_FLOOR: f64 = 10.0 * f64::EPSILON;

/// Sizes of a block Krylov–Schur iteration.
pub(super) struct BlockSizes {
    /// Number of wanted eigenpairs n (largest θ).
    pub wanted: usize,
    /// Block size b (columns per operator application).
    pub block: usize,
    /// Basis size m before a restart; `n + 2b ≤ m` and `m + b ≤ N_dof`.
    pub max_dim: usize,
}

/// The state of a block Krylov–Schur iteration: basis, projected matrix, coupling to the next
/// block. [`BlockKrylov::converge`] can be called again with a tighter tolerance and continues
/// from where the previous call stopped.
pub(super) struct BlockKrylov {
    sizes: BlockSizes,
    /// Basis `V` (`N_dof × (m + b)`): `active` columns with known image, then the next block.
    v: Mat<f64>,
    /// Projected matrix `H = Vᵀ A V` (`m × m`, leading `active × active` block in use).
    h: Mat<f64>,
    /// R factor B of the next block: `A V − V H = V_next B E_lastᵀ`.
    coupling: Mat<f64>,
    active: usize,
    rng: SplitMix,
}

impl BlockKrylov {
    /// A new iteration for `op` with a random orthonormal start block.
    pub(super) fn new(n_dof: usize, sizes: BlockSizes) -> Self {
        let (b, m) = (sizes.block, sizes.max_dim);
        let mut rng = SplitMix(0x5EED_0FEE_1600);
        let mut v = Mat::<f64>::zeros(n_dof, m + b);
        for c in 0..b {
            orthonormal_random_column(v.as_mut(), c, &mut rng);
        }
        BlockKrylov {
            sizes,
            v,
            h: Mat::zeros(m, m),
            coupling: Mat::zeros(b, b),
            active: 0,
            rng,
        }
    }

    /// Iterates (at most `max_restarts` thick restarts) until the wanted Ritz pairs satisfy
    /// `‖A x − θ x‖₂ ≤ tolerance · θ + NOISE_FLOOR · θ_max`; returns θ descending and the
    /// orthonormal Ritz vectors (`N_dof × n`).
    pub(super) fn converge(
        &mut self,
        op: &Operator<'_, '_>,
        tolerance: f64,
        max_restarts: usize,
    ) -> Result<(Vec<f64>, Mat<f64>)> {
        let (n, b, m) = (self.sizes.wanted, self.sizes.block, self.sizes.max_dim);
        for restart in 0..=max_restarts {
            while self.active + b <= m {
                self.coupling = expand(
                    op,
                    self.v.as_mut(),
                    self.h.as_mut(),
                    self.active,
                    b,
                    &mut self.rng,
                )?;
                self.active += b;
            }
            let active = self.active;
            let (theta, s) = rayleigh_ritz(self.h.as_ref().get(..active, ..active))?;
            let residuals = ritz_residuals(
                self.coupling.as_ref(),
                s.as_ref().get(active - b..active, ..),
            );
            let floor = NOISE_FLOOR * theta[0].abs();
            let converged = (0..n)
                .filter(|&i| residuals[i] <= tolerance * theta[i] + floor)
                .count();
            if converged == n {
                let y = self.v.as_ref().get(.., ..active) * s.as_ref().get(.., ..n);
                return Ok((theta[..n].to_vec(), y));
            }
            if restart == max_restarts {
                return Err(not_converged(converged, &self.sizes, max_restarts));
            }
            let keep = (n + (m - n) / 2).min(m - b);
            thick_restart(
                self.v.as_mut(),
                self.h.as_mut(),
                s.as_ref(),
                &theta,
                active,
                keep,
                b,
            );
            self.active = keep;
        }
        Err(not_converged(0, &self.sizes, max_restarts))
    }
}

/// The error for a run that used up its restarts with `converged` of the wanted pairs.
fn not_converged(converged: usize, sizes: &BlockSizes, max_restarts: usize) -> Error {
    Error::Compute(format!(
        "the block Krylov–Schur iteration converged {converged} of {} modes in {max_restarts} \
         restarts; raise max_restarts or subspace_dim (now {}), or check the shift (a shift far \
         below the wanted eigenvalues slows convergence)",
        sizes.wanted, sizes.max_dim
    ))
}

/// Applies A to the block `V[:, active..active+b]`, fills its columns (and rows) of H, and
/// writes the next orthonormal block to `V[:, active+b..active+2b]`; returns its R factor B.
fn expand(
    op: &Operator<'_, '_>,
    v: MatMut<'_, f64>,
    mut h: MatMut<'_, f64>,
    active: usize,
    b: usize,
    rng: &mut SplitMix,
) -> Result<Mat<f64>> {
    let mut w = Mat::<f64>::zeros(v.nrows(), b);
    op.apply(w.as_mut(), v.rb().get(.., active..active + b))?;
    let norms: Vec<f64> = (0..b).map(|c| w.col(c).norm_l2()).collect();
    let c = project_out(v.rb().get(.., ..active + b), w.as_mut());
    for j in 0..b {
        for i in 0..active + b {
            let x = if i >= active {
                0.5 * (c[(i, j)] + c[(active + j, i - active)])
            } else {
                c[(i, j)]
            };
            h[(i, active + j)] = x;
            h[(active + j, i)] = x;
        }
    }
    Ok(orthonormalize_block(v, w.as_mut(), active + b, &norms, rng))
}

/// Classical Gram–Schmidt done twice: `w ← w − V (Vᵀ w)` two times; returns the summed
/// coefficients `Vᵀ w` (the projection of the original w on V). The tall-skinny products are
/// split into row chunks of [`GS_ROWS`] rows over rayon's threads (each chunk sequential, partial
/// `Vᵀ w` summed), and the subtraction of one pass and the product of the next share one sweep
/// over V: faer's own parallel matrix product spent most of its time synchronising its threads on
/// these thin (b-column) products (measured: more time than the shift-invert solves).
fn project_out(basis: MatRef<'_, f64>, mut w: MatMut<'_, f64>) -> Mat<f64> {
    let mut c = basis_gram(basis, w.rb());
    let second = subtract_projection(basis, w.rb_mut(), c.as_ref(), true);
    subtract_projection(basis, w.rb_mut(), second.as_ref(), false);
    c += &second;
    c
}

/// Rows per parallel chunk of the products with the Krylov basis (a chunk of V, ~200 columns,
/// stays in the L2 cache between the two products of [`subtract_projection`]).
const GS_ROWS: usize = 512;

/// `Vᵀ w`, summed over row chunks in parallel.
fn basis_gram(basis: MatRef<'_, f64>, w: MatRef<'_, f64>) -> Mat<f64> {
    let (k, b) = (basis.ncols(), w.ncols());
    basis
        .par_row_chunks(GS_ROWS)
        .zip(w.par_row_chunks(GS_ROWS))
        .map(|(v, w)| {
            let mut c = Mat::<f64>::zeros(k, b);
            matmul(c.as_mut(), Accum::Replace, v.transpose(), w, 1.0, Par::Seq);
            c
        })
        .reduce(|| Mat::zeros(k, b), |a, b| a + b)
}

/// `w ← w − V c`, then, if `gram`, returns `Vᵀ w` of the updated w (zero matrix otherwise), in
/// one parallel sweep over row chunks.
fn subtract_projection(
    basis: MatRef<'_, f64>,
    w: MatMut<'_, f64>,
    c: MatRef<'_, f64>,
    gram: bool,
) -> Mat<f64> {
    let (k, b) = (basis.ncols(), w.ncols());
    let rows = if gram { k } else { 0 };
    basis
        .par_row_chunks(GS_ROWS)
        .zip(w.par_row_chunks_mut(GS_ROWS))
        .map(|(v, mut w)| {
            matmul(w.rb_mut(), Accum::Add, v, c, -1.0, Par::Seq);
            let mut g = Mat::<f64>::zeros(rows, b);
            if gram {
                matmul(
                    g.as_mut(),
                    Accum::Replace,
                    v.transpose(),
                    w.rb(),
                    1.0,
                    Par::Seq,
                );
            }
            g
        })
        .reduce(|| Mat::zeros(rows, b), |a, b| a + b)
}

/// QR of `w` (already orthogonal to `V[:, ..start]`) into `V[:, start..start+b]` by modified
/// Gram–Schmidt with re-orthogonalisation; a column reduced below `DEFLATION_RATIO` of its
/// original norm `norms[c]` is replaced by a random orthonormal direction (zero column in B).
fn orthonormalize_block(
    mut v: MatMut<'_, f64>,
    mut w: MatMut<'_, f64>,
    start: usize,
    norms: &[f64],
    rng: &mut SplitMix,
) -> Mat<f64> {
    let b = w.ncols();
    let mut r = Mat::<f64>::zeros(b, b);
    for c in 0..b {
        for _ in 0..2 {
            for i in 0..c {
                let q = v.rb().col(start + i);
                let d = q.transpose() * w.rb().col(c);
                sub_scaled(w.rb_mut().col_mut(c), q, d);
                r[(i, c)] += d;
            }
        }
        let norm = w.rb().col(c).norm_l2();
        if norm > DEFLATION_RATIO * norms[c] && norm > 0.0 {
            r[(c, c)] = norm;
            let mut dst = v.rb_mut().col_mut(start + c);
            dst.copy_from(w.rb().col(c));
            dst /= norm;
        } else {
            orthonormal_random_column(v.rb_mut(), start + c, rng);
        }
    }
    r
}

/// `x ← x − d · q`.
fn sub_scaled(mut x: ColMut<'_, f64>, q: ColRef<'_, f64>, d: f64) {
    for i in 0..x.nrows() {
        x[i] -= d * q[i];
    }
}

/// Writes a random unit vector orthogonal to `V[:, ..col]` into `V[:, col]`.
fn orthonormal_random_column(mut v: MatMut<'_, f64>, col: usize, rng: &mut SplitMix) {
    let mut x = Mat::<f64>::from_fn(v.nrows(), 1, |_, _| rng.uniform());
    project_out(v.rb().get(.., ..col), x.as_mut());
    let norm = x.col(0).norm_l2();
    let mut dst = v.rb_mut().col_mut(col);
    dst.copy_from(x.col(0));
    dst /= norm;
}

/// Eigenpairs of the projected matrix, θ descending with the matching columns of S, by
/// [`self_adjoint_eigen_qr`]. faer's default (divide and conquer above 128 × 128) loses the
/// orthogonality of the eigenvectors of clustered Ritz values on these projected matrices:
/// measured with 100 wanted modes (m = 200), the 10 878-DOF Craig–Bampton interior of the
/// bundled sector then converged only 41 of 100 pairs in 200 restarts, and the 22³ lattice
/// returned modes M-orthonormal only to 1e-9 instead of 1e-15.
fn rayleigh_ritz(h: MatRef<'_, f64>) -> Result<(Vec<f64>, Mat<f64>)> {
    let k = h.nrows();
    let sym = Mat::from_fn(k, k, |i, j| 0.5 * (h[(i, j)] + h[(j, i)]));
    let (values, u) = self_adjoint_eigen_qr(sym.as_ref())?;
    let theta = (0..k).map(|i| values[k - 1 - i]).collect();
    let s = Mat::from_fn(k, k, |i, j| u[(i, k - 1 - j)]);
    Ok((theta, s))
}

/// `‖B s_i‖₂` for every column `s_i` of the last-block rows of S.
fn ritz_residuals(coupling: MatRef<'_, f64>, s_last: MatRef<'_, f64>) -> Vec<f64> {
    let bs = coupling * s_last;
    (0..bs.ncols()).map(|i| bs.col(i).norm_l2()).collect()
}

/// Compresses the basis to the `keep` leading Ritz vectors, moves the pending block
/// `V[:, active..active+b]` behind them and resets H to `diag(θ_1..θ_keep)`. `V[:, ..keep] ←
/// V[:, ..active] S[:, ..keep]` is computed in row blocks of [`RESTART_ROWS`] rows, so the
/// temporary holds `RESTART_ROWS × keep` values instead of `N_dof × keep`.
fn thick_restart(
    mut v: MatMut<'_, f64>,
    mut h: MatMut<'_, f64>,
    s: MatRef<'_, f64>,
    theta: &[f64],
    active: usize,
    keep: usize,
    b: usize,
) {
    let s_keep = s.get(.., ..keep);
    v.rb_mut()
        .par_row_chunks_mut(RESTART_ROWS)
        .for_each(|mut rows| {
            let mut ritz = Mat::<f64>::zeros(rows.nrows(), keep);
            let old = rows.rb().get(.., ..active);
            matmul(ritz.as_mut(), Accum::Replace, old, s_keep, 1.0, Par::Seq);
            rows.rb_mut().get_mut(.., ..keep).copy_from(&ritz);
            for c in 0..b {
                for i in 0..rows.nrows() {
                    rows[(i, keep + c)] = rows[(i, active + c)];
                }
            }
        });
    h.fill(0.0);
    for (i, &t) in theta.iter().take(keep).enumerate() {
        h[(i, i)] = t;
    }
}

/// Rows per block of the thick-restart basis compression.
const RESTART_ROWS: usize = 2048;

/// SplitMix64: a small deterministic generator for start and replacement vectors.
pub(super) struct SplitMix(pub(super) u64);

impl SplitMix {
    /// Uniform in [−1, 1).
    pub(super) fn uniform(&mut self) -> f64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^= z >> 31;
        (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Largest |QᵀQ − I| over the first `k` columns.
    fn orthonormality_error(v: MatRef<'_, f64>, k: usize) -> f64 {
        let q = v.get(.., ..k);
        let g = q.transpose() * q;
        let mut worst = 0.0_f64;
        for i in 0..k {
            for j in 0..k {
                let target = if i == j { 1.0 } else { 0.0 };
                worst = worst.max((g[(i, j)] - target).abs());
            }
        }
        worst
    }

    #[test]
    fn random_numbers_are_in_range_and_deterministic() {
        let (mut a, mut b) = (SplitMix(1), SplitMix(1));
        for _ in 0..1000 {
            let x = a.uniform();
            assert!((-1.0..1.0).contains(&x));
            assert_eq!(x, b.uniform());
        }
    }

    // A block whose two columns are equal (rank 1) gives an orthonormal basis, a zero R entry
    // for the lost direction, and Q R equal to the block.
    #[test]
    fn rank_deficient_block_is_completed() {
        let n = 50;
        let mut rng = SplitMix(3);
        let mut v = Mat::<f64>::zeros(n, 4);
        orthonormal_random_column(v.as_mut(), 0, &mut rng);
        orthonormal_random_column(v.as_mut(), 1, &mut rng);
        let mut w = Mat::<f64>::from_fn(n, 2, |i, _| ((i * 3) % 7) as f64);
        let norms: Vec<f64> = (0..2).map(|c| w.col(c).norm_l2()).collect();
        project_out(v.as_ref().get(.., ..2), w.as_mut());
        let block = w.clone();
        let r = orthonormalize_block(v.as_mut(), w.as_mut(), 2, &norms, &mut rng);
        assert!(r[(0, 0)] > 0.0);
        assert_eq!(r[(1, 1)], 0.0, "the repeated column must be detected");
        assert!(orthonormality_error(v.as_ref(), 4) < 1e-14);
        let q_r = v.as_ref().get(.., 2..4) * &r;
        assert!((&q_r - &block).norm_max() < 1e-12 * norms[0]);
    }

    #[test]
    fn rayleigh_ritz_sorts_descending() {
        let h = Mat::<f64>::from_fn(3, 3, |i, j| if i == j { [2.0, 5.0, 1.0][i] } else { 0.0 });
        let (theta, s) = rayleigh_ritz(h.as_ref()).unwrap();
        assert_eq!(theta, vec![5.0, 2.0, 1.0]);
        assert_eq!(s[(1, 0)].abs(), 1.0);
    }
}
