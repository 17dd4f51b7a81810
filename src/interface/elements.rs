//! The pairs of an interface as node-to-node friction elements of the harmonic balance
//! ([`crate::contact::pairs::PairElement`]): with the array coupling one element per c–t_j with
//! the weighted parameters of eq 31 (SAMA paper, Fig. 7a: the parallel array of node-to-node
//! elements); with the interpolated coupling one element per contact node on a virtual node
//! (Fig. 8), whose rows are combinations Σ_j N_j u_tj of the target nodes' rows.

use crate::case::SamaCoupling;
use crate::contact::law::ContactParams;
use crate::contact::pairs::PairElement;
use crate::error::{Error, Result};

use super::{ContactInterface, ContactPair};

/// The virtual nodes of interpolated couplings: rows appended after the physical DOF rows.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct VirtualNodes {
    /// Row of the first virtual DOF (= the number of physical DOF rows).
    pub first_row: usize,
    /// Per virtual DOF row (x, y, z of each virtual node in turn): (physical row, N_j).
    pub rows: Vec<Vec<(usize, f64)>>,
}

impl VirtualNodes {
    /// No virtual node yet; virtual rows start at `first_row`.
    pub fn new(first_row: usize) -> VirtualNodes {
        VirtualNodes {
            first_row,
            rows: Vec::new(),
        }
    }

    /// Adds the node Σ_j w_j u_tj (`targets`: rows of each t_j) and returns its three rows.
    fn add(&mut self, targets: &[([usize; 3], f64)]) -> [usize; 3] {
        let first = self.first_row + self.rows.len();
        for c in 0..3 {
            self.rows
                .push(targets.iter().map(|(rows, w)| (rows[c], *w)).collect());
        }
        [first, first + 1, first + 2]
    }
}

impl ContactInterface {
    /// One friction element per pair c–t_j: rows of c and t_j from `rows(node_tag)` (the x, y, z
    /// rows of a node in the DOF vector of the contact set, e.g. a ROM's physical master rows),
    /// the pair's frame and σ, parameters (k_tj, k_nj, μ, n0_j) of eq 31, and
    /// preload_rate = ∂n0_j/∂n0 = w_j · n0_c/n0 (the rate per unit of the interface's total
    /// preload n0, the parameter swept as `contact.<name>.n0`).
    ///
    /// Errors ([`Error::Input`]): a contact or target node without rows (not a master node),
    /// invalid parameters.
    /// With `coupling = "interpolated"` a contact node with several targets needs a virtual node:
    /// use [`ContactInterface::elements_with`]; here that is an error.
    pub fn elements(&self, rows: impl Fn(u64) -> Option<[usize; 3]>) -> Result<Vec<PairElement>> {
        let mut virtuals = VirtualNodes::new(usize::MAX);
        let elements = self.elements_with(rows, &mut virtuals)?;
        if !virtuals.rows.is_empty() {
            return Err(Error::input(format!(
                "contact '{}': the interpolated coupling needs virtual-node rows (elements_with)",
                self.name
            )));
        }
        Ok(elements)
    }

    /// Number of friction elements [`ContactInterface::elements_with`] makes: Σ n_T over the
    /// pairs for the array, one per contact node for the interpolated coupling.
    pub fn element_count(&self) -> usize {
        self.pairs.iter().map(|p| self.elements_of(p)).sum()
    }

    fn elements_of(&self, p: &ContactPair) -> usize {
        match self.coupling {
            SamaCoupling::Interpolated => 1,
            SamaCoupling::Array => p.targets.len(),
        }
    }

    /// As [`ContactInterface::elements`]; a contact node of the interpolated coupling with
    /// several targets becomes one element with the contact node's parameters (k_t, k_n, μ,
    /// n0_c; preload rate n0_c/n0) on a virtual node appended to `virtuals` (rows Σ_j N_j u_tj).
    pub fn elements_with(
        &self,
        rows: impl Fn(u64) -> Option<[usize; 3]>,
        virtuals: &mut VirtualNodes,
    ) -> Result<Vec<PairElement>> {
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
            if self.coupling == SamaCoupling::Interpolated && p.targets.len() > 1 {
                let targets = p
                    .targets
                    .iter()
                    .zip(&p.weights)
                    .map(|(&t, &w)| Ok((node_rows(t, "target")?, w)))
                    .collect::<Result<Vec<_>>>()?;
                let context = format!(
                    "contact '{}', node {} (interpolated)",
                    self.name, p.contact_node
                );
                let (kt, kn) = (p.kt.iter().sum(), p.kn.iter().sum());
                out.push(PairElement {
                    contact,
                    target: Some(virtuals.add(&targets)),
                    frame: p.frame,
                    sigma: self.sigma,
                    params: ContactParams::new(kt, kn, self.mu, p.n0_node, &context)?,
                    preload_rate: p.preload_share,
                });
                continue;
            }
            for (j, &t) in p.targets.iter().enumerate() {
                let context = format!("contact '{}', pair {}–{}", self.name, p.contact_node, t);
                out.push(PairElement {
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
