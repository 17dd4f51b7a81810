//! A small HDF5 layer over `hdf5-pure`: an in-memory tree of groups, datasets and attributes that
//! is serialised in one piece and written atomically, and a reader that loads such a file back
//! into the same tree.
//!
//! What it writes (`docs/conventions.md` §5):
//!
//! * datasets of `f64`, `i64`, `u64` of any shape (row-major, shape `[]` is a scalar);
//! * complex datasets as the compound `{r: f64, i: f64}`, which h5py reads as `complex128`;
//! * compound record datasets ([`Records`]) with `f64`/`i64`/`u64`/`u8` columns and `u8`-based
//!   HDF5 enumerations (h5py: a structured array; enum labels via `h5py.check_enum_dtype`);
//! * variable-length UTF-8 string datasets and attributes (h5py returns `str`);
//! * numeric and string attributes on groups, datasets and the root.
//!
//! Every dataset must carry a `unit` and a `description` string attribute: [`H5File::to_bytes`]
//! refuses a dataset without them, and one whose shape does not match its data. Files are built
//! in memory ([`H5File`]) and written by [`write_atomic`]: the bytes go to `<name>.tmp-<pid>` in the
//! destination directory, which is then renamed over the destination, so no reader ever sees a
//! half-written file, also when the write fails.

use std::collections::BTreeMap;
use std::fs::{self, File};
use std::io::Write;
use std::path::{Path, PathBuf};

use faer::{c64, Mat};
use hdf5_pure as h5;

use crate::error::{Error, Result};

/// Name of the attribute that gives a dataset's unit (SI, e.g. `"rad/s"`; `"1"` for a pure number).
pub const UNIT: &str = "unit";
/// Name of the attribute that says what a dataset means.
pub const DESCRIPTION: &str = "description";

/// Field names of the complex compound type, the ones h5py maps to `complex128`.
const COMPLEX_FIELDS: [&str; 2] = ["r", "i"];

/// An attribute value.
#[derive(Clone, Debug, PartialEq)]
pub enum Attr {
    /// A UTF-8 string (variable length; h5py returns `str`).
    Str(String),
    /// A 64-bit float.
    F64(f64),
    /// A signed 64-bit integer.
    I64(i64),
    /// An unsigned 64-bit integer.
    U64(u64),
    /// A 1-D array of floats.
    F64s(Vec<f64>),
    /// A 1-D array of signed integers.
    I64s(Vec<i64>),
    /// A 1-D array of unsigned integers.
    U64s(Vec<u64>),
    /// A 1-D array of UTF-8 strings.
    Strs(Vec<String>),
}

impl Attr {
    /// The string, if this is a [`Attr::Str`].
    pub fn as_str(&self) -> Option<&str> {
        match self {
            Attr::Str(s) => Some(s),
            _ => None,
        }
    }
}

/// One column of a compound record dataset.
#[derive(Clone, Debug, PartialEq)]
pub enum Column {
    /// 64-bit floats.
    F64(Vec<f64>),
    /// Signed 64-bit integers.
    I64(Vec<i64>),
    /// Unsigned 64-bit integers.
    U64(Vec<u64>),
    /// Unsigned 8-bit integers.
    U8(Vec<u8>),
    /// An HDF5 enumeration over `u8`: `codes[j]` is the index into `labels` of record j.
    Enum {
        /// The names of the values 0, 1, … .
        labels: Vec<String>,
        /// One code per record, each `< labels.len()`.
        codes: Vec<u8>,
    },
}

impl Column {
    /// Number of records in the column.
    pub fn len(&self) -> usize {
        match self {
            Column::F64(v) => v.len(),
            Column::I64(v) => v.len(),
            Column::U64(v) => v.len(),
            Column::U8(v) => v.len(),
            Column::Enum { codes, .. } => codes.len(),
        }
    }

    /// True when the column has no records.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The values, if this is a [`Column::F64`].
    pub fn as_f64(&self) -> Option<&[f64]> {
        match self {
            Column::F64(v) => Some(v),
            _ => None,
        }
    }

    /// The values, if this is a [`Column::U64`].
    pub fn as_u64(&self) -> Option<&[u64]> {
        match self {
            Column::U64(v) => Some(v),
            _ => None,
        }
    }

    /// The values, if this is a [`Column::I64`].
    pub fn as_i64(&self) -> Option<&[i64]> {
        match self {
            Column::I64(v) => Some(v),
            _ => None,
        }
    }

    /// Bytes per record of this column.
    fn width(&self) -> usize {
        match self {
            Column::F64(_) | Column::I64(_) | Column::U64(_) => 8,
            Column::U8(_) | Column::Enum { .. } => 1,
        }
    }

    /// The HDF5 datatype of the column.
    fn datatype(&self) -> std::result::Result<h5::Datatype, String> {
        Ok(match self {
            Column::F64(_) => h5::make_f64_type(),
            Column::I64(_) => h5::make_i64_type(),
            Column::U64(_) => h5::make_u64_type(),
            Column::U8(_) => h5::make_u8_type(),
            Column::Enum { labels, .. } => {
                let mut builder = h5::EnumTypeBuilder::u8_based();
                for (code, label) in labels.iter().enumerate() {
                    let code = u8::try_from(code).map_err(|_| "more than 256 enum labels")?;
                    builder = builder.u8_value(label, code);
                }
                builder.build().map_err(|e| e.to_string())?
            }
        })
    }

