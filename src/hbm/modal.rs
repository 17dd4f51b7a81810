//! Harmonic balance on modal coordinates: a linear part given by m modes (natural frequencies
//! ω_r, modal damping ratios ζ_r and the mass-normalised mode shapes at the contact, forced and
//! response DOFs — a modal ROM as exported from a finite element code) and a contact force on
//! n_c physical DOFs, with the m(2H + 1) modal harmonics as the unknowns.
//!
//! Modal superposition u(t) = Φ q(t) with modal damping (Craig & Kurdila 2006, "Fundamentals
//! of Structural Dynamics", mode-superposition method) gives per mode r
//! q̈_r + 2ζ_r ω_r q̇_r + ω_r² q_r = φ_rᵀ (f_e − f_nl(Φ_c q)), so the linear part is
//! K = diag(ω_r²) (1/s²), M = I, C = diag(2ζ_r ω_r) (1/s) on the modal coordinates q (m·√kg):
//! a [`LinearModel`] whose every DOF is a nonlinear one (nothing to condense), excited on
//! harmonic 1 by Φ_fᵀ f_e. The contact force is wrapped in [`ModalForce`]: per harmonic
//! coefficient the physical contact displacements U = Φ_c Q, the modal forces Φ_cᵀ F_nl(U) and
//! the Jacobian Φ_cᵀ (∂F_nl/∂U) Φ_c (the harmonic balance residual of the SAMA paper,
//! Battiato 2021, eqs. 19 and 21, in the coordinates q), formed element by element from the contact elements' own Jacobians
//! ([`JacobianSink`]) without any n_c × n_c or n_c(2H+1) × n_c(2H+1) matrix:
//!
//! - an element whose Jacobian is one matrix K_e on every harmonic coefficient and couples none
//!   (a pair that sticks, or stays in contact, all period: a constant weight of the AFT) adds
//!   Φ_eᵀ K_e Φ_e to every coefficient's diagonal block; these are summed once per evaluation,
//!   S = Φ_cᵀ (K_s Φ_c), K_s the sparse sum of the constant elements' K_e (2 n_c m² flops);
//! - the other elements (whose state changes within the period) couple the coefficients a, b:
//!   per pair (a, b) the block Φ_Tᵀ (J_ab Φ_T), Φ_T the rows of their DOFs
//!   (2 |T| m² flops per pair).
//!
//! The modal Jacobian is dense in the m(2H + 1) unknowns (an element in transition couples every
//! pair of modes across harmonics): the force reports no sparse harmonic coupling
//! ([`HarmonicForce::sparse_harmonic_coupling`]), so the harmonic balance gives no block
//! partition and every linear solver choice takes the dense LU, (2/3)(m(2H + 1))³ flops per
//! factorisation.
//! The response at physical DOFs is Φ_o Q per harmonic ([`ModalModel::physical_response`]).

use std::sync::atomic::{AtomicUsize, Ordering};

use faer::linalg::matmul::matmul;
use faer::{Accum, Mat, MatMut, MatRef, Par};
use rayon::prelude::*;

use super::linear::LinearModel;
use super::response::{peak_of, OutputResponse, ResponseOptions};
use crate::error::{Error, Result};
use crate::harmonics::{HarmonicForce, HarmonicLayout, JacobianMut, JacobianSink};

/// A modal model of the linear structure: m modes with their natural frequencies, modal damping
/// ratios and mass-normalised shapes at the contact, forced and response DOFs.
#[derive(Clone, Debug)]
pub struct ModalModel {
    /// ω_r (rad/s), length m.
    frequencies: Vec<f64>,
    /// ζ_r (1), length m.
    damping_ratios: Vec<f64>,
    /// Φ_c (1/√kg): n_c × m, row i = the modes at contact DOF i (in the contact force's order).
    contact: Mat<f64>,
    /// Φ_f (1/√kg): n_f × m, the modes at the forced DOFs.
    forced: Mat<f64>,
    /// f_e (N), length n_f: amplitude of f_e(t) = f_e cos ωt at the forced DOFs.
    force: Vec<f64>,
    /// Φ_o (1/√kg): n_o × m, the modes at the response DOFs.
    response: Mat<f64>,
}

