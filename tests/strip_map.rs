//! Stick–slip–separation maps of a `[[strip]]` (`/contact/<name>/map/<i>`, Cigeroglu, An & Menq
//! 2007, §2.3) on the single-mode bar of the paper's §4.1 (its comparison with Cigeroglu, Lu &
//! Menq 2006; check C6 of the method notes): one modal coordinate q of a bar with a spring β at
//! x = 0 (free modes φ_n ∝ cos λ_n(L − x), λL tan λL = βL/EA), a friction strip along the bar
//! whose tangential weights are φ₁(x), no normal motion, solved by the harmonic balance at H = 1
//! through its resonance. With u(x, τ) = φ₁(x) A cos(τ + ψ) every point sees the Jenkins cycle
//! with n̄0(x) = μ q(x)/(k_u A φ₁(x)), which gives, independently of the evaluator:
//! * every slipping point switches slip → stick at the same instants, where u is extremal
//!   (τ = −ψ and π − ψ);
//! * stick → negative slip at τ = −ψ + arccos(1 − 2 n̄0(x)) (the paper's n̄0 = (1 − sin θ)/2 with
//!   θ = τ + ψ + π/2), and stick → positive slip half a period later;
//! * points with n̄0 ≥ 1 stick throughout.
//!
//! The map read back from the results file is checked against these angles, the boundary of the
//! negative-slip zone at every phase angle against the closed-form front position (within one
//! integration point), and the front's direction against the paper's Figs 4 and 5: from the
//! loaded end x = L for a constant load, from inside (right of centre) for a U-shaped load.
//! `tools/post/plot_map.py` reads the file with h5py, finds every stored sample consistent with the
//! stored transitions and draws the map.

mod support;

use std::f64::consts::{PI, TAU};
use std::path::Path;

use nlrom::case::Case;
use nlrom::commands::progress::Reporter;
use nlrom::commands::solve::{solve_case, SolveOptions};
use nlrom::output::{read_results, write_results, ContactMap};
use nlrom::problem::rom_store::RomPolicy;

/// λL of the first free mode for κ = βL/EA = 4 (λL tan λL = κ).
fn lambda_l() -> f64 {
    let (mut lo, mut hi) = (0.1, PI / 2.0 - 1e-12);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if mid * mid.tan() < 4.0 {
            lo = mid
        } else {
            hi = mid
        }
    }
    0.5 * (lo + hi)
}

/// φ₁(x) on [0, 1] (L = 1), 1 at the loaded end.
fn phi(x: f64) -> f64 {
    (lambda_l() * (1.0 - x)).cos()
}

/// φ₁ as the strip sees it: interpolated linearly between the stations (`[[strip]]`).
fn phi_strip(x: f64) -> f64 {
    let h = 1.0 / (STATIONS - 1) as f64;
    let j = ((x / h).floor() as usize).min(STATIONS - 2);
    let eta = x / h - j as f64;
    (1.0 - eta) * phi(j as f64 * h) + eta * phi((j + 1) as f64 * h)
}

const KU: f64 = 10.0;
const MU: f64 = 0.3;
const STATIONS: usize = 101;

/// A one-mode modal case (K = ω₁², M = 1, 2 % modal damping, ω₁ = 2π rad/s) with a strip of
/// 100 segments × 2 Gauss points, a map of 720 angles, `evaluation` and `extra` strip keys.
fn case(
    dir: &Path,
    force: f64,
    extra: &str,
    harmonics: usize,
    evaluation: &str,
) -> nlrom::error::Result<Case> {
    std::fs::write(
        dir.join("K.mtx"),
        format!(
            "%%MatrixMarket matrix coordinate real symmetric\n1 1 1\n1 1 {:e}\n",
            TAU * TAU
        ),
    )
    .unwrap();
    std::fs::write(
        dir.join("M.mtx"),
        "%%MatrixMarket matrix coordinate real symmetric\n1 1 1\n1 1 1\n",
    )
    .unwrap();
    let xs: Vec<f64> = (0..STATIONS)
        .map(|j| j as f64 / (STATIONS - 1) as f64)
        .collect();
    let list = |v: Vec<String>| format!("[{}]", v.join(", "));
    let stations = list(xs.iter().map(|x| format!("{x:e}")).collect());
    let rows = list(xs.iter().map(|&x| format!("[{:e}]", phi(x))).collect());
    let text = format!(
        r#"
[model]
stiffness = "K.mtx"
mass = "M.mtx"
damping = {{ modal = 0.02 }}

[excitation]
dofs = [0]
force = [{force}]

[[strip]]
name = "bar"
dofs = [0]
stations = {stations}
tangential = {rows}
kt = {KU}
mu = {MU}
preload = 1.0
evaluation = "{evaluation}"
map = 720
{extra}

[harmonic_balance]
harmonics = {harmonics}

[continuation]
start_hz = 0.8
end_hz = 1.3
step_hz = 0.01
"#
    );
    Case::from_str(&text, &dir.join("bar.toml"))
}