    /// Appends the little-endian bytes of record `row` to `out`.
    fn encode(&self, row: usize, out: &mut Vec<u8>) {
        match self {
            Column::F64(v) => out.extend_from_slice(&v[row].to_le_bytes()),
            Column::I64(v) => out.extend_from_slice(&v[row].to_le_bytes()),
            Column::U64(v) => out.extend_from_slice(&v[row].to_le_bytes()),
            Column::U8(v) => out.push(v[row]),
            Column::Enum { codes, .. } => out.push(codes[row]),
        }
    }
}

/// A table of records (an HDF5 compound dataset, 1-D): named columns of equal length.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Records {
    /// The columns in field order: (field name, values).
    pub fields: Vec<(String, Column)>,
}

impl Records {
    /// An empty table (add columns with [`Records::column`]).
    pub fn new() -> Self {
        Self::default()
    }

    /// Appends the column `name` (builder style).
    pub fn column(mut self, name: &str, values: Column) -> Self {
        self.fields.push((name.to_string(), values));
        self
    }

    /// The column `name`, if present.
    pub fn get(&self, name: &str) -> Option<&Column> {
        self.fields.iter().find(|(n, _)| n == name).map(|(_, c)| c)
    }

    /// Number of records (the length of the first column; 0 without columns).
    pub fn len(&self) -> usize {
        self.fields.first().map_or(0, |(_, c)| c.len())
    }

    /// True when there are no records.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The values of a dataset, row-major.
#[derive(Clone, Debug, PartialEq)]
pub enum Data {
    /// 64-bit floats.
    F64(Vec<f64>),
    /// Signed 64-bit integers.
    I64(Vec<i64>),
    /// Unsigned 64-bit integers.
    U64(Vec<u64>),
    /// Complex numbers, stored as the compound `{r, i}` (h5py: `complex128`).
    Complex(Vec<c64>),
    /// Compound records (the dataset is 1-D, one element per record).
    Records(Records),
    /// Variable-length UTF-8 strings.
    Strings(Vec<String>),
}

impl Data {
    /// Number of elements.
    pub fn len(&self) -> usize {
        match self {
            Data::F64(v) => v.len(),
            Data::I64(v) => v.len(),
            Data::U64(v) => v.len(),
            Data::Complex(v) => v.len(),
            Data::Records(r) => r.len(),
            Data::Strings(v) => v.len(),
        }
    }

    /// True when there are no elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Short name of the element type, for messages.
    pub fn type_name(&self) -> &'static str {
        match self {
            Data::F64(_) => "f64",
            Data::I64(_) => "i64",
            Data::U64(_) => "u64",
            Data::Complex(_) => "complex {r, i}",
            Data::Records(_) => "compound records",
            Data::Strings(_) => "strings",
        }
    }
}

/// A dataset: shape (row-major), values and attributes.
#[derive(Clone, Debug, PartialEq)]
pub struct Dataset {
    /// Extent of each dimension; the product equals the number of values. `[]` is a scalar.
    pub shape: Vec<usize>,
    /// The values, row-major.
    pub data: Data,
    /// Attributes by name; [`UNIT`] and [`DESCRIPTION`] are required.
    pub attrs: BTreeMap<String, Attr>,
}

impl Dataset {
    /// A dataset of the given shape with its `unit` and `description` attributes.
    pub fn new(shape: &[usize], data: Data, unit: &str, description: &str) -> Self {
        let mut attrs = BTreeMap::new();
        attrs.insert(UNIT.to_string(), Attr::Str(unit.to_string()));
        attrs.insert(DESCRIPTION.to_string(), Attr::Str(description.to_string()));
        Dataset {
            shape: shape.to_vec(),
            data,
            attrs,
        }
    }

    /// A 1-D dataset of floats.
    pub fn f64s(values: Vec<f64>, unit: &str, description: &str) -> Self {
        Self::new(&[values.len()], Data::F64(values), unit, description)
    }

    /// A 1-D dataset of signed integers.
    pub fn i64s(values: Vec<i64>, unit: &str, description: &str) -> Self {
        Self::new(&[values.len()], Data::I64(values), unit, description)
    }

    /// A 1-D dataset of unsigned integers.
    pub fn u64s(values: Vec<u64>, unit: &str, description: &str) -> Self {
        Self::new(&[values.len()], Data::U64(values), unit, description)
    }

    /// A 1-D compound dataset, one element per record.
    pub fn records(records: Records, unit: &str, description: &str) -> Self {
        Self::new(&[records.len()], Data::Records(records), unit, description)
    }

    /// A dense real matrix, shape `[rows, cols]`, row-major.
    pub fn real_matrix(m: &Mat<f64>, unit: &str, description: &str) -> Self {
        let values = (0..m.nrows())
            .flat_map(|i| (0..m.ncols()).map(move |j| m[(i, j)]))
            .collect();
        Self::new(
            &[m.nrows(), m.ncols()],
            Data::F64(values),
            unit,
            description,
        )
    }

