//! Alternating frequency/time (AFT) transforms of one periodic signal with `realfft`
//! (Cameron & Griffin 1989; SAMA paper §3, Fig. 4), in the real harmonic layout of
//! `docs/conventions.md` §4.
//!
//! A signal's coefficients are stored contiguously in *signal order*
//! `[Q⁽⁰⁾, Re Q⁽¹⁾, Im Q⁽¹⁾, …, Re Q⁽ᴴ⁾, Im Q⁽ᴴ⁾]` (length m = 2H + 1) for
//! q(τ) = Q⁽⁰⁾ + Σ_{n≥1} (Re Q⁽ⁿ⁾ cos nτ − Im Q⁽ⁿ⁾ sin nτ); [`gather`] and [`global_index`]
//! map between one DOF's signal order and the harmonic-major vector of many DOFs. Samples are
//! taken at τ_j = 2πj/N_t, j = 0..N_t−1. The forward transform is scaled so that a band-limited signal
//! (harmonics ≤ H < N_t/2) round-trips exactly.

use std::sync::Arc;

use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};

use crate::error::{Error, Result};
use crate::harmonics::HarmonicLayout;

/// FFT plans and the explicit synthesis/analysis tables of one [`HarmonicLayout`].
pub struct Aft {
    layout: HarmonicLayout,
    forward: Arc<dyn RealToComplex<f64>>,
    inverse: Arc<dyn ComplexToReal<f64>>,
    /// Row j (length m): the value at τ_j of the basis function of each coefficient,
    /// [1, cos τ_j, −sin τ_j, cos 2τ_j, …]; q(τ_j) = Σ_l synthesis[j][l] Q_l.
    synthesis: Vec<f64>,
    /// The analysis table (Q_k = Σ_j A[k][j] q(τ_j) for a band-limited q) transposed: row j
    /// (length m) holds ∂Q_k/∂q(τ_j) for k = 0..2H.
    analysis_columns: Vec<f64>,
    /// Cumulative sums of the analysis columns: row j (length m, j = 0..=N_t) holds
    /// Σ_{i<j} ∂Q_k/∂q(τ_i), for [`Aft::add_analysis_sum`].
    analysis_prefix: Vec<f64>,
    /// cos(2πq/N_t), sin(2πq/N_t) for q = 0..N_t−1.
    unit_circle: (Vec<f64>, Vec<f64>),
    /// 1/(1 − z_p) as (Re, Im) for z_p = e^{−2πip/N_t}, p = 0..=2H (entry 0 unused), for
    /// [`Aft::step_fourier_sums`].
    step_factors: Vec<(f64, f64)>,
    /// Row j (length 4H): z_p^j = (cos pτ_j, −sin pτ_j) for p = 1..=2H.
    step_table: Vec<f64>,
}

impl std::fmt::Debug for Aft {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Aft").field("layout", &self.layout).finish()
    }
}

/// Buffers of one thread for [`Aft`] (from [`Aft::scratch`]).
pub struct AftScratch {
    spectrum: Vec<Complex<f64>>,
    fft: Vec<Complex<f64>>,
    time: Vec<f64>,
}

