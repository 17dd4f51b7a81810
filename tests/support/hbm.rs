//! Test nonlinearities and helpers shared by the harmonic balance and continuation tests: a
//! grounded polynomial spring f = k1 q + k3 q³ per DOF evaluated by a direct DFT (AFT) with an
//! analytic Jacobian, and dense matrix helpers.
#![allow(dead_code)]

use faer::{c64, Mat, MatMut};
use nlrom::harmonics::{HarmonicForce, HarmonicLayout};
use nlrom::Result;

/// Grounded springs f_d(q) = k1[d] q_d + k3[d] q_d³ on each of its DOFs (N, q in m).
#[derive(Clone, Debug)]
pub struct PolynomialSprings {
    pub k1: Vec<f64>,
    pub k3: Vec<f64>,
}

/// The value at τ of basis function `c` of the real layout for one DOF: coefficient 0 is the
/// static part, 2n−1 the cosine (Re Q⁽ⁿ⁾) and 2n the −sine (Im Q⁽ⁿ⁾) of harmonic n.
pub fn basis(c: usize, tau: f64) -> f64 {
    if c == 0 {
        return 1.0;
    }
    let n = c.div_ceil(2) as f64;
    if c % 2 == 1 {
        (n * tau).cos()
    } else {
        -(n * tau).sin()
    }
}

/// The weight of sample value at τ in coefficient `c` of the forward DFT (inverse of `basis`).
pub fn projection(c: usize, tau: f64, samples: usize) -> f64 {
    let nt = samples as f64;
    if c == 0 {
        1.0 / nt
    } else {
        2.0 / nt * basis(c, tau)
    }
}

/// Index in the real layout of coefficient `c` (0..2H+1) of DOF `d` among `nd`.
pub fn layout_index(layout: &HarmonicLayout, c: usize, d: usize, nd: usize) -> usize {
    if c == 0 {
        layout.static_index(d)
    } else {
        let n = c.div_ceil(2);
        layout.cos_index(n, d, nd) + usize::from(c.is_multiple_of(2))
    }
}

impl HarmonicForce for PolynomialSprings {
    type State = ();

    fn n_dofs(&self) -> usize {
        self.k1.len()
    }

    fn initial_state(&self) {}

    fn evaluate(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        _state: &mut (),
        force: &mut [f64],
        jacobian: Option<MatMut<'_, f64>>,
    ) -> Result<()> {
        let nd = self.n_dofs();
        let nc = layout.coefficients();
        let nt = layout.time_samples;
        let mut jac = jacobian;
        for d in 0..nd {
            for k in 0..nt {
                let tau = 2.0 * std::f64::consts::PI * k as f64 / nt as f64;
                let qt: f64 = (0..nc)
                    .map(|c| q[layout_index(layout, c, d, nd)] * basis(c, tau))
                    .sum();
                let f = self.k1[d] * qt + self.k3[d] * qt * qt * qt;
                let df = self.k1[d] + 3.0 * self.k3[d] * qt * qt;
                for r in 0..nc {
                    let w = projection(r, tau, nt);
                    let ri = layout_index(layout, r, d, nd);
                    force[ri] += w * f;
                    if let Some(j) = jac.as_mut() {
                        for c in 0..nc {
                            let ci = layout_index(layout, c, d, nd);
                            j[(ri, ci)] += w * df * basis(c, tau);
                        }
                    }
                }
            }
        }
        Ok(())
    }
}

/// A nonlinear force on a subset of the DOFs of another one, zero on the rest: the same physics
/// seen from a larger condensed set (for condensed = uncondensed tests).
#[derive(Clone, Debug)]
pub struct Embedded<F> {
    pub inner: F,
    /// Position of each of the inner force's DOFs among the `n_total` DOFs.
    pub positions: Vec<usize>,
    pub n_total: usize,
}

impl<F: HarmonicForce> HarmonicForce for Embedded<F> {
    type State = F::State;

    fn n_dofs(&self) -> usize {
        self.n_total
    }

    fn initial_state(&self) -> F::State {
        self.inner.initial_state()
    }

