//! The Moreau–Jean θ-method with a velocity-level Newton impact law (Thorin et al., ASME
//! GT2018-75959, 2018, eqs (12)–(18); Acary & Brogliato, "Numerical Methods for Nonsmooth
//! Dynamical Systems", 2008, §10.1), completed as follows (the paper prints K u_n for K x_n in
//! eq. 15, y_n for the free output ỹ_{n+1} in λ = Ŵ⁻¹(·), and leaves the heat rows out of
//! p_{n+1}; all three are corrected here).
//!
//! Each row r has its θ-method parameter γ_r (γ on the mechanical rows, γ_θ on the thermal ones,
//! Γ = diag γ_r); the row's smooth terms are evaluated at t_{n+γ_r} and the position update is
//! x_{n+1} = x_n + h(Γ v_{n+1} + (I − Γ) v_n). With M̂ = M + hΓC + h²ΓKΓ (eq. 15's iteration
//! matrix) one step is:
//!
//! 1. free velocity ṽ = v_n + M̂⁻¹[−h(C v_n + K x_n − f_{n+Γ}) − h²ΓK v_n] (eq. 15 with p = 0),
//!    f_{n+Γ} = Γ f(t_{n+1}) + (I − Γ) f(t_n);
//! 2. active set I = {i : g_i(u_n + h u̇_n/2) ≤ ε_g} (the predicted gap, eq. 16);
//! 3. the LCP 0 ≤ W_II λ_I + q_I ⊥ λ_I ≥ 0 with the Delassus matrix W = G M̂⁻¹H and
//!    q = Gṽ + e·y_n (eq. 17 as Moreau's projection in the metric of M̂, not componentwise),
//!    λ_i = 0 off I, solved exactly by Lemke ([`super::lcp`]);
//! 4. v_{n+1} = ṽ + M̂⁻¹Hλ (eq. 18, heat rows included), then the position update.
//!
//! λ is an impulse (N·s); λ/h is the mean contact force over the step. M̂, M̂⁻¹H and W are formed
//! once per step size (by blocks when the heat rows have no mechanical column). Without contact and thermal DOF and with γ = 1/2 the scheme is Newmark's
//! average acceleration. The mechanical energy balance ([`super::obstacle::EnergyTerms`]) and the
//! heat balance ([`super::obstacle::HeatTerms`]) are accumulated every step.

use std::time::Instant;

use super::lcp;
use super::obstacle::{
    EnergyTerms, HeatTerms, NonsmoothHistory, NonsmoothSettings, NonsmoothSystem, SparseRows,
    StepLu,
};
use crate::error::{Error, Result};

