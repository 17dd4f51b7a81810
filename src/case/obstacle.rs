//! `[[obstacle]]` tables: rigid obstacles with unilateral (Signorini) contact on weighted
//! combinations of matrix rows, marched by `nlrom march --scheme moreau-jean` or `carpenter`
//! (`docs/theory.md`, nonsmooth contact).

use serde::Deserialize;

use super::{Case, WeightedDofs};
use crate::error::Result;

/// `[[obstacle]]`: a rigid obstacle. The gap is g = `gap` + Σ normal.weights·q\[normal.dofs\] ≥ 0
/// (m); the contact force λ ≥ 0 acts along the same weights, the friction force μλ along
/// `sliding` (a fixed sliding direction).
#[derive(Clone, Debug, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObstacleTable {
    /// Name in the results; default `obstacle[i]`.
    #[serde(default)]
    pub name: Option<String>,
    /// The gap's linear part: matrix rows and weights (dimensionless).
    pub normal: WeightedDofs,
    /// The gap g0 at zero displacement (m); default 0.
    #[serde(default)]
    pub gap: f64,
    /// Newton restitution coefficient e ∈ [0, 1]: ẏ⁺ = −e ẏ⁻ at an impact; default 0.
    #[serde(default)]
    pub restitution: f64,
    /// Coulomb friction coefficient μ ≥ 0; default 0 (needs `sliding` when > 0).
    #[serde(default)]
    pub mu: f64,
    /// The direction of the friction force per unit μλ (matrix rows and weights).
    #[serde(default)]
    pub sliding: Option<WeightedDofs>,
}

impl ObstacleTable {
    /// The obstacle's name: `name`, else `obstacle[i]`.
    pub fn label(&self, i: usize) -> String {
        self.name
            .clone()
            .unwrap_or_else(|| format!("obstacle[{i}]"))
    }
}

impl Case {
    /// Checks every `[[obstacle]]`: weights per row, finite gap, e ∈ [0, 1], μ ≥ 0 with a
    /// sliding direction.
    pub(super) fn validate_obstacles(&self) -> Result<()> {
        for (i, o) in self.obstacle.iter().enumerate() {
            let key = format!("obstacle[{i}]");
            let combination = |k: &str, w: &WeightedDofs| -> Result<()> {
                self.require(!w.dofs.is_empty(), &format!("{key}.{k}.dofs"), || {
                    "needs at least one matrix row"
                })?;
                self.require(
                    w.dofs.len() == w.weights.len(),
                    &format!("{key}.{k}.weights"),
                    || {
                        format!(
                            "needs one weight per row ({} rows, {} weights)",
                            w.dofs.len(),
                            w.weights.len()
                        )
                    },
                )?;
                self.finite(&format!("{key}.{k}.weights"), &w.weights)
            };
            combination("normal", &o.normal)?;
            self.finite(&format!("{key}.gap"), &[o.gap])?;
            self.require(
                (0.0..=1.0).contains(&o.restitution),
                &format!("{key}.restitution"),
                || format!("must lie in [0, 1] (found {})", o.restitution),
            )?;
            self.non_negative(&format!("{key}.mu"), o.mu)?;
            match &o.sliding {
                Some(s) => combination("sliding", s)?,
                None => self.require(o.mu == 0.0, &format!("{key}.mu"), || {
                    "friction needs `sliding = { dofs = [...], weights = [...] }`, the direction of the friction force"
                })?,
            }
        }
        Ok(())
    }
}
