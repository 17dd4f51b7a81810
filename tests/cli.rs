//! The `nlrom` binary: `mesh info` output and exit statuses (`docs/user-guide.md`).

mod support;

use support::cli::nlrom;

use std::path::Path;

#[test]
fn mesh_info_json_has_the_contract_keys() {
    let out = nlrom(&[
        "mesh",
        "info",
        "meshes/formats/sector_conforming.v41-binary.msh",
        "--json",
    ]);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value =
        serde_json::from_slice(&out.stdout).expect("one JSON object on stdout");
    assert_eq!(v["format"], "4.1");
    assert_eq!(v["binary"], true);
    assert_eq!(v["nodes"], 3914);
    assert_eq!(v["elements"]["tetra10"], 1878);
    let hub = v["groups"]
        .as_array()
        .expect("groups")
        .iter()
        .find(|g| g["name"] == "hub")
        .expect("hub");
    assert_eq!(
        (
            hub["dim"].as_u64(),
            hub["elements"].as_u64(),
            hub["nodes"].as_u64()
        ),
        (Some(2), Some(14), Some(37))
    );
    assert_eq!(v["bbox"][1][0], 0.26);
    assert!(v["wall_seconds"].as_f64().is_some());
}

#[test]
fn mesh_info_text_lists_groups() {
    let out = nlrom(&["mesh", "info", "meshes/formats/bar_hex20.v22-ascii.msh"]);
    assert_eq!(out.status.code(), Some(0));
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("MSH 2.2 ASCII") && text.contains("hexa20") && text.contains("clamp"),
        "{text}"
    );
}

#[test]
fn bad_input_exits_2_with_the_file_and_line() {
    let out = nlrom(&["mesh", "info", "tests/data/broken/trailing_token.msh"]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("trailing_token.msh: line 10") && err.contains("$Elements"),
        "{err}"
    );
    assert!(out.stdout.is_empty());
    let out = nlrom(&["mesh", "info", "no/such.msh"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no/such.msh"));
}

#[test]
fn every_command_has_help_and_a_missing_case_is_bad_input() {
    for cmd in [
        "modes", "export", "reduce", "contact", "solve", "march", "run", "batch", "demo", "mesh",
    ] {
        let out = nlrom(&[cmd, "--help"]);
        assert_eq!(out.status.code(), Some(0), "{cmd} --help");
        assert!(!out.stdout.is_empty());
    }
    assert!(Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("meshes/sector_conforming.msh")
        .exists());
    let out = nlrom(&["modes", "no/such/case.toml", "--stage", "cb"]);
    assert_eq!(
        out.status.code(),
        Some(2),
        "a missing case file is bad input"
    );
    for cmd in ["solve", "run", "reduce"] {
        let out = nlrom(&[cmd, "no/such/case.toml", "-o", "r.h5"]);
        assert_eq!(
            out.status.code(),
            Some(2),
            "{cmd}: a missing case is bad input"
        );
        assert!(String::from_utf8_lossy(&out.stderr).contains("no/such/case.toml"));
        assert!(!Path::new(env!("CARGO_MANIFEST_DIR")).join("r.h5").exists());
    }
}

/// A case for the bundled tetra10 cube (clamped at the bottom unless `clamp` is empty).
fn cube_case(dir: &Path, clamp: &str) -> std::path::PathBuf {
    let mesh = Path::new(env!("CARGO_MANIFEST_DIR")).join("meshes/cube_tet10.msh");
    let case = dir.join("cube.toml");
    let text = format!(
        "title = \"cube\"\n[model]\nmesh = \"{}\"\nmaterial = {{ young = 210e9, poisson = 0.3, density = 7800.0 }}\nclamp = [{clamp}]\n",
        mesh.display()
    );
    std::fs::write(&case, text).expect("case");
    case
}

/// Runs nlrom, asserts exit status 0 (showing stderr otherwise) and returns stdout.
fn run_ok(args: &[&str]) -> Vec<u8> {
    let out = nlrom(args);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    out.stdout
}

/// `nlrom modes CASE --json` with `extra` arguments: the JSON report.
fn modes_json(case: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec!["modes", case.to_str().expect("utf8"), "--json"];
    args.extend_from_slice(extra);
    serde_json::from_slice(&run_ok(&args)).expect("one JSON object on stdout")
}

/// A list of numbers from a JSON report.
fn numbers(v: &serde_json::Value) -> Vec<f64> {
    v.as_array()
        .expect("list")
        .iter()
        .map(|x| x.as_f64().expect("number"))
        .collect()
}

#[test]
fn modes_and_export_agree() {
    let dir = tempfile::tempdir().expect("tempdir");
    let case = cube_case(dir.path(), "\"bottom\"");
    let v = modes_json(&case, &["--num", "6"]);
    assert_eq!(v["stage"], "full");
    let freqs = numbers(&v["frequencies_hz"]);
    assert_eq!(freqs.len(), 6);
    assert!(numbers(&v["residuals"]).iter().all(|&r| r < 1e-8));

    let export = dir.path().join("export");
    run_ok(&[
        "export",
        case.to_str().expect("utf8"),
        "--dir",
        export.to_str().expect("utf8"),
    ]);
    let k = nlrom::matrix_io::read_real_matrix(&export.join("K.mtx")).expect("K");
    let m = nlrom::matrix_io::read_real_matrix(&export.join("M.mtx")).expect("M");
    let dofs = nlrom::matrix_io::read_dof_map(&export.join("dofs.csv")).expect("dofs");
    assert_eq!(k.nrows(), v["dofs"].as_u64().expect("dofs") as usize);
    assert_eq!(dofs.len(), k.nrows());
    let modes =
        nlrom::eigen::lowest_modes(k.as_ref(), m.as_ref(), 6, &Default::default()).expect("modes");
    for (a, b) in modes.frequencies_hz().iter().zip(&freqs) {
        assert!((a / b - 1.0).abs() < 1e-10, "{a} vs {b}");
    }
    // The exported matrices define a matrix-only case that gives the same frequencies again.
    let matrix_case = dir.path().join("matrices.toml");
    std::fs::write(
        &matrix_case,
        "[model]\nstiffness = \"export/K.mtx\"\nmass = \"export/M.mtx\"\n",
    )
    .expect("case");
    let again = numbers(&modes_json(&matrix_case, &["--num", "6"])["frequencies_hz"]);
    for (a, b) in again.iter().zip(&freqs) {
        assert!((a / b - 1.0).abs() < 1e-10, "{a} vs {b}");
    }
}

#[test]
fn free_free_without_shift_is_refused_with_advice() {
    let dir = tempfile::tempdir().expect("tempdir");
    let case = cube_case(dir.path(), "");
    let out = nlrom(&["modes", case.to_str().expect("utf8"), "--num", "8"]);
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("--shift-hz"), "{err}");
    let f = numbers(&modes_json(&case, &["--num", "8", "--shift-hz", "100"])["frequencies_hz"]);
    assert!(f[5] < 1e-4 * f[6], "{f:?}");
}

#[test]
fn bad_case_exits_2_naming_the_key() {
    let dir = tempfile::tempdir().expect("tempdir");
    let case = cube_case(dir.path(), "\"bottom\"");
    let text = std::fs::read_to_string(&case)
        .expect("read")
        .replace("poisson = 0.3", "poisson = 0.5");
    std::fs::write(&case, text).expect("write");
    let out = nlrom(&["modes", case.to_str().expect("utf8")]);
    assert_eq!(out.status.code(), Some(2));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("cube.toml") && err.contains("model.material"),
        "{err}"
    );
}
