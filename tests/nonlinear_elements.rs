//! The `[[element]]` kinds besides `friction` (`nlrom::contact::memoryless`, the element library of
//! Krack & Gross 2019): each force against its closed-form Fourier coefficients (cubic spring
//! ¾ k3 a³ and ¼ k3 a³; polynomial spring; quadratic damper 8/(3π) c ω² a²; the clipped cosine of
//! the unilateral spring; tanh friction in its viscous and Coulomb limits), Jacobians and ∂F/∂ω
//! against central differences on two-DOF combinations, case-file errors, and a frequency
//! response through `nlrom::commands` of an oscillator with a cubic spring and a quadratic damper
//! (both folds traced) against its one-harmonic amplitude relation.

use std::f64::consts::PI;
use std::path::{Path, PathBuf};

use faer::Mat;
use nlrom::case::{Case, FrictionElement};
use nlrom::commands::{solve_case, Reporter, RomPolicy, SolveOptions};
use nlrom::contact::grounded::DofElements;
use nlrom::harmonics::{HarmonicForce, HarmonicLayout, JacobianMut};

mod support;
use support::random::XorShift;

fn case_text(elements: &str) -> String {
    format!(
        "[model]\nstiffness = \"K.mtx\"\nmass = \"M.mtx\"\n\n[excitation]\ndofs = [0]\nforce = [1.0]\n\n{elements}"
    )
}

fn case_elements(elements: &str) -> Vec<FrictionElement> {
    Case::from_str(&case_text(elements), Path::new("/tmp/case.toml"))
        .unwrap()
        .element
}

fn case_error(elements: &str) -> String {
    Case::from_str(&case_text(elements), Path::new("/tmp/case.toml"))
        .unwrap_err()
        .to_string()
}

/// F(Q) at ω of one DOF's elements (`n` DOFs), with the Jacobian and ∂F/∂ω.
fn evaluate(
    set: &DofElements,
    layout: &HarmonicLayout,
    q: &[f64],
    omega: f64,
) -> (Vec<f64>, Mat<f64>, Vec<f64>) {
    let n = q.len();
    let mut state = set.initial_state();
    let mut f = vec![0.0; n];
    let mut jac = Mat::<f64>::zeros(n, n);
    let mut dw = vec![0.0; n];
    set.evaluate_into(
        layout,
        q,
        omega,
        &mut state,
        &mut f,
        Some(JacobianMut::Dense(jac.as_mut())),
        Some(&mut dw),
    )
    .unwrap();
    (f, jac, dw)
}

fn force(set: &DofElements, layout: &HarmonicLayout, q: &[f64], omega: f64) -> Vec<f64> {
    evaluate(set, layout, q, omega).0
}

/// One DOF, q = x0 + a cos τ (H harmonics): the force coefficients [F0, Re F1, Im F1, …].
fn single(element: &str, h: usize, n_t: usize, x0: f64, a: f64, omega: f64) -> Vec<f64> {
    let set = DofElements::from_case(&case_elements(element), 1).unwrap();
    let layout = HarmonicLayout::new(h, n_t).unwrap();
    let mut q = vec![0.0; layout.len(1)];
    q[0] = x0;
    q[1] = a;
    force(&set, &layout, &q, omega)
}

fn close(got: f64, want: f64, tol: f64, what: &str) {
    assert!(
        (got - want).abs() <= tol,
        "{what}: {got} vs closed form {want} (tolerance {tol:e})"
    );
}

/// Cubic spring under a cos τ: F1 = ¾ k3 a³, F3 = ¼ k3 a³, nothing else (exact for N_t ≥ 4H).
#[test]
fn cubic_spring_closed_form() {
    let (k3, a) = (2.5, 0.7);
    let f = single(
        "[[element]]\nkind = \"cubic_spring\"\ndisplacement = { dofs = [0], weights = [1.0] }\nk3 = 2.5\n",
        3,
        16,
        0.0,
        a,
        1.0,
    );
    close(f[1], 0.75 * k3 * a.powi(3), 1e-13, "Re F1");
    close(f[5], 0.25 * k3 * a.powi(3), 1e-13, "Re F3");
    for i in [0, 2, 3, 4, 6] {
        close(f[i], 0.0, 1e-13, &format!("F[{i}]"));
    }
}

