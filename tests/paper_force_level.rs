//! The paper case `cases/paper/m1_conforming.toml` (preload n0 = 113 N) with the excitation
//! raised from 0.2 N to 5 N, as a force sweep would: at 760 Hz the shroud slips over most of the
//! period, Newton from the linear (stuck) solution misses the start point, and the start is
//! reached by continuation in the excitation level. The curve must then go on to its end with
//! every accepted point within the Newton tolerance.

mod support;

use support::cli::{json_report, root};

/// `cases/paper/m1_conforming.toml` at one preload (113 N), force `force` (N), 760–764 Hz.
fn case_text(force: f64, out: &std::path::Path) -> String {
    let paper = std::fs::read_to_string(root().join("cases/paper/m1_conforming.toml")).unwrap();
    let mesh = root().join("meshes/sector_conforming.msh");
    let mut text = String::new();
    let mut in_sweep = false;
    for line in paper.lines() {
        if line.starts_with('[') {
            in_sweep = line == "[sweep]";
        }
        if in_sweep {
            continue;
        }
        let line = match line {
            l if l.starts_with("mesh = ") => format!("mesh = {:?}", mesh.to_str().unwrap()),
            l if l.starts_with("force = ") => format!("force = [0.0, 0.0, {force:.1}]"),
            l if l.starts_with("end_hz = ") => "end_hz = 764.0".to_string(),
            l if l.starts_with("file = ") => format!("file = {:?}", out.to_str().unwrap()),
            l => l.to_string(),
        };
        text.push_str(&line);
        text.push('\n');
    }
    for key in [
        "force = [0.0, 0.0, ",
        "start_hz = 760.0",
        "end_hz = 764.0",
        "n0 = 113.0",
    ] {
        assert!(
            text.contains(key),
            "cases/paper/m1_conforming.toml changed: {key} not found"
        );
    }
    text
}

#[test]
fn paper_case_at_5_newton_starts_and_reaches_the_end() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("m1_5n.h5");
    let case = dir.path().join("m1_5n.toml");
    std::fs::write(&case, case_text(5.0, &out)).unwrap();
    let report = json_report("solve", &case, &out, &[]);
    let frf = &report["frf"][0];
    assert_eq!(frf["end"], "reached_end", "{frf}");
    assert!(frf["points"].as_u64().unwrap() >= 3, "{frf}");
    let results = nlrom::output::results::read_results(&out).unwrap();
    let points = &results.frfs[0].points;
    let hz: Vec<f64> = points
        .iter()
        .map(|p| p.omega / std::f64::consts::TAU)
        .collect();
    assert!(
        (hz[0] - 760.0).abs() < 1e-9 && (hz[hz.len() - 1] - 764.0).abs() < 1e-9,
        "{hz:?}"
    );
    let worst = points.iter().map(|p| p.residual).fold(0.0, f64::max);
    assert!(
        worst <= 1e-8,
        "an accepted point has the scaled residual {worst:.2e}"
    );
}
