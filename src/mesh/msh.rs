//! Gmsh MSH reader: versions 2.2 and 4.1, ASCII and binary, written with `nom`.
//!
//! Sections read: `$MeshFormat`, `$PhysicalNames`, `$Entities` (4.1), `$Nodes`, `$Elements`,
//! `$Periodic`; any other section (`$NodeData`, `$Parametrizations`, ...) is skipped up to its
//! `$End...` line. Binary files must have data size 8; their byte order is recognised from the
//! check integer `1` that follows the format line (both little- and big-endian are read).
//!
//! Node tags and element tags may be non-contiguous and unsorted; nodes are re-indexed in ascending
//! tag order (`docs/conventions.md` §1). In 4.1 files, parametric node coordinates (`u`, `v`, `w`) are
//! read past and dropped. Physical groups are resolved per element: in 2.2 from the element's first
//! tag, in 4.1 from the physical tags of the element block's entity in `$Entities`.
//!
//! Every error carries the section, the byte offset and the line number of the offending token.
//! Counts read from the file are checked against the bytes left before anything is allocated, so a
//! corrupt count cannot exhaust memory.
//!
//! Reference: Gmsh reference manual, "MSH file format" (version 4.1) and "Legacy formats" (2.2).

use std::borrow::Cow;
use std::collections::{BTreeSet, HashMap};
use std::path::Path;

use nom::bytes::complete::{tag, take, take_until};
use nom::error::{ErrorKind, ParseError};
use nom::{IResult, Parser};
use rayon::prelude::*;

use super::ascii;
use super::{
    ElementBlock, ElementTags, ElementType, Mesh, MshFormat, MshVersion, PeriodicLink,
    PhysicalGroup,
};
use crate::error::Error;

/// A malformed MSH file: where (section, line, byte offset) and what.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{file}: line {line} (byte {offset}), section {section}: {message}")]
pub struct MshError {
    /// The file name (`<memory>` when parsed from bytes).
    pub file: String,
    /// The section being read, e.g. `$Nodes`.
    pub section: String,
    /// 1-based line number of the offending byte (counting `\n` before it, also in binary files).
    pub line: usize,
    /// 0-based byte offset of the offending token.
    pub offset: usize,
    /// What is wrong, and where it helps, what to do.
    pub message: String,
}

/// Reads and parses the MSH file at `path`.
///
/// The file is memory-mapped (pre-faulted) rather than copied into a buffer; if mapping is not
/// possible (a pipe, an exotic file system) it is read into memory instead.
pub fn read_msh(path: &Path) -> crate::Result<Mesh> {
    let file = std::fs::File::open(path).map_err(|e| Error::io(path, e))?;
    // SAFETY: the map is read-only and lives only for this call. The usual caveat of memory maps
    // applies: if another process truncates the file while it is parsed, the process may receive
    // SIGBUS; nlrom never modifies its input files.
    let mapped = unsafe { memmap2::MmapOptions::new().populate().map(&file) };
    let owned;
    let bytes: &[u8] = match &mapped {
        Ok(m) => m,
        Err(_) => {
            owned = std::fs::read(path).map_err(|e| Error::io(path, e))?;
            &owned
        }
    };
    let mut mesh = parse_msh(bytes).map_err(|mut e| {
        e.file = path.display().to_string();
        e
    })?;
    mesh.source = Some(path.to_path_buf());
    Ok(mesh)
}

/// Parses an MSH file held in memory.
pub fn parse_msh(bytes: &[u8]) -> Result<Mesh, MshError> {
    let mut state = State::default();
    let mut input = bytes;
    let mut first = true;
    loop {
        input = skip_ws(input);
        if input.is_empty() {
            break;
        }
        let (rest, name) =
            section_header(input).map_err(|e| to_error(bytes, "(file structure)", e))?;
        let section = format!("${}", String::from_utf8_lossy(name));
        if first && name != b"MeshFormat" {
            return Err(located(
                bytes,
                input,
                &section,
                "not a Gmsh MSH file: it must start with $MeshFormat",
            ));
        }
        first = false;
        input = state
            .section(name, rest)
            .map_err(|e| to_error(bytes, &section, e))?;
    }
    state.finish(bytes)
}

// ---------------------------------------------------------------------------------------------
// nom plumbing: the error type, positions, and the primitive parsers.

/// The parse error: the remaining input where it happened and a message.
#[derive(Debug)]
struct PErr<'a> {
    at: &'a [u8],
    msg: Cow<'static, str>,
}

impl<'a> ParseError<&'a [u8]> for PErr<'a> {
    fn from_error_kind(input: &'a [u8], kind: ErrorKind) -> Self {
        let msg = if input.is_empty() {
            Cow::Borrowed(EOF_MSG)
        } else {
            Cow::Owned(format!(
                "unexpected input ({kind:?}) near '{}'",
                show(input)
            ))
        };
        PErr { at: input, msg }
    }

    fn append(_: &'a [u8], _: ErrorKind, other: Self) -> Self {
        other
    }
}

type PResult<'a, T> = IResult<&'a [u8], T, PErr<'a>>;

const EOF_MSG: &str = "unexpected end of file: the file is truncated";

/// A hard failure at `at`.
fn fail<'a, T>(at: &'a [u8], msg: impl Into<Cow<'static, str>>) -> PResult<'a, T> {
    Err(nom::Err::Failure(PErr {
        at,
        msg: msg.into(),
    }))
}

/// The first token of `i`, for messages (at most 24 bytes, lossy UTF-8).
fn show(i: &[u8]) -> String {
    let n = i
        .iter()
        .take(24)
        .position(|c| c.is_ascii_whitespace())
        .unwrap_or(i.len().min(24));
    String::from_utf8_lossy(&i[..n]).into_owned()
}

/// Converts a nom error into an [`MshError`] located in `whole`.
fn to_error(whole: &[u8], section: &str, e: nom::Err<PErr<'_>>) -> MshError {
    match e {
        nom::Err::Error(p) | nom::Err::Failure(p) => located(whole, p.at, section, &p.msg),
        nom::Err::Incomplete(_) => located(whole, &[], section, EOF_MSG),
    }
}

/// An [`MshError`] at the position of the suffix `at` of `whole`.
fn located(whole: &[u8], at: &[u8], section: &str, msg: &str) -> MshError {
    let offset = whole.len().saturating_sub(at.len());
    let line = 1 + whole[..offset].iter().filter(|&&c| c == b'\n').count();
    MshError {
        file: "<memory>".to_string(),
        section: section.to_string(),
        line,
        offset,
        message: msg.to_string(),
    }
}

/// Skips ASCII white space (space, tab, CR, LF).
#[inline]
fn skip_ws(i: &[u8]) -> &[u8] {
    let n = i
        .iter()
        .position(|c| !c.is_ascii_whitespace())
        .unwrap_or(i.len());
    &i[n..]
}

/// Consumes the rest of the current line including its `\n` (only blanks may precede it): the
/// boundary between an ASCII header line and binary data.
fn end_of_line(i: &[u8]) -> PResult<'_, ()> {
    let mut n = 0;
    while n < i.len() && (i[n] == b' ' || i[n] == b'\t' || i[n] == b'\r') {
        n += 1;
    }
    match i.get(n) {
        Some(b'\n') => Ok((&i[n + 1..], ())),
        None => fail(&i[n..], EOF_MSG),
        Some(_) => fail(
            &i[n..],
            format!("expected the end of the line, found '{}'", show(&i[n..])),
        ),
    }
}

/// A white-space delimited token.
fn token(i: &[u8]) -> PResult<'_, &[u8]> {
    let i = skip_ws(i);
    if i.is_empty() {
        return fail(i, EOF_MSG);
    }
    let n = i
        .iter()
        .position(|c| c.is_ascii_whitespace())
        .unwrap_or(i.len());
    Ok((&i[n..], &i[..n]))
}

