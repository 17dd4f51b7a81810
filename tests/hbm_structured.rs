//! The structured linear solve of Newton steps and continuation tangents
//! (`nlrom::nonlinear::linsolve`: LU factors of the harmonic blocks of the harmonic balance
//! Jacobian and an exact Woodbury correction for the contact elements that couple harmonics)
//! against the dense LU, on whole continuations: the same points, the same Newton iterations
//! per point and the same solutions, on
//! - the two oscillators with friction and contact separation (both folds of the separation
//!   resonance, where the determinant sign orients the tangent; H = 5, 256 samples, 22 unknowns),
//! - the paper's shrouded sector (mode M1, SAMA interpolated coupling, coarse target face) at
//!   n0 = 50 N in microslip, H = 2, where some pairs stick only part of the period.
//!
//! The structured path is forced (`SolverChoice::Structured`); the automatic choice would take
//! the dense LU at these sizes. With it, the Newton steps after the first of each corrector are
//! solved by GMRES on the last factors (`LinearSolver::solve_krylov`), so these comparisons check
//! the Krylov steps against the dense LU as well.

mod support;

use std::path::Path;
use std::sync::Mutex;

use nlrom::case::Case;
use nlrom::continuation::{trace, ContinuationOptions, Path as CurvePath, PathEnd};
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::{FrequencyPath, HbmSystem};
use nlrom::interface::build_interfaces;
use nlrom::nonlinear::linsolve::{stats, SolverStats};
use nlrom::nonlinear::{norm, ParameterSystem, SolverChoice};
use nlrom::problem::sector::SectorProblem;
use nlrom::problem::settings::case_continuation;
use nlrom::reduction::reduce;
use nlrom::{model, Result};
use support::hbm::{tangential_normal_element, two_oscillators};

/// The solve counts are per process: the tests of this file run one at a time.
static SERIAL: Mutex<()> = Mutex::new(());

/// The counts between two snapshots.
fn delta(a: SolverStats, b: SolverStats) -> SolverStats {
    SolverStats {
        dense: b.dense - a.dense,
        structured: b.structured - a.structured,
        fallbacks: b.fallbacks - a.fallbacks,
        rank_sum: b.rank_sum - a.rank_sum,
        size_sum: b.size_sum - a.size_sum,
        factorizations: b.factorizations - a.factorizations,
        krylov: b.krylov - a.krylov,
        krylov_iterations: b.krylov_iterations - a.krylov_iterations,
    }
}

/// Traces `fp` with `opts` once per linear solver; the solve counts of each run.
#[allow(clippy::type_complexity)]
fn both<S: ParameterSystem>(
    fp: &S,
    opts: &ContinuationOptions,
) -> Result<(
    (CurvePath<S::State>, SolverStats),
    (CurvePath<S::State>, SolverStats),
)> {
    let mut o = opts.clone();
    o.newton.linear_solver = SolverChoice::Dense;
    let s0 = stats();
    let dense = trace(fp, &o, &mut |_| {})?;
    let s1 = stats();
    o.newton.linear_solver = SolverChoice::Structured;
    let structured = trace(fp, &o, &mut |_| {})?;
    let s2 = stats();
    Ok(((dense, delta(s0, s1)), (structured, delta(s1, s2))))
}

/// Largest relative difference ‖x_s − x_d‖ / ‖x_d‖ (and of the parameter) over the points;
/// asserts the same number of points, the same end and the same iterations per point.
fn compare<T>(dense: &CurvePath<T>, structured: &CurvePath<T>) -> f64 {
    assert_eq!(dense.end, structured.end);
    assert_eq!(dense.points.len(), structured.points.len());
    let mut worst = 0.0_f64;
    for (d, s) in dense.points.iter().zip(&structured.points) {
        assert_eq!(d.iterations, s.iterations, "at ω = {}", d.parameter);
        let dx: Vec<f64> = d.x.iter().zip(&s.x).map(|(a, b)| a - b).collect();
        let rel = norm(&dx) / norm(&d.x);
        let rel_p = (d.parameter - s.parameter).abs() / d.parameter.abs();
        worst = worst.max(rel).max(rel_p);
    }
    worst
}

