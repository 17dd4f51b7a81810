//! The underplatform-damper demonstrator of Gastaldi & Berruti 2018 (§6), shipped as
//! cases/damper.toml: bilateral gross slip, the state changes per period, all methods giving the
//! same contact forces (paper: "perfectly superposed"), the iteration counts of Fig. 5, and the
//! `nlrom march` command with its results file.

mod support;

use support::cli::{json_report, nlrom};

use std::path::Path;

use nlrom::case::{Case, MarchScheme};
use nlrom::march::element::Direction;
use nlrom::march::{march, MarchOutcome};
use nlrom::output::{read_results, H5Reader, ResponseDof};
use nlrom::problem::march_case::{case_march, CaseMarch};

fn damper_case() -> Case {
    Case::load(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/damper.toml"
    )))
    .unwrap()
}

fn run(scheme: MarchScheme) -> MarchOutcome {
    let case = damper_case();
    let cm = case_march(&case, Some(scheme), &mut |_| {}).unwrap();
    march(&cm.system, &cm.settings).unwrap()
}

/// Largest |f(t) − f_ref(t)| over the last period on `out`'s instants (reference interpolated
/// linearly), relative to the largest reference force of that period.
fn force_difference(out: &MarchOutcome, reference: &MarchOutcome) -> f64 {
    let (h, r) = (&out.history, &reference.history);
    let ne = 3;
    let t0 = r.time[reference.periods[reference.periods.len() - 2].end_index];
    let interp = |t: f64, e: usize, c: usize| -> f64 {
        let k = r.time.partition_point(|&x| x <= t).clamp(1, r.len() - 1);
        let (ta, tb) = (r.time[k - 1], r.time[k]);
        let (fa, fb) = (
            r.force[((k - 1) * ne + e) * 2 + c],
            r.force[(k * ne + e) * 2 + c],
        );
        fa + (fb - fa) * (t - ta) / (tb - ta)
    };
    let scale = (0..r.len())
        .filter(|&k| r.time[k] >= t0)
        .flat_map(|k| (0..2 * ne).map(move |j| r.force[k * 2 * ne + j].abs()))
        .fold(0.0, f64::max);
    let mut worst: f64 = 0.0;
    for k in (0..h.len()).filter(|&k| h.time[k] >= t0) {
        for e in 0..ne {
            for c in 0..2 {
                let d = (h.force[(k * ne + e) * 2 + c] - interp(h.time[k], e, c)).abs();
                worst = worst.max(d);
            }
        }
    }
    worst / scale
}

/// Changes of the interfaces' states over the last period, counted cyclically: the left
/// (flat-on-flat: L1, L2) and the right interface are each "in gross slip" when all their points
/// slip (in the same direction), and "stuck" otherwise (the paper's count of §6 is per interface).
fn interface_changes(out: &MarchOutcome) -> usize {
    let h = &out.history;
    let first = out.periods[out.periods.len() - 2].end_index + 1;
    let interface = |k: usize| -> (u8, u8) {
        let s = &h.state[3 * k..3 * k + 3];
        let left = if s[0] == s[1] && s[0] >= 2 { s[0] } else { 1 };
        (left, s[2])
    };
    let last = h.len() - 1;
    (first..=last)
        .filter(|&k| {
            let prev = if k == first { last } else { k - 1 };
            interface(k) != interface(prev)
        })
        .count()
}

/// Instants of the last period at which every contact slips (bilateral gross slip).
fn bilateral_slip_instants(out: &MarchOutcome) -> usize {
    let h = &out.history;
    let first = out.periods[out.periods.len() - 2].end_index;
    (first..h.len())
        .filter(|&k| h.state[3 * k..3 * k + 3].iter().all(|&s| s >= 2))
        .count()
}