impl ModalModel {
    /// Checks the shapes: `frequencies` (ω_r > 0, rad/s) and `damping_ratios` (ζ_r ≥ 0) of the
    /// same length m, every shape matrix with m columns, `force` (N) one entry per row of
    /// `forced`, every value finite. The errors name the argument.
    pub fn new(
        frequencies: Vec<f64>,
        damping_ratios: Vec<f64>,
        contact: Mat<f64>,
        forced: Mat<f64>,
        force: Vec<f64>,
        response: Mat<f64>,
    ) -> Result<ModalModel> {
        let m = frequencies.len();
        if m == 0 {
            return Err(Error::input(
                "modal model: `frequencies` is empty (no mode)",
            ));
        }
        if let Some(w) = frequencies.iter().find(|w| !(w.is_finite() && **w > 0.0)) {
            return Err(Error::input(format!(
                "modal model: `frequencies` has {w}: natural frequencies must be finite and > 0 rad/s"
            )));
        }
        if damping_ratios.len() != m {
            return Err(Error::input(format!(
                "modal model: `damping_ratios` has {} entries for {m} modes (`frequencies`)",
                damping_ratios.len()
            )));
        }
        if let Some(z) = damping_ratios
            .iter()
            .find(|z| !(z.is_finite() && **z >= 0.0))
        {
            return Err(Error::input(format!(
                "modal model: `damping_ratios` has {z}: damping ratios must be finite and ≥ 0"
            )));
        }
        for (name, shapes) in [
            ("contact_shapes", &contact),
            ("forced_shapes", &forced),
            ("response_shapes", &response),
        ] {
            check_shapes(name, shapes.as_ref(), m)?;
        }
        if force.len() != forced.nrows() {
            return Err(Error::input(format!(
                "modal model: `force` has {} entries for {} forced DOFs (rows of `forced_shapes`)",
                force.len(),
                forced.nrows()
            )));
        }
        if force.iter().any(|f| !f.is_finite()) {
            return Err(Error::input(
                "modal model: `force` has a value that is not finite",
            ));
        }
        Ok(ModalModel {
            frequencies,
            damping_ratios,
            contact,
            forced,
            force,
            response,
        })
    }

    /// Number of modes m.
    pub fn n_modes(&self) -> usize {
        self.frequencies.len()
    }

    /// Number of contact DOFs n_c.
    pub fn n_contact(&self) -> usize {
        self.contact.nrows()
    }

