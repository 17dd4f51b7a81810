//! Stick–slip–separation maps of a set of friction points (Cigeroglu, An & Menq, Nonlinear
//! Dynamics 2007, §2.3, Figs 4–8 and 14–15): per point and per phase angle of the cycle, the
//! point's state (stick, positive slip, negative slip, separation) and the normalised friction
//! force f/(μn), with the exact transition angles of every point as the map's boundaries.
//!
//! Each point is the 1-D law of [`super::law`] under u and v that are each a constant plus one
//! harmonic (H = 1), evaluated by the exact cycle of [`super::microslip`]: the state at a phase
//! angle is the state of the cycle's phase that contains it (no sampling), and the boundaries are
//! the cycle's transition angles (eqs 21–28 in the singularity-free form of
//! [`super::microslip`]). Phase angles are τ = ωt of nlrom's harmonic layout
//! (x = X0 + Re X1 cos τ − Im X1 sin τ), shared by all points: for a forced response τ is the
//! phase of the excitation force F cos τ, the global angle of the paper's Figs 6–8, not the phase
//! of each point's own u.

use std::f64::consts::TAU;

use super::law::ContactParams;
use super::microslip::{cycle, state_at, PhaseKind};
use crate::error::Result;

/// One point of a map: its law's parameters (k_t, k_n in N/m, μ, n0 in N), its harmonic motion
/// u, v as (X0, Re X1, Im X1) (m; v = 0 without normal motion) and its slider state w (m) at
/// τ = 0 (kept only in complete stick, where the cycle depends on it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MapPoint {
    /// The law's parameters.
    pub params: ContactParams,
    /// Tangential relative displacement harmonics (m).
    pub u: [f64; 3],
    /// Normal approach harmonics (m), v > 0 loads the contact.
    pub v: [f64; 3],
    /// Slider state at τ = 0 (m).
    pub slider: f64,
}

/// A stick–slip–separation map of E points over N_θ phase angles τ_j = 2πj/N_θ.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SlipMap {
    /// The phase angles τ_j (rad), N_θ of them.
    pub phases: Vec<f64>,
    /// State code per point and angle, `[e * N_θ + j]` ([`PhaseKind::code`]: 0 stick,
    /// 1 positive slip, −1 negative slip, 2 separation).
    pub state: Vec<i8>,
    /// f/(μn) per point and angle, laid out as `state`: +1 in positive slip, −1 in negative slip,
    /// in between in stick; NaN where μn = 0 (separation, or μ = 0).
    pub friction_ratio: Vec<f64>,
    /// Point e's transitions are `transition_angles[transition_offsets[e]..transition_offsets[e + 1]]`
    /// (E + 1 offsets).
    pub transition_offsets: Vec<usize>,
    /// Transition angles τ (rad, in [0, 2π), ascending per point): where a point enters a new
    /// state. None for a point that keeps one state over the cycle.
    pub transition_angles: Vec<f64>,
    /// The code of the state entered at each transition (as `state`).
    pub transition_states: Vec<i8>,
}

impl SlipMap {
    /// Number of phase angles N_θ.
    pub fn phase_count(&self) -> usize {
        self.phases.len()
    }

    /// Number of points E.
    pub fn point_count(&self) -> usize {
        self.transition_offsets.len().saturating_sub(1)
    }

    /// The transitions (τ, state code entered) of point `e`.
    pub fn transitions(&self, e: usize) -> impl Iterator<Item = (f64, i8)> + '_ {
        let (a, b) = (self.transition_offsets[e], self.transition_offsets[e + 1]);
        self.transition_angles[a..b]
            .iter()
            .copied()
            .zip(self.transition_states[a..b].iter().copied())
    }
}

/// The map of `points` over `phases` angles τ_j = 2πj/N_θ (`phases` ≥ 1). Errors only where the
/// exact cycle does (non-finite motion, a degenerate cycle).
pub fn slip_map(points: &[MapPoint], phases: usize) -> Result<SlipMap> {
    let angles: Vec<f64> = (0..phases)
        .map(|j| TAU * j as f64 / phases as f64)
        .collect();
    let mut map = SlipMap {
        phases: angles,
        transition_offsets: vec![0],
        ..SlipMap::default()
    };
    for p in points {
        let c = cycle(&p.params, p.u, p.v, p.slider)?;
        for &t in &map.phases {
            let (f, n, _, kind) = state_at(&p.params, p.u, p.v, &c, t);
            let limit = p.params.mu * n;
            map.state.push(kind.code());
            map.friction_ratio.push(match kind {
                PhaseKind::PositiveSlip if limit > 0.0 => 1.0,
                PhaseKind::NegativeSlip if limit > 0.0 => -1.0,
                _ if limit > 0.0 => f / limit,
                _ => f64::NAN,
            });
        }
        let ph = c.phases();
        let mut entered: Vec<(f64, i8)> = (0..ph.len())
            .filter_map(|i| {
                let (a, b) = (&ph[i], &ph[(i + 1) % ph.len()]);
                (ph.len() > 1 && a.kind.code() != b.kind.code())
                    .then(|| (a.end.rem_euclid(TAU), b.kind.code()))
            })
            .collect();
        entered.sort_by(|x, y| x.0.total_cmp(&y.0));
        for (t, code) in entered {
            map.transition_angles.push(t);
            map.transition_states.push(code);
        }
        map.transition_offsets.push(map.transition_angles.len());
    }
    Ok(map)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Jenkins point (no normal motion) under u = a cos τ: slip ends at the extrema of u
    /// (τ = 0 and π) and restarts after the force has swung by 2μn0, i.e. where
    /// k_t a (1 − cos τ) = 2 μ n0 (negative slip) and a half period later (positive slip).
    #[test]
    fn jenkins_map_has_the_closed_form_boundaries() {
        let (kt, mu, n0, a) = (10.0, 0.5, 2.0, 1.0);
        let params = ContactParams {
            kt,
            kn: 0.0,
            mu,
            n0,
        };
        let point = MapPoint {
            params,
            u: [0.0, a, 0.0],
            v: [0.0; 3],
            slider: 0.0,
        };
        let map = slip_map(&[point], 3600).unwrap();
        let start = (1.0 - 2.0 * mu * n0 / (kt * a)).acos();
        let got: Vec<(f64, i8)> = map.transitions(0).collect();
        let want = [
            (0.0, 0),
            (start, -1),
            (std::f64::consts::PI, 0),
            (std::f64::consts::PI + start, 1),
        ];
        assert_eq!(got.len(), 4, "{got:?}");
        for (tw, cw) in want {
            let found = got.iter().any(|&(t, c)| {
                let d = (t - tw).rem_euclid(TAU);
                d.min(TAU - d) < 1e-12 && c == cw
            });
            assert!(found, "{got:?} vs {want:?}");
        }
        // Samples: stick with |f/(μn)| < 1 between, ±1 while slipping.
        for (j, &t) in map.phases.iter().enumerate() {
            let (s, r) = (map.state[j], map.friction_ratio[j]);
            if t > 1e-9 && t < start - 1e-9 {
                assert_eq!(s, 0);
                let f = mu * n0 - kt * a * (1.0 - t.cos());
                assert!((r - f / (mu * n0)).abs() < 1e-12, "{t}: {r}");
            } else if t > start + 1e-9 && t < std::f64::consts::PI - 1e-9 {
                assert_eq!((s, r), (-1, -1.0));
            }
        }
    }
}
