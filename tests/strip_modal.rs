//! A `[[strip]]` with an initial gap on a modal model against the full model it was reduced
//! from. Two fixed–free spring chains of N unit masses (node j at s = j/N, j = 1..N, springs k),
//! one moving tangentially (u) and one normally (v, v > 0 closes the contact), are in contact
//! with rigid ground along a strip through their nodes: friction k_u, μ and normal stiffness
//! k_v per length with a uniform initial gap g₀ (total preload −k_v g₀ ∫ds), driven at the free
//! ends through the first resonance at H = 1 with the exact cycle.
//!
//! The full model reads the nodes' rows (weights 1 at the station's node); the modal model has
//! all 2N modes of the chains in closed form (φ_r(j) = 2/√(2N+1) sin((2r − 1)πj/(2N+1)),
//! ω_r = 2√k sin((2r − 1)π/(2(2N+1)))), reads the modal coordinates with the mode-shape values
//! at the stations as weights, and is excited by the modal forces φ_r(N)·F. With all modes the
//! two are the same system in other coordinates, and 2 % modal damping is the same damping in
//! both. At frequencies where each curve gets a solution (`map_hz`), the free-end response
//! recovered from the modal coordinates equals the full model's, and so do the
//! stick–slip–separation maps of the strip, with separation, stick and both slips present.

mod support;

use std::f64::consts::{PI, TAU};
use std::path::Path;

use nlrom::case::Case;
use nlrom::commands::progress::Reporter;
use nlrom::commands::solve::{solve_case, SolveOptions};
use nlrom::output::{ContactMap, ResultsFile};
use nlrom::problem::rom_store::RomPolicy;
use support::chain::{self, list, spring_for, stiffness, write_mtx};

/// Nodes per chain.
const N: usize = 10;
const KT: f64 = 200.0;
const KN: f64 = 200.0;
const MU: f64 = 0.3;
const GAP: f64 = 3e-3;
const FORCE: f64 = 0.1;
const MAP_HZ: [f64; 2] = [1.0, 1.061];

/// The chains' spring stiffness k, so that ω₁ = 2π rad/s.
fn spring() -> f64 {
    spring_for(N, TAU)
}

/// Mass-normalised mode r ≥ 1 of a chain at node j ∈ 1..=N.
fn mode(r: usize, j: usize) -> f64 {
    chain::mode(N, r, j)
}

/// The case text of the full model (`modal` false) or the modal model.
/// The case on the full model (`modal` false) or the modal one; `modes`: the full model solved
/// on the modal coordinates of its lowest modes (`[harmonic_balance] modes`).
fn case(dir: &Path, modal: bool, modes: Option<usize>) -> Case {
    let n2 = 2 * N;
    let mut k = Vec::new();
    let mut m = Vec::new();
    if modal {
        for c in 0..2 {
            for r in 1..=N {
                k.push((c * N + r - 1, c * N + r - 1, chain::omega2(N, spring(), r)));
            }
        }
    } else {
        for c in 0..2 {
            k.extend(stiffness(N, spring(), c * N));
        }
    }
    for i in 0..n2 {
        m.push((i, i, 1.0));
    }
    write_mtx(&dir.join("K.mtx"), n2, &k);
    write_mtx(&dir.join("M.mtx"), n2, &m);
    let dofs = list((0..n2).map(|i| i.to_string()));
    // weights of station j (node j) on the 2N rows, for chain c (0 tangential, 1 normal)
    let weights = |c: usize| {
        list((1..=N).map(|j| {
            list((0..n2).map(|i| {
                let w = if i / N != c {
                    0.0
                } else if modal {
                    mode(i % N + 1, j)
                } else if i % N + 1 == j {
                    1.0
                } else {
                    0.0
                };
                format!("{w:e}")
            }))
        }))
    };
    let (excited, forces, response) = if modal {
        let f = (0..n2).map(|i| format!("{:e}", FORCE * mode(i % N + 1, N)));
        (dofs.clone(), list(f), dofs.clone())
    } else {
        let tips = format!("[{}, {}]", N - 1, n2 - 1);
        (tips.clone(), format!("[{FORCE}, {FORCE}]"), tips)
    };
    let stations = list((1..=N).map(|j| format!("{:e}", j as f64 / N as f64)));
    let length = 1.0 - 1.0 / N as f64;
    let text = format!(
        r#"
[model]
stiffness = "K.mtx"
mass = "M.mtx"
damping = {{ modal = 0.02 }}

[excitation]
dofs = {excited}
force = {forces}

[response]
dofs = {response}

[[strip]]
name = "ground"
dofs = {dofs}
stations = {stations}
tangential = {tangential}
normal = {normal}
kt = {KT}
kn = {KN}
mu = {MU}
preload = {preload:e}
evaluation = "analytic"
map = 360
map_hz = {map_hz}

[harmonic_balance]
harmonics = 1
{modes}

[continuation]
start_hz = 0.8
end_hz = 1.4
step_hz = 0.01
"#,
        tangential = weights(0),
        normal = weights(1),
        preload = -KN * GAP * length,
        map_hz = list(MAP_HZ.iter().map(|f| f.to_string())),
        modes = modes.map_or(String::new(), |m| format!("modes = {m}")),
    );
    Case::from_str(
        &text,
        &dir.join(if modal { "modal.toml" } else { "full.toml" }),
    )
    .unwrap()
}

