//! The results file (`nlrom::output::results`): exact round trip, size checks naming the
//! curve / dataset, and `tools/post/nlrom_results.py` (h5py only) loading it, with the derived
//! datasets (amplitude = abs(Q1), frequency_hz = ω/2π) recomputed in numpy.

mod support;

use std::collections::BTreeMap;

use faer::c64;
use nlrom::output::{
    read_results, write_results, ContactCurveDetail, ContactData, ContactMap, ContactPairData,
    FileInfo, FrfData, FrfRecord, MarchData, PointLoops, ResponseDof, ResultsFile,
};
use nlrom::output::{Attr, Data, Dataset, Group};
use serde_json::{json, Value};

fn frf(n0: f64, points: usize, harmonics: usize, contacts: usize) -> FrfData {
    let response_dofs = vec![
        ResponseDof::Node {
            tag: 17,
            component: 2,
        },
        ResponseDof::Node {
            tag: 4_000_000_001,
            component: 0,
        },
    ];
    let r = response_dofs.len();
    let h1 = harmonics + 1;
    let points = (0..points)
        .map(|p| {
            let w = 5000.0 + 7.3 * p as f64 - if p > 3 { 20.0 } else { 0.0 }; // a fold
            FrfRecord {
                omega: w,
                harmonics: (0..r * h1)
                    .map(|j| {
                        c64::new(
                            (j as f64 + 1.0) * 1e-5 / (p as f64 + 1.0),
                            -(j as f64) * 3e-6,
                        )
                    })
                    .collect(),
                peak: (0..r).map(|j| 1e-4 * (p + j) as f64 + 1.0 / 3.0).collect(),
                arc_length: 0.1 * p as f64,
                newton_iterations: (p % 4) as u64 + 1,
                residual: 1e-10 * (p as f64 + 1.0),
                stable: Some(p % 3 != 1),
                contact_fractions: (0..contacts)
                    .map(|c| {
                        let stick = 0.1 * c as f64 + 0.05 * p as f64;
                        [stick, 0.5, 0.5 - stick]
                    })
                    .collect(),
            }
        })
        .collect();
    let mut sweep = BTreeMap::new();
    sweep.insert("contact.shroud.n0".to_string(), n0);
    FrfData {
        sweep,
        harmonics,
        response_dofs,
        points,
        jumps: Vec::new(),
    }
}

/// Per-element detail for curves of `points[i]` points; loops (N_t = 5) on the first curve only.
fn details(elements: usize, points: &[usize]) -> Vec<ContactCurveDetail> {
    points
        .iter()
        .enumerate()
        .map(|(i, &p)| {
            let n = p * elements;
            let loops = (i == 0).then(|| {
                let m = elements * 5;
                PointLoops {
                    point: p - 1,
                    samples: 5,
                    u: (0..2 * m).map(|j| (j as f64 * 0.7).sin() * 1e-6).collect(),
                    force: (0..2 * m).map(|j| (j as f64 * 0.3).cos()).collect(),
                    approach: (0..m).map(|j| j as f64 * -1e-7).collect(),
                    normal_force: (0..m).map(|j| 2.5 + j as f64).collect(),
                }
            });
            ContactCurveDetail {
                fractions: (0..n)
                    .map(|j| [0.25, 0.75 - 0.01 * (j % 7) as f64, 0.01 * (j % 7) as f64])
                    .collect(),
                dissipated_energy: (0..n).map(|j| 1e-7 * j as f64 / 3.0).collect(),
                loops,
            }
        })
        .collect()
}

fn contact(name: &str, elements: usize) -> ContactData {
    ContactData {
        curves: details(elements, &[6, 3]),
        name: name.to_string(),
        model: "sama".to_string(),
        coupling: "interpolated".to_string(),
        element: "2d".to_string(),
        sigma: -1,
        mu: 0.5,
        pairs: (0..elements)
            .map(|j| ContactPairData {
                contact_node: 100 + j as u64 / 2,
                target_node: 200 + j as u64,
                weight: 0.5 - 0.1 * (j % 2) as f64,
                frame: [[1.0, 0.0, 0.0], [0.0, 0.6, 0.8], [0.0, -0.8, 0.6]],
                kt: 1e8 * (j + 1) as f64,
                kn: 2e8,
                preload: 113.0 / (j + 1) as f64,
                virtual_point: [0.25, -1e-3 * j as f64, 0.01 / 3.0],
            })
            .collect(),
    }
}

