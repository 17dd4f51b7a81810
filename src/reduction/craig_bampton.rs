//! Craig–Bampton reduction with streamed static modes (methods.md, "Craig–Bampton"; Craig &
//! Bampton, AIAA J. 6 (1968) 1313).
//!
//! Symbols: K, M the free (clamped) stiffness (N/m) and mass (kg) matrices, partitioned into
//! masters b and interior i ([`Partition`]); Ψ = −K_ii⁻¹ K_ib the static constraint modes
//! (n_i × n_b, dimensionless); Φ the n_m lowest fixed-interface modes K_ii φ = ω² M_ii φ,
//! mass-normalised (Φᵀ M_ii Φ = I); T_CB = [[I, 0], [Ψ, Φ]]. The reduced matrices are
//!
//! ```text
//! K_cb = T_CBᵀ K T_CB = [[K_bb + K_bi Ψ, 0], [0, diag ω²]]
//! M_cb = T_CBᵀ M T_CB = [[M_bb + M_bi Ψ + Ψᵀ(M_ib + M_ii Ψ), (M_bi + Ψᵀ M_ii) Φ], [sym., I]]
//! ```
//!
//! (K_bi Ψ + Ψᵀ K_ib + Ψᵀ K_ii Ψ = K_bi Ψ since K_ii Ψ = −K_ib, and the coupling Ψᵀ K_ii Φ + K_bi Φ
//! vanishes for the same reason.) Reduced coordinates: the n_b master DOF, then the n_m modal
//! coordinates, in the order of [`Partition::masters`].
//!
//! # Streaming
//! One sparse Cholesky factorisation of K_ii ([`ShiftInvert`] with σ = 0) serves the
//! fixed-interface modes (computed first) and the static modes. The masters are processed in
//! column blocks B of [`CbOptions::block_columns`]: X = Ψ_B = −K_ii⁻¹ K_ib[:, B] (one multi-column
//! solve, parallel over columns), then
//! `K_cb_bb[:, B] = K_bb[:, B] + K_ibᵀ X`, `Y = M_ib[:, B] + M_ii X`, `M_cb_mb[:, B] = Φᵀ Y` and,
//! since `Ψᵀ Y = −K_ibᵀ K_ii⁻¹ Y` (a second solve), `M_cb_bb[:, B] = M_bb[:, B] + M_ibᵀ X −
//! K_ibᵀ K_ii⁻¹ Y`. Ψ is never stored whole: the memory beyond the factor is three
//! n_i × |B| blocks plus the dense reduced matrices, at the price of two solves per master DOF
//! instead of one. Finally K_cb and M_cb are symmetrised ((A + Aᵀ)/2; they are symmetric in exact
//! arithmetic, the asymmetry is round-off).

use faer::linalg::matmul::matmul;
use faer::sparse::linalg::matmul::sparse_dense_matmul;
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;
use std::time::Instant;

use super::masters::Partition;
use crate::eigen::{EigenOptions, ShiftInvert};
use crate::error::{Error, Result};

/// Options of the Craig–Bampton reduction.
#[derive(Clone, Debug, PartialEq)]
pub struct CbOptions {
    /// Number of fixed-interface modes n_m (0: static (Guyan) reduction only).
    pub interface_modes: usize,
    /// Master columns per static-mode block (memory: 3 × n_i × `block_columns` values).
    /// Default 128.
    pub block_columns: usize,
    /// Options of the fixed-interface eigensolver (σ must stay 0: K_ii is factorised once).
    pub eigen: EigenOptions,
}

impl Default for CbOptions {
    fn default() -> Self {
        CbOptions {
            interface_modes: 0,
            block_columns: 128,
            eigen: EigenOptions::default(),
        }
    }
}

