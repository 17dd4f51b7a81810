//! The linear part of the harmonic balance: per temporal harmonic n the dynamic stiffness
//! D⁽ⁿ⁾(ω) = K − (nω)² M + i nω C of the matrices of its harmonic index k_n (SAMA paper, eq. 12),
//! condensed on the nonlinear DOFs (eqs. 15–18).
//!
//! A [`LinearModel`] holds one or more [`MatrixBlock`]s (complex K, M, C of one harmonic index, or
//! the real matrices of a model without cyclic symmetry) and, per harmonic n = 0..H, which block
//! it uses and its excitation F_e⁽ⁿ⁾. Every block lists the rows of the nonlinear (condensed) DOFs
//! in one common order — the DOF order of the [`crate::harmonics::HarmonicForce`] — and the rows
//! reported as the response. Condensation is dense and done per frequency.

use std::mem::MaybeUninit;
use std::sync::{Arc, Mutex, OnceLock};

use faer::linalg::matmul::matmul;
use faer::{c64, Accum, Mat, MatMut, MatRef, Par};

use crate::error::{Error, Result};
use crate::nonlinear::lu::PackedLu;

/// The matrices of one harmonic index (or of a model without cyclic symmetry) and its
/// partition into nonlinear (condensed) and linear DOFs.
#[derive(Clone, Debug)]
pub struct MatrixBlock {
    /// K (N/m), square, n × n.
    pub stiffness: Mat<c64>,
    /// M (kg), n × n.
    pub mass: Mat<c64>,
    /// C (N·s/m), n × n; `None` is undamped.
    pub damping: Option<Mat<c64>>,
    /// Rows of the nonlinear DOFs, in the order of the nonlinear force's DOFs.
    pub nonlinear: Vec<usize>,
    /// Rows reported as the response, in output order.
    pub outputs: Vec<usize>,
}

/// The blocks of a [`MatrixBlock`] split by the partition N (nonlinear) / L (linear) of eq. 15.
#[derive(Clone, Debug)]
struct Partitioned {
    k: Split,
    m: Split,
    c: Option<Split>,
    /// Rows of the linear DOFs (the complement of `nonlinear`), ascending.
    linear: Vec<usize>,
    nonlinear: Vec<usize>,
    outputs: Vec<usize>,
    n_rows: usize,
}

/// The four partitions of one matrix.
#[derive(Clone, Debug)]
struct Split {
    nn: Mat<c64>,
    nl: Mat<c64>,
    ln: Mat<c64>,
    ll: Mat<c64>,
}

impl Split {
    fn part(&self, part: Part) -> MatRef<'_, c64> {
        match part {
            Part::NN => self.nn.as_ref(),
            Part::NL => self.nl.as_ref(),
            Part::LN => self.ln.as_ref(),
            Part::LL => self.ll.as_ref(),
        }
    }

    /// The whole matrix with the rows and columns ordered [nonlinear; linear].
    fn joined(&self) -> Mat<c64> {
        let n_n = self.nn.nrows();
        let n = n_n + self.ll.nrows();
        Mat::from_fn(n, n, |i, j| match (i < n_n, j < n_n) {
            (true, true) => self.nn[(i, j)],
            (true, false) => self.nl[(i, j - n_n)],
            (false, true) => self.ln[(i - n_n, j)],
            (false, false) => self.ll[(i - n_n, j - n_n)],
        })
    }

    fn new(a: MatRef<'_, c64>, nonlinear: &[usize], linear: &[usize]) -> Split {
        let sub = |r: &[usize], c: &[usize]| Mat::from_fn(r.len(), c.len(), |i, j| a[(r[i], c[j])]);
        Split {
            nn: sub(nonlinear, nonlinear),
            nl: sub(nonlinear, linear),
            ln: sub(linear, nonlinear),
            ll: sub(linear, linear),
        }
    }
}

/// Which part of a matrix to form the dynamic stiffness of.
#[derive(Clone, Copy, Debug)]
enum Part {
    NN,
    NL,
    LN,
    LL,
}

impl Partitioned {
    /// D⁽ⁿ⁾ = K − s² M + i s C on one partition, s = nω (rad/s).
    fn dynamic(&self, part: Part, s: f64) -> Mat<c64> {
        let (k, m) = (self.k.part(part), self.m.part(part));
        let c = self.c.as_ref().map(|c| c.part(part));
        Mat::from_fn(k.nrows(), k.ncols(), |i, j| dynamic_entry(k, m, c, i, j, s))
    }

    /// D⁽ⁿ⁾ v = K v − s² M v + i s C v on one partition, by matrix–vector products (no matrix
    /// of D is formed).
    fn dynamic_times(&self, part: Part, s: f64, v: &[c64]) -> Vec<c64> {
        let v = MatRef::from_column_major_slice(v, v.len(), 1);
        let k = product(self.k.part(part), v);
        let m = product(self.m.part(part), v);
        let c = self.c.as_ref().map(|c| product(c.part(part), v));
        (0..k.nrows())
            .map(|i| {
                let mut d = k[(i, 0)] - m[(i, 0)] * (s * s);
                if let Some(c) = &c {
                    d += c[(i, 0)] * c64::new(0.0, s);
                }
                d
            })
            .collect()
    }

    /// ∂D⁽ⁿ⁾/∂ω v = −2 n² ω M v + i n C v on one partition, by matrix–vector products.
    fn dynamic_derivative_times(&self, part: Part, n: f64, omega: f64, v: &[c64]) -> Vec<c64> {
        let v = MatRef::from_column_major_slice(v, v.len(), 1);
        let m = product(self.m.part(part), v);
        let c = self.c.as_ref().map(|c| product(c.part(part), v));
        (0..m.nrows())
            .map(|i| {
                let mut d = m[(i, 0)] * (-2.0 * n * n * omega);
                if let Some(c) = &c {
                    d += c[(i, 0)] * c64::new(0.0, n);
                }
                d
            })
            .collect()
    }

    /// ∂D⁽ⁿ⁾/∂ω = −2 n² ω M + i n C on one partition.
    fn dynamic_derivative(&self, part: Part, n: f64, omega: f64) -> Mat<c64> {
        let m = self.m.part(part);
        let c = self.c.as_ref().map(|c| c.part(part));
        Mat::from_fn(m.nrows(), m.ncols(), |i, j| {
            derivative_entry(m, c, i, j, n, omega)
        })
    }

    /// [`Partitioned::dynamic`] into `out` (of the partition's shape).
    fn dynamic_into(&self, part: Part, s: f64, out: &mut Mat<c64>) {
        let (k, m, c) = self.views(part);
        for j in 0..k.ncols() {
            for i in 0..k.nrows() {
                out[(i, j)] = dynamic_entry(k, m, c, i, j, s);
            }
        }
    }

    /// [`Partitioned::dynamic_derivative`] into `out` (of the partition's shape).
    fn derivative_into(&self, part: Part, n: f64, omega: f64, out: &mut Mat<c64>) {
        let (_, m, c) = self.views(part);
        for j in 0..m.ncols() {
            for i in 0..m.nrows() {
                out[(i, j)] = derivative_entry(m, c, i, j, n, omega);
            }
        }
    }

    /// The views (K, M, C) of one partition.
    fn views(&self, part: Part) -> Views<'_> {
        (
            self.k.part(part),
            self.m.part(part),
            self.c.as_ref().map(|c| c.part(part)),
        )
    }
}

/// K, M and (if damped) C of one partition.
type Views<'a> = (MatRef<'a, c64>, MatRef<'a, c64>, Option<MatRef<'a, c64>>);

/// Entry (i, j) of D = K − s² M + i s C.
#[inline]
fn dynamic_entry(
    k: MatRef<'_, c64>,
    m: MatRef<'_, c64>,
    c: Option<MatRef<'_, c64>>,
    i: usize,
    j: usize,
    s: f64,
) -> c64 {
    let mut d = k[(i, j)] - m[(i, j)] * (s * s);
    if let Some(c) = c {
        d += c[(i, j)] * c64::new(0.0, s);
    }
    d
}

