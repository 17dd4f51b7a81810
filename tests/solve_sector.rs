//! The harmonic balance problem of a reduced sector (`nlrom::problem::sector::SectorProblem`) on the N = 8
//! bundled sector (meshes/sector8.msh): linear limit against the full unreduced sector under the
//! cyclic constraint, stuck limit against the ROM plus independently assembled contact springs,
//! and the cyclic consistency of the pair rows, σ and phases under a rigid rotation.

mod support;

use std::path::PathBuf;

use faer::linalg::solvers::Solve;
use faer::sparse::{SparseColMat, Triplet};
use faer::{c64, Mat};
use nlrom::case::Case;
use nlrom::contact::pairs::PairState;
use nlrom::cyclic::{phase, CyclicGeometry, CyclicTransform};
use nlrom::harmonics::HarmonicForce;
use nlrom::hbm::{FrequencyPath, HbmSystem};
use nlrom::interface::build_interfaces;
use nlrom::mesh::Mesh;
use nlrom::model::{self, StructuralModel};
use nlrom::nonlinear::{solve_fixed, NewtonOptions};
use nlrom::problem::sector::SectorProblem;
use nlrom::reduction::{free_frontier_pairs, reduce};
use nlrom::rom::Rom;

const N: usize = 8;
/// Rayleigh damping C = αM + βK (exactly projected by the reduction, so the full model has the
/// same damping): β = 2e-7 s gives ζ ≈ 0.06 % at 1 kHz.
const RAYLEIGH: [f64; 2] = [0.0, 2e-7];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The sector8 case with engine order `m`, H harmonics, node-to-node shroud contact
/// (kt, kn, μ, n0).
fn case_text(m: usize, harmonics: usize, contact: [f64; 4]) -> String {
    let [kt, kn, mu, n0] = contact;
    format!(
        r#"
[model]
mesh = "../meshes/sector8.msh"
material = {{ young = 210e9, poisson = 0.3, density = 7800.0 }}
clamp = ["hub"]
damping = {{ rayleigh = [{a}, {b}] }}

[cyclic]
sectors = {N}
low = "left_frontier"
high = "right_frontier"

[reduction]
interface_modes = 30
keep = ["excitation"]

[[contact]]
name = "shroud"
contact = "shroud_contact"
target = "shroud_target"
model = "node-to-node"
mu = {mu:e}
kt = {kt:e}
kn = {kn:e}
n0 = {n0:e}

[excitation]
engine_order = {m}
group = "excitation"
force = [0.3, -0.2, 1.0]

[harmonic_balance]
harmonics = {harmonics}
"#,
        a = RAYLEIGH[0],
        b = RAYLEIGH[1],
    )
}

/// Everything a test needs: the case, its full model, the ROM and the sector problem.
struct Setup {
    case: Case,
    model: StructuralModel,
    rom: Rom,
    problem: SectorProblem,
}

fn setup(m: usize, harmonics: usize, contact: [f64; 4]) -> Setup {
    let case = Case::from_str(
        &case_text(m, harmonics, contact),
        &root().join("cases/test_solve_sector.toml"),
    )
    .expect("case");
    let model = model::build(&case, &mut |_| {}).expect("model");
    let rom = reduce(&case, &model, &mut |_| {}).expect("rom");
    let mesh = model.mesh.as_ref().unwrap();
    let interfaces = build_interfaces(&case, mesh, rom.cyclic.as_ref()).expect("interfaces");
    let problem = SectorProblem::build(&case, &rom, mesh, &interfaces).expect("problem");
    Setup {
        case,
        model,
        rom,
        problem,
    }
}

/// Harmonic 1 of the output DOFs from a converged HB solution x (eq 18).
fn outputs_h1(p: &SectorProblem, x: &[f64], omega: f64) -> Vec<c64> {
    let nd = p.linear.n_condensed();
    let q1: Vec<c64> = (0..nd)
        .map(|i| {
            let r = p.layout.cos_index(1, i, nd);
            c64::new(x[r], x[r + 1])
        })
        .collect();
    p.linear.condense(1, omega).unwrap().recover(&q1)
}

/// The HB solution at ω (rad/s) by Newton from zero.
fn hb_solve(p: &SectorProblem, omega: f64) -> Vec<f64> {
    hb_solve_with(p, &p.contact, omega)
}

