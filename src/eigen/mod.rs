//! Sparse generalized symmetric eigensolver: the lowest `n` modes of K φ = λ M φ.
//!
//! Symbols: K the stiffness matrix (N/m, symmetric positive semi-definite), M the mass matrix (kg,
//! symmetric positive definite, or semi-definite with massless DOFs), λ = ω² the eigenvalue
//! (rad²/s²), ω the circular frequency (rad/s), φ the mode shape (mass-normalised: φᵀ M φ = 1),
//! σ the shift (rad²/s², below the lowest eigenvalue), n the number of wanted modes, `N_dof` the
//! size of K and M.
//!
//! # Method: shift-invert block Krylov–Schur with the Cholesky factor of the shifted matrix
//! 1. Sparse Cholesky (faer; supernodal or simplicial as faer picks, parallel; fill-reducing
//!    ordering: nlrom's nested dissection (`ordering.rs`) or faer's AMD, whichever gives the
//!    smaller factor — nested dissection on 3-D meshes) of
//!    the shifted matrix `P (K − σM) Pᵀ = L Lᵀ`; write `F = Pᵀ L`, so `K − σM = F Fᵀ`. It exists
//!    only if σ lies below every eigenvalue (σ = 0 for a clamped model, σ < 0 for a free–free one
//!    with rigid-body modes). [`ShiftInvert`] holds it; the same object solves (K − σM) X = B for
//!    many right-hand sides (Craig–Bampton static modes).
//! 2. With `y = Fᵀ φ` the pencil becomes the standard symmetric problem
//!    `A y = θ y`, `A = F⁻¹ M F⁻ᵀ`, `θ = 1/(λ − σ)`:
//!    from `F Fᵀ φ = (λ − σ) M φ` follows `y = (λ − σ) F⁻¹ M F⁻ᵀ y`. A is symmetric positive
//!    (semi-)definite in the plain inner product; its largest θ are the lowest λ. One
//!    application of A costs a forward and a backward triangular solve and a product with M — the
//!    same as one shifted solve. This differs from the textbook `A = L_Mᵀ (K − σM)⁻¹ L_M`
//!    (M = L_M L_Mᵀ) only in the factor used for the symmetrising change of variables, so the
//!    spectrum and the Krylov iteration are the same; it needs no second factorisation (for a
//!    consistent mass matrix that would double the factorisation time and memory) and no positive
//!    definite M (massless DOFs give θ = 0, i.e. λ = ∞, never among the wanted modes).
//! 3. The largest θ by block Krylov–Schur (thick-restart block Lanczos, block size b = 8 by
//!    default, full re-orthogonalisation by classical Gram–Schmidt done twice, explicit
//!    Rayleigh–Ritz; see `lanczos.rs`). faer's single-vector
//!    [`partial_self_adjoint_eigen`](faer::matrix_free::eigen::partial_self_adjoint_eigen) was
//!    tried first and rejected: a single-vector Krylov space holds one copy of a repeated
//!    eigenvalue, and on the 40×40×40 lattice of the tests it returned 3 of the 6 copies of a
//!    6-fold eigenvalue and 2 of 3 of a triple one (so the 20 "lowest" modes skipped four), at
//!    every tolerance down to 1e-12; it also spent as much time re-orthogonalising as solving.
//!    A block of b vectors finds multiplicities up to b reliably (higher ones usually, through
//!    round-off, without a guarantee) and lets each application solve b right-hand sides at once,
//!    which reads the factor once per block (measured: ~3× cheaper per column for b = 8).
//! 4. Back-transformation `φ = F⁻ᵀ y` (multi-column backward solve), eigenvalue from the
//!    Rayleigh quotient `λ = φᵀKφ / φᵀMφ` (second-order accurate, and free of the cancellation in
//!    `σ + 1/θ` for rigid-body modes), mass normalisation, ascending sort.
//!
//! Problems with `N_dof ≤ m + b` (m the Krylov basis size) are solved densely: A is applied to
//! the identity and faer's dense self-adjoint eigensolver takes over.
//!
//! # Residual (reported per mode, checked against [`EigenOptions::tolerance`])
//! `r = ‖Kφ − λMφ‖₂ / max(‖(K − σM)φ‖₂, τ ‖K‖₁ ‖φ‖₂)`, τ = 1e-6.
//! * The numerator is shift-invariant (`Kφ − λMφ = (K − σM)φ − (λ − σ)Mφ`).
//! * For σ = 0 the first term of the denominator is `‖Kφ‖₂`: r is the usual relative residual;
//!   for an elastic mode of a free–free model (λ ≫ |σ|) it is ≈ `‖Kφ‖₂` too. It is the relative
//!   residual of the shifted pencil, the quantity the shift-invert iteration controls.
//! * Round-off leaves any computed φ with a residual of about `ε ‖K‖ ‖φ‖` (ε = 2.2e-16), so the
//!   relative residual cannot fall below about `ε ‖K‖ ‖φ‖ / ‖(K − σM)φ‖` — 2e-8 when
//!   `‖(K − σM)φ‖ = 1e-8 ‖K‖ ‖φ‖`, as for a rigid-body mode with a small shift (`‖(K − σM)φ‖ ≈ |σ| ‖Mφ‖`) or an
//!   elastic mode with `λ/λ_max ≈ 1e-8` in a stiff model. Modes with
//!   `‖(K − σM)φ‖₂ < τ ‖K‖₁ ‖φ‖₂` are therefore measured against that floor instead: `r ≤ tol`
//!   then means a normwise backward error `‖Kφ − λMφ‖ / (‖K‖₁ ‖φ‖) ≤ τ · tol` (1e-14 for the
//!   default tolerance), i.e. (λ, φ) is exact for a K perturbed at round-off level.
//!
//! If any returned mode exceeds the tolerance after the tightening retries, the call fails with an
//! [`Error::Compute`] naming the mode, its residual and the tolerance.
//!
//! # Choice of the shift
//! σ = 0 for a clamped model. For a free–free model σ must be negative; `K − σM` then has the
//! condition number ≈ λ_max/|σ|, and the modes lose accuracy as it grows. On the 30×30×33 free
//! lattice (λ₁ = 1.8e4 for the first elastic mode, λ_max ≈ 2.4e7) σ = −100, −1.8, −0.18 and
//! −0.01 (condition number up to 2.4e9) all meet the default tolerance (worst residual 8e-9 at
//! −0.01), while σ = −1e-4 fails loudly (residual 6e-5). Keep λ_max/|σ| below about 1e9; a few
//! percent of λ₁ (e.g. `−(0.2 · 2π f₁)²` for an expected first frequency f₁) is a safe choice.
//!
//! # Parallelism
//! All faer calls use [`faer::get_global_parallelism`], which faer initialises to
//! `Par::rayon(0)` (every thread of rayon's global pool; `RAYON_NUM_THREADS` limits it); the CLI
//! may change it with [`faer::set_global_parallelism`] (faer panics if its global parallelism
//! was disabled with `faer::disable_global_parallelism`; nlrom never does). The numeric
//! factorisation runs in parallel inside faer. Triangular solves are parallelised across
//! right-hand sides: the columns are split into one chunk per thread (at least 4 columns per
//! chunk), each solved sequentially — faer's parallelism inside the many small supernodes of a
//! solve spent half its time in thread synchronisation. The solves of the iteration keep each
//! chunk stored by rows in the factor's order (`rows.rs`). Products with the Krylov basis
//! (Gram–Schmidt, restarts) are split into row chunks over rayon's threads, each chunk a
//! sequential faer product (faer's own parallel product synchronised its threads more than it
//! computed on these thin products).

