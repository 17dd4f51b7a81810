//! The relative-displacement operator of a contact pair c–t_j and its adjoint (force assembly).
//!
//! For temporal harmonic n on harmonic index k_n, the target node's displacement as seen from the
//! contact sector is e^{iσφ} R_α^σ u_t (`docs/conventions.md` §3; paper eq 33 with σ = ±1), φ = φ_{k_n}
//! = 2πk_n/N the inter-sector phase (rad). The local relative displacement of the pair is
//!
//!   r_loc = F (u_c − e^{iσφ} R_α^σ u_t) = A_c u_c + A_t u_t,  A_c = F,  A_t = −e^{iσφ} F R_α^σ,
//!
//! F = the pair's frame (rows t1, t2, n), so r_loc = (u1, u2, r·n); the normal approach of
//! `docs/conventions.md` §3 is v = −r·n. A local force f_loc acting on the contact node (f_n along +n
//! pushes c away from the target) acts on the nodes as f_c = A_cᴴ f_loc and f_t = A_tᴴ f_loc (the
//! adjoint, so that δr_locᴴ f_loc = δu_cᴴ f_c + δu_tᴴ f_t: virtual work is preserved). For σ = 0 or
//! φ = 0 everything is real. The weights enter the pair's parameters (eq 31), not this operator.

use faer::c64;

use super::geom::mat_mul;
use super::{ContactInterface, ContactPair};

impl ContactInterface {
    /// e^{iσφ} for the inter-sector phase φ (rad).
    pub fn phase_factor(&self, phi: f64) -> c64 {
        let a = self.sigma as f64 * phi;
        c64::new(a.cos(), a.sin())
    }

    /// A_c = F: the real 3×3 block (row-major) from u_c to r_loc.
    pub fn contact_block(&self, pair: &ContactPair) -> [[f64; 3]; 3] {
        pair.frame
    }

    /// −F R_α^σ: the real part of the block from u_t to r_loc, before the phase factor e^{iσφ}.
    pub fn target_block(&self, pair: &ContactPair) -> [[f64; 3]; 3] {
        mat_mul(&pair.frame, &self.rotation).map(|row| row.map(|x| -x))
    }

    /// r_loc = F (u_c − e^{iσφ} R_α^σ u_t) for one harmonic: complex amplitudes of the contact
    /// node's and a target node's displacements (m, global axes of their own sectors) → local
    /// relative displacement (t1, t2, n components, m).
    pub fn relative_displacement(
        &self,
        pair: &ContactPair,
        phi: f64,
        u_c: [c64; 3],
        u_t: [c64; 3],
    ) -> [c64; 3] {
        let a_c = self.contact_block(pair);
        let a_t = self.target_block(pair);
        let e = self.phase_factor(phi);
        let mut r = [c64::new(0.0, 0.0); 3];
        for (i, ri) in r.iter_mut().enumerate() {
            for k in 0..3 {
                *ri += u_c[k] * a_c[i][k] + e * u_t[k] * a_t[i][k];
            }
        }
        r
    }

    /// The nodal forces (N, global axes of each node's own sector) of a local pair force f_loc
    /// (t1, t2, n components, acting on the contact node): (A_cᴴ f_loc, A_tᴴ f_loc).
    pub fn pair_forces(
        &self,
        pair: &ContactPair,
        phi: f64,
        f_loc: [c64; 3],
    ) -> ([c64; 3], [c64; 3]) {
        let a_c = self.contact_block(pair);
        let a_t = self.target_block(pair);
        let e = self.phase_factor(phi).conj();
        let mut f_c = [c64::new(0.0, 0.0); 3];
        let mut f_t = [c64::new(0.0, 0.0); 3];
        for k in 0..3 {
            for i in 0..3 {
                f_c[k] += f_loc[i] * a_c[i][k];
                f_t[k] += e * f_loc[i] * a_t[i][k];
            }
        }
        (f_c, f_t)
    }
}
