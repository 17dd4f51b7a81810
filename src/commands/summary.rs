//! The scalar summary of one frequency response curve: resonance frequency, peak amplitude and
//! Q-factor (the performance curves of the SAMA paper, Battiato 2021, §6.2, Figs 23–25 and 28–30).
//!
//! Definitions (used by `nlrom solve --json`, `nlrom batch` and its `summary.csv`):
//! - the *response DOF of the curve* is the response DOF whose first-harmonic amplitude
//!   |Q⁽¹⁾| (m) is largest anywhere on the curve (with one response DOF, that DOF);
//! - *peak amplitude* A_r (m): that largest |Q⁽¹⁾|, at a computed point (no interpolation);
//! - *resonance frequency* f_r (Hz): the excitation frequency of that point;
//! - *Q-factor*: half-power bandwidth on the same DOF's curve, Q = f_r / (f₂ − f₁), where f₁ and
//!   f₂ are the first frequencies below and above the peak (walking the curve in path order from
//!   the peak point) at which the amplitude falls to A_r/√2, each located by linear interpolation
//!   between the two points that bracket A_r/√2. Q is `None` when the curve does not fall below
//!   A_r/√2 on both sides of the peak within the computed range.
//!
//! For a linear single-DOF oscillator with small damping ratio ζ this gives Q ≈ 1/(2ζ); the unit
//! test checks the exact half-power frequencies ω² = 1 − 2ζ² ± 2ζ√(1 − ζ²) (k = m = 1).

/// Summary of one curve (see the module documentation for the definitions).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveSummary {
    /// Resonance frequency f_r (Hz).
    pub resonance_hz: f64,
    /// Peak first-harmonic amplitude A_r (m).
    pub peak_amplitude: f64,
    /// Index of the response DOF the summary refers to.
    pub response_dof: usize,
    /// Index of the peak point in the curve (path order).
    pub peak_point: usize,
    /// Half-power Q-factor f_r/(f₂ − f₁); `None` when the curve does not drop below A_r/√2 on
    /// both sides of the peak.
    pub q_factor: Option<f64>,
}

/// Summarises a curve of `frequency_hz[p]` (Hz, path order) and first-harmonic amplitudes
/// `amplitude[p][r]` (m) of R response DOFs. `None` for an empty curve or one without response
/// DOFs.
pub fn summarize(frequency_hz: &[f64], amplitude: &[Vec<f64>]) -> Option<CurveSummary> {
    let mut best: Option<(usize, usize, f64)> = None;
    for (p, row) in amplitude.iter().enumerate() {
        for (r, &a) in row.iter().enumerate() {
            if a.is_finite() && best.is_none_or(|(_, _, b)| a > b) {
                best = Some((p, r, a));
            }
        }
    }
    let (peak_point, r, peak) = best?;
    let curve: Vec<f64> = amplitude.iter().map(|row| row[r]).collect();
    Some(CurveSummary {
        resonance_hz: frequency_hz[peak_point],
        peak_amplitude: peak,
        response_dof: r,
        peak_point,
        q_factor: half_power_q(frequency_hz, &curve, peak_point),
    })
}

/// Q = f_r/(f₂ − f₁) of the curve `a[p]` over `f[p]` with its peak at point `peak` (module
/// documentation); `None` without both half-power crossings or with f₂ ≤ f₁.
pub fn half_power_q(f: &[f64], a: &[f64], peak: usize) -> Option<f64> {
    let level = a[peak] / std::f64::consts::SQRT_2;
    let below = crossing(f, a, peak, level, -1)?;
    let above = crossing(f, a, peak, level, 1)?;
    let (f1, f2) = if below <= above {
        (below, above)
    } else {
        (above, below)
    };
    (f2 > f1).then(|| f[peak] / (f2 - f1))
}

