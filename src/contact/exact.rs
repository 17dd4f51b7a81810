//! The exact multi-harmonic evaluation of the 1-D friction law with normal load variation: the
//! continuous-time stick–slip–separation cycle under a tangential motion u(τ) and a normal
//! approach v(τ) that are trigonometric polynomials of degree H, with the transition instants
//! located as roots of trigonometric polynomials and the harmonic coefficients of the forces
//! integrated exactly over the phases of the cycle — no time sampling, hence no sampling kinks
//! and no aliasing.
//!
//! It is the multi-harmonic form of the single-harmonic cycle of [`super::microslip`]
//! (Cigeroglu, An & Menq 2007, §2): the same point law (normal force n = max(n0 + k_n v, 0),
//! eq. 4; friction f = k_t (u − w) with slider w, |f| ≤ μ n, f = ±μ n while slipping, eqs 5–6;
//! f = 0 and w = u while separated) and the same transition conditions (eqs 8–17), with the
//! angles found numerically instead of in closed form. Symbols and units: u, v, w (m), k_t, k_n
//! (N/m), μ (–), n0 (N; negative: an initial gap), τ = ωt (rad).
//!
//! Phases and their exits (g₊ = k_t u − μ n₀ₑ(τ), with n₀ₑ(τ) = n0 + k_n v(τ) the unclipped
//! normal force):
//! * stick with slider w: positive slip where k_t (u − w) − μ n₀ₑ rises through 0, negative slip
//!   where k_t (u − w) + μ n₀ₑ falls through 0, separation where n₀ₑ falls through 0;
//! * positive slip (f = μ n): stick where k_t u̇ − μ ṅ₀ₑ falls through 0 (the slider is left at
//!   w = u − μ n/k_t), separation where n₀ₑ falls through 0; negative slip likewise with
//!   k_t u̇ + μ ṅ₀ₑ rising through 0 and w = u + μ n/k_t;
//! * separation (f = n = 0, w = u): contact where n₀ₑ rises through 0, then positive slip if
//!   k_t u̇ − μ ṅ₀ₑ > 0, negative slip if k_t u̇ + μ ṅ₀ₑ < 0, else stick with w = u.
//!
//! Roots are bracketed on a grid of [`scan_samples`] points per period and refined by bisection
//! to rounding. The cycle is marched from τ = 0 and the given slider position until the first
//! event after which the state no longer depends on the start (the end of a slip, the start of a
//! separation), then over one period from there, which is the periodic cycle. As for the
//! time-sampled element (`super::element`), the map is a function of the harmonics alone: where
//! the periodic cycle keeps a slider position from its start (stick all period, or slip one way
//! only), it is the cycle reached from rest (w = 0).
//!
//! The forces are continuous in τ, so the derivative of a harmonic coefficient is the sum over the
//! phases of the integral of the derivative of the phase's force (the moving limits cancel). A
//! stick phase's slider depends on the harmonics through the event that set it: after a slip
//! end, w = u(τ_e) ∓ μ n₀ₑ(τ_e)/k_t, whose τ-derivative vanishes there (the end condition); after a
//! contact at τ_c (n₀ₑ(τ_c) = 0), w = u(τ_c) with ∂τ_c = −∂n₀ₑ(τ_c)/ṅ₀ₑ(τ_c).

use std::f64::consts::{PI, TAU};

use crate::contact::aft::Aft;
use crate::contact::element::{LocalElement, Workspace};
use crate::contact::law::{ContactParams, Regime, Sample, Variant};
use crate::error::{Error, Result};

/// Most events marched in one evaluation before it gives up (a guard against a degenerate input).
const MAX_EVENTS: usize = 4096;

/// Bisection steps of a root (the bracket shrinks below rounding well before).
const BISECTIONS: usize = 64;

/// Points per period of the grid the transition roots are bracketed on: at least the AFT's
/// N_t and 8 (2H + 1), so that two transitions of a degree-H motion closer than a grid step —
/// the only ones missed — bound an excursion of second order in its length.
pub fn scan_samples(harmonics: usize, time_samples: usize) -> usize {
    time_samples.max(8 * (2 * harmonics + 1))
}

/// The basis e(τ) = [1, cos τ, −sin τ, …, cos Hτ, −sin Hτ] of the real harmonic layout
/// (`docs/conventions.md` §4) into `out` (length 2H + 1).
fn basis(tau: f64, out: &mut [f64]) {
    out[0] = 1.0;
    let (s1, c1) = tau.sin_cos();
    let (mut c, mut s) = (1.0, 0.0);
    for n in 1..=out.len() / 2 {
        let cn = c * c1 - s * s1;
        s = s * c1 + c * s1;
        c = cn;
        out[2 * n - 1] = c;
        out[2 * n] = -s;
    }
}

/// x(τ) = Σ_l X_l e_l(τ) and its τ-derivative from the basis values `e`.
fn value_rate(x: &[f64], e: &[f64]) -> (f64, f64) {
    let mut value = x[0];
    let mut rate = 0.0;
    for n in 1..=x.len() / 2 {
        let (a, b) = (x[2 * n - 1], x[2 * n]);
        value += a * e[2 * n - 1] + b * e[2 * n];
        // d/dτ cos nτ = n·(−sin nτ); d/dτ (−sin nτ) = −n cos nτ
        rate += n as f64 * (a * e[2 * n] - b * e[2 * n - 1]);
    }
    (value, rate)
}

