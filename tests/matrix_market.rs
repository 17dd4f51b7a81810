//! Matrix Market import/export and the DOF map.

mod support;

use std::path::{Path, PathBuf};
use support::random::Lcg;

use faer::c64;
use faer::sparse::{SparseColMat, Triplet};
use nlrom::matrix_io::{
    parse_dof_map, read_dof_map, read_matrix_market, read_real_matrix, write_dof_map,
    write_matrix_market_general, write_matrix_market_symmetric, DofEntry, DofMap, SparseMatrix,
};
use nlrom::Error;

/// Writes `text` to `name` in a fresh temporary directory.
fn file_with(text: &str, name: &str) -> (tempfile::TempDir, PathBuf) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, text).unwrap();
    (dir, path)
}

/// Reads a real matrix from `text`.
fn read_real(text: &str) -> SparseColMat<usize, f64> {
    let (_dir, path) = file_with(text, "A.mtx");
    read_real_matrix(&path).unwrap()
}

/// Sorted (row, col, value) of a real matrix.
fn entries(m: &SparseColMat<usize, f64>) -> Vec<(usize, usize, f64)> {
    let mut v: Vec<_> = m
        .as_ref()
        .triplet_iter()
        .map(|t| (t.row, t.col, *t.val))
        .collect();
    v.sort_by_key(|e| (e.0, e.1));
    v
}

/// The message of the `Error::Input` that reading `text` (as `K.mtx`) gives, with the
/// temporary directory taken off the front (it must start with the file's full path).
fn read_error(text: &str) -> String {
    let (dir, path) = file_with(text, "K.mtx");
    let msg = match read_matrix_market(&path) {
        Err(Error::Input(m)) => m,
        other => panic!("expected Error::Input for\n{text}\ngot {other:?}"),
    };
    let prefix = format!("{}/", dir.path().display());
    match msg.strip_prefix(&prefix) {
        Some(rest) => rest.to_string(),
        None => panic!("the message does not start with the file's path: {msg}"),
    }
}

/// A random symmetric n×n matrix with values over many decades (and a few negative).
fn random_symmetric(n: usize, seed: u64) -> SparseColMat<usize, f64> {
    let mut rng = Lcg(seed);
    let mut t = Vec::new();
    for j in 0..n {
        t.push(Triplet::new(j, j, 1.0 + rng.next() * 1e9));
        for i in j + 1..n {
            if rng.next() < 0.2 {
                let exponent = (rng.next() * 40.0 - 20.0).floor() as i32;
                let v = (rng.next() - 0.5) * 10f64.powi(exponent);
                t.push(Triplet::new(i, j, v));
                t.push(Triplet::new(j, i, v));
            }
        }
    }
    SparseColMat::try_new_from_triplets(n, n, &t).unwrap()
}

#[test]
fn random_symmetric_round_trip_is_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let a = random_symmetric(60, 7);
    let path = dir.path().join("K.mtx");
    write_matrix_market_symmetric(&path, &a).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(text.starts_with("%%MatrixMarket matrix coordinate real symmetric\n"));
    let b = read_real_matrix(&path).unwrap();
    let (ea, eb) = (entries(&a), entries(&b));
    assert_eq!(ea.len(), eb.len());
    for (x, y) in ea.iter().zip(&eb) {
        assert_eq!((x.0, x.1, x.2.to_bits()), (y.0, y.1, y.2.to_bits()));
    }
    // only the lower triangle is stored: n diagonal + half the off-diagonal entries
    let stored = text.lines().filter(|l| !l.starts_with('%')).count() - 1;
    assert_eq!(stored, (ea.len() + 60) / 2);
    assert!(!dir.path().join("K.mtx.tmp").exists());
}