/// Separation resonance with both folds (the case of `continuation_separation`): the paths agree
/// point by point to 1e-8 relative, the Newton tolerance (measured 7e-9: the Krylov steps are
/// solved to a backward error of 1e-12, not to rounding, and the difference is carried along 638
/// points), with the same folds passed, so the same tangent orientations; the structured run
/// never fell back to the dense LU, its correction had positive rank (the element separates
/// within the period, coupling the harmonics), and it factorised less often than the dense run
/// (the other steps and most tangents by GMRES on earlier factors, the tangents' orientation
/// from the GMRES Hessenberg matrix: 16 factorisations against 1 313 measured).
#[test]
fn separation_folds_are_the_same_with_the_structured_solve() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let h = 5;
    let lin = two_oscillators(0.1, [0.05, 0.015], h);
    let force = tangential_normal_element(0.2).unwrap();
    let layout = HarmonicLayout::new(h, 256).unwrap();
    let system = HbmSystem::new(layout, &lin, &force).unwrap();
    let fp = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    assert_eq!(fp.jacobian_blocks(), vec![2, 4, 4, 4, 4, 4]);
    let mut opts = ContinuationOptions::new(1.3, 2.2, 0.005);
    opts.max_step = Some(0.005);
    opts.max_points = 3000;
    let ((dense, sd), (structured, ss)) = both(&fp, &opts).unwrap();
    assert_eq!(dense.end, PathEnd::ReachedEnd);
    let folds = dense
        .points
        .windows(2)
        .filter(|w| w[0].tangent_parameter * w[1].tangent_parameter < 0.0)
        .count();
    let worst = compare(&dense, &structured);
    eprintln!(
        "{} points, {folds} folds; worst relative difference {worst:.2e}; dense {sd:?}; structured {ss:?}",
        dense.points.len()
    );
    assert!(folds >= 2, "{folds}");
    assert!(worst <= 1e-8, "{worst:e}");
    assert_eq!((sd.structured, sd.krylov), (0, 0));
    assert_eq!((ss.dense, ss.fallbacks), (0, 0), "{ss:?}");
    assert!(ss.structured > 0, "{ss:?}");
    // most corrector steps and tangents after the first reuse the factors by GMRES: at least
    // 20 times fewer factorisations than the dense run (measured 16 against 1 313)
    assert!(
        ss.krylov > 100 && 20 * ss.factorizations <= sd.factorizations,
        "{ss:?} {sd:?}"
    );
    // the bordered systems alone give rank 2; the separating element adds to it
    assert!(ss.rank_sum > 2 * ss.structured, "{ss:?}");
}

/// The SAMA sector in microslip (interpolated coupling): 6 continuation points from 774 Hz, the
/// same to 1e-8 relative (measured 2e-9) with a correction of positive rank and fewer
/// factorisations than the dense run; and the residual alone of a damping trial (no condensed
/// matrix) equal to the full evaluation's.
#[test]
fn sector_microslip_is_the_same_with_the_structured_solve() {
    let _serial = SERIAL.lock().unwrap_or_else(|e| e.into_inner());
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/paper/m1_nonconforming.toml");
    let mut case = Case::load(&path).unwrap();
    case.harmonic_balance.harmonics = 2;
    case.contact.iter_mut().for_each(|c| c.n0 = 50.0);
    case.continuation.as_mut().unwrap().start = 774.0;
    let sm = model::build(&case, &mut |_| {}).unwrap();
    let rom = reduce(&case, &sm, &mut |_| {}).unwrap();
    let mesh = sm.mesh.as_ref().unwrap();
    let interfaces = build_interfaces(&case, mesh, rom.cyclic.as_ref()).unwrap();
    let problem = SectorProblem::build(&case, &rom, mesh, &interfaces).unwrap();
    let system = problem.system().unwrap();
    let fp = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let mut opts = case_continuation(&case).unwrap();
    opts.max_points = 6;
    let ((dense, sd), (structured, ss)) = both(&fp, &opts).unwrap();
    let worst = compare(&dense, &structured);
    let last = dense.points.last().unwrap();
    let reports = problem
        .contact
        .inner
        .reports(
            &problem.layout,
            &last.x,
            &dense.points[dense.points.len() - 2].state,
            false,
        )
        .unwrap();
    let mixed = reports
        .iter()
        .filter(|(r, _)| r.stick > 0.0 && r.stick < 1.0)
        .count();
    eprintln!(
        "{} unknowns, {} points, {mixed} of {} pairs stick part of the period; worst relative difference {worst:.2e}; structured {ss:?}",
        system.dim(),
        dense.points.len(),
        reports.len(),
    );
    assert_eq!(dense.points.len(), 6);
    assert!(mixed > 0);
    assert!(worst <= 1e-8, "{worst:e}");
    assert_eq!((ss.dense, ss.fallbacks), (0, 0), "{ss:?}");
    assert!(ss.rank_sum > 2 * ss.structured, "{ss:?}");
    assert!(
        ss.krylov > 0 && ss.factorizations < sd.factorizations,
        "{ss:?} {sd:?}"
    );
    // a damping trial's residual alone (no condensed matrix) is the full evaluation's residual,
    // away from the path (1 Hz above the last point), to 1e-8 relative (measured 2e-9: the two
    // forms round differently, against linear terms of k = 1e8 N/m times the displacements that
    // cancel to the residual)
    let omega = last.parameter + 2.0 * std::f64::consts::PI;
    let mut lin = nlrom::nonlinear::Linearization::zeros(fp.dim());
    fp.evaluate(&last.x, omega, &last.state, &mut lin).unwrap();
    let mut alone = vec![0.0; fp.dim()];
    fp.evaluate_residual(&last.x, omega, &last.state, &mut alone)
        .unwrap();
    let diff: Vec<f64> = alone
        .iter()
        .zip(&lin.residual)
        .map(|(a, b)| a - b)
        .collect();
    let rel = norm(&diff) / norm(&lin.residual);
    eprintln!("residual alone against the full evaluation: {rel:.1e}");
    assert!(rel <= 1e-8, "{rel:e}");
}
