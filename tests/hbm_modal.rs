//! Harmonic balance on modal coordinates (`nlrom::hbm::modal`) against the physical-coordinate
//! path and against finite differences:
//! - a fixed–free chain of 8 unit masses with modal damping and two friction elements (one with
//!   normal load variation and separation) solved with the full modal basis (m = n) gives the
//!   physical path's response at every point of its frequency response (1e-8 relative);
//! - the projected Jacobian Φ_cᵀ J Φ_c, formed element by element, equals the projection of the
//!   dense physical Jacobian (1e-12) and central differences of the projected forces (1e-6), on a
//!   synthetic interface where some pairs stick all period and others slip and separate;
//! - with a truncated basis (the first m of 24 chain modes) the error of the tip response
//!   decreases as m grows;
//! - shapes that do not match are errors naming the argument.

mod support;

use faer::{c64, Mat};
use nlrom::case::WeightedDofs;
use nlrom::contact::grounded::{DofElement, DofElements};
use nlrom::contact::law::ContactParams;
use nlrom::continuation::ContinuationOptions;
use nlrom::harmonics::{HarmonicForce, HarmonicLayout, JacobianMut};
use nlrom::hbm::frf::frequency_response;
use nlrom::hbm::modal::ModalModel;
use nlrom::hbm::response::output_response;
use nlrom::hbm::{FrequencyPath, HbmSystem, LinearModel, ResponseOptions};
use nlrom::nonlinear::{norm, solve_fixed, NewtonOptions, ParameterSystem, SolverChoice};
use support::chain;
use support::hbm::{layout_index, synthetic_modal_interface};

/// Newton to 1e-11 of the force level (the solutions compared to 1e-8).
fn tight() -> NewtonOptions {
    NewtonOptions {
        tolerance: 1e-11,
        increment_tolerance: 1e-10,
        linear_solver: SolverChoice::Dense,
        ..NewtonOptions::default()
    }
}

/// A chain's matrices K, M, C, its mass-normalised modes Φ (n × n) and ω_r (rad/s).
struct Chain {
    k: Mat<f64>,
    m: Mat<f64>,
    c: Mat<f64>,
    phi: Mat<f64>,
    omega: Vec<f64>,
}

/// A fixed–free chain of n unit masses (first mode at 1 rad/s) with modal damping ζ = 0.02:
/// K, M = I, C = Φ diag(2ζω_r) Φᵀ.
fn chain_model(n: usize) -> Chain {
    let k = chain::spring_for(n, 1.0);
    let mut stiffness = Mat::<f64>::zeros(n, n);
    for (i, j, v) in chain::stiffness(n, k, 0) {
        stiffness[(i, j)] = v;
        stiffness[(j, i)] = v;
    }
    let phi = Mat::from_fn(n, n, |j, r| chain::mode(n, r + 1, j + 1));
    let omega: Vec<f64> = (1..=n).map(|r| chain::omega2(n, k, r).sqrt()).collect();
    let damping = Mat::from_fn(n, n, |i, j| {
        (0..n)
            .map(|r| phi[(i, r)] * 2.0 * 0.02 * omega[r] * phi[(j, r)])
            .sum()
    });
    Chain {
        k: stiffness,
        m: Mat::identity(n, n),
        c: damping,
        phi,
        omega,
    }
}

/// The rows `rows` and the first m columns of Φ.
fn rows_of(phi: &Mat<f64>, rows: &[usize], m: usize) -> Mat<f64> {
    Mat::from_fn(rows.len(), m, |i, r| phi[(rows[i], r)])
}

fn one(d: usize) -> WeightedDofs {
    WeightedDofs {
        dofs: vec![d],
        weights: vec![1.0],
    }
}

/// On the 3 contact DOFs (chain rows 3, 4, 7): a friction element reading u_t = row 3 with the
/// normal approach row 4 (k_t = 5, k_n = 10 N/m, μ = 0.5, n0 = 0.5 N) and a Jenkins element at
/// the tip (k_t = 5 N/m, slip force 0.2 N).
fn chain_elements() -> DofElements {
    DofElements::new(
        vec![
            DofElement {
                tangential: one(0),
                normal: Some(one(1)),
                params: ContactParams::new(5.0, 10.0, 0.5, 0.5, "test").unwrap(),
            },
            DofElement {
                tangential: one(2),
                normal: None,
                params: ContactParams::new(5.0, 0.0, 0.5, 0.4, "test").unwrap(),
            },
        ],
        3,
    )
    .unwrap()
}