#[test]
fn general_round_trip_is_bit_exact() {
    let dir = tempfile::tempdir().unwrap();
    let t = [
        Triplet::new(0, 2, std::f64::consts::PI),
        Triplet::new(1, 0, -1e-300),
        Triplet::new(1, 2, 0.1 + 0.2),
    ];
    let a = SparseColMat::try_new_from_triplets(2, 3, &t).unwrap();
    let path = dir.path().join("G.mtx");
    write_matrix_market_general(&path, &a).unwrap();
    let b = read_real_matrix(&path).unwrap();
    assert_eq!((b.nrows(), b.ncols()), (2, 3));
    let eb = entries(&b);
    assert_eq!(
        eb,
        [
            (0, 2, std::f64::consts::PI),
            (1, 0, -1e-300),
            (1, 2, 0.1 + 0.2)
        ]
    );
    assert_eq!(eb[2].2.to_bits(), (0.1f64 + 0.2).to_bits());
}

#[test]
fn writing_an_unsymmetric_matrix_as_symmetric_fails() {
    let dir = tempfile::tempdir().unwrap();
    let t = [Triplet::new(0, 1, 1.0), Triplet::new(1, 0, 2.0)];
    let a = SparseColMat::try_new_from_triplets(2, 2, &t).unwrap();
    let path = dir.path().join("A.mtx");
    let msg = write_matrix_market_symmetric(&path, &a)
        .unwrap_err()
        .to_string();
    assert!(
        msg.contains("A.mtx") && msg.contains("not symmetric"),
        "{msg}"
    );
    assert!(!path.exists());
}

#[test]
fn symmetric_file_expands_to_the_full_matrix() {
    let text = "%%MatrixMarket matrix coordinate real symmetric\n\
                % a comment\n\
                \n\
                3 3 4\n\
                1 1 4.0\n\
                2 1 -1.5\n\
                3 2 2e-3\n\
                3 3 7\n";
    let a = read_real(text);
    assert_eq!((a.nrows(), a.ncols()), (3, 3));
    assert_eq!(
        entries(&a),
        [
            (0, 0, 4.0),
            (0, 1, -1.5),
            (1, 0, -1.5),
            (1, 2, 2e-3),
            (2, 1, 2e-3),
            (2, 2, 7.0)
        ]
    );
}

#[test]
fn upper_triangle_storage_is_accepted_too() {
    let text = "%%MatrixMarket matrix coordinate real symmetric\n2 2 2\n1 2 3.0\n2 2 1.0\n";
    assert_eq!(
        entries(&read_real(text)),
        [(0, 1, 3.0), (1, 0, 3.0), (1, 1, 1.0)]
    );
}

#[test]
fn duplicates_are_summed_and_integers_read() {
    let text = "%%MatrixMarket matrix coordinate integer general\n2 2 3\n1 2 3\n1 2 -5\n2 1 4\n";
    assert_eq!(entries(&read_real(text)), [(0, 1, -2.0), (1, 0, 4.0)]);
}

#[test]
fn skew_symmetric_file_expands_with_the_sign() {
    let text = "%%MatrixMarket matrix coordinate real skew-symmetric\n3 3 2\n2 1 1.5\n3 1 -2\n";
    assert_eq!(
        entries(&read_real(text)),
        [(0, 1, -1.5), (0, 2, 2.0), (1, 0, 1.5), (2, 0, -2.0)]
    );
}

#[test]
fn array_files_are_read_column_major() {
    let general = "%%MatrixMarket matrix array real general\n2 3\n1\n2\n0\n4\n5\n0\n";
    assert_eq!(
        entries(&read_real(general)),
        [(0, 0, 1.0), (0, 2, 5.0), (1, 0, 2.0), (1, 1, 4.0)]
    );
    let symmetric = "%%MatrixMarket matrix array real symmetric\n3 3\n1\n2\n3\n4\n5\n6\n";
    assert_eq!(
        entries(&read_real(symmetric)),
        [
            (0, 0, 1.0),
            (0, 1, 2.0),
            (0, 2, 3.0),
            (1, 0, 2.0),
            (1, 1, 4.0),
            (1, 2, 5.0),
            (2, 0, 3.0),
            (2, 1, 5.0),
            (2, 2, 6.0)
        ]
    );
}

