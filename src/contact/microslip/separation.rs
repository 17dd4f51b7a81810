//! The closed form of a single-harmonic cycle with separation (Cigeroglu, An & Menq 2007,
//! §2.2.2): the contact window as six phases of fixed states, their boundaries at angles from the
//! re-contact instant, the phase integrals summed per state, and the forces and the Jacobian from
//! small matrices.
//!
//! Symbols as in the parent module: g = k_t u1 − μ k_n v1 = |G| cos(τ + α_G),
//! h = k_t u1 + μ k_n v1 = |H| cos(τ + α_H) (N), n0e (N) the effective preload, the contact window
//! [τ_Sp2, τ_Sp1] of length len = 2 arccos(−n0e/|k_n V1|) (rad), θ = τ − τ_Sp2 ∈ [0, len] the
//! angle from the re-contact. After the phase the re-contact enters (eqs 15–17) the phases follow
//! the stick–slip sequence (positive slip, stick, negative slip, stick), each ending at a fixed
//! instant mod 2π ([`sequence_ends`]) after a fixed length ([`sequence_lengths`]), so every
//! boundary is the first event's angle plus lengths of the sequence, cut at len: no event is
//! searched for, and the five inverse functions (the window's length, the first event, β_N, β_P
//! and δ) are independent of each other. No absolute phase angle α_G, α_H, α_V is formed.

use std::f64::consts::{FRAC_1_PI, PI, TAU};

use super::{
    ahead, angle, sequence_ends, sequence_lengths, Arc, At, Harmonics, Motion, PhaseIntegrals,
    PointJacobian, Window, TANGENCY,
};
use crate::vec3::dot;

/// [sin x, cos x] of an angle x (rad).
type SinCos = [f64; 2];

/// e(τ) = (1, cos τ, −sin τ) of an instant given as [sin τ, cos τ].
#[inline(always)]
fn basis([s, c]: SinCos) -> [f64; 3] {
    [1.0, c, -s]
}

/// The phase a re-contact enters (Cigeroglu, An & Menq 2007, eqs 15–17: positive slip if
/// g′(τ_Sp2) > 0, negative slip if h′(τ_Sp2) < 0, else stick with f = 0) and where the first
/// slip of the window ends.
struct First {
    /// Whether the re-contact enters stick (the stick after a re-contact, left by a slip).
    stick: bool,
    /// σ = +1 (true) if the first slip of the window is positive, −1 if negative.
    positive: bool,
    /// The angles from the re-contact (rad) of the end of the stick after the re-contact (0 if
    /// the re-contact enters a slip, ∞ if only the separation ends the stick) and of the end of
    /// the first slip.
    theta: [f64; 2],
    /// [sin θ, cos θ] of the stick's end (relative to the re-contact; [0, 1] without a stick).
    end: SinCos,
}

