//! Friction elements on DOF combinations of a matrix-defined system (`docs/case-file.md`,
//! `[[element]] kind = "friction"`), as one [`HarmonicForce`].
//!
//! An element reads a tangential relative displacement u_t = Σ_i w_i q_{d_i} (m) and, optionally,
//! a normal approach v = Σ_i w'_i q_{d'_i} (m) (normal load variation, SAMA paper eq. 13); it
//! applies the 1-D law of [`super::law`] (Jenkins element with f_n = max(n0 + k_n v, 0); without
//! a normal direction the slip limit is μ n0) and its forces act back along the same weights:
//! F_{d_i} += w_i f_t, F_{d'_i} += w'_i f_n (internal-force sign of [`HarmonicForce`]). A DOF
//! combination with a single DOF is an element to the ground; two DOFs with weights −1, 1 join
//! them.
//!
//! The other `[[element]]` kinds (springs, dampers, tanh friction: [`super::memoryless`]) read
//! one combination x = Σ_i w_i q_{d_i} and act back along it the same way, F_{d_i} += w_i f; they
//! carry no state. Elements that read velocities make the force depend on ω
//! ([`HarmonicForce::evaluate_into`]).

use std::sync::Arc;

use faer::MatMut;

use crate::case::{ElementKind, Evaluation, FrictionElement, WeightedDofs};
use crate::contact::aft::{check_finite, global_index, Aft, AftCache};
use crate::contact::assembly::{assemble, Outputs, Slot, SlotStorage, Wanted};
use crate::contact::element::{
    evaluate_as, ElementReport, HysteresisLoop, LocalElement, Workspace,
};
use crate::contact::law::{ContactParams, Variant};
use crate::contact::memoryless::{self, Law, LocalOutputs};
use crate::contact::slip_map::MapPoint;
use crate::error::{Error, Result};
use crate::harmonics::{HarmonicForce, HarmonicLayout, JacobianMut};

/// One element: tangential and optional normal DOF combinations and the law's parameters.
#[derive(Clone, Debug, PartialEq)]
pub struct DofElement {
    /// u_t = Σ weights·q\[dofs\].
    pub tangential: WeightedDofs,
    /// v = Σ weights·q\[dofs\], if the element has normal load variation.
    pub normal: Option<WeightedDofs>,
    /// Contact parameters.
    pub params: ContactParams,
}

impl DofElement {
    fn local(&self) -> LocalElement {
        LocalElement {
            params: self.params,
            variant: Variant::OneD,
            tangential: 1,
            normal: self.normal.is_some(),
        }
    }

    /// The signals' DOF combinations: tangential, then normal if present.
    fn combinations(&self) -> impl Iterator<Item = &WeightedDofs> {
        std::iter::once(&self.tangential).chain(self.normal.iter())
    }
}

/// A stateless element ([`super::memoryless`]) on one DOF combination.
#[derive(Clone, Debug, PartialEq)]
pub struct MemorylessElement {
    /// x = Σ weights·q\[dofs\].
    pub coordinate: WeightedDofs,
    /// f(x, ẋ).
    pub law: Law,
}

/// The `[[element]]` list of a case as one nonlinear force on the `n_dofs` matrix rows.
/// State: the slider position w (m) of every friction element.
pub struct DofElements {
    n_dofs: usize,
    elements: Vec<DofElement>,
    /// How each friction element is evaluated (default AFT).
    evaluations: Vec<Evaluation>,
    memoryless: Vec<MemorylessElement>,
    aft: AftCache,
    slots: SlotStorage,
    buffers: BufferPool,
}

impl std::fmt::Debug for DofElements {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DofElements")
            .field("n_dofs", &self.n_dofs)
            .field("elements", &self.elements)
            .field("memoryless", &self.memoryless)
            .finish()
    }
}