/// The HB solution at ω (rad/s) by Newton from zero with the contact force `force`.
fn hb_solve_with<F: HarmonicForce>(p: &SectorProblem, force: &F, omega: f64) -> Vec<f64> {
    let system = HbmSystem::new(p.layout, &p.linear, force).unwrap();
    let path = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let opts = NewtonOptions {
        tolerance: 1e-9,
        ..NewtonOptions::default()
    };
    let x0 = vec![0.0; system.dim()];
    let state = force.initial_state();
    solve_fixed(&path, &x0, omega, &state, &opts)
        .expect("HB converges")
        .x
}

/// The full (unreduced) sector's harmonic 1 at the output DOFs: T_kᴴ (K − ω²M + iωC) T_k q_k =
/// T_kᴴ f with the library's sparse T_k (`nlrom::cyclic::CyclicTransform`, `docs/conventions.md` §2:
/// u_high = e^{iφ_k} R_α u_low) of the frontier pairs, solved by faer's sparse LU; u = T_k q_k.
fn full_frf(s: &Setup, k: usize, omega: f64) -> Vec<c64> {
    let (geom, pairs) = free_frontier_pairs(&s.case, &s.model).unwrap();
    let tk = CyclicTransform::new(&geom, k, s.model.free.n_free(), &pairs).unwrap();
    let nk = tk.n_reduced();
    let t = |r: usize| tk.row(r);
    // D = (1 + iωβ) K + (iωα − ω²) M, projected.
    let (a, b) = (RAYLEIGH[0], RAYLEIGH[1]);
    let fk = c64::new(1.0, omega * b);
    let fm = c64::new(-omega * omega, omega * a);
    let mut trip = Vec::new();
    for (mat, factor) in [(&s.model.free.k, fk), (&s.model.free.m, fm)] {
        for tr in mat.triplet_iter() {
            let v = factor * *tr.val;
            for &(ci, ti) in t(tr.row) {
                for &(cj, tj) in t(tr.col) {
                    trip.push(Triplet::new(ci, cj, ti.conj() * v * tj));
                }
            }
        }
    }
    let dk = SparseColMat::<usize, c64>::try_new_from_triplets(nk, nk, &trip).unwrap();
    // Force at the excitation node rows of the full model, then T_kᴴ f.
    let rows = free_rows(s);
    let mesh = s.model.mesh.as_ref().unwrap();
    let force = [0.3, -0.2, 1.0];
    let mut f = Mat::<c64>::zeros(nk, 1);
    for node in mesh.nodes_of("excitation").unwrap() {
        let tag = mesh.node_tags[node as usize];
        for (c, &fc) in force.iter().enumerate() {
            let r = rows[&(tag, c as u8)];
            for &(cj, tj) in t(r) {
                f[(cj, 0)] += tj.conj() * fc;
            }
        }
    }
    let lu = dk.sp_lu().unwrap();
    lu.solve_in_place(f.as_mut());
    s.problem
        .outputs
        .iter()
        .map(|o| {
            let r = rows[&(o.node_tag, o.component)];
            t(r).iter().map(|&(c, v)| v * f[(c, 0)]).sum()
        })
        .collect()
}

/// (node tag, component) → free row of the full model.
fn free_rows(s: &Setup) -> std::collections::HashMap<(u64, u8), usize> {
    let map = s.model.free_dof_map().unwrap();
    map.entries
        .iter()
        .map(|e| ((e.node_tag, e.component), e.row))
        .collect()
}

fn rel_err(a: &[c64], b: &[c64]) -> f64 {
    let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y).norm_sqr()).sum();
    let n: f64 = b.iter().map(|y| y.norm_sqr()).sum();
    (d / n).sqrt()
}