/// The frequency where the curve first falls to `level`, walking from point `peak` in direction
/// `dir` (±1) along the path; linear interpolation between the bracketing points.
fn crossing(f: &[f64], a: &[f64], peak: usize, level: f64, dir: isize) -> Option<f64> {
    let mut i = peak;
    loop {
        let j = i.checked_add_signed(dir).filter(|&j| j < a.len())?;
        if a[j] <= level {
            let t = (a[i] - level) / (a[i] - a[j]);
            return Some(f[i] + t * (f[j] - f[i]));
        }
        i = j;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// |X(ω)| of m ẍ + c ẋ + k x = cos ωt with k = m = 1, c = 2ζ.
    fn sdof(omega: f64, zeta: f64) -> f64 {
        1.0 / ((1.0 - omega * omega).powi(2) + (2.0 * zeta * omega).powi(2)).sqrt()
    }

    #[test]
    fn sdof_resonance_peak_and_q_match_the_closed_form() {
        let zeta: f64 = 0.02;
        let n = 20_001;
        let (w0, w1) = (0.8, 1.2);
        let omega: Vec<f64> = (0..n)
            .map(|i| w0 + (w1 - w0) * i as f64 / (n - 1) as f64)
            .collect();
        let two_pi = 2.0 * std::f64::consts::PI;
        let hz: Vec<f64> = omega.iter().map(|w| w / two_pi).collect();
        // two response DOFs: the second is the larger one (2 |X|) and must be chosen
        let amp: Vec<Vec<f64>> = omega
            .iter()
            .map(|&w| vec![sdof(w, zeta), 2.0 * sdof(w, zeta)])
            .collect();
        let s = summarize(&hz, &amp).unwrap();
        assert_eq!(s.response_dof, 1);
        // exact: ω_p = √(1 − 2ζ²), A = 1/(2ζ√(1 − ζ²)), half-power ω² = 1 − 2ζ² ± 2ζ√(1 − ζ²)
        let wp = (1.0 - 2.0 * zeta * zeta).sqrt();
        let peak = 2.0 / (2.0 * zeta * (1.0 - zeta * zeta).sqrt());
        let d = 2.0 * zeta * (1.0 - zeta * zeta).sqrt();
        let (wa, wb) = ((wp * wp - d).sqrt(), (wp * wp + d).sqrt());
        let q_exact = wp / (wb - wa);
        let dw = (w1 - w0) / (n - 1) as f64;
        assert!(
            (s.resonance_hz * two_pi - wp).abs() <= dw,
            "{}",
            s.resonance_hz
        );
        assert!((s.peak_amplitude / peak - 1.0).abs() < 1e-6);
        let q = s.q_factor.unwrap();
        assert!((q / q_exact - 1.0).abs() < 1e-4, "Q {q} vs {q_exact}");
        // and Q ≈ 1/(2ζ) for small damping
        assert!((q * 2.0 * zeta - 1.0).abs() < 2e-3);
    }

    #[test]
    fn q_is_none_without_both_half_power_points() {
        let zeta = 0.02;
        // the range stops just above the peak: no upper half-power point
        let omega: Vec<f64> = (0..1001).map(|i| 0.8 + 0.2 * i as f64 / 1000.0).collect();
        let amp: Vec<Vec<f64>> = omega.iter().map(|&w| vec![sdof(w, zeta)]).collect();
        let s = summarize(&omega, &amp).unwrap();
        assert!(s.q_factor.is_none());
        assert!(summarize(&[], &[]).is_none());
    }

    #[test]
    fn a_fold_is_walked_in_path_order() {
        // f goes 0, 1, 2, 1.5 (fold), 3; amplitudes peak at the fold's upper branch
        let f = [0.0, 1.0, 2.0, 1.5, 3.0];
        let a = [0.1, 0.5, 1.0, 0.9, 0.1];
        let s = summarize(&f, &a.map(|x| vec![x])).unwrap();
        assert_eq!(s.resonance_hz, 2.0);
        // below: between points 1 (0.5) and 2 (1.0) at 1/√2; above: between 3 (0.9) and 4 (0.1)
        let l = std::f64::consts::FRAC_1_SQRT_2;
        let f1 = 2.0 + (1.0 - l) / 0.5 * (1.0 - 2.0);
        let f2 = 1.5 + (0.9 - l) / 0.8 * (3.0 - 1.5);
        assert!((s.q_factor.unwrap() - 2.0 / (f2 - f1)).abs() < 1e-12);
    }
}
