//! The blade-to-ground damper of Cigeroglu, An & Menq (2007, §4.2, Figs 11–15; check C8 of the
//! method notes) on the bundled synthetic blade `cases/blade_ground.toml`: a two-mode modal model
//! (f₁ = 300 Hz, f₂ = 900 Hz, unit modal masses, 0.5 % modal damping) whose platform rubs on rigid
//! ground along a `[[strip]]` s ∈ [0, 1] (20 integration points). The modes move the platform
//! tangentially and normally (weights linear in s: mode 1 slides and lifts, more at s = 1; mode 2
//! rocks), so the normal load varies over the period and the platform can separate. The total
//! preload is swept (`strip.platform.preload`) from initial gaps (negative) to a nearly stuck
//! platform, and each curve is traced at H = 1 with the exact cycle and Hill's stability.
//!
//! The linear limits are independent closed forms: the free blade (no contact) and the stuck one
//! (modal stiffness plus ∫ k_u φ_t φ_tᵀ + k_v φ_n φ_nᵀ ds, exact for weights linear in s), from
//! the constants below, which the first test checks against the bundled case.

use std::f64::consts::{PI, TAU};
use std::path::{Path, PathBuf};

use faer::c64;
use nlrom::case::{Case, Damping, Evaluation, ExcitationLoad};
use nlrom::commands::progress::Reporter;
use nlrom::commands::solve::{solve_case, SolveOptions};
use nlrom::output::{FrfData, ResultsFile};
use nlrom::problem::rom_store::RomPolicy;

const F: [f64; 2] = [300.0, 900.0];
const ZETA: f64 = 0.005;
const KT: f64 = 3.0e6;
const KN: f64 = 3.0e6;
const MU: f64 = 0.3;
const FORCE: [f64; 2] = [1.0, 0.3];
/// Tangential and normal weights of mode r at s: a + b s.
const TANGENTIAL: [[f64; 2]; 2] = [[1.0, 0.0], [0.3, 0.0]];
const NORMAL: [[f64; 2]; 2] = [[0.5, 0.5], [-1.0, 2.0]];
const PRELOADS: [f64; 12] = [
    -100.0, -30.0, 1.0, 3.0, 10.0, 30.0, 100.0, 300.0, 1000.0, 3000.0, 10000.0, 30000.0,
];
/// The map frequency (Hz), inside the softening fold of P = 3.
const MAP_HZ: f64 = 347.0;

fn case_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/blade_ground.toml")
}

fn case() -> Case {
    Case::load(&case_path()).unwrap()
}

/// The bundled case is the model of the closed forms: the modal stiffness and mass matrices, the
/// damping, the force, the strip's stiffness, friction and weights (a + b s at every station, to
/// rounding of the printed decimals), the preload sweep and the map frequency.
#[test]
fn bundled_blade_case_is_the_model_of_the_closed_forms() {
    let case = case();
    let dir = case_path().parent().unwrap().to_path_buf();
    let diagonal = |file: &str| -> Vec<f64> {
        let text = std::fs::read_to_string(dir.join(file)).unwrap();
        let rows: Vec<Vec<f64>> = text
            .lines()
            .filter(|l| !l.starts_with('%'))
            .skip(1)
            .map(|l| l.split_whitespace().map(|x| x.parse().unwrap()).collect())
            .collect();
        assert!(rows.iter().all(|r| r[0] == r[1]), "{file}: diagonal");
        rows.iter().map(|r| r[2]).collect()
    };
    let k = diagonal("blade_ground/K.mtx");
    for (kr, f) in k.iter().zip(F) {
        assert!((kr - (TAU * f).powi(2)).abs() <= 1e-15 * kr, "{kr}");
    }
    assert_eq!(diagonal("blade_ground/M.mtx"), vec![1.0, 1.0]);
    assert_eq!(case.model.damping, Some(Damping::Modal(ZETA)));
    let load = &case.excitation.as_ref().unwrap().load;
    assert_eq!(
        load,
        &ExcitationLoad::Dofs {
            dofs: vec![0, 1],
            force: FORCE.to_vec()
        }
    );
    let strip = &case.strip[0];
    assert_eq!((strip.kt, strip.kn, strip.mu), (KT, KN, MU));
    assert_eq!(strip.dofs, vec![0, 1]);
    assert_eq!(strip.evaluation, Evaluation::Analytic);
    assert_eq!(strip.map_hz, Some(vec![MAP_HZ]));
    assert_eq!(strip.stations.len(), 11);
    let normal = strip.normal.as_ref().unwrap();
    for (j, &s) in strip.stations.iter().enumerate() {
        assert!((s - j as f64 / 10.0).abs() <= 1e-15);
        for r in 0..2 {
            let t = TANGENTIAL[r][0] + TANGENTIAL[r][1] * s;
            let n = NORMAL[r][0] + NORMAL[r][1] * s;
            assert!((strip.tangential[j][r] - t).abs() <= 1e-15, "station {j}");
            assert!((normal[j][r] - n).abs() <= 1e-15, "station {j}");
        }
    }
    assert_eq!(
        case.sweep.get("strip.platform.preload"),
        Some(&PRELOADS.to_vec())
    );
    assert_eq!(case.harmonic_balance.harmonics, 1);
}

