//! Matrix Market import/export and the DOF map (`dofs.csv`).
//!
//! Reading accepts the `coordinate` and `array` formats with the `real`, `integer` and `complex`
//! fields and the `general`, `symmetric`, `skew-symmetric` and `hermitian` symmetries (a `real
//! hermitian` file is read as symmetric). Symmetric storage is expanded to the full matrix and
//! duplicate coordinate entries are summed. Every error is an [`Error::Input`] that names the file
//! and the line, e.g. `K.mtx: line 17: expected 3 fields (row col value), found 2`.
//!
//! Writing produces coordinate files with 17 significant digits, so a write/read round trip is
//! bit-exact; files are written to `<path>.tmp` in the same directory and then renamed, so a reader
//! never sees a half-written file.
//!
//! The DOF map relates matrix rows to mesh nodes: `dofs.csv` has the header `row,node_tag,component`
//! and one line per row, component 0/1/2 for x/y/z (`docs/conventions.md` §1).

use std::collections::HashMap;
use std::fmt::Write as _;
use std::io::Write as _;
use std::path::{Path, PathBuf};

use faer::c64;
use faer::sparse::{SparseColMat, Triplet};

use crate::error::{Error, Result};

/// A sparse matrix read from a Matrix Market file: real (`real`/`integer` fields) or complex.
#[derive(Clone, Debug)]
pub enum SparseMatrix {
    /// A matrix of a `real` or `integer` file.
    Real(SparseColMat<usize, f64>),
    /// A matrix of a `complex` file.
    Complex(SparseColMat<usize, c64>),
}

impl SparseMatrix {
    /// Number of rows.
    pub fn nrows(&self) -> usize {
        match self {
            SparseMatrix::Real(m) => m.nrows(),
            SparseMatrix::Complex(m) => m.nrows(),
        }
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        match self {
            SparseMatrix::Real(m) => m.ncols(),
            SparseMatrix::Complex(m) => m.ncols(),
        }
    }
}

/// Reads a Matrix Market file (coordinate or array; real, integer or complex; any symmetry).
pub fn read_matrix_market(path: &Path) -> Result<SparseMatrix> {
    let text = read_text(path)?;
    parse_matrix_market(&text, &path.display().to_string())
}

/// Reads a Matrix Market file that must hold a real matrix (`real` or `integer` field).
pub fn read_real_matrix(path: &Path) -> Result<SparseColMat<usize, f64>> {
    match read_matrix_market(path)? {
        SparseMatrix::Real(m) => Ok(m),
        SparseMatrix::Complex(_) => Err(Error::input(format!(
            "{}: line 1: the matrix is complex, but a real matrix is needed here; write it with the `real` field",
            path.display()
        ))),
    }
}

/// Parses the text of a Matrix Market file; `name` is the file name used in messages.
pub fn parse_matrix_market(text: &str, name: &str) -> Result<SparseMatrix> {
    let mut lines = DataLines::new(text, name);
    let header = Header::parse(&mut lines)?;
    let mut full = FullStorage::new(&header);
    match header.format {
        Format::Coordinate => read_coordinate(&mut lines, &header, &mut full)?,
        Format::Array => read_array(&mut lines, &header, &mut full)?,
    };
    lines.expect_end()?;
    full.build(&header, name)
}

/// Reads a whole file as UTF-8 text; errors name the file.
fn read_text(path: &Path) -> Result<String> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    String::from_utf8(bytes).map_err(|e| {
        Error::input(format!(
            "{}: not a text file (invalid UTF-8 at byte {}); Matrix Market and CSV files are plain text",
            path.display(),
            e.utf8_error().valid_up_to()
        ))
    })
}

// ---------------------------------------------------------------------------------------------
// Reading: lines and header
// ---------------------------------------------------------------------------------------------

/// The lines of a file with their 1-based numbers, skipping comments (`%`) and blank lines.
struct DataLines<'a> {
    name: &'a str,
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    /// Number of the last line handed out (0 before the first).
    last: usize,
}

impl<'a> DataLines<'a> {
    fn new(text: &'a str, name: &'a str) -> Self {
        DataLines {
            name,
            lines: text.lines().enumerate(),
            last: 0,
        }
    }

    /// The next raw line (comments included), with its number.
    fn next_raw(&mut self) -> Option<(usize, &'a str)> {
        let (i, line) = self.lines.next()?;
        self.last = i + 1;
        Some((i + 1, line))
    }

