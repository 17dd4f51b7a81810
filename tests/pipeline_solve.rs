//! `nlrom solve` on matrix-defined cases (`cases/chain3_jenkins.toml`: the 3-DOF chain with two
//! Jenkins elements of the harmonic-balance speed case): the written file against the library's
//! `frequency_response`, the stuck limit against a direct linear solve, sweeps in order, bad
//! input (exit 2 naming the key) and a failing continuation (exit 1, converged points written).

mod support;

use std::path::{Path, PathBuf};

use faer::linalg::solvers::Solve;
use faer::{c64, Mat};
use nlrom::case::Case;
use nlrom::contact::grounded::DofElements;
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::frf::frequency_response;
use nlrom::hbm::{HbmSystem, ResponseOptions};
use nlrom::model;
use nlrom::output::{read_results, ResponseDof, ResultsFile};
use nlrom::problem::matrix_case::matrix_setup;
use nlrom::problem::settings::case_continuation;
use support::cli::{json_report, nlrom, root, stderr};

/// `nlrom solve CASE -o OUT --json -q`: asserts exit status 0, returns the JSON report.
fn solve_json(case: &Path, out: &Path) -> serde_json::Value {
    json_report("solve", case, out, &[])
}

/// The chain of `cases/chain3_jenkins.toml` (matrices of `cases/chain3/`) with the given force,
/// μ of both elements, H, N_t and extra tables.
fn chain_case(
    dir: &Path,
    name: &str,
    force: f64,
    mu: f64,
    h: usize,
    nt: usize,
    extra: &str,
) -> PathBuf {
    let m = root().join("cases/chain3");
    let text = format!(
        r#"title = "chain {name}"
[model]
stiffness = "{k}"
mass = "{mm}"
damping = {{ rayleigh = [0.0, 0.02] }}

[excitation]
dofs = [2]
force = [{force:e}]

[response]
dofs = [0, 1, 2]

[[element]]
kind = "friction"
tangential = {{ dofs = [0], weights = [1.0] }}
kt = 1.0
mu = {mu:e}
n0 = 0.2

[[element]]
kind = "friction"
tangential = {{ dofs = [1, 2], weights = [-1.0, 1.0] }}
kt = 1.0
mu = {mu:e}
n0 = 0.2

[harmonic_balance]
harmonics = {h}
time_samples = {nt}
{extra}"#,
        k = m.join("K.mtx").display(),
        mm = m.join("M.mtx").display(),
    );
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

const RANGE: &str = "\n[continuation]\nstart_rad_s = 0.2\nend_rad_s = 2.2\nstep_rad_s = 0.02\n";

/// First-harmonic amplitudes [P][R] of curve `i` of a results file.
fn amplitudes(r: &ResultsFile, i: usize) -> Vec<Vec<f64>> {
    let f = &r.frfs[i];
    let h1 = f.harmonics + 1;
    f.points
        .iter()
        .map(|p| p.harmonics.chunks(h1).map(|h| h[1].norm()).collect())
        .collect()
}

/// The bundled case: exit 0, the file reads back, and its ω and amplitudes equal the library's
/// frequency_response on the same case to 1e-12; the JSON summary is the file's maximum.
#[test]
fn solve_chain3_equals_the_library_frequency_response() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("chain3.h5");
    let case_path = root().join("cases/chain3_jenkins.toml");
    let report = solve_json(&case_path, &out);
    let file = read_results(&out).expect("results file");
    assert_eq!(file.frfs.len(), 1);
    assert_eq!(file.info.title, "3-DOF chain, two Jenkins elements");
    let frf = &file.frfs[0];
    assert_eq!(frf.harmonics, 7);
    assert_eq!(
        frf.response_dofs,
        vec![
            ResponseDof::Row(0),
            ResponseDof::Row(1),
            ResponseDof::Row(2)
        ]
    );
    // the library, directly: no clamp, so the elements' rows are the condensed rows 0, 1, 2
    let case = Case::load(&case_path).unwrap();
    let model = model::build(&case, &mut |_| {}).unwrap();
    let setup = matrix_setup(&case, &model).unwrap();
    assert_eq!(setup.nonlinear_rows, vec![0, 1, 2]);
    let elements = DofElements::from_case(&case.element, 3).unwrap();
    let system = HbmSystem::new(
        HarmonicLayout::new(7, 1024).unwrap(),
        &setup.linear,
        &elements,
    )
    .unwrap();
    let opts = case_continuation(&case).unwrap();
    let lib = frequency_response(&system, &opts, &ResponseOptions::default(), &mut |_| {}).unwrap();
    assert_eq!(lib.points.len(), frf.points.len());
    let amp = amplitudes(&file, 0);
    let scale = amp.iter().flatten().fold(0.0_f64, |a, &b| a.max(b));
    for (p, (lp, fp)) in lib.points.iter().zip(&frf.points).enumerate() {
        assert!((lp.omega - fp.omega).abs() <= 1e-12 * lp.omega, "point {p}");
        for (r, a) in amp[p].iter().enumerate() {
            let d = (lp.response.amplitude[r] - a).abs();
            assert!(d <= 1e-12 * scale, "point {p} dof {r}: {d:e}");
            assert_eq!(lp.response.peak[r], fp.peak[r]);
        }
        assert_eq!(lp.iterations as u64, fp.newton_iterations);
    }
    // summary: the largest first-harmonic amplitude over the points and DOFs
    let (mut best, mut at) = (0.0, 0.0);
    for (p, row) in amp.iter().enumerate() {
        for &a in row {
            if a > best {
                best = a;
                at = frf.points[p].omega / (2.0 * std::f64::consts::PI);
            }
        }
    }
    let s = &report["frf"][0];
    assert_eq!(s["points"].as_u64(), Some(frf.points.len() as u64));
    // (serde_json parses floats to within an ulp, not always exactly)
    let close = |v: &serde_json::Value, x: f64| (v.as_f64().unwrap() - x).abs() <= 1e-14 * x;
    assert!(
        close(&s["peak_amplitude"], best),
        "{} vs {best}",
        s["peak_amplitude"]
    );
    assert!(
        close(&s["resonance_hz"], at),
        "{} vs {at}",
        s["resonance_hz"]
    );
    assert_eq!(s["end"], "reached_end");
    assert!(report["wall_seconds"].as_f64().is_some());
    // the traced curve's CPU time: positive, at most the process's wall time times its threads
    let cpu = s["cpu_seconds"].as_f64().unwrap();
    let wall = report["wall_seconds"].as_f64().unwrap();
    assert!(
        cpu > 0.0 && cpu <= wall * 64.0,
        "{cpu} s CPU, {wall} s wall"
    );
}

