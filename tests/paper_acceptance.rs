//! The SAMA acceptance on the bundled models, at the paper's nominal preload: the SAMA model of
//! the non-conforming sector (`cases/paper/m1_nonconforming.toml`, target face 2× coarser,
//! interpolated coupling) against the node-to-node benchmark on the conforming sector
//! (`cases/paper/m1_conforming.toml`), mode M1, n0 = 113 N, each solved end to end by
//! `nlrom solve` (mesh, assembly, CB + cyclic reduction, SAMA, HB with continuation).
//! Goal: resonance frequency within 0.5 %, peak amplitude within 3 %. Every preload of both
//! modes is checked by `python3 tools/validation/paper_comparison.py` (`docs/validation.md`, "The SAMA paper's experiment").

mod support;

use std::path::{Path, PathBuf};

use support::cli::{json_report, root};

/// `cases/paper/m1_<model>.toml` with one preload (`n0` = 113 N, no sweep), the window
/// 776–796 Hz around the resonance, absolute mesh path, written to `dir`.
fn one_preload_case(dir: &Path, model: &str) -> PathBuf {
    let text = std::fs::read_to_string(root().join(format!("cases/paper/m1_{model}.toml")))
        .expect("paper case");
    let sweep = text.find("[sweep]").expect("the paper case sweeps n0");
    let output = text.find("[output]").expect("[output]");
    let text = format!("{}{}", &text[..sweep], &text[output..])
        .replace("../../meshes/", &format!("{}/meshes/", root().display()))
        .replace("start_hz = 760.0", "start_hz = 776.0")
        .replace("end_hz = 800.0", "end_hz = 796.0");
    assert!(text.contains("n0 = 113.0") && text.contains("start_hz = 776.0"));
    let path = dir.join(format!("{model}.toml"));
    std::fs::write(&path, text).expect("write case");
    path
}

/// (resonance frequency in Hz, peak amplitude in m) of `nlrom solve CASE --json`.
fn resonance(case: &Path, out: &Path) -> (f64, f64) {
    let json = json_report("solve", case, out, &[]);
    let frf = &json["frf"][0];
    assert_eq!(frf["end"], "reached_end", "{frf}");
    (
        frf["resonance_hz"].as_f64().expect("resonance"),
        frf["peak_amplitude"].as_f64().expect("amplitude"),
    )
}

#[test]
fn sama_on_the_nonconforming_sector_matches_the_conforming_benchmark() {
    let dir = std::env::temp_dir().join(format!("nlrom_paper_acceptance_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (f_c, a_c) = resonance(
        &one_preload_case(&dir, "conforming"),
        &dir.join("conforming.h5"),
    );
    let (f_n, a_n) = resonance(
        &one_preload_case(&dir, "nonconforming"),
        &dir.join("nonconforming.h5"),
    );
    let df = f_n / f_c - 1.0;
    let da = a_n / a_c - 1.0;
    println!(
        "n0 = 113 N: conforming {f_c:.3} Hz {a_c:.4e} m, SAMA {f_n:.3} Hz {a_n:.4e} m: \
         Δf {:+.3} %, ΔA {:+.2} %",
        100.0 * df,
        100.0 * da
    );
    // The benchmark itself: the full-window run of `docs/validation.md` (785.502 Hz, 1.0064e-6 m); the
    // peak is sampled by the continuation, so the two agree to about a step.
    assert!((f_c / 785.502 - 1.0).abs() < 1e-3, "{f_c}");
    assert!((a_c / 1.0064e-6 - 1.0).abs() < 1e-2, "{a_c}");
    // The acceptance: 0.5 % / 3 % (measured +0.09 %, +0.25 % in the full-window run).
    assert!(df.abs() < 5e-3, "resonance: {:+.3} %", 100.0 * df);
    assert!(da.abs() < 3e-2, "amplitude: {:+.2} %", 100.0 * da);
    std::fs::remove_dir_all(&dir).ok();
}