    /// The next line that is neither blank nor a comment, with its number.
    fn next_data(&mut self) -> Option<(usize, &'a str)> {
        loop {
            let (no, line) = self.next_raw()?;
            let t = line.trim();
            if !t.is_empty() && !t.starts_with('%') {
                return Some((no, t));
            }
        }
    }

    /// An input error at `line`.
    fn err(&self, line: usize, msg: impl std::fmt::Display) -> Error {
        Error::input(format!("{}: line {}: {}", self.name, line, msg))
    }

    /// Errors if another data line follows.
    fn expect_end(&mut self) -> Result<()> {
        match self.next_data() {
            None => Ok(()),
            Some((no, _)) => Err(self.err(
                no,
                "more entries than the size line declares; correct the entry count or remove the extra lines",
            )),
        }
    }
}

/// Storage format of a Matrix Market file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Format {
    Coordinate,
    Array,
}

/// Value field of a Matrix Market file (`pattern` is rejected).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Field {
    Real,
    Integer,
    Complex,
}

/// Symmetry of a Matrix Market file.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Symmetry {
    General,
    Symmetric,
    SkewSymmetric,
    Hermitian,
}

/// The banner and the size line.
#[derive(Clone, Copy, Debug)]
struct Header {
    format: Format,
    field: Field,
    symmetry: Symmetry,
    nrows: usize,
    ncols: usize,
    /// Declared number of stored entries (coordinate) or values (array, derived from the shape).
    count: usize,
}

const BANNER_HELP: &str =
    "expected a banner like `%%MatrixMarket matrix coordinate real symmetric`";

impl Header {
    /// Parses the banner (line 1) and the size line.
    fn parse(lines: &mut DataLines) -> Result<Header> {
        let (no, banner) = lines
            .next_raw()
            .ok_or_else(|| lines.err(1, format!("empty file; {BANNER_HELP}")))?;
        let (format, field, symmetry) = parse_banner(banner).map_err(|m| lines.err(no, m))?;
        let (no, size) = lines.next_data().ok_or_else(|| {
            lines.err(lines.last + 1, "missing size line (rows columns [entries])")
        })?;
        let mut h = Header {
            format,
            field,
            symmetry,
            nrows: 0,
            ncols: 0,
            count: 0,
        };
        h.parse_size(size).map_err(|m| lines.err(no, m))?;
        Ok(h)
    }

    /// Parses the size line: `M N NNZ` (coordinate) or `M N` (array).
    fn parse_size(&mut self, line: &str) -> std::result::Result<(), String> {
        let fields: Vec<&str> = line.split_ascii_whitespace().collect();
        let want = match self.format {
            Format::Coordinate => 3,
            Format::Array => 2,
        };
        if fields.len() != want {
            let what = match self.format {
                Format::Coordinate => "rows columns entries",
                Format::Array => "rows columns",
            };
            return Err(format!(
                "size line: expected {want} fields ({what}), found {}",
                fields.len()
            ));
        }
        let nums: Vec<usize> = fields
            .iter()
            .map(|f| {
                f.parse::<usize>()
                    .map_err(|_| format!("size line: '{f}' is not a non-negative integer"))
            })
            .collect::<std::result::Result<_, _>>()?;
        self.nrows = nums[0];
        self.ncols = nums[1];
        if self.symmetry != Symmetry::General && self.nrows != self.ncols {
            return Err(format!(
                "a {} matrix must be square, but the size line says {} x {}",
                symmetry_name(self.symmetry),
                self.nrows,
                self.ncols
            ));
        }
        self.count = match self.format {
            Format::Coordinate => nums[2],
            Format::Array => self.array_count(),
        };
        Ok(())
    }

    /// Number of values an array file stores for its shape and symmetry.
    fn array_count(&self) -> usize {
        let n = self.ncols;
        match self.symmetry {
            Symmetry::General => self.nrows * self.ncols,
            Symmetry::Symmetric | Symmetry::Hermitian => n * (n + 1) / 2,
            Symmetry::SkewSymmetric => n * n.saturating_sub(1) / 2,
        }
    }

    /// Number of value fields per entry (1 real, 2 complex).
    fn value_fields(&self) -> usize {
        if self.field == Field::Complex {
            2
        } else {
            1
        }
    }
}

