//! The closed form of a single-harmonic cycle with separation (Cigeroglu, An & Menq 2007,
//! §2.2.2): the contact window's phases in angles relative to the re-contact instant, their
//! integrals summed per state, and the forces and the Jacobian from small matrices.
//!
//! Symbols as in the parent module: g = k_t u1 − μ k_n v1 = |G| cos(τ + α_G),
//! h = k_t u1 + μ k_n v1 = |H| cos(τ + α_H) (N), n0e (N) the effective preload, the contact window
//! [τ_Sp2, τ_Sp1] of length 2 arccos(−n0e/|k_n V1|) (rad). In the frame of the re-contact,
//! θ = τ − τ_Sp2 ∈ [0, len], every event of the window is at a fixed angle (mod 2π) given by the
//! phase φ_X = τ_Sp2 + α_X of g or h at the re-contact, cos φ_X = x(τ_Sp2)/|X|, and the levels'
//! arccosines: no absolute phase angle α_G, α_H, α_V is formed.

use std::f64::consts::TAU;

use super::{
    ahead, angle, At, Harmonics, Motion, PhaseIntegrals, PointJacobian, Window, BEHIND, TANGENCY,
};
use crate::vec3::dot;

/// [sin x, cos x] of an angle x (rad).
type SinCos = [f64; 2];

/// Most phases of a contact window: the state entered at the re-contact and the four of one
/// stick–slip sequence after it (their four lengths add up to at least a period, so a fifth
/// boundary lies beyond the window).
const MOST_PHASES: usize = 5;

/// The contact states of a cycle with separation (Cigeroglu, An & Menq 2007, §2.2.2), numbered
/// in the order of the stick–slip sequence they follow each other in (positive slip, the stick
/// it leaves, negative slip, the stick it leaves, then positive slip again), and the stick after
/// a re-contact, which only the first phase of the window can be. The number indexes the ends of
/// [`Frame`] and the phase integrals summed per state.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum WindowState {
    /// f = +μ n, ending at the maximum of g.
    PositiveSlip = 0,
    /// Stick with w_P = u(τ_P) − μ n(τ_P)/k_t, ending where h falls through c_N.
    AfterPositiveSlip = 1,
    /// f = −μ n, ending at the minimum of h.
    NegativeSlip = 2,
    /// Stick with w_N = u(τ_N) + μ n(τ_N)/k_t, ending where g rises through c_P.
    AfterNegativeSlip = 3,
    /// Stick with w = u(τ_Sp2), ending where g rises or h falls through its re-contact value.
    AfterRecontact = 4,
}

impl WindowState {
    /// The state after this one in the stick–slip sequence (the stick after a re-contact is
    /// left by [`Frame::first`]).
    #[inline]
    fn following(self) -> WindowState {
        match self {
            WindowState::PositiveSlip => WindowState::AfterPositiveSlip,
            WindowState::AfterPositiveSlip => WindowState::NegativeSlip,
            WindowState::NegativeSlip => WindowState::AfterNegativeSlip,
            _ => WindowState::PositiveSlip,
        }
    }
}

/// The events of a cycle with separation in the frame of the re-contact instant τ_Sp2
/// (θ = τ − τ_Sp2, rad), from φ_G = τ_Sp2 + α_G and φ_H = τ_Sp2 + α_H, whose cosines and sines
/// are g(τ_Sp2)/|G|, −g′(τ_Sp2)/|G| and h(τ_Sp2)/|H|, −h′(τ_Sp2)/|H|:
/// * the maximum of g, θ_P ≡ −φ_G (eq. 8, θ_P of eq. 21);
/// * h falling through c_N = |G| − 2μ n0e, the level after positive slip (the slider w_P =
///   u(τ_P) − μ n(τ_P)/k_t in eq. 12), θ_StN ≡ β_N − φ_H with cos β_N = c_N/|H| (eq. 24);
/// * the minimum of h, θ_N ≡ π − φ_H (eq. 9, θ_N of eq. 22);
/// * g rising through c_P = 2μ n0e − |H|, the level after negative slip (eq. 11),
///   θ_StP ≡ −φ_G − β_P with cos β_P = c_P/|G| (eq. 23);
/// * after a re-contact in stick (w = u(τ_Sp2), n(τ_Sp2) = 0, so c_P = g(τ_Sp2) and
///   c_N = h(τ_Sp2)), g rising through its re-contact value at the mirror of τ_Sp2 about the
///   minimum of g, θ_SpP ≡ −2φ_G, or h falling through it at the mirror about the maximum of h,
///   θ_SpN ≡ −2φ_H (eqs 27–28).
///
/// Each as [sin θ, cos θ] by the addition theorems (no inverse function); a level beyond its
/// sinusoid's range (to [`TANGENCY`]) has no crossing, as in the event march.
struct Frame {
    /// The ends of the states of the stick–slip sequence, indexed by [`WindowState`]: θ_P,
    /// θ_StN, θ_N, θ_StP.
    ends: [SinCos; 4],
    /// Whether each end exists (the sticks' levels within the amplitude).
    exists: [bool; 4],
    /// [sin, cos] of φ_G and φ_H.
    phi_g: SinCos,
    phi_h: SinCos,
    /// g′(τ_Sp2) and h′(τ_Sp2) (N/rad), for the state at the re-contact (eqs 15–17).
    rates: [f64; 2],
}

