//! The time-discrete friction contact law of one node-to-node element with normal load variation,
//! evaluated at a single time sample (SAMA paper, Battiato 2021, §3 eqs 13–14; the algorithm of
//! `docs/theory.md`, "The friction contact element").
//!
//! Local coordinates of an element (`docs/conventions.md` §3): tangential relative displacements
//! u = (u1, u2) (m) along t1, t2, normal approach v (m, v > 0 closes the gap), slider positions
//! w = (w1, w2) (m). Parameters: tangential stiffness k_t (N/m), normal stiffness k_n (N/m),
//! friction coefficient μ (–), static normal load n0 (N; n0 < 0 is an initial gap −n0/k_n).
//!
//! * normal force (eq. 13): f_n = max(n0 + k_n v, 0) ≥ 0;
//! * separation (f_n = 0): f_t = 0, w ← u;
//! * trial force f_tr = k_t (u − w); stick if |f_tr| ≤ μ f_n: f_t = f_tr, w unchanged;
//! * slip otherwise (eq. 14): f_t = μ f_n f_tr/|f_tr|, w ← u − f_t/k_t (radial return).
//!
//! The `1d` variant applies this to t1 and t2 independently (each direction its own slider, both
//! limited by μ f_n, as the SAMA paper uses); the `2d` variant uses the vector trial force and the
//! Coulomb disc |f_t| ≤ μ f_n.
//!
//! Forces are returned with the sign of an internal force (the `HarmonicForce` convention): f_t is
//! the force conjugate to u (a stuck element is the spring k_t (u − w)) and f_n ≥ 0 is conjugate
//! to v. On the contact node the element thus acts with −(f_1 t1 + f_2 t2) + f_n **n**.
//!
//! The functions are pure: (slider state, u, v, parameters) → (forces, new slider state, regime).
//! [`sample_with_tangent`] also returns the partial derivatives used by the harmonic-balance
//! Jacobian and by an implicit time integrator.

use crate::error::{Error, Result};

/// Parameters of one contact element (SAMA paper eq. 13–14; SAMA's weighted parameters of eq. 31
/// are just other values of these).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactParams {
    /// Tangential contact stiffness k_t (N/m), ≥ 0.
    pub kt: f64,
    /// Normal contact stiffness k_n (N/m), ≥ 0.
    pub kn: f64,
    /// Friction coefficient μ (–), ≥ 0.
    pub mu: f64,
    /// Static normal load n0 (N); negative: initial gap g0 = −n0/k_n.
    pub n0: f64,
}

impl ContactParams {
    /// Checked parameters; `context` names where they come from (e.g. `"[[element]] 3"` or
    /// "contact pair 12") and is put into the error message.
    pub fn new(kt: f64, kn: f64, mu: f64, n0: f64, context: &str) -> Result<Self> {
        let p = ContactParams { kt, kn, mu, n0 };
        p.validate(context)?;
        Ok(p)
    }

    /// Errors when a parameter is not finite or k_t, k_n, μ is negative.
    pub fn validate(&self, context: &str) -> Result<()> {
        for (name, value) in [
            ("kt", self.kt),
            ("kn", self.kn),
            ("mu", self.mu),
            ("n0", self.n0),
        ] {
            if !value.is_finite() {
                return Err(Error::input(format!(
                    "{context}: contact parameter {name} = {value} is not a finite number"
                )));
            }
        }
        for (name, value, unit) in [
            ("kt", self.kt, "N/m"),
            ("kn", self.kn, "N/m"),
            ("mu", self.mu, ""),
        ] {
            if value < 0.0 {
                return Err(Error::input(format!(
                    "{context}: contact parameter {name} = {value} {unit} is negative; stiffnesses and the friction coefficient must be ≥ 0"
                )));
            }
        }
        Ok(())
    }
}

/// Which tangential law an element uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Variant {
    /// t1 and t2 independent, each with its own slider and the limit μ f_n (SAMA paper Fig. 2a, 3).
    OneD,
    /// Vector trial force, Coulomb disc |f_t| ≤ μ f_n, radial return (SAMA paper Fig. 2b).
    TwoD,
}

/// Contact regime of a tangential direction at one sample.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Regime {
    /// |k_t (u − w)| ≤ μ f_n: the slider does not move.
    Stick,
    /// The trial force exceeded μ f_n: the slider moved, |f_t| = μ f_n.
    Slip,
    /// f_n = 0: no contact force, the slider follows u.
    Separation,
}

/// Normal force f_n = max(n0 + k_n v, 0) (N), SAMA paper eq. 13.
#[inline]
pub fn normal_force(p: &ContactParams, v: f64) -> f64 {
    (p.n0 + p.kn * v).max(0.0)
}

/// Forces and new slider state of one sample (no derivatives).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sample {
    /// (f1, f2, f_n) (N): tangential forces (internal-force sign) and the normal force ≥ 0.
    pub force: [f64; 3],
    /// Slider positions (w1, w2) (m) after the sample.
    pub slider: [f64; 2],
    /// Regime of t1 and t2 (identical for the 2-D variant).
    pub regime: [Regime; 2],
}