impl First {
    /// The first phases of the window from the re-contact `recontact` ([sin, cos] of τ_Sp2),
    /// with φ_G = τ_Sp2 + α_G and φ_H = τ_Sp2 + α_H, whose cosines and sines are g(τ_Sp2)/|G|,
    /// −g′(τ_Sp2)/|G| and h(τ_Sp2)/|H|, −h′(τ_Sp2)/|H| (addition theorems, no α): positive slip
    /// ends at the maximum of g, θ_P ≡ −φ_G (eq. 8, θ_P of eq. 21), negative slip at the minimum
    /// of h, θ_N ≡ π − φ_H (eq. 9, θ_N of eq. 22), one inverse function of [sin θ, cos θ]
    /// ([`angle`], [`ahead`]: an end less than a rounding behind the re-contact is immediate, as
    /// in the event march). After a re-contact in stick (w = u(τ_Sp2), n(τ_Sp2) = 0, so
    /// c_P = g(τ_Sp2) and c_N = h(τ_Sp2)) g rises through its re-contact value at the mirror of
    /// τ_Sp2 about the minimum of g, θ_SpP ≡ −2φ_G, and h falls through it at the mirror about
    /// the maximum of h, θ_SpN ≡ −2φ_H (eqs 27–28); with g′ ≤ 0 and h′ ≥ 0 there, φ_G ∈ [0, π]
    /// and φ_H ∈ [−π, 0], so with a = π − φ_G = arccos(−cos φ_G) or a = −φ_H = arccos(cos φ_H)
    /// (one inverse function of its cosine and sine, [`angle`]: well conditioned where the
    /// cosine is near ±1) the stick lasts 2a and the slip after it π − a (to θ_P or θ_N), and
    /// g's mirror comes first iff
    /// −cos φ_G ≥ cos φ_H (g's on a tie, as in the event march); a level at its sinusoid's
    /// extremum (to [`TANGENCY`]) has no crossing.
    #[inline(always)]
    fn new(mo: &Motion, [s_r, c_r]: SinCos) -> First {
        let (g, h) = (&mo.g, &mo.h);
        let at = At {
            t: f64::NAN,
            s: s_r,
            c: c_r,
        };
        let (sg, cg) = (g.sa * c_r + g.ca * s_r, g.ca * c_r - g.sa * s_r);
        let (sh, ch) = (h.sa * c_r + h.ca * s_r, h.ca * c_r - h.sa * s_r);
        if g.rate(at) > 0.0 {
            return First::slip(true, [-sg, cg]);
        }
        if h.rate(at) < 0.0 {
            return First::slip(false, [sh, -ch]);
        }
        let rising = cg < 1.0 - TANGENCY;
        let falling = ch > -1.0 + TANGENCY;
        // a = π − φ_G or −φ_H, each in [0, π] from its cosine and its sine (≥ 0)
        let (positive, end, [c, s]) = if rising && (!falling || -cg >= ch) {
            (true, [-2.0 * sg * cg, (cg - sg) * (cg + sg)], [-cg, sg])
        } else if falling {
            (false, [-2.0 * sh * ch, (ch - sh) * (ch + sh)], [ch, -sh])
        } else {
            return First {
                stick: true,
                positive: true,
                theta: [f64::INFINITY; 2],
                end: [0.0, 1.0],
            };
        };
        let a = angle(c, s);
        First {
            stick: true,
            positive,
            theta: [2.0 * a, 2.0 * a + (PI - a)],
            end,
        }
    }

    /// The re-contact entering the slip of sign `positive`, which ends at [sin θ, cos θ] = `end`.
    #[inline(always)]
    fn slip(positive: bool, [s, c]: SinCos) -> First {
        First {
            stick: false,
            positive,
            theta: [0.0, ahead(angle(c, s), 0.0)],
            end: [0.0, 1.0],
        }
    }
}

/// The phases of a contact window from the re-contact τ_Sp2 to the separation τ_Sp1 in six slots
/// of fixed states: the stick after a re-contact, the slip of sign σ, the stick after it (slider
/// set at that slip's end), the slip of sign −σ, the stick after it and the slip of sign σ again
/// (σ = +1 if the window's first slip is positive). A window is these six phases with some of
/// them empty: the first at the re-contact unless the re-contact enters stick, those beyond the
/// separation at the separation (a phase of zero length adds exactly zero to every integral).
struct Slots {
    /// [sin τ, cos τ] of the seven boundaries: the re-contact, then the end of each slot (the
    /// last the separation).
    at: [SinCos; 7],
    /// The boundaries' angles θ from the re-contact (rad; 0 ≤ θ_1 ≤ … ≤ θ_6 = len).
    theta: [f64; 7],
    /// σ (+1 or −1).
    sign: f64,
    /// [sin, cos] of the ends of the two slips (slots 2 and 4), where the sliders of the sticks
    /// after them are set: τ_P and τ_N (σ = +1) or τ_N and τ_P (σ = −1).
    slip_ends: [SinCos; 2],
}

