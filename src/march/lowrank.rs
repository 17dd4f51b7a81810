//! Step matrices of a contact state as a low-rank change of the all-stick one (Sherman–Morrison–
//! Woodbury), for models with many elements (a sector's shroud pairs meet thousands of state
//! combinations; inverting each n × n step matrix dominated the march).
//!
//! Against full stick, an element's linear piece (paper Table 1, [`Element::add_linear_piece`])
//! changes the step matrix A = A_stick + Σ u vᵀ by
//! - slip with sign s: u = g_t, v = s μ k_n g_n − k_t g_t (the normal terms are the same);
//! - separation: u = g_t, v = −k_t g_t and, when it applies its normal force, u = g_n, v = −k_n g_n.
//!
//! With U, V of the r such columns and Z = A_stick⁻¹ U, A⁻¹ b = y − Z (I + VᵀZ)⁻¹ Vᵀ y with
//! y = A_stick⁻¹ b: O(n·r + r³) to factor a state instead of O(n³).

use super::dense;
use super::element::{Direction, Element};
use super::law::ContactState;

/// The factors of one state: Z = A_stick⁻¹ U (n × r, row-major), (I + VᵀZ)⁻¹ (r × r) and the
/// sparse columns of V.
#[derive(Clone, Debug)]
pub struct LowRank {
    z: Vec<f64>,
    capacitance_inverse: Vec<f64>,
    v: Vec<Sparse>,
}

/// Sparse vector: (index, value) pairs.
pub type Sparse = Vec<(usize, f64)>;

/// One column pair (u, v) of the change U Vᵀ.
pub type Column = (Sparse, Sparse);

/// Sparse a·x + b·y of two directions' weights.
fn combine(a: f64, x: &Direction, b: f64, y: Option<&Direction>) -> Sparse {
    let mut out: Sparse = x.weights.iter().map(|&(i, w)| (i, a * w)).collect();
    for &(i, w) in y.map_or(&[][..], |d| &d.weights[..]) {
        match out.iter_mut().find(|(j, _)| *j == i) {
            Some(e) => e.1 += b * w,
            None => out.push((i, b * w)),
        }
    }
    out
}

/// The (u, v) columns of the states' change from full stick (module documentation).
pub fn columns(elements: &[Element], states: &[ContactState]) -> Vec<Column> {
    let mut out = Vec::new();
    for (e, &s) in elements.iter().zip(states) {
        let (p, gt) = (&e.params, &e.tangential);
        match s {
            ContactState::Stick => {}
            ContactState::Slip(sign) => {
                let v = combine(-p.kt, gt, sign.value() * p.mu * p.kn, e.normal.as_ref());
                out.push((gt.weights.clone(), v));
            }
            ContactState::Separated => {
                out.push((gt.weights.clone(), combine(-p.kt, gt, 0.0, None)));
                if let Some(gn) = e.normal.as_ref().filter(|_| e.applies_normal) {
                    out.push((gn.weights.clone(), combine(-p.kn, gn, 0.0, None)));
                }
            }
        }
    }
    out
}

impl LowRank {
    /// The factors of the state whose change from full stick is `cols`, given A_stick⁻¹ (n × n,
    /// row-major); `None` when I + VᵀZ is singular (the state's step matrix is).
    pub fn new(stick_inverse: &[f64], n: usize, cols: Vec<Column>) -> Option<Self> {
        let r = cols.len();
        let mut z = vec![0.0; n * r];
        for (j, row) in stick_inverse.chunks_exact(n).enumerate() {
            for (a, (u, _)) in cols.iter().enumerate() {
                z[j * r + a] = u.iter().map(|&(i, w)| w * row[i]).sum();
            }
        }
        let mut c = vec![0.0; r * r];
        for (a, (_, v)) in cols.iter().enumerate() {
            c[a * r + a] = 1.0;
            for &(i, w) in v {
                for b in 0..r {
                    c[a * r + b] += w * z[i * r + b];
                }
            }
        }
        let capacitance_inverse = dense::inverse(&c, r)?;
        Some(LowRank {
            z,
            capacitance_inverse,
            v: cols.into_iter().map(|(_, v)| v).collect(),
        })
    }

