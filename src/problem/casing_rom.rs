//! The Craig–Bampton reduced model of a `[[casing]]` case with `[reduction]`: the nonsmooth
//! thermoelastic model of [`super::casing_case`] projected
//! on x = T x_r, T = blockdiag(T_u, T_θ), as Thorin et al. (ASME GT2018-75959, 2018, §2.3)
//! reduce the blade before marching it.
//!
//! - T_u is the Craig–Bampton basis ([`crate::reduction::craig_bampton()`]; Craig & Bampton, AIAA
//!   J. 6, 1968) of the clamped K^uu, M^uu with the nodes of the casing groups, the excitation
//!   group, the response groups and `reduction.keep` as masters, and `reduction.interface_modes`
//!   fixed-interface modes. The contact nodes stay physical coordinates, so gaps, impulses and
//!   the recorded displacements are exact functions of the reduced state.
//! - T_θ is the Craig–Bampton basis of the conduction pencil (K^θθ, C^θθ) with the contact
//!   nodes' temperatures as masters and *every* fixed-interface conduction mode
//!   K^θθ_ii φ = μ C^θθ_ii φ: a change of coordinates, not a truncation. Every conduction mode of
//!   a blade is slow against the contact, so none may be condensed statically (with the
//!   consistent capacity, keeping 40, 100 or 200 of the surrogate's 483 interior modes gives a
//!   peak temperature rise over one revolution of 24.6, 33.7 or 48.0 K instead of 54.5 K). The
//!   gain is in the structure: K̃^θθ = blockdiag(K_bb + K_bi Ψ, diag μ) and
//!   C̃^θθ = [[·, ·], [·, I]] (an arrow matrix), cheaper to multiply and factorise than the FE
//!   conduction matrices.
//!
//! C^uu, K^uθ and the load are projected with the same basis, so the reduced model is the
//! Galerkin projection of the full one. The projection works on the sparse rows of the full model
//! block by block ([`crate::march::reduced::project_sparse`]), so no n × n array is formed: the
//! Craig–Bampton basis itself comes from a sparse factorisation of K^uu_ii with faer, and the dense parts are the reduced matrices and the conduction modes of the
//! temperature rows (n_θ × n_θ, an eigen-decomposition of O(n_θ³)).

use faer::linalg::solvers::Solve;
use faer::Mat;

use super::casing_case::CasingModel;
use super::nonsmooth_case::NonsmoothCase;
use crate::case::{Case, Reduction};
use crate::eigen::pencil::pencil_modes;
use crate::error::{Error, Result};
use crate::march::reduced::{project, project_sparse, BlockBasis};
use crate::model::StructuralModel;
use crate::reduction::{case_master_groups, craig_bampton, partition, CbOptions, Partition};
use crate::rom::MasterRole;

/// The columns of T for the Craig–Bampton model of `partition` (`n_free` rows): masters then
/// modes (module doc of [`mod@crate::reduction::craig_bampton`]).
fn cb_columns(
    k: faer::sparse::SparseColMatRef<'_, usize, f64>,
    m: faer::sparse::SparseColMatRef<'_, usize, f64>,
    p: &Partition,
    modes: usize,
) -> Result<Mat<f64>> {
    let cb = craig_bampton(
        k,
        m,
        p,
        &CbOptions {
            interface_modes: modes,
            keep_basis: true,
            ..CbOptions::default()
        },
    )?;
    let basis = cb
        .basis
        .ok_or_else(|| Error::Compute("Craig–Bampton: no basis returned".into()))?;
    let (nb, r) = (p.n_masters(), p.n_masters() + modes);
    let mut t = Mat::<f64>::zeros(p.n_free, r);
    for (c, d) in p.masters.iter().enumerate() {
        t[(d.free_row, c)] = 1.0;
    }
    for (a, &row) in p.interior.iter().enumerate() {
        for c in 0..nb {
            t[(row, c)] = basis.psi[(a, c)];
        }
        for j in 0..modes {
            t[(row, nb + j)] = basis.phi[(a, j)];
        }
    }
    Ok(t)
}