/// Relative margin of the stick test |trial| ≤ μ f_n (1 + margin): a slider placed by a slip
/// (w = u − f/k_t with |f| = μ f_n) lies on the limit up to rounding, and when the same input
/// comes back (the next period, after a shakedown) it must stick rather than "slip" by one ulp —
/// that ulp decides the derivative branch (for the 2-D law, a slip with |trial| → μ f_n has the
/// near-singular memory tangent A → t tᵀ). The force changes by at most this relative amount.
pub const STICK_MARGIN: f64 = 8.0 * f64::EPSILON;

/// One tangential direction of the 1-D law: returns (f_t, new w, regime) for the limit
/// `limit` = μ f_n (N), `separated` = (f_n = 0).
#[inline]
pub fn tangential_1d(kt: f64, limit: f64, separated: bool, u: f64, w: f64) -> (f64, f64, Regime) {
    tangential_1d_reach(kt, limit, limit / kt, separated, u, w)
}

/// [`tangential_1d`] with the slip offset of the slider `reach` = `limit` / k_t (m) given,
/// formed once for a whole period of constant limit: the slip sets w = u − σ·reach, σ = sgn
/// f_tr, which is u − f_t/k_t bit for bit (IEEE division is correctly rounded and odd in its
/// numerator, (−a)/b = −(a/b)), without a division on the chain from one sample's slider to
/// the next.
#[inline]
pub fn tangential_1d_reach(
    kt: f64,
    limit: f64,
    reach: f64,
    separated: bool,
    u: f64,
    w: f64,
) -> (f64, f64, Regime) {
    if separated {
        return (0.0, u, Regime::Separation);
    }
    let trial = kt * (u - w);
    if trial.abs() <= limit * (1.0 + STICK_MARGIN) {
        (trial, w, Regime::Stick)
    } else {
        (
            limit.copysign(trial),
            u - reach.copysign(trial),
            Regime::Slip,
        )
    }
}

/// The 2-D law (Coulomb disc, radial return): returns (f_t, new w, regime).
#[inline]
pub fn tangential_2d(
    kt: f64,
    limit: f64,
    separated: bool,
    u: [f64; 2],
    w: [f64; 2],
) -> ([f64; 2], [f64; 2], Regime) {
    if separated {
        return ([0.0; 2], u, Regime::Separation);
    }
    let trial = [kt * (u[0] - w[0]), kt * (u[1] - w[1])];
    // √(a² + b²) rather than `hypot` (several times slower; no overflow risk at contact scales).
    let norm = (trial[0] * trial[0] + trial[1] * trial[1]).sqrt();
    if norm <= limit * (1.0 + STICK_MARGIN) {
        (trial, w, Regime::Stick)
    } else {
        let scale = limit / norm;
        let f = [trial[0] * scale, trial[1] * scale];
        (f, [u[0] - f[0] / kt, u[1] - f[1] / kt], Regime::Slip)
    }
}

/// One sample of the element law: forces, new slider state and regimes for the local relative
/// displacements `u` = (u1, u2), approach `v` and the slider state `w` before the sample.
#[inline]
pub fn sample(variant: Variant, p: &ContactParams, u: [f64; 2], v: f64, w: [f64; 2]) -> Sample {
    let fnorm = normal_force(p, v);
    let separated = fnorm <= 0.0;
    let limit = p.mu * fnorm;
    match variant {
        Variant::OneD => {
            let (f1, w1, r1) = tangential_1d(p.kt, limit, separated, u[0], w[0]);
            let (f2, w2, r2) = tangential_1d(p.kt, limit, separated, u[1], w[1]);
            Sample {
                force: [f1, f2, fnorm],
                slider: [w1, w2],
                regime: [r1, r2],
            }
        }
        Variant::TwoD => {
            let (f, wn, r) = tangential_2d(p.kt, limit, separated, u, w);
            Sample {
                force: [f[0], f[1], fnorm],
                slider: wn,
                regime: [r, r],
            }
        }
    }
}

/// A sample with the partial derivatives of its outputs. Inputs are x = (u1, u2, v, n0) and the
/// slider state w before the sample; everything else is held fixed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampleTangent {
    /// Forces, new slider state and regimes (as [`sample`]).
    pub sample: Sample,
    /// ∂(f1, f2, f_n)/∂(u1, u2, v, n0) at fixed w.
    pub dforce_dx: [[f64; 4]; 3],
    /// ∂(f1, f2)/∂(w1, w2) at fixed x (f_n does not depend on w).
    pub dforce_dw: [[f64; 2]; 2],
    /// ∂(w1', w2')/∂(u1, u2, v, n0) of the new slider state at fixed w.
    pub dslider_dx: [[f64; 4]; 2],
    /// ∂(w1', w2')/∂(w1, w2) at fixed x.
    pub dslider_dw: [[f64; 2]; 2],
}

