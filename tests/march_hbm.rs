//! Time marching against the project's harmonic balance (`nlrom::hbm`, H = 7): matrix-defined
//! oscillators with an `[[element]]` friction element (`contact::grounded::DofElements` on the HB
//! side, `march::element` on the marching side — the same `contact::law`), marched to steady state
//! by piecewise-linear Newmark, whose first-harmonic amplitude must equal the HB's within 1 %
//! (the cross-check of the two methods). The HB point is the end of a frequency
//! continuation (`hbm::frf::frequency_response`) that stops exactly at the marched ω.

use std::path::Path;

use nlrom::case::{Case, FrictionElement, MarchScheme};
use nlrom::contact::grounded::DofElements;
use nlrom::continuation::{ContinuationOptions, PathEnd};
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::frf::frequency_response;
use nlrom::hbm::{HbmSystem, ResponseOptions};
use nlrom::march::march;
use nlrom::model;
use nlrom::problem::march_case::case_march;
use nlrom::problem::matrix_case::matrix_setup;

const HARMONICS: usize = 7;

fn write(dir: &Path, name: &str, text: &str) {
    std::fs::write(dir.join(name), text).unwrap();
}

/// A case file of matrices K, M (MatrixMarket, symmetric, lower triangle entries (i, j, v), 0-based)
/// with `body` appended (excitation, damping, elements, march).
fn matrix_case(
    dir: &Path,
    n: usize,
    k: &[(usize, usize, f64)],
    m: &[(usize, usize, f64)],
    body: &str,
) -> Case {
    let mtx = |e: &[(usize, usize, f64)]| {
        let mut s = format!(
            "%%MatrixMarket matrix coordinate real symmetric\n{n} {n} {}\n",
            e.len()
        );
        for (i, j, v) in e {
            s.push_str(&format!("{} {} {v}\n", i + 1, j + 1));
        }
        s
    };
    write(dir, "K.mtx", &mtx(k));
    write(dir, "M.mtx", &mtx(m));
    let text = format!(
        "[model]\nstiffness = \"K.mtx\"\nmass = \"M.mtx\"\n{body}\n[harmonic_balance]\nharmonics = {HARMONICS}\n\n[march]\nfrequency_rad_s = 1.0\nperiods = 400\nsteps_per_period = 800\nscheme = \"piecewise-linear\"\nstop_at_steady = true\nsteady_tolerance = 1e-8\ntolerance = 1e-10\n"
    );
    write(dir, "case.toml", &text);
    Case::load(&dir.join("case.toml")).unwrap()
}

/// |Q1| of the output DOF at ω from the HB: the case's elements with their matrix rows mapped to
/// the condensed (nonlinear) DOF, continuation from `start` up or down to exactly ω.
fn hb_amplitude(case: &Case, start: f64, omega: f64) -> f64 {
    let sm = model::build(case, &mut |_| {}).unwrap();
    let setup = matrix_setup(case, &sm).unwrap();
    let to_condensed = |dofs: &[usize]| -> Vec<usize> {
        dofs.iter()
            .map(|&r| setup.nonlinear_position(r).unwrap())
            .collect()
    };
    let elements: Vec<FrictionElement> = case
        .element
        .iter()
        .map(|e| {
            let mut c = e.clone();
            c.tangential.dofs = to_condensed(&e.tangential.dofs);
            if let Some(nrm) = c.normal.as_mut() {
                nrm.dofs = to_condensed(&nrm.dofs);
            }
            c
        })
        .collect();
    let force = DofElements::from_case(&elements, setup.nonlinear_rows.len()).unwrap();
    let layout = HarmonicLayout::new(HARMONICS, 1024).unwrap();
    let system = HbmSystem::new(layout, &setup.linear, &force).unwrap();
    let opts = ContinuationOptions::new(start, omega, 0.01);
    let frf = frequency_response(&system, &opts, &ResponseOptions::default(), &mut |_| {}).unwrap();
    assert_eq!(frf.end, PathEnd::ReachedEnd);
    let last = frf.points.last().unwrap();
    assert!((last.omega - omega).abs() < 1e-12 * omega);
    last.response.amplitude[0]
}

/// |Q1| of response DOF 0 of the march at ω, marched to steady state; also the periods it took.
fn march_amplitude(case: &Case, omega: f64) -> (f64, usize) {
    let mut cm = case_march(case, Some(MarchScheme::PiecewiseLinear), &mut |_| {}).unwrap();
    cm.settings.omega = omega;
    let out = march(&cm.system, &cm.settings).unwrap();
    let steady = out.steady_period.expect("steady state within 400 periods");
    (out.first_harmonic_amplitude()[cm.response[0]], steady)
}

fn compare(case: &Case, start: f64, omega: f64, what: &str) -> f64 {
    let hb = hb_amplitude(case, start, omega);
    let (amp, steady) = march_amplitude(case, omega);
    let rel = (amp - hb).abs() / hb;
    eprintln!(
        "{what}, ω = {omega}: march |Q1| = {amp:.6} (steady after {steady} periods), HB(H = 7) = {hb:.6}, rel {rel:.2e}"
    );
    assert!(rel < 0.01, "{what} ω {omega}: march {amp} vs HB {hb}");
    rel
}

/// the Jenkins oscillator of `docs/theory.md` (m = k = 1, c = 0.1, k_t = 1, F_s = μ n0 = 0.3, F = 0.5) at
/// ω = 0.952957, where the one-harmonic balance crosses amplitude 1.
#[test]
fn jenkins_sdof_matches_hbm() {
    let dir = tempfile::tempdir().unwrap();
    let case = matrix_case(
        dir.path(),
        1,
        &[(0, 0, 1.0)],
        &[(0, 0, 1.0)],
        "damping = { rayleigh = [0.1, 0.0] }\n\n[excitation]\ndofs = [0]\nforce = [0.5]\n\n[[element]]\nkind = \"friction\"\ntangential = { dofs = [0], weights = [1.0] }\nkt = 1.0\nmu = 1.0\nn0 = 0.3\n",
    );
    let rel = compare(&case, 0.5, 0.952957, "Jenkins SDOF");
    assert!(rel < 1e-3, "{rel}");
}

/// A two-DOF chain (K = [[2, −1], [−1, 1]], M = I, C = 0.03 M) with a Jenkins element from DOF 1 to
/// the ground (k_t = 1, F_s = μ n0 = 0.15), forced at DOF 1 (F = 0.3): the element slips through
/// most of the period near the peak (|Q1| ≈ 4.4 at ω = 0.62, the free chain's first mode 0.618; the
/// stuck chain's is 1.0). Four frequencies: below, at the peak, on its flank, above.
#[test]
fn two_dof_chain_with_friction_matches_hbm_at_four_frequencies() {
    let dir = tempfile::tempdir().unwrap();
    let case = matrix_case(
        dir.path(),
        2,
        &[(0, 0, 2.0), (1, 0, -1.0), (1, 1, 1.0)],
        &[(0, 0, 1.0), (1, 1, 1.0)],
        "damping = { rayleigh = [0.03, 0.0] }\n\n[excitation]\ndofs = [1]\nforce = [0.3]\n\n[[element]]\nkind = \"friction\"\ntangential = { dofs = [1], weights = [1.0] }\nkt = 1.0\nmu = 0.5\nn0 = 0.3\n",
    );
    for (start, omega) in [(0.45, 0.5), (0.58, 0.62), (0.75, 0.8), (1.4, 1.3)] {
        compare(&case, start, omega, "2-DOF chain");
    }
}
