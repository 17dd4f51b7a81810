//! The exact single-harmonic evaluation of the 1-D friction point law with normal load variation:
//! the continuous-time stick–slip–separation cycle of Cigeroglu, An & Menq (Nonlinear Dynamics
//! 2007, §2, eqs 4–29) under u and v that are each a constant plus one harmonic, with closed-form
//! transition angles, exact harmonic coefficients of the friction and normal forces, the energy
//! dissipated per cycle, the end-of-period slider state and the analytic Jacobian.
//!
//! The point is the continuous-time limit of the time-discrete law of [`super::law`] (1-D
//! variant, one tangential direction): normal force n = max(n0 + k_n v, 0) (eq. 4), friction
//! f = k_t (u − w) with slider w (eq. 5), |f| ≤ μ n, f = ±μ n while slipping (eq. 6), f = 0 and
//! w = u while separated. Symbols and units: u (m) tangential relative displacement, v (m) normal
//! approach (v > 0 loads the contact), k_t, k_n (N/m), μ (–), n0 (N, negative: initial gap),
//! w (m). For a distributed interface these are the per-point values times the point's area
//! (k_u dA, k_v dA, n0 dA of the paper).
//!
//! Harmonic layout (nlrom, `docs/conventions.md` §4): x(τ) = X0 + X1 cos τ − X2 sin τ with
//! τ = ωt and (X0, X1, X2) = (X⁽⁰⁾, Re X⁽¹⁾, Im X⁽¹⁾); the basis is e(τ) = (1, cos τ, −sin τ).
//! The paper writes u = a sin θ, v = b sin(θ + φ) (eq. 18); its θ is τ + θ_u with
//! θ_u = atan2(U1, −U2), and its dimensionless groups are b̄ = μ k_n b/(k_t a),
//! n̄0 = μ n0/(k_t a).
//!
//! The construction (force-unit form of the paper's transition angles, valid at φ = 0, π and
//! b̄ = 0 where eqs 21–28 divide by zero): with n0e = n0 + k_n V0 the effective preload (eq. 41
//! with the sign of eq. 4) and the harmonic parts u1, v1,
//! * g(τ) = k_t u1 − μ k_n v1 = |G| cos(τ + α_G) and h(τ) = k_t u1 + μ k_n v1 = |H| cos(τ + α_H);
//!   positive slip ends at the maximum of g (eq. 8, θ_P of eq. 21), negative slip at the minimum
//!   of h (eq. 9, θ_N of eq. 22);
//! * a stick phase with slider w ends in positive slip where g rises through
//!   c_P = μ n0e − k_t (U0 − w) (eq. 11; θ_StP, θ_SpP of eqs 23, 27) and in negative slip where h
//!   falls through c_N = −μ n0e − k_t (U0 − w) (eq. 12; θ_StN, θ_SpN of eqs 24, 28);
//! * contact is lost where n0e + k_n v1 falls through 0 and regained where it rises through 0
//!   (eqs 13–14 with the sign of ∂v/∂t that eq. 4 implies: the paper's eqs 13 and 14 have the
//!   two inequalities exchanged; θ_Sp1, θ_Sp2 of eqs 25–26); at re-contact the point slips
//!   positively if g′ > 0, negatively if h′ < 0 and sticks with f = 0 otherwise (eqs 15–17).
//!
//! The cycle is built by marching these events from τ = 0 and the given slider state until the
//! first event after which the state no longer depends on the history (the end of a slip, the
//! start of a separation), then over one period from there (which is then periodic; in complete
//! stick, eq. 19, the slider is kept, as the time-discrete element keeps it). The friction force
//! is on every phase a constant plus one harmonic, so the harmonic coefficients (eq. 29) are sums
//! of exact integrals. The force is continuous in τ, so the derivative of a coefficient is the sum
//! over the phases of the derivative of the phase's force (the moving limits cancel); the stick
//! phase after a re-contact depends on the re-contact instant, which enters through the slider.

use std::f64::consts::{PI, TAU};

use crate::contact::law::ContactParams;
use crate::error::{Error, Result};
use crate::vec3::dot;

/// Most events marched before the evaluation gives up (a cycle has at most about eight; the
/// bound only guards against a degenerate input that would loop).
const MAX_EVENTS: usize = 64;

/// Relative tolerance on |c|/A of a sinusoid A cos(τ + α) = c at its extremum: within it a
/// crossing is the tangency at the extremum (touching from inside: no transition; from outside: an
/// immediate one).
const TANGENCY: f64 = 1e-12;

/// An event less than this angle (rad) *behind* the current instant (by rounding) is taken as
/// immediate rather than one period later.
const BEHIND: f64 = 1e-9;

