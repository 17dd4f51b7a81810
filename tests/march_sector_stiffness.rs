//! Why the adaptive step of Gastaldi & Berruti 2018 (§4.2, eq. 8) cannot lengthen the step of the
//! reduced sector of `cases/sector8_march.toml`, and where it can: the shortest natural period
//! 𝕋 = 2π/√λ_max of the pencil (K + K_c(states), M) in full stick and with every element
//! separated (no contact stiffness: the longest 𝕋 any state can have, since a state's K_c lies
//! between none and full stick's), the top mode's share of strain energy in the contact springs,
//! and the structure's own stiffness at the contact coordinates against k_t, for the bundled
//! contact stiffness (k_t = k_n = 1e8 N/m) and the same sector with k_t, k_n ×10 and ×100.
//! Dense symmetric eigenproblems ([`dense::generalized_symmetric_eigen`]) against the dense
//! spectral radius of M⁻¹(K + K_c) that eq. 8 takes ([`MarchSystem::shortest_period`]). And the
//! same sector on its 20 lowest modes with the contacts open, where the contact does set the top
//! mode, marched by standard Newmark and the adaptive step.

use std::path::Path;

use nlrom::case::{Case, MarchScheme};
use nlrom::march::dense;
use nlrom::march::law::{ContactState, Sign};
use nlrom::march::{march, MarchSettings, MarchSystem};
use nlrom::problem::march_case::case_march;

/// The reduced sector of `cases/sector8_march.toml` with every element's k_t and k_n multiplied
/// by `factor` (K_c is linear in them, [`nlrom::march::element::Element::add_stiffness`]).
fn sector(factor: f64) -> MarchSystem {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/sector8_march.toml");
    let case = Case::load(&path).expect("bundled case");
    let mut sys = case_march(&case, None, &mut |_| {})
        .expect("sector march")
        .system;
    for e in &mut sys.elements {
        e.params.kt *= factor;
        e.params.kn *= factor;
    }
    sys
}

/// What the contact does to the top of the sector's spectrum.
struct Top {
    /// Highest natural frequency in full stick and with every element separated (Hz).
    f_stick: f64,
    f_separated: f64,
    /// Highest natural frequency with every element slipping (positive sign) (Hz).
    f_slip: f64,
    /// Share of the full-stick top mode's strain energy in the contact springs.
    contact_share: f64,
    /// The fewest elements holding 90 % of that contact energy.
    carriers: usize,
    /// The structure's stiffness g_tᵀ K g_t along the elements' tangential directions (N/m):
    /// smallest and largest.
    local: (f64, f64),
    /// 𝕋_stick from the spectral radius of M⁻¹(K + K_c) (s).
    period_stick: f64,
}

fn top(sys: &MarchSystem) -> Top {
    let n = sys.n;
    let stick = sys.stick_states();
    let separated = vec![ContactState::Separated; sys.elements.len()];
    let k_stick = sys.effective_stiffness(&stick);
    let k_sep = sys.effective_stiffness(&separated);
    let (l_stick, phi) =
        dense::generalized_symmetric_eigen(&k_stick, &sys.mass, n).expect("full-stick modes");
    let (l_sep, _) =
        dense::generalized_symmetric_eigen(&k_sep, &sys.mass, n).expect("separated modes");
    let hz = |l: f64| l.sqrt() / (2.0 * std::f64::consts::PI);
    let slip = vec![ContactState::Slip(Sign::Positive); sys.elements.len()];
    let f_slip = 1.0 / sys.shortest_period(&slip).expect("a period in slip");
    let top_mode: Vec<f64> = (0..n).map(|i| phi[i * n + n - 1]).collect();
    let mut kphi = vec![0.0; n];
    dense::matvec(&k_stick, &top_mode, &mut kphi);
    let total: f64 = top_mode.iter().zip(&kphi).map(|(a, b)| a * b).sum();
    let dot = |w: &[(usize, f64)], x: &[f64]| w.iter().map(|&(i, g)| g * x[i]).sum::<f64>();
    let mut per_element: Vec<f64> = sys
        .elements
        .iter()
        .map(|e| {
            let t = e.params.kt * dot(&e.tangential.weights, &top_mode).powi(2);
            let nrm = e
                .normal
                .as_ref()
                .map_or(0.0, |d| e.params.kn * dot(&d.weights, &top_mode).powi(2));
            t + nrm
        })
        .collect();
    let contact: f64 = per_element.iter().sum();
    per_element.sort_by(|a, b| b.total_cmp(a));
    let mut held = 0.0;
    let carriers = 1 + per_element
        .iter()
        .take_while(|&&x| {
            held += x;
            held < 0.9 * contact
        })
        .count();
    let mut local = (f64::INFINITY, 0.0f64);
    for e in &sys.elements {
        let w = &e.tangential.weights;
        let kg: f64 = w
            .iter()
            .map(|&(i, gi)| {
                gi * w
                    .iter()
                    .map(|&(j, gj)| sys.stiffness[i * n + j] * gj)
                    .sum::<f64>()
            })
            .sum();
        local = (local.0.min(kg), local.1.max(kg));
    }
    Top {
        f_stick: hz(l_stick[n - 1]),
        f_separated: hz(l_sep[n - 1]),
        f_slip,
        contact_share: contact / total,
        carriers,
        local,
        period_stick: sys.shortest_period(&stick).expect("a period"),
    }
}