/// The physical harmonic vector of `rows.len()` DOFs for the modal one `q` (m modes): Φ_rows q
/// per coefficient.
fn physical(layout: &HarmonicLayout, shapes: &Mat<f64>, q: &[f64]) -> Vec<f64> {
    let (nc, m) = (shapes.nrows(), shapes.ncols());
    let mut u = vec![0.0; layout.len(nc)];
    for c in 0..layout.coefficients() {
        for d in 0..nc {
            u[layout_index(layout, c, d, nc)] = (0..m)
                .map(|r| shapes[(d, r)] * q[layout_index(layout, c, r, m)])
                .sum();
        }
    }
    u
}

/// Largest |a − b| over the outputs' harmonics, relative to the largest |b|.
fn relative_difference(a: &[Vec<c64>], b: &[Vec<c64>]) -> f64 {
    let mut diff = 0.0_f64;
    let mut scale = 0.0_f64;
    for (ra, rb) in a.iter().zip(b) {
        for (x, y) in ra.iter().zip(rb) {
            diff = diff.max((x - y).norm());
            scale = scale.max(y.norm());
        }
    }
    diff / scale
}

#[test]
fn full_modal_basis_gives_the_physical_frequency_response() {
    let n = 8;
    let h = 3;
    let Chain {
        k,
        m,
        c,
        phi,
        omega,
    } = chain_model(n);
    let contact = [3, 4, 7];
    let outputs = [0, 4, 7];
    let mut force = vec![0.0; n];
    force[7] = 0.3;
    let linear = LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        Some(c.as_ref()),
        &force,
        contact.to_vec(),
        outputs.to_vec(),
        h,
    )
    .unwrap();
    let layout = HarmonicLayout::new(h, 64).unwrap();
    let elements = chain_elements();
    let physical_system = HbmSystem::new(layout, &linear, &elements).unwrap();
    let physical_path = FrequencyPath {
        system: &physical_system,
        level: 1.0,
    };
    let modal = ModalModel::new(
        omega,
        vec![0.02; n],
        rows_of(&phi, &contact, n),
        rows_of(&phi, &[7], n),
        vec![0.3],
        rows_of(&phi, &outputs, n),
    )
    .unwrap();
    let modal_linear = modal.linear_model(h).unwrap();
    let modal_force = modal.project(chain_elements()).unwrap();
    let modal_system = HbmSystem::new(layout, &modal_linear, &modal_force).unwrap();
    // no block partition: every solver choice takes the dense LU
    assert!(modal_system.jacobian_blocks().is_empty());
    let mut opts = ContinuationOptions::new(0.7, 1.6, 0.02);
    opts.newton.tolerance = 1e-11;
    let response = ResponseOptions::default();
    let frf = frequency_response(&modal_system, &opts, &response, &mut |_| {}).unwrap();
    assert!(frf.points.len() >= 20, "{} points", frf.points.len());
    let contact_shapes = rows_of(&phi, &contact, n);
    let (mut worst, mut worst_residual, mut largest_tip) = (0.0_f64, 0.0_f64, 0.0_f64);
    let mut slipping = 0;
    for p in &frf.points {
        // the modal solution's contact motion Φ_c q solves the physical equations ...
        let exact = physical(&layout, &contact_shapes, &p.q);
        let mut r = vec![0.0; exact.len()];
        physical_path
            .evaluate_residual(&exact, p.omega, &p.state, &mut r)
            .unwrap();
        let residual = norm(&r) / physical_path.residual_scale();
        assert!(
            residual <= 1e-10,
            "ω = {}: physical residual {residual:.2e}",
            p.omega
        );
        worst_residual = worst_residual.max(residual);
        // ... and gives the same response at the output DOFs
        let sol = solve_fixed(&physical_path, &exact, p.omega, &p.state, &tight()).unwrap();
        let want = output_response(&physical_system, &sol.x, p.omega, 1.0, &response).unwrap();
        let got = modal.physical_response(&p.response, &response).unwrap();
        let rel = relative_difference(&got.harmonics, &want.harmonics);
        assert!(
            rel <= 1e-8,
            "ω = {}: relative difference {rel:.2e}",
            p.omega
        );
        worst = worst.max(rel);
        largest_tip = largest_tip.max(want.amplitude[2]);
        // the Jenkins element slips where its force would exceed 0.2 N
        if 5.0 * want.amplitude[2] > 0.2 {
            slipping += 1;
        }
    }
    let stuck = frf.points.len() - slipping;
    assert!(
        slipping >= 5 && stuck >= 5,
        "{slipping} points in slip, {stuck} stuck"
    );
    println!(
        "{} points from 0.7 to 1.6 rad/s ({:?}), largest tip amplitude {largest_tip:.3} m, {slipping} points with the tip in slip, {stuck} stuck: largest physical residual of a modal solution {worst_residual:.1e}, largest relative difference of the responses {worst:.2e}",
        frf.points.len(),
        frf.end
    );
}

