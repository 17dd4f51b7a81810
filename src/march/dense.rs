//! Small dense row-major matrices of the march (the damper has 3 DOF, matrix-defined systems and
//! reduced models a few hundred at most): matrix–vector products, inverses and spectral radii.
//! Factorisations and eigenvalues use faer.

use std::mem::MaybeUninit;

use faer::Mat;

use crate::nonlinear::lu::PackedLu;

/// Vectors from this length on take the VEX-encoded kernel of [`dot`] where the CPU has AVX.
const VEX_FROM: usize = 64;

/// xᵀ y, summed in eight interleaved partial sums ([`dot_baseline`]). From `VEX_FROM` (64)
/// entries on, on an x86-64 CPU with AVX, the same operations in the same order run in
/// VEX-encoded instructions (the same result to the bit): SSE-encoded instructions slow down while
/// the upper halves of the vector registers are in use (left so by a kernel of another library,
/// here faer's AVX-512 kernels, after which this module clears them), the VEX-encoded ones do
/// not. Measured on the sector's pass over [A_stick⁻¹P, −A_stick⁻¹C] (289 × 578): 101 µs
/// SSE-encoded with the upper halves in use, 37 µs without, 36 µs VEX-encoded in either case.
pub fn dot(x: &[f64], y: &[f64]) -> f64 {
    #[cfg(target_arch = "x86_64")]
    if x.len() >= VEX_FROM && std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX, detected just above.
        return unsafe { dot_avx(x, y) };
    }
    dot_baseline(x, y)
}

/// [`dot_partial_sums`] compiled for AVX (VEX encoding, no FMA: the same roundings).
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn dot_avx(x: &[f64], y: &[f64]) -> f64 {
    dot_partial_sums(x, y)
}

/// xᵀ y in the baseline instruction set of the target (SSE2 on x86-64): the reference of
/// [`dot`]'s kernels.
pub fn dot_baseline(x: &[f64], y: &[f64]) -> f64 {
    dot_partial_sums(x, y)
}

/// xᵀ y, summed in eight interleaved partial sums (independent additions the compiler
/// vectorises, instead of one chain of dependent ones), the pairs (s₀ + s₄) + (s₁ + s₅) +
/// ((s₂ + s₆) + (s₃ + s₇)) and the tail of fewer than eight products added last.
#[inline(always)]
fn dot_partial_sums(x: &[f64], y: &[f64]) -> f64 {
    let (cx, cy) = (x.chunks_exact(8), y.chunks_exact(8));
    let tail: f64 = cx
        .remainder()
        .iter()
        .zip(cy.remainder())
        .map(|(a, b)| a * b)
        .sum();
    let mut s = [0.0; 8];
    for (a, b) in cx.zip(cy) {
        for k in 0..8 {
            s[k] += a[k] * b[k];
        }
    }
    ((s[0] + s[4]) + (s[1] + s[5])) + ((s[2] + s[6]) + (s[3] + s[7])) + tail
}

/// x ← x + Σ_a s_a z_a over the columns z_a = `column(a)` (as long as x), a = 0..s.len(): the
/// correction x + Z s of a low-rank solve ([`super::lowrank`]). Each x_j takes the products in
/// the order of the columns, as one pass x ← x + s_a z_a per column would (the same result to
/// the bit), but four columns per pass over x; from `VEX_FROM` entries on, where the CPU has
/// AVX, in VEX-encoded instructions (no fused multiply–add: the same bits), as [`dot`].
pub fn add_scaled_columns<'z>(x: &mut [f64], s: &[f64], column: impl Fn(usize) -> &'z [f64]) {
    let vex = uses_vex(x.len());
    let quads = s.len() / 4;
    for g in 0..quads {
        let a = 4 * g;
        let z = [column(a), column(a + 1), column(a + 2), column(a + 3)];
        let c = [s[a], s[a + 1], s[a + 2], s[a + 3]];
        #[cfg(target_arch = "x86_64")]
        if vex {
            // SAFETY: the CPU has AVX, detected by `uses_vex`.
            unsafe { four_columns_avx(x, c, z) };
            continue;
        }
        four_columns(x, c, z);
    }
    for (a, &c) in s.iter().enumerate().skip(4 * quads) {
        let z = column(a);
        #[cfg(target_arch = "x86_64")]
        if vex {
            // SAFETY: the CPU has AVX, detected by `uses_vex`.
            unsafe { one_column_avx(x, c, z) };
            continue;
        }
        one_column(x, c, z);
    }
}

