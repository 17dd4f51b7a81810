//! Periodic time signals of the march: a static part plus a first harmonic at the excitation
//! frequency ω (rad/s), used for external forces f_e(t) and prescribed (platform) motions.

/// s(t) = `mean` + `cos`·cos(ωt) + `sin`·sin(ωt), in the unit of the quantity it describes
/// (N for forces, m for prescribed displacements).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Harmonic {
    /// Static part.
    pub mean: f64,
    /// Coefficient of cos(ωt).
    pub cos: f64,
    /// Coefficient of sin(ωt).
    pub sin: f64,
}

impl Harmonic {
    /// A constant signal.
    pub fn constant(mean: f64) -> Self {
        Harmonic {
            mean,
            ..Harmonic::default()
        }
    }

    /// `amplitude`·cos(ωt + `phase`) (phase in rad): cos part a·cos φ, sin part −a·sin φ.
    pub fn cosine(amplitude: f64, phase: f64) -> Self {
        Harmonic {
            mean: 0.0,
            cos: amplitude * phase.cos(),
            sin: -amplitude * phase.sin(),
        }
    }

    /// The value at time `t` (s) for the excitation frequency `omega` (rad/s).
    pub fn at(&self, omega: f64, t: f64) -> f64 {
        let (s, c) = (omega * t).sin_cos();
        self.at_phase(c, s)
    }

    /// The value at the phase ωt given by its cosine `c` and sine `s` (one sin_cos shared by
    /// every signal of an instant).
    pub fn at_phase(&self, c: f64, s: f64) -> f64 {
        self.mean + self.cos * c + self.sin * s
    }

    /// The largest |s(t)| bound: |mean| + √(cos² + sin²).
    pub fn bound(&self) -> f64 {
        self.mean.abs() + self.cos.hypot(self.sin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cosine_with_phase_matches_its_definition() {
        let h = Harmonic::cosine(2.0, 0.3);
        for t in [0.0, 0.1, 0.77] {
            let expected = 2.0 * (3.0 * t + 0.3_f64).cos();
            assert!((h.at(3.0, t) - expected).abs() < 1e-14);
        }
        assert!((h.bound() - 2.0).abs() < 1e-14);
    }
}
