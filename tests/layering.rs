//! The module layering of `src/` (the table in the crate documentation, `src/lib.rs`): a
//! top-level module may use only the modules listed before it, and only the builders
//! ([`BUILDERS`]) may read a whole case (`case::Case`). Every `crate::<module>` path in
//! compiled code (comments, string literals and `#[cfg(test)]` items removed) of every file under
//! `src/` is checked against [`ORDER`], and the crate documentation must list the same order.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

/// The top-level modules, lowest first: each may use only those before it.
const ORDER: &[&str] = &[
    "error",
    "vec3",
    "mesh",
    "matrix_io",
    "harmonics",
    "case",
    "cyclic",
    "rom",
    "output",
    "fe",
    "eigen",
    "model",
    "reduction",
    "contact",
    "interface",
    "nonlinear",
    "continuation",
    "hbm",
    "march",
    "problem",
    "commands",
    "cli",
];

/// The one allowed upward use: `error` wraps the mesh reader's `MshError`.
const EXCEPTIONS: &[(&str, &str)] = &[("error", "mesh")];

/// The builders: the only modules that may read a whole case (`case::Case`). The kernels take
/// plain values or, at most, one table or value type of the schema.
const BUILDERS: &[&str] = &[
    "case",
    "model",
    "reduction",
    "interface",
    "problem",
    "commands",
    "cli",
];

/// `src` with comments, string and character literals blanked (replaced by spaces, so that
/// positions and line numbers stay), and every `#[cfg(test)]` item removed.
fn strip(src: &str) -> String {
    let b = src.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    let blank = |out: &mut Vec<u8>, s: &[u8]| {
        out.extend(s.iter().map(|&c| if c == b'\n' { b'\n' } else { b' ' }))
    };
    while i < b.len() {
        let rest = &b[i..];
        if rest.starts_with(b"//") {
            let end = rest.iter().position(|&c| c == b'\n').unwrap_or(rest.len());
            blank(&mut out, &rest[..end]);
            i += end;
        } else if rest.starts_with(b"/*") {
            let (mut depth, mut j) = (1, 2);
            while j < rest.len() && depth > 0 {
                if rest[j..].starts_with(b"/*") {
                    depth += 1;
                    j += 2;
                } else if rest[j..].starts_with(b"*/") {
                    depth -= 1;
                    j += 2;
                } else {
                    j += 1;
                }
            }
            blank(&mut out, &rest[..j]);
            i += j;
        } else if rest[0] == b'r'
            && (rest.starts_with(b"r\"") || rest.starts_with(b"r#"))
            && (i == 0 || !(b[i - 1].is_ascii_alphanumeric() || b[i - 1] == b'_'))
        {
            let hashes = rest[1..].iter().take_while(|&&c| c == b'#').count();
            if rest.get(1 + hashes) != Some(&b'"') {
                out.push(rest[0]);
                i += 1;
                continue;
            }
            let mut close = vec![b'"'];
            close.extend(std::iter::repeat_n(b'#', hashes));
            let body = 2 + hashes;
            let end = rest[body..]
                .windows(close.len())
                .position(|w| w == close.as_slice())
                .map_or(rest.len(), |p| body + p + close.len());
            blank(&mut out, &rest[..end]);
            i += end;
        } else if rest[0] == b'"' {
            let mut j = 1;
            while j < rest.len() && rest[j] != b'"' {
                j += if rest[j] == b'\\' { 2 } else { 1 };
            }
            let end = (j + 1).min(rest.len());
            blank(&mut out, &rest[..end]);
            i += end;
        } else if rest[0] == b'\'' {
            // a character literal ('x', '\n', '\u{..}', '"'); otherwise a lifetime
            let len = if rest.get(1) == Some(&b'\\') {
                rest[2..].iter().position(|&c| c == b'\'').map(|p| p + 3)
            } else {
                let ch = std::str::from_utf8(&rest[1..rest.len().min(5)])
                    .ok()
                    .or_else(|| std::str::from_utf8(&rest[1..rest.len().min(2)]).ok())
                    .and_then(|s| s.chars().next());
                ch.map(char::len_utf8)
                    .filter(|&n| rest.get(1 + n) == Some(&b'\''))
                    .map(|n| n + 2)
            };
            match len {
                Some(n) => {
                    blank(&mut out, &rest[..n]);
                    i += n;
                }
                None => {
                    out.push(b'\'');
                    i += 1;
                }
            }
        } else {
            out.push(rest[0]);
            i += 1;
        }
    }
    remove_test_items(&String::from_utf8_lossy(&out))
}