    fn evaluate(
        &self,
        layout: &HarmonicLayout,
        q: &[f64],
        state: &mut F::State,
        force: &mut [f64],
        jacobian: Option<MatMut<'_, f64>>,
    ) -> Result<()> {
        let ni = self.inner.n_dofs();
        let nc = layout.coefficients();
        let map = |c: usize, d: usize| layout_index(layout, c, self.positions[d], self.n_total);
        let mut qi = vec![0.0; layout.len(ni)];
        for d in 0..ni {
            for c in 0..nc {
                qi[layout_index(layout, c, d, ni)] = q[map(c, d)];
            }
        }
        let mut fi = vec![0.0; qi.len()];
        let mut ji = Mat::<f64>::zeros(qi.len(), qi.len());
        let want = jacobian.is_some();
        self.inner
            .evaluate(layout, &qi, state, &mut fi, want.then_some(ji.as_mut()))?;
        let all: Vec<(usize, usize)> = (0..ni).flat_map(|d| (0..nc).map(move |c| (c, d))).collect();
        for &(c, d) in &all {
            force[map(c, d)] += fi[layout_index(layout, c, d, ni)];
        }
        if let Some(mut j) = jacobian {
            for &(r, dr) in &all {
                for &(c, dc) in &all {
                    j[(map(r, dr), map(c, dc))] += ji[(
                        layout_index(layout, r, dr, ni),
                        layout_index(layout, c, dc, ni),
                    )];
                }
            }
        }
        Ok(())
    }
}

/// A dense real matrix from rows.
pub fn dense(rows: &[&[f64]]) -> Mat<f64> {
    Mat::from_fn(rows.len(), rows[0].len(), |i, j| rows[i][j])
}

/// Solves the complex system A x = b densely.
pub fn complex_solve(a: &Mat<c64>, b: &[c64]) -> Vec<c64> {
    use faer::linalg::solvers::Solve;
    let lu = a.partial_piv_lu();
    let mut x = Mat::from_fn(b.len(), 1, |i, _| b[i]);
    lu.solve_in_place(x.as_mut());
    (0..b.len()).map(|i| x[(i, 0)]).collect()
}

/// A 4-DOF chain (masses 1, 2, 1.5, 1 kg; springs to ground and between neighbours) with
/// non-proportional damping: K, M, C.
pub fn chain4() -> (Mat<f64>, Mat<f64>, Mat<f64>) {
    let k = dense(&[
        &[3.0, -1.0, 0.0, 0.0],
        &[-1.0, 2.5, -1.5, 0.0],
        &[0.0, -1.5, 3.5, -2.0],
        &[0.0, 0.0, -2.0, 2.6],
    ]);
    let m = dense(&[
        &[1.0, 0.0, 0.0, 0.0],
        &[0.0, 2.0, 0.0, 0.0],
        &[0.0, 0.0, 1.5, 0.0],
        &[0.0, 0.0, 0.0, 1.0],
    ]);
    let c = dense(&[
        &[0.05, -0.01, 0.0, 0.0],
        &[-0.01, 0.03, 0.0, 0.0],
        &[0.0, 0.0, 0.08, -0.02],
        &[0.0, 0.0, -0.02, 0.04],
    ]);
    (k, m, c)
}

/// Friction elements without normal kinematics (slip limit μ n0) on DOF combinations
/// u_t = Σ w_i q[d_i], one per entry of `tangential`, among `n_total` DOFs
/// ([`nlrom::contact::grounded::DofElements`]).
pub fn friction_elements(
    params: nlrom::contact::law::ContactParams,
    tangential: Vec<Vec<(usize, f64)>>,
    n_total: usize,
) -> nlrom::contact::grounded::DofElements {
    use nlrom::case::WeightedDofs;
    use nlrom::contact::grounded::{DofElement, DofElements};
    let elements = tangential
        .into_iter()
        .map(|combination| DofElement {
            tangential: WeightedDofs {
                dofs: combination.iter().map(|&(d, _)| d).collect(),
                weights: combination.iter().map(|&(_, w)| w).collect(),
            },
            normal: None,
            params,
        })
        .collect();
    DofElements::new(elements, n_total).unwrap()
}

/// Two unit oscillators (m = 1 kg, k = 1 N/m, damping c), DOF 0 tangential and DOF 1 normal at
/// one friction element ([`tangential_normal_element`]), excited by `force` on harmonic 1, H
/// harmonics; both DOFs nonlinear and output.
pub fn two_oscillators(c: f64, force: [f64; 2], h: usize) -> nlrom::hbm::LinearModel {
    let k = Mat::from_fn(2, 2, |i, j| if i == j { 1.0 } else { 0.0 });
    let cm = Mat::from_fn(2, 2, |i, j| if i == j { c } else { 0.0 });
    nlrom::hbm::LinearModel::from_real(
        k.as_ref(),
        k.as_ref(),
        Some(cm.as_ref()),
        &force,
        vec![0, 1],
        vec![0, 1],
        h,
    )
    .unwrap()
}

