//! A results file written by `nlrom solve` read in Python with h5py only — the
//! documented datasets exist with the documented shapes and units (`docs/results-file.md`), and the FRF peak computed in Python by `tools/post/plot_frf.py`
//! from the file equals the summary `nlrom solve --json` printed.

mod support;

use std::path::Path;
use std::process::Command;

use support::python::run_python;

/// Runs `nlrom ARGS` and returns its stdout (panics with stderr on failure).
fn nlrom(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_nlrom"))
        .current_dir(env!("CARGO_MANIFEST_DIR"))
        .args(args)
        .output()
        .expect("the nlrom binary runs");
    assert!(
        out.status.success(),
        "nlrom {args:?} failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8(out.stdout).expect("utf-8 output")
}

/// The Python side: loads the file with h5py (no nlrom code), checks names, shapes, units and
/// attributes, and prints the resonance metrics of tools/post/plot_frf.py as JSON.
const CHECK: &str = r#"
import json, sys
import h5py, numpy as np
sys.path.insert(0, "tools/post")
import plot_frf, nlrom_results

path = sys.argv[1]
with h5py.File(path, "r") as f:
    root = dict(f.attrs)
    for key in ["program", "version", "title", "case_text", "created", "file_kind"]:
        assert key in root, f"root attribute {key} missing: {sorted(root)}"
    g = f["frf/0"]
    H = int(g.attrs["harmonics"])
    P = g["omega"].shape[0]
    R = g["response_dofs"].shape[0]
    expected = {"omega": ((P,), "rad/s"), "frequency_hz": ((P,), "Hz"),
                "amplitude": ((P, R), "m"), "peak": ((P, R), "m"),
                "harmonics": ((P, R, H + 1), "m"), "arc_length": ((P,), "1"),
                "newton_iterations": ((P,), "1"), "response_dofs": ((R,), "1")}
    for name, (shape, unit) in expected.items():
        ds = g[name]
        assert ds.shape == shape, f"{name}: shape {ds.shape}, expected {shape}"
        u = ds.attrs["unit"]
        u = u.decode() if isinstance(u, bytes) else u
        assert u == unit, f"{name}: unit {u!r}, expected {unit!r}"
    assert g["harmonics"].dtype == np.complex128, g["harmonics"].dtype
    omega = g["omega"][()]
    assert np.allclose(g["frequency_hz"][()], omega / (2 * np.pi), rtol=1e-14, atol=0)
    amp = g["amplitude"][()]
    assert np.allclose(amp, np.abs(g["harmonics"][()][:, :, 1]), rtol=1e-14, atol=0)
    # peak = max |q(t)| over a period, recomputed here from the harmonics (512 samples)
    tau = np.linspace(0, 2 * np.pi, 512, endpoint=False)
    n = np.arange(H + 1)
    q = np.real(np.einsum("prn,nt->prt", g["harmonics"][()], np.exp(1j * np.outer(n, tau))))
    assert np.allclose(g["peak"][()], np.abs(q).max(axis=2), rtol=1e-3, atol=0)
tree = nlrom_results.load(path)
f_r, a_r, q, r = plot_frf.metrics(tree["frf"][0])
print(json.dumps({"points": int(P), "dofs": int(R), "harmonics": H,
                  "resonance_hz": f_r, "peak_amplitude": a_r, "q_factor": q}))
"#;

fn number(v: &serde_json::Value, key: &str) -> f64 {
    v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("key {key} missing or not a number in {v}"))
}

#[test]
fn solve_result_file_read_in_python_matches_the_printed_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("chain3.h5");
    let printed = nlrom(&[
        "solve",
        "cases/chain3_jenkins.toml",
        "-o",
        out.to_str().unwrap(),
        "--json",
        "--quiet",
    ]);
    let summary: serde_json::Value = serde_json::from_str(printed.trim()).expect("one JSON object");
    let frf = &summary["frf"][0];

    let python: serde_json::Value =
        serde_json::from_str(run_python(CHECK, &[Path::new(&out)]).trim()).unwrap();
    assert_eq!(python["harmonics"].as_u64(), Some(7));
    assert_eq!(python["dofs"].as_u64(), Some(3));
    assert_eq!(python["points"].as_u64(), frf["points"].as_u64());
    // Same numbers read from the file: equal to rounding of the JSON printing (1e-12).
    for key in ["resonance_hz", "peak_amplitude"] {
        let (a, b) = (number(&python, key), number(frf, key));
        assert!(
            (a - b).abs() <= 1e-12 * b.abs(),
            "{key}: Python {a} vs nlrom {b}"
        );
    }
    // The chain's curve falls below half power on both sides of its peak in 0.2–2.2 rad/s.
    let (qa, qb) = (number(&python, "q_factor"), number(frf, "q_factor"));
    assert!(
        (qa - qb).abs() <= 1e-12 * qb.abs(),
        "Q-factor: Python {qa} vs nlrom {qb}"
    );
    assert!(qb > 1.0, "Q-factor {qb}");
}