impl DofElements {
    /// Builds the elements of a case's `[[element]]` entries for a system of `n_dofs` rows
    /// (friction elements in [`DofElements::elements`], the other kinds in
    /// [`DofElements::memoryless`], each list in file order).
    pub fn from_case(elements: &[FrictionElement], n_dofs: usize) -> Result<Self> {
        let mut friction = Vec::new();
        let mut evaluations = Vec::new();
        let mut others = Vec::new();
        for (i, e) in elements.iter().enumerate() {
            let key = format!("element[{i}]");
            let value = |name: &str, v: Option<f64>| {
                v.ok_or_else(|| {
                    Error::input(format!(
                        "{key}: kind = \"{}\" needs `{name}`",
                        e.kind.name()
                    ))
                })
            };
            let law = match e.kind {
                ElementKind::Friction => {
                    check_combination(&format!("{key}.tangential"), &e.tangential, n_dofs)?;
                    if let Some(n) = &e.normal {
                        check_combination(&format!("{key}.normal"), n, n_dofs)?;
                    }
                    friction.push(DofElement {
                        tangential: e.tangential.clone(),
                        normal: e.normal.clone(),
                        params: ContactParams::new(
                            value("kt", e.kt)?,
                            e.kn,
                            value("mu", e.mu)?,
                            value("n0", e.n0)?,
                            &key,
                        )?,
                    });
                    evaluations.push(e.evaluation);
                    continue;
                }
                ElementKind::CubicSpring => Law::Cubic {
                    k3: value("k3", e.k3)?,
                },
                ElementKind::PolynomialSpring => {
                    let c = e.coefficients.as_deref().unwrap_or_default();
                    let p = e.exponents.as_deref().unwrap_or_default();
                    if c.is_empty() || c.len() != p.len() || p.contains(&0) {
                        return Err(Error::input(format!(
                            "{key}: `coefficients` ({} entries) and `exponents` ({} entries, each ≥ 1) must be non-empty lists of equal length",
                            c.len(),
                            p.len()
                        )));
                    }
                    Law::Polynomial {
                        terms: c.iter().copied().zip(p.iter().copied()).collect(),
                    }
                }
                ElementKind::UnilateralSpring => Law::Unilateral {
                    k: value("k", e.k)?,
                    gap: e.gap.unwrap_or(0.0),
                },
                ElementKind::QuadraticDamper => Law::QuadraticDamper {
                    c: value("c", e.c)?,
                },
                ElementKind::TanhFriction => Law::TanhFriction {
                    limit: value("mu", e.mu)? * value("n0", e.n0)?,
                    eps: value("eps", e.eps)?,
                },
            };
            law.validate(&key)?;
            check_combination(&format!("{key}.displacement"), &e.tangential, n_dofs)?;
            others.push(MemorylessElement {
                coordinate: e.tangential.clone(),
                law,
            });
        }
        let mut out = Self::new(friction, n_dofs)?.with_evaluations(evaluations)?;
        out.memoryless = others;
        Ok(out)
    }

    /// Adds stateless elements (springs, dampers, tanh friction) to the force, after checking
    /// their DOF combinations and parameters (`memoryless[i]` in messages, from 0).
    pub fn with_memoryless(mut self, elements: Vec<MemorylessElement>) -> Result<Self> {
        for (i, e) in elements.iter().enumerate() {
            let key = format!("memoryless[{i}]");
            e.law.validate(&key)?;
            check_combination(&key, &e.coordinate, self.n_dofs)?;
        }
        self.memoryless.extend(elements);
        Ok(self)
    }

    /// The stateless elements.
    pub fn memoryless(&self) -> &[MemorylessElement] {
        &self.memoryless
    }

    /// Checks every element (non-empty DOF lists of the weights' length, rows < `n_dofs`, finite
    /// weights, valid parameters; `element[i]` in messages is the i-th `[[element]]`, from 0).
    pub fn new(elements: Vec<DofElement>, n_dofs: usize) -> Result<Self> {
        for (i, e) in elements.iter().enumerate() {
            let key = format!("element[{i}]");
            e.params.validate(&key)?;
            for (name, c) in [
                ("tangential", Some(&e.tangential)),
                ("normal", e.normal.as_ref()),
            ] {
                let Some(c) = c else { continue };
                check_combination(&format!("{key}.{name}"), c, n_dofs)?;
            }
        }
        Ok(DofElements {
            n_dofs,
            evaluations: vec![Evaluation::Aft; elements.len()],
            elements,
            memoryless: Vec::new(),
            aft: AftCache::default(),
            slots: SlotStorage::default(),
            buffers: BufferPool::default(),
        })
    }

