//! Stage 2: Craig–Bampton reduction, cyclic symmetry per harmonic index and Gram–Schmidt
//! interface reduction (`docs/theory.md`; `docs/conventions.md` §2), producing the [`Rom`] of a case.
//!
//! | module | what it holds |
//! |---|---|
//! | [`masters`] | master/interior partition of the free DOF |
//! | [`craig_bampton`](mod@craig_bampton) | the CB model with streamed static modes |
//! | [`gsi`] | Gram–Schmidt interface reduction of the low frontier |
//!
//! Pipeline ([`Sector::build`], [`Sector::harmonic`], [`reduce`]): masters from the case
//! ([`masters::case_master_groups`]); one CB model of the sector with both frontiers as masters;
//! for each harmonic index k the cyclic transform ([`crate::cyclic::CyclicTransform`]) of the CB
//! matrices, which eliminates the high-frontier rows (only frontier masters are constrained;
//! contact, target, keep and modal coordinates stay); optionally GSI on the low frontier; then
//! damping and the eigenfrequencies of the result.
//!
//! # Damping (C_k, N·s/m)
//! Built by [`crate::model::damping`] on the reduced K_k, M_k of each harmonic index:
//! * `rayleigh = [α, β]`: C_k = α M_k + β K_k — the exact projection of αM + βK, since all
//!   transformations are linear.
//! * `modal = ζ`: C_k = M_k X_k diag(2ζω_j) X_kᴴ M_k with the ROM's own modes (K_k x_j = ω_j² M_k
//!   x_j, x_jᴴ M_k x_j = 1, every mode of the reduced model), so that every ROM mode has damping
//!   ratio ζ exactly (X_kᴴ C_k X_k = diag(2ζω_j)).
//! * `matrix = "D.mtx"`: not supported with a mesh reduction (an input error).
//!
//! # Nodes on the axis
//! A free frontier node on the symmetry axis belongs to both frontiers and is its own image; its
//! displacement obeys `u = e^{iφ_k} R_α u` ([`crate::cyclic::FrontierPairs`]). It is a master
//! (low-frontier role) of the CB model like any frontier node, and the cyclic transform replaces
//! its 3 rows by the amplitudes of [`crate::cyclic::axis_basis`]: the axial component for k = 0,
//! one circularly polarised in-plane component for k = 1 and N − 1 (both in-plane components for
//! N = 2), none otherwise. Each such coordinate is labelled with the node's component of largest
//! weight in its basis vector (for k = 1, N − 1 it is a complex combination of two components).
//! Clamped axis nodes have no DOF and need nothing.

pub mod craig_bampton;
pub mod gsi;
pub mod masters;

use std::collections::BTreeMap;
use std::time::Instant;

use faer::{c64, Mat};

use crate::case::{Case, Damping};
use crate::cyclic::{
    check_frontier_clamps, distinct_harmonic_indices, match_frontiers, CyclicGeometry,
    CyclicTransform, DofPair,
};
use crate::eigen::{frequencies_hz, hermitian_eigenvalues};
use crate::error::{Error, Result};
use crate::model::{self, StructuralModel};
use crate::rom::{HarmonicRom, MasterNode, MasterRole, ReducedDof, Rom};

pub use craig_bampton::{
    craig_bampton, CbBasis, CbOptions, CbTimings, CraigBampton, CB_EIGEN_BLOCK,
};
pub use masters::{case_master_groups, partition, MasterDof, Partition};

/// Number of eigenfrequencies stored per harmonic index in the ROM.
pub const STORED_FREQUENCIES: usize = 20;

/// The reduced sector: the partition, the CB model, and the cyclic frontier pairing (in CB rows).
#[derive(Clone, Debug)]
pub struct Sector {
    /// Master/interior partition of the free DOF.
    pub partition: Partition,
    /// The Craig–Bampton model (both frontiers free).
    pub cb: CraigBampton,
    /// Cyclic geometry and frontier pairs in CB rows, for a cyclic model.
    pub cyclic: Option<(CyclicGeometry, Vec<DofPair>)>,
}