    /// A dense complex matrix, shape `[rows, cols]`, row-major, compound `{r, i}`.
    pub fn complex_matrix(m: &Mat<c64>, unit: &str, description: &str) -> Self {
        let values = (0..m.nrows())
            .flat_map(|i| (0..m.ncols()).map(move |j| m[(i, j)]))
            .collect();
        Self::new(
            &[m.nrows(), m.ncols()],
            Data::Complex(values),
            unit,
            description,
        )
    }

    /// Sets (or replaces) an attribute; builder style.
    pub fn with_attr(mut self, name: &str, value: Attr) -> Self {
        self.attrs.insert(name.to_string(), value);
        self
    }

    /// The `unit` attribute, if present and a string.
    pub fn unit(&self) -> Option<&str> {
        self.attrs.get(UNIT).and_then(Attr::as_str)
    }
}

/// A group: attributes, datasets and sub-groups, each by name (names hold no `/`).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Group {
    /// Attributes by name.
    pub attrs: BTreeMap<String, Attr>,
    /// Datasets by name.
    pub datasets: BTreeMap<String, Dataset>,
    /// Sub-groups by name.
    pub groups: BTreeMap<String, Group>,
}

impl Group {
    /// The sub-group `name`, created empty if it does not exist.
    pub fn group(&mut self, name: &str) -> &mut Group {
        self.groups.entry(name.to_string()).or_default()
    }

    /// Sets (or replaces) the attribute `name`.
    pub fn set_attr(&mut self, name: &str, value: Attr) -> &mut Self {
        self.attrs.insert(name.to_string(), value);
        self
    }

    /// Adds (or replaces) the dataset `name`.
    pub fn add(&mut self, name: &str, dataset: Dataset) -> &mut Self {
        self.datasets.insert(name.to_string(), dataset);
        self
    }
}

/// An HDF5 file assembled in memory: the root group.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct H5File {
    /// The root group `/` (its attributes are the file-level attributes).
    pub root: Group,
}

impl H5File {
    /// An empty file.
    pub fn new() -> Self {
        Self::default()
    }

    /// Serialises the file. Fails (naming the dataset) when a dataset's shape does not match its
    /// data, when it lacks the `unit` or `description` attribute, or when a name is empty or holds
    /// a `/`.
    pub fn to_bytes(&self) -> Result<Vec<u8>> {
        validate_group(&self.root, "")?;
        let mut builder = h5::FileBuilder::new();
        fill(&mut builder, &self.root, "")?;
        builder
            .finish()
            .map_err(|e| Error::Compute(format!("HDF5 serialisation failed: {e}")))
    }

    /// Serialises the file and writes it to `path` atomically ([`write_atomic`]).
    pub fn write(&self, path: &Path) -> Result<()> {
        let bytes = self.to_bytes()?;
        write_atomic(path, &bytes)
    }
}

/// Writes `bytes` to `path` so that `path` is either untouched or complete: the bytes go to
/// `<path>.tmp-<pid>` (same directory), are flushed to disk, and the temporary file is renamed
/// over `path`. On any failure the temporary file is removed and the error names `path`.
pub fn write_atomic(path: &Path, bytes: &[u8]) -> Result<()> {
    let tmp = temporary_path(path);
    let written = write_and_sync(&tmp, bytes).and_then(|()| fs::rename(&tmp, path));
    if let Err(source) = written {
        let _ = fs::remove_file(&tmp);
        return Err(Error::io(path, source));
    }
    Ok(())
}

/// `<path>.tmp-<pid>`: the name a file is written under before it is renamed to `path`.
pub fn temporary_path(path: &Path) -> PathBuf {
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(format!(".tmp-{}", std::process::id()));
    path.with_file_name(name)
}

/// Whether [`publish_once`] created the file or found one already there.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Published {
    /// This call created the file.
    Created,
    /// The file existed (another writer published first); it was left untouched.
    Existing,
}

/// Writes `bytes` to `path` unless `path` exists, so that any number of writers (threads,
/// processes, machines on a shared file system) publishing the same content leave exactly one
/// complete file: the bytes go to a temporary file of a name unique to this host, process and call
/// ([`unique_temporary_path`]), are flushed, and are hard-linked to `path`, which fails, without
/// touching `path`, when another writer linked first. The temporary file is removed in every case.
/// On a file system without hard links the temporary file is renamed over `path` instead (still
/// atomic: readers see one complete file, the last writer's).
pub fn publish_once(path: &Path, bytes: &[u8]) -> Result<Published> {
    if path.exists() {
        return Ok(Published::Existing);
    }
    let tmp = unique_temporary_path(path);
    if let Err(source) = write_and_sync(&tmp, bytes) {
        let _ = fs::remove_file(&tmp);
        return Err(Error::io(path, source));
    }
    let linked = fs::hard_link(&tmp, path);
    let outcome = match linked {
        Ok(()) => Ok(Published::Created),
        Err(e) if e.kind() == std::io::ErrorKind::AlreadyExists => Ok(Published::Existing),
        Err(_) => fs::rename(&tmp, path)
            .map(|()| Published::Created)
            .map_err(|source| Error::io(path, source)),
    };
    let _ = fs::remove_file(&tmp);
    outcome
}

/// `<path>.tmp-<host>-<pid>-<n>`: a temporary name no other writer uses, also across machines
/// sharing the directory (`n` counts the calls in this process).
pub fn unique_temporary_path(path: &Path) -> PathBuf {
    static CALLS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);
    let n = CALLS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let mut name = path
        .file_name()
        .map(|n| n.to_os_string())
        .unwrap_or_default();
    name.push(format!(".tmp-{}-{}-{n}", host_name(), std::process::id()));
    path.with_file_name(name)
}