/// Marches `sys` with the Moreau–Jean θ-method from x₀, v₀ for `s.steps` steps of `s.step`.
pub fn moreau_jean(sys: &NonsmoothSystem, s: &NonsmoothSettings) -> Result<NonsmoothHistory> {
    sys.validate("moreau-jean")?;
    s.validate()?;
    let start = Instant::now();
    let (n, nm, h) = (sys.n, sys.n_mech, s.step);
    let gamma: Vec<f64> = (0..n)
        .map(|r| if r < nm { s.gamma } else { s.gamma_thermal })
        .collect();
    // M̂ = M + hΓC + h²ΓKΓ.
    let mhat: Vec<f64> = (0..n * n)
        .map(|ij| {
            let (i, j) = (ij / n, ij % n);
            sys.mass[ij]
                + h * gamma[i] * sys.damping[ij]
                + h * h * gamma[i] * gamma[j] * sys.stiffness[ij]
        })
        .collect();
    let lu = StepSolver::new(sys, &mhat)?;
    let b = Blocks::new(sys);
    let m = sys.obstacles.len();
    let columns: Vec<Vec<f64>> = sys.obstacles.iter().map(|o| o.column(n)).collect();
    let z: Vec<Vec<f64>> = columns.iter().map(|c| lu.solve(c)).collect();
    // W_ij = G_i Z_j.
    let w: Vec<f64> = (0..m * m)
        .map(|ij| sys.obstacles[ij / m].rate(&z[ij % m]))
        .collect();
    // K^uθ Z_i: the thermal load of a unit impulse's heat (the energy balance's coupling term).
    let kz: Vec<Vec<f64>> = z.iter().map(|zi| b.k_ut.mul(zi)).collect();
    let mut x = sys.x0.clone();
    let mut v = sys.v0.clone();
    let mut hist = NonsmoothHistory::new("moreau-jean", sys, s);
    let (k0, s0) = sys.mechanical_energy(&x, &v);
    let mut energy = EnergyTerms {
        kinetic: k0,
        strain: s0,
        ..EnergyTerms::default()
    };
    let thermal = nm < n;
    let mut heat = HeatTerms::default();
    hist.push(
        sys,
        s.start,
        &x,
        &v,
        &vec![0.0; m],
        &vec![false; m],
        (0.0, 0),
    );
    hist.energy.push(energy);
    if thermal {
        hist.heat.push(heat);
    }
    let mut f0 = sys.load(s.start);
    for step in 0..s.steps {
        let t1 = s.start + (step + 1) as f64 * h;
        let f1 = sys.load(t1);
        let fg: Vec<f64> = (0..n)
            .map(|r| gamma[r] * f1[r] + (1.0 - gamma[r]) * f0[r])
            .collect();
        let (dv, kut_free) = lu.free_increment(&b, (&x, &v), &fg, h, (s.gamma, s.gamma_thermal));
        let mut v1: Vec<f64> = v.iter().zip(&dv).map(|(a, b)| a + b).collect();
        // Active set from the predicted gap g(u_n + h u̇_n / 2).
        let mid: Vec<f64> = x.iter().zip(&v).map(|(a, b)| a + 0.5 * h * b).collect();
        let active: Vec<bool> = sys
            .obstacles
            .iter()
            .map(|o| o.gap_at(&mid) <= s.activation_tolerance)
            .collect();
        let idx: Vec<usize> = (0..m).filter(|&i| active[i]).collect();
        let mut lambda = vec![0.0; m];
        let mut lcp_info = (0.0, 0);
        if !idx.is_empty() {
            let k = idx.len();
            let q: Vec<f64> = idx
                .iter()
                .map(|&i| {
                    let o = &sys.obstacles[i];
                    o.rate(&v1) + o.restitution * o.rate(&v)
                })
                .collect();
            let wi: Vec<f64> = (0..k * k)
                .map(|ab| w[idx[ab / k] * m + idx[ab % k]])
                .collect();
            let sol = lcp::solve(&wi, &q).ok_or_else(|| {
                Error::Compute(format!(
                    "moreau-jean: the contact LCP of step {} (t = {t1:.6e} s) has no solution (the Delassus matrix is not a P-matrix)",
                    step + 1
                ))
            })?;
            lcp_info = (lcp::residual(&sol.lambda, &sol.w), sol.pivots as u32);
            for (a, &i) in idx.iter().enumerate() {
                lambda[i] = sol.lambda[a];
                for (vr, zr) in v1.iter_mut().zip(&z[i]) {
                    *vr += zr * sol.lambda[a];
                }
            }
        }
        let x1: Vec<f64> = (0..n)
            .map(|r| x[r] + h * (gamma[r] * v1[r] + (1.0 - gamma[r]) * v[r]))
            .collect();
        // K^uθ θ_{n+γ}: from the free step's product plus the impulses' share, or directly.
        let kut_theta_g: Vec<f64> = match &kut_free {
            Some(p) => {
                let c = s.gamma * h * s.gamma_thermal;
                (0..nm)
                    .map(|r| {
                        p[r] + c * kz
                            .iter()
                            .zip(&lambda)
                            .filter(|(_, &l)| l != 0.0)
                            .map(|(k, &l)| k[r] * l)
                            .sum::<f64>()
                    })
                    .collect()
            }
            None if thermal => {
                let theta_g: Vec<f64> = (0..n).map(|c| x[c] + s.gamma * (x1[c] - x[c])).collect();
                b.k_ut.mul(&theta_g)
            }
            None => vec![0.0; nm],
        };
        accumulate_energy(
            sys,
            &b,
            s.gamma,
            h,
            (&x, &x1),
            (&v, &v1),
            &fg,
            &kut_theta_g,
            &columns,
            &lambda,
            k0 + s0,
            &mut energy,
        );
        if thermal {
            accumulate_heat(
                sys,
                &b,
                s.gamma_thermal,
                h,
                (&x, &x1),
                &fg,
                &columns,
                &lambda,
                &mut heat,
            );
        }
        x = x1;
        v = v1;
        f0 = f1;
        hist.push(sys, t1, &x, &v, &lambda, &active, lcp_info);
        hist.energy.push(energy);
        if thermal {
            hist.heat.push(heat);
        }
        if x.iter().any(|a| !a.is_finite()) {
            return Err(Error::Compute(format!(
                "moreau-jean: the state is not finite at step {} (t = {t1:.6e} s)",
                step + 1
            )));
        }
    }
    hist.x_final = x;
    hist.v_final = v;
    hist.wall_seconds = start.elapsed().as_secs_f64();
    Ok(hist)
}

