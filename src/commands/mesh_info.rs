//! `nlrom mesh info`: format, node count, element counts by type, physical groups and bounding
//! box of a Gmsh MSH file, as text or one JSON object (`docs/user-guide.md`).

use std::path::Path;
use std::time::Instant;

use serde_json::{json, Value};

use super::Reporter;
use crate::error::Result;
use crate::mesh::msh::read_msh;
use crate::mesh::Mesh;

/// `nlrom mesh info`: prints the summary of a mesh as text or JSON.
pub fn mesh_info_command(path: &Path, rep: &Reporter, as_json: bool) -> Result<()> {
    let start = Instant::now();
    let mesh = read_msh(path)?;
    rep.detail(&format!(
        "read {} in {:.3} s",
        path.display(),
        start.elapsed().as_secs_f64()
    ));
    if as_json {
        let mut report = mesh_summary(&mesh);
        report["wall_seconds"] = json!(start.elapsed().as_secs_f64());
        println!("{report}");
    } else {
        print!("{}", mesh_summary_text(path, &mesh));
    }
    Ok(())
}

/// The `mesh info` JSON object of `docs/user-guide.md`.
pub fn mesh_summary(mesh: &Mesh) -> Value {
    let elements: serde_json::Map<String, Value> = mesh
        .element_counts()
        .into_iter()
        .map(|(k, n)| (k.name().to_string(), json!(n)))
        .collect();
    let groups: Vec<Value> = mesh
        .groups
        .iter()
        .map(|g| {
            json!({
                "name": g.name,
                "dim": g.dim,
                "tag": g.tag,
                "elements": mesh.group_element_count(g),
                "nodes": mesh.group_node_count(g),
            })
        })
        .collect();
    json!({
        "format": mesh.format.version.as_str(),
        "binary": mesh.format.binary,
        "nodes": mesh.num_nodes(),
        "elements": elements,
        "groups": groups,
        "bbox": mesh.bbox(),
    })
}

/// The human-readable `mesh info` report.
fn mesh_summary_text(path: &Path, mesh: &Mesh) -> String {
    let mut s = format!(
        "{}\n  format   MSH {} {}{}\n  nodes    {}\n  elements {}\n",
        path.display(),
        mesh.format.version.as_str(),
        if mesh.format.binary {
            "binary"
        } else {
            "ASCII"
        },
        if mesh.format.big_endian {
            " (big-endian)"
        } else {
            ""
        },
        mesh.num_nodes(),
        mesh.num_elements()
    );
    for (kind, n) in mesh.element_counts() {
        s += &format!("    {:<10} {n}\n", kind.name());
    }
    s += &format!("  physical groups ({})\n", mesh.groups.len());
    s += &format!(
        "    {:<24} {:>3} {:>6} {:>9} {:>7}\n",
        "name", "dim", "tag", "elements", "nodes"
    );
    for g in &mesh.groups {
        s += &format!(
            "    {:<24} {:>3} {:>6} {:>9} {:>7}\n",
            g.name,
            g.dim,
            g.tag,
            mesh.group_element_count(g),
            mesh.group_node_count(g)
        );
    }
    let [lo, hi] = mesh.bbox();
    s += &format!(
        "  bounding box [{:.6e}, {:.6e}, {:.6e}] .. [{:.6e}, {:.6e}, {:.6e}]\n",
        lo[0], lo[1], lo[2], hi[0], hi[1], hi[2]
    );
    s
}
