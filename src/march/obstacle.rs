//! Rigid obstacles with unilateral (Signorini) contact and the model the nonsmooth schemes march
//! ([`super::moreau_jean`], [`super::carpenter`]); after Thorin, Guérin, Legrand, Thouverez &
//! Almeida, "Nonsmooth thermoelastic simulations of blade–casing contact interactions", ASME
//! GT2018-75959 (2018), eqs (1)–(7).
//!
//! The generalised coordinates are x = [u; θ] (eq. 7): `n_mech` mechanical DOF u (m) followed by
//! `n - n_mech` thermal DOF θ (K, the rise above the reference temperature). The model is
//!
//! M ẍ + C ẋ + K x = f(t) + H λ,   M = [[M^uu, 0], [0, 0]],  C = [[C^uu, 0], [0, C^θθ]],
//! K = [[K^uu, K^uθ], [0, K^θθ]]  (eqs 5–6),
//!
//! with one column of H per obstacle. Obstacle i has the gap g_i = g0_i + Σ_j w_ij u_j ≥ 0
//! (G = ∇g, one row per obstacle), the contact force λ_i ≥ 0 acting along Gᵀ plus the Coulomb
//! friction μ_i λ_i along a fixed sliding direction t_i (eq. 3 with a sliding direction that never
//! reverses), and the frictional heat flow α_i λ_i into the thermal DOF it names; so
//! H_i = [G_iᵀ + μ_i t_i; α_i P_i]. Signorini 0 ≤ g ⊥ λ ≥ 0 (eq. 2) and the Newton impact law
//! ẏ⁺ = −e ẏ⁻ (y = g) close the problem.

use faer::linalg::solvers::Solve;

use crate::error::{Error, Result};

use super::signal::Harmonic;

/// A rigid obstacle acting on a weighted combination of DOF.
#[derive(Clone, Debug, PartialEq)]
pub struct Obstacle {
    /// Name (results).
    pub name: String,
    /// Gap weights (DOF index, w): g = `gap` + Σ w·u (m); the DOF must be mechanical.
    pub normal: Vec<(usize, f64)>,
    /// Initial gap g0 (m): the gap at u = 0.
    pub gap: f64,
    /// Newton restitution coefficient e ∈ [0, 1].
    pub restitution: f64,
    /// Friction coefficient μ ≥ 0 (0: frictionless).
    pub mu: f64,
    /// Direction t of the friction force per unit μλ (DOF index, weight), a fixed sliding
    /// direction; empty without friction.
    pub tangential: Vec<(usize, f64)>,
    /// Heating coefficient α (W/N = m/s): the frictional heat flow α·λ (W) enters the thermal
    /// DOF below with their weights.
    pub heating: f64,
    /// Thermal DOF (index ≥ `n_mech`) and the share of α·λ each receives.
    pub heated: Vec<(usize, f64)>,
}

impl Obstacle {
    /// A frictionless, non-heating obstacle g = `gap` + Σ w·u with restitution `e`.
    pub fn new(name: &str, normal: Vec<(usize, f64)>, gap: f64, e: f64) -> Self {
        Obstacle {
            name: name.to_string(),
            normal,
            gap,
            restitution: e,
            mu: 0.0,
            tangential: Vec::new(),
            heating: 0.0,
            heated: Vec::new(),
        }
    }

    /// g(u) = g0 + G u (m).
    pub fn gap_at(&self, x: &[f64]) -> f64 {
        self.gap + self.rate(x)
    }

    /// G x (the gap's linear part; y = G v for a velocity v).
    pub fn rate(&self, x: &[f64]) -> f64 {
        self.normal.iter().map(|&(j, w)| w * x[j]).sum()
    }

    /// The column H_i of the generalised contact matrix (length n): Gᵀ + μt on the mechanical
    /// rows, α·share on the heated thermal rows.
    pub fn column(&self, n: usize) -> Vec<f64> {
        let mut h = vec![0.0; n];
        for &(j, w) in &self.normal {
            h[j] += w;
        }
        for &(j, w) in &self.tangential {
            h[j] += self.mu * w;
        }
        for &(j, w) in &self.heated {
            h[j] += self.heating * w;
        }
        h
    }
}