/// One friction element (k_t = 1, k_n = 3 N/m, μ = 0.3, preload n0) reading u_t = q0 and the
/// normal approach v = q1.
pub fn tangential_normal_element(n0: f64) -> Result<nlrom::contact::grounded::DofElements> {
    use nlrom::case::WeightedDofs;
    use nlrom::contact::grounded::{DofElement, DofElements};
    let one = |d: usize| WeightedDofs {
        dofs: vec![d],
        weights: vec![1.0],
    };
    DofElements::new(
        vec![DofElement {
            tangential: one(0),
            normal: Some(one(1)),
            params: nlrom::contact::law::ContactParams::new(1.0, 3.0, 0.3, n0, "test")?,
        }],
        2,
    )
}

/// A synthetic contact interface of `contact_dofs` / 6 node-to-node pairs (frames along x, y, z;
/// k_t = k_n = 1 N/m, μ = 0.5, n0 = 1 N, 1-D friction) on a chain of as many unit masses and
/// unit springs (C = 0.01 K), every DOF nonlinear, forced on harmonic 1; with H harmonics and
/// `samples` AFT samples. Returns the linear model, the pairs, the layout and a harmonic-1 state
/// x of 0.5–2 m per DOF with varied phases, where the pairs stick, slip and separate — or, with
/// `slipping` = Some(F), where only every ⌈1/F⌉-th pair moves that much and the others move 50
/// times less and stick all period.
pub fn synthetic_interface(
    contact_dofs: usize,
    h: usize,
    samples: usize,
    slipping: Option<f64>,
) -> Result<(
    nlrom::hbm::LinearModel,
    nlrom::contact::pairs::PairSet,
    HarmonicLayout,
    Vec<f64>,
)> {
    use nlrom::contact::law::ContactParams;
    let pairs = contact_dofs / 6;
    let n = 6 * pairs;
    let k = Mat::from_fn(n, n, |i, j| match i.abs_diff(j) {
        0 => 2.0,
        1 => -1.0,
        _ => 0.0,
    });
    let m = Mat::<f64>::identity(n, n);
    let c = Mat::from_fn(n, n, |i, j| 0.01 * k[(i, j)]);
    let force: Vec<f64> = (0..n).map(|i| 0.3 * ((i % 7) as f64 - 3.0)).collect();
    let linear = nlrom::hbm::LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        Some(c.as_ref()),
        &force,
        (0..n).collect(),
        vec![0],
        h,
    )?;
    let params = ContactParams::new(1.0, 1.0, 0.5, 1.0, "synthetic")?;
    let set = synthetic_pairs(pairs, |_| params)?;
    let layout = HarmonicLayout::new(h, samples)?;
    let mut x = vec![0.0; layout.len(n)];
    let every = slipping.map_or(1, |f| (1.0 / f).ceil() as usize);
    for d in 0..n {
        let c1 = layout.cos_index(1, d, n);
        let (mut a, phi) = (0.5 + 1.5 * ((d * 37 % 101) as f64 / 100.0), d as f64 * 0.7);
        if (d / 6) % every != 0 {
            a *= 0.02;
        }
        x[c1] = a * phi.cos();
        x[c1 + 1] = a * phi.sin();
    }
    Ok((linear, set, layout, x))
}

