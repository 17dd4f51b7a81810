//! The harmonic balance of a matrix case on modal coordinates (`[harmonic_balance] modes`,
//! `nlrom::problem::modal_case`): with every mode the same solutions as on the physical rows,
//! through a fold with slip and separation; a stuck case against the closed-form linear
//! response with Rayleigh damping (`nlrom solve` end to end); the sparse eigensolver's modes
//! against the closed form; beyond the dense limit; bad input.

mod support;

use std::f64::consts::PI;
use std::path::Path;

use faer::{c64, Mat};
use nlrom::case::Case;
use nlrom::commands::progress::Reporter;
use nlrom::commands::solve::{solve_case, SolveOptions, SolveOutcome};
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::frf::frequency_response;
use nlrom::hbm::response::output_response;
use nlrom::hbm::{FrequencyPath, HbmSystem, ResponseOptions};
use nlrom::model;
use nlrom::nonlinear::{solve_fixed, NewtonOptions, ParameterSystem};
use nlrom::problem::matrix_case::{matrix_elements, matrix_setup};
use nlrom::problem::modal_case::modal_setup;
use nlrom::problem::rom_store::RomPolicy;
use nlrom::problem::settings::case_continuation;
use support::cli::{nlrom, root, stderr};
use support::hbm::{complex_solve, layout_index};

/// A fixed–free chain of n masses m_i = 1 + 0.1 i (kg) joined by springs k_i = 1 + 0.05 i
/// (N/m, spring i between mass i − 1 and mass i, spring 0 to ground), in Matrix Market files.
fn write_chain(dir: &Path, n: usize) {
    write_chain_of(dir, n, |i| 1.0 + 0.1 * i as f64, |i| 1.0 + 0.05 * i as f64);
}

/// A fixed–free chain of n unit masses joined by unit springs, in Matrix Market files.
fn write_uniform_chain(dir: &Path, n: usize) {
    write_chain_of(dir, n, |_| 1.0, |_| 1.0);
}

/// A fixed–free chain of n masses `mass(i)` (kg) joined by springs `spring(i)` (N/m, spring i
/// between mass i − 1 and mass i, spring 0 to ground): K.mtx and M.mtx in `dir`.
fn write_chain_of(
    dir: &Path,
    n: usize,
    mass: impl Fn(usize) -> f64,
    spring: impl Fn(usize) -> f64,
) {
    let mut k = Vec::new();
    for i in 0..n {
        let diagonal = spring(i) + if i + 1 < n { spring(i + 1) } else { 0.0 };
        k.push(format!("{} {} {diagonal}", i + 1, i + 1));
        if i + 1 < n {
            k.push(format!("{} {} {}", i + 2, i + 1, -spring(i + 1)));
        }
    }
    let m: Vec<String> = (0..n)
        .map(|i| format!("{} {} {}", i + 1, i + 1, mass(i)))
        .collect();
    for (name, entries) in [("K.mtx", k), ("M.mtx", m)] {
        std::fs::write(
            dir.join(name),
            format!(
                "%%MatrixMarket matrix coordinate real symmetric\n{n} {n} {}\n{}\n",
                entries.len(),
                entries.join("\n")
            ),
        )
        .unwrap();
    }
}

/// The chain case with Rayleigh damping [0.01 1/s, 0.02 s], 0.3 N at the last mass, and `extra`
/// (elements, harmonic balance, continuation).
fn chain_case(dir: &Path, n: usize, extra: &str) -> nlrom::Result<Case> {
    let text = format!(
        "[model]\nstiffness = \"K.mtx\"\nmass = \"M.mtx\"\ndamping = {{ rayleigh = [0.01, 0.02] }}\n\n[excitation]\ndofs = [{}]\nforce = [0.3]\n\n[response]\ndofs = [0, 4, {}]\n{extra}",
        n - 1,
        n - 1
    );
    Case::from_str(&text, &dir.join("case.toml"))
}