impl Frame {
    /// The frame of the re-contact instant `recontact` ([sin, cos] of τ_Sp2).
    #[inline(always)]
    fn new(mo: &Motion, [s, c]: SinCos) -> Frame {
        let (g, h) = (&mo.g, &mo.h);
        let at = At { t: f64::NAN, s, c };
        // −g′/|G| = sin φ_G and −h′/|H| = sin φ_H
        let (sg, cg) = (g.sa * c + g.ca * s, g.ca * c - g.sa * s);
        let (sh, ch) = (h.sa * c + h.ca * s, h.ca * c - h.sa * s);
        let mun2 = 2.0 * mo.p.mu * mo.n0e;
        let r_n = ((g.amp - mun2) * h.inv).clamp(-1.0, 1.0);
        let r_p = ((mun2 - h.amp) * g.inv).clamp(-1.0, 1.0);
        let sb_n = ((1.0 - r_n) * (1.0 + r_n)).sqrt();
        let sb_p = ((1.0 - r_p) * (1.0 + r_p)).sqrt();
        Frame {
            ends: [
                [-sg, cg],
                [sb_n * ch - r_n * sh, r_n * ch + sb_n * sh],
                [sh, -ch],
                [-(sg * r_p + cg * sb_p), cg * r_p - sg * sb_p],
            ],
            exists: [true, r_n > -1.0 + TANGENCY, true, r_p < 1.0 - TANGENCY],
            phi_g: [sg, cg],
            phi_h: [sh, ch],
            rates: [g.rate(at), h.rate(at)],
        }
    }

    /// The state entered at the re-contact (eqs 15–17: positive slip if g′ > 0, negative slip if
    /// h′ < 0, else stick with f = 0), the end of its phase ([sin θ, cos θ]; `None` if only the
    /// separation ends it) and the state after that end. The stick after the re-contact ends at
    /// the earlier of its two mirrors: with g′ ≤ 0 and h′ ≥ 0 there, φ_G ∈ [0, π] and
    /// φ_H ∈ [−π, 0], so θ_SpP = 2 arccos(−cos φ_G) and θ_SpN = 2 arccos(cos φ_H), and g's comes
    /// first iff −cos φ_G ≥ cos φ_H (g's on a tie, as in the event march).
    #[inline(always)]
    fn first(&self) -> (WindowState, Option<SinCos>, WindowState) {
        let [g_rate, h_rate] = self.rates;
        if g_rate > 0.0 {
            return (
                WindowState::PositiveSlip,
                Some(self.ends[0]),
                WindowState::AfterPositiveSlip,
            );
        }
        if h_rate < 0.0 {
            return (
                WindowState::NegativeSlip,
                Some(self.ends[2]),
                WindowState::AfterNegativeSlip,
            );
        }
        let ([sg, cg], [sh, ch]) = (self.phi_g, self.phi_h);
        let positive = cg < 1.0 - TANGENCY;
        let negative = ch > -1.0 + TANGENCY;
        let (end, next) = if positive && (!negative || -cg >= ch) {
            (
                Some([-2.0 * sg * cg, (cg - sg) * (cg + sg)]),
                WindowState::PositiveSlip,
            )
        } else if negative {
            (
                Some([-2.0 * sh * ch, (ch - sh) * (ch + sh)]),
                WindowState::NegativeSlip,
            )
        } else {
            (None, WindowState::PositiveSlip)
        };
        (WindowState::AfterRecontact, end, next)
    }
}

