//! The travelling-wave march model of a reduced sector (`nlrom::problem::travelling_wave`: engine order
//! m = 3 on the N = 8 shrouded sector of meshes/sector8.msh, node-to-node shroud contact) against
//! the frequency-domain models of the same case:
//! - linear (no contact elements): the real model of the 8 sectors solved at ω equals the direct
//!   complex solve (K_3 − ω²M_3 + iωC_3) Q = F of the harmonic-index-3 ROM, with sector 1 moving
//!   as sector 0 times e^{iφ_3} (u_1(τ) = R_α u_0(τ + 2π·3/8));
//! - stuck shroud (μ = 1e6): the same solve with every contact stuck equals the harmonic balance
//!   (PairSet kinematics with e^{iσφ_{k_n}} R_α^σ, H = 5);
//!
//! The steady states are solved in the frequency domain on the travelling-wave subspace and
//! checked by the residual of the full 8-sector equations.

mod support;

use faer::linalg::solvers::Solve;
use faer::{c64, Mat};
use nlrom::case::{Case, MarchScheme};
use nlrom::interface::build_interfaces;
use nlrom::march::{InitialCondition, MarchSystem};
use nlrom::model;
use nlrom::problem::march_case::case_march;
use nlrom::problem::sector::{SectorDofs, SectorProblem};
use nlrom::problem::travelling_wave::{travelling_wave, TravellingWave};
use nlrom::reduction::reduce;
use nlrom::rom::{ReducedDof, Rom};

use support::cli::root;
use support::sector_hb::{case_text, hb_outputs, rel_err};

const N: usize = 8;
const M: usize = 3;

/// The sector8 case at engine order `M` (H = 5, 200 steps per period at `hz`): shroud contact
/// (kt, kn, μ, n0), the excitation times `scale`.
fn case(contact: [f64; 4], scale: f64, hz: f64) -> String {
    case_text(M, contact, scale, 5, hz, 200)
}

fn load(text: &str) -> Case {
    Case::from_str(text, &root().join("cases/test_march_travelling.toml")).expect("case")
}

/// The pieces of one case: the ROM of every harmonic index 0..N − 1 (reduced once), the
/// travelling wave on it, its march system and the HB problem (H = 5) on the same ROM.
struct Pieces {
    wave: TravellingWave,
    system: MarchSystem,
    hb: SectorProblem,
    rom: Rom,
    dofs: SectorDofs,
}

fn pieces(case: &Case) -> Pieces {
    let sm = model::build(case, &mut |_| {}).expect("model");
    let mut all = case.clone();
    all.harmonic_balance.harmonics = N - 1;
    let rom = reduce(&all, &sm, &mut |_| {}).expect("rom");
    let mesh = sm.mesh.as_ref().unwrap();
    let interfaces = build_interfaces(case, mesh, rom.cyclic.as_ref()).expect("interfaces");
    let hb = SectorProblem::build(case, &rom, mesh, &interfaces).expect("problem");
    let dofs = SectorDofs::new(case, mesh).expect("dofs");
    let wave = travelling_wave(&rom, M, &interfaces, &dofs, "test").expect("wave");
    let system = MarchSystem {
        n: wave.n,
        mass: wave.mass.clone(),
        damping: wave.damping.clone(),
        stiffness: wave.stiffness.clone(),
        force: wave.force.clone(),
        damping_force: Vec::new(),
        elements: wave.elements.clone(),
        dof_names: wave.dof_names.clone(),
        initial: InitialCondition::Rest,
        displacement_scale: 1.0,
    };
    Pieces {
        wave,
        system,
        hb,
        rom,
        dofs,
    }
}

/// e^{iφ_3}, the inter-sector phase of the wave.
fn wave_phase() -> c64 {
    let phi = 2.0 * std::f64::consts::PI * M as f64 / N as f64;
    c64::new(phi.cos(), phi.sin())
}

