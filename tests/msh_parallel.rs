//! The parallel reading of large ASCII `$Nodes` and `$Elements` blocks: a generated mesh large
//! enough to be read in chunks gives the same mesh as the same records laid out so that the
//! line-based reader refuses them (a blank line after every record: the sequential token reader
//! then reads the block), in MSH 4.1 and 2.2; and a bad token deep inside a large block gives the
//! error of the sequential reader, naming its line; read from a file, by the library and by
//! `nlrom mesh info`, the error names the file and the line.

mod support;

use nlrom::mesh::msh::{parse_msh, read_msh};
use nlrom::mesh::{ElementTags, Mesh};
use support::cli::{nlrom, stderr};

/// Nodes of an n × n × n lattice (tags from 1, coordinates with 17 significant digits, some
/// negative and some in exponent form) and its cells' Kuhn tetrahedra; every `tri_every`-th
/// element record is a triangle on another entity and physical group (MSH 2.2 only), so 2.2
/// blocks start and end inside chunks.
struct Lattice {
    nodes: Vec<(u64, [f64; 3])>,
    tets: Vec<[u64; 4]>,
}

fn lattice(n: usize) -> Lattice {
    let id = |i: usize, j: usize, k: usize| (1 + i + n * (j + n * k)) as u64;
    let mut nodes = Vec::new();
    for k in 0..n {
        for j in 0..n {
            for i in 0..n {
                let x = [i, j, k].map(|c| (c as f64 / 3.0 - 1.7) * 1e-3 * (1.0 + c as f64));
                nodes.push((id(i, j, k), x));
            }
        }
    }
    let mut tets = Vec::new();
    for k in 0..n - 1 {
        for j in 0..n - 1 {
            for i in 0..n - 1 {
                for perm in [
                    [0, 1, 2],
                    [0, 2, 1],
                    [1, 0, 2],
                    [1, 2, 0],
                    [2, 0, 1],
                    [2, 1, 0],
                ] {
                    let mut c = [[i, j, k]; 4];
                    for s in 0..3 {
                        c[s + 1] = c[s];
                        c[s + 1][perm[s]] += 1;
                    }
                    tets.push(c.map(|p| id(p[0], p[1], p[2])));
                }
            }
        }
    }
    Lattice { nodes, tets }
}

/// `{:e}` for some values, `{}` for others, as different writers do.
fn num(k: usize, v: f64) -> String {
    if k.is_multiple_of(3) {
        format!("{v:.16e}")
    } else {
        format!("{v}")
    }
}

/// Element tags 1, 2, … as Gmsh writes them, or with a jump of 1000 after element `jump`.
fn msh41(m: &Lattice, sep: &str, jump: Option<usize>) -> String {
    let (nn, ne) = (m.nodes.len(), m.tets.len());
    let mut s = String::from(
        "$MeshFormat\n4.1 0 8\n$EndMeshFormat\n$PhysicalNames\n1\n3 1 \"volume\"\n$EndPhysicalNames\n\
         $Entities\n0 0 0 1\n1 0 0 0 1 1 1 1 1 0\n$EndEntities\n",
    );
    s += &format!("$Nodes\n1 {nn} 1 {nn}\n3 1 0 {nn}\n");
    for (t, _) in &m.nodes {
        s += &format!("{t}{sep}\n");
    }
    for (k, (_, x)) in m.nodes.iter().enumerate() {
        s += &format!(
            "{} {} {}{sep}\n",
            num(k, x[0]),
            num(k + 1, x[1]),
            num(k + 2, x[2])
        );
    }
    s += &format!("$EndNodes\n$Elements\n1 {ne} 1 {ne}\n3 1 4 {ne}\n");
    for (e, t) in m.tets.iter().enumerate() {
        let tag = element_tag(e, jump);
        s += &format!("{tag} {} {} {} {}{sep}\n", t[0], t[1], t[2], t[3]);
    }
    s + "$EndElements\n"
}

fn element_tag(e: usize, jump: Option<usize>) -> u64 {
    e as u64 + 1 + if jump.is_some_and(|j| e > j) { 1000 } else { 0 }
}