    /// Φ_c: n_c × m, the modes at the contact DOFs.
    pub fn contact_shapes(&self) -> MatRef<'_, f64> {
        self.contact.as_ref()
    }

    /// The linear part on the m modal coordinates with H harmonics: K = diag(ω_r²),
    /// M = I, C = diag(2ζ_r ω_r), every coordinate nonlinear and reported, excited on harmonic 1
    /// by the modal force Φ_fᵀ f_e (module documentation).
    pub fn linear_model(&self, harmonics: usize) -> Result<LinearModel> {
        let m = self.n_modes();
        let w = &self.frequencies;
        let k = Mat::from_fn(m, m, |i, j| if i == j { w[i] * w[i] } else { 0.0 });
        let mass = Mat::<f64>::identity(m, m);
        let c = Mat::from_fn(m, m, |i, j| {
            if i == j {
                2.0 * self.damping_ratios[i] * w[i]
            } else {
                0.0
            }
        });
        let modal_force: Vec<f64> = (0..m)
            .map(|r| {
                (0..self.forced.nrows())
                    .map(|i| self.forced[(i, r)] * self.force[i])
                    .sum()
            })
            .collect();
        LinearModel::from_real(
            k.as_ref(),
            mass.as_ref(),
            Some(c.as_ref()),
            &modal_force,
            (0..m).collect(),
            (0..m).collect(),
            harmonics,
        )
    }

    /// The contact force `inner` (on the n_c contact DOFs, in the rows' order of the contact
    /// shapes) projected on the modes.
    pub fn project<F: HarmonicForce>(&self, inner: F) -> Result<ModalForce<F>> {
        if inner.n_dofs() != self.n_contact() {
            return Err(Error::input(format!(
                "modal model: the contact force acts on {} DOFs but `contact_shapes` has {} rows",
                inner.n_dofs(),
                self.n_contact()
            )));
        }
        Ok(ModalForce {
            inner,
            shapes: self.contact.clone(),
            shapes_t: self.contact.transpose().to_owned(),
            constant_elements: AtomicUsize::new(0),
            coupled_elements: AtomicUsize::new(0),
        })
    }

    /// The response at the physical response DOFs from the response of the modal coordinates
    /// (of a solution of [`ModalModel::linear_model`], whose outputs are the m coordinates in
    /// order): Q_o⁽ⁿ⁾ = Φ_o Q⁽ⁿ⁾ per harmonic n, the first-harmonic amplitude and the peak over
    /// the period sampled as [`super::response::output_response`] does.
    pub fn physical_response(
        &self,
        modal: &OutputResponse,
        opts: &ResponseOptions,
    ) -> Result<OutputResponse> {
        let m = self.n_modes();
        if modal.harmonics.len() != m {
            return Err(Error::Compute(format!(
                "modal model: a response of {} coordinates for {m} modes",
                modal.harmonics.len()
            )));
        }
        let h = modal
            .harmonics
            .first()
            .map_or(0, |q| q.len().saturating_sub(1));
        let harmonics: Vec<Vec<faer::c64>> = (0..self.response.nrows())
            .map(|o| {
                (0..=h)
                    .map(|n| {
                        (0..m)
                            .map(|r| modal.harmonics[r][n] * self.response[(o, r)])
                            .sum()
                    })
                    .collect()
            })
            .collect();
        let amplitude = harmonics
            .iter()
            .map(|q: &Vec<faer::c64>| q.get(1).map_or(0.0, |v| v.norm()))
            .collect();
        let samples = opts.peak_samples.max(8 * (h + 1));
        let peak = harmonics.iter().map(|q| peak_of(q, samples)).collect();
        Ok(OutputResponse {
            harmonics,
            amplitude,
            peak,
        })
    }
}

/// Checks that a shape matrix has m columns and finite entries.
fn check_shapes(name: &str, shapes: MatRef<'_, f64>, m: usize) -> Result<()> {
    if shapes.ncols() != m {
        return Err(Error::input(format!(
            "modal model: `{name}` has {} columns for {m} modes (`frequencies`)",
            shapes.ncols()
        )));
    }
    for j in 0..shapes.ncols() {
        for i in 0..shapes.nrows() {
            if !shapes[(i, j)].is_finite() {
                return Err(Error::input(format!(
                    "modal model: `{name}` has a value that is not finite at row {i}, mode {j}"
                )));
            }
        }
    }
    Ok(())
}

/// Index in the real layout (`docs/conventions.md` §4) of coefficient `c` of DOF `dof` among
/// `n_dof`: c = 0 the static part, c = 2n − 1 Re Q⁽ⁿ⁾, c = 2n Im Q⁽ⁿ⁾.
fn coefficient_index(layout: &HarmonicLayout, c: usize, dof: usize, n_dof: usize) -> usize {
    if c == 0 {
        layout.static_index(dof)
    } else {
        layout.cos_index(c.div_ceil(2), dof, n_dof) + usize::from(c.is_multiple_of(2))
    }
}

/// The DOF and the coefficient (as [`coefficient_index`]) of index `i` of the real layout of
/// `n_dof` DOFs.
fn dof_and_coefficient(i: usize, n_dof: usize) -> (usize, usize) {
    if i < n_dof {
        return (i, 0);
    }
    let k = i - n_dof;
    let n = k / (2 * n_dof) + 1;
    let within = k % (2 * n_dof);
    (within / 2, 2 * n - 1 + within % 2)
}

