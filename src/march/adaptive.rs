//! The adaptive time step of Gastaldi & Berruti 2018 (§4.2, eq. 8): in the contact state s the
//! step is Δτ(s) = r 𝕋(s), capped at the largest step Δτ_max, with r the step ratio and
//! 𝕋(s) = 2π/√ρ(s) (s) the shortest natural period of the state's linear piece, ρ(s) (rad²/s²)
//! the largest eigenvalue of M⁻¹(K + K_c(s)).
//!
//! The step is rounded down to a ladder Δτ_stick ϱᵏ (k an integer, ϱ = [`LADDER_RATIO`],
//! Δτ_stick the full-stick step), or is Δτ_max itself when eq. 8 reaches it ([`ladder_step`]):
//! the states whose steps fall on the same rung share one step size, hence its step matrices and
//! factorisations ([`super::schemes::Cache`]). A step is never above the eq. 8 value of its state.
//!
//! Below [`DENSE_BELOW`] DOF, and in a state whose change from full stick has as many columns
//! as the model has DOF (a modal model with many elements), ρ(s) is the spectral radius of
//! M⁻¹(K + K_c(s)) (a dense eigenproblem per state, no dearer there than one rung test). Otherwise
//! a state meets no eigenproblem: the rung is found by
//! testing rungs ([`RungCheck`]): Δτ ≤ r 𝕋(s) holds exactly when ρ_Δτ M − K − K_c(s) has no
//! negative eigenvalue, ρ_Δτ = (2π r/Δτ)², and K_c(s) differs from the full-stick K_c by a few
//! columns per element out of stick, so Sylvester's law of inertia counts its negative eigenvalues
//! from the full-stick pencil's eigenvalues and an r × r matrix (r the columns). The test takes
//! the symmetric part of K_c(s) (a slipping element's σ μ k_n g_t g_nᵀ is not symmetric): its
//! largest eigenvalue bounds every real eigenvalue of M⁻¹(K + K_c(s)) from above (the field of
//! values), so the step is never longer than eq. 8's (but for [`THRESHOLD_MARGIN`]); on the
//! sector of `cases/sector8_march.toml` the two differ by 1.4e-4 of ρ at most in the states
//! compared by `tests/march_adaptive.rs` (1.4e-3 in another sample of 30).

use std::collections::HashMap;

use super::dense;
use super::element::Element;
use super::law::{ContactState, LawSample};
use super::system::MarchSystem;

/// Ratio ϱ of consecutive rungs of the step ladder Δτ_stick ϱᵏ: a step at most 1 % shorter than
/// eq. 8 allows.
pub const LADDER_RATIO: f64 = 1.01;

/// Below this many DOF a state's ρ is the spectral radius of M⁻¹(K + K_c(s)) from a dense
/// eigenproblem ([`MarchSystem::shortest_period`]), which costs little there; from there on the
/// rungs are tested ([`RungCheck`]).
pub const DENSE_BELOW: usize = 16;

/// The largest rung Δτ_stick ϱᵏ (k an integer, possibly negative) not above `dt` (s), or
/// `dt_max` (s) when `dt` ≥ `dt_max`.
pub fn ladder_step(dt: f64, dt_stick: f64, dt_max: f64) -> f64 {
    if dt >= dt_max {
        return dt_max;
    }
    let rung = |k: i32| dt_stick * LADDER_RATIO.powi(k);
    let mut k = ((dt / dt_stick).ln() / LADDER_RATIO.ln()).floor() as i32;
    // the logarithms round: settle k on the exact rungs
    while rung(k) > dt {
        k -= 1;
    }
    while rung(k + 1) <= dt {
        k += 1;
    }
    rung(k)
}

/// Rungs tried below Δτ_stick for a state stiffer than full stick before its step is found from
/// the dense eigenproblem.
const MAX_RUNGS_DOWN: i32 = 64;

/// A rung's threshold ρ_Δτ is raised by this fraction: the full-stick pencil has an eigenvalue at
/// rung 0's threshold itself (a state within 1e-6 of a threshold takes the rung, a step at most
/// 5e-7 longer than eq. 8's).
pub const THRESHOLD_MARGIN: f64 = 1e-6;

