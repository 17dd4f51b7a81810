//! Carpenter's explicit forward-increment Lagrange multiplier method (Carpenter, Taylor & Katona,
//! "Lagrange constraints for transient finite element surface contact", IJNME 32:103–128, 1991),
//! the explicit reference of Thorin et al. (ASME GT2018-75959, 2018, §3), with an explicit heat
//! update.
//!
//! Central differences on the mechanical rows, the equation at t_n and the constraint at
//! t_{n+1} (the multiplier λ_n, a force in N, is referenced one increment ahead):
//!
//! M ü_n + C u̇_n + K^uu u_n + K^uθ θ_n = f^u_n + H^u λ_n,   0 ≤ g(u_{n+1}) ⊥ λ_n ≥ 0,
//! ü_n = (u_{n+1} − 2u_n + u_{n−1})/h²,  u̇_n = (u_{n+1} − u_{n−1})/(2h).
//!
//! With A_c = M/h² + C/(2h):
//! 1. prediction A_c u^p = f^u_n − K^uθθ_n − (K^uu − 2M/h²)u_n − (M/h² − C/(2h))u_{n−1};
//! 2. the LCP 0 ≤ g0 + G u^p + W_c λ_n ⊥ λ_n ≥ 0 with W_c = G A_c⁻¹H^u (Carpenter drops the
//!    non-penetrating contacts and the tensile multipliers iteratively; the LCP is the same
//!    problem solved exactly by Lemke);
//! 3. correction u_{n+1} = u^p + A_c⁻¹H^u λ_n;
//! 4. heat by forward Euler, C^θθ(θ_{n+1} − θ_n) = h(f^θ_n − K^θθθ_n + H^θλ_n).
//!
//! Start-up: u_{−1} = u_0 − h u̇_0 + (h²/2) ü_0 with ü_0 = M⁻¹(f_0 − C u̇_0 − K^uu u_0 − K^uθθ_0).
//! The scheme is stable for h < h_c = 2/ω_max, ω_max² = λ_max(K^uu, M^uu) (any damping, since C
//! is centred), and its heat update for h < 2/μ_max, μ_max = λ_max(K^θθ, C^θθ)
//! ([`stability_limits`]). The recorded velocity is (u_{n+1} − u_n)/h, the recorded impulse
//! h λ_n.

use std::time::Instant;

use faer::Mat;

use super::lcp;
use super::obstacle::{
    mul, HeatTerms, NonsmoothHistory, NonsmoothSettings, NonsmoothSystem, SparseRows, StepLu,
};
use crate::eigen::pencil::direct_eigenvalues;
use crate::error::{Error, Result};

/// The stability limits of the explicit scheme (s).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StabilityLimits {
    /// Central differences: h_c = 2/ω_max.
    pub mechanical: f64,
    /// Forward-Euler heat update: 2/μ_max (∞ without thermal DOF).
    pub thermal: f64,
}

impl StabilityLimits {
    /// The smaller of the two.
    pub fn step(&self) -> f64 {
        self.mechanical.min(self.thermal)
    }
}

/// The largest generalised eigenvalue of the symmetric pencil (A, B) with B positive definite
/// (rows/columns `range` of the row-major n × n matrices), by [`direct_eigenvalues`].
fn largest_eigenvalue(
    a: &[f64],
    b: &[f64],
    n: usize,
    range: std::ops::Range<usize>,
) -> Result<f64> {
    let k = range.len();
    let off = range.start;
    let am = Mat::from_fn(k, k, |i, j| a[(off + i) * n + off + j]);
    let bm = Mat::from_fn(k, k, |i, j| b[(off + i) * n + off + j]);
    let values = direct_eigenvalues(am.as_ref(), bm.as_ref())
        .map_err(|e| Error::Compute(format!("carpenter: the stability limit: {e}")))?;
    Ok(values.iter().fold(0.0_f64, |m, &v| m.max(v)))
}

/// The stability limits of [`carpenter`] on `sys` (module doc).
pub fn stability_limits(sys: &NonsmoothSystem) -> Result<StabilityLimits> {
    let (n, nm) = (sys.n, sys.n_mech);
    let w2 = largest_eigenvalue(&sys.stiffness, &sys.mass, n, 0..nm)?;
    let thermal = if nm < n {
        let mu = largest_eigenvalue(&sys.stiffness, &sys.damping, n, nm..n)?;
        2.0 / mu
    } else {
        f64::INFINITY
    };
    Ok(StabilityLimits {
        mechanical: 2.0 / w2.sqrt(),
        thermal,
    })
}