impl Aft {
    /// Plans the transforms; errors when N_t < 2H + 2 (`docs/conventions.md` §4).
    pub fn new(layout: HarmonicLayout) -> Result<Self> {
        let layout = HarmonicLayout::new(layout.harmonics, layout.time_samples)?;
        let n = layout.time_samples;
        let m = layout.coefficients();
        let mut planner = RealFftPlanner::<f64>::new();
        let forward = planner.plan_fft_forward(n);
        let inverse = planner.plan_fft_inverse(n);
        let mut synthesis = vec![0.0; n * m];
        let mut analysis = vec![0.0; m * n];
        for j in 0..n {
            synthesis[j * m] = 1.0;
            analysis[j] = 1.0 / n as f64;
            for h in 1..=layout.harmonics {
                let phase = 2.0 * std::f64::consts::PI * ((h * j) % n) as f64 / n as f64;
                let (s, c) = phase.sin_cos();
                synthesis[j * m + 2 * h - 1] = c;
                synthesis[j * m + 2 * h] = -s;
                analysis[(2 * h - 1) * n + j] = 2.0 * c / n as f64;
                analysis[2 * h * n + j] = -2.0 * s / n as f64;
            }
        }
        let mut analysis_columns = vec![0.0; n * m];
        for k in 0..m {
            for j in 0..n {
                analysis_columns[j * m + k] = analysis[k * n + j];
            }
        }
        let analysis_prefix = prefix_sums(&analysis_columns, m);
        let unit_circle = (0..n)
            .map(|q| {
                let (s, c) = (2.0 * std::f64::consts::PI * q as f64 / n as f64).sin_cos();
                (c, s)
            })
            .unzip();
        let step_factors = (0..=2 * layout.harmonics)
            .map(|p| {
                // 1 − z_p = (1 − cos θ) + i sin θ, θ = 2πp/N_t (nonzero: 0 < p ≤ 2H < N_t).
                let (s, c) = (2.0 * std::f64::consts::PI * p as f64 / n as f64).sin_cos();
                let (a, b) = (1.0 - c, s);
                let norm = a * a + b * b;
                if p == 0 {
                    (0.0, 0.0)
                } else {
                    (a / norm, -b / norm)
                }
            })
            .collect();
        let h2 = 2 * layout.harmonics;
        let mut step_table = vec![0.0; n * 2 * h2];
        for j in 0..n {
            for p in 1..=h2 {
                let (s, c) =
                    (2.0 * std::f64::consts::PI * ((p * j) % n) as f64 / n as f64).sin_cos();
                step_table[j * 2 * h2 + 2 * (p - 1)] = c;
                step_table[j * 2 * h2 + 2 * (p - 1) + 1] = -s;
            }
        }
        Ok(Aft {
            layout,
            forward,
            inverse,
            synthesis,
            analysis_columns,
            analysis_prefix,
            unit_circle,
            step_factors,
            step_table,
        })
    }

    /// The layout the transforms were planned for.
    pub fn layout(&self) -> HarmonicLayout {
        self.layout
    }

    /// Buffers for [`Aft::to_time`] and [`Aft::to_harmonics`].
    pub fn scratch(&self) -> AftScratch {
        let scratch_len = self
            .forward
            .get_scratch_len()
            .max(self.inverse.get_scratch_len());
        AftScratch {
            spectrum: self.forward.make_output_vec(),
            fft: vec![Complex::new(0.0, 0.0); scratch_len],
            time: vec![0.0; self.layout.time_samples],
        }
    }

    /// Samples q(τ_j), j = 0..N_t−1, of the signal with coefficients `coefficients` (signal
    /// order, length 2H+1) into `samples` (length N_t).
    pub fn to_time(&self, coefficients: &[f64], samples: &mut [f64], scratch: &mut AftScratch) {
        let h = self.layout.harmonics;
        debug_assert_eq!(coefficients.len(), 2 * h + 1);
        let spec = &mut scratch.spectrum;
        spec.fill(Complex::new(0.0, 0.0));
        // x_j = Σ_k X_k e^{2πijk/N} (unnormalised inverse): X_0 = Q⁽⁰⁾, X_n = Q⁽ⁿ⁾/2.
        spec[0] = Complex::new(coefficients[0], 0.0);
        for n in 1..=h {
            spec[n] = Complex::new(0.5 * coefficients[2 * n - 1], 0.5 * coefficients[2 * n]);
        }
        self.inverse
            .process_with_scratch(spec, samples, &mut scratch.fft)
            .expect("AFT inverse transform: buffer lengths fixed by the plan");
    }

    /// Harmonic coefficients (signal order, length 2H+1) of the samples `samples` (length N_t):
    /// Q⁽⁰⁾ = X_0/N_t, Q⁽ⁿ⁾ = 2 X_n/N_t with X the forward DFT.
    pub fn to_harmonics(
        &self,
        samples: &[f64],
        coefficients: &mut [f64],
        scratch: &mut AftScratch,
    ) {
        let h = self.layout.harmonics;
        let n_t = self.layout.time_samples as f64;
        scratch.time.copy_from_slice(samples);
        self.forward
            .process_with_scratch(&mut scratch.time, &mut scratch.spectrum, &mut scratch.fft)
            .expect("AFT forward transform: buffer lengths fixed by the plan");
        let spec = &scratch.spectrum;
        coefficients[0] = spec[0].re / n_t;
        for n in 1..=h {
            coefficients[2 * n - 1] = 2.0 * spec[n].re / n_t;
            coefficients[2 * n] = 2.0 * spec[n].im / n_t;
        }
    }

