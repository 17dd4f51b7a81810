//! A set of node-to-node contact pairs acting on a vector of physical DOFs, as one
//! [`HarmonicForce`] (SAMA paper, Battiato 2021: node-to-node elements §3 eqs 13–14, 25–27;
//! weighted pairs eqs 31–32; cyclic-symmetry relative displacement eq. 33).
//!
//! Each [`PairElement`] joins a contact node c (3 rows of the DOF vector, x y z) to a target node
//! t (3 rows) or to the ground, with a local frame (t1, t2, n) in the global axes, the
//! inter-sector rotation σ ∈ {−1, 0, 1} and its own contact parameters (SAMA's weighted k_t, k_n,
//! n0). The local relative motion is (u1, u2, v) = (t1·r, t2·r, −n·r) with
//! r = u_c − e^{iσφ_{k_n}} R_α^σ u_t per harmonic ([`super::kinematics`]); the element forces
//! return to the nodes through the transpose, and the Jacobian is Lᵀ J_local L (eq. 26 with the
//! kinematic map L in place of eq. 27's R).
//!
//! Pairs are evaluated in parallel and summed by the private `assembly` module (the result does not
//! depend on the number of threads).

use std::sync::Arc;

use faer::MatMut;

use crate::case::Evaluation;
use crate::contact::aft::{check_finite, gather, global_index, Aft, AftCache};
use crate::contact::assembly::{assemble, Outputs, Slot, SlotStorage, Wanted};
use crate::contact::element::{
    evaluate_as, ElementReport, HysteresisLoop, LocalElement, Workspace,
};
use crate::contact::kinematics::{
    check_frame, node_jacobian, relative_local, relative_transpose, Phases,
};
use crate::contact::law::{ContactParams, Variant};
use crate::contact::mapped::{element_to_outer, LinearMap};
use crate::error::{Error, Result};
use crate::harmonics::{HarmonicForce, HarmonicLayout, JacobianMut};
use crate::vec3::{mat_mul, transpose, Mat3};

/// One contact pair.
#[derive(Clone, Debug, PartialEq)]
pub struct PairElement {
    /// Rows (0-based, in the DOF vector of the set) of the contact node's x, y, z displacement.
    pub contact: [usize; 3],
    /// Rows of the target node's x, y, z displacement; `None`: the target is the ground.
    pub target: Option<[usize; 3]>,
    /// Local frame, rows t1, t2, n (unit vectors in the global axes; n points from the target
    /// towards the contact body, `docs/conventions.md` §3).
    pub frame: Mat3,
    /// Inter-sector rotation of the target: σ ∈ {−1, 0, 1} (0: same sector).
    pub sigma: i32,
    /// Contact parameters of this pair (SAMA: already multiplied by the pair's weight, eq. 31).
    pub params: ContactParams,
    /// ∂n0/∂p: rate of this pair's preload per unit of the parameter of
    /// [`HarmonicForce::parameter_derivative`] (SAMA: the weight w_j, so p is the contact's
    /// total preload; 1 for an unweighted pair).
    pub preload_rate: f64,
}

/// Cyclic symmetry data for pairs with σ ≠ 0 (`docs/conventions.md` §2).
#[derive(Clone, Debug, PartialEq)]
pub struct SectorCoupling {
    /// Number of sectors N.
    pub sectors: usize,
    /// R_α, the rotation by +α = 2π/N about the axis (e.g. `CyclicGeometry::rotation(1)`).
    pub rotation: Mat3,
    /// Harmonic index k_n of each temporal harmonic n = 0..=H (at least H+1 entries; k_0 = 0).
    pub harmonic_indices: Vec<usize>,
}

/// Slider states (w1, w2) (m) of every pair at the start of the period.
pub type PairState = Vec<[f64; 2]>;

/// Pairs with precomputed signed frames.
#[derive(Clone, Debug)]
struct Prepared {
    /// P = [t1; t2; −n]: local (u1, u2, v) = P r.
    frame: Mat3,
    /// P R^σ.
    target_frame: Mat3,
}

/// A set of contact pairs as one nonlinear force (see the module documentation).
pub struct PairSet {
    n_dofs: usize,
    variant: Variant,
    pairs: Vec<PairElement>,
    prepared: Vec<Prepared>,
    coupling: Option<SectorCoupling>,
    /// Rows of the pairs are inner DOFs y = B x of this map (x: the DOFs the force acts on).
    map: Option<LinearMap>,
    /// Most DOFs of one pair's node-space results: 6, or through the map the most outer DOFs a
    /// pair reads.
    slot_dofs: usize,
    aft: AftCache,
    slots: SlotStorage,
    /// How each pair is evaluated (empty: all by the AFT).
    evaluations: Vec<Evaluation>,
}