/// State of the point on a phase of the cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PhaseKind {
    /// Stick: f = k_t (u − w) with the slider w (m) fixed.
    Stick {
        /// The slider position w (m).
        slider: f64,
        /// Where w comes from (for its derivative).
        origin: SliderOrigin,
    },
    /// Positive slip: f = +μ n.
    PositiveSlip,
    /// Negative slip: f = −μ n.
    NegativeSlip,
    /// Separation: f = n = 0, the slider follows u.
    Separation,
}

impl PhaseKind {
    /// Short name: `stick`, `+slip`, `-slip`, `separation`.
    pub fn name(&self) -> &'static str {
        match self {
            PhaseKind::Stick { .. } => "stick",
            PhaseKind::PositiveSlip => "+slip",
            PhaseKind::NegativeSlip => "-slip",
            PhaseKind::Separation => "separation",
        }
    }

    /// The regime code of the stick–slip–separation maps: 0 stick, 1 positive slip, −1 negative
    /// slip, 2 separation.
    pub fn code(&self) -> i8 {
        match self {
            PhaseKind::Stick { .. } => 0,
            PhaseKind::PositiveSlip => 1,
            PhaseKind::NegativeSlip => -1,
            PhaseKind::Separation => 2,
        }
    }
}

/// How the slider of a stick phase was set.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum SliderOrigin {
    /// The caller's state, kept (complete stick): a parameter of the evaluation.
    Carried,
    /// Set at τ = 0 by the limit: w = u(0) − s μ n(0)/k_t (s = ±1), when the caller's state was
    /// outside the friction cone there and the point then stuck.
    Clamped(f64),
    /// End of positive slip at τ (the maximum of g): w = u(τ) − μ n(τ)/k_t.
    AfterPositiveSlip(f64),
    /// End of negative slip at τ (the minimum of h): w = u(τ) + μ n(τ)/k_t.
    AfterNegativeSlip(f64),
    /// Re-contact at τ with f = 0: w = u(τ).
    Recontact(f64),
}

/// One phase [start, end] (rad of τ) of the cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phase {
    /// The point's state on the phase.
    pub kind: PhaseKind,
    /// Start τ (rad).
    pub start: f64,
    /// End τ (rad), ≥ start.
    pub end: f64,
}

/// Which of the paper's regimes (§2.2) the cycle is in.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CycleRegime {
    /// Stuck over the whole cycle (eq. 19).
    CompleteStick,
    /// Stick and slip, contact kept over the whole cycle (§2.2.1).
    StickSlip,
    /// Stick, slip and separation (§2.2.2).
    Separation,
    /// Out of contact over the whole cycle (max n ≤ 0).
    AlwaysSeparated,
}

impl CycleRegime {
    /// Name used in reports: `complete stick`, `stick-slip`, `separation`, `always separated`.
    pub fn name(self) -> &'static str {
        match self {
            CycleRegime::CompleteStick => "complete stick",
            CycleRegime::StickSlip => "stick-slip",
            CycleRegime::Separation => "separation",
            CycleRegime::AlwaysSeparated => "always separated",
        }
    }
}

/// The harmonic motion of a point and its law's parameters, with the derived sinusoids.
#[derive(Clone, Copy, Debug)]
struct Motion {
    p: ContactParams,
    u: [f64; 3],
    v: [f64; 3],
    /// n0e = n0 + k_n V0 (N).
    n0e: f64,
    /// |G|, α_G of g = k_t u1 − μ k_n v1.
    g: (f64, f64),
    /// |H|, α_H of h = k_t u1 + μ k_n v1.
    h: (f64, f64),
    /// Contact window: None if in contact over the whole cycle; Some((τ_Sp2, length)) with the
    /// re-contact instant and the length of the contact window (0 when always separated).
    window: Option<(f64, f64)>,
}

/// e(τ) = (1, cos τ, −sin τ).
#[inline]
fn basis(t: f64) -> [f64; 3] {
    let (s, c) = t.sin_cos();
    [1.0, c, -s]
}

/// de/dτ = (0, −sin τ, −cos τ).
#[inline]
fn basis_rate(t: f64) -> [f64; 3] {
    let (s, c) = t.sin_cos();
    [0.0, -s, -c]
}

/// Amplitude and phase (A, α) of X1 cos τ − X2 sin τ = A cos(τ + α).
#[inline]
fn polar(x1: f64, x2: f64) -> (f64, f64) {
    (x1.hypot(x2), x2.atan2(x1))
}

/// How far ahead of `from` the angle `target` (mod 2π) lies, in [0, 2π); an angle less than
/// [`BEHIND`] behind counts as 0.
#[inline]
fn ahead(target: f64, from: f64) -> f64 {
    let d = (target - from).rem_euclid(TAU);
    if d > TAU - BEHIND {
        0.0
    } else {
        d
    }
}