/// Parses `%%MatrixMarket matrix <format> <field> <symmetry>` (case-insensitive).
fn parse_banner(line: &str) -> std::result::Result<(Format, Field, Symmetry), String> {
    let words: Vec<String> = line
        .split_ascii_whitespace()
        .map(str::to_ascii_lowercase)
        .collect();
    if words.first().map(String::as_str) != Some("%%matrixmarket") {
        return Err(format!("not a Matrix Market file; {BANNER_HELP}"));
    }
    if words.len() != 5 {
        return Err(format!(
            "the banner has {} words, expected 5; {BANNER_HELP}",
            words.len()
        ));
    }
    if words[1] != "matrix" {
        return Err(format!(
            "object '{}' is not supported; only `matrix` is",
            words[1]
        ));
    }
    let format = match words[2].as_str() {
        "coordinate" => Format::Coordinate,
        "array" => Format::Array,
        f => {
            return Err(format!(
                "unknown format '{f}'; expected `coordinate` or `array`"
            ))
        }
    };
    let field = match words[3].as_str() {
        "real" | "double" => Field::Real,
        "integer" => Field::Integer,
        "complex" => Field::Complex,
        "pattern" => {
            return Err(
                "`pattern` matrices carry no values; write the matrix with the `real` field".into(),
            )
        }
        f => {
            return Err(format!(
                "unknown field '{f}'; expected `real`, `integer` or `complex`"
            ))
        }
    };
    let symmetry = match words[4].as_str() {
        "general" => Symmetry::General,
        "symmetric" => Symmetry::Symmetric,
        "skew-symmetric" => Symmetry::SkewSymmetric,
        "hermitian" if field == Field::Complex => Symmetry::Hermitian,
        "hermitian" => Symmetry::Symmetric,
        s => return Err(format!(
            "unknown symmetry '{s}'; expected `general`, `symmetric`, `skew-symmetric` or `hermitian`"
        )),
    };
    Ok((format, field, symmetry))
}

/// The banner word of a symmetry.
fn symmetry_name(s: Symmetry) -> &'static str {
    match s {
        Symmetry::General => "general",
        Symmetry::Symmetric => "symmetric",
        Symmetry::SkewSymmetric => "skew-symmetric",
        Symmetry::Hermitian => "hermitian",
    }
}

// ---------------------------------------------------------------------------------------------
// Reading: entries
// ---------------------------------------------------------------------------------------------

/// One stored entry, 0-based, with its value as (re, im).
#[derive(Clone, Copy, Debug)]
struct Entry {
    row: usize,
    col: usize,
    re: f64,
    im: f64,
}

/// Parses one value field; `integer` files must hold integers, every value must be finite.
fn parse_value(field: Field, s: &str) -> std::result::Result<f64, String> {
    let v = if field == Field::Integer {
        s.parse::<i64>().map(|i| i as f64).map_err(|_| {
            format!("'{s}' is not an integer (the file declares the `integer` field)")
        })?
    } else {
        s.parse::<f64>()
            .map_err(|_| format!("'{s}' is not a number"))?
    };
    if v.is_finite() {
        Ok(v)
    } else {
        Err(format!("value '{s}' is not finite"))
    }
}

/// Parses a 1-based index in `1..=max`; `what` is "row" or "column".
fn parse_index(s: &str, max: usize, what: &str) -> std::result::Result<usize, String> {
    let i: usize = s
        .parse()
        .map_err(|_| format!("{what} index '{s}' is not a positive integer"))?;
    if i == 0 || i > max {
        return Err(format!(
            "{what} index {i} is out of range 1..={max} (indices are 1-based)"
        ));
    }
    Ok(i - 1)
}

/// The value fields of one entry as (re, im).
fn parse_values(h: &Header, fields: &[&str]) -> std::result::Result<(f64, f64), String> {
    let re = parse_value(h.field, fields[0])?;
    let im = if h.field == Field::Complex {
        parse_value(h.field, fields[1])?
    } else {
        0.0
    };
    Ok((re, im))
}

/// Parses one coordinate line `i j value [imag]`.
fn parse_coordinate_line(h: &Header, line: &str) -> std::result::Result<Entry, String> {
    let fields: Vec<&str> = line.split_ascii_whitespace().collect();
    let want = 2 + h.value_fields();
    if fields.len() != want {
        let what = if h.field == Field::Complex {
            "row col real imag"
        } else {
            "row col value"
        };
        return Err(format!(
            "expected {want} fields ({what}), found {}",
            fields.len()
        ));
    }
    let row = parse_index(fields[0], h.nrows, "row")?;
    let col = parse_index(fields[1], h.ncols, "column")?;
    let (re, im) = parse_values(h, &fields[2..])?;
    Ok(Entry { row, col, re, im })
}