/// A friction element on row 3 with the normal approach of row 4 (k_t = 0.5, k_n = 1 N/m,
/// μ = 0.5, n0 = 0.05 N: it slips and separates near resonance) and a Jenkins element on the
/// last row (k_t = 0.5 N/m, slip force 0.02 N).
fn elements(n: usize) -> String {
    format!(
        "\n[[element]]\nkind = \"friction\"\ntangential = {{ dofs = [3], weights = [1.0] }}\nnormal = {{ dofs = [4], weights = [1.0] }}\nkt = 0.5\nkn = 1.0\nmu = 0.5\nn0 = 0.05\n\n[[element]]\nkind = \"friction\"\ntangential = {{ dofs = [{}], weights = [1.0] }}\nkt = 0.5\nmu = 0.4\nn0 = 0.05\n",
        n - 1
    )
}

/// `nlrom solve` on `case`, silently.
fn solve(case: &Case) -> nlrom::Result<SolveOutcome> {
    solve_case(
        case,
        &SolveOptions::new(RomPolicy::ReadIfMatching),
        &Reporter::silent(),
    )
}

/// Largest |a − b| over the outputs' harmonics, relative to the largest |b|.
fn relative_difference(a: &[Vec<c64>], b: &[Vec<c64>]) -> f64 {
    let scale = b.iter().flatten().map(|v| v.norm()).fold(0.0_f64, f64::max);
    a.iter()
        .flatten()
        .zip(b.iter().flatten())
        .map(|(x, y)| (x - y).norm())
        .fold(0.0_f64, f64::max)
        / scale
}

/// With every mode (8 of 8), the modal case's solutions are the physical case's: along a curve
/// of 3 harmonics through the first resonance (both elements slipping, the first separating),
/// each modal point's contact motion Φ_c q solves the physical harmonic balance (scaled
/// residual ≤ 1e-10) and gives the same output harmonics as the physical solution there
/// (≤ 1e-8 of the largest). This checks the case's rows, the excitation's projection, the
/// Rayleigh ratios ζ_r = α/(2ω_r) + βω_r/2 and the output rows.
#[test]
fn every_mode_gives_the_physical_solutions() {
    let dir = tempfile::tempdir().unwrap();
    let n = 8;
    write_chain(dir.path(), n);
    let extra = format!(
        "{}\n[harmonic_balance]\nharmonics = 3\ntime_samples = 64\nmodes = {n}\n\n[continuation]\nstart_rad_s = 0.1\nend_rad_s = 0.35\nstep_rad_s = 0.005\n",
        elements(n)
    );
    let case = chain_case(dir.path(), n, &extra).unwrap();
    let model = model::build(&case, &mut |_| {}).unwrap();
    let setup = modal_setup(&case, &model, n).unwrap();
    assert_eq!(setup.rows.nonlinear_rows, vec![3, 4, n - 1]);
    let layout = HarmonicLayout::new(3, 64).unwrap();
    let modal_linear = setup.modal.linear_model(3).unwrap();
    let modal_force = setup
        .modal
        .project(matrix_elements(&case, &model, &setup.rows.nonlinear_rows).unwrap())
        .unwrap();
    let modal_system = HbmSystem::new(layout, &modal_linear, &modal_force).unwrap();
    let physical = matrix_setup(&case, &model).unwrap();
    let physical_elements = matrix_elements(&case, &model, &physical.nonlinear_rows).unwrap();
    let physical_system = HbmSystem::new(layout, &physical.linear, &physical_elements).unwrap();
    let path = FrequencyPath {
        system: &physical_system,
        level: 1.0,
    };
    let mut opts = case_continuation(&case).unwrap();
    opts.newton.tolerance = 1e-11;
    let response = ResponseOptions::default();
    let frf = frequency_response(&modal_system, &opts, &response, &mut |_| {}).unwrap();
    assert!(frf.points.len() >= 30, "{} points", frf.points.len());
    let shapes = setup.modal.contact_shapes();
    let tight = NewtonOptions {
        tolerance: 1e-11,
        ..NewtonOptions::default()
    };
    let (mut worst, mut worst_residual, mut largest) = (0.0_f64, 0.0_f64, 0.0_f64);
    for p in &frf.points {
        let nc = shapes.nrows();
        let mut exact = vec![0.0; layout.len(nc)];
        for c in 0..layout.coefficients() {
            for i in 0..nc {
                exact[layout_index(&layout, c, i, nc)] = (0..n)
                    .map(|r| shapes[(i, r)] * p.q[layout_index(&layout, c, r, n)])
                    .sum::<f64>();
            }
        }
        let mut r = vec![0.0; exact.len()];
        path.evaluate_residual(&exact, p.omega, &p.state, &mut r)
            .unwrap();
        let residual = r.iter().map(|v| v * v).sum::<f64>().sqrt() / path.residual_scale();
        assert!(
            residual <= 1e-10,
            "ω = {}: physical residual {residual:.2e}",
            p.omega
        );
        worst_residual = worst_residual.max(residual);
        let sol = solve_fixed(&path, &exact, p.omega, &p.state, &tight).unwrap();
        let want = output_response(&physical_system, &sol.x, p.omega, 1.0, &response).unwrap();
        let got = setup
            .modal
            .physical_response(&p.response, &response)
            .unwrap();
        let rel = relative_difference(&got.harmonics, &want.harmonics);
        assert!(
            rel <= 1e-8,
            "ω = {}: relative difference {rel:.2e}",
            p.omega
        );
        worst = worst.max(rel);
        largest = largest.max(want.amplitude[2]);
    }
    // near the resonance the Jenkins element slips: k_t |u| > slip force 0.02 N
    assert!(0.5 * largest > 0.02 * 2.0, "tip amplitude {largest}");
    println!(
        "{} points ({:?}): largest physical residual {worst_residual:.1e}, largest relative difference {worst:.2e}, tip amplitude up to {largest:.3} m",
        frf.points.len(),
        frf.end
    );
}

