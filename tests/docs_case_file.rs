//! `docs/case-file.md` documents the whole case schema, so that a user can write a case from it
//! alone:
//!
//! - every key of the schema appears in it. The keys are derived from the source of the schema
//!   (`src/case.rs` or `src/case/**/*.rs`): every struct that derives `Deserialize` is a table,
//!   its fields are keys (`#[serde(rename = "…")]` and every `alias` honoured, `#[serde(skip)]`
//!   left out), a field whose type is another such struct — or a type read through
//!   `#[serde(try_from = "Spec")]` — is a nested table, walked from `Case` down. A key is documented when it is the first cell
//!   of a table row of the page, written as its full dotted path (`contact.misalignment.rotate.axis`);
//! - every key used by a bundled case (`cases/**/*.toml`) is documented there, and every sweep
//!   path they use matches a documented sweepable path.
//!
//! The parser is checked on a small synthetic schema, and the comparison on a page with a key
//! left out, so that neither test can pass by finding nothing.

use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

// ---------------------------------------------------------------------------------------------
// The schema, read from the serde structs
// ---------------------------------------------------------------------------------------------

/// A deserialised type of the schema: its fields (key, type text) or, for a `try_from` type,
/// the type it is read through.
#[derive(Debug, Default)]
struct Item {
    fields: Vec<(String, String)>,
    try_from: Option<String>,
}

/// The value of `name = "…"` inside an attribute text, if present.
fn attr_value(attrs: &str, name: &str) -> Option<String> {
    let at = attrs.find(&format!("{name} = \""))?;
    let rest = &attrs[at + name.len() + 4..];
    rest.find('"').map(|end| rest[..end].to_string())
}

/// Every value of `name = "…"` inside an attribute text (e.g. several `alias`es).
fn attr_values(attrs: &str, name: &str) -> Vec<String> {
    let pat = format!("{name} = \"");
    let mut out = Vec::new();
    let mut rest = attrs;
    while let Some(at) = rest.find(&pat) {
        rest = &rest[at + pat.len()..];
        if let Some(end) = rest.find('"') {
            out.push(rest[..end].to_string());
        }
    }
    out
}

/// Net count of `open` minus `close` characters.
fn depth(text: &str, open: char, close: char) -> i64 {
    text.chars()
        .map(|c| (c == open) as i64 - (c == close) as i64)
        .sum()
}

/// Appends `line` to the attribute text `buf` when it is (part of) an attribute; false otherwise.
fn take_attribute(buf: &mut String, line: &str) -> bool {
    let inside = line.starts_with("#[") || (!buf.is_empty() && depth(buf, '[', ']') > 0);
    if inside {
        buf.push_str(line);
        buf.push(' ');
    }
    inside
}

/// The deserialised structs and enums of Rust source text, by name.
fn parse_schema(source: &str) -> BTreeMap<String, Item> {
    let mut items = BTreeMap::new();
    let lines: Vec<&str> = source.lines().collect();
    let mut attrs = String::new();
    let mut i = 0;
    while i < lines.len() {
        let line = lines[i].trim();
        i += 1;
        if take_attribute(&mut attrs, line) || line.starts_with("//") || line.is_empty() {
            continue;
        }
        let decl = line
            .trim_start_matches("pub(crate) ")
            .trim_start_matches("pub ");
        let kind = if decl.starts_with("struct ") {
            Some("struct")
        } else if decl.starts_with("enum ") {
            Some("enum")
        } else {
            None
        };
        let item_attrs = std::mem::take(&mut attrs);
        let Some(kind) = kind else { continue };
        let name: String = decl[kind.len() + 1..]
            .chars()
            .take_while(|c| c.is_alphanumeric() || *c == '_')
            .collect();
        let deserialized = item_attrs.contains("Deserialize");
        let try_from = attr_value(&item_attrs, "try_from");
        assert!(
            !(kind == "struct" && item_attrs.contains("rename_all")),
            "struct {name}: `rename_all` on a struct is not understood by this test; extend it"
        );
        // The body: until the closing brace at the item's own indentation.
        let mut fields = Vec::new();
        if line.ends_with('{') {
            let mut field_attrs = String::new();
            while i < lines.len() {
                let l = lines[i].trim();
                i += 1;
                if l == "}" {
                    break;
                }
                if kind != "struct" {
                    continue;
                }
                if take_attribute(&mut field_attrs, l) || l.starts_with("//") || l.is_empty() {
                    continue;
                }
                let f = l
                    .trim_start_matches("pub(crate) ")
                    .trim_start_matches("pub ");
                let Some((ident, ty)) = f.split_once(": ") else {
                    field_attrs.clear();
                    continue;
                };
                let mut ty = ty.to_string();
                while depth(&ty, '<', '>') > 0 && i < lines.len() {
                    ty.push_str(lines[i].trim());
                    i += 1;
                }
                let fa = std::mem::take(&mut field_attrs);
                assert!(
                    !fa.contains("flatten"),
                    "struct {name}: `flatten` is not understood by this test; extend it"
                );
                if fa.contains("serde(skip") {
                    continue;
                }
                let key = attr_value(&fa, "rename").unwrap_or_else(|| ident.to_string());
                let ty = ty.trim_end_matches(',').to_string();
                for alias in attr_values(&fa, "alias") {
                    fields.push((alias, ty.clone()));
                }
                fields.push((key, ty));
            }
        }
        if deserialized || try_from.is_some() {
            items.insert(name, Item { fields, try_from });
        }
    }
    items
}

