//! Malformed MSH input: every broken file gives an error naming the section, the line and the byte
//! offset — never a panic. The corpus is derived from the bundled meshes (truncations in every
//! section, wrong counts, bad numbers, unknown element types, missing `$End` lines, corrupt binary
//! headers) plus the hand-written files in `tests/data/broken/` with their expected sections and
//! lines in `tests/data/broken/EXPECTED`.

use std::path::PathBuf;

use nlrom::mesh::msh::{parse_msh, MshError};

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn bytes(rel: &str) -> Vec<u8> {
    std::fs::read(root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

const SMALL: [&str; 8] = [
    "meshes/cube_tet4.msh",
    "meshes/formats/cube_tet4.v41-binary.msh",
    "meshes/formats/cube_tet4.v22-ascii.msh",
    "meshes/formats/cube_tet4.v22-binary.msh",
    "meshes/mixed_o2i.msh",
    "meshes/formats/mixed_o2i.v41-binary.msh",
    "meshes/formats/mixed_o2i.v22-ascii.msh",
    "meshes/formats/mixed_o2i.v22-binary.msh",
];

/// The error must be internally consistent: line = 1 + newlines before the offset.
fn check_location(input: &[u8], e: &MshError) {
    assert!(
        e.offset <= input.len(),
        "offset {} beyond {} bytes",
        e.offset,
        input.len()
    );
    let line = 1 + input[..e.offset].iter().filter(|&&c| c == b'\n').count();
    assert_eq!(e.line, line, "line of {e}");
    let text = e.to_string();
    assert!(
        text.contains(&format!("line {}", e.line)) && text.contains(&e.section),
        "{text}"
    );
}

/// Section names and the byte ranges [start of `$Name`, end of `$EndName` line).
fn sections(input: &[u8]) -> Vec<(String, usize, usize)> {
    let mut out = Vec::new();
    let mut k = 0;
    while k < input.len() {
        let name_end = k + input[k..]
            .iter()
            .position(|c| c.is_ascii_whitespace())
            .unwrap_or(input.len() - k);
        let name = String::from_utf8_lossy(&input[k + 1..name_end]).into_owned();
        let closing = format!("\n$End{name}");
        let end = find(&input[name_end..], closing.as_bytes())
            .map(|e| e + name_end + closing.len())
            .expect("closing");
        out.push((format!("${name}"), k, end));
        k = end
            + input[end..]
                .iter()
                .position(|&c| c == b'$')
                .unwrap_or(input.len() - end);
    }
    out
}

fn find(hay: &[u8], needle: &[u8]) -> Option<usize> {
    hay.windows(needle.len()).position(|w| w == needle)
}

#[test]
fn truncation_inside_every_section_names_that_section() {
    for rel in SMALL {
        let input = bytes(rel);
        let secs = sections(&input);
        assert!(secs.len() >= 4, "{rel}: sections {secs:?}");
        for (name, start, end) in &secs {
            for cut in [start + name.len() + 1, (start + end) / 2, end - 2] {
                let e = parse_msh(&input[..cut]).expect_err("truncated file must fail");
                assert_eq!(&e.section, name, "{rel} cut at {cut}: {e}");
                check_location(&input[..cut], &e);
                assert!(
                    e.message.contains("truncated")
                        || e.message.contains("end of file")
                        || e.message.contains("unterminated")
                        || e.message.contains("missing $End"),
                    "{rel} cut at {cut}: {e}"
                );
            }
        }
    }
}

#[test]
fn truncation_anywhere_never_panics() {
    for rel in SMALL {
        let input = bytes(rel);
        let last_end = input.len()
            - input
                .iter()
                .rev()
                .position(|c| !c.is_ascii_whitespace())
                .unwrap_or(0);
        let step = (input.len() / 400).max(1);
        for cut in (0..input.len()).step_by(step) {
            match parse_msh(&input[..cut]) {
                Ok(_) => assert!(cut >= last_end, "{rel}: a prefix of {cut} bytes parsed"),
                Err(e) => check_location(&input[..cut], &e),
            }
        }
    }
}

/// Replaces the first occurrence of `from` after `after` by `to` (text files).
fn edit(text: &str, after: &str, from: &str, to: &str) -> (String, usize) {
    let base = text.find(after).expect("anchor") + after.len();
    let k = base + text[base..].find(from).expect("pattern");
    let line = 1 + text[..k].matches('\n').count();
    (
        format!("{}{}{}", &text[..k], to, &text[k + from.len()..]),
        line,
    )
}

fn expect_error(input: &str, section: &str, line: usize, words: &str) {
    let e = parse_msh(input.as_bytes()).expect_err("must fail");
    check_location(input.as_bytes(), &e);
    assert_eq!(e.section, section, "{e}");
    assert_eq!(e.line, line, "{e}");
    assert!(e.message.contains(words), "'{words}' not in: {e}");
}

#[test]
fn bad_numbers_name_the_line() {
    let v41 = String::from_utf8(bytes("meshes/cube_tet4.msh")).expect("utf8");
    // The first coordinate line of the first node block with a letter in it.
    let header_end = v41.find("$Nodes\n").expect("nodes") + 7;
    let first_block = header_end + v41[header_end..].find('\n').expect("line") + 1;
    let block_line_end = first_block + v41[first_block..].find('\n').expect("line");
    let n: usize = v41[first_block..block_line_end]
        .split_whitespace()
        .nth(3)
        .expect("count")
        .parse()
        .expect("n");
    let mut k = block_line_end + 1;
    for _ in 0..n {
        k += v41[k..].find('\n').expect("tag line") + 1;
    }
    let line = 1 + v41[..k].matches('\n').count();
    let bad = format!(
        "{}0.5x{}",
        &v41[..k],
        &v41[k + v41[k..].find(' ').expect("space")..]
    );
    expect_error(&bad, "$Nodes", line, "expected a number, found '0.5x'");

    let v22 = String::from_utf8(bytes("meshes/formats/cube_tet4.v22-ascii.msh")).expect("utf8");
    let (bad, line) = edit(&v22, "$Elements\n", "\n", "\n-3 ");
    expect_error(
        &bad,
        "$Elements",
        line + 1,
        "expected an unsigned integer, found '-3'",
    );
    let (bad, line) = edit(&v22, "$Nodes\n", "\n", "\n1e999 ");
    expect_error(&bad, "$Nodes", line + 1, "expected an unsigned integer");
}

#[test]
fn unknown_element_type_names_it() {
    let v22 = String::from_utf8(bytes("meshes/formats/cube_tet4.v22-ascii.msh")).expect("utf8");
    // First element line: "tag type ntags ..." -> type 99.
    let start = v22.find("$Elements\n").expect("elements") + 10;
    let line_start = start + v22[start..].find('\n').expect("count line") + 1;
    let tag_end = line_start + v22[line_start..].find(' ').expect("space");
    let type_end = tag_end + 1 + v22[tag_end + 1..].find(' ').expect("space");
    let bad = format!("{} 99{}", &v22[..tag_end], &v22[type_end..]);
    let line = 1 + v22[..line_start].matches('\n').count();
    expect_error(
        &bad,
        "$Elements",
        line,
        "unknown or unsupported element type 99",
    );

    let v41 = String::from_utf8(bytes("meshes/cube_tet4.msh")).expect("utf8");
    let (bad, line) = edit(&v41, "$Elements\n", "\n", "\n2 1 26 1\n1 1 2 3\n");
    expect_error(&bad, "$Elements", line + 1, "element type 26");
}

#[test]
fn wrong_counts_are_reported() {
    let v41 = String::from_utf8(bytes("meshes/cube_tet4.msh")).expect("utf8");
    // One block more than there is: the next token is $EndNodes.
    let nodes = v41.find("$Nodes\n").expect("nodes") + 7;
    let head_end = nodes + v41[nodes..].find('\n').expect("line");
    let fields: Vec<&str> = v41[nodes..head_end].split_whitespace().collect();
    let more_blocks = format!(
        "{} {}",
        fields[0].parse::<u64>().expect("n") + 1,
        fields[1..].join(" ")
    );
    let bad = format!("{}{}{}", &v41[..nodes], more_blocks, &v41[head_end..]);
    let e = parse_msh(bad.as_bytes()).expect_err("must fail");
    assert_eq!(e.section, "$Nodes");
    check_location(bad.as_bytes(), &e);
    // Total nodes off by one.
    let fewer = format!(
        "{} {} {}",
        fields[0],
        fields[1].parse::<u64>().expect("n") - 1,
        fields[2..].join(" ")
    );
    let bad = format!("{}{}{}", &v41[..nodes], fewer, &v41[head_end..]);
    let line = 1 + v41[..nodes].matches('\n').count();
    expect_error(&bad, "$Nodes", line, "declares");

    let v22 = String::from_utf8(bytes("meshes/formats/cube_tet4.v22-ascii.msh")).expect("utf8");
    let start = v22.find("$Elements\n").expect("elements") + 10;
    let end = start + v22[start..].find('\n').expect("line");
    let n: u64 = v22[start..end].trim().parse().expect("count");
    let bad = format!("{}{}{}", &v22[..start], n - 1, &v22[end..]);
    let e = parse_msh(bad.as_bytes()).expect_err("one element too many");
    assert_eq!(e.section, "$Elements");
    assert!(e.message.contains("expected $EndElements"), "{e}");
    // A count far beyond the file size must be refused before allocating.
    let bad = format!("{}{}{}", &v22[..start], u64::MAX / 2, &v22[end..]);
    expect_error(
        &bad,
        "$Elements",
        1 + v22[..start].matches('\n').count(),
        "only",
    );
}

#[test]
fn missing_end_lines_are_reported() {
    for rel in [
        "meshes/cube_tet4.msh",
        "meshes/formats/cube_tet4.v22-ascii.msh",
    ] {
        let text = String::from_utf8(bytes(rel)).expect("utf8");
        for section in ["MeshFormat", "PhysicalNames", "Nodes", "Elements"] {
            let bad = text.replacen(&format!("$End{section}\n"), "", 1);
            let e = parse_msh(bad.as_bytes()).expect_err("must fail");
            assert_eq!(e.section, format!("${section}"), "{rel}: {e}");
            assert!(e.message.contains(&format!("$End{section}")), "{rel}: {e}");
            check_location(bad.as_bytes(), &e);
        }
    }
}

#[test]
fn corrupt_binary_headers_are_reported() {
    let bin = bytes("meshes/formats/cube_tet4.v41-binary.msh");
    let k = find(&bin, b"4.1 1 8\n").expect("format") + 8;
    let mut bad = bin.clone();
    bad[k..k + 4].copy_from_slice(&[7, 0, 0, 0]);
    let e = parse_msh(&bad).expect_err("bad check integer");
    assert_eq!(e.section, "$MeshFormat");
    assert!(e.message.contains("check integer"), "{e}");

    // An element block type set to 200 in the binary 4.1 elements header.
    let k = find(&bin, b"$Elements\n").expect("elements") + 10 + 4 * 8;
    let mut bad = bin.clone();
    bad[k + 8..k + 12].copy_from_slice(&200i32.to_le_bytes());
    let e = parse_msh(&bad).expect_err("bad type");
    assert_eq!(e.section, "$Elements");
    assert!(e.message.contains("element type 200"), "{e}");
    assert_eq!(e.offset, k + 8);

    // A node reference out of range in 2.2 binary.
    let bin22 = bytes("meshes/formats/cube_tet4.v22-binary.msh");
    let k = find(&bin22, b"$Elements\n").expect("elements") + 10;
    let data = k
        + bin22[k..]
            .iter()
            .position(|&c| c == b'\n')
            .expect("count line")
        + 1;
    let ty = i32::from_le_bytes(bin22[data..data + 4].try_into().expect("4"));
    let ntags = i32::from_le_bytes(bin22[data + 8..data + 12].try_into().expect("4")) as usize;
    assert!(ty > 0);
    let first_node = data + 12 + 4 + 4 * ntags;
    let mut bad = bin22.clone();
    bad[first_node..first_node + 4].copy_from_slice(&999_999i32.to_le_bytes());
    let e = parse_msh(&bad).expect_err("unknown node");
    assert_eq!(e.offset, first_node);
    assert!(e.message.contains("node 999999"), "{e}");
}

#[test]
fn hand_written_corpus() {
    let dir = root().join("tests/data/broken");
    let manifest = std::fs::read_to_string(dir.join("EXPECTED")).expect("EXPECTED");
    let mut n = 0;
    for line in manifest
        .lines()
        .filter(|l| !l.trim().is_empty() && !l.starts_with('#'))
    {
        // file | section | line | words in the message
        let f: Vec<&str> = line.split('|').map(str::trim).collect();
        assert_eq!(f.len(), 4, "manifest line: {line}");
        let input = std::fs::read(dir.join(f[0])).expect("corpus file");
        let e = parse_msh(&input).expect_err(f[0]);
        check_location(&input, &e);
        assert_eq!(e.section, f[1], "{}: {e}", f[0]);
        assert_eq!(e.line.to_string(), f[2], "{}: {e}", f[0]);
        assert!(e.message.contains(f[3]), "{}: '{}' not in {e}", f[0], f[3]);
        n += 1;
    }
    assert!(n >= 10, "corpus has {n} files");
}