/// A contact force on n_c physical DOFs seen on m modal coordinates (module documentation): a
/// [`HarmonicForce`] on the m DOFs of [`ModalModel::linear_model`].
pub struct ModalForce<F> {
    inner: F,
    /// Φ_c, n_c × m.
    shapes: Mat<f64>,
    /// Φ_cᵀ, m × n_c (column i: the modes at contact DOF i, contiguous).
    shapes_t: Mat<f64>,
    /// Elements of the last Jacobian projected as one matrix on every coefficient.
    constant_elements: AtomicUsize,
    /// Elements of the last Jacobian projected per pair of coefficients.
    coupled_elements: AtomicUsize,
}

impl<F> ModalForce<F> {
    /// The physical contact force.
    pub fn inner(&self) -> &F {
        &self.inner
    }

    /// Of the elements of the last Jacobian evaluated: how many were projected as one matrix
    /// on every harmonic coefficient (stuck or in contact all period), how many per pair of
    /// coefficients (in transition).
    pub fn last_split(&self) -> (usize, usize) {
        (
            self.constant_elements.load(Ordering::Relaxed),
            self.coupled_elements.load(Ordering::Relaxed),
        )
    }

    /// U = Φ_c Q per coefficient: the physical harmonic vector of the contact DOFs (the real
    /// layout of the inner force's n_c DOFs) for the modal one `q` (of the m modes).
    pub fn to_physical(&self, layout: &HarmonicLayout, q: &[f64]) -> Result<Vec<f64>> {
        let (nc, m) = (self.shapes.nrows(), self.shapes.ncols());
        let cc = layout.coefficients();
        if q.len() != layout.len(m) {
            return Err(Error::Compute(format!(
                "modal force: harmonic vector of length {} for {m} modes × {cc} coefficients",
                q.len()
            )));
        }
        let x = Mat::from_fn(m, cc, |r, c| q[coefficient_index(layout, c, r, m)]);
        let mut u = Mat::<f64>::zeros(nc, cc);
        gemm(u.as_mut(), self.shapes.as_ref(), x.as_ref());
        let mut out = vec![0.0; layout.len(nc)];
        for c in 0..cc {
            for d in 0..nc {
                out[coefficient_index(layout, c, d, nc)] = u[(d, c)];
            }
        }
        Ok(out)
    }

    /// `out` += Φ_cᵀ F per coefficient for the physical harmonic vector `f` of the contact DOFs.
    fn add_modal(&self, layout: &HarmonicLayout, f: &[f64], out: &mut [f64]) {
        let (nc, m) = (self.shapes.nrows(), self.shapes.ncols());
        let cc = layout.coefficients();
        let fm = Mat::from_fn(nc, cc, |d, c| f[coefficient_index(layout, c, d, nc)]);
        let mut g = Mat::<f64>::zeros(m, cc);
        gemm(g.as_mut(), self.shapes_t.as_ref(), fm.as_ref());
        for c in 0..cc {
            for r in 0..m {
                out[coefficient_index(layout, c, r, m)] += g[(r, c)];
            }
        }
    }

    /// Adds Φ_cᵀ J Φ_c of the collected element Jacobians to `out` (module documentation).
    fn project(&self, layout: &HarmonicLayout, elements: &ElementJacobians, out: JacobianMut<'_>) {
        self.constant_elements
            .store(elements.constant_elements, Ordering::Relaxed);
        self.coupled_elements
            .store(elements.coupled_elements, Ordering::Relaxed);
        let mut out = out;
        let m = self.shapes.ncols();
        if !elements.constant.is_empty() {
            let s = self.constant_projection(&elements.constant);
            for c in 0..layout.coefficients() {
                add_block(layout, m, (c, c), s.as_ref(), &mut out);
            }
        }
        self.add_coupled(layout, &elements.coupled, &mut out);
    }