/// Which triangle the off-diagonal entries of a symmetric file use (the first line of each).
#[derive(Default)]
struct Triangles {
    lower: Option<usize>,
    upper: Option<usize>,
}

impl Triangles {
    /// Records an entry; errors if the file mixes strictly-lower and strictly-upper entries.
    fn record(&mut self, e: &Entry, line: usize) -> std::result::Result<(), String> {
        use std::cmp::Ordering::*;
        let (mine, other, side) = match e.row.cmp(&e.col) {
            Equal => return Ok(()),
            Greater => (&mut self.lower, self.upper, "below"),
            Less => (&mut self.upper, self.lower, "above"),
        };
        mine.get_or_insert(line);
        match other {
            Some(first) => Err(format!(
                "entry ({}, {}) is {side} the diagonal, but line {first} stores the other triangle; \
                 a symmetric file stores one triangle only (the lower: row >= column)",
                e.row + 1,
                e.col + 1
            )),
            None => Ok(()),
        }
    }
}

/// Reads the entries of a coordinate file, checking the declared count.
fn read_coordinate(lines: &mut DataLines, h: &Header, full: &mut FullStorage) -> Result<()> {
    let mut triangles = Triangles::default();
    for k in 0..h.count {
        let Some((no, line)) = lines.next_data() else {
            return Err(lines.err(
                lines.last + 1,
                format!(
                    "end of file after {k} entries, but the size line declares {}; the file is truncated or the count is wrong",
                    h.count
                ),
            ));
        };
        let e = parse_coordinate_line(h, line).map_err(|m| lines.err(no, m))?;
        if h.symmetry != Symmetry::General {
            triangles.record(&e, no).map_err(|m| lines.err(no, m))?;
        }
        full.add(e, h.symmetry).map_err(|m| lines.err(no, m))?;
    }
    Ok(())
}

/// The first stored row of column `col` of an array file: 0 (general), `col` (symmetric lower
/// triangle with the diagonal) or `col + 1` (skew-symmetric, strictly lower).
fn first_array_row(h: &Header, col: usize) -> usize {
    match h.symmetry {
        Symmetry::General => 0,
        Symmetry::Symmetric | Symmetry::Hermitian => col,
        Symmetry::SkewSymmetric => col + 1,
    }
}

/// Reads the values of an array file; zeros are dropped.
fn read_array(lines: &mut DataLines, h: &Header, full: &mut FullStorage) -> Result<()> {
    let (mut row, mut col) = (first_array_row(h, 0), 0);
    for k in 0..h.count {
        let Some((no, line)) = lines.next_data() else {
            return Err(lines.err(
                lines.last + 1,
                format!(
                    "end of file after {k} values, but a {} x {} {} array needs {}",
                    h.nrows,
                    h.ncols,
                    symmetry_name(h.symmetry),
                    h.count
                ),
            ));
        };
        let fields: Vec<&str> = line.split_ascii_whitespace().collect();
        if fields.len() != h.value_fields() {
            return Err(lines.err(
                no,
                format!(
                    "expected {} value field(s) per line in an array file, found {}",
                    h.value_fields(),
                    fields.len()
                ),
            ));
        }
        let (re, im) = parse_values(h, &fields).map_err(|m| lines.err(no, m))?;
        if re != 0.0 || im != 0.0 {
            let e = Entry { row, col, re, im };
            full.add(e, h.symmetry).map_err(|m| lines.err(no, m))?;
        }
        (row, col) = next_array_position(h, row, col);
    }
    Ok(())
}

/// The position after (row, col) in array order.
fn next_array_position(h: &Header, row: usize, col: usize) -> (usize, usize) {
    if row + 1 < h.nrows {
        return (row + 1, col);
    }
    (first_array_row(h, col + 1), col + 1)
}

/// The full-storage triplets of the matrix being read (real or complex, by the file's field).
struct FullStorage {
    complex: bool,
    real: Vec<Triplet<usize, usize, f64>>,
    cplx: Vec<Triplet<usize, usize, c64>>,
}

impl FullStorage {
    fn new(h: &Header) -> Self {
        FullStorage {
            complex: h.field == Field::Complex,
            real: Vec::new(),
            cplx: Vec::new(),
        }
    }