/// Entry (i, j) of ∂D⁽ⁿ⁾/∂ω = −2 n² ω M + i n C.
#[inline]
fn derivative_entry(
    m: MatRef<'_, c64>,
    c: Option<MatRef<'_, c64>>,
    i: usize,
    j: usize,
    n: f64,
    omega: f64,
) -> c64 {
    let mut d = m[(i, j)] * (-2.0 * n * n * omega);
    if let Some(c) = c {
        d += c[(i, j)] * c64::new(0.0, n);
    }
    d
}

/// The uncondensed matrices of one harmonic n, rows and columns ordered [nonlinear DOFs (in the
/// nonlinear force's order); linear DOFs] (for Hill's method, [`super::stability`]).
#[derive(Clone, Debug)]
pub struct Uncondensed {
    /// K (N/m).
    pub stiffness: Mat<c64>,
    /// M (kg).
    pub mass: Mat<c64>,
    /// C (N·s/m), zero when the block is undamped.
    pub damping: Mat<c64>,
}

/// One harmonic n condensed at one frequency for one residual evaluation
/// ([`LinearModel::condense_applied`]).
#[derive(Clone, Debug)]
pub struct CondensedApplied {
    /// D̄⁽ⁿ⁾ (N/m), n_N × n_N.
    pub stiffness: Mat<c64>,
    /// F̄_e⁽ⁿ⁾ (N), length n_N.
    pub force: Vec<c64>,
    /// ∂D̄⁽ⁿ⁾/∂ω Q⁽ⁿ⁾ (N·s), length n_N.
    pub stiffness_derivative_q: Vec<c64>,
    /// ∂F̄_e⁽ⁿ⁾/∂ω (N·s), length n_N.
    pub force_derivative: Vec<c64>,
}

/// The products of one harmonic n condensed at one frequency with the harmonic q_n of one
/// evaluation ([`LinearModel::condense_deferred`]).
#[derive(Clone, Debug)]
pub struct Applied {
    /// D̄⁽ⁿ⁾ q_n (N), length n_N.
    pub stiffness_q: Vec<c64>,
    /// F̄_e⁽ⁿ⁾ (N), length n_N.
    pub force: Vec<c64>,
    /// ∂D̄⁽ⁿ⁾/∂ω q_n (N·s), length n_N.
    pub stiffness_derivative_q: Vec<c64>,
    /// ∂F̄_e⁽ⁿ⁾/∂ω (N·s), length n_N.
    pub force_derivative: Vec<c64>,
}

/// D̄⁽ⁿ⁾(ω) of one harmonic at one frequency, applied to vectors without being formed
/// (D_NN q − D_NL D_LL⁻¹ D_LN q on the LU of D_LL) or formed on demand
/// ([`LinearModel::condense_deferred`]). It shares the model's matrices.
pub struct HarmonicOperator {
    kind: OperatorKind,
    /// The model's ‖D̄⁽ⁿ⁾‖₁ per harmonic and this harmonic's n.
    norm: (Arc<Mutex<Vec<f64>>>, usize),
}

enum OperatorKind {
    /// The static harmonic: D̄⁽⁰⁾ (formed once by the model) and F̄⁽⁰⁾.
    Static(Arc<(Mat<c64>, Vec<c64>)>),
    /// A harmonic n ≥ 1 at s = nω: D_NN(s), and the coupling to the linear DOFs (`None` when
    /// there are none).
    Dynamic {
        d_nn: Mat<c64>,
        coupling: Option<Box<Coupling>>,
    },
}

/// D_NL(s), D_LN(s) and the LU of D_LL(s) of one harmonic.
struct Coupling {
    d_nl: Mat<c64>,
    d_ln: Mat<c64>,
    lu: PackedLu<c64>,
}

impl std::fmt::Debug for HarmonicOperator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.kind {
            OperatorKind::Static(c) => write!(f, "HarmonicOperator(static, {} DOFs)", c.0.nrows()),
            OperatorKind::Dynamic { d_nn, coupling } => write!(
                f,
                "HarmonicOperator({} + {} DOFs)",
                d_nn.nrows(),
                coupling.as_ref().map_or(0, |c| c.d_ln.nrows())
            ),
        }
    }
}

impl HarmonicOperator {
    /// D̄⁽ⁿ⁾ q (N) for a harmonic q of the nonlinear DOFs (m).
    pub fn apply(&self, q: &[c64]) -> Vec<c64> {
        match &self.kind {
            OperatorKind::Static(c) => times(&c.0, q),
            OperatorKind::Dynamic { d_nn, coupling } => {
                let mut r = times(d_nn, q);
                if let Some(c) = coupling {
                    let ln_q = times(&c.d_ln, q);
                    let mut v = Mat::from_fn(ln_q.len(), 1, |i, _| ln_q[i]);
                    c.lu.solve_in_place(v.as_mut());
                    let nl_v = product(c.d_nl.as_ref(), v.as_ref());
                    r.iter_mut()
                        .enumerate()
                        .for_each(|(i, r)| *r -= nl_v[(i, 0)]);
                }
                r
            }
        }
    }

    /// D̄⁽ⁿ⁾ = D_NN − D_NL D_LL⁻¹ D_LN (N/m), n_N × n_N (eq. 16); records its ‖·‖₁ in the real
    /// layout for [`HarmonicOperator::norm_1`].
    pub fn matrix(&self) -> Mat<c64> {
        let d = match &self.kind {
            OperatorKind::Static(c) => c.0.clone(),
            OperatorKind::Dynamic { d_nn, coupling } => match coupling {
                None => d_nn.clone(),
                Some(c) => {
                    let mut x = c.d_ln.clone();
                    c.lu.solve_in_place(x.as_mut());
                    let nl_x = product(c.d_nl.as_ref(), x.as_ref());
                    Mat::from_fn(d_nn.nrows(), d_nn.ncols(), |i, j| {
                        d_nn[(i, j)] - nl_x[(i, j)]
                    })
                }
            },
        };
        let norm = real_layout_norm_1(&d);
        if let Ok(mut norms) = self.norm.0.lock() {
            norms[self.norm.1] = norm;
        }
        d
    }

    /// ‖D̄⁽ⁿ⁾‖₁ in the real layout (max over columns of Σ |Re| + |Im|; for the static harmonic
    /// Σ |Re|) at the frequency this harmonic was last formed at by any operator of the model
    /// (an estimate of this operator's: the scale of backward errors); formed now if never.
    pub fn norm_1(&self) -> f64 {
        let known = self
            .norm
            .0
            .lock()
            .map(|n| n[self.norm.1])
            .unwrap_or(f64::NAN);
        if known.is_finite() {
            known
        } else {
            real_layout_norm_1(&self.matrix())
        }
    }
}

/// Products of fewer multiply–adds run on the calling thread ([`product`]).
const PARALLEL_PRODUCT: usize = 1 << 15;

/// The product a b: faer's, on the calling thread below [`PARALLEL_PRODUCT`] multiply–adds.
/// faer's parallel product splits even a rank-one update of a few entries (an inner dimension
/// of 1: one linear DOF) over rayon's threads, and the hand-over costs far more than the product.
fn product(a: MatRef<'_, c64>, b: MatRef<'_, c64>) -> Mat<c64> {
    let mut out = Mat::zeros(a.nrows(), b.ncols());
    product_into(a, b, out.as_mut());
    out
}

/// [`product`] into `out` (a.nrows() × b.ncols()).
fn product_into(a: MatRef<'_, c64>, b: MatRef<'_, c64>, out: MatMut<'_, c64>) {
    let par = if a.nrows() * a.ncols() * b.ncols() < PARALLEL_PRODUCT {
        Par::Seq
    } else {
        faer::get_global_parallelism()
    };
    matmul(out, Accum::Replace, a, b, c64::new(1.0, 0.0), par);
}

/// a v for a complex matrix and vector.
fn times(a: &Mat<c64>, v: &[c64]) -> Vec<c64> {
    let av = product(a.as_ref(), MatRef::from_column_major_slice(v, v.len(), 1));
    (0..av.nrows()).map(|i| av[(i, 0)]).collect()
}

/// max_j Σ_i (|Re a_ij| + |Im a_ij|): the 1-norm of the real 2×2-block form of a complex matrix.
fn real_layout_norm_1(a: &Mat<c64>) -> f64 {
    (0..a.ncols())
        .map(|j| {
            (0..a.nrows())
                .map(|i| a[(i, j)].re.abs() + a[(i, j)].im.abs())
                .sum::<f64>()
        })
        .fold(0.0, f64::max)
}

