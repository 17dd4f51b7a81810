//! The system the march integrates: M q̈ + C q̇ + K q = f_e(t) + f_c(q, t) (Gastaldi & Berruti 2018
//! eq. 1), with dense M, C, K (row-major), a first-harmonic external force per DOF and the friction
//! elements of [`super::element`] (whose prescribed parts carry platform motions, eqs 2–4).

use super::dense;
use super::element::Element;
use super::law::ContactState;
use super::signal::Harmonic;
use crate::error::{Error, Result};

/// How the march starts.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum InitialCondition {
    /// q = q̇ = 0, sliders at zero (a forced oscillator started from rest).
    Rest,
    /// Static equilibrium (K + K_c) q = f_e(0) + r_c at t = 0, found by the quasi-static state
    /// iteration from sliders at zero; q̇ = 0 (the damper settled under the centrifugal load).
    Static,
}

/// A time-marching model.
#[derive(Clone, Debug)]
pub struct MarchSystem {
    /// Number of DOF n.
    pub n: usize,
    /// Mass matrix M (kg, row-major n×n); all zero for a quasi-static-only model.
    pub mass: Vec<f64>,
    /// Viscous damping matrix C (N·s/m, row-major n×n).
    pub damping: Vec<f64>,
    /// Structural stiffness K (N/m, row-major n×n).
    pub stiffness: Vec<f64>,
    /// External force f_e(t) per DOF (N).
    pub force: Vec<Harmonic>,
    /// The viscous force of C against prescribed velocities (e.g. a dashpot to a moving platform,
    /// −c ṗ(t) g) per DOF (N), empty for none: part of the dynamic equation with C q̇, and like C
    /// absent from the quasi-static one (eq. 10).
    pub damping_force: Vec<Harmonic>,
    /// Friction contact elements.
    pub elements: Vec<Element>,
    /// A name per DOF (results, messages).
    pub dof_names: Vec<String>,
    /// How the march starts.
    pub initial: InitialCondition,
    /// Displacement scale (m) the corrector tolerance is relative to.
    pub displacement_scale: f64,
}

impl MarchSystem {
    /// Checks sizes, finiteness and element DOF indices; `what` names the model in messages.
    pub fn validate(&self, what: &str) -> Result<()> {
        let n = self.n;
        for (name, m) in [
            ("mass", &self.mass),
            ("damping", &self.damping),
            ("stiffness", &self.stiffness),
        ] {
            if m.len() != n * n {
                return Err(Error::input(format!(
                    "{what}: the {name} matrix has {} entries, expected {n}×{n}",
                    m.len()
                )));
            }
            if m.iter().any(|x| !x.is_finite()) {
                return Err(Error::input(format!(
                    "{what}: the {name} matrix has a non-finite entry"
                )));
            }
        }
        if !(self.damping_force.is_empty() || self.damping_force.len() == n) {
            return Err(Error::input(format!(
                "{what}: {} damping forces for {n} DOF",
                self.damping_force.len()
            )));
        }
        if self.force.len() != n || self.dof_names.len() != n {
            return Err(Error::input(format!(
                "{what}: {} forces and {} DOF names for {n} DOF",
                self.force.len(),
                self.dof_names.len()
            )));
        }
        for e in &self.elements {
            let dirs = std::iter::once(&e.tangential).chain(e.normal.as_ref());
            for d in dirs {
                if let Some(&(i, _)) = d.weights.iter().find(|(i, _)| *i >= n) {
                    return Err(Error::input(format!(
                        "{what}: element '{}' uses DOF {i}, but the model has {n} DOF (0..{})",
                        e.name,
                        n.saturating_sub(1)
                    )));
                }
            }
        }
        if !(self.displacement_scale.is_finite() && self.displacement_scale > 0.0) {
            return Err(Error::input(format!(
                "{what}: displacement scale {} must be > 0",
                self.displacement_scale
            )));
        }
        Ok(())
    }

    /// f_e(t) (N) into `f`.
    pub fn external_force(&self, omega: f64, t: f64, f: &mut [f64]) {
        for (fi, h) in f.iter_mut().zip(&self.force) {
            *fi = h.at(omega, t);
        }
    }

    /// f_e(t) plus the damping force against prescribed velocities (N) into `f`: the force side of
    /// the dynamic equation M q̈ + C q̇ + K q = f_e + f_d + f_c.
    pub fn dynamic_force(&self, omega: f64, t: f64, f: &mut [f64]) {
        self.external_force(omega, t, f);
        for (fi, h) in f.iter_mut().zip(&self.damping_force) {
            *fi += h.at(omega, t);
        }
    }

    /// K + K_c(states) (row-major) and r_c(states, sliders, t): the system's linear piece
    /// f_c = −K_c q + r_c in the given contact states (paper eq. 7).
    pub fn linear_piece(
        &self,
        states: &[ContactState],
        sliders: &[f64],
        omega: f64,
        t: f64,
        k: &mut [f64],
        r: &mut [f64],
    ) {
        k.copy_from_slice(&self.stiffness);
        r.iter_mut().for_each(|x| *x = 0.0);
        for ((e, &s), &w) in self.elements.iter().zip(states).zip(sliders) {
            e.add_linear_piece(s, w, omega, t, k, r);
        }
    }

    /// K + K_c(states) alone (row-major).
    pub fn effective_stiffness(&self, states: &[ContactState]) -> Vec<f64> {
        let mut k = self.stiffness.clone();
        for (e, &s) in self.elements.iter().zip(states) {
            e.add_stiffness(s, &mut k, self.n);
        }
        k
    }

