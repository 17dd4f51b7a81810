//! Craig–Bampton reduction with streamed static modes (`docs/theory.md`, "Craig–Bampton reduction"; Craig &
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
//! column blocks B of [`CbOptions::block_columns`], one block per thread at a time (rayon), each
//! block sequential and stored by rows in the factor's row order ([`crate::eigen::rows`]):
//! X = Ψ_B = −K_ii⁻¹ K_ib[:, B] (one multi-column solve), then
//! `K_cb_bb[:, B] = K_bb[:, B] + K_ibᵀ X`, `Y = M_ib[:, B] + M_ii X`, `M_cb_mb[:, B] = Φᵀ Y` and,
//! since `Ψᵀ Y = −K_ibᵀ K_ii⁻¹ Y` (a second solve), `M_cb_bb[:, B] = M_bb[:, B] + M_ibᵀ X −
//! K_ibᵀ K_ii⁻¹ Y`. Ψ is never stored whole: the memory beyond the factor is two n_i × |B|
//! blocks per thread plus the dense reduced matrices, at the price of two solves per master DOF
//! instead of one. Two of the four triangular sweeps are cut to part of the elimination tree
//! ([`CholeskyFactor::forward_reach`]): the forward sweep of the first solve runs only on the
//! reach of the rows of K_ib[:, B] (37 % of the factor's values per 64-column block on the issue-4
//! benchmark), and the backward sweep of the second only on the supernodes of the rows K_ibᵀ
//! reads and their ancestors (60 %); both give the same values as the full sweeps. Finally K_cb
//! and M_cb are symmetrised ((A + Aᵀ)/2; they are symmetric in exact
//! arithmetic, the asymmetry is round-off).

use faer::linalg::matmul::matmul;
use faer::sparse::{SparseColMat, SparseColMatRef, SymbolicSparseColMat};
use faer::{Accum, Mat, MatMut, Par};
use rayon::prelude::*;
use std::sync::Mutex;
use std::time::Instant;

use super::masters::Partition;
use crate::eigen::rows::{
    renumber_rows, scatter_rows, symmetric_product_rows, transpose_product_rows, RowBlock,
};
use crate::eigen::{CholeskyFactor, EigenOptions, ShiftInvert};
use crate::error::{Error, Result};

/// Options of the Craig–Bampton reduction.
#[derive(Clone, Debug, PartialEq)]
pub struct CbOptions {
    /// Number of fixed-interface modes n_m (0: static (Guyan) reduction only).
    pub interface_modes: usize,
    /// Master columns per static-mode block (memory: 2 × n_i × `block_columns` values per
    /// thread). Default 64: on the 47 000-DOF variant of the issue-4 benchmark 32 columns cost
    /// 1.4× the CPU time of 64 (each block reads the whole factor twice per solve).
    pub block_columns: usize,
    /// Options of the fixed-interface eigensolver (σ must stay 0: K_ii is factorised once).
    /// Default: [`EigenOptions::default`] with block size [`CB_EIGEN_BLOCK`].
    pub eigen: EigenOptions,
    /// Also return the basis Ψ, Φ ([`CraigBampton::basis`]) for projecting further matrices
    /// and loads of the same DOF (memory: n_i × (n_b + n_m) values). Default false.
    pub keep_basis: bool,
}

/// Block size of the fixed-interface eigensolver in [`CbOptions::default`]: 16 columns per
/// shift-invert application (8 per thread on 2 threads) instead of the eigensolver's default 8.
/// On the issue-4 benchmark's 47 000-DOF variant it needs 576 instead of 392 applications for 100
/// modes but 12 % less CPU time, the cost per column of a solve falling with the block width.
pub const CB_EIGEN_BLOCK: usize = 16;

