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
//! [`super::element`].

use super::element::{Direction, Element};
use super::law::FrictionParams;
use super::signal::Harmonic;
use super::system::{InitialCondition, MarchSystem};
use crate::case::Damper;
use crate::error::{Error, Result};

/// The damper of a `[damper]` table as a march system (3 DOF: u (m), w (m), φ (rad)), starting
/// from static equilibrium under the centrifugal load.
pub fn damper_system(d: &Damper) -> Result<MarchSystem> {
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
        elements,
        dof_names: vec!["u".into(), "w".into(), "phi".into()],
        initial: InitialCondition::Static,
        displacement_scale: 1.0,
    };
    sys.displacement_scale = damper_scale(d);
    sys.validate("[damper]")?;
    Ok(sys)
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