/// The model marched by the nonsmooth schemes (module doc): dense row-major n × n matrices.
#[derive(Clone, Debug)]
pub struct NonsmoothSystem {
    /// Number of DOF n.
    pub n: usize,
    /// Mechanical DOF: rows 0..n_mech are u, the rest θ.
    pub n_mech: usize,
    /// M (kg on the mechanical block, zero thermal rows and columns).
    pub mass: Vec<f64>,
    /// C (N·s/m on the mechanical block, C^θθ in J/K on the thermal block).
    pub damping: Vec<f64>,
    /// K: K^uu (N/m), K^uθ (N/K), K^θθ (W/K); the block K^θu is zero.
    pub stiffness: Vec<f64>,
    /// External load per DOF (N on u rows, W on θ rows) at the frequency `omega`.
    pub force: Vec<Harmonic>,
    /// Frequency ω (rad/s) of the load's harmonic part.
    pub omega: f64,
    /// The obstacles.
    pub obstacles: Vec<Obstacle>,
    /// Name of each DOF.
    pub dof_names: Vec<String>,
    /// Initial state x₀ (m; K).
    pub x0: Vec<f64>,
    /// Initial velocity v₀ (m/s; K/s, the latter without effect on the Moreau–Jean solution).
    pub v0: Vec<f64>,
    /// The weight w_r of each thermal row in the heat balance ([`HeatTerms`]: wᵀ times the heat
    /// rows), one per row n_mech..n; empty: 1 each (rows that are nodal temperatures). A model
    /// projected on x = T x_r has rows Tᵀ(·), so w solves T_θ w = 1 and the balance stays the
    /// physical one ([`super::reduced::project`]).
    pub heat_weights: Vec<f64>,
}

impl NonsmoothSystem {
    /// A mechanical model (no thermal DOF) at rest with no load and no obstacle.
    pub fn mechanical(mass: Vec<f64>, damping: Vec<f64>, stiffness: Vec<f64>) -> Self {
        let n = (mass.len() as f64).sqrt().round() as usize;
        NonsmoothSystem {
            n,
            n_mech: n,
            mass,
            damping,
            stiffness,
            force: vec![Harmonic::default(); n],
            omega: 0.0,
            obstacles: Vec::new(),
            dof_names: (0..n).map(|i| format!("dof {i}")).collect(),
            x0: vec![0.0; n],
            v0: vec![0.0; n],
            heat_weights: Vec::new(),
        }
    }

    /// The weight of row `r` (≥ n_mech) in the heat balance (`heat_weights`, else 1).
    pub fn heat_weight(&self, r: usize) -> f64 {
        self.heat_weights
            .get(r - self.n_mech)
            .copied()
            .unwrap_or(1.0)
    }

    /// The load f(t) (N; W).
    pub fn load(&self, t: f64) -> Vec<f64> {
        self.force.iter().map(|f| f.at(self.omega, t)).collect()
    }

    /// The gaps g(x) of every obstacle (m).
    pub fn gaps(&self, x: &[f64]) -> Vec<f64> {
        self.obstacles.iter().map(|o| o.gap_at(x)).collect()
    }

    /// The normal rates y = G v of every obstacle (m/s).
    pub fn rates(&self, v: &[f64]) -> Vec<f64> {
        self.obstacles.iter().map(|o| o.rate(v)).collect()
    }

    /// Mechanical energy ½vᵀM^uu v + ½uᵀK^uu u (J).
    pub fn mechanical_energy(&self, x: &[f64], v: &[f64]) -> (f64, f64) {
        let (n, nm) = (self.n, self.n_mech);
        let quad = |a: &[f64], z: &[f64]| -> f64 {
            (0..nm)
                .map(|i| z[i] * (0..nm).map(|j| a[i * n + j] * z[j]).sum::<f64>())
                .sum()
        };
        (0.5 * quad(&self.mass, v), 0.5 * quad(&self.stiffness, x))
    }