mod dense;
mod input;
mod krylov;
mod lanczos;
mod ordering;
pub mod pencil;
pub mod rows;
mod shift_invert;

pub use dense::{self_adjoint_eigen_qr, self_adjoint_eigenvalues_qr};
pub use pencil::{
    frequencies_hz, hermitian_eigenvalues, hermitian_modes, symmetric_modes, DenseModes,
};
pub use rows::CholeskyFactor;
pub use shift_invert::{FillOrdering, ShiftInvert};

use faer::sparse::SparseColMatRef;
use faer::Mat;

use crate::error::{Error, Result};

/// Options of the eigensolver.
#[derive(Clone, Debug, PartialEq)]
pub struct EigenOptions {
    /// The shift σ (rad²/s²), strictly below the lowest eigenvalue: 0 for a clamped model, a
    /// negative value for a free–free one (a few percent of the lowest elastic eigenvalue λ₁ in
    /// magnitude; see "Choice of the shift" in the module documentation). Default 0.
    pub shift: f64,
    /// Largest accepted residual r of a returned mode (dimensionless; the relative residual
    /// defined in the module documentation). Default 1e-8; must lie in [1e-14, 1e-1].
    pub tolerance: f64,
    /// Krylov basis size m before a restart (vectors of `N_dof` values each; memory
    /// `8 (m + b) N_dof` bytes). 0 (default) means `max(2n, n + 6b, 10b)` with b =
    /// `block_size`; values below `n + 2b` are raised to it. Larger values need fewer restarts.
    pub subspace_dim: usize,
    /// Largest number of thick restarts of the Krylov–Schur iteration per convergence check
    /// (each restart adds about `(m − n) / 2` basis vectors, i.e. as many shifted solves).
    /// Default 200.
    pub max_restarts: usize,
    /// Block size b of the block Krylov–Schur iteration: columns per shift-invert application.
    /// Eigenvalues of multiplicity up to b are found reliably. Default 8; must be ≥ 1.
    pub block_size: usize,
}