/// |Q₁| of mode 1 at every point of a curve, with ω (Hz) and the stability flag.
fn curve(frf: &FrfData) -> Vec<(f64, f64, Option<bool>)> {
    frf.points
        .iter()
        .map(|p| (p.omega / TAU, p.harmonics[1].norm(), p.stable))
        .collect()
}

/// The linear response |Q₁| of mode 1 at f (Hz) with the stuck contact stiffness (`stuck`) or
/// none: (K + K_c − ω² + iωC) Q = F, with ∫₀¹ (a + bs)(c + ds) ds in closed form.
fn linear(f: f64, stuck: bool) -> f64 {
    let w = TAU * f;
    let int = |p: [f64; 2], q: [f64; 2]| {
        p[0] * q[0] + (p[0] * q[1] + p[1] * q[0]) / 2.0 + p[1] * q[1] / 3.0
    };
    let mut a = [[c64::new(0.0, 0.0); 2]; 2];
    for r in 0..2 {
        let wr = TAU * F[r];
        a[r][r] = c64::new(wr * wr - w * w, 2.0 * ZETA * wr * w);
        if stuck {
            for c in 0..2 {
                let kc = KT * int(TANGENTIAL[r], TANGENTIAL[c]) + KN * int(NORMAL[r], NORMAL[c]);
                a[r][c] += c64::new(kc, 0.0);
            }
        }
    }
    let det = a[0][0] * a[1][1] - a[0][1] * a[1][0];
    let q0 = (a[1][1] * FORCE[0] - a[0][1] * FORCE[1]) / det;
    q0.norm()
}

/// The peak (f, |Q₁|) of the linear response on a fine grid.
fn linear_peak(stuck: bool) -> (f64, f64) {
    (0..=30000)
        .map(|i| 250.0 + 0.01 * i as f64)
        .map(|f| (f, linear(f, stuck)))
        .fold((0.0, 0.0), |a, b| if b.1 > a.1 { b } else { a })
}

fn solve() -> ResultsFile {
    let mut opts = SolveOptions::new(RomPolicy::ReadIfMatching);
    opts.stability = true;
    solve_case(&case(), &opts, &Reporter::silent())
        .unwrap()
        .results
}

/// The turning points (f, |Q₁|) of a curve, in path order.
fn turns(c: &[(f64, f64, Option<bool>)]) -> Vec<(f64, f64)> {
    (1..c.len() - 1)
        .filter(|&k| (c[k].0 - c[k - 1].0) * (c[k + 1].0 - c[k].0) < 0.0)
        .map(|k| (c[k].0, c[k].1))
        .collect()
}