impl Motion {
    fn new(p: &ContactParams, u: [f64; 3], v: [f64; 3]) -> Self {
        let (kt, kn, mu) = (p.kt, p.kn, p.mu);
        let n0e = p.n0 + kn * v[0];
        let g = polar(kt * u[1] - mu * kn * v[1], kt * u[2] - mu * kn * v[2]);
        let h = polar(kt * u[1] + mu * kn * v[1], kt * u[2] + mu * kn * v[2]);
        let (vamp, valpha) = polar(kn * v[1], kn * v[2]);
        let window = if n0e + vamp <= 1e-14 * (n0e.abs() + vamp) {
            Some((0.0, 0.0))
        } else if vamp > 0.0 {
            // n = n0e + vamp cos(τ + α_V) < 0 where cos(τ + α_V) < ρ.
            let rho = -n0e / vamp;
            if rho > -1.0 + TANGENCY {
                let a = rho.min(1.0).acos();
                // Re-contact (n rising through 0): τ + α_V = −arccos ρ; contact length 2 arccos ρ.
                Some(((-valpha - a).rem_euclid(TAU), 2.0 * a))
            } else {
                None
            }
        } else {
            None
        };
        Motion {
            p: *p,
            u,
            v,
            n0e,
            g,
            h,
            window,
        }
    }

    fn u_at(&self, t: f64) -> f64 {
        dot(self.u, basis(t))
    }

    /// n0e + k_n v1(τ) (the normal force in contact).
    fn n_at(&self, t: f64) -> f64 {
        let e = basis(t);
        self.n0e + self.p.kn * (self.v[1] * e[1] + self.v[2] * e[2])
    }

    /// g′(τ) = −|G| sin(τ + α_G), h′(τ).
    fn rates(&self, t: f64) -> (f64, f64) {
        (
            -self.g.0 * (t + self.g.1).sin(),
            -self.h.0 * (t + self.h.1).sin(),
        )
    }

    /// The start of separation (n falling through 0) and the end.
    fn separation_start(&self) -> Option<f64> {
        self.window.map(|(t2, len)| t2 + len)
    }

    /// The state at a re-contact instant τ (eqs 15–17).
    fn recontact_state(&self, t: f64) -> PhaseKind {
        let (dg, dh) = self.rates(t);
        if dg > 0.0 {
            PhaseKind::PositiveSlip
        } else if dh < 0.0 {
            PhaseKind::NegativeSlip
        } else {
            PhaseKind::Stick {
                slider: self.u_at(t),
                origin: SliderOrigin::Recontact(t),
            }
        }
    }

    /// The state at τ = 0 from the slider w (the first sample of the time-discrete law).
    fn initial_state(&self, w: f64) -> PhaseKind {
        if let Some((t2, len)) = self.window {
            if len <= 0.0 || ahead(0.0, t2) >= len {
                return PhaseKind::Separation;
            }
        }
        let n = self.n_at(0.0).max(0.0);
        let u0 = self.u_at(0.0);
        let trial = self.p.kt * (u0 - w);
        let limit = self.p.mu * n;
        if trial.abs() <= limit * (1.0 + super::law::STICK_MARGIN) {
            return PhaseKind::Stick {
                slider: w,
                origin: SliderOrigin::Carried,
            };
        }
        let s = trial.signum();
        let (dg, dh) = self.rates(0.0);
        if s > 0.0 && dg > 0.0 {
            PhaseKind::PositiveSlip
        } else if s < 0.0 && dh < 0.0 {
            PhaseKind::NegativeSlip
        } else {
            PhaseKind::Stick {
                slider: u0 - s * limit / self.p.kt,
                origin: SliderOrigin::Clamped(s),
            }
        }
    }

