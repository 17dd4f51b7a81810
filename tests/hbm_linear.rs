//! Harmonic balance on matrix-defined systems: exactness on linear systems (against a direct
//! complex solve), condensed = uncondensed, analytic derivatives against finite differences.

mod support;

use faer::{c64, Mat};
use nlrom::harmonics::{HarmonicForce, HarmonicLayout};
use nlrom::hbm::response::output_response;
use nlrom::hbm::{FrequencyPath, HbmSystem, LinearModel, MatrixBlock, ResponseOptions};
use nlrom::nonlinear::{solve_fixed, Linearization, NewtonOptions, ParameterSystem};
use support::hbm::{chain4, complex_solve, Embedded, PolynomialSprings};

fn c(re: f64) -> c64 {
    c64::new(re, 0.0)
}

/// Grounded linear springs k1 on DOFs 0 and 2 of the chain, as a nonlinear force.
fn linear_springs() -> PolynomialSprings {
    PolynomialSprings {
        k1: vec![0.7, 1.3],
        k3: vec![0.0, 0.0],
    }
}

/// The HB of a linear system equals the direct solution (K + K_s − ω²M + iωC) X = F on harmonic
/// 1, and zero on the other harmonics, to 1e-10, both with condensation and without.
#[test]
fn linear_system_is_exact() {
    let (k, m, cm) = chain4();
    let force = [0.0, 1.0, 0.0, 0.5];
    let layout = HarmonicLayout::new(3, 16).unwrap();
    let omega = 1.23;
    // direct complex solve with the springs added to K
    let mut ks = k.clone();
    ks[(0, 0)] += 0.7;
    ks[(2, 2)] += 1.3;
    let d = Mat::from_fn(4, 4, |i, j| {
        c(ks[(i, j)] - omega * omega * m[(i, j)]) + c64::new(0.0, omega * cm[(i, j)])
    });
    let x = complex_solve(&d, &force.map(c));
    for condensed_on in [vec![0, 2], vec![2, 0, 1, 3]] {
        let springs = if condensed_on.len() == 2 {
            Embedded {
                inner: linear_springs(),
                positions: vec![0, 1],
                n_total: 2,
            }
        } else {
            Embedded {
                inner: linear_springs(),
                positions: vec![1, 0],
                n_total: 4,
            }
        };
        let linear = LinearModel::from_real(
            k.as_ref(),
            m.as_ref(),
            Some(cm.as_ref()),
            &force,
            condensed_on.clone(),
            vec![0, 1, 2, 3],
            3,
        )
        .unwrap();
        let system = HbmSystem::new(layout, &linear, &springs).unwrap();
        let path = FrequencyPath {
            system: &system,
            level: 1.0,
        };
        let x0 = vec![0.0; path.dim()];
        let sol = solve_fixed(&path, &x0, omega, &(), &NewtonOptions::default()).unwrap();
        assert!(sol.iterations <= 2, "{} iterations", sol.iterations);
        let resp =
            output_response(&system, &sol.x, omega, 1.0, &ResponseOptions::default()).unwrap();
        let scale = x.iter().map(|v| v.norm()).fold(0.0, f64::max);
        for (dof, xd) in x.iter().enumerate() {
            let h = &resp.harmonics[dof];
            assert!(
                (h[1] - xd).norm() <= 1e-10 * scale,
                "dof {dof}: {} vs {xd}",
                h[1]
            );
            for n in [0, 2, 3] {
                assert!(
                    h[n].norm() <= 1e-12 * scale,
                    "dof {dof} harmonic {n}: {}",
                    h[n]
                );
            }
            assert!((resp.amplitude[dof] - xd.norm()).abs() <= 1e-10 * scale);
            assert!((resp.peak[dof] - xd.norm()).abs() <= 1e-3 * xd.norm());
        }
    }
}