/// The Moreau–Jean iteration matrix M̂ factorised once: whole, or, when its thermal rows have
/// no mechanical column (M^θ· = 0, C^θu = 0, K^θu = 0 as in the thermoelastic model), by blocks,
/// M̂ = [[A, B], [0, D]]: D Δv_θ = r_θ, then A Δv_u = r_u − B Δv_θ (two smaller factors).
enum StepSolver {
    Whole(Box<StepLu>),
    Blocks(Box<BlockLu>),
}

/// The factors of [`StepSolver::Blocks`].
struct BlockLu {
    a: StepLu,
    d: StepLu,
    b: SparseRows,
    nm: usize,
}

impl StepSolver {
    fn new(sys: &NonsmoothSystem, mhat: &[f64]) -> Result<Self> {
        let (n, nm) = (sys.n, sys.n_mech);
        let what = "the Moreau–Jean iteration matrix M + hγC + h²γ²K";
        // Blocks when M and C have no mechanical–thermal entries and K^θu = 0.
        let cross = |a: &[f64], i: usize, j: usize| a[i * n + j] != 0.0 || a[j * n + i] != 0.0;
        let coupled = (nm..n).any(|i| {
            (0..nm).any(|j| {
                cross(&sys.mass, i, j)
                    || cross(&sys.damping, i, j)
                    || sys.stiffness[i * n + j] != 0.0
            })
        });
        if nm == n || nm == 0 || coupled {
            return Ok(StepSolver::Whole(Box::new(StepLu::new(mhat, n, what)?)));
        }
        let sub = |r: std::ops::Range<usize>| -> Vec<f64> {
            let k = r.len();
            (0..k * k)
                .map(|ij| mhat[(r.start + ij / k) * n + r.start + ij % k])
                .collect()
        };
        Ok(StepSolver::Blocks(Box::new(BlockLu {
            a: StepLu::new(&sub(0..nm), nm, &format!("{what} (mechanical rows)"))?,
            d: StepLu::new(&sub(nm..n), n - nm, &format!("{what} (heat rows)"))?,
            b: SparseRows::new(mhat, n, 0..nm, nm..n),
            nm,
        })))
    }