/// The Craig–Bampton basis of the pencil (K, M) (n × n dense) with the rows `masters` as masters
/// and every fixed-interface mode: T = [[I, 0], [Ψ, Φ]] (rows in the original order, columns the
/// masters then the modes), Ψ = −K_ii⁻¹K_ib, K_ii Φ = M_ii Φ diag μ, ΦᵀM_iiΦ = I. A change of
/// coordinates, so nothing is truncated.
struct FullCb {
    /// T (n × n).
    t: Mat<f64>,
    /// Number of masters.
    n_masters: usize,
    /// Eigenvalues μ of the interior pencil, ascending (1/s for conduction).
    mu: Vec<f64>,
}

fn full_cb_basis(
    k: faer::MatRef<'_, f64>,
    m: faer::MatRef<'_, f64>,
    masters: &[usize],
) -> Result<FullCb> {
    let n = k.nrows();
    let interior: Vec<usize> = (0..n).filter(|a| !masters.contains(a)).collect();
    let (nb, ni) = (masters.len(), interior.len());
    let k_ii = Mat::from_fn(ni, ni, |i, j| k[(interior[i], interior[j])]);
    let m_ii = Mat::from_fn(ni, ni, |i, j| m[(interior[i], interior[j])]);
    let llt = k_ii
        .llt(faer::Side::Lower)
        .map_err(|_| Error::Compute("K_ii is not positive definite".into()))?;
    let mut psi = Mat::from_fn(ni, nb, |i, j| -k[(interior[i], masters[j])]);
    llt.solve_in_place(psi.as_mut());
    let (mu, phi) = pencil_modes(k_ii.as_ref(), m_ii.as_ref())?;
    let mut t = Mat::<f64>::zeros(n, n);
    for (c, &a) in masters.iter().enumerate() {
        t[(a, c)] = 1.0;
    }
    for (i, &a) in interior.iter().enumerate() {
        for c in 0..nb {
            t[(a, c)] = psi[(i, c)];
        }
        for j in 0..ni {
            t[(a, nb + j)] = phi[(i, j)];
        }
    }
    Ok(FullCb {
        t,
        n_masters: nb,
        mu,
    })
}

/// How [`reduce_casing`] forms the reduced matrices TᵀAT.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Projection {
    /// From the sparse rows by blocks ([`crate::march::reduced::project_sparse`]): no n × n
    /// array, no size limit but the reduced model's.
    Sparse,
    /// From the dense full model ([`crate::march::reduced::project`]; n ≤
    /// [`super::casing_case::MAX_DENSE_DOF`]): the reference the sparse projection is tested
    /// against.
    Dense,
}

