//! The HDF5 layer (`nlrom::output::h5`): exact round trip through our reader, h5py as the
//! independent reader (dtypes, complex128, compound records, enums, string attributes), refusal of
//! malformed datasets, atomic writes, and reader errors that name the file and the dataset.

mod support;

use std::path::Path;

use faer::{c64, Mat};
use nlrom::output::h5::{temporary_path, write_atomic};
use nlrom::output::{
    file_attributes, Attr, Column, Data, Dataset, FileInfo, H5File, H5Reader, Records,
};
use serde_json::Value;

/// Floats whose bits a lossy path would change: signed zero, NaN with a payload, infinities,
/// a subnormal, the extremes.
fn awkward_floats() -> Vec<f64> {
    vec![
        0.0,
        -0.0,
        f64::from_bits(0x7ff8_0000_0000_0123),
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::from_bits(1),
        f64::MAX,
        -f64::MIN_POSITIVE,
        std::f64::consts::PI,
        1.0 / 3.0,
        -2.5e-300,
        7.0,
    ]
}

fn sample_file() -> H5File {
    let info = FileInfo {
        title: "round trip — ünïcode".to_string(),
        case_text: "title = \"x\"\n[model]\nmesh = \"a.msh\"\n".to_string(),
    };
    let mut file = H5File {
        root: file_attributes(&info, "test"),
    };
    let root = &mut file.root;
    root.set_attr("pi", Attr::F64(std::f64::consts::PI))
        .set_attr("count", Attr::I64(-42))
        .set_attr("big", Attr::U64(u64::MAX))
        .set_attr("list_f", Attr::F64s(vec![1.5, -2.0]))
        .set_attr("list_i", Attr::I64s(vec![i64::MIN, 0, i64::MAX]))
        .set_attr("list_u", Attr::U64s(vec![0, 1 << 63]))
        .set_attr(
            "names",
            Attr::Strs(vec!["a".into(), "bé".into(), "".into()]),
        );
    root.add(
        "scalar",
        Dataset::new(&[], Data::F64(vec![2.5]), "m", "a scalar"),
    );
    let g = root.group("numbers");
    g.set_attr("sweep_value", Attr::F64(113.0));
    g.add(
        "floats",
        Dataset::new(
            &[3, 4],
            Data::F64(awkward_floats()),
            "N",
            "awkward floats, 3×4",
        ),
    );
    g.add(
        "ints",
        Dataset::new(
            &[2, 1, 3],
            Data::I64(vec![i64::MIN, -1, 0, 1, 2, i64::MAX]),
            "1",
            "signed, 2×1×3",
        ),
    );
    g.add(
        "uints",
        Dataset::u64s(vec![0, 7, u64::MAX], "1", "unsigned"),
    );
    g.add("empty", Dataset::f64s(vec![], "s", "no values"));
    let complex: Vec<c64> = (0..6)
        .map(|j| c64::new(j as f64 + 0.25, -(j as f64) * 1e-3))
        .collect();
    let sub = g.group("deeper");
    sub.add(
        "complex",
        Dataset::new(&[2, 3], Data::Complex(complex), "m", "complex 2×3"),
    );
    sub.add(
        "words",
        Dataset::new(
            &[2],
            Data::Strings(vec!["stick".into(), "slip ü".into()]),
            "1",
            "strings",
        ),
    );
    let records = Records::new()
        .column("node_tag", Column::U64(vec![17, 17, 101]))
        .column("component", Column::U8(vec![0, 2, 1]))
        .column("offset", Column::I64(vec![-3, 0, 9]))
        .column("weight", Column::F64(vec![0.5, -0.25, 1e-9]))
        .column(
            "kind",
            Column::Enum {
                labels: vec!["physical".into(), "interface".into(), "modal".into()],
                codes: vec![0, 2, 1],
            },
        );
    root.group("records").add(
        "dofs",
        Dataset::records(records, "1", "compound records").with_attr("extra", Attr::I64(3)),
    );
    file
}

/// Bitwise equality of two files (f64 compared by bits, so NaN payloads and −0 count).
fn assert_bitwise_equal(a: &H5File, b: &H5File) {
    assert_eq!(format!("{:?}", bits(a)), format!("{:?}", bits(b)));
}

/// The file with every f64 replaced by its bit pattern (as an integer dataset/attribute).
fn bits(file: &H5File) -> H5File {
    let mut out = file.clone();
    bits_group(&mut out.root);
    out
}

