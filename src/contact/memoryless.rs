//! Elements whose force is a function of the instantaneous value x (m) and rate ẋ (m/s) of one
//! coordinate: the library of Krack & Gross 2019 (*Harmonic Balance for Nonlinear Vibration
//! Problems*, §2.4 and the NLvib elements) without memory — cubic and polynomial springs, the
//! unilateral (penalty, normal-only) spring with a gap, the quadratic damper and the
//! tanh-regularised Coulomb friction — evaluated by the alternating frequency/time method
//! (Cameron & Griffin 1989) with analytic Jacobians.
//!
//! With the coordinate's coefficients X (signal order of [`super::aft`], length m = 2H + 1), the
//! samples are x_j = (S X)_j and ẋ_j = ω (S D X)_j at τ_j = 2πj/N_t, where D is the derivative
//! d/dτ in coefficient space (harmonic n: Re' = −n Im, Im' = n Re) and ω (rad/s) the frequency
//! of the fundamental. The force coefficients are F = A f(x, ẋ) (A the analysis of [`Aft`]), and
//! the exact derivatives of this sampled map are
//! ∂F/∂X = M(∂f/∂x) + ω M(∂f/∂ẋ) D and ∂F/∂ω = A(∂f/∂ẋ ∘ S D X),
//! where M(a) = A diag(a) S is the harmonic matrix of multiplication by the samples a, formed
//! from their discrete Fourier sums. Forces carry the internal-force sign of
//! [`HarmonicForce`](crate::harmonics::HarmonicForce) (a spring gives f = k x).

use crate::contact::aft::{Aft, AftScratch};
use crate::contact::element::add_multiplication_block;
use crate::error::{Error, Result};

/// The force law f(x, ẋ) of one element (SI units; x in m, ẋ in m/s, f in N).
#[derive(Clone, Debug, PartialEq)]
pub enum Law {
    /// f = k3 x³ (k3 in N/m³).
    Cubic {
        /// Cubic stiffness k3 (N/m³).
        k3: f64,
    },
    /// f = Σ c_p x^p for the (c_p, p) pairs (c_p in N/m^p, p ≥ 1).
    Polynomial {
        /// (coefficient, exponent) pairs.
        terms: Vec<(f64, u32)>,
    },
    /// f = k max(x − g, 0): penalty contact closing when x reaches the gap g (k in N/m, g in m).
    Unilateral {
        /// Contact stiffness k (N/m).
        k: f64,
        /// Gap g (m).
        gap: f64,
    },
    /// f = c ẋ|ẋ| (c in N·s²/m²).
    QuadraticDamper {
        /// Damping coefficient c (N·s²/m²).
        c: f64,
    },
    /// f = f_s tanh(ẋ/ε): Coulomb friction of slip force f_s = μ n0 (N), regularised over the
    /// velocity ε (m/s).
    TanhFriction {
        /// Slip force f_s (N).
        limit: f64,
        /// Regularising velocity ε (m/s) > 0.
        eps: f64,
    },
}

impl Law {
    /// Whether the force depends on ẋ (and so on ω).
    pub fn reads_velocity(&self) -> bool {
        matches!(self, Law::QuadraticDamper { .. } | Law::TanhFriction { .. })
    }

    /// (f, ∂f/∂x, ∂f/∂ẋ) at one sample. At the kink of the unilateral spring (x = g) the
    /// contact branch is taken, as for the force (x ≥ g is in contact).
    #[inline]
    pub fn sample(&self, x: f64, v: f64) -> (f64, f64, f64) {
        match self {
            Law::Cubic { k3 } => (k3 * x * x * x, 3.0 * k3 * x * x, 0.0),
            Law::Polynomial { terms } => {
                let (mut f, mut df) = (0.0, 0.0);
                for &(c, p) in terms {
                    let lower = x.powi(p as i32 - 1);
                    f += c * lower * x;
                    df += c * p as f64 * lower;
                }
                (f, df, 0.0)
            }
            Law::Unilateral { k, gap } => {
                let d = x - gap;
                if d >= 0.0 {
                    (k * d, *k, 0.0)
                } else {
                    (0.0, 0.0, 0.0)
                }
            }
            Law::QuadraticDamper { c } => (c * v * v.abs(), 0.0, 2.0 * c * v.abs()),
            Law::TanhFriction { limit, eps } => {
                let t = (v / eps).tanh();
                (limit * t, 0.0, limit * (1.0 - t * t) / eps)
            }
        }
    }

