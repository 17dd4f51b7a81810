//! The ROM file (`nlrom::output::{write_rom, read_rom}`): bitwise round trip of every field,
//! h5py reading the layout of `docs/results-file.md`, "ROM file", and errors that name the file and the dataset.

mod support;

use std::collections::BTreeMap;
use std::path::Path;

use faer::{c64, Mat};
use nlrom::cyclic::CyclicGeometry;
use nlrom::output::rom_file::rom_file;
use nlrom::output::{read_rom, write_rom, Dataset, FileInfo, H5File};
use nlrom::rom::{GsiReport, HarmonicRom, MasterNode, MasterRole, ReducedDof, Rom};
use serde_json::Value;

fn dofs() -> Vec<ReducedDof> {
    vec![
        ReducedDof::Physical {
            node_tag: 17,
            component: 0,
            role: MasterRole::LowFrontier,
        },
        ReducedDof::Physical {
            node_tag: 17,
            component: 2,
            role: MasterRole::Contact,
        },
        ReducedDof::Physical {
            node_tag: 4_000_000_001,
            component: 1,
            role: MasterRole::Keep,
        },
        ReducedDof::Physical {
            node_tag: 5,
            component: 1,
            role: MasterRole::HighFrontier,
        },
        ReducedDof::Physical {
            node_tag: 6,
            component: 2,
            role: MasterRole::Target,
        },
        ReducedDof::Interface { index: 0 },
        ReducedDof::Interface { index: 1 },
        ReducedDof::Modal { mode: 0 },
        ReducedDof::Modal { mode: 7 },
    ]
}

/// A Hermitian matrix with irrational-looking entries (so a lossy path would show).
fn hermitian(n: usize, seed: f64, real: bool) -> Mat<c64> {
    Mat::from_fn(n, n, |i, j| {
        let (a, b) = (i.min(j) as f64, i.max(j) as f64);
        let re = (seed * (1.0 + a) + (b * 0.7).sin()) / 3.0;
        let im = if real || i == j {
            0.0
        } else {
            (seed + a - b).cos() / 7.0 * if i < j { 1.0 } else { -1.0 }
        };
        c64::new(re * 1e7, im * 1e7)
    })
}

fn sample_rom() -> Rom {
    let n = dofs().len();
    let mut k12 = hermitian(n, 0.3, true);
    k12[(1, 1)].im = -0.0; // "real", but a −0.0 imaginary part must survive too
    let harmonics = vec![
        HarmonicRom {
            harmonic_index: 0,
            real: true,
            stiffness: hermitian(n, 1.1, true),
            mass: hermitian(n, 2.3, true),
            damping: Some(hermitian(n, 0.01, true)),
            dofs: dofs(),
            frequencies_hz: vec![101.5, 233.25, 1.0 / 3.0],
            gsi: Some(GsiReport {
                modes_used: 20,
                retained: 2,
                dropped: vec![3, 11],
            }),
        },
        HarmonicRom {
            harmonic_index: 3,
            real: false,
            stiffness: hermitian(n, 1.7, false),
            mass: hermitian(n, 0.9, false),
            damping: None,
            dofs: dofs(),
            frequencies_hz: vec![150.0],
            gsi: Some(GsiReport {
                modes_used: 20,
                retained: 2,
                dropped: vec![],
            }),
        },
        HarmonicRom {
            harmonic_index: 12,
            real: true,
            stiffness: k12,
            mass: hermitian(n, 0.5, true),
            damping: None,
            dofs: dofs(),
            frequencies_hz: vec![],
            gsi: None,
        },
    ];
    let mut groups = BTreeMap::new();
    groups.insert("left_frontier".to_string(), vec![17, 5]);
    groups.insert("excitation".to_string(), vec![4_000_000_001]);
    groups.insert("empty".to_string(), vec![]);
    Rom {
        cyclic: Some(CyclicGeometry::new(24, [0.1, -0.2, 1.0 / 3.0], [0.0, 0.6, 0.8]).unwrap()),
        full_dofs: 20_637,
        nodes: vec![
            MasterNode {
                tag: 5,
                position: [0.1, 0.2, -0.0],
            },
            MasterNode {
                tag: 6,
                position: [1e-300, 2.0 / 3.0, 5.5],
            },
            MasterNode {
                tag: 17,
                position: [3.0, 4.0, 5.0],
            },
            MasterNode {
                tag: 4_000_000_001,
                position: [-1.0, 0.0, 0.5],
            },
        ],
        groups,
        interface_modes: 30,
        interface_frequencies_hz: vec![812.5, 1.0e4 / 7.0],
        harmonics,
        key: "3f2a9c".to_string(),
    }
}

fn info() -> FileInfo {
    FileInfo {
        title: "shrouded sector".to_string(),
        case_text: "title = \"shrouded sector\"\n".to_string(),
    }
}

