//! Fuzz target for the Gmsh MSH reader: `nlrom::mesh::msh::parse_msh` must return `Ok` or `Err`
//! for every input, never panic (index out of bounds, arithmetic overflow — cargo fuzz builds with
//! debug assertions —, `unwrap`/`expect`, allocation failure, ...). On `Ok`, the mesh is exercised
//! a little, so that a parse that yields an inconsistent mesh (e.g. a node index out of range)
//! panics downstream and is caught too.

#![no_main]

use libfuzzer_sys::fuzz_target;
use nlrom::mesh::{faces, msh};

fuzz_target!(|data: &[u8]| {
    let mesh = match msh::parse_msh(data) {
        Ok(mesh) => mesh,
        Err(e) => {
            // The error's location must lie inside the input.
            assert!(
                e.offset <= data.len(),
                "error offset {} past the end ({} bytes)",
                e.offset,
                data.len()
            );
            let _ = e.to_string();
            return;
        }
    };

    // Invariants of a parsed mesh.
    let n = mesh.num_nodes();
    assert_eq!(mesh.coords.len(), n, "one coordinate triple per node");
    assert!(
        mesh.node_tags.windows(2).all(|w| w[0] < w[1]),
        "node tags ascending and distinct"
    );
    assert!(
        mesh.coords.iter().flatten().all(|x| x.is_finite()),
        "finite coordinates"
    );
    for b in &mesh.blocks {
        assert_eq!(
            b.connectivity.len(),
            b.len() * b.kind.num_nodes(),
            "block connectivity length"
        );
        assert!(
            b.connectivity.iter().all(|&i| (i as usize) < n),
            "node index in range"
        );
    }
    for p in &mesh.periodic {
        assert!(p
            .nodes
            .iter()
            .all(|&(a, b)| (a as usize) < n && (b as usize) < n));
    }
    for (i, &t) in mesh.node_tags.iter().enumerate() {
        assert_eq!(mesh.node_index(t), Some(i as u32));
    }

    // Exercise the mesh API downstream of the parse.
    let _ = mesh.bbox();
    let _ = mesh.size();
    let _ = mesh.num_elements();
    let _ = mesh.element_counts();
    for b in &mesh.blocks {
        for e in b.elements() {
            let _ = e.len();
        }
        if !b.is_empty() {
            let _ = b.element(b.len() - 1);
        }
    }
    for g in &mesh.groups {
        let _ = mesh.group_element_count(g);
        let nodes = mesh.group_node_indices(g);
        assert!(nodes.iter().all(|&i| (i as usize) < n));
        let _ = mesh.group(&g.name);
        let _ = mesh.nodes_of(&g.name);
        if g.dim == 2 {
            // Errors (no volume behind a face, ...) are fine; panics are not.
            if let Ok(fs) = faces::group_faces(&mesh, &g.name) {
                for f in &fs {
                    assert_eq!(f.nodes.len(), f.kind.num_nodes());
                    let xs: Vec<[f64; 3]> =
                        f.nodes.iter().map(|&i| mesh.coords[i as usize]).collect();
                    let _ = faces::face_area(f.kind, &xs);
                }
            }
        }
    }
});