    /// Row j of the synthesis table: ∂q(τ_j)/∂Q_l for l = 0..2H (length 2H+1).
    pub fn synthesis_row(&self, j: usize) -> &[f64] {
        let m = self.layout.coefficients();
        &self.synthesis[j * m..(j + 1) * m]
    }

    /// Column j of the analysis table: ∂Q_k/∂q(τ_j) for k = 0..2H (length 2H+1, contiguous).
    pub fn analysis_column(&self, j: usize) -> &[f64] {
        let m = self.layout.coefficients();
        &self.analysis_columns[j * m..(j + 1) * m]
    }

    /// `beta` (length m) += Σ_j ∂Q/∂q(τ_j) over the `length` samples j = `first`, `first` + 1,
    /// … taken cyclically (a run that passes τ_{N_t−1} goes on at τ_0): the analysis columns
    /// ([`Aft::analysis_column`]) of a run of samples. A run of more than [`DIRECT_RUN`]
    /// samples costs O(m) whatever its length, from the cumulative sums of the columns: these
    /// are bounded by about 1 (|Σ_{i<j} cos pτ_i| ≤ 1/sin(pπ/N_t), times 2/N_t), so their
    /// difference is within a few ε of the direct sum. A shorter run is summed column by
    /// column in the order of the samples: as cheap, and accurate relative to its own size.
    pub fn add_analysis_sum(&self, first: usize, length: usize, beta: &mut [f64]) {
        let m = self.layout.coefficients();
        let n = self.layout.time_samples;
        debug_assert!(first < n && length <= n);
        let end = first + length;
        if length <= DIRECT_RUN {
            // [first, N_t) then [0, end − N_t)
            for j in (first..end.min(n)).chain(0..end.saturating_sub(n)) {
                for (b, a) in beta.iter_mut().zip(self.analysis_column(j)) {
                    *b += a;
                }
            }
            return;
        }
        let row = |j: usize| &self.analysis_prefix[j * m..(j + 1) * m];
        if end <= n {
            for ((b, hi), lo) in beta.iter_mut().zip(row(end)).zip(row(first)) {
                *b += hi - lo;
            }
        } else {
            let (whole, lo, wrapped) = (row(n), row(first), row(end - n));
            for (((b, w), l), r) in beta.iter_mut().zip(whole).zip(lo).zip(wrapped) {
                *b += (w - l) + r;
            }
        }
    }

    /// Discrete Fourier sums of the samples `a` (length N_t) of orders p = 0..=2H:
    /// c_p = Σ_j a_j cos(pτ_j)/N_t into `sums[2p]` and s_p = Σ_j a_j sin(pτ_j)/N_t into
    /// `sums[2p + 1]` (length 2(2H+1)), by one real FFT X_p = Σ_j a_j e^{−ipτ_j}
    /// (c_p = Re X_p/N_t, s_p = −Im X_p/N_t; orders above N_t/2 by X_p = conj X_{N_t−p}).
    pub fn fourier_sums(&self, a: &[f64], sums: &mut [f64], scratch: &mut AftScratch) {
        let h = self.layout.harmonics;
        let n = self.layout.time_samples;
        let scale = 1.0 / n as f64;
        scratch.time.copy_from_slice(a);
        self.forward
            .process_with_scratch(&mut scratch.time, &mut scratch.spectrum, &mut scratch.fft)
            .expect("AFT forward transform: buffer lengths fixed by the plan");
        let spec = &scratch.spectrum;
        for p in 0..=2 * h {
            let (x, sign) = if p < spec.len() {
                (spec[p], 1.0)
            } else {
                (spec[n - p], -1.0)
            };
            sums[2 * p] = x.re * scale;
            sums[2 * p + 1] = -sign * x.im * scale;
        }
    }