/// μ = 1e9: the elements never slip, and every point's harmonic 1 equals the direct solution
/// of (K + K_t − ω²M + iωC) X = F with the elements' springs (k_t = 1 at m1–ground and m2–m3),
/// to 1e-8 of max |X|; the higher harmonics vanish; `--stability` marks every point stable.
#[test]
fn stuck_limit_equals_the_direct_linear_frf() {
    let dir = tempfile::tempdir().unwrap();
    let case = chain_case(dir.path(), "stuck", 0.5, 1e9, 3, 64, RANGE);
    let out = dir.path().join("stuck.h5");
    let o = nlrom(&[
        "solve",
        case.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--stability",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let file = read_results(&out).unwrap();
    let frf = &file.frfs[0];
    assert!(frf.points.len() > 20);
    // a damped linear system: every point is stable (Hill's method, `--stability`)
    assert!(frf.points.iter().all(|p| p.stable == Some(true)));
    let k = [[2.0, -1.0, 0.0], [-1.0, 2.0, -1.0], [0.0, -1.0, 1.0]];
    let kt = [[1.0, 0.0, 0.0], [0.0, 1.0, -1.0], [0.0, -1.0, 1.0]];
    let mut crossed_resonance = false;
    for p in &frf.points {
        let w = p.omega;
        let d = Mat::from_fn(3, 3, |i, j| {
            let m = if i == j { 1.0 } else { 0.0 };
            c64::new(k[i][j] + kt[i][j] - w * w * m, w * 0.02 * k[i][j])
        });
        let mut f = Mat::<c64>::zeros(3, 1);
        f[(2, 0)] = c64::new(0.5, 0.0);
        let x = d.partial_piv_lu().solve(&f);
        let scale = (0..3).map(|i| x[(i, 0)].norm()).fold(0.0, f64::max);
        for r in 0..3 {
            let h = &p.harmonics[r * 4..r * 4 + 4];
            assert!((h[1] - x[(r, 0)]).norm() <= 1e-8 * scale, "ω {w} dof {r}");
            assert!(h[2].norm() + h[3].norm() <= 1e-8 * scale, "ω {w} dof {r}");
        }
        crossed_resonance |= scale > 10.0;
    }
    assert!(
        crossed_resonance,
        "the range holds a resonance of the stuck system"
    );
}

/// `[sweep] "element.1.n0" = [0.1, 0.2, 0.4]`: three groups /frf/0..2 in sweep order, each with
/// its value as attribute and equal to the case solved alone with that value.
#[test]
fn a_sweep_gives_one_group_per_value_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let values = [0.1, 0.2, 0.4];
    let sweep = format!("{RANGE}\n[sweep]\n\"element.1.n0\" = [0.1, 0.2, 0.4]\n");
    let case = chain_case(dir.path(), "sweep", 0.5, 1.0, 3, 128, &sweep);
    let out = dir.path().join("sweep.h5");
    let report = solve_json(&case, &out);
    let file = read_results(&out).unwrap();
    assert_eq!(file.frfs.len(), 3);
    for (i, v) in values.iter().enumerate() {
        assert_eq!(file.frfs[i].sweep.get("element.1.n0"), Some(v));
        assert_eq!(report["frf"][i]["sweep_point"].as_u64(), Some(i as u64));
        assert_eq!(
            report["frf"][i]["params"]["element.1.n0"].as_f64(),
            Some(*v)
        );
        // the same case with n0 = v and no sweep
        let text = std::fs::read_to_string(&case).unwrap();
        let text = text.split("\n[sweep]").next().unwrap().replacen(
            "kt = 1.0\nmu = 1e0\nn0 = 0.2\n\n[harmonic_balance]",
            &format!("kt = 1.0\nmu = 1e0\nn0 = {v}\n\n[harmonic_balance]"),
            1,
        );
        let single = dir.path().join(format!("single{i}.toml"));
        std::fs::write(&single, text).unwrap();
        let single_out = dir.path().join(format!("single{i}.h5"));
        solve_json(&single, &single_out);
        let alone = read_results(&single_out).unwrap();
        assert_eq!(
            alone.frfs[0].points.len(),
            file.frfs[i].points.len(),
            "sweep {i}"
        );
        assert_eq!(amplitudes(&alone, 0), amplitudes(&file, i), "sweep {i}");
    }
    // the curves differ (the slip force of element 1 changes the response)
    assert_ne!(amplitudes(&file, 0).len(), 0);
    assert_ne!(
        report["frf"][0]["peak_amplitude"],
        report["frf"][2]["peak_amplitude"]
    );
}

/// Bad input: exit status 2, the key named, no results file.
#[test]
fn bad_input_exits_2_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let crossing = RANGE.replace("start_rad_s = 0.2", "start_rad_s = -0.5");
    let cases = [
        (
            "crossing_zero",
            0.5,
            3,
            crossing.as_str(),
            "continuation.start_rad_s",
        ),
        ("no_harmonics", 0.5, 0, RANGE, "harmonic_balance.harmonics"),
        ("no_continuation", 0.5, 3, "", "continuation"),
    ];
    for (name, force, h, extra, key) in cases {
        let case = chain_case(dir.path(), name, force, 1.0, h, 64, extra);
        let out = dir.path().join(format!("{name}.h5"));
        let o = nlrom(&["solve", case.to_str().unwrap(), "-o", out.to_str().unwrap()]);
        assert_eq!(o.status.code(), Some(2), "{name}: {}", stderr(&o));
        let err = stderr(&o);
        assert!(
            err.contains(key) && err.contains(&format!("{name}.toml")),
            "{name}: {err}"
        );
        assert!(!out.exists(), "{name}: no results file on bad input");
    }
}