impl Slots {
    /// The slots of the window of `len` (rad) from `recontact` to `separation` ([sin, cos] of
    /// τ_Sp2 and τ_Sp1). The first phase ([`First`]) ends at θ_1; the sequence after it ends at
    /// θ_1 plus its lengths ([`sequence_lengths`]: positive slip β_P, stick after it β_N − δ,
    /// negative slip π − β_N, stick after it δ − β_P − π, each mod 2π, with c_N = |G| − 2μ n0e
    /// and c_P = 2μ n0e − |H| the levels after positive and negative slip, eqs 11–12 and 23–24;
    /// a stick whose level is beyond its sinusoid's range, to [`TANGENCY`], lasts to the
    /// separation), at the instants of [`sequence_ends`]; a boundary at or beyond len is the
    /// separation. `None` where the march is needed: the four events of the sequence coincide, so
    /// that a sixth phase would start inside the window.
    #[inline(always)]
    fn new(mo: &Motion, recontact: SinCos, separation: SinCos, len: f64) -> Option<Slots> {
        let (g, h) = (&mo.g, &mo.h);
        let mun2 = 2.0 * mo.p.mu * mo.n0e;
        let arc_n = Arc::side_by_side((g.amp - mun2) * h.inv);
        let arc_p = Arc::side_by_side((mun2 - h.amp) * g.inv);
        let [p, stn, n, stp] = sequence_ends(g, h, arc_n, arc_p);
        let [mut l_stn, l_n, mut l_stp, l_p] = sequence_lengths(g, h, arc_n, arc_p, false);
        if arc_n.r <= -1.0 + TANGENCY {
            l_stn = f64::INFINITY;
        }
        if arc_p.r >= 1.0 - TANGENCY {
            l_stp = f64::INFINITY;
        }
        let first = First::new(mo, recontact);
        // the ends of slots 2–5 and the lengths of slots 2–5 (slot 6's is slot 2's)
        let ([e2, e3, e4, e5], [l2, l3, l4, l5]) = if first.positive {
            ([p, stn, n, stp], [l_p, l_stn, l_n, l_stp])
        } else {
            ([n, stp, p, stn], [l_n, l_stp, l_p, l_stn])
        };
        let [s_r, c_r] = recontact;
        let [t1, t2] = first.theta;
        let e1 = if first.stick {
            let [s, c] = first.end;
            [s_r * c + c_r * s, c_r * c - s_r * s]
        } else {
            recontact
        };
        let t3 = t2 + l3;
        let t4 = t3 + l4;
        let t5 = t4 + l5;
        // the end of the window's last phase (slot 5 after a stick, else slot 6) lies beyond it
        let last = if first.stick { t5 } else { t5 + l2 };
        if last < len {
            return None;
        }
        let cut = |t: f64, e: SinCos| if t < len { (t, e) } else { (len, separation) };
        let [(t1, e1), (t2, e2c), (t3, e3), (t4, e4c), (t5, e5)] = [
            cut(t1, e1),
            cut(t2, e2),
            cut(t3, e3),
            cut(t4, e4),
            cut(t5, e5),
        ];
        Some(Slots {
            at: [recontact, e1, e2c, e3, e4c, e5, separation],
            theta: [0.0, t1, t2, t3, t4, t5, len],
            sign: if first.positive { 1.0 } else { -1.0 },
            slip_ends: [e2, e4],
        })
    }

    /// The phase integrals ([`PhaseIntegrals`]) of the sticks' sum, of σ times positive minus
    /// negative slip and of the whole window, and of the three sticks (after the re-contact,
    /// after the slip of sign σ, after the slip of sign −σ), from the boundaries' values
    /// ([`ends_values`]): each slot the difference of its two ends.
    #[inline(always)]
    fn integrals(&self) -> [PhaseIntegrals; 6] {
        let x: [[f64; 5]; 7] = std::array::from_fn(|k| ends_values(self.theta[k], self.at[k]));
        let slot = |k: usize| -> [f64; 5] { std::array::from_fn(|i| x[k][i] - x[k - 1][i]) };
        let [r, s1, a, s2, b, s3] = [slot(1), slot(2), slot(3), slot(4), slot(5), slot(6)];
        [
            PhaseIntegrals(std::array::from_fn(|i| r[i] + a[i] + b[i])),
            PhaseIntegrals(std::array::from_fn(|i| s1[i] - s2[i] + s3[i])),
            PhaseIntegrals(std::array::from_fn(|i| x[6][i] - x[0][i])),
            PhaseIntegrals(r),
            PhaseIntegrals(a),
            PhaseIntegrals(b),
        ]
    }

    /// The slot holding τ ≡ 0 (mod 2π): 1–6, 0 if it lies between the separation and the
    /// re-contact, by the signs of the boundaries ([`arc_holds_zero`]; at a boundary both
    /// neighbours give the same slider state); `None` where rounding leaves it on no phase.
    #[inline(always)]
    fn slot_of_zero(&self) -> Option<usize> {
        for k in 1..7 {
            let length = self.theta[k] - self.theta[k - 1];
            if arc_holds_zero(self.at[k - 1], self.at[k], length) {
                return Some(k);
            }
        }
        arc_holds_zero(self.at[6], self.at[0], TAU - self.theta[6]).then_some(0)
    }
}

