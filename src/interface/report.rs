//! The `nlrom contact` report (`docs/user-guide.md`): JSON object and text table of the
//! interfaces, and an interface as the `/contact/<name>` group of the results file
//! ([`ContactData`]).

use serde_json::{json, Value};

use crate::case::{ContactElement, ContactModel, SamaCoupling};
use crate::output::{ContactData, ContactPairData};

use super::ContactInterface;

/// The model's spelling in the case file and the report.
pub fn model_name(model: ContactModel) -> &'static str {
    match model {
        ContactModel::Sama => "sama",
        ContactModel::NodeToNode => "node-to-node",
    }
}

/// The coupling's spelling in the case file and the report.
pub fn coupling_name(coupling: SamaCoupling) -> &'static str {
    match coupling {
        SamaCoupling::Array => "array",
        SamaCoupling::Interpolated => "interpolated",
    }
}

/// The friction element's spelling in the case file and the results.
pub fn element_name(element: ContactElement) -> &'static str {
    match element {
        ContactElement::OneD => "1d",
        ContactElement::TwoD => "2d",
    }
}

impl ContactData {
    /// The friction elements of a SAMA / node-to-node interface, in the order of the harmonic
    /// balance's elements: with the array coupling one per target node t_j of each contact node,
    /// with the weights, frames and eq. 31 parameters [`crate::interface`] computed; with the interpolated
    /// coupling one per contact node (weight 1, the node's k_t, k_n and n0_c), whose
    /// `target_node` is the target node of the largest shape-function share.
    pub fn from_interface(interface: &ContactInterface) -> Self {
        let interpolated = interface.coupling == SamaCoupling::Interpolated;
        let mut pairs = Vec::new();
        for pair in &interface.pairs {
            let row =
                |target_node: u64, weight: f64, kt: f64, kn: f64, preload: f64| ContactPairData {
                    contact_node: pair.contact_node,
                    target_node,
                    weight,
                    frame: pair.frame,
                    kt,
                    kn,
                    preload,
                    virtual_point: pair.virtual_point,
                };
            if interpolated && pair.targets.len() > 1 {
                let dominant = (0..pair.targets.len())
                    .max_by(|&a, &b| pair.weights[a].abs().total_cmp(&pair.weights[b].abs()))
                    .unwrap_or(0);
                pairs.push(row(
                    pair.targets[dominant],
                    1.0,
                    pair.kt.iter().sum(),
                    pair.kn.iter().sum(),
                    pair.n0_node,
                ));
            } else {
                for j in 0..pair.targets.len() {
                    pairs.push(row(
                        pair.targets[j],
                        pair.weights[j],
                        pair.kt[j],
                        pair.kn[j],
                        pair.n0[j],
                    ));
                }
            }
        }
        ContactData {
            name: interface.name.clone(),
            model: model_name(interface.model).to_string(),
            coupling: coupling_name(interface.coupling).to_string(),
            element: element_name(interface.element).to_string(),
            sigma: i64::from(interface.sigma),
            mu: interface.mu,
            pairs,
            curves: Vec::new(),
        }
    }
}