    /// Sets how each friction element is evaluated (one entry per element, in order; the
    /// default is [`Evaluation::Aft`] for all). `analytic` needs H = 1, checked at evaluation.
    pub fn with_evaluations(mut self, evaluations: Vec<Evaluation>) -> Result<Self> {
        if evaluations.len() != self.elements.len() {
            return Err(Error::Compute(format!(
                "friction elements: {} evaluation choices for {} elements",
                evaluations.len(),
                self.elements.len()
            )));
        }
        self.evaluations = evaluations;
        Ok(self)
    }

    /// How each friction element is evaluated.
    pub fn evaluations(&self) -> &[Evaluation] {
        &self.evaluations
    }

    /// The elements.
    pub fn elements(&self) -> &[DofElement] {
        &self.elements
    }

    /// Per-element state over the period and, if `loops`, the hysteresis samples, for the
    /// harmonics `q` from the starting state `state` (not changed).
    pub fn reports(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &[f64],
        loops: bool,
    ) -> Result<Vec<(ElementReport, Option<HysteresisLoop>)>> {
        let aft = self.prepare(layout, q, state)?;
        let mut ws = Workspace::new(&aft);
        let mut out = Vec::with_capacity(self.elements.len());
        let m = layout.coefficients();
        let (mut x, mut g) = (vec![0.0; 2 * m], vec![0.0; 2 * m]);
        for (i, (e, &w)) in self.elements.iter().zip(state).enumerate() {
            let mut slider = [w, 0.0];
            self.local_eval(
                i,
                e,
                &aft,
                layout,
                q,
                &mut slider,
                false,
                &mut x,
                &mut g,
                &mut ws,
            )?;
            out.push((ws.report(), loops.then(|| ws.hysteresis())));
        }
        Ok(out)
    }

    /// The friction elements `range` as points of a stick–slip–separation map
    /// ([`super::slip_map`]): each element's tangential and normal harmonics (U0, Re U1, Im U1),
    /// (V0, Re V1, Im V1) at the harmonic vector `q` of an H = 1 layout, its parameters and its
    /// slider state from `state`. An input error for H ≠ 1 (the maps are built from the exact
    /// single-harmonic cycle).
    pub fn map_points(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &[f64],
        range: std::ops::Range<usize>,
    ) -> Result<Vec<MapPoint>> {
        if layout.harmonics != 1 {
            return Err(Error::input(format!(
                "stick–slip–separation maps are built from the exact single-harmonic cycle and need harmonics = 1 (here H = {})",
                layout.harmonics
            )));
        }
        self.prepare(layout, q, state)?;
        let elements = self.elements.get(range.clone()).ok_or_else(|| {
            Error::Compute(format!(
                "friction elements: map of elements {range:?} of {}",
                self.elements.len()
            ))
        })?;
        let motion = |c: &WeightedDofs| {
            let mut x = [0.0; 3];
            for (&d, &w) in c.dofs.iter().zip(&c.weights) {
                for (l, xl) in x.iter_mut().enumerate() {
                    *xl += w * q[global_index(layout, l, d, self.n_dofs)];
                }
            }
            x
        };
        Ok(elements
            .iter()
            .zip(&state[range])
            .map(|(e, &slider)| MapPoint {
                params: e.params,
                u: motion(&e.tangential),
                v: e.normal.as_ref().map_or([0.0; 3], motion),
                slider,
            })
            .collect())
    }

    fn prepare(&self, layout: &HarmonicLayout, q: &[f64], state: &[f64]) -> Result<Arc<Aft>> {
        if q.len() != layout.len(self.n_dofs) || state.len() != self.elements.len() {
            return Err(Error::Compute(format!(
                "friction elements: harmonic vector of length {} and {} slider states for {} DOFs × {} coefficients and {} elements",
                q.len(),
                state.len(),
                self.n_dofs,
                layout.coefficients(),
                self.elements.len()
            )));
        }
        check_finite(q, "friction elements")?;
        self.aft.get(layout)
    }

