//! Time marching of a reduced sector (`nlrom::problem::sector_march`: the real ROM of meshes/sector8.msh
//! with node-to-node shroud contact) against the project's other methods on the same case:
//! - stuck contact (μ = 1e6): the steady first harmonic equals the direct complex solve
//!   (K + K_c − ω²M + iωC) Q = F of the marched matrices, for k = 0 and k = N/2, and without
//!   `[cyclic]` or contact;
//! - micro-slip: the steady first-harmonic amplitude equals the harmonic balance of
//!   `nlrom::problem::sector::SectorProblem` (PairSet kinematics, AFT, H = 5) within 1 %;
//! - the quasi-static method far below the first mode (15 Hz): the same harmonic balance, with
//!   inertia, within 3 %;
//!
//! Travelling waves (k ≠ 0, N/2): tests/march_travelling.rs.

mod support;

use faer::linalg::solvers::Solve;
use faer::{c64, Mat};
use nlrom::case::{Case, MarchScheme};
use nlrom::interface::build_interfaces;
use nlrom::march::{march, MarchOutcome};
use nlrom::model;
use nlrom::problem::march_case::{case_march, CaseMarch};
use nlrom::problem::sector::SectorProblem;
use nlrom::reduction::reduce;

use support::cli::root;
use support::sector_hb::{case_text, hb_outputs, rel_err};

const N: usize = 8;
fn load(text: &str) -> Case {
    Case::from_str(text, &root().join("cases/test_march_sector.toml")).expect("case")
}

/// The march of `case` to steady state.
fn run(case: &Case) -> (CaseMarch, MarchOutcome) {
    let cm = case_march(case, Some(MarchScheme::PiecewiseLinear), &mut |l| {
        println!("{l}")
    })
    .expect("sector march");
    let out = march(&cm.system, &cm.settings).expect("march");
    println!(
        "march: {} steps, steady after {:?} periods (periodicity error {:.1e}), {} factorisations, {:.2} s",
        out.steps,
        out.steady_period,
        out.periods.last().and_then(|p| p.periodicity_error).unwrap_or(f64::NAN),
        out.factorisations,
        out.wall_seconds
    );
    assert!(
        out.steady_period.is_some(),
        "the march reached no steady state"
    );
    (cm, out)
}

/// The first harmonics (complex, `docs/conventions.md` §4) of the reported rows over the last period.
fn march_h1(cm: &CaseMarch, out: &MarchOutcome) -> Vec<c64> {
    cm.response
        .iter()
        .map(|&r| {
            let (re, im) = out.harmonics[r][1];
            c64::new(re, im)
        })
        .collect()
}

/// Direct complex solve (K + K_c − ω²M + iωC) Q = F of the marched system with every contact
/// stuck (K_c: the elements' stick stiffness), at the reported rows.
fn stuck_solve(cm: &CaseMarch) -> Vec<c64> {
    let sys = &cm.system;
    let (n, w) = (sys.n, cm.settings.omega);
    let k = sys.effective_stiffness(&sys.stick_states());
    let d = Mat::from_fn(n, n, |i, j| {
        c64::new(
            k[i * n + j] - w * w * sys.mass[i * n + j],
            w * sys.damping[i * n + j],
        )
    });
    let f = Mat::from_fn(n, 1, |i, _| c64::new(sys.force[i].cos, -sys.force[i].sin));
    let q = d.partial_piv_lu().solve(&f);
    cm.response.iter().map(|&r| q[(r, 0)]).collect()
}

/// Stuck shroud (μ = 1e6): march and direct complex solve agree, for harmonic index `k`
/// (engine order m = k), at 0.9 of the first stuck natural frequency.
fn stuck_case(m: usize, hz: f64) {
    let case = load(&case_text(m, [1e8, 1e8, 1e6, 100.0], 1.0, 3, hz, 200));
    let (cm, out) = run(&case);
    let direct = stuck_solve(&cm);
    let marched = march_h1(&cm, &out);
    let err = rel_err(&marched, &direct);
    let without = {
        let mut free = cm.system.clone();
        free.elements.clear();
        let cmf = CaseMarch {
            system: free,
            response: cm.response.clone(),
            response_dofs: cm.response_dofs.clone(),
            settings: cm.settings.clone(),
        };
        rel_err(&stuck_solve(&cmf), &direct)
    };
    let amp = direct.iter().map(|z| z.norm()).fold(0.0, f64::max);
    println!(
        "stuck m = {m}: |Q1| = {amp:.4e} m, march vs direct {err:.2e} (without contact {without:.2e})"
    );
    assert!(err < 2e-3, "stuck march vs direct solve: {err:.3e}");
    assert!(without > 0.1, "the contact springs matter: {without:.3e}");
}

#[test]
fn stuck_k0_equals_direct_complex_solve() {
    stuck_case(0, 170.0);
}

#[test]
fn stuck_k_half_equals_direct_complex_solve() {
    stuck_case(N / 2, 1700.0);
}

