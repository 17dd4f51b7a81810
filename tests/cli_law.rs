//! `nlrom law`: one friction point under a prescribed harmonic motion. The Jenkins closed forms
//! in the text and JSON output; the analytic and AFT evaluations of a separating case agree to
//! first order in 1/N_t; a TOML input overridden by the command line; the loop CSV and its plot
//! (`tools/post/plot_law.py`, whose loop area equals the printed energy); bad input exits 2
//! with a message naming the key.

mod support;

use support::cli::{nlrom, stderr};
use support::python::run_python;

fn json(args: &[&str]) -> serde_json::Value {
    let mut all = vec!["law"];
    all.extend_from_slice(args);
    all.push("--json");
    let o = nlrom(&all);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    serde_json::from_slice(&o.stdout).expect("one JSON object")
}

fn num(v: &serde_json::Value, i: usize) -> f64 {
    v.as_array().unwrap()[i].as_f64().unwrap()
}

/// k_t = 1, μ n0 = 0.3, u = cos τ: Re F1 = 0.2523158, Im F1 = 0.2673803, W = 0.84
/// (`docs/theory.md`), in the text and in the JSON, with the transitions P at 0° and N at 180°.
#[test]
fn jenkins_closed_forms_in_text_and_json() {
    let o = nlrom(&[
        "law", "--kt", "1", "--mu", "0.3", "--n0", "1", "--u", "0,1,0",
    ]);
    assert_eq!(o.status.code(), Some(0), "{}", stderr(&o));
    let text = String::from_utf8(o.stdout).unwrap();
    assert!(text.contains("2.523158e-1 +2.673803e-1i"), "{text}");
    assert!(
        text.contains("energy per cycle (J): 8.400000000e-1"),
        "{text}"
    );
    assert!(text.contains("regime: stick-slip"), "{text}");
    let j = json(&["--kt", "1", "--mu", "0.3", "--n0", "1", "--u", "0,1,0"]);
    assert!((num(&j["friction"], 1) - 0.2523158).abs() < 1e-7);
    assert!((num(&j["friction"], 2) - 0.2673803).abs() < 1e-7);
    assert!((j["energy_per_cycle"].as_f64().unwrap() - 0.84).abs() < 1e-14);
    let names: Vec<(String, f64)> = j["transitions"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| {
            (
                t["name"].as_str().unwrap().to_string(),
                t["tau_deg"].as_f64().unwrap(),
            )
        })
        .collect();
    let at = |n: &str| names.iter().find(|x| x.0 == n).unwrap().1;
    assert!(
        at("P").abs() < 1e-9 || (at("P") - 360.0).abs() < 1e-9,
        "{names:?}"
    );
    assert!((at("N") - 180.0).abs() < 1e-9, "{names:?}");
    // StN where cos τ = 1 − 2μ n0/(k_t A) = 0.4
    assert!(
        (at("StN") - 0.4f64.acos().to_degrees()).abs() < 1e-9,
        "{names:?}"
    );
    assert_eq!(j["loop"]["f"].as_array().unwrap().len(), 256);
}

/// A case with separation (n0 = 0.7, k_n = 5, μ = 0.4, v with amplitude 0.36 against u of 0.7):
/// the AFT at N_t = 2048 and 8192 against the analytic harmonics, error within 2e-4·k_t a at
/// 8192 and falling by 3 to 6 times; the transitions and fractions within two samples.
#[test]
fn analytic_and_aft_agree_to_first_order() {
    let base = [
        "--kt",
        "2",
        "--kn",
        "5",
        "--mu",
        "0.4",
        "--n0",
        "0.7",
        "--u",
        "0,0,-0.7",
        "--v",
        "0,0.3,0.2",
    ];
    let a = json(&base);
    assert_eq!(a["regime"], "separation");
    let mut errs = Vec::new();
    for n_t in ["2048", "8192"] {
        let mut args = base.to_vec();
        args.extend_from_slice(&["--evaluation", "aft", "--time-samples", n_t]);
        let d = json(&args);
        assert_eq!(d["regime"], "separation");
        let e = (0..3)
            .map(|i| (num(&d["friction"], i) - num(&a["friction"], i)).abs())
            .fold(0.0, f64::max)
            / (2.0 * 0.7);
        errs.push(e);
        if n_t == "8192" {
            let dt = 360.0 / 8192.0;
            for (ta, td) in a["transitions"]
                .as_array()
                .unwrap()
                .iter()
                .zip(d["transitions"].as_array().unwrap())
            {
                assert_eq!(ta["name"], td["name"]);
                let x = ta["tau_deg"].as_f64().unwrap() - td["tau_deg"].as_f64().unwrap();
                assert!(x.abs() <= 2.0 * dt, "{ta} vs {td}");
            }
            for k in ["stick", "slip", "separation"] {
                let x = a["fractions"][k].as_f64().unwrap() - d["fractions"][k].as_f64().unwrap();
                assert!(x.abs() < 4.0 / 8192.0, "{k}: {x}");
            }
        }
    }
    assert!(errs[1] < 2e-4, "{errs:?}");
    assert!((3.0..6.0).contains(&(errs[0] / errs[1])), "{errs:?}");
}