/// One interface as the JSON object of `docs/user-guide.md` (`nlrom contact`), with extra keys: per
/// pair the frame rows `t1`, `t2`, the `virtual_point`, signed `gap`, target `face` tag and its
/// reference coordinates, tributary `area`, the pair parameters `kt`, `kn`, `n0` (eq 31) and the
/// node's preload share `n0_node` and, for a node paired on the target's border, its
/// `tangential_offset` (null otherwise); per interface the unprojected nodes' details, the nodes
/// paired on the border (`edge_projected`, with distance, offset and edge tolerance — null where
/// unbounded) and the tolerances.
pub fn interface_json(iface: &ContactInterface) -> Value {
    let pairs: Vec<Value> = iface
        .pairs
        .iter()
        .map(|p| {
            json!({
                "contact_node": p.contact_node,
                "targets": p.targets,
                "weights": p.weights,
                "distance": p.distance,
                "gap": p.gap,
                "normal": p.frame[2],
                "t1": p.frame[0],
                "t2": p.frame[1],
                "virtual_point": p.virtual_point,
                "face": p.face,
                "reference": p.reference,
                "area": p.area,
                "kt": p.kt,
                "kn": p.kn,
                "n0": p.n0,
                "n0_node": p.n0_node,
                "tangential_offset": p.edge.map(|e| e.tangential_offset),
            })
        })
        .collect();
    let details: Vec<Value> = iface
        .unprojected
        .iter()
        .map(|u| {
            json!({
                "node": u.node,
                "distance": u.distance,
                "tangential_offset": u.tangential_offset,
            })
        })
        .collect();
    let edge: Vec<Value> = iface
        .edge_pairs()
        .map(|p| {
            let e = p.edge.expect("edge pair");
            json!({
                "node": p.contact_node,
                "distance": p.distance,
                "tangential_offset": e.tangential_offset,
                "tolerance": e.tolerance.is_finite().then_some(e.tolerance),
            })
        })
        .collect();
    json!({
        "name": iface.name,
        "model": model_name(iface.model),
        "coupling": coupling_name(iface.coupling),
        "sigma": iface.sigma,
        "contact_nodes": iface.contact_nodes,
        "projected": iface.pairs.len(),
        "pairs": pairs,
        "unprojected": iface.unprojected.iter().map(|u| u.node).collect::<Vec<u64>>(),
        "unprojected_detail": details,
        "edge_projected": iface.edge_pairs().map(|p| p.contact_node).collect::<Vec<u64>>(),
        "edge_projected_detail": edge,
        "sum_kt": iface.sum_kt,
        "sum_kn": iface.sum_kn,
        "sum_n0": iface.sum_n0,
        "max_distance": iface.max_distance,
        "coincident_tolerance": iface.coincident_tolerance,
    })
}

/// A readable summary: one header per interface and one row per contact node.
pub fn interfaces_text(interfaces: &[ContactInterface]) -> String {
    let mut s = String::new();
    for iface in interfaces {
        let max_gap = iface.pairs.iter().map(|p| p.gap.abs()).fold(0.0, f64::max);
        s += &format!(
            "contact '{}': model {}, σ = {}, {} contact nodes, {} projected{}, {} unprojected\n",
            iface.name,
            model_name(iface.model),
            iface.sigma,
            iface.contact_nodes,
            iface.pairs.len(),
            match iface.edge_pairs().count() {
                0 => String::new(),
                n => format!(" ({n} on the target's edge)"),
            },
            iface.unprojected.len()
        );
        s += &format!(
            "  Σ kt = {:.6e} N/m, Σ kn = {:.6e} N/m, Σ n0 = {:.6e} N, max |gap| = {:.3e} m\n",
            iface.sum_kt, iface.sum_kn, iface.sum_n0, max_gap
        );
        s += &format!(
            "  {:>8} {:>10} {:>11} {:>11}  targets (weight)\n",
            "node", "gap (m)", "n0 (N)", "area (m²)"
        );
        for p in &iface.pairs {
            let targets: Vec<String> = p
                .targets
                .iter()
                .zip(&p.weights)
                .map(|(t, w)| format!("{t} ({w:.4})"))
                .collect();
            s += &format!(
                "  {:>8} {:>10.2e} {:>11.4e} {:>11.4e}  {}\n",
                p.contact_node,
                p.gap,
                p.n0_node,
                p.area,
                targets.join(", ")
            );
        }
        let edge: Vec<String> = iface
            .edge_pairs()
            .map(|p| {
                let e = p.edge.expect("edge pair");
                format!(
                    "{} (outside by {:.3e} m, distance {:.3e} m)",
                    p.contact_node, e.tangential_offset, p.distance
                )
            })
            .collect();
        if !edge.is_empty() {
            s += &format!("  on the target's edge: {}\n", edge.join(", "));
        }
        if !iface.unprojected.is_empty() {
            let list: Vec<String> = iface
                .unprojected
                .iter()
                .map(|u| match u.distance {
                    Some(d) => format!("{} (nearest {:.3e} m)", u.node, d),
                    None => format!("{} (no face within {:.3e} m)", u.node, iface.max_distance),
                })
                .collect();
            s += &format!("  unprojected: {}\n", list.join(", "));
        }
    }
    s
}