/// One harmonic n condensed on the nonlinear DOFs at one frequency (eqs. 16–18).
#[derive(Clone, Debug)]
pub struct Condensed {
    /// D̄⁽ⁿ⁾ = D_NN − D_NL D_LL⁻¹ D_LN (N/m), n_N × n_N.
    pub stiffness: Mat<c64>,
    /// F̄_e⁽ⁿ⁾ = F_eN − D_NL D_LL⁻¹ F_eL (N), length n_N.
    pub force: Vec<c64>,
    /// ∂D̄⁽ⁿ⁾/∂ω (N·s/m).
    pub stiffness_derivative: Mat<c64>,
    /// ∂F̄_e⁽ⁿ⁾/∂ω (N·s).
    pub force_derivative: Vec<c64>,
    /// Response recovery (eq. 18): Q_out = `recovery_offset` + `recovery` · Q_N, n_out × n_N.
    pub recovery: Mat<c64>,
    /// Response of the output DOFs with Q_N = 0 (m), length n_out.
    pub recovery_offset: Vec<c64>,
}

impl Condensed {
    /// The complex harmonic n of the output DOFs for the nonlinear-DOF harmonic `q_n` (eq. 18).
    pub fn recover(&self, q_n: &[c64]) -> Vec<c64> {
        recover(&self.recovery, &self.recovery_offset, q_n)
    }
}

/// The complex harmonic of the output DOFs for the nonlinear-DOF harmonic `q_n` (eq. 18):
/// `offset` + `recovery` · `q_n` ([`LinearModel::recovery`]).
pub fn recover(recovery: &Mat<c64>, offset: &[c64], q_n: &[c64]) -> Vec<c64> {
    (0..recovery.nrows())
        .map(|i| {
            let mut v = offset[i];
            for (j, q) in q_n.iter().enumerate() {
                v += recovery[(i, j)] * q;
            }
            v
        })
        .collect()
}

/// The linear structure of a harmonic balance problem: per harmonic n = 0..H its matrix block
/// and excitation.
#[derive(Clone, Debug)]
pub struct LinearModel {
    blocks: Vec<Arc<Partitioned>>,
    /// Block used by harmonic n (length H+1).
    harmonic_block: Vec<usize>,
    /// F_e⁽ⁿ⁾ over the rows of the harmonic's block (N); empty = no excitation on harmonic n.
    forcing: Vec<Vec<c64>>,
    n_condensed: usize,
    n_outputs: usize,
    /// D̄⁽⁰⁾ and F̄⁽⁰⁾ of the static harmonic, which do not depend on ω (s = 0·ω): condensed
    /// once, on first use.
    static_condensed: OnceLock<Arc<(Mat<c64>, Vec<c64>)>>,
    /// ‖D̄⁽ⁿ⁾‖₁ of the real layout per harmonic n at the last frequency D̄⁽ⁿ⁾ was formed at by a
    /// [`HarmonicOperator`] (NaN before): the scale of backward errors of products with it.
    norms: Arc<Mutex<Vec<f64>>>,
}

impl LinearModel {
    /// A model from matrix blocks: harmonic n = 0..H uses `blocks[harmonic_block[n]]` and is
    /// excited by `forcing[n]` (complex amplitude per row of that block, N; empty for none).
    /// Every block must list the same number of nonlinear and output rows, and the block of
    /// n = 0 must be real (the static coefficient is real). The blocks are taken one at a time
    /// and dropped once split, so that a lazy iterator holds one block's matrices beside the
    /// model at most.
    pub fn new(
        blocks: impl IntoIterator<Item = MatrixBlock>,
        harmonic_block: Vec<usize>,
        forcing: Vec<Vec<c64>>,
    ) -> Result<LinearModel> {
        if harmonic_block.is_empty() || forcing.len() != harmonic_block.len() {
            return Err(Error::input(format!(
                "the linear model needs one block index and one forcing per harmonic 0..H ({} and {} given)",
                harmonic_block.len(),
                forcing.len()
            )));
        }
        let mut parts: Vec<Arc<Partitioned>> = Vec::new();
        let (mut n_condensed, mut n_outputs) = (0, 0);
        for (b, block) in blocks.into_iter().enumerate() {
            if b == 0 {
                n_condensed = block.nonlinear.len();
                n_outputs = block.outputs.len();
            }
            if b == harmonic_block[0] {
                check_static_block_real(&block, &forcing[0])?;
            }
            parts.push(Arc::new(partition(b, &block, n_condensed, n_outputs)?));
        }
        if parts.is_empty() {
            return Err(Error::input("the linear model has no matrix block"));
        }
        for (n, (&b, f)) in harmonic_block.iter().zip(&forcing).enumerate() {
            let part = parts.get(b).ok_or_else(|| {
                Error::input(format!(
                    "harmonic {n} uses matrix block {b}, but there are {} blocks",
                    parts.len()
                ))
            })?;
            if !f.is_empty() && f.len() != part.n_rows {
                return Err(Error::input(format!(
                    "the excitation of harmonic {n} has {} entries for a block of {} rows",
                    f.len(),
                    part.n_rows
                )));
            }
        }
        let norms = Arc::new(Mutex::new(vec![f64::NAN; harmonic_block.len()]));
        Ok(LinearModel {
            blocks: parts,
            harmonic_block,
            forcing,
            n_condensed,
            n_outputs,
            static_condensed: OnceLock::new(),
            norms,
        })
    }