/// The change of one element's K_c from full stick on its directions (g_t, g_n), symmetric part
/// [[a, b], [b, d]] (N/m; paper Table 1): slip of sign σ replaces k_t g_t g_tᵀ by σ μ k_n g_t g_nᵀ
/// (a = −k_t, b = σ μ k_n/2), separation removes k_t g_t g_tᵀ (a = −k_t) and, when the element
/// applies its normal force, k_n g_n g_nᵀ (d = −k_n). `None` in stick.
fn change_from_stick(e: &Element, s: ContactState) -> Option<[f64; 3]> {
    let p = &e.params;
    let normal = e.normal.is_some();
    match s {
        ContactState::Stick => None,
        ContactState::Slip(sign) => {
            let b = if normal {
                0.5 * sign.value() * p.mu * p.kn
            } else {
                0.0
            };
            Some([-p.kt, b, 0.0])
        }
        ContactState::Separated => {
            let d = if normal && e.applies_normal {
                -p.kn
            } else {
                0.0
            };
            Some([-p.kt, 0.0, d])
        }
    }
}

/// The number of columns r of the change of K_c from full stick in `states` (one or two per
/// element out of stick, [`change_from_stick`]): a rung test factors an r × r matrix.
fn state_columns(sys: &MarchSystem, states: &[ContactState]) -> usize {
    sys.elements
        .iter()
        .zip(states)
        .filter_map(|(e, &s)| change_from_stick(e, s))
        .map(|[a, b, d]| {
            if b != 0.0 {
                2
            } else {
                usize::from(a != 0.0) + usize::from(d != 0.0)
            }
        })
        .sum()
}

/// One column u (an element's g_t or g_n) of the change of K_c from full stick.
#[derive(Clone, Copy)]
struct Column {
    element: usize,
    normal: bool,
}

/// The index of the column `c` among all the elements' columns: 2 e for element e's tangential
/// direction, 2 e + 1 for its normal one (the order in which a state's test lists its columns).
fn column_index(c: Column) -> usize {
    2 * c.element + usize::from(c.normal)
}

/// uᵀ G⁻¹ u' of every pair of the columns of `sys` ([`column_index`]; row-major 2E × 2E, for
/// indices p ≥ q summed with u of p outside and u' of q inside, as a state's test sums its
/// entries), with G⁻¹ = (ρ M − K − K_c(stick))⁻¹ = Φ diag(1/(ρ − λ_j)) Φᵀ from the full-stick
/// eigenvalues `stick` and eigenvectors `modes` (row-major n × n).
fn column_forms(sys: &MarchSystem, stick: &[f64], modes: &[f64], rho: f64) -> Vec<f64> {
    let n = sys.n;
    let mut scaled = modes.to_vec();
    let mut transposed = vec![0.0; n * n];
    for i in 0..n {
        for j in 0..n {
            scaled[i * n + j] /= rho - stick[j];
            transposed[j * n + i] = modes[i * n + j];
        }
    }
    let g = dense::product(&scaled, &transposed, n);
    let m = 2 * sys.elements.len();
    let column = |p: usize| Column {
        element: p / 2,
        normal: p % 2 == 1,
    };
    let mut w = vec![0.0; m * m];
    for p in 0..m {
        let up = column_weights(sys, column(p));
        for q in 0..=p {
            let uq = column_weights(sys, column(q));
            let mut x = 0.0;
            for &(i, wi) in up {
                let row = &g[i * n..(i + 1) * n];
                for &(j, wj) in uq {
                    x += wi * wj * row[j];
                }
            }
            w[p * m + q] = x;
            w[q * m + p] = x;
        }
    }
    w
}

/// The sparse weights of the column `c` of `sys`.
fn column_weights(sys: &MarchSystem, c: Column) -> &[(usize, f64)] {
    let e = &sys.elements[c.element];
    match (c.normal, e.normal.as_ref()) {
        (true, Some(d)) => &d.weights,
        _ => &e.tangential.weights,
    }
}