fn solve(dir: &Path, modal: bool, modes: Option<usize>) -> ResultsFile {
    let case = case(dir, modal, modes);
    solve_case(
        &case,
        &SolveOptions::new(RomPolicy::ReadIfMatching),
        &Reporter::silent(),
    )
    .unwrap()
    .results
}

/// The first harmonics (re, im) of the free ends (u, v) at point `p` of the only curve.
fn tips(r: &ResultsFile, p: usize, modal: bool) -> [(f64, f64); 2] {
    let h = &r.frfs[0].points[p].harmonics;
    // harmonics[row * (H + 1) + n], H = 1
    let first = |row: usize| (h[2 * row + 1].re, h[2 * row + 1].im);
    if !modal {
        return [first(0), first(1)];
    }
    let mut out = [(0.0, 0.0); 2];
    for (c, o) in out.iter_mut().enumerate() {
        for r in 1..=N {
            let (re, im) = first(c * N + r - 1);
            o.0 += mode(r, N) * re;
            o.1 += mode(r, N) * im;
        }
    }
    out
}

/// Samples of two maps in different states, away from every transition of either (1e-6 rad),
/// and the largest difference of matching transition angles (rad).
fn compare_maps(a: &ContactMap, b: &ContactMap) -> (usize, f64) {
    assert_eq!(a.position, b.position);
    assert_eq!(a.phase.len(), b.phase.len());
    assert_eq!(a.transition_offsets, b.transition_offsets);
    assert_eq!(a.transition_states, b.transition_states);
    let n = a.phase.len();
    let apart = |x: f64, y: f64| {
        let d = (x - y).rem_euclid(TAU);
        d.min(TAU - d)
    };
    let angle = a
        .transition_angles
        .iter()
        .zip(&b.transition_angles)
        .map(|(&x, &y)| apart(x, y))
        .fold(0.0, f64::max);
    let mut differ = 0;
    for e in 0..a.position.len() {
        let (lo, hi) = (
            a.transition_offsets[e] as usize,
            a.transition_offsets[e + 1] as usize,
        );
        for j in 0..n {
            let near = a.transition_angles[lo..hi]
                .iter()
                .chain(&b.transition_angles[lo..hi])
                .any(|&t| apart(t, a.phase[j]) < 1e-6);
            if !near && a.state[e * n + j] != b.state[e * n + j] {
                differ += 1;
            }
        }
    }
    (differ, angle)
}