/// The machine's host name (`/proc/sys/kernel/hostname`, else `$HOSTNAME`, else `localhost`).
pub fn host_name() -> String {
    std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .or_else(|| std::env::var("HOSTNAME").ok())
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .unwrap_or_else(|| "localhost".into())
}

fn write_and_sync(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    let mut file = File::create(path)?;
    file.write_all(bytes)?;
    file.sync_all()
}

/// The file path of `name` inside the group at `parent` (`"/a/b"` style, root = `""`).
fn join(parent: &str, name: &str) -> String {
    format!("{parent}/{name}")
}

fn check_name(name: &str, parent: &str) -> Result<()> {
    if name.is_empty() || name.contains('/') || name == "." {
        return Err(Error::Compute(format!(
            "HDF5 output: invalid object name {name:?} in group {:?} (empty, \".\" or holding a '/')",
            display_path(parent)
        )));
    }
    Ok(())
}

fn display_path(path: &str) -> &str {
    if path.is_empty() {
        "/"
    } else {
        path
    }
}

/// Checks names, shapes and the required attributes of every dataset under `group`.
fn validate_group(group: &Group, path: &str) -> Result<()> {
    for (name, dataset) in &group.datasets {
        check_name(name, path)?;
        validate_dataset(dataset, &join(path, name))?;
    }
    for (name, sub) in &group.groups {
        check_name(name, path)?;
        validate_group(sub, &join(path, name))?;
    }
    Ok(())
}

fn validate_dataset(dataset: &Dataset, path: &str) -> Result<()> {
    let elements: usize = dataset.shape.iter().product();
    if elements != dataset.data.len() {
        return Err(Error::Compute(format!(
            "HDF5 output: dataset {path} has shape {:?} ({elements} elements) but {} values",
            dataset.shape,
            dataset.data.len()
        )));
    }
    for required in [UNIT, DESCRIPTION] {
        if !matches!(dataset.attrs.get(required), Some(Attr::Str(_))) {
            return Err(Error::Compute(format!(
                "HDF5 output: dataset {path} has no string attribute {required:?} (docs/conventions.md §5)"
            )));
        }
    }
    if let Data::Records(records) = &dataset.data {
        if dataset.shape.len() != 1 {
            return Err(Error::Compute(format!(
                "HDF5 output: compound dataset {path} must be 1-D, has shape {:?}",
                dataset.shape
            )));
        }
        validate_records(records, path)?;
    }
    Ok(())
}

fn validate_records(records: &Records, path: &str) -> Result<()> {
    if records.fields.is_empty() {
        return Err(Error::Compute(format!(
            "HDF5 output: compound dataset {path} has no fields"
        )));
    }
    let n = records.len();
    for (name, column) in &records.fields {
        if column.len() != n {
            return Err(Error::Compute(format!(
                "HDF5 output: compound dataset {path}: field {name:?} has {} records, the first field {n}",
                column.len()
            )));
        }
        if let Column::Enum { labels, codes } = column {
            if let Some(bad) = codes.iter().find(|&&c| c as usize >= labels.len()) {
                return Err(Error::Compute(format!(
                    "HDF5 output: compound dataset {path}: field {name:?} has code {bad} but only {} labels",
                    labels.len()
                )));
            }
        }
    }
    Ok(())
}

/// The two hdf5-pure builders a group's content goes into (the root and the other groups).
trait Sink {
    fn dataset(&mut self, name: &str) -> &mut h5::DatasetBuilder;
    fn sub_group(&mut self, name: &str) -> h5::GroupBuilder;
    fn add_sub_group(&mut self, group: h5::FinishedGroup);
    fn attr(&mut self, name: &str, value: h5::AttrValue);
}

impl Sink for h5::FileBuilder {
    fn dataset(&mut self, name: &str) -> &mut h5::DatasetBuilder {
        self.create_dataset(name)
    }
    fn sub_group(&mut self, name: &str) -> h5::GroupBuilder {
        self.create_group(name)
    }
    fn add_sub_group(&mut self, group: h5::FinishedGroup) {
        self.add_group(group)
    }
    fn attr(&mut self, name: &str, value: h5::AttrValue) {
        self.set_attr(name, value)
    }
}

impl Sink for h5::GroupBuilder {
    fn dataset(&mut self, name: &str) -> &mut h5::DatasetBuilder {
        self.create_dataset(name)
    }
    fn sub_group(&mut self, name: &str) -> h5::GroupBuilder {
        self.create_group(name)
    }
    fn add_sub_group(&mut self, group: h5::FinishedGroup) {
        self.add_group(group)
    }
    fn attr(&mut self, name: &str, value: h5::AttrValue) {
        self.set_attr(name, value)
    }
}

/// Puts the content of `group` (at file path `path`) into `sink`, recursively.
fn fill(sink: &mut impl Sink, group: &Group, path: &str) -> Result<()> {
    for (name, value) in &group.attrs {
        sink.attr(name, to_h5_attr(value));
    }
    for (name, dataset) in &group.datasets {
        let builder = sink.dataset(name);
        put_dataset(builder, dataset, &join(path, name))?;
    }
    for (name, sub) in &group.groups {
        let mut builder = sink.sub_group(name);
        fill(&mut builder, sub, &join(path, name))?;
        sink.add_sub_group(builder.finish());
    }
    Ok(())
}

