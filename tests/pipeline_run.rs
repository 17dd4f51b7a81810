//! `nlrom reduce`, `run`, `solve` with a ROM file, and `demo` on the bundled N = 8 sector:
//! the ROM file's frequencies against `nlrom modes` (an independent path: the Sector built in
//! memory), ROM reuse by key (reused while unchanged, rebuilt when the material changes, the
//! results identical), and the demo end to end.

mod support;

use std::path::{Path, PathBuf};

use nlrom::output::{read_results, read_rom};
use serde_json::Value;
use support::cli::{nlrom, root};

/// Runs nlrom, asserts exit status 0 and returns (stdout JSON, stderr).
fn ok_json(args: &[&str]) -> (Value, String) {
    let o = nlrom(args);
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(0), "{args:?}: {err}");
    (
        serde_json::from_slice(&o.stdout).expect("one JSON object"),
        err,
    )
}

fn freqs(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|f| f.as_f64().unwrap())
        .collect()
}

/// The ROM of every harmonic index has the frequencies `nlrom modes` reports for the same
/// stage (`gsi` for the bundled case with `gsi_modes`, `cs` for the same case without it), to
/// 1e-9 relative.
#[test]
fn reduce_writes_the_rom_with_the_modes_frequencies() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join("cases/sector8_cs.toml")).unwrap();
    let no_gsi = dir.path().join("no_gsi.toml");
    std::fs::write(
        &no_gsi,
        text.replace("gsi_modes = 10\n", "")
            .replace("../meshes/", &format!("{}/meshes/", root().display())),
    )
    .unwrap();
    let bundled = root().join("cases/sector8_cs.toml");
    for (case, stage) in [(bundled.as_path(), "gsi"), (no_gsi.as_path(), "cs")] {
        let out = dir.path().join(format!("{stage}.rom.h5"));
        let (report, _) = ok_json(&[
            "reduce",
            case.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "--json",
        ]);
        let rom = read_rom(&out).expect("ROM file");
        assert_eq!(report["key"].as_str(), Some(rom.key.as_str()));
        // engine order 3, H = 3, N = 8: k = 0, 3, 6 (= 3·2 mod 8), 1 (= 9 mod 8)
        let ks: Vec<usize> = rom.harmonics.iter().map(|h| h.harmonic_index).collect();
        assert_eq!(ks, vec![0, 1, 3, 6], "{stage}");
        for h in &rom.harmonics {
            let k = h.harmonic_index.to_string();
            let (modes, _) = ok_json(&[
                "modes",
                case.to_str().unwrap(),
                "--stage",
                stage,
                "--harmonic",
                &k,
                "--num",
                "5",
                "--json",
            ]);
            let expected = freqs(&modes["frequencies_hz"]);
            assert_eq!(modes["dofs"].as_u64(), Some(h.len() as u64), "k = {k}");
            for (a, b) in h.frequencies_hz.iter().zip(&expected) {
                assert!((a / b - 1.0).abs() < 1e-9, "{stage} k = {k}: {a} vs {b}");
            }
        }
    }
}

/// The demo case with a short range (3 points), its mesh by absolute path, and `young`.
fn small_case(dir: &Path, name: &str, young: &str, rom: Option<&Path>) -> PathBuf {
    let text = std::fs::read_to_string(root().join("cases/demo.toml"))
        .unwrap()
        .replace("../meshes/", &format!("{}/meshes/", root().display()))
        .replace("young = 210e9", &format!("young = {young}"))
        .replace("end_hz = 175.0", "end_hz = 160.0")
        .replace("step_hz = 2.0", "step_hz = 5.0");
    let text = match rom {
        Some(r) => format!("{text}\n[rom]\nfile = \"{}\"\n", r.display()),
        None => text,
    };
    let path = dir.join(format!("{name}.toml"));
    std::fs::write(&path, text).unwrap();
    path
}

/// `nlrom run` twice: the second run reuses the ROM file (log line, JSON `rom.reused`) and
/// gives identical results; a changed Young's modulus makes the third run reduce again (and
/// shifts the response); `nlrom solve` with `[rom] file` reads the ROM when its key matches.
#[test]
fn run_reuses_the_rom_until_the_material_changes() {
    let dir = tempfile::tempdir().unwrap();
    let case = small_case(dir.path(), "small", "210e9", None);
    let out = dir.path().join("small.h5");
    let args = [
        "run",
        case.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--json",
    ];
    let rom_file = dir.path().join("small.rom.h5");
    let (first, log1) = ok_json(&args);
    assert_eq!(first["rom"]["reused"], false);
    assert!(
        log1.contains("wrote the ROM to") && rom_file.exists(),
        "{log1}"
    );
    let r1 = read_results(&out).unwrap();
    let (second, log2) = ok_json(&args);
    assert_eq!(second["rom"]["reused"], true, "{log2}");
    assert!(log2.contains("reusing the ROM in"), "{log2}");
    let r2 = read_results(&out).unwrap();
    assert!(!r1.frfs[0].points.is_empty());
    assert_eq!(
        r1.frfs[0].points, r2.frfs[0].points,
        "same ROM, same results"
    );
    // the stiffer material: new key, new reduction, another response
    let stiff = small_case(dir.path(), "small", "230e9", None);
    let (third, log3) = ok_json(&[
        "run",
        stiff.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "--json",
    ]);
    assert_eq!(third["rom"]["reused"], false);
    assert!(log3.contains("was built from other inputs"), "{log3}");
    let r3 = read_results(&out).unwrap();
    assert_ne!(
        r3.frfs[0].points[0].harmonics,
        r1.frfs[0].points[0].harmonics
    );
    // solve with [rom] file = the (now 230 GPa) ROM: reused for the 230 GPa case only
    for (young, reused) in [("230e9", true), ("210e9", false)] {
        let c = small_case(dir.path(), "with_rom", young, Some(&rom_file));
        let o = dir.path().join("with_rom.h5");
        let (rep, log) = ok_json(&[
            "solve",
            c.to_str().unwrap(),
            "-o",
            o.to_str().unwrap(),
            "--json",
        ]);
        assert_eq!(rep["rom"]["reused"], reused, "{young}: {log}");
    }
}

/// `nlrom demo --out DIR`: exit 0, the results file and the ROM file in DIR, the summary
/// printed with the results path.
#[test]
fn demo_runs_end_to_end() {
    let dir = tempfile::tempdir().unwrap();
    let o = nlrom(&["demo", "--out", dir.path().to_str().unwrap()]);
    let out = String::from_utf8_lossy(&o.stdout);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let result = dir.path().join("demo.h5");
    assert!(
        out.contains(&format!("results: {}", result.display())),
        "{out}"
    );
    assert!(out.contains("plots:"), "{out}");
    assert!(dir.path().join("demo.rom.h5").exists());
    let r = read_results(&result).unwrap();
    assert!(r.frfs[0].points.len() > 10);
    assert_eq!(r.contacts.len(), 1);
    assert_eq!(r.contacts[0].name, "shroud");
}
