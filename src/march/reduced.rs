//! Galerkin projection of the nonsmooth model ([`super::obstacle`]) onto a reduced basis, for
//! marching Craig–Bampton reduced mechanics (Craig & Bampton, AIAA J. 6, 1968) with the
//! Moreau–Jean and Carpenter schemes, as Thorin et al. (ASME GT2018-75959, 2018, §2.3) do.
//!
//! With x = T x_r, T = blockdiag(T_u, T_θ) (n × r, the first `n_mech` columns mechanical), the
//! reduced model is
//!
//! M_r = TᵀMT, C_r = TᵀCT, K_r = TᵀKT, f_r = Tᵀf, G_r = G T, t_r = t T, P_r = P T
//!
//! (G the gap rows, t the sliding directions, P the heated rows of the obstacles). Because T is
//! block diagonal, the zero blocks of M, C and K (thermal rows of M, K^θu) stay exactly zero. With
//! T_CB's master rows the identity (contact nodes kept as physical masters), the gaps, impulses
//! and the contact nodes' temperatures of the reduced march are physical quantities; the kinetic
//! and strain energies and the works of the energy balance are those of the physical model
//! (quadratic forms are invariant under the projection). The heat terms
//! ([`super::obstacle::HeatTerms`]) sum the reduced thermal rows with the weights w of the
//! least-squares solution of T_θ w = 1 (`heat_weights`): the reduced rows are T_θᵀ times the full
//! ones, so wᵀ(reduced rows) = (T_θ w)ᵀ(full rows) is the physical balance 1ᵀ(full rows) whenever
//! 1 lies in the span of T_θ, as it does for a basis of every conduction mode.

use faer::linalg::solvers::SolveLstsq;
use faer::{Mat, MatRef};

use super::obstacle::{NonsmoothSystem, Obstacle};
use super::signal::Harmonic;
use crate::error::{Error, Result};

/// Tᵀ A T for the row-major n × n `a` (row-major r × r).
fn galerkin(a: &[f64], n: usize, t: MatRef<'_, f64>) -> Vec<f64> {
    let am = Mat::from_fn(n, n, |i, j| a[i * n + j]);
    let at = &am * t;
    let ar = t.transpose() * &at;
    let r = t.ncols();
    (0..r * r).map(|ij| ar[(ij / r, ij % r)]).collect()
}

/// The basis T = blockdiag(T_u, T_θ) of a reduction by blocks: T_u (n_mech × r_u) on the
/// mechanical rows, T_θ ((n − n_mech) × r_θ) on the thermal rows.
#[derive(Clone, Copy)]
pub struct BlockBasis<'a> {
    /// T_u.
    pub mech: MatRef<'a, f64>,
    /// T_θ (0 × 0 without thermal rows).
    pub thermal: MatRef<'a, f64>,
}

impl BlockBasis<'_> {
    /// Row `j` of T as (first reduced column, entries).
    fn row(&self, j: usize) -> (usize, MatRef<'_, f64>) {
        let nm = self.mech.nrows();
        if j < nm {
            (0, self.mech.subrows(j, 1))
        } else {
            (self.mech.ncols(), self.thermal.subrows(j - nm, 1))
        }
    }

    /// Number of reduced coordinates r_u + r_θ.
    fn ncols(&self) -> usize {
        self.mech.ncols() + self.thermal.ncols()
    }
}

