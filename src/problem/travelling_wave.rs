//! A travelling wave of a reduced sector as a real time-domain model: the N′ sectors of one wave
//! period, built from the complex ROMs of the harmonic indices the wave can excite.
//!
//! Engine order m excites the harmonic index k = m mod N, and in steady state sector j + 1 moves
//! as sector j shifted in time by the inter-sector phase: u_{j+1}(τ) = R_α u_j(τ + φ_k) with
//! τ = ωt and φ_k = 2πk/N (`docs/conventions.md` §2: harmonic n of the field of sector j + 1 is
//! that of sector j times e^{inφ_k}, since k_n ≡ n·k mod N). The motion repeats every
//! N′ = N / gcd(k, N) sectors, and its cyclic components are the harmonic indices
//! 𝒦 = {0, d, 2d, …} (d = gcd(k, N)), the indices k_n = n·m mod N of every temporal harmonic n.
//! The frontier between two sectors is a solid cut, so the linear coupling of the sectors is
//! itself a delayed relation on the reference sector; instead of delaying it, this module
//! marches the N′ sectors together in real coordinates:
//!
//! - block k ∈ 𝒦 with 0 < k < N/2 is the complex ROM q_k = x_k + i y_k of harmonic index k,
//!   standing for k and N − k (q_{N−k} = q̄_k); blocks k = 0 and k = N/2 are real. Sector j reads
//!   u_j = Σ_k Re(e^{ijφ_k} T_k q_k) in its own frame (the rotation R_α^j removed);
//! - the kinetic energy Σ_j ½ u̇_jᵀ M u̇_j is ½ N′ q̇_kᵀ M_k q̇_k for a real block and
//!   ½ (N′/2) q̇_kᴴ M_k q̇_k = ½ (N′/2) [ẋ; ẏ]ᵀ [[A, −S], [S, A]] [ẋ; ẏ] for a complex one
//!   (M_k = A + iS Hermitian), and so for K_k and C_k: the blocks are the real forms of the ROM
//!   matrices scaled by N′ or N′/2;
//! - the physical master DOFs of the ROM (contact, target, `keep` nodes; the same in every block)
//!   are replaced by the displacements u_j of every sector, the inverse of the real discrete
//!   Fourier transform q_0 = (1/N′) Σ_j u_j, x_k = (2/N′) Σ_j cos(jφ_k) u_j,
//!   y_k = −(2/N′) Σ_j sin(jφ_k) u_j, q_{N/2} = (1/N′) Σ_j (−1)^j u_j (the matrices are
//!   transformed as Bᵀ M B). The modal and interface coordinates stay per block;
//! - every sector carries its contact pairs, the target of a pair with σ ≠ 0 on sector j + σ
//!   (its displacement R_α^σ u_{j+σ} in the frame of sector j), and the excitation
//!   f_j(t) = Re(f e^{i(ωt + jφ_k)}) on its excitation nodes.
//!
//! The coordinates are therefore: the physical master DOFs of sector 0, of sector 1, …, of
//! sector N′ − 1, then the other coordinates of each block in ascending k (x_k then y_k). The
//! reported rows are those of sector 0. The model holds every temporal harmonic the time
//! signals carry; the harmonic balance of the same case truncates them at H.

use super::sector::{DofLabel, SectorDofs};
use super::sector_march::pair_elements;
use crate::cyclic::phase;
use crate::error::{Error, Result};
use crate::interface::ContactInterface;
use crate::march::element::Element;
use crate::march::signal::Harmonic;
use crate::rom::{HarmonicRom, ReducedDof, Rom};