/// `nlrom solve` on the modal case end to end, with both elements stuck (slip forces 1e6 N): the
/// elements are springs k_t, so every point's first harmonic at the output rows equals the
/// closed-form response x = (K + K_t − ω²M + iω(αM + βK))⁻¹ f with every mode (≤ 1e-9 of the
/// largest), and with the 4 lowest of the 8 modes differs from it by less than with 2.
#[test]
fn a_stuck_modal_case_gives_the_linear_response() {
    let dir = tempfile::tempdir().unwrap();
    let n = 8;
    write_chain(dir.path(), n);
    let k = nlrom::matrix_io::read_real_matrix(&dir.path().join("K.mtx"))
        .unwrap()
        .to_dense();
    let m = nlrom::matrix_io::read_real_matrix(&dir.path().join("M.mtx"))
        .unwrap()
        .to_dense();
    let stuck = format!(
        "\n[[element]]\nkind = \"friction\"\ntangential = {{ dofs = [3], weights = [1.0] }}\nkt = 0.5\nmu = 0.5\nn0 = 2e6\n\n[[element]]\nkind = \"friction\"\ntangential = {{ dofs = [{}], weights = [1.0] }}\nkt = 0.5\nmu = 0.5\nn0 = 2e6\n",
        n - 1
    );
    let mut kt = k.clone();
    kt[(3, 3)] += 0.5;
    kt[(n - 1, n - 1)] += 0.5;
    let outputs = [0usize, 4, n - 1];
    let error_with = |modes: usize| -> f64 {
        let extra = format!(
            "{stuck}\n[harmonic_balance]\nharmonics = 1\nmodes = {modes}\n\n[continuation]\nstart_rad_s = 0.1\nend_rad_s = 0.6\nstep_rad_s = 0.02\n"
        );
        let case = chain_case(dir.path(), n, &extra).unwrap();
        let out = solve(&case).unwrap();
        let points = &out.results.frfs[0].points;
        assert!(points.len() >= 20, "{} points", points.len());
        let mut worst = 0.0_f64;
        for p in points {
            let w = p.omega;
            let d = Mat::from_fn(n, n, |i, j| {
                c64::new(
                    kt[(i, j)] - w * w * m[(i, j)],
                    w * (0.01 * m[(i, j)] + 0.02 * k[(i, j)]),
                )
            });
            let mut f = vec![c64::new(0.0, 0.0); n];
            f[n - 1] = c64::new(0.3, 0.0);
            let x = complex_solve(&d, &f);
            let scale = outputs.iter().map(|&r| x[r].norm()).fold(0.0, f64::max);
            for (o, &row) in outputs.iter().enumerate() {
                // harmonics of output o: H + 1 = 2 values, the first harmonic second
                let got = p.harmonics[o * 2 + 1];
                worst = worst.max((got - x[row]).norm() / scale);
            }
        }
        worst
    };
    let full = error_with(n);
    assert!(full <= 1e-9, "every mode: relative error {full:.2e}");
    let (two, four) = (error_with(2), error_with(4));
    assert!(
        four < two && two > 1e-6,
        "2 modes {two:.2e}, 4 modes {four:.2e}"
    );
    println!("relative error of the first harmonic: 8 modes {full:.1e}, 4 modes {four:.1e}, 2 modes {two:.1e}");
}

