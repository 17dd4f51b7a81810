//! Isotropic linear elastic materials and their assignment to volume groups.

use crate::error::{Error, Result};
use crate::mesh::{ElementBlock, Mesh};

pub use crate::case::Material;

/// Hooke's law σ = λ tr(ε) I + 2μ ε of an isotropic linear elastic [`Material`] (the case
/// schema's `material` table).
impl Material {
    /// Checks E > 0, −1 < ν < 0.5 and ρ > 0 (all finite). `what` names the material in the message
    /// (e.g. `material of volume group 'blade'`).
    pub fn validate(&self, what: &str) -> Result<()> {
        let bad = |msg: String| Err(Error::input(format!("{what}: {msg}")));
        if !(self.young.is_finite() && self.young > 0.0) {
            return bad(format!(
                "Young's modulus young = {} Pa must be positive and finite",
                self.young
            ));
        }
        if !(self.poisson > -1.0 && self.poisson < 0.5) {
            return bad(format!(
                "Poisson's ratio poisson = {} must satisfy −1 < ν < 0.5 (ν = 0.5 is incompressible, which displacement elements cannot represent; use e.g. 0.499 or a mixed formulation)",
                self.poisson
            ));
        }
        if !(self.density.is_finite() && self.density > 0.0) {
            return bad(format!(
                "density = {} kg/m³ must be positive and finite",
                self.density
            ));
        }
        Ok(())
    }

    /// Lamé constants (λ, μ) in Pa: λ = Eν/((1+ν)(1−2ν)), μ = E/(2(1+ν)).
    pub fn lame(&self) -> (f64, f64) {
        let (e, nu) = (self.young, self.poisson);
        (
            e * nu / ((1.0 + nu) * (1.0 - 2.0 * nu)),
            e / (2.0 * (1.0 + nu)),
        )
    }

    /// The 6×6 elasticity matrix D (Pa) in Voigt order (xx, yy, zz, yz, xz, xy) with engineering
    /// shear strains: σ = D ε. The element kernels use the equivalent Lamé form.
    pub fn elasticity_matrix(&self) -> [[f64; 6]; 6] {
        let (l, m) = self.lame();
        let mut d = [[0.0; 6]; 6];
        for (i, row) in d.iter_mut().enumerate().take(3) {
            row[..3].fill(l);
            row[i] = l + 2.0 * m;
        }
        for (i, row) in d.iter_mut().enumerate().skip(3) {
            row[i] = m;
        }
        d
    }
}

/// The materials of a model: per volume (dimension-3) physical group, and a default for the volume
/// elements of no listed group.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Materials {
    /// Material of every volume element whose groups are not listed in `by_group`.
    pub default: Option<Material>,
    /// (volume group name, material), overriding `default` on that group.
    pub by_group: Vec<(String, Material)>,
}

impl Materials {
    /// One material everywhere.
    pub fn uniform(material: Material) -> Self {
        Materials {
            default: Some(material),
            by_group: Vec::new(),
        }
    }

    /// The materials of a case file's `[model]` (`material` and `materials`).
    pub fn from_case(model: &crate::case::Model) -> Self {
        Materials {
            default: model.material,
            by_group: model
                .materials
                .iter()
                .map(|g| (g.group.clone(), g.material()))
                .collect(),
        }
    }

    /// Validates every material and checks that every listed group exists in `mesh` with
    /// dimension 3.
    pub fn validate(&self, mesh: &Mesh) -> Result<()> {
        if let Some(m) = &self.default {
            m.validate("default material ([model] material)")?;
        }
        for (name, m) in &self.by_group {
            m.validate(&format!(
                "material of volume group '{name}' ([model] materials)"
            ))?;
            let g = mesh.group(name)?;
            if g.dim != 3 {
                return Err(Error::input(format!(
                    "{}: material given for group '{name}', which has dimension {}; materials apply to volume groups (dimension 3)",
                    mesh.source_name(),
                    g.dim
                )));
            }
        }
        Ok(())
    }