#[test]
fn all_methods_agree_on_the_damper_with_bilateral_gross_slip() {
    let standard = run(MarchScheme::Newmark);
    let others: Vec<(MarchScheme, MarchOutcome)> = [
        MarchScheme::Adaptive,
        MarchScheme::PiecewiseLinear,
        MarchScheme::AdaptivePiecewiseLinear,
        MarchScheme::QuasiStatic,
    ]
    .into_iter()
    .map(|s| (s, run(s)))
    .collect();
    // bilateral gross slip: both platforms' contacts slide at once, in every method
    assert!(bilateral_slip_instants(&standard) > 10);
    for (s, o) in &others {
        assert!(
            bilateral_slip_instants(o) > 5,
            "{s}: no bilateral gross slip"
        );
    }
    // the same forces as standard Newmark (measured: adaptive 1.4e-3, piecewise-linear 9.5e-10,
    // both 1.4e-3, quasi-static 1.6e-2 of the largest contact force — the quasi-static run lacks
    // the damper's ringing on its springs after each transition)
    let limits = [6e-3, 1e-7, 6e-3, 3e-2];
    for ((s, o), lim) in others.iter().zip(limits) {
        let d = force_difference(o, &standard);
        eprintln!(
            "{s}: max contact-force difference to standard Newmark {d:.2e} of the largest force"
        );
        assert!(d < lim, "{s}: {d}");
    }
    // about six contact-state changes per period in the steady state (paper §6: six; §4.3: 4–7),
    // in every method: the damped inner vibration no longer makes the contacts chatter
    // (measured: standard 7, adaptive 7, piecewise-linear 7, both 7, quasi-static 8)
    let count = |o: &MarchOutcome| o.periods.last().unwrap().state_changes;
    eprintln!("state changes per period: standard {}", count(&standard));
    // per interface (left flat, right), as the paper counts: six, stick → left slips → both slip →
    // stick twice a period, or five when both interfaces start sliding within one step
    for (s, o) in std::iter::once(&(MarchScheme::Newmark, standard.clone())).chain(&others) {
        let n = interface_changes(o);
        eprintln!("interface state changes per period: {s} {n}");
        assert!((5..=6).contains(&n), "{s}: {n}");
    }
    assert!((5..=8).contains(&count(&standard)), "{}", count(&standard));
    for (s, o) in &others {
        eprintln!("state changes per period: {s} {}", count(o));
        assert!((5..=9).contains(&count(o)), "{s}: {}", count(o));
        assert_eq!(o.steady_period, Some(2), "{s}: steady after one period");
    }
    assert_eq!(standard.steady_period, Some(2));
    // Fig. 5: standard Newmark ≈ 11 iterations per step at 200 Hz, piecewise-linear mostly one
    let mean = |o: &MarchOutcome| o.total_iterations as f64 / o.steps as f64;
    eprintln!(
        "iterations per step: standard {:.2}, piecewise-linear {:.3}",
        mean(&standard),
        mean(&others[1].1)
    );
    assert!((8.0..14.0).contains(&mean(&standard)));
    let pl = &others[1].1;
    assert!(
        pl.single_iteration_fraction() > 0.9,
        "{}",
        pl.single_iteration_fraction()
    );
    assert!(pl.iteration_histogram().len() <= 4);
    // the adaptive step takes longer steps outside stick and never exceeds the stability ratio
    let adaptive = &others[0].1;
    assert!(adaptive.steps < standard.steps);
    assert!(adaptive.step_range.1 > 1.2 * standard.step_range.1);
}

/// In bilateral gross slip every contact force is s_i μ f_n,i along its tangent plus f_n,i along its
/// normal, so the three normal forces follow from the damper's static equilibrium alone,
/// Σ_i (s_i μ g_t,i + g_n,i) f_n,i = f_e = (0, −CF, 0) (independent of the contact stiffnesses and
/// of the motion). Returns the largest relative deviation of the run's normal forces from that
/// solution over the last period's all-slip instants at least `settle` (s) after the slip began
/// (the transition rings the damper on its springs for a while), and how many instants there were.
fn slip_statics_deviation(
    cm: &CaseMarch,
    out: &MarchOutcome,
    cf: f64,
    settle: f64,
) -> (f64, usize) {
    let h = &out.history;
    let first = out.periods[out.periods.len() - 2].end_index + 1;
    let dense = |d: &Direction| {
        let mut g = nalgebra::Vector3::zeros();
        for &(i, w) in &d.weights {
            g[i] += w;
        }
        g
    };
    let (mut worst, mut count) = (0.0f64, 0usize);
    let mut slip_since = f64::INFINITY;
    for k in first..h.len() {
        let states = &h.state[3 * k..3 * k + 3];
        if states.iter().any(|&s| s < 2) {
            slip_since = f64::INFINITY;
            continue;
        }
        if slip_since.is_infinite() || states != &h.state[3 * (k - 1)..3 * k] {
            slip_since = h.time[k];
        }
        if h.time[k] - slip_since < settle {
            continue;
        }
        let mut a = nalgebra::Matrix3::zeros();
        for (j, (e, &s)) in cm.system.elements.iter().zip(states).enumerate() {
            let sign = if s == 2 { 1.0 } else { -1.0 };
            let col = sign * e.params.mu * dense(&e.tangential)
                + dense(e.normal.as_ref().expect("damper contacts have normals"));
            a.set_column(j, &col);
        }
        let fe = nalgebra::Vector3::new(0.0, -cf, 0.0);
        let fn_static = a.lu().solve(&fe).expect("independent contact directions");
        for j in 0..3 {
            let got = h.force[(k * 3 + j) * 2 + 1];
            worst = worst.max((got - fn_static[j]).abs() / fn_static[j].abs());
        }
        count += 1;
    }
    (worst, count)
}