    /// Whether M is symmetric positive definite (needed by the dynamic schemes).
    pub fn mass_is_positive_definite(&self) -> bool {
        let n = self.n;
        let m = faer::Mat::from_fn(n, n, |i, j| {
            0.5 * (self.mass[i * n + j] + self.mass[j * n + i])
        });
        n > 0 && m.llt(faer::Side::Lower).is_ok()
    }

    /// Shortest natural period 𝕋 (s) of the effective system in `states` (paper eq. 8, with the
    /// structural K_D added as the paper says for a flexible body): 𝕋 = 2π/√ρ(M⁻¹(K + K_c)).
    /// `None` when K + K_c vanishes (no period limit) or M is singular.
    pub fn shortest_period(&self, states: &[ContactState]) -> Option<f64> {
        let n = self.n;
        let minv = dense::inverse(&self.mass, n)?;
        let k = self.effective_stiffness(states);
        let rho = dense::spectral_radius(&dense::matmul(&minv, &k, n), n)?;
        (rho > 0.0).then(|| 2.0 * std::f64::consts::PI / rho.sqrt())
    }

    /// The model on its modes φ_j, j < `m` (the columns of `modes`, row-major n × n, as
    /// [`dense::generalized_symmetric_eigen`] returns them; Φᵀ M Φ = I for those): q = Φ_m η,
    /// with Φ_mᵀ (M, C, K) Φ_m, the forces Φ_mᵀ f_e and Φ_mᵀ f_d, every element direction's weights
    /// g Φ_m (dense over the m modal coordinates; the prescribed parts unchanged) and the
    /// coordinates named `mode 1` … `mode m`. The modal march's η maps back to the model's
    /// coordinates by Φ_m η. Errors when `modes` is not n × n or `m` is 0 or above n.
    pub fn on_modes(&self, modes: &[f64], m: usize) -> Result<MarchSystem> {
        let n = self.n;
        if modes.len() != n * n || m == 0 || m > n {
            return Err(Error::input(format!(
                "march model on modes: {} mode-shape entries for {n} DOF (n × n expected) and {m} modes (1 to {n})",
                modes.len()
            )));
        }
        let shapes: Vec<Vec<f64>> = (0..m)
            .map(|j| (0..n).map(|i| modes[i * n + j]).collect())
            .collect();
        let mut out = self.clone();
        out.n = m;
        out.mass = project_matrix(&self.mass, &shapes);
        out.damping = project_matrix(&self.damping, &shapes);
        out.stiffness = project_matrix(&self.stiffness, &shapes);
        out.force = project_forces(&self.force, &shapes);
        out.damping_force = project_forces(&self.damping_force, &shapes);
        out.dof_names = (1..=m).map(|j| format!("mode {j}")).collect();
        for e in &mut out.elements {
            e.tangential.weights = project_weights(&e.tangential.weights, &shapes);
            if let Some(d) = e.normal.as_mut() {
                d.weights = project_weights(&d.weights, &shapes);
            }
        }
        Ok(out)
    }

    /// All elements in stick: the stiffest state (paper §4.2).
    pub fn stick_states(&self) -> Vec<ContactState> {
        vec![ContactState::Stick; self.elements.len()]
    }

    /// A displacement scale: the largest prescribed motion bound and the static response to the
    /// force bounds in full stick, whichever is larger (1 if both vanish).
    pub fn default_displacement_scale(&self) -> f64 {
        let prescribed = self
            .elements
            .iter()
            .flat_map(|e| std::iter::once(&e.tangential).chain(e.normal.as_ref()))
            .map(|d| d.prescribed.bound())
            .fold(0.0, f64::max);
        let k = self.effective_stiffness(&self.stick_states());
        let f: Vec<f64> = self.force.iter().map(Harmonic::bound).collect();
        let static_resp = dense::inverse(&k, self.n)
            .map(|kinv| {
                let mut q = vec![0.0; self.n];
                dense::matvec(&kinv, &f, &mut q);
                dense::norm_inf(&q)
            })
            .unwrap_or(0.0);
        let s = prescribed.max(static_resp);
        if s > 0.0 && s.is_finite() {
            s
        } else {
            1.0
        }
    }
}

/// Φᵀ A Φ (row-major m × m) of the row-major n × n `a` for the m mode shapes `shapes` (each of
/// length n).
fn project_matrix(a: &[f64], shapes: &[Vec<f64>]) -> Vec<f64> {
    let (m, n) = (shapes.len(), shapes.first().map_or(0, Vec::len));
    let mut out = vec![0.0; m * m];
    let mut a_phi = vec![0.0; n];
    for (p, shape_p) in shapes.iter().enumerate() {
        dense::matvec(a, shape_p, &mut a_phi);
        for (q, shape_q) in shapes.iter().enumerate() {
            out[q * m + p] = dense::dot(shape_q, &a_phi);
        }
    }
    out
}

/// Φᵀ f of a per-DOF harmonic force (empty stays empty).
fn project_forces(f: &[Harmonic], shapes: &[Vec<f64>]) -> Vec<Harmonic> {
    if f.is_empty() {
        return Vec::new();
    }
    let sum = |shape: &[f64], part: fn(&Harmonic) -> f64| -> f64 {
        shape.iter().zip(f).map(|(p, h)| p * part(h)).sum()
    };
    shapes
        .iter()
        .map(|shape| Harmonic {
            mean: sum(shape, |h| h.mean),
            cos: sum(shape, |h| h.cos),
            sin: sum(shape, |h| h.sin),
        })
        .collect()
}

/// The weights g Φ of a sparse direction g on the modes (one per mode).
fn project_weights(w: &[(usize, f64)], shapes: &[Vec<f64>]) -> Vec<(usize, f64)> {
    shapes
        .iter()
        .enumerate()
        .map(|(j, shape)| (j, w.iter().map(|&(i, g)| g * shape[i]).sum()))
        .collect()
}