    /// Local coefficients x = [U; V] of element `e`, then the element evaluation (forces in `g`).
    #[allow(clippy::too_many_arguments)]
    fn local_eval(
        &self,
        i: usize,
        e: &DofElement,
        aft: &Aft,
        layout: &HarmonicLayout,
        q: &[f64],
        slider: &mut [f64; 2],
        jacobian: bool,
        x: &mut [f64],
        g: &mut [f64],
        ws: &mut Workspace,
    ) -> Result<()> {
        let m = layout.coefficients();
        let local = e.local();
        let ns = local.signals();
        x[..ns * m].fill(0.0);
        for (s, c) in e.combinations().enumerate() {
            for (&d, &w) in c.dofs.iter().zip(&c.weights) {
                for l in 0..m {
                    x[s * m + l] += w * q[global_index(layout, l, d, self.n_dofs)];
                }
            }
        }
        evaluate_as(
            self.evaluations[i],
            &local,
            aft,
            &x[..ns * m],
            slider,
            &mut g[..ns * m],
            jacobian,
            ws,
        )
        .map_err(|err| match err {
            Error::Input(msg) => Error::input(format!("friction element {i} (from 0): {msg}")),
            other => other,
        })?;
        Ok(())
    }

    /// Node-space results of element `i` into `slot` (entries (signal s, DOF i of its
    /// combination, coefficient l); column-major Jacobian
    /// J[(s, i, l), (t, i', l')] = w_i w_i' J_local[(s, l), (t, l')]).
    #[allow(clippy::too_many_arguments)]
    fn element_slot(
        &self,
        i: usize,
        aft: &Aft,
        layout: &HarmonicLayout,
        q: &[f64],
        w: &mut f64,
        wanted: Wanted,
        b: &mut ElementBuffers,
        slot: Slot<'_>,
    ) -> Result<()> {
        let e = &self.elements[i];
        let m = layout.coefficients();
        let local_jacobian = wanted.jacobian || wanted.dn0;
        let mut slider = [*w, 0.0];
        let (x, g, ws) = (&mut b.x, &mut b.g, &mut b.ws);
        self.local_eval(i, e, aft, layout, q, &mut slider, local_jacobian, x, g, ws)?;
        *w = slider[0];
        // (signal, weight) of each node-space DOF, in entry order.
        let mut np = 0;
        for (s, c) in e.combinations().enumerate() {
            for (&d, &wt) in c.dofs.iter().zip(&c.weights) {
                for l in 0..m {
                    slot.index[np] = global_index(layout, l, d, self.n_dofs);
                    slot.force[np] = wt * g[s * m + l];
                    np += 1;
                }
            }
        }
        *slot.len = np;
        if !local_jacobian {
            return Ok(());
        }
        let (jac, cols) = ws.jacobian();
        let weights = || {
            e.combinations()
                .enumerate()
                .flat_map(|(s, c)| c.weights.iter().map(move |&wt| (s, wt)))
        };
        if wanted.dn0 {
            let n0_col = cols - 1;
            for (k, (s, wt)) in weights().enumerate() {
                for l in 0..m {
                    slot.dn0[k * m + l] = wt * jac[(s * m + l) * cols + n0_col];
                }
            }
        }
        if wanted.jacobian {
            for (kc, (t, wc)) in weights().enumerate() {
                for lp in 0..m {
                    let column = &mut slot.jacobian[(kc * m + lp) * np..(kc * m + lp + 1) * np];
                    for (kr, (s, wr)) in weights().enumerate() {
                        for l in 0..m {
                            column[kr * m + l] = wr * wc * jac[(s * m + l) * cols + t * m + lp];
                        }
                    }
                }
            }
        }
        Ok(())
    }