#[test]
fn projected_jacobian_equals_the_dense_projection_and_central_differences() {
    let (contact_dofs, modes, h) = (48, 10, 3);
    let (model, set, layout, q) = synthetic_modal_interface(contact_dofs, modes, h, 32, 4).unwrap();
    let (_, reference, _, _) = synthetic_modal_interface(contact_dofs, modes, h, 32, 4).unwrap();
    let shapes = model.contact_shapes().to_owned();
    let force = model.project(set).unwrap();
    let nq = q.len();
    let nu = layout.len(contact_dofs);
    let evaluate = |x: &[f64], jacobian: Option<&mut Mat<f64>>| {
        let mut state = force.initial_state();
        let mut f = vec![0.0; nq];
        let target = jacobian.map(|j| JacobianMut::Dense(j.as_mut()));
        force
            .evaluate_into(&layout, x, 0.8, &mut state, &mut f, target, None)
            .unwrap();
        f
    };
    let mut jac = Mat::<f64>::zeros(nq, nq);
    let f = evaluate(&q, Some(&mut jac));
    let (constant, coupled) = force.last_split();
    assert!(
        constant > 0 && coupled > 0,
        "{constant} constant, {coupled} coupled"
    );
    // the dense physical Jacobian and forces at u = Φ_c q, projected: Ψᵀ J Ψ, Ψᵀ F
    let u = physical(&layout, &shapes, &q);
    let mut state = reference.initial_state();
    let mut fu = vec![0.0; nu];
    let mut ju = Mat::<f64>::zeros(nu, nu);
    reference
        .evaluate(&layout, &u, &mut state, &mut fu, Some(ju.as_mut()))
        .unwrap();
    let psi = Mat::from_fn(nu, nq, |i, j| {
        let (di, ci) = split(&layout, i, contact_dofs);
        let (rj, cj) = split(&layout, j, modes);
        if ci == cj {
            shapes[(di, rj)]
        } else {
            0.0
        }
    });
    let projected = psi.transpose() * &ju * &psi;
    let scale = (0..nq)
        .flat_map(|j| (0..nq).map(move |i| (i, j)))
        .fold(0.0_f64, |a, (i, j)| a.max(jac[(i, j)].abs()));
    let mut worst = 0.0_f64;
    for j in 0..nq {
        for i in 0..nq {
            worst = worst.max((jac[(i, j)] - projected[(i, j)]).abs());
        }
    }
    assert!(
        worst <= 1e-12 * scale,
        "projection: {worst:.2e} of {scale:.2e}"
    );
    let fp: Vec<f64> = (0..nq)
        .map(|j| (0..nu).map(|i| psi[(i, j)] * fu[i]).sum())
        .collect();
    let f_scale = f.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    for (a, b) in f.iter().zip(&fp) {
        assert!((a - b).abs() <= 1e-12 * f_scale, "force {a} vs {b}");
    }
    // central differences of the projected forces
    // the forces' rounding (≈ 1e-14, from the AFT's periods) over the step: 3e-6 at 1e-8
    let step = 1e-6;
    let mut fd_worst = 0.0_f64;
    for j in 0..nq {
        let mut plus = q.clone();
        plus[j] += step;
        let mut minus = q.clone();
        minus[j] -= step;
        let (fp, fm) = (evaluate(&plus, None), evaluate(&minus, None));
        for i in 0..nq {
            let d = (fp[i] - fm[i]) / (2.0 * step);
            fd_worst = fd_worst.max((d - jac[(i, j)]).abs());
        }
    }
    assert!(
        fd_worst <= 1e-6 * scale,
        "central differences: {fd_worst:.2e} of {scale:.2e}"
    );
    println!(
        "{constant} pairs projected as constant, {coupled} in transition; against the dense projection {:.1e}, against central differences {:.1e} (relative)",
        worst / scale,
        fd_worst / scale
    );
}

/// (DOF, coefficient) of index i of the real layout of `n` DOFs.
fn split(layout: &HarmonicLayout, i: usize, n: usize) -> (usize, usize) {
    for c in 0..layout.coefficients() {
        for d in 0..n {
            if layout_index(layout, c, d, n) == i {
                return (d, c);
            }
        }
    }
    unreachable!()
}