/// (θ, sin τ, cos τ, sin τ cos τ, sin² τ) of an instant at θ (rad) from the re-contact with
/// [sin τ, cos τ] = `sc`: a phase's integrals ([`PhaseIntegrals`]) are the differences of these
/// between its ends.
#[inline(always)]
fn ends_values(theta: f64, [s, c]: SinCos) -> [f64; 5] {
    [theta, s, c, s * c, s * s]
}

/// The phases of a contact window from the re-contact `recontact` to the separation `separation`
/// ([sin, cos] of τ_Sp2 and τ_Sp1 = τ_Sp2 + `len`), integrated as they are found: the state
/// entered at the re-contact, then the stick–slip sequence, each phase ending at the one event its
/// state allows ([`Frame`]) or at the separation, whichever comes first. An event's position is
/// the first θ at or after the phase's start at its angle, one inverse function of its
/// [sin θ, cos θ] ([`angle`], [`ahead`]: an event less than a rounding behind the start is
/// immediate, as in the event march); its instant's sine and cosine by the addition theorems.
/// The window holds at most [`MOST_PHASES`] phases: the four of the sequence after the first add
/// up to a whole period, so a fifth boundary lies beyond the window unless they all coincide.
///
/// Returns the phase integrals summed per state (indexed by [`WindowState`]) and the state at
/// τ ≡ 0 (mod 2π; `None`: separated), found by the signs of the phases' ends
/// ([`arc_holds_zero`]; at a boundary both neighbours give the same slider state); `None` where
/// the march is needed (coinciding events, or rounding leaves τ ≡ 0 on no phase).
#[inline(always)]
fn walk(
    frame: &Frame,
    recontact: SinCos,
    separation: SinCos,
    len: f64,
) -> Option<([PhaseIntegrals; 5], Option<WindowState>)> {
    let (mut state, mut end, mut next) = frame.first();
    let [s_r, c_r] = recontact;
    let mut sums = [PhaseIntegrals::default(); 5];
    let (mut a, mut a_sc) = (ends_values(0.0, recontact), recontact);
    let mut at_zero = None;
    let mut theta_1 = 0.0;
    for i in 1..=MOST_PHASES {
        let mut b_sc = separation;
        let mut theta = len;
        if let Some([s, c]) = end {
            if i == MOST_PHASES {
                // the fifth boundary is the first one a period later, beyond the window,
                // unless the four events of the sequence coincide
                if a[0] - theta_1 <= BEHIND {
                    return None;
                }
            } else {
                let d = ahead(angle(c, s), a[0]);
                if a[0] + d < len {
                    theta = a[0] + d;
                    b_sc = [s_r * c + c_r * s, c_r * c - s_r * s];
                }
            }
        }
        let b = ends_values(theta, b_sc);
        let sum = &mut sums[state as usize].0;
        for k in 0..5 {
            sum[k] += b[k] - a[k];
        }
        if at_zero.is_none() && arc_holds_zero(a_sc, b_sc, theta - a[0]) {
            at_zero = Some(state);
        }
        if theta >= len {
            break;
        }
        if i == 1 {
            theta_1 = theta;
        }
        (a, a_sc) = (b, b_sc);
        state = next;
        let k = next as usize;
        end = frame.exists[k].then_some(frame.ends[k]);
        next = next.following();
    }
    if at_zero.is_none() && !arc_holds_zero(separation, recontact, TAU - len) {
        return None;
    }
    Some((sums, at_zero))
}

/// Whether the arc from the instant `a` to `b` (each [sin, cos]) of the given length (rad, in
/// [0, 2π]) holds τ ≡ 0 (mod 2π), by signs (no angle): an arc of length ≤ π holds it iff it runs
/// from the lower half-plane (sin ≤ 0) to the upper one (sin ≥ 0) through cos > 0
/// (cos a + cos b ≥ 0), a longer one iff its complement does not (sin b < 0 and sin a > 0).
#[inline(always)]
fn arc_holds_zero([sa, ca]: SinCos, [sb, cb]: SinCos, length: f64) -> bool {
    if length <= std::f64::consts::PI {
        sa <= 0.0 && sb >= 0.0 && ca + cb >= 0.0
    } else {
        !(sb < 0.0 && sa > 0.0)
    }
}