#[test]
fn complex_hermitian_expands_to_the_conjugate() {
    let text = "%%MatrixMarket matrix coordinate complex hermitian\n\
                2 2 3\n\
                1 1 2.0 0.0\n\
                2 1 1.0 -3.0\n\
                2 2 5.0 0.0\n";
    let (_dir, path) = file_with(text, "H.mtx");
    let SparseMatrix::Complex(h) = read_matrix_market(&path).unwrap() else {
        panic!("expected a complex matrix")
    };
    let mut e: Vec<_> = h
        .as_ref()
        .triplet_iter()
        .map(|t| (t.row, t.col, *t.val))
        .collect();
    e.sort_by_key(|e| (e.0, e.1));
    assert_eq!(
        e,
        [
            (0, 0, c64::new(2.0, 0.0)),
            (0, 1, c64::new(1.0, 3.0)),
            (1, 0, c64::new(1.0, -3.0)),
            (1, 1, c64::new(5.0, 0.0))
        ]
    );
    let msg = read_real_matrix(&path).unwrap_err().to_string();
    assert!(msg.contains("H.mtx") && msg.contains("complex"), "{msg}");
}

#[test]
fn malformed_files_name_the_file_and_the_line() {
    let cases: [(&str, &str); 14] = [
        ("%%MatrixMarket matrix coordinat real general\n1 1 1\n1 1 1\n", "K.mtx: line 1: unknown format 'coordinat'"),
        ("% not a banner\n1 1 1\n1 1 1\n", "K.mtx: line 1: not a Matrix Market file"),
        ("", "K.mtx: line 1: empty file"),
        ("%%MatrixMarket matrix coordinate pattern general\n1 1 1\n1 1\n", "K.mtx: line 1: `pattern` matrices"),
        ("%%MatrixMarket matrix coordinate real general\n% c\n2 2\n", "K.mtx: line 3: size line: expected 3 fields (rows columns entries), found 2"),
        ("%%MatrixMarket matrix coordinate real symmetric\n2 3 1\n1 1 1\n", "K.mtx: line 2: a symmetric matrix must be square"),
        ("%%MatrixMarket matrix coordinate real general\n3 3 2\n1 1 1.0\n2 2\n", "K.mtx: line 4: expected 3 fields (row col value), found 2"),
        ("%%MatrixMarket matrix coordinate real general\n3 3 2\n1 1 1.0\n4 1 2.0\n", "K.mtx: line 4: row index 4 is out of range 1..=3"),
        ("%%MatrixMarket matrix coordinate real general\n3 3 1\n1 0 1.0\n", "K.mtx: line 3: column index 0 is out of range 1..=3 (indices are 1-based)"),
        ("%%MatrixMarket matrix coordinate real general\n3 3 3\n1 1 1.0\n2 2 1.0\n", "K.mtx: line 5: end of file after 2 entries, but the size line declares 3"),
        ("%%MatrixMarket matrix coordinate real general\n3 3 1\n1 1 1.0\n2 2 1.0\n", "K.mtx: line 4: more entries than the size line declares"),
        ("%%MatrixMarket matrix coordinate real general\n3 3 2\n1 1 1.0\n2 2 abc\n", "K.mtx: line 4: 'abc' is not a number"),
        ("%%MatrixMarket matrix coordinate real general\n3 3 1\n1 1 nan\n", "K.mtx: line 3: value 'nan' is not finite"),
        ("%%MatrixMarket matrix coordinate real symmetric\n3 3 2\n2 1 1.0\n1 3 1.0\n", "K.mtx: line 4: entry (1, 3) is above the diagonal, but line 3 stores the other triangle"),
    ];
    assert_errors_start_with(&cases);
}

/// Every (file text, expected message start) pair: reading the text fails with that message.
fn assert_errors_start_with(cases: &[(&str, &str)]) {
    for (text, expected) in cases {
        let msg = read_error(text);
        assert!(
            msg.starts_with(expected),
            "expected '{expected}', got '{msg}'"
        );
    }
}