fn assert_matrix_bits(a: &Mat<c64>, b: &Mat<c64>, what: &str) {
    assert_eq!((a.nrows(), a.ncols()), (b.nrows(), b.ncols()), "{what}");
    for i in 0..a.nrows() {
        for j in 0..a.ncols() {
            let (x, y) = (a[(i, j)], b[(i, j)]);
            assert_eq!(
                (x.re.to_bits(), x.im.to_bits()),
                (y.re.to_bits(), y.im.to_bits()),
                "{what}[{i},{j}]: {x:?} vs {y:?}"
            );
        }
    }
}

fn f64_bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

/// Every field of `b` equals `a` bit for bit.
fn assert_same_rom(a: &Rom, b: &Rom) {
    let (ca, cb) = (a.cyclic.unwrap(), b.cyclic.unwrap());
    assert_eq!(ca.sectors, cb.sectors);
    assert_eq!(f64_bits(&ca.origin), f64_bits(&cb.origin));
    assert_eq!(f64_bits(&ca.axis), f64_bits(&cb.axis));
    assert_eq!(ca.alpha.to_bits(), cb.alpha.to_bits());
    assert_eq!(a.full_dofs, b.full_dofs);
    assert_eq!(a.nodes.len(), b.nodes.len());
    for (x, y) in a.nodes.iter().zip(&b.nodes) {
        assert_eq!(x.tag, y.tag);
        assert_eq!(f64_bits(&x.position), f64_bits(&y.position));
    }
    assert_eq!(a.groups, b.groups);
    assert_eq!(a.interface_modes, b.interface_modes);
    assert_eq!(
        f64_bits(&a.interface_frequencies_hz),
        f64_bits(&b.interface_frequencies_hz)
    );
    assert_eq!(a.key, b.key);
    assert_eq!(a.harmonics.len(), b.harmonics.len());
    for (x, y) in a.harmonics.iter().zip(&b.harmonics) {
        let k = x.harmonic_index;
        assert_eq!(k, y.harmonic_index);
        assert_eq!(x.real, y.real, "k{k}");
        assert_matrix_bits(&x.stiffness, &y.stiffness, &format!("k{k} stiffness"));
        assert_matrix_bits(&x.mass, &y.mass, &format!("k{k} mass"));
        assert_eq!(x.damping.is_some(), y.damping.is_some(), "k{k} damping");
        if let (Some(c), Some(d)) = (&x.damping, &y.damping) {
            assert_matrix_bits(c, d, &format!("k{k} damping"));
        }
        assert_eq!(x.dofs, y.dofs, "k{k} dofs");
        assert_eq!(f64_bits(&x.frequencies_hz), f64_bits(&y.frequencies_hz));
        assert_eq!(x.gsi, y.gsi, "k{k} gsi");
    }
}

#[test]
fn rom_round_trip_is_bitwise_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rom.h5");
    let rom = sample_rom();
    write_rom(&path, &rom, &info()).unwrap();
    let back = read_rom(&path).unwrap();
    assert_same_rom(&rom, &back);
    assert_eq!(back.harmonic(3).unwrap().row_of(17, 2), Some(1));

    // without cyclic symmetry, no harmonics beyond k = 0, no GSI
    let mut plain = sample_rom();
    plain.cyclic = None;
    plain.harmonics.truncate(1);
    plain.harmonics[0].gsi = None;
    write_rom(&path, &plain, &info()).unwrap();
    let back = read_rom(&path).unwrap();
    assert!(back.cyclic.is_none());
    assert_eq!(back.harmonics.len(), 1);
    assert!(back.harmonics[0].gsi.is_none());
    assert_matrix_bits(
        &plain.harmonics[0].mass,
        &back.harmonics[0].mass,
        "plain mass",
    );
}

/// The round-trip comparison is not vacuous: a one-bit change is caught.
#[test]
#[should_panic(expected = "k3 stiffness[0,1]")]
fn rom_comparison_detects_a_one_bit_change() {
    let rom = sample_rom();
    let mut other = sample_rom();
    let z = other.harmonics[1].stiffness[(0, 1)];
    other.harmonics[1].stiffness[(0, 1)] = c64::new(f64::from_bits(z.re.to_bits() ^ 1), z.im);
    assert_same_rom(&rom, &other);
}

#[test]
fn h5py_reads_the_rom_layout() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("rom.h5");
    write_rom(&path, &sample_rom(), &info()).unwrap();
    let script = r#"