/// Complex (cyclic-like) blocks: harmonic 1 on a Hermitian block, harmonic 2 on another, excited
/// on both; the HB of the linear system equals the per-harmonic complex solves to 1e-10.
#[test]
fn complex_blocks_are_exact() {
    let (k, m, cm) = chain4();
    let herm = |a: &Mat<f64>, phase: f64| {
        Mat::from_fn(4, 4, |i, j| {
            let v = a[(i, j)];
            if i == 0 && j == 3 {
                c64::new(0.0, phase) * v.abs().max(0.3)
            } else if i == 3 && j == 0 {
                c64::new(0.0, -phase) * v.abs().max(0.3)
            } else {
                c(v)
            }
        })
    };
    let real = |a: &Mat<f64>| Mat::from_fn(4, 4, |i, j| c(a[(i, j)]));
    let blocks = vec![
        MatrixBlock {
            stiffness: real(&k),
            mass: real(&m),
            damping: Some(real(&cm)),
            nonlinear: vec![1, 3],
            outputs: vec![0, 3],
        },
        MatrixBlock {
            stiffness: herm(&k, 0.4),
            mass: real(&m),
            damping: Some(herm(&cm, 0.01)),
            nonlinear: vec![1, 3],
            outputs: vec![0, 3],
        },
    ];
    let f1 = vec![c(1.0), c64::new(0.2, 0.3), c(0.0), c(0.0)];
    let f2 = vec![c(0.0), c(0.0), c64::new(0.0, 0.5), c(0.1)];
    let linear = LinearModel::new(
        blocks.clone(),
        vec![0, 1, 0],
        vec![vec![], f1.clone(), f2.clone()],
    )
    .unwrap();
    let springs = PolynomialSprings {
        k1: vec![0.5, 0.9],
        k3: vec![0.0, 0.0],
    };
    let layout = HarmonicLayout::new(2, 8).unwrap();
    let system = HbmSystem::new(layout, &linear, &springs).unwrap();
    let path = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let omega = 0.9;
    let x0 = vec![0.0; path.dim()];
    let sol = solve_fixed(&path, &x0, omega, &(), &NewtonOptions::default()).unwrap();
    let resp = output_response(&system, &sol.x, omega, 1.0, &ResponseOptions::default()).unwrap();
    for (n, block, f) in [(1usize, &blocks[1], &f1), (2, &blocks[0], &f2)] {
        let s = n as f64 * omega;
        let cmat = block.damping.as_ref().unwrap();
        let mut d = Mat::from_fn(4, 4, |i, j| {
            block.stiffness[(i, j)] - block.mass[(i, j)] * (s * s) + cmat[(i, j)] * c64::new(0.0, s)
        });
        d[(1, 1)] += c(0.5);
        d[(3, 3)] += c(0.9);
        let x = complex_solve(&d, f);
        for (o, row) in [0usize, 3].iter().enumerate() {
            let got = resp.harmonics[o][n];
            assert!(
                (got - x[*row]).norm() <= 1e-10 * x[*row].norm().max(1e-3),
                "n {n} row {row}: {got} vs {}",
                x[*row]
            );
        }
    }
}

/// A cubic nonlinearity: the condensed solution (on the two nonlinear DOFs) and the uncondensed
/// one (all four DOFs as unknowns) agree at every output DOF to 1e-9.
#[test]
fn condensed_equals_uncondensed() {
    let (k, m, cm) = chain4();
    let force = [0.0, 0.4, 0.0, 0.0];
    let layout = HarmonicLayout::new(5, 32).unwrap();
    let cubic = PolynomialSprings {
        k1: vec![0.2, 0.0],
        k3: vec![2.0, 1.5],
    };
    let omega = 0.8;
    let mut responses = vec![];
    for (rows, positions, n_total) in [
        (vec![0, 2], vec![0, 1], 2),
        (vec![0, 1, 2, 3], vec![0, 2], 4),
    ] {
        let linear = LinearModel::from_real(
            k.as_ref(),
            m.as_ref(),
            Some(cm.as_ref()),
            &force,
            rows,
            vec![0, 1, 2, 3],
            5,
        )
        .unwrap();
        let f = Embedded {
            inner: cubic.clone(),
            positions,
            n_total,
        };
        let system = HbmSystem::new(layout, &linear, &f).unwrap();
        let path = FrequencyPath {
            system: &system,
            level: 1.0,
        };
        let x0 = vec![0.0; path.dim()];
        let opts = NewtonOptions {
            tolerance: 1e-12,
            ..NewtonOptions::default()
        };
        let sol = solve_fixed(&path, &x0, omega, &(), &opts).unwrap();
        responses.push(
            output_response(&system, &sol.x, omega, 1.0, &ResponseOptions::default()).unwrap(),
        );
    }
    let scale = responses[0].amplitude.iter().cloned().fold(0.0, f64::max);
    for dof in 0..4 {
        for n in 0..=5 {
            let (a, b) = (
                responses[0].harmonics[dof][n],
                responses[1].harmonics[dof][n],
            );
            assert!(
                (a - b).norm() <= 1e-9 * scale,
                "dof {dof} n {n}: {a} vs {b}"
            );
        }
    }
    // the cubic spring generates odd harmonics: harmonic 3 is present, harmonic 2 is not
    assert!(responses[0].harmonics[0][3].norm() > 1e-4 * scale);
    assert!(responses[0].harmonics[0][2].norm() <= 1e-10 * scale);
}