/// Solves the case, writes and reads back the results file, and returns the map with the first
/// harmonic (Re Q1, Im Q1) of the modal coordinate at the map's point.
fn solved_map(dir: &Path, force: f64, extra: &str) -> (ContactMap, f64, f64, Case) {
    let case = case(dir, force, extra, 1, "analytic").unwrap();
    let out = solve_case(
        &case,
        &SolveOptions::new(RomPolicy::ReadIfMatching),
        &Reporter::silent(),
    )
    .unwrap();
    let path = dir.join("bar.h5");
    write_results(&path, &out.results).unwrap();
    let back = read_results(&path).unwrap();
    assert_eq!(back.maps, out.results.maps, "the map reads back as written");
    assert_eq!(back.maps.len(), 1);
    let map = back.maps[0].clone();
    assert_eq!((map.name.as_str(), map.curve), ("bar", 0));
    let point = &back.frfs[0].points[map.point];
    assert_eq!(point.omega, map.omega);
    // harmonics[r * (H + 1) + n]: the first harmonic of row 0.
    let q1 = point.harmonics[1];
    (map, q1.re, q1.im, case)
}

/// Circular distance of two angles.
fn apart(a: f64, b: f64) -> f64 {
    let d = (a - b).rem_euclid(TAU);
    d.min(TAU - d)
}

/// Checks the map against the Jenkins closed form of every point (see the module documentation)
/// and returns, per point, n̄0.
fn check_against_closed_form(
    map: &ContactMap,
    re: f64,
    im: f64,
    shape: &dyn Fn(f64) -> f64,
) -> Vec<f64> {
    let (amp, psi) = ((re * re + im * im).sqrt(), im.atan2(re));
    let e = map.position.len();
    let n = map.phase.len();
    assert_eq!((e, n), (2 * (STATIONS - 1), 720));
    // n̄0 = μ q(x)/(k_u A φ(x)) with q normalised to the total preload 1 over [0, 1].
    // (the strip normalises by its own 2-point Gauss rule: weights h/2 at the map's positions)
    let h = 1.0 / (STATIONS - 1) as f64;
    let total: f64 = map.position.iter().map(|&x| 0.5 * h * shape(x)).sum();
    let nbar: Vec<f64> = map
        .position
        .iter()
        .map(|&x| MU * shape(x) / total / (KU * amp * phi_strip(x)))
        .collect();
    let (mut slipping, mut stuck) = (0, 0);
    for (p, &nb) in nbar.iter().enumerate() {
        let lo = map.transition_offsets[p] as usize;
        let hi = map.transition_offsets[p + 1] as usize;
        let got: Vec<(f64, i64)> = (lo..hi)
            .map(|k| (map.transition_angles[k], map.transition_states[k]))
            .collect();
        let row = &map.state[p * n..(p + 1) * n];
        if nb >= 1.0 + 1e-6 {
            stuck += 1;
            assert!(
                got.is_empty(),
                "point {p} (n̄0 = {nb}) should stick: {got:?}"
            );
            assert!(row.iter().all(|&s| s == 0), "point {p} sticks");
            continue;
        }
        if nb > 1.0 - 1e-6 {
            continue; // at the slip limit within rounding: either is right
        }
        slipping += 1;
        let onset = (1.0 - 2.0 * nb).acos();
        let want = [
            (-psi, 0),
            (-psi + onset, -1),
            (PI - psi, 0),
            (PI - psi + onset, 1),
        ];
        assert_eq!(got.len(), 4, "point {p} (n̄0 = {nb}): {got:?}");
        for (tw, cw) in want {
            assert!(
                got.iter().any(|&(t, c)| c == cw && apart(t, tw) < 1e-9),
                "point {p} (n̄0 = {nb}): {got:?} lacks ({tw}, {cw})"
            );
        }
        // Every sample away from the transitions is in the state of the closed form, and in
        // stick f/(μn) = 1 − (1 − cos ϑ)/n̄0 after positive slip (ϑ = τ + ψ).
        for (j, &t) in map.phase.iter().enumerate() {
            let th = (t + psi).rem_euclid(TAU);
            if want.iter().any(|&(tw, _)| apart(t, tw) < 1e-6) {
                continue;
            }
            let (state, ratio) = if th < onset {
                (0, 1.0 - (1.0 - th.cos()) / nb)
            } else if th < PI {
                (-1, -1.0)
            } else if th < PI + onset {
                (0, -1.0 + (1.0 + th.cos()) / nb)
            } else {
                (1, 1.0)
            };
            assert_eq!(row[j], state, "point {p}, τ = {t}");
            let r = map.friction_ratio[p * n + j];
            assert!(
                (r - ratio).abs() < 1e-8,
                "point {p}, τ = {t}: f/(μn) {r} vs {ratio}"
            );
        }
    }
    eprintln!("{slipping} slipping and {stuck} stuck points of {e}; A = {amp:.6e}");
    assert!(
        slipping >= e / 5 && stuck >= e / 5,
        "partial slip: {slipping} slipping, {stuck} stuck"
    );
    nbar
}