/// The tip response of a chain of 24 masses with a Jenkins element at the tip (k_t = 5 N/m, slip
/// force 0.2 N), forced at the tip (1 N at 1.05 rad/s, above the first resonance, H = 3):
/// the first m modes give errors that decrease with m, and all 24 the physical path's response.
#[test]
fn truncated_basis_error_decreases_with_the_number_of_modes() {
    let n = 24;
    let h = 3;
    let omega_f = 1.05;
    let Chain {
        k,
        m,
        c,
        phi,
        omega,
    } = chain_model(n);
    let tip = n - 1;
    let mut force = vec![0.0; n];
    force[tip] = 1.0;
    let linear = LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        Some(c.as_ref()),
        &force,
        vec![tip],
        vec![tip],
        h,
    )
    .unwrap();
    let layout = HarmonicLayout::new(h, 64).unwrap();
    let jenkins = || {
        DofElements::new(
            vec![DofElement {
                tangential: one(0),
                normal: None,
                params: ContactParams::new(5.0, 0.0, 0.5, 0.4, "test").unwrap(),
            }],
            1,
        )
        .unwrap()
    };
    let elements = jenkins();
    let system = HbmSystem::new(layout, &linear, &elements).unwrap();
    let path = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let zero = vec![0.0; path_dim(&layout, 1)];
    let sol = solve_fixed(&path, &zero, omega_f, &elements.initial_state(), &tight()).unwrap();
    let response = ResponseOptions::default();
    let want = output_response(&system, &sol.x, omega_f, 1.0, &response).unwrap();
    assert!(
        5.0 * want.amplitude[0] > 0.2,
        "the tip does not slip: amplitude {}",
        want.amplitude[0]
    );
    let mut errors = Vec::new();
    for modes in [1, 2, 4, 8, 16, 24] {
        let modal = ModalModel::new(
            omega[..modes].to_vec(),
            vec![0.02; modes],
            rows_of(&phi, &[tip], modes),
            rows_of(&phi, &[tip], modes),
            vec![1.0],
            rows_of(&phi, &[tip], modes),
        )
        .unwrap();
        let modal_linear = modal.linear_model(h).unwrap();
        let force = modal.project(jenkins()).unwrap();
        let modal_system = HbmSystem::new(layout, &modal_linear, &force).unwrap();
        let modal_path = FrequencyPath {
            system: &modal_system,
            level: 1.0,
        };
        let zero = vec![0.0; path_dim(&layout, modes)];
        let s = solve_fixed(
            &modal_path,
            &zero,
            omega_f,
            &force.initial_state(),
            &tight(),
        )
        .unwrap();
        let coordinates = output_response(&modal_system, &s.x, omega_f, 1.0, &response).unwrap();
        let got = modal.physical_response(&coordinates, &response).unwrap();
        errors.push((modes, relative_difference(&got.harmonics, &want.harmonics)));
    }
    println!("relative error of the tip response against the physical path: {errors:?}");
    for w in errors.windows(2) {
        assert!(w[1].1 < w[0].1, "{errors:?}");
    }
    assert!(errors[5].1 <= 1e-8, "{errors:?}");
}

/// Unknowns of `n` DOFs.
fn path_dim(layout: &HarmonicLayout, n: usize) -> usize {
    layout.len(n)
}

/// Mismatched shapes and values are input errors naming the argument.
#[test]
fn mismatched_modal_data_are_keyed_errors() {
    let shapes = |rows: usize, cols: usize| Mat::from_fn(rows, cols, |i, j| (i + j) as f64);
    // frequencies, damping ratios, (rows, columns) of the contact shapes, forced rows
    let build = |w: &[f64], z: &[f64], contact: (usize, usize), forced: usize| {
        ModalModel::new(
            w.to_vec(),
            z.to_vec(),
            shapes(contact.0, contact.1),
            shapes(forced, 2),
            vec![1.0],
            shapes(1, 2),
        )
    };
    let error = |r: nlrom::Result<ModalModel>| r.unwrap_err().to_string();
    let (w, z) = ([1.0, 2.0], [0.01, 0.01]);
    assert!(build(&w, &z, (3, 2), 1).is_ok());
    for (model, message) in [
        (
            build(&w, &z[..1], (3, 2), 1),
            "`damping_ratios` has 1 entries for 2 modes",
        ),
        (
            build(&w, &z, (3, 3), 1),
            "`contact_shapes` has 3 columns for 2 modes",
        ),
        (
            build(&w, &z, (3, 2), 2),
            "`force` has 1 entries for 2 forced DOFs",
        ),
        (build(&[1.0, -2.0], &z, (3, 2), 1), "`frequencies` has -2"),
    ] {
        let e = error(model);
        assert!(e.contains(message), "{e}");
    }
    let model = build(&w, &z, (4, 2), 1).unwrap();
    let e = model.project(chain_elements()).err().unwrap().to_string();
    assert!(
        e.contains("acts on 3 DOFs but `contact_shapes` has 4 rows"),
        "{e}"
    );
}