/// One harmonic index of the reduced model (before damping).
#[derive(Clone, Debug)]
pub struct HarmonicModel {
    /// Harmonic index k.
    pub k: usize,
    /// Whether the matrices are real (imaginary parts exactly zero).
    pub real: bool,
    /// K_k (N/m).
    pub stiffness: Mat<c64>,
    /// M_k (kg).
    pub mass: Mat<c64>,
    /// The reduced coordinates.
    pub dofs: Vec<ReducedDof>,
    /// GSI report when the frontier was reduced.
    pub gsi: Option<crate::rom::GsiReport>,
}

impl Sector {
    /// Builds the partition and the CB model of `model` for `case` (`[reduction]`
    /// interface_modes; masters per [`masters::case_master_groups`]); logs progress to `log`.
    pub fn build(
        case: &Case,
        model: &StructuralModel,
        log: &mut dyn FnMut(&str),
    ) -> Result<Sector> {
        let reduction = case.reduction.as_ref().ok_or_else(|| {
            Error::input(format!(
                "{}: the case has no [reduction] table; add `[reduction] interface_modes = 30` \
                 (the number of Craig–Bampton fixed-interface modes)",
                case.path.display()
            ))
        })?;
        let groups = case_master_groups(case);
        let opts = CbOptions {
            interface_modes: reduction.interface_modes,
            ..CbOptions::default()
        };
        Self::build_with(case, model, &groups, &opts, log)
    }

    /// [`Sector::build`] with explicit master groups and CB options.
    pub fn build_with(
        case: &Case,
        model: &StructuralModel,
        groups: &[(String, MasterRole)],
        opts: &CbOptions,
        log: &mut dyn FnMut(&str),
    ) -> Result<Sector> {
        let t = Instant::now();
        let partition = partition(model, groups)?;
        let cyclic = match &case.cyclic {
            Some(c) => Some(frontier_pairs(case, model, c, &|n| {
                partition.rows_of_node(n)
            })?),
            None => None,
        };
        log(&format!(
            "masters: {} DOF, interior {} DOF",
            partition.n_masters(),
            partition.interior.len()
        ));
        let cb = craig_bampton(
            model.free.k.as_ref(),
            model.free.m.as_ref(),
            &partition,
            opts,
        )?;
        log(&format!(
            "Craig–Bampton: {} masters + {} modes in {:.2} s (factorisation {:.2} s, \
             interface modes {:.2} s, static modes {:.2} s; CPU {:.1} + {:.1} + {:.1} s)",
            cb.n_masters,
            cb.n_modes(),
            t.elapsed().as_secs_f64(),
            cb.timings.factor_s,
            cb.timings.modes_s,
            cb.timings.static_s,
            cb.timings.factor_cpu_s,
            cb.timings.modes_cpu_s,
            cb.timings.static_cpu_s
        ));
        Ok(Sector {
            partition,
            cb,
            cyclic,
        })
    }

    /// Description of the CB coordinates (masters, then modes).
    pub fn cb_dofs(&self) -> Vec<ReducedDof> {
        self.partition
            .masters
            .iter()
            .map(|d| ReducedDof::Physical {
                node_tag: d.node_tag,
                component: d.component,
                role: d.role,
            })
            .chain((0..self.cb.n_modes()).map(|mode| ReducedDof::Modal { mode }))
            .collect()
    }

    /// The CB model without cyclic constraint as a (real) harmonic model with k = 0.
    pub fn cb_model(&self) -> HarmonicModel {
        let to_c =
            |a: &Mat<f64>| Mat::from_fn(a.nrows(), a.ncols(), |i, j| c64::new(a[(i, j)], 0.0));
        HarmonicModel {
            k: 0,
            real: true,
            stiffness: to_c(&self.cb.stiffness),
            mass: to_c(&self.cb.mass),
            dofs: self.cb_dofs(),
            gsi: None,
        }
    }

