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

    /// The element-local part of B for the inner DOFs `inner`: `outer` receives the outer DOFs
    /// they read (ascending, each once) and `b` the |inner| × |outer| coefficients (row-major),
    /// so that y_inner = B_e x_outer.
    pub fn local(&self, inner: &[usize], outer: &mut Vec<usize>, b: &mut Vec<f64>) {
        outer.clear();
        for &r in inner {
            outer.extend(self.rows[r].iter().map(|&(s, _)| s));
        }
        outer.sort_unstable();
        outer.dedup();
        b.clear();
        b.resize(inner.len() * outer.len(), 0.0);
        for (i, &r) in inner.iter().enumerate() {
            for &(s, c) in &self.rows[r] {
                let k = outer.binary_search(&s).expect("listed above");
                b[i * outer.len() + k] += c;
            }
        }
    }

    /// Most outer DOFs read by any `group` of inner DOFs (the size of the element-local B_e of
    /// [`LinearMap::local`]).
    pub fn max_outer(&self, groups: impl Iterator<Item = Vec<usize>>) -> usize {
        let (mut outer, mut b) = (Vec::new(), Vec::new());
        groups
            .map(|g| {
                self.local(&g, &mut outer, &mut b);
                outer.len()
            })
            .max()
            .unwrap_or(0)
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

/// One element's node-space results on its inner DOFs mapped to its outer DOFs with the
/// element-local B_e of [`LinearMap::local`] (`b`, n_in × n_out row-major), the same for each of
/// the m coefficients: node-space entry p = d·m + l is DOF d, coefficient l (signal order).
/// `vectors` are (inner, outer) pairs mapped as v_x = B_eᵀ v_y; with `jacobian` = (J_y, J_x),
/// both column-major, J_x = B_eᵀ J_y B_e. `work` is scratch.
pub fn element_to_outer(
    b: &[f64],
    (n_in, n_out, m): (usize, usize, usize),
    vectors: &mut [(&[f64], &mut [f64])],
    jacobian: Option<(&[f64], &mut [f64])>,
    work: &mut Vec<f64>,
) {
    let (pi, po) = (n_in * m, n_out * m);
    for (vy, vx) in vectors.iter_mut() {
        transpose_apply(b, (n_in, n_out, m), vy, &mut vx[..po]);
    }
    let Some((jy, jx)) = jacobian else {
        return;
    };
    // T = J_y B (pi × po, column-major): column (k, l) = Σ_d B[d, k] · column (d, l) of J_y.
    work.clear();
    work.resize(pi * po, 0.0);
    for k in 0..n_out {
        for d in 0..n_in {
            let c = b[d * n_out + k];
            if c == 0.0 {
                continue;
            }
            for l in 0..m {
                let src = &jy[(d * m + l) * pi..(d * m + l + 1) * pi];
                let dst = &mut work[(k * m + l) * pi..(k * m + l + 1) * pi];
                for (o, s) in dst.iter_mut().zip(src) {
                    *o += c * s;
                }
            }
        }
    }
    // J_x = Bᵀ T, column by column.
    for col in 0..po {
        let t = &work[col * pi..(col + 1) * pi];
        transpose_apply(b, (n_in, n_out, m), t, &mut jx[col * po..(col + 1) * po]);
    }
}

/// out = B_eᵀ v on node-space vectors (entry d·m + l; `out` of length n_out·m).
fn transpose_apply(b: &[f64], (n_in, n_out, m): (usize, usize, usize), v: &[f64], out: &mut [f64]) {
    out.fill(0.0);
    for d in 0..n_in {
        for k in 0..n_out {
            let c = b[d * n_out + k];
            if c == 0.0 {
                continue;
            }
            for l in 0..m {
                out[k * m + l] += c * v[d * m + l];
            }
        }
    }
}