/// Without `[cyclic]` (the Craig–Bampton sector, frontiers free) and without contact: the march
/// of the 13-coordinate ROM equals its direct complex solve at 170 Hz.
#[test]
fn no_cyclic_rom_equals_direct_complex_solve() {
    let text = case_text(0, [1e8, 1e8, 0.3, 100.0], 1.0, 3, 170.0, 200);
    let strip = |t: &str, from: &str, to: &str| {
        let (i, j) = (t.find(from).unwrap(), t.find(to).unwrap());
        format!("{}{}", &t[..i], &t[j..])
    };
    let text = strip(&text, "[cyclic]", "[reduction]");
    let text = strip(&text, "[[contact]]", "[excitation]")
        .replace("engine_order = 0\n", "")
        .replace("gsi_modes = 6\n", "");
    let (cm, out) = run(&load(&text));
    assert!(cm.system.elements.is_empty());
    let err = rel_err(&march_h1(&cm, &out), &stuck_solve(&cm));
    println!("no cyclic: march vs direct {err:.2e}");
    assert!(err < 2e-3, "march vs direct solve: {err:.3e}");
}

/// The harmonic balance of the same case at ω: Newton from zero, then |Q1| at the outputs.
fn hb_h1(case: &Case, omega: f64) -> Vec<c64> {
    let sm = model::build(case, &mut |_| {}).expect("model");
    let rom = reduce(case, &sm, &mut |_| {}).expect("rom");
    let mesh = sm.mesh.as_ref().unwrap();
    let interfaces = build_interfaces(case, mesh, rom.cyclic.as_ref()).expect("interfaces");
    let p = SectorProblem::build(case, &rom, mesh, &interfaces).expect("problem");
    hb_outputs(&p, omega)
}

/// Micro-slip of the shroud at k = 0 (engine order 0), 170 Hz (the first stuck k = 0 mode is near
/// 185 Hz, the free-shroud one near 150 Hz), 100× the unit force: the marched steady first
/// harmonic equals the harmonic balance (H = 5, 256 AFT samples, Newton from zero) within 1 %, and
/// the contact matters (the stuck response differs by more than 5 %). The periodicity error
/// levels off near 5e-5 (the ROM's high modes, undamped by average-acceleration Newmark, decay
/// only by the modal damping), hence `steady_tolerance = 1e-4`.
#[test]
fn microslip_k0_first_harmonic_equals_harmonic_balance() {
    let case = load(&case_text(0, [1e8, 1e8, 0.3, 100.0], 100.0, 5, 170.0, 200));
    let (cm, out) = run(&case);
    let marched = march_h1(&cm, &out);
    let hb = hb_h1(&case, cm.settings.omega);
    let err = rel_err(&marched, &hb);
    let stuck = rel_err(&stuck_solve(&cm), &hb);
    let amp = hb.iter().map(|z| z.norm()).fold(0.0, f64::max);
    println!("micro-slip: |Q1| = {amp:.4e} m, march vs HB {err:.2e} (stuck vs HB {stuck:.2e})");
    assert!(err < 1e-2, "march vs HB: {err:.3e}");
    assert!(stuck > 5e-2, "the response is not nonlinear: {stuck:.3e}");
}

/// The quasi-static method (Gastaldi & Berruti 2018 §5) where it applies: at 15 Hz, a tenth of
/// the free-shroud k = 0 mode (≈ 150 Hz), inertia and damping forces are about 1 % of the elastic
/// ones; with 10× the force of the micro-slip case above the shroud slips. The quasi-static march
/// (300 steps per period, 10 periods from rest; the end-of-period states repeat within 1e-3, the
/// sliders of the 90 elements still shaking down by about 4e-4 a period) equals the harmonic
/// balance of the same case with inertia (H = 5) within 3 % in the first harmonic (measured
/// 0.37 %), and the contact matters (the stuck response differs by more than 5 %: 6.3 %).
#[test]
fn quasi_static_far_below_the_first_mode_equals_harmonic_balance() {
    let text = case_text(0, [1e8, 1e8, 0.3, 100.0], 1000.0, 5, 15.0, 300);
    let case = load(&text.replace("periods = 200", "periods = 10"));
    let cm = case_march(&case, Some(MarchScheme::QuasiStatic), &mut |_| {}).expect("march");
    let out = march(&cm.system, &cm.settings).expect("quasi-static march");
    let last = out.periods.last().and_then(|p| p.periodicity_error);
    let periodic = last.unwrap_or(f64::INFINITY);
    assert!(periodic < 1e-3, "the periods do not repeat: {periodic:.2e}");
    let marched = march_h1(&cm, &out);
    let hb = hb_h1(&case, cm.settings.omega);
    let err = rel_err(&marched, &hb);
    let stuck = rel_err(&stuck_solve(&cm), &hb);
    let amp = hb.iter().map(|z| z.norm()).fold(0.0, f64::max);
    println!(
        "quasi-static at 15 Hz: {} steps, periodicity error {periodic:.1e}, |Q1| = {amp:.4e} m, march vs HB {err:.2e} (stuck vs HB {stuck:.2e})",
        out.steps
    );
    assert!(err < 3e-2, "quasi-static march vs HB: {err:.3e}");
    assert!(stuck > 5e-2, "the response is not nonlinear: {stuck:.3e}");
}
