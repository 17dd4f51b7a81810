//! The demo sector with normal load variation (`kn = 1e8`) over 880–960 Hz, at 1 N and at
//! 50 N: the frequency responses must reach their end. At 50 N the shroud pairs shake down (a
//! slider that slips one way and then sticks) and the excitation-level start passes several
//! sharp folds; this is the case whose start failed while the contact force depended on the
//! slider state carried from point to point. The 50 N curve takes a few minutes.

mod support;

use support::cli::{json_report, root};

/// `cases/demo.toml` with `kn = 1e8`, the axial force `force` (N) and 880–960 Hz.
fn case_text(force: f64) -> String {
    let demo = std::fs::read_to_string(root().join("cases/demo.toml")).unwrap();
    let mesh = root().join("meshes/sector8.msh");
    let replaced = demo
        .replace(
            "mesh = \"../meshes/sector8.msh\"",
            &format!("mesh = {:?}", mesh.to_str().unwrap()),
        )
        .replace("kn = 0.0", "kn = 1.0e8")
        .replace(
            "force = [0.0, 0.0, 1.0]",
            &format!("force = [0.0, 0.0, {force:.1}]"),
        )
        .replace("start_hz = 150.0", "start_hz = 880.0")
        .replace("end_hz = 175.0", "end_hz = 960.0");
    for key in ["kn = 1.0e8", "start_hz = 880.0", "end_hz = 960.0"] {
        assert!(
            replaced.contains(key),
            "cases/demo.toml changed: {key} not set"
        );
    }
    replaced
}

#[test]
fn demo_with_normal_load_variation_reaches_the_end_at_1_and_50_newton() {
    let dir = tempfile::tempdir().unwrap();
    for force in [1.0, 50.0] {
        let case = dir.path().join(format!("demo_kn_{force}.toml"));
        std::fs::write(&case, case_text(force)).unwrap();
        let out = dir.path().join(format!("demo_kn_{force}.h5"));
        let report = json_report("run", &case, &out, &[]);
        let frf = &report["frf"][0];
        assert_eq!(frf["end"], "reached_end", "{force} N: {frf}");
        assert!(frf["points"].as_u64().unwrap() >= 10, "{force} N: {frf}");
    }
}