import sys, json, h5py
f = h5py.File(sys.argv[1], "r")
r = f["rom"]
d = r["k3/dofs"]
out = {
    "file_kind": f.attrs["file_kind"], "title": f.attrs["title"],
    "harmonic_indices": [int(x) for x in r.attrs["harmonic_indices"]],
    "sectors": int(r.attrs["sectors"]), "groups": sorted(r["groups"].keys()),
    "k0_dtype": str(r["k0/stiffness"].dtype), "k3_dtype": str(r["k3/stiffness"].dtype),
    "k12_dtype": str(r["k12/stiffness"].dtype), "k0_damping": "damping" in r["k0"],
    "k3_damping": "damping" in r["k3"], "k3_shape": list(r["k3/mass"].shape),
    "k3_01": [float(r["k3/stiffness"][0, 1].real), float(r["k3/stiffness"][0, 1].imag)],
    "k3_10": [float(r["k3/stiffness"][1, 0].real), float(r["k3/stiffness"][1, 0].imag)],
    "kind": {k: int(v) for k, v in h5py.check_enum_dtype(d.dtype["kind"]).items()},
    "kinds": [int(x) for x in d["kind"]], "tags": [int(x) for x in d["node_tag"]],
    "unit": r["k0/mass"].attrs["unit"], "node_tags": [int(x) for x in r["nodes"]["tag"]],
}
print(json.dumps(out))
"#;
    let v: Value =
        serde_json::from_str(&support::python::run_python(script, &[path.as_path()])).unwrap();
    assert_eq!(v["file_kind"], "rom");
    assert_eq!(v["title"], "shrouded sector");
    assert_eq!(v["harmonic_indices"], serde_json::json!([0, 3, 12]));
    assert_eq!(v["sectors"], 24);
    assert_eq!(
        v["groups"],
        serde_json::json!(["empty", "excitation", "left_frontier"])
    );
    assert_eq!(v["k0_dtype"], "float64");
    assert_eq!(v["k3_dtype"], "complex128");
    assert_eq!(
        v["k12_dtype"], "complex128",
        "a −0.0 imaginary part forces complex storage"
    );
    assert_eq!(v["k0_damping"], true);
    assert_eq!(v["k3_damping"], false);
    assert_eq!(v["k3_shape"], serde_json::json!([9, 9]));
    let k = hermitian(9, 1.7, false);
    assert_eq!(v["k3_01"], serde_json::json!([k[(0, 1)].re, k[(0, 1)].im]));
    assert_eq!(v["k3_10"], serde_json::json!([k[(1, 0)].re, k[(1, 0)].im]));
    assert_eq!(
        v["kind"],
        serde_json::json!({"physical": 0, "interface": 1, "modal": 2})
    );
    assert_eq!(v["kinds"], serde_json::json!([0, 0, 0, 0, 0, 1, 1, 2, 2]));
    assert_eq!(
        v["tags"],
        serde_json::json!([17, 17, 4_000_000_001u64, 5, 6, 0, 0, 0, 0])
    );
    assert_eq!(v["unit"], "kg");
    assert_eq!(
        v["node_tags"],
        serde_json::json!([5, 6, 17, 4_000_000_001u64])
    );
}

/// Writes `file` to `path` and asserts that `read_rom` refuses it (exit status 2) with a message
/// holding every one of `parts`.
fn assert_refused(file: &H5File, path: &Path, parts: &[&str]) {
    file.write(path).unwrap();
    let err = read_rom(path).expect_err("malformed ROM accepted");
    assert_eq!(err.exit_code(), 2, "{err}");
    let msg = err.to_string();
    for part in parts {
        assert!(msg.contains(part), "{part:?} not in: {msg}");
    }
}

#[test]
fn malformed_rom_files_are_refused_naming_file_and_dataset() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bad.h5");
    let good = rom_file(&sample_rom(), &info());

    let mut missing = good.clone();
    let k3 = missing
        .root
        .groups
        .get_mut("rom")
        .unwrap()
        .groups
        .get_mut("k3")
        .unwrap();
    k3.datasets.remove("mass");
    assert_refused(&missing, &path, &["bad.h5", "/rom/k3/mass"]);

    let mut no_group = good.clone();
    no_group
        .root
        .groups
        .get_mut("rom")
        .unwrap()
        .groups
        .remove("k12");
    assert_refused(&no_group, &path, &["bad.h5", "/rom/k12"]);

    let mut shape = good.clone();
    shape
        .root
        .groups
        .get_mut("rom")
        .unwrap()
        .groups
        .get_mut("k0")
        .unwrap()
        .add(
            "stiffness",
            Dataset::real_matrix(&Mat::zeros(9, 8), "N/m", "wrong shape"),
        );
    assert_refused(&shape, &path, &["bad.h5", "/rom/k0/stiffness", "[9, 8]"]);

    let mut dofs = good.clone();
    dofs.root
        .groups
        .get_mut("rom")
        .unwrap()
        .groups
        .get_mut("k0")
        .unwrap()
        .add("dofs", Dataset::u64s(vec![1, 2], "1", "not records"));
    assert_refused(&dofs, &path, &["/rom/k0/dofs", "compound"]);

    let mut no_rom = good.clone();
    no_rom.root.groups.clear();
    assert_refused(&no_rom, &path, &["bad.h5", "/rom"]);

    let mut foreign = good.clone();
    foreign.root.attrs.clear();
    assert_refused(&foreign, &path, &["bad.h5", "not an nlrom file"]);

    let mut results = good.clone();
    results
        .root
        .set_attr("file_kind", nlrom::output::Attr::Str("results".into()));
    assert_refused(&results, &path, &["expected a rom file"]);

    std::fs::write(&path, "K = [1 2; 3 4]").unwrap();
    let msg = read_rom(&path).unwrap_err().to_string();
    assert!(
        msg.contains("bad.h5") && msg.contains("not an HDF5 file"),
        "{msg}"
    );
}
