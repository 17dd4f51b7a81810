//! The bundled models parse identically in all four MSH variants, and agree with meshio.
//!
//! Reference: `tests/data/meshio_counts.json`, written by `python3 tools/validation/meshio_compare.py --write`
//! from `meshio.read` of every bundled file (node count, element counts by type, per physical group
//! the element and node counts, bounding box).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use nlrom::mesh::msh::read_msh;
use nlrom::mesh::{ElementType, Mesh, MshVersion};

const MODELS: [&str; 14] = [
    "sector_conforming",
    "sector_nonconforming",
    "sector_coarse_target",
    "sector8",
    "cube_tet4",
    "cube_tet10",
    "bar_hex20",
    "bar_tet10",
    "damper_bar",
    "mixed_o1",
    "mixed_o2",
    "mixed_o2i",
    "blade",
    "blade_coarse",
];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The four variants of a model: (relative path, version, binary).
fn variants(model: &str) -> Vec<(String, MshVersion, bool)> {
    vec![
        (format!("meshes/{model}.msh"), MshVersion::V41, false),
        (
            format!("meshes/formats/{model}.v41-binary.msh"),
            MshVersion::V41,
            true,
        ),
        (
            format!("meshes/formats/{model}.v22-ascii.msh"),
            MshVersion::V22,
            false,
        ),
        (
            format!("meshes/formats/{model}.v22-binary.msh"),
            MshVersion::V22,
            true,
        ),
    ]
}