/// Removes every item after `#[cfg(test)]`: up to the `;` or the matching `}` of its first `{`.
fn remove_test_items(src: &str) -> String {
    let mut out = String::with_capacity(src.len());
    let mut rest = src;
    while let Some(p) = rest.find("#[cfg(test)]") {
        out.push_str(&rest[..p]);
        let after = &rest[p..];
        let mut depth = 0usize;
        let mut end = after.len();
        for (j, c) in after.char_indices() {
            match c {
                '{' => depth += 1,
                '}' => {
                    depth = depth.saturating_sub(1);
                    if depth == 0 {
                        end = j + 1;
                        break;
                    }
                }
                ';' if depth == 0 => {
                    end = j + 1;
                    break;
                }
                _ => {}
            }
        }
        rest = &after[end..];
    }
    out.push_str(rest);
    out
}

/// The top-level modules named by the `crate::` paths of `code` (already stripped), with the
/// line of each: `crate::a::b`, and every item of `crate::{a::x, b::{y, z}}`.
fn crate_uses(code: &str) -> Vec<(String, usize)> {
    let mut found = Vec::new();
    let line_of = |pos: usize| code[..pos].matches('\n').count() + 1;
    for (pos, _) in code.match_indices("crate::") {
        let before = code[..pos].chars().next_back();
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$') {
            continue;
        }
        let rest = code[pos + "crate::".len()..].trim_start();
        if let Some(group) = rest.strip_prefix('{') {
            // the first identifier of every top-level item of the group
            let mut depth = 0usize;
            let mut item = String::new();
            let mut items = Vec::new();
            for c in group.chars() {
                match c {
                    '{' => {
                        depth += 1;
                        item.push(c);
                    }
                    '}' if depth == 0 => break,
                    '}' => {
                        depth -= 1;
                        item.push(c);
                    }
                    ',' if depth == 0 => items.push(std::mem::take(&mut item)),
                    _ => item.push(c),
                }
            }
            items.push(item);
            for it in items {
                let name = first_ident(it.trim_start());
                if !name.is_empty() {
                    found.push((name, line_of(pos)));
                }
            }
        } else {
            let name = first_ident(rest);
            if !name.is_empty() {
                found.push((name, line_of(pos)));
            }
        }
    }
    found
}

/// The leading identifier of `s`.
fn first_ident(s: &str) -> String {
    s.chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect()
}

/// The top-level module a file under `src/` belongs to (`None` for `lib.rs` and `main.rs`).
fn top_module(relative: &Path) -> Option<String> {
    let first = relative.components().next()?.as_os_str().to_str()?;
    let name = first.strip_suffix(".rs").unwrap_or(first);
    (name != "lib" && name != "main").then(|| name.to_string())
}