    /// A model without cyclic symmetry: real K, M, C used by every harmonic, excited by the real
    /// amplitude `force` (N per row) on harmonic 1, f(t) = force·cos(ωt).
    pub fn from_real(
        stiffness: MatRef<'_, f64>,
        mass: MatRef<'_, f64>,
        damping: Option<MatRef<'_, f64>>,
        force: &[f64],
        nonlinear: Vec<usize>,
        outputs: Vec<usize>,
        harmonics: usize,
    ) -> Result<LinearModel> {
        let complex = |a: MatRef<'_, f64>| {
            Mat::from_fn(a.nrows(), a.ncols(), |i, j| c64::new(a[(i, j)], 0.0))
        };
        let block = MatrixBlock {
            stiffness: complex(stiffness),
            mass: complex(mass),
            damping: damping.map(complex),
            nonlinear,
            outputs,
        };
        let mut forcing = vec![Vec::new(); harmonics + 1];
        if harmonics >= 1 {
            forcing[1] = force.iter().map(|&f| c64::new(f, 0.0)).collect();
        }
        LinearModel::new(vec![block], vec![0; harmonics + 1], forcing)
    }

    /// Highest harmonic H.
    pub fn harmonics(&self) -> usize {
        self.harmonic_block.len() - 1
    }

    /// Number of nonlinear (condensed) DOFs n_N.
    pub fn n_condensed(&self) -> usize {
        self.n_condensed
    }

    /// Number of output DOFs.
    pub fn n_outputs(&self) -> usize {
        self.n_outputs
    }

    /// The most rows of any matrix block (condensed and linear DOFs): the size of the largest
    /// per-harmonic condensation.
    pub fn block_rows(&self) -> usize {
        self.blocks.iter().map(|b| b.n_rows).max().unwrap_or(0)
    }

    /// Euclidean norm of the (uncondensed) excitation over all harmonics in the real layout (N):
    /// the force level the residual is scaled by.
    pub fn force_norm(&self) -> f64 {
        self.forcing
            .iter()
            .flat_map(|f| f.iter())
            .map(|f| f.norm_sqr())
            .sum::<f64>()
            .sqrt()
    }

    /// The uncondensed K, M, C of harmonic n's block, ordered [nonlinear; linear].
    pub fn uncondensed(&self, n: usize) -> Uncondensed {
        let part = &self.blocks[self.harmonic_block[n]];
        let size = part.n_rows;
        Uncondensed {
            stiffness: part.k.joined(),
            mass: part.m.joined(),
            damping: part
                .c
                .as_ref()
                .map_or_else(|| Mat::zeros(size, size), Split::joined),
        }
    }

    /// The excitation of harmonic n on the nonlinear and on the linear rows of its block.
    fn forcing_parts(&self, n: usize) -> (Vec<c64>, Vec<c64>) {
        let part = &self.blocks[self.harmonic_block[n]];
        let force = &self.forcing[n];
        let f_at = |rows: &[usize]| -> Vec<c64> {
            if force.is_empty() {
                vec![c64::new(0.0, 0.0); rows.len()]
            } else {
                rows.iter().map(|&r| force[r]).collect()
            }
        };
        (f_at(&part.nonlinear), f_at(&part.linear))
    }

    /// Harmonic n condensed at ω (rad/s) for one evaluation of the residual at the harmonic
    /// `q_n` of the nonlinear DOFs: D̄⁽ⁿ⁾ and F̄⁽ⁿ⁾ as [`LinearModel::condense`], but of the
    /// ω-derivatives only the products ∂D̄⁽ⁿ⁾/∂ω q_n and ∂F̄⁽ⁿ⁾/∂ω, by matrix–vector products
    /// (differentiating eq. 16: ∂D̄/∂ω q = D'_NN q − D'_NL v − D_NL D_LL⁻¹(D'_LN q − D'_LL v) with
    /// v = D_LL⁻¹ D_LN q), without the three n_N × n_L × n_N products of the full ∂D̄/∂ω.
    pub fn condense_applied(&self, n: usize, omega: f64, q_n: &[c64]) -> Result<CondensedApplied> {
        if n == 0 {
            let (stiffness, force) = &**self.static_condensed()?;
            let zero = vec![c64::new(0.0, 0.0); self.n_condensed];
            return Ok(CondensedApplied {
                stiffness: stiffness.clone(),
                force: force.clone(),
                stiffness_derivative_q: zero.clone(),
                force_derivative: zero,
            });
        }
        let part = &self.blocks[self.harmonic_block[n]];
        let s = n as f64 * omega;
        let nf = n as f64;
        let (f_n, f_l) = self.forcing_parts(n);
        let n_n = part.nonlinear.len();
        let n_l = part.linear.len();
        let d_nn = part.dynamic(Part::NN, s);
        let dd_nn = part.dynamic_derivative(Part::NN, nf, omega);
        let q = MatRef::from_column_major_slice(q_n, n_n, 1);
        let dd_nn_q = product(dd_nn.as_ref(), q);
        if n_l == 0 {
            return Ok(CondensedApplied {
                stiffness: d_nn,
                force: f_n,
                stiffness_derivative_q: (0..n_n).map(|i| dd_nn_q[(i, 0)]).collect(),
                force_derivative: vec![c64::new(0.0, 0.0); n_n],
            });
        }
        let (lu, xw) = solve_ll(part, n, omega, &f_l)?;
        let d_nl = part.dynamic(Part::NL, s);
        let nl_xw = product(d_nl.as_ref(), xw.as_ref());
        let stiffness = Mat::from_fn(n_n, n_n, |i, j| d_nn[(i, j)] - nl_xw[(i, j)]);
        let force_c: Vec<c64> = (0..n_n).map(|i| f_n[i] - nl_xw[(i, n_n)]).collect();
        // [v | w] and t = D_LL⁻¹ [D'_LN q − D'_LL v | −D'_LL w]
        let vw = Mat::from_fn(n_l, 2, |i, j| {
            if j == 0 {
                (0..n_n).map(|k| xw[(i, k)] * q_n[k]).sum()
            } else {
                xw[(i, n_n)]
            }
        });
        let dd_ll = part.dynamic_derivative(Part::LL, nf, omega);
        let dd_ln = part.dynamic_derivative(Part::LN, nf, omega);
        let dd_nl = part.dynamic_derivative(Part::NL, nf, omega);
        let ll_vw = product(dd_ll.as_ref(), vw.as_ref());
        let ln_q = product(dd_ln.as_ref(), q);
        let mut t = Mat::from_fn(n_l, 2, |i, j| {
            let ln = if j == 0 {
                ln_q[(i, 0)]
            } else {
                c64::new(0.0, 0.0)
            };
            ln - ll_vw[(i, j)]
        });
        lu.solve_in_place(t.as_mut());
        let nl_vw = product(dd_nl.as_ref(), vw.as_ref());
        let nl_t = product(d_nl.as_ref(), t.as_ref());
        Ok(CondensedApplied {
            stiffness,
            force: force_c,
            stiffness_derivative_q: (0..n_n)
                .map(|i| dd_nn_q[(i, 0)] - nl_vw[(i, 0)] - nl_t[(i, 0)])
                .collect(),
            force_derivative: (0..n_n).map(|i| -nl_vw[(i, 1)] - nl_t[(i, 1)]).collect(),
        })
    }

    /// [`LinearModel::condense_applied`] into `out` (its matrix n_N × n_N, its vectors resized)
    /// with the buffers `b`, both reused from one evaluation to the next: the same operations
    /// (faer's products and LU, on views of the buffers) in the same order, so the same values
    /// bit for bit, without a matrix or vector made per evaluation. For small models, where
    /// the products are of a few entries and making their matrices costs more than the
    /// arithmetic. Fails as [`LinearModel::condense`].
    pub fn condense_small(
        &self,
        n: usize,
        omega: f64,
        q_n: &[c64],
        out: &mut CondensedApplied,
        b: &mut SmallBuffers,
    ) -> Result<()> {
        let n_n = self.n_condensed;
        let zero = c64::new(0.0, 0.0);
        if out.stiffness.nrows() != n_n || out.stiffness.ncols() != n_n {
            out.stiffness = Mat::zeros(n_n, n_n);
        }
        for v in [
            &mut out.force,
            &mut out.stiffness_derivative_q,
            &mut out.force_derivative,
        ] {
            v.clear();
            v.resize(n_n, zero);
        }
        if n == 0 {
            let (stiffness, force) = &**self.static_condensed()?;
            out.stiffness.copy_from(stiffness);
            out.force.copy_from_slice(force);
            return Ok(());
        }
        let part = &self.blocks[self.harmonic_block[n]];
        let (s, nf) = (n as f64 * omega, n as f64);
        let n_l = part.linear.len();
        b.resize(n_l, n_n);
        let forcing = &self.forcing[n];
        let f_at = |row: usize| forcing.get(row).copied().unwrap_or(zero);
        let SmallBuffers {
            lu,
            stack,
            xw,
            d_nl,
            dd_nn,
            dd_ll,
            dd_ln,
            dd_nl,
            vw,
            t,
            nl_xw,
            ll_vw,
            ln_q,
            nl_vw,
            nl_t,
        } = b;
        let q = MatRef::from_column_major_slice(q_n, n_n, 1);
        let (k, m, c) = part.views(Part::NN);
        for i in 0..n_n {
            for j in 0..n_n {
                out.stiffness[(i, j)] = dynamic_entry(k, m, c, i, j, s);
                dd_nn[(i, j)] = derivative_entry(m, c, i, j, nf, omega);
            }
            out.force[i] = f_at(part.nonlinear[i]);
        }
        let sdq = MatMut::from_column_major_slice_mut(&mut out.stiffness_derivative_q, n_n, 1);
        product_into(dd_nn.as_ref(), q, sdq);
        if n_l == 0 {
            return Ok(());
        }
        // the LU of D_LL and [X | w] = D_LL⁻¹ [D_LN | F_L] (`solve_ll`)
        let par = faer::get_global_parallelism();
        lu.refactor(n_l, par, stack, |ll| part.dynamic_into(Part::LL, s, ll));
        if !regular_pivots((0..n_l).map(|i| lu.pivot(i).norm())) {
            return Err(singular_ll(n, omega));
        }
        let (k, m, c) = part.views(Part::LN);
        for i in 0..n_l {
            for j in 0..n_n {
                xw[(i, j)] = dynamic_entry(k, m, c, i, j, s);
            }
            xw[(i, n_n)] = f_at(part.linear[i]);
        }
        lu.solve_in_place_with(xw.as_mut(), par, stack);
        // D̄ = D_NN − D_NL X, F̄ = F_N − D_NL w
        part.dynamic_into(Part::NL, s, d_nl);
        product_into(d_nl.as_ref(), xw.as_ref(), nl_xw.as_mut());
        for i in 0..n_n {
            for j in 0..n_n {
                out.stiffness[(i, j)] -= nl_xw[(i, j)];
            }
            out.force[i] -= nl_xw[(i, n_n)];
        }
        // [v | w] and t = D_LL⁻¹ [D'_LN q − D'_LL v | −D'_LL w]
        for i in 0..n_l {
            vw[(i, 0)] = (0..n_n).map(|k| xw[(i, k)] * q_n[k]).sum();
            vw[(i, 1)] = xw[(i, n_n)];
        }
        part.derivative_into(Part::LL, nf, omega, dd_ll);
        part.derivative_into(Part::LN, nf, omega, dd_ln);
        part.derivative_into(Part::NL, nf, omega, dd_nl);
        product_into(dd_ll.as_ref(), vw.as_ref(), ll_vw.as_mut());
        product_into(dd_ln.as_ref(), q, ln_q.as_mut());
        for i in 0..n_l {
            t[(i, 0)] = ln_q[(i, 0)] - ll_vw[(i, 0)];
            t[(i, 1)] = zero - ll_vw[(i, 1)];
        }
        lu.solve_in_place_with(t.as_mut(), par, stack);
        product_into(dd_nl.as_ref(), vw.as_ref(), nl_vw.as_mut());
        product_into(d_nl.as_ref(), t.as_ref(), nl_t.as_mut());
        for i in 0..n_n {
            let sdq = out.stiffness_derivative_q[i];
            out.stiffness_derivative_q[i] = sdq - nl_vw[(i, 0)] - nl_t[(i, 0)];
            out.force_derivative[i] = -nl_vw[(i, 1)] - nl_t[(i, 1)];
        }
        Ok(())
    }

    /// The condensed residual of harmonic n at ω (rad/s), D̄⁽ⁿ⁾ q_n − `level` F̄⁽ⁿ⁾ (eqs. 16–17),
    /// without forming D̄⁽ⁿ⁾: D_NN q_n − level F_N − D_NL D_LL⁻¹ (D_LN q_n − level F_L), by
    /// matrix–vector products and one LU of D_LL (for a residual alone, e.g. a damping trial of
    /// Newton: (8/3) n_L³ flops against the 8 n_N² n_L of the product D_NL D_LL⁻¹ D_LN of
    /// [`LinearModel::condense_applied`]). Fails as [`LinearModel::condense`].
    pub fn condensed_residual(
        &self,
        n: usize,
        omega: f64,
        q_n: &[c64],
        level: f64,
    ) -> Result<Vec<c64>> {
        if n == 0 {
            let (stiffness, force) = &**self.static_condensed()?;
            let q = MatRef::from_column_major_slice(q_n, q_n.len(), 1);
            let kq = product(stiffness.as_ref(), q);
            return Ok((0..q_n.len())
                .map(|i| kq[(i, 0)] - force[i] * level)
                .collect());
        }
        let part = &self.blocks[self.harmonic_block[n]];
        let s = n as f64 * omega;
        let (f_n, f_l) = self.forcing_parts(n);
        let mut r = part.dynamic_times(Part::NN, s, q_n);
        r.iter_mut().zip(&f_n).for_each(|(r, f)| *r -= f * level);
        if part.linear.is_empty() {
            return Ok(r);
        }
        let lu = factor(part.dynamic(Part::LL, s), n, omega)?;
        let ln_q = part.dynamic_times(Part::LN, s, q_n);
        let mut t = Mat::from_fn(ln_q.len(), 1, |i, _| ln_q[i] - f_l[i] * level);
        lu.solve_in_place(t.as_mut());
        let t: Vec<c64> = (0..t.nrows()).map(|i| t[(i, 0)]).collect();
        let nl_t = part.dynamic_times(Part::NL, s, &t);
        r.iter_mut().zip(nl_t).for_each(|(r, v)| *r -= v);
        Ok(r)
    }

    /// D̄⁽⁰⁾ = K_NN − K_NL K_LL⁻¹ K_LN and F̄⁽⁰⁾ (eqs. 16–17 at s = 0), condensed on the first
    /// call and kept (the static harmonic does not depend on ω).
    fn static_condensed(&self) -> Result<&Arc<(Mat<c64>, Vec<c64>)>> {
        if let Some(c) = self.static_condensed.get() {
            return Ok(c);
        }
        let c = self.condense(0, 0.0)?;
        Ok(self
            .static_condensed
            .get_or_init(|| Arc::new((c.stiffness, c.force))))
    }

    /// Harmonic n at ω (rad/s) for one evaluation of the residual at the harmonic `q_n` of the
    /// nonlinear DOFs, without forming D̄⁽ⁿ⁾: D̄⁽ⁿ⁾ q_n, F̄⁽ⁿ⁾ and the ω-derivatives
    /// ∂D̄⁽ⁿ⁾/∂ω q_n, ∂F̄⁽ⁿ⁾/∂ω of [`LinearModel::condense_applied`] by matrix–vector products
    /// on one LU of D_LL (eqs. 16–17: D̄ q = D_NN q − D_NL v with v = D_LL⁻¹ D_LN q; the
    /// derivative as in [`LinearModel::condense_applied`]), and the [`HarmonicOperator`] that
    /// applies D̄⁽ⁿ⁾ to further vectors on the same LU, or forms it. That costs (8/3) n_L³ flops
    /// and products of order n_N² and n_L², against the 8 n_N² n_L of the product
    /// D_NL D_LL⁻¹ D_LN, which is left to the evaluations whose matrix is factorised. Fails as
    /// [`LinearModel::condense`].
    pub fn condense_deferred(
        &self,
        n: usize,
        omega: f64,
        q_n: &[c64],
    ) -> Result<(Applied, HarmonicOperator)> {
        let slot = (self.norms.clone(), n);
        if n == 0 {
            let c = self.static_condensed()?.clone();
            let zero = vec![c64::new(0.0, 0.0); self.n_condensed];
            let q = MatRef::from_column_major_slice(q_n, q_n.len(), 1);
            let kq = product(c.0.as_ref(), q);
            let applied = Applied {
                stiffness_q: (0..q_n.len()).map(|i| kq[(i, 0)]).collect(),
                force: c.1.clone(),
                stiffness_derivative_q: zero.clone(),
                force_derivative: zero,
            };
            let op = HarmonicOperator {
                kind: OperatorKind::Static(c),
                norm: slot,
            };
            return Ok((applied, op));
        }
        let part = &self.blocks[self.harmonic_block[n]];
        let s = n as f64 * omega;
        let nf = n as f64;
        let (f_n, f_l) = self.forcing_parts(n);
        let n_n = part.nonlinear.len();
        // D_NN, D_NL, D_LN formed once: the operator's products read them (one complex matrix
        // each instead of K, M and C)
        let d_nn = part.dynamic(Part::NN, s);
        let mut stiffness_q = times(&d_nn, q_n);
        let mut stiffness_derivative_q = part.dynamic_derivative_times(Part::NN, nf, omega, q_n);
        if part.linear.is_empty() {
            let applied = Applied {
                stiffness_q,
                force: f_n,
                stiffness_derivative_q,
                force_derivative: vec![c64::new(0.0, 0.0); n_n],
            };
            let op = HarmonicOperator {
                kind: OperatorKind::Dynamic {
                    d_nn,
                    coupling: None,
                },
                norm: slot,
            };
            return Ok((applied, op));
        }
        let n_l = part.linear.len();
        let lu = factor(part.dynamic(Part::LL, s), n, omega)?;
        let (d_nl, d_ln) = (part.dynamic(Part::NL, s), part.dynamic(Part::LN, s));
        // [v | w] = D_LL⁻¹ [D_LN q | F_L]
        let ln_q = times(&d_ln, q_n);
        let mut vw = Mat::from_fn(n_l, 2, |i, j| if j == 0 { ln_q[i] } else { f_l[i] });
        lu.solve_in_place(vw.as_mut());
        let col =
            |m: &Mat<c64>, j: usize| -> Vec<c64> { (0..m.nrows()).map(|i| m[(i, j)]).collect() };
        let (v, w) = (col(&vw, 0), col(&vw, 1));
        let nl_v = times(&d_nl, &v);
        let nl_w = times(&d_nl, &w);
        stiffness_q.iter_mut().zip(&nl_v).for_each(|(a, b)| *a -= b);
        let force: Vec<c64> = f_n.iter().zip(&nl_w).map(|(a, b)| a - b).collect();
        // t = D_LL⁻¹ [D'_LN q − D'_LL v | −D'_LL w]
        let dln_q = part.dynamic_derivative_times(Part::LN, nf, omega, q_n);
        let dll_v = part.dynamic_derivative_times(Part::LL, nf, omega, &v);
        let dll_w = part.dynamic_derivative_times(Part::LL, nf, omega, &w);
        let mut t = Mat::from_fn(n_l, 2, |i, j| {
            if j == 0 {
                dln_q[i] - dll_v[i]
            } else {
                -dll_w[i]
            }
        });
        lu.solve_in_place(t.as_mut());
        let nl_t0 = times(&d_nl, &col(&t, 0));
        let nl_t1 = times(&d_nl, &col(&t, 1));
        let dnl_v = part.dynamic_derivative_times(Part::NL, nf, omega, &v);
        let dnl_w = part.dynamic_derivative_times(Part::NL, nf, omega, &w);
        for i in 0..n_n {
            stiffness_derivative_q[i] -= dnl_v[i] + nl_t0[i];
        }
        let force_derivative = (0..n_n).map(|i| -dnl_w[i] - nl_t1[i]).collect();
        let applied = Applied {
            stiffness_q,
            force,
            stiffness_derivative_q,
            force_derivative,
        };
        let op = HarmonicOperator {
            kind: OperatorKind::Dynamic {
                d_nn,
                coupling: Some(Box::new(Coupling { d_nl, d_ln, lu })),
            },
            norm: slot,
        };
        Ok((applied, op))
    }

    /// The response recovery of harmonic n at ω (rad/s) alone (eq. 18): the recovery matrix and
    /// offset of [`Condensed`], the same values as [`LinearModel::condense`] gives, without the
    /// condensed matrices and their ω-derivatives. Fails as [`LinearModel::condense`].
    pub fn recovery(&self, n: usize, omega: f64) -> Result<(Mat<c64>, Vec<c64>)> {
        let part = &self.blocks[self.harmonic_block[n]];
        if part.linear.is_empty() {
            let zero = vec![c64::new(0.0, 0.0); part.outputs.len()];
            return Ok((output_recovery(part, None), zero));
        }
        let (_, f_l) = self.forcing_parts(n);
        let (_, xw) = solve_ll(part, n, omega, &f_l)?;
        Ok(recovery_of(part, &xw))
    }

    /// Harmonic n condensed on the nonlinear DOFs at ω (rad/s), with its ω-derivatives and the
    /// response recovery (eqs. 16–18). Fails when D_LL⁽ⁿ⁾ is singular (ω·n at a natural frequency
    /// of the undamped linear partition with the nonlinear DOFs fixed).
    pub fn condense(&self, n: usize, omega: f64) -> Result<Condensed> {
        let part = &self.blocks[self.harmonic_block[n]];
        let s = n as f64 * omega;
        let nf = n as f64;
        let (f_n, f_l) = self.forcing_parts(n);
        let n_n = part.nonlinear.len();
        let n_l = part.linear.len();
        let d_nn = part.dynamic(Part::NN, s);
        let dd_nn = part.dynamic_derivative(Part::NN, nf, omega);
        if n_l == 0 {
            return Ok(Condensed {
                stiffness: d_nn,
                force: f_n,
                stiffness_derivative: dd_nn,
                force_derivative: vec![c64::new(0.0, 0.0); n_n],
                recovery: output_recovery(part, None),
                recovery_offset: vec![c64::new(0.0, 0.0); part.outputs.len()],
            });
        }
        let (lu, xw) = solve_ll(part, n, omega, &f_l)?;
        let d_nl = part.dynamic(Part::NL, s);
        let dd_nl = part.dynamic_derivative(Part::NL, nf, omega);
        let dd_ln = part.dynamic_derivative(Part::LN, nf, omega);
        let dd_ll = part.dynamic_derivative(Part::LL, nf, omega);
        // Z = D_LL⁻¹ [D'_LN − D'_LL X | −D'_LL w]
        let ll_xw = product(dd_ll.as_ref(), xw.as_ref());
        let mut z = Mat::from_fn(n_l, n_n + 1, |i, j| {
            let ln = if j < n_n {
                dd_ln[(i, j)]
            } else {
                c64::new(0.0, 0.0)
            };
            ln - ll_xw[(i, j)]
        });
        lu.solve_in_place(z.as_mut());
        let nl_xw = product(d_nl.as_ref(), xw.as_ref());
        let nl_z = product(d_nl.as_ref(), z.as_ref());
        let dnl_xw = product(dd_nl.as_ref(), xw.as_ref());
        let stiffness = Mat::from_fn(n_n, n_n, |i, j| d_nn[(i, j)] - nl_xw[(i, j)]);
        let stiffness_derivative = Mat::from_fn(n_n, n_n, |i, j| {
            dd_nn[(i, j)] - dnl_xw[(i, j)] - nl_z[(i, j)]
        });
        let force_c: Vec<c64> = (0..n_n).map(|i| f_n[i] - nl_xw[(i, n_n)]).collect();
        let force_derivative: Vec<c64> = (0..n_n)
            .map(|i| -dnl_xw[(i, n_n)] - nl_z[(i, n_n)])
            .collect();
        let (recovery, recovery_offset) = recovery_of(part, &xw);
        Ok(Condensed {
            stiffness,
            force: force_c,
            stiffness_derivative,
            force_derivative,
            recovery,
            recovery_offset,
        })
    }
}