    /// The material of the elements of `block` (a volume block): that of its listed group, else the
    /// default. Errors name the entity and groups when there is none, or when two of its groups are
    /// listed with different materials.
    pub fn for_block(&self, mesh: &Mesh, block: &ElementBlock) -> Result<Material> {
        let names = block_group_names(mesh, block);
        let listed: Vec<(&str, &Material)> = self
            .by_group
            .iter()
            .filter(|(n, _)| names.iter().any(|g| g == n))
            .map(|(n, m)| (n.as_str(), m))
            .collect();
        match listed.as_slice() {
            [] => self.default.ok_or_else(|| {
                Error::input(format!(
                    "{}: the {} elements of volume entity {} ({}) have no material: no material is given for their groups and there is no default material; add `material = {{ young, poisson, density }}` or a `materials` entry for {}",
                    mesh.source_name(),
                    block.kind,
                    block.entity,
                    describe_groups(&names),
                    names.first().map(|n| format!("group '{n}'")).unwrap_or_else(|| "a physical volume group containing them".into())
                ))
            }),
            [(_, m), rest @ ..] => {
                if let Some((other, _)) = rest.iter().find(|(_, o)| *o != *m) {
                    return Err(Error::input(format!(
                        "{}: volume entity {} belongs to groups '{}' and '{other}', which are given different materials; give the entity one material",
                        mesh.source_name(),
                        block.entity,
                        listed[0].0
                    )));
                }
                Ok(**m)
            }
        }
    }
}

/// Names of the physical groups (dimension 3) the elements of `block` belong to.
pub(crate) fn block_group_names(mesh: &Mesh, block: &ElementBlock) -> Vec<String> {
    mesh.groups
        .iter()
        .filter(|g| g.dim == block.kind.dim() && block.physicals.contains(&g.tag))
        .map(|g| g.name.clone())
        .collect()
}

/// "groups 'a', 'b'" or "in no physical group".
pub(crate) fn describe_groups(names: &[String]) -> String {
    if names.is_empty() {
        "in no physical group".to_string()
    } else {
        let quoted: Vec<String> = names.iter().map(|n| format!("'{n}'")).collect();
        format!("group {}", quoted.join(", "))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lame_constants_of_steel() {
        // E = 210 GPa, ν = 0.3: λ = 121.15 GPa, μ = 80.77 GPa (to 4 digits, hand computed).
        let m = Material {
            young: 210e9,
            poisson: 0.3,
            density: 7800.0,
        };
        let (l, mu) = m.lame();
        assert!((l - 210e9 * 0.3 / (1.3 * 0.4)).abs() < 1e-3);
        assert!((mu - 210e9 / 2.6).abs() < 1e-3);
        assert!((l / 1e9 - 121.1538).abs() < 1e-4);
        // D has E(1−ν)/((1+ν)(1−2ν)) on the normal diagonal.
        let d = m.elasticity_matrix();
        let c11 = 210e9 * 0.7 / (1.3 * 0.4);
        assert!((d[0][0] - c11).abs() < 1e-3 && (d[5][5] - mu).abs() < 1e-3 && d[0][3] == 0.0);
    }

    #[test]
    fn validation_names_the_material_and_the_key() {
        let ok = Material {
            young: 1.0,
            poisson: 0.3,
            density: 1.0,
        };
        assert!(ok.validate("x").is_ok());
        for (m, key) in [
            (Material { poisson: 0.5, ..ok }, "poisson = 0.5"),
            (
                Material {
                    poisson: -1.0,
                    ..ok
                },
                "poisson = -1",
            ),
            (Material { young: 0.0, ..ok }, "young = 0"),
            (
                Material {
                    density: f64::NAN,
                    ..ok
                },
                "density = NaN",
            ),
        ] {
            let e = m.validate("material of volume group 'blade'").unwrap_err();
            let s = e.to_string();
            assert!(s.contains("'blade'") && s.contains(key), "{s}");
            assert_eq!(e.exit_code(), 2);
        }
    }
}
