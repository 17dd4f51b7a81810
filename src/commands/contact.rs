//! `nlrom contact`: the contact pairs of every `[[contact]]` of a case (SAMA or node-to-node):
//! targets, weights, local frames and distances, as a table or one JSON object.

use std::path::Path;
use std::time::Instant;

use serde_json::{json, Value};

use super::solve::{projection_line, unprojected_warning};
use super::Reporter;
use crate::case::Case;
use crate::cyclic::CyclicGeometry;
use crate::error::{Error, Result};
use crate::interface::build_interfaces;
use crate::interface::report::{interface_json, interfaces_text};
use crate::mesh::msh::read_msh;

/// `nlrom contact`: the contact pairs of every `[[contact]]` of the case (SAMA or node-to-node).
pub fn contact_command(case_path: &Path, rep: &Reporter, as_json: bool) -> Result<()> {
    let start = Instant::now();
    let case = Case::load(case_path)?;
    if case.contact.is_empty() {
        return Err(Error::input(format!(
            "{}: the case has no [[contact]] table; add one with `contact`, `target`, `mu`, `kt`, `kn`, `n0` (see docs/case-file.md)",
            case_path.display()
        )));
    }
    let Some(mesh_path) = &case.model.mesh else {
        return Err(Error::input(format!(
            "{}: [[contact]] needs `model.mesh` (the groups and coordinates of the contact and target nodes)",
            case_path.display()
        )));
    };
    let mesh = read_msh(mesh_path)?;
    case.check_groups(&mesh)?;
    let cyclic = case
        .cyclic
        .as_ref()
        .map(CyclicGeometry::from_case)
        .transpose()?;
    let interfaces = build_interfaces(&case, &mesh, cyclic.as_ref())?;
    for iface in &interfaces {
        rep.info(&projection_line(iface));
        if let Some(w) = unprojected_warning(iface, "listed under \"unprojected\"") {
            rep.warn(&w);
        }
    }
    if as_json {
        let list: Vec<Value> = interfaces.iter().map(interface_json).collect();
        let report = json!({
            "interfaces": list,
            "wall_seconds": start.elapsed().as_secs_f64(),
        });
        println!("{report}");
    } else {
        print!("{}", interfaces_text(&interfaces));
    }
    Ok(())
}