/// An unsigned decimal integer token.
#[inline]
fn uint(i: &[u8]) -> PResult<'_, u64> {
    let i = skip_ws(i);
    // Up to 19 digits cannot overflow a u64: no checks on the hot path.
    let mut value: u64 = 0;
    let mut n = 0;
    while let Some(&c) = i.get(n) {
        let d = c.wrapping_sub(b'0');
        if d > 9 || n == 19 {
            break;
        }
        value = value * 10 + u64::from(d);
        n += 1;
    }
    while let Some(&c) = i.get(n) {
        let d = c.wrapping_sub(b'0');
        if d > 9 {
            break;
        }
        value = match value
            .checked_mul(10)
            .and_then(|v| v.checked_add(u64::from(d)))
        {
            Some(v) => v,
            None => return fail(i, format!("integer '{}' is too large", show(i))),
        };
        n += 1;
    }
    if n == 0 || i.get(n).is_some_and(|c| !c.is_ascii_whitespace()) {
        if i.is_empty() {
            return fail(i, EOF_MSG);
        }
        return fail(
            i,
            format!("expected an unsigned integer, found '{}'", show(i)),
        );
    }
    Ok((&i[n..], value))
}

/// A signed decimal integer token that fits an `i32` (entity and physical tags, dimensions).
fn int32(i: &[u8]) -> PResult<'_, i32> {
    let i = skip_ws(i);
    let (neg, digits) = match i.first() {
        Some(b'-') => (true, &i[1..]),
        Some(b'+') => (false, &i[1..]),
        _ => (false, i),
    };
    if digits.is_empty() {
        return fail(digits, EOF_MSG);
    }
    if digits.first().is_some_and(|c| c.is_ascii_whitespace()) {
        return fail(i, format!("expected an integer, found '{}'", show(i)));
    }
    let (rest, v) = uint(digits).map_err(|_| {
        nom::Err::Failure(PErr {
            at: i,
            msg: format!("expected an integer, found '{}'", show(i)).into(),
        })
    })?;
    let v = if neg { -(v as i128) } else { v as i128 };
    match i32::try_from(v) {
        Ok(v) => Ok((rest, v)),
        Err(_) => fail(
            i,
            format!("integer '{}' is out of range for a tag", show(i)),
        ),
    }
}

/// A floating-point token; non-finite values are rejected.
fn float(i: &[u8]) -> PResult<'_, f64> {
    let (rest, tok) = token(i)?;
    let at = skip_ws(i);
    let parsed = std::str::from_utf8(tok)
        .ok()
        .and_then(|s| s.parse::<f64>().ok());
    match parsed {
        Some(v) if v.is_finite() => Ok((rest, v)),
        Some(_) => fail(at, format!("non-finite number '{}'", show(tok))),
        None => fail(at, format!("expected a number, found '{}'", show(tok))),
    }
}

/// Exactly `n` bytes of binary data.
fn bytes_n<'a>(i: &'a [u8], n: usize, what: &str) -> PResult<'a, &'a [u8]> {
    take::<usize, &[u8], PErr<'a>>(n).parse(i).or_else(|_| {
        fail(
            &i[i.len()..],
            format!("unexpected end of file while reading {what} ({n} bytes needed, {} left): the file is truncated", i.len()),
        )
    })
}

/// A count of items read from the file, checked against the bytes that remain (each item needs at
/// least `min_bytes`), so that a corrupt count is reported instead of exhausting memory.
fn checked_count<'a>(
    at: &'a [u8],
    rest: &'a [u8],
    n: u64,
    min_bytes: usize,
    what: &str,
) -> PResult<'a, usize> {
    let max = (rest.len() / min_bytes.max(1)) as u64;
    if n > max {
        return fail(
            at,
            format!("the file declares {n} {what}, but only {} bytes remain: the file is truncated or the count is wrong", rest.len()),
        );
    }
    Ok((rest, n as usize))
}

/// Records decoded per parallel task in binary node and element blocks.
const PAR_RECORDS: usize = 1 << 14;

/// Byte order of binary data.
#[derive(Clone, Copy, Debug)]
struct Endian {
    big: bool,
}

impl Endian {
    #[inline]
    fn i32(self, b: &[u8]) -> i32 {
        let a = [b[0], b[1], b[2], b[3]];
        if self.big {
            i32::from_be_bytes(a)
        } else {
            i32::from_le_bytes(a)
        }
    }

    #[inline]
    fn u64(self, b: &[u8]) -> u64 {
        let a = [b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]];
        if self.big {
            u64::from_be_bytes(a)
        } else {
            u64::from_le_bytes(a)
        }
    }

    #[inline]
    fn f64(self, b: &[u8]) -> f64 {
        f64::from_bits(self.u64(b))
    }
}

/// Reads integers and reals either as ASCII tokens or as binary values of the file's byte order
/// (`int` = 4 bytes, `size_t` and `double` = 8 bytes).
#[derive(Clone, Copy, Debug)]
struct Reader {
    binary: Option<Endian>,
}

impl Reader {
    fn int<'a>(self, i: &'a [u8], what: &str) -> PResult<'a, i32> {
        match self.binary {
            None => int32(i),
            Some(e) => bytes_n(i, 4, what).map(|(r, b)| (r, e.i32(b))),
        }
    }

    fn size<'a>(self, i: &'a [u8], what: &str) -> PResult<'a, u64> {
        match self.binary {
            None => uint(i),
            Some(e) => bytes_n(i, 8, what).map(|(r, b)| (r, e.u64(b))),
        }
    }

    fn real<'a>(self, i: &'a [u8], what: &str) -> PResult<'a, f64> {
        match self.binary {
            None => float(i),
            Some(e) => {
                let (r, b) = bytes_n(i, 8, what)?;
                let v = e.f64(b);
                if v.is_finite() {
                    Ok((r, v))
                } else {
                    fail(i, format!("non-finite value in {what}"))
                }
            }
        }
    }

    /// A count (`size_t`), checked against the remaining bytes.
    fn count<'a>(
        self,
        i: &'a [u8],
        min_ascii: usize,
        min_binary: usize,
        what: &str,
    ) -> PResult<'a, usize> {
        let at = skip_ws(i);
        let (rest, n) = self.size(i, what)?;
        let min = if self.binary.is_some() {
            min_binary
        } else {
            min_ascii
        };
        checked_count(at, rest, n, min, what)
    }
}

/// `$Name` followed by the end of its line.
fn section_header(i: &[u8]) -> PResult<'_, &[u8]> {
    let (i, _) =
        tag::<&[u8], &[u8], PErr<'_>>(b"$")
            .parse(i)
            .or_else(|_: nom::Err<PErr<'_>>| {
                fail(
                    i,
                    format!("expected a section header like $Nodes, found '{}'", show(i)),
                )
            })?;
    let n = i
        .iter()
        .position(|c| c.is_ascii_whitespace())
        .unwrap_or(i.len());
    let name = &i[..n];
    if name.is_empty() {
        return fail(i, "empty section name after '$'");
    }
    if name.starts_with(b"End") {
        return fail(
            i,
            format!("'${}' without a matching section start", show(name)),
        );
    }
    let (rest, ()) = end_of_line(&i[n..])?;
    Ok((rest, name))
}

/// The `$End<name>` line closing a section.
fn section_end<'a>(i: &'a [u8], name: &[u8]) -> PResult<'a, ()> {
    let i = skip_ws(i);
    let mut closing = b"$End".to_vec();
    closing.extend_from_slice(name);
    if i.starts_with(&closing) && i.get(closing.len()).is_none_or(|c| c.is_ascii_whitespace()) {
        return Ok((&i[closing.len()..], ()));
    }
    let what = String::from_utf8_lossy(&closing).into_owned();
    if i.is_empty() {
        fail(
            i,
            format!("missing {what}: the file ends inside the section (truncated?)"),
        )
    } else {
        fail(i, format!("expected {what}, found '{}' (wrong count in the section header, or a missing {what})", show(i)))
    }
}

// ---------------------------------------------------------------------------------------------
// The parser state: what has been read so far.

/// Maps node tags to compact indices.
#[derive(Debug)]
enum NodeLookup {
    /// Tags are exactly `first .. first + n`.
    Contiguous { first: u64, n: u64 },
    /// Dense table indexed by tag (`u32::MAX` = absent).
    Dense(Vec<u32>),
    /// Sparse tags.
    Sparse(HashMap<u64, u32>),
}