/// Linear limit: contact removed (kt = kn = n0 = 0) → the HB response at
/// the excitation node equals the full sector's FRF under the cyclic constraint of k_1, within
/// the Craig–Bampton error (30 fixed-interface modes): below 1e-3 between resonances.
fn linear_limit(m: usize) {
    let s = setup(m, 1, [0.0, 0.0, 0.3, 0.0]);
    let k1 = s.problem.harmonic_indices[1];
    assert_eq!(k1, m % N);
    let f = &s.rom.harmonic(k1).unwrap().frequencies_hz;
    let two_pi = 2.0 * std::f64::consts::PI;
    let points = [
        0.5 * f[0],
        0.5 * (f[0] + f[1]),
        0.5 * (f[1] + f[2]),
        1.002 * f[0],
    ];
    for (i, hz) in points.iter().enumerate() {
        let omega = two_pi * hz;
        let x = hb_solve(&s.problem, omega);
        let rom = outputs_h1(&s.problem, &x, omega);
        let full = full_frf(&s, k1, omega);
        let err = rel_err(&rom, &full);
        println!(
            "k1 = {k1}: {hz:.2} Hz: |u| = {:.3e} m, ROM vs full {err:.2e}",
            norm(&full)
        );
        // Near resonance (last point, 0.2 % above f_1) the ROM's frequency error is amplified.
        let tol = if i + 1 == points.len() { 2e-2 } else { 1e-3 };
        assert!(err < tol, "k1 = {k1}, {hz} Hz: ROM vs full {err:.3e}");
    }
}

fn norm(v: &[c64]) -> f64 {
    v.iter().map(|z| z.norm_sqr()).sum::<f64>().sqrt()
}

#[test]
fn linear_limit_complex_harmonic_index() {
    linear_limit(3);
}

#[test]
fn linear_limit_harmonic_index_zero() {
    linear_limit(0);
}

/// The contact stiffness of the pairs in the ROM coordinates of k, assembled here from the pair
/// data: r = u_c − e^{iσφ_k} R_α^σ u_t, local (u1, u2, v) = [t1; t2; −n] r, springs diag(kt, kt,
/// kn): K_c = Lᴴ Pᵀ diag P L.
fn contact_springs(s: &Setup, k: usize, closed: &[bool]) -> Mat<c64> {
    let h = s.rom.harmonic(k).unwrap();
    let geom: CyclicGeometry = s.rom.cyclic.unwrap();
    let p = &s.problem;
    let rom_row = |i: usize| {
        let d = p.nonlinear[i];
        h.row_of(d.node_tag, d.component).unwrap()
    };
    let mut kc = Mat::<c64>::zeros(h.len(), h.len());
    for (pair, _) in p
        .contact
        .inner
        .pairs()
        .iter()
        .zip(closed)
        .filter(|(_, &c)| c)
    {
        let f = pair.frame;
        let pm = [f[0], f[1], [-f[2][0], -f[2][1], -f[2][2]]];
        let stiff = [pair.params.kt, pair.params.kt, pair.params.kn];
        // G = Pᵀ diag P (global 3×3).
        let g = |a: usize, b: usize| (0..3).map(|l| pm[l][a] * stiff[l] * pm[l][b]).sum::<f64>();
        let rot = geom.rotation(pair.sigma);
        let e = c64::from_polar(1.0, pair.sigma as f64 * phase(k, geom.sectors));
        // L as (rom row, 3 columns of the global r): contact +I, target −e R^σ.
        let mut l: Vec<(usize, [c64; 3])> = Vec::new();
        for c in 0..3 {
            let mut row = [c64::new(0.0, 0.0); 3];
            row[c] = c64::new(1.0, 0.0);
            l.push((rom_row(pair.contact[c]), row));
        }
        let t = pair.target.unwrap();
        for d in 0..3 {
            // r_a = −e Σ_d R[a][d] u_t[d]
            let col = [0, 1, 2].map(|a| -e * rot[a][d]);
            l.push((rom_row(t[d]), col));
        }
        support::springs::add_spring(&mut kc, &l, g);
    }
    kc
}

fn geom_of(s: &Setup) -> CyclicGeometry {
    s.rom.cyclic.unwrap()
}

/// Whether each pair is in contact at the static part Q⁽⁰⁾ of the HB solution x:
/// n0_j + k_nj v₀ > 0 with v₀ = −n·(u_c − R_α^σ u_t) (k_0 = 0: no phase; `docs/conventions.md` §3).
fn closed_pairs(p: &SectorProblem, x: &[f64], geom: &CyclicGeometry) -> Vec<bool> {
    let q0 = |r: usize| x[p.layout.static_index(r)];
    p.contact
        .inner
        .pairs()
        .iter()
        .map(|pair| {
            let rot = geom.rotation(pair.sigma);
            let t = pair.target.unwrap();
            let r: Vec<f64> = (0..3)
                .map(|a| q0(pair.contact[a]) - (0..3).map(|d| rot[a][d] * q0(t[d])).sum::<f64>())
                .collect();
            let v0 = -(0..3).map(|a| pair.frame[2][a] * r[a]).sum::<f64>();
            pair.params.n0 + pair.params.kn * v0 > 0.0
        })
        .collect()
}