/// The motion of one tangential direction and the normal approach, with the law's parameters.
struct Motion<'a> {
    params: ContactParams,
    /// U (m), 2H + 1 coefficients.
    u: &'a [f64],
    /// V (m), 2H + 1 coefficients; `None`: no normal kinematics (n₀ₑ ≡ n0).
    v: Option<&'a [f64]>,
}

/// The motion at one instant.
#[derive(Clone, Copy, Debug)]
struct At {
    /// u (m) and u̇ = du/dτ (m/rad).
    u: f64,
    du: f64,
    /// n₀ₑ = n0 + k_n v (N, unclipped) and its τ-derivative.
    n: f64,
    dn: f64,
}

impl Motion<'_> {
    fn at(&self, tau: f64, e: &mut [f64]) -> At {
        basis(tau, e);
        self.at_basis(e)
    }

    fn at_basis(&self, e: &[f64]) -> At {
        let (u, du) = value_rate(self.u, e);
        let (n, dn) = match self.v {
            Some(v) => {
                let (v, dv) = value_rate(v, e);
                (self.params.n0 + self.params.kn * v, self.params.kn * dv)
            }
            None => (self.params.n0, 0.0),
        };
        At { u, du, n, dn }
    }
}

/// Where a stick phase's slider position comes from (for its derivative).
#[derive(Clone, Copy, Debug, PartialEq)]
enum Origin {
    /// The start state (rest or the caller's): constant.
    Start,
    /// The end of a slip at τ_e with sign σ = ±1: w = u(τ_e) − σ μ n₀ₑ(τ_e)/k_t.
    SlipEnd { tau: f64, sign: f64 },
    /// A contact at τ_c after separation: w = u(τ_c).
    Contact { tau: f64 },
}

/// The state of the point on a phase.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Phase {
    Stick { slider: f64, origin: Origin },
    Slip { sign: f64 },
    Separation,
}

/// One phase of the periodic cycle, on [start, end] (rad).
#[derive(Clone, Copy, Debug)]
struct Segment {
    start: f64,
    end: f64,
    phase: Phase,
}

/// A crossing to look for: the function, its direction (+1 rising, −1 falling) and the phase it
/// leads to (resolved at the root).
#[derive(Clone, Copy)]
enum Exit {
    /// k_t (u − w) − μ n₀ₑ rising: positive slip.
    StickToPositive(f64),
    /// k_t (u − w) + μ n₀ₑ falling: negative slip.
    StickToNegative(f64),
    /// k_t u̇ − σ μ ṅ₀ₑ crossing against σ: the end of a slip of sign σ.
    SlipEnd(f64),
    /// n₀ₑ falling: separation.
    Separate,
    /// n₀ₑ rising: contact.
    Contact,
}

impl Exit {
    /// The τ-derivative of [`Exit::value`], for the exits whose function may rise above 0 and
    /// fall back between two grid points (a brief excursion that the signs at the grid points
    /// miss); `None` for the end of a slip (an excursion there is a brief stick within the slip,
    /// which leaves the slip's end state as it is).
    fn rate(&self, p: &ContactParams, a: &At) -> Option<f64> {
        match *self {
            Exit::StickToPositive(_) => Some(p.kt * a.du - p.mu * a.dn),
            Exit::StickToNegative(_) => Some(-(p.kt * a.du + p.mu * a.dn)),
            Exit::SlipEnd(_) => None,
            Exit::Separate => Some(-a.dn),
            Exit::Contact => Some(a.dn),
        }
    }

    /// The signed function whose rise through 0 is the event.
    fn value(&self, p: &ContactParams, a: &At) -> f64 {
        match *self {
            Exit::StickToPositive(w) => p.kt * (a.u - w) - p.mu * a.n,
            Exit::StickToNegative(w) => -(p.kt * (a.u - w) + p.mu * a.n),
            Exit::SlipEnd(sign) => -sign * (p.kt * a.du - sign * p.mu * a.dn),
            Exit::Separate => -a.n,
            Exit::Contact => a.n,
        }
    }
}

/// The exits of a phase.
fn exits(phase: Phase, normal: bool) -> ([Exit; 3], usize) {
    // separation (listed last) only with normal kinematics; unused slots are never read
    let sep = usize::from(normal);
    match phase {
        Phase::Stick { slider, .. } => (
            [
                Exit::StickToPositive(slider),
                Exit::StickToNegative(slider),
                Exit::Separate,
            ],
            2 + sep,
        ),
        Phase::Slip { sign } => (
            [Exit::SlipEnd(sign), Exit::Separate, Exit::Contact],
            1 + sep,
        ),
        Phase::Separation => ([Exit::Contact; 3], 1),
    }
}

/// The phase entered at an event at τ (motion `a` there).
fn entered(exit: Exit, tau: f64, p: &ContactParams, a: &At) -> Phase {
    match exit {
        Exit::StickToPositive(_) => Phase::Slip { sign: 1.0 },
        Exit::StickToNegative(_) => Phase::Slip { sign: -1.0 },
        Exit::SlipEnd(sign) => Phase::Stick {
            slider: a.u - sign * p.mu * a.n.max(0.0) / p.kt,
            origin: Origin::SlipEnd { tau, sign },
        },
        Exit::Separate => Phase::Separation,
        Exit::Contact => contact_phase(tau, p, a),
    }
}

