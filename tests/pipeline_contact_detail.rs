//! The per-element contact data of a sector FRF (`/contact/<name>/elements/<i>`)
//! and the Python plots made from it. The bundled demo (N = 8 shrouded sector, node-to-node
//! shroud, constant normal load, 1 N excitation: the shroud slips around resonance):
//! - the per-element fractions average to the interface's `state_fractions` (1e-12) and each
//!   element's fractions sum to 1;
//! - the loops are recorded at the resonance peak that `nlrom run --json` reports;
//! - each element's dissipated energy per cycle (the law's Σ f_t Δw) equals the area of its
//!   hysteresis loop ∮ f·du computed here from the stored samples (trapezoidal rule), an
//!   independent quantity, within 3 % (the difference is O(Δf²/k_t) per sample step, 32 samples);
//! - `tools/post/plot_contact.py` reads the file with h5py and writes both PNGs.

mod support;

use std::path::Path;

use nlrom::output::read_results;
use serde_json::Value;
use support::cli::{json_report, root};
use support::python::run_python;

fn slipping_demo(dir: &Path) -> std::path::PathBuf {
    let text = std::fs::read_to_string(root().join("cases/demo.toml"))
        .unwrap()
        .replace("../meshes/", &format!("{}/meshes/", root().display()));
    assert!(text.contains("force = [0.0, 0.0, 1.0]") && text.contains("time_samples = 32"));
    let path = dir.join("slip.toml");
    std::fs::write(&path, text).unwrap();
    path
}

/// ∮ f du over a closed loop of samples, trapezoidal rule with wrap-around.
fn loop_area(u: &[f64], f: &[f64]) -> f64 {
    let n = u.len();
    (0..n)
        .map(|j| 0.5 * (f[j] + f[(j + 1) % n]) * (u[(j + 1) % n] - u[j]))
        .sum()
}

#[test]
fn per_element_state_and_loops_at_the_peak() {
    let dir = tempfile::tempdir().unwrap();
    let case = slipping_demo(dir.path());
    let out = dir.path().join("slip.h5");
    let summary: Value = json_report("run", &case, &out, &[]);
    let resonance_hz = summary["frf"][0]["resonance_hz"].as_f64().unwrap();

    let r = read_results(&out).unwrap();
    let frf = &r.frfs[0];
    let contact = &r.contacts[0];
    let (p, e) = (frf.points.len(), contact.pairs.len());
    assert_eq!(contact.curves.len(), 1);
    let d = &contact.curves[0];
    assert_eq!(
        (d.fractions.len(), d.dissipated_energy.len()),
        (p * e, p * e)
    );
    for (i, point) in frf.points.iter().enumerate() {
        let rows = &d.fractions[i * e..(i + 1) * e];
        for c in 0..3 {
            let mean = rows.iter().map(|f| f[c]).sum::<f64>() / e as f64;
            assert!((mean - point.contact_fractions[0][c]).abs() < 1e-12);
        }
        assert!(rows
            .iter()
            .all(|f| (f.iter().sum::<f64>() - 1.0).abs() < 1e-12));
    }

    let loops = d.loops.as_ref().expect("loops at the peak");
    let peak_hz = frf.points[loops.point].omega / (2.0 * std::f64::consts::PI);
    assert!((peak_hz - resonance_hz).abs() <= 1e-12 * resonance_hz);
    let energy = &d.dissipated_energy[loops.point * e..(loops.point + 1) * e];
    let slipping = d.fractions[loops.point * e..(loops.point + 1) * e]
        .iter()
        .filter(|f| f[1] > 0.0)
        .count();
    assert!(
        slipping > e / 2,
        "{slipping} of {e} elements slip at the peak"
    );
    let w_max = energy.iter().cloned().fold(0.0, f64::max);
    assert!(w_max > 0.0);
    let n_t = loops.samples;
    let mut checked = 0;
    for el in 0..e {
        if energy[el] < 0.05 * w_max {
            continue;
        }
        let dir_series = |v: &[f64], k: usize| -> Vec<f64> {
            (0..n_t).map(|j| v[(el * n_t + j) * 2 + k]).collect()
        };
        let area: f64 = (0..2)
            .map(|k| loop_area(&dir_series(&loops.u, k), &dir_series(&loops.force, k)))
            .sum();
        let rel = (area - energy[el]).abs() / energy[el];
        assert!(
            rel < 0.03,
            "element {el}: W = {:e}, loop area {area:e} ({rel:.3})",
            energy[el]
        );
        checked += 1;
    }
    assert!(checked > e / 4, "only {checked} elements dissipate");

    let plots = dir.path().join("plots");
    let printed = run_python(
        "import sys, runpy; sys.argv = ['plot_contact.py', sys.argv[1], '--out', sys.argv[2]]; \
         runpy.run_path('tools/post/plot_contact.py', run_name='__main__')",
        &[&out, &plots],
    );
    assert!(printed.contains("loop area"), "{printed}");
    for png in ["loops.png", "state_map.png"] {
        let meta = std::fs::metadata(plots.join(png)).expect("plot written");
        assert!(meta.len() > 10_000, "{png}: {} bytes", meta.len());
    }
}