/// The response recovery of eq. 18 from [X | w] = D_LL⁻¹ [D_LN | F_L] (`xw`): the recovery
/// matrix ([`output_recovery`]) and the response of the outputs with Q_N = 0.
fn recovery_of(part: &Partitioned, xw: &Mat<c64>) -> (Mat<c64>, Vec<c64>) {
    let n_n = part.nonlinear.len();
    let recovery = output_recovery(part, Some(xw.as_ref()));
    let offset = part
        .outputs
        .iter()
        .map(|r| match part.linear.binary_search(r) {
            Ok(l) => xw[(l, n_n)],
            Err(_) => c64::new(0.0, 0.0),
        })
        .collect();
    (recovery, offset)
}

/// Buffers of [`LinearModel::condense_small`], of the shapes [`LinearModel::condense_applied`]
/// forms: the LU factors of D_LL (n_L × n_L), its row permutation and the scratch of faer's LU
/// and solves, [X | w] (n_L × (n_N + 1)), D_NL, the ω-derivatives ∂D/∂ω of the partitions,
/// [v | w] and t (n_L × 2), and the products D_NL [X | w], D'_LL [v | w], D'_LN q,
/// D'_NL [v | w] and D_NL t.
#[derive(Debug)]
pub struct SmallBuffers {
    lu: PackedLu<c64>,
    stack: Vec<MaybeUninit<u8>>,
    xw: Mat<c64>,
    d_nl: Mat<c64>,
    dd_nn: Mat<c64>,
    dd_ll: Mat<c64>,
    dd_ln: Mat<c64>,
    dd_nl: Mat<c64>,
    vw: Mat<c64>,
    t: Mat<c64>,
    nl_xw: Mat<c64>,
    ll_vw: Mat<c64>,
    ln_q: Mat<c64>,
    nl_vw: Mat<c64>,
    nl_t: Mat<c64>,
}