fn march(t: usize) -> MarchData {
    MarchData {
        scheme: "piecewise-linear".to_string(),
        wall_seconds: 1.25,
        omega: 2.0 * std::f64::consts::PI * 200.0,
        steps: t as u64 - 1,
        response_dofs: vec![ResponseDof::Row(0), ResponseDof::Row(3)],
        time: (0..t).map(|i| i as f64 * 1e-4).collect(),
        response: (0..2 * t).map(|i| (i as f64 * 0.1).sin() * 1e-3).collect(),
        element_names: vec!["element 0".to_string(), "shroud ü".to_string()],
        contact_force: (0..4 * t).map(|i| i as f64 - 3.5).collect(),
        contact_state: (0..2 * t).map(|i| (i % 4) as u8).collect(),
        first_harmonic_last_period: vec![1e-3, 2.5e-4],
        iterations_per_step: (0..t).map(|i| (i % 3) as u64).collect(),
        extra: march_extra(t),
    }
}

/// Datasets and attributes beyond the /march layout (the marcher's own), read back verbatim.
fn march_extra(t: usize) -> Group {
    let mut g = Group::default();
    g.add(
        "contact_displacement",
        Dataset::new(
            &[t, 2, 2],
            Data::F64((0..4 * t).map(|i| i as f64 * 1e-7).collect()),
            "m",
            "(u_t, v) per element",
        ),
    )
    .set_attr("steady_period", Attr::I64(-1));
    g
}

fn sample() -> ResultsFile {
    let mut no_stability = frf(250.0, 3, 1, 2);
    for p in &mut no_stability.points {
        p.stable = None;
    }
    ResultsFile {
        info: FileInfo {
            title: "shroud sweep".to_string(),
            case_text: "[sweep]\n\"contact.shroud.n0\" = [113.0, 250.0]\n".to_string(),
        },
        frfs: vec![
            FrfData {
                jumps: vec![2, 4],
                ..frf(113.0, 6, 3, 2)
            },
            no_stability,
        ],
        // not in alphabetical order: the order of the points' fractions must survive
        contacts: vec![contact("underplatform", 3), contact("shroud", 4)],
        march: Some(march(9)),
        maps: vec![map("bar", 0, 5), map("bar", 1, 2)],
    }
}

/// A stick–slip–separation map of 3 points over 4 angles at point `point` of curve `curve`
/// (one point without transitions, one NaN ratio: separated).
fn map(name: &str, curve: usize, point: usize) -> ContactMap {
    ContactMap {
        name: name.to_string(),
        mu: 0.3,
        curve,
        point,
        omega: 6.5,
        position: vec![0.1, 0.5, 0.9],
        phase: (0..4)
            .map(|j| j as f64 * std::f64::consts::FRAC_PI_2)
            .collect(),
        state: vec![0, 0, 0, 0, 1, 0, -1, 0, 2, 0, 0, 2],
        friction_ratio: vec![
            0.1,
            0.2,
            0.3,
            0.4,
            1.0,
            0.5,
            -1.0,
            -0.5,
            f64::NAN,
            0.0,
            -0.0,
            f64::NAN,
        ],
        transition_offsets: vec![0, 0, 4, 6],
        transition_angles: vec![0.5, 1.0, 3.0, 4.0, 1.0, 5.0],
        transition_states: vec![1, 0, -1, 0, 0, 2],
    }
}