/// The harmonics of a point whose contact window is part of the period (Cigeroglu, An & Menq
/// 2007, §2.2.2) into `out` and, if given, its Jacobian into `jac`, in closed form: the window's
/// phases in the frame of the re-contact ([`walk`]: the cycle starts at the re-contact τ_Sp2,
/// history-free, so the caller's slider does not enter), their integrals summed per state, and
/// the forces from small matrices ([`separation_forces`]). The phases are those of the event
/// march of the parent module (to rounding). False where the march is needed: no separation, a
/// degenerate sinusoid (|G| = 0 or |H| = 0, k_t = 0), coinciding events, or τ ≡ 0 on no phase
/// by rounding.
#[inline(always)]
pub(super) fn separation_form(
    mo: &Motion,
    jac: Option<&mut PointJacobian>,
    out: &mut Harmonics,
) -> bool {
    let Window::Part {
        recontact,
        separation,
        len,
        ..
    } = mo.window
    else {
        return false;
    };
    if mo.p.kt <= 0.0 || mo.g.amp <= 0.0 || mo.h.amp <= 0.0 {
        return false;
    }
    let frame = Frame::new(mo, recontact);
    let Some((sums, at_zero)) = walk(&frame, recontact, separation, len) else {
        return false;
    };
    let window = PhaseIntegrals::between(0.0, recontact, len, separation);
    separation_forces(mo, &sums, &window, recontact, jac, out);
    out.slider = slider_at_zero(mo, at_zero, recontact);
    true
}

/// e(τ) = (1, cos τ, −sin τ) of the maximum of g (τ_P = −α_G), the minimum of h (τ_N = π − α_H)
/// and the re-contact instant `recontact` ([sin, cos] of τ_Sp2): where the sliders of the three
/// sticks are set.
#[inline(always)]
fn slider_instants(mo: &Motion, [s_r, c_r]: SinCos) -> [[f64; 3]; 3] {
    [
        [1.0, mo.g.ca, mo.g.sa],
        [1.0, -mo.h.ca, -mo.h.sa],
        [1.0, c_r, -s_r],
    ]
}