impl Default for CbOptions {
    fn default() -> Self {
        CbOptions {
            interface_modes: 0,
            block_columns: 64,
            eigen: EigenOptions {
                block_size: CB_EIGEN_BLOCK,
                ..EigenOptions::default()
            },
            keep_basis: false,
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
    /// The basis T_CB, with [`CbOptions::keep_basis`].
    pub basis: Option<CbBasis>,
}

/// The interior rows of the Craig–Bampton basis T_CB = [[I, 0], [Ψ, Φ]]: the physical
/// displacement is u_b = q_b on the masters and u_i = Ψ q_b + Φ η on the interior DOF, rows in
/// the order of [`Partition::interior`], columns in reduced-coordinate order.
#[derive(Clone, Debug)]
pub struct CbBasis {
    /// Static constraint modes Ψ = −K_ii⁻¹ K_ib (n_i × n_b, dimensionless).
    pub psi: Mat<f64>,
    /// Fixed-interface modes Φ (n_i × n_m), mass-normalised (Φᵀ M_ii Φ = I).
    pub phi: Mat<f64>,
}

/// Wall time and CPU time (s) of the phases of [`craig_bampton`]. CPU time is the process's
/// user + system time over all threads (`/proc/self/stat`; 0 where it cannot be read), so it
/// includes other threads of the calling program if they run at the same time.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CbTimings {
    /// Partition of K and M, ordering and Cholesky factorisation of K_ii.
    pub factor_s: f64,
    /// Fixed-interface modes (block Krylov–Schur with the factor).
    pub modes_s: f64,
    /// Static modes streamed into K_cb and M_cb, and assembly of the reduced matrices.
    pub static_s: f64,
    /// CPU time of the factorisation phase.
    pub factor_cpu_s: f64,
    /// CPU time of the fixed-interface modes.
    pub modes_cpu_s: f64,
    /// CPU time of the static modes.
    pub static_cpu_s: f64,
}

/// User + system CPU time (s) of this process over all its threads so far, from fields 14 and
/// 15 of `/proc/self/stat` (clock ticks of 1/100 s, Linux's fixed `USER_HZ`); 0 if unreadable.
fn process_cpu_s() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // Fields after the command name (which may contain spaces) start at field 3.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| fields.get(i - 3).and_then(|f| f.parse::<f64>().ok());
    match (ticks(14), ticks(15)) {
        (Some(u), Some(s)) => (u + s) / 100.0,
        _ => 0.0,
    }
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
    let cpu0 = process_cpu_s();
    let Blocks {
        k_ii,
        m_ii,
        k_ib,
        m_ib,
    } = Blocks::split(k, m, partition);
    let factor = ShiftInvert::new(k_ii.as_ref(), m_ii.as_ref(), 0.0).map_err(|e| match e {
        Error::Compute(msg) => Error::Compute(format!(
            "Craig–Bampton: the interior stiffness K_ii cannot be factorised ({msg}). A part \
             of the model is neither clamped nor connected to a master node"
        )),
        other => other,
    })?;
    let factor_s = t0.elapsed().as_secs_f64();
    let cpu1 = process_cpu_s();
    let (lambda, residuals, phi) = if n_m > 0 {
        let modes = factor.lowest_modes(n_m, &opts.eigen)?;
        (modes.eigenvalues, modes.residuals, modes.vectors)
    } else {
        (Vec::new(), Vec::new(), Mat::zeros(n_i, 0))
    };
    let modes_s = t0.elapsed().as_secs_f64() - factor_s;
    let cpu2 = process_cpu_s();
    let basis = if opts.keep_basis {
        // Ψ = −K_ii⁻¹ K_ib, all master columns in one solve.
        let mut psi = Mat::<f64>::zeros(n_i, n_b);
        for j in 0..n_b {
            for (i, &v) in k_ib.row_idx_of_col(j).zip(k_ib.val_of_col(j)) {
                psi[(i, j)] = -v;
            }
        }
        factor.solve_in_place(psi.as_mut())?;
        Some(CbBasis {
            psi,
            phi: phi.clone(),
        })
    } else {
        None
    };

    // K_ii is not needed any more: release it before the static-mode blocks are allocated.
    let factor = factor.into_factor();
    drop(k_ii);
    let statics = StaticInputs {
        k_ib: renumber_rows(k_ib.as_ref(), factor.factor_rows()),
        m_ib: renumber_rows(m_ib.as_ref(), factor.factor_rows()),
        m_ii: m_ii.as_ref(),
        phi: factor_order_rows(phi, factor.factor_rows()),
        factor,
    };
    drop((k_ib, m_ib));
    let (k_bb, m_bb, m_mb) = statics.stream(k, m, partition, opts.block_columns)?;
    drop(statics);
    drop(m_ii);
    let (stiffness, mass) = assemble(k_bb, m_bb, m_mb, &lambda);
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
            factor_cpu_s: cpu1 - cpu0,
            modes_cpu_s: cpu2 - cpu1,
            static_cpu_s: process_cpu_s() - cpu2,
        },
        basis,
    })
}

