//! Hill's method (`nlrom::hbm::stability`) against independent references: the exact
//! eigenvalues of a linear damped system (closed form for one DOF, the quadratic eigenproblem of
//! the 4-DOF chain), the Duffing oscillator's fold-bounded middle branch (unstable) and outer
//! branches (stable), and a direct Floquet computation (RK4 integration of the variational
//! equation over one period, monodromy matrix) at points on each branch.

mod support;

use faer::linalg::solvers::Solve;
use faer::{c64, Mat};
use nlrom::continuation::{trace, ContinuationOptions, PathEnd, PathPoint};
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::frf::frequency_response;
use nlrom::hbm::stability::{floquet, is_stable, HillOptions};
use nlrom::hbm::{FrequencyPath, HbmSystem, LinearModel, ResponseOptions};
use support::hbm::{chain4, PolynomialSprings};

const K: f64 = 1.0;
const M: f64 = 1.0;
const C: f64 = 0.05;
const K3: f64 = 0.5;
const F: f64 = 0.1;

fn no_force(n: usize) -> PolynomialSprings {
    PolynomialSprings {
        k1: vec![0.0; n],
        k3: vec![0.0; n],
    }
}

/// A damped SDOF: its Hill exponents are exactly −c/2 ± i ω_d (shifted by i nω), so the kept
/// ones have the real part −c/2.
#[test]
fn linear_single_dof_exponents_are_exact() {
    let (k, m, c) = (4.0, 1.0, 0.3);
    let km = Mat::from_fn(1, 1, |_, _| k);
    let mm = Mat::from_fn(1, 1, |_, _| m);
    let cm = Mat::from_fn(1, 1, |_, _| c);
    let model = LinearModel::from_real(
        km.as_ref(),
        mm.as_ref(),
        Some(cm.as_ref()),
        &[1.0],
        vec![0],
        vec![0],
        3,
    )
    .unwrap();
    let force = no_force(1);
    let system = HbmSystem::new(HarmonicLayout::new(3, 16).unwrap(), &model, &force).unwrap();
    let wd = (k / m - c * c / (4.0 * m * m)).sqrt();
    for omega in [0.7, 1.9, 2.0, 3.3] {
        let q = vec![0.0; system.dim()];
        let f = floquet(&system, &q, omega, &(), &HillOptions::default()).unwrap();
        assert_eq!(f.exponents.len(), 2);
        assert!(f.stable);
        for l in &f.exponents {
            assert!((l.re + c / (2.0 * m)).abs() < 1e-10, "ω {omega}: {l:?}");
            // Im λ = ±ω_d − jω for an integer j
            let off_integer = |v: f64| (v - v.round()).abs();
            let shifted = off_integer((l.im - wd) / omega).min(off_integer((l.im + wd) / omega));
            assert!(shifted < 1e-9, "ω {omega}: Im {} vs ω_d {wd}", l.im);
        }
    }
}

/// The 4-DOF chain (non-proportional damping), condensed on two DOFs: every kept Hill exponent
/// has the real part of an eigenvalue of λ²M + λC + K = 0 (computed from its own companion
/// matrix), and the solution is stable.
#[test]
fn linear_chain_is_stable_with_the_exact_decay_rates() {
    let (k, m, c) = chain4();
    let model = LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        Some(c.as_ref()),
        &[1.0, 0.0, 0.0, 0.5],
        vec![1, 3],
        vec![0],
        2,
    )
    .unwrap();
    let force = no_force(2);
    let system = HbmSystem::new(HarmonicLayout::new(2, 8).unwrap(), &model, &force).unwrap();
    // reference: companion of the 4-DOF system
    let minv_k = m.partial_piv_lu().solve(&k);
    let minv_c = m.partial_piv_lu().solve(&c);
    let comp = Mat::from_fn(8, 8, |i, j| {
        if i < 4 {
            if j == i + 4 {
                1.0
            } else {
                0.0
            }
        } else if j < 4 {
            -minv_k[(i - 4, j)]
        } else {
            -minv_c[(i - 4, j - 4)]
        }
    });
    let reference: Vec<c64> = comp.eigenvalues().unwrap();
    for omega in [0.3, 0.9, 1.7] {
        let q = vec![0.0; system.dim()];
        let f = floquet(&system, &q, omega, &(), &HillOptions::default()).unwrap();
        assert_eq!(f.exponents.len(), 8);
        assert!(f.stable && f.max_real < 0.0);
        for l in &f.exponents {
            let nearest = reference
                .iter()
                .map(|r| (r.re - l.re).abs())
                .fold(f64::INFINITY, f64::min);
            assert!(nearest < 1e-10, "ω {omega}: exponent {l:?}");
        }
        assert!(is_stable(&system, &q, omega, &()).unwrap());
    }
}

fn duffing_model(h: usize) -> LinearModel {
    let k = Mat::from_fn(1, 1, |_, _| K);
    let m = Mat::from_fn(1, 1, |_, _| M);
    let c = Mat::from_fn(1, 1, |_, _| C);
    LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        Some(c.as_ref()),
        &[F],
        vec![0],
        vec![0],
        h,
    )
    .unwrap()
}