fn bits_group(g: &mut nlrom::output::Group) {
    for attr in g.attrs.values_mut() {
        bits_attr(attr);
    }
    for ds in g.datasets.values_mut() {
        for attr in ds.attrs.values_mut() {
            bits_attr(attr);
        }
        ds.data = match &ds.data {
            Data::F64(v) => Data::U64(v.iter().map(|x| x.to_bits()).collect()),
            Data::Complex(v) => Data::U64(
                v.iter()
                    .flat_map(|z| [z.re.to_bits(), z.im.to_bits()])
                    .collect(),
            ),
            other => other.clone(),
        };
    }
    for sub in g.groups.values_mut() {
        bits_group(sub);
    }
}

fn bits_attr(a: &mut Attr) {
    let replaced = match &*a {
        Attr::F64(x) => Attr::U64(x.to_bits()),
        Attr::F64s(v) => Attr::U64s(v.iter().map(|x| x.to_bits()).collect()),
        other => other.clone(),
    };
    *a = replaced;
}

#[test]
fn round_trip_is_bitwise_exact() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("round.h5");
    let file = sample_file();
    file.write(&path).unwrap();
    let back = H5Reader::open(&path).unwrap().read_all().unwrap();
    assert_bitwise_equal(&file, &back);
    // the comparison itself can fail: flip one bit of one value
    let mut changed = back.clone();
    if let Data::F64(v) = &mut changed
        .root
        .groups
        .get_mut("numbers")
        .unwrap()
        .datasets
        .get_mut("floats")
        .unwrap()
        .data
    {
        v[0] = -0.0;
    }
    assert_ne!(
        format!("{:?}", bits(&file)),
        format!("{:?}", bits(&changed))
    );
    // nothing but the file itself is left in the directory
    let names: Vec<_> = std::fs::read_dir(dir.path())
        .unwrap()
        .map(|e| e.unwrap().file_name())
        .collect();
    assert_eq!(names, vec![std::ffi::OsString::from("round.h5")]);
}

#[test]
fn matrices_are_stored_row_major() {
    let m = Mat::<f64>::from_fn(2, 3, |i, j| (10 * i + j) as f64);
    let z = Mat::<c64>::from_fn(3, 2, |i, j| c64::new(i as f64, j as f64));
    let real = Dataset::real_matrix(&m, "N/m", "real");
    let complex = Dataset::complex_matrix(&z, "N/m", "complex");
    assert_eq!(real.shape, vec![2, 3]);
    assert_eq!(real.data, Data::F64(vec![0.0, 1.0, 2.0, 10.0, 11.0, 12.0]));
    assert_eq!(complex.shape, vec![3, 2]);
    let Data::Complex(values) = &complex.data else {
        panic!()
    };
    assert_eq!(values[1], c64::new(0.0, 1.0));
    assert_eq!(values[2], c64::new(1.0, 0.0));
}

/// h5py, the independent reader: dtypes (complex128 for `{r, i}`), shapes, values, compound field
/// names and types, enum labels, str attributes and the root attributes.
#[test]
fn h5py_reads_what_we_write() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("py.h5");
    sample_file().write(&path).unwrap();
    let script = r#"
import sys, json, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
def s(x):
    return x.decode() if isinstance(x, bytes) else str(x)