    /// Checks sizes, finiteness and the obstacles' DOF; `what` names the model in errors.
    pub fn validate(&self, what: &str) -> Result<()> {
        let (n, nm) = (self.n, self.n_mech);
        let bad = |m: String| Err(Error::input(format!("{what}: {m}")));
        if nm > n {
            return bad(format!("{nm} mechanical DOF of {n}"));
        }
        for (name, a) in [
            ("mass", &self.mass),
            ("damping", &self.damping),
            ("stiffness", &self.stiffness),
        ] {
            if a.len() != n * n {
                return bad(format!(
                    "the {name} matrix has {} entries, not {n}²",
                    a.len()
                ));
            }
            if a.iter().any(|v| !v.is_finite()) {
                return bad(format!("the {name} matrix has a non-finite entry"));
            }
        }
        if self.force.len() != n || self.x0.len() != n || self.v0.len() != n {
            return bad("the load or the initial state does not have one entry per DOF".into());
        }
        if !self.heat_weights.is_empty() && self.heat_weights.len() != n - nm {
            return bad(format!(
                "{} heat-balance weights for {} thermal rows",
                self.heat_weights.len(),
                n - nm
            ));
        }
        for o in &self.obstacles {
            let key = format!("obstacle '{}'", o.name);
            if o.normal.is_empty() {
                return bad(format!("{key}: no DOF in the gap"));
            }
            if o.normal.iter().chain(&o.tangential).any(|&(j, _)| j >= nm) {
                return bad(format!("{key}: a gap or friction DOF is not mechanical"));
            }
            if o.heated.iter().any(|&(j, _)| j < nm || j >= n) {
                return bad(format!("{key}: a heated DOF is not thermal"));
            }
            if !(0.0..=1.0).contains(&o.restitution) {
                return bad(format!(
                    "{key}: restitution {} outside [0, 1]",
                    o.restitution
                ));
            }
            if !(o.mu >= 0.0 && o.heating >= 0.0 && o.gap.is_finite()) {
                return bad(format!("{key}: mu and heating must be ≥ 0, the gap finite"));
            }
        }
        Ok(())
    }
}

/// The settings shared by the nonsmooth schemes.
#[derive(Clone, Debug, PartialEq)]
pub struct NonsmoothSettings {
    /// Time step h (s), > 0.
    pub step: f64,
    /// Number of steps.
    pub steps: usize,
    /// Start time t₀ (s); t_n = t₀ + n h.
    pub start: f64,
    /// θ-method parameter γ ∈ [1/2, 1] of the mechanical rows (Moreau–Jean).
    pub gamma: f64,
    /// θ-method parameter γ_θ ∈ [1/2, 1] of the thermal rows (Moreau–Jean).
    pub gamma_thermal: f64,
    /// Activation tolerance ε_g (m): obstacle i is active when the predicted gap
    /// g(u_n + h u̇_n/2) ≤ ε_g (Moreau–Jean; default 0).
    pub activation_tolerance: f64,
    /// DOF recorded every step (`None`: all).
    pub record: Option<Vec<usize>>,
}

impl Default for NonsmoothSettings {
    fn default() -> Self {
        NonsmoothSettings {
            step: 1e-5,
            steps: 100,
            start: 0.0,
            gamma: 0.5,
            gamma_thermal: 0.5,
            activation_tolerance: 0.0,
            record: None,
        }
    }
}

impl NonsmoothSettings {
    /// Checks h > 0 and γ, γ_θ ∈ [1/2, 1], naming the case-file keys in the message.
    pub fn validate(&self) -> Result<()> {
        if !(self.step > 0.0 && self.step.is_finite()) {
            return Err(Error::input(format!(
                "key 'march.time_step_s': the time step must be > 0, got {}",
                self.step
            )));
        }
        for (key, g) in [
            ("march.gamma", self.gamma),
            ("march.gamma_thermal", self.gamma_thermal),
        ] {
            if !(0.5..=1.0).contains(&g) {
                return Err(Error::input(format!(
                    "key '{key}': γ = {g} is outside [1/2, 1] (the θ-method is unconditionally stable only there)"
                )));
            }
        }
        Ok(())
    }
}

