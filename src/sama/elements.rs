//! The pairs of an interface as node-to-node friction elements of the harmonic balance
//! ([`crate::contact::pairs::ContactPair`]): one element per c–t_j with the weighted parameters
//! of eq 31 (SAMA paper, Fig. 7a: the parallel array of node-to-node elements).

use crate::contact::law::ContactParams;
use crate::contact::pairs::ContactPair as Element;
use crate::error::{Error, Result};

use super::ContactInterface;

impl ContactInterface {
    /// One friction element per pair c–t_j: rows of c and t_j from `rows(node_tag)` (the x, y, z
    /// rows of a node in the DOF vector of the contact set, e.g. a ROM's physical master rows),
    /// the pair's frame and σ, parameters (k_tj, k_nj, μ, n0_j) of eq 31, and
    /// preload_rate = ∂n0_j/∂n0 = w_j · n0_c/n0 (the rate per unit of the interface's total
    /// preload n0, the parameter swept as `contact.<name>.n0`).
    ///
    /// Errors ([`Error::Input`]): a contact or target node without rows (not a master node),
    /// invalid parameters.
    pub fn elements(&self, rows: impl Fn(u64) -> Option<[usize; 3]>) -> Result<Vec<Element>> {
        let node_rows = |tag: u64, role: &str| {
            rows(tag).ok_or_else(|| {
                Error::input(format!(
                    "contact '{}': {role} node {tag} has no DOF rows in the contact DOF vector; keep the contact and target groups as master nodes of the reduction",
                    self.name
                ))
            })
        };
        let mut out = Vec::new();
        for p in &self.pairs {
            let contact = node_rows(p.contact_node, "contact")?;
            for (j, &t) in p.targets.iter().enumerate() {
                let context = format!("contact '{}', pair {}–{}", self.name, p.contact_node, t);
                out.push(Element {
                    contact,
                    target: Some(node_rows(t, "target")?),
                    frame: p.frame,
                    sigma: self.sigma,
                    params: ContactParams::new(p.kt[j], p.kn[j], self.mu, p.n0[j], &context)?,
                    preload_rate: p.weights[j] * p.preload_share,
                });
            }
        }
        Ok(out)
    }
}