/// On a uniform fixed–free chain of 3000 unit masses and unit springs the modes come from the
/// sparse shift-invert eigensolver; they equal the closed form ω_r = 2 sin((2r − 1)π/(2(2N+1)))
/// rad/s, φ_r(j) = 2/√(2N+1) sin((2r − 1)πj/(2N+1)) at node j = row + 1: frequencies to 1e-9
/// relative, and the sign-free products φ_r(4) φ_r(N) of each mode at a contact row and the last
/// row to 1e-9 of the largest.
#[test]
fn sparse_modes_equal_the_closed_form() {
    let dir = tempfile::tempdir().unwrap();
    let n = 3000;
    write_uniform_chain(dir.path(), n);
    let extra = format!(
        "{}\n[harmonic_balance]\nmodes = 6\n\n[continuation]\nstart_rad_s = 0.01\nend_rad_s = 0.02\nstep_rad_s = 0.001\n",
        elements(n)
    );
    let case = chain_case(dir.path(), n, &extra).unwrap();
    let model = model::build(&case, &mut |_| {}).unwrap();
    let setup = modal_setup(&case, &model, 6).unwrap();
    let shapes = setup.modal.contact_shapes();
    let denominator = (2 * n + 1) as f64;
    let phi = |r: usize, j: usize| {
        2.0 / denominator.sqrt() * ((2 * r - 1) as f64 * PI * j as f64 / denominator).sin()
    };
    // contact rows 3, 4, n − 1 (ascending): nodes 4, 5, n
    let products: Vec<(f64, f64)> = (1..=6)
        .map(|r| {
            (
                shapes[(0, r - 1)] * shapes[(2, r - 1)],
                phi(r, 4) * phi(r, n),
            )
        })
        .collect();
    let scale = products.iter().map(|p| p.1.abs()).fold(0.0, f64::max);
    for r in 1..=6 {
        let omega = 2.0 * ((2 * r - 1) as f64 * PI / (2.0 * denominator)).sin();
        let f_exact = omega / (2.0 * PI);
        let rel = (setup.frequencies_hz[r - 1] - f_exact).abs() / f_exact;
        assert!(
            rel <= 1e-9,
            "mode {r}: {} vs {f_exact} Hz",
            setup.frequencies_hz[r - 1]
        );
        let (got, want) = products[r - 1];
        assert!(
            (got - want).abs() <= 1e-9 * scale,
            "mode {r}: φ(4)φ(N) {got:e} vs {want:e}"
        );
    }
}

/// Bad input names the key: more modes than free DOF, `modes = 0`, an external damping matrix,
/// `modes` on a case that is not a matrix case.
#[test]
fn bad_modal_input_names_the_key() {
    let dir = tempfile::tempdir().unwrap();
    let n = 8;
    write_chain(dir.path(), n);
    let message = |extra: &str| -> String {
        let case = match chain_case(dir.path(), n, extra) {
            Ok(c) => c,
            Err(e) => return e.to_string(),
        };
        match solve(&case) {
            Ok(_) => "solved".to_string(),
            Err(e) => e.to_string(),
        }
    };
    let range = "\n[continuation]\nstart_rad_s = 0.1\nend_rad_s = 0.2\nstep_rad_s = 0.05\n";
    let too_many = message(&format!(
        "{}\n[harmonic_balance]\nmodes = 9\n{range}",
        elements(n)
    ));
    assert!(
        too_many.contains("harmonic_balance.modes") && too_many.contains("1 to 8"),
        "{too_many}"
    );
    let zero = message(&format!(
        "{}\n[harmonic_balance]\nmodes = 0\n{range}",
        elements(n)
    ));
    assert!(zero.contains("harmonic_balance.modes"), "{zero}");
    std::fs::write(
        dir.path().join("C.mtx"),
        "%%MatrixMarket matrix coordinate real symmetric\n8 8 1\n1 1 0.1\n",
    )
    .unwrap();
    let text = format!(
        "[model]\nstiffness = \"K.mtx\"\nmass = \"M.mtx\"\ndamping = {{ matrix = \"C.mtx\" }}\n\n[excitation]\ndofs = [7]\nforce = [0.3]\n{}\n[harmonic_balance]\nmodes = 4\n{range}",
        elements(n)
    );
    let case = Case::from_str(&text, &dir.path().join("c.toml")).unwrap();
    let matrix = solve(&case).unwrap_err().to_string();
    assert!(
        matrix.contains("model.damping.matrix") && matrix.contains("modal"),
        "{matrix}"
    );
    let sector = Case::from_str(
        "[model]\nmesh = \"sector.msh\"\nmaterial = { young = 2e11, poisson = 0.3, density = 7800.0 }\nclamp = [\"hub\"]\n\n[reduction]\nkeep = [\"tip\"]\ninterface_modes = 4\n\n[[contact]]\nname = \"shroud\"\ncontact = \"a\"\ntarget = \"b\"\nkt = 1e5\nkn = 1e5\nmu = 0.3\nn0 = 10.0\n\n[excitation]\ngroup = \"tip\"\nforce = [1.0, 0.0, 0.0]\n\n[harmonic_balance]\nmodes = 4\n\n[continuation]\nstart_hz = 100.0\nend_hz = 200.0\nstep_hz = 1.0\n",
        &dir.path().join("s.toml"),
    )
    .unwrap_err()
    .to_string();
    assert!(
        sector.contains("harmonic_balance.modes") && sector.contains("matrix rows"),
        "{sector}"
    );
}

