//! [`ShiftInvert`]: the sparse Cholesky factorisation `P (K − σM) Pᵀ = L Lᵀ` and the solves built
//! on it (full solves for static modes, half solves with `F = Pᵀ L` for the eigensolver).

use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::linalg::solvers::LltError;
use faer::perm::PermRef;
use faer::reborrow::{Reborrow, ReborrowMut};
use faer::sparse::linalg::cholesky::supernodal::SupernodalLltRef;
use faer::sparse::linalg::cholesky::{
    factorize_symbolic_cholesky, CholeskySymbolicParams, LltRef, SymbolicCholesky,
    SymbolicCholeskyRaw, SymmetricOrdering,
};
use faer::sparse::linalg::triangular_solve;
use faer::sparse::{SparseColMat, SparseColMatRef};
use faer::{Conj, Mat, MatMut, Par, Side};

use super::rows::CholeskyFactor;
use super::{input, ordering};
use crate::error::{Error, Result};

/// Smallest accepted pivot ratio `d_i / a_ii` (`d_i = L_ii²`, `a_ii` the diagonal entry of
/// K − σM that row i of the factor eliminates). Exact singularity (the rigid-body modes of a
/// free–free model at σ = 0) leaves a zero or negative pivot (then faer's factorisation fails) or
/// a positive one at round-off level, ~1e-15; a positive definite matrix has
/// `d_i / a_ii ≥ 1/κ(K − σM)`, so only condition numbers above 1e12 — where a residual of 1e-8 is
/// out of reach anyway — are rejected as well.
pub(super) const MIN_PIVOT_RATIO: f64 = 1e-12;

/// The factorised shifted matrix K − σM of a pencil (K, M), reusable for many solves and for the
/// eigensolver ([`ShiftInvert::lowest_modes`]).
///
/// Holds views of K (N/m) and M (kg) — they must outlive it — and the sparse Cholesky factor
/// `P (K − σM) Pᵀ = L Lᵀ` (faer's supernodal or simplicial LLᵀ; fill-reducing ordering P by
/// nested dissection or AMD, whichever gives the smaller factor, see [`FillOrdering`]).
/// With σ = 0 it is a factorisation of K itself, as Craig–Bampton needs for its static modes
/// Ψ = −K_ii⁻¹ K_ib ([`ShiftInvert::solve_in_place`]) and its fixed-interface modes (the same
/// factor, [`ShiftInvert::lowest_modes`]).
pub struct ShiftInvert<'a> {
    pub(super) k: SparseColMatRef<'a, usize, f64>,
    pub(super) m: SparseColMatRef<'a, usize, f64>,
    shift: f64,
    ordering: FillOrdering,
    min_pivot_ratio: f64,
    factor: CholeskyFactor,
}

impl std::fmt::Debug for ShiftInvert<'_> {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ShiftInvert")
            .field("n_dof", &self.n_dof())
            .field("shift", &self.shift)
            .field("factor_values", &self.factor.l_values.len())
            .field("ordering", &self.ordering)
            .field("min_pivot_ratio", &self.min_pivot_ratio)
            .finish()
    }
}

/// The parallelism of every faer call of this module: faer's global setting (rayon's global pool
/// by default).
pub(super) fn par() -> Par {
    faer::get_global_parallelism()
}

/// Number of threads of [`par`] (1 when sequential).
fn threads() -> usize {
    match par() {
        Par::Seq => 1,
        Par::Rayon(n) => n.get(),
    }
}

/// Smallest number of columns per parallel chunk in [`for_each_column_chunk`]: a triangular
/// solve costs per column about half as much with 4 columns as with 1 (the factor is read once
/// per chunk), so thinner chunks would waste the gain.
const MIN_CHUNK_COLUMNS: usize = 4;