/// Whether vectors of `len` entries take the VEX-encoded kernels (x86-64 with AVX, from
/// `VEX_FROM` entries on).
fn uses_vex(len: usize) -> bool {
    #[cfg(target_arch = "x86_64")]
    if len >= VEX_FROM {
        return std::arch::is_x86_feature_detected!("avx");
    }
    let _ = len;
    false
}

/// x_j ← (((x_j + c₀ z₀ⱼ) + c₁ z₁ⱼ) + c₂ z₂ⱼ) + c₃ z₃ⱼ.
#[inline(always)]
fn four_columns(x: &mut [f64], c: [f64; 4], z: [&[f64]; 4]) {
    let columns = z[0].iter().zip(z[1]).zip(z[2]).zip(z[3]);
    for (xj, (((a, b), d), e)) in x.iter_mut().zip(columns) {
        *xj = (((*xj + c[0] * a) + c[1] * b) + c[2] * d) + c[3] * e;
    }
}

/// x_j ← x_j + c z_j.
#[inline(always)]
fn one_column(x: &mut [f64], c: f64, z: &[f64]) {
    for (xj, zj) in x.iter_mut().zip(z) {
        *xj += c * zj;
    }
}

/// [`four_columns`] in VEX-encoded instructions.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn four_columns_avx(x: &mut [f64], c: [f64; 4], z: [&[f64]; 4]) {
    four_columns(x, c, z)
}

/// [`one_column`] in VEX-encoded instructions.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn one_column_avx(x: &mut [f64], c: f64, z: &[f64]) {
    one_column(x, c, z)
}

/// Clears the upper halves of the vector registers (`vzeroupper`) where the CPU has AVX, after a
/// faer kernel ran on this thread: its AVX-512 kernels return with them in use (the ZMM_Hi256
/// component of XINUSE set, read by `xgetbv` after the capacitance inverses of
/// [`super::lowrank::LowRank`]), and while they are, the SSE-encoded instructions of the march
/// slow down (2.7 times on the products of [`dot_baseline`]).
fn release_vector_registers() {
    #[cfg(target_arch = "x86_64")]
    if std::arch::is_x86_feature_detected!("avx") {
        // SAFETY: the CPU has AVX, detected just above.
        unsafe { zero_upper() }
    }
}

/// `vzeroupper`.
///
/// # Safety
/// The CPU must support AVX.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
unsafe fn zero_upper() {
    std::arch::x86_64::_mm256_zeroupper();
}

/// y = A x for row-major `a` (n×n).
pub fn matvec(a: &[f64], x: &[f64], y: &mut [f64]) {
    let n = x.len();
    for (yi, row) in y.iter_mut().zip(a.chunks_exact(n.max(1))) {
        *yi = dot(row, x);
    }
}

/// y += A x for row-major `a` (n×n).
pub fn matvec_add(a: &[f64], x: &[f64], y: &mut [f64]) {
    let n = x.len();
    for (yi, row) in y.iter_mut().zip(a.chunks_exact(n.max(1))) {
        *yi += dot(row, x);
    }
}

/// y += α A x for row-major `a` (n×n).
pub fn matvec_scaled_add(alpha: f64, a: &[f64], x: &[f64], y: &mut [f64]) {
    let n = x.len();
    for (yi, row) in y.iter_mut().zip(a.chunks_exact(n.max(1))) {
        *yi += alpha * dot(row, x);
    }
}