/// The phase after a contact at τ (eqs 15–17): slip in the direction the stuck force would leave
/// the friction cone, else stick with f = 0.
fn contact_phase(tau: f64, p: &ContactParams, a: &At) -> Phase {
    if p.kt * a.du - p.mu * a.dn > 0.0 {
        Phase::Slip { sign: 1.0 }
    } else if p.kt * a.du + p.mu * a.dn < 0.0 {
        Phase::Slip { sign: -1.0 }
    } else {
        Phase::Stick {
            slider: a.u,
            origin: Origin::Contact { tau },
        }
    }
}

/// The phase at τ = 0 from the slider position `w`.
fn initial_phase(p: &ContactParams, a: &At, normal: bool, w: f64) -> Phase {
    let limit = p.mu * a.n.max(0.0);
    let trial = p.kt * (a.u - w);
    if (normal || p.n0 <= 0.0) && a.n <= 0.0 {
        Phase::Separation
    } else if trial > limit {
        Phase::Slip { sign: 1.0 }
    } else if trial < -limit {
        Phase::Slip { sign: -1.0 }
    } else {
        Phase::Stick {
            slider: w,
            origin: Origin::Start,
        }
    }
}

/// The motion on the bracketing grid τ_k = 2πk/N (k = 0..N), reused by every search.
struct Grid {
    points: Vec<At>,
}

impl Grid {
    fn new(motion: &Motion<'_>, samples: usize, e: &mut [f64]) -> Grid {
        let points = (0..samples)
            .map(|k| motion.at(TAU * k as f64 / samples as f64, e))
            .collect();
        Grid { points }
    }

    fn len(&self) -> usize {
        self.points.len()
    }

    /// The grid point of global index `k` (any k ≥ 0; the motion is 2π-periodic).
    fn point(&self, k: usize) -> (f64, &At) {
        let n = self.len();
        (TAU * k as f64 / n as f64, &self.points[k % n])
    }
}

/// The first event after `from` (where the phase holds) and before `limit`: (τ, exit).
fn next_event(
    motion: &Motion<'_>,
    grid: &Grid,
    phase: Phase,
    from: f64,
    limit: f64,
    e: &mut [f64],
) -> Option<(f64, Exit)> {
    let p = &motion.params;
    let (all, count) = exits(phase, motion.v.is_some());
    let list = &all[..count];
    let start = motion.at(from, e);
    let mut before = [0.0; 3];
    for (b, x) in before.iter_mut().zip(list) {
        *b = x.value(p, &start);
    }
    let mut before_at = start;
    let mut t_before = from;
    let n = grid.len();
    let mut k = (from / TAU * n as f64).floor() as usize + 1;
    loop {
        let (mut t, mut at) = grid.point(k);
        let last = t >= limit;
        let end_point;
        if last {
            end_point = motion.at(limit, e);
            t = limit;
            at = &end_point;
        }
        let at = *at;
        let mut first: Option<(f64, Exit)> = None;
        for (i, x) in list.iter().enumerate() {
            let after = x.value(p, &at);
            let mut upper = None;
            if before[i] <= 0.0 && after > 0.0 {
                upper = Some(t);
            } else if before[i] <= 0.0 {
                // a maximum above 0 between the grid points: the crossing lies before it
                upper = excursion(motion, *x, (t_before, &before_at), (t, &at), e);
            }
            if let Some(upper) = upper {
                let root = bisect(motion, *x, t_before, upper, e);
                if root > from && first.is_none_or(|(r, _)| root < r) {
                    first = Some((root, *x));
                }
            }
            before[i] = after;
        }
        before_at = at;
        if first.is_some() || last {
            return first;
        }
        t_before = t;
        k += 1;
    }
}

/// Where `exit`'s function, ≤ 0 at both ends of (a, b), rises above 0 in between: its rate
/// falls through 0 inside (a maximum), located by bisection; `Some(τ_max)` if the function is
/// positive there.
fn excursion(
    motion: &Motion<'_>,
    exit: Exit,
    (mut a, at_a): (f64, &At),
    (mut b, at_b): (f64, &At),
    e: &mut [f64],
) -> Option<f64> {
    let p = &motion.params;
    if !(exit.rate(p, at_a)? > 0.0 && exit.rate(p, at_b)? < 0.0) {
        return None;
    }
    for _ in 0..BISECTIONS {
        let c = 0.5 * (a + b);
        if c <= a || c >= b {
            break;
        }
        if exit.rate(p, &motion.at(c, e))? > 0.0 {
            a = c;
        } else {
            b = c;
        }
    }
    (exit.value(p, &motion.at(b, e)) > 0.0).then_some(b)
}

/// The root of `exit`'s function in (a, b], where it is ≤ 0 at a and > 0 at b.
fn bisect(motion: &Motion<'_>, exit: Exit, mut a: f64, mut b: f64, e: &mut [f64]) -> f64 {
    for _ in 0..BISECTIONS {
        let c = 0.5 * (a + b);
        if c <= a || c >= b {
            break;
        }
        if exit.value(&motion.params, &motion.at(c, e)) > 0.0 {
            b = c;
        } else {
            a = c;
        }
    }
    b
}

/// Most periods marched before the last one is taken without a repeated state (the state of a
/// motion whose range exceeds the stick band repeats after at most two).
const MAX_PERIODS: usize = 10;

/// Relative tolerance on the slider position for "the state at the period's end repeats".
const STATE_TOLERANCE: f64 = 1e-13;