/// [`sample`] with its partial derivatives (`docs/theory.md`: separation ∂w' = ∂u; stick
/// ∂f_t = k_t (∂u − ∂w), ∂w' = ∂w; slip ∂f_t = sgn μ ∂f_n (1-D) or the radial-return tangent
/// (2-D), ∂w' = ∂u − ∂f_t/k_t). Where the law is not differentiable (exactly on a regime
/// boundary) the derivative of the regime selected by [`sample`] is returned.
#[inline]
pub fn sample_with_tangent(
    variant: Variant,
    p: &ContactParams,
    u: [f64; 2],
    v: f64,
    w: [f64; 2],
) -> SampleTangent {
    let s = sample(variant, p, u, v, w);
    let mut t = SampleTangent {
        sample: s,
        dforce_dx: [[0.0; 4]; 3],
        dforce_dw: [[0.0; 2]; 2],
        dslider_dx: [[0.0; 4]; 2],
        dslider_dw: [[0.0; 2]; 2],
    };
    if s.force[2] <= 0.0 {
        // Separation: f = 0, w' = u.
        t.dslider_dx[0][0] = 1.0;
        t.dslider_dx[1][1] = 1.0;
        return t;
    }
    // ∂f_n/∂(u1, u2, v, n0) and ∂(μ f_n)/∂x.
    t.dforce_dx[2] = [0.0, 0.0, p.kn, 1.0];
    let dlimit = [0.0, 0.0, p.mu * p.kn, p.mu];
    match variant {
        Variant::OneD => {
            for d in 0..2 {
                match s.regime[d] {
                    Regime::Stick => {
                        t.dforce_dx[d][d] = p.kt;
                        t.dforce_dw[d][d] = -p.kt;
                        t.dslider_dw[d][d] = 1.0;
                    }
                    Regime::Slip => {
                        let sign = s.force[d].signum();
                        // f = sign μ f_n; w' = u − f/k_t.
                        for (c, dl) in dlimit.iter().enumerate() {
                            t.dforce_dx[d][c] = sign * dl;
                            t.dslider_dx[d][c] = -sign * dl / p.kt;
                        }
                        t.dslider_dx[d][d] += 1.0;
                    }
                    Regime::Separation => unreachable!("f_n > 0 here"),
                }
            }
        }
        Variant::TwoD => match s.regime[0] {
            Regime::Stick => {
                for d in 0..2 {
                    t.dforce_dx[d][d] = p.kt;
                    t.dforce_dw[d][d] = -p.kt;
                    t.dslider_dw[d][d] = 1.0;
                }
            }
            Regime::Slip => {
                // f = L t̂, t̂ = e/|e|, e = u − w, L = μ f_n:
                // ∂f = t̂ ∂L + (L/|e|)(I − t̂ t̂ᵀ)(∂u − ∂w); w' = u − f/k_t.
                let e = [u[0] - w[0], u[1] - w[1]];
                let norm = (e[0] * e[0] + e[1] * e[1]).sqrt();
                let dir = [e[0] / norm, e[1] / norm];
                let limit = p.mu * s.force[2];
                let ratio = limit / norm;
                for a in 0..2 {
                    for b in 0..2 {
                        let proj = if a == b { 1.0 } else { 0.0 } - dir[a] * dir[b];
                        t.dforce_dx[a][b] = ratio * proj;
                        t.dforce_dw[a][b] = -ratio * proj;
                    }
                    for (c, dl) in dlimit.iter().enumerate().skip(2) {
                        t.dforce_dx[a][c] = dir[a] * dl;
                    }
                }
                for a in 0..2 {
                    for c in 0..4 {
                        let unit = if a == c { 1.0 } else { 0.0 };
                        t.dslider_dx[a][c] = unit - t.dforce_dx[a][c] / p.kt;
                    }
                    for b in 0..2 {
                        t.dslider_dw[a][b] = -t.dforce_dw[a][b] / p.kt;
                    }
                }
            }
            Regime::Separation => unreachable!("f_n > 0 here"),
        },
    }
    t
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn jenkins_branches() {
        let p = ContactParams::new(2.0, 0.0, 0.5, 1.0, "test").unwrap();
        // limit 0.5: stick for |2(u − w)| ≤ 0.5
        let s = sample(Variant::OneD, &p, [0.1, -0.2], 0.0, [0.0, 0.0]);
        assert_eq!(s.regime, [Regime::Stick, Regime::Stick]);
        assert!((s.force[0] - 0.2).abs() < 1e-15 && (s.force[1] + 0.4).abs() < 1e-15);
        let s = sample(Variant::OneD, &p, [1.0, -1.0], 0.0, [0.0, 0.0]);
        assert_eq!(s.regime, [Regime::Slip, Regime::Slip]);
        assert_eq!(s.force, [0.5, -0.5, 1.0]);
        assert!((s.slider[0] - 0.75).abs() < 1e-15 && (s.slider[1] + 0.75).abs() < 1e-15);
    }
}