/// Polynomial spring 1.5 x − 0.7 x² + 2 x³ under x0 + a cos τ equals its closed form
/// (x² = x0² + 2 x0 a cos τ + a²(1 + cos 2τ)/2, and the cubic of the cubic spring), and the term
/// 2 x³ alone equals the cubic spring.
#[test]
fn polynomial_spring_closed_form() {
    let (x0, a) = (0.2, 0.6);
    let f = single(
        "[[element]]\nkind = \"polynomial_spring\"\ndisplacement = { dofs = [0], weights = [1.0] }\ncoefficients = [1.5, -0.7, 2.0]\nexponents = [1, 2, 3]\n",
        3,
        16,
        x0,
        a,
        1.0,
    );
    // x³ = x0³ + 3x0²a c + 3x0 a² c² + a³ c³, c² = (1 + cos2τ)/2, c³ = (3c + cos3τ)/4.
    let f0 = 1.5 * x0 - 0.7 * (x0 * x0 + a * a / 2.0) + 2.0 * (x0.powi(3) + 1.5 * x0 * a * a);
    let f1 = 1.5 * a - 0.7 * 2.0 * x0 * a + 2.0 * (3.0 * x0 * x0 * a + 0.75 * a.powi(3));
    let f2 = -0.7 * a * a / 2.0 + 2.0 * 1.5 * x0 * a * a;
    let f3 = 2.0 * 0.25 * a.powi(3);
    for (i, want) in [(0, f0), (1, f1), (3, f2), (5, f3)] {
        close(f[i], want, 1e-13, &format!("F[{i}]"));
    }
    let cubic = single(
        "[[element]]\nkind = \"cubic_spring\"\ndisplacement = { dofs = [0], weights = [1.0] }\nk3 = 2.0\n",
        3,
        16,
        x0,
        a,
        1.0,
    );
    let poly3 = single(
        "[[element]]\nkind = \"polynomial_spring\"\ndisplacement = { dofs = [0], weights = [1.0] }\ncoefficients = [2.0]\nexponents = [3]\n",
        3,
        16,
        x0,
        a,
        1.0,
    );
    for (c, p) in cubic.iter().zip(&poly3) {
        close(*p, *c, 1e-14, "x³ term vs cubic spring");
    }
}

/// Quadratic damper c ẋ|ẋ| under a cos τ at ω: ẋ = −ωa sin τ, so f = −cω²a² sin τ|sin τ|, whose
/// first harmonic is −8/(3π) c ω² a² sin τ (Im F1 = +8/(3π) c ω² a² in the layout
/// q = Re cos − Im sin); no cosine or even harmonic; the third harmonic is −1/5 of the first
/// (sin τ|sin τ| = (8/π)(sin τ/3 − sin 3τ/15 − …)).
#[test]
fn quadratic_damper_closed_form() {
    let (c, a, omega) = (0.8, 0.5, 1.7);
    let f = single(
        "[[element]]\nkind = \"quadratic_damper\"\ndisplacement = { dofs = [0], weights = [1.0] }\nc = 0.8\n",
        3,
        4096,
        0.0,
        a,
        omega,
    );
    let im1 = 8.0 / (3.0 * PI) * c * omega * omega * a * a;
    let tol = 1e-9 * im1;
    close(f[2], im1, tol, "Im F1");
    close(f[6], -im1 / 5.0, tol, "Im F3");
    for i in [0, 1, 3, 4, 5] {
        close(f[i], 0.0, tol, &format!("F[{i}]"));
    }
}