/// A continuation that cannot converge (at most 2 Newton iterations per point and a fixed step:
/// the stuck points converge, the first slipping one cannot) and may not jump
/// (`max_jumps = 0`; with jumps the sweep goes on beyond that corner): exit 1, a message saying
/// where it stopped, and the file holds the converged points, all below the failure frequency.
#[test]
fn a_failed_continuation_exits_1_with_the_converged_points_written() {
    let dir = tempfile::tempdir().unwrap();
    let settings = "\n[continuation]\nstart_rad_s = 0.2\nend_rad_s = 2.2\nstep_rad_s = 0.02\nmin_step_rad_s = 0.02\nmax_step_rad_s = 0.02\nmax_iterations = 2\nmax_jumps = 0\n";
    let case = chain_case(dir.path(), "diverging", 0.1, 1.0, 3, 64, settings);
    let out = dir.path().join("diverging.h5");
    let o = nlrom(&[
        "solve",
        case.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--json",
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", stderr(&o));
    let err = stderr(&o);
    assert!(
        err.contains("continuation failed after") && err.contains("diverging.h5"),
        "{err}"
    );
    let report: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(report["frf"][0]["end"], "failed");
    let file = read_results(&out).expect("the partial file is written");
    let p = file.frfs[0].points.len();
    assert!(p > 1, "{p} points");
    assert_eq!(report["frf"][0]["points"].as_u64(), Some(p as u64));
    let last = file.frfs[0].points.last().unwrap().omega;
    assert!(last < 2.2, "stopped before the end: {last}");
    assert!(file.frfs[0].points.iter().all(|q| q.newton_iterations <= 2));
}