    /// The Fourier sums of [`Aft::fourier_sums`] (same layout, same values up to rounding) from
    /// the jumps of the cyclic sequence `a` (summation by parts): with z_p = e^{−2πip/N_t} and
    /// Δ_j = a_j − a_{j−1} (a_{−1} = a_{N_t−1}), X_p (1 − z_p) = Σ_j Δ_j z_p^j for p = 1..=2H
    /// (2H < N_t, so z_p ≠ 1) and X_0 = Σ_j a_j. Costs O(N_t + J·H) for J jumps: cheaper than
    /// the FFT for the piecewise-constant weight sequences of the 1-D law (stick, slip and
    /// contact indicators, a few runs per period). Returns false if `a` is all zero (`sums`
    /// then zero).
    pub fn step_fourier_sums(&self, a: &[f64], sums: &mut [f64]) -> bool {
        let n = self.layout.time_samples;
        debug_assert_eq!(a.len(), n);
        let total: f64 = a.iter().sum();
        let mut prev = a[n - 1];
        let jumps = a.iter().enumerate().filter_map(|(j, &aj)| {
            let delta = aj - prev;
            prev = aj;
            (delta != 0.0).then_some((j, delta))
        });
        self.jump_fourier_sums(jumps, total, sums)
    }

    /// The Fourier sums of [`Aft::step_fourier_sums`] of a piecewise-constant cyclic sequence
    /// given by its jumps (j, Δ_j) (the samples where it changes, in increasing j, Δ_j = a_j −
    /// a_{j−1}) and its sum `total` = Σ_j a_j: O(J·H) for J jumps, without visiting the samples.
    /// Returns false if the sequence is all zero (no jump and `total` zero; `sums` then zero).
    pub fn jump_fourier_sums(
        &self,
        jumps: impl Iterator<Item = (usize, f64)>,
        total: f64,
        sums: &mut [f64],
    ) -> bool {
        let h2 = 2 * self.layout.harmonics;
        let n = self.layout.time_samples;
        sums[..2 * h2 + 2].fill(0.0);
        let mut jumped = false;
        // Y_p = Σ_j Δ_j z_p^j accumulated in sums[2p], sums[2p + 1] (Re, Im).
        let y = &mut sums[2..2 * h2 + 2];
        for (j, delta) in jumps {
            jumped = true;
            let row = &self.step_table[j * 2 * h2..(j + 1) * 2 * h2];
            for (yp, z) in y.iter_mut().zip(row) {
                *yp += delta * z;
            }
        }
        let scale = 1.0 / n as f64;
        sums[0] = total * scale;
        for p in 1..=h2 {
            let (yr, yi) = (sums[2 * p], sums[2 * p + 1]);
            let (rr, ri) = self.step_factors[p];
            // X_p = Y_p/(1 − z_p); c_p = Re X_p/N_t, s_p = −Im X_p/N_t.
            sums[2 * p] = (yr * rr - yi * ri) * scale;
            sums[2 * p + 1] = -(yr * ri + yi * rr) * scale;
        }
        jumped || total != 0.0
    }

    /// cos(2πq/N_t) and sin(2πq/N_t) for q = 0..N_t−1.
    pub fn unit_circle(&self) -> (&[f64], &[f64]) {
        (&self.unit_circle.0, &self.unit_circle.1)
    }
}

/// The longest run of samples that [`Aft::add_analysis_sum`] sums directly.
pub const DIRECT_RUN: usize = 16;

/// The cumulative sums of the rows of `rows` (row length `m`): N + 1 rows, row j the sum of
/// rows 0..j, each by compensated (Kahan) summation, so that every entry is the exact sum
/// correctly rounded to within about ε.
fn prefix_sums(rows: &[f64], m: usize) -> Vec<f64> {
    let n = rows.len() / m;
    let mut out = vec![0.0; (n + 1) * m];
    let mut sum = vec![0.0; m];
    let mut carry = vec![0.0; m];
    for j in 0..n {
        for k in 0..m {
            let y = rows[j * m + k] - carry[k];
            let t = sum[k] + y;
            carry[k] = (t - sum[k]) - y;
            sum[k] = t;
        }
        out[(j + 1) * m..(j + 2) * m].copy_from_slice(&sum);
    }
    out
}

/// Copies the coefficients of `dof` from the harmonic-major vector `q` of `n_dof` DOFs into
/// `out` in signal order.
pub fn gather(layout: &HarmonicLayout, q: &[f64], dof: usize, n_dof: usize, out: &mut [f64]) {
    out[0] = q[layout.static_index(dof)];
    for n in 1..=layout.harmonics {
        let i = layout.cos_index(n, dof, n_dof);
        out[2 * n - 1] = q[i];
        out[2 * n] = q[i + 1];
    }
}