    /// The CB+CS model of harmonic index k (`docs/conventions.md` §2), then GSI when `gsi_modes` is
    /// given. A model without `[cyclic]` has only k = 0, the CB model itself.
    ///
    /// Errors ([`Error::Input`]): k ≥ N (or k ≠ 0 without `[cyclic]`), GSI without frontier or
    /// with a bad mode count.
    pub fn harmonic(&self, k: usize, gsi_modes: Option<usize>) -> Result<HarmonicModel> {
        let Some((geom, pairs)) = &self.cyclic else {
            if k != 0 {
                return Err(Error::input(format!(
                    "harmonic index {k}: the case has no [cyclic] table, so only k = 0 (the \
                     Craig–Bampton model) exists"
                )));
            }
            if gsi_modes.is_some() {
                return Err(Error::input(
                    "[reduction] gsi_modes needs cyclic frontiers (a [cyclic] table): GSI \
                     reduces the low frontier",
                ));
            }
            return Ok(self.cb_model());
        };
        let t = CyclicTransform::new(geom, k, self.cb.len(), pairs)?;
        let stiffness = t.project(self.cb.stiffness.as_ref());
        let mass = t.project(self.cb.mass.as_ref());
        let all = self.cb_dofs();
        let dofs: Vec<ReducedDof> = t.kept.iter().map(|&r| all[r]).collect();
        let model = HarmonicModel {
            k,
            real: t.real,
            stiffness,
            mass,
            dofs,
            gsi: None,
        };
        match gsi_modes {
            Some(n_g) => apply_gsi(model, n_g),
            None => Ok(model),
        }
    }
}

/// The GSI reduction of a CB+CS model (its low-frontier rows come first).
fn apply_gsi(model: HarmonicModel, n_g: usize) -> Result<HarmonicModel> {
    let is_low = |d: &ReducedDof| {
        matches!(
            d,
            ReducedDof::Physical {
                role: MasterRole::LowFrontier,
                ..
            }
        )
    };
    let n_f = model.dofs.iter().take_while(|d| is_low(d)).count();
    let n_phys = model
        .dofs
        .iter()
        .take_while(|d| matches!(d, ReducedDof::Physical { .. }))
        .count();
    let g = gsi::gsi(
        model.stiffness.as_ref(),
        model.mass.as_ref(),
        model.real,
        n_f,
        n_phys - n_f,
        n_g,
    )?;
    let mut dofs: Vec<ReducedDof> = model.dofs[n_f..n_phys].to_vec();
    dofs.extend((0..g.report.retained).map(|index| ReducedDof::Interface { index }));
    dofs.extend_from_slice(&model.dofs[n_phys..]);
    Ok(HarmonicModel {
        k: model.k,
        real: model.real,
        stiffness: g.stiffness,
        mass: g.mass,
        dofs,
        gsi: Some(g.report),
    })
}

/// The cyclic frontier pairs of a case in rows of the free (clamped, unreduced) model, for the
/// cyclic transform of the sparse sector matrices (`T_kᴴ K T_k` without Craig–Bampton).
///
/// Errors: no `[cyclic]` table, and those of the frontier matching (see [`Sector::build`]).
pub fn free_frontier_pairs(
    case: &Case,
    model: &StructuralModel,
) -> Result<(CyclicGeometry, Vec<DofPair>)> {
    let c = case.cyclic.as_ref().ok_or_else(|| {
        Error::input(format!(
            "{}: the case has no [cyclic] table",
            case.path.display()
        ))
    })?;
    let mesh = model
        .mesh
        .as_ref()
        .ok_or_else(|| Error::input("[cyclic] needs a mesh (the frontiers are mesh groups)"))?;
    let map = model.free_dof_map().ok_or_else(|| {
        Error::input("the model has no DOF map: give `[model] dofs = \"dofs.csv\"`")
    })?;
    let mut rows_of: Vec<Vec<usize>> = vec![Vec::new(); mesh.num_nodes()];
    let mut entries = map.entries.clone();
    entries.sort_by_key(|e| (e.node_tag, e.component));
    for e in &entries {
        if let Some(n) = mesh.node_index(e.node_tag) {
            rows_of[n as usize].push(e.row);
        }
    }
    frontier_pairs(case, model, c, &|n| rows_of[n as usize].clone())
}