/// The Craig–Bampton model of a sector (dense, symmetric).
#[derive(Clone, Debug)]
pub struct CraigBampton {
    /// K_cb (N/m), (n_b + n_m)², block diagonal.
    pub stiffness: Mat<f64>,
    /// M_cb (kg), (n_b + n_m)².
    pub mass: Mat<f64>,
    /// Number of master DOF n_b (the first rows).
    pub n_masters: usize,
    /// ω² (rad²/s²) of the fixed-interface modes, ascending.
    pub interface_eigenvalues: Vec<f64>,
    /// Residual of each fixed-interface mode (see [`crate::eigen::Modes::residuals`]).
    pub interface_residuals: Vec<f64>,
    /// Wall time of the phases of the reduction.
    pub timings: CbTimings,
}

/// Wall time (s) of the phases of [`craig_bampton`].
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CbTimings {
    /// Partition of K and M, ordering and Cholesky factorisation of K_ii.
    pub factor_s: f64,
    /// Fixed-interface modes (block Krylov–Schur with the factor).
    pub modes_s: f64,
    /// Static modes streamed into K_cb and M_cb, and assembly of the reduced matrices.
    pub static_s: f64,
}

impl CraigBampton {
    /// Number of fixed-interface modes n_m.
    pub fn n_modes(&self) -> usize {
        self.interface_eigenvalues.len()
    }

    /// Size n_b + n_m of the reduced model.
    pub fn len(&self) -> usize {
        self.stiffness.nrows()
    }

