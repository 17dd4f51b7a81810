//! The linear part of matrix-defined cases: damping models against closed forms, rows of the
//! excitation/elements/outputs, a case's FRF equal to the direct linear solution, bad input.

mod support;

use std::path::Path;
use support::random::Lcg;

use faer::{c64, Mat};
use nlrom::case::Case;
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::frf::frequency_response;
use nlrom::hbm::{HbmSystem, ResponseOptions};
use nlrom::model;
use nlrom::model::damping::modal_damping;
use nlrom::problem::matrix_case::matrix_setup;
use nlrom::problem::settings::case_continuation;
use support::hbm::{complex_solve, dense};

/// A 3-DOF chain ground–1–2–3 (springs 2, 1, 1; masses 1, 1, 2) in Matrix Market files.
fn write_chain(dir: &Path) {
    std::fs::write(
        dir.join("K.mtx"),
        "%%MatrixMarket matrix coordinate real symmetric\n3 3 5\n1 1 3.0\n2 1 -1.0\n2 2 2.0\n3 2 -1.0\n3 3 1.0\n",
    )
    .unwrap();
    std::fs::write(
        dir.join("M.mtx"),
        "%%MatrixMarket matrix coordinate real symmetric\n3 3 3\n1 1 1.0\n2 2 1.0\n3 3 2.0\n",
    )
    .unwrap();
}

fn chain_case(dir: &Path, extra: &str) -> nlrom::Result<Case> {
    let text = format!(
        "[model]\nstiffness = \"K.mtx\"\nmass = \"M.mtx\"\ndamping = {{ rayleigh = [0.01, 0.02] }}\n\n[excitation]\ndofs = [2]\nforce = [0.5]\n\n[continuation]\nstart_rad_s = 0.2\nend_rad_s = 2.5\nstep_rad_s = 0.05\n{extra}"
    );
    Case::from_str(&text, &dir.join("case.toml"))
}

#[test]
fn modal_damping_matches_closed_forms() {
    // uncoupled: C = diag(2ζ√(k m))
    let k = dense(&[&[4.0, 0.0], &[0.0, 9.0]]);
    let m = dense(&[&[1.0, 0.0], &[0.0, 4.0]]);
    let c = modal_damping(k.as_ref(), m.as_ref(), 0.05).unwrap();
    assert!((c[(0, 0)] - 2.0 * 0.05 * 2.0).abs() < 1e-14);
    assert!((c[(1, 1)] - 2.0 * 0.05 * 6.0).abs() < 1e-13);
    assert!(c[(0, 1)].abs() < 1e-14);
    // coupled, M = I: modes of [[2, -1], [-1, 2]] are (1, ±1)/√2 with ω² = 1, 3
    let k = dense(&[&[2.0, -1.0], &[-1.0, 2.0]]);
    let m = dense(&[&[1.0, 0.0], &[0.0, 1.0]]);
    let c = modal_damping(k.as_ref(), m.as_ref(), 0.02).unwrap();
    let s = std::f64::consts::FRAC_1_SQRT_2;
    for (phi, omega) in [([s, s], 1.0_f64), ([s, -s], 3.0_f64.sqrt())] {
        let cphi = [
            c[(0, 0)] * phi[0] + c[(0, 1)] * phi[1],
            c[(1, 0)] * phi[0] + c[(1, 1)] * phi[1],
        ];
        let modal = phi[0] * cphi[0] + phi[1] * cphi[1];
        assert!((modal - 2.0 * 0.02 * omega).abs() < 1e-14, "{modal}");
    }
    let not_spd = dense(&[&[1.0, 0.0], &[0.0, -1.0]]);
    assert!(modal_damping(k.as_ref(), not_spd.as_ref(), 0.02).is_err());
}

/// Above 128 × 128 with clustered eigenvalues (faer's default dense eigensolver lost
/// orthogonality there): K = Q diag(λ) Qᵀ with Q orthogonal, M = I, three clusters of 70 modes
/// (λ = 1, 4, 9 up to 1e-13); the modal damping must be Qᵀ C Q = diag(2ζ√λ) to 1e-10.
#[test]
fn modal_damping_is_exact_for_clustered_modes_above_128() {
    let n = 210;
    let mut lcg = Lcg(12345);
    let mut rand = move || lcg.next() - 0.5;
    let g = Mat::<f64>::from_fn(n, n, |_, _| rand());
    let q = g.qr().compute_Q();
    let lambda: Vec<f64> = (0..n)
        .map(|j| [1.0, 4.0, 9.0][j / 70] * (1.0 + 1e-13 * (j % 70) as f64))
        .collect();
    let scaled = Mat::<f64>::from_fn(n, n, |i, j| q[(i, j)] * lambda[j]);
    let k = &scaled * q.transpose();
    let k = Mat::<f64>::from_fn(n, n, |i, j| 0.5 * (k[(i, j)] + k[(j, i)]));
    let m = Mat::<f64>::identity(n, n);
    let zeta = 0.03;
    let c = modal_damping(k.as_ref(), m.as_ref(), zeta).unwrap();
    let modal = q.transpose() * &c * &q;
    let mut worst = 0.0_f64;
    for i in 0..n {
        for j in 0..n {
            let expected = if i == j {
                2.0 * zeta * lambda[i].sqrt()
            } else {
                0.0
            };
            worst = worst.max((modal[(i, j)] - expected).abs() / (2.0 * zeta * 3.0));
        }
    }
    assert!(
        worst < 1e-10,
        "Qᵀ C Q differs from diag(2ζω) by {worst:e} (relative)"
    );
}