/// On the bundled sector (k_t = k_n = 1e8 N/m) the top mode is the structure's: the contact
/// springs hold 5.5 % of its strain energy, k_t lies 11 to 79 times below the structure's own
/// stiffness g_tᵀ K g_t along the elements' directions (1.07e9–7.87e9 N/m), and even with every
/// element separated the shortest period is only 2.8 % longer than in full stick (1.0401 against
/// 1.0689 MHz): the most eq. 8 can lengthen the step in any state, so the adaptive march takes
/// ≈ 0.996 of Newmark's steps. With k_t, k_n ×10 the contact springs hold 48 % of the top mode's
/// energy and separation lengthens the shortest period by 30 %; ×100, 96 % (90 % of it in 3
/// elements) and 3.3 times. Slip alone does not: a slipping element keeps its normal spring, and
/// with every element slipping the shortest period is 2.4 %, 9.4 % and 6.0 % longer than in full
/// stick (×1, ×10, ×100), short of the 25 % that 0.8 of Newmark's steps needs.
#[test]
fn the_contact_stiffness_sets_the_sector_top_mode_only_when_it_rivals_the_structure() {
    let mut rows = Vec::new();
    for factor in [1.0, 10.0, 100.0] {
        let sys = sector(factor);
        let t = top(&sys);
        let gain = t.f_stick / t.f_separated;
        eprintln!(
            "k_t = k_n = {:.0e} N/m: f_max stick {:.4e} Hz, separated {:.4e} Hz (𝕋 ratio {gain:.4}), all slipping {:.4e} Hz (𝕋 ratio {:.4}); contact share of the top mode's strain energy {:.3e}, 90 % of it in {} elements; structure g_tᵀKg_t {:.3e}–{:.3e} N/m; 𝕋_stick {:.4e} s",
            1.0e8 * factor,
            t.f_stick,
            t.f_separated,
            t.f_slip,
            t.f_stick / t.f_slip,
            t.contact_share,
            t.carriers,
            t.local.0,
            t.local.1,
            t.period_stick,
        );
        // eq. 8's dense spectral radius and the symmetric pencil agree
        assert!(
            (1.0 / t.period_stick / t.f_stick - 1.0).abs() < 1e-6,
            "spectral radius {} Hz against the pencil {} Hz",
            1.0 / t.period_stick,
            t.f_stick
        );
        rows.push((factor, gain, t));
    }
    let slip_gain = |t: &Top| t.f_stick / t.f_slip;
    let (_, gain, bundled) = &rows[0];
    assert!(
        (1.02..1.03).contains(gain),
        "bundled sector: 𝕋 ratio {gain}"
    );
    assert!(slip_gain(bundled) < 1.03, "{}", slip_gain(bundled));
    assert!(bundled.contact_share < 0.06, "{}", bundled.contact_share);
    assert!(bundled.local.0 > 10.0 * 1.0e8, "{:?}", bundled.local);
    let (_, gain, ten) = &rows[1];
    assert!((1.25..1.35).contains(gain), "k ×10: 𝕋 ratio {gain}");
    assert!((1.05..1.12).contains(&slip_gain(ten)), "{}", slip_gain(ten));
    assert!(
        (0.4..0.55).contains(&ten.contact_share),
        "{}",
        ten.contact_share
    );
    let (_, gain, hundred) = &rows[2];
    assert!((3.2..3.4).contains(gain), "k ×100: 𝕋 ratio {gain}");
    assert!(
        (1.03..1.09).contains(&slip_gain(hundred)),
        "{}",
        slip_gain(hundred)
    );
    assert!(hundred.contact_share > 0.95, "{}", hundred.contact_share);
    assert!(hundred.carriers <= 5, "{}", hundred.carriers);
}