#[test]
fn bilateral_slip_normal_forces_follow_from_statics() {
    let case = damper_case();
    let cf = case.damper.as_ref().unwrap().centrifugal_force;
    for (scheme, settle, limit) in [
        (MarchScheme::QuasiStatic, 0.0, 1e-9),
        (MarchScheme::PiecewiseLinear, 0.0, 0.1),
        (MarchScheme::PiecewiseLinear, 1e-3, 1e-2),
        (MarchScheme::Newmark, 1e-3, 1e-2),
    ] {
        let cm = case_march(&case, Some(scheme), &mut |_| {}).unwrap();
        let out = march(&cm.system, &cm.settings).unwrap();
        let (dev, n) = slip_statics_deviation(&cm, &out, cf, settle);
        eprintln!("{scheme}: normal forces in bilateral slip ({settle} s after it began) vs statics: {dev:.2e} over {n} instants");
        assert!(n > 50, "{scheme}: {n} all-slip instants");
        assert!(dev < limit, "{scheme}: {dev}");
    }
}

#[test]
fn march_command_writes_the_results_file() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("damper.h5");
    let case = concat!(env!("CARGO_MANIFEST_DIR"), "/cases/damper.toml");
    let report = json_report(
        "march",
        Path::new(case),
        &out,
        &["--scheme", "quasi-static"],
    );
    assert_eq!(report["scheme"], "quasi-static");
    assert_eq!(report["steps"], 900);
    assert!(report["wall_seconds"].as_f64().unwrap() > 0.0);
    let file = H5Reader::open(&out).unwrap();
    let time = file.dataset("/march/time").unwrap();
    assert_eq!(time.shape, vec![901]);
    let force = file.dataset("/march/contact_force").unwrap();
    assert_eq!(force.shape, vec![901, 3, 2]);
    assert_eq!(force.unit(), Some("N"));
    let g = file.group("/march").unwrap();
    assert_eq!(g.attrs["scheme"].as_str(), Some("quasi-static"));
    // one writer owns the file: output::results reads it back whole
    let m = read_results(&out).unwrap().march.unwrap();
    assert_eq!(m.time.len(), 901);
    assert_eq!(m.steps, 900);
    assert_eq!(m.element_names, ["L1", "L2", "R"]);
    assert_eq!(
        m.response_dofs,
        (0..3).map(ResponseDof::Row).collect::<Vec<_>>()
    );
    assert_eq!(m.contact_state.len(), 901 * 3);
    assert_eq!(m.first_harmonic_last_period.len(), 3);
    for name in [
        "contact_displacement",
        "iteration_histogram",
        "state_changes",
        "response_names",
    ] {
        assert!(m.extra.datasets.contains_key(name), "{name}");
    }

    // bad input: a march case whose scheme needs mass it does not have is refused by the library;
    // a case without [march] and a sector (mesh, cyclic) model with the 2-D friction element are
    // clear input errors (exit 2)
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "[damper]\nmass = 0.01\ninertia = 1e-7\ncentrifugal_force = 10.0\nplatform = []\ncontact = []\n").unwrap();
    let res = nlrom(&[
        "march",
        bad.to_str().unwrap(),
        "-o",
        dir.path().join("x.h5").to_str().unwrap(),
    ]);
    assert_eq!(res.status.code(), Some(2));
    let err = String::from_utf8_lossy(&res.stderr);
    assert!(err.contains("damper") && err.contains("contact"), "{err}");
    assert!(!dir.path().join("x.h5").exists());

    // a damping ratio of 1 or more is refused naming the key
    let damper_text =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/cases/damper.toml")).unwrap();
    assert!(damper_text.contains("damping_ratio = 0.2 "));
    let overdamped = dir.path().join("overdamped.toml");
    std::fs::write(
        &overdamped,
        damper_text.replace("damping_ratio = 0.2 ", "damping_ratio = 1.5 "),
    )
    .unwrap();
    let res = nlrom(&[
        "march",
        overdamped.to_str().unwrap(),
        "-o",
        dir.path().join("z.h5").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&res.stderr);
    assert_eq!(res.status.code(), Some(2), "{err}");
    assert!(
        err.contains("damping_ratio") && err.contains("below 1"),
        "{err}"
    );

    let sector = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/sector8_cs.toml"
    ))
    .unwrap()
    .replace(
        "../meshes/",
        concat!(env!("CARGO_MANIFEST_DIR"), "/meshes/"),
    )
    .replace(
        "model = \"node-to-node\"",
        "model = \"node-to-node\"\nelement = \"2d\"",
    );
    let sector_case = dir.path().join("sector.toml");
    std::fs::write(
        &sector_case,
        format!(
            "{sector}
[march]
frequency_hz = 200.0
periods = 1
steps_per_period = 100
"
        ),
    )
    .unwrap();
    let res = nlrom(&[
        "march",
        sector_case.to_str().unwrap(),
        "-o",
        dir.path().join("y.h5").to_str().unwrap(),
    ]);
    let err = String::from_utf8_lossy(&res.stderr);
    assert_eq!(res.status.code(), Some(2), "{err}");
    assert!(
        err.contains("sector.toml") && err.contains("shroud") && err.contains("element = \"1d\""),
        "{err}"
    );
    assert!(!dir.path().join("y.h5").exists());
}

