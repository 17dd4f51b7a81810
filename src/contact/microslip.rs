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

use std::cell::Cell;
use std::f64::consts::{FRAC_1_PI, FRAC_PI_2, PI, TAU};

use crate::contact::law::ContactParams;
use crate::error::{Error, Result};
use crate::vec3::dot;

mod separation;
use separation::separation_form;

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
    /// sin and cos of `start`, then of `end` (computed once per event, in closed form).
    sc: [f64; 4],
}

impl Phase {
    fn new(kind: PhaseKind, start: At, end: At) -> Self {
        Phase {
            kind,
            start: start.t,
            end: end.t,
            sc: [start.s, start.c, end.s, end.c],
        }
    }

    /// A phase over [start, start + 2π] from τ = `start` given with its sine and cosine.
    fn whole(kind: PhaseKind, start: At) -> Self {
        Phase::new(kind, start, start.labelled(start.t + TAU))
    }
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

/// Most phases of one periodic cycle: a cycle has at most about eight; more is a degenerate
/// input and an error.
const MAX_PHASES: usize = 16;

/// An instant τ (rad) with its sine and cosine, computed once per event (in closed form from
/// the sinusoid it is an event of, not by evaluating sin and cos of τ).
#[derive(Clone, Copy, Debug, PartialEq)]
struct At {
    t: f64,
    s: f64,
    c: f64,
}

impl At {
    const ZERO: At = At {
        t: 0.0,
        s: 0.0,
        c: 1.0,
    };

    /// The same instant labelled τ + 2πk (the caller's `t` differs from `self.t` by whole
    /// periods, up to rounding).
    #[inline]
    fn labelled(self, t: f64) -> At {
        At { t, ..self }
    }

    /// e(τ) = (1, cos τ, −sin τ).
    #[inline]
    fn basis(self) -> [f64; 3] {
        [1.0, self.c, -self.s]
    }

    /// de/dτ = (0, −sin τ, −cos τ).
    #[inline]
    fn basis_rate(self) -> [f64; 3] {
        [0.0, -self.s, -self.c]
    }
}

/// The angle α (rad, in [−π, π]) with cos α = `c` and sin α = `s` (a unit vector, the
/// atan2(s, c) of a sinusoid's phase): arcsin s where |s| ≤ 1/2, else ± arccos c (|c| < √3/2),
/// each on the side where it is well conditioned; within 1.4 ulp of atan2 and inline (no call
/// into libm, whose calls make every live floating-point register spill).
#[inline(always)]
fn angle(c: f64, s: f64) -> f64 {
    if s.abs() <= 0.5 {
        let a = arcsin_small(s);
        if c >= 0.0 {
            a
        } else if s >= 0.0 {
            PI - a
        } else {
            -PI - a
        }
    } else {
        let a = arccos(c);
        if s >= 0.0 {
            a
        } else {
            -a
        }
    }
}

// The rational approximation below is that of FDLIBM's e_asin.c and e_acos.c:
// ====================================================
// Copyright (C) 1993 by Sun Microsystems, Inc. All rights reserved.
//
// Developed at SunSoft, a Sun Microsystems, Inc. business.
// Permission to use, copy, modify, and distribute this
// software is freely granted, provided that this notice
// is preserved.
// ====================================================

/// π/2 minus its double [`FRAC_PI_2`] (FDLIBM's `pio2_lo`): arccos keeps this part.
const PIO2_LO: f64 = 6.123233995736766e-17;

/// R(z) = (arcsin √z − √z)/√z for z in [0, 1/4] (FDLIBM's rational approximation P(z)/Q(z),
/// Sun Microsystems 1993, error below 2^−58.75), so arcsin x = x + x R(x²) for |x| ≤ 1/2. P and
/// Q by Estrin's scheme (pairs of terms, then z² and z⁴): a shorter dependent chain than
/// Horner's, whose latency the exact point's chain of inverse functions would add up.
#[inline(always)]
fn arcsin_ratio(z: f64) -> f64 {
    let z2 = z * z;
    let z4 = z2 * z2;
    let p = z
        * ((0.16666666666666666 - 0.3255658186224009 * z)
            + z2 * (0.20121253213486293 - 0.04005553450067941 * z)
            + z4 * (0.0007915349942898145 + 3.479331075960212e-05 * z));
    let q = (1.0 - 2.403394911734414 * z)
        + z2 * (2.0209457602335057 - 0.6882839716054533 * z)
        + z4 * 0.07703815055590194;
    p / q
}

/// arcsin x (rad) for |x| ≤ 1/2: x + x R(x²) ([`arcsin_ratio`]).
#[inline(always)]
fn arcsin_small(x: f64) -> f64 {
    x + x * arcsin_ratio(x * x)
}

/// arccos x (rad, in [0, π]) for x in [−1, 1], inline (the reduction of FDLIBM's acos without
/// its last-bit correction for x > 1/2): π/2 − arcsin x for |x| ≤ 1/2, else
/// 2 arcsin √z with z = (1 − |x|)/2 ≤ 1/4 (exact), mirrored to π − 2 arcsin √z for x < 0.
/// Within 1.1 ulp of the correctly rounded value (libm's is within 0.52).
#[inline(always)]
fn arccos(x: f64) -> f64 {
    if x.abs() <= 0.5 {
        return FRAC_PI_2 - (x - (PIO2_LO - x * arcsin_ratio(x * x)));
    }
    let z = 0.5 * (1.0 - x.abs());
    let s = z.sqrt();
    let r = s * arcsin_ratio(z);
    if x > 0.0 {
        2.0 * (s + r)
    } else {
        2.0 * (FRAC_PI_2 - (s + (r - PIO2_LO)))
    }
}

/// A sinusoid X1 cos τ − X2 sin τ = A cos(τ + α) with its amplitude A = |X| and phase α.
#[derive(Clone, Debug)]
struct Wave {
    x1: f64,
    x2: f64,
    amp: f64,
    /// 1/A (0 for A = 0): levels relative to the amplitude by a product, not a division.
    inv: f64,
    /// α (rad), computed on first use ([`Wave::phase`]; NaN before): the closed form of a cycle
    /// in contact ([`closed_form`]) never needs it.
    alpha: Cell<f64>,
    /// cos α and sin α (1 and 0 for A = 0).
    ca: f64,
    sa: f64,
}

impl Wave {
    fn new(x1: f64, x2: f64) -> Self {
        let amp = (x1 * x1 + x2 * x2).sqrt();
        let (inv, ca, sa) = if amp > 0.0 {
            let inv = 1.0 / amp;
            (inv, x1 * inv, x2 * inv)
        } else {
            (0.0, 1.0, 0.0)
        };
        Wave {
            x1,
            x2,
            amp,
            inv,
            alpha: Cell::new(f64::NAN),
            ca,
            sa,
        }
    }

    /// The phase α (rad, in [−π, π]; 0 for A = 0).
    #[inline]
    fn phase(&self) -> f64 {
        let a = self.alpha.get();
        if !a.is_nan() {
            return a;
        }
        self.first_phase()
    }

    /// [`Wave::phase`] on its first use, out of line (the inline [`angle`] would make every
    /// caller of the phase too large to inline).
    #[inline(never)]
    fn first_phase(&self) -> f64 {
        let a = angle(self.ca, self.sa);
        self.alpha.set(a);
        a
    }

    /// The rate d/dτ at τ.
    #[inline]
    fn rate(&self, a: At) -> f64 {
        -self.x1 * a.s - self.x2 * a.c
    }

    /// The maximum, τ = −α.
    fn maximum(&self) -> At {
        At {
            t: -self.phase(),
            s: -self.sa,
            c: self.ca,
        }
    }

    /// The minimum, τ = π − α.
    fn minimum(&self) -> At {
        At {
            t: PI - self.phase(),
            s: self.sa,
            c: -self.ca,
        }
    }

    /// Where the sinusoid equals A·r (r in [−1, 1]), rising (τ = −α − arccos r) or falling
    /// (τ = −α + arccos r); sin τ and cos τ by the addition theorems.
    fn crossing(&self, r: f64, rising: bool) -> At {
        let arc = Arc::new(r);
        if rising {
            self.rising(arc)
        } else {
            self.falling(arc)
        }
    }

    /// The rising crossing of A·r, τ = −α − β with β = arccos r.
    #[inline]
    fn rising(&self, arc: Arc) -> At {
        let [s, c] = self.rising_sc(arc);
        At {
            t: -self.phase() - arc.b,
            s,
            c,
        }
    }

    /// [sin τ, cos τ] of the rising crossing τ = −α − β of A·r (β = arccos r) by the addition
    /// theorems, without α.
    #[inline]
    fn rising_sc(&self, arc: Arc) -> [f64; 2] {
        let (r, sb) = (arc.r, arc.sb);
        [-(self.sa * r + self.ca * sb), self.ca * r - self.sa * sb]
    }

    /// The falling crossing of A·r, τ = −α + β with β = arccos r.
    #[inline]
    fn falling(&self, arc: Arc) -> At {
        let [s, c] = self.falling_sc(arc);
        At {
            t: arc.b - self.phase(),
            s,
            c,
        }
    }

    /// [sin τ, cos τ] of the falling crossing τ = −α + β of A·r (β = arccos r) by the addition
    /// theorems, without α.
    #[inline]
    fn falling_sc(&self, arc: Arc) -> [f64; 2] {
        let (r, sb) = (arc.r, arc.sb);
        [sb * self.ca - r * self.sa, r * self.ca + sb * self.sa]
    }
}

/// A level r of a sinusoid relative to its amplitude (clamped to [−1, 1]) with β = arccos r
/// (rad) and sin β, shared by the level's rising and falling crossings (one arccos for both).
#[derive(Clone, Copy, Debug)]
struct Arc {
    r: f64,
    b: f64,
    sb: f64,
}

impl Arc {
    /// The arc of the level r (clamped to [−1, 1]) by libm's arccos: in the chains of dependent
    /// events (the contact window, at whose length every boundary of the separation is cut, and
    /// the crossings of the march) its latency is shorter than that of the inline [`arccos`].
    #[inline]
    fn new(r: f64) -> Self {
        let r = r.clamp(-1.0, 1.0);
        Arc::with(r, r.acos())
    }

    /// [`Arc::new`] by the inline [`arccos`], for arcs computed side by side (the two levels'
    /// arcs β_N and β_P of [`closed_form`] and of the separation): without a call, the two
    /// evaluations overlap.
    #[inline(always)]
    fn side_by_side(r: f64) -> Self {
        let r = r.clamp(-1.0, 1.0);
        Arc::with(r, arccos(r))
    }

    /// The arc of the level r in [−1, 1] with β = arccos r given.
    #[inline(always)]
    fn with(r: f64, b: f64) -> Self {
        Arc {
            r,
            b,
            sb: ((1.0 - r) * (1.0 + r)).sqrt(),
        }
    }