    /// x = A⁻¹ b for A = A_stick + U Vᵀ, given A_stick⁻¹ (n × n).
    pub fn solve(&self, stick_inverse: &[f64], b: &[f64], x: &mut [f64]) {
        self.solve_with(stick_inverse, b, x, &mut Vec::new());
    }

    /// [`LowRank::solve`] with caller-held scratch of 2r entries (no allocation once its
    /// capacity holds the rank).
    pub fn solve_with(
        &self,
        stick_inverse: &[f64],
        b: &[f64],
        x: &mut [f64],
        scratch: &mut Vec<f64>,
    ) {
        dense::matvec(stick_inverse, b, x);
        let r = self.v.len();
        if r == 0 {
            return;
        }
        scratch.clear();
        scratch.resize(2 * r, 0.0);
        let (w, s) = scratch.split_at_mut(r);
        for (wi, v) in w.iter_mut().zip(&self.v) {
            *wi = v.iter().map(|&(i, c)| c * x[i]).sum();
        }
        dense::matvec(&self.capacitance_inverse, w, s);
        for (xj, zj) in x.iter_mut().zip(self.z.chunks_exact(r)) {
            *xj -= zj.iter().zip(s.iter()).map(|(a, b)| a * b).sum::<f64>();
        }
    }

    /// Memory of the factors (f64 entries).
    pub fn len(&self) -> usize {
        self.z.len() + self.capacitance_inverse.len()
    }

    /// Whether the factors are empty (the all-stick state).
    pub fn is_empty(&self) -> bool {
        self.v.is_empty()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::march::law::{FrictionParams, Sign};
    use crate::march::signal::Harmonic;

    fn dir(w: &[(usize, f64)]) -> Direction {
        Direction {
            weights: w.to_vec(),
            prescribed: Harmonic::default(),
        }
    }

    /// A(state)⁻¹ b by the low-rank factors equals the direct solve of A_stick + ΔK_c(state) for
    /// every state of three elements (one sharing its normal force).
    #[test]
    fn low_rank_solve_equals_the_direct_one() {
        let n = 5;
        let params = FrictionParams {
            kt: 3.0,
            kn: 2.0,
            mu: 0.4,
            n0: 0.5,
        };
        let el = |t: &[(usize, f64)], nm: &[(usize, f64)], applies: bool| Element {
            name: "e".into(),
            tangential: dir(t),
            normal: Some(dir(nm)),
            params,
            applies_normal: applies,
        };
        let elements = vec![
            el(&[(0, 1.0), (1, -0.5)], &[(1, 0.8), (2, 0.3)], true),
            el(&[(3, 1.0)], &[(1, 0.8), (2, 0.3)], false),
            el(&[(2, 0.7), (4, -1.0)], &[(4, 1.0)], true),
        ];
        let base: Vec<f64> = (0..n * n)
            .map(|ij| {
                let (i, j) = (ij / n, ij % n);
                if i == j {
                    10.0 + i as f64
                } else {
                    0.3 / (1.0 + (i + j) as f64)
                }
            })
            .collect();
        let all = [
            ContactState::Stick,
            ContactState::Slip(Sign::Positive),
            ContactState::Slip(Sign::Negative),
            ContactState::Separated,
        ];
        let stiffness = |states: &[ContactState]| {
            let mut k = base.clone();
            for (e, &s) in elements.iter().zip(states) {
                e.add_stiffness(s, &mut k, n);
            }
            k
        };
        let stick_inverse = dense::inverse(&stiffness(&[ContactState::Stick; 3]), n).unwrap();
        let b: Vec<f64> = (0..n).map(|i| 1.0 + 0.5 * i as f64).collect();
        for code in 0..64 {
            let states = [all[code % 4], all[(code / 4) % 4], all[code / 16]];
            let lr = LowRank::new(&stick_inverse, n, columns(&elements, &states)).unwrap();
            let mut x = vec![0.0; n];
            lr.solve(&stick_inverse, &b, &mut x);
            let direct = dense::inverse(&stiffness(&states), n).unwrap();
            let mut y = vec![0.0; n];
            dense::matvec(&direct, &b, &mut y);
            for (a, e) in x.iter().zip(&y) {
                assert!(
                    (a - e).abs() < 1e-12 * e.abs().max(1.0),
                    "{states:?}: {a} vs {e}"
                );
            }
        }
    }
}