/// (θ, sin τ, cos τ, sin τ cos τ, sin² τ) of an instant at θ (rad) from the re-contact with
/// [sin τ, cos τ] = `sc`: a phase's integrals ([`PhaseIntegrals`]) are the differences of these
/// between its ends.
#[inline(always)]
fn ends_values(theta: f64, [s, c]: SinCos) -> [f64; 5] {
    [theta, s, c, s * c, s * s]
}

/// Whether the arc from the instant `a` to `b` (each [sin, cos]) of the given length (rad, in
/// [0, 2π]) holds τ ≡ 0 (mod 2π), by signs (no angle): an arc of length ≤ π holds it iff it runs
/// from the lower half-plane (sin ≤ 0) to the upper one (sin ≥ 0) through cos > 0
/// (cos a + cos b ≥ 0), a longer one iff its complement does not (sin b < 0 and sin a > 0).
#[inline(always)]
fn arc_holds_zero([sa, ca]: SinCos, [sb, cb]: SinCos, length: f64) -> bool {
    if length <= PI {
        sa <= 0.0 && sb >= 0.0 && ca + cb >= 0.0
    } else {
        !(sb < 0.0 && sa > 0.0)
    }
}

/// The harmonics of a point whose contact window is part of the period (Cigeroglu, An & Menq
/// 2007, §2.2.2) into `out` and, if given, its Jacobian into `jac`, in closed form: the window's
/// phases in six slots of fixed states ([`Slots`]: the cycle starts at the re-contact τ_Sp2,
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
    let Some(slots) = Slots::new(mo, recontact, separation, len) else {
        return false;
    };
    let Some(zero) = slots.slot_of_zero() else {
        return false;
    };
    separation_forces(mo, &slots, jac, out);
    out.slider = slider_at_zero(mo, &slots, zero);
    true
}