/// The rung tests of one model ([module documentation](self)): the eigenvalues and eigenvectors
/// of the full-stick pencil (K + K_c(stick), M), and for each rung tested the products uᵀG⁻¹u'
/// of every pair of the elements' directions with G⁻¹ = (ρ_Δτ M − K − K_c(stick))⁻¹ formed from
/// them (rung 0's threshold lies 1e-6 above the largest eigenvalue, where an LU of the matrix
/// loses the digits the test needs), from which each state's test gathers its r × r matrix.
pub struct RungCheck {
    /// Eigenvalues λ_j of the full-stick pencil, ascending (rad²/s²).
    stick: Vec<f64>,
    /// Its eigenvectors (row-major n × n, column j the φ_j of λ_j, Φᵀ M Φ = I).
    modes: Vec<f64>,
    /// (g_t·φ₁, g_n·φ₁) of each element, φ₁ the dominant full-stick eigenvector (φ₁ᵀMφ₁ = 1).
    top: Vec<(f64, f64)>,
    /// uᵀ (ρ M − K − K_c(stick))⁻¹ u' of every pair of columns per threshold ρ (bits)
    /// ([`column_forms`]).
    forms: HashMap<u64, Vec<f64>>,
    columns: Vec<Column>,
    /// C⁻¹ − Uᵀ G⁻¹ U (row-major).
    s: Vec<f64>,
    /// Inertia tests made.
    pub tests: usize,
    /// Rungs excluded by the Rayleigh quotient of φ₁ alone.
    pub bound_exclusions: usize,
}

impl RungCheck {
    /// The full-stick pencil of `sys`; `None` when M is not positive definite.
    pub fn new(sys: &MarchSystem) -> Option<Self> {
        let n = sys.n;
        let k_stick = sys.effective_stiffness(&sys.stick_states());
        let (stick, modes) = dense::generalized_symmetric_eigen(&k_stick, &sys.mass, n)?;
        let phi: Vec<f64> = modes.chunks_exact(n).map(|row| row[n - 1]).collect();
        let top = sys
            .elements
            .iter()
            .map(|e| {
                let n = e.normal.as_ref().map_or(0.0, |d| d.dot(&phi));
                (e.tangential.dot(&phi), n)
            })
            .collect();
        Some(RungCheck {
            stick,
            modes,
            top,
            forms: HashMap::new(),
            columns: Vec::new(),
            s: Vec::new(),
            tests: 0,
            bound_exclusions: 0,
        })
    }

    /// φ₁ᵀ(K + K_c(s))φ₁ (symmetric part; rad²/s² since φ₁ᵀMφ₁ = 1): a lower bound of the largest
    /// eigenvalue of the state's symmetric pencil.
    fn lower_bound(&self, sys: &MarchSystem, states: &[ContactState]) -> f64 {
        let top = self.stick.last().copied().unwrap_or(0.0);
        let change: f64 = sys
            .elements
            .iter()
            .zip(states)
            .zip(&self.top)
            .filter_map(|((e, &s), &(t, n))| {
                change_from_stick(e, s).map(|[a, b, d]| a * t * t + 2.0 * b * t * n + d * n * n)
            })
            .sum();
        top + change
    }