/// ∂r/∂Q and ∂r/∂ω of the whole system (condensed, cubic force) against central differences
/// (relative 1e-6); also checks the test force's own Jacobian.
#[test]
fn jacobian_and_frequency_derivative_match_finite_differences() {
    let (k, m, cm) = chain4();
    let force = [0.3, 1.0, 0.0, 0.2];
    let layout = HarmonicLayout::new(3, 16).unwrap();
    let cubic = PolynomialSprings {
        k1: vec![0.2, 0.4],
        k3: vec![2.0, 1.5],
    };
    let linear = LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        Some(cm.as_ref()),
        &force,
        vec![3, 1],
        vec![0],
        3,
    )
    .unwrap();
    let system = HbmSystem::new(layout, &linear, &cubic).unwrap();
    let path = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let dim = path.dim();
    let q: Vec<f64> = (0..dim)
        .map(|i| 0.3 * ((i as f64) * 1.7).sin() + 0.1)
        .collect();
    let omega = 1.1;
    let mut lin = Linearization::zeros(dim);
    path.evaluate(&q, omega, &(), &mut lin).unwrap();
    let residual = |q: &[f64], w: f64| {
        let mut l = Linearization::zeros(dim);
        path.evaluate(q, w, &(), &mut l).unwrap();
        l.residual
    };
    let h = 1e-6;
    let jnorm = (0..dim)
        .flat_map(|i| (0..dim).map(move |j| (i, j)))
        .map(|(i, j)| lin.jacobian[(i, j)].abs())
        .fold(0.0, f64::max);
    for j in 0..dim {
        let (mut qp, mut qm) = (q.clone(), q.clone());
        qp[j] += h;
        qm[j] -= h;
        let (rp, rm) = (residual(&qp, omega), residual(&qm, omega));
        for i in 0..dim {
            let fd = (rp[i] - rm[i]) / (2.0 * h);
            assert!(
                (fd - lin.jacobian[(i, j)]).abs() <= 1e-6 * jnorm,
                "J[{i},{j}] {} vs fd {fd}",
                lin.jacobian[(i, j)]
            );
        }
    }
    let (rp, rm) = (residual(&q, omega + h), residual(&q, omega - h));
    let dnorm = lin.d_parameter.iter().map(|v| v.abs()).fold(0.0, f64::max);
    for i in 0..dim {
        let fd = (rp[i] - rm[i]) / (2.0 * h);
        assert!(
            (fd - lin.d_parameter[i]).abs() <= 1e-6 * dnorm,
            "dr/dω[{i}] {} vs fd {fd}",
            lin.d_parameter[i]
        );
    }
}

