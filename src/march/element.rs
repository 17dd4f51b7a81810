//! Friction contact elements of the march and their piecewise-linear form.
//!
//! An element reads two scalar relative displacements of the model's DOF vector q (m) and of a
//! prescribed input (the platform motion of the underplatform damper, Gastaldi & Berruti 2018
//! eqs 2–4):
//! - tangential u_t(q, t) = g_tᵀ q + p_t(t),
//! - normal approach v(q, t) = g_nᵀ q + p_n(t) (v > 0 closes the gap; `docs/conventions.md` §3).
//!
//! The time-discrete law ([`law`]) gives the normal force f_n = max(n0 + k_n v, 0) and the friction
//! force f_t with the slider memory w (`docs/theory.md`, "The friction contact element"). The element
//! acts on the structure with the generalized force f_c = −g_t f_t − g_n f_n (the force "acts back
//! along the same weights", `docs/case-file.md` `[[element]]`; eq. 3 of the paper for the damper).
//!
//! Within one contact state the force is affine in q (paper §3, eq. 5 and Table 1):
//! f_c = −K_c q + r_c, see [`Element::add_linear_piece`]. This is what the piecewise-linear Newmark
//! (Appendix A.4), the quasi-static method (Appendix B) and the adaptive step (eq. 8) use.

use super::law::{self, ContactState, FrictionParams, LawSample};
use super::signal::Harmonic;

/// A scalar linear form g·q + p(t) of the DOF vector and a prescribed signal.
#[derive(Clone, Debug, PartialEq)]
pub struct Direction {
    /// Sparse weights (DOF index, weight) of g (dimensionless for displacement DOF).
    pub weights: Vec<(usize, f64)>,
    /// Prescribed part p(t) (m).
    pub prescribed: Harmonic,
}

impl Direction {
    /// g·q + p(t).
    pub fn value(&self, q: &[f64], omega: f64, t: f64) -> f64 {
        self.dot(q) + self.prescribed.at(omega, t)
    }

    /// g·q alone.
    pub fn dot(&self, q: &[f64]) -> f64 {
        self.weights.iter().map(|&(i, w)| w * q[i]).sum()
    }

    /// y ← y + a·g.
    fn axpy(&self, a: f64, y: &mut [f64]) {
        for &(i, w) in &self.weights {
            y[i] += a * w;
        }
    }
}

/// One friction contact element: a tangential direction, an optional normal direction and the
/// friction parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct Element {
    /// Name used in messages and results.
    pub name: String,
    /// Tangential relative displacement u_t.
    pub tangential: Direction,
    /// Normal approach v; `None`: constant normal load n0 (no normal load variation).
    pub normal: Option<Direction>,
    /// k_t (N/m), k_n (N/m), μ, n0 (N).
    pub params: FrictionParams,
    /// Whether the element applies its normal force −g_n f_n to the structure. `false` for the
    /// second tangential direction of a 3-D node-to-node pair under the 1-D law (SAMA paper §3:
    /// t1 and t2 each with its own slider and the limit μ f_n of the pair's one normal force):
    /// its normal direction then only sets the friction limit, and the pair's first element
    /// applies f_n.
    pub applies_normal: bool,
}

/// The local kinematics of an element at one instant: (u_t, v) in m; v = 0 without a normal.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Local {
    /// Tangential relative displacement u_t (m).
    pub ut: f64,
    /// Normal approach v (m).
    pub v: f64,
}

impl Element {
    /// (u_t, v) at displacement `q` and time `t`.
    pub fn local(&self, q: &[f64], omega: f64, t: f64) -> Local {
        Local {
            ut: self.tangential.value(q, omega, t),
            v: self.normal.as_ref().map_or(0.0, |n| n.value(q, omega, t)),
        }
    }

    /// The prescribed parts (p_t(t), p_n(t)) (m) at time `t`; p_n = 0 without a normal.
    pub fn prescribed_at(&self, omega: f64, t: f64) -> (f64, f64) {
        (
            self.tangential.prescribed.at(omega, t),
            self.normal
                .as_ref()
                .map_or(0.0, |n| n.prescribed.at(omega, t)),
        )
    }

    /// (u_t, v) at displacement `q` with the prescribed parts `pt`, `pn` (m) of the instant
    /// already evaluated ([`Element::prescribed_at`]).
    pub fn local_with(&self, q: &[f64], pt: f64, pn: f64) -> Local {
        Local {
            ut: self.tangential.dot(q) + pt,
            v: self.normal.as_ref().map_or(0.0, |n| n.dot(q) + pn),
        }
    }

    /// The time-discrete law at (u_t, v) with the slider at `w` (m) from the previous step.
    pub fn sample(&self, local: Local, w: f64) -> LawSample {
        let v = self.normal.as_ref().map(|_| local.v);
        law::sample(&self.params, local.ut, v, w)
    }

    /// Adds the generalized force −g_t f_t − g_n f_n of the element (N) to `f`.
    pub fn add_force(&self, f_t: f64, f_n: f64, f: &mut [f64]) {
        self.tangential.axpy(-f_t, f);
        if let Some(n) = self.normal.as_ref().filter(|_| self.applies_normal) {
            n.axpy(-f_n, f);
        }
    }

