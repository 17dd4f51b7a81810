//! Reading a case file: TOML parsing with the error located at its key (file, line, column,
//! key path), path resolution against the case's directory, and the key-naming error helpers
//! the validation uses.

use super::*;

/// One step of a key path: a table key or an array index.
#[derive(Clone, Debug, PartialEq)]
pub(super) enum Seg {
    Key(String),
    Index(usize),
}

/// A path to a value in the case file, displayed as `contact[0].mu` or `sweep."contact.a.n0"[2]`.
#[derive(Clone, Debug, Default, PartialEq)]
pub(super) struct KeyPath(pub(super) Vec<Seg>);

impl KeyPath {
    /// Parses `a.b[2].c` (keys without dots).
    pub(super) fn parse(s: &str) -> KeyPath {
        let mut segs = Vec::new();
        for part in s.split('.').filter(|p| !p.is_empty()) {
            let mut pieces = part.split('[');
            if let Some(key) = pieces.next().filter(|k| !k.is_empty()) {
                segs.push(Seg::Key(key.to_string()));
            }
            for idx in pieces {
                if let Ok(i) = idx.trim_end_matches(']').parse() {
                    segs.push(Seg::Index(i));
                }
            }
        }
        KeyPath(segs)
    }

    /// The path of a sweep value: `sweep."<key>"[index]`.
    pub(super) fn sweep(key: &str, index: Option<usize>) -> KeyPath {
        let mut segs = vec![Seg::Key("sweep".into()), Seg::Key(key.into())];
        segs.extend(index.map(Seg::Index));
        KeyPath(segs)
    }

    /// Converts a `serde_path_to_error` path.
    pub(super) fn from_serde(p: &serde_path_to_error::Path) -> KeyPath {
        use serde_path_to_error::Segment;
        KeyPath(
            p.iter()
                .filter_map(|s| match s {
                    Segment::Seq { index } => Some(Seg::Index(*index)),
                    Segment::Map { key } => Some(Seg::Key(key.clone())),
                    Segment::Enum { variant } => Some(Seg::Key(variant.clone())),
                    _ => None,
                })
                .collect(),
        )
    }
}

impl fmt::Display for KeyPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, s) in self.0.iter().enumerate() {
            match s {
                Seg::Index(n) => write!(f, "[{n}]")?,
                Seg::Key(k) => {
                    if i > 0 {
                        f.write_str(".")?;
                    }
                    let bare = !k.is_empty()
                        && k.chars()
                            .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
                    if bare {
                        f.write_str(k)?
                    } else {
                        write!(f, "\"{k}\"")?
                    }
                }
            }
        }
        Ok(())
    }
}

/// 1-based (line, column) of byte `offset` in `text`.
pub(super) fn line_col(text: &str, offset: usize) -> (usize, usize) {
    let offset = offset.min(text.len());
    let before = text.get(..offset).unwrap_or(text);
    let line = before.matches('\n').count() + 1;
    let col = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
    (line, col)
}

/// Byte span of the value at `path` in the TOML `text` (of the deepest part of the path found).
pub(super) fn locate(text: &str, path: &KeyPath) -> Option<std::ops::Range<usize>> {
    let root = toml::de::DeTable::parse(text).ok()?;
    let mut span = root.span();
    let root = toml::de::DeValue::Table(root.into_inner());
    let mut cur = &root;
    for seg in &path.0 {
        let next = match seg {
            Seg::Key(k) => cur.get(k.as_str()),
            Seg::Index(i) => cur.get(*i),
        };
        let Some(next) = next else { break };
        span = next.span();
        cur = next.get_ref();
    }
    Some(span)
}

/// `file: line L, column C: key 'path': message`, leaving out what is unknown.
pub(super) fn format_error(
    file: &Path,
    text: &str,
    path: &KeyPath,
    span: Option<std::ops::Range<usize>>,
    with_column: bool,
    msg: &str,
) -> Error {
    let mut s = file.display().to_string();
    if let Some(span) = span {
        let (line, col) = line_col(text, span.start);
        s += &format!(": line {line}");
        if with_column {
            s += &format!(", column {col}");
        }
    }
    if !path.0.is_empty() {
        s += &format!(": key '{path}'");
    }
    Error::input(format!("{s}: {msg}"))
}

