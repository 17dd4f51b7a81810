//! The harmonic balance of a sector problem at one frequency, as a reference for other methods.

use faer::c64;

use super::cli::root;
use nlrom::harmonics::HarmonicForce;
use nlrom::hbm::{FrequencyPath, HbmSystem};
use nlrom::nonlinear::{solve_fixed, NewtonOptions};
use nlrom::problem::sector::SectorProblem;

/// Harmonic 1 of the output DOFs (m) of the HB solution at ω (rad/s), by Newton from zero
/// (tolerance 1e-10), recovered from the condensed solution (SAMA paper eq 18).
pub fn hb_outputs(problem: &SectorProblem, omega: f64) -> Vec<c64> {
    let system = HbmSystem::new(problem.layout, &problem.linear, &problem.contact).unwrap();
    let path = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let opts = NewtonOptions {
        tolerance: 1e-10,
        ..NewtonOptions::default()
    };
    let x0 = vec![0.0; system.dim()];
    let x = solve_fixed(&path, &x0, omega, &problem.contact.initial_state(), &opts)
        .expect("HB converges")
        .x;
    let nd = problem.linear.n_condensed();
    let q1: Vec<c64> = (0..nd)
        .map(|i| {
            let r = problem.layout.cos_index(1, i, nd);
            c64::new(x[r], x[r + 1])
        })
        .collect();
    problem.linear.condense(1, omega).unwrap().recover(&q1)
}

/// The unit force per excitation node of the sector8 test cases (N, x y z).
pub const FORCE: [f64; 3] = [0.3, -0.2, 1.0];

/// The N = 8 sectors of the sector8 test cases.
const N: usize = 8;

/// The sector8 case: engine order `m`, shroud contact (kt, kn, μ, n0), the excitation `FORCE`
/// times `scale` per node, H harmonics, a march at `hz` with `steps` per period.
pub fn case_text(
    m: usize,
    contact: [f64; 4],
    scale: f64,
    harmonics: usize,
    hz: f64,
    steps: usize,
) -> String {
    let [kt, kn, mu, n0] = contact;
    format!(
        r#"
[model]
mesh = "{mesh}"
material = {{ young = 210e9, poisson = 0.3, density = 7800.0 }}
clamp = ["hub"]
damping = {{ modal = 0.03 }}

[cyclic]
sectors = {N}
low = "left_frontier"
high = "right_frontier"

[reduction]
interface_modes = 10
gsi_modes = 6
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
force = [{f0}, {f1}, {f2}]
force_scale = {scale:e}

[harmonic_balance]
harmonics = {harmonics}
time_samples = 256

[march]
frequency_hz = {hz}
periods = 200
steps_per_period = {steps}
scheme = "piecewise-linear"
time_step_s = {dt:e}
stop_at_steady = true
steady_tolerance = 1e-4
"#,
        mesh = root().join("meshes/sector8.msh").display(),
        f0 = FORCE[0],
        f1 = FORCE[1],
        f2 = FORCE[2],
        dt = 1.0 / (hz * steps as f64),
    )
}

/// max_i |a_i − b_i| / max_i |b_i|.
pub fn rel_err(a: &[c64], b: &[c64]) -> f64 {
    let scale = b.iter().map(|z| z.norm()).fold(0.0, f64::max);
    let diff = a
        .iter()
        .zip(b)
        .map(|(x, y)| (x - y).norm())
        .fold(0.0, f64::max);
    diff / scale
}