/// The real matrices, excitation, friction elements and reported rows of a travelling wave
/// (module documentation).
pub struct TravellingWave {
    /// Number of coordinates.
    pub n: usize,
    /// Mass (kg, row-major n × n).
    pub mass: Vec<f64>,
    /// Damping (N·s/m, row-major n × n).
    pub damping: Vec<f64>,
    /// Stiffness (N/m, row-major n × n).
    pub stiffness: Vec<f64>,
    /// The excitation of every coordinate (N).
    pub force: Vec<Harmonic>,
    /// The friction elements of every sector's contact pairs (two per pair).
    pub elements: Vec<Element>,
    /// A name per coordinate.
    pub dof_names: Vec<String>,
    /// The reported rows (sector 0's physical rows of the output DOFs).
    pub response: Vec<usize>,
    /// Number of sectors N′ of one wave period.
    pub sectors: usize,
    /// The harmonic indices of the blocks, ascending.
    pub blocks: Vec<usize>,
}

/// One block: the ROM of harmonic index k ≤ N/2 (read from that of N − k, conjugated, when the
/// ROM holds only N − k).
struct Block<'a> {
    k: usize,
    rom: &'a HarmonicRom,
    conjugate: bool,
    /// Real block (k = 0 or N/2): one real coordinate per ROM coordinate; else two (x, y).
    real: bool,
    /// ROM row of each physical master DOF (in the order of the model's physical list).
    physical_rows: Vec<usize>,
    /// ROM rows of the other coordinates (interface, modal).
    other_rows: Vec<usize>,
}