    /// Stores one value at (row, col).
    fn push(&mut self, row: usize, col: usize, re: f64, im: f64) {
        if self.complex {
            self.cplx.push(Triplet::new(row, col, c64::new(re, im)));
        } else {
            self.real.push(Triplet::new(row, col, re));
        }
    }

    /// Stores a file entry and, for symmetric storage, its mirror image.
    fn add(&mut self, e: Entry, sym: Symmetry) -> std::result::Result<(), String> {
        let diagonal = e.row == e.col;
        match sym {
            Symmetry::Hermitian if diagonal && e.im != 0.0 => {
                return Err(format!(
                    "diagonal entry ({0}, {0}) of a hermitian matrix has imaginary part {1}; it must be real",
                    e.row + 1,
                    e.im
                ))
            }
            Symmetry::SkewSymmetric if diagonal && (e.re != 0.0 || e.im != 0.0) => {
                return Err(format!(
                    "diagonal entry ({0}, {0}) of a skew-symmetric matrix must be zero",
                    e.row + 1
                ))
            }
            _ => {}
        }
        self.push(e.row, e.col, e.re, e.im);
        if !diagonal {
            let (re, im) = match sym {
                Symmetry::General => return Ok(()),
                Symmetry::Symmetric => (e.re, e.im),
                Symmetry::Hermitian => (e.re, -e.im),
                Symmetry::SkewSymmetric => (-e.re, -e.im),
            };
            self.push(e.col, e.row, re, im);
        }
        Ok(())
    }

    /// Builds the matrix (duplicates summed).
    fn build(self, h: &Header, name: &str) -> Result<SparseMatrix> {
        if self.complex {
            from_triplets(h, &self.cplx, name).map(SparseMatrix::Complex)
        } else {
            from_triplets(h, &self.real, name).map(SparseMatrix::Real)
        }
    }
}

/// Builds a faer matrix from full-storage triplets (duplicates are summed).
fn from_triplets<T: faer::traits::ComplexField + Clone>(
    h: &Header,
    t: &[Triplet<usize, usize, T>],
    name: &str,
) -> Result<SparseColMat<usize, T>> {
    SparseColMat::try_new_from_triplets(h.nrows, h.ncols, t).map_err(|e| {
        Error::input(format!(
            "{name}: cannot build the {} x {} sparse matrix: {e:?}",
            h.nrows, h.ncols
        ))
    })
}

// ---------------------------------------------------------------------------------------------
// Writing
// ---------------------------------------------------------------------------------------------

/// Writes a real symmetric matrix as `%%MatrixMarket matrix coordinate real symmetric`: the lower
/// triangle (row ≥ column), values with 17 significant digits (bit-exact round trip).
///
/// The matrix must be square, finite and symmetric to a relative tolerance of 1e-12 of its largest
/// entry; otherwise an [`Error::Input`] names the offending entry (use
/// [`write_matrix_market_general`] for unsymmetric matrices). The file is written atomically.
pub fn write_matrix_market_symmetric(path: &Path, m: &SparseColMat<usize, f64>) -> Result<()> {
    let name = path.display();
    if m.nrows() != m.ncols() {
        return Err(Error::input(format!(
            "{name}: cannot write a {} x {} matrix as symmetric; it is not square",
            m.nrows(),
            m.ncols()
        )));
    }
    let entries = finite_triplets(m, path)?;
    check_symmetric(&entries, path)?;
    let lower: Vec<&(usize, usize, f64)> = entries.iter().filter(|(r, c, _)| r >= c).collect();
    let mut text = String::with_capacity(32 * lower.len() + 128);
    write_header(&mut text, "symmetric", m.nrows(), m.ncols(), lower.len());
    for (r, c, v) in lower {
        push_entry(&mut text, *r, *c, *v);
    }
    write_atomic(path, text.as_bytes())
}

/// Writes a real matrix as `%%MatrixMarket matrix coordinate real general` (all stored entries,
/// 17 significant digits). Non-finite values are an error. The file is written atomically.
pub fn write_matrix_market_general(path: &Path, m: &SparseColMat<usize, f64>) -> Result<()> {
    let entries = finite_triplets(m, path)?;
    let mut text = String::with_capacity(32 * entries.len() + 128);
    write_header(&mut text, "general", m.nrows(), m.ncols(), entries.len());
    for (r, c, v) in &entries {
        push_entry(&mut text, *r, *c, *v);
    }
    write_atomic(path, text.as_bytes())
}