/// A matrix model beyond the dense limit of the physical rows (5 000 free DOF): refused on the
/// physical rows with the limit named, solved on 4 modal coordinates from the sparse
/// eigensolver (H = 1, around the second mode at 5.93e-4 rad/s; every point's tip response
/// finite and non-zero).
#[test]
fn modal_coordinates_lift_the_dense_limit() {
    let dir = tempfile::tempdir().unwrap();
    let n = 5000;
    write_chain(dir.path(), n);
    let range =
        "\n[continuation]\nstart_rad_s = 0.0005\nend_rad_s = 0.0006\nstep_rad_s = 0.00002\n";
    let run = |modes: &str| {
        let case = chain_case(dir.path(), n, &format!("{}{modes}{range}", elements(n))).unwrap();
        solve(&case)
    };
    let dense = run("").unwrap_err().to_string();
    assert!(dense.contains("4000"), "{dense}");
    let out = run("\n[harmonic_balance]\nmodes = 4\n").unwrap();
    let points = &out.results.frfs[0].points;
    assert!(points.len() >= 5, "{} points", points.len());
    let tip: Vec<f64> = points.iter().map(|p| p.harmonics[5].norm()).collect();
    assert!(tip.iter().all(|a| a.is_finite() && *a > 0.0), "{tip:?}");
    println!(
        "{} points from {} to {} rad/s, tip amplitude {:.3e} → {:.3e} m",
        points.len(),
        points[0].omega,
        points[points.len() - 1].omega,
        tip[0],
        tip[tip.len() - 1]
    );
}

/// `nlrom solve` warns, naming the key, when the highest mode of a truncated basis lies below
/// twice H × the highest swept frequency (the bundled 3-DOF chain, H = 7 up to 2.2 rad/s, with
/// 2 of its 3 modes: highest mode 0.198 Hz), and not with every mode.
#[test]
fn a_basis_below_the_swept_harmonics_is_warned_about() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(root().join("cases/chain3_jenkins.toml")).unwrap();
    let chain = root().join("cases/chain3");
    let text = text.replace("\"chain3/", &format!("\"{}/", chain.display()));
    for (modes, warned) in [(2, true), (3, false)] {
        let case = dir.path().join(format!("chain{modes}.toml"));
        std::fs::write(
            &case,
            text.replace(
                "time_samples = 1024",
                &format!("time_samples = 1024\nmodes = {modes}"),
            ),
        )
        .unwrap();
        let out = nlrom(&[
            "solve",
            case.to_str().unwrap(),
            "-o",
            dir.path().join("r.h5").to_str().unwrap(),
        ]);
        let err = stderr(&out);
        assert!(out.status.success(), "{err}");
        assert_eq!(
            err.contains("warning: harmonic_balance.modes"),
            warned,
            "{modes} modes: {err}"
        );
    }
}