    /// Errors when a parameter is not finite (or ε ≤ 0); `context` names the element.
    pub fn validate(&self, context: &str) -> Result<()> {
        let values: Vec<(&str, f64)> = match self {
            Law::Cubic { k3 } => vec![("k3", *k3)],
            Law::Polynomial { terms } => terms.iter().map(|t| ("coefficients", t.0)).collect(),
            Law::Unilateral { k, gap } => vec![("k", *k), ("gap", *gap)],
            Law::QuadraticDamper { c } => vec![("c", *c)],
            Law::TanhFriction { limit, eps } => vec![("mu·n0", *limit), ("eps", *eps)],
        };
        if let Some((name, v)) = values.iter().find(|(_, v)| !v.is_finite()) {
            return Err(Error::input(format!(
                "{context}: {name} = {v} is not a finite number"
            )));
        }
        if let Law::TanhFriction { eps, .. } = self {
            if *eps <= 0.0 {
                return Err(Error::input(format!(
                    "{context}: eps = {eps} m/s must be > 0 (the velocity over which tanh regularises the Coulomb force)"
                )));
            }
        }
        Ok(())
    }
}

/// Buffers of one evaluation (from [`Buffers::new`]).
pub struct Buffers {
    scratch: AftScratch,
    x: Vec<f64>,
    rate: Vec<f64>,
    f: Vec<f64>,
    dfdx: Vec<f64>,
    dfdv: Vec<f64>,
    derivative: Vec<f64>,
    sums: Vec<f64>,
    signed: Vec<[f64; 2]>,
    block: Vec<f64>,
}

impl Buffers {
    /// Buffers for the layout of `aft`.
    pub fn new(aft: &Aft) -> Self {
        let layout = aft.layout();
        let n = layout.time_samples;
        let m = layout.coefficients();
        Buffers {
            scratch: aft.scratch(),
            x: vec![0.0; n],
            rate: vec![0.0; n],
            f: vec![0.0; n],
            dfdx: vec![0.0; n],
            dfdv: vec![0.0; n],
            derivative: vec![0.0; m],
            sums: vec![0.0; 2 * (2 * layout.harmonics + 1)],
            signed: Vec::new(),
            block: vec![0.0; m * m],
        }
    }
}

/// The outputs of [`evaluate`] (each filled when given, overwritten, signal order).
pub struct LocalOutputs<'a> {
    /// F (N), length m.
    pub force: Option<&'a mut [f64]>,
    /// ∂F/∂X, m × m row-major.
    pub jacobian: Option<&'a mut [f64]>,
    /// ∂F/∂ω (N·s), length m.
    pub d_omega: Option<&'a mut [f64]>,
}

