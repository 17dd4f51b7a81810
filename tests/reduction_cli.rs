//! `nlrom modes --stage cb|cs|gsi [--harmonic K] --json` on the bundled N = 8 cyclic case
//! (`cases/sector8_cs.toml`): the JSON keys of `docs/user-guide.md`, consistency between the stages, and exit
//! status 2 with a message for bad input.

mod support;

use support::cli::nlrom;

use serde_json::Value;

fn modes_json(args: &[&str]) -> Value {
    let mut all = vec!["modes", "cases/sector8_cs.toml", "--json"];
    all.extend_from_slice(args);
    let out = nlrom(&all);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("one JSON object")
}

fn freqs(v: &Value) -> Vec<f64> {
    v["frequencies_hz"]
        .as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_f64().unwrap())
        .collect()
}

fn max_rel(a: &[f64], b: &[f64]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (x / y - 1.0).abs())
        .fold(0.0, f64::max)
}

#[test]
fn modes_stages_report_consistent_frequencies() {
    let full = modes_json(&["--stage", "full", "--num", "5"]);
    let cb = modes_json(&["--stage", "cb", "--num", "5"]);
    assert_eq!(cb["stage"], "cb");
    assert!(cb["harmonic"].is_null());
    assert!(cb["wall_seconds"].as_f64().is_some());
    let dofs = cb["dofs"].as_u64().unwrap();
    assert!(
        dofs > 30 && dofs < full["dofs"].as_u64().unwrap() / 4,
        "{dofs}"
    );
    // CB frequencies are upper bounds, close to the full model's (sector without cyclic
    // constraint: both frontiers free).
    let (f_full, f_cb) = (freqs(&full), freqs(&cb));
    for (a, b) in f_cb.iter().zip(&f_full) {
        assert!(*a >= b * (1.0 - 1e-9) && *a <= b * 1.01, "{a} vs {b}");
    }
    assert!(cb["residuals"]
        .as_array()
        .unwrap()
        .iter()
        .all(|r| r.as_f64().unwrap() < 1e-8));

    let cs2 = modes_json(&["--stage", "cs", "--harmonic", "2", "--num", "12"]);
    let cs6 = modes_json(&["--stage", "cs", "--harmonic", "6", "--num", "12"]);
    assert_eq!(
        (cs2["stage"].as_str(), cs2["harmonic"].as_u64()),
        (Some("cs"), Some(2))
    );
    assert!(cs2["dofs"].as_u64().unwrap() < dofs);
    assert!(max_rel(&freqs(&cs2), &freqs(&cs6)) < 1e-9, "k and N − k");

    // GSI with gsi_modes = 10: the first 10 frequencies are those of the CB+CS model.
    let gsi = modes_json(&["--stage", "gsi", "--harmonic", "2", "--num", "12"]);
    assert_eq!(gsi["stage"], "gsi");
    assert_eq!(gsi["gsi"]["modes_used"], 10);
    assert_eq!(gsi["gsi"]["retained"], 10);
    assert!(gsi["dofs"].as_u64().unwrap() < cs2["dofs"].as_u64().unwrap());
    let (fg, fc) = (freqs(&gsi), freqs(&cs2));
    assert!(max_rel(&fg[..10], &fc[..10]) < 1e-9);
}

#[test]
fn bad_stage_input_exits_2_with_a_message() {
    let cases: [(&[&str], &str); 4] = [
        (
            &[
                "modes",
                "cases/sector8_cs.toml",
                "--stage",
                "cs",
                "--harmonic",
                "8",
            ],
            "k = 8",
        ),
        (
            &["modes", "cases/sector8_cs.toml", "--stage", "cs"],
            "--harmonic",
        ),
        (
            &[
                "modes",
                "cases/sector_modes.toml",
                "--stage",
                "cs",
                "--harmonic",
                "1",
            ],
            "[cyclic]",
        ),
        (
            &["modes", "cases/sector_modes.toml", "--stage", "cb"],
            "[reduction]",
        ),
    ];
    for (args, expected) in cases {
        let out = nlrom(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{args:?}: {err}");
        assert!(err.contains(expected), "{args:?}: {err}");
    }
}