impl NodeLookup {
    fn new(sorted_tags: &[u64]) -> NodeLookup {
        let n = sorted_tags.len() as u64;
        let (first, last) = match (sorted_tags.first(), sorted_tags.last()) {
            (Some(&f), Some(&l)) => (f, l),
            _ => return NodeLookup::Contiguous { first: 0, n: 0 },
        };
        if last - first == n - 1 {
            NodeLookup::Contiguous { first, n }
        } else if last <= 8 * n + (1 << 20) {
            let mut table = vec![u32::MAX; last as usize + 1];
            for (i, &t) in sorted_tags.iter().enumerate() {
                table[t as usize] = i as u32;
            }
            NodeLookup::Dense(table)
        } else {
            NodeLookup::Sparse(
                sorted_tags
                    .iter()
                    .enumerate()
                    .map(|(i, &t)| (t, i as u32))
                    .collect(),
            )
        }
    }

    #[inline]
    fn get(&self, tag: u64) -> Option<u32> {
        match self {
            NodeLookup::Contiguous { first, n } => tag
                .checked_sub(*first)
                .filter(|&d| d < *n)
                .map(|d| d as u32),
            NodeLookup::Dense(t) => t.get(tag as usize).copied().filter(|&i| i != u32::MAX),
            NodeLookup::Sparse(m) => m.get(&tag).copied(),
        }
    }
}

#[derive(Default)]
struct State {
    format: Option<MshFormat>,
    named: Vec<PhysicalGroup>,
    /// Physical tags of each 4.1 entity, indexed by dimension then entity tag.
    entity_physicals: [HashMap<i32, Vec<i32>>; 4],
    has_entities: bool,
    node_tags: Vec<u64>,
    coords: Vec<[f64; 3]>,
    /// Nodes read so far by the blocks of a 4.1 `$Nodes` section (the arrays are allocated at
    /// the declared size first).
    nodes_read: usize,
    lookup: Option<NodeLookup>,
    blocks: Vec<ElementBlock>,
    periodic: Vec<PeriodicLink>,
}

impl State {
    fn reader(&self) -> Reader {
        let binary = self
            .format
            .filter(|f| f.binary)
            .map(|f| Endian { big: f.big_endian });
        Reader { binary }
    }

    fn version(&self) -> MshVersion {
        self.format.map(|f| f.version).unwrap_or(MshVersion::V41)
    }