fn to_faer(a: &[f64], n: usize) -> Mat<f64> {
    Mat::from_fn(n, n, |i, j| a[i * n + j])
}

/// Below this size the march's factorisations run on the calling thread: handing an LU of a few
/// dozen unknowns to faer's thread pool costs more (tens of µs of wake-ups) than the LU itself.
const SEQUENTIAL_BELOW: usize = 128;

/// The parallelism of a dense operation of size n: sequential for small matrices, faer's global
/// setting otherwise.
fn par_for(n: usize) -> faer::Par {
    if n < SEQUENTIAL_BELOW {
        faer::Par::Seq
    } else {
        faer::get_global_parallelism()
    }
}

/// The inverse of row-major `a` (n×n) by LU with partial pivoting, or `None` when `a` is singular
/// to working precision (‖A·A⁻¹ − I‖_max > 1e-8, a zero pivot or non-finite entries).
pub fn inverse(a: &[f64], n: usize) -> Option<Vec<f64>> {
    let inv = faer_inverse(a, n);
    release_vector_registers();
    inv
}

/// [`inverse`] by faer.
fn faer_inverse(a: &[f64], n: usize) -> Option<Vec<f64>> {
    use faer::linalg::matmul::matmul;
    if n == 0 {
        return Some(Vec::new());
    }
    let par = par_for(n);
    let mut scratch = Vec::new();
    let mut lu = PackedLu::empty();
    lu.refactor(n, par, &mut scratch, |m| fill_row_major(m, a));
    if (0..n).any(|i| {
        let d = lu.pivot(i);
        !d.is_finite() || d == 0.0
    }) {
        return None;
    }
    let mut inv = Mat::<f64>::identity(n, n);
    lu.solve_in_place_with(inv.as_mut(), par, &mut scratch);
    // residual check A·A⁻¹ = I (blocked product)
    let mut id = Mat::<f64>::zeros(n, n);
    matmul(
        id.as_mut(),
        faer::Accum::Replace,
        to_faer(a, n).as_ref(),
        inv.as_ref(),
        1.0,
        par,
    );
    let mut worst: f64 = 0.0;
    let mut out: Vec<f64> = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            let x = inv[(i, j)];
            if !x.is_finite() {
                return None;
            }
            out[i * n + j] = x;
            let target = if i == j { 1.0 } else { 0.0 };
            worst = worst.max((id[(i, j)] - target).abs());
        }
    }
    (worst <= 1e-8).then_some(out)
}

/// Copies row-major `a` into the square `m` (n × n, n² = `a.len()`).
fn fill_row_major(m: &mut Mat<f64>, a: &[f64]) {
    let n = m.nrows();
    for j in 0..n {
        for i in 0..n {
            m[(i, j)] = a[i * n + j];
        }
    }
}

/// An LU factorisation (partial pivoting, [`PackedLu`]) held in buffers sized once, for a step
/// matrix factored and used within one step only (the closing step of a period in the adaptive
/// march): [`ScratchLu::factor`] and [`ScratchLu::solve`] allocate nothing after the first call.
pub struct ScratchLu {
    lu: PackedLu<f64>,
    rhs: Mat<f64>,
    scratch: Vec<MaybeUninit<u8>>,
}

impl ScratchLu {
    /// Buffers for n × n matrices (sized by factoring and solving with the identity once).
    pub fn new(n: usize) -> Self {
        let mut lu = PackedLu::empty();
        let mut scratch = Vec::new();
        lu.refactor(n, faer::Par::Seq, &mut scratch, |m| {
            *m = Mat::identity(n, n)
        });
        let mut rhs = Mat::zeros(n, 1);
        lu.solve_in_place_with(rhs.as_mut(), faer::Par::Seq, &mut scratch);
        ScratchLu { lu, rhs, scratch }
    }