fn load(rel: &str) -> Mesh {
    read_msh(&root().join(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// An element by content: its type and its node tags in Gmsh order.
type ElementKey = (ElementType, Vec<u64>);

/// The elements of some blocks by content, sorted: independent of block layout and of element
/// tags (Gmsh's 2.2 writer renumbers the elements of mixed meshes).
fn element_keys<'a>(
    m: &Mesh,
    blocks: impl Iterator<Item = &'a nlrom::mesh::ElementBlock>,
) -> Vec<ElementKey> {
    let mut v: Vec<ElementKey> = blocks
        .flat_map(|b| {
            b.elements()
                .map(move |n| (b.kind, n.iter().map(|&i| m.node_tags[i as usize]).collect()))
        })
        .collect();
    v.sort();
    v
}

fn element_list(m: &Mesh) -> Vec<ElementKey> {
    element_keys(m, m.blocks.iter())
}

/// Groups by name: (dim, tag, elements by content, sorted node tags).
type GroupKey = (u8, i32, Vec<ElementKey>, Vec<u64>);

fn group_list(m: &Mesh) -> BTreeMap<String, GroupKey> {
    m.groups
        .iter()
        .map(|g| {
            let elements = element_keys(m, m.group_blocks(g));
            let nodes = m
                .group_node_indices(g)
                .iter()
                .map(|&i| m.node_tags[i as usize])
                .collect();
            (g.name.clone(), (g.dim, g.tag, elements, nodes))
        })
        .collect()
}

#[test]
fn all_four_variants_parse_identically() {
    for model in MODELS {
        let vs = variants(model);
        let meshes: Vec<Mesh> = vs.iter().map(|(p, _, _)| load(p)).collect();
        for ((path, version, binary), m) in vs.iter().zip(&meshes) {
            assert_eq!(m.format.version, *version, "{path}");
            assert_eq!(m.format.binary, *binary, "{path}");
            assert!(!m.format.big_endian, "{path}");
        }
        let reference = &meshes[0];
        let ref_elements = element_list(reference);
        let ref_groups = group_list(reference);
        let size = reference.size();
        for ((path, _, _), m) in vs.iter().zip(&meshes).skip(1) {
            assert_eq!(m.node_tags, reference.node_tags, "{path}: node tags");
            // ASCII files carry 16 significant digits, so ASCII vs binary differ by an ulp or so.
            for (a, b) in m.coords.iter().zip(&reference.coords) {
                for c in 0..3 {
                    assert!(
                        (a[c] - b[c]).abs() <= 1e-15 * size,
                        "{path}: coordinates {a:?} vs {b:?}"
                    );
                }
            }
            assert!(
                element_list(m) == ref_elements,
                "{path}: the elements differ from {model}.msh"
            );
            assert!(
                group_list(m) == ref_groups,
                "{path}: the groups differ from {model}.msh"
            );
        }
        // Binary vs binary: bit-identical coordinates.
        assert_eq!(
            meshes[1].coords, meshes[3].coords,
            "{model}: v41 vs v22 binary coordinates"
        );
    }
}

#[test]
fn counts_agree_with_meshio() {
    let text = std::fs::read_to_string(root().join("tests/data/meshio_counts.json"))
        .expect("meshio_counts.json");
    let expected: serde_json::Value = serde_json::from_str(&text).expect("valid JSON");
    let files = expected.as_object().expect("object");
    // Every model in four variants, and disk8.msh (tools/meshes/make_disk_mesh.py) in MSH 4.1 ASCII only.
    assert_eq!(
        files.len(),
        4 * MODELS.len() + 1,
        "one entry per bundled file"
    );
    assert!(files.contains_key("meshes/disk8.msh"));
    for (rel, want) in files {
        let m = load(rel);
        let got = nlrom::commands::mesh_info::mesh_summary(&m);
        assert_eq!(got["nodes"], want["nodes"], "{rel}: nodes");
        assert_eq!(got["elements"], want["elements"], "{rel}: element counts");
        let groups = want["groups"].as_object().expect("groups");
        assert_eq!(
            got["groups"].as_array().expect("array").len(),
            groups.len(),
            "{rel}: group count"
        );
        for g in got["groups"].as_array().expect("array") {
            let name = g["name"].as_str().expect("name");
            let w = &groups[name];
            for key in ["dim", "tag", "elements", "nodes"] {
                assert_eq!(g[key], w[key], "{rel}: group {name} {key}");
            }
        }
        for (a, b) in got["bbox"]
            .as_array()
            .into_iter()
            .flatten()
            .zip(want["bbox"].as_array().into_iter().flatten())
        {
            for (x, y) in a
                .as_array()
                .into_iter()
                .flatten()
                .zip(b.as_array().into_iter().flatten())
            {
                let (x, y) = (x.as_f64().expect("number"), y.as_f64().expect("number"));
                assert!(
                    (x - y).abs() <= 1e-15 * (1.0 + y.abs()),
                    "{rel}: bbox {x} vs {y}"
                );
            }
        }
    }
}

#[test]
fn mixed_meshes_cover_every_element_type() {
    let mut seen = std::collections::BTreeSet::new();
    for model in ["mixed_o1", "mixed_o2", "mixed_o2i"] {
        seen.extend(
            load(&format!("meshes/{model}.msh"))
                .element_counts()
                .into_keys(),
        );
    }
    assert_eq!(
        seen.len(),
        nlrom::mesh::element::ALL_TYPES.len(),
        "{seen:?}"
    );
}

#[test]
fn big_endian_binary_is_recognised() {
    // Byte-swap the binary 4.1 cube: every int/size_t/double swapped; the parse must be identical.
    let path = root().join("meshes/formats/cube_tet4.v41-binary.msh");
    let m = read_msh(&path).expect("parses");
    let swapped = swap_v41_binary(&std::fs::read(&path).expect("read"));
    let b = nlrom::mesh::msh::parse_msh(&swapped).expect("big-endian parses");
    assert!(b.format.big_endian);
    assert_eq!(b.node_tags, m.node_tags);
    assert_eq!(b.coords, m.coords);
    assert!(element_list(&b) == element_list(&m), "elements differ");
    assert!(group_list(&b) == group_list(&m), "groups differ");
}

/// Re-encodes a little-endian MSH 4.1 binary file as big-endian by re-parsing its structure.
fn swap_v41_binary(bytes: &[u8]) -> Vec<u8> {
    let m = nlrom::mesh::msh::parse_msh(bytes).expect("little-endian parses");
    let text = String::from_utf8_lossy(bytes);
    // Keep the $PhysicalNames text as is and write the other sections anew in big-endian.
    let names_start = text.find("$PhysicalNames").expect("names");
    let names_end =
        text.find("$EndPhysicalNames").expect("names end") + "$EndPhysicalNames\n".len();
    let mut out = b"$MeshFormat\n4.1 1 8\n".to_vec();
    out.extend_from_slice(&1i32.to_be_bytes());
    out.extend_from_slice(b"\n$EndMeshFormat\n");
    out.extend_from_slice(&bytes[names_start..names_end]);
    // One entity per physical group and dimension, so the group resolution is exercised.
    let mut entities: [Vec<(i32, Vec<i32>)>; 4] = Default::default();
    for b in &m.blocks {
        let list = &mut entities[b.kind.dim() as usize];
        if !list.iter().any(|(t, _)| *t == b.entity) {
            list.push((b.entity, b.physicals.clone()));
        }
    }
    out.extend_from_slice(b"$Entities\n");
    for list in &entities {
        out.extend_from_slice(&(list.len() as u64).to_be_bytes());
    }
    for (dim, list) in entities.iter().enumerate() {
        for (tag, phys) in list {
            out.extend_from_slice(&tag.to_be_bytes());
            for _ in 0..if dim == 0 { 3 } else { 6 } {
                out.extend_from_slice(&0f64.to_be_bytes());
            }
            out.extend_from_slice(&(phys.len() as u64).to_be_bytes());
            for p in phys {
                out.extend_from_slice(&p.to_be_bytes());
            }
            if dim > 0 {
                out.extend_from_slice(&0u64.to_be_bytes());
            }
        }
    }
    out.extend_from_slice(b"\n$EndEntities\n$Nodes\n");
    let n = m.num_nodes() as u64;
    for v in [1u64, n, m.node_tags[0], *m.node_tags.last().expect("nodes")] {
        out.extend_from_slice(&v.to_be_bytes());
    }
    out.extend_from_slice(&3i32.to_be_bytes());
    out.extend_from_slice(&1i32.to_be_bytes());
    out.extend_from_slice(&0i32.to_be_bytes());
    out.extend_from_slice(&n.to_be_bytes());
    for t in &m.node_tags {
        out.extend_from_slice(&t.to_be_bytes());
    }
    for p in &m.coords {
        for x in p {
            out.extend_from_slice(&x.to_be_bytes());
        }
    }
    out.extend_from_slice(b"\n$EndNodes\n$Elements\n");
    let total: u64 = m.num_elements() as u64;
    for v in [m.blocks.len() as u64, total, 1, u64::MAX] {
        out.extend_from_slice(&v.to_be_bytes());
    }
    for b in &m.blocks {
        out.extend_from_slice(&i32::from(b.kind.dim()).to_be_bytes());
        out.extend_from_slice(&b.entity.to_be_bytes());
        out.extend_from_slice(&b.kind.gmsh_id().to_be_bytes());
        out.extend_from_slice(&(b.len() as u64).to_be_bytes());
        for (e, nodes) in b.elements().enumerate() {
            out.extend_from_slice(&b.tags.at(e).to_be_bytes());
            for &i in nodes {
                out.extend_from_slice(&m.node_tags[i as usize].to_be_bytes());
            }
        }
    }
    out.extend_from_slice(b"\n$EndElements\n");
    out
}

/// The expected outward unit normal at a point of a face.
type NormalAt = dyn Fn([f64; 3]) -> [f64; 3];

#[test]
fn sector_faces_point_out_of_the_volume() {
    // Sector θ ∈ [0, α] about z, α = 2π/24: the shroud contact face (θ = α) has outward normal
    // +e_θ(α); the target face (θ = 0) −e_θ(0) = −y; the hub (r = 0.1) points towards the axis.
    let m = load("meshes/sector_conforming.msh");
    let alpha = 2.0 * std::f64::consts::PI / 24.0;
    let checks: [(&str, Box<NormalAt>); 3] = [
        (
            "shroud_contact",
            Box::new(move |_| [-alpha.sin(), alpha.cos(), 0.0]),
        ),
        ("shroud_target", Box::new(|_| [0.0, -1.0, 0.0])),
        (
            "hub",
            Box::new(|c: [f64; 3]| {
                let r = (c[0] * c[0] + c[1] * c[1]).sqrt();
                [-c[0] / r, -c[1] / r, 0.0]
            }),
        ),
    ];
    for (name, expected) in checks {
        let faces = nlrom::mesh::faces::group_faces(&m, name).expect("faces");
        let group = m.group(name).expect("group");
        assert_eq!(faces.len(), m.group_element_count(group), "{name}");
        let mut area = 0.0;
        for f in &faces {
            let xs: Vec<[f64; 3]> = f.nodes.iter().map(|&i| m.coords[i as usize]).collect();
            let n = nlrom::mesh::faces::area_vector(f.kind, &xs, 1.0 / 3.0, 1.0 / 3.0);
            let len = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2]).sqrt();
            let e = expected(xs[0]);
            let cos = (n[0] * e[0] + n[1] * e[1] + n[2] * e[2]) / len;
            assert!(cos > 0.99, "{name}: face normal {n:?} vs expected {e:?}");
            area += nlrom::mesh::faces::face_area(f.kind, &xs);
        }
        assert!(area > 0.0, "{name}");
    }
    // The hub is a cylinder r = 0.1, z ∈ [0, 0.03], θ ∈ [0, α]: area r·α·h (curved faces, 1e-4).
    let hub: f64 = nlrom::mesh::faces::group_faces(&m, "hub")
        .expect("hub")
        .iter()
        .map(|f| {
            let xs: Vec<[f64; 3]> = f.nodes.iter().map(|&i| m.coords[i as usize]).collect();
            nlrom::mesh::faces::face_area(f.kind, &xs)
        })
        .sum();
    let exact = 0.1 * alpha * 0.03;
    assert!(
        (hub - exact).abs() / exact < 1e-4,
        "hub area {hub} vs {exact}"
    );
}