    /// Reads the section `name` (header already consumed) including its `$End` line.
    fn section<'a>(&mut self, name: &[u8], i: &'a [u8]) -> Result<&'a [u8], nom::Err<PErr<'a>>> {
        let i = match name {
            b"MeshFormat" => {
                if self.format.is_some() {
                    return fail(i, "a second $MeshFormat section").map(|(r, ())| r);
                }
                let (i, f) = mesh_format(i)?;
                self.format = Some(f);
                i
            }
            b"PhysicalNames" => self.physical_names(i)?.0,
            b"Entities" if self.version() == MshVersion::V41 => self.entities(i)?.0,
            b"Nodes" => self.nodes(i)?.0,
            b"Elements" => self.elements(i)?.0,
            b"Periodic" => self.periodic_links(i)?.0,
            _ => skip_section(i, name)?.0,
        };
        Ok(section_end(i, name)?.0)
    }

    fn physical_names<'a>(&mut self, i: &'a [u8]) -> PResult<'a, ()> {
        let at = skip_ws(i);
        let (mut i, n) = uint(i)?;
        let (_, n) = checked_count(at, i, n, 6, "physical names")?;
        for _ in 0..n {
            let at = skip_ws(i);
            let (r, dim) = int32(i)?;
            if !(0..=3).contains(&dim) {
                return fail(at, format!("physical group dimension {dim} is not 0..3"));
            }
            let (r, tag) = int32(r)?;
            let (r, name) = quoted_name(r)?;
            self.named.push(PhysicalGroup {
                name,
                dim: dim as u8,
                tag,
            });
            i = r;
        }
        Ok((i, ()))
    }

    fn entities<'a>(&mut self, i: &'a [u8]) -> PResult<'a, ()> {
        let rd = self.reader();
        let mut counts = [0usize; 4];
        let mut i = i;
        for (d, c) in counts.iter_mut().enumerate() {
            let (r, n) = rd.count(i, 2, 4, ["points", "curves", "surfaces", "volumes"][d])?;
            *c = n;
            i = r;
        }
        if rd.binary.is_none() {
            i = skip_ws(i);
        }
        for (dim, &n) in counts.iter().enumerate() {
            for _ in 0..n {
                let at = skip_ws(i);
                let (r, tag) = rd.int(i, "an entity tag")?;
                let mut r = r;
                let nreal = if dim == 0 { 3 } else { 6 };
                for _ in 0..nreal {
                    r = rd.real(r, "entity coordinates")?.0;
                }
                let (r2, phys) = int_list(rd, r, "physical tags")?;
                r = r2;
                if dim > 0 {
                    r = int_list(rd, r, "bounding entities")?.0;
                }
                if self.entity_physicals[dim].insert(tag, phys).is_some() {
                    return fail(
                        at,
                        format!("entity of dimension {dim} with tag {tag} is defined twice"),
                    );
                }
                i = r;
            }
        }
        self.has_entities = true;
        Ok((i, ()))
    }

    fn nodes<'a>(&mut self, i: &'a [u8]) -> PResult<'a, ()> {
        if self.lookup.is_some() {
            return fail(i, "a second $Nodes section: nlrom reads one");
        }
        let at = i;
        let i = match self.version() {
            MshVersion::V22 => self.nodes_v22(i)?.0,
            MshVersion::V41 => self.nodes_v41(i)?.0,
        };
        self.index_nodes(at)?;
        Ok((i, ()))
    }

    fn nodes_v22<'a>(&mut self, i: &'a [u8]) -> PResult<'a, ()> {
        let rd = self.reader();
        let (mut i, n) = rd_count_ascii(i, 8, 28, rd.binary.is_some(), "nodes")?;
        self.node_tags.reserve(n);
        self.coords.reserve(n);
        match rd.binary {
            Some(e) => {
                i = end_of_line(i)?.0;
                let (r, data) = bytes_n(i, n * 28, "the node records (int tag, 3 doubles)")?;
                for (k, rec) in data.chunks_exact(28).enumerate() {
                    let tag = e.i32(rec);
                    if tag <= 0 {
                        return fail(&i[k * 28..], format!("node tag {tag} is not positive"));
                    }
                    let p = [e.f64(&rec[4..]), e.f64(&rec[12..]), e.f64(&rec[20..])];
                    if !p.iter().all(|v| v.is_finite()) {
                        return fail(
                            &i[k * 28..],
                            format!("node {tag} has a non-finite coordinate"),
                        );
                    }
                    self.node_tags.push(tag as u64);
                    self.coords.push(p);
                }
                i = r;
            }
            None => {
                if let Some(r) = self.nodes_v22_parallel(i, n) {
                    return Ok((r, ()));
                }
                for _ in 0..n {
                    let at = skip_ws(i);
                    let (r, tag) = uint(i)?;
                    if tag == 0 {
                        return fail(at, "node tag 0 is not allowed");
                    }
                    let (r, x) = float(r)?;
                    let (r, y) = float(r)?;
                    let (r, z) = float(r)?;
                    self.node_tags.push(tag);
                    self.coords.push([x, y, z]);
                    i = r;
                }
            }
        }
        Ok((i, ()))
    }

    fn nodes_v41<'a>(&mut self, i: &'a [u8]) -> PResult<'a, ()> {
        let rd = self.reader();
        let (i, nblocks) = rd.count(i, 8, 20, "node blocks")?;
        let at = skip_ws(i);
        let (i, total) = rd.size(i, "the number of nodes")?;
        let (i, total) = checked_count(at, i, total, 4, "nodes")?;
        let (i, _min_tag) = rd.size(i, "the minimum node tag")?;
        let (mut i, _max_tag) = rd.size(i, "the maximum node tag")?;
        // The blocks write into zeroed arrays of the declared size (no `memset` pass, see
        // `ascii::zeroed`); `nodes_read` counts what they hold.
        self.node_tags = ascii::zeroed(total);
        self.coords = ascii::zeroed(total);
        self.nodes_read = 0;
        for _ in 0..nblocks {
            let at = skip_ws(i);
            let (r, dim) = rd.int(i, "the entity dimension")?;
            let (r, _entity) = rd.int(r, "the entity tag")?;
            let (r, parametric) = rd.int(r, "the parametric flag")?;
            if !(0..=3).contains(&dim) || !(0..=1).contains(&parametric) {
                return fail(
                    at,
                    format!(
                        "bad node block header: entity dimension {dim}, parametric {parametric}"
                    ),
                );
            }
            let extra = if parametric == 1 { dim as usize } else { 0 };
            let (r, n) = rd.count(r, 4, 8 + 24, "nodes in the block")?;
            i = match rd.binary {
                Some(e) => self.node_block_binary(r, n, extra, e)?.0,
                None => self.node_block_ascii(r, n, extra)?.0,
            };
        }
        if self.nodes_read != total {
            return fail(
                at,
                format!(
                    "the header declares {total} nodes but the blocks hold {}",
                    self.nodes_read
                ),
            );
        }
        Ok((i, ()))
    }

    /// The slots of the next `n` nodes of a 4.1 `$Nodes` section: index of the first, the
    /// arrays grown if the blocks hold more nodes than the header declares.
    fn next_nodes(&mut self, n: usize) -> usize {
        let first = self.nodes_read;
        if self.node_tags.len() < first + n {
            self.node_tags.resize(first + n, 0);
            self.coords.resize(first + n, [0.0; 3]);
        }
        first
    }

    fn node_block_binary<'a>(
        &mut self,
        i: &'a [u8],
        n: usize,
        extra: usize,
        e: Endian,
    ) -> PResult<'a, ()> {
        let start = i;
        let (i, tags) = bytes_n(i, n * 8, "node tags")?;
        let stride = 8 * (3 + extra);
        let (i, xyz) = bytes_n(i, n * stride, "node coordinates")?;
        let first = self.next_nodes(n);
        for (t, b) in self.node_tags[first..first + n]
            .iter_mut()
            .zip(tags.chunks_exact(8))
        {
            *t = e.u64(b);
        }
        if let Some(k) = self.node_tags[first..first + n]
            .iter()
            .position(|&t| t == 0)
        {
            return fail(&start[k * 8..], "node tag 0 is not allowed");
        }
        let bad = self.coords[first..first + n]
            .par_chunks_mut(PAR_RECORDS)
            .enumerate()
            .filter_map(|(c, out)| {
                let records = xyz[c * PAR_RECORDS * stride..].chunks_exact(stride);
                for (k, (p, rec)) in out.iter_mut().zip(records).enumerate() {
                    *p = [e.f64(rec), e.f64(&rec[8..]), e.f64(&rec[16..])];
                    if !p.iter().all(|v| v.is_finite()) {
                        return Some(c * PAR_RECORDS + k);
                    }
                }
                None
            })
            .min();
        if let Some(k) = bad {
            return fail(&start[n * 8 + k * stride..], "non-finite node coordinate");
        }
        self.nodes_read = first + n;
        Ok((i, ()))
    }

    /// The ASCII node records `tag x y z` of MSH 2.2, one per line, read in parallel
    /// ([`ascii`]); `None` (nothing read) for an empty block or when any line is not such a record:
    /// the caller then reads them sequentially.
    fn nodes_v22_parallel<'a>(&mut self, i: &'a [u8], n: usize) -> Option<&'a [u8]> {
        if n == 0 {
            return None;
        }
        self.node_tags = ascii::zeroed(n);
        self.coords = ascii::zeroed(n);
        let rest = ascii::read_records2(
            skip_ws(i),
            n,
            (&mut self.node_tags, 1),
            (&mut self.coords, 1),
            |line, tag, p| {
                let (r, t) = ascii::uint(line)?;
                let (r, x) = ascii::float(r)?;
                let (r, y) = ascii::float(r)?;
                let (r, z) = ascii::float(r)?;
                (tag[0], p[0]) = (t, [x, y, z]);
                (t != 0).then_some(r)
            },
        );
        if rest.is_none() {
            self.node_tags.clear();
            self.coords.clear();
        }
        rest
    }

    /// A 4.1 ASCII node block (n tag lines, then n coordinate lines) read in parallel into the
    /// next `n` slots, as [`State::nodes_v22_parallel`]; on `None` nothing is counted.
    fn node_block_ascii_parallel<'a>(
        &mut self,
        i: &'a [u8],
        n: usize,
        extra: usize,
    ) -> Option<&'a [u8]> {
        if n == 0 {
            return None;
        }
        let first = self.next_nodes(n);
        let read = ascii::read_records(
            skip_ws(i),
            n,
            1,
            &mut self.node_tags[first..first + n],
            |line, t| {
                let (r, tag) = ascii::uint(line)?;
                t[0] = tag;
                (tag != 0).then_some(r)
            },
        )
        .and_then(|i| {
            ascii::read_records(i, n, 1, &mut self.coords[first..first + n], |line, p| {
                let (r, x) = ascii::float(line)?;
                let (r, y) = ascii::float(r)?;
                let (mut r, z) = ascii::float(r)?;
                for _ in 0..extra {
                    r = ascii::float(r)?.0;
                }
                p[0] = [x, y, z];
                Some(r)
            })
        });
        if read.is_some() {
            self.nodes_read = first + n;
        }
        read
    }

    fn node_block_ascii<'a>(&mut self, mut i: &'a [u8], n: usize, extra: usize) -> PResult<'a, ()> {
        if let Some(r) = self.node_block_ascii_parallel(i, n, extra) {
            return Ok((r, ()));
        }
        let first = self.next_nodes(n);
        for k in first..first + n {
            let at = skip_ws(i);
            let (r, tag) = uint(i)?;
            if tag == 0 {
                return fail(at, "node tag 0 is not allowed");
            }
            self.node_tags[k] = tag;
            i = r;
        }
        for k in first..first + n {
            let (r, x) = float(i)?;
            let (r, y) = float(r)?;
            let (mut r, z) = float(r)?;
            for _ in 0..extra {
                r = float(r)?.0;
            }
            self.coords[k] = [x, y, z];
            i = r;
        }
        self.nodes_read = first + n;
        Ok((i, ()))
    }

    /// Sorts the nodes by tag (if needed), rejects duplicate tags and builds the tag lookup.
    fn index_nodes<'a>(&mut self, at: &'a [u8]) -> PResult<'a, ()> {
        if !self.node_tags.windows(2).all(|w| w[0] < w[1]) {
            let mut order: Vec<usize> = (0..self.node_tags.len()).collect();
            order.sort_unstable_by_key(|&k| self.node_tags[k]);
            self.node_tags = order.iter().map(|&k| self.node_tags[k]).collect();
            self.coords = order.iter().map(|&k| self.coords[k]).collect();
            if let Some(w) = self.node_tags.windows(2).find(|w| w[0] == w[1]) {
                return fail(at, format!("node tag {} appears twice", w[0]));
            }
        }
        if self.node_tags.len() > u32::MAX as usize {
            return fail(at, "more than 4 294 967 295 nodes");
        }
        self.lookup = Some(NodeLookup::new(&self.node_tags));
        Ok((at, ()))
    }

    fn elements<'a>(&mut self, i: &'a [u8]) -> PResult<'a, ()> {
        if self.lookup.is_none() {
            return fail(i, "$Elements before $Nodes: nodes must be defined first");
        }
        match self.version() {
            MshVersion::V22 => self.elements_v22(i),
            MshVersion::V41 => self.elements_v41(i),
        }
    }

    fn elements_v41<'a>(&mut self, i: &'a [u8]) -> PResult<'a, ()> {
        let rd = self.reader();
        let (i, nblocks) = rd.count(i, 8, 20, "element blocks")?;
        let at = skip_ws(i);
        let (i, total) = rd.size(i, "the number of elements")?;
        let (i, total) = checked_count(at, i, total, 4, "elements")?;
        let (i, _) = rd.size(i, "the minimum element tag")?;
        let (mut i, _) = rd.size(i, "the maximum element tag")?;
        let mut read = 0usize;
        for _ in 0..nblocks {
            let at = skip_ws(i);
            let (r, dim) = rd.int(i, "the entity dimension")?;
            let (r, entity) = rd.int(r, "the entity tag")?;
            let type_at = skip_ws(r);
            let (r, ty) = rd.int(r, "the element type")?;
            let kind = element_type(type_at, i64::from(ty))?.1;
            if i32::from(kind.dim()) != dim {
                return fail(
                    at,
                    format!(
                        "a block of {kind} elements (dimension {}) on an entity of dimension {dim}",
                        kind.dim()
                    ),
                );
            }
            let nn = kind.num_nodes();
            let (r, n) = rd.count(r, 2 * (nn + 1), 8 * (nn + 1), "elements in the block")?;
            let mut block = ElementBlock {
                kind,
                entity,
                physicals: Vec::new(),
                tags: ElementTags::default(),
                connectivity: Vec::new(),
            };
            i = match rd.binary {
                Some(e) => self.element_block_binary(r, n, &mut block, e)?.0,
                None => self.element_block_ascii(r, n, &mut block)?.0,
            };
            read += n;
            self.blocks.push(block);
        }
        if read != total {
            return fail(
                at,
                format!("the header declares {total} elements but the blocks hold {read}"),
            );
        }
        Ok((i, ()))
    }

    fn element_block_binary<'a>(
        &self,
        i: &'a [u8],
        n: usize,
        block: &mut ElementBlock,
        e: Endian,
    ) -> PResult<'a, ()> {
        let nn = block.kind.num_nodes();
        let stride = 8 * (nn + 1);
        let start = i;
        let (i, data) = bytes_n(i, n * stride, "element records")?;
        let lookup = self
            .lookup
            .as_ref()
            .expect("nodes are read before elements");
        let mut tags: Vec<u64> = ascii::zeroed(n);
        block.connectivity = ascii::zeroed(n * nn);
        // Fixed-size records: decode chunks of records in parallel; report the first bad one.
        let bad = tags
            .par_chunks_mut(PAR_RECORDS)
            .zip(block.connectivity.par_chunks_mut(PAR_RECORDS * nn))
            .enumerate()
            .filter_map(|(c, (tags, conn))| {
                let first = c * PAR_RECORDS;
                let records = data[first * stride..].chunks_exact(stride);
                for (k, ((tag, out), rec)) in tags
                    .iter_mut()
                    .zip(conn.chunks_exact_mut(nn))
                    .zip(records)
                    .enumerate()
                {
                    *tag = e.u64(rec);
                    for (j, (o, t)) in out.iter_mut().zip(rec[8..].chunks_exact(8)).enumerate() {
                        match lookup.get(e.u64(t)) {
                            Some(idx) => *o = idx,
                            None => return Some((first + k, j)),
                        }
                    }
                }
                None
            })
            .min();
        if let Some((k, j)) = bad {
            let rec = &data[k * stride..];
            let node = e.u64(&rec[8 * (j + 1)..]);
            return fail(
                &start[k * stride + 8 * (j + 1)..],
                unknown_node(e.u64(rec), node),
            );
        }
        block.tags = tags.into();
        Ok((i, ()))
    }

    /// A 4.1 ASCII element block (`tag node...` per line) read in parallel, as
    /// [`State::nodes_v22_parallel`]: the element tags checked to run on from the first one
    /// (Gmsh's numbering, stored as [`ElementTags::Run`]), else read into a list; on `None` the
    /// block is left empty.
    fn element_block_ascii_parallel<'a>(
        lookup: &NodeLookup,
        i: &'a [u8],
        n: usize,
        block: &mut ElementBlock,
    ) -> Option<&'a [u8]> {
        if n == 0 {
            return None;
        }
        let nn = block.kind.num_nodes();
        let i = skip_ws(i);
        let first = ascii::uint(i)?.1;
        block.connectivity = ascii::zeroed(n * nn);
        let read = |tags: ascii::TagsOut<'_>, conn: &mut [u32]| match *lookup {
            // The usual contiguous numbering without the lookup's match per node.
            NodeLookup::Contiguous { first, n: count } => {
                ascii::element_records(i, n, tags, conn, nn, |node| {
                    let k = node.wrapping_sub(first);
                    (k < count).then_some(k as u32)
                })
            }
            _ => ascii::element_records(i, n, tags, conn, nn, |node| lookup.get(node)),
        };
        let rest = match read(ascii::TagsOut::Run(first), &mut block.connectivity) {
            Some(rest) => {
                block.tags = ElementTags::Run { first, len: n };
                Some(rest)
            }
            None => {
                let mut tags: Vec<u64> = ascii::zeroed(n);
                let rest = read(ascii::TagsOut::Store(&mut tags), &mut block.connectivity);
                block.tags = tags.into();
                rest
            }
        };
        if rest.is_none() {
            block.tags = ElementTags::default();
            block.connectivity.clear();
        }
        rest
    }

    fn element_block_ascii<'a>(
        &self,
        mut i: &'a [u8],
        n: usize,
        block: &mut ElementBlock,
    ) -> PResult<'a, ()> {
        let nn = block.kind.num_nodes();
        let lookup = self
            .lookup
            .as_ref()
            .expect("nodes are read before elements");
        if let Some(r) = Self::element_block_ascii_parallel(lookup, i, n, block) {
            return Ok((r, ()));
        }
        for _ in 0..n {
            let (r, tag) = uint(i)?;
            block.tags.push(tag);
            i = r;
            for _ in 0..nn {
                let at = skip_ws(i);
                let (r, node) = uint(i)?;
                match lookup.get(node) {
                    Some(idx) => block.connectivity.push(idx),
                    None => return fail(at, unknown_node(tag, node)),
                }
                i = r;
            }
        }
        Ok((i, ()))
    }

    fn elements_v22<'a>(&mut self, i: &'a [u8]) -> PResult<'a, ()> {
        let rd = self.reader();
        let (i, n) = rd_count_ascii(i, 8, 16, rd.binary.is_some(), "elements")?;
        match rd.binary {
            Some(e) => self.elements_v22_binary(end_of_line(i)?.0, n, e),
            None => self.elements_v22_ascii(i, n),
        }
    }

    /// The ASCII element records of MSH 2.2 (`tag type ntags tag... node...` per line) read in
    /// parallel, as [`State::nodes_v22_parallel`]: each chunk of lines gives its runs of
    /// consecutive elements of one (type, entity, physical), appended in order to the blocks as
    /// the sequential reader does ([`State::block_v22`]). On `None` nothing is kept.
    fn elements_v22_ascii_parallel<'a>(&mut self, i: &'a [u8], n: usize) -> Option<&'a [u8]> {
        struct Run {
            kind: ElementType,
            entity: i32,
            physical: i32,
            tags: ElementTags,
            connectivity: Vec<u32>,
        }
        if n == 0 {
            return None;
        }
        let lookup = self.lookup.as_ref()?;
        let start = skip_ws(i);
        let (chunks, end) = ascii::line_chunks(start, n, ascii::lines_per_chunk(n))?;
        let runs: Vec<Vec<Run>> = chunks
            .par_iter()
            .map(|&(first, lines)| {
                let mut runs: Vec<Run> = Vec::new();
                let mut r = &start[first..];
                for _ in 0..lines {
                    let (r1, tag) = ascii::uint(r)?;
                    let (r1, ty) = ascii::uint(r1)?;
                    let kind = element_type(r1, ty as i64).ok()?.1;
                    let (mut r1, ntags) = ascii::uint(r1)?;
                    if ntags > 64 {
                        return None;
                    }
                    let mut tags = [0i32; 2];
                    for k in 0..ntags as usize {
                        let (r2, t) = ascii::int32(r1)?;
                        if let Some(slot) = tags.get_mut(k) {
                            *slot = t;
                        }
                        r1 = r2;
                    }
                    let [physical, entity] = tags;
                    let same = runs.last().is_some_and(|l: &Run| {
                        l.kind == kind && l.entity == entity && l.physical == physical
                    });
                    if !same {
                        // Most chunks hold one run: room for all their lines.
                        let room = if runs.is_empty() { lines } else { 0 };
                        let mut run = Run {
                            kind,
                            entity,
                            physical,
                            tags: ElementTags::default(),
                            connectivity: Vec::with_capacity(room * kind.num_nodes()),
                        };
                        ascii::huge_pages(&mut run.connectivity);
                        runs.push(run);
                    }
                    let run = runs.last_mut().expect("pushed");
                    run.tags.push(tag);
                    for _ in 0..kind.num_nodes() {
                        let (r2, node) = ascii::uint(r1)?;
                        run.connectivity.push(lookup.get(node)?);
                        r1 = r2;
                    }
                    r = ascii::line_end(r1)?;
                }
                Some(runs)
            })
            .collect::<Option<_>>()?;
        for run in runs.into_iter().flatten() {
            let b = self.block_v22(run.kind, run.entity, run.physical);
            let b = &mut self.blocks[b];
            if b.tags.is_empty() {
                (b.tags, b.connectivity) = (run.tags, run.connectivity);
            } else {
                b.tags.extend(&run.tags);
                b.connectivity.extend_from_slice(&run.connectivity);
            }
        }
        Some(&start[end..])
    }

    fn elements_v22_ascii<'a>(&mut self, mut i: &'a [u8], n: usize) -> PResult<'a, ()> {
        if let Some(r) = self.elements_v22_ascii_parallel(i, n) {
            return Ok((r, ()));
        }
        for _ in 0..n {
            let (r, tag) = uint(i)?;
            let type_at = skip_ws(r);
            let (r, ty) = uint(r)?;
            let (_, kind) = element_type(type_at, ty as i64)?;
            let ntags_at = skip_ws(r);
            let (mut r, ntags) = uint(r)?;
            if ntags > 64 {
                return fail(ntags_at, format!("element {tag} declares {ntags} tags"));
            }
            let mut tags = [0i32; 2];
            for k in 0..ntags as usize {
                let (r2, t) = int32(r)?;
                if let Some(slot) = tags.get_mut(k) {
                    *slot = t;
                }
                r = r2;
            }
            let block = self.block_v22(kind, tags[1], tags[0]);
            let lookup = self
                .lookup
                .as_ref()
                .expect("nodes are read before elements");
            let mut conn = [0u32; 27];
            for c in conn.iter_mut().take(kind.num_nodes()) {
                let at = skip_ws(r);
                let (r2, node) = uint(r)?;
                *c = match lookup.get(node) {
                    Some(idx) => idx,
                    None => return fail(at, unknown_node(tag, node)),
                };
                r = r2;
            }
            let b = &mut self.blocks[block];
            b.tags.push(tag);
            b.connectivity.extend_from_slice(&conn[..kind.num_nodes()]);
            i = r;
        }
        Ok((i, ()))
    }

    fn elements_v22_binary<'a>(&mut self, mut i: &'a [u8], n: usize, e: Endian) -> PResult<'a, ()> {
        let mut read = 0usize;
        while read < n {
            let (r, head) = bytes_n(i, 12, "an element header (type, count, number of tags)")?;
            let ty = e.i32(head);
            let (_, kind) = element_type(i, i64::from(ty))?;
            let follow = e.i32(&head[4..]);
            let ntags = e.i32(&head[8..]);
            if follow <= 0 || (follow as usize) > n - read || !(0..=64).contains(&ntags) {
                return fail(
                    &i[4..],
                    format!(
                        "bad element header: {follow} elements with {ntags} tags ({} of {n} read)",
                        read
                    ),
                );
            }
            let nn = kind.num_nodes();
            let stride = 4 * (1 + ntags as usize + nn);
            let start = r;
            let (r, data) = bytes_n(r, follow as usize * stride, "element records")?;
            for (k, rec) in data.chunks_exact(stride).enumerate() {
                let tag = e.i32(rec);
                if tag <= 0 {
                    return fail(
                        &start[k * stride..],
                        format!("element tag {tag} is not positive"),
                    );
                }
                let physical = if ntags >= 1 { e.i32(&rec[4..]) } else { 0 };
                let entity = if ntags >= 2 { e.i32(&rec[8..]) } else { 0 };
                let block = self.block_v22(kind, entity, physical);
                let lookup = self
                    .lookup
                    .as_ref()
                    .expect("nodes are read before elements");
                let nodes_at = 4 * (1 + ntags as usize);
                let mut conn = [0u32; 27];
                for (j, c) in conn.iter_mut().take(nn).enumerate() {
                    let node = e.i32(&rec[nodes_at + 4 * j..]);
                    *c = match u64::try_from(node).ok().and_then(|t| lookup.get(t)) {
                        Some(idx) => idx,
                        None => {
                            return fail(
                                &start[k * stride + nodes_at + 4 * j..],
                                unknown_node(tag as u64, node as u64),
                            )
                        }
                    };
                }
                let b = &mut self.blocks[block];
                b.tags.push(tag as u64);
                b.connectivity.extend_from_slice(&conn[..nn]);
            }
            read += follow as usize;
            i = r;
        }
        Ok((i, ()))
    }

    /// The block that a 2.2 element of `kind` on `entity` with physical tag `physical` (0 = none)
    /// goes to: the last block if it matches, else a new one.
    fn block_v22(&mut self, kind: ElementType, entity: i32, physical: i32) -> usize {
        let physicals = if physical != 0 {
            vec![physical]
        } else {
            Vec::new()
        };
        if let Some(last) = self.blocks.last() {
            if last.kind == kind && last.entity == entity && last.physicals == physicals {
                return self.blocks.len() - 1;
            }
        }
        self.blocks.push(ElementBlock {
            kind,
            entity,
            physicals,
            tags: ElementTags::default(),
            connectivity: Vec::new(),
        });
        self.blocks.len() - 1
    }

    fn periodic_links<'a>(&mut self, i: &'a [u8]) -> PResult<'a, ()> {
        if self.lookup.is_none() {
            return fail(i, "$Periodic before $Nodes: nodes must be defined first");
        }
        // MSH 2.2 writes $Periodic in ASCII even in binary files.
        let rd = match self.version() {
            MshVersion::V22 => Reader { binary: None },
            MshVersion::V41 => self.reader(),
        };
        let (mut i, n) = rd.count(i, 6, 20, "periodic links")?;
        for _ in 0..n {
            let at = skip_ws(i);
            let (r, dim) = rd.int(i, "the entity dimension")?;
            if !(0..=3).contains(&dim) {
                return fail(at, format!("periodic entity dimension {dim} is not 0..3"));
            }
            let (r, entity) = rd.int(r, "the entity tag")?;
            let (r, master) = rd.int(r, "the master entity tag")?;
            let (r, affine) = self.periodic_affine(rd, r)?;
            let (mut r, npairs) = rd.count(r, 4, 16, "periodic node pairs")?;
            let lookup = self.lookup.as_ref().expect("checked above");
            let mut nodes = Vec::with_capacity(npairs);
            for _ in 0..npairs {
                let at = skip_ws(r);
                let (r2, a) = rd.size(r, "a node tag")?;
                let (r2, b) = rd.size(r2, "a master node tag")?;
                match (lookup.get(a), lookup.get(b)) {
                    (Some(x), Some(y)) => nodes.push((x, y)),
                    _ => {
                        return fail(
                            at,
                            format!(
                                "periodic node pair ({a}, {b}) names a node that is not in $Nodes"
                            ),
                        )
                    }
                }
                r = r2;
            }
            self.periodic.push(PeriodicLink {
                dim: dim as u8,
                entity,
                master,
                affine,
                nodes,
            });
            i = r;
        }
        Ok((i, ()))
    }

    /// The optional affine transform of a periodic link: 2.2 `Affine a1..a16` line, 4.1 a count
    /// followed by that many reals.
    fn periodic_affine<'a>(&self, rd: Reader, i: &'a [u8]) -> PResult<'a, Vec<f64>> {
        let mut affine = Vec::new();
        match self.version() {
            MshVersion::V22 => {
                let s = skip_ws(i);
                if let Ok((mut r, _)) = tag::<&[u8], &[u8], PErr<'_>>(b"Affine").parse(s) {
                    for _ in 0..16 {
                        let (r2, v) = float(r)?;
                        affine.push(v);
                        r = r2;
                    }
                    return Ok((r, affine));
                }
                Ok((i, affine))
            }
            MshVersion::V41 => {
                let (mut r, n) = rd.count(i, 2, 8, "affine values")?;
                for _ in 0..n {
                    let (r2, v) = rd.real(r, "the affine transform")?;
                    affine.push(v);
                    r = r2;
                }
                Ok((r, affine))
            }
        }
    }

    /// Resolves physical groups and builds the mesh.
    fn finish(mut self, whole: &[u8]) -> Result<Mesh, MshError> {
        let format = self.format.ok_or_else(|| {
            located(
                whole,
                whole,
                "$MeshFormat",
                "not a Gmsh MSH file: no $MeshFormat section",
            )
        })?;
        if self.lookup.is_none() {
            return Err(located(
                whole,
                &[],
                "$Nodes",
                "the file has no $Nodes section",
            ));
        }
        if format.version == MshVersion::V41 {
            for b in &mut self.blocks {
                let dim = b.kind.dim() as usize;
                b.physicals = self.entity_physicals[dim]
                    .get(&b.entity)
                    .cloned()
                    .unwrap_or_default();
            }
        }
        let mut groups = self.named;
        let mut known: BTreeSet<(u8, i32)> = groups.iter().map(|g| (g.dim, g.tag)).collect();
        for b in &self.blocks {
            for &p in &b.physicals {
                let key = (b.kind.dim(), p);
                if known.insert(key) {
                    groups.push(PhysicalGroup {
                        name: format!("dim{}_tag{}", key.0, key.1),
                        dim: key.0,
                        tag: key.1,
                    });
                }
            }
        }
        Ok(Mesh {
            source: None,
            format,
            node_tags: self.node_tags,
            coords: self.coords,
            blocks: self.blocks,
            groups,
            periodic: self.periodic,
        })
    }
}