/// Reduces the full casing model `full` of `case` (module doc), projecting its matrices as `how`
/// says.
pub fn reduce_casing(
    case: &Case,
    sm: &StructuralModel,
    red: &Reduction,
    full: CasingModel,
    how: Projection,
) -> Result<NonsmoothCase> {
    let file = case.path.display().to_string();
    let sys = &full.case.system;
    let (n, nm) = (sys.n, sys.n_mech);
    if red.gsi_modes.is_some() {
        return Err(Error::input(format!(
            "{file}: key 'reduction.gsi_modes': a casing case has no cyclic frontier to reduce"
        )));
    }
    // Mechanical masters.
    let mut groups = case_master_groups(case);
    for cs in &case.casing {
        groups.push((cs.group.clone(), MasterRole::Contact));
    }
    let pu = partition(sm, &groups).map_err(|e| Error::input(format!("{file}: {e}")))?;
    let tu = cb_columns(
        sm.free.k.as_ref(),
        sm.free.m.as_ref(),
        &pu,
        red.interface_modes,
    )
    .map_err(|e| match e {
        Error::Input(m) => Error::input(format!("{file}: key 'reduction.interface_modes': {m}")),
        other => other,
    })?;
    let ru = tu.ncols();
    let mut reduced_of = vec![None; n];
    for (c, d) in pu.masters.iter().enumerate() {
        reduced_of[d.free_row] = Some(c);
    }
    let mut names: Vec<String> = pu
        .masters
        .iter()
        .map(|d| sys.dof_names[d.free_row].clone())
        .collect();
    names.extend((0..red.interface_modes).map(|j| format!("mode {}", j + 1)));
    // Thermal basis: the contact nodes' temperatures (heated or recorded rows) and every
    // conduction mode.
    let nt = n - nm;
    let recorded = full.case.settings.record.clone().unwrap_or_default();
    let mut thermal_masters: Vec<usize> = Vec::new();
    for &r in sys
        .obstacles
        .iter()
        .flat_map(|o| o.heated.iter().map(|(r, _)| r))
        .chain(recorded.iter().filter(|&&r| r >= nm))
    {
        if !thermal_masters.contains(&(r - nm)) {
            thermal_masters.push(r - nm);
        }
    }
    let thermal = if nt > 0 {
        let block = |rows: &[Vec<(usize, f64)>]| {
            let mut b = Mat::<f64>::zeros(nt, nt);
            for (a, row) in rows[nm..].iter().enumerate() {
                for &(j, v) in row.iter().filter(|&&(j, _)| j >= nm) {
                    b[(a, j - nm)] += v;
                }
            }
            b
        };
        let basis = full_cb_basis(
            block(&full.stiffness).as_ref(),
            block(&full.damping).as_ref(),
            &thermal_masters,
        )
        .map_err(|e| Error::Compute(format!("{file}: the heat rows' modes: {e}")))?;
        for (c, &a) in thermal_masters.iter().enumerate() {
            reduced_of[nm + a] = Some(ru + c);
            names.push(sys.dof_names[nm + a].clone());
        }
        names.extend((0..basis.mu.len()).map(|j| format!("conduction mode {}", j + 1)));
        Some(basis)
    } else {
        None
    };
    let tt = thermal
        .as_ref()
        .map_or_else(|| Mat::<f64>::zeros(0, 0), |b| b.t.clone());
    let blocks = BlockBasis {
        mech: tu.as_ref(),
        thermal: tt.as_ref(),
    };
    let mut system = match how {
        Projection::Sparse => project_sparse(
            sys,
            [&full.mass, &full.damping, &full.stiffness],
            &blocks,
            names,
        )?,
        Projection::Dense => {
            let r = ru + tt.ncols();
            let mut t = Mat::<f64>::zeros(n, r);
            t.as_mut().submatrix_mut(0, 0, nm, ru).copy_from(&tu);
            t.as_mut()
                .submatrix_mut(nm, ru, nt, tt.ncols())
                .copy_from(&tt);
            let dense = CasingModel {
                case: NonsmoothCase {
                    system: sys.clone(),
                    settings: full.case.settings.clone(),
                    response: Vec::new(),
                    temperature_nodes: Vec::new(),
                    reference_temperature: None,
                },
                mass: full.mass.clone(),
                damping: full.damping.clone(),
                stiffness: full.stiffness.clone(),
            }
            .dense(&file)?;
            project(&dense.system, t.as_ref(), ru, names)?
        }
    };
    if let Some(b) = &thermal {
        // The exact structure of the heat rows (the projection leaves round-off in the zero
        // blocks): K̃ = blockdiag(K_bb + K_bi Ψ, diag μ), C̃ = [[·, ·], [·, I]].
        let (r, nb) = (system.n, b.n_masters);
        for p in ru + nb..r {
            for q in ru..r {
                let (k, c) = if p == q {
                    (b.mu[p - ru - nb], 1.0)
                } else if q >= ru + nb {
                    (0.0, 0.0)
                } else {
                    (0.0, system.damping[p * r + q])
                };
                system.stiffness[p * r + q] = k;
                system.stiffness[q * r + p] = k;
                system.damping[p * r + q] = c;
                system.damping[q * r + p] = c;
            }
        }
    }
    let record = recorded
        .iter()
        .map(|&d| {
            reduced_of[d].ok_or_else(|| {
                Error::input(format!(
                    "{file}: the recorded DOF '{}' is not a master of the reduction: add its group to `reduction.keep`",
                    sys.dof_names[d]
                ))
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let full = full.case;
    Ok(NonsmoothCase {
        system,
        settings: crate::march::obstacle::NonsmoothSettings {
            record: Some(record),
            ..full.settings
        },
        ..full
    })
}