/// The condensed dynamic stiffness and force of a complex Hermitian block: D̄ equals the Schur
/// complement computed independently, and their ω-derivatives match central differences.
#[test]
fn condensation_of_a_complex_block() {
    let n = 5;
    let a = Mat::from_fn(n, n, |i, j| {
        let v = 1.0 / (1.0 + (i as f64 - j as f64).abs());
        if i == j {
            c(4.0 + i as f64)
        } else if i < j {
            c64::new(v, 0.3 * v)
        } else {
            c64::new(v, -0.3 * v)
        }
    });
    let mass = Mat::from_fn(n, n, |i, j| {
        if i == j {
            c(1.0 + 0.1 * i as f64)
        } else {
            c(0.0)
        }
    });
    let damp = Mat::from_fn(n, n, |i, j| a[(i, j)] * 0.02);
    let nonlinear = vec![4, 1];
    let block = MatrixBlock {
        stiffness: a.clone(),
        mass: mass.clone(),
        damping: Some(damp.clone()),
        nonlinear: nonlinear.clone(),
        outputs: vec![0, 4],
    };
    let f: Vec<c64> = (0..n).map(|i| c64::new(0.1 * i as f64, 0.05)).collect();
    let static_block = MatrixBlock {
        stiffness: Mat::from_fn(n, n, |i, j| c(a[(i, j)].re)),
        ..block.clone()
    };
    let linear = LinearModel::new(
        vec![static_block, block],
        vec![0, 1],
        vec![vec![], f.clone()],
    )
    .unwrap();
    let omega = 1.7;
    let cond = linear.condense(1, omega).unwrap();
    // independent Schur complement
    let d = Mat::from_fn(n, n, |i, j| {
        a[(i, j)] - mass[(i, j)] * (omega * omega) + damp[(i, j)] * c64::new(0.0, omega)
    });
    let lin_rows = [0usize, 2, 3];
    let d_ll = Mat::from_fn(3, 3, |i, j| d[(lin_rows[i], lin_rows[j])]);
    for (jj, &col) in nonlinear.iter().enumerate() {
        let rhs: Vec<c64> = lin_rows.iter().map(|&r| d[(r, col)]).collect();
        let x = complex_solve(&d_ll, &rhs);
        for (ii, &row) in nonlinear.iter().enumerate() {
            let mut expect = d[(row, col)];
            for (l, &lr) in lin_rows.iter().enumerate() {
                expect -= d[(row, lr)] * x[l];
            }
            assert!((cond.stiffness[(ii, jj)] - expect).norm() <= 1e-12 * expect.norm().max(1.0));
        }
    }
    let h = 1e-6;
    let (cp, cm) = (
        linear.condense(1, omega + h).unwrap(),
        linear.condense(1, omega - h).unwrap(),
    );
    for i in 0..2 {
        for j in 0..2 {
            let fd = (cp.stiffness[(i, j)] - cm.stiffness[(i, j)]) / c(2.0 * h);
            assert!((fd - cond.stiffness_derivative[(i, j)]).norm() <= 1e-6 * fd.norm().max(1.0));
        }
        let fd = (cp.force[i] - cm.force[i]) / c(2.0 * h);
        assert!(
            (fd - cond.force_derivative[i]).norm() <= 1e-6 * fd.norm().max(1e-3),
            "dF̄/dω {i}: {} vs {fd}",
            cond.force_derivative[i]
        );
    }
    // the form of one residual evaluation: the same D̄ and F̄, and ∂D̄/∂ω q and ∂F̄/∂ω equal to
    // the full derivative's (checked against finite differences above)
    let qv = [c64::new(0.3, -0.2), c64::new(-0.1, 0.4)];
    let applied = linear.condense_applied(1, omega, &qv).unwrap();
    for i in 0..2 {
        let expect: c64 = (0..2)
            .map(|j| cond.stiffness_derivative[(i, j)] * qv[j])
            .sum();
        let got = applied.stiffness_derivative_q[i];
        assert!(
            (got - expect).norm() <= 1e-12 * expect.norm(),
            "{got} vs {expect}"
        );
        let df = cond.force_derivative[i];
        assert!((applied.force_derivative[i] - df).norm() <= 1e-12 * df.norm());
        assert!((applied.force[i] - cond.force[i]).norm() <= 1e-14 * cond.force[i].norm());
        for j in 0..2 {
            let d = cond.stiffness[(i, j)];
            assert!((applied.stiffness[(i, j)] - d).norm() <= 1e-14 * d.norm());
        }
    }
    // recovery of the linear output row 0 reproduces the full solve
    let x_full = complex_solve(&d, &f);
    let q_n: Vec<c64> = nonlinear.iter().map(|&r| x_full[r]).collect();
    let out = cond.recover(&q_n);
    assert!((out[0] - x_full[0]).norm() <= 1e-12 * x_full[0].norm().max(1.0));
    assert!((out[1] - x_full[4]).norm() <= 1e-14);
}

/// Bad input: a force on the wrong number of DOFs, a complex static block, mismatched H.
#[test]
fn inconsistent_models_are_rejected() {
    let (k, m, _) = chain4();
    let linear = LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        None,
        &[1.0, 0.0, 0.0, 0.0],
        vec![0],
        vec![0],
        2,
    )
    .unwrap();
    let two = PolynomialSprings {
        k1: vec![1.0, 1.0],
        k3: vec![0.0, 0.0],
    };
    let e = HbmSystem::new(HarmonicLayout::new(2, 8).unwrap(), &linear, &two)
        .err()
        .unwrap();
    assert!(e.to_string().contains("acts on 2 DOFs"), "{e}");
    let one = PolynomialSprings {
        k1: vec![1.0],
        k3: vec![0.0],
    };
    assert!(HbmSystem::new(HarmonicLayout::new(3, 8).unwrap(), &linear, &one).is_err());
    let block = MatrixBlock {
        stiffness: Mat::from_fn(2, 2, |i, j| {
            if i == j {
                c(2.0)
            } else {
                c64::new(0.0, if i < j { 0.5 } else { -0.5 })
            }
        }),
        mass: Mat::from_fn(2, 2, |i, j| if i == j { c(1.0) } else { c(0.0) }),
        damping: None,
        nonlinear: vec![0],
        outputs: vec![1],
    };
    let e = LinearModel::new(vec![block], vec![0, 0], vec![vec![], vec![c(1.0), c(0.0)]])
        .err()
        .unwrap();
    assert!(e.to_string().contains("harmonic 0"), "{e}");
    assert_eq!(one.n_dofs(), 1);
}