    /// S = Φ_cᵀ K_s Φ_c (m × m) for the entries (row DOF, column DOF, value) of K_s.
    fn constant_projection(&self, entries: &[(usize, usize, f64)]) -> Mat<f64> {
        let (nc, m) = (self.shapes.nrows(), self.shapes.ncols());
        // Yᵀ = (K_s Φ_c)ᵀ, m × n_c: column i += k Φ_c[j, :]ᵀ for each entry (i, j, k)
        let mut yt = Mat::<f64>::zeros(m, nc);
        for &(i, j, k) in entries {
            let src = self.shapes_t.col(j);
            let mut dst = yt.col_mut(i);
            for r in 0..m {
                dst[r] += k * src[r];
            }
        }
        let mut s = Mat::<f64>::zeros(m, m);
        gemm(s.as_mut(), self.shapes_t.as_ref(), yt.transpose());
        s
    }

    /// Adds Φ_Tᵀ J_ab Φ_T on every pair of coefficients (a, b) of the entries of the elements in
    /// transition, in parallel over the pairs (a few at a time, so that at most that many m × m
    /// blocks are held).
    fn add_coupled(&self, layout: &HarmonicLayout, coupled: &[Entry], out: &mut JacobianMut<'_>) {
        if coupled.is_empty() {
            return;
        }
        let m = self.shapes.ncols();
        let mut entries = coupled.to_vec();
        entries.sort_unstable_by_key(|e| (e.rc, e.cc));
        // the DOFs of the entries, numbered locally, and their rows of Φ_c (as columns)
        let mut local = vec![usize::MAX; self.shapes.nrows()];
        let mut dofs = Vec::new();
        for e in &entries {
            for d in [e.rd, e.cd] {
                if local[d] == usize::MAX {
                    local[d] = dofs.len();
                    dofs.push(d);
                }
            }
        }
        let phi_t = Mat::from_fn(m, dofs.len(), |r, t| self.shapes_t[(r, dofs[t])]);
        let groups: Vec<&[Entry]> = entries
            .chunk_by(|a, b| (a.rc, a.cc) == (b.rc, b.cc))
            .collect();
        let batch = 2 * rayon::current_num_threads().max(1);
        for part in groups.chunks(batch) {
            let blocks: Vec<Mat<f64>> = part
                .par_iter()
                .map(|g| coupled_block(g, &local, phi_t.as_ref()))
                .collect();
            for (g, b) in part.iter().zip(&blocks) {
                add_block(layout, m, (g[0].rc, g[0].cc), b.as_ref(), out);
            }
        }
    }
}

/// Φ_Tᵀ J_ab Φ_T (m × m) for the entries of one pair of coefficients (a, b); `local` numbers
/// the DOFs as the columns of `phi_t` (Φ_Tᵀ, m × |T|).
fn coupled_block(entries: &[Entry], local: &[usize], phi_t: MatRef<'_, f64>) -> Mat<f64> {
    let m = phi_t.nrows();
    // Zᵀ = (J_ab Φ_T)ᵀ, m × |T|
    let mut zt = Mat::<f64>::zeros(m, phi_t.ncols());
    for e in entries {
        let src = phi_t.col(local[e.cd]);
        let mut dst = zt.col_mut(local[e.rd]);
        for r in 0..m {
            dst[r] += e.value * src[r];
        }
    }
    let mut b = Mat::<f64>::zeros(m, m);
    matmul(
        b.as_mut(),
        Accum::Replace,
        phi_t,
        zt.transpose(),
        1.0,
        Par::Seq,
    );
    b
}

/// Adds the m × m block `b` at the rows of coefficient `a.0` and the columns of coefficient
/// `a.1` of the modal Jacobian.
fn add_block(
    layout: &HarmonicLayout,
    m: usize,
    (a, c): (usize, usize),
    b: MatRef<'_, f64>,
    out: &mut JacobianMut<'_>,
) {
    for s in 0..m {
        let col = coefficient_index(layout, c, s, m);
        for r in 0..m {
            let v = b[(r, s)];
            if v != 0.0 {
                out.add(coefficient_index(layout, a, r, m), col, v);
            }
        }
    }
}

/// out = a b (faer's product on the global parallelism).
fn gemm(out: MatMut<'_, f64>, a: MatRef<'_, f64>, b: MatRef<'_, f64>) {
    matmul(
        out,
        Accum::Replace,
        a,
        b,
        1.0,
        faer::get_global_parallelism(),
    );
}