/// Marches `sys` with Carpenter's scheme for `s.steps` steps of `s.step` (γ and ε_g unused).
pub fn carpenter(sys: &NonsmoothSystem, s: &NonsmoothSettings) -> Result<NonsmoothHistory> {
    sys.validate("carpenter")?;
    if !(s.step > 0.0 && s.step.is_finite()) {
        return Err(Error::input(format!(
            "key 'march.time_step_s': the time step must be > 0, got {}",
            s.step
        )));
    }
    let start = Instant::now();
    let (n, nm, h) = (sys.n, sys.n_mech, s.step);
    let sub = |a: &[f64], r: std::ops::Range<usize>| -> Vec<f64> {
        let k = r.len();
        (0..k * k)
            .map(|ij| a[(r.start + ij / k) * n + r.start + ij % k])
            .collect()
    };
    let mm = sub(&sys.mass, 0..nm);
    let cm = sub(&sys.damping, 0..nm);
    let ac: Vec<f64> = mm
        .iter()
        .zip(&cm)
        .map(|(m, c)| m / (h * h) + c / (2.0 * h))
        .collect();
    let ac_lu = StepLu::new(&ac, nm, "carpenter: M/h² + C/(2h)")?;
    let cap_lu = if nm < n {
        Some(StepLu::new(
            &sub(&sys.damping, nm..n),
            n - nm,
            "carpenter: the heat capacity C^θθ",
        )?)
    } else {
        None
    };
    let m = sys.obstacles.len();
    let columns: Vec<Vec<f64>> = sys.obstacles.iter().map(|o| o.column(n)).collect();
    let z: Vec<Vec<f64>> = columns.iter().map(|c| ac_lu.solve(&c[..nm])).collect();
    let w: Vec<f64> = (0..m * m)
        .map(|ij| sys.obstacles[ij / m].rate(&z[ij % m]))
        .collect();
    // Start-up from the consistent initial acceleration.
    let mut x = sys.x0.clone();
    let f0 = sys.load(s.start);
    let kx = mul(&sys.stiffness, &x);
    let cv = mul(&sys.damping, &sys.v0);
    let m_lu = StepLu::new(&mm, nm, "carpenter: the mass matrix")?;
    let a0 = m_lu.solve(&(0..nm).map(|r| f0[r] - cv[r] - kx[r]).collect::<Vec<_>>());
    let mut u_prev: Vec<f64> = (0..nm)
        .map(|r| x[r] - h * sys.v0[r] + 0.5 * h * h * a0[r])
        .collect();
    let mut hist = NonsmoothHistory::new("carpenter", sys, s);
    hist.push(
        sys,
        s.start,
        &x,
        &sys.v0,
        &vec![0.0; m],
        &vec![false; m],
        (0.0, 0),
    );
    let mut heat = HeatTerms::default();
    if nm < n {
        hist.heat.push(heat);
    }
    let mut v = sys.v0.clone();
    let b_prev: Vec<f64> = (0..nm * nm)
        .map(|ij| mm[ij] / (h * h) - cm[ij] / (2.0 * h))
        .collect();
    // The products of the loop on the non-zero entries.
    let k_rows = SparseRows::new(&sys.stiffness, n, 0..n, 0..n);
    let c_th = SparseRows::new(&sys.damping, n, nm..n, 0..n);
    let m_rows = SparseRows::new(&mm, nm, 0..nm, 0..nm);
    let b_rows = SparseRows::new(&b_prev, nm, 0..nm, 0..nm);
    for step in 0..s.steps {
        let tn = s.start + step as f64 * h;
        let f = sys.load(tn);
        let kx = k_rows.mul(&x);
        let mu_n = m_rows.mul(&x[..nm]);
        let bp = b_rows.mul(&u_prev);
        let rhs: Vec<f64> = (0..nm)
            .map(|r| f[r] - kx[r] + 2.0 * mu_n[r] / (h * h) - bp[r])
            .collect();
        let mut up = ac_lu.solve(&rhs);
        let gp: Vec<f64> = sys.obstacles.iter().map(|o| o.gap_at(&up)).collect();
        let sol = lcp::solve(&w, &gp).ok_or_else(|| {
            Error::Compute(format!(
                "carpenter: the contact LCP of step {} has no solution",
                step + 1
            ))
        })?;
        for (i, &l) in sol.lambda.iter().enumerate() {
            for (ur, zr) in up.iter_mut().zip(&z[i]) {
                *ur += zr * l;
            }
        }
        let mut x1 = x.clone();
        x1[..nm].copy_from_slice(&up);
        if let Some(cap) = &cap_lu {
            let q: Vec<f64> = (nm..n)
                .map(|r| {
                    f[r] - kx[r]
                        + columns
                            .iter()
                            .zip(&sol.lambda)
                            .map(|(c, &l)| c[r] * l)
                            .sum::<f64>()
                })
                .collect();
            let dtheta = cap.solve(&q);
            for (r, d) in (nm..n).zip(&dtheta) {
                x1[r] += h * d;
            }
            let dx: Vec<f64> = x1.iter().zip(&x).map(|(a, b)| a - b).collect();
            let stored: f64 = (0..n - nm)
                .map(|a| sys.heat_weight(nm + a) * c_th.row_dot(a, &dx))
                .sum();
            heat.stored += stored;
            heat.exchanged += h
                * (nm..n)
                    .map(|r| sys.heat_weight(r) * (f[r] - kx[r]))
                    .sum::<f64>();
            heat.frictional += h
                * (nm..n)
                    .map(|r| {
                        sys.heat_weight(r)
                            * columns
                                .iter()
                                .zip(&sol.lambda)
                                .map(|(c, &l)| c[r] * l)
                                .sum::<f64>()
                    })
                    .sum::<f64>();
            heat.residual = heat.stored - heat.exchanged - heat.frictional;
        }
        for r in 0..n {
            v[r] = (x1[r] - x[r]) / h;
        }
        u_prev = x[..nm].to_vec();
        x = x1;
        let impulse: Vec<f64> = sol.lambda.iter().map(|l| l * h).collect();
        let active: Vec<bool> = sol.lambda.iter().map(|&l| l > 0.0).collect();
        let t1 = s.start + (step + 1) as f64 * h;
        hist.push(
            sys,
            t1,
            &x,
            &v,
            &impulse,
            &active,
            (lcp::residual(&sol.lambda, &sol.w), sol.pivots as u32),
        );
        if nm < n {
            hist.heat.push(heat);
        }
        if x.iter().any(|a| !a.is_finite() || a.abs() > 1e150) {
            return Err(Error::Compute(format!(
                "carpenter: the state is not finite at step {} (t = {t1:.6e} s); the step exceeds the stability limit?",
                step + 1
            )));
        }
    }
    hist.x_final = x;
    hist.v_final = v;
    hist.wall_seconds = start.elapsed().as_secs_f64();
    Ok(hist)
}