impl Default for SmallBuffers {
    /// Empty buffers (sized on first use).
    fn default() -> SmallBuffers {
        let empty = || Mat::zeros(0, 0);
        SmallBuffers {
            lu: PackedLu::empty(),
            stack: Vec::new(),
            xw: empty(),
            d_nl: empty(),
            dd_nn: empty(),
            dd_ll: empty(),
            dd_ln: empty(),
            dd_nl: empty(),
            vw: empty(),
            t: empty(),
            nl_xw: empty(),
            ll_vw: empty(),
            ln_q: empty(),
            nl_vw: empty(),
            nl_t: empty(),
        }
    }
}

impl SmallBuffers {
    /// Sizes the buffers for n_L linear and n_N nonlinear DOFs (kept when they fit).
    fn resize(&mut self, n_l: usize, n_n: usize) {
        for (a, rows, cols) in [
            (&mut self.xw, n_l, n_n + 1),
            (&mut self.d_nl, n_n, n_l),
            (&mut self.dd_nn, n_n, n_n),
            (&mut self.dd_ll, n_l, n_l),
            (&mut self.dd_ln, n_l, n_n),
            (&mut self.dd_nl, n_n, n_l),
            (&mut self.vw, n_l, 2),
            (&mut self.t, n_l, 2),
            (&mut self.nl_xw, n_n, n_n + 1),
            (&mut self.ll_vw, n_l, 2),
            (&mut self.ln_q, n_l, 1),
            (&mut self.nl_vw, n_n, 2),
            (&mut self.nl_t, n_n, 2),
        ] {
            if a.nrows() != rows || a.ncols() != cols {
                *a = Mat::zeros(rows, cols);
            }
        }
    }
}