/// Matches the frontiers, checks the clamps and the axis nodes, and expresses the free pairs in
/// the rows `rows_of_node` gives (x, y, z rows of a node; empty when it has no free DOF).
fn frontier_pairs(
    case: &Case,
    model: &StructuralModel,
    c: &crate::case::Cyclic,
    rows_of_node: &dyn Fn(u32) -> Vec<usize>,
) -> Result<(CyclicGeometry, Vec<DofPair>)> {
    let mesh = model
        .mesh
        .as_ref()
        .ok_or_else(|| Error::input("[cyclic] needs a mesh (the frontiers are mesh groups)"))?;
    let geom = CyclicGeometry::from_case(c)?;
    let pairs = match_frontiers(mesh, &geom, &c.low, &c.high)?;
    let both_clamped = check_frontier_clamps(mesh, &pairs, &c.low, &c.high, &case.model.clamp)?;
    let mut dof_pairs = Vec::with_capacity(pairs.len());
    for (i, (&l, &h)) in pairs.low.iter().zip(&pairs.high).enumerate() {
        if both_clamped.binary_search(&i).is_ok() {
            continue;
        }
        let (rl, rh) = (rows_of_node(l), rows_of_node(h));
        if rl.len() != 3 || rh.len() != 3 {
            return Err(Error::input(format!(
                "{}: frontier nodes {} ('{}', {} free DOF) and {} ('{}', {} free DOF) are a cyclic \
                 pair but do not both have 3 free DOF; clamp both nodes or neither",
                mesh.source_name(),
                mesh.node_tags[l as usize],
                c.low,
                rl.len(),
                mesh.node_tags[h as usize],
                c.high,
                rh.len()
            )));
        }
        dof_pairs.push(DofPair {
            low: [rl[0], rl[1], rl[2]],
            high: [rh[0], rh[1], rh[2]],
        });
    }
    for &n in &pairs.axis_nodes {
        match rows_of_node(n)[..] {
            [] => {} // clamped: nothing to constrain
            [x, y, z] => dof_pairs.push(DofPair::on_axis([x, y, z])),
            ref rows => {
                return Err(Error::input(format!(
                    "{}: node {} lies on the symmetry axis (both cyclic frontiers) with {} free \
                     DOF; clamp all 3 components of an axis node or none",
                    mesh.source_name(),
                    mesh.node_tags[n as usize],
                    rows.len()
                )))
            }
        }
    }
    Ok((geom, dof_pairs))
}

/// The damping matrix C_k of a harmonic model ([`crate::model::damping`]; see the module
/// documentation), or `None`. The real models of k = 0 and N/2 are damped in real arithmetic.
pub fn damping_matrix(h: &HarmonicModel, damping: Option<&Damping>) -> Result<Option<Mat<c64>>> {
    let refuse = |p: &std::path::Path| {
        Error::input(format!(
            "[model] damping = {{ matrix = \"{}\" }} cannot be reduced with a mesh model yet; use \
             `modal = ζ` or `rayleigh = [α, β]`",
            p.display()
        ))
    };
    if h.real {
        let re = |a: &Mat<c64>| Mat::from_fn(a.nrows(), a.ncols(), |i, j| a[(i, j)].re);
        let (k, m) = (re(&h.stiffness), re(&h.mass));
        let c =
            model::damping::damping_matrix(damping, k.as_ref(), m.as_ref(), |p| Err(refuse(p)))?;
        return Ok(c.map(|c| Mat::from_fn(c.nrows(), c.ncols(), |i, j| c64::new(c[(i, j)], 0.0))));
    }
    model::damping::damping_matrix(damping, h.stiffness.as_ref(), h.mass.as_ref(), |p| {
        Err(refuse(p))
    })
}