/// The travelling-wave subspace of the 8-sector coordinates (complex amplitudes, columns of E
/// per coordinate of the k = 3 ROM): a physical ROM coordinate p moves sector j by e^{ijφ_3},
/// another coordinate o is x_3 = 1, y_3 = −i (q_3(t) = Q e^{iωt}). Sparse columns.
fn wave_basis(p: &Pieces) -> Vec<Vec<(usize, c64)>> {
    let h = p.rom.harmonic(M).expect("k = 3");
    let names = &p.wave.dof_names;
    let n_phys = names.iter().filter(|x| x.starts_with("sector 0 ")).count();
    let rot = wave_phase();
    let others: Vec<usize> = (0..h.len())
        .filter(|&r| !matches!(h.dofs[r], ReducedDof::Physical { .. }))
        .collect();
    let block_start = names
        .iter()
        .position(|x| x.starts_with(&format!("k {M} ")))
        .expect("block of k = 3");
    (0..h.len())
        .map(|r| match h.dofs[r] {
            ReducedDof::Physical {
                node_tag,
                component,
                ..
            } => {
                let name = format!(
                    "sector 0 node {node_tag} {}",
                    ["x", "y", "z"][component as usize]
                );
                let p0 = names.iter().position(|x| *x == name).expect("physical row");
                let mut z = c64::new(1.0, 0.0);
                (0..N)
                    .map(|j| {
                        let e = (j * n_phys + p0, z);
                        z *= rot;
                        e
                    })
                    .collect()
            }
            _ => {
                let i = others.iter().position(|&o| o == r).unwrap();
                vec![
                    (block_start + i, c64::new(1.0, 0.0)),
                    (block_start + others.len() + i, c64::new(0.0, -1.0)),
                ]
            }
        })
        .collect()
}

/// The steady response of the 8-sector system with every element stuck (`stuck`) or without
/// contact, solved on the travelling-wave subspace E (Galerkin: (Eᴴ D E) Q = Eᴴ F), as the
/// full amplitude vector z = E Q, and the relative residual ‖D z − F‖ / ‖F‖ of the full
/// 8-sector equations.
fn wave_solve(p: &Pieces, omega: f64, stuck: bool) -> (Vec<c64>, f64) {
    let sys = &p.system;
    let n = sys.n;
    let k = if stuck {
        sys.effective_stiffness(&sys.stick_states())
    } else {
        sys.stiffness.clone()
    };
    let d = |i: usize, j: usize| {
        c64::new(
            k[i * n + j] - omega * omega * sys.mass[i * n + j],
            omega * sys.damping[i * n + j],
        )
    };
    let f: Vec<c64> = sys.force.iter().map(|h| c64::new(h.cos, -h.sin)).collect();
    let e = wave_basis(p);
    let r = e.len();
    // D E, column by column (E sparse)
    let de: Vec<Vec<c64>> = e
        .iter()
        .map(|col| {
            (0..n)
                .map(|i| col.iter().map(|&(j, w)| d(i, j) * w).sum())
                .collect()
        })
        .collect();
    let a = Mat::from_fn(r, r, |i, j| {
        e[i].iter().map(|&(l, w)| w.conj() * de[j][l]).sum::<c64>()
    });
    let b = Mat::from_fn(r, 1, |i, _| {
        e[i].iter().map(|&(l, w)| w.conj() * f[l]).sum::<c64>()
    });
    let q = a.partial_piv_lu().solve(&b);
    let mut z = vec![c64::new(0.0, 0.0); n];
    for (col, i) in e.iter().zip(0..r) {
        for &(l, w) in col {
            z[l] += w * q[(i, 0)];
        }
    }
    let mut res2 = 0.0;
    for i in 0..n {
        let di: c64 = (0..r).map(|j| de[j][i] * q[(j, 0)]).sum();
        res2 += (di - f[i]).norm_sqr();
    }
    let f2: f64 = f.iter().map(|x| x.norm_sqr()).sum();
    (z, (res2 / f2).sqrt())
}

fn pick(q: &[c64], rows: &[usize]) -> Vec<c64> {
    rows.iter().map(|&r| q[r]).collect()
}