/// The periodic cycle of one direction from the slider position `w_start` at τ = 0: periods are
/// marched until the state at the end of a period (phase, and the slider in stick) repeats the
/// state at its start (at most [`MAX_PERIODS`]); returns the phases of that last period
/// [2πk, 2π(k + 1)].
fn periodic_cycle(
    motion: &Motion<'_>,
    grid: &Grid,
    w_start: f64,
    e: &mut [f64],
) -> Result<Vec<Segment>> {
    let p = &motion.params;
    let normal = motion.v.is_some();
    let mut phase = initial_phase(p, &motion.at(0.0, e), normal, w_start);
    let scale = motion
        .u
        .iter()
        .fold(w_start.abs(), |a, x| a + x.abs())
        .max(f64::MIN_POSITIVE);
    let mut events = 0;
    let mut segments = Vec::new();
    for period in 0..MAX_PERIODS {
        let start_phase = phase;
        let from_period = TAU * period as f64;
        let end = from_period + TAU;
        segments.clear();
        let mut from = from_period;
        while let Some((t, exit)) = next_event(motion, grid, phase, from, end, e) {
            events += 1;
            if events > MAX_EVENTS {
                return Err(too_many_events());
            }
            segments.push(Segment {
                start: from,
                end: t,
                phase,
            });
            phase = entered(exit, t, p, &motion.at(t, e));
            from = t;
        }
        segments.push(Segment {
            start: from,
            end,
            phase,
        });
        if same_state(start_phase, phase, STATE_TOLERANCE * scale) {
            break;
        }
    }
    // the first phase of the period continues the last one: its slider comes from the last
    // period's event (by periodicity), not from the start state
    let last = segments[segments.len() - 1].phase;
    if segments.len() > 1 {
        if let (Phase::Stick { .. }, Phase::Stick { .. }) = (segments[0].phase, last) {
            segments[0].phase = last;
        }
    }
    Ok(segments)
}

/// Whether two states are the same: the same phase, and in stick sliders within `tol` (m).
fn same_state(a: Phase, b: Phase, tol: f64) -> bool {
    match (a, b) {
        (Phase::Stick { slider: x, .. }, Phase::Stick { slider: y, .. }) => (x - y).abs() <= tol,
        (Phase::Slip { sign: x }, Phase::Slip { sign: y }) => x == y,
        (Phase::Separation, Phase::Separation) => true,
        _ => false,
    }
}

fn too_many_events() -> Error {
    Error::Compute(format!(
        "the exact friction cycle needed more than {MAX_EVENTS} transitions in one evaluation (a degenerate motion); use evaluation = \"aft\""
    ))
}

/// Whether the cycle forgets its start state: it separates, or slips both ways.
fn forgets_start(segments: &[Segment]) -> bool {
    let mut slips = [false; 2];
    for s in segments.iter().filter(|s| s.end > s.start) {
        match s.phase {
            Phase::Separation => return true,
            Phase::Slip { sign } => slips[usize::from(sign > 0.0)] = true,
            Phase::Stick { .. } => {}
        }
    }
    slips[0] && slips[1]
}

/// ∫_a^b e_k(τ) e_l(τ) dτ for k, l = 0..2H (m × m, row-major) — the products of the basis as
/// sums of cos and sin of (k ± l)τ integrated in closed form.
fn product_integrals(a: f64, b: f64, m: usize, out: &mut [f64]) {
    let h = m / 2;
    // S_j = ∫ cos jτ, C_j = ∫ sin jτ for j = 0..2H
    let mut s = vec![0.0; 2 * h + 1];
    let mut c = vec![0.0; 2 * h + 1];
    s[0] = b - a;
    for j in 1..=2 * h {
        let jf = j as f64;
        let (sb, cb) = (jf * b).sin_cos();
        let (sa, ca) = (jf * a).sin_cos();
        s[j] = (sb - sa) / jf;
        c[j] = (ca - cb) / jf;
    }
    // C of a signed index: sin(−jτ) = −sin jτ
    let cs = |j: isize| -> f64 {
        if j >= 0 {
            c[j as usize]
        } else {
            -c[(-j) as usize]
        }
    };
    // index l → (n, is_sine)
    let kind = |l: usize| -> (usize, bool) {
        if l == 0 {
            (0, false)
        } else {
            (l.div_ceil(2), l.is_multiple_of(2))
        }
    };
    for k in 0..m {
        let (nk, sk) = kind(k);
        for l in 0..m {
            let (nl, sl) = kind(l);
            let diff = nk.abs_diff(nl);
            let sum = nk + nl;
            out[k * m + l] = match (sk, sl) {
                // cos nk · cos nl
                (false, false) => 0.5 * (s[diff] + s[sum]),
                // (−sin nk) · (−sin nl)
                (true, true) => 0.5 * (s[diff] - s[sum]),
                // cos nl · (−sin nk) = −½ [sin (nk+nl) + sin (nk−nl)]
                (true, false) => -0.5 * (c[sum] + cs(nk as isize - nl as isize)),
                (false, true) => -0.5 * (c[sum] + cs(nl as isize - nk as isize)),
            };
        }
    }
}