/// The friction and normal forces, the energy and, if given, the Jacobian of a cycle with
/// separation into `out` and `jac`, from the window's slots ([`Slots::integrals`]).
///
/// With M(·) the projection of a sum of phases ([`PhaseIntegrals::projection`]), m_A, m_B, m_R
/// the first columns of the projections of the sticks after the slip of sign σ, after the slip
/// of sign −σ and after the re-contact, e_A, e_B, e_R the basis e(τ) where their sliders are set
/// (the two slips' ends, [`Slots::slip_ends`], and τ_Sp2) and N = (n0e, k_n V1, k_n V2) (N): the
/// sliders w_P = e_P·U − (μ/k_t) e_P·N, w_N = e_N·U + (μ/k_t) e_N·N and w_R = u(τ_Sp2) = e_R·U make
/// the friction force of eq. 29, F = k_t (M_stick U − w_P m_P − w_N m_N − w_R m_R) + μ M_slip N,
/// linear in U and N: F = k_t A U + μ B N with A = M_stick − m_A ⊗ e_A − m_B ⊗ e_B − m_R ⊗ e_R
/// and B = σ (M_σslip + m_A ⊗ e_A − m_B ⊗ e_B) (3 × 3, dimensionless; M_σslip of σ times
/// positive minus negative slip). The force is continuous at every phase end (f = 0 at both ends
/// of the window), so the ends' derivatives cancel; τ_P and τ_N are extrema (their τ-derivatives
/// vanish) and τ_Sp2 moves with n0e + k_n v1(τ_Sp2) = 0, ∂w_R = e_R·∂U + r_R (k_n e_R·∂V + ∂n0)
/// with r_R = −u1′(τ_Sp2)/(k_n v1′(τ_Sp2)) (m/N). So ∂F/∂U = k_t A, ∂F/∂V = k_n (μ B − k_t r_R
/// m_R ⊗ e_R) and ∂F/∂n0 = μ B_·0 − k_t r_R m_R (N/m, –). The normal force over the window is
/// N = M_window N with the rows k_n M_window on V and M_window_·0 on n0. A_·0 = 0 (M_stick's
/// first column is m_A + m_B + m_R): F does not depend on U0, and A's first column is not formed.
#[inline(always)]
fn separation_forces(
    mo: &Motion,
    slots: &Slots,
    jac: Option<&mut PointJacobian>,
    out: &mut Harmonics,
) {
    let [stick, slip, window, stick_r, stick_a, stick_b] = slots.integrals();
    // π M of each sum (the factor 1/π folded into k_t, μ and k_n below) and π m of each stick
    let (p_stick, p_slip, p_window) = (
        stick.projection_pi(),
        slip.projection_pi(),
        window.projection_pi(),
    );
    let [m_r, m_a, m_b] = [stick_r, stick_a, stick_b].map(|i| i.first_column_pi());
    let (kt, kn) = (mo.p.kt, mo.p.kn);
    let (ktq, muq, q) = (kt * FRAC_1_PI, slots.sign * mo.p.mu * FRAC_1_PI, FRAC_1_PI);
    let [e_a, e_b] = slots.slip_ends.map(basis);
    let recontact = slots.at[0];
    let e_r = basis(recontact);
    let (u, cn) = (mo.u, [mo.n0e, mo.nv[0], mo.nv[1]]);
    // k_t A (columns 1 and 2) and μ B, row by row
    let mut ka = [[0.0; 2]; 3];
    let mut mb = [[0.0; 3]; 3];
    for k in 0..3 {
        let (pa, pb, pr) = (m_a[k], m_b[k], m_r[k]);
        for l in 1..3 {
            ka[k][l - 1] = ktq * (p_stick[k][l] - pa * e_a[l] - pb * e_b[l] - pr * e_r[l]);
        }
        mb[k][0] = muq * (p_slip[k][0] + pa - pb);
        for l in 1..3 {
            mb[k][l] = muq * (p_slip[k][l] + pa * e_a[l] - pb * e_b[l]);
        }
        out.friction[k] = ka[k][0] * u[1] + ka[k][1] * u[2] + dot(mb[k], cn);
        out.normal[k] = q * dot(p_window[k], cn);
    }
    out.energy = PI * (u[1] * out.friction[2] - u[2] * out.friction[1]);
    let Some(j) = jac else {
        return;
    };
    // k_t r_R / π with r_R = −u1′/(k_n v1′) at τ_Sp2 (0 where v1′ = 0: a tangent window)
    let [s_r, c_r] = recontact;
    let dv = kn * (mo.v[1] * s_r + mo.v[2] * c_r);
    let r = if dv.abs() > 0.0 {
        -ktq * (u[1] * s_r + u[2] * c_r) / dv
    } else {
        0.0
    };
    let knq = kn * FRAC_1_PI;
    for k in 0..3 {
        let ([a1, a2], [b0, b1, b2]) = (ka[k], mb[k]);
        let rm = r * m_r[k];
        j[k] = [
            0.0,
            a1,
            a2,
            kn * (b0 - rm),
            kn * (b1 - rm * e_r[1]),
            kn * (b2 - rm * e_r[2]),
            b0 - rm,
        ];
        let w = p_window[k];
        j[3 + k] = [0.0, 0.0, 0.0, knq * w[0], knq * w[1], knq * w[2], q * w[0]];
    }
}

/// The slider state at τ ≡ 0 in the slot `zero` ([`Slots::slot_of_zero`]; 0: separated):
/// w = u(0) − f(0)/k_t, that is the stick's slider (w_P, w_N at the extremum that set it, u(τ_Sp2)
/// after the re-contact), u(0) ∓ μ n(0)/k_t in positive or negative slip, u(0) separated (m).
#[inline(always)]
fn slider_at_zero(mo: &Motion, slots: &Slots, zero: usize) -> f64 {
    let sign = slots.sign;
    let origin = [1.0, 1.0, 0.0];
    let (e, k) = match zero {
        1 => (basis(slots.at[0]), 0.0),
        2 | 6 => (origin, -sign),
        3 => (basis(slots.slip_ends[0]), -sign),
        4 => (origin, sign),
        5 => (basis(slots.slip_ends[1]), sign),
        _ => (origin, 0.0),
    };
    let cn = [mo.n0e, mo.nv[0], mo.nv[1]];
    dot(e, mo.u) + k * mo.p.mu / mo.p.kt * dot(e, cn)
}