/// Linear (no contact elements), 170 Hz: the travelling wave solves the full 8-sector equations
/// (residual), its sector 0 equals the direct complex solve (K_3 − ω²M_3 + iωC_3) Q = F of the
/// ROM of k = 3, and sector 1 is sector 0 times e^{iφ_3}.
#[test]
fn linear_wave_equals_the_complex_rom_of_its_harmonic_index() {
    let hz = 170.0;
    let omega = 2.0 * std::f64::consts::PI * hz;
    let case = load(&case([1e8, 1e8, 0.3, 100.0], 1.0, hz));
    let mut p = pieces(&case);
    p.system.elements.clear();
    let (z, residual) = wave_solve(&p, omega, false);
    let h = p.rom.harmonic(M).expect("k = 3");
    let f = p.dofs.excitation_vector(h).unwrap();
    let c = h.damping.as_ref().unwrap();
    let d = Mat::from_fn(h.len(), h.len(), |i, j| {
        h.stiffness[(i, j)] - h.mass[(i, j)] * (omega * omega) + c[(i, j)] * c64::new(0.0, omega)
    });
    let q3 = d
        .partial_piv_lu()
        .solve(Mat::from_fn(h.len(), 1, |i, _| f[i]));
    let rom_rows: Vec<c64> = p
        .dofs
        .output_rows(h)
        .unwrap()
        .iter()
        .map(|&r| q3[(r, 0)])
        .collect();
    let s0 = pick(&z, &p.wave.response);
    let err = rel_err(&s0, &rom_rows);
    println!(
        "linear: {} coordinates ({} sectors, blocks k = {:?}), residual {residual:.2e}, sector 0 vs ROM k = 3 {err:.2e}",
        p.wave.n, p.wave.sectors, p.wave.blocks
    );
    assert_eq!(
        (p.wave.sectors, p.wave.blocks.clone()),
        (N, vec![0, 1, 2, 3, 4])
    );
    assert!(residual < 1e-9, "8-sector residual: {residual:.3e}");
    assert!(err < 1e-9, "sector 0 vs the ROM of k = 3: {err:.3e}");
}

/// Stuck shroud (μ = 1e6), 170 Hz: the 8-sector model with every element stuck has the
/// travelling wave as solution (residual of the full equations) and its sector 0 equals the
/// harmonic balance (Newton from zero, PairSet kinematics e^{iσφ_{k_n}} R_α^σ).
#[test]
fn stuck_wave_equals_harmonic_balance() {
    let hz = 170.0;
    let omega = 2.0 * std::f64::consts::PI * hz;
    let case = load(&case([1e8, 1e8, 1e6, 100.0], 1.0, hz));
    let p = pieces(&case);
    let (z, residual) = wave_solve(&p, omega, true);
    let hb = hb_outputs(&p.hb, omega);
    let err = rel_err(&pick(&z, &p.wave.response), &hb);
    let (free, _) = wave_solve(&p, omega, false);
    let without = rel_err(&pick(&free, &p.wave.response), &hb);
    println!(
        "stuck: {} friction elements, residual {residual:.2e}, sector 0 vs HB {err:.2e} (without contact {without:.2e})",
        p.system.elements.len()
    );
    assert!(residual < 1e-9, "8-sector residual: {residual:.3e}");
    assert!(err < 1e-6, "stuck wave vs HB: {err:.3e}");
    assert!(without > 0.1, "the contact matters: {without:.3e}");

    // `nlrom march` builds the same model (its own ROM of every harmonic index), reporting sector 0
    let cm = case_march(&case, Some(MarchScheme::PiecewiseLinear), &mut |l| {
        println!("{l}")
    })
    .expect("travelling-wave march");
    assert_eq!(cm.system.n, p.wave.n);
    assert_eq!(cm.response, p.wave.response);
    assert_eq!(cm.system.elements.len(), p.system.elements.len());
    assert!(cm.system.dof_names[cm.response[0]].starts_with("sector 0 node "));
    let rel = |a: &[f64], b: &[f64]| {
        let d = a
            .iter()
            .zip(b)
            .map(|(x, y)| (x - y).abs())
            .fold(0.0, f64::max);
        d / b.iter().map(|x| x.abs()).fold(0.0, f64::max)
    };
    assert!(rel(&cm.system.stiffness, &p.system.stiffness) < 1e-12);
    assert!(rel(&cm.system.mass, &p.system.mass) < 1e-12);
}