/// The stored entries (0-based row, column, value); errors on a non-finite value.
fn finite_triplets(m: &SparseColMat<usize, f64>, path: &Path) -> Result<Vec<(usize, usize, f64)>> {
    let mut out = Vec::new();
    for t in m.as_ref().triplet_iter() {
        if !t.val.is_finite() {
            return Err(Error::input(format!(
                "{}: cannot write entry ({}, {}) = {}: Matrix Market values must be finite",
                path.display(),
                t.row + 1,
                t.col + 1,
                t.val
            )));
        }
        out.push((t.row, t.col, *t.val));
    }
    Ok(out)
}

/// Checks |a_ij − a_ji| ≤ 1e-12·max|a| for every stored pair (a missing entry counts as zero).
fn check_symmetric(entries: &[(usize, usize, f64)], path: &Path) -> Result<()> {
    let scale = entries.iter().fold(0.0f64, |a, e| a.max(e.2.abs()));
    let tol = 1e-12 * scale;
    let mut lower: HashMap<(usize, usize), f64> = entries
        .iter()
        .filter(|(r, c, _)| r > c)
        .map(|&(r, c, v)| ((r, c), v))
        .collect();
    let mut bad = None;
    for &(r, c, v) in entries.iter().filter(|(r, c, _)| r < c) {
        let w = lower.remove(&(c, r)).unwrap_or(0.0);
        if (v - w).abs() > tol {
            bad = Some((r, c, v, w));
            break;
        }
    }
    if bad.is_none() {
        bad = lower
            .iter()
            .find(|(_, v)| v.abs() > tol)
            .map(|(&(r, c), &v)| (c, r, 0.0, v));
    }
    match bad {
        None => Ok(()),
        Some((r, c, v, w)) => Err(Error::input(format!(
            "{}: the matrix is not symmetric: entry ({}, {}) = {v:e} but ({}, {}) = {w:e}; write it as general",
            path.display(),
            r + 1,
            c + 1,
            c + 1,
            r + 1
        ))),
    }
}

/// The banner, a comment and the size line.
fn write_header(text: &mut String, symmetry: &str, nrows: usize, ncols: usize, nnz: usize) {
    let _ = writeln!(text, "%%MatrixMarket matrix coordinate real {symmetry}");
    let _ = writeln!(text, "% written by nlrom {}", env!("CARGO_PKG_VERSION"));
    let _ = writeln!(text, "{nrows} {ncols} {nnz}");
}

/// One coordinate line, 1-based, with 17 significant digits.
fn push_entry(text: &mut String, r: usize, c: usize, v: f64) {
    let _ = writeln!(text, "{} {} {:.16e}", r + 1, c + 1, v);
}

/// `path` with `.tmp` appended to its file name (same directory).
fn tmp_path(path: &Path) -> PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".tmp");
    path.with_file_name(name)
}

/// Writes `bytes` to `<path>.tmp`, syncs it and renames it to `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = tmp_path(path);
    let result = (|| {
        let mut f = std::fs::File::create(&tmp)?;
        f.write_all(bytes)?;
        f.sync_all()
    })();
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        return Err(Error::io(&tmp, e));
    }
    std::fs::rename(&tmp, path).map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        Error::io(path, e)
    })
}

// ---------------------------------------------------------------------------------------------
// The DOF map
// ---------------------------------------------------------------------------------------------

/// The header line of `dofs.csv`.
pub const DOF_MAP_HEADER: &str = "row,node_tag,component";

/// One matrix row and the node DOF it stands for.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct DofEntry {
    /// 0-based matrix row.
    pub row: usize,
    /// Gmsh node tag.
    pub node_tag: u64,
    /// Displacement component: 0 = x, 1 = y, 2 = z (global Cartesian frame).
    pub component: u8,
}

/// The relation between matrix rows and node DOFs (`dofs.csv`), one entry per row.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct DofMap {
    /// Entries in file order (rows need not be sorted, but each row and each (node, component)
    /// appears once).
    pub entries: Vec<DofEntry>,
}