    /// The next event after τ = `t` in state `kind`: (how far ahead, the state after it).
    fn next_event(&self, t: f64, kind: PhaseKind) -> (f64, PhaseKind) {
        let mut best = (f64::INFINITY, kind);
        let mut consider = |d: f64, next: PhaseKind| {
            if d < best.0 {
                best = (d, next);
            }
        };
        let separation = |consider: &mut dyn FnMut(f64, PhaseKind)| {
            if let Some(ts1) = self.separation_start() {
                consider(ahead(ts1, t), PhaseKind::Separation);
            }
        };
        match kind {
            PhaseKind::Separation => {
                if let Some((t2, len)) = self.window {
                    if len > 0.0 {
                        consider(ahead(t2, t), self.recontact_state(t2));
                    }
                }
            }
            PhaseKind::PositiveSlip => {
                if self.g.0 > 0.0 {
                    let tp = -self.g.1;
                    consider(
                        ahead(tp, t),
                        PhaseKind::Stick {
                            slider: f64::NAN,
                            origin: SliderOrigin::AfterPositiveSlip(tp),
                        },
                    );
                }
                separation(&mut consider);
            }
            PhaseKind::NegativeSlip => {
                if self.h.0 > 0.0 {
                    let tn = PI - self.h.1;
                    consider(
                        ahead(tn, t),
                        PhaseKind::Stick {
                            slider: f64::NAN,
                            origin: SliderOrigin::AfterNegativeSlip(tn),
                        },
                    );
                }
                separation(&mut consider);
            }
            PhaseKind::Stick { slider, .. } => {
                let offset = self.p.kt * (self.u[0] - slider);
                let mun = self.p.mu * self.n0e;
                // g rises through c_P.
                let (ga, gal) = self.g;
                if ga > 0.0 {
                    let r = (mun - offset) / ga;
                    if r < 1.0 - TANGENCY {
                        let tc = -gal - r.max(-1.0).acos();
                        consider(ahead(tc, t), PhaseKind::PositiveSlip);
                    }
                }
                // h falls through c_N.
                let (ha, hal) = self.h;
                if ha > 0.0 {
                    let r = (-mun - offset) / ha;
                    if r > -1.0 + TANGENCY {
                        let tc = -hal + r.min(1.0).acos();
                        consider(ahead(tc, t), PhaseKind::NegativeSlip);
                    }
                }
                separation(&mut consider);
            }
        }
        // Fill in the slider of a stick that follows a slip.
        let next = match best.1 {
            PhaseKind::Stick {
                origin: SliderOrigin::AfterPositiveSlip(tp),
                ..
            } => PhaseKind::Stick {
                slider: self.u_at(tp) - self.p.mu * self.n_at(tp) / self.p.kt,
                origin: SliderOrigin::AfterPositiveSlip(tp),
            },
            PhaseKind::Stick {
                origin: SliderOrigin::AfterNegativeSlip(tn),
                ..
            } => PhaseKind::Stick {
                slider: self.u_at(tn) + self.p.mu * self.n_at(tn) / self.p.kt,
                origin: SliderOrigin::AfterNegativeSlip(tn),
            },
            other => other,
        };
        (best.0, next)
    }
}

/// Whether the state after a transition from `from` to `to` no longer depends on the history.
fn history_free(from: PhaseKind, to: PhaseKind) -> bool {
    matches!(to, PhaseKind::Separation)
        || matches!(
            from,
            PhaseKind::PositiveSlip | PhaseKind::NegativeSlip | PhaseKind::Separation
        )
}

/// The periodic cycle of one point (see the module documentation).
#[derive(Clone, Debug, PartialEq)]
pub struct Cycle {
    /// The phases, contiguous over one period [phases\[0\].start, phases\[0\].start + 2π].
    pub phases: Vec<Phase>,
    /// The regime of the cycle.
    pub regime: CycleRegime,
}

impl Cycle {
    /// Fraction of the period in each state: (stick, positive slip, negative slip, separation).
    pub fn fractions(&self) -> [f64; 4] {
        let mut out = [0.0; 4];
        for ph in &self.phases {
            let i = match ph.kind {
                PhaseKind::Stick { .. } => 0,
                PhaseKind::PositiveSlip => 1,
                PhaseKind::NegativeSlip => 2,
                PhaseKind::Separation => 3,
            };
            out[i] += (ph.end - ph.start) / TAU;
        }
        out
    }

    /// The phase at τ (any real; taken mod 2π).
    pub fn phase_at(&self, t: f64) -> &Phase {
        let t0 = self.phases[0].start;
        let t = t0 + (t - t0).rem_euclid(TAU);
        self.phases
            .iter()
            .find(|ph| t <= ph.end)
            .unwrap_or(&self.phases[self.phases.len() - 1])
    }

    /// The transitions of the cycle: (τ in [0, 2π), name) with the names of the paper's angles:
    /// `StP`, `SpP` (stick → positive slip, the stick after slip or after re-contact), `P`
    /// (positive slip → stick), `StN`, `SpN`, `N`, `Sp1` (start of separation), `Sp2` (end).
    pub fn transitions(&self) -> Vec<(f64, &'static str)> {
        let n = self.phases.len();
        let mut out = Vec::new();
        if n < 2 {
            return out;
        }
        for i in 0..n {
            let (a, b) = (&self.phases[i], &self.phases[(i + 1) % n]);
            let name = match (a.kind, b.kind) {
                (_, PhaseKind::Separation) => "Sp1",
                (PhaseKind::Separation, _) => "Sp2",
                (PhaseKind::PositiveSlip, _) => "P",
                (PhaseKind::NegativeSlip, _) => "N",
                (
                    PhaseKind::Stick {
                        origin: SliderOrigin::Recontact(_),
                        ..
                    },
                    PhaseKind::PositiveSlip,
                ) => "SpP",
                (
                    PhaseKind::Stick {
                        origin: SliderOrigin::Recontact(_),
                        ..
                    },
                    PhaseKind::NegativeSlip,
                ) => "SpN",
                (_, PhaseKind::PositiveSlip) => "StP",
                (_, PhaseKind::NegativeSlip) => "StN",
                _ => continue,
            };
            if a.kind == b.kind {
                continue;
            }
            out.push((a.end.rem_euclid(TAU), name));
        }
        out.sort_by(|x, y| x.0.total_cmp(&y.0));
        out
    }
}