    /// The level −r: arccos(−r) = π − arccos r, the same sin β (no inverse function).
    #[inline]
    fn opposite(self) -> Self {
        Arc {
            r: -self.r,
            b: PI - self.b,
            sb: self.sb,
        }
    }
}

/// When the point is in contact over a cycle.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Window {
    /// In contact over the whole cycle.
    Always,
    /// Out of contact over the whole cycle (max n ≤ 0).
    Never,
    /// In contact from the re-contact instant τ_Sp2 (n rising through 0) to the start of
    /// separation τ_Sp1 = τ_Sp2 + `len` (rad): `recontact` and `separation` are [sin, cos] of the
    /// two instants and `unit` = [cos α_V, sin α_V] of k_n v1 = |V| cos(τ + α_V), from which
    /// [`Window::labelled`] forms their angles where the event march needs them.
    Part {
        recontact: [f64; 2],
        separation: [f64; 2],
        len: f64,
        unit: [f64; 2],
    },
}

impl Window {
    /// Whether n(τ) = n0e + k_n v1(τ) stays positive all period because n0e > |k_n V1| (N),
    /// decided on squares: ρ = −n0e/|k_n V1| < −1 (the squares' rounding, ~1e-16, lies well
    /// inside the tangency tolerance of [`Window::of`], which gives the whole period there too).
    #[inline(always)]
    fn always(n0e: f64, [x1, x2]: [f64; 2]) -> bool {
        n0e > 0.0 && n0e * n0e > x1 * x1 + x2 * x2
    }

    /// The contact window of n(τ) = n0e + k_n v1(τ) (N), `nv` = (k_n V1, k_n V2) (N). In
    /// contact all period (n0e > |k_n V1|, decided on squares) it is the whole period without a
    /// square root; otherwise from the sinusoid of k_n v1 (Cigeroglu, An & Menq 2007, §2.2.2):
    /// n < 0 where cos(τ + α_V) < ρ = −n0e/|k_n V1|, so contact is regained at
    /// τ_Sp2 = −α_V − arccos ρ and lasts 2 arccos ρ (one inverse function; the instants' sines
    /// and cosines by the addition theorems, without α_V).
    #[inline(always)]
    fn of(n0e: f64, [x1, x2]: [f64; 2]) -> Window {
        if Window::always(n0e, [x1, x2]) {
            return Window::Always;
        }
        let nv = Wave::new(x1, x2);
        let vamp = nv.amp;
        if n0e + vamp <= 1e-14 * (n0e.abs() + vamp) {
            Window::Never
        } else if vamp > 0.0 {
            let rho = -n0e * nv.inv;
            if rho > -1.0 + TANGENCY {
                let arc = Arc::new(rho);
                Window::Part {
                    recontact: nv.rising_sc(arc),
                    separation: nv.falling_sc(arc),
                    len: 2.0 * arc.b,
                    unit: [nv.ca, nv.sa],
                }
            } else {
                Window::Always
            }
        } else {
            Window::Always
        }
    }

    /// The re-contact and separation instants of a window shorter than the period with the
    /// angles the event march labels them by, τ_Sp2 = −α_V − arccos ρ reduced to [0, 2π) and
    /// τ_Sp1 = τ_Sp2 + len, and the length len (rad); `None` for the other windows.
    fn labelled(&self) -> Option<(At, At, f64)> {
        let Window::Part {
            recontact: [s, c],
            separation: [s1, c1],
            len,
            unit: [ca, sa],
        } = *self
        else {
            return None;
        };
        let t = wrap(-angle(ca, sa) - 0.5 * len);
        Some((
            At { t, s, c },
            At {
                t: t + len,
                s: s1,
                c: c1,
            },
            len,
        ))
    }
}

/// The harmonic motion of a point and its law's parameters, with the derived sinusoids.
#[derive(Clone, Debug)]
struct Motion {
    p: ContactParams,
    u: [f64; 3],
    v: [f64; 3],
    /// n0e = n0 + k_n V0 (N).
    n0e: f64,
    /// g = k_t u1 − μ k_n v1.
    g: Wave,
    /// h = k_t u1 + μ k_n v1.
    h: Wave,
    /// (k_n V1, k_n V2) (N): k_n v1 = k_n V1 cos τ − k_n V2 sin τ.
    nv: [f64; 2],
    window: Window,
}

/// x reduced to [0, 2π) (cheaply for the few periods the construction spans).
#[inline(always)]
fn wrap(x: f64) -> f64 {
    if (0.0..TAU).contains(&x) {
        x
    } else if (-TAU..0.0).contains(&x) {
        x + TAU
    } else if (TAU..2.0 * TAU).contains(&x) {
        x - TAU
    } else {
        x.rem_euclid(TAU)
    }
}

/// How far ahead of `from` the angle `target` (mod 2π) lies, in [0, 2π); an angle less than
/// [`BEHIND`] behind counts as 0.
#[inline(always)]
fn ahead(target: f64, from: f64) -> f64 {
    let d = wrap(target - from);
    if d > TAU - BEHIND {
        0.0
    } else {
        d
    }
}

impl Motion {
    #[inline(always)]
    fn new(p: &ContactParams, u: [f64; 3], v: [f64; 3]) -> Self {
        let (kt, kn, mu) = (p.kt, p.kn, p.mu);
        let n0e = p.n0 + kn * v[0];
        let g = Wave::new(kt * u[1] - mu * kn * v[1], kt * u[2] - mu * kn * v[2]);
        let h = Wave::new(kt * u[1] + mu * kn * v[1], kt * u[2] + mu * kn * v[2]);
        // The phase of k_n v1 is computed only when the point separates.
        let nv = [kn * v[1], kn * v[2]];
        let window = Window::of(n0e, nv);
        Motion {
            p: *p,
            u,
            v,
            n0e,
            g,
            h,
            nv,
            window,
        }
    }

    #[inline]
    fn u_at(&self, a: At) -> f64 {
        self.u[0] + self.u[1] * a.c - self.u[2] * a.s
    }

    /// n0e + k_n v1(τ) (the normal force in contact).
    #[inline]
    fn n_at(&self, a: At) -> f64 {
        self.n0e + self.nv[0] * a.c - self.nv[1] * a.s
    }

    /// The slider position w (m) at the instant `a` in the state `kind`: the stick slider, the
    /// slider a slip drags (w = u ∓ μ n/k_t) or, separated, u.
    fn slider_in(&self, kind: PhaseKind, a: At) -> f64 {
        match kind {
            PhaseKind::Stick { slider, .. } => slider,
            PhaseKind::Separation => self.u_at(a),
            PhaseKind::PositiveSlip => self.u_at(a) - self.p.mu * self.n_at(a) / self.p.kt,
            PhaseKind::NegativeSlip => self.u_at(a) + self.p.mu * self.n_at(a) / self.p.kt,
        }
    }

    /// The state at a re-contact instant (eqs 15–17).
    fn recontact_state(&self, a: At) -> PhaseKind {
        if self.g.rate(a) > 0.0 {
            PhaseKind::PositiveSlip
        } else if self.h.rate(a) < 0.0 {
            PhaseKind::NegativeSlip
        } else {
            PhaseKind::Stick {
                slider: self.u_at(a),
                origin: SliderOrigin::Recontact(a.t),
            }
        }
    }

    /// The state at τ = 0 from the slider w (the first sample of the time-discrete law).
    #[inline(always)]
    fn initial_state(&self, w: f64) -> PhaseKind {
        if self.window == Window::Never {
            return PhaseKind::Separation;
        }
        // (the discriminant first: where the caller knows the window, no call is left)
        if let Window::Part { .. } = self.window {
            if let Some((recontact, _, len)) = self.window.labelled() {
                if ahead(0.0, recontact.t) >= len {
                    return PhaseKind::Separation;
                }
            }
        }
        let z = At::ZERO;
        let n = self.n_at(z).max(0.0);
        let u0 = self.u_at(z);
        let trial = self.p.kt * (u0 - w);
        let limit = self.p.mu * n;
        if trial.abs() <= limit * (1.0 + super::law::STICK_MARGIN) {
            return PhaseKind::Stick {
                slider: w,
                origin: SliderOrigin::Carried,
            };
        }
        let s = trial.signum();
        if s > 0.0 && self.g.rate(z) > 0.0 {
            PhaseKind::PositiveSlip
        } else if s < 0.0 && self.h.rate(z) < 0.0 {
            PhaseKind::NegativeSlip
        } else {
            PhaseKind::Stick {
                slider: u0 - s * limit / self.p.kt,
                origin: SliderOrigin::Clamped(s),
            }
        }
    }

    /// The next event after τ = `t` in state `kind`: (how far ahead, the state after it, the
    /// event's instant).
    #[inline(always)]
    fn next_event(&self, t: f64, kind: PhaseKind) -> (f64, PhaseKind, At) {
        let mut best = (f64::INFINITY, kind, At::ZERO);
        #[inline(always)]
        fn consider(best: &mut (f64, PhaseKind, At), t: f64, a: At, next: PhaseKind) {
            let d = ahead(a.t, t);
            if d < best.0 {
                *best = (d, next, a);
            }
        }
        let unset = f64::NAN;
        match kind {
            PhaseKind::Separation => {
                if let Some((recontact, _, _)) = self.window.labelled() {
                    consider(&mut best, t, recontact, self.recontact_state(recontact));
                }
            }
            PhaseKind::PositiveSlip => {
                if self.g.amp > 0.0 {
                    let tp = self.g.maximum();
                    let next = PhaseKind::Stick {
                        slider: unset,
                        origin: SliderOrigin::AfterPositiveSlip(tp.t),
                    };
                    consider(&mut best, t, tp, next);
                }
            }
            PhaseKind::NegativeSlip => {
                if self.h.amp > 0.0 {
                    let tn = self.h.minimum();
                    let next = PhaseKind::Stick {
                        slider: unset,
                        origin: SliderOrigin::AfterNegativeSlip(tn.t),
                    };
                    consider(&mut best, t, tn, next);
                }
            }
            PhaseKind::Stick { slider, .. } => {
                let offset = self.p.kt * (self.u[0] - slider);
                let mun = self.p.mu * self.n0e;
                // g rises through c_P.
                if self.g.amp > 0.0 {
                    let r = (mun - offset) / self.g.amp;
                    if r < 1.0 - TANGENCY {
                        let a = self.g.crossing(r, true);
                        consider(&mut best, t, a, PhaseKind::PositiveSlip);
                    }
                }
                // h falls through c_N.
                if self.h.amp > 0.0 {
                    let r = (-mun - offset) / self.h.amp;
                    if r > -1.0 + TANGENCY {
                        let a = self.h.crossing(r, false);
                        consider(&mut best, t, a, PhaseKind::NegativeSlip);
                    }
                }
            }
        }
        // Every contact phase also ends at the start of separation.
        if let (Some((_, separation, _)), false) = (
            self.window.labelled(),
            matches!(kind, PhaseKind::Separation),
        ) {
            consider(&mut best, t, separation, PhaseKind::Separation);
        }
        // Fill in the slider of a stick that follows a slip.
        let (d, next, a) = best;
        let next = match next {
            PhaseKind::Stick {
                origin: origin @ SliderOrigin::AfterPositiveSlip(_),
                ..
            } => PhaseKind::Stick {
                slider: self.slider_in(PhaseKind::PositiveSlip, a),
                origin,
            },
            PhaseKind::Stick {
                origin: origin @ SliderOrigin::AfterNegativeSlip(_),
                ..
            } => PhaseKind::Stick {
                slider: self.slider_in(PhaseKind::NegativeSlip, a),
                origin,
            },
            other => other,
        };
        (d, next, a)
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

/// An unused entry of a cycle's phase list.
const NO_PHASE: Phase = Phase {
    kind: PhaseKind::Separation,
    start: 0.0,
    end: 0.0,
    sc: [0.0, 1.0, 0.0, 1.0],
};

/// The periodic cycle of one point (see the module documentation), held inline (no heap).
#[derive(Clone, Copy)]
pub struct Cycle {
    phases: [Phase; MAX_PHASES],
    len: usize,
    /// The regime of the cycle.
    pub regime: CycleRegime,
}

impl PartialEq for Cycle {
    fn eq(&self, other: &Self) -> bool {
        self.phases() == other.phases() && self.regime == other.regime
    }
}

impl std::fmt::Debug for Cycle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Cycle")
            .field("phases", &self.phases())
            .field("regime", &self.regime)
            .finish()
    }
}