/// Unilateral spring k max(x − g, 0) under x0 + a cos τ: the clipped cosine, in contact for
/// |τ| < θ with cos θ = (g − x0)/a: F0 = (k/π)((x0 − g)θ + a sin θ),
/// F1 = (k/π)(2(x0 − g) sin θ + a(θ + sin 2θ/2)),
/// Fn = (2k/π)((x0 − g) sin nθ/n + (a/2)(sin (n−1)θ/(n−1) + sin (n+1)θ/(n+1))), sine parts 0.
/// The sampled kink converges as N_t⁻²: 1e-6·k·a at N_t = 8192.
#[test]
fn unilateral_spring_closed_form() {
    let (k, g, x0, a) = (3.0, 0.25, 0.1, 0.6);
    let h = 4;
    let f = single(
        "[[element]]\nkind = \"unilateral_spring\"\ndisplacement = { dofs = [0], weights = [1.0] }\nk = 3.0\ngap = 0.25\n",
        h,
        8192,
        x0,
        a,
        1.0,
    );
    let theta = ((g - x0) / a).acos();
    let d = x0 - g;
    let tol = 1e-6 * k * a;
    close(f[0], k / PI * (d * theta + a * theta.sin()), tol, "F0");
    close(
        f[1],
        k / PI * (2.0 * d * theta.sin() + a * (theta + (2.0 * theta).sin() / 2.0)),
        tol,
        "Re F1",
    );
    for n in 2..=h {
        let nf = n as f64;
        let want = 2.0 * k / PI
            * (d * (nf * theta).sin() / nf
                + a / 2.0
                    * (((nf - 1.0) * theta).sin() / (nf - 1.0)
                        + ((nf + 1.0) * theta).sin() / (nf + 1.0)));
        close(f[2 * n - 1], want, tol, &format!("Re F{n}"));
    }
    for n in 1..=h {
        close(f[2 * n], 0.0, tol, &format!("Im F{n}"));
    }
    // Never in contact: no force.
    let open = single(
        "[[element]]\nkind = \"unilateral_spring\"\ndisplacement = { dofs = [0], weights = [1.0] }\nk = 3.0\ngap = 0.8\n",
        h,
        64,
        x0,
        a,
        1.0,
    );
    assert!(open.iter().all(|&x| x == 0.0), "{open:?}");
}

/// tanh friction μ n0 tanh(ẋ/ε): for ε ≫ ωa a viscous damper f_s/ε (Im F1 = f_s ωa/ε to the
/// relative cubic term (ωa/ε)²·¾/3); for ε ≪ ωa the Coulomb force, Im F1 → 4 f_s/π.
#[test]
fn tanh_friction_limits() {
    let (fs, a, omega) = (1.5, 0.4, 2.0);
    let element = |eps: f64| {
        format!("[[element]]\nkind = \"tanh_friction\"\ndisplacement = {{ dofs = [0], weights = [1.0] }}\nmu = 0.5\nn0 = 3.0\neps = {eps:e}\n")
    };
    let eps = 1e3 * omega * a;
    let f = single(&element(eps), 3, 64, 0.0, a, omega);
    let viscous = fs * omega * a / eps;
    close(f[2], viscous, 1e-6 * viscous, "viscous limit Im F1");
    close(f[1], 0.0, 1e-12, "viscous limit Re F1");
    let f = single(&element(1e-6 * omega * a), 3, 4096, 0.0, a, omega);
    close(f[2], 4.0 * fs / PI, 2e-3 * fs, "Coulomb limit Im F1");
    close(
        f[6],
        4.0 * fs / (3.0 * PI),
        2e-3 * fs,
        "Coulomb limit Im F3",
    );
}