/// Results of [`evaluate`] for one point and one tangential direction.
#[derive(Clone, Debug, PartialEq)]
pub struct PointResult {
    /// Friction force harmonics (F0, Re F1, Im F1) (N), internal-force sign of [`super::law`].
    pub friction: [f64; 3],
    /// Normal force harmonics (N0, Re N1, Im N1) (N).
    pub normal: [f64; 3],
    /// Energy dissipated per cycle W = ∮ f du = π (U1 Im F1 − U2 Re F1) (J).
    pub energy: f64,
    /// Slider state at τ = 0 of the periodic cycle: u(0) − f(0)/k_t in contact, u(0) separated.
    pub slider: f64,
    /// The periodic cycle.
    pub cycle: Cycle,
    /// ∂(F0, Re F1, Im F1)/∂(U0, U1, U2, V0, V1, V2, n0), if asked.
    pub friction_jacobian: Option<[[f64; 7]; 3]>,
    /// ∂(N0, Re N1, Im N1)/∂(U0, U1, U2, V0, V1, V2, n0), if asked.
    pub normal_jacobian: Option<[[f64; 7]; 3]>,
}

/// M_kl = p_k ∫_a^b e_k e_l dτ with the projection weights p = (1/2π, 1/π, 1/π) of the harmonic
/// coefficients (F0 = (1/2π)∮f, Re F1 = (1/π)∮f cos τ, Im F1 = −(1/π)∮f sin τ).
fn projection(a: f64, b: f64) -> [[f64; 3]; 3] {
    let d = b - a;
    let (sa, ca) = a.sin_cos();
    let (sb, cb) = b.sin_cos();
    let s2 = 2.0 * (sb * cb - sa * ca);
    let i1 = d;
    let ic = sb - sa;
    let is = cb - ca; // ∫ −sin
    let icc = 0.5 * d + 0.25 * s2;
    let iss = 0.5 * d - 0.25 * s2;
    let ics = -0.5 * (sb * sb - sa * sa); // ∫ cos·(−sin)
    let raw = [[i1, ic, is], [ic, icc, ics], [is, ics, iss]];
    let w = [1.0 / TAU, 1.0 / PI, 1.0 / PI];
    let mut m = [[0.0; 3]; 3];
    for k in 0..3 {
        for l in 0..3 {
            m[k][l] = w[k] * raw[k][l];
        }
    }
    m
}

/// The periodic cycle of a point with the harmonic motion u, v (layout (X0, Re X1, Im X1), m)
/// and the slider state `slider` (m) at τ = 0.
pub fn cycle(p: &ContactParams, u: [f64; 3], v: [f64; 3], slider: f64) -> Result<Cycle> {
    build(&Motion::new(p, u, v), slider)
}