/// The result of one direction.
pub(crate) struct DirectionResult {
    /// Friction force coefficients F (N), 2H + 1.
    pub friction: Vec<f64>,
    /// Normal force coefficients F_n (N), 2H + 1 (the same for every direction).
    pub normal: Vec<f64>,
    /// ∂F/∂U, ∂F/∂V, ∂F/∂n0: rows of F, columns U (m), then V (m), then n0 (row-major,
    /// m × (2m + 1)); empty unless asked.
    pub friction_jacobian: Vec<f64>,
    /// ∂F_n/∂V and ∂F_n/∂n0 (m × (m + 1)); empty unless asked.
    pub normal_jacobian: Vec<f64>,
    /// The slider position at τ = 0 of the periodic cycle (m).
    pub slider: f64,
    /// The periodic cycle.
    segments: Vec<Segment>,
}

/// The exact cycle of one direction with tangential coefficients `u` and normal `v` from the
/// slider position `slider`: force harmonics, the slider at the period's start, and (if
/// `jacobian`) their derivatives. `scan` is the bracketing grid's size ([`scan_samples`]).
pub(crate) fn direction(
    params: &ContactParams,
    u: &[f64],
    v: Option<&[f64]>,
    slider: f64,
    scan: usize,
    jacobian: bool,
) -> Result<DirectionResult> {
    let m = u.len();
    let motion = Motion {
        params: *params,
        u,
        v,
    };
    let mut e = vec![0.0; m];
    let grid = Grid::new(&motion, scan, &mut e);
    let mut segments = periodic_cycle(&motion, &grid, slider, &mut e)?;
    if slider != 0.0 && !forgets_start(&segments) {
        segments = periodic_cycle(&motion, &grid, 0.0, &mut e)?;
    }
    let mut out = DirectionResult {
        friction: vec![0.0; m],
        normal: vec![0.0; m],
        friction_jacobian: if jacobian {
            vec![0.0; m * (2 * m + 1)]
        } else {
            Vec::new()
        },
        normal_jacobian: if jacobian {
            vec![0.0; m * (m + 1)]
        } else {
            Vec::new()
        },
        slider: slider_at_zero(&motion, &segments, &mut e),
        segments: Vec::new(),
    };
    let mut prod = vec![0.0; m * m];
    for s in &segments {
        if s.end <= s.start {
            continue;
        }
        product_integrals(s.start, s.end, m, &mut prod);
        add_segment(&motion, s, &prod, &mut out, &mut e);
    }
    // F_0 = (1/2π) ∫ f, F_k = (1/π) ∫ f e_k for k ≥ 1
    let weight = |k: usize| if k == 0 { 0.5 / PI } else { 1.0 / PI };
    for k in 0..m {
        let wk = weight(k);
        out.friction[k] *= wk;
        out.normal[k] *= wk;
        if jacobian {
            out.friction_jacobian[k * (2 * m + 1)..(k + 1) * (2 * m + 1)]
                .iter_mut()
                .for_each(|x| *x *= wk);
            out.normal_jacobian[k * (m + 1)..(k + 1) * (m + 1)]
                .iter_mut()
                .for_each(|x| *x *= wk);
        }
    }
    out.segments = segments;
    Ok(out)
}

/// The slider position at τ = 0 (≡ 2π) of the periodic cycle.
fn slider_at_zero(motion: &Motion<'_>, segments: &[Segment], e: &mut [f64]) -> f64 {
    let (phase, tau) = phase_at(segments, 0.0);
    let p = &motion.params;
    let a = motion.at(tau, e);
    match phase {
        Phase::Stick { slider, .. } => slider,
        Phase::Slip { sign } => a.u - sign * p.mu * a.n.max(0.0) / p.kt,
        Phase::Separation => a.u,
    }
}

/// The phase of the periodic cycle at τ (any value), and τ moved into the cycle's period.
fn phase_at(segments: &[Segment], tau: f64) -> (Phase, f64) {
    let start = segments[0].start;
    let t = start + (tau - start).rem_euclid(TAU);
    let s = segments
        .iter()
        .find(|s| t <= s.end)
        .unwrap_or(&segments[segments.len() - 1]);
    (s.phase, t)
}

/// Adds the integrals over one segment (without the 1/π weights): the forces and, if asked,
/// their derivatives. `prod` holds ∫ e_k e_l over the segment.
fn add_segment(
    motion: &Motion<'_>,
    s: &Segment,
    prod: &[f64],
    out: &mut DirectionResult,
    e: &mut [f64],
) {
    let p = &motion.params;
    let m = motion.u.len();
    let jacobian = !out.friction_jacobian.is_empty();
    let cols = 2 * m + 1;
    let normal = motion.v.is_some();
    let in_contact = s.phase != Phase::Separation;
    // the normal force n₀ₑ on a contact segment: n0 + k_n V (or n0 alone)
    if in_contact && (normal || p.n0 > 0.0) {
        for k in 0..m {
            let row = &prod[k * m..(k + 1) * m];
            let mut f = p.n0 * row[0];
            if let Some(v) = motion.v {
                f += p.kn * dot(row, v);
                if jacobian {
                    let jrow = &mut out.normal_jacobian[k * (m + 1)..(k + 1) * (m + 1)];
                    for (j, r) in jrow[..m].iter_mut().zip(row) {
                        *j += p.kn * r;
                    }
                    jrow[m] += row[0];
                }
            } else if jacobian {
                out.normal_jacobian[k * (m + 1) + m] += row[0];
            }
            out.normal[k] += f;
        }
    }
    match s.phase {
        Phase::Separation => {}
        Phase::Slip { sign } => {
            let mu = sign * p.mu;
            for k in 0..m {
                let row = &prod[k * m..(k + 1) * m];
                let mut f = mu * p.n0 * row[0];
                if let Some(v) = motion.v {
                    f += mu * p.kn * dot(row, v);
                }
                out.friction[k] += f;
                if jacobian {
                    let jrow = &mut out.friction_jacobian[k * cols..(k + 1) * cols];
                    if normal {
                        for (j, r) in jrow[m..2 * m].iter_mut().zip(row) {
                            *j += mu * p.kn * r;
                        }
                    }
                    jrow[2 * m] += mu * row[0];
                }
            }
        }
        Phase::Stick { slider, origin } => {
            // ∂w/∂U, ∂w/∂V, ∂w/∂n0
            let (dw_u, dw_v, dw_n0) = slider_derivative(motion, origin, e);
            for k in 0..m {
                let row = &prod[k * m..(k + 1) * m];
                out.friction[k] += p.kt * (dot(row, motion.u) - slider * row[0]);
                if jacobian {
                    let jrow = &mut out.friction_jacobian[k * cols..(k + 1) * cols];
                    let i_k = row[0];
                    for l in 0..m {
                        jrow[l] += p.kt * (row[l] - i_k * dw_u[l]);
                        if normal {
                            jrow[m + l] -= p.kt * i_k * dw_v[l];
                        }
                    }
                    jrow[2 * m] -= p.kt * i_k * dw_n0;
                }
            }
        }
    }
}