/// `$MeshFormat` body: `version file-type data-size`, then for binary files the check integer.
fn mesh_format(i: &[u8]) -> PResult<'_, MshFormat> {
    let at = skip_ws(i);
    let (i, ver) = token(i)?;
    let version = match ver {
        b"4.1" => MshVersion::V41,
        b"2.2" | b"2.1" | b"2" | b"2.0" => MshVersion::V22,
        b"4" | b"4.0" => {
            return fail(at, "MSH 4.0 is not supported: re-export the mesh from Gmsh as 4.1 (Mesh.MshFileVersion = 4.1) or 2.2")
        }
        _ => return fail(at, format!("unsupported MSH version '{}': nlrom reads 2.2 and 4.1", show(ver))),
    };
    let ft_at = skip_ws(i);
    let (i, file_type) = uint(i)?;
    if file_type > 1 {
        return fail(
            ft_at,
            format!("file-type {file_type} is neither 0 (ASCII) nor 1 (binary)"),
        );
    }
    let ds_at = skip_ws(i);
    let (i, data_size) = uint(i)?;
    if data_size != 8 {
        return fail(
            ds_at,
            format!("data-size {data_size} is not supported (only 8)"),
        );
    }
    let mut big_endian = false;
    let mut i = i;
    if file_type == 1 {
        let (r, ()) = end_of_line(i)?;
        let start = r;
        let (r, one) = bytes_n(r, 4, "the binary check integer")?;
        let word = [one[0], one[1], one[2], one[3]];
        big_endian = if i32::from_le_bytes(word) == 1 {
            false
        } else if i32::from_be_bytes(word) == 1 {
            true
        } else {
            return fail(
                start,
                "the binary check integer is not 1 in either byte order: the file is corrupt",
            );
        };
        i = r;
    }
    Ok((
        i,
        MshFormat {
            version,
            binary: file_type == 1,
            big_endian,
        },
    ))
}