fn build(mo: &Motion, slider: f64) -> Result<Cycle> {
    if mo.window == Some((0.0, 0.0)) {
        return Ok(Cycle {
            phases: vec![Phase {
                kind: PhaseKind::Separation,
                start: 0.0,
                end: TAU,
            }],
            regime: CycleRegime::AlwaysSeparated,
        });
    }
    if mo.p.kt <= 0.0 {
        // No tangential stiffness: f ≡ 0; only the contact window matters.
        let stick = PhaseKind::Stick {
            slider,
            origin: SliderOrigin::Carried,
        };
        return Ok(match mo.window {
            None => Cycle {
                phases: vec![Phase {
                    kind: stick,
                    start: 0.0,
                    end: TAU,
                }],
                regime: CycleRegime::CompleteStick,
            },
            Some((t2, len)) => Cycle {
                phases: vec![
                    Phase {
                        kind: stick,
                        start: t2,
                        end: t2 + len,
                    },
                    Phase {
                        kind: PhaseKind::Separation,
                        start: t2 + len,
                        end: t2 + TAU,
                    },
                ],
                regime: CycleRegime::Separation,
            },
        });
    }
    // A history-free start known in closed form: the re-contact (separation), or the end of
    // positive slip at the maximum of g (stick–slip without separation, 2μ n0e < |G| + |H|,
    // eq. 19); else (complete stick, or a degenerate sinusoid) the transient march below.
    let known = match mo.window {
        Some((t2, _)) => Some((t2, mo.recontact_state(t2))),
        None if mo.g.0 > 0.0
            && mo.h.0 > 0.0
            && 2.0 * mo.p.mu * mo.n0e < (mo.g.0 + mo.h.0) * (1.0 - 1e-9) =>
        {
            let tp = (-mo.g.1).rem_euclid(TAU);
            Some((
                tp,
                PhaseKind::Stick {
                    slider: mo.u_at(tp) - mo.p.mu * mo.n_at(tp) / mo.p.kt,
                    origin: SliderOrigin::AfterPositiveSlip(tp),
                },
            ))
        }
        None => None,
    };
    // Transient: from τ = 0 until the first history-free event (at most two periods).
    let mut t = 0.0;
    let mut kind = mo.initial_state(slider);
    let mut start = None;
    let transient_events = match known {
        Some((t0, k0)) => {
            start = Some(t0);
            kind = k0;
            0
        }
        None => MAX_EVENTS,
    };
    for _ in 0..transient_events {
        let (d, next) = mo.next_event(t, kind);
        if t + d > 2.0 * TAU {
            break;
        }
        let free = history_free(kind, next);
        t += d;
        kind = next;
        if free {
            start = Some(t);
            break;
        }
    }
    let Some(t0) = start else {
        // No slip and no separation: stuck over the whole cycle with the state at τ = 0.
        if let PhaseKind::Stick { .. } = kind {
            let first = mo.initial_state(slider);
            return Ok(Cycle {
                phases: vec![Phase {
                    kind: first,
                    start: 0.0,
                    end: TAU,
                }],
                regime: CycleRegime::CompleteStick,
            });
        }
        return Err(Error::Compute(format!(
            "analytic friction point: no periodic state reached (u = {:?}, v = {:?}, {:?})",
            mo.u, mo.v, mo.p
        )));
    };
    // One period from the history-free event.
    let end = t0 + TAU;
    let mut phases = Vec::with_capacity(8);
    let mut t = t0;
    for _ in 0..MAX_EVENTS {
        let (d, next) = mo.next_event(t, kind);
        if t + d >= end - BEHIND {
            phases.push(Phase {
                kind,
                start: t,
                end,
            });
            break;
        }
        if d > 0.0 {
            phases.push(Phase {
                kind,
                start: t,
                end: t + d,
            });
        }
        t += d;
        kind = next;
    }
    if phases.last().map(|p| p.end) != Some(end) {
        return Err(Error::Compute(format!(
            "analytic friction point: more than {MAX_EVENTS} transitions in one cycle (u = {:?}, v = {:?}, {:?})",
            mo.u, mo.v, mo.p
        )));
    }
    // Merge neighbouring phases of the same kind (zero-length intermediates removed above).
    let mut merged: Vec<Phase> = Vec::with_capacity(phases.len());
    for ph in phases {
        match merged.last_mut() {
            Some(last) if same_state(&last.kind, &ph.kind) => last.end = ph.end,
            _ => merged.push(ph),
        }
    }
    let slips = merged
        .iter()
        .any(|p| matches!(p.kind, PhaseKind::PositiveSlip | PhaseKind::NegativeSlip));
    let regime = if mo.window.is_some() {
        CycleRegime::Separation
    } else if slips {
        CycleRegime::StickSlip
    } else {
        CycleRegime::CompleteStick
    };
    Ok(Cycle {
        phases: merged,
        regime,
    })
}

fn same_state(a: &PhaseKind, b: &PhaseKind) -> bool {
    match (a, b) {
        (PhaseKind::Stick { slider: x, .. }, PhaseKind::Stick { slider: y, .. }) => x == y,
        _ => std::mem::discriminant(a) == std::mem::discriminant(b),
    }
}