    /// The free velocity increment ṽ − v_n = M̂⁻¹[−h(C v_n + K x_n − f_{n+Γ}) − h²ΓK v_n] (step 1
    /// of the module doc) and, by blocks, K^uθ(θ_n + hγ v^θ_n + hγγ_θ Δṽ^θ), the thermal load at
    /// t_{n+γ} of the contact-free step.
    fn free_increment(
        &self,
        b: &Blocks,
        (x, v): (&[f64], &[f64]),
        fg: &[f64],
        h: f64,
        (gamma, gamma_t): (f64, f64),
    ) -> (Vec<f64>, Option<Vec<f64>>) {
        let n = x.len();
        match self {
            StepSolver::Whole(lu) => {
                // K x_n + hΓK v_n row block by row block: K_u(x_n + hγ v_n), K_θ(x_n + hγ_θ v_n).
                let mut ky = Vec::with_capacity(n);
                for (rows, g) in [(&b.k_uu, gamma), (&b.k_t, gamma_t)] {
                    let y: Vec<f64> = x.iter().zip(v).map(|(a, b)| a + h * g * b).collect();
                    ky.extend(rows.mul(&y));
                }
                let y: Vec<f64> = x.iter().zip(v).map(|(a, b)| a + h * gamma * b).collect();
                for (k, p) in ky.iter_mut().zip(b.k_ut.mul(&y)) {
                    *k += p;
                }
                let cv = b.c.mul(v);
                let rhs: Vec<f64> = (0..n).map(|r| -h * (cv[r] + ky[r] - fg[r])).collect();
                (lu.solve(&rhs), None)
            }
            StepSolver::Blocks(blocks) => {
                let BlockLu { a, d, nm, .. } = blocks.as_ref();
                let nm = *nm;
                // Heat rows first: D Δṽ^θ = −h(C^θθ v^θ + K^θθ(θ + hγ_θ v^θ) − f^θ).
                let y: Vec<f64> = x.iter().zip(v).map(|(a, b)| a + h * gamma_t * b).collect();
                let kt = b.k_t.mul(&y);
                let rt: Vec<f64> = (0..n - nm)
                    .map(|a| -h * (b.c.row_dot(nm + a, v) + kt[a] - fg[nm + a]))
                    .collect();
                let dvt = d.solve(&rt);
                // Then A Δṽ^u = −h(C v + K^uu(u + hγv^u) + K^uθ(θ + hγv^θ + hγγ_θΔṽ^θ) − f^u).
                let mut z: Vec<f64> = x.iter().zip(v).map(|(a, b)| a + h * gamma * b).collect();
                for (za, d) in z[nm..].iter_mut().zip(&dvt) {
                    *za += h * gamma * gamma_t * d;
                }
                let (kuu, kut) = (b.k_uu.mul(&z), b.k_ut.mul(&z));
                let ru: Vec<f64> = (0..nm)
                    .map(|r| -h * (b.c.row_dot(r, v) + kuu[r] + kut[r] - fg[r]))
                    .collect();
                let mut dv = a.solve(&ru);
                dv.extend(dvt);
                (dv, Some(kut))
            }
        }
    }

    /// M̂⁻¹ r.
    fn solve(&self, r: &[f64]) -> Vec<f64> {
        match self {
            StepSolver::Whole(lu) => lu.solve(r),
            StepSolver::Blocks(blocks) => {
                let BlockLu { a, d, b, nm } = blocks.as_ref();
                let mut x = vec![0.0; r.len()];
                let xt = d.solve(&r[*nm..]);
                x[*nm..].copy_from_slice(&xt);
                let ru: Vec<f64> = (0..*nm).map(|i| r[i] - b.row_dot(i, &x)).collect();
                x[..*nm].copy_from_slice(&a.solve(&ru));
                x
            }
        }
    }
}

/// The blocks of M, C and K the time loop multiplies by, as sparse rows.
struct Blocks {
    /// The thermal rows of K (all columns), and C.
    k_t: SparseRows,
    c: SparseRows,
    /// M^uu, C^uu, K^uu.
    m_uu: SparseRows,
    c_uu: SparseRows,
    k_uu: SparseRows,
    /// K^uθ (mechanical rows, thermal columns).
    k_ut: SparseRows,
    /// The sums of the thermal rows of C and K (1ᵀC_θ·, 1ᵀK_θ·), length n.
    c_th: Vec<f64>,
    k_th: Vec<f64>,
}

