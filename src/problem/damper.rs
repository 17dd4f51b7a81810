//! The demonstrator of Gastaldi & Berruti 2018 (§2 eqs 2–4, Fig. 2b, §6): a rigid 2-D underplatform
//! damper with DOF q_D = (u_D, w_D, φ_D) at its centre of mass, mass matrix
//! M_D = diag(m_D, m_D, I_z), external force f_ED = (0, −|CF|, 0), and contact points between the
//! damper and blade platforms whose displacements q_P(t) are prescribed (the input of eq. 2).
//!
//! Contact point i at r_i = (x_i, y_i) from the centre of mass, unit normal **n**_i pointing from
//! the platform into the damper and tangent **t**_i = (n_y, −n_x). The damper point moves by
//! (u − φ y_i, w + φ x_i) (small rotation: the rows of Γ_iD, eq. 4), the platform point by
//! q_iP(t). Local relative displacements platform − damper (eq. 3): u_t = **t**·(q_iP − q_iD),
//! normal approach v = **n**·(q_iP − q_iD) (v > 0: interference, Table 1). The contact force on the
//! damper, Γ_iDᵀ f_i*, is the element's generalized force −g_t f_t − g_n f_n of
//! [`crate::march::element`].

use crate::case::Damper;
use crate::error::{Error, Result};
use crate::march::element::{Direction, Element};
use crate::march::law::FrictionParams;
use crate::march::signal::Harmonic;
use crate::march::{InitialCondition, MarchSystem};

/// The damper of a `[damper]` table as a march system (3 DOF: u (m), w (m), φ (rad)), starting
/// from static equilibrium under the centrifugal load; `omega` (rad/s) is the excitation frequency
/// (the platforms' velocity drives the contact dashpots of `damping_ratio`).
pub fn damper_system(d: &Damper, omega: f64) -> Result<MarchSystem> {
    let n = 3;
    let mut mass = vec![0.0; n * n];
    mass[0] = d.mass;
    mass[4] = d.mass;
    mass[8] = d.inertia;
    let mut elements = Vec::with_capacity(d.contact.len());
    for c in &d.contact {
        let p = d
            .platform
            .iter()
            .find(|p| p.name == c.platform)
            .ok_or_else(|| {
                Error::input(format!(
                    "[damper] contact '{}': no platform '{}'",
                    c.name, c.platform
                ))
            })?;
        let len = c.normal[0].hypot(c.normal[1]);
        let nrm = [c.normal[0] / len, c.normal[1] / len];
        let tan = [nrm[1], -nrm[0]];
        let phase = p.phase_deg.to_radians();
        let direction = |e: [f64; 2]| -> Direction {
            // e·(q_P − q_D), q_D at the point = (u − φ y, w + φ x)
            let [x, y] = c.point;
            Direction {
                weights: vec![(0, -e[0]), (1, -e[1]), (2, -(e[1] * x - e[0] * y))],
                prescribed: Harmonic::cosine(e[0] * p.amplitude[0] + e[1] * p.amplitude[1], phase),
            }
        };
        elements.push(Element {
            name: c.name.clone(),
            tangential: direction(tan),
            normal: Some(direction(nrm)),
            params: FrictionParams::new(
                c.kt,
                c.kn,
                c.mu,
                c.n0,
                &format!("[[damper.contact]] '{}'", c.name),
            )?,
            applies_normal: true,
        });
    }
    let mut sys = MarchSystem {
        n,
        mass,
        damping: vec![0.0; n * n],
        stiffness: vec![0.0; n * n],
        force: vec![
            Harmonic::default(),
            Harmonic::constant(-d.centrifugal_force),
            Harmonic::default(),
        ],
        damping_force: Vec::new(),
        elements,
        dof_names: vec!["u".into(), "w".into(), "phi".into()],
        initial: InitialCondition::Static,
        displacement_scale: 1.0,
    };
    sys.displacement_scale = damper_scale(d);
    sys.validate("[damper]")?;
    if d.damping_ratio > 0.0 {
        add_normal_dashpots(&mut sys, d.damping_ratio, omega)?;
    }
    Ok(sys)
}