#[test]
fn results_round_trip_exactly() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("results.h5");
    let results = sample();
    write_results(&path, &results).unwrap();
    let back = read_results(&path).unwrap();
    // Debug of f64 is shortest-round-trip (and shows -0.0): equal strings = equal bits
    assert_eq!(format!("{results:?}"), format!("{back:?}"));

    // an FRF-only file, a march-only file
    let frf_only = ResultsFile {
        march: None,
        contacts: vec![],
        maps: vec![],
        frfs: vec![frf(1.0, 2, 2, 0)],
        ..sample()
    };
    write_results(&path, &frf_only).unwrap();
    assert_eq!(read_results(&path).unwrap(), frf_only);
    let march_only = ResultsFile {
        frfs: vec![],
        contacts: vec![],
        maps: vec![],
        ..sample()
    };
    write_results(&path, &march_only).unwrap();
    assert_eq!(read_results(&path).unwrap(), march_only);
}

fn write_error(results: &ResultsFile) -> String {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("r.h5");
    let err = write_results(&path, results).expect_err("inconsistent results written");
    assert!(!path.exists(), "a refused file must not exist");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 0);
    err.to_string()
}

#[test]
fn inconsistent_sizes_are_refused() {
    let mut r = sample();
    r.frfs[1].points[2].harmonics.pop();
    let msg = write_error(&r);
    assert!(
        msg.contains("/frf/1 point 2") && msg.contains("harmonics"),
        "{msg}"
    );

    let mut r = sample();
    r.frfs[0].points[0].stable = None;
    let msg = write_error(&r);
    assert!(msg.contains("/frf/0") && msg.contains("stability"), "{msg}");

    let mut r = sample();
    r.frfs[0].points[5].contact_fractions.pop();
    let msg = write_error(&r);
    assert!(
        msg.contains("/frf/0 point 5") && msg.contains("interfaces"),
        "{msg}"
    );

    let mut r = sample();
    r.march.as_mut().unwrap().contact_state.pop();
    let msg = write_error(&r);
    assert!(
        msg.contains("/march/contact_state") && msg.contains("E = 2"),
        "{msg}"
    );

    let mut r = sample();
    r.contacts[1].curves[0].dissipated_energy.pop();
    let msg = write_error(&r);
    assert!(msg.contains("/contact/shroud/elements/0"), "{msg}");

    let mut r = sample();
    r.contacts[0].curves[0].loops.as_mut().unwrap().point = 6;
    let msg = write_error(&r);
    assert!(
        msg.contains("/contact/underplatform/elements/0") && msg.contains("loops"),
        "{msg}"
    );

    let mut r = sample();
    r.frfs[0].jumps = vec![4, 2];
    let msg = write_error(&r);
    assert!(msg.contains("/frf/0") && msg.contains("jumps"), "{msg}");

    let mut r = sample();
    r.contacts[1].name = "underplatform".to_string();
    let msg = write_error(&r);
    assert!(msg.contains("underplatform"), "{msg}");
}

#[test]
fn reading_a_rom_file_as_results_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("r.h5");
    write_results(&path, &sample()).unwrap();
    let err = nlrom::output::read_rom(&path).unwrap_err().to_string();
    assert!(
        err.contains("r.h5") && err.contains("expected a rom file"),
        "{err}"
    );
}

/// `tools/post/nlrom_results.py` loads the file with h5py; numpy recomputes amplitude = abs(Q1) and
/// frequency_hz = ω/2π from the stored harmonics and ω.
#[test]
fn python_tool_loads_results() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("results.h5");
    write_results(&path, &sample()).unwrap();
    let script = r#"