    /// Whether the step `dt` (s) satisfies eq. 8 in the contact `states` (step ratio `ratio`):
    /// whether ρ_Δτ M − K − K_c(s) (symmetric part, ρ_Δτ = (2π r/Δτ)² (1 + [`THRESHOLD_MARGIN`]))
    /// has no negative eigenvalue. With G = ρ_Δτ M − K − K_c(stick) and the state's change
    /// K_c(s) − K_c(stick) = U C Uᵀ (r columns), Sylvester's law of inertia on
    /// [[G, U], [Uᵀ, C⁻¹]] gives neg(G − U C Uᵀ) = neg(G) + neg(C⁻¹ − UᵀG⁻¹U) − neg(C⁻¹), neg(G)
    /// being the number of full-stick eigenvalues above ρ_Δτ.
    fn allows(&mut self, sys: &MarchSystem, states: &[ContactState], ratio: f64, dt: f64) -> bool {
        let rho = (2.0 * std::f64::consts::PI * ratio / dt).powi(2) * (1.0 + THRESHOLD_MARGIN);
        let above = self.stick.iter().filter(|&&l| l > rho).count();
        let m = 2 * sys.elements.len();
        let (stick, modes) = (&self.stick, &self.modes);
        let w = self
            .forms
            .entry(rho.to_bits())
            .or_insert_with(|| column_forms(sys, stick, modes, rho));
        self.tests += 1;
        // the columns and C⁻¹ (1 × 1 or 2 × 2 blocks per element) with neg(C⁻¹)
        self.columns.clear();
        let mut blocks: Vec<(usize, usize, [f64; 4])> = Vec::new();
        let mut negative_c = 0;
        for (i, (e, &s)) in sys.elements.iter().zip(states).enumerate() {
            let Some([a, b, d]) = change_from_stick(e, s) else {
                continue;
            };
            let first = self.columns.len();
            if b != 0.0 {
                let det = a * d - b * b;
                negative_c += if det < 0.0 {
                    1
                } else if a < 0.0 {
                    2
                } else {
                    0
                };
                self.columns.push(Column {
                    element: i,
                    normal: false,
                });
                self.columns.push(Column {
                    element: i,
                    normal: true,
                });
                blocks.push((first, 2, [d / det, -b / det, -b / det, a / det]));
                continue;
            }
            for (value, normal) in [(a, false), (d, true)] {
                if value != 0.0 {
                    negative_c += usize::from(value < 0.0);
                    blocks.push((self.columns.len(), 1, [1.0 / value, 0.0, 0.0, 0.0]));
                    self.columns.push(Column { element: i, normal });
                }
            }
        }
        let r = self.columns.len();
        if r == 0 {
            return above == 0;
        }
        self.s.clear();
        self.s.resize(r * r, 0.0);
        for a in 0..r {
            let pa = column_index(self.columns[a]);
            for b in 0..=a {
                let x = w[pa * m + column_index(self.columns[b])];
                self.s[a * r + b] = -x;
                self.s[b * r + a] = -x;
            }
        }
        for (first, size, c) in blocks {
            for p in 0..size {
                for q in 0..size {
                    self.s[(first + p) * r + first + q] += c[2 * p + q];
                }
            }
        }
        above + dense::negative_eigenvalues(&self.s, r) == negative_c
    }
}

/// The adaptive steps of the states met, per state (codes), with the last one used checked first
/// without hashing (most steps keep the previous step's states).
pub struct AdaptiveSteps {
    map: HashMap<Vec<u8>, f64>,
    last: Vec<u8>,
    last_dt: f64,
    /// The step ratio r = Δτ/𝕋.
    ratio: f64,
    /// The largest step Δτ_max (s).
    dt_max: f64,
    /// The full-stick step min(r 𝕋_stick, Δτ_max) (s), the ladder's rung 0.
    dt_stick: f64,
    /// The rung tests (from [`DENSE_BELOW`] DOF on).
    check: Option<RungCheck>,
    states: Vec<ContactState>,
    /// States whose step came from the dense eigenproblem.
    dense_solves: usize,
}

impl AdaptiveSteps {
    /// The steps of `sys` with the step ratio `ratio` and the largest step `dt_max` (s): the
    /// full-stick step from the dense eigenproblem.
    pub fn new(sys: &MarchSystem, ratio: f64, dt_max: f64) -> Self {
        let stick = sys.stick_states();
        let dt_stick = sys
            .shortest_period(&stick)
            .map_or(dt_max, |t| (ratio * t).min(dt_max));
        let check = (sys.n >= DENSE_BELOW)
            .then(|| RungCheck::new(sys))
            .flatten();
        let codes: Vec<u8> = stick.iter().map(|s| s.code()).collect();
        AdaptiveSteps {
            map: HashMap::from([(codes, dt_stick)]),
            last: Vec::new(),
            last_dt: dt_stick,
            ratio,
            dt_max,
            dt_stick,
            check,
            states: Vec::with_capacity(stick.len()),
            dense_solves: 0,
        }
    }

    /// The full-stick step (s).
    pub fn stick(&self) -> f64 {
        self.dt_stick
    }

    /// (states met, inertia tests, rungs excluded by the Rayleigh quotient alone, states solved by
    /// the dense eigenproblem).
    pub fn counts(&self) -> (usize, usize, usize, usize) {
        let (tests, bound) = self
            .check
            .as_ref()
            .map_or((0, 0), |c| (c.tests, c.bound_exclusions));
        (self.map.len(), tests, bound, self.dense_solves)
    }