/// The derivatives of a stick phase's slider position with respect to U, V and n0.
fn slider_derivative(
    motion: &Motion<'_>,
    origin: Origin,
    e: &mut [f64],
) -> (Vec<f64>, Vec<f64>, f64) {
    let m = motion.u.len();
    let p = &motion.params;
    match origin {
        Origin::Start => (vec![0.0; m], vec![0.0; m], 0.0),
        Origin::SlipEnd { tau, sign } => {
            let a = motion.at(tau, e);
            let du = e.to_vec();
            if a.n <= 0.0 {
                return (du, vec![0.0; m], 0.0);
            }
            let f = sign * p.mu / p.kt;
            let dv: Vec<f64> = e.iter().map(|x| -f * p.kn * x).collect();
            (du, dv, -f)
        }
        Origin::Contact { tau } => {
            let a = motion.at(tau, e);
            let du = e.to_vec();
            if a.dn == 0.0 {
                return (du, vec![0.0; m], 0.0);
            }
            // w = u(τ_c), ∂τ_c = −(k_n e ∂V + ∂n0)/ṅ₀ₑ
            let r = a.du / a.dn;
            let dv: Vec<f64> = e.iter().map(|x| -r * p.kn * x).collect();
            (du, dv, -r)
        }
    }
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

impl DirectionResult {
    /// The friction force, normal force, slider and regime of the periodic cycle at τ.
    pub(crate) fn state_at(
        &self,
        params: &ContactParams,
        u: &[f64],
        v: Option<&[f64]>,
        tau: f64,
    ) -> (f64, f64, f64, Regime) {
        let motion = Motion {
            params: *params,
            u,
            v,
        };
        let mut e = vec![0.0; u.len()];
        let (phase, t) = phase_at(&self.segments, tau);
        let a = motion.at(t, &mut e);
        let n = a.n.max(0.0);
        match phase {
            Phase::Stick { slider, .. } => (params.kt * (a.u - slider), n, slider, Regime::Stick),
            Phase::Slip { sign } => (
                sign * params.mu * n,
                n,
                a.u - sign * params.mu * n / params.kt,
                Regime::Slip,
            ),
            Phase::Separation => (0.0, 0.0, a.u, Regime::Separation),
        }
    }
}

/// [`super::element::evaluate_as`] with `evaluation = "analytic"` and H > 1: the exact cycle of
/// every tangential direction of a 1-D element (inputs, outputs, slider state and Jacobian
/// layout as [`super::element::evaluate`]; the last column of the Jacobian is ∂/∂n0). The
/// time samples of the workspace (for the state report and the hysteresis loop) are the exact
/// cycle at τ_j = 2πj/N_t.
pub(crate) fn evaluate_element(
    element: &LocalElement,
    aft: &Aft,
    x: &[f64],
    slider: &mut [f64; 2],
    force: &mut [f64],
    jacobian: bool,
    ws: &mut Workspace,
) -> Result<()> {
    if element.variant != Variant::OneD {
        return Err(Error::input(
            "evaluation = \"analytic\" is the exact cycle of the 1-D friction law; the 2-D (Coulomb disc) element is evaluated by the AFT only (evaluation = \"aft\")",
        ));
    }
    let layout = aft.layout();
    let m = layout.coefficients();
    let nt = element.tangential;
    let nsig = element.signals();
    if x.iter().any(|v| !v.is_finite()) || slider.iter().any(|w| !w.is_finite()) {
        return Err(Error::Compute(
            "the exact friction cycle got a non-finite displacement or slider position".into(),
        ));
    }
    let v = element.normal.then(|| &x[nt * m..(nt + 1) * m]);
    let scan = scan_samples(layout.harmonics, layout.time_samples);
    let mut results = Vec::with_capacity(nt);
    for d in 0..nt {
        let r = direction(
            &element.params,
            &x[d * m..(d + 1) * m],
            v,
            slider[d],
            scan,
            jacobian,
        )?;
        slider[d] = r.slider;
        force[d * m..(d + 1) * m].copy_from_slice(&r.friction);
        if element.normal && d == 0 {
            force[nt * m..(nt + 1) * m].copy_from_slice(&r.normal);
        }
        results.push(r);
    }
    if jacobian {
        let cols = nsig * m + 1;
        let jac = ws.analytic_jacobian(nsig * m, cols);
        for (d, r) in results.iter().enumerate() {
            for k in 0..m {
                let src = &r.friction_jacobian[k * (2 * m + 1)..(k + 1) * (2 * m + 1)];
                let row = &mut jac[(d * m + k) * cols..(d * m + k + 1) * cols];
                row[d * m..(d + 1) * m].copy_from_slice(&src[..m]);
                if element.normal {
                    row[nt * m..(nt + 1) * m].copy_from_slice(&src[m..2 * m]);
                }
                row[cols - 1] = src[2 * m];
            }
        }
        if element.normal {
            let r = &results[0];
            for k in 0..m {
                let src = &r.normal_jacobian[k * (m + 1)..(k + 1) * (m + 1)];
                let row = &mut jac[(nt * m + k) * cols..(nt * m + k + 1) * cols];
                row[nt * m..(nt + 1) * m].copy_from_slice(&src[..m]);
                row[cols - 1] = src[m];
            }
        }
    }
    let n_t = layout.time_samples;
    let mut e = vec![0.0; m];
    for j in 0..n_t {
        let tau = TAU * j as f64 / n_t as f64;
        basis(tau, &mut e);
        let mut sample = Sample {
            force: [0.0; 3],
            slider: [0.0; 2],
            regime: [Regime::Stick; 2],
        };
        let mut u = [0.0; 2];
        let vj = v.map_or(0.0, |v| dot(v, &e));
        for (d, r) in results.iter().enumerate() {
            let ud = &x[d * m..(d + 1) * m];
            u[d] = dot(ud, &e);
            let (f, n, w, regime) = r.state_at(&element.params, ud, v, tau);
            sample.force[d] = f;
            sample.force[2] = n;
            sample.slider[d] = w;
            sample.regime[d] = regime;
        }
        if nt == 1 && sample.regime[0] == Regime::Separation {
            sample.regime[1] = Regime::Separation;
        }
        ws.store_exact(j, u, vj, &sample);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn params() -> ContactParams {
        ContactParams {
            kt: 3.0,
            kn: 2.0,
            mu: 0.4,
            n0: 1.0,
        }
    }

    /// ∫_a^b e_k e_l by the trapezoidal rule on a fine grid.
    #[test]
    fn product_integrals_equal_quadrature() {
        let m = 7;
        let (a, b) = (0.3, 2.9);
        let mut p = vec![0.0; m * m];
        product_integrals(a, b, m, &mut p);
        let n = 200_000;
        let mut q = vec![0.0; m * m];
        let mut e = vec![0.0; m];
        for j in 0..=n {
            let t = a + (b - a) * j as f64 / n as f64;
            let w = if j == 0 || j == n { 0.5 } else { 1.0 } * (b - a) / n as f64;
            basis(t, &mut e);
            for k in 0..m {
                for l in 0..m {
                    q[k * m + l] += w * e[k] * e[l];
                }
            }
        }
        for (x, y) in p.iter().zip(&q) {
            assert!((x - y).abs() < 1e-9, "{x} vs {y}");
        }
    }

    /// Complete stick from rest: f = k_t u exactly, F = k_t U.
    #[test]
    fn small_motion_sticks() {
        let p = params();
        let u = [0.01, 0.02, -0.01, 0.005, 0.003];
        let v = [0.0, 0.01, 0.0, 0.0, 0.002];
        let r = direction(&p, &u, Some(&v), 0.0, 64, true).unwrap();
        for (f, x) in r.friction.iter().zip(&u) {
            assert!((f - p.kt * x).abs() < 1e-13, "{f} vs {}", p.kt * x);
        }
    }
}

#[cfg(test)]
mod element_tests {
    use super::*;
    use crate::contact::element::evaluate_as;
    use crate::harmonics::HarmonicLayout;

    fn element(normal: bool, n0: f64) -> LocalElement {
        LocalElement {
            params: ContactParams {
                kt: 5.0,
                kn: 4.0,
                mu: 0.3,
                n0,
            },
            variant: Variant::OneD,
            tangential: 1,
            normal,
        }
    }

    /// U and V of a multi-harmonic motion (H = 3) that sticks, slips both ways and separates.
    fn motion(h: usize) -> Vec<f64> {
        let m = 2 * h + 1;
        let mut x = vec![0.0; 2 * m];
        let u = [0.05, 0.4, -0.1, 0.08, 0.05, -0.03, 0.02];
        let v = [0.02, 0.1, 0.12, -0.04, 0.03, 0.01, -0.02];
        x[..m].copy_from_slice(&u[..m]);
        x[m..].copy_from_slice(&v[..m]);
        x
    }

    fn run(
        ev: Evaluation,
        el: &LocalElement,
        layout: HarmonicLayout,
        x: &[f64],
        jacobian: bool,
    ) -> (Vec<f64>, Vec<f64>) {
        let aft = Aft::new(layout).unwrap();
        let mut ws = Workspace::new(&aft);
        let mut slider = [0.0; 2];
        let mut force = vec![0.0; x.len()];
        evaluate_as(ev, el, &aft, x, &mut slider, &mut force, jacobian, &mut ws).unwrap();
        let r = ws.report();
        println!(
            "{ev:?} N_t {}: stick {:.3} slip {:.3} separation {:.3}",
            layout.time_samples, r.stick, r.slip, r.separation
        );
        (force, ws.jacobian().0.to_vec())
    }

    use crate::case::Evaluation;

    /// The exact coefficients are the limit of the time-sampled law's: the AFT at N_t samples
    /// differs by O(1/N_t) (the sampled transition instants), here below 2e-4·k_t·|U| at
    /// N_t = 8192 and falling at least 3× from 2048 to 8192.
    #[test]
    fn aft_converges_to_the_exact_cycle() {
        let h = 3;
        let x = motion(h);
        let el = element(true, 0.1);
        let (exact, _) = run(
            Evaluation::Analytic,
            &el,
            HarmonicLayout::new(h, 64).unwrap(),
            &x,
            false,
        );
        let err = |nt: usize| {
            let (f, _) = run(
                Evaluation::Aft,
                &el,
                HarmonicLayout::new(h, nt).unwrap(),
                &x,
                false,
            );
            f.iter()
                .zip(&exact)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max)
        };
        let scale = el.params.kt * 0.4;
        let (e2, e8) = (err(2048), err(8192));
        println!("AFT − exact: {e2:.3e} at N_t = 2048, {e8:.3e} at 8192");
        assert!(e8 < 2e-4 * scale, "error {e8:.3e} at N_t = 8192");
        assert!(e2 > 3.0 * e8, "errors {e2:.3e} → {e8:.3e}");
    }

    /// The analytic Jacobian equals central differences of the exact map (∂/∂U, ∂/∂V, ∂/∂n0).
    #[test]
    fn jacobian_equals_central_differences() {
        let h = 3;
        let layout = HarmonicLayout::new(h, 64).unwrap();
        for (normal, n0) in [(true, 0.1), (true, 0.6), (false, 0.5)] {
            let el = element(normal, n0);
            let mut x = motion(h);
            if !normal {
                x.truncate(2 * h + 1);
            }
            let (_, jac) = run(Evaluation::Analytic, &el, layout, &x, true);
            let rows = x.len();
            let cols = rows + 1;
            let step = 1e-6;
            for c in 0..cols {
                let (plus, minus) = if c < rows {
                    let mut xp = x.clone();
                    let mut xm = x.clone();
                    xp[c] += step;
                    xm[c] -= step;
                    (
                        run(Evaluation::Analytic, &el, layout, &xp, false).0,
                        run(Evaluation::Analytic, &el, layout, &xm, false).0,
                    )
                } else {
                    let mut ep = el;
                    let mut em = el;
                    ep.params.n0 += step;
                    em.params.n0 -= step;
                    (
                        run(Evaluation::Analytic, &ep, layout, &x, false).0,
                        run(Evaluation::Analytic, &em, layout, &x, false).0,
                    )
                };
                for r in 0..rows {
                    let fd = (plus[r] - minus[r]) / (2.0 * step);
                    let an = jac[r * cols + c];
                    assert!(
                        (fd - an).abs() < 1e-6 * (1.0 + an.abs()),
                        "normal {normal} n0 {n0}: ∂F{r}/∂x{c}: analytic {an:.9e}, differences {fd:.9e}"
                    );
                }
            }
        }
    }

    /// At H = 1 the root-located cycle equals the closed-form cycle of [`super::super::microslip`]
    /// (evaluated as H = 1 in a layout of H = 2 whose second harmonic is zero).
    #[test]
    fn single_harmonic_motion_equals_the_closed_form() {
        let el = element(true, 0.1);
        let one = HarmonicLayout::new(1, 64).unwrap();
        let two = HarmonicLayout::new(2, 64).unwrap();
        let x1 = [0.05, 0.4, -0.1, 0.02, 0.1, 0.12];
        let x2 = [0.05, 0.4, -0.1, 0.0, 0.0, 0.02, 0.1, 0.12, 0.0, 0.0];
        let (f1, _) = run(Evaluation::Analytic, &el, one, &x1, false);
        let (f2, _) = run(Evaluation::Analytic, &el, two, &x2, false);
        for (i, j) in [(0, 0), (1, 1), (2, 2), (3, 5), (4, 6), (5, 7)] {
            assert!((f1[i] - f2[j]).abs() < 1e-12, "{i}: {} vs {}", f1[i], f2[j]);
        }
    }
}

#[cfg(test)]
mod history {
    use super::*;

    /// The map is a function of the harmonics: from 200 random warm sliders, multi-harmonic
    /// motions (H = 15, harmonics decaying as 1/n², stick to gross slip) give the cycle from
    /// rest to 1e-12.
    #[test]
    fn warm_start_gives_the_cycle_from_rest() {
        let p = ContactParams {
            kt: 10.0,
            kn: 0.0,
            mu: 1.0,
            n0: 1.0,
        };
        let h = 15;
        let m = 2 * h + 1;
        let mut seed = 12345u64;
        let mut rnd = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        for case in 0..200 {
            let mut u = vec![0.0; m];
            for (l, x) in u.iter_mut().enumerate() {
                let n = l.div_ceil(2);
                *x = rnd() * 2.0 / (1 + n * n) as f64;
            }
            let rest = direction(&p, &u, None, 0.0, 248, false).unwrap();
            let warm = direction(&p, &u, None, rest.slider + 0.3 * rnd(), 248, false).unwrap();
            let d = rest
                .friction
                .iter()
                .zip(&warm.friction)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(d < 1e-12, "case {case}: warm and rest differ by {d:.3e}");
        }
    }
}