/// The travelling wave of engine order `m` on the ROM `rom` (with cyclic symmetry, N sectors),
/// its contact `interfaces`, excitation and output DOFs `dofs`; `what` names the case in messages.
///
/// Errors ([`Error::Input`]): a harmonic index of 𝒦 (or N − k) missing from the ROM, physical
/// master DOFs that differ between the blocks, a contact, target, excitation or output node that
/// is not a physical master DOF, and the errors of the contact interfaces.
pub fn travelling_wave(
    rom: &Rom,
    m: usize,
    interfaces: &[ContactInterface],
    dofs: &SectorDofs,
    what: &str,
) -> Result<TravellingWave> {
    let n_sec = rom
        .cyclic
        .as_ref()
        .map(|g| g.sectors)
        .ok_or_else(|| Error::input(format!("{what}: a travelling wave needs [cyclic]")))?;
    let k_m = m % n_sec;
    let d = gcd(k_m, n_sec);
    let np = n_sec / d;
    let physical = physical_list(rom)?;
    let np_f = np as f64;
    let mut blocks = Vec::new();
    for k in (0..=n_sec / 2).filter(|k| k % d == 0) {
        let (h, conjugate) = match (rom.harmonic(k), rom.harmonic((n_sec - k) % n_sec)) {
            (Some(h), _) => (h, false),
            (None, Some(h)) => (h, true),
            (None, None) => {
                return Err(Error::input(format!(
                    "{what}: the travelling wave of engine order {m} needs the ROM of harmonic index k = {k} (or {}); rebuild it with `nlrom reduce`",
                    n_sec - k
                )))
            }
        };
        let physical_rows = physical
            .iter()
            .map(|l| {
                h.row_of(l.node_tag, l.component).ok_or_else(|| {
                    Error::input(format!(
                        "{what}: node {} is a physical master DOF of harmonic index {} but not of {}: the blocks of a travelling wave need the same physical master DOFs",
                        l.node_tag,
                        rom.harmonics.first().map_or(0, |h| h.harmonic_index),
                        h.harmonic_index
                    ))
                })
            })
            .collect::<Result<Vec<_>>>()?;
        let other_rows: Vec<usize> = (0..h.len())
            .filter(|&r| !matches!(h.dofs[r], ReducedDof::Physical { .. }))
            .collect();
        if physical_rows.len() + other_rows.len() != h.len() {
            return Err(Error::input(format!(
                "{what}: harmonic index {} has physical master DOFs the others do not have",
                h.harmonic_index
            )));
        }
        blocks.push(Block {
            k,
            rom: h,
            conjugate,
            real: k == 0 || 2 * k == n_sec,
            physical_rows,
            other_rows,
        });
    }
    let np_phys = physical.len();
    // coordinate layout: sectors' physical DOFs, then each block's other coordinates (x, then y)
    let mut n = np * np_phys;
    let mut other_offset = Vec::with_capacity(blocks.len());
    for b in &blocks {
        other_offset.push(n);
        n += b.other_rows.len() * if b.real { 1 } else { 2 };
    }
    // B: block coordinates from the model's (row-major per block: width × n)
    let mut mass = vec![0.0; n * n];
    let mut damping = vec![0.0; n * n];
    let mut stiffness = vec![0.0; n * n];
    for (b, &off) in blocks.iter().zip(&other_offset) {
        let nk = b.rom.len();
        let parts = if b.real { 1 } else { 2 };
        let width = parts * nk;
        let phi = phase(b.k, n_sec);
        // row l of B: the model coordinates block coordinate l reads, with their weights
        let mut map: Vec<Vec<(usize, f64)>> = vec![Vec::new(); width];
        for part in 0..parts {
            for (p, &row) in b.physical_rows.iter().enumerate() {
                map[part * nk + row] = (0..np)
                    .map(|j| {
                        let a = j as f64 * phi;
                        let w = match (b.real, part) {
                            (true, _) => a.cos() / np_f,
                            (false, 0) => 2.0 * a.cos() / np_f,
                            _ => -2.0 * a.sin() / np_f,
                        };
                        (j * np_phys + p, w)
                    })
                    .collect();
            }
            for (i, &row) in b.other_rows.iter().enumerate() {
                map[part * nk + row] = vec![(off + part * b.other_rows.len() + i, 1.0)];
            }
        }
        let scale = if b.real { np_f } else { np_f / 2.0 };
        let real_form = |a: &faer::Mat<faer::c64>| -> Vec<f64> {
            let mut out = vec![0.0; width * width];
            for i in 0..nk {
                for j in 0..nk {
                    let v = a[(i, j)];
                    let (re, im) = (v.re, if b.conjugate { -v.im } else { v.im });
                    out[i * width + j] = scale * re;
                    if !b.real {
                        out[i * width + nk + j] = -scale * im;
                        out[(nk + i) * width + j] = scale * im;
                        out[(nk + i) * width + nk + j] = scale * re;
                    }
                }
            }
            out
        };
        add_congruence(&mut mass, &real_form(&b.rom.mass), &map, n);
        add_congruence(&mut stiffness, &real_form(&b.rom.stiffness), &map, n);
        if let Some(c) = &b.rom.damping {
            add_congruence(&mut damping, &real_form(c), &map, n);
        }
    }
    let index = |tag: u64, c: u8| -> Option<usize> {
        physical
            .iter()
            .position(|l| l.node_tag == tag && l.component == c)
    };
    // excitation f_j(t) = Re(f e^{i(ωt + jφ_k)}) on each sector's excitation nodes
    let mut force = vec![Harmonic::default(); n];
    let phi_m = phase(k_m, n_sec);
    for &tag in &dofs.excitation_nodes {
        for (c, &f) in dofs.force.iter().enumerate() {
            let p = index(tag, c as u8).ok_or_else(|| {
                Error::input(format!(
                    "{what}: excitation node {tag} ('{}') is not a physical master DOF of the ROM; add its group to `[reduction] keep`",
                    dofs.group
                ))
            })?;
            for j in 0..np {
                let h = Harmonic::cosine(f, j as f64 * phi_m);
                let e = &mut force[j * np_phys + p];
                e.cos += h.cos;
                e.sin += h.sin;
            }
        }
    }
    let elements = sector_elements(interfaces, &physical, np, what)?;
    let response = dofs
        .outputs
        .iter()
        .map(|l| {
            index(l.node_tag, l.component).ok_or_else(|| {
                Error::input(format!(
                    "{what}: response node {} is not a physical master DOF of the ROM; add its group to `[reduction] keep`",
                    l.node_tag
                ))
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let mut dof_names = Vec::with_capacity(n);
    for j in 0..np {
        for l in &physical {
            dof_names.push(format!(
                "sector {j} node {} {}",
                l.node_tag,
                ["x", "y", "z"][l.component as usize % 3]
            ));
        }
    }
    for b in &blocks {
        let parts: &[&str] = if b.real { &[""] } else { &[" re", " im"] };
        for part in parts {
            for &r in &b.other_rows {
                dof_names.push(match b.rom.dofs[r] {
                    ReducedDof::Interface { index } => format!("k {} interface {index}{part}", b.k),
                    ReducedDof::Modal { mode } => format!("k {} mode {mode}{part}", b.k),
                    ReducedDof::Physical { node_tag, .. } => {
                        format!("k {} node {node_tag}{part}", b.k)
                    }
                });
            }
        }
    }
    Ok(TravellingWave {
        n,
        mass,
        damping,
        stiffness,
        force,
        elements,
        dof_names,
        response,
        sectors: np,
        blocks: blocks.iter().map(|b| b.k).collect(),
    })
}

/// The physical master DOFs of the first ROM block, in its order.
fn physical_list(rom: &Rom) -> Result<Vec<DofLabel>> {
    let h = rom
        .harmonics
        .first()
        .ok_or_else(|| Error::input("the ROM has no harmonic index".to_string()))?;
    Ok(h.dofs
        .iter()
        .filter_map(|d| match *d {
            ReducedDof::Physical {
                node_tag,
                component,
                ..
            } => Some(DofLabel {
                node_tag,
                component,
            }),
            _ => None,
        })
        .collect())
}

/// a += Bᵀ A B for the square block A (row-major, `map.len()` rows) and the sparse rows of
/// B (`map[l]`: the (column, weight) entries of row l) on n columns.
fn add_congruence(a: &mut [f64], block: &[f64], map: &[Vec<(usize, f64)>], n: usize) {
    let width = map.len();
    for (l1, row1) in map.iter().enumerate() {
        for (l2, row2) in map.iter().enumerate() {
            let v = block[l1 * width + l2];
            if v == 0.0 {
                continue;
            }
            for &(i, b1) in row1 {
                for &(j, b2) in row2 {
                    a[i * n + j] += b1 * v * b2;
                }
            }
        }
    }
}

/// The friction elements of every sector j < `np`: each pair's contact node on sector j, its
/// target on sector j + σ (mod `np`), on the rows j·|P| + p of the physical list `physical`.
fn sector_elements(
    interfaces: &[ContactInterface],
    physical: &[DofLabel],
    np: usize,
    what: &str,
) -> Result<Vec<Element>> {
    let np_phys = physical.len();
    let rows = |tag: u64| -> Option<[usize; 3]> {
        let at = |c: u8| {
            physical
                .iter()
                .position(|l| l.node_tag == tag && l.component == c)
        };
        Some([at(0)?, at(1)?, at(2)?])
    };
    let mut out = Vec::new();
    for iface in interfaces {
        let pairs = iface
            .elements(rows)
            .map_err(|e| Error::input(format!("{what}: {e}")))?;
        for pair in pairs {
            let tag = |p: usize| physical[p].node_tag;
            for j in 0..np {
                let mut shifted = pair.clone();
                shifted.contact = pair.contact.map(|p| j * np_phys + p);
                let target_sector = (j as i64 + pair.sigma as i64).rem_euclid(np as i64) as usize;
                shifted.target = pair.target.map(|t| t.map(|p| target_sector * np_phys + p));
                let label = match pair.target {
                    Some(t) => format!(
                        "{} sector {j} {}-{}",
                        iface.name,
                        tag(pair.contact[0]),
                        tag(t[0])
                    ),
                    None => format!("{} sector {j} {}", iface.name, tag(pair.contact[0])),
                };
                out.extend(pair_elements(&shifted, &iface.rotation, 1.0, &label));
            }
        }
    }
    Ok(out)
}

/// Greatest common divisor (gcd(0, n) = n).
fn gcd(a: usize, b: usize) -> usize {
    if b == 0 {
        a
    } else {
        gcd(b, a % b)
    }
}