/// Every kind on a two-DOF combination (weights −1, 1.5) with a friction element beside it: the
/// Jacobian and ∂F/∂ω equal central differences (relative 1e-6 of the largest entry).
#[test]
fn jacobians_and_frequency_derivatives_match_differences() {
    let combo = "{ dofs = [0, 1], weights = [-1.0, 1.5] }";
    let kinds = [
        "kind = \"cubic_spring\"\nk3 = 2.0".to_string(),
        "kind = \"polynomial_spring\"\ncoefficients = [1.0, -0.5, 0.3]\nexponents = [1, 2, 5]"
            .to_string(),
        "kind = \"unilateral_spring\"\nk = 4.0\ngap = 0.05".to_string(),
        "kind = \"quadratic_damper\"\nc = 0.7".to_string(),
        "kind = \"tanh_friction\"\nmu = 0.5\nn0 = 2.0\neps = 0.2".to_string(),
    ];
    for kind in &kinds {
        let text = format!(
            "[[element]]\n{kind}\ndisplacement = {combo}\n\n[[element]]\nkind = \"friction\"\ntangential = {{ dofs = [1], weights = [1.0] }}\nkt = 3.0\nmu = 0.4\nn0 = 0.2\n"
        );
        let set = DofElements::from_case(&case_elements(&text), 2).unwrap();
        for h in [1, 3, 5] {
            let layout = HarmonicLayout::new(h, 64).unwrap();
            let n = layout.len(2);
            let mut rng = XorShift(7 + h as u64);
            let q = rng.vec(n, 0.3);
            let omega = 1.3;
            let (_, jac, dw) = evaluate(&set, &layout, &q, omega);
            let mut scale: f64 = 1e-12;
            for r in 0..n {
                for c in 0..n {
                    scale = scale.max(jac[(r, c)].abs());
                }
            }
            let step = 1e-7;
            for c in 0..n {
                let (mut qp, mut qm) = (q.clone(), q.clone());
                qp[c] += step;
                qm[c] -= step;
                let (fp, fm) = (
                    force(&set, &layout, &qp, omega),
                    force(&set, &layout, &qm, omega),
                );
                for r in 0..n {
                    let fd = (fp[r] - fm[r]) / (2.0 * step);
                    assert!(
                        (fd - jac[(r, c)]).abs() <= 1e-6 * scale,
                        "{kind} H={h}: J[{r},{c}] = {} vs central difference {fd}",
                        jac[(r, c)]
                    );
                }
            }
            let (fp, fm) = (
                force(&set, &layout, &q, omega + step),
                force(&set, &layout, &q, omega - step),
            );
            let velocity = kind.contains("damper") || kind.contains("tanh");
            assert_eq!(set.reads_velocity(), velocity, "{kind}");
            for r in 0..n {
                let fd = (fp[r] - fm[r]) / (2.0 * step);
                assert!(
                    (fd - dw[r]).abs() <= 1e-6 * scale.max(1.0),
                    "{kind} H={h}: ∂F[{r}]/∂ω = {} vs central difference {fd}",
                    dw[r]
                );
                if !velocity {
                    assert_eq!(dw[r], 0.0);
                }
            }
        }
    }
}