impl std::fmt::Debug for PairSet {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("PairSet")
            .field("n_dofs", &self.n_dofs)
            .field("variant", &self.variant)
            .field("pairs", &self.pairs.len())
            .finish()
    }
}

/// The inputs shared by all pairs of one evaluation.
#[derive(Clone, Copy)]
struct Inputs<'a> {
    aft: &'a Aft,
    /// Phases for σ = −1, 0, 1.
    phases: &'a [Phases; 3],
    layout: &'a HarmonicLayout,
    q: &'a [f64],
}

/// Buffers of one thread.
struct Buffers {
    ws: Workspace,
    q: Vec<f64>,
    x: Vec<f64>,
    g: Vec<f64>,
    jl: Vec<f64>,
    col: Vec<f64>,
    /// Through the map: the pair's inner rows, outer DOFs, local B_e, the inner Jacobian and
    /// scratch.
    inner: Vec<usize>,
    outer: Vec<usize>,
    b_e: Vec<f64>,
    jy: Vec<f64>,
    work: Vec<f64>,
}

impl PairSet {
    /// Checks the pairs (rows < `n_dofs`, orthonormal right-handed frames, valid parameters,
    /// σ ∈ {−1, 0, 1} with a coupling when σ ≠ 0) and prepares them.
    pub fn new(
        n_dofs: usize,
        variant: Variant,
        pairs: Vec<PairElement>,
        coupling: Option<SectorCoupling>,
    ) -> Result<Self> {
        let mut prepared = Vec::with_capacity(pairs.len());
        for (i, p) in pairs.iter().enumerate() {
            let context = format!("contact pair {i}");
            p.params.validate(&context)?;
            check_frame(&p.frame, &context)?;
            let rows = p.contact.iter().chain(p.target.iter().flatten());
            if let Some(r) = rows.into_iter().find(|&&r| r >= n_dofs) {
                return Err(Error::input(format!(
                    "{context}: DOF row {r} is out of range (the contact DOF vector has {n_dofs} rows)"
                )));
            }
            if !(-1..=1).contains(&p.sigma) || (p.sigma != 0 && coupling.is_none()) {
                return Err(Error::input(format!(
                    "{context}: σ = {} needs σ ∈ {{−1, 0, 1}} and, when σ ≠ 0, the cyclic-symmetry coupling (sectors, R_α, harmonic indices)",
                    p.sigma
                )));
            }
            if !p.preload_rate.is_finite() {
                return Err(Error::input(format!(
                    "{context}: preload rate {} is not finite",
                    p.preload_rate
                )));
            }
            let f = p.frame;
            let frame = [f[0], f[1], [-f[2][0], -f[2][1], -f[2][2]]];
            let rot = match (p.sigma, &coupling) {
                (0, _) | (_, None) => [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
                (1, Some(c)) => c.rotation,
                (_, Some(c)) => transpose(&c.rotation),
            };
            prepared.push(Prepared {
                frame,
                target_frame: mat_mul(&frame, &rot),
            });
        }
        Ok(PairSet {
            n_dofs,
            variant,
            pairs,
            prepared,
            coupling,
            map: None,
            slot_dofs: 6,
            aft: AftCache::default(),
            slots: SlotStorage::default(),
            evaluations: Vec::new(),
        })
    }

    /// Sets how each pair's friction element is evaluated (one entry per pair, in order; the
    /// default is [`Evaluation::Aft`] for all). `analytic` (the exact single-harmonic cycle of
    /// [`crate::contact::microslip`]) needs the 1-D variant, checked here, and H = 1, checked at
    /// evaluation.
    pub fn with_evaluations(mut self, evaluations: Vec<Evaluation>) -> Result<Self> {
        if evaluations.len() != self.pairs.len() {
            return Err(Error::Compute(format!(
                "contact pairs: {} evaluation choices for {} pairs",
                evaluations.len(),
                self.pairs.len()
            )));
        }
        if self.variant != Variant::OneD && evaluations.contains(&Evaluation::Analytic) {
            return Err(Error::input(
                "evaluation = \"analytic\" is the exact cycle of the 1-D friction law; the 2-D (Coulomb disc) element is evaluated by the AFT only",
            ));
        }
        self.evaluations = evaluations;
        Ok(self)
    }

    /// The same pairs reading inner DOFs y = B x ([`LinearMap`]): the rows given to [`PairSet::new`]
    /// (its `n_dofs`) are rows of y, and the set acts on x (`map.outer()` DOFs) with forces Bᵀ F_y
    /// and Jacobian Bᵀ J_y B. Error ([`Error::Input`]) when the map's inner size is not `n_dofs`.
    pub fn with_map(mut self, map: LinearMap) -> Result<Self> {
        if map.inner() != self.n_dofs {
            return Err(Error::input(format!(
                "contact pairs: the DOF map gives {} inner DOFs, the pairs use {}",
                map.inner(),
                self.n_dofs
            )));
        }
        self.slot_dofs = map
            .max_outer((0..self.pairs.len()).map(|i| self.inner_rows(i)))
            .max(6);
        self.map = Some(map);
        Ok(self)
    }

    /// The pairs.
    pub fn pairs(&self) -> &[PairElement] {
        &self.pairs
    }

    /// Per-pair state over the period (fractions, dissipated energy) and, if `loops`, the
    /// hysteresis samples, for the harmonics `q` from the starting state `state` (not changed).
    pub fn reports(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &PairState,
        loops: bool,
    ) -> Result<Vec<(ElementReport, Option<HysteresisLoop>)>> {
        let mapped = self.map.as_ref().map(|map| map.forward(layout, q));
        let q = mapped.as_deref().unwrap_or(q);
        let (aft, phases) = self.prepare(layout, q, state)?;
        let m = layout.coefficients();
        let mut out = Vec::with_capacity(self.pairs.len());
        let mut b = buffers(&aft, m);
        let input = Inputs {
            aft: &aft,
            phases: &phases,
            layout,
            q,
        };
        for (i, slider) in state.iter().enumerate() {
            let mut s = *slider;
            self.evaluate_pair(i, &input, &mut s, false, false, &mut b)?;
            out.push((b.ws.report(), loops.then(|| b.ws.hysteresis())));
        }
        Ok(out)
    }

    /// The shared AFT plan for `layout`, the phases per σ, and input checks.
    fn prepare(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &PairState,
    ) -> Result<(Arc<Aft>, [Phases; 3])> {
        if q.len() != layout.len(self.n_dofs) || state.len() != self.pairs.len() {
            return Err(Error::Compute(format!(
                "contact pairs: harmonic vector of length {} and {} slider states for {} DOFs × {} coefficients and {} pairs",
                q.len(),
                state.len(),
                self.n_dofs,
                layout.coefficients(),
                self.pairs.len()
            )));
        }
        check_finite(q, "contact pairs")?;
        let aft = self.aft.get(layout)?;
        let h = layout.harmonics;
        let phases = match &self.coupling {
            None => [Phases::zero(h), Phases::zero(h), Phases::zero(h)],
            Some(c) => {
                if c.harmonic_indices.len() < h + 1 {
                    return Err(Error::input(format!(
                        "contact pairs: {} harmonic indices given for H = {h} harmonics (need k_0..k_H)",
                        c.harmonic_indices.len()
                    )));
                }
                let k = &c.harmonic_indices[..=h];
                [
                    Phases::cyclic(-1, k, c.sectors)?,
                    Phases::zero(h),
                    Phases::cyclic(1, k, c.sectors)?,
                ]
            }
        };
        Ok((aft, phases))
    }

    /// Evaluates pair `i`: local element on the relative harmonics; leaves the node forces in
    /// `b.q` ([contact; target], 3m each) and, with `jacobian`, the local Jacobian in `b.ws`.
    fn evaluate_pair(
        &self,
        i: usize,
        input: &Inputs<'_>,
        slider: &mut [f64; 2],
        jacobian: bool,
        forces: bool,
        b: &mut Buffers,
    ) -> Result<()> {
        let Inputs {
            aft,
            phases,
            layout,
            q,
        } = *input;
        let pair = &self.pairs[i];
        let prep = &self.prepared[i];
        let m = layout.coefficients();
        let ph = &phases[(pair.sigma + 1) as usize];
        for (c, &row) in pair.contact.iter().enumerate() {
            gather(layout, q, row, self.n_dofs, &mut b.q[c * m..(c + 1) * m]);
        }
        if let Some(t) = pair.target {
            for (c, &row) in t.iter().enumerate() {
                gather(
                    layout,
                    q,
                    row,
                    self.n_dofs,
                    &mut b.q[(3 + c) * m..(4 + c) * m],
                );
            }
        }
        let (qc, qt) = b.q.split_at(3 * m);
        relative_local(
            &prep.frame,
            &prep.target_frame,
            ph,
            qc,
            pair.target.map(|_| qt),
            &mut b.x,
        );
        let element = LocalElement {
            params: pair.params,
            variant: self.variant,
            tangential: 2,
            normal: true,
        };
        evaluate_as(
            self.evaluations.get(i).copied().unwrap_or_default(),
            &element,
            aft,
            &b.x,
            slider,
            &mut b.g,
            jacobian,
            &mut b.ws,
        )?;
        if forces {
            let (fc, ft) = b.q.split_at_mut(3 * m);
            relative_transpose(
                &prep.frame,
                &prep.target_frame,
                ph,
                &b.g,
                fc,
                pair.target.map(|_| ft),
            );
        }
        Ok(())
    }

    /// Node-space results of pair `i` into `slot`: forces, ∂/∂n0 (times the preload rate) and
    /// the Jacobian Lᵀ J L (column-major), as asked by `wanted`; through the DOF map, on the
    /// outer DOFs the pair reads (B_eᵀ F, B_eᵀ J B_e with the pair's local part of B).
    fn pair_slot(
        &self,
        i: usize,
        input: &Inputs<'_>,
        slider: &mut [f64; 2],
        wanted: Wanted,
        b: &mut Buffers,
        slot: Slot<'_>,
    ) -> Result<()> {
        let local_jacobian = wanted.jacobian || wanted.dn0;
        self.evaluate_pair(i, input, slider, local_jacobian, true, b)?;
        let pair = &self.pairs[i];
        let prep = &self.prepared[i];
        let ph = &input.phases[(pair.sigma + 1) as usize];
        let layout = input.layout;
        let m = layout.coefficients();
        let sides = if pair.target.is_some() { 2 } else { 1 };
        let np = 3 * m * sides;
        let mapped = self.map.as_ref().map(|map| {
            b.inner = self.inner_rows(i);
            map.local(&b.inner, &mut b.outer, &mut b.b_e);
            (map.outer(), b.outer.len())
        });
        let n_out = match mapped {
            None => {
                for (p, g) in slot.index[..np].iter_mut().enumerate() {
                    *g = global_index(layout, p % m, self.node_row(i, p, m), self.n_dofs);
                }
                *slot.len = np;
                slot.force[..np].copy_from_slice(&b.q[..np]);
                np
            }
            Some((outer, n_outer)) => {
                let po = n_outer * m;
                for (q, g) in slot.index[..po].iter_mut().enumerate() {
                    *g = global_index(layout, q % m, b.outer[q / m], outer);
                }
                *slot.len = po;
                let dims = (3 * sides, n_outer, m);
                element_to_outer(
                    &b.b_e,
                    dims,
                    &mut [(&b.q[..np], &mut slot.force[..po])],
                    None,
                    &mut b.work,
                );
                po
            }
        };
        if !local_jacobian {
            return Ok(());
        }
        let nl = 3 * m;
        let (jac, cols) = b.ws.jacobian();
        if wanted.dn0 {
            // Local ∂F/∂n0 (last column) to the nodes.
            for (r, c) in b.col.iter_mut().enumerate() {
                *c = pair.preload_rate * jac[r * cols + nl];
            }
            let (fc, ft) = b.q.split_at_mut(3 * m);
            relative_transpose(
                &prep.frame,
                &prep.target_frame,
                ph,
                &b.col,
                fc,
                pair.target.map(|_| ft),
            );
            if mapped.is_some() {
                element_to_outer(
                    &b.b_e,
                    (3 * sides, b.outer.len(), m),
                    &mut [(&b.q[..np], &mut slot.dn0[..n_out])],
                    None,
                    &mut b.work,
                );
            } else {
                slot.dn0[..np].copy_from_slice(&b.q[..np]);
            }
        }
        if !wanted.jacobian {
            return Ok(());
        }
        let target = pair.target.is_some();
        if mapped.is_none() {
            node_jacobian(
                &prep.frame,
                &prep.target_frame,
                ph,
                jac,
                cols,
                m,
                target,
                &mut b.jl,
                &mut slot.jacobian[..np * np],
            );
            return Ok(());
        }
        b.jy.resize(np * np, 0.0);
        node_jacobian(
            &prep.frame,
            &prep.target_frame,
            ph,
            jac,
            cols,
            m,
            target,
            &mut b.jl,
            &mut b.jy[..np * np],
        );
        element_to_outer(
            &b.b_e,
            (3 * sides, b.outer.len(), m),
            &mut [],
            Some((&b.jy[..np * np], &mut slot.jacobian[..n_out * n_out])),
            &mut b.work,
        );
        Ok(())
    }

    /// The rows (in the pairs' own DOF vector) of pair `i`: contact x y z, then target x y z.
    fn inner_rows(&self, i: usize) -> Vec<usize> {
        let pair = &self.pairs[i];
        pair.contact
            .iter()
            .chain(pair.target.iter().flatten())
            .copied()
            .collect()
    }

    /// Row in the DOF vector of node-space index `p` (side, component, coefficient) of pair `i`.
    fn node_row(&self, i: usize, p: usize, m: usize) -> usize {
        let pair = &self.pairs[i];
        let side = p / (3 * m);
        let comp = (p % (3 * m)) / m;
        if side == 0 {
            pair.contact[comp]
        } else {
            pair.target.expect("target side exists")[comp]
        }
    }

    /// Evaluates every pair into the outputs, through the DOF map when there is one.
    fn run(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &mut PairState,
        outputs: Outputs<'_>,
    ) -> Result<()> {
        let Some(map) = &self.map else {
            return self.run_inner(layout, q, state, outputs);
        };
        if q.len() != layout.len(map.outer()) {
            return Err(Error::Compute(format!(
                "contact pairs: harmonic vector of length {} for {} DOFs × {} coefficients",
                q.len(),
                map.outer(),
                layout.coefficients()
            )));
        }
        // the pairs read y = B x; each pair's results go to the outer DOFs it reads
        // (`pair_slot`), so the outputs are summed on x directly
        let y = map.forward(layout, q);
        self.run_inner(layout, &y, state, outputs)
    }

    /// Evaluates every pair in parallel on the pairs' own DOF vector and sums into the outputs.
    fn run_inner(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &mut PairState,
        outputs: Outputs<'_>,
    ) -> Result<()> {
        let (aft, phases) = self.prepare(layout, q, state)?;
        let m = layout.coefficients();
        let input = Inputs {
            aft: &aft,
            phases: &phases,
            layout,
            q,
        };
        assemble(
            state,
            self.slot_dofs * m,
            outputs,
            &self.slots,
            || buffers(&aft, m),
            |i, slider, b, wanted, slot| self.pair_slot(i, &input, slider, wanted, b, slot),
        )
    }
}

fn buffers(aft: &Aft, m: usize) -> Buffers {
    Buffers {
        ws: Workspace::new(aft),
        q: vec![0.0; 6 * m],
        x: vec![0.0; 3 * m],
        g: vec![0.0; 3 * m],
        jl: Vec::new(),
        col: vec![0.0; 3 * m],
        inner: Vec::new(),
        outer: Vec::new(),
        b_e: Vec::new(),
        jy: Vec::new(),
        work: Vec::new(),
    }
}

impl HarmonicForce for PairSet {
    type State = PairState;