/// A count on an ASCII line (2.2 headers are ASCII also in binary files), checked against the
/// bytes that remain (`min_ascii` / `min_binary` bytes per item).
fn rd_count_ascii<'a>(
    i: &'a [u8],
    min_ascii: usize,
    min_binary: usize,
    binary: bool,
    what: &str,
) -> PResult<'a, usize> {
    let at = skip_ws(i);
    let (rest, n) = uint(i)?;
    checked_count(
        at,
        rest,
        n,
        if binary { min_binary } else { min_ascii },
        what,
    )
}

/// A list `n v1 .. vn` of `int`s preceded by its `size_t` length.
fn int_list<'a>(rd: Reader, i: &'a [u8], what: &str) -> PResult<'a, Vec<i32>> {
    let (mut i, n) = rd.count(i, 2, 4, what)?;
    let mut out = Vec::with_capacity(n);
    for _ in 0..n {
        let (r, v) = rd.int(i, what)?;
        out.push(v);
        i = r;
    }
    Ok((i, out))
}

/// A physical name in double quotes (Gmsh writes them so; an unquoted word is accepted).
fn quoted_name(i: &[u8]) -> PResult<'_, String> {
    let i = skip_ws(i);
    if let Some(body) = i.strip_prefix(b"\"") {
        let n = match body.iter().position(|&c| c == b'"' || c == b'\n') {
            Some(n) if body[n] == b'"' => n,
            _ => return fail(i, "unterminated physical name (missing closing '\"')"),
        };
        return Ok((
            &body[n + 1..],
            String::from_utf8_lossy(&body[..n]).into_owned(),
        ));
    }
    let (r, tok) = token(i)?;
    Ok((r, String::from_utf8_lossy(tok).into_owned()))
}