/// Runs `f` on column chunks of `x`, at most one chunk per thread of [`par`] (rayon) and at least
/// [`MIN_CHUNK_COLUMNS`] columns per chunk, each chunk sequential. Triangular solves parallelise
/// far better across right-hand sides than inside the many small supernodes, where thread
/// synchronisation costs more than it saves (measured: half the time in futex calls).
pub(super) fn for_each_column_chunk(
    x: MatMut<'_, f64>,
    f: &(dyn Fn(MatMut<'_, f64>) -> Result<()> + Sync),
) -> Result<()> {
    let parts = threads().min(x.ncols() / MIN_CHUNK_COLUMNS).max(1);
    split_columns(x, parts, f)
}

/// [`for_each_column_chunk`] over `parts` chunks.
fn split_columns(
    x: MatMut<'_, f64>,
    parts: usize,
    f: &(dyn Fn(MatMut<'_, f64>) -> Result<()> + Sync),
) -> Result<()> {
    let left = parts / 2;
    let mid = x.ncols() * left / parts.max(1);
    if parts <= 1 || mid == 0 {
        return f(x);
    }
    let (a, b) = x.split_at_col_mut(mid);
    let (ra, rb) = rayon::join(
        || split_columns(a, left, f),
        || split_columns(b, parts - left, f),
    );
    ra.and(rb)
}

/// An [`Error::Compute`] for a failed allocation of `what`.
fn out_of_memory(what: &str) -> Error {
    Error::Compute(format!(
        "out of memory while allocating {what}; use a machine with more memory or a smaller model"
    ))
}

/// A work buffer for `req`, or an out-of-memory error.
pub(super) fn buffer(req: StackReq, what: &str) -> Result<MemBuffer> {
    MemBuffer::try_new(req).map_err(|_| out_of_memory(what))
}

impl<'a> ShiftInvert<'a> {
    /// Checks the pencil (see [`lowest_modes`](super::lowest_modes)) and factorises K − σM
    /// (`shift` = σ in rad²/s²) by sparse Cholesky: ordering (nested dissection or AMD) and
    /// symbolic analysis, then the
    /// numeric factorisation, in parallel.
    ///
    /// Errors: [`Error::Input`] for bad matrices or a non-finite σ; [`Error::Compute`] if K − σM
    /// is not positive definite (a non-positive pivot, or a pivot ratio `L_ii² / a_ii` below
    /// 1e-12): K is singular (rigid-body modes: is the model clamped? for a free–free model use a
    /// negative σ) or σ is at or above an eigenvalue.
    pub fn new(
        k: SparseColMatRef<'a, usize, f64>,
        m: SparseColMatRef<'a, usize, f64>,
        shift: f64,
    ) -> Result<Self> {
        input::check_pencil(k, m)?;
        check_shift(shift)?;
        let shifted = (shift != 0.0)
            .then(|| shifted_matrix(k, m, shift))
            .transpose()?;
        let a = shifted.as_ref().map_or(k, |s| s.as_ref());
        let (symbolic, ordering) = symbolic_analysis(a)?;
        let l_values = factorize_numeric(&symbolic, a, shift)?;
        let mut this = ShiftInvert {
            k,
            m,
            shift,
            ordering,
            min_pivot_ratio: 0.0,
            factor: CholeskyFactor::new(symbolic, l_values),
        };
        this.min_pivot_ratio = this.pivot_ratio(a);
        if this.min_pivot_ratio < MIN_PIVOT_RATIO {
            return Err(not_positive_definite(
                shift,
                &format!(
                    "its smallest pivot ratio L_ii²/a_ii is {:.1e} < {MIN_PIVOT_RATIO:e}, i.e. it \
                     is singular to working precision",
                    this.min_pivot_ratio
                ),
            ));
        }
        Ok(this)
    }

    /// The Cholesky factor `P (K − σM) Pᵀ = L Lᵀ` (row-stored solves, [`super::rows`]).
    pub fn factor(&self) -> &CholeskyFactor {
        &self.factor
    }

    /// The Cholesky factor alone, releasing the borrows of K and M (so the caller may drop
    /// them while it keeps solving).
    pub fn into_factor(self) -> CholeskyFactor {
        self.factor
    }

    /// The shift σ (rad²/s²) the factorisation was built with.
    pub fn shift(&self) -> f64 {
        self.shift
    }

    /// Number of DOF `N_dof` (rows of K and M).
    pub fn n_dof(&self) -> usize {
        self.k.nrows()
    }

    /// Number of values stored for the Cholesky factor L (supernodal storage counts the dense
    /// blocks in full); 8 bytes each.
    pub fn factor_len(&self) -> usize {
        self.factor.l_values.len()
    }

    /// The fill-reducing ordering of the factor (nested dissection or AMD, whichever gives the
    /// smaller factor).
    pub fn ordering(&self) -> FillOrdering {
        self.ordering
    }

    /// Smallest pivot ratio `L_ii² / a_ii` over the rows of the factor (dimensionless, in (0, 1]);
    /// a small value means K − σM is nearly singular.
    pub fn min_pivot_ratio(&self) -> f64 {
        self.min_pivot_ratio
    }

    /// Solves (K − σM) X = B in place: `rhs` holds B (`N_dof × n_rhs`) on entry and X on return.
    /// All columns are solved together (parallel dense kernels in the supernodal case). With σ = 0
    /// this gives the Craig–Bampton static modes, e.g. Ψ = −K_ii⁻¹ K_ib for B = −K_ib.
    ///
    /// Errors: [`Error::Input`] if `rhs` does not have `N_dof` rows; [`Error::Compute`] if the
    /// work buffer cannot be allocated.
    pub fn solve_in_place(&self, rhs: MatMut<'_, f64>) -> Result<()> {
        if rhs.nrows() != self.n_dof() {
            return Err(Error::input(format!(
                "solve_in_place: the right-hand side has {} rows but K − σM has {}; pass one row \
                 per DOF",
                rhs.nrows(),
                self.n_dof()
            )));
        }
        for_each_column_chunk(rhs, &|chunk| {
            let req = self
                .factor
                .symbolic
                .solve_in_place_scratch::<f64>(chunk.ncols(), Par::Seq);
            let mut mem = buffer(req, "the solve workspace")?;
            LltRef::new(&self.factor.symbolic, &self.factor.l_values).solve_in_place_with_conj(
                Conj::No,
                chunk,
                Par::Seq,
                MemStack::new(&mut mem),
            );
            Ok(())
        })
    }

    /// `rhs ← F⁻ᵀ rhs = Pᵀ L⁻ᵀ rhs` (backward substitution, then the inverse permutation),
    /// sequential.
    pub(super) fn backward_in_place(&self, mut rhs: MatMut<'_, f64>) -> Result<()> {
        match self.factor.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let l = SparseColMatRef::new(s.factor(), &self.factor.l_values);
                triangular_solve::solve_lower_triangular_transpose_in_place(
                    l,
                    Conj::No,
                    rhs.rb_mut(),
                    Par::Seq,
                );
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let mut mem = buffer(
                    s.solve_in_place_scratch::<f64>(rhs.ncols(), Par::Seq),
                    "the solve workspace",
                )?;
                SupernodalLltRef::new(s, &self.factor.l_values).l_transpose_solve_with_conj(
                    Conj::No,
                    rhs.rb_mut(),
                    Par::Seq,
                    MemStack::new(&mut mem),
                );
            }
        }
        let mut x = Mat::<f64>::zeros(rhs.nrows(), rhs.ncols());
        self.scatter(x.as_mut(), rhs.rb());
        rhs.copy_from(&x);
        Ok(())
    }

    /// `dst ← Pᵀ src`: `dst[perm[i]] = src[i]`.
    fn scatter(&self, mut dst: MatMut<'_, f64>, src: faer::MatRef<'_, f64>) {
        match self.factor.symbolic.perm() {
            Some(p) => {
                let fwd = p.arrays().0;
                for j in 0..src.ncols() {
                    for (i, &f) in fwd.iter().enumerate() {
                        dst[(f, j)] = src[(i, j)];
                    }
                }
            }
            None => dst.copy_from(src),
        }
    }

    /// The diagonal of L (row order of the factor).
    fn factor_diagonal(&self) -> Vec<f64> {
        match self.factor.symbolic.raw() {
            SymbolicCholeskyRaw::Simplicial(s) => {
                let l = SparseColMatRef::new(s.factor(), &self.factor.l_values);
                (0..l.ncols()).map(|j| l.val_of_col(j)[0]).collect()
            }
            SymbolicCholeskyRaw::Supernodal(s) => {
                let l = SupernodalLltRef::new(s, &self.factor.l_values);
                let mut d = Vec::with_capacity(s.nrows());
                for i in 0..s.n_supernodes() {
                    let block = l.supernode(i).val();
                    d.extend((0..block.ncols()).map(|c| block[(c, c)]));
                }
                d
            }
        }
    }

    /// `min_i L_ii² / a_ii` for the shifted matrix `a` (1 if a diagonal entry is not positive,
    /// which cannot happen after a successful factorisation).
    fn pivot_ratio(&self, a: SparseColMatRef<'_, usize, f64>) -> f64 {
        let diag = self.factor_diagonal();
        let fwd: Vec<usize> = match self.factor.symbolic.perm() {
            Some(p) => p.arrays().0.to_vec(),
            None => (0..diag.len()).collect(),
        };
        diag.iter()
            .zip(&fwd)
            .map(|(l, &orig)| {
                let a_ii = diagonal_entry(a, orig);
                if a_ii > 0.0 {
                    l * l / a_ii
                } else {
                    1.0
                }
            })
            .fold(1.0, f64::min)
    }
}

/// The stored diagonal entry `a_jj` (0 if absent); `a` has sorted columns.
fn diagonal_entry(a: SparseColMatRef<'_, usize, f64>, j: usize) -> f64 {
    match a.row_idx_of_col_raw(j).binary_search(&j) {
        Ok(p) => a.val_of_col(j)[p],
        Err(_) => 0.0,
    }
}

/// σ must be finite.
fn check_shift(shift: f64) -> Result<()> {
    if shift.is_finite() {
        return Ok(());
    }
    Err(Error::input(format!(
        "shift = {shift} is not a finite number; use 0 for a clamped model or a negative value \
         for a free–free one"
    )))
}

/// The fill-reducing ordering the symbolic analysis chose.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FillOrdering {
    /// faer's approximate minimum degree.
    Amd,
    /// nlrom's nested dissection (`ordering.rs`).
    NestedDissection,
}

/// Symbolic Cholesky analysis of the pattern of `a` (both triangles stored) with the given
/// ordering.
fn analyse_with(
    a: SparseColMatRef<'_, usize, f64>,
    ordering: FillOrdering,
) -> Result<SymbolicCholesky<usize>> {
    let nd = match ordering {
        FillOrdering::Amd => None,
        FillOrdering::NestedDissection => {
            let fwd = ordering::nested_dissection(a.symbolic());
            let inv = ordering::inverse(&fwd);
            Some((fwd, inv))
        }
    };
    let ord = match &nd {
        None => SymmetricOrdering::Amd,
        Some((fwd, inv)) => SymmetricOrdering::Custom(PermRef::new_checked(fwd, inv, a.nrows())),
    };
    factorize_symbolic_cholesky(
        a.symbolic(),
        Side::Lower,
        ord,
        CholeskySymbolicParams::default(),
    )
    .map_err(|e| {
        Error::Compute(format!(
            "symbolic Cholesky analysis of K − σM failed ({e:?}); the factor is too large for \
             this machine"
        ))
    })
}

/// Symbolic Cholesky analyses of `a` with nested dissection and with AMD; keeps the one with
/// the smaller factor (stored values, supernodal blocks counted in full), which is nested
/// dissection on 3-D meshes and lattices (0.65× AMD's on the 30³ lattice; 38.1 M values on the
/// 50×50×48 one, `docs/performance.md`) and may be AMD on thin or small models. The symbolic analyses cost little next to
/// the numeric factorisation.
fn symbolic_analysis(
    a: SparseColMatRef<'_, usize, f64>,
) -> Result<(SymbolicCholesky<usize>, FillOrdering)> {
    let nd = analyse_with(a, FillOrdering::NestedDissection)?;
    let amd = analyse_with(a, FillOrdering::Amd)?;
    Ok(if nd.len_val() <= amd.len_val() {
        (nd, FillOrdering::NestedDissection)
    } else {
        (amd, FillOrdering::Amd)
    })
}

/// K − σM on the union of the two patterns.
fn shifted_matrix(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    shift: f64,
) -> Result<SparseColMat<usize, f64>> {
    faer::sparse::ops::binary_op(k, m, |a, b| {
        a.copied().unwrap_or(0.0) - shift * b.copied().unwrap_or(0.0)
    })
    .map_err(|_| out_of_memory("K − σM"))
}

/// The numeric Cholesky factor values of `a` (= K − σM) for the analysed `symbolic`.
fn factorize_numeric(
    symbolic: &SymbolicCholesky<usize>,
    a: SparseColMatRef<'_, usize, f64>,
    shift: f64,
) -> Result<Vec<f64>> {
    let mut values = Vec::new();
    values
        .try_reserve_exact(symbolic.len_val())
        .map_err(|_| out_of_memory("the Cholesky factor"))?;
    values.resize(symbolic.len_val(), 0.0);
    let req = symbolic.factorize_numeric_llt_scratch::<f64>(par(), Default::default());
    let mut mem = buffer(req, "the factorisation workspace")?;
    let result = symbolic.factorize_numeric_llt(
        &mut values,
        a,
        Side::Lower,
        Default::default(),
        par(),
        MemStack::new(&mut mem),
        Default::default(),
    );
    match result {
        Ok(_) => Ok(values),
        Err(LltError::NonPositivePivot { index }) => Err(not_positive_definite(
            shift,
            &format!("the Cholesky factorisation met a non-positive pivot in row {index} of the reordered matrix"),
        )),
    }
}

/// The error for a K − σM that is not positive definite; `why` says how it was detected.
fn not_positive_definite(shift: f64, why: &str) -> Error {
    Error::Compute(format!(
        "K − σM (σ = {shift:e} rad²/s²) is not positive definite: {why}. Either K is singular — \
         is the model clamped? for a free–free model set a negative shift, a few percent of the \
         lowest elastic eigenvalue ω₁² — or the shift is at or above an eigenvalue; lower it"
    ))
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    // Every column is visited exactly once, whatever the chunking.
    #[test]
    fn column_chunks_cover_every_column_once() {
        for ncols in [0, 1, 3, 4, 7, 8, 9, 33] {
            let mut x = Mat::<f64>::zeros(5, ncols);
            for_each_column_chunk(x.as_mut(), &|mut chunk| {
                for j in 0..chunk.ncols() {
                    for i in 0..chunk.nrows() {
                        chunk[(i, j)] += 1.0;
                    }
                }
                Ok(())
            })
            .unwrap();
            assert!(
                x.col_iter().all(|c| c.iter().all(|&v| v == 1.0)),
                "ncols = {ncols}"
            );
        }
    }

    // Errors of a chunk are returned, not lost.
    #[test]
    fn column_chunk_errors_propagate() {
        let mut x = Mat::<f64>::zeros(2, 16);
        let r = for_each_column_chunk(x.as_mut(), &|_| Err(Error::Compute("boom".into())));
        assert!(matches!(r, Err(Error::Compute(m)) if m == "boom"));
    }

    /// The 7-point Laplacian on an n³ grid (Dirichlet outside) plus `shift` on the diagonal,
    /// both triangles stored (also used by the tests of `rows.rs`).
    pub(in crate::eigen) fn lattice(n: usize, shift: f64) -> SparseColMat<usize, f64> {
        let id = |i: usize, j: usize, k: usize| i + n * (j + n * k);
        let mut t = Vec::new();
        for k in 0..n {
            for j in 0..n {
                for i in 0..n {
                    let p = id(i, j, k);
                    t.push(faer::sparse::Triplet::new(p, p, 6.0 + shift));
                    for (di, dj, dk) in [(1, 0, 0), (0, 1, 0), (0, 0, 1)] {
                        if i + di < n && j + dj < n && k + dk < n {
                            let q = id(i + di, j + dj, k + dk);
                            t.push(faer::sparse::Triplet::new(p, q, -1.0));
                            t.push(faer::sparse::Triplet::new(q, p, -1.0));
                        }
                    }
                }
            }
        }
        SparseColMat::try_new_from_triplets(n * n * n, n * n * n, &t).unwrap()
    }

    // Nested dissection against AMD on a 3-D lattice (30³): a smaller factor, and the analysis
    // keeps it. Measured: see the printed sizes.
    #[test]
    fn nested_dissection_beats_amd_on_a_3d_lattice() {
        let k = lattice(30, 0.0);
        let nd = analyse_with(k.as_ref(), FillOrdering::NestedDissection).unwrap();
        let amd = analyse_with(k.as_ref(), FillOrdering::Amd).unwrap();
        println!(
            "30³ lattice factor values: nested dissection {}, AMD {} (ratio {:.2})",
            nd.len_val(),
            amd.len_val(),
            nd.len_val() as f64 / amd.len_val() as f64
        );
        assert!(nd.len_val() < amd.len_val());
        let si = ShiftInvert::new(k.as_ref(), k.as_ref(), 0.0).unwrap();
        assert_eq!(si.ordering(), FillOrdering::NestedDissection);
        // The factorisation with the custom permutation solves correctly: K x = K 1 gives x = 1.
        let ones = Mat::<f64>::from_fn(k.nrows(), 1, |_, _| 1.0);
        let mut x = &k * &ones;
        si.solve_in_place(x.as_mut()).unwrap();
        assert!((&x - &ones).norm_max() < 1e-10);
    }
}
