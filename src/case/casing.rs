//! `[[casing]]` and `[thermal]`: a rigid casing (stator) with unilateral contact, Coulomb friction
//! and frictional heating on the nodes of a mesh group, and the thermal data of a thermoelastic
//! mesh model, marched by `nlrom march --scheme moreau-jean` or `carpenter` (`docs/theory.md`,
//! nonsmooth contact; Thorin, Guérin, Legrand, Thouverez & Almeida, ASME GT2018-75959, 2018).

use serde::Deserialize;

use super::{Axis, Case};
use crate::error::Result;

/// `[[casing]]`: a rigid circular casing of radius R about the rotation axis, in contact with the
/// nodes of `group`. Node i (initial position p_i, radius r_i from the axis, radial unit vector
/// e_r,i) has the gap g_i = g0_i − e_r,i·u_i ≥ 0 with g0_i = R − r_i (`radius`) or g0_i from `gap`
/// (one value for every node, or one per node: [`CasingGap`]);
/// the contact force λ_i ≥ 0 pushes the node along −e_r,i, the friction force μλ_i acts along
/// −sgn(Ω) e_φ,i (e_φ = a × e_r, the casing sliding past the blade at −RΩ e_φ), and the heat flow
/// α λ_i (W) enters the node's temperature row.
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CasingTable {
    /// Name in the results (the obstacles are `name:node tag`); default `casing[i]`.
    #[serde(default)]
    pub name: Option<String>,
    /// The mesh group of the contact nodes.
    pub group: String,
    /// The rotation axis a (the casing's axis); default z through the origin.
    #[serde(default)]
    pub axis: Axis,
    /// Casing radius R (m): g0_i = R − r_i. Exclusive with `gap`.
    #[serde(default)]
    pub radius: Option<f64>,
    /// The initial gaps g0_i (m) instead of `radius`: one value for every node, or one per node.
    #[serde(default)]
    pub gap: Option<CasingGap>,
    /// With a list `gap`: the node tags its values belong to, in the same order (each node of
    /// `group` exactly once); without it the values follow the group's nodes in ascending tag
    /// order.
    #[serde(default)]
    pub gap_nodes: Option<Vec<u64>>,
    /// Newton restitution coefficient e ∈ [0, 1]; default 0.
    #[serde(default)]
    pub restitution: f64,
    /// Coulomb friction coefficient μ ≥ 0; default 0 (needs `speed_rpm` when > 0).
    #[serde(default)]
    pub mu: f64,
    /// Rotation speed Ω (rpm, signed about `axis`): its sign sets the sliding direction; the
    /// rotation's inertia effects are not modelled.
    #[serde(default)]
    pub speed_rpm: Option<f64>,
    /// Heating coefficient α (W/N = m/s): the frictional heat flow α·λ enters each contact node's
    /// temperature row (needs `[thermal]`); default 0.
    #[serde(default)]
    pub heating: f64,
}

/// `casing.gap`: the initial gap g0 (m) of every contact node, or one per node.
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(untagged)]
pub enum CasingGap {
    /// The same g0 at every node.
    Uniform(f64),
    /// g0_i per node: in ascending node tag order of the group, or in the order of `gap_nodes`.
    PerNode(Vec<f64>),
}

impl CasingTable {
    /// The casing's name: `name`, else `casing[i]`.
    pub fn label(&self, i: usize) -> String {
        self.name.clone().unwrap_or_else(|| format!("casing[{i}]"))
    }

    /// The initial gap g0 (m) of the node with tag `tag` at radius `r` (m) from the axis:
    /// `radius` − r, the uniform `gap`, or the node's entry of a per-node `gap` (`tags` are the
    /// group's node tags in ascending order). `None` for a node without a gap (the case check
    /// [`Case::check_casing_gaps`] excludes it).
    pub fn initial_gap(&self, tag: u64, r: f64, tags: &[u64]) -> Option<f64> {
        match (&self.gap, self.radius) {
            (Some(CasingGap::Uniform(g)), _) => Some(*g),
            (Some(CasingGap::PerNode(gaps)), _) => {
                let k = match &self.gap_nodes {
                    Some(nodes) => nodes.iter().position(|&t| t == tag)?,
                    None => tags.iter().position(|&t| t == tag)?,
                };
                gaps.get(k).copied()
            }
            (None, Some(radius)) => Some(radius - r),
            (None, None) => None,
        }
    }
}