    /// Factors row-major `a` (n×n); false when a pivot is zero or not finite (singular).
    pub fn factor(&mut self, a: &[f64]) -> bool {
        let n = self.lu.nrows();
        self.lu.refactor(n, faer::Par::Seq, &mut self.scratch, |m| {
            fill_row_major(m, a)
        });
        release_vector_registers();
        (0..n).all(|i| {
            let d = self.lu.pivot(i);
            d.is_finite() && d != 0.0
        })
    }

    /// x = A⁻¹ b with the last factored A.
    pub fn solve(&mut self, b: &[f64], x: &mut [f64]) {
        for (i, &bi) in b.iter().enumerate() {
            self.rhs[(i, 0)] = bi;
        }
        self.lu
            .solve_in_place_with(self.rhs.as_mut(), faer::Par::Seq, &mut self.scratch);
        release_vector_registers();
        for (i, xi) in x.iter_mut().enumerate() {
            *xi = self.rhs[(i, 0)];
        }
    }
}

/// The spectral radius max |λ| of row-major `a` (n×n, not necessarily symmetric).
pub fn spectral_radius(a: &[f64], n: usize) -> Option<f64> {
    if n == 0 {
        return Some(0.0);
    }
    let m = to_faer(a, n);
    let ev = m.eigenvalues();
    release_vector_registers();
    Some(ev.ok()?.iter().map(|z| z.norm()).fold(0.0, f64::max))
}

/// The number of negative eigenvalues of the symmetric row-major `a` (n×n; its lower triangle is
/// read), by Sylvester's law of inertia from its Bunch–Kaufman factorisation P A Pᵀ = L B Lᵀ
/// (faer, on the calling thread): the negative eigenvalues of the 1 × 1 and 2 × 2 blocks of B.
pub fn negative_eigenvalues(a: &[f64], n: usize) -> usize {
    use faer::linalg::cholesky::lblt::factor::{cholesky_in_place, cholesky_in_place_scratch};
    let par = faer::Par::Seq;
    let mut m = to_faer(a, n);
    let mut subdiag = faer::diag::Diag::<f64>::zeros(n);
    let (mut perm, mut perm_inv) = (vec![0usize; n], vec![0usize; n]);
    let req = cholesky_in_place_scratch::<usize, f64>(n, par, Default::default());
    let mut stack = faer::dyn_stack::MemBuffer::new(req);
    cholesky_in_place(
        m.as_mut(),
        subdiag.as_mut(),
        &mut perm,
        &mut perm_inv,
        par,
        faer::dyn_stack::MemStack::new(&mut stack),
        Default::default(),
    );
    release_vector_registers();
    let mut negative = 0;
    let mut i = 0;
    while i < n {
        let e = subdiag[i];
        if e != 0.0 && i + 1 < n {
            let (d0, d1) = (m[(i, i)], m[(i + 1, i + 1)]);
            let det = d0 * d1 - e * e;
            negative += if det < 0.0 {
                1
            } else if d0 + d1 < 0.0 {
                2
            } else {
                0
            };
            i += 2;
        } else {
            negative += usize::from(m[(i, i)] < 0.0);
            i += 1;
        }
    }
    negative
}