/// The friction and normal forces, the energy and, if given, the Jacobian of a cycle with
/// separation into `out` and `jac`, from the phase integrals summed per state (`sums`, indexed
/// by [`WindowState`]), those of the whole window (`window`) and the re-contact instant
/// `recontact` ([sin, cos] of τ_Sp2).
///
/// With M(·) the projection of a sum of phases ([`PhaseIntegrals::projection`]), m_P, m_N, m_R
/// the first columns of the projections of the sticks after positive slip, after negative slip
/// and after the re-contact, e_P, e_N, e_R the basis e(τ) where their sliders are set
/// ([`slider_instants`]) and N = (n0e, k_n V1, k_n V2) (N), the sliders w_P = e_P·U − (μ/k_t)
/// e_P·N, w_N = e_N·U + (μ/k_t) e_N·N and w_R = u(τ_Sp2) = e_R·U make the friction force of
/// eq. 29, F = k_t (M_stick U − w_P m_P − w_N m_N − w_R m_R) + μ M_slip N, linear in U and N:
/// F = k_t A U + μ B N with A = M_stick − m_P ⊗ e_P − m_N ⊗ e_N − m_R ⊗ e_R and
/// B = M_slip + m_P ⊗ e_P − m_N ⊗ e_N (3 × 3, dimensionless; M_slip of positive minus negative
/// slip). The force is continuous at every phase end (f = 0 at both ends of the window), so the
/// ends' derivatives cancel; τ_P and τ_N are extrema (their τ-derivatives vanish) and τ_Sp2
/// moves with n0e + k_n v1(τ_Sp2) = 0, ∂w_R = e_R·∂U + r_R (k_n e_R·∂V + ∂n0) with
/// r_R = −u1′(τ_Sp2)/(k_n v1′(τ_Sp2)) (m/N). So ∂F/∂U = k_t A, ∂F/∂V = k_n (μ B − k_t r_R
/// m_R ⊗ e_R) and ∂F/∂n0 = μ B_·0 − k_t r_R m_R (N/m, –). The normal force over the window is
/// N = M_window N with the rows k_n M_window on V and M_window_·0 on n0. A_·0 = 0: F does not
/// depend on U0.
#[inline(always)]
fn separation_forces(
    mo: &Motion,
    [pos, stick_p, neg, stick_n, stick_r]: &[PhaseIntegrals; 5],
    window: &PhaseIntegrals,
    recontact: SinCos,
    jac: Option<&mut PointJacobian>,
    out: &mut Harmonics,
) {
    let (kt, kn, mu) = (mo.p.kt, mo.p.kn, mo.p.mu);
    let mut stick = *stick_p;
    stick.add(stick_n, 1.0);
    stick.add(stick_r, 1.0);
    let mut slip = *pos;
    slip.add(neg, -1.0);
    let (m_stick, m_slip) = (stick.projection(), slip.projection());
    let (m_p, m_n, m_r) = (
        stick_p.first_column(),
        stick_n.first_column(),
        stick_r.first_column(),
    );
    let [e_p, e_n, e_r] = slider_instants(mo, recontact);
    // k_t A and μ B
    let (mut ka, mut mb) = (m_stick, m_slip);
    add_outer(&mut ka, m_p, e_p, -1.0);
    add_outer(&mut ka, m_n, e_n, -1.0);
    add_outer(&mut ka, m_r, e_r, -1.0);
    add_outer(&mut mb, m_p, e_p, 1.0);
    add_outer(&mut mb, m_n, e_n, -1.0);
    for k in 0..3 {
        // A_·0 = 0 (M_stick's first column is m_P + m_N + m_R)
        ka[k] = [0.0, kt * ka[k][1], kt * ka[k][2]];
        mb[k] = mb[k].map(|x| mu * x);
    }
    let (u, cn) = (mo.u, [mo.n0e, mo.nv[0], mo.nv[1]]);
    let m_window = window.projection();
    for k in 0..3 {
        out.friction[k] = dot(ka[k], u) + dot(mb[k], cn);
        out.normal[k] = dot(m_window[k], cn);
    }
    out.energy = std::f64::consts::PI * (u[1] * out.friction[2] - u[2] * out.friction[1]);
    let Some(j) = jac else {
        return;
    };
    // k_t r_R with r_R = −u1′/(k_n v1′) at τ_Sp2 (0 where v1′ = 0: a tangent window)
    let [s_r, c_r] = recontact;
    let dv = kn * (mo.v[1] * s_r + mo.v[2] * c_r);
    let q = if dv.abs() > 0.0 {
        -kt * (mo.u[1] * s_r + mo.u[2] * c_r) / dv
    } else {
        0.0
    };
    for k in 0..3 {
        let [a, b] = [ka[k], mb[k]];
        let qm = q * m_r[k];
        j[k] = [
            a[0],
            a[1],
            a[2],
            kn * (b[0] - qm),
            kn * (b[1] - qm * e_r[1]),
            kn * (b[2] - qm * e_r[2]),
            b[0] - qm,
        ];
        let w = m_window[k];
        j[3 + k] = [0.0, 0.0, 0.0, kn * w[0], kn * w[1], kn * w[2], w[0]];
    }
}

/// m + k a ⊗ b (3 × 3).
#[inline(always)]
fn add_outer(m: &mut [[f64; 3]; 3], a: [f64; 3], b: [f64; 3], k: f64) {
    for (row, ak) in m.iter_mut().zip(a) {
        for (x, bl) in row.iter_mut().zip(b) {
            *x += k * (ak * bl);
        }
    }
}

/// The slider state at τ ≡ 0 in the state `at_zero` (`None`: separation): w = u(0) − f(0)/k_t,
/// that is the stick's slider (w_P, w_N at the extremum that set it, u(τ_Sp2) after the
/// re-contact), u(0) ∓ μ n(0)/k_t in positive or negative slip, u(0) separated (m).
#[inline(always)]
fn slider_at_zero(mo: &Motion, at_zero: Option<WindowState>, recontact: SinCos) -> f64 {
    let [e_p, e_n, e_r] = slider_instants(mo, recontact);
    let zero = [1.0, 1.0, 0.0];
    let (e, sign) = match at_zero {
        None => (zero, 0.0),
        Some(WindowState::PositiveSlip) => (zero, -1.0),
        Some(WindowState::NegativeSlip) => (zero, 1.0),
        Some(WindowState::AfterPositiveSlip) => (e_p, -1.0),
        Some(WindowState::AfterNegativeSlip) => (e_n, 1.0),
        Some(WindowState::AfterRecontact) => (e_r, 0.0),
    };
    let cn = [mo.n0e, mo.nv[0], mo.nv[1]];
    dot(e, mo.u) + sign * mo.p.mu / mo.p.kt * dot(e, cn)
}