/// At every phase angle of the negative-slip half cycle, the negative-slip zone of the map is
/// {x : n̄0(x) < (1 − cos ϑ)/2}; its boundary (the last point before the front) is within one
/// integration point of the closed-form front found by bisection on n̄0 as a function of x.
/// Returns the largest boundary error in integration points.
fn check_front(map: &ContactMap, re: f64, im: f64, nbar: &[f64]) -> usize {
    let psi = im.atan2(re);
    let n = map.phase.len();
    let e = map.position.len();
    let mut worst = 0;
    for (j, &t) in map.phase.iter().enumerate() {
        let th = (t + psi).rem_euclid(TAU);
        if th <= 1e-3 || th >= PI - 1e-3 {
            continue;
        }
        let level = 0.5 * (1.0 - th.cos());
        let slipping: Vec<usize> = (0..e).filter(|&p| map.state[p * n + j] == -1).collect();
        let closed: Vec<usize> = (0..e).filter(|&p| nbar[p] < level).collect();
        // The two sets differ only at points whose n̄0 is within rounding of the level.
        let differ = slipping
            .iter()
            .filter(|p| !closed.contains(p))
            .chain(closed.iter().filter(|p| !slipping.contains(p)))
            .count();
        worst = worst.max(differ);
    }
    eprintln!("negative-slip zone off the closed form by at most {worst} integration points");
    worst
}

/// Constant load: the closed-form angles at every point, the front within one integration point
/// at every phase angle, and slip starting at the loaded end x = L and moving left (Fig. 4).
#[test]
fn constant_load_map_matches_the_single_mode_closed_form() {
    let dir = tempfile::tempdir().unwrap();
    let (map, re, im, _) = solved_map(dir.path(), 0.06, "");
    let nbar = check_against_closed_form(&map, re, im, &|_| 1.0);
    let worst = check_front(&map, re, im, &nbar);
    assert!(worst <= 1, "front off by {worst} integration points");
    // The slip onset angle ϑ_N = arccos(1 − 2n̄0) decreases towards x = L: the last point slips
    // first and the front moves left.
    let onset = |p: usize| {
        let lo = map.transition_offsets[p] as usize;
        let hi = map.transition_offsets[p + 1] as usize;
        (lo..hi)
            .find(|&k| map.transition_states[k] == -1)
            .map(|k| (map.transition_angles[k] + im.atan2(re)).rem_euclid(TAU))
    };
    let e = map.position.len();
    let order: Vec<f64> = (0..e).filter_map(onset).collect();
    assert!(
        order.windows(2).all(|w| w[1] <= w[0] + 1e-12),
        "onset not decreasing in x"
    );
    assert!(onset(e - 1).is_some() && onset(0).is_none());
    // The plotting tool (h5py only) finds the samples and transitions of the file consistent.
    let out = support::python::run_python(
        "import sys, runpy; sys.argv = ['plot_map.py'] + sys.argv[1:]; \
         runpy.run_path('tools/post/plot_map.py', run_name='__main__')",
        &[&dir.path().join("bar.h5"), Path::new("--out"), dir.path()],
    );
    let report: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(report["points"], 200, "{report}");
    assert_eq!(report["angles"], 720, "{report}");
    assert_eq!(report["disagreeing_samples"], 0, "{report}");
    assert!(report["transitions"].as_u64().unwrap() > 200, "{report}");
    assert!(dir.path().join("map_bar_0.png").exists());
}