    /// The step (s) of the contact state of `samples` (codes `codes`): the ladder's highest rung
    /// not above r 𝕋(s) ([`ladder_step`]), found once per state.
    pub fn step(&mut self, sys: &MarchSystem, codes: &[u8], samples: &[LawSample]) -> f64 {
        if !self.last.is_empty() && self.last.iter().eq(codes.iter()) {
            return self.last_dt;
        }
        let dt = match self.map.get(codes) {
            Some(&dt) => dt,
            None => {
                self.states.clear();
                self.states.extend(samples.iter().map(|s| s.state));
                let dt = self
                    .tested_rung(sys)
                    .unwrap_or_else(|| self.dense_step(sys));
                self.map.insert(codes.to_vec(), dt);
                dt
            }
        };
        self.last.clear();
        self.last.extend_from_slice(codes);
        self.last_dt = dt;
        dt
    }

    /// The step (s) of the previous call's contact state when `samples` are in it, recognised
    /// from the samples' states without forming codes.
    #[inline]
    pub fn last_step(&self, samples: &[LawSample]) -> Option<f64> {
        let same = self.last.len() == samples.len()
            && self
                .last
                .iter()
                .zip(samples)
                .all(|(&c, s)| c == s.state.code());
        same.then_some(self.last_dt)
    }

    /// [`AdaptiveSteps::step`] of the contact state of `samples` (their codes formed into
    /// `codes`, scratch) when it is not the previous call's ([`AdaptiveSteps::last_step`]).
    pub fn step_of(
        &mut self,
        sys: &MarchSystem,
        samples: &[LawSample],
        codes: &mut Vec<u8>,
    ) -> f64 {
        if let Some(dt) = self.last_step(samples) {
            return dt;
        }
        codes.clear();
        codes.extend(samples.iter().map(|s| s.state.code()));
        self.step(sys, codes, samples)
    }

    /// The ladder's rung below eq. 8 from the dense eigenproblem of the state in `self.states`.
    fn dense_step(&mut self, sys: &MarchSystem) -> f64 {
        self.dense_solves += 1;
        let dt = sys
            .shortest_period(&self.states)
            .map_or(self.dt_max, |t| (self.ratio * t).min(self.dt_max));
        ladder_step(dt, self.dt_stick, self.dt_max)
    }

    /// The highest rung (or Δτ_max) the state in `self.states` allows, by the rung tests (`None`,
    /// for the dense eigenproblem, when the state has at least as many columns as the model has
    /// DOF: each test would factor a matrix larger than the model's): up from
    /// Δτ_stick while the next rung is allowed (a rung is first tried against φ₁'s Rayleigh
    /// quotient; a state allowed a rung above Δτ_stick is allowed Δτ_stick), else Δτ_stick, or
    /// down from it when the state is stiffer than full stick. `None` without the tests or when no
    /// rung within [`MAX_RUNGS_DOWN`] below Δτ_stick is allowed.
    fn tested_rung(&mut self, sys: &MarchSystem) -> Option<f64> {
        let (ratio, dt_stick, dt_max) = (self.ratio, self.dt_stick, self.dt_max);
        let states = &self.states;
        let check = self.check.as_mut()?;
        if state_columns(sys, states) >= sys.n {
            return None;
        }
        let rung = |k: i32| dt_stick * LADDER_RATIO.powi(k);
        let bound = check.lower_bound(sys, states);
        let mut k = 0;
        loop {
            let next = rung(k + 1).min(dt_max);
            if next <= rung(k) {
                break;
            }
            let threshold = (2.0 * std::f64::consts::PI * ratio / next).powi(2);
            if bound > threshold * (1.0 + THRESHOLD_MARGIN) {
                check.bound_exclusions += 1;
                break;
            }
            if !check.allows(sys, states, ratio, next) {
                break;
            }
            if next == dt_max {
                return Some(dt_max);
            }
            k += 1;
        }
        if k > 0 || check.allows(sys, states, ratio, rung(0)) {
            return Some(rung(k));
        }
        (1..=MAX_RUNGS_DOWN)
            .map(|k| rung(-k))
            .find(|&dt| check.allows(sys, states, ratio, dt))
    }
}
