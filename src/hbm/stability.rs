//! Stability of a harmonic balance solution by Hill's method on the uncondensed model
//! (`docs/theory.md`, "Stability: Hill's method").
//!
//! Method (von Groll & Ewins, J. Sound Vib. 241 (2001) 223–233; in the quadratic form of
//! Detroux, Renson, Masset & Kerschen, CMAME 296 (2015) 18–38, §3): a perturbation
//! y(t) = e^{λt} p(t) of the periodic solution, p with the period 2π/ω, written with
//! slowly varying harmonic coefficients P(t) in the real layout, satisfies
//! Δ₂ P̈ + Δ₁ Ṗ + Δ₀ P = 0 with, per harmonic n (complex 2×2-embedded as in SAMA eq. 24),
//! - Δ₀ = D⁽ⁿ⁾(ω) + ∂F_nl/∂Q (the uncondensed harmonic balance Jacobian, eqs. 12, 21),
//! - Δ₁ = C + 2 i nω M,
//! - Δ₂ = M.
//!
//! The quadratic eigenproblem (λ² Δ₂ + λ Δ₁ + Δ₀) P = 0 is solved through its companion form
//! [[0, I], [−Δ₂⁻¹Δ₀, −Δ₂⁻¹Δ₁]]. Every Floquet exponent appears (approximately) repeated at
//! λ + i jω; the 2N exponents kept are those with the smallest |Im λ| (N = DOF of the time
//! domain system) — the selection criterion of Detroux et al. §3.2 (also Peletan et al.,
//! Nonlinear Dyn. 72 (2013) 671–682). The solution is stable when every kept exponent has
//! Re λ ≤ `tolerance`·ω.
//!
//! Choice: the uncondensed model. The condensation of eqs. 15–18 eliminates the linear DOFs
//! with a frequency-dependent D_LL⁻¹(nω), which turns the eigenproblem into a nonlinear one in
//! λ; on the uncondensed system it stays quadratic. The cost is a dense eigenproblem of size
//! 2·Σ_n (rows of harmonic n)·(1 or 2), so this is meant for small models and ROMs (see
//! [`MAX_HILL_SIZE`]).
//!
//! Limitations: the friction sliders' memory is not a state of the Hill problem (the
//! AFT Jacobian already contains the periodic slider dependence), and the AFT Jacobian of a
//! nonsmooth law is its almost-everywhere derivative. With cyclic symmetry, harmonics on
//! different harmonic indices have blocks of different sizes; N is then the size of the block of
//! harmonic 1 and the selection is approximate.

use faer::linalg::solvers::Solve;
use faer::{c64, Mat};

use super::system::HbmSystem;
use crate::error::{Error, Result};
use crate::harmonics::HarmonicForce;

/// Largest companion matrix (2 × real Hill size) the dense eigensolver is asked for.
pub const MAX_HILL_SIZE: usize = 6000;

/// Settings of the stability test.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HillOptions {
    /// Stable when max Re λ ≤ `tolerance`·ω over the kept exponents (–).
    pub tolerance: f64,
}

impl Default for HillOptions {
    fn default() -> Self {
        HillOptions { tolerance: 1e-6 }
    }
}

/// The Floquet exponents of a periodic solution and the verdict.
#[derive(Clone, Debug, PartialEq)]
pub struct Floquet {
    /// The 2N kept exponents λ (1/s), sorted by |Im λ|.
    pub exponents: Vec<c64>,
    /// max Re λ over the kept exponents (1/s).
    pub max_real: f64,
    /// max Re λ ≤ tolerance·ω.
    pub stable: bool,
}

/// Whether the solution `q` (condensed real harmonic vector) at ω (rad/s), with the force
/// memory `state` (a converged point's state, e.g. `FrfPoint::state`), is stable by Hill's
/// method with the default tolerance.
pub fn is_stable<F: HarmonicForce>(
    system: &HbmSystem<'_, F>,
    q: &[f64],
    omega: f64,
    state: &F::State,
) -> Result<bool> {
    Ok(floquet(system, q, omega, state, &HillOptions::default())?.stable)
}