fn msh22(m: &Lattice, sep: &str, tri_every: usize) -> String {
    let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n");
    s += &format!("$Nodes\n{}\n", m.nodes.len());
    for (k, (t, x)) in m.nodes.iter().enumerate() {
        s += &format!(
            "{t} {} {} {}{sep}\n",
            num(k, x[0]),
            num(k + 1, x[1]),
            num(k + 2, x[2])
        );
    }
    s += &format!("$EndNodes\n$Elements\n{}\n", m.tets.len());
    for (e, t) in m.tets.iter().enumerate() {
        if e % tri_every == tri_every - 1 {
            s += &format!("{} 2 2 2 7 {} {} {}{sep}\n", e + 1, t[0], t[1], t[2]);
        } else {
            s += &format!(
                "{} 4 2 1 1 {} {} {} {}{sep}\n",
                e + 1,
                t[0],
                t[1],
                t[2],
                t[3]
            );
        }
    }
    s + "$EndElements\n"
}

fn same(a: &Mesh, b: &Mesh) {
    assert_eq!(a.node_tags, b.node_tags);
    assert_eq!(a.coords, b.coords);
    assert_eq!(a.blocks, b.blocks);
    assert_eq!(a.groups, b.groups);
}

#[test]
fn parallel_blocks_read_as_the_sequential_reader_does() {
    let m = lattice(26); // 17 576 nodes, 93 750 tetrahedra: several chunks per block
    let jump = Some(m.tets.len() * 2 / 3); // in a middle chunk
    for (name, fast, slow) in [
        ("4.1", msh41(&m, "", None), msh41(&m, "\n", None)),
        ("4.1 tag jump", msh41(&m, "", jump), msh41(&m, "\n", jump)),
        ("2.2", msh22(&m, "", 4999), msh22(&m, "\n", 4999)),
    ] {
        let a = parse_msh(fast.as_bytes()).unwrap();
        let b = parse_msh(slow.as_bytes()).unwrap();
        same(&a, &b);
        assert_eq!(a.num_nodes(), m.nodes.len(), "{name}");
        let elements: usize = a.blocks.iter().map(|b| b.tags.len()).sum();
        assert_eq!(elements, m.tets.len(), "{name}");
        // The values themselves: coordinates parse to the nearest double of their text.
        for (k, (t, x)) in m.nodes.iter().enumerate() {
            assert_eq!(a.node_tags[k], *t);
            let want: [f64; 3] = std::array::from_fn(|c| num(k + c, x[c]).parse().unwrap());
            assert_eq!(a.coords[k], want, "{name}: node {t}");
        }
    }
    // Element tags: a run as Gmsh writes them, the list of the file's tags otherwise.
    for j in [None, jump] {
        let a = parse_msh(msh41(&m, "", j).as_bytes()).unwrap();
        let tags = &a.blocks[0].tags;
        assert_eq!(matches!(tags, ElementTags::Run { .. }), j.is_none());
        let want: Vec<u64> = (0..m.tets.len()).map(|e| element_tag(e, j)).collect();
        assert_eq!(tags.iter().collect::<Vec<_>>(), want);
    }
    // 2.2: the triangles split the tetrahedra into runs; blocks alternate as in the file.
    let a = parse_msh(msh22(&m, "", 4999).as_bytes()).unwrap();
    assert_eq!(a.blocks.len(), 2 * (m.tets.len() / 4999) + 1);
}

/// The line (1-based) of the text that contains byte `offset`.
fn line_of(text: &str, offset: usize) -> usize {
    1 + text[..offset].matches('\n').count()
}