/// At each map of `a` and `b` (the same frequencies): the free ends' amplitude in `a`, the
/// largest difference of `b`'s free ends from it (`modal`: `b` on the closed-form modal model),
/// and [`compare_maps`] of the two maps.
fn differences(a: &ResultsFile, b: &ResultsFile, modal: bool) -> Vec<(f64, f64, usize, f64)> {
    assert_eq!(a.maps.len(), b.maps.len());
    a.maps
        .iter()
        .zip(&b.maps)
        .map(|(ma, mb)| {
            assert_eq!(ma.omega, mb.omega);
            let (ta, tb) = (tips(a, ma.point, false), tips(b, mb.point, modal));
            let amp = ta.iter().map(|t| t.0.hypot(t.1)).fold(0.0, f64::max);
            let off = ta
                .iter()
                .zip(&tb)
                .map(|(x, y)| (x.0 - y.0).hypot(x.1 - y.1))
                .fold(0.0, f64::max);
            let (differ, angle) = compare_maps(ma, mb);
            (amp, off, differ, angle)
        })
        .collect()
}

/// With all modes, the modal model's strip with an initial gap gives the full model's response
/// (1e-6 of the amplitude; measured ≤ 3.8e-13) and maps (no sample off, transition angles within
/// 1e-6 rad; measured ≤ 7.1e-13) at the chosen frequencies, on each of the three branches inside
/// a fold, and the maps show separation next to stick and slip.
#[test]
fn modal_strip_with_a_gap_equals_the_full_model() {
    let dir = tempfile::tempdir().unwrap();
    let full = solve(dir.path(), false, None);
    let modal = solve(dir.path(), true, None);
    // one crossing of 1 Hz, three of 1.061 Hz (inside the fold of the normal chain's hardening
    // resonance: large, middle and small amplitude in path order)
    let at: Vec<f64> = full.maps.iter().map(|m| m.omega).collect();
    assert_eq!(at, [1.0, 1.061, 1.061, 1.061].map(|f| 2.0 * PI * f));
    let found = differences(&full, &modal, true);
    for (a, (amp, off, differ, angle)) in full.maps.iter().zip(found) {
        let count = |code: i64| a.state.iter().filter(|&&s| s == code).count();
        eprintln!(
            "{} Hz: free-end amplitude {amp:.4e}, modal − full {:.2e} of it; maps: {differ} samples differ, angles within {angle:.2e} rad; samples stick {} slip- {} slip+ {} separated {}",
            a.omega / TAU,
            off / amp,
            count(0),
            count(-1),
            count(1),
            count(2)
        );
        assert!(off <= 1e-6 * amp, "{off:e} of {amp:e}");
        assert_eq!(differ, 0);
        assert!(angle < 1e-6, "{angle:e}");
        for code in [0, 2] {
            assert!(count(code) > 0, "no sample in state {code}");
        }
        assert!(count(-1) + count(1) > 0, "no slip");
    }
}

/// The full model solved on the modal coordinates of all its 2N modes
/// (`[harmonic_balance] modes`, the modes from its matrices, the maps from the elements' motion
/// Φ_c Q) gives the full model's response (1e-6 of the amplitude) and maps (no sample off,
/// transition angles within 1e-6 rad) at the chosen frequencies.
#[test]
fn the_full_model_on_all_its_modes_gives_its_maps() {
    let dir = tempfile::tempdir().unwrap();
    let full = solve(dir.path(), false, None);
    let on_modes = solve(dir.path(), false, Some(2 * N));
    let found = differences(&full, &on_modes, false);
    for (a, (amp, off, differ, angle)) in full.maps.iter().zip(found) {
        eprintln!(
            "{} Hz: free-end amplitude {amp:.4e}, on modes − full {:.2e} of it; maps: {differ} samples differ, angles within {angle:.2e} rad",
            a.omega / TAU,
            off / amp
        );
        assert!(off <= 1e-6 * amp, "{off:e} of {amp:e}");
        assert_eq!(differ, 0);
        assert!(angle < 1e-6, "{angle:e}");
    }
}