    /// Adds the element's piecewise-linear force in `state` (paper Table 1, eq. 7) as
    /// f_c = −K_c q + r_c: `k` (row-major n×n, N/m) += K_c and `r` (N) += r_c, at time `t` with
    /// the slider at `w` from the previous step.
    ///
    /// Stick: f_t = k_t (u_t − w), f_n = n0 + k_n v. Slip with sign s: f_t = s μ f_n.
    /// Separation: no force. Without a normal direction f_n = n0. The normal force's own terms
    /// only when the element [applies](Element::applies_normal) it.
    pub fn add_linear_piece(
        &self,
        state: ContactState,
        w: f64,
        omega: f64,
        t: f64,
        k: &mut [f64],
        r: &mut [f64],
    ) {
        let (pt, pn) = self.prescribed_at(omega, t);
        self.add_linear_piece_with(state, w, pt, pn, Some(k), r);
    }

    /// [`Element::add_linear_piece`] with the prescribed parts `pt`, `pn` (m) of the instant
    /// already evaluated; `k` = `None` adds r_c alone (the state's K_c is then factored already).
    pub fn add_linear_piece_with(
        &self,
        state: ContactState,
        w: f64,
        pt: f64,
        pn: f64,
        mut k: Option<&mut [f64]>,
        r: &mut [f64],
    ) {
        let n = r.len();
        let p = &self.params;
        let gt = &self.tangential;
        // f_n = a_n + k_n g_n·q (a_n: the constant part), when in contact.
        let (an, gn) = match &self.normal {
            Some(d) => (p.n0 + p.kn * pn, Some(d)),
            None => (p.n0, None),
        };
        // −g_n f_n = −g_n (a_n + k_n g_n·q), when this element applies the normal force.
        let add_normal = |k: &mut Option<&mut [f64]>, r: &mut [f64]| {
            if let Some(gn) = gn.filter(|_| self.applies_normal) {
                if let Some(k) = k.as_deref_mut() {
                    outer_add(k, n, p.kn, gn, gn);
                }
                gn.axpy(-an, r);
            }
        };
        match state {
            ContactState::Separated => {}
            ContactState::Stick => {
                // −g_t k_t (g_t·q + p_t − w)
                if let Some(k) = k.as_deref_mut() {
                    outer_add(k, n, p.kt, gt, gt);
                }
                gt.axpy(-p.kt * (pt - w), r);
                add_normal(&mut k, r);
            }
            ContactState::Slip(s) => {
                let sm = s.value() * p.mu;
                gt.axpy(-sm * an, r);
                if let (Some(gn), Some(k)) = (gn, k.as_deref_mut()) {
                    outer_add(k, n, sm * p.kn, gt, gn);
                }
                add_normal(&mut k, r);
            }
        }
    }

    /// The element's stiffness matrix contribution in `state` (row-major n×n): K_c alone.
    pub fn add_stiffness(&self, state: ContactState, k: &mut [f64], n: usize) {
        let mut r = vec![0.0; n];
        self.add_linear_piece(state, 0.0, 0.0, 0.0, k, &mut r);
    }
}

/// k += c·a bᵀ (row-major n×n).
fn outer_add(k: &mut [f64], n: usize, c: f64, a: &Direction, b: &Direction) {
    for &(i, wa) in &a.weights {
        for &(j, wb) in &b.weights {
            k[i * n + j] += c * wa * wb;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::march::law::Sign;

    fn element() -> Element {
        Element {
            name: "e".into(),
            tangential: Direction {
                weights: vec![(0, 1.0), (1, -0.5)],
                prescribed: Harmonic::cosine(0.2, 0.1),
            },
            normal: Some(Direction {
                weights: vec![(1, 0.8), (2, 0.3)],
                prescribed: Harmonic::constant(0.05),
            }),
            params: FrictionParams {
                kt: 3.0,
                kn: 2.0,
                mu: 0.4,
                n0: 0.5,
            },
            applies_normal: true,
        }
    }

    /// The affine piece of each state reproduces the law's force wherever the law is in that
    /// state (paper §3: "the same ultimate result").
    #[test]
    fn linear_piece_equals_the_law_in_its_state() {
        check_linear_piece(&element());
    }

    /// The same for an element whose normal force another element applies.
    #[test]
    fn linear_piece_equals_the_law_without_its_normal_force() {
        let e = Element {
            applies_normal: false,
            ..element()
        };
        check_linear_piece(&e);
    }

    fn check_linear_piece(e: &Element) {
        let (omega, w) = (2.0, 0.07);
        let mut seen = Vec::new();
        for i in 0..400 {
            let x = i as f64 * 0.37;
            let q = [x.sin(), 0.9 * (1.3 * x).cos(), 0.4 * (0.7 * x).sin() - 0.2];
            let t = 0.01 * i as f64;
            let s = e.sample(e.local(&q, omega, t), w);
            let mut f_law = [0.0; 3];
            e.add_force(s.f_t, s.f_n, &mut f_law);
            let mut k = [0.0; 9];
            let mut r = [0.0; 3];
            e.add_linear_piece(s.state, w, omega, t, &mut k, &mut r);
            for a in 0..3 {
                let kq: f64 = (0..3).map(|b| k[a * 3 + b] * q[b]).sum();
                let f_lin = r[a] - kq;
                assert!(
                    (f_lin - f_law[a]).abs() < 1e-12,
                    "{:?}: {f_lin} vs {}",
                    s.state,
                    f_law[a]
                );
            }
            if !seen.contains(&s.state) {
                seen.push(s.state);
            }
        }
        for st in [
            ContactState::Stick,
            ContactState::Separated,
            ContactState::Slip(Sign::Positive),
            ContactState::Slip(Sign::Negative),
        ] {
            assert!(seen.contains(&st), "state {st:?} not exercised");
        }
    }
}