    /// Evaluates every element (in parallel) and adds forces, Jacobian and ∂F/∂n0 (each if
    /// given).
    fn run(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &mut [f64],
        outputs: Outputs<'_>,
    ) -> Result<()> {
        let aft = self.prepare(layout, q, state)?;
        let m = layout.coefficients();
        let capacity = self
            .elements
            .iter()
            .map(|e| m * e.combinations().map(|c| c.dofs.len()).sum::<usize>())
            .max()
            .unwrap_or(0);
        assemble(
            state,
            capacity,
            outputs,
            &self.slots,
            || self.buffers.take(&aft),
            |i, w, b, wanted, slot| self.element_slot(i, &aft, layout, q, w, wanted, b, slot),
        )
    }
}

impl DofElements {
    /// Adds the forces of the stateless elements at ω (rad/s), their Jacobian (J_node =
    /// w_i w_i' J_local on the DOFs of the combination) and ∂F/∂ω.
    fn add_memoryless(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        omega: f64,
        force: &mut [f64],
        mut jacobian: Option<JacobianMut<'_>>,
        mut d_omega: Option<&mut [f64]>,
    ) -> Result<()> {
        if self.memoryless.is_empty() {
            return Ok(());
        }
        if q.len() != layout.len(self.n_dofs) || force.len() != q.len() {
            return Err(Error::Compute(format!(
                "nonlinear elements: harmonic vectors of length {} and {} for {} DOFs × {} coefficients",
                q.len(),
                force.len(),
                self.n_dofs,
                layout.coefficients()
            )));
        }
        check_finite(q, "nonlinear elements")?;
        let aft = self.aft.get(layout)?;
        let m = layout.coefficients();
        let mut b = memoryless::Buffers::new(&aft);
        let (mut x, mut f, mut d) = (vec![0.0; m], vec![0.0; m], vec![0.0; m]);
        let mut jac = vec![0.0; m * m];
        for e in &self.memoryless {
            let c = &e.coordinate;
            let index = |d: usize, l: usize| global_index(layout, l, d, self.n_dofs);
            x.fill(0.0);
            for (&dof, &w) in c.dofs.iter().zip(&c.weights) {
                for (l, xl) in x.iter_mut().enumerate() {
                    *xl += w * q[index(dof, l)];
                }
            }
            let velocity = e.law.reads_velocity();
            let out = LocalOutputs {
                force: Some(&mut f),
                jacobian: jacobian.is_some().then_some(&mut jac[..]),
                d_omega: (velocity && d_omega.is_some()).then_some(&mut d[..]),
            };
            memoryless::evaluate(&e.law, &aft, &x, omega, out, &mut b)?;
            for (&dof, &w) in c.dofs.iter().zip(&c.weights) {
                for l in 0..m {
                    force[index(dof, l)] += w * f[l];
                    if velocity {
                        if let Some(dw) = d_omega.as_deref_mut() {
                            dw[index(dof, l)] += w * d[l];
                        }
                    }
                }
            }
            if let Some(j) = jacobian.as_mut() {
                for (&dr, &wr) in c.dofs.iter().zip(&c.weights) {
                    for (&dc, &wc) in c.dofs.iter().zip(&c.weights) {
                        for k in 0..m {
                            for l in 0..m {
                                j.add(index(dr, k), index(dc, l), wr * wc * jac[k * m + l]);
                            }
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// Buffers of one thread.
struct ElementBuffers {
    ws: Workspace,
    x: Vec<f64>,
    g: Vec<f64>,
}

impl ElementBuffers {
    fn new(aft: &Aft) -> Self {
        let m = aft.layout().coefficients();
        ElementBuffers {
            ws: Workspace::new(aft),
            x: vec![0.0; 2 * m],
            g: vec![0.0; 2 * m],
        }
    }
}

/// Buffers kept between evaluations, one set per chunk of elements evaluated at a time: a
/// [`Workspace`] holds a dozen vectors of N_t samples, and making and zeroing them at every
/// evaluation cost a tenth of the continuation of a 3-DOF chain at N_t = 1024. Every evaluation
/// writes the buffers before it reads them (as for the elements that share a set within one
/// evaluation), so that a reused set gives the same results as a new one.
#[derive(Default)]
struct BufferPool(std::sync::Mutex<Vec<ElementBuffers>>);

impl BufferPool {
    /// A set of buffers for the layout of `aft` (a kept one if it has that layout), returned to
    /// the pool when dropped.
    fn take(&self, aft: &Aft) -> Pooled<'_> {
        let kept = self
            .0
            .lock()
            .ok()
            .and_then(|mut kept| kept.pop())
            .filter(|b| b.ws.fits(aft));
        Pooled {
            buffers: Some(kept.unwrap_or_else(|| ElementBuffers::new(aft))),
            pool: self,
        }
    }
}

/// Buffers taken from a [`BufferPool`], given back when dropped.
struct Pooled<'a> {
    buffers: Option<ElementBuffers>,
    pool: &'a BufferPool,
}

impl std::ops::Deref for Pooled<'_> {
    type Target = ElementBuffers;
    fn deref(&self) -> &ElementBuffers {
        self.buffers.as_ref().expect("buffers until dropped")
    }
}

impl std::ops::DerefMut for Pooled<'_> {
    fn deref_mut(&mut self) -> &mut ElementBuffers {
        self.buffers.as_mut().expect("buffers until dropped")
    }
}

impl Drop for Pooled<'_> {
    fn drop(&mut self) {
        if let (Some(b), Ok(mut kept)) = (self.buffers.take(), self.pool.0.lock()) {
            kept.push(b);
        }
    }
}

fn check_combination(key: &str, c: &WeightedDofs, n_dofs: usize) -> Result<()> {
    if c.dofs.is_empty() || c.dofs.len() != c.weights.len() {
        return Err(Error::input(format!(
            "{key}: `dofs` ({} entries) and `weights` ({} entries) must be non-empty lists of equal length",
            c.dofs.len(),
            c.weights.len()
        )));
    }
    if let Some(w) = c.weights.iter().find(|w| !w.is_finite()) {
        return Err(Error::input(format!(
            "{key}.weights: {w} is not a finite number"
        )));
    }
    if let Some(d) = c.dofs.iter().find(|&&d| d >= n_dofs) {
        return Err(Error::input(format!(
            "{key}.dofs: row {d} is out of range (the matrices have {n_dofs} rows, numbered from 0)"
        )));
    }
    Ok(())
}

impl HarmonicForce for DofElements {
    type State = Vec<f64>;

    fn n_dofs(&self) -> usize {
        self.n_dofs
    }

    /// Sliders at rest at u_t = 0.
    fn initial_state(&self) -> Vec<f64> {
        vec![0.0; self.elements.len()]
    }

    /// Errors when an element reads velocities (those need ω: [`HarmonicForce::evaluate_into`]).
    fn evaluate(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &mut Vec<f64>,
        force: &mut [f64],
        jacobian: Option<MatMut<'_, f64>>,
    ) -> Result<()> {
        if self.reads_velocity() {
            return Err(Error::Compute(
                "the [[element]] list holds a quadratic_damper or tanh_friction element, whose force depends on the frequency; it is evaluated by the frequency response only (Hill stability and the time-domain tools take displacement elements)".into(),
            ));
        }
        let jacobian = jacobian.map(JacobianMut::Dense);
        self.evaluate_into(layout, q, 0.0, state, force, jacobian, None)
    }

    fn reads_velocity(&self) -> bool {
        self.memoryless.iter().any(|e| e.law.reads_velocity())
    }

    /// The elements' Jacobians are added element by element (no dense temporary).
    fn evaluate_into(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        omega: f64,
        state: &mut Vec<f64>,
        force: &mut [f64],
        mut jacobian: Option<JacobianMut<'_>>,
        d_omega: Option<&mut [f64]>,
    ) -> Result<()> {
        let outputs = Outputs {
            force: Some(&mut *force),
            dn0: None,
            jacobian: jacobian.as_mut().map(|j| j.rb_mut()),
        };
        self.run(layout, q, state, outputs)?;
        self.add_memoryless(layout, q, omega, force, jacobian, d_omega)
    }

    /// ∂F/∂n0 with the static normal load n0 of every element moving together (∂n0_e/∂p = 1).
    fn parameter_derivative(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &Vec<f64>,
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