/// `--input` TOML, overridden by the command line; the loop CSV, and the plot script's loop
/// area equals the printed energy to 1e-3 (trapezoidal rule over 1024 samples).
#[test]
fn input_file_loop_csv_and_plot() {
    let dir = tempfile::tempdir().unwrap();
    let input = dir.path().join("law.toml");
    std::fs::write(
        &input,
        "kt = 2.0\nkn = 5.0\nmu = 0.4\nn0 = 100.0\nu = [0.0, 0.0, -0.7]\nv = [0.0, 0.3, 0.2]\n",
    )
    .unwrap();
    let csv = dir.path().join("loop.csv");
    let png = dir.path().join("loop.png");
    let j = json(&[
        "--input",
        input.to_str().unwrap(),
        "--n0",
        "0.7",
        "--loop",
        csv.to_str().unwrap(),
        "--loop-samples",
        "1024",
        "-q",
    ]);
    assert_eq!(j["regime"], "separation", "n0 from the command line");
    let lines = std::fs::read_to_string(&csv).unwrap().lines().count();
    assert_eq!(lines, 1025);
    let area: f64 = run_python(
        "import sys, runpy; sys.argv = ['plot_law.py', sys.argv[1], '-o', sys.argv[2]]; \
         runpy.run_path('tools/post/plot_law.py', run_name='__main__')",
        &[&csv, &png],
    )
    .trim()
    .parse()
    .unwrap();
    let w = j["energy_per_cycle"].as_f64().unwrap();
    assert!((area - w).abs() < 1e-3 * w, "loop area {area} vs W {w}");
    assert!(std::fs::metadata(&png).unwrap().len() > 1000);
}

/// Bad input: exit status 2 and a message naming the key.
#[test]
fn bad_input_exits_2_naming_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(
        &bad,
        "kt = 1.0\nmu = 0.3\nn0 = 1.0\nu = [0.0, 1.0, 0.0]\nfoo = 2\n",
    )
    .unwrap();
    for (args, needle) in [
        (
            vec!["--kt", "1", "--mu", "0.3", "--u", "0,1,0"],
            "`n0` is missing",
        ),
        (
            vec![
                "--kt",
                "1",
                "--mu",
                "0.3",
                "--n0",
                "1",
                "--u",
                "0,1,0,0.1,0",
            ],
            "--evaluation aft",
        ),
        (
            vec!["--kt", "1", "--mu", "0.3", "--n0", "1", "--u", "0,1"],
            "`u` has 2 values",
        ),
        (
            vec![
                "--kt", "1", "--mu", "0.3", "--n0", "1", "--u", "0,1,0", "--v", "0,1",
            ],
            "`v` has 2 values",
        ),
        (
            vec!["--kt", "-1", "--mu", "0.3", "--n0", "1", "--u", "0,1,0"],
            "kt",
        ),
        (vec!["--input", bad.to_str().unwrap()], "foo"),
    ] {
        let mut all = vec!["law"];
        all.extend_from_slice(&args);
        let o = nlrom(&all);
        assert_eq!(o.status.code(), Some(2), "{args:?}: {}", stderr(&o));
        assert!(stderr(&o).contains(needle), "{args:?}: {}", stderr(&o));
    }
}