/// `[thermal]`: isotropic thermal data of every volume of a mesh model, which adds one
/// temperature-rise DOF θ per node (K, above the stress-free `reference_temperature`).
#[derive(Clone, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ThermalTable {
    /// Conductivity k (W/(m·K)), ≥ 0.
    pub conductivity: f64,
    /// Specific heat c_p (J/(kg·K)), > 0.
    pub specific_heat: f64,
    /// Linear thermal expansion coefficient α_th (1/K); 0 removes the thermal load on the
    /// mechanics.
    pub expansion: f64,
    /// The stress-free temperature (°C) that θ = 0 stands for (reported only); default 25.
    #[serde(default = "room_temperature")]
    pub reference_temperature: f64,
    /// Groups whose nodes keep θ = 0 (eliminated like a clamp); none: an insulated body.
    #[serde(default)]
    pub fixed: Vec<String>,
    /// The heat capacity matrix: `"consistent"` (default) or `"lumped"` (HRZ diagonal).
    #[serde(default)]
    pub capacity: Capacity,
}

/// `thermal.capacity`: the form of the heat capacity matrix C^θθ (`crate::fe::thermal`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Capacity {
    /// C_ab = ∫ ρ c_p Nₐ N_b dV.
    #[default]
    Consistent,
    /// The HRZ diagonal of each element's consistent matrix, scaled to its ρ c_p V_e (Hinton,
    /// Rock & Zienkiewicz, 1976).
    Lumped,
}

fn room_temperature() -> f64 {
    25.0
}