#[test]
fn more_malformed_files() {
    let cases: [(&str, &str); 4] = [
        (
            "%%MatrixMarket matrix coordinate integer general\n1 1 1\n1 1 1.5\n",
            "K.mtx: line 3: '1.5' is not an integer",
        ),
        (
            "%%MatrixMarket matrix coordinate complex general\n1 1 1\n1 1 1.5\n",
            "K.mtx: line 3: expected 4 fields (row col real imag), found 3",
        ),
        (
            "%%MatrixMarket matrix coordinate complex hermitian\n1 1 1\n1 1 1.5 2.0\n",
            "K.mtx: line 3: diagonal entry (1, 1) of a hermitian matrix has imaginary part 2",
        ),
        (
            "%%MatrixMarket matrix array real general\n2 2\n1\n2\n3\n",
            "K.mtx: line 6: end of file after 3 values, but a 2 x 2 general array needs 4",
        ),
    ];
    assert_errors_start_with(&cases);
}

#[test]
fn missing_file_is_an_io_error_naming_it() {
    let err = read_matrix_market(Path::new("/nonexistent/K.mtx")).unwrap_err();
    assert!(matches!(err, Error::Io { .. }));
    assert!(err.to_string().starts_with("/nonexistent/K.mtx: "));
    assert_eq!(err.exit_code(), 2);
}

#[test]
fn dof_map_round_trip() {
    let dir = tempfile::tempdir().unwrap();
    let map = DofMap::structural(&[3, 7, 12]);
    assert_eq!(map.len(), 9);
    assert_eq!(
        map.entries[4],
        DofEntry {
            row: 4,
            node_tag: 7,
            component: 1
        }
    );
    assert_eq!(map.row_of(12, 2), Some(8));
    let path = dir.path().join("dofs.csv");
    write_dof_map(&path, &map).unwrap();
    let text = std::fs::read_to_string(&path).unwrap();
    assert!(
        text.starts_with("row,node_tag,component\n0,3,0\n1,3,1\n2,3,2\n3,7,0\n"),
        "{text}"
    );
    assert_eq!(read_dof_map(&path).unwrap(), map);
}

#[test]
fn dof_map_accepts_letters_and_blank_lines() {
    let map = parse_dof_map("row,node_tag,component\n1, 5, y\n\n0,5,x\n", "dofs.csv").unwrap();
    assert_eq!(
        map.entries,
        [
            DofEntry {
                row: 1,
                node_tag: 5,
                component: 1
            },
            DofEntry {
                row: 0,
                node_tag: 5,
                component: 0
            }
        ]
    );
}

#[test]
fn malformed_dof_maps_name_the_line() {
    let cases = [
        (
            "row,node,component\n0,1,0\n",
            "dofs.csv: line 1: expected the header `row,node_tag,component`",
        ),
        (
            "row,node_tag,component\n0,1,0\n1,1\n",
            "dofs.csv: line 3: expected 3 comma-separated fields",
        ),
        (
            "row,node_tag,component\n0,1,3\n",
            "dofs.csv: line 2: component '3' is not 0, 1 or 2",
        ),
        (
            "row,node_tag,component\n0,-1,0\n",
            "dofs.csv: line 2: node tag '-1' is not a non-negative integer",
        ),
        (
            "row,node_tag,component\n0,1,0\n0,2,0\n",
            "dofs.csv: line 3: row 0 is already listed on line 2",
        ),
        (
            "row,node_tag,component\n0,1,0\n1,1,0\n",
            "dofs.csv: line 3: node 1 component 0 is already listed on line 2",
        ),
        ("", "dofs.csv: line 1: empty file"),
    ];
    for (text, expected) in cases {
        let msg = match parse_dof_map(text, "dofs.csv") {
            Err(Error::Input(m)) => m,
            other => panic!("{other:?}"),
        };
        assert!(
            msg.starts_with(expected),
            "expected '{expected}', got '{msg}'"
        );
    }
}