/// What every static-mode block needs: the factor of K_ii, K_ib and M_ib with their rows in
/// the factor's order, M_ii (original order) and Φ with its rows in the factor's order.
struct StaticInputs<'a> {
    factor: CholeskyFactor,
    k_ib: SparseColMat<usize, f64>,
    m_ib: SparseColMat<usize, f64>,
    m_ii: SparseColMatRef<'a, usize, f64>,
    phi: Mat<f64>,
}

/// The work blocks of one thread: X = Ψ_B and Y (n_i × |B| each, stored by rows) and the solve
/// scratch.
struct StaticWork {
    x: RowBlock,
    y: RowBlock,
    scratch: Vec<f64>,
}

impl StaticWork {
    fn new(s: &StaticInputs<'_>, w: usize) -> Result<StaticWork> {
        let n_i = s.factor.n_dof();
        Ok(StaticWork {
            x: RowBlock::zeros(w, n_i)?,
            y: RowBlock::zeros(w, n_i)?,
            scratch: s.factor.row_scratch(w),
        })
    }
}

impl StaticInputs<'_> {
    /// K_cb_bb, M_cb_bb (n_b × n_b, symmetrised) and M_cb_mb (n_m × n_b) from the static modes,
    /// streamed in blocks of `w` master columns in parallel (module documentation).
    fn stream(
        &self,
        k: SparseColMatRef<'_, usize, f64>,
        m: SparseColMatRef<'_, usize, f64>,
        p: &Partition,
        w: usize,
    ) -> Result<(Mat<f64>, Mat<f64>, Mat<f64>)> {
        let mut master_index = vec![usize::MAX; p.n_free];
        for (new, d) in p.masters.iter().enumerate() {
            master_index[d.free_row] = new;
        }
        let master_rows = p.master_rows();
        let mut k_bb = dense_select(k, &master_index, &master_rows);
        let mut m_bb = dense_select(m, &master_index, &master_rows);
        let mut m_mb = Mat::<f64>::zeros(self.phi.ncols(), master_rows.len());
        // Work blocks are taken from a pool for each block and returned after it (a block has
        // no rayon join inside), so at most one pair per thread exists at any time.
        let pool = Mutex::new(Vec::<StaticWork>::new());
        // The supernodes whose rows K_ibᵀ reads, with their ancestors: the second backward
        // sweep of every block is needed only there.
        let coupled = self.factor.forward_reach(
            (0..self.k_ib.ncols())
                .flat_map(|j| self.k_ib.as_ref().row_idx_of_col_raw(j).iter().copied()),
        );
        k_bb.as_mut()
            .par_col_chunks_mut(w)
            .zip(m_bb.as_mut().par_col_chunks_mut(w))
            .zip(m_mb.as_mut().par_col_chunks_mut(w))
            .enumerate()
            .try_for_each(|(c, ((k_cols, m_cols), mb_cols))| {
                let pooled = pool.lock().ok().and_then(|mut p| p.pop());
                let mut work = match pooled {
                    Some(work) => work,
                    None => StaticWork::new(self, w)?,
                };
                self.block(
                    c * w,
                    coupled.as_deref(),
                    &mut work,
                    k_cols,
                    m_cols,
                    mb_cols,
                );
                if let Ok(mut p) = pool.lock() {
                    p.push(work);
                }
                Ok::<(), Error>(())
            })?;
        symmetrise(k_bb.as_mut());
        symmetrise(m_bb.as_mut());
        Ok((k_bb, m_bb, m_mb))
    }

    /// The columns `first..first + |B|` of K_cb_bb, M_cb_bb (on entry K_bb, M_bb) and M_cb_mb
    /// (module documentation, "Streaming"), sequential.
    fn block(
        &self,
        first: usize,
        coupled: Option<&[usize]>,
        work: &mut StaticWork,
        k_cols: MatMut<'_, f64>,
        mut m_cols: MatMut<'_, f64>,
        mb_cols: MatMut<'_, f64>,
    ) {
        let (w, n_i) = (k_cols.ncols(), self.factor.n_dof());
        // X = Ψ_B = −K_ii⁻¹ K_ib[:, B]; the forward sweep only on the reach of K_ib[:, B].
        work.x.reset(w, n_i);
        scatter_rows(&mut work.x, self.k_ib.as_ref(), first, -1.0);
        let rows = (first..first + w)
            .flat_map(|j| self.k_ib.as_ref().row_idx_of_col_raw(j).iter().copied());
        let reach = self.factor.forward_reach(rows);
        self.factor
            .forward_rows_in(&mut work.x, reach.as_deref(), &mut work.scratch);
        self.factor.backward_rows(&mut work.x, &mut work.scratch);
        // K_cb_bb[:, B] += K_ibᵀ Ψ_B
        transpose_product_rows(k_cols, self.k_ib.as_ref(), &work.x, 1.0);
        // Y = M_ib[:, B] + M_ii Ψ_B
        work.y.reset(w, n_i);
        scatter_rows(&mut work.y, self.m_ib.as_ref(), first, 1.0);
        symmetric_product_rows(
            &mut work.y,
            self.m_ii,
            self.factor.factor_rows(),
            &work.x,
            1.0,
        );
        if self.phi.ncols() > 0 {
            matmul(
                mb_cols,
                Accum::Replace,
                self.phi.transpose(),
                work.y.as_transposed().transpose(),
                1.0,
                Par::Seq,
            );
        }
        // M_cb_bb[:, B] += M_ibᵀ Ψ_B + Ψᵀ Y = M_ibᵀ Ψ_B − K_ibᵀ K_ii⁻¹ Y, the backward sweep
        // only on the supernodes K_ibᵀ reads (`coupled`).
        transpose_product_rows(m_cols.as_mut(), self.m_ib.as_ref(), &work.x, 1.0);
        self.factor.forward_rows(&mut work.y, &mut work.scratch);
        self.factor
            .backward_rows_in(&mut work.y, coupled, &mut work.scratch);
        transpose_product_rows(m_cols, self.k_ib.as_ref(), &work.y, -1.0);
    }
}