c = f["numbers/deeper/complex"]
d = f["records/dofs"]
kind_map = h5py.check_enum_dtype(d.dtype["kind"])
fl = f["numbers/floats"][()]
out = {
    "root_attrs": {k: s(f.attrs[k]) for k in ["program", "version", "file_kind", "title", "case_text", "created"]},
    "root_attr_types": {k: type(f.attrs[k]).__name__ for k in ["title", "case_text"]},
    "pi": float(f.attrs["pi"]), "count": int(f.attrs["count"]), "big": int(f.attrs["big"]),
    "list_i": [int(x) for x in f.attrs["list_i"]], "list_u": [int(x) for x in f.attrs["list_u"]],
    "names": [s(x) for x in f.attrs["names"]],
    "complex_dtype": str(c.dtype), "complex_shape": list(c.shape),
    "complex_re": c[()].real.ravel().tolist(), "complex_im": c[()].imag.ravel().tolist(),
    "complex_unit": s(c.attrs["unit"]),
    "floats_dtype": str(fl.dtype), "floats_shape": list(fl.shape),
    "floats_bits": [int(x) for x in fl.view(np.uint64).ravel()],
    "ints_dtype": str(f["numbers/ints"].dtype), "ints_shape": list(f["numbers/ints"].shape),
    "ints": [int(x) for x in f["numbers/ints"][()].ravel()],
    "uints_dtype": str(f["numbers/uints"].dtype), "uints": [int(x) for x in f["numbers/uints"][()]],
    "empty_shape": list(f["numbers/empty"].shape),
    "scalar_shape": list(f["scalar"].shape), "scalar": float(f["scalar"][()]),
    "words": [s(x) for x in f["numbers/deeper/words"][()]],
    "record_fields": list(d.dtype.names),
    "record_types": [str(d.dtype[n].base) for n in ["node_tag", "component", "offset", "weight"]],
    "node_tag": [int(x) for x in d["node_tag"]], "component": [int(x) for x in d["component"]],
    "weight": [float(x) for x in d["weight"]],
    "kind": [int(x) for x in d["kind"]], "kind_map": {k: int(v) for k, v in kind_map.items()},
    "sweep_value": float(f["numbers"].attrs["sweep_value"]),
    "description": s(d.attrs["description"]),
}
print(json.dumps(out))
"#;
    let out = support::python::run_python(script, &[path.as_path()]);
    let v: Value = serde_json::from_str(&out).unwrap();
    assert_eq!(v["root_attrs"]["program"], "nlrom");
    assert_eq!(v["root_attrs"]["version"], env!("CARGO_PKG_VERSION"));
    assert_eq!(v["root_attrs"]["file_kind"], "test");
    assert_eq!(v["root_attrs"]["title"], "round trip — ünïcode");
    assert_eq!(
        v["root_attrs"]["case_text"],
        "title = \"x\"\n[model]\nmesh = \"a.msh\"\n"
    );
    let created = v["root_attrs"]["created"].as_str().unwrap();
    assert!(
        created.len() == 20 && created.ends_with('Z') && created.starts_with("20"),
        "{created}"
    );
    assert_eq!(
        v["root_attr_types"]["title"], "str",
        "strings must come back as str, not bytes"
    );
    assert_eq!(v["pi"], std::f64::consts::PI);
    assert_eq!(v["count"], -42);
    assert_eq!(v["big"], u64::MAX);
    assert_eq!(v["list_i"], serde_json::json!([i64::MIN, 0, i64::MAX]));
    assert_eq!(v["list_u"], serde_json::json!([0u64, 1u64 << 63]));
    assert_eq!(v["names"], serde_json::json!(["a", "bé", ""]));
    assert_eq!(v["complex_dtype"], "complex128");
    assert_eq!(v["complex_shape"], serde_json::json!([2, 3]));
    for j in 0..6 {
        assert_eq!(v["complex_re"][j], j as f64 + 0.25);
        assert_eq!(v["complex_im"][j], -(j as f64) * 1e-3);
    }
    assert_eq!(v["complex_unit"], "m");
    assert_eq!(v["floats_dtype"], "float64");
    assert_eq!(v["floats_shape"], serde_json::json!([3, 4]));
    let expected_bits: Vec<u64> = awkward_floats().iter().map(|x| x.to_bits()).collect();
    assert_eq!(v["floats_bits"], serde_json::json!(expected_bits));
    assert_eq!(v["ints_dtype"], "int64");
    assert_eq!(v["ints_shape"], serde_json::json!([2, 1, 3]));
    assert_eq!(
        v["ints"],
        serde_json::json!([i64::MIN, -1, 0, 1, 2, i64::MAX])
    );
    assert_eq!(v["uints_dtype"], "uint64");
    assert_eq!(v["uints"], serde_json::json!([0u64, 7u64, u64::MAX]));
    assert_eq!(v["empty_shape"], serde_json::json!([0]));
    assert_eq!(v["scalar_shape"], serde_json::json!([]));
    assert_eq!(v["scalar"], 2.5);
    assert_eq!(v["words"], serde_json::json!(["stick", "slip ü"]));
    assert_eq!(
        v["record_fields"],
        serde_json::json!(["node_tag", "component", "offset", "weight", "kind"])
    );
    assert_eq!(
        v["record_types"],
        serde_json::json!(["uint64", "uint8", "int64", "float64"])
    );
    assert_eq!(v["node_tag"], serde_json::json!([17, 17, 101]));
    assert_eq!(v["component"], serde_json::json!([0, 2, 1]));
    assert_eq!(v["weight"], serde_json::json!([0.5, -0.25, 1e-9]));
    assert_eq!(v["kind"], serde_json::json!([0, 2, 1]));
    assert_eq!(
        v["kind_map"],
        serde_json::json!({"physical": 0, "interface": 1, "modal": 2})
    );
    assert_eq!(v["sweep_value"], 113.0);
    assert_eq!(v["description"], "compound records");
}

fn error_text(file: &H5File, path: &Path) -> String {
    file.write(path).unwrap_err().to_string()
}