/// One entry of an element Jacobian in transition: row DOF and coefficient, column DOF and
/// coefficient, value.
#[derive(Clone, Copy, Debug)]
struct Entry {
    rd: usize,
    rc: usize,
    cd: usize,
    cc: usize,
    value: f64,
}

/// The element Jacobians of one evaluation of the physical force, sorted into the elements whose
/// Jacobian is one matrix K_e on every coefficient (kept as the entries of K_e) and the others
/// (kept entry by entry).
struct ElementJacobians {
    /// Physical contact DOFs n_c.
    n_dof: usize,
    /// Coefficients 2H + 1.
    coefficients: usize,
    /// Entries (row DOF, column DOF, value) of the constant elements' K_e.
    constant: Vec<(usize, usize, f64)>,
    /// Entries of the other elements and single entries.
    coupled: Vec<Entry>,
    constant_elements: usize,
    coupled_elements: usize,
    /// Per entry of the patch being sorted: its local DOF and its coefficient.
    decoded: Vec<(usize, usize)>,
    /// The DOFs of the patch being sorted.
    dofs: Vec<usize>,
}

impl ElementJacobians {
    fn new(layout: &HarmonicLayout, n_dof: usize) -> ElementJacobians {
        ElementJacobians {
            n_dof,
            coefficients: layout.coefficients(),
            constant: Vec::new(),
            coupled: Vec::new(),
            constant_elements: 0,
            coupled_elements: 0,
            decoded: Vec::new(),
            dofs: Vec::new(),
        }
    }

    /// K_e (d × d over `self.dofs`, column-major) if the patch is one matrix on every
    /// coefficient of each of its DOFs and couples no two coefficients; `None` otherwise.
    fn constant_matrix(&self, values: &[f64]) -> Option<Vec<f64>> {
        let (d, cc, l) = (self.dofs.len(), self.coefficients, self.decoded.len());
        if l != d * cc {
            return None;
        }
        let mut seen = vec![false; d * cc];
        for &(ld, c) in &self.decoded {
            if std::mem::replace(&mut seen[ld * cc + c], true) {
                return None;
            }
        }
        let mut k = vec![0.0; d * d];
        for (col, &(cd, c0)) in self.decoded.iter().enumerate() {
            for (row, &(rd, r0)) in self.decoded.iter().enumerate() {
                if r0 == 0 && c0 == 0 {
                    k[cd * d + rd] = values[col * l + row];
                }
            }
        }
        for (col, &(cd, c0)) in self.decoded.iter().enumerate() {
            for (row, &(rd, r0)) in self.decoded.iter().enumerate() {
                let want = if r0 == c0 { k[cd * d + rd] } else { 0.0 };
                if values[col * l + row] != want {
                    return None;
                }
            }
        }
        Some(k)
    }
}

impl JacobianSink for ElementJacobians {
    fn add_patch(&mut self, index: &[usize], values: &[f64]) {
        self.dofs.clear();
        self.decoded.clear();
        for &i in index {
            let (dof, c) = dof_and_coefficient(i, self.n_dof);
            let ld = match self.dofs.iter().position(|&x| x == dof) {
                Some(p) => p,
                None => {
                    self.dofs.push(dof);
                    self.dofs.len() - 1
                }
            };
            self.decoded.push((ld, c));
        }
        if values.iter().all(|&v| v == 0.0) {
            return;
        }
        if let Some(k) = self.constant_matrix(values) {
            let d = self.dofs.len();
            for (cl, &cd) in self.dofs.iter().enumerate() {
                for (rl, &rd) in self.dofs.iter().enumerate() {
                    let v = k[cl * d + rl];
                    if v != 0.0 {
                        self.constant.push((rd, cd, v));
                    }
                }
            }
            self.constant_elements += 1;
            return;
        }
        let l = index.len();
        for (col, &(cl, cc)) in self.decoded.iter().enumerate() {
            for (row, &(rl, rc)) in self.decoded.iter().enumerate() {
                let value = values[col * l + row];
                if value != 0.0 {
                    self.coupled.push(Entry {
                        rd: self.dofs[rl],
                        rc,
                        cd: self.dofs[cl],
                        cc,
                        value,
                    });
                }
            }
        }
        self.coupled_elements += 1;
    }