/// The violations of [`ORDER`] in one file: "file:line: `from` uses `crate::to`".
fn check_file(relative: &Path, source: &str) -> Vec<String> {
    let Some(from) = top_module(relative) else {
        return Vec::new();
    };
    let rank = |m: &str| ORDER.iter().position(|&o| o == m);
    let Some(from_rank) = rank(&from) else {
        return vec![format!(
            "{}: module `{from}` is not in the layering table",
            relative.display()
        )];
    };
    let code = strip(source);
    let mut bad = Vec::new();
    if !BUILDERS.contains(&from.as_str()) {
        for (pos, _) in code.match_indices("Case") {
            let before = code[..pos].chars().next_back();
            let after = code[pos + 4..].chars().next();
            let ident = |c: Option<char>| c.is_some_and(|c| c.is_alphanumeric() || c == '_');
            if !ident(before) && !ident(after) {
                let line = code[..pos].matches('\n').count() + 1;
                bad.push(format!(
                    "{}:{line}: `{from}` reads the whole case (`Case`); only builders may",
                    relative.display()
                ));
            }
        }
    }
    for (to, line) in crate_uses(&code) {
        if to == from || ["Result", "Error"].contains(&to.as_str()) {
            continue;
        }
        let allowed = match rank(&to) {
            Some(r) => r < from_rank || EXCEPTIONS.contains(&(from.as_str(), to.as_str())),
            None => false,
        };
        if !allowed {
            bad.push(format!(
                "{}:{line}: `{from}` uses `crate::{to}`, which is not below it",
                relative.display()
            ));
        }
    }
    bad
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).expect("read src") {
        let path = entry.expect("entry").path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

#[test]
fn every_module_uses_only_modules_below_it() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    files.sort();
    assert!(files.len() > 50, "found only {} files", files.len());
    let mut bad = Vec::new();
    let mut modules = BTreeSet::new();
    for f in &files {
        let relative = f.strip_prefix(&src).expect("under src");
        if let Some(m) = top_module(relative) {
            modules.insert(m);
        }
        bad.extend(check_file(
            relative,
            &std::fs::read_to_string(f).expect("read"),
        ));
    }
    assert!(bad.is_empty(), "layering violations:\n{}", bad.join("\n"));
    let table: BTreeSet<String> = ORDER.iter().map(|s| s.to_string()).collect();
    assert_eq!(
        modules, table,
        "the top-level modules and the layering table differ"
    );
}

/// The crate documentation states the same order: its layering table lists the modules as
/// [`ORDER`], one row each, in order.
#[test]
fn the_crate_documentation_states_the_order() {
    let lib = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("src/lib.rs"))
        .expect("lib.rs");
    let rows: Vec<String> = lib
        .lines()
        .filter_map(|l| l.strip_prefix("//! | "))
        .filter_map(|l| {
            let cell = l.split('|').nth(1)?.trim();
            let name = cell.strip_prefix("[`")?.strip_suffix("`]")?;
            Some(name.to_string())
        })
        .collect();
    assert_eq!(
        rows, ORDER,
        "src/lib.rs's layering table differs from ORDER"
    );
}

#[test]
fn the_checker_fails_on_a_back_edge() {
    // a time integrator that reaches into the command layer
    let back = "use crate::error::Result;\nuse crate::commands::Reporter;\n";
    let bad = check_file(Path::new("march/sector.rs"), back);
    assert_eq!(bad.len(), 1, "{bad:?}");
    assert!(bad[0].contains("march/sector.rs:2") && bad[0].contains("crate::commands"));
    // inside a use group, and as an expression path
    let grouped =
        "use crate::{case::CaseKind, problem::{rom_store, sector}};\nfn f() { crate::cli::main(); }";
    let bad = check_file(Path::new("hbm/frf.rs"), grouped);
    assert_eq!(bad.len(), 2, "{bad:?}");
    assert!(bad[0].contains("crate::problem") && bad[1].contains("crate::cli"));
    // an unknown module is a violation too
    assert_eq!(
        check_file(Path::new("mesh/mod.rs"), "use crate::shiny::X;").len(),
        1
    );
}

#[test]
fn the_checker_ignores_comments_strings_and_test_code() {
    let src = r##"
//! Built by [`crate::problem`] (a doc link, not a use).
use crate::error::Result; // crate::cli in a comment
/* crate::commands in a /* nested */ block comment */
const S: &str = "crate::commands";
const R: &str = r#"crate::cli "quoted""#;
const C: char = '"';
fn f<'a>(x: &'a str) -> &'a str { x }
#[cfg(test)]
use crate::problem::sector;
#[cfg(test)]
mod tests {
    use crate::commands::Reporter;
    fn g() { let _ = "}"; }
}
use crate::mesh::Mesh;
"##;
    assert!(check_file(Path::new("march/x.rs"), src).is_empty());
    let uses: Vec<String> = crate_uses(&strip(src))
        .into_iter()
        .map(|(m, _)| m)
        .collect();
    assert_eq!(uses, ["error", "mesh"]);
    // the rank check itself: a use of a higher module after the test block is still caught
    let src = format!("{src}use crate::problem::Log;\n");
    assert_eq!(check_file(Path::new("march/x.rs"), &src).len(), 1);
}