/// Normal contact dashpots c_i = β k_n,i across every contact's normal spring, β = 2ζ/ω_1 (s) with
/// ω_1 the lowest natural frequency (rad/s) of the damper on its contact springs in full stick (the
/// ≈ 10 kHz "inner resonance" of Gastaldi & Berruti 2018 §5.1). Mode j gets the damping ratio
/// ζ (ω_j/ω_1) e_j, e_j its share of strain energy in the normal springs (stiffness-proportional
/// damping of the normal springs only). The dashpot force on the damper is −c_i v̇_i g_i with v_i = g_i·q + p_i(t) the normal
/// approach (m), so C = Σ c_i g_i g_iᵀ (N·s/m) and the platforms' normal velocity enters as the
/// damping force −c_i ṗ_i(t) g_i at the excitation frequency `omega` (rad/s) (with C, absent from
/// the quasi-static method). Sliding along a flank
/// and following the platforms in stick leave v̇ ≈ 0: the dashpots damp the inner vibration, not the
/// 200 Hz motion. They act in every contact state (the demonstrator never lifts off).
fn add_normal_dashpots(sys: &mut MarchSystem, zeta: f64, omega: f64) -> Result<()> {
    let n = sys.n;
    let lowest = lowest_frequency(sys).filter(|w| *w > 0.0).ok_or_else(|| {
        Error::input(format!(
            "[damper] damping_ratio = {zeta}: the contact springs do not hold the damper in every direction (a zero natural frequency in full stick); give every contact kn > 0 or set damping_ratio = 0"
        ))
    })?;
    let beta = 2.0 * zeta / lowest;
    sys.damping_force = vec![Harmonic::default(); n];
    for e in &sys.elements {
        let Some(dir) = &e.normal else { continue };
        let c = beta * e.params.kn;
        for &(i, gi) in &dir.weights {
            for &(j, gj) in &dir.weights {
                sys.damping[i * n + j] += c * gi * gj;
            }
            // ṗ = ω(−cos_p sin ωt + sin_p cos ωt): force −c ṗ g_i
            let p = dir.prescribed;
            sys.damping_force[i].cos -= c * gi * omega * p.sin;
            sys.damping_force[i].sin += c * gi * omega * p.cos;
        }
    }
    Ok(())
}

/// The lowest natural angular frequency (rad/s) of (K + K_c(stick), M) for the damper's diagonal
/// M = diag(m, m, I_z): the smallest eigenvalue of M^(−1/2) K M^(−1/2), square-rooted.
fn lowest_frequency(sys: &MarchSystem) -> Option<f64> {
    let n = sys.n;
    let k = sys.effective_stiffness(&sys.stick_states());
    let s: Vec<f64> = (0..n).map(|i| 1.0 / sys.mass[i * n + i].sqrt()).collect();
    let a = faer::Mat::from_fn(n, n, |i, j| {
        0.5 * (k[i * n + j] + k[j * n + i]) * s[i] * s[j]
    });
    let ev = a.self_adjoint_eigenvalues(faer::Side::Lower).ok()?;
    ev.first().map(|l| l.max(0.0).sqrt())
}

/// The displacement scale of the damper: the largest platform amplitude, or the static
/// centrifugal deflection |CF|/k when the platforms do not move.
fn damper_scale(d: &Damper) -> f64 {
    let motion = d
        .platform
        .iter()
        .map(|p| p.amplitude[0].hypot(p.amplitude[1]))
        .fold(0.0, f64::max);
    let kmax = d.contact.iter().map(|c| c.kn.max(c.kt)).fold(0.0, f64::max);
    let deflection = if kmax > 0.0 {
        d.centrifugal_force / kmax
    } else {
        0.0
    };
    let s = motion.max(deflection);
    if s > 0.0 {
        s
    } else {
        1e-6
    }
}