import sys, json
import numpy as np
sys.path.insert(0, "tools/post")
import nlrom_results
r = nlrom_results.load(sys.argv[1])
f0 = r["frf"][0]
sh = r["contact"]["shroud"]
m = r["march"]
out = {
    "title": r["attrs"]["title"], "kind": r["attrs"]["file_kind"],
    "frf_count": len(r["frf"]),
    "harmonics_dtype": str(f0["harmonics"].dtype), "harmonics_shape": list(f0["harmonics"].shape),
    "amplitude_error": float(np.max(np.abs(f0["amplitude"] - np.abs(f0["harmonics"][:, :, 1])))),
    "hz_error": float(np.max(np.abs(f0["frequency_hz"] - f0["omega"] / (2 * np.pi)))),
    "omega": f0["omega"].tolist(), "unit_omega": f0["units"]["omega"],
    "n0": f0["attrs"]["contact.shroud.n0"], "sweep_parameters": f0["attrs"]["sweep_parameters"],
    "stable": f0["stable"].tolist(), "has_stable_1": "stable" in r["frf"][1],
    "dof_tags": f0["response_dofs"]["node_tag"].tolist(), "dof_components": f0["response_dofs"]["component"].tolist(),
    "contact_order": r["contact"]["attrs"]["names"],
    "shroud_pairs": sh["pairs"]["target_node"].tolist(), "shroud_frames": list(sh["frames"].shape),
    "shroud_fractions_0": sh["state_fractions"]["0"].tolist(),
    "shroud_model": sh["attrs"]["model"], "shroud_sigma": sh["attrs"]["sigma"],
    "march_response_shape": list(m["response"].shape), "march_force_shape": list(m["contact_force"].shape),
    "march_state": m["contact_state"][:, 1].tolist(), "march_names": m["element_names"],
    "march_scheme": m["attrs"]["scheme"], "march_rows": m["response_dofs"]["node_tag"].tolist(),
    "march_components": m["response_dofs"]["component"].tolist(),
    "summary": nlrom_results.summary(r),
}
print(json.dumps(out))
"#;
    let v: Value =
        serde_json::from_str(&support::python::run_python(script, &[path.as_path()])).unwrap();
    let s = sample();
    assert_eq!(v["title"], "shroud sweep");
    assert_eq!(v["kind"], "results");
    assert_eq!(v["frf_count"], 2);
    assert_eq!(v["harmonics_dtype"], "complex128");
    assert_eq!(v["harmonics_shape"], json!([6, 2, 4]));
    assert!(
        v["amplitude_error"].as_f64().unwrap() <= 1e-20,
        "{}",
        v["amplitude_error"]
    );
    assert!(
        v["hz_error"].as_f64().unwrap() <= 1e-12,
        "{}",
        v["hz_error"]
    );
    let omega: Vec<f64> = s.frfs[0].points.iter().map(|p| p.omega).collect();
    assert_eq!(v["omega"], json!(omega));
    assert_eq!(v["unit_omega"], "rad/s");
    assert_eq!(v["n0"], 113.0);
    assert_eq!(v["sweep_parameters"], json!(["contact.shroud.n0"]));
    assert_eq!(v["stable"], json!([1, 0, 1, 1, 0, 1]));
    assert_eq!(v["has_stable_1"], false);
    assert_eq!(v["dof_tags"], json!([17, 4_000_000_001u64]));
    assert_eq!(v["dof_components"], json!([2, 0]));
    assert_eq!(v["contact_order"], json!(["underplatform", "shroud"]));
    assert_eq!(v["shroud_pairs"], json!([200, 201, 202, 203]));
    assert_eq!(v["shroud_frames"], json!([4, 3, 3]));
    // the shroud is interface 1 of the points
    let expected: Vec<Vec<f64>> = s.frfs[0]
        .points
        .iter()
        .map(|p| p.contact_fractions[1].to_vec())
        .collect();
    assert_eq!(v["shroud_fractions_0"], json!(expected));
    assert_eq!(v["shroud_model"], "sama");
    assert_eq!(v["shroud_sigma"], -1);
    assert_eq!(v["march_response_shape"], json!([9, 2]));
    assert_eq!(v["march_force_shape"], json!([9, 2, 2]));
    assert_eq!(v["march_state"], json!([1, 3, 1, 3, 1, 3, 1, 3, 1]));
    assert_eq!(v["march_names"], json!(["element 0", "shroud ü"]));
    assert_eq!(v["march_scheme"], "piecewise-linear");
    assert_eq!(v["march_rows"], json!([0, 3]));
    assert_eq!(v["march_components"], json!([-1, -1]));
    let summary = v["summary"].as_str().unwrap();
    assert!(
        summary.contains("frf 0") && summary.contains("6 points"),
        "{summary}"
    );
}