impl Default for EigenOptions {
    fn default() -> Self {
        EigenOptions {
            shift: 0.0,
            tolerance: 1e-8,
            subspace_dim: 0,
            max_restarts: 200,
            block_size: 8,
        }
    }
}

impl EigenOptions {
    /// Checks the ranges documented on the fields ([`Error::Input`] otherwise).
    pub fn validate(&self) -> Result<()> {
        if !self.shift.is_finite() {
            return Err(Error::input(format!(
                "eigen options: shift = {} is not a finite number; use 0 for a clamped model or a \
                 negative value for a free–free one",
                self.shift
            )));
        }
        if !(1e-14..=1e-1).contains(&self.tolerance) {
            return Err(Error::input(format!(
                "eigen options: tolerance = {:e} is outside [1e-14, 1e-1]; the default is 1e-8",
                self.tolerance
            )));
        }
        if self.block_size == 0 {
            return Err(Error::input(
                "eigen options: block_size = 0; use at least 1 (default 8)",
            ));
        }
        if self.max_restarts == 0 {
            return Err(Error::input(
                "eigen options: max_restarts = 0; use at least 1 (default 200)",
            ));
        }
        Ok(())
    }
}

/// The lowest modes of a pencil (K, M), sorted by ascending eigenvalue.
#[derive(Clone, Debug)]
pub struct Modes {
    /// Eigenvalues λ = ω² (rad²/s²), ascending; Rayleigh quotients φᵀKφ of the returned vectors.
    pub eigenvalues: Vec<f64>,
    /// Mode shapes, one per column (`N_dof × n`), mass-normalised (φᵀ M φ = 1), in the order of
    /// `eigenvalues`.
    pub vectors: Mat<f64>,
    /// Residual r of each mode (dimensionless): `‖Kφ − λMφ‖₂ / max(‖(K − σM)φ‖₂,
    /// 1e-6 ‖K‖₁ ‖φ‖₂)`, see the module documentation.
    pub residuals: Vec<f64>,
    /// Number of columns the shift-invert operator was applied to in total (each a forward and
    /// a backward triangular solve); a cost measure.
    pub operator_applications: usize,
}

impl Modes {
    /// Natural frequencies f = √max(λ, 0) / 2π (Hz); rigid-body modes with a slightly negative
    /// computed λ give 0.
    pub fn frequencies_hz(&self) -> Vec<f64> {
        self.eigenvalues
            .iter()
            .map(|&l| l.max(0.0).sqrt() / (2.0 * std::f64::consts::PI))
            .collect()
    }

    /// Number of modes.
    pub fn len(&self) -> usize {
        self.eigenvalues.len()
    }

    /// Whether no mode is held.
    pub fn is_empty(&self) -> bool {
        self.eigenvalues.is_empty()
    }
}

/// The lowest `n` modes of K φ = λ M φ: factorises K − σM (σ = `opts.shift`) with
/// [`ShiftInvert::new`] and calls [`ShiftInvert::lowest_modes`]; see the module documentation for
/// the method.
///
/// `k` (N/m) and `m` (kg) are square, of the same size `N_dof`, stored with both triangles and
/// sorted row indices. Errors: [`Error::Input`] for bad matrices, options or `n` (0 or ≥ `N_dof`);
/// [`Error::Compute`] if K − σM is not positive definite (singular K of a free–free model with
/// σ = 0, or σ above an eigenvalue) or a mode does not converge.
pub fn lowest_modes(
    k: SparseColMatRef<'_, usize, f64>,
    m: SparseColMatRef<'_, usize, f64>,
    n: usize,
    opts: &EigenOptions,
) -> Result<Modes> {
    opts.validate()?;
    ShiftInvert::new(k, m, opts.shift)?.lowest_modes(n, opts)
}