/// Tᵀ A T for the sparse rows `a` of an n × n matrix and the block basis `t` (row-major r × r),
/// by blocks: for the row block p and column block q, T_pᵀ (A_pq T_q) or (T_pᵀ A_pq) T_q, whichever
/// dense intermediate is smaller, so the cost is that of the sparse products plus dense products
/// of the reduced size, and no n × n or n × r array is formed.
pub fn sparse_galerkin(a: &[Vec<(usize, f64)>], t: &BlockBasis<'_>) -> Vec<f64> {
    let nm = t.mech.nrows();
    let r = t.ncols();
    let blocks = [(0, t.mech), (t.mech.ncols(), t.thermal)];
    let row_start = [0, nm];
    let mut out = Mat::<f64>::zeros(r, r);
    for (p, &(cp, tp)) in blocks.iter().enumerate() {
        for (q, &(cq, tq)) in blocks.iter().enumerate() {
            let (np, nq) = (tp.nrows(), tq.nrows());
            if np == 0 || nq == 0 || tp.ncols() == 0 || tq.ncols() == 0 {
                continue;
            }
            let (rp, rq) = (tp.ncols(), tq.ncols());
            let in_q = |j: usize| j >= row_start[q] && j < row_start[q] + nq;
            let block = if np * rq <= rp * nq {
                // A_pq T_q (np × rq), then T_pᵀ times it.
                let mut at = Mat::<f64>::zeros(np, rq);
                for i in 0..np {
                    for &(j, v) in &a[row_start[p] + i] {
                        if in_q(j) {
                            let jj = j - row_start[q];
                            for c in 0..rq {
                                at[(i, c)] += v * tq[(jj, c)];
                            }
                        }
                    }
                }
                tp.transpose() * &at
            } else {
                // T_pᵀ A_pq (rp × nq), then times T_q.
                let mut ta = Mat::<f64>::zeros(rp, nq);
                for i in 0..np {
                    for &(j, v) in &a[row_start[p] + i] {
                        if in_q(j) {
                            let jj = j - row_start[q];
                            for c in 0..rp {
                                ta[(c, jj)] += tp[(i, c)] * v;
                            }
                        }
                    }
                }
                &ta * tq
            };
            out.as_mut().submatrix_mut(cp, cq, rp, rq).copy_from(&block);
        }
    }
    (0..r * r).map(|ij| out[(ij / r, ij % r)]).collect()
}

/// Σ w_j T[j, :] over the weighted DOF `w`, keeping the non-zero entries.
fn combine(w: &[(usize, f64)], t: &BlockBasis<'_>) -> Vec<(usize, f64)> {
    let mut acc = vec![0.0; t.ncols()];
    for &(j, wj) in w {
        let (c0, row) = t.row(j);
        for c in 0..row.ncols() {
            acc[c0 + c] += wj * row[(0, c)];
        }
    }
    acc.into_iter()
        .enumerate()
        .filter(|&(_, v)| v != 0.0)
        .collect()
}

/// The model `sys` projected on x = T x_r (module doc): `t` is n × r, block diagonal with its
/// first `n_mech` columns on the mechanical rows; `names` names the r reduced coordinates. The
/// reduced march starts at rest, so `sys` must too.
///
/// Errors ([`Error::Input`]): sizes that do not match, a T that couples mechanical and thermal
/// rows, a non-zero initial state.
pub fn project(
    sys: &NonsmoothSystem,
    t: MatRef<'_, f64>,
    n_mech: usize,
    names: Vec<String>,
) -> Result<NonsmoothSystem> {
    let (n, nm, r) = (sys.n, sys.n_mech, t.ncols());
    if t.nrows() != n || names.len() != r || n_mech > r {
        return bad(format!(
            "the basis is {}×{r} with {} names and {n_mech} mechanical columns for {n} DOF",
            t.nrows(),
            names.len()
        ));
    }
    for i in 0..n {
        for c in 0..r {
            if t[(i, c)] != 0.0 && ((i < nm) != (c < n_mech)) {
                return bad(format!(
                    "the basis couples row {i} and column {c} across the mechanical and thermal blocks"
                ));
            }
        }
    }
    let blocks = BlockBasis {
        mech: t.submatrix(0, 0, nm, n_mech),
        thermal: t.submatrix(nm, n_mech, n - nm, r - n_mech),
    };
    let matrices = [
        galerkin(&sys.mass, n, t),
        galerkin(&sys.damping, n, t),
        galerkin(&sys.stiffness, n, t),
    ];
    finish(sys, &blocks, names, matrices)
}