/// Index in the harmonic-major vector of `n_dof` DOFs of coefficient `l` (signal order) of `dof`.
pub fn global_index(layout: &HarmonicLayout, l: usize, dof: usize, n_dof: usize) -> usize {
    if l == 0 {
        layout.static_index(dof)
    } else {
        layout.cos_index(l.div_ceil(2), dof, n_dof) + (1 - l % 2)
    }
}

/// Errors (as a failed computation) when a harmonic vector holds a value that is not finite.
pub fn check_finite(q: &[f64], what: &str) -> Result<()> {
    match q.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(i) => Err(Error::Compute(format!(
            "{what}: harmonic coefficient {i} is {} (not finite); the iteration diverged or the input holds NaN/inf",
            q[i]
        ))),
    }
}

/// The [`Aft`] of the last layout used, shared by the threads of a nonlinear force (plans are
/// made once per layout).
#[derive(Default)]
pub struct AftCache(std::sync::Mutex<Option<Arc<Aft>>>);

impl AftCache {
    /// The transforms for `layout` (planned on first use or when the layout changes).
    pub fn get(&self, layout: &HarmonicLayout) -> Result<Arc<Aft>> {
        let mut cache = self.0.lock().unwrap_or_else(|e| e.into_inner());
        match cache.as_ref() {
            Some(a) if a.layout() == *layout => Ok(a.clone()),
            _ => {
                let a = Arc::new(Aft::new(*layout)?);
                *cache = Some(a.clone());
                Ok(a)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sum of the analysis columns of a cyclic run of samples from the cumulative table
    /// equals the direct sum to 1e-15 (absolute; the columns are of order 2/N_t), for runs
    /// inside the period, wrapping round it, of one sample, of the whole period and on either
    /// side of the length summed directly.
    #[test]
    fn analysis_sum_equals_the_direct_sum() {
        for (h, n) in [(1, 4), (3, 16), (7, 33), (7, 1024)] {
            let aft = Aft::new(HarmonicLayout::new(h, n).unwrap()).unwrap();
            let m = 2 * h + 1;
            for (first, length) in [
                (0, 1),
                (0, n),
                (n - 1, 1),
                (n / 3, n / 2),
                (n - 2, 3),
                (1, n),
            ] {
                let mut direct = vec![0.0; m];
                for i in 0..length {
                    for (d, a) in direct.iter_mut().zip(aft.analysis_column((first + i) % n)) {
                        *d += a;
                    }
                }
                let mut beta = vec![0.5; m];
                aft.add_analysis_sum(first, length, &mut beta);
                for (k, (b, d)) in beta.iter().zip(&direct).enumerate() {
                    assert!(
                        (b - 0.5 - d).abs() <= 1e-15,
                        "H={h} N_t={n} run ({first}, {length}) coefficient {k}: {b} vs {d} + 0.5"
                    );
                }
            }
        }
    }

    /// The summation-by-parts Fourier sums equal the FFT ones for a piecewise-constant sequence
    /// (the weights of the 1-D law), a constant, a zero and an arbitrary sequence.
    #[test]
    fn step_fourier_sums_equal_fft_sums() {
        for (h, n) in [(0, 2), (1, 4), (3, 16), (3, 32), (7, 32), (7, 33)] {
            let aft = Aft::new(HarmonicLayout::new(h, n).unwrap()).unwrap();
            let mut scratch = aft.scratch();
            let runs: Vec<f64> = (0..n)
                .map(|j| match (5 * j / n) % 3 {
                    0 => 1.0,
                    1 => 0.0,
                    _ => -2.5,
                })
                .collect();
            let arbitrary: Vec<f64> = (0..n)
                .map(|j| ((j * j * 7 + 3) % 11) as f64 - 4.2)
                .collect();
            for a in [runs, vec![3.0; n], vec![0.0; n], arbitrary] {
                let mut fft = vec![0.0; 2 * (2 * h + 1)];
                let mut steps = vec![f64::NAN; 2 * (2 * h + 1)];
                aft.fourier_sums(&a, &mut fft, &mut scratch);
                let nonzero = aft.step_fourier_sums(&a, &mut steps);
                assert_eq!(nonzero, a.iter().any(|&x| x != 0.0));
                for (p, (x, y)) in fft.iter().zip(&steps).enumerate() {
                    assert!(
                        (x - y).abs() <= 1e-13,
                        "H={h} N_t={n} entry {p}: FFT {x} vs steps {y}"
                    );
                }
            }
        }
    }
}