/// Parses the TOML text into a [`Case`] (no path resolution, no validation).
pub(super) fn parse_toml(text: &str, file: &Path) -> Result<Case> {
    let de = toml::de::Deserializer::parse(text).map_err(|e| {
        format_error(
            file,
            text,
            &KeyPath::default(),
            e.span(),
            true,
            e.message().trim(),
        )
    })?;
    serde_path_to_error::deserialize(de).map_err(|e| {
        let path = KeyPath::from_serde(e.path());
        let inner = e.inner();
        let span = inner.span().or_else(|| locate(text, &path));
        format_error(file, text, &path, span, true, inner.message().trim())
    })
}

impl Case {
    /// Reads, parses and validates the case file at `path`; relative paths in it are resolved
    /// against its directory.
    pub fn load(path: &Path) -> Result<Case> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Case::from_str(&text, path)
    }

    /// Parses and validates case text as if read from `path` (used in messages and as the base
    /// of relative paths).
    pub fn from_str(text: &str, path: &Path) -> Result<Case> {
        let mut case = parse_toml(text, path)?;
        case.path = path.to_path_buf();
        case.source_text = text.to_string();
        if case.title.is_empty() {
            case.title = path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default();
        }
        case.resolve_paths();
        case.validate()?;
        case.sweep_points()?;
        Ok(case)
    }

    /// The directory relative paths of the case refer to.
    pub fn base_dir(&self) -> PathBuf {
        self.path
            .parent()
            .map(Path::to_path_buf)
            .unwrap_or_default()
    }

    /// Joins every relative path of the case to [`Case::base_dir`].
    pub(super) fn resolve_paths(&mut self) {
        let dir = self.base_dir();
        let fix = |p: &mut PathBuf| {
            if p.is_relative() {
                *p = dir.join(&*p);
            }
        };
        let m = &mut self.model;
        m.mesh.iter_mut().for_each(fix);
        m.stiffness.iter_mut().for_each(fix);
        m.mass.iter_mut().for_each(fix);
        m.dofs.iter_mut().for_each(fix);
        if let Some(Damping::Matrix(p)) = &mut m.damping {
            fix(p);
        }
        if let Some(o) = &mut self.output {
            fix(&mut o.file);
        }
        if let Some(r) = &mut self.rom {
            fix(&mut r.file);
        }
    }

    /// An input error at `key` (its line found in the source text).
    pub(super) fn key_error(&self, key: &KeyPath, msg: impl fmt::Display) -> Error {
        let span = locate(&self.source_text, key);
        format_error(
            &self.path,
            &self.source_text,
            key,
            span,
            false,
            &msg.to_string(),
        )
    }

    /// `Ok(())` if `ok`, else an input error at `key` with the message `msg()`.
    pub(super) fn require<M: fmt::Display>(
        &self,
        ok: bool,
        key: &str,
        msg: impl FnOnce() -> M,
    ) -> Result<()> {
        if ok {
            Ok(())
        } else {
            Err(self.key_error(&KeyPath::parse(key), msg()))
        }
    }

    /// Error unless `v` is finite and > 0.
    pub(super) fn positive(&self, key: &str, v: f64) -> Result<()> {
        self.require(v.is_finite() && v > 0.0, key, || {
            format!("must be a finite number > 0 (found {v})")
        })
    }

    /// Error unless `v` is finite and ≥ 0.
    pub(super) fn non_negative(&self, key: &str, v: f64) -> Result<()> {
        self.require(v.is_finite() && v >= 0.0, key, || {
            format!("must be a finite number ≥ 0 (found {v})")
        })
    }

    /// Error unless every value is finite.
    pub(super) fn finite(&self, key: &str, v: &[f64]) -> Result<()> {
        match v.iter().find(|x| !x.is_finite()) {
            None => Ok(()),
            Some(x) => {
                Err(self.key_error(&KeyPath::parse(key), format!("must be finite (found {x})")))
            }
        }
    }
}