/// ∂w/∂(U0, U1, U2, V0, V1, V2, n0) of a stick phase's slider.
fn slider_derivative(mo: &Motion, origin: SliderOrigin) -> [f64; 7] {
    let (kt, kn, mu) = (mo.p.kt, mo.p.kn, mo.p.mu);
    let mut d = [0.0; 7];
    // w = u(τ) − s μ (n0 + k_n v(τ))/k_t at a fixed τ (or at an extremum of g or h, where the
    // τ-derivative vanishes).
    let mut at_limit = |t: f64, s: f64| {
        let e = basis(t);
        for l in 0..3 {
            d[l] = e[l];
            d[3 + l] = -s * mu * kn * e[l] / kt;
        }
        d[6] = -s * mu / kt;
    };
    match origin {
        SliderOrigin::Carried => {}
        SliderOrigin::Clamped(s) => at_limit(0.0, s),
        SliderOrigin::AfterPositiveSlip(t) => at_limit(t, 1.0),
        SliderOrigin::AfterNegativeSlip(t) => at_limit(t, -1.0),
        SliderOrigin::Recontact(t) => {
            // w = u(τ_Sp2), with n0 + k_n v(τ_Sp2) = 0:
            // ∂τ = −(∂n0 + k_n e·∂V)/(k_n v1′(τ)), ∂w = e·∂U + u1′(τ) ∂τ.
            let e = basis(t);
            let de = basis_rate(t);
            d[..3].copy_from_slice(&e);
            let dv = kn * (mo.v[1] * de[1] + mo.v[2] * de[2]);
            if dv.abs() > 0.0 {
                let du = mo.u[1] * de[1] + mo.u[2] * de[2];
                for l in 0..3 {
                    d[3 + l] = -du * kn * e[l] / dv;
                }
                d[6] = -du / dv;
            }
        }
    }
    d
}

/// Evaluates one point (one tangential direction): the periodic cycle from the slider state
/// `slider` (m, at τ = 0), the harmonics of the friction and normal forces, the energy per cycle,
/// the end slider state and, if `jacobian`, the derivatives with respect to (U, V, n0).
///
/// `u` and `v` are (X0, Re X1, Im X1) (m); `v = [0; 3]` for a point without normal motion.
/// Errors only on non-finite input or a degenerate cycle (`Error::Compute`).
pub fn evaluate(
    p: &ContactParams,
    u: [f64; 3],
    v: [f64; 3],
    slider: f64,
    jacobian: bool,
) -> Result<PointResult> {
    if !u.iter().chain(&v).chain([&slider]).all(|x| x.is_finite()) {
        return Err(Error::Compute(format!(
            "analytic friction point: non-finite input u = {u:?}, v = {v:?}, slider = {slider}"
        )));
    }
    let mo = Motion::new(p, u, v);
    let cycle = build(&mo, slider)?;
    let (kt, kn, mu) = (p.kt, p.kn, p.mu);
    let mut friction = [0.0; 3];
    let mut normal = [0.0; 3];
    let mut fj = [[0.0; 7]; 3];
    let mut nj = [[0.0; 7]; 3];
    for ph in &cycle.phases {
        if let PhaseKind::Separation = ph.kind {
            continue;
        }
        let m = projection(ph.start, ph.end);
        // Normal force on every contact phase: n = n0e + k_n v1.
        let cn = [mo.n0e, kn * v[1], kn * v[2]];
        // Friction: coefficients c on the basis e, and ∂c/∂x.
        let mut dc = [[0.0; 7]; 3];
        let c = match ph.kind {
            PhaseKind::Stick { slider: w, origin } => {
                if jacobian {
                    let dw = slider_derivative(&mo, origin);
                    for (l, row) in dc.iter_mut().enumerate() {
                        row[l] = kt;
                    }
                    for (x, dwx) in dw.iter().enumerate() {
                        dc[0][x] -= kt * dwx;
                    }
                }
                [kt * (u[0] - w), kt * u[1], kt * u[2]]
            }
            PhaseKind::PositiveSlip | PhaseKind::NegativeSlip => {
                let s = if ph.kind == PhaseKind::PositiveSlip {
                    1.0
                } else {
                    -1.0
                };
                if jacobian {
                    for (l, row) in dc.iter_mut().enumerate() {
                        row[3 + l] = s * mu * kn;
                    }
                    dc[0][6] = s * mu;
                }
                [s * mu * cn[0], s * mu * cn[1], s * mu * cn[2]]
            }
            PhaseKind::Separation => unreachable!("skipped above"),
        };
        for k in 0..3 {
            friction[k] += dot(m[k], c);
            normal[k] += dot(m[k], cn);
            if jacobian {
                for x in 0..7 {
                    fj[k][x] += m[k][0] * dc[0][x] + m[k][1] * dc[1][x] + m[k][2] * dc[2][x];
                }
                for l in 0..3 {
                    nj[k][3 + l] += m[k][l] * kn;
                }
                nj[k][6] += m[k][0];
            }
        }
    }
    let energy = PI * (u[1] * friction[2] - u[2] * friction[1]);
    let end = match cycle.phase_at(0.0).kind {
        PhaseKind::Stick { slider: w, .. } => w,
        PhaseKind::Separation => mo.u_at(0.0),
        PhaseKind::PositiveSlip => mo.u_at(0.0) - mu * mo.n_at(0.0) / kt,
        PhaseKind::NegativeSlip => mo.u_at(0.0) + mu * mo.n_at(0.0) / kt,
    };
    Ok(PointResult {
        friction,
        normal,
        energy,
        slider: end,
        cycle,
        friction_jacobian: jacobian.then_some(fj),
        normal_jacobian: jacobian.then_some(nj),
    })
}