/// F(X, ω) of `law` on the coordinate coefficients `x` (signal order, m = 2H + 1) at the
/// fundamental frequency `omega` (rad/s), with the derivatives asked for in `out`.
pub fn evaluate(
    law: &Law,
    aft: &Aft,
    x: &[f64],
    omega: f64,
    out: LocalOutputs<'_>,
    b: &mut Buffers,
) -> Result<()> {
    let layout = aft.layout();
    let h = layout.harmonics;
    let m = layout.coefficients();
    if x.len() != m {
        return Err(Error::Compute(format!(
            "nonlinear element: {} coefficients for H = {h} (expected {m})",
            x.len()
        )));
    }
    aft.to_time(x, &mut b.x, &mut b.scratch);
    let velocity = law.reads_velocity();
    if velocity {
        // D X: harmonic n, Re' = −n Im, Im' = n Re.
        b.derivative[0] = 0.0;
        for n in 1..=h {
            b.derivative[2 * n - 1] = -(n as f64) * x[2 * n];
            b.derivative[2 * n] = n as f64 * x[2 * n - 1];
        }
        aft.to_time(&b.derivative, &mut b.rate, &mut b.scratch);
    } else {
        b.rate.fill(0.0);
    }
    for j in 0..layout.time_samples {
        let (f, dx, dv) = law.sample(b.x[j], omega * b.rate[j]);
        b.f[j] = f;
        b.dfdx[j] = dx;
        b.dfdv[j] = dv;
    }
    if let Some(force) = out.force {
        aft.to_harmonics(&b.f, force, &mut b.scratch);
    }
    if let Some(d) = out.d_omega {
        if velocity {
            // ∂ẋ_j/∂ω = (S D X)_j, so ∂F/∂ω = A(∂f/∂ẋ ∘ S D X).
            for (r, g) in b.rate.iter_mut().zip(&b.dfdv) {
                *r *= g;
            }
            aft.to_harmonics(&b.rate, d, &mut b.scratch);
        } else {
            d.fill(0.0);
        }
    }
    if let Some(jac) = out.jacobian {
        jac.fill(0.0);
        if !velocity || b.dfdx.iter().any(|&a| a != 0.0) {
            aft.fourier_sums(&b.dfdx, &mut b.sums, &mut b.scratch);
            add_multiplication_block(h, &b.sums, &mut b.signed, jac, m, 0, 0);
        }
        if velocity {
            // ω M(∂f/∂ẋ) D: column (n, Re) = n·column (n, Im) of M, column (n, Im) = −n·column
            // (n, Re).
            aft.fourier_sums(&b.dfdv, &mut b.sums, &mut b.scratch);
            b.block.fill(0.0);
            add_multiplication_block(h, &b.sums, &mut b.signed, &mut b.block, m, 0, 0);
            for k in 0..m {
                let row = &b.block[k * m..(k + 1) * m];
                let out = &mut jac[k * m..(k + 1) * m];
                for n in 1..=h {
                    let s = omega * n as f64;
                    out[2 * n - 1] += s * row[2 * n];
                    out[2 * n] -= s * row[2 * n - 1];
                }
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::harmonics::HarmonicLayout;

    /// Every law's ∂f/∂x and ∂f/∂ẋ equal central differences away from kinks.
    #[test]
    fn sample_derivatives_match_differences() {
        let laws = [
            Law::Cubic { k3: 2.5 },
            Law::Polynomial {
                terms: vec![(1.5, 1), (-0.7, 2), (0.3, 5)],
            },
            Law::Unilateral { k: 3.0, gap: 0.1 },
            Law::QuadraticDamper { c: 0.8 },
            Law::TanhFriction {
                limit: 1.2,
                eps: 0.3,
            },
        ];
        let h = 1e-6;
        for law in &laws {
            for &(x, v) in &[(0.7, -0.4), (-0.35, 0.9), (0.2, 0.05)] {
                let (_, dx, dv) = law.sample(x, v);
                let fdx = (law.sample(x + h, v).0 - law.sample(x - h, v).0) / (2.0 * h);
                let fdv = (law.sample(x, v + h).0 - law.sample(x, v - h).0) / (2.0 * h);
                assert!((dx - fdx).abs() <= 1e-7 * (1.0 + dx.abs()), "{law:?} x={x}");
                assert!((dv - fdv).abs() <= 1e-7 * (1.0 + dv.abs()), "{law:?} v={v}");
            }
        }
    }

    /// A velocity law's Jacobian and ω-derivative equal central differences of the sampled map.
    #[test]
    fn local_jacobian_matches_differences() {
        let aft = Aft::new(HarmonicLayout::new(3, 64).unwrap()).unwrap();
        let mut b = Buffers::new(&aft);
        let x: Vec<f64> = (0..7).map(|i| 0.3 * (1.3 * i as f64 + 0.4).sin()).collect();
        let omega = 1.7;
        let law = Law::TanhFriction {
            limit: 1.0,
            eps: 0.5,
        };
        let mut jac = vec![0.0; 49];
        let mut dw = vec![0.0; 7];
        let out = LocalOutputs {
            force: None,
            jacobian: Some(&mut jac),
            d_omega: Some(&mut dw),
        };
        evaluate(&law, &aft, &x, omega, out, &mut b).unwrap();
        let f = |x: &[f64], w: f64, b: &mut Buffers| {
            let mut f = vec![0.0; 7];
            let out = LocalOutputs {
                force: Some(&mut f),
                jacobian: None,
                d_omega: None,
            };
            evaluate(&law, &aft, x, w, out, b).unwrap();
            f
        };
        let step = 1e-6;
        for l in 0..7 {
            let (mut p, mut q) = (x.clone(), x.clone());
            p[l] += step;
            q[l] -= step;
            let (fp, fq) = (f(&p, omega, &mut b), f(&q, omega, &mut b));
            for k in 0..7 {
                let fd = (fp[k] - fq[k]) / (2.0 * step);
                assert!((jac[k * 7 + l] - fd).abs() < 1e-7, "({k},{l})");
            }
        }
        let (fp, fq) = (f(&x, omega + step, &mut b), f(&x, omega - step, &mut b));
        for k in 0..7 {
            assert!(
                (dw[k] - (fp[k] - fq[k]) / (2.0 * step)).abs() < 1e-7,
                "d/dω {k}"
            );
        }
    }
}