/// Recovery matrix of the outputs: a unit row for an output that is a nonlinear DOF, −X of its
/// linear row otherwise (eq. 18, X = D_LL⁻¹ D_LN stored in the first n_N columns of `xw`).
fn output_recovery(part: &Partitioned, xw: Option<MatRef<'_, c64>>) -> Mat<c64> {
    let n_n = part.nonlinear.len();
    let mut r = Mat::<c64>::zeros(part.outputs.len(), n_n);
    for (o, row) in part.outputs.iter().enumerate() {
        if let Some(j) = part.nonlinear.iter().position(|x| x == row) {
            r[(o, j)] = c64::new(1.0, 0.0);
        } else if let (Some(xw), Ok(l)) = (xw, part.linear.binary_search(row)) {
            for j in 0..n_n {
                r[(o, j)] = -xw[(l, j)];
            }
        }
    }
    r
}

/// The LU of D_LL⁽ⁿ⁾ at ω and [X | w] = D_LL⁻¹ [D_LN | F_L] (eq. 16).
fn solve_ll(
    part: &Partitioned,
    n: usize,
    omega: f64,
    f_l: &[c64],
) -> Result<(PackedLu<c64>, Mat<c64>)> {
    let s = n as f64 * omega;
    let n_n = part.nonlinear.len();
    let lu = factor(part.dynamic(Part::LL, s), n, omega)?;
    let d_ln = part.dynamic(Part::LN, s);
    let mut xw = Mat::<c64>::zeros(part.linear.len(), n_n + 1);
    xw.as_mut().subcols_mut(0, n_n).copy_from(&d_ln);
    for (i, f) in f_l.iter().enumerate() {
        xw[(i, n_n)] = *f;
    }
    lu.solve_in_place(xw.as_mut());
    Ok((lu, xw))
}

/// LU of D_LL⁽ⁿ⁾ with a check on the pivots (relative 1e-13) for singularity.
fn factor(d: Mat<c64>, n: usize, omega: f64) -> Result<PackedLu<c64>> {
    let lu = PackedLu::in_place(d);
    if !regular_pivots((0..lu.nrows()).map(|i| lu.pivot(i).norm())) {
        return Err(singular_ll(n, omega));
    }
    Ok(lu)
}

/// Whether the moduli of the pivots of an LU show a regular matrix (the smallest above 1e-13
/// times the largest).
fn regular_pivots(moduli: impl Iterator<Item = f64>) -> bool {
    let (min, max) = moduli.fold((f64::INFINITY, 0.0_f64), |(lo, hi), v| {
        (lo.min(v), hi.max(v))
    });
    min > 1e-13 * max
}

/// The error of a singular D_LL of harmonic n at ω (rad/s).
fn singular_ll(n: usize, omega: f64) -> Error {
    Error::Compute(format!(
        "condensation: the linear partition's dynamic stiffness D_LL of harmonic {n} is singular at ω = {omega} rad/s (n·ω at a natural frequency of the structure with the nonlinear DOFs fixed, or a free-floating part); add damping or change the frequency range"
    ))
}

/// Splits a block; checks sizes and rows.
fn partition(
    b: usize,
    block: &MatrixBlock,
    n_condensed: usize,
    n_outputs: usize,
) -> Result<Partitioned> {
    let n = block.stiffness.nrows();
    let square = |a: &Mat<c64>| a.nrows() == n && a.ncols() == n;
    let sizes_ok = square(&block.stiffness)
        && square(&block.mass)
        && block.damping.as_ref().is_none_or(square);
    if !sizes_ok {
        return Err(Error::input(format!(
            "matrix block {b}: K, M and C must be square and of the same size ({n})"
        )));
    }
    if block.nonlinear.len() != n_condensed || block.outputs.len() != n_outputs {
        return Err(Error::input(format!(
            "matrix block {b} has {} nonlinear and {} output rows; block 0 has {n_condensed} and {n_outputs}",
            block.nonlinear.len(),
            block.outputs.len()
        )));
    }
    let mut is_nonlinear = vec![false; n];
    for &r in &block.nonlinear {
        if r >= n || is_nonlinear[r] {
            return Err(Error::input(format!(
                "matrix block {b}: nonlinear row {r} is out of range (0..{n}) or listed twice"
            )));
        }
        is_nonlinear[r] = true;
    }
    if let Some(&r) = block.outputs.iter().find(|&&r| r >= n) {
        return Err(Error::input(format!(
            "matrix block {b}: output row {r} is out of range (0..{n})"
        )));
    }
    let linear: Vec<usize> = (0..n).filter(|&r| !is_nonlinear[r]).collect();
    let nl = &block.nonlinear;
    Ok(Partitioned {
        k: Split::new(block.stiffness.as_ref(), nl, &linear),
        m: Split::new(block.mass.as_ref(), nl, &linear),
        c: block
            .damping
            .as_ref()
            .map(|c| Split::new(c.as_ref(), nl, &linear)),
        linear,
        nonlinear: nl.clone(),
        outputs: block.outputs.clone(),
        n_rows: n,
    })
}