#[test]
fn missing_group_names_the_file_and_the_groups() {
    let m = load("meshes/cube_tet4.msh");
    let err = m.group("shroud").expect_err("no such group").to_string();
    assert!(
        err.contains("cube_tet4.msh") && err.contains("'shroud'") && err.contains("bottom"),
        "{err}"
    );
    let err = nlrom::mesh::faces::group_faces(&m, "volume")
        .expect_err("not a surface")
        .to_string();
    assert!(err.contains("dimension 3"), "{err}");
}

#[test]
fn file_not_found_is_an_io_error() {
    let err = read_msh(Path::new("no/such/file.msh")).expect_err("missing");
    assert_eq!(err.exit_code(), 2);
    assert!(err.to_string().contains("no/such/file.msh"));
}

#[test]
fn periodic_links_map_frontier_corners_by_rotation() {
    // Gmsh writes $Periodic for the frontier surfaces (and, in 4.1, their curves and points): the
    // row-major affine map is a rotation by ±α = 2π/24 about z that takes every master node of a
    // listed pair onto its slave node (to 1e-12 of the model size). Only corner nodes are listed
    // (`docs/theory.md`).
    for (rel, links, sectors) in [
        ("meshes/sector_conforming.msh", 18, 24.0),
        ("meshes/formats/sector_conforming.v41-binary.msh", 18, 24.0),
        ("meshes/formats/sector_conforming.v22-ascii.msh", 2, 24.0),
        ("meshes/formats/sector_conforming.v22-binary.msh", 2, 24.0),
        ("meshes/sector8.msh", 18, 8.0),
        ("meshes/formats/sector8.v22-binary.msh", 2, 8.0),
    ] {
        let alpha = 2.0 * std::f64::consts::PI / sectors;
        let m = load(rel);
        assert_eq!(m.periodic.len(), links, "{rel}");
        let size = m.size();
        let mut pairs = 0;
        for link in &m.periodic {
            let a = &link.affine;
            assert_eq!(a.len(), 16, "{rel}");
            assert!(
                (a[0] - alpha.cos()).abs() < 1e-12
                    && (a[1].abs() - alpha.sin()).abs() < 1e-12
                    && a[1] == -a[4],
                "{rel}: {a:?}"
            );
            for &(slave, master) in &link.nodes {
                let (p, q) = (m.coords[master as usize], m.coords[slave as usize]);
                let image: Vec<f64> = (0..3)
                    .map(|r| {
                        a[4 * r] * p[0] + a[4 * r + 1] * p[1] + a[4 * r + 2] * p[2] + a[4 * r + 3]
                    })
                    .collect();
                let d = ((image[0] - q[0]).powi(2)
                    + (image[1] - q[1]).powi(2)
                    + (image[2] - q[2]).powi(2))
                .sqrt();
                assert!(
                    d < 1e-12 * size,
                    "{rel}: pair ({slave}, {master}) off by {d}"
                );
                pairs += 1;
            }
        }
        assert!(pairs > 0, "{rel}");
    }
}