fn put_dataset(builder: &mut h5::DatasetBuilder, dataset: &Dataset, path: &str) -> Result<()> {
    match &dataset.data {
        Data::F64(v) => {
            builder.with_f64_data(v);
        }
        Data::I64(v) => {
            builder.with_i64_data(v);
        }
        Data::U64(v) => {
            builder.with_u64_data(v);
        }
        Data::Complex(v) => {
            let (datatype, raw) = complex_bytes(v, path)?;
            builder.with_compound_data(datatype, raw, v.len() as u64);
        }
        Data::Records(records) => {
            let (datatype, raw) = records_bytes(records, path)?;
            builder.with_compound_data(datatype, raw, records.len() as u64);
        }
        Data::Strings(v) => {
            let refs: Vec<&str> = v.iter().map(String::as_str).collect();
            builder.with_vlen_strings(&refs);
        }
    }
    let shape: Vec<u64> = dataset.shape.iter().map(|&d| d as u64).collect();
    builder.with_shape(&shape);
    for (name, value) in &dataset.attrs {
        builder.set_attr(name, to_h5_attr(value));
    }
    Ok(())
}

fn format_error(path: &str, e: impl std::fmt::Display) -> Error {
    Error::Compute(format!("HDF5 output: dataset {path}: {e}"))
}

/// The `{r: f64, i: f64}` compound type and the little-endian bytes of `values`.
fn complex_bytes(values: &[c64], path: &str) -> Result<(h5::Datatype, Vec<u8>)> {
    let datatype = h5::CompoundTypeBuilder::new()
        .f64_field(COMPLEX_FIELDS[0])
        .f64_field(COMPLEX_FIELDS[1])
        .build()
        .map_err(|e| format_error(path, e))?;
    let mut raw = Vec::with_capacity(values.len() * 16);
    for z in values {
        raw.extend_from_slice(&z.re.to_le_bytes());
        raw.extend_from_slice(&z.im.to_le_bytes());
    }
    Ok((datatype, raw))
}

/// The packed compound type of `records` and their little-endian bytes.
fn records_bytes(records: &Records, path: &str) -> Result<(h5::Datatype, Vec<u8>)> {
    let mut builder = h5::CompoundTypeBuilder::new();
    for (name, column) in &records.fields {
        builder = builder.field(name, column.datatype().map_err(|e| format_error(path, e))?);
    }
    let datatype = builder.build().map_err(|e| format_error(path, e))?;
    let width: usize = records.fields.iter().map(|(_, c)| c.width()).sum();
    let mut raw = Vec::with_capacity(records.len() * width);
    for row in 0..records.len() {
        for (_, column) in &records.fields {
            column.encode(row, &mut raw);
        }
    }
    Ok((datatype, raw))
}

fn to_h5_attr(value: &Attr) -> h5::AttrValue {
    match value {
        Attr::Str(s) => h5::AttrValue::VarLenString(s.clone()),
        Attr::F64(x) => h5::AttrValue::F64(*x),
        Attr::I64(x) => h5::AttrValue::I64(*x),
        Attr::U64(x) => h5::AttrValue::U64(*x),
        Attr::F64s(v) => h5::AttrValue::F64Array(v.clone()),
        Attr::I64s(v) => h5::AttrValue::I64Array(v.clone()),
        Attr::U64s(v) => h5::AttrValue::U64Array(v.clone()),
        Attr::Strs(v) => h5::AttrValue::VarLenStringArray(v.clone()),
    }
}

// ---------------------------------------------------------------------------------------------
// Reading

/// A file written by [`H5File`], loaded back. Every error names the file and the object.
pub struct H5Reader {
    path: PathBuf,
    file: h5::File,
}

impl H5Reader {
    /// Opens `path`; a file that is not HDF5 is bad input (exit status 2).
    pub fn open(path: &Path) -> Result<Self> {
        let bytes = fs::read(path).map_err(|e| Error::io(path, e))?;
        if !h5::is_hdf5_bytes(&bytes) {
            return Err(Error::input(format!(
                "{}: not an HDF5 file (no HDF5 signature); give a file written by nlrom",
                path.display()
            )));
        }
        let file = h5::File::from_bytes(bytes).map_err(|e| {
            Error::input(format!(
                "{}: unreadable HDF5 file: {e}; it may be truncated or corrupt",
                path.display()
            ))
        })?;
        Ok(H5Reader {
            path: path.to_path_buf(),
            file,
        })
    }

    /// The file this reader reads.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// An input error that names the file and `object`.
    pub fn error(&self, object: &str, what: impl std::fmt::Display) -> Error {
        Error::input(format!("{}: {}: {what}", self.path.display(), object))
    }

    fn h5_group(&self, path: &str) -> Result<h5::Group> {
        let found = if path.is_empty() || path == "/" {
            Ok(self.file.root())
        } else {
            self.file.group(path)
        };
        found.map_err(|e| self.error(display_path(path), format!("no such group ({e})")))
    }

    /// True when the group `path` exists.
    pub fn has_group(&self, path: &str) -> bool {
        self.h5_group(path).is_ok()
    }