/// C8 on the bundled synthetic blade, preload P (N) swept from gaps to a stuck platform:
/// * limits: P = −100 (the gap never closes) is the free linear response and P = 30 000 the
///   stuck one at every point (1e-6);
/// * (i) every curve's peak lies between the linear ones: its frequency between the free and
///   stuck peak frequencies (within the 1 Hz step), its amplitude below the larger linear peak
///   (1e-4: the linear peaks are found on a 0.01 Hz grid; pointwise the hardening
///   branch of a gap does pass the free response beyond its resonance);
/// * (ii) for P > 0 the peak frequency does not decrease with P (within the 1 Hz step) and ends
///   at the stuck peak;
/// * (iii) an interior P minimises the peak: P = 10, 16× below the stuck peak;
/// * (iv) P = 3 (separation, normal load variation): a softening fold (the second turning point
///   of the path lies at a lower frequency and a larger amplitude than the first), with Hill
///   marking points unstable only between the turns;
/// * (v) the gap P = −30: a hardening fold (the first turn at the larger frequency and amplitude);
/// * (vi) maps at 347 Hz, inside the softening fold: the large-amplitude branch is separated over
///   a larger part of the interface and period than the small-amplitude branch (measured 0.48,
///   0.37 on the middle branch and 0.03);
/// * (vii) in those maps some phase angle has stick, slip and separation at once (Fig. 15;
///   measured 31 of 360 angles on the small-amplitude branch).
#[test]
fn blade_preload_sweep_has_the_papers_properties() {
    let results = solve();
    assert_eq!(results.frfs.len(), PRELOADS.len());
    let curves: Vec<_> = results.frfs.iter().map(curve).collect();
    let at = |p: f64| PRELOADS.iter().position(|&x| x == p).unwrap();
    let peak = |c: &[(f64, f64, Option<bool>)]| {
        c.iter()
            .fold((0.0, 0.0), |a, p| if p.1 > a.1 { (p.0, p.1) } else { a })
    };
    let (free, stuck) = (linear_peak(false), linear_peak(true));
    eprintln!("linear peaks: free {free:?}, stuck {stuck:?}");
    for (i, c) in curves.iter().enumerate() {
        let unstable = c.iter().filter(|p| p.2 == Some(false)).count();
        eprintln!(
            "preload {}: {} points, peak {:?}, turns {:?}, {unstable} unstable",
            PRELOADS[i],
            c.len(),
            peak(c),
            turns(c)
        );
    }
    // limits
    for (p, stuck) in [(-100.0, false), (30000.0, true)] {
        for q in &curves[at(p)] {
            let l = linear(q.0, stuck);
            assert!(
                (q.1 - l).abs() <= 1e-6 * l,
                "P = {p} at {} Hz: {} vs {l}",
                q.0,
                q.1
            );
        }
    }
    // (i)
    for (i, c) in curves.iter().enumerate() {
        let (f, a) = peak(c);
        assert!(
            a <= free.1.max(stuck.1) * (1.0 + 1e-4) && f >= free.0 - 1.0 && f <= stuck.0 + 1.0,
            "P = {}: peak {a} at {f} Hz",
            PRELOADS[i]
        );
    }
    // (ii)
    let positive: Vec<(f64, f64)> = (0..PRELOADS.len())
        .filter(|&i| PRELOADS[i] > 0.0)
        .map(|i| peak(&curves[i]))
        .collect();
    assert!(
        positive.windows(2).all(|w| w[1].0 >= w[0].0 - 1.0),
        "{positive:?}"
    );
    assert!((positive[positive.len() - 1].0 - stuck.0).abs() <= 1.0);
    // (iii)
    let best = (0..positive.len())
        .min_by(|&a, &b| positive[a].1.total_cmp(&positive[b].1))
        .unwrap();
    assert!(best > 0 && best + 1 < positive.len(), "{positive:?}");
    assert!(positive[best].1 < stuck.1 / 10.0 && positive[best].1 < free.1 / 10.0);
    // (iv), (v): turning points and the unstable middle branch
    for (p, softening) in [(3.0, true), (-30.0, false)] {
        let c = &curves[at(p)];
        let t = turns(c);
        assert_eq!(t.len(), 2, "P = {p}: {t:?}");
        if softening {
            assert!(t[1].0 < t[0].0 && t[1].1 > t[0].1, "P = {p}: {t:?}");
        } else {
            assert!(t[0].0 > t[1].0 && t[0].1 > t[1].1, "P = {p}: {t:?}");
        }
        let k: Vec<usize> = (1..c.len() - 1)
            .filter(|&k| (c[k].0 - c[k - 1].0) * (c[k + 1].0 - c[k].0) < 0.0)
            .collect();
        for (j, q) in c.iter().enumerate() {
            if j + 1 < k[0] || j > k[1] + 1 {
                assert_eq!(q.2, Some(true), "P = {p}, point {j} at {} Hz", q.0);
            } else if j > k[0] + 1 && j + 1 < k[1] {
                assert_eq!(q.2, Some(false), "P = {p}, point {j} at {} Hz", q.0);
            }
        }
    }
    // (vi), (vii): the maps of P = 3 at 347 Hz, on its three branches in path order
    let maps: Vec<_> = results.maps.iter().filter(|m| m.curve == at(3.0)).collect();
    assert_eq!(maps.len(), 3);
    let mut separated = Vec::new();
    let mut all_three = 0;
    for m in &maps {
        assert_eq!(m.omega, 2.0 * PI * MAP_HZ);
        let amp = results.frfs[m.curve].points[m.point].harmonics[1].norm();
        let frac = m.state.iter().filter(|&&s| s == 2).count() as f64 / m.state.len() as f64;
        let (e, n) = (m.position.len(), m.phase.len());
        let mixed = (0..n)
            .filter(|&j| {
                let has = |f: &dyn Fn(i64) -> bool| (0..e).any(|p| f(m.state[p * n + j]));
                has(&|s| s == 0) && has(&|s| s == 1 || s == -1) && has(&|s| s == 2)
            })
            .count();
        eprintln!(
            "347 Hz: |Q1| {amp:.4e}, separated {frac:.3} of the map, {mixed} of {n} angles with all three states"
        );
        separated.push((amp, frac));
        all_three += mixed;
    }
    separated.sort_by(|a, b| a.0.total_cmp(&b.0));
    assert!(separated[2].1 > separated[0].1, "{separated:?}");
    assert!(all_three > 0);
}