/// Where the contact sets the top mode and the step may grow, eq. 8 still saves too few steps:
/// the bundled sector on its 20 lowest modes with every element separated (the structure's own
/// modes, up to 17.3 kHz; a ROM whose first-harmonic response at the case's three output DOFs
/// lies about 11 % from the Craig–Bampton model's, 2 % on 40 modes) has its full-stick top mode
/// at 50.2 kHz, set by the contact (the contact springs hold most of its strain energy); every
/// element slipping lengthens the shortest period 1.42 times, every element separated 2.91
/// times. Marched from rest for two periods at 170 Hz (the bench's settings: Newmark at
/// 0.15 𝕋_stick), the adaptive step takes 0.866 of standard Newmark's steps, short of the 0.8
/// of Gastaldi & Berruti (2018, Fig. 8): at this response about 40 of the 90 elements are out of
/// stick at an instant, and the states with most elements stuck keep the step near the full-stick
/// one. The two marches give the same response (first harmonics within 1e-5).
#[test]
fn on_its_free_modes_the_contact_sets_the_sector_top_mode_but_the_adaptive_step_saves_13_percent() {
    let full = sector(1.0);
    let separated = vec![ContactState::Separated; full.elements.len()];
    let k_open = full.effective_stiffness(&separated);
    let (lambda, phi) =
        dense::generalized_symmetric_eigen(&k_open, &full.mass, full.n).expect("open modes");
    let m = 20;
    let sys = full.on_modes(&phi, m).expect("modal model");
    let t = top(&sys);
    let basis_top = lambda[m - 1].sqrt() / (2.0 * std::f64::consts::PI);
    let (slip_gain, open_gain) = (t.f_stick / t.f_slip, t.f_stick / t.f_separated);
    eprintln!(
        "{m} open modes (up to {basis_top:.4e} Hz): f_max stick {:.4e} Hz, all slipping 𝕋 ratio {slip_gain:.4}, all separated {open_gain:.4}; contact share of the top mode's strain energy {:.3}",
        t.f_stick, t.contact_share
    );
    assert!((1.7e4..1.75e4).contains(&basis_top), "{basis_top}");
    assert!((4.9e4..5.1e4).contains(&t.f_stick), "{}", t.f_stick);
    assert!(t.contact_share > 0.5, "{}", t.contact_share);
    assert!((1.38..1.46).contains(&slip_gain), "{slip_gain}");
    assert!((2.8..3.0).contains(&open_gain), "{open_gain}");

    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/sector8_march.toml");
    let case = Case::load(&path).expect("bundled case");
    let base = case_march(&case, None, &mut |_| {})
        .expect("sector march")
        .settings;
    let run = |scheme: MarchScheme| {
        let settings = MarchSettings {
            scheme,
            periods: 2,
            steps_per_period: 300,
            time_step: None,
            stop_at_steady: false,
            ..base.clone()
        };
        march(&sys, &settings).expect("modal march")
    };
    let newmark = run(MarchScheme::Newmark);
    let adaptive = run(MarchScheme::Adaptive);
    let steps = adaptive.steps as f64 / newmark.steps as f64;
    let (a, b) = (
        newmark.first_harmonic_amplitude(),
        adaptive.first_harmonic_amplitude(),
    );
    let scale = a.iter().fold(0.0f64, |s, x| s.max(*x));
    let diff = a
        .iter()
        .zip(&b)
        .fold(0.0f64, |s, (x, y)| s.max((x - y).abs()))
        / scale;
    eprintln!(
        "Newmark {} steps, adaptive {} ({steps:.4}); first harmonics within {diff:.2e}",
        newmark.steps, adaptive.steps
    );
    assert!(
        (0.84..0.89).contains(&steps),
        "adaptive/Newmark steps {steps}"
    );
    assert!(diff < 1e-5, "{diff}");

    // How far the 20- and 40-mode ROMs lie from the Craig–Bampton model: the case's march
    // (piecewise-linear Newmark, 200 steps per period) to steady state, first-harmonic amplitudes
    // at the case's output DOFs (Φ q on the modes).
    let cm = case_march(&case, Some(MarchScheme::PiecewiseLinear), &mut |_| {}).expect("march");
    let settings = MarchSettings {
        periods: 150,
        stop_at_steady: true,
        ..cm.settings.clone()
    };
    let amplitudes = |sys: &MarchSystem, modes: Option<usize>| -> Vec<f64> {
        let o = march(sys, &settings).expect("steady march");
        assert!(o.steady_period.is_some(), "no steady state in 150 periods");
        let first = |i: usize| -> (f64, f64) {
            match modes {
                None => o.harmonics[i][1],
                Some(m) => (0..m).fold((0.0, 0.0), |(re, im), j| {
                    let (a, b) = o.harmonics[j][1];
                    let p = phi[i * full.n + j];
                    (re + p * a, im + p * b)
                }),
            }
        };
        cm.response
            .iter()
            .map(|&i| {
                let (re, im) = first(i);
                re.hypot(im)
            })
            .collect()
    };
    let reference = amplitudes(&full, None);
    let largest = reference.iter().fold(0.0f64, |s, x| s.max(*x));
    let error = |m: usize| -> f64 {
        amplitudes(&full.on_modes(&phi, m).expect("modal model"), Some(m))
            .iter()
            .zip(&reference)
            .fold(0.0f64, |s, (x, y)| s.max((x - y).abs()))
            / largest
    };
    let (e20, e40) = (error(20), error(40));
    eprintln!("first harmonics at the outputs against the Craig–Bampton model: 20 modes {e20:.3e}, 40 modes {e40:.3e}");
    assert!((0.08..0.15).contains(&e20), "20 modes: {e20}");
    assert!(e40 < 0.03, "40 modes: {e40}");
}

