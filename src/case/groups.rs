//! The physical groups a case names, checked against a mesh (with the closest existing name as
//! a hint).

use super::parse::KeyPath;
use super::*;

impl Case {
    /// Every group the case names, with the key that names it, in file order.
    pub fn group_references(&self) -> Vec<(String, String)> {
        let mut refs = Vec::new();
        let mut add = |key: String, g: &str| refs.push((key, g.to_string()));
        for (i, g) in self.model.clamp.iter().enumerate() {
            add(format!("model.clamp[{i}]"), g);
        }
        for (i, m) in self.model.materials.iter().enumerate() {
            add(format!("model.materials[{i}].group"), &m.group);
        }
        if let Some(c) = &self.cyclic {
            add("cyclic.low".into(), &c.low);
            add("cyclic.high".into(), &c.high);
        }
        for (i, g) in self
            .reduction
            .iter()
            .flat_map(|r| r.keep.iter())
            .enumerate()
        {
            add(format!("reduction.keep[{i}]"), g);
        }
        for (i, c) in self.contact.iter().enumerate() {
            add(format!("contact[{i}].contact"), &c.contact);
            add(format!("contact[{i}].target"), &c.target);
        }
        if let Some(Excitation {
            load: ExcitationLoad::Group { group, .. },
            ..
        }) = &self.excitation
        {
            add("excitation.group".into(), group);
        }
        for (i, g) in self
            .response
            .iter()
            .flat_map(|r| r.groups.iter())
            .enumerate()
        {
            add(format!("response.groups[{i}]"), g);
        }
        for (i, s) in self.strip.iter().enumerate() {
            if let Some(face) = &s.face {
                add(format!("strip[{i}].face"), face);
            }
        }
        for (i, c) in self.casing.iter().enumerate() {
            add(format!("casing[{i}].group"), &c.group);
        }
        for (i, g) in self.thermal.iter().flat_map(|t| t.fixed.iter()).enumerate() {
            add(format!("thermal.fixed[{i}]"), g);
        }
        refs
    }

    /// Checks that every group the case names exists in `mesh` and has elements, and that
    /// per-group materials name volume (dim 3) groups. The error lists every problem, each with the
    /// case file, line and key, and the groups the mesh has.
    pub fn check_groups(&self, mesh: &Mesh) -> Result<()> {
        let problems: Vec<String> = self
            .group_references()
            .iter()
            .filter_map(|(key, name)| self.group_problem(mesh, key, name))
            .collect();
        if problems.is_empty() {
            return self.check_casing_gaps(mesh);
        }
        Err(Error::input(format!(
            "{}\nthe mesh {} has: {}",
            problems.join("\n"),
            mesh.source_name(),
            describe_groups(mesh)
        )))
    }

    /// What is wrong with the group `name` named at `key`, if anything.
    pub(super) fn group_problem(&self, mesh: &Mesh, key: &str, name: &str) -> Option<String> {
        let path = KeyPath::parse(key);
        let Some(g) = mesh.groups.iter().find(|g| g.name == name) else {
            let hint = closest_group(mesh, name)
                .map(|c| format!("; did you mean '{c}'?"))
                .unwrap_or_default();
            let msg = format!(
                "the mesh {} has no physical group '{name}'{hint}",
                mesh.source_name()
            );
            return Some(self.key_error(&path, msg).to_string());
        };
        if mesh.group_element_count(g) == 0 {
            let msg = format!(
                "physical group '{name}' (dim {}, tag {}) of {} has no elements",
                g.dim,
                g.tag,
                mesh.source_name()
            );
            return Some(self.key_error(&path, msg).to_string());
        }
        if key.starts_with("strip[") && key.ends_with(".face") && g.dim != 2 {
            let msg = format!(
                "a strip's face needs a surface group (dim 2) of faces on the volume, but '{name}' has dim {}",
                g.dim
            );
            return Some(self.key_error(&path, msg).to_string());
        }
        if key.starts_with("model.materials") && g.dim != 3 {
            let msg = format!(
                "a material needs a volume group (dim 3), but '{name}' has dim {}",
                g.dim
            );
            return Some(self.key_error(&path, msg).to_string());
        }
        None
    }
}

/// `name (dim D, tag T, E elements), ...` for the groups of a mesh.
pub(super) fn describe_groups(mesh: &Mesh) -> String {
    if mesh.groups.is_empty() {
        return "no physical groups; define them in Gmsh (Physical Point/Curve/Surface/Volume)"
            .into();
    }
    mesh.groups
        .iter()
        .map(|g| {
            format!(
                "'{}' (dim {}, tag {}, {} elements)",
                g.name,
                g.dim,
                g.tag,
                mesh.group_element_count(g)
            )
        })
        .collect::<Vec<_>>()
        .join(", ")
}

/// The mesh group whose name is closest to `name` (case-insensitive edit distance ≤ 2).
pub(super) fn closest_group<'a>(mesh: &'a Mesh, name: &str) -> Option<&'a str> {
    let lower = name.to_lowercase();
    mesh.groups
        .iter()
        .map(|g| {
            (
                edit_distance(&g.name.to_lowercase(), &lower),
                g.name.as_str(),
            )
        })
        .filter(|(d, _)| *d <= 2)
        .min_by_key(|(d, _)| *d)
        .map(|(_, n)| n)
}

/// Levenshtein distance between two strings (by chars).
pub(super) fn edit_distance(a: &str, b: &str) -> usize {
    let b: Vec<char> = b.chars().collect();
    let mut prev: Vec<usize> = (0..=b.len()).collect();
    for (i, ca) in a.chars().enumerate() {
        let mut cur = vec![i + 1; b.len() + 1];
        for (j, cb) in b.iter().enumerate() {
            let sub = prev[j] + usize::from(ca != *cb);
            cur[j + 1] = sub.min(prev[j + 1] + 1).min(cur[j] + 1);
        }
        prev = cur;
    }
    prev[b.len()]
}
