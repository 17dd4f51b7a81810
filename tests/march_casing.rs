//! `[[casing]]` and `[thermal]` on mesh cases (the blade–casing model of Thorin et al. 2018):
//! the obstacles a case builds against a model built by hand from the FE matrices, the
//! persistent contact of a pressed blade against the static contact solution, the heat balance
//! of frictional heating against α Σλ and the insulated closed form, and bad input.

use faer::linalg::solvers::Solve;
use faer::Mat;
use nlrom::case::Case;
use nlrom::fe::{assemble, Materials, Quadrature};
use nlrom::march::moreau_jean::moreau_jean;
use nlrom::march::obstacle::{NonsmoothSettings, NonsmoothSystem, Obstacle};
use nlrom::march::signal::Harmonic;
use nlrom::mesh::msh::read_msh;
use nlrom::problem::nonsmooth_case::nonsmooth_case;
use std::path::PathBuf;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The coarse blade (hexa20, 2 × 2 × 4 cells, chord 30 mm along x, thickness 4 mm along y,
/// span 50 mm along z from r = 0.2 m) clamped at its root, five contact nodes on the tip line.
fn blade_case(extra: &str) -> String {
    blade_case_on("../meshes/blade_coarse.msh", extra)
}

/// [`blade_case`] on the mesh `mesh` (groups "root" and "tip_contact").
fn blade_case_on(mesh: &str, extra: &str) -> String {
    format!(
        r#"
[model]
mesh = "{mesh}"
material = {{ young = 110e9, poisson = 0.3, density = 4430 }}
clamp = ["root"]
damping = {{ rayleigh = [0.0, 1e-5] }}

[excitation]
group = "tip_contact"
force = [0, 0, 100]

[march]
frequency_hz = 33.333333333333336
periods = 1
steps_per_period = 3000
time_step_s = 1e-5
{extra}
"#
    )
}

fn load(text: &str) -> Case {
    Case::from_str(text, &root().join("cases/casing_test.toml")).unwrap()
}

fn build(text: &str) -> nlrom::problem::nonsmooth_case::NonsmoothCase {
    let case = load(text);
    let sm = nlrom::model::build(&case, &mut |_| {}).unwrap();
    nonsmooth_case(&case, &sm).unwrap()
}

fn with_steps(s: &NonsmoothSettings, steps: usize) -> NonsmoothSettings {
    NonsmoothSettings {
        steps,
        record: None,
        ..s.clone()
    }
}

/// K, M (dense, free rows), the free global DOF 3i + c and the mesh of the coarse blade,
/// assembled here from the FE layer.
fn hand_built() -> (Mat<f64>, Mat<f64>, Vec<usize>, nlrom::mesh::Mesh) {
    let mesh = read_msh(&root().join("meshes/blade_coarse.msh")).unwrap();
    let mat = nlrom::fe::Material {
        young: 110e9,
        poisson: 0.3,
        density: 4430.0,
    };
    let asm = assemble(&mesh, &Materials::uniform(mat), &Quadrature::default()).unwrap();
    let clamped: Vec<u32> = mesh.nodes_of("root").unwrap();
    let free: Vec<usize> = (0..3 * mesh.num_nodes())
        .filter(|p| !clamped.contains(&((p / 3) as u32)))
        .collect();
    let (k, m) = (asm.k.to_dense(), asm.m.to_dense());
    let n = free.len();
    (
        Mat::from_fn(n, n, |i, j| k[(free[i], free[j])]),
        Mat::from_fn(n, n, |i, j| m[(free[i], free[j])]),
        free,
        mesh,
    )
}

fn row_major(a: &Mat<f64>) -> Vec<f64> {
    let n = a.nrows();
    (0..n * n).map(|ij| a[(ij / n, ij % n)]).collect()
}

// ---------------------------------------------------------------------------------------------
// Geometry of the casing and the model it builds
// ---------------------------------------------------------------------------------------------

#[test]
fn casing_builds_the_hand_built_blade_model_and_marches_it_identically() {
    let text = blade_case(
        r#"
[[casing]]
name = "stator"
group = "tip_contact"
axis = { origin = [0, 0, 0], direction = [2, 0, 0] }
radius = 0.2500001
mu = 0.15
speed_rpm = 2000
"#,
    );
    let nc = build(&text);
    let (k, m, free, mesh) = hand_built();
    let n = free.len();
    assert_eq!(nc.system.n, n);
    assert_eq!(nc.system.n_mech, n);
    // The same model built from the FE layer: C = 1e-5 K, 100 N along z on the tip line nodes,
    // one obstacle per tip node with e_r = e_z (the nodes lie at y = 0 on the plane through the
    // x axis), g0 = R − 0.25 m, friction along −sgn(Ω) e_φ = −(e_x × e_z) = +e_y.
    let mut sys = NonsmoothSystem::mechanical(
        row_major(&m),
        row_major(&k).iter().map(|v| 1e-5 * v).collect(),
        row_major(&k),
    );
    sys.omega = 2.0 * std::f64::consts::PI * 100.0 / 3.0;
    let row = |node: u32, c: usize| free.iter().position(|&p| p == 3 * node as usize + c);
    let tip = mesh.nodes_of("tip_contact").unwrap();
    assert_eq!(tip.len(), 5);
    for &node in &tip {
        let x = mesh.coords[node as usize];
        assert!(x[1].abs() < 1e-15 && (x[2] - 0.25).abs() < 1e-12);
        let (ry, rz) = (row(node, 1).unwrap(), row(node, 2).unwrap());
        sys.force[rz].cos = 100.0;
        let mut o = Obstacle::new("tip", vec![(rz, -1.0)], 0.2500001 - x[2], 0.0);
        o.mu = 0.15;
        o.tangential = vec![(ry, 1.0)];
        sys.obstacles.push(o);
    }
    for (a, b) in nc.system.obstacles.iter().zip(&sys.obstacles) {
        assert_eq!(a.normal.len(), 1, "{a:?}");
        assert_eq!(a.normal[0].0, b.normal[0].0);
        assert!((a.normal[0].1 + 1.0).abs() < 1e-15);
        assert!((a.gap - b.gap).abs() < 1e-15, "{} vs {}", a.gap, b.gap);
        assert_eq!(a.tangential.len(), 1, "{a:?}");
        assert_eq!(a.tangential[0].0, b.tangential[0].0);
        assert!((a.tangential[0].1 - 1.0).abs() < 1e-15);
        assert!(a.name.starts_with("stator:"));
    }
    for (r, (a, b)) in nc.system.force.iter().zip(&sys.force).enumerate() {
        assert!((a.cos - b.cos).abs() < 1e-12, "force row {r}");
    }
    let s = with_steps(&nc.settings, 600);
    let from_case = moreau_jean(&nc.system, &s).unwrap();
    let by_hand = moreau_jean(&sys, &s).unwrap();
    let total: f64 = by_hand.impulse.iter().sum();
    assert!(total > 0.0, "the blade must hit the casing");
    let worst = from_case
        .impulse
        .iter()
        .zip(&by_hand.impulse)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(
        worst < 1e-9 * total,
        "impulses differ by {worst} (total {total})"
    );
    let scale = by_hand.x_final.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    let dx = from_case
        .x_final
        .iter()
        .zip(&by_hand.x_final)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    assert!(dx < 1e-9 * scale, "states differ by {dx} of {scale}");
}

#[test]
fn an_off_centre_axis_gives_the_radial_gap_and_directions_of_each_node() {
    // The axis through (0, 0.1, 0) along x: node (x, 0, z) has r = √(0.1² + z²),
    // e_r = (0, −0.1, z)/r, e_φ = e_x × e_r = (0, −z, −0.1)/r; Ω < 0 puts the friction along +e_φ.
    let text = blade_case(
        r#"
[[casing]]
group = "tip_contact"
axis = { origin = [0, 0.1, 0], direction = [1, 0, 0] }
radius = 0.3
mu = 0.2
speed_rpm = -2000
"#,
    );
    let nc = build(&text);
    let (_, _, free, mesh) = hand_built();
    for (o, &node) in nc
        .system
        .obstacles
        .iter()
        .zip(&mesh.nodes_of("tip_contact").unwrap())
    {
        let z = mesh.coords[node as usize][2];
        let r = (0.01 + z * z).sqrt();
        assert!(
            (o.gap - (0.3 - r)).abs() < 1e-15,
            "{} vs {}",
            o.gap,
            0.3 - r
        );
        let weight = |list: &[(usize, f64)], c: usize| -> f64 {
            let row = free
                .iter()
                .position(|&p| p == 3 * node as usize + c)
                .unwrap();
            list.iter().find(|e| e.0 == row).map_or(0.0, |e| e.1)
        };
        // G = −e_rᵀ, t = +e_φ.
        assert!((weight(&o.normal, 0)).abs() < 1e-15);
        assert!((weight(&o.normal, 1) - 0.1 / r).abs() < 1e-14);
        assert!((weight(&o.normal, 2) + z / r).abs() < 1e-14);
        assert!((weight(&o.tangential, 1) + z / r).abs() < 1e-14);
        assert!((weight(&o.tangential, 2) + 0.1 / r).abs() < 1e-14);
        assert_eq!(o.mu, 0.2);
    }
}

// ---------------------------------------------------------------------------------------------
// Persistent contact against the static contact solution
// ---------------------------------------------------------------------------------------------

/// The static contact forces of `sys` under its constant load (`Harmonic::mean`) with every
/// obstacle in contact at the gaps `g_final`: K u = F + Hλ, g0 + G u = g_f, i.e.
/// λ = (G K⁻¹ H)⁻¹ (g_f − g0 − G K⁻¹ F).
fn static_contact_forces(sys: &NonsmoothSystem, g_final: &[f64]) -> Vec<f64> {
    let (n, m) = (sys.n, sys.obstacles.len());
    let k = Mat::from_fn(n, n, |i, j| sys.stiffness[i * n + j]);
    let lu = k.partial_piv_lu();
    let solve = |b: &[f64]| -> Vec<f64> {
        let mut x = faer::Col::from_fn(n, |i| b[i]);
        lu.solve_in_place(x.as_mut());
        (0..n).map(|i| x[i]).collect()
    };
    let f: Vec<f64> = sys.force.iter().map(|f| f.mean).collect();
    let kf = solve(&f);
    let kh: Vec<Vec<f64>> = sys.obstacles.iter().map(|o| solve(&o.column(n))).collect();
    let a = Mat::from_fn(m, m, |i, j| sys.obstacles[i].rate(&kh[j]));
    let b = faer::Col::from_fn(m, |i| {
        g_final[i] - sys.obstacles[i].gap - sys.obstacles[i].rate(&kf)
    });
    let lambda = a.partial_piv_lu().solve(&b);
    (0..m).map(|i| lambda[i]).collect()
}

/// Marches `nc` for 2000 steps with its load held at its peak (a constant) and heavy damping
/// C = 2e-4 s·K: the history, the settings, the last step's contact forces λ/h and the static
/// contact forces at the last step's gaps ([`static_contact_forces`]).
fn press(
    nc: &mut nlrom::problem::nonsmooth_case::NonsmoothCase,
) -> (
    nlrom::march::obstacle::NonsmoothHistory,
    NonsmoothSettings,
    Vec<f64>,
    Vec<f64>,
) {
    let sys = &mut nc.system;
    for f in &mut sys.force {
        *f = Harmonic::constant(f.cos);
    }
    sys.damping = sys.stiffness.iter().map(|k| 2e-4 * k).collect();
    let s = with_steps(&nc.settings, 2000);
    let h = moreau_jean(sys, &s).unwrap();
    let m = sys.obstacles.len();
    let last: Vec<f64> = (0..m)
        .map(|i| h.impulses(i).last().unwrap() / s.step)
        .collect();
    let lambda = static_contact_forces(sys, &h.gap[h.gap.len() - m..]);
    (h, s, last, lambda)
}

#[test]
fn a_blade_pressed_on_the_casing_settles_on_the_static_contact_forces() {
    // Gap 0, a constant 100 N per tip node outward, friction μ = 0.15 along +y and heavy
    // damping C = 2e-4 s·K: after the transient (the end nodes lift off and land again, keeping
    // the residual penetration g_f of their landing step) the contact forces λ/h settle on the
    // static solution of K u = F + Hλ, g0 + G u = g_f: λ = (G K⁻¹ H)⁻¹ (g_f − g0 − G K⁻¹ F).
    let text = blade_case(
        r#"
[[casing]]
group = "tip_contact"
axis = { direction = [1, 0, 0] }
gap = 0.0
mu = 0.15
speed_rpm = 2000
"#,
    );
    let mut nc = build(&text);
    let (h, s, last, lambda) = press(&mut nc);
    let m = nc.system.obstacles.len();
    let total: f64 = (0..m).map(|i| lambda[i]).sum();
    for i in 0..m {
        assert!(lambda[i] > 0.0, "static contact force {i}: {}", lambda[i]);
        assert!(
            (last[i] - lambda[i]).abs() < 1e-6 * total,
            "node {i}: march {} N, static {} N",
            last[i],
            lambda[i]
        );
    }
    // Σλ = 5 × 100 N minus what the friction moment takes off the tip (about a per cent).
    assert!((total - 500.0).abs() < 0.05 * 500.0, "total {total}");
    // The residual penetration is below h times the largest normal speed, and never grows
    // while a node stays in contact (Thorin et al. 2018, Fig. 4).
    let vmax = h.rate.iter().fold(0.0_f64, |a, y| a.max(y.abs()));
    let pen = h.max_penetration();
    assert!(
        pen > 0.0 && pen <= s.step * vmax,
        "penetration {pen} m, h·max|ẏ| = {}",
        s.step * vmax
    );
    for i in 0..m {
        for t in 1..h.len() - 1 {
            let (g0, g1) = (h.gap[t * m + i], h.gap[(t + 1) * m + i]);
            if h.active[(t + 1) * m + i] && h.impulse[(t + 1) * m + i] > 0.0 && g0 < 0.0 {
                assert!(
                    g1 >= g0 - 1e-18,
                    "node {i} step {t}: penetration grew {g0} → {g1}"
                );
            }
        }
    }
}

#[test]
fn per_node_gaps_set_each_nodes_initial_gap_and_its_static_contact_force() {
    // `gap = [...]` gives g0 per node, in ascending tag order or in the order of `gap_nodes`.
    // Pressed by a constant 100 N per node (heavy damping), every node lands and the forces
    // settle on the static solution with those gaps, which differs from the uniform gap's.
    let mesh = read_msh(&root().join("meshes/blade_coarse.msh")).unwrap();
    let mut tags: Vec<u64> = mesh
        .nodes_of("tip_contact")
        .unwrap()
        .iter()
        .map(|&i| mesh.node_tags[i as usize])
        .collect();
    tags.sort_unstable();
    let gaps = [0.0, 1e-7, 3e-7, 2e-7, 0.5e-7];
    let list = |v: &[f64]| {
        v.iter()
            .map(|g| format!("{g:e}"))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let casing = |gap: &str| {
        blade_case(&format!(
            "[[casing]]\ngroup = \"tip_contact\"\naxis = {{ direction = [1, 0, 0] }}\n{gap}\nmu = 0.15\nspeed_rpm = 2000\n"
        ))
    };
    let sorted = build(&casing(&format!("gap = [{}]", list(&gaps))));
    let reversed: Vec<f64> = gaps.iter().rev().copied().collect();
    let rev_tags: Vec<String> = tags.iter().rev().map(|t| t.to_string()).collect();
    let keyed = build(&casing(&format!(
        "gap = [{}]\ngap_nodes = [{}]",
        list(&reversed),
        rev_tags.join(", ")
    )));
    let tag_of = |o: &Obstacle| -> u64 { o.name.rsplit(':').next().unwrap().parse().unwrap() };
    for nc in [&sorted, &keyed] {
        assert_eq!(nc.system.obstacles.len(), 5);
        for o in &nc.system.obstacles {
            let k = tags.iter().position(|&t| t == tag_of(o)).unwrap();
            assert_eq!(o.gap, gaps[k], "node {}", tag_of(o));
        }
    }
    let uniform = build(&casing("gap = 0.0"));
    let (_, _, march, stat) = press(&mut { sorted });
    let (_, _, march_u, _) = press(&mut { uniform });
    let total: f64 = stat.iter().sum();
    let mut spread = 0.0_f64;
    for i in 0..5 {
        assert!(stat[i] > 0.0, "node {i}: static force {}", stat[i]);
        assert!(
            (march[i] - stat[i]).abs() < 1e-6 * total,
            "node {i}: march {} N, static {} N",
            march[i],
            stat[i]
        );
        spread = spread.max((march[i] - march_u[i]).abs());
    }
    eprintln!("per-node gaps: forces {march:?} N; uniform gap {march_u:?} N");
    // Sub-micrometre gaps against the blade's micrometre deflection under the load: the forces
    // shift by newtons, not by round-off.
    assert!(spread > 1.0, "largest force change {spread} N");
}

// ---------------------------------------------------------------------------------------------
// Frictional heating
// ---------------------------------------------------------------------------------------------

fn thermal_blade(fixed: &str, expansion: f64, heating: f64) -> String {
    blade_case(&format!(
        r#"
[thermal]
conductivity = 6.7
specific_heat = 520
expansion = {expansion}
fixed = [{fixed}]

[[casing]]
group = "tip_contact"
axis = {{ direction = [1, 0, 0] }}
gap = 1e-6
mu = 0.15
speed_rpm = 2000
heating = {heating}
"#
    ))
}

#[test]
fn frictional_heat_enters_as_alpha_times_the_impulses_and_balances_every_step() {
    // Root at θ = 0: the heat stored equals the frictional heat α Σλ minus the heat conducted
    // out through the root, every step; the energy balance closes with the thermal load term.
    let nc = build(&thermal_blade("\"root\"", 9e-6, 0.1));
    let (nm, n) = (nc.system.n_mech, nc.system.n);
    let root_nodes = 21;
    assert_eq!(n - nm, 141 - root_nodes);
    assert_eq!(nc.temperature_nodes.len(), 5);
    let s = with_steps(&nc.settings, 1500);
    let h = moreau_jean(&nc.system, &s).unwrap();
    let total: f64 = h.impulse.iter().sum();
    assert!(total > 0.0);
    let q = h.heat.last().unwrap();
    assert!(
        (q.frictional - 0.1 * total).abs() < 1e-12 * q.frictional,
        "{} vs α Σλ = {}",
        q.frictional,
        0.1 * total
    );
    let worst_heat = h.heat.iter().map(|q| q.residual.abs()).fold(0.0, f64::max);
    assert!(
        worst_heat < 1e-9 * q.frictional,
        "heat residual {worst_heat}"
    );
    // Over 15 ms the heat diffuses about √(κt) ≈ 0.2 mm from the tip: next to nothing reaches
    // the root 50 mm away.
    assert!(q.exchanged.abs() < 1e-4 * q.frictional, "{q:?}");
    let scale = h
        .energy
        .iter()
        .map(|e| e.external.abs().max(e.kinetic + e.strain))
        .fold(0.0, f64::max);
    let worst = h
        .energy
        .iter()
        .map(|e| e.residual.abs())
        .fold(0.0, f64::max);
    assert!(worst < 1e-9 * scale, "energy residual {worst} of {scale}");
    // The contact nodes heat up (the recorded temperatures), θ ≥ 0 nowhere violated much.
    let theta_tip = &h.x_final[nm..];
    assert!(theta_tip.iter().cloned().fold(0.0, f64::max) > 0.0);
}

#[test]
fn an_insulated_blade_stores_all_frictional_heat_as_its_mean_temperature() {
    // No fixed temperature: K^θθ 1 = 0, so 1ᵀC^θθθ = α Σλ and the capacity-weighted mean rise is
    // α Σλ / (ρ c_p V) with V = 30 × 4 × 50 mm³, with the consistent and the lumped capacity.
    for capacity in ["consistent", "lumped"] {
        let text = thermal_blade("", 0.0, 0.1).replace(
            "fixed = []",
            &format!("fixed = []\ncapacity = \"{capacity}\""),
        );
        let nc = build(&text);
        let s = with_steps(&nc.settings, 800);
        let h = moreau_jean(&nc.system, &s).unwrap();
        let total: f64 = h.impulse.iter().sum();
        let (nm, n) = (nc.system.n_mech, nc.system.n);
        assert_eq!(n - nm, 141);
        let c = &nc.system.damping;
        let c1: Vec<f64> = (nm..n)
            .map(|a| (nm..n).map(|b| c[a * n + b]).sum())
            .collect();
        let off_diagonal = (nm..n)
            .flat_map(|a| (nm..n).filter(move |&b| b != a).map(move |b| (a, b)))
            .any(|(a, b)| c[a * n + b] != 0.0);
        assert_eq!(off_diagonal, capacity == "consistent", "{capacity}");
        let volume = 0.03 * 0.004 * 0.05;
        let rho_c_v = 4430.0 * 520.0 * volume;
        assert!((c1.iter().sum::<f64>() - rho_c_v).abs() < 1e-9 * rho_c_v);
        let mean = c1
            .iter()
            .zip(&h.x_final[nm..])
            .map(|(c, t)| c * t)
            .sum::<f64>()
            / c1.iter().sum::<f64>();
        let expected = 0.1 * total / rho_c_v;
        assert!(
            (mean - expected).abs() < 1e-9 * expected,
            "{capacity}: {mean} vs {expected}"
        );
    }
}

#[test]
fn response_groups_record_the_temperatures_of_their_nodes() {
    // The insulated coarse blade with `[response] groups = ["volume"]`: every node's temperature
    // is recorded (the five contact nodes first), and weighted by the row sums of a capacity
    // matrix assembled here from the FE layer, indexed by node tag, they give the mean rise
    // α Σλ / (ρ c_p V) of the stored frictional heat: the tags name the right temperatures.
    use nlrom::fe::thermal::{assemble_thermal, Capacity, ThermalMaterial};
    use nlrom::fe::Material;
    let text = thermal_blade("", 0.0, 0.1).replace(
        "fixed = []",
        "fixed = []\ncapacity = \"lumped\"\n\n[response]\ngroups = [\"volume\"]",
    );
    let nc = build(&text);
    assert_eq!(nc.temperature_nodes.len(), 141);
    let mesh = read_msh(&root().join("meshes/blade_coarse.msh")).unwrap();
    let contact: Vec<u64> = mesh
        .nodes_of("tip_contact")
        .unwrap()
        .iter()
        .map(|&i| mesh.node_tags[i as usize])
        .collect();
    let mut first: Vec<u64> = nc.temperature_nodes[..5].to_vec();
    first.sort_unstable();
    let mut expected_first = contact.clone();
    expected_first.sort_unstable();
    assert_eq!(first, expected_first);
    let s = NonsmoothSettings {
        steps: 800,
        ..nc.settings.clone()
    };
    let h = moreau_jean(&nc.system, &s).unwrap();
    let total: f64 = h.impulse.iter().sum();
    let capacity = assemble_thermal(
        &mesh,
        &Materials::uniform(Material {
            young: 110e9,
            poisson: 0.3,
            density: 4430.0,
        }),
        &ThermalMaterial {
            conductivity: 6.7,
            specific_heat: 520.0,
            expansion: 0.0,
            capacity: Capacity::Lumped,
        },
        &Quadrature::default(),
    )
    .unwrap()
    .capacity
    .to_dense();
    let (r, first_theta) = (h.dofs.len(), nc.response.len());
    let theta = &h.x[s.steps * r + first_theta..(s.steps + 1) * r];
    let stored: f64 = nc
        .temperature_nodes
        .iter()
        .zip(theta)
        .map(|(tag, t)| {
            let i = mesh.node_tags.iter().position(|x| x == tag).unwrap();
            (0..mesh.num_nodes()).map(|j| capacity[(i, j)]).sum::<f64>() * t
        })
        .sum();
    assert!(
        (stored - 0.1 * total).abs() < 1e-9 * 0.1 * total,
        "Σ C θ = {stored} J vs α Σλ = {} J",
        0.1 * total
    );
}

// ---------------------------------------------------------------------------------------------
// Bad input
// ---------------------------------------------------------------------------------------------

fn load_err(text: &str) -> String {
    let path = root().join("cases/casing_test.toml");
    match Case::from_str(text, &path) {
        Err(e) => e.to_string(),
        Ok(case) => {
            let sm = nlrom::model::build(&case, &mut |_| {});
            match sm.and_then(|sm| nonsmooth_case(&case, &sm).map(|_| ())) {
                Err(e) => e.to_string(),
                Ok(()) => panic!("accepted:\n{text}"),
            }
        }
    }
}

#[test]
fn bad_casing_and_thermal_keys_are_reported_with_their_path() {
    let casing = |body: &str| blade_case(&format!("[[casing]]\n{body}\n"));
    for (text, key) in [
        (casing("group = \"tip\"\ngap = 0"), "casing[0].group"),
        (casing("group = \"tip_contact\""), "casing[0]"),
        (
            casing("group = \"tip_contact\"\ngap = 0\nradius = 0.3"),
            "casing[0].gap",
        ),
        (casing("group = \"tip_contact\"\nradius = -1"), "casing[0].radius"),
        (casing("group = \"tip_contact\"\ngap = 0\nmu = 0.1"), "casing[0].mu"),
        (
            casing("group = \"tip_contact\"\ngap = 0\nheating = 0.1"),
            "casing[0].heating",
        ),
        (
            casing("group = \"tip_contact\"\ngap = 0\nrestitution = 2"),
            "casing[0].restitution",
        ),
        (
            casing("group = \"tip_contact\"\ngap = 0\naxis = { direction = [0, 0, 0] }"),
            "casing[0].axis.direction",
        ),
        (
            casing("group = \"tip_contact\"\ngap = [0, 0, 0]"),
            "casing[0].gap",
        ),
        (
            casing("group = \"tip_contact\"\ngap = [0, 0, 0, 0, 1e-6, 0]"),
            "casing[0].gap",
        ),
        (
            casing("group = \"tip_contact\"\ngap = [0, 0, 0, 0, 0]\ngap_nodes = [1, 2, 3, 4]"),
            "casing[0].gap_nodes",
        ),
        (
            casing("group = \"tip_contact\"\ngap = [0, 0, 0, 0, 0]\ngap_nodes = [999999, 2, 3, 4, 5]"),
            "casing[0].gap_nodes[0]",
        ),
        (
            casing("group = \"tip_contact\"\ngap = 0\ngap_nodes = [1]"),
            "casing[0].gap_nodes",
        ),
        (
            blade_case("[thermal]\nspecific_heat = 520\nexpansion = 9e-6\n"),
            "conductivity",
        ),
        (
            blade_case("[thermal]\nconductivity = 6.7\nspecific_heat = 0\nexpansion = 9e-6\n"),
            "thermal.specific_heat",
        ),
        (
            blade_case(
                "[thermal]\nconductivity = 6.7\nspecific_heat = 520\nexpansion = 9e-6\nfixed = [\"bore\"]\n",
            ),
            "thermal.fixed[0]",
        ),
        (
            blade_case(
                "[thermal]\nconductivity = 6.7\nspecific_heat = 520\nexpansion = 9e-6\ncapacity = \"diagonal\"\n",
            ),
            "thermal.capacity",
        ),
    ] {
        let err = load_err(&text);
        assert!(err.contains(key), "expected '{key}' in: {err}");
    }
    // Per-node gaps: the count and the node tags are checked against the group.
    let err = load_err(&casing("group = \"tip_contact\"\ngap = [0, 0, 0]"));
    assert!(
        err.contains("3 gaps for the 5 nodes of group 'tip_contact'"),
        "{err}"
    );
    let err = load_err(&casing(
        "group = \"tip_contact\"\ngap = [0, 0, 0, 0, 0]\ngap_nodes = [999999, 2, 3, 4, 5]",
    ));
    assert!(
        err.contains("node 999999 is not a node of group 'tip_contact'"),
        "{err}"
    );
    let mesh = read_msh(&root().join("meshes/blade_coarse.msh")).unwrap();
    let t: Vec<u64> = mesh
        .nodes_of("tip_contact")
        .unwrap()
        .iter()
        .map(|&i| mesh.node_tags[i as usize])
        .collect();
    let err = load_err(&casing(&format!(
        "group = \"tip_contact\"\ngap = [0, 0, 0, 0, 0]\ngap_nodes = [{}, {}, {}, {}, {}]",
        t[0], t[1], t[2], t[3], t[1]
    )));
    assert!(
        err.contains("casing[0].gap_nodes[4]") && err.contains("listed twice"),
        "{err}"
    );
    // A casing on a node that lies on the axis has no radial direction.
    let err = load_err(&casing(
        "group = \"tip_contact\"\ngap = 0\naxis = { origin = [0, 0, 0.25], direction = [1, 0, 0] }",
    ));
    assert!(err.contains("on the rotation axis"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Moreau–Jean against Carpenter on the blade (Thorin et al. 2018, §3)
// ---------------------------------------------------------------------------------------------

/// η = Σ|a − b| / Σ|b| (Thorin et al. 2018, eq. 19, rectangle rule on a common grid).
fn eta(a: &[f64], b: &[f64]) -> f64 {
    let num: f64 = a.iter().zip(b).map(|(x, y)| (x - y).abs()).sum();
    num / b.iter().map(|y| y.abs()).sum::<f64>()
}

/// Samples of a history on the grid of step `coarse` (`k` times its step): the gap of
/// obstacle `i` and recorded column `col` at t_k, and the mean contact force of obstacle `i`
/// over each coarse step (the sum of its impulses in it over the coarse step).
fn on_grid(
    h: &nlrom::march::obstacle::NonsmoothHistory,
    k: usize,
    coarse: f64,
    i: usize,
    col: usize,
) -> (Vec<f64>, Vec<f64>, Vec<f64>) {
    let m = h.gap.len() / h.len();
    let r = h.dofs.len();
    let steps = (h.len() - 1) / k;
    let gap = (0..=steps).map(|s| h.gap[s * k * m + i]).collect();
    let column = (0..=steps).map(|s| h.x[s * k * r + col]).collect();
    let force = (1..=steps)
        .map(|s| {
            ((s - 1) * k + 1..=s * k)
                .map(|t| h.impulse[t * m + i])
                .sum::<f64>()
                / coarse
        })
        .collect();
    (gap, column, force)
}

#[test]
fn moreau_jean_at_a_hundred_times_carpenters_limit_agrees_with_carpenter() {
    // The coarse thermal blade touching the casing at rest (g0 = 0), 100 N per tip node at
    // 2000/60 Hz, μ = 0.15, α = 0.1 m/s, over 2 ms (the friction drives the blade's flexural
    // vibration, ≈ 1.3 kHz): Carpenter at 0.9 times its limit 2/ω_max and Moreau–Jean at
    // h = 1e-5 s, more than a hundred times that limit, agree on the middle tip node's
    // circumferential displacement, temperature and contact force (Thorin et al. 2018, §3.3: the
    // two schemes agree within 0.82 / 5.1 / 7.3 %).
    use nlrom::march::carpenter::{carpenter, stability_limits};
    let text = thermal_blade("\"root\"", 9e-6, 0.1)
        .replace(
            "time_step_s = 1e-5",
            "time_step_s = 1e-5\nactivation_tolerance = 1e-8",
        )
        .replace("gap = 1e-6", "gap = 0.0");
    let nc = build(&text);
    let sys = &nc.system;
    let lim = stability_limits(sys).unwrap();
    let coarse = 1e-5;
    assert!(coarse > 100.0 * lim.mechanical, "limit {}", lim.mechanical);
    assert!(lim.thermal > 1e-3, "heat limit {}", lim.thermal);
    let k = (coarse / (0.9 * lim.mechanical)).ceil() as usize;
    let n_coarse = 200;
    let middle = 2;
    let uy_col = 3 * middle + 1;
    let theta_col = nc.response.len() + middle;
    let c = carpenter(
        sys,
        &NonsmoothSettings {
            step: coarse / k as f64,
            steps: n_coarse * k,
            ..nc.settings.clone()
        },
    )
    .unwrap();
    let mj = moreau_jean(
        sys,
        &NonsmoothSettings {
            step: coarse,
            steps: n_coarse,
            ..nc.settings.clone()
        },
    )
    .unwrap();
    let (_, tc, fc) = on_grid(&c, k, coarse, middle, theta_col);
    let (_, t1, f1) = on_grid(&mj, 1, coarse, middle, theta_col);
    let (_, uc, _) = on_grid(&c, k, coarse, middle, uy_col);
    let (_, u1, _) = on_grid(&mj, 1, coarse, middle, uy_col);
    let (eu, et, ef) = (eta(&u1, &uc), eta(&t1, &tc), eta(&f1, &fc));
    assert!(
        eu < 0.02 && et < 0.02 && ef < 0.02,
        "u_y {eu:.4}, θ {et:.4}, λ/h {ef:.4} (k = {k})"
    );
    eprintln!(
        "η: u_y {eu:.2e}, θ {et:.2e}, λ/h {ef:.2e} at h = {coarse:.0e} s = {:.0} h_c",
        coarse / lim.mechanical
    );
    // The friction does bend the blade: u_y is not negligible against its own range.
    let span = uc.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    assert!(span > 1e-8, "u_y {span}");
}

// ---------------------------------------------------------------------------------------------
// `nlrom march` on a casing case and tools/post/plot_nonsmooth.py
// ---------------------------------------------------------------------------------------------

/// Runs the Python tool `script` (a path from the repository root) with `args`; its JSON
/// stdout.
fn python_json<S: AsRef<std::ffi::OsStr>>(
    script: &str,
    args: impl IntoIterator<Item = S>,
) -> serde_json::Value {
    let mut cmd = std::process::Command::new("python3");
    cmd.current_dir(root()).arg(script).args(args);
    json_of(&mut cmd)
}

/// Runs `cmd`, which must succeed; its JSON stdout.
fn json_of(cmd: &mut std::process::Command) -> serde_json::Value {
    let out = cmd.output().unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).unwrap()
}

#[test]
fn nlrom_march_writes_temperatures_and_plot_nonsmooth_compares_two_steps() {
    // The thermal coarse blade at 1000/3 Hz (one 3 ms period) at h = 2.5e-6 s and 1e-5 s.
    let dir = std::env::temp_dir().join(format!("nlrom_casing_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = root().join("meshes/blade_coarse.msh");
    let run = |h: &str, name: &str| -> serde_json::Value {
        let text = thermal_blade("\"root\"", 9e-6, 0.1)
            .replace("../meshes/blade_coarse.msh", &mesh.display().to_string())
            .replace("33.333333333333336", "333.33333333333336")
            .replace(
                "time_step_s = 1e-5",
                &format!("time_step_s = {h}\nactivation_tolerance = 1e-8"),
            )
            .replace("gap = 1e-6", "gap = 0.0");
        let case = dir.join(format!("{name}.toml"));
        std::fs::write(&case, text.clone()).unwrap();
        if h == "1e-5" {
            // Without a nonsmooth scheme the casing is refused with its key.
            let plain = dir.join("plain.toml");
            std::fs::write(&plain, &text).unwrap();
            let out = std::process::Command::new(env!("CARGO_BIN_EXE_nlrom"))
                .arg("march")
                .arg(&plain)
                .arg("-o")
                .arg(dir.join("plain.h5"))
                .output()
                .unwrap();
            let err = String::from_utf8_lossy(&out.stderr);
            assert!(
                !out.status.success() && err.contains("key 'casing'"),
                "{err}"
            );
        }
        std::fs::write(
            &case,
            text.replace("[march]\n", "[march]\nscheme = \"moreau-jean\"\n"),
        )
        .unwrap();
        json_of(
            std::process::Command::new(env!("CARGO_BIN_EXE_nlrom"))
                .arg("march")
                .arg(&case)
                .arg("-o")
                .arg(dir.join(format!("{name}.h5")))
                .arg("--json"),
        )
    };
    let fine = run("2.5e-6", "fine");
    let coarse = run("1e-5", "coarse");
    for r in [&fine, &coarse] {
        let frictional = r["frictional_heat_j"].as_f64().unwrap();
        assert!(frictional > 0.0, "{r}");
        assert!(r["heat_balance_residual_j"].as_f64().unwrap().abs() < 1e-9 * frictional);
        assert!(r["max_temperature_rise_k"].as_f64().unwrap() > 0.0);
    }
    let e = python_json(
        "tools/post/plot_nonsmooth.py",
        [
            dir.join("fine.h5").into_os_string(),
            dir.join("coarse.h5").into_os_string(),
            "-o".into(),
            dir.join("plot.png").into_os_string(),
            "--labels".into(),
            "fine".into(),
            "coarse".into(),
        ],
    );
    for key in ["gap", "temperature", "force"] {
        let v = e["coarse"][key].as_f64().unwrap();
        assert!(v.is_finite() && v < 0.05, "{key}: {v} ({e})");
    }
    assert!(dir.join("plot.png").exists());
    std::fs::remove_dir_all(&dir).ok();
}

// ---------------------------------------------------------------------------------------------
// Craig–Bampton reduced mechanics
// ---------------------------------------------------------------------------------------------

/// The bundled surrogate `cases/blade_casing.toml` with its text passed through `edit`.
fn surrogate_edited(
    edit: impl Fn(String) -> String,
) -> nlrom::problem::nonsmooth_case::NonsmoothCase {
    let path = root().join("cases/blade_casing.toml");
    let text = edit(std::fs::read_to_string(&path).unwrap());
    let case = Case::from_str(&text, &path).unwrap();
    let sm = nlrom::model::build(&case, &mut |_| {}).unwrap();
    nonsmooth_case(&case, &sm).unwrap()
}

/// The bundled surrogate `cases/blade_casing.toml` with `extra` appended.
fn surrogate(extra: &str) -> nlrom::problem::nonsmooth_case::NonsmoothCase {
    surrogate_edited(|text| text + extra)
}

#[test]
fn craig_bampton_reduced_blade_follows_the_full_thermoelastic_march() {
    // The surrogate (1476 displacement and 492 temperature DOF) over 5 ms at h = 1e-5 s against
    // its Craig–Bampton model (the 7 contact nodes as masters, 21 DOF, plus fixed-interface
    // modes; the heat rows in contact temperatures and every conduction mode): the middle
    // contact node's circumferential displacement, temperature and contact force.
    let full = surrogate("");
    let steps = 500;
    let settings = |nc: &nlrom::problem::nonsmooth_case::NonsmoothCase| NonsmoothSettings {
        steps,
        ..nc.settings.clone()
    };
    let reference = moreau_jean(&full.system, &settings(&full)).unwrap();
    let middle = 3;
    let (uy, theta) = (3 * middle + 1, full.response.len() + middle);
    let errors = |modes: usize| -> (f64, f64, f64, usize) {
        let rom = surrogate(&format!("\n[reduction]\ninterface_modes = {modes}\n"));
        assert_eq!(rom.response, full.response);
        assert_eq!(rom.temperature_nodes, full.temperature_nodes);
        let h = moreau_jean(&rom.system, &settings(&rom)).unwrap();
        let (_, t1, f1) = on_grid(&h, 1, 1e-5, middle, theta);
        let (_, t0, f0) = on_grid(&reference, 1, 1e-5, middle, theta);
        let (_, u1, _) = on_grid(&h, 1, 1e-5, middle, uy);
        let (_, u0, _) = on_grid(&reference, 1, 1e-5, middle, uy);
        let last = h.heat.last().unwrap();
        assert!(last.residual.abs() < 1e-9 * last.frictional, "{last:?}");
        // The heat balance is the full model's (stored, conducted and frictional heat).
        let q = reference.heat.last().unwrap();
        for (a, b) in [
            (last.stored, q.stored),
            (last.exchanged, q.exchanged),
            (last.frictional, q.frictional),
        ] {
            assert!((a - b).abs() < 1e-6 * q.frictional, "{last:?} vs {q:?}");
        }
        (eta(&u1, &u0), eta(&t1, &t0), eta(&f1, &f0), rom.system.n)
    };
    let (eu5, et5, ef5, n5) = errors(5);
    let (eu, et, ef, n) = errors(20);
    eprintln!("CB 5 modes ({n5} DOF): η u_y {eu5:.2e}, θ {et5:.2e}, λ/h {ef5:.2e}");
    eprintln!("CB 20 modes ({n} DOF): η u_y {eu:.2e}, θ {et:.2e}, λ/h {ef:.2e}");
    assert_eq!(n, 21 + 20 + full.system.n - full.system.n_mech);
    assert!(eu < 2e-4 && et < 1e-6 && ef < 1e-6, "{eu} {et} {ef}");
    assert!(eu < eu5 && ef < ef5, "{eu} {eu5} {ef} {ef5}");
}

/// max |a − b| over the rows `rows` and columns `cols` of two row-major n × n matrices, relative
/// to max |b| there (0 for a zero block).
fn block_difference(
    a: &[f64],
    b: &[f64],
    n: usize,
    rows: std::ops::Range<usize>,
    cols: std::ops::Range<usize>,
) -> (f64, f64) {
    let (mut diff, mut size) = (0.0f64, 0.0f64);
    for i in rows {
        for j in cols.clone() {
            diff = diff.max((a[i * n + j] - b[i * n + j]).abs());
            size = size.max(b[i * n + j].abs());
        }
    }
    (if size > 0.0 { diff / size } else { diff }, size)
}

#[test]
fn the_sparse_projection_of_the_reduced_blade_equals_the_dense_one() {
    // The surrogate (1968 DOF) reduced to 533 coordinates twice: the sparse rows projected by
    // blocks (the path of every `[reduction]`) and the dense full model projected with the dense
    // basis. Every block of M, C and K, the load, the obstacles' rows and the heat weights agree to
    // 1e-10 of the block's largest entry, and so do 200 steps of the march.
    use nlrom::problem::casing_case::casing_model;
    use nlrom::problem::casing_rom::{reduce_casing, Projection};
    let path = root().join("cases/blade_casing.toml");
    let text = std::fs::read_to_string(&path).unwrap() + "\n[reduction]\ninterface_modes = 20\n";
    let case = Case::from_str(&text, &path).unwrap();
    let sm = nlrom::model::build(&case, &mut |_| {}).unwrap();
    let red = case.reduction.as_ref().unwrap();
    let reduce = |how| {
        let t0 = std::time::Instant::now();
        let model = casing_model(&case, &sm).unwrap();
        let nc = reduce_casing(&case, &sm, red, model, how).unwrap();
        eprintln!("{how:?}: {:.3} s", t0.elapsed().as_secs_f64());
        nc
    };
    let sparse = reduce(Projection::Sparse);
    let dense = reduce(Projection::Dense);
    let (s, d) = (&sparse.system, &dense.system);
    let (n, nm) = (d.n, d.n_mech);
    assert_eq!((s.n, s.n_mech), (n, nm));
    assert_eq!((n, nm), (533, 41));
    let mut nonzero_blocks = 0;
    for (name, a, b) in [
        ("M", &s.mass, &d.mass),
        ("C", &s.damping, &d.damping),
        ("K", &s.stiffness, &d.stiffness),
    ] {
        for (block, rows, cols) in [
            ("uu", 0..nm, 0..nm),
            ("uθ", 0..nm, nm..n),
            ("θu", nm..n, 0..nm),
            ("θθ", nm..n, nm..n),
        ] {
            let (e, size) = block_difference(a, b, n, rows, cols);
            eprintln!("{name}^{block}: largest entry {size:.3e}, difference {e:.2e}");
            assert!(e <= 1e-10, "{name}^{block}: {e:e} of {size:e}");
            if size > 0.0 {
                nonzero_blocks += 1;
            }
        }
    }
    // M^uu, C^uu, C^θθ, K^uu, K^uθ, K^θθ.
    assert_eq!(nonzero_blocks, 6);
    let fmax = d.force.iter().map(|f| f.cos.abs()).fold(0.0, f64::max);
    for (a, b) in s.force.iter().zip(&d.force) {
        assert!((a.cos - b.cos).abs() <= 1e-10 * fmax && a.mean == b.mean && a.sin == b.sin);
    }
    assert_eq!(s.obstacles.len(), 7);
    for (a, b) in s.obstacles.iter().zip(&d.obstacles) {
        for (x, y) in [
            (&a.normal, &b.normal),
            (&a.tangential, &b.tangential),
            (&a.heated, &b.heated),
        ] {
            assert_eq!(x.len(), y.len(), "{}", a.name);
            for (p, q) in x.iter().zip(y) {
                assert!(p.0 == q.0 && (p.1 - q.1).abs() <= 1e-12, "{p:?} {q:?}");
            }
        }
    }
    let wmax = d.heat_weights.iter().map(|w| w.abs()).fold(0.0, f64::max);
    for (a, b) in s.heat_weights.iter().zip(&d.heat_weights) {
        assert!((a - b).abs() <= 1e-10 * wmax, "{a} {b}");
    }
    assert_eq!(s.heat_weights.len(), d.heat_weights.len());
    assert_eq!(sparse.settings.record, dense.settings.record);
    let settings = NonsmoothSettings {
        steps: 200,
        ..dense.settings.clone()
    };
    let (hs, hd) = (
        moreau_jean(s, &settings).unwrap(),
        moreau_jean(d, &settings).unwrap(),
    );
    let e = eta(&hs.x, &hd.x);
    let ei = eta(&hs.impulse, &hd.impulse);
    eprintln!("200 steps: η recorded rows {e:.2e}, impulses {ei:.2e}");
    assert!(hd.impulse.iter().any(|&l| l > 0.0));
    assert!(e < 1e-10 && ei < 1e-10, "{e} {ei}");
}

/// A straight hexa8 blade in Gmsh 2.2 ASCII: chord 30 mm along x (`nx` cells), thickness 4 mm
/// along y (2 cells), span 50 mm along z from r = 0.2 m (`nz` cells); groups "volume", "root"
/// (the quads at z = 0.2 m) and "tip_contact" (the line of tip nodes at mid-thickness).
fn hexa8_blade_msh(nx: usize, nz: usize) -> String {
    let ny = 2;
    let id = |i: usize, j: usize, k: usize| 1 + i + (nx + 1) * (j + (ny + 1) * k);
    let mut nodes = String::new();
    for k in 0..=nz {
        for j in 0..=ny {
            for i in 0..=nx {
                let (x, y, z) = (
                    0.03 * i as f64 / nx as f64,
                    -0.002 + 0.004 * j as f64 / ny as f64,
                    0.2 + 0.05 * k as f64 / nz as f64,
                );
                nodes += &format!("{} {x} {y} {z}\n", id(i, j, k));
            }
        }
    }
    let mut elements = Vec::new();
    for k in 0..nz {
        for j in 0..ny {
            for i in 0..nx {
                let c = [
                    id(i, j, k),
                    id(i + 1, j, k),
                    id(i + 1, j + 1, k),
                    id(i, j + 1, k),
                    id(i, j, k + 1),
                    id(i + 1, j, k + 1),
                    id(i + 1, j + 1, k + 1),
                    id(i, j + 1, k + 1),
                ];
                elements.push(format!("5 2 1 1 {}", c.map(|v| v.to_string()).join(" ")));
            }
        }
    }
    for j in 0..ny {
        for i in 0..nx {
            let q = [
                id(i, j, 0),
                id(i, j + 1, 0),
                id(i + 1, j + 1, 0),
                id(i + 1, j, 0),
            ];
            elements.push(format!("3 2 2 2 {}", q.map(|v| v.to_string()).join(" ")));
        }
    }
    for i in 0..nx {
        elements.push(format!("1 2 3 3 {} {}", id(i, 1, nz), id(i + 1, 1, nz)));
    }
    let n_nodes = (nx + 1) * (ny + 1) * (nz + 1);
    let mut out = format!(
        "$MeshFormat\n2.2 0 8\n$EndMeshFormat\n$PhysicalNames\n3\n3 1 \"volume\"\n2 2 \"root\"\n1 3 \"tip_contact\"\n$EndPhysicalNames\n$Nodes\n{n_nodes}\n{nodes}$EndNodes\n$Elements\n{}\n",
        elements.len()
    );
    for (e, line) in elements.iter().enumerate() {
        out += &format!("{} {line}\n", e + 1);
    }
    out + "$EndElements\n"
}

#[test]
fn a_casing_model_beyond_the_dense_limit_is_reduced_from_its_sparse_rows() {
    // A hexa8 blade of 9792 free displacement DOF, above the 6000 DOF of the dense model: without
    // `[reduction]` a keyed error; with it the Craig–Bampton model (the 17 tip contact nodes as
    // masters, 10 modes) is formed from the sparse rows. Its static response to the tip load
    // equals the full model's, solved with faer's sparse LU (Craig–Bampton is exact for loads on
    // the masters), to 1e-10; it marches into contact (the static tip rise, 6 µm, exceeds the
    // 2 µm gap).
    use nlrom::problem::casing_case::casing_model;
    let dir = std::env::temp_dir().join(format!("nlrom_big_casing_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mesh = dir.join("blade_hexa8.msh");
    std::fs::write(&mesh, hexa8_blade_msh(16, 64)).unwrap();
    let text = blade_case_on(
        &mesh.display().to_string(),
        r#"
[[casing]]
name = "casing"
group = "tip_contact"
axis = { origin = [0, 0, 0], direction = [1, 0, 0] }
gap = 2e-6
restitution = 0.0
mu = 0.15
speed_rpm = 2000
"#,
    );
    let path = dir.join("big.toml");
    let case = Case::from_str(&text, &path).unwrap();
    let sm = nlrom::model::build(&case, &mut |_| {}).unwrap();
    let nm = sm.free.n_free();
    assert_eq!(nm, 9792);
    let err = nonsmooth_case(&case, &sm).err().unwrap().to_string();
    assert!(
        err.contains("9792 DOF") && err.contains("[reduction]"),
        "{err}"
    );
    let full = casing_model(&case, &sm).unwrap();
    let reduced_case =
        Case::from_str(&(text + "\n[reduction]\ninterface_modes = 10\n"), &path).unwrap();
    let t0 = std::time::Instant::now();
    let rom = nonsmooth_case(&reduced_case, &sm).unwrap();
    eprintln!(
        "{nm} DOF reduced to {} in {:.2} s",
        rom.system.n,
        t0.elapsed().as_secs_f64()
    );
    assert_eq!(rom.system.n, 17 * 3 + 10);
    // Static tip response: full K u = f (sparse LU) against the reduced K_r u_r = f_r.
    let f_full = Mat::from_fn(nm, 1, |i, _| full.case.system.force[i].cos);
    let lu = sm.free.k.as_ref().sp_lu().unwrap();
    let mut u_full = f_full;
    lu.solve_in_place(u_full.as_mut());
    let r = rom.system.n;
    let k_r = Mat::from_fn(r, r, |i, j| rom.system.stiffness[i * r + j]);
    let f_r = Mat::from_fn(r, 1, |i, _| rom.system.force[i].cos);
    let u_r = k_r.partial_piv_lu().solve(&f_r);
    let rows_full = full.case.settings.record.clone().unwrap();
    let rows_red = rom.settings.record.clone().unwrap();
    assert_eq!(rows_full.len(), 51);
    let scale = rows_full
        .iter()
        .map(|&i| u_full[(i, 0)].abs())
        .fold(0.0, f64::max);
    let diff = rows_full
        .iter()
        .zip(&rows_red)
        .map(|(&i, &j)| (u_full[(i, 0)] - u_r[(j, 0)]).abs())
        .fold(0.0, f64::max);
    eprintln!("static tip response: largest {scale:.3e} m, difference {diff:.2e} m");
    assert!(scale > 1e-6 && diff <= 1e-10 * scale, "{diff} of {scale}");
    let h = moreau_jean(&rom.system, &with_steps(&rom.settings, 300)).unwrap();
    assert!(h.impulse.iter().any(|&l| l > 0.0));
    assert!(h.x.iter().all(|v| v.is_finite()));
    std::fs::remove_dir_all(&dir).ok();
}

#[test]
fn a_casing_case_refuses_an_interface_reduction() {
    let path = root().join("cases/blade_casing.toml");
    let text = std::fs::read_to_string(&path).unwrap()
        + "\n[reduction]\ninterface_modes = 5\ngsi_modes = 3\n";
    let case = Case::from_str(&text, &path).unwrap();
    let sm = nlrom::model::build(&case, &mut |_| {}).unwrap();
    let err = nonsmooth_case(&case, &sm).err().unwrap().to_string();
    assert!(err.contains("reduction.gsi_modes"), "{err}");
}

// ---------------------------------------------------------------------------------------------
// Step-size study (Thorin et al. 2018, Figs 4–5)
// ---------------------------------------------------------------------------------------------

/// Runs the study `script` (a path from the repository root) with `args` on the Craig–Bampton
/// surrogate (`--modes 20`) with this build's `nlrom` and `--plot` into a temporary file (one per
/// call), which must be written; its JSON stdout.
fn reduced_study(script: &str, args: &[&str]) -> serde_json::Value {
    static RUNS: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let run = RUNS.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
    let plot = std::env::temp_dir().join(format!("nlrom_study_{}_{run}.png", std::process::id()));
    let mut all: Vec<&str> = args.to_vec();
    all.extend([
        "--modes",
        "20",
        "--nlrom",
        env!("CARGO_BIN_EXE_nlrom"),
        "--plot",
        plot.to_str().unwrap(),
    ]);
    let report = python_json(script, all);
    assert!(plot.exists(), "{script}: no {}", plot.display());
    std::fs::remove_file(&plot).ok();
    report
}

/// The errors of `key` ("gap", "temperature" or "force") in the JSON report of
/// tools/validation/step_study.py, one per step in decreasing order of the step.
fn study_errors(report: &serde_json::Value, key: &str) -> Vec<f64> {
    report["errors"][key]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect()
}

#[test]
fn step_study_errors_fall_at_first_order_with_the_step() {
    // tools/validation/step_study.py on the Craig–Bampton surrogate (20 modes), one revolution
    // (30 ms) from rest in contact (g0 = 0): h = 4e-5, 1e-5, 5e-6 s against h = 1.25e-6 s.
    let r = reduced_study(
        "tools/validation/step_study.py",
        &["--steps", "4e-5", "1e-5", "5e-6", "--reference", "1.25e-6"],
    );
    eprintln!("{r}");
    for key in ["gap", "temperature", "force"] {
        let e = study_errors(&r, key);
        assert!(e[0] > e[1] && e[1] > e[2], "{key}: {e:?}");
        let p = r["order"][key].as_f64().unwrap();
        assert!(p > 0.8, "{key}: order {p} ({e:?})");
        // The paper's accuracy at h = 1e-5 s: within a few per cent.
        assert!(e[1] < 0.02, "{key}: {e:?}");
    }
}

#[test]
fn moreau_jean_agrees_with_carpenter_at_carpenters_step_on_the_reduced_surrogate() {
    // tools/validation/step_study.py with Carpenter's scheme as the reference: the Craig–Bampton
    // surrogate (20 modes, 2/ω_max = 3.68e-7 s) over one revolution (30 ms) from rest in contact,
    // Carpenter at h = 3.3e-7 s (0.9 of its limit) against Moreau–Jean at the same step and at
    // 1e-5 s (Thorin et al. 2018, §3.3: the schemes agree; Moreau–Jean within a few per cent at
    // steps far above Carpenter's limit). `--plot` draws the errors against h.
    let r = reduced_study(
        "tools/validation/step_study.py",
        &[
            "--steps",
            "1e-5",
            "3.3e-7",
            "--reference",
            "3.3e-7",
            "--reference-scheme",
            "carpenter",
        ],
    );
    eprintln!("{r}");
    assert_eq!(r["reference_scheme"], "carpenter");
    let limit = r["reference_stability_limit"].as_f64().unwrap();
    assert!((3.3e-7..3.7e-7).contains(&limit), "2/ω_max = {limit}");
    for key in ["gap", "temperature", "force"] {
        let e = study_errors(&r, key);
        // [at 1e-5 s, at Carpenter's step]
        assert!(e[1] < 0.01, "{key}: {e:?}");
        assert!(e[0] < 0.02, "{key}: {e:?}");
    }
}

#[test]
fn residual_penetration_of_a_first_impact_falls_with_the_step() {
    // The Craig–Bampton surrogate from a 1 µm gap, 10 ms: the largest penetration after the
    // first impact, bounded by h·|ẏ|, shrinks with h (Thorin et al. 2018, Fig. 4).
    let rom = surrogate("\n[reduction]\ninterface_modes = 20\n");
    let mut sys = rom.system.clone();
    for o in &mut sys.obstacles {
        o.gap = 1e-6;
    }
    let pen: Vec<f64> = [4e-5, 2e-5, 1e-5, 5e-6]
        .iter()
        .map(|&h| {
            let s = NonsmoothSettings {
                step: h,
                steps: (0.01 / h).round() as usize,
                record: Some(Vec::new()),
                ..rom.settings.clone()
            };
            moreau_jean(&sys, &s).unwrap().max_penetration()
        })
        .collect();
    eprintln!("max penetration at h = 4e-5, 2e-5, 1e-5, 5e-6 s: {pen:?}");
    assert!(pen.windows(2).all(|w| w[1] < w[0]), "{pen:?}");
    assert!(pen[0] > 1e-7 && pen[3] < 0.8 * pen[0], "{pen:?}");
}

// ---------------------------------------------------------------------------------------------
// Thermoelastic instability of the surrogate (the temperature runaway)
// ---------------------------------------------------------------------------------------------

/// The contact forces' change per kelvin of the temperature rows (N/K, one row per obstacle of
/// `active`) of `sys` held on those obstacles with quasi-static mechanics: from
/// K^uu u + K^uθ θ = f + H^u λ and g0_A + G_A u = 0, λ_A = λ_f + S θ with
/// S = (G_A K⁻¹ H^u_A)⁻¹ G_A K⁻¹ K^uθ.
fn thermal_sensitivity(sys: &NonsmoothSystem, active: &[usize]) -> Mat<f64> {
    let (n, nm) = (sys.n, sys.n_mech);
    let nt = n - nm;
    let lu = Mat::from_fn(nm, nm, |i, j| sys.stiffness[i * n + j]).partial_piv_lu();
    let a = active.len();
    let k_h = lu.solve(Mat::from_fn(nm, a, |i, j| {
        sys.obstacles[active[j]].column(n)[i]
    }));
    let k_t = lu.solve(Mat::from_fn(nm, nt, |i, j| sys.stiffness[i * n + nm + j]));
    let g = |r: usize, x: &Mat<f64>, c: usize| -> f64 {
        sys.obstacles[active[r]]
            .normal
            .iter()
            .map(|&(j, w)| w * x[(j, c)])
            .sum()
    };
    let w = Mat::from_fn(a, a, |r, c| g(r, &k_h, c));
    w.partial_piv_lu()
        .solve(Mat::from_fn(a, nt, |r, c| g(r, &k_t, c)))
}

/// The growth rate σ (1/s) of the thermoelastic instability of `sys` held on the obstacles
/// `active`: with λ_A = λ_f + S θ ([`thermal_sensitivity`]) the heat rows
/// C^θθ θ̇ + K^θθ θ = α P_A λ_A grow as e^{σt} along the eigenvectors v of
/// C^θθ⁻¹(α P_A S − K^θθ). σ is the largest real eigenvalue whose mode loads every held node
/// the same way (S v of one sign, so the active set can persist); the other modes open a contact.
fn instability_rate(sys: &NonsmoothSystem, active: &[usize]) -> f64 {
    let (n, nm) = (sys.n, sys.n_mech);
    let nt = n - nm;
    let s = thermal_sensitivity(sys, active);
    let cols: Vec<Vec<f64>> = active.iter().map(|&i| sys.obstacles[i].column(n)).collect();
    let rhs = Mat::from_fn(nt, nt, |i, j| {
        -sys.stiffness[(nm + i) * n + nm + j]
            + (0..active.len())
                .map(|k| cols[k][nm + i] * s[(k, j)])
                .sum::<f64>()
    });
    let c = Mat::from_fn(nt, nt, |i, j| sys.damping[(nm + i) * n + nm + j]);
    let e = c.partial_piv_lu().solve(rhs).eigen().unwrap();
    let (values, vectors) = (e.S(), e.U());
    (0..nt)
        .filter(|&k| values[k].im.abs() <= 1e-9 * values[k].re.abs())
        .filter(|&k| {
            let sv: Vec<f64> = (0..active.len())
                .map(|r| (0..nt).map(|j| s[(r, j)] * vectors[(j, k)].re).sum())
                .collect();
            sv.iter().all(|&x| x >= 0.0) || sv.iter().all(|&x| x <= 0.0)
        })
        .map(|k| values[k].re)
        .fold(f64::NEG_INFINITY, f64::max)
}

/// The bundled surrogate's Craig–Bampton model (20 modes), with `expansion` as the thermal
/// expansion coefficient (1/K).
fn reduced_surrogate(expansion: &str) -> nlrom::problem::nonsmooth_case::NonsmoothCase {
    surrogate_edited(|text| {
        text.replace("expansion = 9e-6", &format!("expansion = {expansion}"))
            + "\n[reduction]\ninterface_modes = 20\n"
    })
}

#[test]
fn the_temperature_runaway_is_the_thermoelastic_instability_of_the_blade_held_on_the_casing() {
    // The bundled surrogate (Craig–Bampton, 20 modes) over 33 revolutions (0.99 s): frictional
    // heat expands the tip against the rigid casing, so the contact forces rise with the
    // temperature and the heat with the forces. Once the middle node alone holds the blade (the
    // others lift off), temperatures and forces grow as e^{σt} with σ the admissible rate of
    // the quasi-static linearisation on that node ([`instability_rate`]). As in Thorin et al.
    // (2018, §3.2, Figs 2–3 and 6) the middle of the tip (node 4) heats most and reaches
    // thousands of degrees, and the end nodes 1 and 7 separate from the casing for good.
    let rom = reduced_surrogate("9e-6");
    let (per, periods) = (3000, 33);
    let s = NonsmoothSettings {
        steps: per * periods,
        ..rom.settings.clone()
    };
    let h = moreau_jean(&rom.system, &s).unwrap();
    let m = rom.system.obstacles.len();
    let last = per * periods;
    let window = last - 3 * per..=last;
    let pressed = |i: usize| h.impulse[last * m + i] > 0.0;
    let held: Vec<usize> = (0..m).filter(|&i| pressed(i)).collect();
    for i in 0..m {
        let steps = window
            .clone()
            .filter(|&t| h.impulse[t * m + i] > 0.0)
            .count();
        assert!(
            steps == if pressed(i) { 3 * per + 1 } else { 0 },
            "obstacle {i}: in contact {steps} of the last {} steps",
            3 * per + 1
        );
    }
    let order = along_chord(&rom.system);
    assert_eq!(held, [order[3]], "held {held:?}, chord order {order:?}");
    let (r, first_theta) = (h.dofs.len(), rom.response.len());
    let theta = |t: usize| -> Vec<f64> {
        order
            .iter()
            .map(|&i| h.x[t * r + first_theta + i])
            .collect()
    };
    for t in [last / 2, last] {
        let th = theta(t);
        eprintln!("{:.3} s: θ of nodes 1–7 {th:.1?} K", t as f64 * s.step);
        assert!((0..7).all(|i| i == 3 || th[3] > 2.0 * th[i]), "{th:?}");
    }
    let hottest = |t: usize| theta(t)[3];
    assert!(hottest(last) > 1000.0);
    let last_touch: Vec<f64> = [0, 6]
        .iter()
        .map(|&k| {
            (0..=last)
                .rev()
                .find(|&t| h.impulse[t * m + order[k]] > 0.0)
                .unwrap() as f64
                * s.step
        })
        .collect();
    assert!(last_touch.iter().all(|&e| e < 0.6), "{last_touch:?}");
    let fitted = (hottest(last) / hottest(last - 3 * per)).ln() / (3.0 * per as f64 * s.step);
    let sigma = instability_rate(&rom.system, &held);
    let full = instability_rate(&surrogate("").system, &held);
    let plain = instability_rate(
        &reduced_surrogate("0.0").system,
        &(0..m).collect::<Vec<_>>(),
    );
    eprintln!(
        "held {held:?}: fitted {fitted:.4} 1/s, σ {sigma:.4} 1/s (full model {full:.4}); node 4 at {:.0} K at {:.2} s; nodes 1 and 7 last touch at {last_touch:.3?} s; without expansion σ {plain:.2e} 1/s",
        hottest(last),
        last as f64 * s.step
    );
    assert!((fitted - sigma).abs() < 0.01 * sigma, "{fitted} vs {sigma}");
    assert!((full - sigma).abs() < 1e-4 * sigma, "{full} vs {sigma}");
    // The end nodes end below the reference temperature although every heat input is ≥ 0,
    // which the heat equation forbids (maximum principle): a spatial oscillation, not a
    // physical effect nor one of the time stepping (h μ_max ≈ 5e-4). Heat at node 4 growing as
    // e^{σt} penetrates √(κ/σ) = √(6.7 / (4430·520·8.08)) m = 0.6 mm, far below the node spacing
    // (5 mm along the chord); the discrete response (σ C^θθ + K^θθ) y = e_4 of the full model's
    // heat rows (HRZ-lumped capacity, hexa20 conduction with positive off-diagonal entries: not
    // an M-matrix) changes sign at the end nodes, as the march does, while the steady response
    // K^θθ y = e_4 and the response to a source growing 100 times slower (a 6 mm layer) stay
    // positive.
    let full_nc = surrogate("");
    let fs = &full_nc.system;
    let (n, nm) = (fs.n, fs.n_mech);
    let nt = n - nm;
    let rows: Vec<usize> = order
        .iter()
        .map(|&i| fs.obstacles[i].heated[0].0 - nm)
        .collect();
    let response = |rate: f64| -> Vec<f64> {
        let a = Mat::from_fn(nt, nt, |i, j| {
            rate * fs.damping[(nm + i) * n + nm + j] + fs.stiffness[(nm + i) * n + nm + j]
        });
        let y = a
            .partial_piv_lu()
            .solve(Mat::from_fn(nt, 1, |i, _| f64::from(i == rows[3])));
        rows.iter().map(|&r| y[(r, 0)] / y[(rows[3], 0)]).collect()
    };
    let positive_off_diagonal = (0..nt)
        .flat_map(|i| (0..nt).map(move |j| (i, j)))
        .filter(|&(i, j)| i != j && fs.stiffness[(nm + i) * n + nm + j] > 0.0)
        .count();
    let (growing, slow, steady) = (response(sigma), response(0.01 * sigma), response(0.0));
    let th = theta(last);
    let marched: Vec<f64> = th.iter().map(|t| t / th[3]).collect();
    eprintln!(
        "θ/θ_4 at 0.99 s {marched:.4?}; response to heat growing at σ {growing:.4?}, at σ/100 {slow:.4?}, steady {steady:.4?}; K^θθ has {positive_off_diagonal} positive off-diagonal entries"
    );
    assert!(positive_off_diagonal > 0);
    for v in [&growing, &marched] {
        assert!(v[0] < 0.0 && v[6] < 0.0, "{v:?}");
    }
    for v in [&slow, &steady] {
        assert!(v.iter().all(|&y| y > 0.0), "{v:?}");
    }
    // The march's end-node ratio is the growing response's within a factor 2 (the field also
    // holds what is left of the heat from before the end nodes lifted off at 0.51 s).
    for k in [0, 6] {
        let q = marched[k] / growing[k];
        assert!((0.5..2.0).contains(&q), "node {}: {q}", k + 1);
    }
    // Without the thermal expansion the heat rows alone decay (conduction to the root).
    assert!(plain < 0.0, "{plain}");
}

#[test]
fn frictional_heating_changes_the_forces_and_displacements_as_the_thermal_load_predicts() {
    // Thorin et al. 2018, Figs 6–7: the surrogate over five revolutions (150 ms) with and
    // without the thermal expansion (`tools/validation/thermal_coupling.py` at the end). Both marches share the load and the heating; their
    // difference is the response to the thermal load K^uθ θ, quasi-static against the blade's
    // 1.3 kHz mode: in free flight (135 ms) Δu = −K⁻¹K^uθ θ, in contact (150 ms, every node
    // pressed) Δλ = S θ ([`thermal_sensitivity`]), with θ the coupled march's temperatures.
    let coupled = reduced_surrogate("9e-6");
    let plain = reduced_surrogate("0.0");
    let revs = 5;
    let all = NonsmoothSettings {
        record: None,
        steps: 3000 * revs,
        ..coupled.settings.clone()
    };
    let hc = moreau_jean(&coupled.system, &all).unwrap();
    let hp = moreau_jean(&plain.system, &all).unwrap();
    let sys = &coupled.system;
    let (n, nm, m) = (sys.n, sys.n_mech, sys.obstacles.len());
    let rows = coupled.settings.record.clone().unwrap();
    let theta = |t: usize| &hc.x[t * n + nm..(t + 1) * n];
    // Free flight half a revolution before the end.
    let t = 3000 * revs - 1500;
    assert!((0..m).all(|i| hc.impulse[t * m + i] == 0.0 && hp.impulse[t * m + i] == 0.0));
    let lu = Mat::from_fn(nm, nm, |i, j| sys.stiffness[i * n + j]).partial_piv_lu();
    let du = lu.solve(Mat::from_fn(nm, 1, |i, _| {
        -(0..n - nm)
            .map(|j| sys.stiffness[i * n + nm + j] * theta(t)[j])
            .sum::<f64>()
    }));
    let radial: Vec<usize> = (0..m).map(|i| rows[3 * i + 2]).collect();
    let march_du: Vec<f64> = radial
        .iter()
        .map(|&r| hc.x[t * n + r] - hp.x[t * n + r])
        .collect();
    let largest = march_du.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    for (k, &r) in radial.iter().enumerate() {
        assert!(
            (march_du[k] - du[(r, 0)]).abs() < 1e-3 * largest,
            "node {k}: Δu {} vs {}",
            march_du[k],
            du[(r, 0)]
        );
    }
    // Every node pressed at the end (the load at its outward peak).
    let t = 3000 * revs;
    let force = |hist: &nlrom::march::obstacle::NonsmoothHistory| -> Vec<f64> {
        (0..m).map(|i| hist.impulse[t * m + i] / all.step).collect()
    };
    let (fc, fp) = (force(&hc), force(&hp));
    assert!(fc.iter().chain(&fp).all(|&f| f > 0.0), "{fc:?} {fp:?}");
    let s = thermal_sensitivity(sys, &(0..m).collect::<Vec<_>>());
    let predicted: Vec<f64> = (0..m)
        .map(|i| (0..n - nm).map(|j| s[(i, j)] * theta(t)[j]).sum())
        .collect();
    let change: Vec<f64> = (0..m).map(|i| fc[i] - fp[i]).collect();
    let largest = change.iter().fold(0.0_f64, |a, v| a.max(v.abs()));
    // The effect itself: the thermal expansion spreads the forces of the seven nodes, presses
    // the middle node (node 4) hardest and heats it more.
    let spread = |f: &[f64]| {
        f.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
            - f.iter().cloned().fold(f64::INFINITY, f64::min)
    };
    // The middle node's temperature (a physical coordinate of the reduced heat rows).
    let middle = along_chord(sys)[3];
    let theta_middle = |hist: &nlrom::march::obstacle::NonsmoothHistory| {
        hist.x[t * n + sys.obstacles[middle].heated[0].0]
    };
    eprintln!(
        "150 ms: forces {fc:.1?} N with the coupling, {fp:.1?} N without; S θ − Δλ/h ≤ {:.2} N of {largest:.1} N; middle node {:.2} / {:.2} K; 135 ms: Δu_r {:.4?} µm",
        (0..m).map(|i| (change[i] - predicted[i]).abs()).fold(0.0, f64::max),
        theta_middle(&hc),
        theta_middle(&hp),
        march_du.iter().map(|v| 1e6 * v).collect::<Vec<_>>()
    );
    for i in 0..m {
        assert!(
            (change[i] - predicted[i]).abs() < 0.05 * largest,
            "node {i}: Δλ/h {} vs S θ {}",
            change[i],
            predicted[i]
        );
    }
    assert!(spread(&fc) > 40.0 && spread(&fp) < 1.0, "{fc:?} {fp:?}");
    assert!(
        (0..m).all(|i| i == middle || fc[middle] > fc[i] + 20.0),
        "{fc:?}"
    );
    assert!(theta_middle(&hc) > theta_middle(&hp) + 1.0);
    // tools/validation/thermal_coupling.py runs the same two marches through `nlrom march` and
    // the results files: every node's end force and temperature as above.
    let r = reduced_study("tools/validation/thermal_coupling.py", &[]);
    let names: Vec<&str> = r["nodes"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    let scale = fc.iter().cloned().fold(0.0, f64::max);
    for (run, hist, f) in [("coupled", &hc, &fc), ("uncoupled", &hp, &fp)] {
        for (i, o) in sys.obstacles.iter().enumerate() {
            let k = names.iter().position(|&name| name == o.name).unwrap();
            let force = r[run]["force_end"][k].as_f64().unwrap();
            let temperature = r[run]["temperature_end"][k].as_f64().unwrap();
            let theta_i = hist.x[t * n + o.heated[0].0];
            assert!(
                (force - f[i]).abs() < 1e-9 * scale,
                "{run} {}: {force} vs {}",
                o.name,
                f[i]
            );
            assert!(
                (temperature - theta_i).abs() < 1e-9 * theta_i.abs().max(1.0),
                "{run} {}: {temperature} vs {theta_i}",
                o.name
            );
        }
    }
}

/// The obstacles of a surrogate model in order along the chord (x of their node in
/// `meshes/blade.msh`): contact nodes 1 to 7 of Thorin et al. (2018, Fig. 1).
fn along_chord(sys: &NonsmoothSystem) -> Vec<usize> {
    let mesh = read_msh(&root().join("meshes/blade.msh")).unwrap();
    let x_of = |i: usize| {
        let tag: u64 = sys.obstacles[i]
            .name
            .rsplit(':')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let k = mesh.node_tags.iter().position(|&t| t == tag).unwrap();
        mesh.coords[k][0]
    };
    let mut order: Vec<usize> = (0..sys.obstacles.len()).collect();
    order.sort_by(|&a, &b| x_of(a).total_cmp(&x_of(b)));
    order
}

#[test]
fn lumped_capacity_keeps_each_nodes_frictional_heat_on_that_node() {
    // The full surrogate over one revolution (30 ms, h = 1e-5 s) with the consistent and the
    // lumped (HRZ) capacity. Heat diffuses √(κ t) ≈ 0.3 mm in 30 ms against cells of 2–10 mm, so
    // with the lumped capacity each contact node holds its own heat: θ_i ≈ α Σ_t λ_i / C_ii with
    // C_ii the HRZ share of the hexa20 cells around node i (ρ c_p V_e times 7/248 per cell at a
    // vertex, 2/31 at a mid-edge node; closed forms of ∫N² on the reference cube), less what
    // conduction carries away. The consistent capacity couples each heated node to its cell
    // neighbours: the heat concentrates on the vertex nodes and their neighbours undershoot.
    let mut report = Vec::new();
    for capacity in ["consistent", "lumped"] {
        let nc = surrogate_edited(|t| {
            t.replace(
                "capacity = \"lumped\"",
                &format!("capacity = \"{capacity}\""),
            )
        });
        let sys = &nc.system;
        let (n, nm, m) = (sys.n, sys.n_mech, sys.obstacles.len());
        let s = NonsmoothSettings {
            record: None,
            ..nc.settings.clone()
        };
        let h = moreau_jean(sys, &s).unwrap();
        let t = s.steps;
        let order = along_chord(sys);
        let heated = |i: usize| sys.obstacles[i].heated[0].0;
        let theta: Vec<f64> = order.iter().map(|&i| h.x[t * n + heated(i)]).collect();
        let heat: Vec<f64> = order
            .iter()
            .map(|&i| 0.1 * (0..=t).map(|k| h.impulse[k * m + i]).sum::<f64>())
            .collect();
        let all = &h.x[t * n + nm..(t + 1) * n];
        let (low, high) = (
            all.iter().cloned().fold(f64::INFINITY, f64::min),
            all.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        );
        report.push(format!(
            "{capacity}: θ {theta:.2?} K for α Σλ {heat:.4?} J; nodal θ in [{low:.2}, {high:.2}] K"
        ));
        if capacity == "consistent" {
            // The vertex nodes 1, 3, 5, 7 run hot, the mid-edge ones cold, and nodes fall
            // below the reference temperature.
            assert!(theta[0] > 4.0 * theta[3], "{theta:?}");
            assert!(low < -0.1 * high, "{low} {high}");
        } else {
            let rho_c_ve = 4430.0 * 520.0 * 0.010 * 0.002 * (0.05 / 12.0);
            let cells = [2.0, 2.0, 4.0, 2.0, 4.0, 2.0, 2.0];
            for i in 0..7 {
                let share = if i % 2 == 0 { 7.0 / 248.0 } else { 2.0 / 31.0 };
                let c_ii = cells[i] * share * rho_c_ve;
                assert!(
                    (sys.damping[heated(order[i]) * n + heated(order[i])] - c_ii).abs()
                        < 1e-9 * c_ii
                );
                let adiabatic = heat[i] / c_ii;
                assert!(
                    theta[i] <= adiabatic && theta[i] > 0.85 * adiabatic,
                    "node {}: {} K against {adiabatic} K without conduction",
                    i + 1,
                    theta[i]
                );
            }
            assert!(low > -0.06 * high, "{low} {high}");
        }
    }
    eprintln!("{}", report.join("\n"));
}