/// Stuck limit: μ = 1e6 (never slips) → the HB harmonic 1 equals the direct solve of the ROM
/// plus the linear contact springs of the pairs closed at the static solution (the preload's
/// static deformation opens some), (K_k − ω²M_k + iωC_k + K_c) Q = F, to 1e-8. The harmonic
/// amplitude (k_n·|u| ≈ 2 N) is far below the preload (n0_c ≈ 330 N), so no pair changes state.
#[test]
fn stuck_limit_equals_rom_with_contact_springs() {
    let s = setup(3, 1, [1e8, 1e8, 1e6, 1e5]);
    let k1 = s.problem.harmonic_indices[1];
    let h = s.rom.harmonic(k1).unwrap();
    let omega = 2.0 * std::f64::consts::PI * 0.5 * h.frequencies_hz[0];
    let x = hb_solve(&s.problem, omega);
    let hb = outputs_h1(&s.problem, &x, omega);
    let closed = closed_pairs(&s.problem, &x, &geom_of(&s));
    let n_closed = closed.iter().filter(|&&c| c).count();
    println!(
        "stuck: {n_closed} of {} pairs closed at the static solution",
        closed.len()
    );
    assert!(n_closed > 0, "no pair is closed");
    let kc = contact_springs(&s, k1, &closed);
    let direct = rom_solve(&s, k1, omega, Some(&kc));
    let err = rel_err(&hb, &direct);
    let without = rel_err(&rom_solve(&s, k1, omega, None), &direct);
    println!(
        "stuck: |u| = {:.3e} m, HB vs ROM + springs {err:.2e} (ROM without springs differs by {without:.2e})",
        norm(&direct)
    );
    assert!(err < 1e-8, "HB stuck vs ROM + springs: {err:.3e}");
    // The springs matter here (the comparison is not against a negligible correction).
    assert!(
        without > 1e-2,
        "contact springs change the response by {without:.3e}"
    );
}

/// Direct dense solve of (K_k − ω²M_k + iωC_k [+ K_c]) Q = F on the ROM of k, at the outputs.
fn rom_solve(s: &Setup, k: usize, omega: f64, springs: Option<&Mat<c64>>) -> Vec<c64> {
    let h = s.rom.harmonic(k).unwrap();
    let c = h.damping.as_ref().unwrap();
    let d = Mat::from_fn(h.len(), h.len(), |i, j| {
        h.stiffness[(i, j)] - h.mass[(i, j)] * (omega * omega)
            + c[(i, j)] * c64::new(0.0, omega)
            + springs.map_or(c64::new(0.0, 0.0), |kc| kc[(i, j)])
    });
    let mut f = Mat::<c64>::zeros(h.len(), 1);
    let force = [0.3, -0.2, 1.0];
    let mesh = s.model.mesh.as_ref().unwrap();
    for node in mesh.nodes_of("excitation").unwrap() {
        let tag = mesh.node_tags[node as usize];
        for (comp, &fc) in force.iter().enumerate() {
            f[(h.row_of(tag, comp as u8).unwrap(), 0)] += c64::new(fc, 0.0);
        }
    }
    let q = d.partial_piv_lu().solve(&f);
    s.problem
        .outputs
        .iter()
        .map(|o| q[(h.row_of(o.node_tag, o.component).unwrap(), 0)])
        .collect()
}

/// Harmonic-1 part of the contact force for the harmonic-1 displacement `u1` of the nonlinear
/// DOFs (real, cos part), minus the force at rest.
fn contact_force_h1(p: &SectorProblem, u1: &[f64]) -> Vec<f64> {
    let nd = p.nonlinear.len();
    let len = p.layout.len(nd);
    let eval = |q: &[f64]| {
        let mut state: PairState = p.contact.initial_state();
        let mut f = vec![0.0; len];
        p.contact
            .inner
            .evaluate(&p.layout, q, &mut state, &mut f, None)
            .unwrap();
        f
    };
    let mut q = vec![0.0; len];
    for (i, u) in u1.iter().enumerate() {
        q[p.layout.cos_index(1, i, nd)] = *u;
    }
    let (f, f0) = (eval(&q), eval(&vec![0.0; len]));
    (0..nd)
        .flat_map(|i| {
            let r = p.layout.cos_index(1, i, nd);
            [f[r] - f0[r], f[r + 1] - f0[r + 1]]
        })
        .collect()
}

