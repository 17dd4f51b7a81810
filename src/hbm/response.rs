//! The response at the output DOFs recovered from a harmonic balance solution (SAMA paper
//! eq. 18): complex harmonics Q⁽⁰⁾..Q⁽ᴴ⁾, first-harmonic amplitude |Q⁽¹⁾| and the peak
//! max_τ |q(τ)| over the period.

use faer::c64;

use super::linear::recover;
use super::system::HbmSystem;
use crate::error::Result;
use crate::harmonics::HarmonicForce;

/// How the peak over the period is sampled.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ResponseOptions {
    /// Samples per period for the peak (at least 8(H+1) are used).
    pub peak_samples: usize,
    /// Whether [`super::frf::frequency_response`] fills `FrfPoint::stable` (Hill's method,
    /// [`super::stability`]; a dense eigenproblem per point).
    pub stability: bool,
}

impl Default for ResponseOptions {
    fn default() -> Self {
        ResponseOptions {
            peak_samples: 256,
            stability: false,
        }
    }
}

/// The response of the output DOFs at one solution point.
#[derive(Clone, Debug, PartialEq)]
pub struct OutputResponse {
    /// Complex harmonics per output DOF, `harmonics[r][n]` = Q⁽ⁿ⁾ (m), n = 0..H
    /// (q(τ) = Re Σ Q⁽ⁿ⁾ e^{inτ}).
    pub harmonics: Vec<Vec<c64>>,
    /// First-harmonic amplitude |Q⁽¹⁾| per output DOF (m).
    pub amplitude: Vec<f64>,
    /// max over the period of |q(τ)| per output DOF (m), sampled.
    pub peak: Vec<f64>,
}

/// The complex harmonic n of condensed DOF `dof` from the real vector `q`.
pub fn complex_harmonic<F: HarmonicForce>(
    system: &HbmSystem<'_, F>,
    q: &[f64],
    n: usize,
    dof: usize,
) -> c64 {
    let layout = system.layout();
    let nd = system.linear().n_condensed();
    if n == 0 {
        c64::new(q[layout.static_index(dof)], 0.0)
    } else {
        let i = layout.cos_index(n, dof, nd);
        c64::new(q[i], q[i + 1])
    }
}

/// Recovers the output DOFs' response from the condensed solution `q` at ω (rad/s) with
/// excitation factor `level` (eq. 18 per harmonic).
pub fn output_response<F: HarmonicForce>(
    system: &HbmSystem<'_, F>,
    q: &[f64],
    omega: f64,
    level: f64,
    opts: &ResponseOptions,
) -> Result<OutputResponse> {
    let h = system.layout().harmonics;
    let nd = system.linear().n_condensed();
    let n_out = system.linear().n_outputs();
    let mut harmonics = vec![vec![c64::new(0.0, 0.0); h + 1]; n_out];
    for n in 0..=h {
        let (recovery, offset) = system.linear().recovery(n, omega)?;
        let q_n: Vec<c64> = (0..nd).map(|d| complex_harmonic(system, q, n, d)).collect();
        let out = recover(&recovery, &offset, &q_n);
        for (o, (slot, v)) in harmonics.iter_mut().zip(out).enumerate() {
            // the offset is the response to the excitation: scale it by the level
            let v = v + offset[o] * (level - 1.0);
            slot[n] = if n == 0 { c64::new(v.re, 0.0) } else { v };
        }
    }
    let amplitude = harmonics
        .iter()
        .map(|hs| hs.get(1).map_or(0.0, |q| q.norm()))
        .collect();
    let circle = unit_circle(opts.peak_samples.max(8 * (h + 1)));
    let peak = harmonics.iter().map(|hs| peak_on(hs, &circle)).collect();
    Ok(OutputResponse {
        harmonics,
        amplitude,
        peak,
    })
}

/// max_τ |Re Σ Q⁽ⁿ⁾ e^{inτ}| over `samples` equally spaced τ; e^{inτ_k} = e^{iτ_(nk mod
/// samples)} read from one table of the unit circle (each value within an ulp or two of
/// (cos nτ_k, sin nτ_k)).
pub fn peak_of(harmonics: &[c64], samples: usize) -> f64 {
    peak_on(harmonics, &unit_circle(samples))
}

/// e^{iτ_k} = (cos τ_k, sin τ_k) at τ_k = 2πk/`samples`, k = 0..samples. When `samples` is a
/// multiple of 4 only the first quarter takes a sine and cosine: e^{i(τ + π/2)} = i e^{iτ}
/// (an exact swap and sign change) gives the others.
fn unit_circle(samples: usize) -> Vec<c64> {
    let direct = |k: usize| {
        let tau = 2.0 * std::f64::consts::PI * k as f64 / samples as f64;
        let (sin, cos) = tau.sin_cos();
        c64::new(cos, sin)
    };
    if !samples.is_multiple_of(4) {
        return (0..samples).map(direct).collect();
    }
    let quarter = samples / 4;
    let mut circle: Vec<c64> = (0..quarter).map(direct).collect();
    for k in quarter..samples {
        let z = circle[k - quarter];
        circle.push(c64::new(-z.im, z.re));
    }
    circle
}

/// [`peak_of`] on the samples e^{iτ_k} of [`unit_circle`].
fn peak_on(harmonics: &[c64], circle: &[c64]) -> f64 {
    let samples = circle.len();
    (0..samples)
        .map(|k| {
            // e^{inτ_k} = circle[n k mod samples], the index advanced by k per harmonic
            let mut index = 0;
            let mut value = 0.0;
            for q in harmonics {
                let phase = circle[index];
                value += q.re * phase.re - q.im * phase.im;
                index += k;
                if index >= samples {
                    index -= samples;
                }
            }
            value.abs()
        })
        .fold(0.0, f64::max)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The peak from the table of the unit circle equals the sum with a sine and cosine per
    /// term to 1e-14 of the amplitudes' sum, for H = 1, 7, 15 and sample counts that are and
    /// are not multiples of 4; a single harmonic's peak is |Q⁽¹⁾| where a sample
    /// meets the maximum (phase 0).
    #[test]
    fn peak_from_the_circle_table_equals_the_direct_sum() {
        for h in [1usize, 7, 15] {
            let harmonics: Vec<c64> = (0..=h)
                .map(|n| {
                    c64::new(
                        0.7 / (n + 1) as f64,
                        0.4 * (n as f64 - 2.5) / (n + 1) as f64,
                    )
                })
                .collect();
            for samples in [256, 250] {
                let direct = (0..samples)
                    .map(|k| {
                        let tau = 2.0 * std::f64::consts::PI * k as f64 / samples as f64;
                        harmonics
                            .iter()
                            .enumerate()
                            .map(|(n, q)| {
                                q.re * (n as f64 * tau).cos() - q.im * (n as f64 * tau).sin()
                            })
                            .sum::<f64>()
                            .abs()
                    })
                    .fold(0.0, f64::max);
                let scale: f64 = harmonics.iter().map(|q| q.norm()).sum();
                let got = peak_of(&harmonics, samples);
                assert!(
                    (got - direct).abs() <= 1e-14 * scale,
                    "H = {h}, {samples} samples: {got} vs {direct}"
                );
            }
        }
        let single = [c64::new(0.0, 0.0), c64::new(1.5, 0.0)];
        assert!((peak_of(&single, 64) - 1.5).abs() <= 1e-15);
    }
}