/// [`project`] for a model whose M, C and K are given as sparse rows `mcdk` = [M, C, K]
/// ([`sparse_galerkin`]) instead of the dense arrays of `sys` (which are not read, and may be
/// empty), on the block basis `t`. The same reduced model as [`project`] up to round-off, in
/// memory of the reduced size and the sparse rows.
///
/// Errors ([`Error::Input`]): sizes that do not match, a non-zero initial state.
pub fn project_sparse(
    sys: &NonsmoothSystem,
    mck: [&[Vec<(usize, f64)>]; 3],
    t: &BlockBasis<'_>,
    names: Vec<String>,
) -> Result<NonsmoothSystem> {
    let (n, nm) = (sys.n, sys.n_mech);
    if t.mech.nrows() != nm
        || t.thermal.nrows() != n - nm && t.thermal.ncols() > 0
        || names.len() != t.ncols()
        || mck.iter().any(|a| a.len() != n)
    {
        return bad(format!(
            "the basis blocks are {}×{} and {}×{} with {} names for {n} DOF ({nm} mechanical)",
            t.mech.nrows(),
            t.mech.ncols(),
            t.thermal.nrows(),
            t.thermal.ncols(),
            names.len()
        ));
    }
    if mck
        .iter()
        .flat_map(|a| a.iter().flatten())
        .any(|&(j, v)| j >= n || !v.is_finite())
    {
        return bad("a sparse row has a column out of range or a non-finite entry".into());
    }
    let matrices = mck.map(|a| sparse_galerkin(a, t));
    finish(sys, t, names, matrices)
}

fn bad<T>(m: String) -> Result<T> {
    Err(Error::input(format!("reduced nonsmooth model: {m}")))
}

/// The reduced model from its matrices `[M_r, C_r, K_r]` (row-major r × r): load, obstacles and
/// heat-balance weights projected with `t`.
fn finish(
    sys: &NonsmoothSystem,
    t: &BlockBasis<'_>,
    names: Vec<String>,
    [mass, damping, stiffness]: [Vec<f64>; 3],
) -> Result<NonsmoothSystem> {
    let (n, nm, r, n_mech) = (sys.n, sys.n_mech, t.ncols(), t.mech.ncols());
    if sys.x0.iter().chain(&sys.v0).any(|&v| v != 0.0) {
        return bad("the full model does not start at rest".into());
    }
    let mut force = vec![Harmonic::default(); r];
    for (i, f) in sys.force.iter().enumerate() {
        let (c0, row) = t.row(i);
        for c in 0..row.ncols() {
            let (w, h) = (row[(0, c)], &mut force[c0 + c]);
            h.mean += w * f.mean;
            h.cos += w * f.cos;
            h.sin += w * f.sin;
        }
    }
    let obstacles = sys
        .obstacles
        .iter()
        .map(|o| Obstacle {
            normal: combine(&o.normal, t),
            tangential: combine(&o.tangential, t),
            heated: combine(&o.heated, t),
            ..o.clone()
        })
        .collect();
    // Heat-balance weights: T_θ w = 1 (least squares), with the full model's own weights.
    let nt = n - nm;
    let heat_weights = if nt > 0 && r > n_mech {
        let ones = Mat::from_fn(nt, 1, |i, _| sys.heat_weight(nm + i));
        let w = t.thermal.qr().solve_lstsq(ones);
        (0..r - n_mech).map(|c| w[(c, 0)]).collect()
    } else {
        Vec::new()
    };
    let reduced = NonsmoothSystem {
        n: r,
        n_mech,
        mass,
        damping,
        stiffness,
        force,
        omega: sys.omega,
        obstacles,
        dof_names: names,
        x0: vec![0.0; r],
        v0: vec![0.0; r],
        heat_weights,
    };
    reduced.validate("reduced nonsmooth model")?;
    Ok(reduced)
}