impl Cycle {
    fn empty() -> Self {
        Cycle {
            phases: [NO_PHASE; MAX_PHASES],
            len: 0,
            regime: CycleRegime::CompleteStick,
        }
    }

    /// Appends a phase, merged with the last one when the state is the same; false when full.
    fn push(&mut self, ph: Phase) -> bool {
        if let Some(last) = self.len.checked_sub(1).map(|i| &mut self.phases[i]) {
            if same_state(&last.kind, &ph.kind) {
                last.end = ph.end;
                last.sc[2] = ph.sc[2];
                last.sc[3] = ph.sc[3];
                return true;
            }
        }
        if self.len == MAX_PHASES {
            return false;
        }
        self.phases[self.len] = ph;
        self.len += 1;
        true
    }

    /// The phases, contiguous over one period [phases()\[0\].start, phases()\[0\].start + 2π].
    pub fn phases(&self) -> &[Phase] {
        &self.phases[..self.len]
    }

    /// Fraction of the period in each state: (stick, positive slip, negative slip, separation).
    pub fn fractions(&self) -> [f64; 4] {
        let mut out = [0.0; 4];
        for ph in self.phases() {
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
        let phases = self.phases();
        let t0 = phases[0].start;
        let t = t0 + wrap(t - t0);
        phases
            .iter()
            .find(|ph| t <= ph.end)
            .unwrap_or(&phases[phases.len() - 1])
    }

    /// The transitions of the cycle: (τ in [0, 2π), name) with the names of the paper's angles:
    /// `StP`, `SpP` (stick → positive slip, the stick after slip or after re-contact), `P`
    /// (positive slip → stick), `StN`, `SpN`, `N`, `Sp1` (start of separation), `Sp2` (end).
    pub fn transitions(&self) -> Vec<(f64, &'static str)> {
        let phases = self.phases();
        let n = phases.len();
        let mut out = Vec::new();
        if n < 2 {
            return out;
        }
        for i in 0..n {
            let (a, b) = (&phases[i], &phases[(i + 1) % n]);
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

/// The integrals of e(τ) ⊗ e(τ) over a phase [a, b] (or a sum of phases) in the five numbers
/// they depend on linearly, (b − a, Δ sin, Δ cos, Δ(sin cos), Δ sin²) with Δx = x(b) − x(a):
/// summed over the phases of one kind they give that kind's projection
/// ([`PhaseIntegrals::projection`]) at the cost of five additions a phase.
#[derive(Clone, Copy, Debug, Default)]
struct PhaseIntegrals([f64; 5]);

impl PhaseIntegrals {
    /// The phase's five numbers, from the sines and cosines of its ends.
    #[inline]
    fn of(ph: &Phase) -> Self {
        let [sa, ca, sb, cb] = ph.sc;
        PhaseIntegrals::between(ph.start, [sa, ca], ph.end, [sb, cb])
    }

    /// The five numbers of the phase [a, b] (rad) from sin and cos of its ends, `[sin, cos]`.
    #[inline]
    fn between(a: f64, [sa, ca]: [f64; 2], b: f64, [sb, cb]: [f64; 2]) -> Self {
        PhaseIntegrals([
            b - a,
            sb - sa,
            cb - ca,
            sb * cb - sa * ca,
            (sb - sa) * (sb + sa),
        ])
    }

    /// self + k·other.
    #[inline]
    fn add(&mut self, other: &PhaseIntegrals, k: f64) {
        for (a, b) in self.0.iter_mut().zip(&other.0) {
            *a += k * b;
        }
    }

    /// The first column M_k0 of [`PhaseIntegrals::projection`]: p_k ∫ e_k dτ.
    #[inline]
    fn first_column(&self) -> [f64; 3] {
        self.first_column_pi().map(|x| x * FRAC_1_PI)
    }

    /// π M_k0 ([`PhaseIntegrals::first_column`] without the factor 1/π): (∫1/2, ∫cos, ∫(−sin)).
    #[inline(always)]
    fn first_column_pi(&self) -> [f64; 3] {
        let [d, ds, dc, _, _] = self.0;
        [0.5 * d, ds, dc]
    }

    /// M_kl = p_k ∫ e_k e_l dτ with the projection weights p = (1/2π, 1/π, 1/π) of the harmonic
    /// coefficients (F0 = (1/2π)∮f, Re F1 = (1/π)∮f cos τ, Im F1 = −(1/π)∮f sin τ), e(τ) =
    /// (1, cos τ, −sin τ): π M ([`PhaseIntegrals::projection_pi`]) times 1/π.
    #[inline(always)]
    fn projection(&self) -> [[f64; 3]; 3] {
        self.projection_pi().map(|row| row.map(|x| x * FRAC_1_PI))
    }

    /// π M of [`PhaseIntegrals::projection`], for callers that fold 1/π into their own factors:
    /// ∫cos = Δ sin, ∫(−sin) = Δ cos, ∫cos² = d/2 + Δ(sin cos)/2, ∫sin² = d/2 − Δ(sin cos)/2,
    /// ∫cos·(−sin) = −Δ sin²/2, the first row halved.
    #[inline(always)]
    fn projection_pi(&self) -> [[f64; 3]; 3] {
        let [d, ds, dc, dsc, dss] = self.0;
        let ics = -0.5 * dss;
        [
            [0.5 * d, 0.5 * ds, 0.5 * dc],
            [ds, 0.5 * (d + dsc), ics],
            [dc, ics, 0.5 * (d - dsc)],
        ]
    }
}

/// The periodic cycle of a point with the harmonic motion u, v (layout (X0, Re X1, Im X1), m)
/// and the slider state `slider` (m) at τ = 0.
pub fn cycle(p: &ContactParams, u: [f64; 3], v: [f64; 3], slider: f64) -> Result<Cycle> {
    let mut out = Cycle::empty();
    out.regime = build(&Motion::new(p, u, v), slider, &mut |ph| out.push(*ph))?;
    Ok(out)
}

/// Builds the periodic cycle of `mo` from the slider state `slider` and hands its phases, in
/// order over one period, to `sink` (which returns false to stop: too many phases). Every phase
/// starts at the instant its state was entered (for a stick phase: where its slider was set).
/// Returns the regime.
fn build(mo: &Motion, slider: f64, sink: &mut impl FnMut(&Phase) -> bool) -> Result<CycleRegime> {
    let z = At::ZERO;
    if mo.window == Window::Never {
        sink(&Phase::whole(PhaseKind::Separation, z));
        return Ok(CycleRegime::AlwaysSeparated);
    }
    if mo.p.kt <= 0.0 {
        // No tangential stiffness: f ≡ 0; only the contact window matters.
        let stick = PhaseKind::Stick {
            slider,
            origin: SliderOrigin::Carried,
        };
        return Ok(match mo.window.labelled() {
            Some((recontact, separation, _)) => {
                let _ = sink(&Phase::new(stick, recontact, separation))
                    && sink(&Phase::new(
                        PhaseKind::Separation,
                        separation,
                        recontact.labelled(recontact.t + TAU),
                    ));
                CycleRegime::Separation
            }
            _ => {
                sink(&Phase::whole(stick, z));
                CycleRegime::CompleteStick
            }
        });
    }
    // A history-free start known in closed form: the re-contact (separation), or the end of
    // positive slip at the maximum of g (stick–slip without separation, 2μ n0e < |G| + |H|,
    // eq. 19); else (complete stick, or a degenerate sinusoid) the transient march below.
    let known = match mo.window.labelled() {
        Some((recontact, _, _)) => Some((recontact, mo.recontact_state(recontact))),
        _ if mo.g.amp > 0.0
            && mo.h.amp > 0.0
            && 2.0 * mo.p.mu * mo.n0e < (mo.g.amp + mo.h.amp) * (1.0 - 1e-9) =>
        {
            let tp = mo.g.maximum();
            let tp = tp.labelled(wrap(tp.t));
            Some((
                tp,
                PhaseKind::Stick {
                    slider: mo.u_at(tp) - mo.p.mu * mo.n_at(tp) / mo.p.kt,
                    origin: SliderOrigin::AfterPositiveSlip(tp.t),
                },
            ))
        }
        _ => None,
    };
    // Transient: from τ = 0 until the first history-free event (at most two periods).
    let (mut start, mut kind) = match known {
        Some((a, k)) => (Some(a), k),
        None => (None, mo.initial_state(slider)),
    };
    if start.is_none() {
        let mut t = 0.0;
        for _ in 0..MAX_EVENTS {
            let (d, next, a) = mo.next_event(t, kind);
            if t + d > 2.0 * TAU {
                break;
            }
            let free = history_free(kind, next);
            t += d;
            kind = next;
            if free {
                start = Some(a.labelled(t));
                break;
            }
        }
    }
    let Some(a0) = start else {
        // No slip and no separation: stuck over the whole cycle with the state at τ = 0.
        if let PhaseKind::Stick { .. } = kind {
            sink(&Phase::whole(mo.initial_state(slider), z));
            return Ok(CycleRegime::CompleteStick);
        }
        return Err(Error::Compute(format!(
            "analytic friction point: no periodic state reached (u = {:?}, v = {:?}, {:?})",
            mo.u, mo.v, mo.p
        )));
    };
    // One period from the history-free event.
    let end = a0.labelled(a0.t + TAU);
    let mut cur = a0;
    let mut closed = false;
    let mut slips = false;
    for _ in 0..MAX_EVENTS {
        let (d, next, a) = mo.next_event(cur.t, kind);
        slips |= matches!(kind, PhaseKind::PositiveSlip | PhaseKind::NegativeSlip);
        if cur.t + d >= end.t - BEHIND {
            closed = sink(&Phase::new(kind, cur, end));
            break;
        }
        let at = a.labelled(cur.t + d);
        if d > 0.0 && !sink(&Phase::new(kind, cur, at)) {
            break;
        }
        cur = at;
        kind = next;
    }
    if !closed {
        return Err(Error::Compute(format!(
            "analytic friction point: more than {MAX_PHASES} phases or {MAX_EVENTS} transitions in one cycle (u = {:?}, v = {:?}, {:?})",
            mo.u, mo.v, mo.p
        )));
    }
    Ok(if matches!(mo.window, Window::Part { .. }) {
        CycleRegime::Separation
    } else if slips {
        CycleRegime::StickSlip
    } else {
        CycleRegime::CompleteStick
    })
}

fn same_state(a: &PhaseKind, b: &PhaseKind) -> bool {
    match (a, b) {
        (PhaseKind::Stick { slider: x, .. }, PhaseKind::Stick { slider: y, .. }) => x == y,
        _ => std::mem::discriminant(a) == std::mem::discriminant(b),
    }
}

/// ∂w/∂(U0, U1, U2, V0, V1, V2, n0) of a stick phase's slider in the form every origin shares,
/// ∂w = e·∂U + r (k_n e·∂V + ∂n0), returned as (e, r) (r in m/N); `at` is the instant the slider
/// was set (the start of the stick phase). A carried slider has e = 0 and r = 0.
fn slider_derivative(mo: &Motion, origin: SliderOrigin, at: At) -> ([f64; 3], f64) {
    let (kt, kn, mu) = (mo.p.kt, mo.p.kn, mo.p.mu);
    // w = u(τ) − s μ (n0 + k_n v(τ))/k_t at a fixed τ (or at an extremum of g or h, where the
    // τ-derivative vanishes).
    let at_limit = |a: At, s: f64| (a.basis(), -s * mu / kt);
    match origin {
        SliderOrigin::Carried => ([0.0; 3], 0.0),
        SliderOrigin::Clamped(s) => at_limit(At::ZERO, s),
        SliderOrigin::AfterPositiveSlip(_) => at_limit(at, 1.0),
        SliderOrigin::AfterNegativeSlip(_) => at_limit(at, -1.0),
        SliderOrigin::Recontact(_) => {
            // w = u(τ_Sp2), with n0 + k_n v(τ_Sp2) = 0:
            // ∂τ = −(∂n0 + k_n e·∂V)/(k_n v1′(τ)), ∂w = e·∂U + u1′(τ) ∂τ.
            let de = at.basis_rate();
            let dv = kn * (mo.v[1] * de[1] + mo.v[2] * de[2]);
            let r = if dv.abs() > 0.0 {
                -(mo.u[1] * de[1] + mo.u[2] * de[2]) / dv
            } else {
                0.0
            };
            (at.basis(), r)
        }
    }
}

/// The harmonic results of one point without its cycle.
#[derive(Default)]
struct Harmonics {
    friction: [f64; 3],
    normal: [f64; 3],
    energy: f64,
    slider: f64,
}

/// ∂(F0, Re F1, Im F1, N0, Re N1, Im N1)/∂(U0, U1, U2, V0, V1, V2, n0) of one point: the local
/// Jacobian in the element's layout for one tangential direction (rows 0–2 friction, 3–5
/// normal; ∂N/∂U = 0). The evaluations that fill it write every entry.
type PointJacobian = [[f64; 7]; 6];

impl Harmonics {
    /// Complete stick with the slider w (m) kept (eq. 19) into `out`: f = k_t (u − w) and
    /// n = n0e + k_n v1 at every instant, so F = k_t (U0 − w, U1, U2), N = (n0e, k_n V1, k_n V2),
    /// no energy, and the Jacobian is k_t on (F, U), k_n on (N, V) and 1 on (N0, n0).
    #[inline(always)]
    fn stuck(mo: &Motion, w: f64, jac: Option<&mut PointJacobian>, out: &mut Harmonics) {
        let (kt, kn) = (mo.p.kt, mo.p.kn);
        let u = mo.u;
        out.friction = [kt * (u[0] - w), kt * u[1], kt * u[2]];
        out.normal = [mo.n0e, mo.nv[0], mo.nv[1]];
        out.energy = PI * (u[1] * out.friction[2] - u[2] * out.friction[1]);
        out.slider = w;
        if let Some(j) = jac {
            let [n0, n1, n2] = contact_rows(kn);
            *j = [
                [kt, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, kt, 0.0, 0.0, 0.0, 0.0, 0.0],
                [0.0, 0.0, kt, 0.0, 0.0, 0.0, 0.0],
                n0,
                n1,
                n2,
            ];
        }
    }
}

/// The normal rows of a point's Jacobian ([`PointJacobian`]) in contact over the whole cycle:
/// n = n0e + k_n v1 at every instant, so ∂N = k_n ∂V and ∂N0/∂n0 = 1 (k_n in N/m).
#[inline]
fn contact_rows(kn: f64) -> [[f64; 7]; 3] {
    [
        [0.0, 0.0, 0.0, kn, 0.0, 0.0, 1.0],
        [0.0, 0.0, 0.0, 0.0, kn, 0.0, 0.0],
        [0.0, 0.0, 0.0, 0.0, 0.0, kn, 0.0],
    ]
}

/// The phase integrals of a cycle summed per kind, with what the stick sliders add: the
/// running sums of [`harmonics`] over the phases of the event march, turned into the harmonic
/// results by [`PhaseSums::finish`].
///
/// On every phase f = c·e(τ) with c constant, so each coefficient is Σ_phases M(phase)·c with
/// M linear in five integrals of the phase ([`PhaseIntegrals`], summed per kind before M is
/// formed): with M_stick, M_slip (signed by the slip direction) and M_contact the sums over the
/// phases of each kind, F = k_t (M_stick U − Σ_stick w M_·0) + μ M_slip N and
/// N = M_contact N with N = (n0e, k_n V1, k_n V2); the derivatives follow from the same sums and
/// the stick sliders' derivatives ([`slider_derivative`]).
#[derive(Clone, Copy, Debug, Default)]
struct PhaseSums {
    stick: PhaseIntegrals,
    positive: PhaseIntegrals,
    negative: PhaseIntegrals,
    /// Σ_stick w (d, Δ sin, Δ cos) of the stick phases.
    w_int: [f64; 3],
    /// Σ_stick M_·0 ⊗ e and Σ_stick r M_·0 ⊗ e of the sliders' derivatives ∂w = e·∂U +
    /// r (k_n e·∂V + ∂n0) ([`slider_derivative`]; e_0 = 1, so the ∂n0 column is w_v's first).
    w_u: [[f64; 3]; 3],
    w_v: [[f64; 3]; 3],
    /// Whether a phase of separation was added (else the contact covers the whole period).
    separates: bool,
}

impl PhaseSums {
    /// Adds one phase of the cycle (with its slider's derivative if `jacobian`).
    #[inline]
    fn add(&mut self, mo: &Motion, ph: &Phase, jacobian: bool) {
        match ph.kind {
            PhaseKind::Separation => self.separates = true,
            PhaseKind::PositiveSlip => self.positive.add(&PhaseIntegrals::of(ph), 1.0),
            PhaseKind::NegativeSlip => self.negative.add(&PhaseIntegrals::of(ph), 1.0),
            PhaseKind::Stick { slider: w, origin } => {
                let at = At {
                    t: ph.start,
                    s: ph.sc[0],
                    c: ph.sc[1],
                };
                let jacobian = jacobian && origin != SliderOrigin::Carried;
                self.add_stick(mo, &PhaseIntegrals::of(ph), w, origin, at, jacobian);
            }
        }
    }

    /// Adds the integrals `i` of stick phases with the slider w (m) set at `at` as `origin`
    /// says and, if `jacobian`, the slider's derivative ([`slider_derivative`]).
    #[inline]
    fn add_stick(
        &mut self,
        mo: &Motion,
        i: &PhaseIntegrals,
        w: f64,
        origin: SliderOrigin,
        at: At,
        jacobian: bool,
    ) {
        self.stick.add(i, 1.0);
        for (a, b) in self.w_int.iter_mut().zip(&i.0[..3]) {
            *a += w * b;
        }
        if jacobian {
            let (e, r) = slider_derivative(mo, origin, at);
            let m0 = i.first_column();
            for (k, &mk) in m0.iter().enumerate() {
                for (l, &el) in e.iter().enumerate() {
                    let t = mk * el;
                    self.w_u[k][l] += t;
                    self.w_v[k][l] += r * t;
                }
            }
        }
    }

    /// The harmonic results from the sums into `out` and, if given, the Jacobian into `jac`, with
    /// `at_zero` the state at τ ≡ 0 (mod 2π) for the end slider state.
    fn finish(
        &self,
        mo: &Motion,
        at_zero: PhaseKind,
        mut jac: Option<&mut PointJacobian>,
        out: &mut Harmonics,
    ) {
        let (kt, kn, mu) = (mo.p.kt, mo.p.kn, mo.p.mu);
        let u = mo.u;
        let m_stick = self.stick.projection();
        let mut slip = self.positive;
        slip.add(&self.negative, -1.0);
        let m_slip = slip.projection();
        let w_col =
            PhaseIntegrals([self.w_int[0], self.w_int[1], self.w_int[2], 0.0, 0.0]).first_column();
        let cn = [mo.n0e, mo.nv[0], mo.nv[1]];
        let Harmonics {
            friction, normal, ..
        } = out;
        for k in 0..3 {
            friction[k] = kt * (dot(m_stick[k], u) - w_col[k]) + mu * dot(m_slip[k], cn);
            if let Some(j) = jac.as_deref_mut() {
                let fj = &mut j[k];
                for l in 0..3 {
                    fj[l] = kt * (m_stick[k][l] - self.w_u[k][l]);
                    fj[3 + l] = kn * (mu * m_slip[k][l] - kt * self.w_v[k][l]);
                }
                fj[6] = mu * m_slip[k][0] - kt * self.w_v[k][0];
            }
        }
        if self.separates {
            let mut contact = self.stick;
            contact.add(&self.positive, 1.0);
            contact.add(&self.negative, 1.0);
            let m_contact = contact.projection();
            for k in 0..3 {
                normal[k] = dot(m_contact[k], cn);
                if let Some(j) = jac.as_deref_mut() {
                    let nj = &mut j[3 + k];
                    nj[..3].fill(0.0);
                    for l in 0..3 {
                        nj[3 + l] = kn * m_contact[k][l];
                    }
                    nj[6] = m_contact[k][0];
                }
            }
        } else {
            // In contact all period M_contact is the identity (the projection of e over a
            // period): the normal force and its rows as in complete stick.
            *normal = cn;
            if let Some(j) = jac {
                [j[3], j[4], j[5]] = contact_rows(kn);
            }
        }
        out.energy = PI * (u[1] * out.friction[2] - u[2] * out.friction[1]);
        out.slider = mo.slider_in(at_zero, At::ZERO);
    }
}

/// Builds the cycle of `mo` from `slider` ([`build`]; each phase is also handed to `keep`) and
/// integrates the forces over it ([`PhaseSums`]).
fn harmonics(
    mo: &Motion,
    slider: f64,
    jac: Option<&mut PointJacobian>,
    mut keep: impl FnMut(&Phase) -> bool,
) -> Result<(Harmonics, CycleRegime)> {
    let jacobian = jac.is_some();
    let mut sums = PhaseSums::default();
    // The state at τ ≡ 0 (mod 2π): the first phase that ends at or after it.
    let mut zero = f64::NAN;
    let mut at_zero = None;
    let regime = build(mo, slider, &mut |ph: &Phase| {
        if zero.is_nan() {
            zero = ph.start + wrap(-ph.start);
        }
        if at_zero.is_none() && ph.end >= zero {
            at_zero = Some(ph.kind);
        }
        sums.add(mo, ph, jacobian);
        keep(ph)
    })?;
    let at_zero = at_zero.unwrap_or(PhaseKind::Separation);
    let mut out = Harmonics::default();
    sums.finish(mo, at_zero, jac, &mut out);
    Ok((out, regime))
}

/// The harmonics of a point into `out` in closed form where the sequence of its cycle's phases
/// follows from the amplitudes alone, without the event march of [`build`] (which gives the same
/// phases to rounding); false where the march is needed (separation, a degenerate sinusoid, a start
/// outside the friction cone). In contact over the whole cycle, with c_P and c_N as in the
/// module documentation:
/// * complete stick (eq. 19): the caller's slider w inside the friction cone at τ = 0, and
///   neither g rising through c_P nor h falling through c_N with that slider — one stick phase
///   with the slider kept;
/// * stick–slip (§2.2.1, 2μ n0e < |G| + |H|): four phases from the end of positive slip at the
///   maximum of g, τ_P = −α_G: stick with w_P = u(τ_P) − μ n(τ_P)/k_t until h falls through
///   c_N = |G| − 2μ n0e at τ_StN = −α_H + arccos(c_N/|H|) (eqs 12, 24), negative slip until the
///   minimum of h at τ_N = π − α_H (eqs 9, 22), stick with w_N = u(τ_N) + μ n(τ_N)/k_t until g
///   rises through c_P = 2μ n0e − |H| at τ_StP = −α_G − arccos(c_P/|G|) (eqs 11, 23), positive
///   slip until τ_P + 2π (eqs 8, 21). After the end of a slip the point cannot slip the same way
///   again before slipping the other way (g ≤ g(τ_P) = c_P after τ_P), so no other sequence
///   exists; the two arccosines depend on the amplitudes only, not on a previous event.
///
/// No phase angle α_G, α_H is formed: the phase lengths follow from the two arccosines and the
/// relative phase δ = α_H − α_G ([`stick_slip_lengths`]; one inverse function at constant load,
/// three with load variation), the ends' sines and cosines from the addition theorems, the
/// phase holding τ ≡ 0 from their signs ([`phase_of_zero`]), and the forces and Jacobian from
/// the integrals of the phases ([`stick_slip_forces`]).
#[inline(always)]
fn closed_form(
    mo: &Motion,
    slider: f64,
    jac: Option<&mut PointJacobian>,
    out: &mut Harmonics,
) -> bool {
    if mo.window != Window::Always || mo.p.kt <= 0.0 {
        return false;
    }
    let mun = mo.p.mu * mo.n0e;
    let (g, h) = (&mo.g, &mo.h);
    if !(g.amp > 0.0 && h.amp > 0.0 && 2.0 * mun < (g.amp + h.amp) * (1.0 - 1e-9)) {
        // The march of `build` from τ = 0: stuck over the whole cycle iff it starts in stick
        // with the caller's slider and neither slip condition is reached.
        let kind = mo.initial_state(slider);
        let PhaseKind::Stick {
            slider: w,
            origin: SliderOrigin::Carried,
        } = kind
        else {
            return false;
        };
        let offset = mo.p.kt * (mo.u[0] - w);
        let positive = g.amp > 0.0 && (mun - offset) / g.amp < 1.0 - TANGENCY;
        let negative = h.amp > 0.0 && (-mun - offset) / h.amp > -1.0 + TANGENCY;
        if positive || negative {
            return false;
        }
        Harmonics::stuck(mo, w, jac, out);
        return true;
    }
    // c_N/|H| and c_P/|G|; at constant load one sinusoid, c_P/|G| = −c_N/|H| and δ = 0
    let arc_n = Arc::side_by_side((g.amp - 2.0 * mun) * h.inv);
    let constant_load = g.x1 == h.x1 && g.x2 == h.x2;
    let arc_p = if constant_load {
        arc_n.opposite()
    } else {
        Arc::side_by_side((2.0 * mun - h.amp) * g.inv)
    };
    let Some(lengths) = stick_slip_lengths(g, h, arc_n, arc_p, constant_load) else {
        return false;
    };
    let ends = sequence_ends(g, h, arc_n, arc_p);
    let Some(zero) = phase_of_zero(&ends, &lengths) else {
        return false;
    };
    let [p, stn, n, stp] = ends;
    // (sin, cos, sin cos, sin²) at each end: a phase's integrals are their differences
    // ([`PhaseIntegrals`]); the sticks [τ_P, τ_StN] and [τ_N, τ_StP] sum to
    // (τ_StN − τ_N) − (τ_P − τ_StP), the slips [τ_StP, τ_P] − [τ_StN, τ_N] to their sum
    let x = |[s, c]: [f64; 2]| [s, c, s * c, s * s];
    let (xp, xstn, xn, xstp) = (x(p), x(stn), x(n), x(stp));
    let d_n: [f64; 4] = std::array::from_fn(|k| xstn[k] - xn[k]);
    let d_p: [f64; 4] = std::array::from_fn(|k| xp[k] - xstp[k]);
    let [l_p, l_neg, l_n, l_pos] = lengths;
    let [dn0, dn1, dn2, dn3] = d_n;
    let [dp0, dp1, dp2, dp3] = d_p;
    let sums = [
        PhaseIntegrals([l_p + l_n, dn0 - dp0, dn1 - dp1, dn2 - dp2, dn3 - dp3]),
        PhaseIntegrals([l_pos - l_neg, dn0 + dp0, dn1 + dp1, dn2 + dp2, dn3 + dp3]),
        PhaseIntegrals([l_p, xstn[0] - xp[0], xstn[1] - xp[1], 0.0, 0.0]),
        PhaseIntegrals([l_n, xstp[0] - xn[0], xstp[1] - xn[1], 0.0, 0.0]),
    ];
    stick_slip_forces(mo, sums, [p, n], jac, out);
    // the slider state at τ ≡ 0: the stick's slider w = u(τ) ∓ μ n(τ)/k_t set where the slip
    // before it ended, or the one the slip drags
    let (at, sign) = match zero {
        0 => (p, -1.0),
        1 => ([0.0, 1.0], 1.0),
        2 => (n, 1.0),
        _ => ([0.0, 1.0], -1.0),
    };
    let at = At {
        t: f64::NAN,
        s: at[0],
        c: at[1],
    };
    out.slider = mo.u_at(at) + sign * mo.p.mu / mo.p.kt * mo.n_at(at);
    true
}

/// The friction and normal forces, the energy and, if given, the Jacobian of a stick–slip cycle
/// in contact ([`closed_form`]) into `out` and `jac`, from the integrals of its phases
/// ([`PhaseIntegrals`]: the two sticks' sum, positive minus negative slip, the stick after
/// positive slip and the stick after negative slip, of the last two the first three numbers) and
/// `[sin, cos]` of the instants τ_P, τ_N where the slips end.
///
/// With M(·) the projection of a sum of phases ([`PhaseIntegrals::projection`]), m_P, m_N the
/// first columns of the two sticks' projections and e_P = e(τ_P), e_N = e(τ_N), the sticks'
/// sliders w_P = e_P·U − (μ/k_t) e_P·N and w_N = e_N·U + (μ/k_t) e_N·N (N = (n0e, k_n V1,
/// k_n V2), N) make the force of [`PhaseSums::finish`],
/// F = k_t (M_stick U − w_P m_P − w_N m_N) + μ M_slip N, linear in U and N: F = k_t A U + μ B N
/// with A = M_stick − m_P ⊗ e_P − m_N ⊗ e_N and B = M_slip + m_P ⊗ e_P − m_N ⊗ e_N (3 × 3,
/// dimensionless). The phase ends depend on ratios of the amplitudes only and the force is
/// continuous at them, so ∂F/∂U = k_t A (N/m), ∂F/∂V = μ k_n B (N/m) and ∂F/∂n0 = μ B_·0 (the
/// derivatives of [`slider_derivative`] summed; Cigeroglu, An & Menq 2007, eq. 29). A_·0 = 0:
/// M_stick's first column is m_P + m_N, so F does not depend on U0. In contact all period N and
/// its rows are those of complete stick.
#[inline(always)]
fn stick_slip_forces(
    mo: &Motion,
    [stick, slip, i_p, i_n]: [PhaseIntegrals; 4],
    [[s_p, c_p], [s_n, c_n]]: [[f64; 2]; 2],
    jac: Option<&mut PointJacobian>,
    out: &mut Harmonics,
) {
    let (kt, kn, mu) = (mo.p.kt, mo.p.kn, mo.p.mu);
    let (m_stick, m_slip) = (stick.projection(), slip.projection());
    let (m_p, m_n) = (i_p.first_column(), i_n.first_column());
    let (e_p, e_n) = ([1.0, c_p, -s_p], [1.0, c_n, -s_n]);
    // k_t A and μ B, row by row
    let mut ka = [[0.0; 3]; 3];
    let mut mb = [[0.0; 3]; 3];
    for k in 0..3 {
        for l in 0..3 {
            let (t_p, t_n) = (m_p[k] * e_p[l], m_n[k] * e_n[l]);
            if l > 0 {
                ka[k][l] = kt * (m_stick[k][l] - t_p - t_n);
            }
            mb[k][l] = mu * (m_slip[k][l] + t_p - t_n);
        }
    }
    let (u, cn) = (mo.u, [mo.n0e, mo.nv[0], mo.nv[1]]);
    for k in 0..3 {
        out.friction[k] = dot(ka[k], u) + dot(mb[k], cn);
    }
    out.normal = cn;
    out.energy = PI * (u[1] * out.friction[2] - u[2] * out.friction[1]);
    if let Some(j) = jac {
        for k in 0..3 {
            let [a, b] = [ka[k], mb[k]];
            j[k] = [a[0], a[1], a[2], kn * b[0], kn * b[1], kn * b[2], b[0]];
        }
        [j[3], j[4], j[5]] = contact_rows(kn);
    }
}

/// [sin, cos] of the ends of the four phases of the stick–slip sequence (Cigeroglu, An & Menq
/// 2007, §2.2.1), by the addition theorems from the phases of g and h and the levels' arcs
/// β_N = arccos(c_N/|H|) (`arc_n`), β_P = arccos(c_P/|G|) (`arc_p`), without α_G, α_H: the
/// maximum of g τ_P = −α_G (eq. 8), h falling through c_N at τ_StN = −α_H + β_N (eq. 24), the
/// minimum of h τ_N = π − α_H (eq. 9) and g rising through c_P at τ_StP = −α_G − β_P (eq. 23).
#[inline(always)]
fn sequence_ends(g: &Wave, h: &Wave, arc_n: Arc, arc_p: Arc) -> [[f64; 2]; 4] {
    [
        [-g.sa, g.ca],
        h.falling_sc(arc_n),
        [h.sa, -h.ca],
        g.rising_sc(arc_p),
    ]
}

/// The lengths (rad) of the four phases of the stick–slip sequence ([`sequence_ends`]; phase i
/// runs from end i to end i + 1) from the levels' arccosines β_N = arccos(c_N/|H|) (`arc_n`),
/// β_P = arccos(c_P/|G|) (`arc_p`) and the relative phase δ = α_H − α_G of h and g: stick after
/// positive slip τ_StN − τ_P = β_N − δ, negative slip τ_N − τ_StN = π − β_N, stick after
/// negative slip τ_StP − τ_N = δ − β_P − π, positive slip τ_P − τ_StP = β_P (each mod 2π; an
/// angle less than [`BEHIND`] below a whole period is 0, as in the event march). δ is one
/// inverse function of the cross and dot products of the phases' unit vectors (cos δ =
/// cos α_G cos α_H + sin α_G sin α_H), none at constant load, where δ = 0 and β_P = π − β_N make
/// both sticks β_N long.
#[inline(always)]
fn sequence_lengths(g: &Wave, h: &Wave, arc_n: Arc, arc_p: Arc, constant_load: bool) -> [f64; 4] {
    let (stick_p, stick_n) = if constant_load {
        (arc_n.b, arc_n.b)
    } else {
        let delta = angle(g.ca * h.ca + g.sa * h.sa, g.ca * h.sa - g.sa * h.ca);
        (
            ahead(arc_n.b - delta, 0.0),
            ahead(delta - arc_p.b - PI, 0.0),
        )
    };
    [stick_p, PI - arc_n.b, stick_n, arc_p.b]
}

/// The lengths (rad) of the four phases of a stick–slip cycle in contact ([`closed_form`],
/// [`sequence_lengths`]); `None` where they do not add up to one period (to 1e-9): the sequence
/// is not the four phases.
#[inline(always)]
fn stick_slip_lengths(
    g: &Wave,
    h: &Wave,
    arc_n: Arc,
    arc_p: Arc,
    constant_load: bool,
) -> Option<[f64; 4]> {
    let lengths = sequence_lengths(g, h, arc_n, arc_p, constant_load);
    let three = lengths[0] + lengths[1] + lengths[2];
    (three < TAU && (three + lengths[3] - TAU).abs() < 1e-9).then_some(lengths)
}

/// Which of the four phases of a stick–slip cycle ([`closed_form`]: `ends` [sin, cos] of the
/// phase starts τ_P, τ_StN, τ_N, τ_StP, the phase i running from ends\[i\] over `lengths`\[i\])
/// holds τ ≡ 0 (mod 2π), by the signs of the ends' sines (no angle): a phase of length ≤ π holds
/// it iff it runs from the lower half-plane (sin ≤ 0) to the upper one (sin ≥ 0) through
/// cos > 0 (cos a + cos b ≥ 0), a longer one iff its complement does not (sin b < 0 and
/// sin a > 0). The first phase that holds it (at a boundary both neighbours give the same slider
/// state); `None` if none does by rounding at a boundary (the caller then marches).
#[inline(always)]
fn phase_of_zero(ends: &[[f64; 2]; 4], lengths: &[f64; 4]) -> Option<usize> {
    let holds = |i: usize, j: usize| {
        let ([sa, ca], [sb, cb]) = (ends[i], ends[j]);
        if lengths[i] <= PI {
            sa <= 0.0 && sb >= 0.0 && ca + cb >= 0.0
        } else {
            !(sb < 0.0 && sa > 0.0)
        }
    };
    if holds(0, 1) {
        Some(0)
    } else if holds(1, 2) {
        Some(1)
    } else if holds(2, 3) {
        Some(2)
    } else if holds(3, 0) {
        Some(3)
    } else {
        None
    }
}

/// An error unless the motion and the slider state are finite: one test of Σ x·0, which is 0 for
/// finite x and NaN as soon as one x is infinite or NaN.
#[inline(always)]
fn check_finite(u: &[f64; 3], v: &[f64; 3], slider: f64) -> Result<()> {
    let zero = (u[0] * 0.0 + u[1] * 0.0 + u[2] * 0.0)
        + (v[0] * 0.0 + v[1] * 0.0 + v[2] * 0.0)
        + slider * 0.0;
    if zero == 0.0 {
        Ok(())
    } else {
        Err(non_finite(*u, *v, slider))
    }
}

/// The error of [`check_finite`], out of line: the motion is then never stored to memory for
/// its message on the path that does not fail.
#[cold]
#[inline(never)]
fn non_finite(u: [f64; 3], v: [f64; 3], slider: f64) -> Error {
    Error::Compute(format!(
        "analytic friction point: non-finite input u = {u:?}, v = {v:?}, slider = {slider}"
    ))
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
    check_finite(&u, &v, slider)?;
    let mut cycle = Cycle::empty();
    let mut j: PointJacobian = [[0.0; 7]; 6];
    let jac = jacobian.then_some(&mut j);
    let (r, regime) = harmonics(&Motion::new(p, u, v), slider, jac, |ph| cycle.push(*ph))?;
    cycle.regime = regime;
    Ok(PointResult {
        friction: r.friction,
        normal: r.normal,
        energy: r.energy,
        slider: r.slider,
        cycle,
        friction_jacobian: jacobian.then_some([j[0], j[1], j[2]]),
        normal_jacobian: jacobian.then_some([j[3], j[4], j[5]]),
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
    let (s, c) = t.sin_cos();
    let a = At { t, s, c };
    let ut = mo.u_at(a);
    let n = mo.n_at(a).max(0.0);
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
#[inline]
pub(crate) fn evaluate_element(
    element: &super::element::LocalElement,
    harmonics_count: usize,
    x: &[f64],
    slider: &mut [f64; 2],
    force: &mut [f64],
    jacobian: bool,
    ws: &mut super::element::Workspace,
) -> Result<()> {
    if element.variant != super::law::Variant::OneD || harmonics_count != 1 {
        return Err(unsupported(element, harmonics_count));
    }
    if let (1, true, Ok(x), Ok(force)) = (
        element.tangential,
        element.normal,
        <&[f64; 6]>::try_from(x),
        <&mut [f64; 6]>::try_from(&mut *force),
    ) {
        return evaluate_one_direction(&element.params, x, slider, force, jacobian, ws);
    }
    evaluate_directions(element, x, slider, force, jacobian, ws)
}

/// The error for an element or a harmonic count the exact cycle does not evaluate: the 2-D law,
/// or H ≠ 1.
#[cold]
#[inline(never)]
fn unsupported(element: &super::element::LocalElement, harmonics_count: usize) -> Error {
    if element.variant != super::law::Variant::OneD {
        return Error::input(
            "evaluation = \"analytic\" is the exact cycle of the 1-D friction law; the 2-D (Coulomb disc) element is evaluated by the AFT only (evaluation = \"aft\")",
        );
    }
    Error::input(format!(
        "evaluation = \"analytic\" is the exact single-harmonic cycle and needs harmonics = 1 (here H = {harmonics_count}); use evaluation = \"aft\" for H > 1"
    ))
}

/// [`evaluate_element`] for the layouts other than [`evaluate_one_direction`]'s: two tangential
/// directions (independent points sharing the normal motion) or no normal direction.
#[inline(never)]
fn evaluate_directions(
    element: &super::element::LocalElement,
    x: &[f64],
    slider: &mut [f64; 2],
    force: &mut [f64],
    jacobian: bool,
    ws: &mut super::element::Workspace,
) -> Result<()> {
    // the 1-D law and H = 1 are checked by the caller, the layout here
    element.check()?;
    let nt = element.tangential;
    let v = if element.normal {
        [x[nt * 3], x[nt * 3 + 1], x[nt * 3 + 2]]
    } else {
        [0.0; 3]
    };
    let cols = element.signals() * 3 + 1;
    // every entry is written below (`write_jacobian`): no zeroing
    let jac: &mut [f64] = if jacobian {
        ws.analytic_jacobian_buffer(element.signals() * 3, cols)
    } else {
        &mut []
    };
    let mut u_all = [[0.0; 3]; 2];
    let slider_in = *slider;
    let mut r = Harmonics::default();
    let mut energy = 0.0;
    for d in 0..nt {
        let u = [x[d * 3], x[d * 3 + 1], x[d * 3 + 2]];
        check_finite(&u, &v, slider[d])?;
        u_all[d] = u;
        let p = &element.params;
        let motion = [u[0], u[1], u[2], v[0], v[1], v[2]];
        if !jacobian {
            point(p, &motion, slider[d], None, &mut r)?;
        } else {
            let mut j: PointJacobian = [[0.0; 7]; 6];
            point(p, &motion, slider[d], Some(&mut j), &mut r)?;
            write_jacobian(element, d, &j, jac, cols);
        }
        slider[d] = r.slider;
        energy += r.energy;
        force[d * 3..d * 3 + 3].copy_from_slice(&r.friction);
        if element.normal && d == 0 {
            force[nt * 3..nt * 3 + 3].copy_from_slice(&r.normal);
        }
    }
    ws.set_analytic(super::element::AnalyticPeriod {
        params: element.params,
        tangential: nt,
        u: u_all,
        v,
        slider: slider_in,
        energy,
    });
    Ok(())
}

/// One point's harmonics into `out` and, if given, its Jacobian into `jac`, for the motion
/// `x` = (U0, U1, U2, V0, V1, V2) (m): the closed forms where they apply ([`separation_form`],
/// [`closed_form`]), else the event march ([`harmonics`]).
#[inline(always)]
fn point(
    p: &ContactParams,
    x: &[f64; 6],
    slider: f64,
    mut jac: Option<&mut PointJacobian>,
    out: &mut Harmonics,
) -> Result<()> {
    let (u, v) = ([x[0], x[1], x[2]], [x[3], x[4], x[5]]);
    let (n0e, nv) = (p.n0 + p.kn * v[0], [p.kn * v[1], p.kn * v[2]]);
    if Window::always(n0e, nv)
        && closed_form(&Motion::new(p, u, v), slider, jac.as_deref_mut(), out)
    {
        return Ok(());
    }
    point_otherwise(p, x, slider, jac, out)
}

/// [`point`] where the contact is not decided on squares or [`closed_form`] does not apply: the
/// closed forms ([`separation_form`], [`closed_form`]) or else the event march ([`harmonics`]).
/// Out of line and building its own motion, so that the motion of the path in contact is never
/// stored to memory; the march builds its own again, so that no address of this one is taken.
/// The motion `x` is the caller's input itself, not a copy stored just before the call: the
/// compiler loads (U1, U2) and (V1, V2) here in 16-byte pairs, which a copy's stores, (U0, U1)
/// and U2 apart, cannot forward (a store-forwarding stall at the head of every chain of the
/// closed form with separation).
#[inline(never)]
fn point_otherwise(
    p: &ContactParams,
    x: &[f64; 6],
    slider: f64,
    mut jac: Option<&mut PointJacobian>,
    out: &mut Harmonics,
) -> Result<()> {
    let (u, v) = ([x[0], x[1], x[2]], [x[3], x[4], x[5]]);
    let mo = Motion::new(p, u, v);
    let exact = match mo.window {
        Window::Part { .. } => separation_form(&mo, jac.as_deref_mut(), out),
        _ => closed_form(&mo, slider, jac.as_deref_mut(), out),
    };
    if !exact {
        march_point(p, u, v, slider, jac, out)?;
    }
    Ok(())
}

/// The harmonics of a point by the event march ([`harmonics`]) into `out`, for the starts and
/// degenerate sinusoids the closed forms leave out. Out of line: inlined, the march's code
/// would crowd the registers of the closed forms beside it.
#[inline(never)]
fn march_point(
    p: &ContactParams,
    u: [f64; 3],
    v: [f64; 3],
    slider: f64,
    jac: Option<&mut PointJacobian>,
    out: &mut Harmonics,
) -> Result<()> {
    *out = harmonics(&Motion::new(p, u, v), slider, jac, |_| true)?.0;
    Ok(())
}

/// [`evaluate_element`] for one tangential direction and the normal direction, the layout of
/// one point: x = (U0, U1, U2, V0, V1, V2) (m), forces (F0, Re F1, Im F1, N0, Re N1, Im N1) (N),
/// and the point's Jacobian ([`PointJacobian`]) written straight into the workspace's buffer.
#[inline(never)]
fn evaluate_one_direction(
    p: &ContactParams,
    x: &[f64; 6],
    slider: &mut [f64; 2],
    force: &mut [f64; 6],
    jacobian: bool,
    ws: &mut super::element::Workspace,
) -> Result<()> {
    let u = [x[0], x[1], x[2]];
    let v = [x[3], x[4], x[5]];
    check_finite(&u, &v, slider[0])?;
    let mut r = Harmonics::default();
    if jacobian {
        let buffer = ws.analytic_jacobian_buffer(6, 7);
        let (rows, _) = buffer.as_chunks_mut::<7>();
        let Ok(j) = <&mut PointJacobian>::try_from(rows) else {
            return Err(Error::Compute(
                "analytic friction point: the Jacobian buffer is not 6 × 7".into(),
            ));
        };
        point(p, x, slider[0], Some(j), &mut r)?;
    } else {
        point(p, x, slider[0], None, &mut r)?;
    }
    let slider_in = *slider;
    slider[0] = r.slider;
    *force = [
        r.friction[0],
        r.friction[1],
        r.friction[2],
        r.normal[0],
        r.normal[1],
        r.normal[2],
    ];
    ws.set_analytic(super::element::AnalyticPeriod {
        params: *p,
        tangential: 1,
        u: [u, [0.0; 3]],
        v,
        slider: slider_in,
        energy: r.energy,
    });
    Ok(())
}

/// Writes the rows of tangential direction `d` (and, for d = 0, the normal rows) of the local
/// Jacobian `jac` (row-major, `cols` columns: U of each direction, V if the element has a normal
/// direction, then n0) from the point's Jacobian `j` ([`PointJacobian`]), every entry of
/// these rows included (the columns of the other direction and ∂N/∂U are zero), so that `jac`
/// needs no zeroing (the layouts other than [`evaluate_one_direction`]'s).
fn write_jacobian(
    element: &super::element::LocalElement,
    d: usize,
    j: &PointJacobian,
    jac: &mut [f64],
    cols: usize,
) {
    let nt = element.tangential;
    for k in 0..3 {
        let row = &mut jac[(d * 3 + k) * cols..(d * 3 + k + 1) * cols];
        row.fill(0.0);
        row[d * 3..d * 3 + 3].copy_from_slice(&j[k][..3]);
        if element.normal {
            row[nt * 3..nt * 3 + 3].copy_from_slice(&j[k][3..6]);
        }
        row[cols - 1] = j[k][6];
        if element.normal && d == 0 {
            let row = &mut jac[(nt * 3 + k) * cols..(nt * 3 + k + 1) * cols];
            row.fill(0.0);
            row[nt * 3..nt * 3 + 3].copy_from_slice(&j[3 + k][3..6]);
            row[cols - 1] = j[3 + k][6];
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A point of the tests' grids: k_t = 2, k_n = 5, μ = 0.4, u = U0 + a sin τ with a = 0.7,
    /// v = V0 + b sin(τ + φ), n̄0 = μ n0/(k_t a) and b̄ = μ k_n b/(k_t a); with its force scale
    /// k_t a + |n0| + k_n b (N).
    fn grid_point(n0bar: f64, bbar: f64, phi: f64, u0: f64, v0: f64) -> (Motion, f64) {
        let (kt, kn, mu, a) = (2.0, 5.0, 0.4, 0.7);
        let b = bbar * kt * a / (mu * kn);
        let p = ContactParams {
            kt,
            kn,
            mu,
            n0: n0bar * kt * a / mu,
        };
        let u = [u0, 0.0, -a];
        let v = [v0, b * phi.sin(), -b * phi.cos()];
        (Motion::new(&p, u, v), kt * a + p.n0.abs() + kn * b)
    }

    /// The largest differences of two evaluations of a point: forces, normal forces, energy and
    /// end slider over `scale`, and the two Jacobians over `jac_scale`.
    fn differences(
        (c, cj): (&Harmonics, &PointJacobian),
        (m, mj): (&Harmonics, &PointJacobian),
        scale: f64,
        jac_scale: f64,
    ) -> (f64, f64) {
        let pairs = c
            .friction
            .iter()
            .zip(&m.friction)
            .chain(c.normal.iter().zip(&m.normal))
            .chain([(&c.energy, &m.energy), (&c.slider, &m.slider)]);
        let values = pairs.fold(0.0f64, |w, (x, y)| w.max((x - y).abs() / scale));
        let jac = cj.iter().zip(mj);
        let mut d: f64 = 0.0;
        for (rc, rm) in jac {
            for (x, y) in rc.iter().zip(rm) {
                d = d.max((x - y).abs() / jac_scale);
            }
        }
        (values, d)
    }

    /// The closed forms ([`closed_form`]) against the event march of [`build`] on the same
    /// point: forces, normal forces, energy and end slider equal to 1e-12 of their scale, both
    /// Jacobians to 1e-12 of k_t + k_n, over the paper's grid of n̄0, b̄ and φ (u = a sin τ,
    /// v = b sin(τ + φ), k_t = 2, k_n = 5, μ = 0.4, a = 0.7) with mean offsets U0, V0 and sliders
    /// inside and outside the friction cone; both closed forms are taken and the march is left
    /// to the rest (separation, clamped starts). Where the contact grazes (min n = 0 exactly:
    /// n̄0 = b̄, φ = 0 or π) the end of a slip lies at an extremum of the level it crosses, where
    /// arccos turns a rounding difference δr of the level into √(2δr) ≈ 2e-8 of the angle; the
    /// Jacobians are compared there to 1e-7 (measured 7.2e-9; elsewhere 5e-16).
    #[test]
    fn closed_forms_equal_the_event_march() {
        // k_t + k_n of the grid points (N/m)
        let (kt, kn) = (2.0, 5.0);
        let (mut stick, mut slip, mut marched, mut grazing) = (0, 0, 0, 0);
        let (mut worst, mut worst_jac, mut worst_grazing) = (0.0f64, 0.0f64, 0.0f64);
        for n0bar in [-0.3, 0.0, 0.2, 0.5, 0.8, 1.2, 2.5, 6.0] {
            for bbar in [0.0, 0.1, 0.3, 0.8, 1.5] {
                for phi in [0.0, 0.7, PI / 2.0, 2.0, PI, 4.0, 5.5] {
                    for (u0, v0, w) in [(0.0, 0.0, 0.0), (0.3, 0.01, 0.2), (-0.2, -0.02, -0.5)] {
                        let (mo, scale) = grid_point(n0bar, bbar, phi, u0, v0);
                        let mut c = Harmonics::default();
                        let (mut cj, mut mj) = ([[0.0; 7]; 6], [[0.0; 7]; 6]);
                        if !closed_form(&mo, w, Some(&mut cj), &mut c) {
                            marched += 1;
                            continue;
                        }
                        let (m, regime) = harmonics(&mo, w, Some(&mut mj), |_| true).unwrap();
                        match regime {
                            CycleRegime::CompleteStick => stick += 1,
                            CycleRegime::StickSlip => slip += 1,
                            other => panic!("closed form taken in regime {other:?}"),
                        }
                        let (values, d) = differences((&c, &cj), (&m, &mj), scale, kt + kn);
                        worst = worst.max(values);
                        if (mo.n0e - mo.nv[0].hypot(mo.nv[1])).abs() <= 1e-12 * mo.n0e.abs() {
                            grazing += 1;
                            worst_grazing = worst_grazing.max(d);
                        } else {
                            worst_jac = worst_jac.max(d);
                        }
                    }
                }
            }
        }
        eprintln!(
            "closed forms: {stick} complete stick, {slip} stick–slip ({grazing} grazing), {marched} marched; largest difference {worst:.2e} of the scale, Jacobians {worst_jac:.2e} ({worst_grazing:.2e} grazing)"
        );
        assert!(
            stick >= 50 && slip >= 100,
            "{stick} stick, {slip} stick–slip"
        );
        assert!(worst < 1e-12, "{worst:e}");
        assert!(worst_jac < 1e-12, "{worst_jac:e}");
        assert!(worst_grazing < 1e-7, "{worst_grazing:e}");
    }

    /// The closed form of a cycle with separation ([`separation_form`]) against the event march
    /// of [`build`] on the same point, over a grid of n̄0 (gaps included), b̄ and φ that separates
    /// (u = a sin τ, v = b sin(τ + φ), k_t = 2, k_n = 5, μ = 0.4, a = 0.7, with mean offsets U0,
    /// V0 and sliders, which a cycle with separation forgets; the points with |G| = 0 or |H| = 0,
    /// b̄ = 1 at φ = 0 or π, are left to the march): forces, normal forces, energy and
    /// end slider equal to 1e-12 of their scale and both Jacobians to 1e-12 of k_t + k_n. Both
    /// take the same phases; the closed form places them by angles relative to the re-contact
    /// (a stick's end after a re-contact at a mirror of the re-contact instant instead of an
    /// arccosine of the level) and forms the forces from small matrices instead of the sliders'
    /// sums, so the two agree to rounding.
    #[test]
    fn separation_form_equals_the_event_march() {
        // k_t + k_n of the grid points (N/m)
        let (kt, kn) = (2.0, 5.0);
        let (mut separating, mut fallback) = (0, 0);
        // the states at the re-contact: positive slip, negative slip, stick (mirror ends)
        let mut entered = [0; 3];
        let (mut worst, mut worst_jac) = (0.0f64, 0.0f64);
        let mut worst_at = (0.0, 0.0, 0.0, 0);
        for n0bar in [-0.5, -0.2, 0.0, 0.2, 0.5, 0.9, 1.4] {
            for bbar in [0.1, 0.3, 0.6, 1.0, 1.5, 2.5, 5.0] {
                for phi in [0.0, 0.7, PI / 2.0, 2.0, PI, 4.0, 5.5] {
                    for (i, (u0, v0, w)) in [(0.0, 0.0, 0.0), (0.3, 0.01, 0.2), (-0.2, -0.02, -0.5)]
                        .into_iter()
                        .enumerate()
                    {
                        let (mo, scale) = grid_point(n0bar, bbar, phi, u0, v0);
                        if !matches!(mo.window, Window::Part { .. }) {
                            continue;
                        }
                        separating += 1;
                        let mut c = Harmonics::default();
                        let (mut cj, mut mj) = ([[0.0; 7]; 6], [[0.0; 7]; 6]);
                        if !separation_form(&mo, Some(&mut cj), &mut c) {
                            // only a degenerate sinusoid (b̄ = 1 at φ = 0 or π) is left to the march
                            assert!(mo.g.amp == 0.0 || mo.h.amp == 0.0, "{n0bar} {bbar} {phi}");
                            fallback += 1;
                            continue;
                        }
                        let (m, regime) = harmonics(&mo, w, Some(&mut mj), |_| true).unwrap();
                        assert_eq!(regime, CycleRegime::Separation);
                        if let Some((recontact, _, _)) = mo.window.labelled() {
                            entered[match mo.recontact_state(recontact) {
                                PhaseKind::PositiveSlip => 0,
                                PhaseKind::NegativeSlip => 1,
                                _ => 2,
                            }] += 1;
                        }
                        let (values, d) = differences((&c, &cj), (&m, &mj), scale, kt + kn);
                        worst = worst.max(values);
                        if d > worst_jac {
                            worst_jac = d;
                            worst_at = (n0bar, bbar, phi, i);
                        }
                    }
                }
            }
        }
        eprintln!(
            "separation: {separating} points, {fallback} marched, re-contact in +slip, -slip, stick {entered:?}; largest difference {worst:.2e} of the scale, Jacobians {worst_jac:.2e} of k_t + k_n (at n̄0, b̄, φ, offsets {worst_at:?})"
        );
        assert!(
            separating - fallback >= 700 && entered.iter().all(|&n| n >= 50),
            "{separating} separating, {fallback} marched, {entered:?}"
        );
        assert!(worst < 1e-12, "{worst:e}");
        assert!(worst_jac < 1e-12, "{worst_jac:e}");
    }

    /// The closed form with separation ([`separation_form`]: the window's phases by angles
    /// relative to the re-contact, F = k_t A U + μ B N) against the event march of [`build`] off
    /// the grid above: 20 000 points with random k_t, k_n, μ, n0 (gaps included), motion and
    /// slider, of which the march finds about 10 000 with separation; each must take the closed
    /// form, with forces, normal forces, end slider (times k_t) and energy equal to 1e-12 of the
    /// force scale k_t |U1| + |n0e| + k_n |V1| and Jacobians to 1e-12 of k_t + k_n.
    #[test]
    fn separation_form_equals_the_march_at_random_points() {
        let mut random = uniform(6789);
        let mut between = |lo: f64, hi: f64| lo + (hi - lo) * random();
        let mut largest = Largest::default();
        for _ in 0..20_000 {
            let p = ContactParams {
                kt: between(0.5, 3.5),
                kn: between(0.5, 8.5),
                mu: between(0.1, 0.9),
                n0: between(-1.0, 2.0),
            };
            let b = between(0.0, 0.6);
            let u = [between(-0.5, 0.5), between(-1.0, 1.0), between(-1.0, 1.0)];
            let v = [between(-0.05, 0.05), between(-b, b), between(-b, b)];
            let w = between(-0.5, 0.5);
            let mo = Motion::new(&p, u, v);
            if !matches!(mo.window, Window::Part { .. }) {
                continue;
            }
            let mut results = [Harmonics::default(), Harmonics::default()];
            let mut jacobians = [[[0.0; 7]; 6]; 2];
            let [c, m] = &mut results;
            let [cj, mj] = &mut jacobians;
            assert!(
                separation_form(&mo, Some(cj), c),
                "separation left to the march: {p:?} {u:?} {v:?}"
            );
            let (marched, regime) = harmonics(&mo, w, Some(mj), |_| true).unwrap();
            assert_eq!(regime, CycleRegime::Separation);
            *m = marched;
            let scale = p.kt * u[1].hypot(u[2]) + mo.n0e.abs() + mo.nv[0].hypot(mo.nv[1]);
            let [c, m] = results;
            largest.add(&p, scale, (c, &jacobians[0]), (m, &jacobians[1]));
        }
        largest.check("random separating points", 5_000);
    }

    /// The stick–slip closed form ([`closed_form`]: lengths from δ, the phase of τ ≡ 0 by sign
    /// tests, F = k_t A U + μ B N) against the event march of [`build`] off the grids above: 20 000
    /// points with random k_t, k_n, μ, n0, motion (a third at constant load) and slider, of which
    /// the march finds about 15 000 in stick–slip; each must take the closed form, with forces,
    /// normal forces, end slider (times k_t) and energy equal to 1e-12 of the force scale and
    /// Jacobians to 1e-12 of k_t + k_n (measured 4.7e-16 and 5.1e-15).
    #[test]
    fn stick_slip_closed_form_equals_the_march_at_random_points() {
        let mut random = uniform(12345);
        let mut largest = Largest::default();
        for _ in 0..20_000 {
            let p = ContactParams {
                kt: 0.5 + 3.0 * random(),
                kn: 0.5 + 8.0 * random(),
                mu: 0.1 + 0.8 * random(),
                n0: 0.05 + 2.0 * random(),
            };
            let u = [random() - 0.5, 2.0 * random() - 1.0, 2.0 * random() - 1.0];
            let b = if random() < 0.3 { 0.0 } else { 0.2 * random() };
            let v = [
                0.05 * (random() - 0.5),
                b * (2.0 * random() - 1.0),
                b * (2.0 * random() - 1.0),
            ];
            let w = random() - 0.5;
            let mo = Motion::new(&p, u, v);
            let mut c = Harmonics::default();
            let (mut cj, mut mj) = ([[0.0; 7]; 6], [[0.0; 7]; 6]);
            let closed = closed_form(&mo, w, Some(&mut cj), &mut c);
            let (m, regime) = harmonics(&mo, w, Some(&mut mj), |_| true).unwrap();
            if regime != CycleRegime::StickSlip {
                continue;
            }
            assert!(
                closed,
                "stick–slip left to the march: {p:?} {u:?} {v:?} {w}"
            );
            let scale = p.kt * u[1].hypot(u[2]) + p.n0 + p.kn * v[1].hypot(v[2]);
            largest.add(&p, scale, (c, &cj), (m, &mj));
        }
        largest.check("random stick–slip points", 10_000);
    }

    /// The largest differences of the closed forms from the event march over random points:
    /// forces, normal forces, end slider (times k_t) and energy relative to each point's force
    /// scale, Jacobians relative to k_t + k_n ([`differences`]).
    #[derive(Default)]
    struct Largest {
        points: usize,
        values: f64,
        jacobian: f64,
    }

    impl Largest {
        /// Adds one point: the closed form's result and Jacobian against the march's, on the
        /// force scale `scale` (N) of the point's law `p`.
        fn add(
            &mut self,
            p: &ContactParams,
            scale: f64,
            (mut c, cj): (Harmonics, &PointJacobian),
            (mut m, mj): (Harmonics, &PointJacobian),
        ) {
            for r in [&mut c, &mut m] {
                r.slider *= p.kt;
                r.energy *= p.kt / scale;
            }
            let (values, d) = differences((&c, cj), (&m, mj), scale, p.kt + p.kn);
            self.points += 1;
            self.values = self.values.max(values);
            self.jacobian = self.jacobian.max(d);
        }

        /// Prints the differences and asserts more than `least` points, each within 1e-12.
        fn check(&self, what: &str, least: usize) {
            let (points, worst, worst_jac) = (self.points, self.values, self.jacobian);
            eprintln!(
                "{what}: {points}; largest difference {worst:.2e} of the scale, Jacobians {worst_jac:.2e} of k_t + k_n"
            );
            assert!(points > least, "{points}");
            assert!(worst < 1e-12, "{worst:e}");
            assert!(worst_jac < 1e-12, "{worst_jac:e}");
        }
    }

    /// Pseudo-random numbers in [0, 1) from `seed` (xorshift64, Marsaglia 2003).
    fn uniform(mut seed: u64) -> impl FnMut() -> f64 {
        move || {
            seed ^= seed << 13;
            seed ^= seed >> 7;
            seed ^= seed << 17;
            (seed >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    /// The inline inverse functions ([`arccos`], [`angle`]) against libm's acos and atan2 on
    /// 200 000 arguments (uniform, crowded towards ±1 and around ±1/2 where the reduction
    /// switches) and 100 000 unit vectors: within 2 ulp of libm's value (each is within 1.1 and
    /// 0.52 ulp of the correctly rounded one, by a comparison at 120 bits).
    #[test]
    fn inline_inverse_functions_equal_libm() {
        let mut random = uniform(987_654_321);
        let ulps = |a: f64, b: f64| (a - b).abs() / (b.abs() * f64::EPSILON).max(f64::MIN_POSITIVE);
        let mut worst = 0.0f64;
        for i in 0..200_000 {
            let r = random();
            let x = match i % 4 {
                0 => 2.0 * r - 1.0,
                1 => 1.0 - r.powi(6),
                2 => -1.0 + r.powi(6),
                _ => (if r < 0.5 { 0.5 } else { -0.5 }) + 1e-6 * (random() - 0.5),
            };
            worst = worst.max(ulps(arccos(x), x.acos()));
        }
        for x in [-1.0, -0.5, 0.0, 0.5, 1.0] {
            worst = worst.max(ulps(arccos(x), f64::acos(x)));
        }
        let mut worst_angle = 0.0f64;
        for _ in 0..100_000 {
            let (s, c) = (TAU * (random() - 0.5)).sin_cos();
            worst_angle = worst_angle.max(ulps(angle(c, s), s.atan2(c)));
        }
        eprintln!(
            "arccos within {worst:.2} ulp of libm's acos, angle within {worst_angle:.2} of atan2"
        );
        assert!(worst <= 2.0 && worst_angle <= 2.0);
    }
}