/// K_cb = [[K_cb_bb, 0], [0, diag λ]] and M_cb = [[M_cb_bb, M_cb_mbᵀ], [M_cb_mb, I]].
fn assemble(
    k_bb: Mat<f64>,
    m_bb: Mat<f64>,
    m_mb: Mat<f64>,
    lambda: &[f64],
) -> (Mat<f64>, Mat<f64>) {
    let (n_b, n_m) = (k_bb.nrows(), lambda.len());
    let n = n_b + n_m;
    let mut stiffness = Mat::<f64>::zeros(n, n);
    let mut mass = Mat::<f64>::zeros(n, n);
    stiffness
        .as_mut()
        .submatrix_mut(0, 0, n_b, n_b)
        .copy_from(&k_bb);
    drop(k_bb);
    mass.as_mut().submatrix_mut(0, 0, n_b, n_b).copy_from(&m_bb);
    drop(m_bb);
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
    (stiffness, mass)
}

/// `phi` with row `pinv[i]` holding its row i.
fn factor_order_rows(phi: Mat<f64>, pinv: &[usize]) -> Mat<f64> {
    let mut out = Mat::<f64>::zeros(phi.nrows(), phi.ncols());
    for j in 0..phi.ncols() {
        for (i, &p) in pinv.iter().enumerate() {
            out[(p, j)] = phi[(i, j)];
        }
    }
    out
}

/// The sparse partitioned blocks of K and M (K_bb and M_bb are extracted densely when the
/// static modes start, [`StaticInputs::stream`]).
struct Blocks {
    k_ii: SparseColMat<usize, f64>,
    m_ii: SparseColMat<usize, f64>,
    k_ib: SparseColMat<usize, f64>,
    m_ib: SparseColMat<usize, f64>,
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
        let master_rows = p.master_rows();
        Blocks {
            k_ii: select(k, &interior_index, &p.interior),
            m_ii: select(m, &interior_index, &p.interior),
            k_ib: select(k, &interior_index, &master_rows),
            m_ib: select(m, &interior_index, &master_rows),
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