    /// The whole group at `path` (`""` or `"/"` = the root), with everything below it.
    pub fn group(&self, path: &str) -> Result<Group> {
        let group = self.h5_group(path)?;
        let path = path.trim_end_matches('/');
        let attrs = group
            .attrs()
            .map_err(|e| self.error(display_path(path), e))?;
        let mut out = Group {
            attrs: self.convert_attrs(attrs, path)?,
            ..Group::default()
        };
        for name in group
            .datasets()
            .map_err(|e| self.error(display_path(path), e))?
        {
            let child = join(path, &name);
            out.datasets.insert(name, self.dataset(&child)?);
        }
        for name in group
            .groups()
            .map_err(|e| self.error(display_path(path), e))?
        {
            let child = join(path, &name);
            out.groups.insert(name, self.group(&child)?);
        }
        Ok(out)
    }

    /// The whole file.
    pub fn read_all(&self) -> Result<H5File> {
        Ok(H5File {
            root: self.group("")?,
        })
    }

    /// The dataset at `path` (e.g. `"/rom/k0/mass"`).
    pub fn dataset(&self, path: &str) -> Result<Dataset> {
        let ds = self
            .file
            .dataset(path)
            .map_err(|e| self.error(path, format!("no such dataset ({e})")))?;
        let shape: Vec<usize> = ds
            .shape()
            .map_err(|e| self.error(path, e))?
            .iter()
            .map(|&d| d as usize)
            .collect();
        let datatype = ds.datatype().map_err(|e| self.error(path, e))?;
        let data = self.read_data(&ds, &datatype, path)?;
        let attrs = ds.attrs().map_err(|e| self.error(path, e))?;
        Ok(Dataset {
            shape,
            data,
            attrs: self.convert_attrs(attrs, path)?,
        })
    }

    /// The attributes of the group or dataset at `path`.
    pub fn attrs(&self, path: &str) -> Result<BTreeMap<String, Attr>> {
        let raw = if let Ok(group) = self.h5_group(path) {
            group.attrs()
        } else {
            let ds = self
                .file
                .dataset(path)
                .map_err(|_| self.error(display_path(path), "no such group or dataset"))?;
            ds.attrs()
        }
        .map_err(|e| self.error(display_path(path), e))?;
        self.convert_attrs(raw, path)
    }

    /// The attribute `name` of the object at `path`.
    pub fn attr(&self, path: &str, name: &str) -> Result<Attr> {
        self.attrs(path)?
            .remove(name)
            .ok_or_else(|| self.error(display_path(path), format!("missing attribute {name:?}")))
    }

    /// The string attribute `name` of the object at `path`.
    pub fn attr_str(&self, path: &str, name: &str) -> Result<String> {
        match self.attr(path, name)? {
            Attr::Str(s) => Ok(s),
            other => Err(self.wrong_attr(path, name, "a string", &other)),
        }
    }

    /// The float attribute `name` of the object at `path`.
    pub fn attr_f64(&self, path: &str, name: &str) -> Result<f64> {
        match self.attr(path, name)? {
            Attr::F64(x) => Ok(x),
            other => Err(self.wrong_attr(path, name, "a float", &other)),
        }
    }

    /// The non-negative integer attribute `name` of the object at `path` (stored as u64, or as a
    /// non-negative i64).
    pub fn attr_u64(&self, path: &str, name: &str) -> Result<u64> {
        match self.attr(path, name)? {
            Attr::U64(x) => Ok(x),
            Attr::I64(x) if x >= 0 => Ok(x as u64),
            other => Err(self.wrong_attr(path, name, "a non-negative integer", &other)),
        }
    }

    /// The signed integer attribute `name` of the object at `path`.
    pub fn attr_i64(&self, path: &str, name: &str) -> Result<i64> {
        match self.attr(path, name)? {
            Attr::I64(x) => Ok(x),
            other => Err(self.wrong_attr(path, name, "an integer", &other)),
        }
    }

    /// The float-array attribute `name` of the object at `path`, of length `len`.
    pub fn attr_f64s(&self, path: &str, name: &str, len: usize) -> Result<Vec<f64>> {
        match self.attr(path, name)? {
            Attr::F64s(v) if v.len() == len => Ok(v),
            other => Err(self.wrong_attr(path, name, &format!("{len} floats"), &other)),
        }
    }

    fn wrong_attr(&self, path: &str, name: &str, expected: &str, found: &Attr) -> Error {
        self.error(
            display_path(path),
            format!("attribute {name:?} should be {expected}, found {found:?}"),
        )
    }

    /// The dataset at `path`, which must have the shape `shape`.
    pub fn dataset_shaped(&self, path: &str, shape: &[usize]) -> Result<Dataset> {
        let ds = self.dataset(path)?;
        if ds.shape != shape {
            return Err(self.error(path, format!("shape {:?}, expected {shape:?}", ds.shape)));
        }
        Ok(ds)
    }

    /// The f64 values of the dataset at `path`, of shape `shape`.
    pub fn f64s(&self, path: &str, shape: &[usize]) -> Result<Vec<f64>> {
        match self.dataset_shaped(path, shape)?.data {
            Data::F64(v) => Ok(v),
            other => Err(self.wrong_type(path, "f64", &other)),
        }
    }