/// The element type for a Gmsh type number, or an error naming it.
fn element_type(at: &[u8], ty: i64) -> PResult<'_, ElementType> {
    match ElementType::from_gmsh(ty) {
        Some(k) => Ok((at, k)),
        None => fail(
            at,
            format!("unknown or unsupported element type {ty}: nlrom reads Gmsh types 1-19 (points, lines, triangles, quads, tetrahedra, hexahedra, prisms, pyramids up to second order)"),
        ),
    }
}

fn unknown_node(element: u64, node: u64) -> String {
    format!("element {element} references node {node}, which is not in $Nodes")
}

/// Skips an unknown section up to (not including) its `$End<name>`.
fn skip_section<'a>(i: &'a [u8], name: &[u8]) -> PResult<'a, ()> {
    let mut closing = b"$End".to_vec();
    closing.extend_from_slice(name);
    let found = take_until::<&[u8], &[u8], nom::error::Error<&[u8]>>(closing.as_slice())
        .parse(i)
        .map(|(rest, _)| rest);
    match found {
        Ok(rest) => Ok((rest, ())),
        Err(_) => fail(
            &i[i.len()..],
            format!(
                "missing ${}: the file ends inside the section",
                String::from_utf8_lossy(&closing[1..])
            ),
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const TINY_41: &str = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n2\n2 1 \"face\"\n3 2 \"solid body\"\n$EndPhysicalNames\n$Entities\n0 0 1 1\n5 0 0 0 1 1 0 1 1 0\n7 0 0 0 1 1 1 1 2 1 5\n$EndEntities\n$Nodes\n2 4 10 40\n2 5 0 3\n10\n20\n30\n0 0 0\n1 0 0\n0 1 0\n3 7 0 1\n40\n0 0 1\n$EndNodes\n$Elements\n2 2 1 9\n2 5 2 1\n1 10 20 30\n3 7 4 1\n9 10 20 30 40\n$EndElements\n";

    /// The parallel line readers take large blocks of one record per line (the integration test
    /// `msh_parallel` checks that they give what the sequential reader gives).
    #[test]
    fn large_ascii_blocks_take_the_parallel_readers() {
        let n = 3 * ascii::CHUNK_LINES + 5;
        let mut nodes = String::from("\n");
        for k in 1..=n {
            nodes += &format!("{k} {}.5 -{k}e-3 0\n", k % 97);
        }
        let mut state = State::default();
        let rest = state.nodes_v22_parallel(nodes.as_bytes(), n).unwrap();
        assert!(rest.is_empty());
        assert_eq!(state.node_tags, (1..=n as u64).collect::<Vec<_>>());
        assert_eq!(state.coords[9], [10.5, -10e-3, 0.0]);
        state.index_nodes(b"").unwrap();
        let lookup = state.lookup.as_ref().unwrap();
        let mut elements = String::from("\n");
        for e in 1..=n {
            elements += &format!("{e} {} {} {}\n", e, e % n + 1, (e + 1) % n + 1);
        }
        let mut block = ElementBlock {
            kind: ElementType::Triangle3,
            entity: 1,
            physicals: Vec::new(),
            tags: ElementTags::default(),
            connectivity: Vec::new(),
        };
        let rest = State::element_block_ascii_parallel(lookup, elements.as_bytes(), n, &mut block)
            .unwrap();
        assert!(rest.is_empty());
        assert_eq!(block.tags.len(), n);
        assert_eq!(&block.connectivity[..6], &[0, 1, 2, 1, 2, 3]);
        // A record over two lines, or an unknown node: refused (the sequential reader decides).
        let broken = elements.replacen("7 7 ", "7\n7 ", 1);
        assert!(
            State::element_block_ascii_parallel(lookup, broken.as_bytes(), n, &mut block).is_none()
        );
        assert!(block.tags.is_empty() && block.connectivity.is_empty());
        let unknown = elements.replacen("\n9 9 ", &format!("\n9 {} ", n + 1), 1);
        assert!(
            State::element_block_ascii_parallel(lookup, unknown.as_bytes(), n, &mut block)
                .is_none()
        );
    }

    #[test]
    fn tiny_41_ascii() {
        let m = parse_msh(TINY_41.as_bytes()).expect("parses");
        assert_eq!(m.node_tags, vec![10, 20, 30, 40]);
        assert_eq!(m.coords[3], [0.0, 0.0, 1.0]);
        assert_eq!(m.blocks.len(), 2);
        assert_eq!(m.blocks[1].kind, ElementType::Tetra4);
        assert_eq!(m.blocks[1].connectivity, vec![0, 1, 2, 3]);
        let g = m.group("solid body").expect("group");
        assert_eq!(m.group_element_count(g), 1);
        let face = m.group("face").expect("face");
        assert_eq!(m.group_node_indices(face), vec![0, 1, 2]);
        assert_eq!(m.group_node_count(face), 3);
        assert_eq!(m.group_node_count(g), 4);
    }

    #[test]
    fn errors_carry_line_and_section() {
        let bad = TINY_41.replace("1 10 20 30\n", "1 10 20 31\n");
        let e = parse_msh(bad.as_bytes()).expect_err("unknown node");
        assert_eq!(e.section, "$Elements");
        assert_eq!(e.line, 30);
        assert!(e.message.contains("node 31"), "{}", e.message);
    }

    #[test]
    fn parametric_node_blocks_are_read_past() {
        // 4.1 ASCII: a parametric curve block (x y z u) and a parametric surface block (x y z u v).
        let text = "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$Nodes\n2 3 1 3\n1 4 1 1\n1\n0 0 0 0.5\n2 5 1 2\n2\n3\n1 0 0 0.1 0.2\n0 1 0 0.3 0.4\n$EndNodes\n$Elements\n1 1 1 1\n2 5 2 1\n1 1 2 3\n$EndElements\n";
        let m = parse_msh(text.as_bytes()).expect("parses");
        assert_eq!(
            m.coords,
            vec![[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]
        );
        // The same in binary: tags, then (x y z u v) per node of the surface block.
        let mut b = b"$MeshFormat\n4.1 1 8\n".to_vec();
        b.extend_from_slice(&1i32.to_le_bytes());
        b.extend_from_slice(b"\n$EndMeshFormat\n$Nodes\n");
        for v in [1u64, 2, 1, 2] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for v in [2i32, 5, 1] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&2u64.to_le_bytes());
        b.extend_from_slice(&1u64.to_le_bytes());
        b.extend_from_slice(&2u64.to_le_bytes());
        for v in [1.0f64, 2.0, 3.0, 0.1, 0.2, 4.0, 5.0, 6.0, 0.3, 0.4] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(b"\n$EndNodes\n");
        let m = parse_msh(&b).expect("parses");
        assert_eq!(m.coords, vec![[1.0, 2.0, 3.0], [4.0, 5.0, 6.0]]);
    }

    #[test]
    fn extreme_node_tags_do_not_overflow() {
        // Found by reading after fuzzing: tags 0 and u64::MAX made `last - first + 1` overflow.
        let input = b"$MeshFormat\n2 0 8\n$EndMeshFormat\n$Nodes\n2\n0 0 0 0\n18446744073709551615 0 0 0\n$EndNodes\n";
        let e = parse_msh(input).expect_err("tag 0");
        assert!(e.message.contains("node tag 0"), "{e}");
        let input = b"$MeshFormat\n2 0 8\n$EndMeshFormat\n$Nodes\n2\n1 0 0 0\n18446744073709551615 0 0 0\n$EndNodes\n";
        let m = parse_msh(input).expect("parses");
        assert_eq!(m.node_index(u64::MAX), Some(1));
    }

    /// A binary 4.1 mesh of `n` nodes on a line and one block of `n` point elements.
    fn binary_points(n: u64) -> Vec<u8> {
        let mut b = b"$MeshFormat\n4.1 1 8\n".to_vec();
        b.extend_from_slice(&1i32.to_le_bytes());
        b.extend_from_slice(b"\n$EndMeshFormat\n$Nodes\n");
        for v in [1u64, n, 1, n] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for v in [0i32, 1, 0] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&n.to_le_bytes());
        (1..=n).for_each(|t| b.extend_from_slice(&t.to_le_bytes()));
        (1..=n).for_each(|t| {
            [t as f64, 0.0, 0.0]
                .iter()
                .for_each(|x| b.extend_from_slice(&x.to_le_bytes()))
        });
        b.extend_from_slice(b"\n$EndNodes\n$Elements\n");
        for v in [1u64, n, 1, n] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        for v in [0i32, 1, 15] {
            b.extend_from_slice(&v.to_le_bytes());
        }
        b.extend_from_slice(&n.to_le_bytes());
        (1..=n).for_each(|t| {
            [t, n + 1 - t]
                .iter()
                .for_each(|x| b.extend_from_slice(&x.to_le_bytes()))
        });
        b.extend_from_slice(b"\n$EndElements\n");
        b
    }

    #[test]
    fn parallel_binary_blocks_keep_order_and_report_the_first_error() {
        let n = 4 * PAR_RECORDS as u64 + 17;
        let bytes = binary_points(n);
        let m = parse_msh(&bytes).expect("parses");
        assert_eq!(m.coords[40_000], [40_001.0, 0.0, 0.0]);
        assert_eq!(m.blocks[0].tags.at(40_000), 40_001);
        assert_eq!(m.blocks[0].connectivity[40_000], (n - 40_001) as u32);
        // Break elements 40 000 and 50 000 (in different parallel chunks): the first is reported.
        let elements = bytes
            .windows(10)
            .position(|w| w == b"$Elements\n")
            .expect("elements")
            + 10
            + 32
            + 20;
        let mut bad = bytes.clone();
        for k in [50_000usize, 40_000] {
            let at = elements + 16 * k + 8;
            bad[at..at + 8].copy_from_slice(&(n + 5).to_le_bytes());
        }
        let e = parse_msh(&bad).expect_err("unknown node");
        assert_eq!(e.offset, elements + 16 * 40_000 + 8, "{e}");
        assert!(e.message.contains("element 40001"), "{e}");
        // A non-finite coordinate in the third chunk.
        let nodes = bytes
            .windows(7)
            .position(|w| w == b"$Nodes\n")
            .expect("nodes")
            + 7
            + 32
            + 20;
        let at = nodes + 8 * n as usize + 24 * 40_000 + 8;
        let mut bad = bytes;
        bad[at..at + 8].copy_from_slice(&f64::NAN.to_le_bytes());
        let e = parse_msh(&bad).expect_err("NaN");
        assert_eq!(e.offset, nodes + 8 * n as usize + 24 * 40_000, "{e}");
    }

    #[test]
    fn integers_at_the_limits() {
        assert_eq!(
            uint(b"18446744073709551615 x").map(|r| r.1).ok(),
            Some(u64::MAX)
        );
        assert_eq!(
            uint(b"12345678901234567890\n").map(|r| r.1).ok(),
            Some(12_345_678_901_234_567_890)
        );
        assert!(uint(b"18446744073709551616").is_err());
        assert!(uint(b"12a").is_err());
        assert_eq!(int32(b" -2147483648 ").map(|r| r.1).ok(), Some(i32::MIN));
        assert!(int32(b"2147483648").is_err());
        assert!(int32(b"-").is_err());
    }

    #[test]
    fn node_lookup_variants() {
        let dense = NodeLookup::new(&[1, 3, 7]);
        assert!(matches!(dense, NodeLookup::Dense(_)));
        assert_eq!(dense.get(7), Some(2));
        assert_eq!(dense.get(2), None);
        let sparse = NodeLookup::new(&[5, 1 << 40]);
        assert!(matches!(sparse, NodeLookup::Sparse(_)));
        assert_eq!(sparse.get(1 << 40), Some(1));
        let contiguous = NodeLookup::new(&[4, 5, 6]);
        assert_eq!(contiguous.get(3), None);
        assert_eq!(contiguous.get(6), Some(2));
    }
}
