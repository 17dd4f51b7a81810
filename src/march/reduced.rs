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

/// Σ w_j T[j, :] over the weighted DOF `w`, keeping the non-zero entries.
fn combine(w: &[(usize, f64)], t: MatRef<'_, f64>) -> Vec<(usize, f64)> {
    let mut acc = vec![0.0; t.ncols()];
    for &(j, wj) in w {
        for (c, a) in acc.iter_mut().enumerate() {
            *a += wj * t[(j, c)];
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
    let bad = |m: String| Err(Error::input(format!("reduced nonsmooth model: {m}")));
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
    if sys.x0.iter().chain(&sys.v0).any(|&v| v != 0.0) {
        return bad("the full model does not start at rest".into());
    }
    let force = (0..r)
        .map(|c| {
            let mut h = Harmonic::default();
            for (i, f) in sys.force.iter().enumerate() {
                let w = t[(i, c)];
                h.mean += w * f.mean;
                h.cos += w * f.cos;
                h.sin += w * f.sin;
            }
            h
        })
        .collect();
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
        let tt = t.submatrix(nm, n_mech, nt, r - n_mech);
        let ones = Mat::from_fn(nt, 1, |i, _| sys.heat_weight(nm + i));
        let w = tt.qr().solve_lstsq(ones);
        (0..r - n_mech).map(|c| w[(c, 0)]).collect()
    } else {
        Vec::new()
    };
    let reduced = NonsmoothSystem {
        n: r,
        n_mech,
        mass: galerkin(&sys.mass, n, t),
        damping: galerkin(&sys.damping, n, t),
        stiffness: galerkin(&sys.stiffness, n, t),
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