/// A malformed dataset is refused with a message naming it, and the destination is untouched
/// (a previous file there survives) with no temporary file left behind.
#[test]
fn malformed_datasets_are_refused_and_nothing_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("out.h5");
    std::fs::write(&path, b"previous content").unwrap();

    let mut no_unit = H5File::new();
    let mut ds = Dataset::f64s(vec![1.0], "m", "x");
    ds.attrs.remove("unit");
    no_unit.root.group("a").add("x", ds);
    let msg = error_text(&no_unit, &path);
    assert!(msg.contains("/a/x") && msg.contains("unit"), "{msg}");

    let mut bad_shape = H5File::new();
    bad_shape.root.group("g").add(
        "y",
        Dataset::new(&[2, 2], Data::F64(vec![1.0; 3]), "m", "y"),
    );
    let msg = error_text(&bad_shape, &path);
    assert!(
        msg.contains("/g/y") && msg.contains("[2, 2]") && msg.contains("3 values"),
        "{msg}"
    );

    let mut ragged = H5File::new();
    let records = Records::new()
        .column("a", Column::I64(vec![1, 2]))
        .column("b", Column::I64(vec![1]));
    ragged.root.add("r", Dataset::records(records, "1", "r"));
    let msg = error_text(&ragged, &path);
    assert!(msg.contains("/r") && msg.contains("\"b\""), "{msg}");

    let mut bad_enum = H5File::new();
    let records = Records::new().column(
        "kind",
        Column::Enum {
            labels: vec!["a".into()],
            codes: vec![0, 1],
        },
    );
    bad_enum.root.add("e", Dataset::records(records, "1", "e"));
    let msg = error_text(&bad_enum, &path);
    assert!(msg.contains("/e") && msg.contains("code 1"), "{msg}");

    let mut bad_name = H5File::new();
    bad_name.root.group("a/b");
    let msg = error_text(&bad_name, &path);
    assert!(msg.contains("a/b"), "{msg}");

    assert_eq!(std::fs::read(&path).unwrap(), b"previous content");
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn atomic_write_replaces_and_cleans_up_on_failure() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("f.bin");
    write_atomic(&path, b"one").unwrap();
    write_atomic(&path, b"two").unwrap();
    assert_eq!(std::fs::read(&path).unwrap(), b"two");
    assert_eq!(
        temporary_path(&path).file_name().unwrap().to_str().unwrap(),
        format!("f.bin.tmp-{}", std::process::id())
    );
    // a destination that is a directory: the rename fails after the temporary file was written
    let blocked = dir.path().join("blocked");
    std::fs::create_dir(&blocked).unwrap();
    std::fs::write(blocked.join("inside"), b"x").unwrap();
    let err = write_atomic(&blocked, b"data").unwrap_err();
    assert!(err.to_string().contains("blocked"), "{err}");
    assert!(
        !temporary_path(&blocked).exists(),
        "temporary file left behind"
    );
    // a missing directory
    let err = write_atomic(&dir.path().join("no/such/dir/f.h5"), b"x").unwrap_err();
    assert!(err.to_string().contains("no/such/dir/f.h5"), "{err}");
    assert_eq!(err.exit_code(), 2);
}

#[test]
fn reader_errors_name_the_file_and_the_object() {
    let dir = tempfile::tempdir().unwrap();
    let text = dir.path().join("not.h5");
    std::fs::write(&text, "this is text").unwrap();
    let Err(err) = H5Reader::open(&text) else {
        panic!("text accepted as HDF5")
    };
    assert!(
        err.to_string().contains("not.h5") && err.to_string().contains("not an HDF5 file"),
        "{err}"
    );
    assert_eq!(err.exit_code(), 2);

    let path = dir.path().join("ok.h5");
    sample_file().write(&path).unwrap();
    // a truncated copy
    let bytes = std::fs::read(&path).unwrap();
    let cut = dir.path().join("cut.h5");
    std::fs::write(&cut, &bytes[..bytes.len() / 3]).unwrap();
    let cut_err = H5Reader::open(&cut).and_then(|r| r.read_all().map(|_| ()));
    let msg = cut_err.expect_err("truncated file read").to_string();
    assert!(msg.contains("cut.h5"), "{msg}");

    let reader = H5Reader::open(&path).unwrap();
    let msg = reader.dataset("/numbers/missing").unwrap_err().to_string();
    assert!(
        msg.contains("ok.h5") && msg.contains("/numbers/missing"),
        "{msg}"
    );
    let msg = reader.group("/nothing/here").unwrap_err().to_string();
    assert!(
        msg.contains("ok.h5") && msg.contains("/nothing/here"),
        "{msg}"
    );
    assert!(reader.has_group("/numbers/deeper"));
    assert!(!reader.has_group("/numbers/floats"));
    assert_eq!(reader.path(), path.as_path());
}