/// U-shaped load q ∝ 1 + (2x − 1)²: slip starts inside, right of the centre, and reaches the
/// loaded end x = L before x = 0 (Fig. 5); the same closed-form checks.
#[test]
fn u_shaped_load_map_slips_first_right_of_centre() {
    let dir = tempfile::tempdir().unwrap();
    let extra = "distribution = \"quadratic\"\nc = 1.0";
    let (map, re, im, _) = solved_map(dir.path(), 0.06, extra);
    let shape = |x: f64| 1.0 + (2.0 * x - 1.0).powi(2);
    let nbar = check_against_closed_form(&map, re, im, &shape);
    assert!(check_front(&map, re, im, &nbar) <= 1);
    let first = (0..nbar.len())
        .min_by(|&a, &b| nbar[a].total_cmp(&nbar[b]))
        .unwrap();
    let x = map.position[first];
    assert!(x > 0.5 && x < 0.9, "first slip at x = {x}");
    assert!(nbar[nbar.len() - 1] < nbar[0], "x = L slips before x = 0");
    // The first point to slip is the one with the earliest negative-slip onset in the map.
    let psi = im.atan2(re);
    let n = map.phase.len();
    let j_first = (0..n)
        .find(|&j| {
            let th = (map.phase[j] + psi).rem_euclid(TAU);
            th < PI && (0..nbar.len()).any(|p| map.state[p * n + j] == -1)
        })
        .unwrap();
    let who: Vec<f64> = (0..nbar.len())
        .filter(|&p| map.state[p * n + j_first] == -1)
        .map(|p| map.position[p])
        .collect();
    assert!(
        who.iter().all(|&s| s > 0.5 && s < 0.9),
        "first slipping points {who:?}"
    );
}

/// A map needs the exact single-harmonic cycle: with H > 1 the case is refused, naming the key.
#[test]
fn map_with_more_than_one_harmonic_is_a_keyed_error() {
    let dir = tempfile::tempdir().unwrap();
    let e = case(dir.path(), 0.06, "", 3, "aft")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("strip[0].map") && e.contains("harmonics = 1") && e.contains("bar.toml"),
        "{e}"
    );
    // the exact cycle itself takes any H; the map still needs H = 1
    let e = case(dir.path(), 0.06, "", 3, "analytic")
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("strip[0].map") && e.contains("harmonics = 1"),
        "{e}"
    );
    case(dir.path(), 0.06, "", 1, "aft").unwrap();
}

/// First-harmonic force F₁ of a Jenkins point (stiffness k, slip force f_s) under
/// u = Re(U e^{iτ}), in the same layout: stuck below k|U| = f_s, else, with θ = τ + arg U and
/// cos β = 1 − 2f_s/(k|U|) (stick on [0, β] from f = f_s, negative slip on [β, π], half-wave
/// symmetric), a₁ = (2/π)[(f_s − k|U|) sin β + k|U|(β/2 + sin 2β/4) + f_s sin β] and
/// b₁ = (2/π)[(f_s − k|U|)(1 − cos β) + k|U| sin²β/2 − f_s(1 + cos β)] of
/// f = a₁ cos θ + b₁ sin θ, so F₁ = (a₁ − i b₁) e^{i arg U}.
fn jenkins_first_harmonic(k: f64, fs: f64, u: (f64, f64)) -> (f64, f64) {
    let a = u.0.hypot(u.1);
    if k * a <= fs {
        return (k * u.0, k * u.1);
    }
    let beta = (1.0 - 2.0 * fs / (k * a)).acos();
    let (s, c) = beta.sin_cos();
    let a1 =
        2.0 / PI * ((fs - k * a) * s + k * a * (beta / 2.0 + (2.0 * beta).sin() / 4.0) + fs * s);
    let b1 = 2.0 / PI * ((fs - k * a) * (1.0 - c) + k * a * s * s / 2.0 - fs * (1.0 + c));
    // (a₁ − i b₁) U / |U|
    ((a1 * u.0 + b1 * u.1) / a, (a1 * u.1 - b1 * u.0) / a)
}