/// A linear case (no element): the FRF at the excitation DOF equals the direct solution with
/// C = αM + βK at every point, to 1e-10.
#[test]
fn linear_matrix_case_frf_equals_the_direct_solution() {
    let dir = tempfile::tempdir().unwrap();
    write_chain(dir.path());
    let case = chain_case(dir.path(), "\n[response]\ndofs = [0, 2]\n").unwrap();
    let model = model::build(&case, &mut |_| {}).unwrap();
    let setup = matrix_setup(&case, &model).unwrap();
    assert_eq!(setup.output_rows, vec![0, 2]);
    assert!(setup.nonlinear_rows.is_empty());
    // a linear case condenses on no DOF: use a zero force on an empty set
    let zero = support::hbm::PolynomialSprings {
        k1: vec![],
        k3: vec![],
    };
    let system = HbmSystem::new(HarmonicLayout::new(1, 8).unwrap(), &setup.linear, &zero).unwrap();
    let opts = case_continuation(&case).unwrap();
    let frf = frequency_response(&system, &opts, &ResponseOptions::default(), &mut |_| {}).unwrap();
    assert!(frf.points.len() > 10);
    let k = dense(&[&[3.0, -1.0, 0.0], &[-1.0, 2.0, -1.0], &[0.0, -1.0, 1.0]]);
    let m = dense(&[&[1.0, 0.0, 0.0], &[0.0, 1.0, 0.0], &[0.0, 0.0, 2.0]]);
    for p in &frf.points {
        let w = p.omega;
        let d = Mat::from_fn(3, 3, |i, j| {
            c64::new(
                k[(i, j)] - w * w * m[(i, j)],
                w * (0.01 * m[(i, j)] + 0.02 * k[(i, j)]),
            )
        });
        let x = complex_solve(
            &d,
            &[c64::new(0.0, 0.0), c64::new(0.0, 0.0), c64::new(0.5, 0.0)],
        );
        for (o, row) in [0usize, 2].iter().enumerate() {
            let got = p.response.harmonics[o][1];
            assert!(
                (got - x[*row]).norm() <= 1e-10 * x[2].norm(),
                "ω {w} row {row}: {got} vs {}",
                x[*row]
            );
        }
    }
}

#[test]
fn element_rows_and_defaults() {
    let dir = tempfile::tempdir().unwrap();
    write_chain(dir.path());
    let elements = "\n[[element]]\nkind = \"friction\"\ntangential = { dofs = [2, 0], weights = [1.0, -1.0] }\nkt = 1.0\nmu = 0.3\nn0 = 1.0\n\n[[element]]\nkind = \"friction\"\ntangential = { dofs = [2], weights = [1.0] }\nkt = 1.0\nmu = 0.3\nn0 = 1.0\n";
    let case = chain_case(dir.path(), elements).unwrap();
    let model = model::build(&case, &mut |_| {}).unwrap();
    let setup = matrix_setup(&case, &model).unwrap();
    assert_eq!(setup.nonlinear_rows, vec![0, 2]);
    assert_eq!(setup.output_rows, vec![2], "default: the excitation rows");
    assert_eq!(setup.nonlinear_position(2), Some(1));
    assert_eq!(setup.linear.n_condensed(), 2);
}

#[test]
fn bad_rows_name_the_key() {
    let dir = tempfile::tempdir().unwrap();
    write_chain(dir.path());
    let case = chain_case(dir.path(), "\n[response]\ndofs = [7]\n").unwrap();
    let model = model::build(&case, &mut |_| {}).unwrap();
    let e = matrix_setup(&case, &model).unwrap_err();
    assert!(
        e.to_string().contains("response.dofs") && e.to_string().contains("row 7"),
        "{e}"
    );
    let bad_element = "\n[[element]]\nkind = \"friction\"\ntangential = { dofs = [3], weights = [1.0] }\nkt = 1.0\nmu = 0.3\nn0 = 1.0\n";
    let case = chain_case(dir.path(), bad_element).unwrap();
    let e = matrix_setup(&case, &model).unwrap_err();
    assert!(e.to_string().contains("element[0].tangential.dofs"), "{e}");
    assert_eq!(e.exit_code(), 2);
}