/// The eigenvalues λ (ascending) of the symmetric-definite pencil K φ = λ M φ (row-major n×n,
/// K symmetric, M symmetric positive definite), by M = L Lᵀ and the symmetric eigenproblem of
/// L⁻¹ K L⁻ᵀ, and the eigenvectors (row-major n×n, column j the φ_j of λ_j, Φᵀ M Φ = I); `None`
/// when M is not positive definite or the iteration fails.
pub fn generalized_symmetric_eigen(k: &[f64], m: &[f64], n: usize) -> Option<(Vec<f64>, Vec<f64>)> {
    use faer::linalg::triangular_solve::{
        solve_lower_triangular_in_place, solve_upper_triangular_in_place,
    };
    if n == 0 {
        return None;
    }
    let par = par_for(n);
    let symmetric = |a: &[f64]| Mat::from_fn(n, n, |i, j| 0.5 * (a[i * n + j] + a[j * n + i]));
    let llt = symmetric(m).llt(faer::Side::Lower).ok()?;
    let l = llt.L().to_owned();
    // L⁻¹ K L⁻ᵀ: two triangular solves (K symmetric)
    let mut x = symmetric(k);
    solve_lower_triangular_in_place(l.as_ref(), x.as_mut(), par);
    let mut y = x.transpose().to_owned();
    solve_lower_triangular_in_place(l.as_ref(), y.as_mut(), par);
    let b = Mat::from_fn(n, n, |i, j| 0.5 * (y[(i, j)] + y[(j, i)]));
    let evd = b.self_adjoint_eigen(faer::Side::Lower).ok();
    let out = evd.map(|e| {
        let values: Vec<f64> = (0..n).map(|i| e.S()[i]).collect();
        let mut v = e.U().to_owned();
        solve_upper_triangular_in_place(l.transpose(), v.as_mut(), par);
        let mut vectors = vec![0.0; n * n];
        for i in 0..n {
            for j in 0..n {
                vectors[i * n + j] = v[(i, j)];
            }
        }
        (values, vectors)
    });
    release_vector_registers();
    out
}

/// The product A B of row-major n×n matrices.
pub fn matmul(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut c = vec![0.0; n * n];
    for i in 0..n {
        for k in 0..n {
            let aik = a[i * n + k];
            if aik != 0.0 {
                for j in 0..n {
                    c[i * n + j] += aik * b[k * n + j];
                }
            }
        }
    }
    c
}

/// The product A B of row-major n×n matrices by faer's blocked product (SIMD kernels, threads
/// from 128 unknowns on): for the large set-up products of the march, where the plain
/// loop of [`matmul`] costs seconds (n in the thousands).
pub fn product(a: &[f64], b: &[f64], n: usize) -> Vec<f64> {
    let mut c = Mat::<f64>::zeros(n, n);
    faer::linalg::matmul::matmul(
        c.as_mut(),
        faer::Accum::Replace,
        to_faer(a, n).as_ref(),
        to_faer(b, n).as_ref(),
        1.0,
        par_for(n),
    );
    release_vector_registers();
    let mut out = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            out[i * n + j] = c[(i, j)];
        }
    }
    out
}

/// ‖x‖_∞.
pub fn norm_inf(x: &[f64]) -> f64 {
    x.iter().fold(0.0, |m, v| m.max(v.abs()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_and_spectral_radius_of_small_matrices() {
        let a = [4.0, 1.0, 0.0, 2.0, 3.0, 1.0, 0.0, 1.0, 2.0];
        let inv = inverse(&a, 3).unwrap();
        let id = matmul(&a, &inv, 3);
        for i in 0..3 {
            for j in 0..3 {
                let t = if i == j { 1.0 } else { 0.0 };
                assert!((id[i * 3 + j] - t).abs() < 1e-14);
            }
        }
        assert!(inverse(&[1.0, 2.0, 2.0, 4.0], 2).is_none());
        // the scratch LU solves like the inverse
        let mut lu = ScratchLu::new(3);
        assert!(lu.factor(&a));
        let b = [1.0, -2.0, 0.5];
        let (mut x, mut y) = ([0.0; 3], [0.0; 3]);
        lu.solve(&b, &mut x);
        matvec(&inv, &b, &mut y);
        for (p, q) in x.iter().zip(&y) {
            assert!((p - q).abs() < 1e-14);
        }
        assert!(!lu.factor(&[1.0, 2.0, 0.0, 2.0, 4.0, 0.0, 0.0, 0.0, 1.0]));
        // the blocked product equals the plain one
        let p = product(&a, &inv, 3);
        for (x, y) in p.iter().zip(&id) {
            assert!((x - y).abs() < 1e-14);
        }
        // rotation-like matrix: eigenvalues ±2i, spectral radius 2
        let r = spectral_radius(&[0.0, -2.0, 2.0, 0.0], 2).unwrap();
        assert!((r - 2.0).abs() < 1e-12);
    }
}