/// Cumulative terms of the discrete mechanical energy balance of the Moreau–Jean θ-method (J):
/// kinetic + strain − initial + numerical + damping = external + thermal + contact, closed to
/// round-off every step (`residual`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct EnergyTerms {
    /// ½vᵀM v.
    pub kinetic: f64,
    /// ½uᵀK^uu u.
    pub strain: f64,
    /// Σ h v_{n+γ}ᵀ C^uu v_{n+γ}: viscous dissipation.
    pub damping: f64,
    /// Σ (γ − ½)(‖Δv‖²_M + ‖Δu‖²_K): the θ-method's numerical dissipation (0 for γ = 1/2).
    pub numerical: f64,
    /// Σ h v_{n+γ}ᵀ f^u_{n+γ}: work of the external load.
    pub external: f64,
    /// −Σ h v_{n+γ}ᵀ K^uθ θ_{n+γ}: work of the thermal expansion load.
    pub thermal: f64,
    /// Σ v_{n+γ}ᵀ H^u λ_{n+1}: work of the contact impulses (≤ 0: impact loss and friction).
    pub contact: f64,
    /// kinetic + strain − E₀ + damping + numerical − external − thermal − contact.
    pub residual: f64,
}

/// Cumulative heat balance (J), the heat rows summed with the weights
/// [`NonsmoothSystem::heat_weights`]: stored = external + conducted + frictional, `residual` the
/// difference.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct HeatTerms {
    /// 1ᵀC^θθ(θ − θ₀): heat stored.
    pub stored: f64,
    /// Σ h 1ᵀ(f^θ_{n+γ} − K^θθ θ_{n+γ}): external heat flow minus the heat conducted out
    /// (through the prescribed temperatures).
    pub exchanged: f64,
    /// Σ α λ: frictional heating.
    pub frictional: f64,
    /// stored − exchanged − frictional.
    pub residual: f64,
}

/// The record of a nonsmooth march (index 0 is the initial state).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct NonsmoothHistory {
    /// The scheme (`moreau-jean`, `carpenter`).
    pub scheme: &'static str,
    /// Recorded DOF.
    pub dofs: Vec<usize>,
    /// Time t_n (s), \[T\].
    pub time: Vec<f64>,
    /// x of the recorded DOF, [T, R] (m; K).
    pub x: Vec<f64>,
    /// v of the recorded DOF, [T, R] (m/s; K/s).
    pub v: Vec<f64>,
    /// Contact impulse of each obstacle over the step ending at t_n, [T, m] (N·s); the mean
    /// force over the step is impulse/h.
    pub impulse: Vec<f64>,
    /// Gap g(u_n) of each obstacle, [T, m] (m).
    pub gap: Vec<f64>,
    /// Normal rate y_n = G u̇_n, [T, m] (m/s).
    pub rate: Vec<f64>,
    /// Whether obstacle i was in the active set of the step ending at t_n, [T, m].
    pub active: Vec<bool>,
    /// Complementarity residual of the step's LCP, \[T\].
    pub lcp_residual: Vec<f64>,
    /// Lemke pivots of the step's LCP, \[T\].
    pub pivots: Vec<u32>,
    /// Cumulative energy terms, \[T\] (Moreau–Jean; empty for Carpenter).
    pub energy: Vec<EnergyTerms>,
    /// Cumulative heat terms, \[T\] (empty without thermal DOF).
    pub heat: Vec<HeatTerms>,
    /// The final state x_N (all DOF).
    pub x_final: Vec<f64>,
    /// The final velocity v_N (all DOF).
    pub v_final: Vec<f64>,
    /// Wall time of the loop (s).
    pub wall_seconds: f64,
}