/// `map_hz`: maps at chosen frequencies instead of the resonance peak. The curve gets a point at
/// exactly each frequency it crosses, which is an H = 1 solution there (the modal equation
/// (ω₁² − ω² + 2iζω₁ω) Q₁ + Σ_p φ_p F₁,p = F with each point's Jenkins force in closed form),
/// and each map has the closed-form transition angles of every point at that point's Q₁; a
/// frequency the curve does not reach gives no map.
#[test]
fn maps_at_chosen_frequencies_match_the_closed_form() {
    let dir = tempfile::tempdir().unwrap();
    let hz = [1.08, 1.065, 2.0];
    let extra = "map_hz = [1.08, 1.065, 2.0]";
    let case = case(dir.path(), 0.06, extra, 1, "analytic").unwrap();
    let out = solve_case(
        &case,
        &SolveOptions::new(RomPolicy::ReadIfMatching),
        &Reporter::silent(),
    )
    .unwrap();
    let path = dir.path().join("bar.h5");
    write_results(&path, &out.results).unwrap();
    let back = read_results(&path).unwrap();
    assert_eq!(back.maps, out.results.maps, "the maps read back as written");
    // one crossing each of 1.065 and 1.08 Hz (either side of the peak at 1.074 Hz), in path
    // order; none of 2 Hz; no peak map
    let got: Vec<f64> = back.maps.iter().map(|m| m.omega / TAU).collect();
    assert_eq!(back.maps.len(), 2, "{got:?}");
    assert_eq!(back.maps[0].omega, TAU * hz[1]);
    assert_eq!(back.maps[1].omega, TAU * hz[0]);
    let points = &back.frfs[0].points;
    let h = 1.0 / (STATIONS - 1) as f64;
    for map in &back.maps {
        assert_eq!((map.name.as_str(), map.curve), ("bar", 0));
        let p = &points[map.point];
        assert_eq!(
            p.omega, map.omega,
            "the map's point is at the chosen frequency"
        );
        let (re, im) = (p.harmonics[1].re, p.harmonics[1].im);
        // the added point solves the harmonic balance: residual of the modal equation with the
        // closed-form Jenkins force of every integration point (2-point Gauss, weight h/2)
        let w = p.omega;
        let (k1, c1) = (TAU * TAU, 2.0 * 0.02 * TAU);
        let mut r = (
            (k1 - w * w) * re - c1 * w * im,
            (k1 - w * w) * im + c1 * w * re,
        );
        for &x in &map.position {
            let ph = phi_strip(x);
            let (fr, fi) =
                jenkins_first_harmonic(KU * h / 2.0, MU * 1.0 * h / 2.0, (ph * re, ph * im));
            r.0 += ph * fr;
            r.1 += ph * fi;
        }
        r.0 -= 0.06;
        let rel = r.0.hypot(r.1) / 0.06;
        eprintln!(
            "map at {} Hz: modal residual {rel:.3e} of the force",
            w / TAU
        );
        assert!(rel < 1e-6, "residual {rel:e} at {} Hz", w / TAU);
        // the neighbours are traced points at other frequencies on either side
        let (a, b) = (&points[map.point - 1], &points[map.point + 1]);
        assert!((a.omega - w) * (b.omega - w) < 0.0);
        let nbar = check_against_closed_form(map, re, im, &|_| 1.0);
        assert!(check_front(map, re, im, &nbar) <= 1);
    }
    // the plotting tool reads the second map
    let out = support::python::run_python(
        "import sys, runpy; sys.argv = ['plot_map.py'] + sys.argv[1:]; \
         runpy.run_path('tools/post/plot_map.py', run_name='__main__')",
        &[
            &path,
            Path::new("--map"),
            Path::new("1"),
            Path::new("--out"),
            dir.path(),
        ],
    );
    let report: serde_json::Value = serde_json::from_str(out.trim()).unwrap();
    assert_eq!(report["disagreeing_samples"], 0, "{report}");
    assert!(dir.path().join("map_bar_1.png").exists());
}

/// `map_hz` without `map`, or a frequency ≤ 0, is refused naming the key.
#[test]
fn map_frequencies_are_checked() {
    let dir = tempfile::tempdir().unwrap();
    let text = |extra: &str| {
        case(dir.path(), 0.06, extra, 1, "analytic")
            .unwrap_err()
            .to_string()
    };
    let e = text("map_hz = [1.0, -2.0]");
    assert!(e.contains("strip[0].map_hz[1]") && e.contains("-2"), "{e}");
    let e = text("map_hz = []");
    assert!(e.contains("strip[0].map_hz"), "{e}");
}