    /// Whether the model has no coordinate (never, for a built model).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Fixed-interface frequencies (Hz).
    pub fn interface_frequencies_hz(&self) -> Vec<f64> {
        self.interface_eigenvalues
            .iter()
            .map(|&l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
            .collect()
    }
}

/// The Craig–Bampton reduction of (K, M) (free model, N/m and kg, full symmetric storage, sorted
/// rows) for the master/interior `partition` (see the module documentation).
///
/// Errors: [`Error::Input`] when `interface_modes` ≥ the number of interior DOF or the options are
/// invalid; [`Error::Compute`] if K_ii is not positive definite (an unclamped part of the model
/// that touches no master) or a fixed-interface mode does not converge.
pub fn craig_bampton(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    partition: &Partition,
    opts: &CbOptions,
) -> Result<CraigBampton> {
    let n_i = partition.interior.len();
    let n_b = partition.n_masters();
    let n_m = opts.interface_modes;
    if n_m >= n_i {
        return Err(Error::input(format!(
            "[reduction] interface_modes = {n_m}: the model has only {n_i} interior DOF (after \
             clamping, {n_b} master DOF); ask for fewer than {n_i} interface modes"
        )));
    }
    if opts.block_columns == 0 {
        return Err(Error::input(
            "Craig–Bampton: block_columns = 0; use at least 1 (default 128)",
        ));
    }
    let t0 = Instant::now();
    let blocks = Blocks::split(k, m, partition);
    let factor =
        ShiftInvert::new(blocks.k_ii.as_ref(), blocks.m_ii.as_ref(), 0.0).map_err(|e| match e {
            Error::Compute(msg) => Error::Compute(format!(
                "Craig–Bampton: the interior stiffness K_ii cannot be factorised ({msg}). A part \
                 of the model is neither clamped nor connected to a master node"
            )),
            other => other,
        })?;
    let factor_s = t0.elapsed().as_secs_f64();
    let (lambda, residuals, phi) = if n_m > 0 {
        let modes = factor.lowest_modes(n_m, &opts.eigen)?;
        (modes.eigenvalues, modes.residuals, modes.vectors)
    } else {
        (Vec::new(), Vec::new(), Mat::zeros(n_i, 0))
    };
    let modes_s = t0.elapsed().as_secs_f64() - factor_s;

    let mut k_bb = blocks.k_bb;
    let mut m_bb = blocks.m_bb;
    let mut m_mb = Mat::<f64>::zeros(n_m, n_b);
    let mut start = 0;
    while start < n_b {
        let w = opts.block_columns.min(n_b - start);
        let mut x = Mat::<f64>::zeros(n_i, w);
        scatter_columns(x.as_mut(), blocks.k_ib.as_ref(), start, -1.0);
        factor.solve_in_place(x.as_mut())?;
        // K_cb_bb[:, B] += K_ibᵀ Ψ_B
        transpose_product_add(
            k_bb.as_mut().subcols_mut(start, w),
            blocks.k_ib.as_ref(),
            x.as_ref(),
            1.0,
        );
        // Y = M_ib[:, B] + M_ii Ψ_B
        let mut y = Mat::<f64>::zeros(n_i, w);
        scatter_columns(y.as_mut(), blocks.m_ib.as_ref(), start, 1.0);
        product_add(y.as_mut(), blocks.m_ii.as_ref(), x.as_ref());
        if n_m > 0 {
            matmul(
                m_mb.as_mut().subcols_mut(start, w),
                Accum::Replace,
                phi.transpose(),
                y.as_ref(),
                1.0,
                faer::get_global_parallelism(),
            );
        }
        transpose_product_add(
            m_bb.as_mut().subcols_mut(start, w),
            blocks.m_ib.as_ref(),
            x.as_ref(),
            1.0,
        );
        drop(x);
        factor.solve_in_place(y.as_mut())?;
        transpose_product_add(
            m_bb.as_mut().subcols_mut(start, w),
            blocks.k_ib.as_ref(),
            y.as_ref(),
            -1.0,
        );
        start += w;
    }
    symmetrise(k_bb.as_mut());
    symmetrise(m_bb.as_mut());

    let n = n_b + n_m;
    let mut stiffness = Mat::<f64>::zeros(n, n);
    let mut mass = Mat::<f64>::zeros(n, n);
    stiffness
        .as_mut()
        .submatrix_mut(0, 0, n_b, n_b)
        .copy_from(&k_bb);
    mass.as_mut().submatrix_mut(0, 0, n_b, n_b).copy_from(&m_bb);
    mass.as_mut()
        .submatrix_mut(n_b, 0, n_m, n_b)
        .copy_from(&m_mb);
    mass.as_mut()
        .submatrix_mut(0, n_b, n_b, n_m)
        .copy_from(m_mb.transpose());
    for (j, &l) in lambda.iter().enumerate() {
        stiffness[(n_b + j, n_b + j)] = l;
        mass[(n_b + j, n_b + j)] = 1.0;
    }
    Ok(CraigBampton {
        stiffness,
        mass,
        n_masters: n_b,
        interface_eigenvalues: lambda,
        interface_residuals: residuals,
        timings: CbTimings {
            factor_s,
            modes_s,
            static_s: t0.elapsed().as_secs_f64() - factor_s - modes_s,
        },
    })
}

/// The partitioned blocks of K and M.
struct Blocks {
    k_ii: SparseColMat<usize, f64>,
    m_ii: SparseColMat<usize, f64>,
    k_ib: SparseColMat<usize, f64>,
    m_ib: SparseColMat<usize, f64>,
    k_bb: Mat<f64>,
    m_bb: Mat<f64>,
}

impl Blocks {
    fn split(
        k: SparseColMatRef<'_, usize, f64>,
        m: SparseColMatRef<'_, usize, f64>,
        p: &Partition,
    ) -> Blocks {
        let n = p.n_free;
        let mut interior_index = vec![usize::MAX; n];
        for (new, &old) in p.interior.iter().enumerate() {
            interior_index[old] = new;
        }
        let mut master_index = vec![usize::MAX; n];
        for (new, d) in p.masters.iter().enumerate() {
            master_index[d.free_row] = new;
        }
        let master_rows = p.master_rows();
        Blocks {
            k_ii: select(k, &interior_index, &p.interior),
            m_ii: select(m, &interior_index, &p.interior),
            k_ib: select(k, &interior_index, &master_rows),
            m_ib: select(m, &interior_index, &master_rows),
            k_bb: dense_select(k, &master_index, &master_rows),
            m_bb: dense_select(m, &master_index, &master_rows),
        }
    }
}

/// A[rows, cols] as a sparse matrix: `row_index[old]` is the new row (`usize::MAX`: dropped,
/// increasing in `old` so rows stay sorted), `cols` the old column of each new column.
fn select(
    a: SparseColMatRef<'_, usize, f64>,
    row_index: &[usize],
    cols: &[usize],
) -> SparseColMat<usize, f64> {
    let n_rows = row_index.iter().filter(|&&r| r != usize::MAX).count();
    let mut col_ptr = Vec::with_capacity(cols.len() + 1);
    col_ptr.push(0usize);
    let mut rows = Vec::new();
    let mut vals = Vec::new();
    for &c in cols {
        for (r, &v) in a.row_idx_of_col(c).zip(a.val_of_col(c)) {
            let new = row_index[r];
            if new != usize::MAX {
                rows.push(new);
                vals.push(v);
            }
        }
        col_ptr.push(rows.len());
    }
    SparseColMat::new(
        SymbolicSparseColMat::new_checked(n_rows, cols.len(), col_ptr, None, rows),
        vals,
    )
}

/// A[rows, cols] as a dense matrix (`row_index[old]` = new row or `usize::MAX`).
fn dense_select(
    a: SparseColMatRef<'_, usize, f64>,
    row_index: &[usize],
    cols: &[usize],
) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(cols.len(), cols.len());
    for (j, &c) in cols.iter().enumerate() {
        for (r, &v) in a.row_idx_of_col(c).zip(a.val_of_col(c)) {
            let new = row_index[r];
            if new != usize::MAX {
                out[(new, j)] = v;
            }
        }
    }
    out
}