impl NonsmoothHistory {
    /// Number of records T.
    pub fn len(&self) -> usize {
        self.time.len()
    }

    /// Whether nothing was recorded.
    pub fn is_empty(&self) -> bool {
        self.time.is_empty()
    }

    /// x of the k-th recorded DOF over time.
    pub fn series(&self, k: usize) -> Vec<f64> {
        let r = self.dofs.len();
        (0..self.len()).map(|t| self.x[t * r + k]).collect()
    }

    /// The impulse of obstacle i over time (N·s).
    pub fn impulses(&self, i: usize) -> Vec<f64> {
        let m = self.impulse.len() / self.len().max(1);
        (0..self.len()).map(|t| self.impulse[t * m + i]).collect()
    }

    /// The largest penetration max(0, −g) over obstacles and time (m).
    pub fn max_penetration(&self) -> f64 {
        self.gap.iter().fold(0.0, |a, &g| a.max(-g))
    }

    pub(crate) fn new(scheme: &'static str, sys: &NonsmoothSystem, s: &NonsmoothSettings) -> Self {
        NonsmoothHistory {
            scheme,
            dofs: s.record.clone().unwrap_or_else(|| (0..sys.n).collect()),
            ..NonsmoothHistory::default()
        }
    }

    /// Appends the state at `t`.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn push(
        &mut self,
        sys: &NonsmoothSystem,
        t: f64,
        x: &[f64],
        v: &[f64],
        impulse: &[f64],
        active: &[bool],
        lcp: (f64, u32),
    ) {
        self.time.push(t);
        self.x.extend(self.dofs.iter().map(|&d| x[d]));
        self.v.extend(self.dofs.iter().map(|&d| v[d]));
        self.impulse.extend_from_slice(impulse);
        self.gap.extend(sys.gaps(x));
        self.rate.extend(sys.rates(v));
        self.active.extend_from_slice(active);
        self.lcp_residual.push(lcp.0);
        self.pivots.push(lcp.1);
    }
}

/// LU of a square row-major matrix, reused for many right-hand sides: dense (faer's partial
/// pivoting) for small or dense matrices, sparse (faer's supernodal LU with a fill-reducing
/// ordering) when n ≥ [`SPARSE_FROM`] and at most a fifth of the entries are non-zero, as for FE
/// models.
pub enum StepLu {
    /// Dense partial-pivoting LU of an n × n matrix.
    Dense {
        /// The factors.
        lu: faer::linalg::solvers::PartialPivLu<f64>,
        /// The order n.
        n: usize,
    },
    /// Sparse LU of an n × n matrix.
    Sparse {
        /// The factors.
        lu: faer::sparse::linalg::solvers::Lu<usize, f64>,
        /// The order n.
        n: usize,
    },
}

/// The order from which a sparse matrix is factorised sparse.
pub const SPARSE_FROM: usize = 200;

impl StepLu {
    /// Factorises `a` (row-major n × n); an error naming `what` when it is singular.
    pub fn new(a: &[f64], n: usize, what: &str) -> Result<Self> {
        let nnz = a.iter().filter(|v| **v != 0.0).count();
        if n >= SPARSE_FROM && 5 * nnz <= n * n {
            let triplets: Vec<faer::sparse::Triplet<usize, usize, f64>> = a
                .iter()
                .enumerate()
                .filter(|(_, v)| **v != 0.0)
                .map(|(ij, &v)| faer::sparse::Triplet::new(ij / n, ij % n, v))
                .collect();
            let m = faer::sparse::SparseColMat::try_new_from_triplets(n, n, &triplets)
                .map_err(|e| Error::Compute(format!("{what}: {e:?}")))?;
            let lu = m
                .sp_lu()
                .map_err(|e| Error::Compute(format!("{what} cannot be factorised: {e:?}")))?;
            return Ok(StepLu::Sparse { lu, n });
        }
        let m = faer::Mat::from_fn(n, n, |i, j| a[i * n + j]);
        let lu = m.partial_piv_lu();
        let u = lu.U();
        let (lo, hi) = (0..n)
            .map(|i| u[(i, i)].abs())
            .fold((f64::INFINITY, 0.0_f64), |(lo, hi), d| {
                (lo.min(d), hi.max(d))
            });
        if n > 0 && (lo.is_nan() || lo <= 1e-15 * hi) {
            return Err(Error::Compute(format!(
                "{what} is singular (pivot ratio {:.1e})",
                lo / hi
            )));
        }
        Ok(StepLu::Dense { lu, n })
    }