#[test]
fn a_bad_token_deep_in_a_large_block_is_reported_at_its_line() {
    let m = lattice(26);
    let cases: Vec<(String, &str, &str, &str)> = vec![
        // (file, token to break, its replacement, expected message part)
        (
            msh41(&m, "", None),
            "\n13000\n",
            "\n13x00\n",
            "expected an unsigned integer, found '13x00'",
        ),
        (
            msh41(&m, "", None),
            "\n50001 ",
            "\n5000y ",
            "expected an unsigned integer, found '5000y'",
        ),
        (
            msh41(&m, "", Some(1000)),
            "\n61001 ",
            "\n61001 7z ",
            "expected an unsigned integer, found '7z'",
        ),
        (
            msh22(&m, "", 4999),
            "\n40001 ",
            "\n4000a ",
            "expected an unsigned integer, found '4000a'",
        ),
    ];
    for (text, from, to, message) in cases {
        let at = text.find(from).unwrap() + 1;
        let broken = text.replacen(from, to, 1);
        let e = parse_msh(broken.as_bytes()).unwrap_err();
        assert!(e.message.contains(message), "{e}");
        assert_eq!(e.line, line_of(&broken, at), "{e}");
    }
    // A coordinate that is not a number, in the 12 000th coordinate line of the 4.1 block.
    let text = msh41(&m, "", None);
    let start = text.find("$Nodes").unwrap();
    let line_start =
        (0..12_000 + m.nodes.len() + 3).fold(start, |p, _| text[p..].find('\n').unwrap() + p + 1);
    let token_end = text[line_start..].find(' ').unwrap() + line_start;
    let mut broken = text.clone();
    broken.replace_range(line_start..token_end, "1.2.3");
    let e = parse_msh(broken.as_bytes()).unwrap_err();
    assert!(
        e.message.contains("expected a number, found '1.2.3'"),
        "{e}"
    );
    assert_eq!(e.line, line_of(&broken, line_start));
    assert_eq!(e.section, "$Nodes");
    // An element that names a node not in $Nodes, deep in the 2.2 block.
    let text = msh22(&m, "", 4999);
    let rec = format!("\n70000 4 2 1 1 {} ", m.tets[69_999][0]);
    let at = text.find(&rec).unwrap() + 1;
    let broken = text.replacen(&rec, "\n70000 4 2 1 1 999999999 ", 1);
    let e = parse_msh(broken.as_bytes()).unwrap_err();
    assert!(
        e.message
            .contains("element 70000 references node 999999999, which is not in $Nodes"),
        "{e}"
    );
    assert_eq!(e.line, line_of(&broken, at));
    assert_eq!(e.section, "$Elements");
}

/// A bad record in a middle chunk of a file's block (not the first chunk, not the last): the
/// error of `read_msh` and of `nlrom mesh info` names the file and the record's line.
#[test]
fn a_bad_line_in_a_parallel_chunk_names_the_file_and_the_line() {
    let m = lattice(26);
    let dir = tempfile::tempdir().unwrap();
    let cases: Vec<(&str, String, String, String, &str, &str)> = vec![
        // (file name, text, record to break, its replacement, section, expected message part)
        (
            "elements41.msh",
            msh41(&m, "", None),
            format!("\n60000 {} ", m.tets[59_999][0]),
            "\n60000 987654321 ".to_string(),
            "$Elements",
            "element 60000 references node 987654321, which is not in $Nodes",
        ),
        (
            "nodes22.msh",
            msh22(&m, "", 4999),
            format!("\n15000 {} ", num(14_999, m.nodes[14_999].1[0])),
            "\n15000 1,5 ".to_string(),
            "$Nodes",
            "expected a number, found '1,5'",
        ),
    ];
    for (name, text, from, to, section, message) in cases {
        assert_eq!(text.matches(from.as_str()).count(), 1, "{name}");
        let at = text.find(&from).unwrap() + 1;
        let broken = text.replacen(&from, &to, 1);
        let line = line_of(&broken, at);
        assert!(line > 8192, "{name}: line {line} is in the first chunk");
        let path = dir.path().join(name);
        std::fs::write(&path, &broken).unwrap();
        let e = read_msh(&path).unwrap_err().to_string();
        let place = format!("{}: line {line} ", path.display());
        assert!(e.contains(&place), "{name}: {e}");
        assert!(e.contains(section) && e.contains(message), "{name}: {e}");
        let out = nlrom(&["mesh", "info", path.to_str().unwrap()]);
        assert_eq!(out.status.code(), Some(2), "{name}");
        let err = stderr(&out);
        assert!(
            err.contains(&place) && err.contains(message),
            "{name}: {err}"
        );
    }
}
