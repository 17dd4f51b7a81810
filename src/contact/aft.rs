//! Alternating frequency/time (AFT) transforms of one periodic signal with `realfft`
//! (Cameron & Griffin 1989; SAMA paper §3, Fig. 4), in the real harmonic layout of
//! `conventions.md` §4.
//!
//! A signal's coefficients are stored contiguously in *signal order*
//! `[Q⁽⁰⁾, Re Q⁽¹⁾, Im Q⁽¹⁾, …, Re Q⁽ᴴ⁾, Im Q⁽ᴴ⁾]` (length m = 2H + 1) for
//! q(τ) = Q⁽⁰⁾ + Σ_{n≥1} (Re Q⁽ⁿ⁾ cos nτ − Im Q⁽ⁿ⁾ sin nτ); [`gather`] and [`scatter_add`] convert
//! between one DOF's signal order and the harmonic-major vector of many DOFs. Samples are taken at
//! τ_j = 2πj/N_t, j = 0..N_t−1. The forward transform is scaled so that a band-limited signal
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
    /// Row k (length N_t): Q_k = Σ_j analysis[k][j] q(τ_j) for a band-limited q.
    analysis: Vec<f64>,
    /// The analysis table transposed: row j (length m) holds ∂Q_k/∂q(τ_j) for k = 0..2H.
    analysis_columns: Vec<f64>,
    /// cos(2πq/N_t), sin(2πq/N_t) for q = 0..N_t−1.
    unit_circle: (Vec<f64>, Vec<f64>),
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
    /// Plans the transforms; errors when N_t < 2H + 2 (`conventions.md` §4).
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
        let unit_circle = (0..n)
            .map(|q| {
                let (s, c) = (2.0 * std::f64::consts::PI * q as f64 / n as f64).sin_cos();
                (c, s)
            })
            .unzip();
        Ok(Aft {
            layout,
            forward,
            inverse,
            synthesis,
            analysis,
            analysis_columns,
            unit_circle,
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

    /// Row k of the analysis table: ∂Q_k/∂q(τ_j) for j = 0..N_t−1 (length N_t).
    pub fn analysis_row(&self, k: usize) -> &[f64] {
        let n = self.layout.time_samples;
        &self.analysis[k * n..(k + 1) * n]
    }

    /// Column j of the analysis table: ∂Q_k/∂q(τ_j) for k = 0..2H (length 2H+1, contiguous).
    pub fn analysis_column(&self, j: usize) -> &[f64] {
        let m = self.layout.coefficients();
        &self.analysis_columns[j * m..(j + 1) * m]
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

    /// cos(2πq/N_t) and sin(2πq/N_t) for q = 0..N_t−1.
    pub fn unit_circle(&self) -> (&[f64], &[f64]) {
        (&self.unit_circle.0, &self.unit_circle.1)
    }

    /// The whole analysis table, row-major m × N_t.
    pub fn analysis_table(&self) -> &[f64] {
        &self.analysis
    }
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

/// Adds `coefficients` (signal order) of `dof` into the harmonic-major vector `f`.
pub fn scatter_add(
    layout: &HarmonicLayout,
    coefficients: &[f64],
    dof: usize,
    n_dof: usize,
    f: &mut [f64],
) {
    f[layout.static_index(dof)] += coefficients[0];
    for n in 1..=layout.harmonics {
        let i = layout.cos_index(n, dof, n_dof);
        f[i] += coefficients[2 * n - 1];
        f[i + 1] += coefficients[2 * n];
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