    /// A⁻¹ b.
    pub fn solve(&self, b: &[f64]) -> Vec<f64> {
        let n = match self {
            StepLu::Dense { n, .. } | StepLu::Sparse { n, .. } => *n,
        };
        let mut x = faer::Col::from_fn(n, |i| b[i]);
        match self {
            StepLu::Dense { lu, .. } => lu.solve_in_place(x.as_mut()),
            StepLu::Sparse { lu, .. } => lu.solve_in_place(x.as_mut()),
        }
        (0..n).map(|i| x[i]).collect()
    }
}

/// The non-zero entries of a block of a row-major matrix, row by row (CSR), for the products of
/// the time loop: a FE model's matrices hold a few per cent of non-zeros.
pub struct SparseRows {
    ptr: Vec<usize>,
    col: Vec<usize>,
    val: Vec<f64>,
}

impl SparseRows {
    /// Rows `rows` and columns `cols` of the row-major matrix `a` with `n` columns; column
    /// indices are kept global (products take full-length vectors).
    pub fn new(
        a: &[f64],
        n: usize,
        rows: std::ops::Range<usize>,
        cols: std::ops::Range<usize>,
    ) -> Self {
        let mut ptr = vec![0];
        let (mut col, mut val) = (Vec::new(), Vec::new());
        for r in rows {
            for c in cols.clone() {
                let v = a[r * n + c];
                if v != 0.0 {
                    col.push(c);
                    val.push(v);
                }
            }
            ptr.push(col.len());
        }
        SparseRows { ptr, col, val }
    }

    /// (A x)_r of row r (local index). A row whose columns are consecutive (a dense block, as
    /// in projected models) is a dot product of two slices; either way four partial sums break
    /// the chain of dependent additions.
    pub fn row_dot(&self, r: usize, x: &[f64]) -> f64 {
        let (a, b) = (self.ptr[r], self.ptr[r + 1]);
        if a == b {
            return 0.0;
        }
        let (cols, vals) = (&self.col[a..b], &self.val[a..b]);
        let first = cols[0];
        if cols[b - a - 1] - first == b - a - 1 {
            return super::dense::dot(vals, &x[first..first + (b - a)]);
        }
        let mut acc = [0.0; 4];
        let (c4, v4) = (cols.chunks_exact(4), vals.chunks_exact(4));
        let (cr, vr) = (c4.remainder(), v4.remainder());
        for (c, v) in c4.zip(v4) {
            for l in 0..4 {
                acc[l] += v[l] * x[c[l]];
            }
        }
        let tail: f64 = cr.iter().zip(vr).map(|(&c, v)| v * x[c]).sum();
        (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
    }

    /// A x over the block's rows.
    pub fn mul(&self, x: &[f64]) -> Vec<f64> {
        (0..self.ptr.len() - 1)
            .map(|r| self.row_dot(r, x))
            .collect()
    }

    /// zᵀ A z for a square block whose rows start at 0.
    pub fn quad(&self, z: &[f64]) -> f64 {
        (0..self.ptr.len() - 1)
            .map(|r| z[r] * self.row_dot(r, z))
            .sum()
    }
}

/// y = A x for row-major A with `rows` rows and x.len() columns.
pub(crate) fn mul(a: &[f64], x: &[f64]) -> Vec<f64> {
    let n = x.len();
    a.chunks_exact(n)
        .map(|row| row.iter().zip(x).map(|(a, b)| a * b).sum())
        .collect()
}