/// The static harmonic (n = 0) has real coefficients: its K and forcing must be real.
fn check_static_block_real(block: &MatrixBlock, force: &[c64]) -> Result<()> {
    let k = &block.stiffness;
    let scale = (0..k.nrows()).map(|i| k[(i, i)].norm()).fold(0.0, f64::max);
    let imag = (0..k.nrows())
        .flat_map(|i| (0..k.ncols()).map(move |j| (i, j)))
        .map(|(i, j)| k[(i, j)].im.abs())
        .fold(0.0, f64::max);
    if imag > 1e-12 * scale || force.iter().any(|f| f.im != 0.0) {
        return Err(Error::input(
            "harmonic 0 (the static part) must use real matrices and a real force (harmonic index k = 0)",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::linalg::solvers::Solve;

    /// Deterministic numbers in [−0.5, 0.5).
    fn noise(seed: usize) -> f64 {
        let s = (seed as u64)
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((s >> 11) as f64 / (1u64 << 53) as f64) - 0.5
    }

    /// A damped 7-DOF model with 3 nonlinear DOFs (rows 4, 0, 2), one response DOF and H = 2:
    /// symmetric K, M (diagonals raised by 6 and 3) and C (0.05 × noise), a force on every row;
    /// `seeds` are the noise seeds of K, M, C and the force.
    fn damped_seven_dof(seeds: [usize; 4]) -> LinearModel {
        let n = 7;
        let sym = |seed: usize, diag: f64| {
            Mat::from_fn(n, n, |i, j| {
                let (a, b) = (i.min(j), i.max(j));
                noise(seed + 31 * a + b) + if i == j { diag } else { 0.0 }
            })
        };
        let (k, m, c) = (sym(seeds[0], 6.0), sym(seeds[1], 3.0), sym(seeds[2], 0.0));
        let c = Mat::from_fn(n, n, |i, j| 0.05 * c[(i, j)]);
        let force: Vec<f64> = (0..n).map(|i| noise(seeds[3] + i)).collect();
        LinearModel::from_real(
            k.as_ref(),
            m.as_ref(),
            Some(c.as_ref()),
            &force,
            vec![4, 0, 2],
            vec![1],
            2,
        )
        .unwrap()
    }

    /// The residual alone ([`LinearModel::condensed_residual`], matrix–vector products) equals
    /// D̄ q − level F̄ from the condensed matrix of [`LinearModel::condense_applied`] on a damped
    /// 7-DOF model with 3 nonlinear DOFs, forced on linear and nonlinear rows, for every
    /// harmonic 0..2 (to 1e-12 relative to ‖D̄‖∞ ‖q‖∞).
    #[test]
    fn residual_alone_matches_the_condensed_matrix() {
        let model = damped_seven_dof([1, 500, 900, 70]);
        let (omega, level) = (0.83, 1.7);
        for h in 0..=2 {
            let q: Vec<c64> = (0..3)
                .map(|i| {
                    let im = if h == 0 { 0.0 } else { noise(40 + i) };
                    c64::new(noise(20 + i), im)
                })
                .collect();
            let full = model.condense_applied(h, omega, &q).unwrap();
            let alone = model.condensed_residual(h, omega, &q, level).unwrap();
            let scale = (0..3)
                .map(|i| (0..3).map(|j| full.stiffness[(i, j)].norm()).sum::<f64>())
                .fold(0.0, f64::max)
                * q.iter().map(|v| v.norm()).fold(0.0, f64::max);
            for (i, a) in alone.iter().enumerate() {
                let expected = (0..3).map(|j| full.stiffness[(i, j)] * q[j]).sum::<c64>()
                    - full.force[i] * level;
                assert!(
                    (a - expected).norm() <= 1e-12 * scale,
                    "harmonic {h}, row {i}: {a:?} vs {expected:?}"
                );
            }
            assert_eq!(alone.len(), 3);
            if h == 1 {
                assert!(full.force.iter().any(|f| f.norm() > 0.1));
            }
        }
    }

    /// The condensation into kept buffers ([`LinearModel::condense_small`]) gives what
    /// [`LinearModel::condense_applied`] gives, bit for bit (D̄, F̄, ∂D̄/∂ω q and ∂F̄/∂ω), for
    /// every harmonic 0..2 of a damped 7-DOF model with 3 nonlinear DOFs forced on linear and
    /// nonlinear rows, at two frequencies, with the same buffers throughout.
    #[test]
    fn small_condensation_equals_the_formed_one_bit_for_bit() {
        let model = damped_seven_dof([5, 400, 650, 30]);
        let mut out = CondensedApplied {
            stiffness: Mat::zeros(0, 0),
            force: Vec::new(),
            stiffness_derivative_q: Vec::new(),
            force_derivative: Vec::new(),
        };
        let mut buffers = SmallBuffers::default();
        for omega in [0.77, 1.21] {
            for h in 0..=2 {
                let q: Vec<c64> = (0..3)
                    .map(|i| {
                        let im = if h == 0 { 0.0 } else { noise(60 + i) };
                        c64::new(noise(80 + i), im)
                    })
                    .collect();
                let full = model.condense_applied(h, omega, &q).unwrap();
                model
                    .condense_small(h, omega, &q, &mut out, &mut buffers)
                    .unwrap();
                for i in 0..3 {
                    for j in 0..3 {
                        assert_eq!(
                            out.stiffness[(i, j)],
                            full.stiffness[(i, j)],
                            "D̄ {h} {i} {j}"
                        );
                    }
                }
                assert_eq!(out.force, full.force, "F̄, harmonic {h}");
                assert_eq!(out.stiffness_derivative_q, full.stiffness_derivative_q);
                assert_eq!(out.force_derivative, full.force_derivative);
            }
        }
    }

    /// The deferred condensation ([`LinearModel::condense_deferred`]: products on the LU of
    /// D_LL) gives what the formed one gives ([`LinearModel::condense_applied`]) on a damped
    /// 7-DOF model with 3 nonlinear DOFs forced on linear and nonlinear rows, for every
    /// harmonic 0..2: D̄ q, F̄, ∂D̄/∂ω q and ∂F̄/∂ω, the operator's product with another vector
    /// and its formed matrix (to 1e-12 relative to the largest entry), and the matrix's real-
    /// layout 1-norm as the operator's norm.
    #[test]
    fn deferred_condensation_matches_the_formed_one() {
        let model = damped_seven_dof([11, 600, 800, 90]);
        let omega = 0.91;
        let close = |a: &[c64], b: &[c64], what: &str| {
            let scale = b.iter().map(|v| v.norm()).fold(1e-300, f64::max);
            for (x, y) in a.iter().zip(b) {
                assert!((x - y).norm() <= 1e-12 * scale, "{what}: {x:?} vs {y:?}");
            }
            assert_eq!(a.len(), b.len(), "{what}");
        };
        for h in 0..=2 {
            let vec_of = |seed: usize| -> Vec<c64> {
                (0..3)
                    .map(|i| {
                        let im = if h == 0 { 0.0 } else { noise(seed + 7 + i) };
                        c64::new(noise(seed + i), im)
                    })
                    .collect()
            };
            let (q, p) = (vec_of(20), vec_of(50));
            let full = model.condense_applied(h, omega, &q).unwrap();
            let (applied, op) = model.condense_deferred(h, omega, &q).unwrap();
            let times = |v: &[c64]| -> Vec<c64> {
                (0..3)
                    .map(|i| (0..3).map(|j| full.stiffness[(i, j)] * v[j]).sum())
                    .collect()
            };
            close(&applied.stiffness_q, &times(&q), "D̄ q");
            close(&applied.force, &full.force, "F̄");
            close(
                &applied.stiffness_derivative_q,
                &full.stiffness_derivative_q,
                "∂D̄/∂ω q",
            );
            close(&applied.force_derivative, &full.force_derivative, "∂F̄/∂ω");
            close(&op.apply(&p), &times(&p), "operator product");
            let formed = op.matrix();
            let flat = |a: &Mat<c64>| -> Vec<c64> {
                (0..3)
                    .flat_map(|j| (0..3).map(move |i| a[(i, j)]))
                    .collect()
            };
            close(&flat(&formed), &flat(&full.stiffness), "formed D̄");
            let norm = real_layout_norm_1(&full.stiffness);
            assert!((op.norm_1() - norm).abs() <= 1e-12 * norm, "{norm}");
        }
    }

    /// The condensed stiffness of every harmonic (the static one kept from its first use)
    /// equals the Schur complement found independently as ((D⁻¹)_NN)⁻¹ from the inverse of the
    /// whole dynamic stiffness D = K − s² M + i s C, at two frequencies (to 1e-10 relative).
    #[test]
    fn condensed_stiffness_is_the_inverse_of_the_inverse_block() {
        let n = 7;
        let sym = |seed: usize, diag: f64| {
            Mat::from_fn(n, n, |i, j| {
                let (a, b) = (i.min(j), i.max(j));
                noise(seed + 31 * a + b) + if i == j { diag } else { 0.0 }
            })
        };
        let (k, m, c) = (sym(3, 6.0), sym(300, 3.0), sym(700, 0.0));
        let c = Mat::from_fn(n, n, |i, j| 0.05 * c[(i, j)]);
        let nonlinear = vec![5, 1, 3];
        let model = LinearModel::from_real(
            k.as_ref(),
            m.as_ref(),
            Some(c.as_ref()),
            &[0.0; 7],
            nonlinear.clone(),
            vec![0],
            2,
        )
        .unwrap();
        let q = vec![c64::new(0.3, -0.2), c64::new(-0.1, 0.4), c64::new(0.2, 0.1)];
        for omega in [0.7, 1.3] {
            for h in 0..=2 {
                let s = h as f64 * omega;
                let d = Mat::from_fn(n, n, |i, j| {
                    c64::new(k[(i, j)] - s * s * m[(i, j)], s * c[(i, j)])
                });
                let inv = d.partial_piv_lu().solve(Mat::<c64>::identity(n, n));
                let block = Mat::from_fn(3, 3, |i, j| inv[(nonlinear[i], nonlinear[j])]);
                let expected = block.partial_piv_lu().solve(Mat::<c64>::identity(3, 3));
                let got = model.condense_applied(h, omega, &q).unwrap().stiffness;
                let scale = (0..3)
                    .flat_map(|i| (0..3).map(move |j| (i, j)))
                    .map(|(i, j)| expected[(i, j)].norm())
                    .fold(0.0, f64::max);
                for i in 0..3 {
                    for j in 0..3 {
                        assert!(
                            (got[(i, j)] - expected[(i, j)]).norm() <= 1e-10 * scale,
                            "ω = {omega}, harmonic {h}, ({i}, {j}): {:?} vs {:?}",
                            got[(i, j)],
                            expected[(i, j)]
                        );
                    }
                }
            }
        }
    }
}
