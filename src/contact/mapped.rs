//! A fixed real linear map between two DOF vectors, applied to harmonic vectors, forces and
//! Jacobians: the elements of a [`super::pairs::PairSet`] may read *inner* DOFs y = B x that are
//! linear combinations of the *outer* DOFs x the harmonic balance solves for — e.g. the virtual
//! target node of SAMA's interpolated coupling, u(t_v) = Σ_j N_j u_tj (Battiato 2021, §4, Fig. 8).
//!
//! B is real and the same for every harmonic coefficient, so on the real harmonic layout it is
//! block diagonal: y⁽ˡ⁾ = B x⁽ˡ⁾ for every coefficient l. By virtual work the forces return as
//! F_x = Bᵀ F_y and the Jacobian as J_x = Bᵀ J_y B; ∂F_x/∂p = Bᵀ ∂F_y/∂p.

use faer::{MatMut, MatRef};

use crate::contact::aft::global_index;
use crate::error::{Error, Result};
use crate::harmonics::HarmonicLayout;

/// y = B x with B sparse: row i of B is `rows[i]`, a list of (outer DOF, coefficient).
#[derive(Clone, Debug, PartialEq)]
pub struct LinearMap {
    outer: usize,
    rows: Vec<Vec<(usize, f64)>>,
}

impl LinearMap {
    /// The map whose first `outer` inner DOFs are the outer DOFs themselves (identity) and whose
    /// further inner DOFs are the combinations `extra` (each a list of (outer DOF, coefficient)).
    ///
    /// Errors ([`Error::Input`]): an outer DOF index ≥ `outer` or a non-finite coefficient.
    pub fn identity_and(outer: usize, extra: Vec<Vec<(usize, f64)>>) -> Result<LinearMap> {
        for (i, row) in extra.iter().enumerate() {
            if let Some(&(s, c)) = row.iter().find(|(s, c)| *s >= outer || !c.is_finite()) {
                return Err(Error::input(format!(
                    "DOF map: combination {i} has the term {c} × DOF {s} (the outer vector has {outer} DOFs, coefficients must be finite)"
                )));
            }
        }
        let rows = (0..outer).map(|s| vec![(s, 1.0)]).chain(extra).collect();
        Ok(LinearMap { outer, rows })
    }

    /// Number of outer DOFs (x).
    pub fn outer(&self) -> usize {
        self.outer
    }

    /// Number of inner DOFs (y).
    pub fn inner(&self) -> usize {
        self.rows.len()
    }

    /// y = B x on the real harmonic layout (`x` of length `layout.len(outer)`).
    pub fn forward(&self, layout: &HarmonicLayout, x: &[f64]) -> Vec<f64> {
        let (no, ni) = (self.outer, self.inner());
        let mut y = vec![0.0; layout.len(ni)];
        for l in 0..layout.coefficients() {
            for (r, row) in self.rows.iter().enumerate() {
                y[global_index(layout, l, r, ni)] = row
                    .iter()
                    .map(|&(s, c)| c * x[global_index(layout, l, s, no)])
                    .sum();
            }
        }
        y
    }

    /// x_out += Bᵀ y_in on the real harmonic layout.
    pub fn add_transpose(&self, layout: &HarmonicLayout, y_in: &[f64], x_out: &mut [f64]) {
        let (no, ni) = (self.outer, self.inner());
        for l in 0..layout.coefficients() {
            for (r, row) in self.rows.iter().enumerate() {
                let v = y_in[global_index(layout, l, r, ni)];
                if v == 0.0 {
                    continue;
                }
                for &(s, c) in row {
                    x_out[global_index(layout, l, s, no)] += c * v;
                }
            }
        }
    }

    /// J_x += Bᵀ J_y B (J_y square of `layout.len(inner)`, J_x of `layout.len(outer)`).
    pub fn add_jacobian(
        &self,
        layout: &HarmonicLayout,
        jy: MatRef<'_, f64>,
        mut jx: MatMut<'_, f64>,
    ) {
        let (no, ni) = (self.outer, self.inner());
        let m = layout.coefficients();
        // T = J_y B (inner rows × outer columns), column by column of B.
        let mut t = faer::Mat::<f64>::zeros(ni * m, no * m);
        for l in 0..m {
            for (r, row) in self.rows.iter().enumerate() {
                let src = jy.col(global_index(layout, l, r, ni));
                for &(s, c) in row {
                    let mut dst = t.col_mut(global_index(layout, l, s, no));
                    for i in 0..ni * m {
                        dst[i] += c * src[i];
                    }
                }
            }
        }
        // J_x += Bᵀ T, row by row of Bᵀ.
        for l in 0..m {
            for (r, row) in self.rows.iter().enumerate() {
                let ri = global_index(layout, l, r, ni);
                for &(s, c) in row {
                    let so = global_index(layout, l, s, no);
                    for j in 0..no * m {
                        jx[(so, j)] += c * t[(ri, j)];
                    }
                }
            }
        }
    }
}