/// Every key path below `ty` (prefix `prefix`), intermediate tables included.
fn walk(
    items: &BTreeMap<String, Item>,
    ty: &str,
    prefix: &str,
    out: &mut BTreeSet<String>,
    seen: &mut Vec<String>,
) {
    let Some(mut item) = items.get(ty) else {
        return;
    };
    let mut name = ty.to_string();
    while let Some(spec) = &item.try_from {
        name = spec.clone();
        item = items
            .get(spec)
            .unwrap_or_else(|| panic!("{ty}: try_from type {spec} not found in the schema"));
    }
    if seen.contains(&name) {
        return;
    }
    seen.push(name);
    for (key, field_ty) in &item.fields {
        let path = if prefix.is_empty() {
            key.clone()
        } else {
            format!("{prefix}.{key}")
        };
        out.insert(path.clone());
        if field_ty.contains("Map<") {
            continue; // keys chosen by the user (e.g. [sweep]); documented separately
        }
        let nested = field_ty
            .split(|c: char| !(c.is_alphanumeric() || c == '_'))
            .find(|t| items.contains_key(*t));
        if let Some(t) = nested {
            walk(items, t, &path, out, seen);
        }
    }
    seen.pop();
}

/// The key paths of the schema rooted at `Case`.
fn schema_keys_of(source: &str) -> BTreeSet<String> {
    let items = parse_schema(source);
    assert!(
        items.contains_key("Case"),
        "no `Case` struct deriving Deserialize found in the schema source"
    );
    let mut keys = BTreeSet::new();
    walk(&items, "Case", "", &mut keys, &mut Vec::new());
    keys
}