/// A synthetic modal interface: `contact_dofs` / 6 node-to-node pairs (frames along x, y, z;
/// k_t = k_n = 1 N/m, μ = 0.5, 1-D friction) at x_p = (p + ½)/P along a strip of length 1, seen
/// by `modes` smooth mode shapes: mode r at side s (contact, target) in direction k,
/// φ_r(x) = √(2/P) sin((1 + r/2) π x + θ_rsk) (θ_rsk = 0.3(r + 2s + 3k) rad), natural
/// frequencies ω_r = 1 + r/2 rad/s, damping ratios 0.01, forced at one DOF (φ at x = 0.3,
/// 1 N on harmonic 1) and one response DOF (the first contact DOF). Returns the modal model, the
/// physical pairs, the layout (H, `samples`) and a harmonic-1 modal state q (q_r ∝ 1/(r + 1),
/// varied phases) scaled so that the largest relative displacement of a pair is 2 m. One pair in
/// `every` has n0 = 0.2 N (it slips and separates at that state), the others n0 = 100 N (they
/// stick all period).
pub fn synthetic_modal_interface(
    contact_dofs: usize,
    modes: usize,
    h: usize,
    samples: usize,
    every: usize,
) -> Result<(
    nlrom::hbm::modal::ModalModel,
    nlrom::contact::pairs::PairSet,
    HarmonicLayout,
    Vec<f64>,
)> {
    use nlrom::contact::law::ContactParams;
    let pairs = contact_dofs / 6;
    let n = 6 * pairs;
    let amplitude = (2.0 / pairs as f64).sqrt();
    let shape = |r: usize, side: usize, k: usize, x: f64| {
        let theta = 0.3 * (r + 2 * side + 3 * k) as f64;
        amplitude * ((1.0 + 0.5 * r as f64) * std::f64::consts::PI * x + theta).sin()
    };
    let x_of = |p: usize| (p as f64 + 0.5) / pairs as f64;
    let contact = Mat::from_fn(n, modes, |i, r| {
        let (p, side, k) = (i / 6, (i % 6) / 3, i % 3);
        shape(r, side, k, x_of(p))
    });
    let forced = Mat::from_fn(1, modes, |_, r| shape(r, 0, 1, 0.3));
    let response = Mat::from_fn(1, modes, |_, r| contact[(0, r)]);
    let frequencies: Vec<f64> = (0..modes).map(|r| 1.0 + 0.5 * r as f64).collect();
    let model = nlrom::hbm::modal::ModalModel::new(
        frequencies,
        vec![0.01; modes],
        contact.clone(),
        forced,
        vec![1.0],
        response,
    )?;
    let stuck = ContactParams::new(1.0, 1.0, 0.5, 100.0, "synthetic")?;
    let moving = ContactParams::new(1.0, 1.0, 0.5, 0.2, "synthetic")?;
    let set = synthetic_pairs(
        pairs,
        |p| {
            if p % every.max(1) == 0 {
                moving
            } else {
                stuck
            }
        },
    )?;
    let layout = HarmonicLayout::new(h, samples)?;
    let mut q = vec![0.0; layout.len(modes)];
    let (mut re, mut im) = (vec![0.0; modes], vec![0.0; modes]);
    for r in 0..modes {
        let phase = 0.7 * r as f64;
        re[r] = phase.cos() / (r + 1) as f64;
        im[r] = phase.sin() / (r + 1) as f64;
    }
    // the largest relative displacement amplitude of a pair at this q
    let mut largest = 0.0_f64;
    for i in 0..n {
        if (i % 6) >= 3 {
            continue;
        }
        let (mut a, mut b) = (0.0, 0.0);
        for r in 0..modes {
            let rel = contact[(i, r)] - contact[(i + 3, r)];
            a += rel * re[r];
            b += rel * im[r];
        }
        largest = largest.max((a * a + b * b).sqrt());
    }
    let s = 2.0 / largest;
    for r in 0..modes {
        let c1 = layout.cos_index(1, r, modes);
        q[c1] = s * re[r];
        q[c1 + 1] = s * im[r];
    }
    Ok((model, set, layout, q))
}

/// `pairs` node-to-node pairs on 6 DOFs each (contact x y z, then target x y z; frames along
/// x, y, z; 1-D friction), pair p with the parameters `params(p)`.
fn synthetic_pairs(
    pairs: usize,
    params: impl Fn(usize) -> nlrom::contact::law::ContactParams,
) -> Result<nlrom::contact::pairs::PairSet> {
    use nlrom::contact::law::Variant;
    use nlrom::contact::pairs::{PairElement, PairSet};
    let identity = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]];
    PairSet::new(
        6 * pairs,
        Variant::OneD,
        (0..pairs)
            .map(|p| PairElement {
                contact: [6 * p, 6 * p + 1, 6 * p + 2],
                target: Some([6 * p + 3, 6 * p + 4, 6 * p + 5]),
                frame: identity,
                sigma: 0,
                params: params(p),
                preload_rate: 1.0,
            })
            .collect(),
        None,
    )
}