    /// The 1-D dataset at `path`, any length.
    fn vector(&self, path: &str) -> Result<Data> {
        let ds = self.dataset(path)?;
        if ds.shape.len() != 1 {
            return Err(self.error(path, format!("shape {:?}, expected 1-D", ds.shape)));
        }
        Ok(ds.data)
    }

    /// The 1-D f64 dataset at `path`, any length.
    pub fn f64_vector(&self, path: &str) -> Result<Vec<f64>> {
        match self.vector(path)? {
            Data::F64(v) => Ok(v),
            other => Err(self.wrong_type(path, "f64", &other)),
        }
    }

    /// The u64 values of the dataset at `path`, of shape `shape`.
    pub fn u64s(&self, path: &str, shape: &[usize]) -> Result<Vec<u64>> {
        match self.dataset_shaped(path, shape)?.data {
            Data::U64(v) => Ok(v),
            other => Err(self.wrong_type(path, "u64", &other)),
        }
    }

    /// The 1-D u64 dataset at `path`, any length.
    pub fn u64_vector(&self, path: &str) -> Result<Vec<u64>> {
        match self.vector(path)? {
            Data::U64(v) => Ok(v),
            other => Err(self.wrong_type(path, "u64", &other)),
        }
    }

    /// The i64 values of the dataset at `path`, of shape `shape`.
    pub fn i64s(&self, path: &str, shape: &[usize]) -> Result<Vec<i64>> {
        match self.dataset_shaped(path, shape)?.data {
            Data::I64(v) => Ok(v),
            other => Err(self.wrong_type(path, "i64", &other)),
        }
    }

    /// The values of the dataset at `path`, of shape `shape`, as complex numbers: a complex
    /// `{r, i}` dataset as stored, an f64 dataset with zero imaginary parts.
    pub fn complexes(&self, path: &str, shape: &[usize]) -> Result<Vec<c64>> {
        match self.dataset_shaped(path, shape)?.data {
            Data::Complex(v) => Ok(v),
            Data::F64(v) => Ok(v.into_iter().map(|x| c64::new(x, 0.0)).collect()),
            other => Err(self.wrong_type(path, "complex or f64", &other)),
        }
    }

    /// The compound records at `path`, which must hold `len` records and the fields `fields`.
    pub fn records(&self, path: &str, len: Option<usize>, fields: &[&str]) -> Result<Records> {
        let ds = self.dataset(path)?;
        let Data::Records(records) = ds.data else {
            return Err(self.wrong_type(path, "compound records", &ds.data));
        };
        if let Some(len) = len {
            if ds.shape != [len] {
                return Err(self.error(path, format!("shape {:?}, expected [{len}]", ds.shape)));
            }
        }
        for field in fields {
            if records.get(field).is_none() {
                return Err(self.error(path, format!("missing compound field {field:?}")));
            }
        }
        Ok(records)
    }

