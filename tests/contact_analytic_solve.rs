//! A whole mesh case solved with `[[contact]] evaluation = "analytic"` (the exact continuous-time
//! cycle of the 1-D friction law) against the same case with the AFT at growing N_t: the N = 8
//! shrouded sector of `cases/demo.toml` (Craig–Bampton ROM, node-to-node shroud pairs with a
//! constant normal load, engine order 3, H = 1) traced through the first resonance, where pairs
//! stick, slip part of the period or slip all of it. Each curve gets solutions at the same
//! frequencies across the resonance ([`nlrom::hbm::frf::land_at`]) and the output DOFs' first
//! harmonics are compared (the static part of a stuck pair's force keeps its history and is not
//! unique): the AFT's distance to the exact cycle falls with N_t and is small at N_t = 4096.

use std::f64::consts::PI;
use std::path::PathBuf;
use std::time::Instant;

use nlrom::case::Case;
use nlrom::hbm::frf::{frequency_response, land_at};
use nlrom::hbm::ResponseOptions;
use nlrom::interface::build_interfaces;
use nlrom::mesh::Mesh;
use nlrom::model;
use nlrom::problem::sector::SectorProblem;
use nlrom::problem::settings::case_continuation;
use nlrom::reduction::reduce;
use nlrom::rom::Rom;

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// The demo sector with normal contact stiffness, evaluated by `evaluation` with N_t samples.
fn case(evaluation: &str, samples: usize) -> Case {
    let text = format!(
        r#"
[model]
mesh = "../meshes/sector8.msh"
material = {{ young = 210e9, poisson = 0.3, density = 7800.0 }}
clamp = ["hub"]
damping = {{ modal = 0.005 }}

[cyclic]
sectors = 8
low = "left_frontier"
high = "right_frontier"

[reduction]
interface_modes = 20
keep = ["excitation"]

[[contact]]
name = "shroud"
contact = "shroud_contact"
target = "shroud_target"
model = "node-to-node"
mu = 0.3
kt = 1.0e8
kn = 0.0
n0 = 100.0
evaluation = "{evaluation}"

[excitation]
engine_order = 3
group = "excitation"
force = [0.0, 0.0, 1.0]

[harmonic_balance]
harmonics = 1
time_samples = {samples}

[continuation]
start_hz = 160.0
end_hz = 170.0
step_hz = 1.0
max_step_hz = 2.0
"#
    );
    Case::from_str(&text, &root().join("cases/test_analytic_solve.toml")).unwrap()
}

/// The frequencies (Hz) the curves are compared at, across the resonance.
const COMPARE_HZ: [f64; 6] = [161.0, 163.0, 164.0, 165.0, 166.0, 168.0];

/// Traces the case's curve on the shared ROM and returns the output DOFs' first harmonics at
/// [`COMPARE_HZ`] (one crossing each), the largest slip and separation fractions of the period
/// over the pairs at those points, and the seconds taken.
fn solved(case: &Case, rom: &Rom, mesh: &Mesh) -> (Vec<Vec<f64>>, [f64; 2], f64) {
    let t = Instant::now();
    let interfaces = build_interfaces(case, mesh, rom.cyclic.as_ref()).unwrap();
    let problem = SectorProblem::build(case, rom, mesh, &interfaces).unwrap();
    let system = problem.system().unwrap();
    let opts = case_continuation(case).unwrap();
    let response = ResponseOptions::default();
    let mut frf = frequency_response(&system, &opts, &response, &mut |_| {}).unwrap();
    let omegas: Vec<f64> = COMPARE_HZ.iter().map(|f| 2.0 * PI * f).collect();
    let landed = land_at(&system, &mut frf, &omegas, &opts.newton, &response).unwrap();
    assert!(landed.failed.is_empty(), "{:?}", landed.failed);
    let mut fractions = [0.0f64; 2];
    let mut q = Vec::new();
    for (at, f) in landed.points.iter().zip(COMPARE_HZ) {
        assert_eq!(at.len(), 1, "{f} Hz crossed {} times", at.len());
        let p = &frf.points[at[0]];
        let reports = problem
            .contact
            .inner
            .reports(&problem.layout, &p.q, &p.state, false)
            .unwrap();
        for (r, _) in reports {
            fractions[0] = fractions[0].max(r.slip);
            fractions[1] = fractions[1].max(r.separation);
        }
        // the first harmonic of the output DOFs (re, im): in complete stick the static part of
        // a pair's force keeps its history (non-unique), the first harmonic does not
        q.push(
            p.response
                .harmonics
                .iter()
                .flat_map(|h| [h[1].re, h[1].im])
                .collect(),
        );
    }
    (q, fractions, t.elapsed().as_secs_f64())
}

/// max over the compared frequencies of ‖q − q_ref‖ / ‖q_ref‖.
fn distance(q: &[Vec<f64>], reference: &[Vec<f64>]) -> f64 {
    let norm = |v: &[f64]| v.iter().map(|x| x * x).sum::<f64>().sqrt();
    q.iter()
        .zip(reference)
        .map(|(a, b)| {
            let d: Vec<f64> = a.iter().zip(b).map(|(x, y)| x - y).collect();
            norm(&d) / norm(b)
        })
        .fold(0.0, f64::max)
}

/// The exact-cycle curve against the AFT at N_t = 256 and 4096: within 1e-6 at 4096 (measured
/// 4.8e-8), and the distance falls by at least 16× over the 16× in N_t (measured 190×: 9.2e-6
/// at 256); pairs slip at the compared points.
#[test]
fn analytic_contact_solve_is_the_aft_limit() {
    let reference_case = case("analytic", 32);
    let model = model::build(&reference_case, &mut |_| {}).unwrap();
    let rom = reduce(&reference_case, &model, &mut |_| {}).unwrap();
    let mesh = model.mesh.as_ref().unwrap();
    let (exact, fractions, t_exact) = solved(&reference_case, &rom, mesh);
    eprintln!("largest slip and separation fractions: {fractions:?}");
    let mut distances = Vec::new();
    for nt in [256, 4096] {
        let (aft, _, t_aft) = solved(&case("aft", nt), &rom, mesh);
        let d = distance(&aft, &exact);
        eprintln!(
            "N_t = {nt}: max relative distance to the exact cycle {d:.3e} ({t_aft:.2} s; exact {t_exact:.2} s)"
        );
        distances.push(d);
    }
    assert!(fractions[0] > 0.0, "no pair slips");
    assert!(distances[1] < 1e-6, "{distances:?}");
    assert!(distances[0] > 16.0 * distances[1], "{distances:?}");
}