    fn add_entry(&mut self, i: usize, j: usize, v: f64) {
        if v == 0.0 {
            return;
        }
        let (rd, rc) = dof_and_coefficient(i, self.n_dof);
        let (cd, cc) = dof_and_coefficient(j, self.n_dof);
        self.coupled.push(Entry {
            rd,
            rc,
            cd,
            cc,
            value: v,
        });
    }
}

impl<F: HarmonicForce> HarmonicForce for ModalForce<F> {
    type State = F::State;

    fn n_dofs(&self) -> usize {
        self.shapes.ncols()
    }

    fn initial_state(&self) -> F::State {
        self.inner.initial_state()
    }

    /// As [`HarmonicForce::evaluate_into`] at ω = 0; a contact force that reads velocities must
    /// be evaluated at a frequency.
    fn evaluate(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &mut F::State,
        force: &mut [f64],
        jacobian: Option<MatMut<'_, f64>>,
    ) -> Result<()> {
        if self.inner.reads_velocity() {
            return Err(Error::Compute(
                "modal force: the contact force reads velocities; evaluate it at a frequency"
                    .into(),
            ));
        }
        let jacobian = jacobian.map(JacobianMut::Dense);
        self.evaluate_into(layout, q, 0.0, state, force, jacobian, None)
    }

    fn reads_velocity(&self) -> bool {
        self.inner.reads_velocity()
    }

    /// An element in transition couples every pair of modes across harmonics.
    fn sparse_harmonic_coupling(&self) -> bool {
        false
    }

    /// F = Φ_cᵀ F_nl(Φ_c Q) per coefficient, its Jacobian Φ_cᵀ J Φ_c projected element by
    /// element (module documentation) and ∂F/∂ω = Φ_cᵀ ∂F_nl/∂ω.
    fn evaluate_into(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        omega: f64,
        state: &mut F::State,
        force: &mut [f64],
        jacobian: Option<JacobianMut<'_>>,
        d_omega: Option<&mut [f64]>,
    ) -> Result<()> {
        let u = self.to_physical(layout, q)?;
        let mut f = vec![0.0; u.len()];
        let mut dw = d_omega.as_ref().map(|_| vec![0.0; u.len()]);
        let mut elements = jacobian
            .as_ref()
            .map(|_| ElementJacobians::new(layout, self.shapes.nrows()));
        let sink = elements
            .as_mut()
            .map(|e| JacobianMut::Sink(e as &mut dyn JacobianSink));
        self.inner
            .evaluate_into(layout, &u, omega, state, &mut f, sink, dw.as_deref_mut())?;
        self.add_modal(layout, &f, force);
        if let (Some(out), Some(dw)) = (d_omega, &dw) {
            self.add_modal(layout, dw, out);
        }
        if let (Some(out), Some(e)) = (jacobian, &elements) {
            self.project(layout, e, out);
        }
        Ok(())
    }

    /// Φ_cᵀ ∂F_nl/∂p per coefficient.
    fn parameter_derivative(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &F::State,
        out: &mut [f64],
    ) -> Result<()> {
        let u = self.to_physical(layout, q)?;
        let mut d = vec![0.0; u.len()];
        self.inner.parameter_derivative(layout, &u, state, &mut d)?;
        self.add_modal(layout, &d, out);
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The index of a (DOF, coefficient) and back.
    #[test]
    fn coefficient_indices_round_trip() {
        let layout = HarmonicLayout::new(3, 16).unwrap();
        let n = 5;
        let mut seen = vec![false; layout.len(n)];
        for c in 0..layout.coefficients() {
            for d in 0..n {
                let i = coefficient_index(&layout, c, d, n);
                assert_eq!(dof_and_coefficient(i, n), (d, c));
                assert!(!std::mem::replace(&mut seen[i], true));
            }
        }
        assert!(seen.iter().all(|&s| s));
    }
}