/// q(τ) of a 1-DOF real harmonic vector.
fn signal(x: &[f64], tau: f64) -> f64 {
    let h = (x.len() - 1) / 2;
    let mut q = x[0];
    for n in 1..=h {
        let (re, im) = (x[2 * n - 1], x[2 * n]);
        q += re * (n as f64 * tau).cos() - im * (n as f64 * tau).sin();
    }
    q
}

/// max Re of the Floquet exponents from the monodromy matrix of ÿ + c ẏ + (k + 3 k3 q(t)²) y = 0
/// over one period T = 2π/ω (RK4, `steps` steps).
fn direct_floquet_max_real(x: &[f64], omega: f64, steps: usize) -> f64 {
    let period = 2.0 * std::f64::consts::PI / omega;
    let dt = period / steps as f64;
    let rhs = |t: f64, y: [f64; 2]| -> [f64; 2] {
        let q = signal(x, omega * t);
        [y[1], -(C * y[1] + (K + 3.0 * K3 * q * q) * y[0]) / M]
    };
    let mut monodromy = [[0.0; 2]; 2];
    for (col, y0) in [[1.0, 0.0], [0.0, 1.0]].into_iter().enumerate() {
        let mut y = y0;
        for s in 0..steps {
            let t = s as f64 * dt;
            let k1 = rhs(t, y);
            let k2 = rhs(
                t + dt / 2.0,
                [y[0] + dt / 2.0 * k1[0], y[1] + dt / 2.0 * k1[1]],
            );
            let k3 = rhs(
                t + dt / 2.0,
                [y[0] + dt / 2.0 * k2[0], y[1] + dt / 2.0 * k2[1]],
            );
            let k4 = rhs(t + dt, [y[0] + dt * k3[0], y[1] + dt * k3[1]]);
            for i in 0..2 {
                y[i] += dt / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
        }
        monodromy[0][col] = y[0];
        monodromy[1][col] = y[1];
    }
    // eigenvalues of the 2×2 monodromy matrix
    let tr = monodromy[0][0] + monodromy[1][1];
    let det = monodromy[0][0] * monodromy[1][1] - monodromy[0][1] * monodromy[1][0];
    let disc = tr * tr / 4.0 - det;
    let largest = if disc >= 0.0 {
        (tr / 2.0).abs() + disc.sqrt()
    } else {
        det.sqrt()
    };
    largest.ln() / period
}

fn fold_indices<S>(points: &[PathPoint<S>]) -> Vec<usize> {
    points
        .windows(2)
        .enumerate()
        .filter(|(_, w)| w[0].tangent_parameter * w[1].tangent_parameter < 0.0)
        .map(|(i, _)| i)
        .collect()
}

/// The Duffing middle branch (between the two folds of the continuation) is unstable, the outer
/// branches are stable; the switch happens at the folds; Hill's largest real part agrees with a
/// direct Floquet computation on both branches (to 1e-6 1/s; measured 4e-8).
#[test]
fn duffing_middle_branch_is_unstable_between_the_folds() {
    let h = 5;
    let model = duffing_model(h);
    let force = PolynomialSprings {
        k1: vec![0.0],
        k3: vec![K3],
    };
    let system = HbmSystem::new(HarmonicLayout::new(h, 32).unwrap(), &model, &force).unwrap();
    let fp = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let mut opts = ContinuationOptions::new(0.5, 2.0, 0.01);
    opts.max_step = Some(0.02);
    let path = trace(&fp, &opts, &mut |_| {}).unwrap();
    assert_eq!(path.end, PathEnd::ReachedEnd);
    let folds = fold_indices(&path.points);
    assert_eq!(folds.len(), 2, "{folds:?}");
    let floquets: Vec<_> = path
        .points
        .iter()
        .map(|p| floquet(&system, &p.x, p.parameter, &(), &HillOptions::default()).unwrap())
        .collect();
    for (i, f) in floquets.iter().enumerate() {
        // the exponent crossing zero at a fold is within one step of zero there
        let near_fold = folds.iter().any(|&k| i == k || i == k + 1);
        if near_fold {
            continue;
        }
        let middle = i > folds[0] && i <= folds[1];
        assert_eq!(
            f.stable, !middle,
            "point {i} at ω {:.5}: max Re λ {:.3e}, folds at {:?}",
            path.points[i].parameter, f.max_real, folds
        );
    }
    // direct Floquet on one point of each branch
    let probes = [
        folds[0] / 2,
        (folds[0] + folds[1]) / 2,
        (folds[1] + path.points.len()) / 2,
    ];
    for &i in &probes {
        let p = &path.points[i];
        let direct = direct_floquet_max_real(&p.x, p.parameter, 20_000);
        let hill = floquets[i].max_real;
        println!(
            "probe ω {:.5}: Hill {hill:.6e} direct {direct:.6e}",
            p.parameter
        );
        assert!(
            (direct - hill).abs() <= 1e-6,
            "point {i} at ω {:.5}: Hill {hill:.6e} vs direct {direct:.6e}",
            p.parameter
        );
        assert_eq!(direct > 0.0, hill > 0.0);
    }
    // the FRF driver fills the flag when asked
    let frf = frequency_response(
        &system,
        &opts,
        &ResponseOptions {
            stability: true,
            ..ResponseOptions::default()
        },
        &mut |_| {},
    )
    .unwrap();
    let unstable = frf
        .points
        .iter()
        .filter(|p| p.stable == Some(false))
        .count();
    assert!(unstable >= 3, "{unstable} unstable points");
    assert!(frf.points.iter().all(|p| p.stable.is_some()));
}

/// The amplitudes A > 0 of the single-harmonic Duffing response at ω (closed form):
/// A²[(K − Mω² + ¾K₃A²)² + (Cω)²] = F², a cubic in z = A², real positive roots by bisection
/// between the cubic's stationary points.
fn duffing_h1_amplitudes(omega: f64) -> Vec<f64> {
    let (a, b) = (0.75 * K3, K - M * omega * omega);
    let g = |z: f64| z * ((b + a * z).powi(2) + (C * omega).powi(2)) - F * F;
    // g' = 3a²z² + 4abz + b² + C²ω²: stationary points of g
    let (qa, qb, qc) = (3.0 * a * a, 4.0 * a * b, b * b + (C * omega).powi(2));
    let disc = qb * qb - 4.0 * qa * qc;
    let mut cuts = vec![0.0];
    if disc > 0.0 {
        for s in [-1.0, 1.0] {
            let z = (-qb + s * disc.sqrt()) / (2.0 * qa);
            if z > 0.0 {
                cuts.push(z);
            }
        }
    }
    cuts.push(10.0 * F.max(1.0));
    let mut roots = Vec::new();
    for w in cuts.windows(2) {
        let (mut lo, mut hi) = (w[0], w[1]);
        if g(lo) * g(hi) > 0.0 {
            continue;
        }
        for _ in 0..200 {
            let mid = 0.5 * (lo + hi);
            if g(lo) * g(mid) <= 0.0 {
                hi = mid
            } else {
                lo = mid
            }
        }
        roots.push((0.5 * (lo + hi)).sqrt());
    }
    roots
}

/// `land_at` inside the Duffing fold (H = 1): the traced path crosses a frequency between its
/// folds three times; the added points lie exactly at that frequency, their amplitudes are the
/// three closed-form single-harmonic amplitudes (large, middle, small in path order, to 1e-7),
/// and Hill marks the middle one unstable. A frequency outside the range gives no point.
#[test]
fn landing_inside_the_fold_gives_the_three_closed_form_branches() {
    use nlrom::hbm::frf::land_at;
    let model = duffing_model(1);
    let force = PolynomialSprings {
        k1: vec![0.0],
        k3: vec![K3],
    };
    let system = HbmSystem::new(HarmonicLayout::new(1, 16).unwrap(), &model, &force).unwrap();
    // a frequency with three closed-form amplitudes, in the middle of that interval
    let three: Vec<f64> = (0..3000)
        .map(|i| 1.0 + 1e-3 * i as f64)
        .filter(|&w| duffing_h1_amplitudes(w).len() == 3)
        .collect();
    assert!(three.len() > 20, "no fold interval found");
    let w = 0.5 * (three[0] + three[three.len() - 1]);
    let want = duffing_h1_amplitudes(w);
    let mut opts = ContinuationOptions::new(0.5, 2.0, 0.01);
    opts.max_step = Some(0.02);
    let response = ResponseOptions {
        stability: true,
        ..ResponseOptions::default()
    };
    let mut frf = frequency_response(&system, &opts, &response, &mut |_| {}).unwrap();
    let traced = frf.points.len();
    let landed = land_at(&system, &mut frf, &[w, 3.0], &opts.newton, &response).unwrap();
    assert!(landed.failed.is_empty(), "{:?}", landed.failed);
    assert_eq!(landed.points[1], Vec::<usize>::new());
    let at = &landed.points[0];
    assert_eq!(at.len(), 3, "{at:?}");
    assert_eq!(frf.points.len(), traced + 3);
    assert!(frf
        .points
        .windows(2)
        .all(|p| p[1].arc_length >= p[0].arc_length));
    let mut got: Vec<(f64, Option<bool>)> = at
        .iter()
        .map(|&k| {
            let p = &frf.points[k];
            assert_eq!(p.omega, w);
            (p.response.amplitude[0], p.stable)
        })
        .collect();
    println!("ω = {w}: landed {got:?}, closed form {want:?}");
    // path order: up the large branch, back along the middle one, out along the small one
    assert!(got[0].0 > got[1].0 && got[1].0 > got[2].0, "{got:?}");
    got.reverse();
    for ((a, stable), (i, b)) in got.iter().zip(want.iter().enumerate()) {
        assert!((a - b).abs() <= 1e-7 * b, "{a} vs {b}");
        assert_eq!(*stable, Some(i != 1), "branch {i} at amplitude {a}");
    }
}