/// A rigid rotation θ a × (x − o) about the cyclic axis at the nonlinear DOFs.
fn rigid_rotation(p: &SectorProblem, mesh: &Mesh, geom: &CyclicGeometry, theta: f64) -> Vec<f64> {
    p.nonlinear
        .iter()
        .map(|d| {
            let x = mesh.coords[mesh.node_index(d.node_tag).unwrap() as usize];
            let r = [0, 1, 2].map(|i| x[i] - geom.origin[i]);
            let a = geom.axis;
            let u = [
                a[1] * r[2] - a[2] * r[1],
                a[2] * r[0] - a[0] * r[2],
                a[0] * r[1] - a[1] * r[0],
            ];
            theta * u[d.component as usize]
        })
        .collect()
}

/// Pair rows, σ and phases: at k = 0 a rigid rotation of the whole disk about the axis moves
/// every contact node with its (rotated) target, so the contact force does not change (relative
/// 1e-9 of kt·|u|); at k = 3 the same field is not a disk motion and gives a force of order kt·|u|.
#[test]
fn rigid_rotation_at_k0_gives_no_contact_force() {
    for (m, expect_zero) in [(0usize, true), (3, false)] {
        let s = setup(m, 1, [1e8, 1e8, 1e6, 100.0]);
        let geom = s.rom.cyclic.unwrap();
        let mesh = s.model.mesh.as_ref().unwrap();
        let u = rigid_rotation(&s.problem, mesh, &geom, 1e-6);
        let f = contact_force_h1(&s.problem, &u);
        let scale = 1e8 * u.iter().map(|v| v * v).sum::<f64>().sqrt();
        let ratio = f.iter().map(|v| v * v).sum::<f64>().sqrt() / scale;
        println!("m = {m}: |F_c| / (kt |u|) = {ratio:.2e}");
        if expect_zero {
            assert!(ratio < 1e-9, "k = 0 rigid rotation: {ratio:.3e}");
        } else {
            assert!(ratio > 1e-2, "k = 3 should load the contact: {ratio:.3e}");
        }
    }
}

/// The preload balanced by the static equilibrium (`SectorProblem::contact`, a
/// [`nlrom::hbm::preload::FromStaticEquilibrium`]): the static solution is the undeformed
/// interface (Q⁽⁰⁾ = 0 to 1e-9 of the harmonic-1 level) and every pair is closed, while without
/// the balance (the bare `PairSet`, `contact.inner`) some pairs open under their own preload.
#[test]
fn balanced_preload_keeps_every_pair_closed() {
    let s = setup(3, 1, [1e8, 1e8, 1e6, 1e5]);
    let k1 = s.problem.harmonic_indices[1];
    let omega = 2.0 * std::f64::consts::PI * 0.5 * s.rom.harmonic(k1).unwrap().frequencies_hz[0];
    let geom = geom_of(&s);
    let unbalanced = hb_solve_with(&s.problem, &s.problem.contact.inner, omega);
    let before = closed_pairs(&s.problem, &unbalanced, &geom);
    let x = hb_solve(&s.problem, omega);
    let after = closed_pairs(&s.problem, &x, &geom);
    let count = |v: &[bool]| v.iter().filter(|&&c| c).count();
    println!(
        "closed pairs: {} of {} unbalanced, {} balanced",
        count(&before),
        before.len(),
        count(&after)
    );
    assert!(count(&before) < before.len());
    assert_eq!(count(&after), after.len());
    let nd = s.problem.linear.n_condensed();
    let q0: f64 = (0..nd)
        .map(|i| x[s.problem.layout.static_index(i)].powi(2))
        .sum::<f64>()
        .sqrt();
    let q1: f64 = x[nd..].iter().map(|v| v * v).sum::<f64>().sqrt();
    assert!(
        q0 <= 1e-9 * q1,
        "static part {q0:.3e} vs harmonic 1 {q1:.3e}"
    );
}