impl DofMap {
    /// The map of `docs/conventions.md` §1 for nodes with these tags (ascending): row `3*i + c` is
    /// component `c` of node `i`.
    pub fn structural(node_tags: &[u64]) -> DofMap {
        let entries = node_tags
            .iter()
            .enumerate()
            .flat_map(|(i, &tag)| {
                (0..3u8).map(move |c| DofEntry {
                    row: 3 * i + c as usize,
                    node_tag: tag,
                    component: c,
                })
            })
            .collect();
        DofMap { entries }
    }

    /// Number of rows mapped.
    pub fn len(&self) -> usize {
        self.entries.len()
    }

    /// Whether the map is empty.
    pub fn is_empty(&self) -> bool {
        self.entries.is_empty()
    }

    /// The row of component `component` of node `node_tag`, if mapped.
    pub fn row_of(&self, node_tag: u64, component: u8) -> Option<usize> {
        self.entries
            .iter()
            .find(|e| e.node_tag == node_tag && e.component == component)
            .map(|e| e.row)
    }
}

/// Reads `dofs.csv`: the header `row,node_tag,component`, then one `row,node_tag,component` line per
/// row (component 0/1/2 or x/y/z). Blank lines are ignored. Errors name the file and line, including
/// a row or a (node, component) listed twice.
pub fn read_dof_map(path: &Path) -> Result<DofMap> {
    let text = read_text(path)?;
    parse_dof_map(&text, &path.display().to_string())
}

/// Parses the text of a `dofs.csv`; `name` is the file name used in messages.
pub fn parse_dof_map(text: &str, name: &str) -> Result<DofMap> {
    let err = |line: usize, msg: String| Error::input(format!("{name}: line {line}: {msg}"));
    let mut lines = text.lines().enumerate().map(|(i, l)| (i + 1, l.trim()));
    let header = lines.find(|(_, l)| !l.is_empty());
    match header {
        Some((_, h)) if h.replace(' ', "").eq_ignore_ascii_case(DOF_MAP_HEADER) => {}
        Some((no, h)) => {
            return Err(err(
                no,
                format!("expected the header `{DOF_MAP_HEADER}`, found `{h}`"),
            ))
        }
        None => {
            return Err(err(
                1,
                format!("empty file; expected the header `{DOF_MAP_HEADER}`"),
            ))
        }
    }
    let mut map = DofMap::default();
    let mut rows: HashMap<usize, usize> = HashMap::new();
    let mut dofs: HashMap<(u64, u8), usize> = HashMap::new();
    for (no, line) in lines.filter(|(_, l)| !l.is_empty()) {
        let e = parse_dof_line(line).map_err(|m| err(no, m))?;
        if let Some(first) = rows.insert(e.row, no) {
            return Err(err(
                no,
                format!("row {} is already listed on line {first}", e.row),
            ));
        }
        if let Some(first) = dofs.insert((e.node_tag, e.component), no) {
            return Err(err(
                no,
                format!(
                    "node {} component {} is already listed on line {first}",
                    e.node_tag, e.component
                ),
            ));
        }
        map.entries.push(e);
    }
    Ok(map)
}

/// Parses one `row,node_tag,component` line.
fn parse_dof_line(line: &str) -> std::result::Result<DofEntry, String> {
    let fields: Vec<&str> = line.split(',').map(str::trim).collect();
    if fields.len() != 3 {
        return Err(format!(
            "expected 3 comma-separated fields (row,node_tag,component), found {}",
            fields.len()
        ));
    }
    let row = fields[0]
        .parse()
        .map_err(|_| format!("row '{}' is not a non-negative integer", fields[0]))?;
    let node_tag = fields[1]
        .parse()
        .map_err(|_| format!("node tag '{}' is not a non-negative integer", fields[1]))?;
    let component = match fields[2].to_ascii_lowercase().as_str() {
        "0" | "x" => 0,
        "1" | "y" => 1,
        "2" | "z" => 2,
        c => return Err(format!("component '{c}' is not 0, 1 or 2 (x, y, z)")),
    };
    Ok(DofEntry {
        row,
        node_tag,
        component,
    })
}

/// Writes `dofs.csv` (header and one line per entry, component as 0/1/2) atomically.
pub fn write_dof_map(path: &Path, map: &DofMap) -> Result<()> {
    let mut text = String::with_capacity(24 * map.entries.len() + 32);
    let _ = writeln!(text, "{DOF_MAP_HEADER}");
    for e in &map.entries {
        let _ = writeln!(text, "{},{},{}", e.row, e.node_tag, e.component);
    }
    write_atomic(path, text.as_bytes())
}