/// Offsets of each harmonic's coefficients in the Hill vector: n = 0 has one real coefficient
/// per row of its block, n ≥ 1 two (Re, Im) interleaved per row.
struct HillLayout {
    offsets: Vec<usize>,
    rows: Vec<usize>,
    len: usize,
}

impl HillLayout {
    fn new(rows: Vec<usize>) -> HillLayout {
        let mut offsets = Vec::with_capacity(rows.len());
        let mut len = 0;
        for (n, &r) in rows.iter().enumerate() {
            offsets.push(len);
            len += if n == 0 { r } else { 2 * r };
        }
        HillLayout { offsets, rows, len }
    }

    /// Index of (harmonic n, row i, part 0 = Re / 1 = Im).
    fn index(&self, n: usize, i: usize, part: usize) -> usize {
        if n == 0 {
            self.offsets[0] + i
        } else {
            self.offsets[n] + 2 * i + part
        }
    }
}

/// Adds the real embedding of the complex matrix `a` of harmonic n into `out` (n = 0: its real
/// part only).
fn add_embedded(out: &mut Mat<f64>, layout: &HillLayout, n: usize, a: &Mat<c64>) {
    let rows = layout.rows[n];
    for i in 0..rows {
        for j in 0..rows {
            let v = a[(i, j)];
            if n == 0 {
                out[(layout.index(0, i, 0), layout.index(0, j, 0))] += v.re;
                continue;
            }
            let (r, c) = (layout.index(n, i, 0), layout.index(n, j, 0));
            out[(r, c)] += v.re;
            out[(r, c + 1)] -= v.im;
            out[(r + 1, c)] += v.im;
            out[(r + 1, c + 1)] += v.re;
        }
    }
}

/// The Hill matrices of a solution (see the module documentation), real, `layout.len` square.
struct HillMatrices {
    /// Δ₀ = D(ω) + ∂F_nl/∂Q (N/m).
    d0: Mat<f64>,
    /// Δ₁ = C + 2 i nω M (N·s/m).
    d1: Mat<f64>,
    /// Δ₂ = M (kg).
    d2: Mat<f64>,
    layout: HillLayout,
}

/// The Hill matrices Δ₀, Δ₁, Δ₂ (see the module documentation) at the solution.
fn hill_matrices<F: HarmonicForce>(
    system: &HbmSystem<'_, F>,
    q: &[f64],
    omega: f64,
    state: &F::State,
) -> Result<HillMatrices> {
    let linear = system.linear();
    let h = system.layout().harmonics;
    let blocks: Vec<_> = (0..=h).map(|n| linear.uncondensed(n)).collect();
    let layout = HillLayout::new(blocks.iter().map(|b| b.stiffness.nrows()).collect());
    if 2 * layout.len > MAX_HILL_SIZE {
        return Err(Error::input(format!(
            "stability: Hill's method on the uncondensed model needs a dense {0}×{0} eigenproblem (more than {MAX_HILL_SIZE}); use fewer harmonics or a smaller ROM, or leave the stability flag off",
            2 * layout.len
        )));
    }
    let size = layout.len;
    let mut d0 = Mat::<f64>::zeros(size, size);
    let mut d1 = Mat::<f64>::zeros(size, size);
    let mut d2 = Mat::<f64>::zeros(size, size);
    for (n, b) in blocks.iter().enumerate() {
        let s = n as f64 * omega;
        let dynamic = Mat::from_fn(b.stiffness.nrows(), b.stiffness.ncols(), |i, j| {
            b.stiffness[(i, j)] - b.mass[(i, j)] * (s * s) + b.damping[(i, j)] * c64::new(0.0, s)
        });
        let first = Mat::from_fn(b.mass.nrows(), b.mass.ncols(), |i, j| {
            b.damping[(i, j)] + b.mass[(i, j)] * c64::new(0.0, 2.0 * s)
        });
        add_embedded(&mut d0, &layout, n, &dynamic);
        add_embedded(&mut d1, &layout, n, &first);
        add_embedded(&mut d2, &layout, n, &b.mass);
    }
    add_force_jacobian(system, q, state, &layout, &mut d0)?;
    Ok(HillMatrices { d0, d1, d2, layout })
}