impl Blocks {
    fn new(sys: &NonsmoothSystem) -> Self {
        let (n, nm) = (sys.n, sys.n_mech);
        let column_sums = |a: &[f64]| -> Vec<f64> {
            (0..n)
                .map(|c| (nm..n).map(|r| sys.heat_weight(r) * a[r * n + c]).sum())
                .collect()
        };
        Blocks {
            k_t: SparseRows::new(&sys.stiffness, n, nm..n, 0..n),
            c: SparseRows::new(&sys.damping, n, 0..n, 0..n),
            m_uu: SparseRows::new(&sys.mass, n, 0..nm, 0..nm),
            c_uu: SparseRows::new(&sys.damping, n, 0..nm, 0..nm),
            k_uu: SparseRows::new(&sys.stiffness, n, 0..nm, 0..nm),
            k_ut: SparseRows::new(&sys.stiffness, n, 0..nm, nm..n),
            c_th: column_sums(&sys.damping),
            k_th: column_sums(&sys.stiffness),
        }
    }
}

/// Adds one step to the mechanical energy balance (module doc of [`super::obstacle`]):
/// with v_γ = γv_{n+1} + (1−γ)v_n over the mechanical rows, the step's equation times v_γᵀ gives
/// ΔE + (γ − ½)(‖Δv‖²_M + ‖Δu‖²_K) + h v_γᵀC v_γ = h v_γᵀ(f_γ − K^uθ θ_γ) + v_γᵀH^u λ.
#[allow(clippy::too_many_arguments)]
fn accumulate_energy(
    sys: &NonsmoothSystem,
    b: &Blocks,
    gamma: f64,
    h: f64,
    (x0, x1): (&[f64], &[f64]),
    (v0, v1): (&[f64], &[f64]),
    fg: &[f64],
    kut_theta_g: &[f64],
    columns: &[Vec<f64>],
    lambda: &[f64],
    e0: f64,
    e: &mut EnergyTerms,
) {
    let nm = sys.n_mech;
    let vg: Vec<f64> = (0..nm)
        .map(|r| gamma * v1[r] + (1.0 - gamma) * v0[r])
        .collect();
    let dv: Vec<f64> = (0..nm).map(|r| v1[r] - v0[r]).collect();
    let du: Vec<f64> = (0..nm).map(|r| x1[r] - x0[r]).collect();
    let (kin, strain) = (0.5 * b.m_uu.quad(v1), 0.5 * b.k_uu.quad(x1));
    e.damping += h * b.c_uu.quad(&vg);
    if gamma != 0.5 {
        e.numerical += (gamma - 0.5) * (b.m_uu.quad(&dv) + b.k_uu.quad(&du));
    }
    e.external += h * (0..nm).map(|r| vg[r] * fg[r]).sum::<f64>();
    let coupling: f64 = (0..nm).map(|r| vg[r] * kut_theta_g[r]).sum();
    e.thermal -= h * coupling;
    e.contact += columns
        .iter()
        .zip(lambda)
        .map(|(col, &l)| l * (0..nm).map(|r| vg[r] * col[r]).sum::<f64>())
        .sum::<f64>();
    e.kinetic = kin;
    e.strain = strain;
    e.residual = kin + strain - e0 + e.damping + e.numerical - e.external - e.thermal - e.contact;
}

/// Adds one step to the heat balance: summing the thermal rows with the weights w
/// ([`NonsmoothSystem::heat_weights`]), wᵀC^θθΔθ = h wᵀ(f^θ_{n+γ_θ} − K_θ x_{n+γ_θ}) + wᵀH^θλ.
#[allow(clippy::too_many_arguments)]
fn accumulate_heat(
    sys: &NonsmoothSystem,
    b: &Blocks,
    gamma_thermal: f64,
    h: f64,
    (x0, x1): (&[f64], &[f64]),
    fg: &[f64],
    columns: &[Vec<f64>],
    lambda: &[f64],
    q: &mut HeatTerms,
) {
    let (n, nm) = (sys.n, sys.n_mech);
    for c in 0..n {
        let dx = x1[c] - x0[c];
        q.stored += b.c_th[c] * dx;
        q.exchanged -= h * b.k_th[c] * (x0[c] + gamma_thermal * dx);
    }
    for r in nm..n {
        let w = sys.heat_weight(r);
        q.exchanged += w * h * fg[r];
        q.frictional += w * columns
            .iter()
            .zip(lambda)
            .map(|(col, &l)| col[r] * l)
            .sum::<f64>();
    }
    q.residual = q.stored - q.exchanged - q.frictional;
}