impl Case {
    /// Checks `[[casing]]` and `[thermal]`: a mesh model, one of `radius`/`gap`, e ∈ [0, 1],
    /// μ ≥ 0 with a non-zero `speed_rpm`, α ≥ 0 with `[thermal]`, and the thermal data's ranges.
    pub(super) fn validate_casings(&self) -> Result<()> {
        if let Some(t) = &self.thermal {
            self.require(self.model.mesh.is_some(), "thermal", || {
                "[thermal] adds temperature DOF to the nodes of a mesh model; give `[model] mesh`"
            })?;
            self.non_negative("thermal.conductivity", t.conductivity)?;
            self.positive("thermal.specific_heat", t.specific_heat)?;
            self.finite("thermal.expansion", &[t.expansion])?;
            self.finite("thermal.reference_temperature", &[t.reference_temperature])?;
            self.require(
                self.casing.is_empty() || self.model.stiffness.is_none(),
                "thermal",
                || "[thermal] assembles the heat matrices from the mesh; it cannot be combined with external `stiffness`/`mass` matrices",
            )?;
        }
        for (i, c) in self.casing.iter().enumerate() {
            let key = format!("casing[{i}]");
            self.require(self.model.mesh.is_some(), &format!("{key}.group"), || {
                "a casing acts on the nodes of a mesh group; a model on matrix rows takes `[[obstacle]]`"
            })?;
            self.require(self.obstacle.is_empty(), &format!("{key}.group"), || {
                "give either `[[casing]]` (mesh models) or `[[obstacle]]` (matrix rows), not both"
            })?;
            self.finite(&format!("{key}.axis.origin"), &c.axis.origin)?;
            self.finite(&format!("{key}.axis.direction"), &c.axis.direction)?;
            let d = c.axis.direction;
            self.require(
                d.iter().map(|x| x * x).sum::<f64>() > 0.0,
                &format!("{key}.axis.direction"),
                || "the axis direction must not be zero",
            )?;
            match (c.radius, &c.gap) {
                (Some(r), None) => self.positive(&format!("{key}.radius"), r)?,
                (None, Some(CasingGap::Uniform(g))) => self.finite(&format!("{key}.gap"), &[*g])?,
                (None, Some(CasingGap::PerNode(g))) => {
                    for (k, v) in g.iter().enumerate() {
                        self.finite(&format!("{key}.gap[{k}]"), &[*v])?;
                    }
                }
                (Some(_), Some(_)) => {
                    return Err(self.key_error(
                        &super::parse::KeyPath::parse(&format!("{key}.gap")),
                        "give either `radius` (g0 = R − r per node) or `gap` (the same g0 at every node), not both",
                    ))
                }
                (None, None) => {
                    return Err(self.key_error(
                        &super::parse::KeyPath::parse(&key),
                        "needs `radius` (the casing radius R, m) or `gap` (the initial gap g0 of every node, or a list of one per node, m)",
                    ))
                }
            }
            self.require(
                c.gap_nodes.is_none() || matches!(c.gap, Some(CasingGap::PerNode(_))),
                &format!("{key}.gap_nodes"),
                || "`gap_nodes` names the nodes of a list `gap = [g0, ...]`; give the gaps as a list",
            )?;
            self.require(
                (0.0..=1.0).contains(&c.restitution),
                &format!("{key}.restitution"),
                || format!("must lie in [0, 1] (found {})", c.restitution),
            )?;
            self.non_negative(&format!("{key}.mu"), c.mu)?;
            if let Some(s) = c.speed_rpm {
                self.finite(&format!("{key}.speed_rpm"), &[s])?;
            }
            self.require(
                c.mu == 0.0 || c.speed_rpm.is_some_and(|s| s != 0.0),
                &format!("{key}.mu"),
                || "friction needs a non-zero `speed_rpm`: its sign sets the sliding direction",
            )?;
            self.non_negative(&format!("{key}.heating"), c.heating)?;
            self.require(
                c.heating == 0.0 || self.thermal.is_some(),
                &format!("{key}.heating"),
                || "frictional heating needs temperature DOF: add a [thermal] table (conductivity, specific_heat, expansion)",
            )?;
        }
        Ok(())
    }

    /// Checks the per-node `gap` lists of `[[casing]]` against the mesh: one value per node of
    /// the group, and with `gap_nodes` each node of the group named exactly once. Errors name the
    /// file, line and key.
    pub fn check_casing_gaps(&self, mesh: &crate::mesh::Mesh) -> Result<()> {
        for (i, c) in self.casing.iter().enumerate() {
            let Some(CasingGap::PerNode(gaps)) = &c.gap else {
                continue;
            };
            let key = format!("casing[{i}]");
            let mut tags: Vec<u64> = mesh
                .nodes_of(&c.group)?
                .iter()
                .map(|&n| mesh.node_tags[n as usize])
                .collect();
            tags.sort_unstable();
            self.require(gaps.len() == tags.len(), &format!("{key}.gap"), || {
                format!(
                    "{} gaps for the {} nodes of group '{}' (one per node, in ascending node tag order or that of `gap_nodes`)",
                    gaps.len(),
                    tags.len(),
                    c.group
                )
            })?;
            if let Some(nodes) = &c.gap_nodes {
                self.require(
                    nodes.len() == gaps.len(),
                    &format!("{key}.gap_nodes"),
                    || format!("{} node tags for {} gaps", nodes.len(), gaps.len()),
                )?;
                for (k, t) in nodes.iter().enumerate() {
                    self.require(
                        tags.binary_search(t).is_ok(),
                        &format!("{key}.gap_nodes[{k}]"),
                        || format!("node {t} is not a node of group '{}'", c.group),
                    )?;
                    self.require(
                        !nodes[..k].contains(t),
                        &format!("{key}.gap_nodes[{k}]"),
                        || format!("node {t} is listed twice"),
                    )?;
                }
            }
        }
        Ok(())
    }
}