/// The harmonic indices a case needs: k_n = n·m mod N for n = 0..H (m the excitation's engine
/// order, 0 without one); `[0]` without `[cyclic]`.
pub fn case_harmonic_indices(case: &Case) -> Vec<usize> {
    match &case.cyclic {
        None => vec![0],
        Some(c) => {
            let m = case
                .excitation
                .as_ref()
                .and_then(|e| e.engine_order)
                .unwrap_or(0);
            distinct_harmonic_indices(c.sectors, m, case.harmonic_balance.harmonics)
        }
    }
}

/// The ROM of a case (`nlrom reduce`): the CB model, then for every harmonic index of
/// [`case_harmonic_indices`] the CB+CS (+GSI) matrices, damping and lowest eigenfrequencies.
pub fn reduce(case: &Case, model: &StructuralModel, log: &mut dyn FnMut(&str)) -> Result<Rom> {
    let sector = Sector::build(case, model, log)?;
    let gsi_modes = case.reduction.as_ref().and_then(|r| r.gsi_modes);
    let mut harmonics = Vec::new();
    for k in case_harmonic_indices(case) {
        let t = Instant::now();
        let h = sector.harmonic(k, gsi_modes)?;
        let damping = damping_matrix(&h, model.free.damping.as_ref())?;
        let lambda = hermitian_eigenvalues(h.stiffness.as_ref(), h.mass.as_ref(), h.real)?;
        log(&format!(
            "harmonic index {k}: {} coordinates ({:.2} s)",
            h.dofs.len(),
            t.elapsed().as_secs_f64()
        ));
        harmonics.push(HarmonicRom {
            harmonic_index: k,
            real: h.real,
            frequencies_hz: frequencies_hz(&lambda, STORED_FREQUENCIES),
            stiffness: h.stiffness,
            mass: h.mass,
            damping,
            dofs: h.dofs,
            gsi: h.gsi,
        });
    }
    let mesh = model
        .mesh
        .as_ref()
        .ok_or_else(|| Error::input("the reduction needs a mesh"))?;
    let nodes = sector
        .partition
        .master_nodes()
        .into_iter()
        .map(|n| MasterNode {
            tag: mesh.node_tags[n as usize],
            position: mesh.coords[n as usize],
        })
        .collect();
    let groups: BTreeMap<String, Vec<u64>> = sector
        .partition
        .groups
        .iter()
        .map(|(g, ns)| {
            (
                g.clone(),
                ns.iter().map(|&n| mesh.node_tags[n as usize]).collect(),
            )
        })
        .collect();
    Ok(Rom {
        cyclic: sector.cyclic.as_ref().map(|(g, _)| *g),
        full_dofs: model.free.n_free(),
        nodes,
        groups,
        interface_modes: sector.cb.n_modes(),
        interface_frequencies_hz: sector.cb.interface_frequencies_hz(),
        harmonics,
        key: rom_key(case)?,
    })
}

/// FNV-1a 64-bit digest (hex) of what the ROM depends on: the mesh (or matrix) files' bytes and
/// the model, cyclic, reduction and contact-group settings.
pub fn rom_key(case: &Case) -> Result<String> {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    let mut feed = |bytes: &[u8]| {
        for &b in bytes {
            h ^= b as u64;
            h = h.wrapping_mul(0x0100_0000_01b3);
        }
    };
    let m = &case.model;
    for path in [&m.mesh, &m.stiffness, &m.mass, &m.dofs]
        .into_iter()
        .flatten()
    {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        feed(&bytes);
    }
    let contacts: Vec<(&str, &str)> = case
        .contact
        .iter()
        .map(|c| (c.contact.as_str(), c.target.as_str()))
        .collect();
    let settings = format!(
        "{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}|{:?}",
        m.material,
        m.materials,
        m.clamp,
        m.damping,
        m.quadrature,
        case.cyclic,
        case.reduction,
        contacts
    );
    feed(settings.as_bytes());
    let ks = case_harmonic_indices(case);
    feed(format!("{ks:?}").as_bytes());
    Ok(format!("{h:016x}"))
}