/// `.rs` files under `dir`, recursively.
fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries.flatten() {
        let p = e.path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

/// The schema source: `src/case.rs` and everything under `src/case/`.
fn schema_source() -> String {
    let mut files = Vec::new();
    let single = root().join("src/case.rs");
    if single.is_file() {
        files.push(single);
    }
    rust_files(&root().join("src/case"), &mut files);
    assert!(
        !files.is_empty(),
        "no schema source (src/case.rs or src/case/) found"
    );
    files.sort();
    files
        .iter()
        .map(|f| std::fs::read_to_string(f).expect("read schema source"))
        .collect::<Vec<_>>()
        .join("\n")
}

// ---------------------------------------------------------------------------------------------
// The documented keys
// ---------------------------------------------------------------------------------------------

/// The backticked words of the first cell of every table row of a markdown page.
fn documented_keys_of(page: &str) -> BTreeSet<String> {
    let mut keys = BTreeSet::new();
    for line in page.lines() {
        let Some(row) = line.trim().strip_prefix('|') else {
            continue;
        };
        let first = row.split('|').next().unwrap_or("");
        for (j, part) in first.split('`').enumerate() {
            if j % 2 == 1 && !part.trim().is_empty() {
                keys.insert(part.trim().to_string());
            }
        }
    }
    keys
}

fn documented_keys() -> BTreeSet<String> {
    let page = std::fs::read_to_string(root().join("docs/case-file.md"))
        .expect("docs/case-file.md is missing");
    documented_keys_of(&page)
}

/// Schema keys that the documentation lacks.
fn missing(schema: &BTreeSet<String>, documented: &BTreeSet<String>) -> Vec<String> {
    schema.difference(documented).cloned().collect()
}

// ---------------------------------------------------------------------------------------------
// The keys of the bundled cases
// ---------------------------------------------------------------------------------------------

/// Key paths used by a TOML table (arrays of tables without index); sweep keys separately.
fn case_keys(
    table: &toml::Table,
    prefix: &str,
    keys: &mut BTreeSet<String>,
    sweeps: &mut BTreeSet<String>,
) {
    for (k, v) in table {
        if prefix == "sweep" {
            sweeps.insert(k.clone());
            continue;
        }
        let path = if prefix.is_empty() {
            k.clone()
        } else {
            format!("{prefix}.{k}")
        };
        keys.insert(path.clone());
        match v {
            toml::Value::Table(t) => case_keys(t, &path, keys, sweeps),
            toml::Value::Array(a) => {
                for t in a.iter().filter_map(toml::Value::as_table) {
                    case_keys(t, &path, keys, sweeps);
                }
            }
            _ => {}
        }
    }
}

/// A sweep path in the documentation's spelling: `contact.<name>.p`, `element.<index>.p`,
/// `strip.<name>.p`.
fn sweep_pattern(path: &str) -> String {
    let parts: Vec<&str> = path.split('.').collect();
    match parts.as_slice() {
        ["contact", _, p] => format!("contact.<name>.{p}"),
        ["strip", _, p] => format!("strip.<name>.{p}"),
        ["element", i, p] if i.parse::<usize>().is_ok() => format!("element.<index>.{p}"),
        _ => path.to_string(),
    }
}

fn toml_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("read cases/").flatten() {
        let p = e.path();
        if p.is_dir() {
            toml_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "toml") {
            out.push(p);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Tests
// ---------------------------------------------------------------------------------------------

#[test]
fn every_schema_key_is_documented_in_case_file_md() {
    let schema = schema_keys_of(&schema_source());
    // The derivation reaches every level: tables, arrays of tables, inline tables, renamed and
    // try_from-read keys. (A parser that found nothing would make the test vacuous.)
    for k in [
        "title",
        "model.material.young",
        "model.damping.rayleigh",
        "cyclic.axis.direction",
        "contact.misalignment.rotate.angle_deg",
        "excitation.force_scale",
        "element.tangential.weights",
        "continuation.min_step_rad_s",
        "march.time_step_s",
        "damper.platform.phase_deg",
        "damper.contact.n0",
        "sweep",
        "rom.file",
    ] {
        assert!(
            schema.contains(k),
            "the schema walk missed '{k}': {schema:?}"
        );
    }
    assert!(
        schema.len() > 100,
        "only {} schema keys found",
        schema.len()
    );
    let lacking = missing(&schema, &documented_keys());
    assert!(
        lacking.is_empty(),
        "keys of the case schema missing from docs/case-file.md (add a table row whose first \
         cell is the key's full path in backticks): {lacking:?}"
    );
}

#[test]
fn every_key_of_the_bundled_cases_is_documented() {
    let mut files = Vec::new();
    toml_files(&root().join("cases"), &mut files);
    assert!(files.len() >= 10, "bundled cases: {files:?}");
    let documented = documented_keys();
    let schema = schema_keys_of(&schema_source());
    let mut problems = Vec::new();
    let mut sweeps_seen = 0;
    for f in &files {
        let text = std::fs::read_to_string(f).expect("read case");
        let table: toml::Table = text
            .parse()
            .unwrap_or_else(|e| panic!("{}: {e}", f.display()));
        let (mut keys, mut sweeps) = (BTreeSet::new(), BTreeSet::new());
        case_keys(&table, "", &mut keys, &mut sweeps);
        for k in &keys {
            if !documented.contains(k) {
                problems.push(format!(
                    "{}: key '{k}' is not in docs/case-file.md",
                    f.display()
                ));
            }
            if !schema.contains(k) {
                problems.push(format!("{}: key '{k}' is not in the schema", f.display()));
            }
        }
        for s in &sweeps {
            sweeps_seen += 1;
            if !documented.contains(&sweep_pattern(s)) {
                problems.push(format!(
                    "{}: sweep path '{s}' matches no sweepable path of docs/case-file.md",
                    f.display()
                ));
            }
        }
    }
    assert!(sweeps_seen > 0, "no bundled case has a [sweep]");
    assert!(problems.is_empty(), "{}", problems.join("\n"));
}

/// The parser on a synthetic schema: nesting, arrays, Option, rename, skip, try_from, maps.
#[test]
fn schema_parser_reads_serde_structs() {
    let source = r#"
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// doc
    #[serde(default)]
    pub title: String,
    pub model: Option<Model>,
    #[serde(default)]
    pub parts: Vec<Part>,
    pub sweep: BTreeMap<String, Vec<f64>>,
    #[serde(skip)]
    pub path: PathBuf,
}

#[derive(Clone, Debug,
    Deserialize)]
struct Model {
    #[serde(rename = "young-modulus")]
    young: f64,
    #[serde(default, alias = "span")]
    length: f64,
    range: Range,
}

#[derive(Deserialize)]
#[serde(try_from = "RangeSpec")]
pub struct Range {
    pub lo: f64,
}

#[derive(Deserialize)]
struct RangeSpec {
    start_hz: Option<f64>,
    start_rad_s: Option<f64>,
}

#[derive(Deserialize)]
pub struct Part {
    pub name: String,
}

pub struct NotSchema {
    pub hidden: f64,
}
"#;
    let keys: Vec<String> = schema_keys_of(source).into_iter().collect();
    assert_eq!(
        keys,
        [
            "model",
            "model.length",
            "model.range",
            "model.range.start_hz",
            "model.range.start_rad_s",
            "model.span",
            "model.young-modulus",
            "parts",
            "parts.name",
            "sweep",
            "title",
        ]
    );
}

/// The comparison reports a key left out of the page, and reads only first cells.
#[test]
fn a_key_missing_from_the_page_is_reported() {
    let page = "| key | type |\n|---|---|\n| `model` | table |\n| `model.mesh` | path, see `model.dofs` |\n";
    let documented = documented_keys_of(page);
    let schema: BTreeSet<String> = ["model", "model.mesh", "model.dofs"]
        .into_iter()
        .map(String::from)
        .collect();
    assert_eq!(missing(&schema, &documented), ["model.dofs"]);
    assert_eq!(sweep_pattern("contact.shroud.n0"), "contact.<name>.n0");
    assert_eq!(sweep_pattern("element.2.kt"), "element.<index>.kt");
}