/// The friction force f (N), normal force n (N) and slider w (m) at τ on the periodic cycle of
/// `result` (for hysteresis loops and maps).
pub fn state_at(
    p: &ContactParams,
    u: [f64; 3],
    v: [f64; 3],
    cycle: &Cycle,
    t: f64,
) -> (f64, f64, f64, PhaseKind) {
    let mo = Motion::new(p, u, v);
    let ph = cycle.phase_at(t);
    let ut = mo.u_at(t);
    let n = mo.n_at(t).max(0.0);
    let (f, w) = match ph.kind {
        PhaseKind::Stick { slider, .. } => (p.kt * (ut - slider), slider),
        PhaseKind::PositiveSlip => (p.mu * n, ut - p.mu * n / p.kt),
        PhaseKind::NegativeSlip => (-p.mu * n, ut + p.mu * n / p.kt),
        PhaseKind::Separation => (0.0, ut),
    };
    let n = if ph.kind == PhaseKind::Separation {
        0.0
    } else {
        n
    };
    (f, n, w, ph.kind)
}

/// The analytic evaluation of a local element ([`super::element::evaluate_as`]): the 1-D law
/// with one or two tangential directions (each an independent point sharing the normal force,
/// Cigeroglu, An & Menq 2007, §2) on the local coefficients `x` = `[U1; U2; V]` with H = 1
/// (three coefficients per signal). Writes the forces `[F1; F2; Fn]`, the end slider state and,
/// if `jacobian`, the local Jacobian (with the ∂n0 column) to the workspace.
pub(crate) fn evaluate_element(
    element: &super::element::LocalElement,
    harmonics: usize,
    x: &[f64],
    slider: &mut [f64; 2],
    force: &mut [f64],
    jacobian: bool,
    ws: &mut super::element::Workspace,
) -> Result<()> {
    if element.variant != super::law::Variant::OneD {
        return Err(Error::input(
            "evaluation = \"analytic\" is the exact cycle of the 1-D friction law; the 2-D (Coulomb disc) element is evaluated by the AFT only (evaluation = \"aft\")",
        ));
    }
    if harmonics != 1 {
        return Err(Error::input(format!(
            "evaluation = \"analytic\" is the exact single-harmonic cycle and needs harmonics = 1 (here H = {harmonics}); use evaluation = \"aft\" for H > 1"
        )));
    }
    let nt = element.tangential;
    let nsig = element.signals();
    let v = if element.normal {
        [x[nt * 3], x[nt * 3 + 1], x[nt * 3 + 2]]
    } else {
        [0.0; 3]
    };
    let cols = nsig * 3 + 1;
    let mut jac = [0.0; 9 * 10];
    let mut u_all = [[0.0; 3]; 2];
    let mut cycles = Vec::with_capacity(nt);
    let mut energy = 0.0;
    for d in 0..nt {
        let u = [x[d * 3], x[d * 3 + 1], x[d * 3 + 2]];
        u_all[d] = u;
        let r = evaluate(&element.params, u, v, slider[d], jacobian)?;
        slider[d] = r.slider;
        energy += r.energy;
        force[d * 3..d * 3 + 3].copy_from_slice(&r.friction);
        if element.normal && d == 0 {
            force[nt * 3..nt * 3 + 3].copy_from_slice(&r.normal);
        }
        if let (Some(fj), Some(nj)) = (r.friction_jacobian, r.normal_jacobian) {
            for k in 0..3 {
                let row = &mut jac[(d * 3 + k) * cols..(d * 3 + k + 1) * cols];
                row[d * 3..d * 3 + 3].copy_from_slice(&fj[k][..3]);
                if element.normal {
                    row[nt * 3..nt * 3 + 3].copy_from_slice(&fj[k][3..6]);
                }
                row[cols - 1] = fj[k][6];
                if element.normal && d == 0 {
                    let row = &mut jac[(nt * 3 + k) * cols..(nt * 3 + k + 1) * cols];
                    row[nt * 3..nt * 3 + 3].copy_from_slice(&nj[k][3..6]);
                    row[cols - 1] = nj[k][6];
                }
            }
        }
        cycles.push(r.cycle);
    }
    ws.set_analytic(
        jacobian.then_some((&jac[..nsig * 3 * cols], cols)),
        super::element::AnalyticPeriod {
            params: element.params,
            tangential: nt,
            u: u_all,
            v,
            cycles,
            energy,
        },
    );
    Ok(())
}