/// A matrix-defined case (the Jenkins oscillator of `docs/theory.md`: m = k = 1, Rayleigh c = 0.1 M, k_t = 1,
/// F_s = 0.3, F = 0.5 at ω = 0.952957) through `nlrom march`: marched to steady state, its
/// first-harmonic amplitude equals the H = 7 harmonic balance of `nlrom::hbm` (0.991341,
/// tests/march_hbm.rs) within 1e-3.
#[test]
fn matrix_case_marches_to_the_harmonic_balance_amplitude() {
    let dir = tempfile::tempdir().unwrap();
    let one = "%%MatrixMarket matrix coordinate real symmetric\n1 1 1\n1 1 1.0\n";
    std::fs::write(dir.path().join("K.mtx"), one).unwrap();
    std::fs::write(dir.path().join("M.mtx"), one).unwrap();
    let case = dir.path().join("sdof.toml");
    std::fs::write(
        &case,
        r#"
[model]
stiffness = "K.mtx"
mass = "M.mtx"
damping = { rayleigh = [0.1, 0.0] }

[excitation]
dofs = [0]
force = [0.5]

[[element]]
kind = "friction"
tangential = { dofs = [0], weights = [1.0] }
kt = 1.0
mu = 1.0
n0 = 0.3

[harmonic_balance]
harmonics = 3

[march]
frequency_rad_s = 0.952957
periods = 200
steps_per_period = 800
scheme = "piecewise-linear"
stop_at_steady = true
steady_tolerance = 1e-7
"#,
    )
    .unwrap();
    let out = dir.path().join("sdof.h5");
    let report = json_report("march", &case, &out, &[]);
    let amp = report["first_harmonic_last_period"][0].as_f64().unwrap();
    assert!((amp - 0.991341).abs() < 1e-3, "{amp}");
    assert!(report["steady_period"].as_u64().unwrap() < 200);
    let file = H5Reader::open(&out).unwrap();
    assert_eq!(
        file.dataset("/march/harmonics_last_period").unwrap().shape,
        vec![1, 4]
    );
}