    fn n_dofs(&self) -> usize {
        self.map.as_ref().map_or(self.n_dofs, LinearMap::outer)
    }

    /// Sliders at rest at the origin of the relative motion.
    fn initial_state(&self) -> PairState {
        vec![[0.0; 2]; self.pairs.len()]
    }

    fn evaluate(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &mut PairState,
        force: &mut [f64],
        jacobian: Option<MatMut<'_, f64>>,
    ) -> Result<()> {
        let outputs = Outputs {
            force: Some(force),
            dn0: None,
            jacobian: jacobian.map(JacobianMut::Dense),
        };
        self.run(layout, q, state, outputs)
    }

    /// The pairs' Jacobians are added pair by pair (no dense temporary).
    fn evaluate_into(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        _omega: f64,
        state: &mut PairState,
        force: &mut [f64],
        jacobian: Option<JacobianMut<'_>>,
        _d_omega: Option<&mut [f64]>,
    ) -> Result<()> {
        let outputs = Outputs {
            force: Some(force),
            dn0: None,
            jacobian,
        };
        self.run(layout, q, state, outputs)
    }

    /// ∂F/∂p with each pair's preload moving as ∂n0_j/∂p = `preload_rate` (SAMA: p = the
    /// contact's total preload n0).
    fn parameter_derivative(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &PairState,
        out: &mut [f64],
    ) -> Result<()> {
        let mut s = state.clone();
        let outputs = Outputs {
            force: None,
            dn0: Some(out),
            jacobian: None,
        };
        self.run(layout, q, &mut s, outputs)
    }
}