/// [`MarchSystem::on_modes`] on every mode of the sector is the same model in other
/// coordinates: one period of the case's march (piecewise-linear Newmark, 200 steps, from rest)
/// gives Φ η = q, the first harmonics of every coordinate within 1e-8 of the largest; and a
/// basis of the wrong size or no modes is refused.
#[test]
fn on_every_mode_the_march_is_the_models() {
    let full = sector(1.0);
    let n = full.n;
    let (_, phi) =
        dense::generalized_symmetric_eigen(&full.stiffness, &full.mass, n).expect("modes");
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/sector8_march.toml");
    let case = Case::load(&path).expect("bundled case");
    let settings = MarchSettings {
        periods: 1,
        stop_at_steady: false,
        ..case_march(&case, Some(MarchScheme::PiecewiseLinear), &mut |_| {})
            .expect("march")
            .settings
    };
    let modal = full.on_modes(&phi, n).expect("every mode");
    let physical = march(&full, &settings).expect("physical march");
    let on_modes = march(&modal, &settings).expect("modal march");
    assert_eq!(physical.steps, on_modes.steps);
    let largest = physical
        .first_harmonic_amplitude()
        .iter()
        .fold(0.0f64, |s, x| s.max(*x));
    let mut worst = 0.0f64;
    for i in 0..n {
        let (re, im) = (0..n).fold((0.0, 0.0), |(re, im), j| {
            let (a, b) = on_modes.harmonics[j][1];
            (re + phi[i * n + j] * a, im + phi[i * n + j] * b)
        });
        let (pr, pi) = physical.harmonics[i][1];
        worst = worst.max((re - pr).hypot(im - pi));
    }
    eprintln!(
        "every mode: first harmonics within {:.2e} of the largest",
        worst / largest
    );
    assert!(worst < 1e-8 * largest, "{}", worst / largest);
    let err = full.on_modes(&phi, 0).unwrap_err().to_string();
    assert!(err.contains("0 modes"), "{err}");
    let err = full.on_modes(&phi[..n], 2).unwrap_err().to_string();
    assert!(err.contains("n × n expected"), "{err}");
}