#[test]
fn bad_elements_name_the_key() {
    let d = "displacement = { dofs = [0], weights = [1.0] }";
    let cases = [
        (format!("[[element]]\nkind = \"cubic_spring\"\n{d}\n"), "k3"),
        (
            format!("[[element]]\nkind = \"cubic_spring\"\n{d}\nk3 = 1.0\nmu = 0.2\n"),
            "element[0].mu",
        ),
        (
            format!("[[element]]\nkind = \"tanh_friction\"\n{d}\nmu = 0.2\nn0 = 1.0\neps = 0.0\n"),
            "element[0].eps",
        ),
        (
            format!("[[element]]\nkind = \"polynomial_spring\"\n{d}\ncoefficients = [1.0, 2.0]\nexponents = [3]\n"),
            "element[0].exponents",
        ),
        (
            format!("[[element]]\nkind = \"polynomial_spring\"\n{d}\ncoefficients = [1.0]\nexponents = [0]\n"),
            "element[0].exponents",
        ),
        (
            format!("[[element]]\nkind = \"unilateral_spring\"\n{d}\nk = -1.0\n"),
            "element[0].k",
        ),
        (
            "[[element]]\nkind = \"friction\"\ntangential = { dofs = [0], weights = [1.0] }\nkt = 1.0\nmu = 0.2\n".to_string(),
            "n0",
        ),
        (format!("[[element]]\nkind = \"spring\"\n{d}\nk = 1.0\n"), "kind"),
    ];
    for (text, key) in &cases {
        let msg = case_error(text);
        assert!(msg.contains(key) && msg.contains("line"), "{key}: {msg}");
    }
    // A velocity element evaluated without ω is an error, not a silent ω = 0.
    let set = DofElements::from_case(
        &case_elements(&format!(
            "[[element]]\nkind = \"quadratic_damper\"\n{d}\nc = 1.0\n"
        )),
        1,
    )
    .unwrap();
    let layout = HarmonicLayout::new(1, 8).unwrap();
    let mut f = vec![0.0; 3];
    let mut s = set.initial_state();
    let e = set
        .evaluate(&layout, &[0.0, 1.0, 0.0], &mut s, &mut f, None)
        .unwrap_err();
    assert!(e.to_string().contains("frequency"), "{e}");
}

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// m q̈ + k q + k3 q³ + c q̇|q̇| = F cos ωt (m = k = 1, k3 = 0.5, c = 0.05, F = 0.1) through
/// `nlrom::commands::solve_case` with H = 1: every point satisfies the one-harmonic relation
/// ((k − mω² + ¾ k3 A²) A)² + (8/(3π) c ω² A²)² = F² to 1e-7 of F², the path turns back in ω
/// twice (both folds traced) and reaches its end.
#[test]
fn hardening_oscillator_with_quadratic_damper_through_a_case() {
    let sdof = root().join("cases/nlvib/sdof");
    let text = format!(
        "title = \"Duffing with quadratic damper\"\n[model]\nstiffness = \"{}\"\nmass = \"{}\"\n\n\
         [excitation]\ndofs = [0]\nforce = [0.1]\n\n\
         [[element]]\nkind = \"cubic_spring\"\ndisplacement = {{ dofs = [0], weights = [1.0] }}\nk3 = 0.5\n\n\
         [[element]]\nkind = \"quadratic_damper\"\ndisplacement = {{ dofs = [0], weights = [1.0] }}\nc = 0.05\n\n\
         [harmonic_balance]\nharmonics = 1\ntime_samples = 1024\n\n\
         [continuation]\nstart_rad_s = 0.5\nend_rad_s = 2.5\nstep_rad_s = 0.01\n",
        sdof.join("K.mtx").display(),
        sdof.join("M.mtx").display()
    );
    let case = Case::from_str(&text, Path::new("/tmp/duffing_quadratic.toml")).unwrap();
    let out = solve_case(
        &case,
        &SolveOptions::new(RomPolicy::ReadIfMatching),
        &Reporter::silent(),
    )
    .unwrap();
    assert_eq!(out.curves[0].end, "reached_end", "{:?}", out.curves[0]);
    let points = &out.results.frfs[0].points;
    let (k, k3, c, f) = (1.0, 0.5, 0.05, 0.1);
    let mut turns = 0;
    let mut peak: f64 = 0.0;
    for (i, p) in points.iter().enumerate() {
        let a = p.harmonics[1].norm();
        peak = peak.max(a);
        let w = p.omega;
        let re = (k - w * w + 0.75 * k3 * a * a) * a;
        let im = 8.0 / (3.0 * PI) * c * w * w * a * a;
        let r = (re * re + im * im - f * f) / (f * f);
        assert!(r.abs() < 1e-7, "ω = {w}, A = {a}: relative residual {r:e}");
        if i >= 2 {
            let (d0, d1) = (
                points[i - 1].omega - points[i - 2].omega,
                p.omega - points[i - 1].omega,
            );
            if d0 * d1 < 0.0 {
                turns += 1;
            }
        }
    }
    assert_eq!(turns, 2, "folds traced");
    assert!(peak > 0.8, "peak amplitude {peak}");
}