    /// The column `name` of `records` (read from `path`), as the type `pick` selects (`what`
    /// names it in the error).
    pub fn column<'a, T>(
        &self,
        path: &str,
        records: &'a Records,
        name: &str,
        pick: fn(&Column) -> Option<&[T]>,
        what: &str,
    ) -> Result<&'a [T]> {
        records
            .get(name)
            .and_then(pick)
            .ok_or_else(|| self.error(path, format!("field {name:?} should be {what}")))
    }

    fn wrong_type(&self, path: &str, expected: &str, found: &Data) -> Error {
        self.error(
            path,
            format!("element type {}, expected {expected}", found.type_name()),
        )
    }

    /// Names of the sub-groups of the group at `path`.
    pub fn group_names(&self, path: &str) -> Result<Vec<String>> {
        self.h5_group(path)?
            .groups()
            .map_err(|e| self.error(display_path(path), e))
    }

    fn read_data(&self, ds: &h5::Dataset, datatype: &h5::Datatype, path: &str) -> Result<Data> {
        let fail = |e: h5::Error| self.error(path, e);
        match Kind::of(datatype) {
            Kind::F64 => Ok(Data::F64(ds.read_f64().map_err(fail)?)),
            Kind::I64 => Ok(Data::I64(ds.read_i64().map_err(fail)?)),
            Kind::U64 => Ok(Data::U64(ds.read_u64().map_err(fail)?)),
            Kind::Str => Ok(Data::Strings(ds.read_string().map_err(fail)?)),
            Kind::Compound => {
                let raw = ds.read_raw().map_err(fail)?;
                self.decode_compound(datatype, &raw, path)
            }
            _ => Err(self.error(
                path,
                format!("unsupported datatype {datatype:?} (nlrom writes f64, i64, u64, complex, compound, strings)"),
            )),
        }
    }

    fn decode_compound(&self, datatype: &h5::Datatype, raw: &[u8], path: &str) -> Result<Data> {
        let h5::Datatype::Compound { size, members } = datatype else {
            return Err(self.error(path, "not a compound datatype"));
        };
        let size = *size as usize;
        if size == 0 || !raw.len().is_multiple_of(size) {
            return Err(self.error(
                path,
                "compound data size is not a multiple of the record size",
            ));
        }
        let rows = raw.len() / size;
        let names: Vec<&str> = members.iter().map(|m| m.name.as_str()).collect();
        let all_f64 = members.iter().all(|m| Kind::of(&m.datatype) == Kind::F64);
        if names == COMPLEX_FIELDS && all_f64 {
            let re = column_f64(raw, size, rows, members[0].byte_offset as usize);
            let im = column_f64(raw, size, rows, members[1].byte_offset as usize);
            return Ok(Data::Complex(
                re.into_iter()
                    .zip(im)
                    .map(|(r, i)| c64::new(r, i))
                    .collect(),
            ));
        }
        let mut records = Records::new();
        for member in members {
            let offset = member.byte_offset as usize;
            let column = self.decode_column(member, raw, size, rows, offset, path)?;
            records.fields.push((member.name.clone(), column));
        }
        Ok(Data::Records(records))
    }

    fn decode_column(
        &self,
        member: &h5::CompoundMember,
        raw: &[u8],
        size: usize,
        rows: usize,
        offset: usize,
        path: &str,
    ) -> Result<Column> {
        if offset + member.datatype.type_size() as usize > size {
            return Err(self.error(
                path,
                format!("field {:?} lies outside the record", member.name),
            ));
        }
        let bytes8 = |row: usize| -> [u8; 8] {
            let start = row * size + offset;
            raw[start..start + 8].try_into().expect("8 bytes")
        };
        match (Kind::of(&member.datatype), &member.datatype) {
            (Kind::F64, _) => Ok(Column::F64(column_f64(raw, size, rows, offset))),
            (Kind::I64, _) => Ok(Column::I64(
                (0..rows).map(|r| i64::from_le_bytes(bytes8(r))).collect(),
            )),
            (Kind::U64, _) => Ok(Column::U64(
                (0..rows).map(|r| u64::from_le_bytes(bytes8(r))).collect(),
            )),
            (Kind::U8, _) => Ok(Column::U8(
                (0..rows).map(|r| raw[r * size + offset]).collect(),
            )),
            (Kind::Enum8, h5::Datatype::Enumeration { members, .. }) => {
                let mut labels = vec![String::new(); members.len()];
                for m in members {
                    let code = m.value.first().copied().unwrap_or(u8::MAX) as usize;
                    if code >= labels.len() {
                        return Err(self.error(
                            path,
                            format!(
                                "field {:?}: enum values are not 0..{}",
                                member.name,
                                labels.len()
                            ),
                        ));
                    }
                    labels[code] = m.name.clone();
                }
                let codes = (0..rows).map(|r| raw[r * size + offset]).collect();
                Ok(Column::Enum { labels, codes })
            }
            _ => Err(self.error(
                path,
                format!(
                    "field {:?} has unsupported type {:?}",
                    member.name, member.datatype
                ),
            )),
        }
    }

    fn convert_attrs(
        &self,
        attrs: std::collections::HashMap<String, h5::AttrValue>,
        path: &str,
    ) -> Result<BTreeMap<String, Attr>> {
        let mut out = BTreeMap::new();
        for (name, value) in attrs {
            let converted = from_h5_attr(&value).ok_or_else(|| {
                self.error(
                    display_path(path),
                    format!(
                        "attribute {name:?} has an unsupported type {}",
                        value.type_name()
                    ),
                )
            })?;
            out.insert(name, converted);
        }
        Ok(out)
    }
}

/// The element types the reader distinguishes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    F64,
    I64,
    U64,
    U8,
    Str,
    Compound,
    /// An enumeration over a 1-byte integer.
    Enum8,
    Other,
}

impl Kind {
    fn of(datatype: &h5::Datatype) -> Kind {
        use h5::Datatype as T;
        match datatype {
            T::FloatingPoint {
                size: 8,
                byte_order,
                ..
            } if little(byte_order) => Kind::F64,
            T::FixedPoint {
                size,
                byte_order,
                layout,
            } if little(byte_order) => match (size, layout.signed) {
                (8, true) => Kind::I64,
                (8, false) => Kind::U64,
                (1, false) => Kind::U8,
                _ => Kind::Other,
            },
            T::String { .. }
            | T::VariableLength {
                is_string: true, ..
            } => Kind::Str,
            T::Compound { .. } => Kind::Compound,
            T::Enumeration { size: 1, .. } => Kind::Enum8,
            _ => Kind::Other,
        }
    }
}

fn little(order: &h5::DatatypeByteOrder) -> bool {
    matches!(order, h5::DatatypeByteOrder::LittleEndian)
}

fn column_f64(raw: &[u8], size: usize, rows: usize, offset: usize) -> Vec<f64> {
    (0..rows)
        .map(|r| {
            let start = r * size + offset;
            f64::from_le_bytes(raw[start..start + 8].try_into().expect("8 bytes"))
        })
        .collect()
}

fn from_h5_attr(value: &h5::AttrValue) -> Option<Attr> {
    use h5::AttrValue as V;
    Some(match value {
        V::F64(x) => Attr::F64(*x),
        V::I64(x) => Attr::I64(*x),
        V::U64(x) => Attr::U64(*x),
        V::F64Array(v) => Attr::F64s(v.clone()),
        V::I64Array(v) => Attr::I64s(v.clone()),
        V::U64Array(v) => Attr::U64s(v.clone()),
        V::VarLenStringArray(v) | V::StringArray(v) | V::AsciiStringArray(v) => {
            Attr::Strs(v.clone())
        }
        other => Attr::Str(other.as_str()?.to_string()),
    })
}