/// `x[:, j] = alpha · a[:, first + j]` for every column j of `x` (x zero on entry).
fn scatter_columns(
    mut x: MatMut<'_, f64>,
    a: SparseColMatRef<'_, usize, f64>,
    first: usize,
    alpha: f64,
) {
    for j in 0..x.ncols() {
        for (r, &v) in a.row_idx_of_col(first + j).zip(a.val_of_col(first + j)) {
            x[(r, j)] = alpha * v;
        }
    }
}

/// Columns per parallel task of the sparse products.
fn chunk_width(ncols: usize) -> usize {
    ncols.div_ceil(rayon::current_num_threads().max(1)).max(1)
}

/// `dst += alpha · aᵀ x` (a sparse n_i × n_b, x dense n_i × w, dst n_b × w), parallel over the
/// columns of x: each entry is a sparse dot product with a contiguous column of x.
fn transpose_product_add(
    dst: MatMut<'_, f64>,
    a: SparseColMatRef<'_, usize, f64>,
    x: MatRef<'_, f64>,
    alpha: f64,
) {
    let w = chunk_width(dst.ncols());
    dst.par_col_chunks_mut(w)
        .enumerate()
        .for_each(|(c, mut d)| {
            for j in 0..d.ncols() {
                let xj = x.col(c * w + j);
                for r in 0..a.ncols() {
                    let s: f64 = a
                        .row_idx_of_col(r)
                        .zip(a.val_of_col(r))
                        .map(|(i, &v)| v * xj[i])
                        .sum();
                    d[(r, j)] += alpha * s;
                }
            }
        });
}

/// `dst += a x` (a sparse, x dense), parallel over column chunks.
fn product_add(dst: MatMut<'_, f64>, a: SparseColMatRef<'_, usize, f64>, x: MatRef<'_, f64>) {
    let w = chunk_width(dst.ncols());
    dst.par_col_chunks_mut(w).enumerate().for_each(|(c, d)| {
        let xc = x.subcols(c * w, d.ncols());
        sparse_dense_matmul(d, Accum::Add, a, xc, 1.0, Par::Seq);
    });
}

/// `a ← (a + aᵀ)/2` for a square matrix.
pub(crate) fn symmetrise(mut a: MatMut<'_, f64>) {
    for j in 0..a.ncols() {
        for i in 0..j {
            let v = 0.5 * (a[(i, j)] + a[(j, i)]);
            a[(i, j)] = v;
            a[(j, i)] = v;
        }
    }
}