/// Adds ∂F_nl/∂Q (condensed layout) at the nonlinear rows (the first rows of every block).
fn add_force_jacobian<F: HarmonicForce>(
    system: &HbmSystem<'_, F>,
    q: &[f64],
    state: &F::State,
    layout: &HillLayout,
    d0: &mut Mat<f64>,
) -> Result<()> {
    let hl = system.layout();
    let nd = system.linear().n_condensed();
    let dim = hl.len(nd);
    if q.len() != dim {
        return Err(Error::Compute(format!(
            "stability: a harmonic vector of length {} for {dim} unknowns",
            q.len()
        )));
    }
    let mut jac = Mat::<f64>::zeros(dim, dim);
    let mut force = vec![0.0; dim];
    let mut s = state.clone();
    system
        .force()
        .evaluate(&hl, q, &mut s, &mut force, Some(jac.as_mut()))?;
    // condensed index → Hill index
    let mut map = vec![0; dim];
    for i in 0..nd {
        map[hl.static_index(i)] = layout.index(0, i, 0);
        for n in 1..=hl.harmonics {
            let c = hl.cos_index(n, i, nd);
            map[c] = layout.index(n, i, 0);
            map[c + 1] = layout.index(n, i, 1);
        }
    }
    for r in 0..dim {
        for c in 0..dim {
            d0[(map[r], map[c])] += jac[(r, c)];
        }
    }
    Ok(())
}

/// The Floquet exponents of the solution `q` at ω (rad/s) from the memory `state` by Hill's
/// method, and the stability verdict.
pub fn floquet<F: HarmonicForce>(
    system: &HbmSystem<'_, F>,
    q: &[f64],
    omega: f64,
    state: &F::State,
    opts: &HillOptions,
) -> Result<Floquet> {
    let HillMatrices { d0, d1, d2, layout } = hill_matrices(system, q, omega, state)?;
    let size = layout.len;
    // −Δ₂⁻¹ [Δ₀ Δ₁]
    let lu = d2.partial_piv_lu();
    let mut rhs = Mat::<f64>::zeros(size, 2 * size);
    rhs.as_mut().subcols_mut(0, size).copy_from(&d0);
    rhs.as_mut().subcols_mut(size, size).copy_from(&d1);
    lu.solve_in_place(rhs.as_mut());
    if !rhs.as_ref().is_all_finite() {
        return Err(Error::Compute(
            "stability: the mass matrix of the Hill problem is singular".into(),
        ));
    }
    let companion = Mat::from_fn(2 * size, 2 * size, |i, j| {
        if i < size {
            if j == size + i {
                1.0
            } else {
                0.0
            }
        } else {
            -rhs[(i - size, j)]
        }
    });
    let mut eigenvalues = companion
        .eigenvalues()
        .map_err(|e| Error::Compute(format!("stability: the eigensolver failed ({e:?})")))?;
    eigenvalues.sort_by(|a, b| a.im.abs().total_cmp(&b.im.abs()));
    let n_phys = if layout.rows.len() > 1 {
        layout.rows[1]
    } else {
        layout.rows[0]
    };
    eigenvalues.truncate(2 * n_phys);
    let max_real = eigenvalues
        .iter()
        .map(|l| l.re)
        .fold(f64::NEG_INFINITY, f64::max);
    Ok(Floquet {
        stable: max_real <= opts.tolerance * omega,
        exponents: eigenvalues,
        max_real,
    })
}
