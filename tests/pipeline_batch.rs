//! `nlrom batch`: three small matrix cases and a broken one (the broken one fails alone, with
//! its message; the others are written and agree with `nlrom solve`; exit status 1;
//! summary.csv), and meshes run with a template case (sharing one ROM).

mod support;

use std::path::{Path, PathBuf};

use nlrom::output::read_results;
use serde_json::Value;
use support::batch::{chain_case, summary_rows};
use support::cli::{nlrom, root};

/// The chain of `cases/chain3_jenkins.toml` with H = 3, N_t = 64 and slip force n0 of element 1;
/// `harmonics` replaces H (0 makes the case invalid).
fn chain(dir: &Path, name: &str, n0: f64, harmonics: usize) -> PathBuf {
    let h = format!("harmonics = {harmonics}");
    chain_case(
        dir,
        name,
        n0,
        &[
            ("harmonics = 7", &h),
            ("time_samples = 1024", "time_samples = 64"),
        ],
    )
}

#[test]
fn a_broken_case_fails_alone() {
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<PathBuf> = [
        ("a", 0.1, 3),
        ("b", 0.2, 3),
        ("broken", 0.2, 0),
        ("c", 0.3, 3),
    ]
    .iter()
    .map(|&(name, n0, h)| chain(dir.path(), name, n0, h))
    .collect();
    let out = dir.path().join("out");
    let mut args = vec![
        "batch",
        "--jobs",
        "2",
        "--out",
        out.to_str().unwrap(),
        "--json",
    ];
    args.extend(cases.iter().map(|c| c.to_str().unwrap()));
    let o = nlrom(&args);
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("1 of 4 jobs failed (broken)"), "{err}");
    let report: Value = serde_json::from_slice(&o.stdout).unwrap();
    let jobs = report["jobs"].as_array().unwrap();
    let status: Vec<&str> = jobs.iter().map(|j| j["status"].as_str().unwrap()).collect();
    assert_eq!(status, ["ok", "ok", "failed", "ok"]);
    let message = jobs[2]["error"].as_str().unwrap();
    assert!(
        message.contains("harmonic_balance.harmonics") && message.contains("broken.toml"),
        "{message}"
    );
    assert!(!out.join("broken.h5").exists());
    let rows = summary_rows(&out.join("summary.csv"));
    assert_eq!(rows.len(), 4);
    for (i, name) in ["a", "b", "broken", "c"].iter().enumerate() {
        assert_eq!(rows[i][0], *name);
        assert_eq!(rows[i][3], status[i]);
    }
    assert!(rows[2][10].contains("harmonic_balance.harmonics"));
    // every written case equals `nlrom solve` of the same case
    for (i, name) in ["a", "b", "c"].iter().enumerate() {
        let case = &cases[if i == 2 { 3 } else { i }];
        let single = dir.path().join(format!("{name}_single.h5"));
        let s = nlrom(&[
            "solve",
            case.to_str().unwrap(),
            "-o",
            single.to_str().unwrap(),
            "--json",
            "-q",
        ]);
        assert_eq!(s.status.code(), Some(0));
        let alone: Value = serde_json::from_slice(&s.stdout).unwrap();
        let row = &rows[if i == 2 { 3 } else { i }];
        let resonance: f64 = row[4].parse().unwrap();
        let expected = alone["frf"][0]["resonance_hz"].as_f64().unwrap();
        assert!(
            (resonance - expected).abs() <= 1e-14 * expected,
            "{name}: {resonance} vs {expected}"
        );
        let a = read_results(&out.join(format!("{name}.h5"))).unwrap();
        let b = read_results(&single).unwrap();
        assert_eq!(a.frfs[0].points, b.frfs[0].points, "{name}");
    }
    // the slip force changes the response: three different peaks
    let peaks: Vec<&str> = [0, 1, 3].iter().map(|&i| rows[i][5].as_str()).collect();
    assert!(peaks[0] != peaks[1] && peaks[1] != peaks[2], "{peaks:?}");
}

/// Meshes with a template case: one results file per mesh (two copies of the same mesh give the
/// same response); a mesh without `--case` fails with advice.
#[test]
fn meshes_run_with_a_template_case() {
    let dir = tempfile::tempdir().unwrap();
    let template = dir.path().join("template.toml");
    let text = std::fs::read_to_string(root().join("cases/demo.toml"))
        .unwrap()
        .replace("../meshes/", &format!("{}/meshes/", root().display()))
        .replace("end_hz = 175.0", "end_hz = 160.0")
        .replace("step_hz = 2.0", "step_hz = 5.0");
    std::fs::write(&template, text).unwrap();
    let copy = dir.path().join("copy.msh");
    std::fs::copy(root().join("meshes/sector8.msh"), &copy).unwrap();
    let out = dir.path().join("out");
    let o = nlrom(&[
        "batch",
        "meshes/sector8.msh",
        copy.to_str().unwrap(),
        "--case",
        template.to_str().unwrap(),
        "--out",
        out.to_str().unwrap(),
        "--jobs",
        "2",
        "-q",
    ]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let table = String::from_utf8_lossy(&o.stdout);
    assert!(
        table.contains("sector8") && table.contains("copy"),
        "{table}"
    );
    let a = read_results(&out.join("sector8.h5")).unwrap();
    let b = read_results(&out.join("copy.h5")).unwrap();
    assert!(!a.frfs[0].points.is_empty());
    assert_eq!(a.frfs[0].points, b.frfs[0].points);
    // the two meshes have the same bytes: one ROM in the content-addressed cache
    let roms: Vec<_> = std::fs::read_dir(out.join("rom-cache"))
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(roms.len(), 1, "{roms:?}");
    let o = nlrom(&[
        "batch",
        "meshes/sector8.msh",
        "--out",
        out.to_str().unwrap(),
        "-q",
    ]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stdout).contains("--case TEMPLATE.toml"));
}
