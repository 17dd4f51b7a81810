//! The speed comparison of Gastaldi & Berruti 2018 §6 / Fig. 8, all in one run, on three models:
//! - the underplatform damper (cases/damper.toml, 200 Hz, one period after the static start);
//! - a one-DOF oscillator with a Jenkins element (m = 1 kg, k = 4 N/m, k_t = 5 N/m, slip force
//!   0.5 N, F = 2 N at ω = 1 rad/s, below resonance), 10 periods from rest, 300 steps per period;
//! - the same oscillator with a stiff contact (k_t = 400 N/m) at ω = 0.2 rad/s, a tenth of its
//!   free natural frequency (inertia negligible: the quasi-static method applies), 5 periods from
//!   rest, Newmark at the step compatible with full stick, the quasi-static method at 300 steps
//!   per period;
//! - the reduced sector of cases/sector8_march.toml (k = 0, shroud contact in micro-slip, 170 Hz),
//!   two periods from rest with the paper's settings: Newmark at the step compatible with full
//!   stick (Δτ = 0.15 𝕋_stick, at most 1/300 of the period), the quasi-static method at 300 steps
//!   per period.
//!
//! Per model and scheme: steps, corrector iterations, single-iteration steps and step-matrix
//! factorisations; the wall time and the CPU time (user + system, of the process) of one whole
//! march (minimum over rounds interleaving the schemes, so a changing machine load hits them
//! alike) and their ratios to standard Newmark; and the largest difference of the contact forces
//! from standard Newmark's over the last period (relative to standard Newmark's largest force),
//! the "same loops" check. Then criterion's wall-time estimates on the damper and the oscillator.
//! The sector ROM (one round, each march's times printed as it ends: the step compatible with full
//! stick is 0.14 µs, 41 917 steps per period, and the adaptive step meets thousands of contact
//! states) runs only with `NLROM_BENCH_SECTOR=1` (every scheme) or
//! `NLROM_BENCH_SECTOR=piecewise-linear,quasi-static` (standard Newmark and the schemes named).
//!
//! With `NLROM_BENCH_SECTOR_QS=1` it adds the sector where the quasi-static method applies (15 Hz,
//! standard Newmark and the quasi-static method, [`sector_quasi_static`]; about 70 s of CPU).
//!
//! With `NLROM_BENCH_SECTOR_STIFF=10,100` it adds the same sector with k_t and k_n ×10 and
//! ×100, every scheme ([`sector_stiff`]).
//!
//! With `NLROM_BENCH_SECTOR_MODES=20` it adds the same sector on its 20 lowest modes with the
//! contacts open, every scheme with more rounds ([`sector_modes`]): a model whose top mode the
//! contact sets.
//!
//! With `NLROM_BENCH_PASS=1` it first times the products of one step in isolation on the sector's
//! matrices ([`product_passes`]).
//!
//! `cargo bench --bench march` — the printed tables are those of docs/performance.md.

use std::path::Path;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion};
use nlrom::case::{Case, MarchScheme};
use nlrom::commands::batch::records::process_cpu_seconds;
use nlrom::march::element::{Direction, Element};
use nlrom::march::law::FrictionParams;
use nlrom::march::signal::Harmonic;
use nlrom::march::{march, InitialCondition, MarchOutcome, MarchSettings, MarchSystem};
use nlrom::problem::march_case::{case_march, CaseMarch};

/// The schemes of Gastaldi & Berruti 2018 (friction elements), standard Newmark first.
fn schemes() -> Vec<MarchScheme> {
    MarchScheme::ALL
        .into_iter()
        .filter(|s| !s.is_nonsmooth())
        .collect()
}

/// A marched model and the settings of its standard-Newmark run.
struct Model {
    name: &'static str,
    system: MarchSystem,
    settings: MarchSettings,
    rounds: usize,
    /// Print each march's wall and CPU times as it ends (the long sector marches).
    progress: bool,
    /// The schemes compared, standard Newmark first.
    schemes: Vec<MarchScheme>,
}

fn case(name: &str) -> Case {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases")
        .join(name);
    Case::load(&path).expect("bundled case")
}

fn damper() -> Model {
    let cm = case_march(&case("damper.toml"), None, &mut |_| {}).expect("damper march");
    Model {
        name: "underplatform damper (3 DOF, 3 contacts)",
        system: cm.system,
        settings: MarchSettings {
            periods: 1,
            ..cm.settings
        },
        rounds: 200,
        progress: false,
        schemes: schemes(),
    }
}

/// The one-DOF oscillator m = 1 kg, k = 4 N/m, c = 0.12 N·s/m with a Jenkins element (tangential
/// stiffness `kt`, slip force 0.5 N) under 2 N at ω.
fn oscillator(kt: f64) -> MarchSystem {
    let mut system = MarchSystem {
        n: 1,
        mass: vec![1.0],
        damping: vec![0.02 * 2.0 * 3.0],
        stiffness: vec![4.0],
        force: vec![Harmonic::cosine(2.0, 0.0)],
        damping_force: Vec::new(),
        elements: vec![Element {
            name: "jenkins".into(),
            tangential: Direction {
                weights: vec![(0, 1.0)],
                prescribed: Harmonic::default(),
            },
            normal: None,
            params: FrictionParams {
                kt,
                kn: 0.0,
                mu: 1.0,
                n0: 0.5,
            },
            applies_normal: true,
        }],
        dof_names: vec!["q".into()],
        initial: InitialCondition::Rest,
        displacement_scale: 1.0,
    };
    system.displacement_scale = system.default_displacement_scale();
    system
}

fn jenkins() -> Model {
    Model {
        name: "Jenkins oscillator (1 DOF)",
        system: oscillator(5.0),
        settings: MarchSettings {
            omega: 1.0,
            periods: 10,
            steps_per_period: 300,
            ..MarchSettings::default()
        },
        rounds: 200,
        progress: false,
        schemes: schemes(),
    }
}

/// The oscillator with a stiff contact (k_t = 400 N/m: full-stick period 0.31 s) driven at
/// ω = 0.2 rad/s, a tenth of its free natural frequency, where inertia is negligible and the
/// quasi-static method applies (paper §5): Newmark at the step compatible with full stick
/// (0.15 𝕋_stick, 670 steps per period), the quasi-static method at 300 steps per period.
fn jenkins_quasi_static() -> Model {
    Model {
        name: "Jenkins oscillator, stiff contact, ω = 0.1 ω_n (1 DOF)",
        system: oscillator(400.0),
        settings: MarchSettings {
            omega: 0.2,
            periods: 5,
            steps_per_period: 300,
            ..MarchSettings::default()
        },
        rounds: 100,
        progress: false,
        schemes: schemes(),
    }
}

/// The schemes of the sector ROM: all, or standard Newmark and those named in
/// `NLROM_BENCH_SECTOR` (comma-separated, e.g. `piecewise-linear,quasi-static`; the adaptive
/// schemes take tens of minutes on a loaded machine).
fn sector_schemes() -> Vec<MarchScheme> {
    let names = std::env::var("NLROM_BENCH_SECTOR").unwrap_or_default();
    let named: Vec<&str> = names.split(',').map(str::trim).collect();
    let all = schemes();
    if !all.iter().any(|s| named.contains(&s.as_str())) {
        return all;
    }
    all.into_iter()
        .filter(|&s| s == MarchScheme::Newmark || named.contains(&s.as_str()))
        .collect()
}

fn sector() -> Model {
    let cm = case_march(&case("sector8_march.toml"), None, &mut |_| {}).expect("sector march");
    let name = "sector8 ROM, k = 0, shroud contact";
    eprintln!(
        "{name}: {} ROM coordinates, {} friction elements",
        cm.system.n,
        cm.system.elements.len()
    );
    sector_model(name, cm, 2, sector_schemes())
}

/// A sector march of `periods` periods with the paper's settings (Newmark at the full-stick step,
/// the quasi-static method at 300 steps per period), one round, `schemes` compared.
fn sector_model(
    name: &'static str,
    cm: CaseMarch,
    periods: usize,
    schemes: Vec<MarchScheme>,
) -> Model {
    Model {
        name,
        system: cm.system,
        settings: MarchSettings {
            periods,
            steps_per_period: 300,
            time_step: None,
            stop_at_steady: false,
            ..cm.settings
        },
        rounds: 1,
        progress: true,
        schemes,
    }
}

/// The reduced sector of `cases/sector8_march.toml` where the quasi-static method applies
/// (`NLROM_BENCH_SECTOR_QS=1`): 15 Hz, a tenth of the first k = 0 mode, with 10× the force (the
/// shroud slipping), as in `tests/march_sector.rs`; one period from the static equilibrium at
/// t = 0 (the quasi-static response there, at rest: no start-up transient), standard Newmark at
/// 0.15 𝕋_stick (about 475 000 steps and 3.6 GB of recorded history) and the quasi-static method
/// at 300 steps per period.
fn sector_quasi_static() -> Model {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/sector8_march.toml");
    let text = std::fs::read_to_string(&path).expect("bundled case");
    let text = text
        .replace("force_scale = 100.0", "force_scale = 1000.0")
        .replace("frequency_hz = 170.0", "frequency_hz = 15.0");
    let case = Case::from_str(&text, &path).expect("sector case at 15 Hz");
    let mut cm = case_march(&case, None, &mut |_| {}).expect("sector march");
    cm.system.initial = InitialCondition::Static;
    let name = "sector8 ROM, k = 0, 15 Hz, 10× the force, from static equilibrium";
    let schemes = vec![MarchScheme::Newmark, MarchScheme::QuasiStatic];
    sector_model(name, cm, 1, schemes)
}

/// The reduced sector of `cases/sector8_march.toml` with its contact stiffnesses k_t and k_n
/// (1e8 N/m) multiplied by `factor` (`NLROM_BENCH_SECTOR_STIFF=factor`), every scheme with the
/// settings of [`sector`]: where the contact springs set the top mode (k ×10 holds 48 % of its
/// strain energy, ×100 96 %; `tests/march_sector_stiffness.rs`), so that eq. 8 can lengthen the
/// step in the states out of stick.
fn sector_stiff(factor: f64) -> Model {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("cases/sector8_march.toml");
    let text = std::fs::read_to_string(&path).expect("bundled case");
    let stiff = format!("{:e}", 1.0e8 * factor);
    let text = text
        .replace("kt = 1.0e8", &format!("kt = {stiff}"))
        .replace("kn = 1.0e8", &format!("kn = {stiff}"));
    let case = Case::from_str(&text, &path).expect("stiff sector case");
    let cm = case_march(&case, None, &mut |_| {}).expect("sector march");
    let name = "sector8 ROM, k = 0, stiffer contact";
    eprintln!("{name}: k_t = k_n = {stiff} N/m (×{factor})");
    sector_model(name, cm, 2, schemes())
}

/// The reduced sector of `cases/sector8_march.toml` on its `m` lowest modes with every element
/// separated (`NLROM_BENCH_SECTOR_MODES=m`; [`MarchSystem::on_modes`]), every scheme with the
/// settings of [`sector`] but 10 interleaved rounds (a march takes about 0.1 s): on 20 modes the
/// contact sets the full-stick top mode (50.2 kHz against the basis's 17.3 kHz; every element
/// slipping lengthens the shortest period 1.42 times, `tests/march_sector_stiffness.rs`).
fn sector_modes(m: usize) -> Model {
    use nlrom::march::dense::generalized_symmetric_eigen;
    use nlrom::march::law::ContactState;
    let mut cm = case_march(&case("sector8_march.toml"), None, &mut |_| {}).expect("sector march");
    let open = vec![ContactState::Separated; cm.system.elements.len()];
    let k_open = cm.system.effective_stiffness(&open);
    let (_, phi) =
        generalized_symmetric_eigen(&k_open, &cm.system.mass, cm.system.n).expect("open modes");
    cm.system = cm.system.on_modes(&phi, m).expect("modal sector");
    eprintln!("sector8 ROM on {m} open modes, k = 0, shroud contact");
    Model {
        rounds: 10,
        progress: false,
        ..sector_model("sector8 ROM on its lowest open modes", cm, 2, schemes())
    }
}

/// The settings of `model` with `scheme`.
fn with_scheme(model: &Model, scheme: MarchScheme) -> MarchSettings {
    MarchSettings {
        scheme,
        ..model.settings.clone()
    }
}

/// CPU time (user + system, s) of this process so far (NaN where it cannot be measured).
fn cpu_seconds() -> f64 {
    process_cpu_seconds().unwrap_or(f64::NAN)
}

/// The outcome of each scheme and the minimum wall and CPU times (s) of one march per scheme
/// over the model's interleaved rounds (the first round's marches give the outcomes).
fn timing(model: &Model) -> (Vec<MarchOutcome>, Vec<f64>, Vec<f64>) {
    let settings: Vec<MarchSettings> = model
        .schemes
        .iter()
        .copied()
        .map(|s| with_scheme(model, s))
        .collect();
    let mut best = vec![f64::INFINITY; settings.len()];
    let mut best_cpu = vec![f64::INFINITY; settings.len()];
    let mut outs = Vec::new();
    for round in 0..model.rounds {
        for ((s, b), c) in settings.iter().zip(&mut best).zip(&mut best_cpu) {
            let (t0, c0) = (Instant::now(), cpu_seconds());
            let out = march(&model.system, s).expect("march");
            let (wall, cpu) = (t0.elapsed().as_secs_f64(), cpu_seconds() - c0);
            *b = b.min(wall);
            *c = c.min(cpu);
            if model.progress {
                let h = &out.history;
                let not_stick = h.state.iter().filter(|&&c| c != 1).count();
                eprintln!(
                    "  round {round}: {} wall {wall:.2} s, CPU {cpu:.2} s, {} factorisations, {:.1} elements out of stick per instant",
                    s.scheme,
                    out.factorisations,
                    not_stick as f64 / h.len() as f64
                );
            }
            if round == 0 {
                outs.push(out);
            }
        }
    }
    (outs, best, best_cpu)
}

/// Largest |f(t) − f_ref(t)| over the last period of `out` (both components of every element,
/// the reference interpolated linearly in time), relative to the largest reference force there.
fn force_difference(out: &MarchOutcome, reference: &MarchOutcome) -> f64 {
    let (h, r) = (&out.history, &reference.history);
    let ne2 = h.force.len() / h.len();
    let np = out.periods.len();
    let t0 = h.time[if np >= 2 {
        out.periods[np - 2].end_index
    } else {
        0
    }];
    let (mut worst, mut scale) = (0.0f64, 0.0f64);
    for k in 0..h.len() {
        let t = h.time[k];
        if t < t0 {
            continue;
        }
        let j = r.time.partition_point(|&x| x <= t).clamp(1, r.len() - 1);
        let (ta, tb) = (r.time[j - 1], r.time[j]);
        let w = ((t - ta) / (tb - ta)).clamp(0.0, 1.0);
        for c in 0..ne2 {
            let f_ref = (1.0 - w) * r.force[(j - 1) * ne2 + c] + w * r.force[j * ne2 + c];
            worst = worst.max((h.force[k * ne2 + c] - f_ref).abs());
            scale = scale.max(f_ref.abs());
        }
    }
    worst / scale.max(f64::MIN_POSITIVE)
}

/// Prints the comparison table of one model.
fn table(model: &Model) {
    let (outs, times, cpus) = timing(model);
    let (r_out, r_time, r_cpu) = (&outs[0], times[0], cpus[0]);
    eprintln!("\n{} — {} period(s)", model.name, model.settings.periods);
    eprintln!("scheme | steps (ratio) | iterations (ratio) | one-iteration steps | factorisations | wall ms (ratio) | CPU ms (ratio) | force difference");
    for (((s, out), wall), cpu) in model.schemes.iter().zip(&outs).zip(&times).zip(&cpus) {
        eprintln!(
            "{s} | {} ({:.3}) | {} ({:.3}) | {:.1} % | {} | {:.3} ({:.3}) | {:.3} ({:.3}) | {:.2e}",
            out.steps,
            out.steps as f64 / r_out.steps as f64,
            out.total_iterations,
            out.total_iterations as f64 / r_out.total_iterations as f64,
            100.0 * out.single_iteration_fraction(),
            out.factorisations,
            wall * 1e3,
            wall / r_time,
            cpu * 1e3,
            cpu / r_cpu,
            force_difference(out, r_out),
        );
    }
}

/// The products of one step in isolation, on the sector's matrices at its Newmark step
/// (`NLROM_BENCH_PASS=1`): the standard step's pass over P = M/(βΔτ²) + γC/(βΔτ) and C (P q*,
/// C v*) and the piecewise-linear step's pass over A_stick⁻¹P and A_stick⁻¹C, the same number of
/// entries, each repeated back to back; CPU time per pass, minimum of three.
fn product_passes() {
    use nlrom::march::dense::{dot, inverse, product};
    use nlrom::march::law::ContactState;
    let model = sector();
    let sys = &model.system;
    let n = sys.n;
    let period = 2.0 * std::f64::consts::PI / model.settings.omega;
    let t_stick = sys
        .shortest_period(&sys.stick_states())
        .expect("full-stick period");
    let dt = period / (period / (0.15 * t_stick)).ceil();
    let (cm, cc) = (4.0 / (dt * dt), 2.0 / dt);
    let p: Vec<f64> = sys
        .mass
        .iter()
        .zip(&sys.damping)
        .map(|(m, c)| cm * m + cc * c)
        .collect();
    let mut a: Vec<f64> = p.iter().zip(&sys.stiffness).map(|(x, k)| x + k).collect();
    for e in &sys.elements {
        e.add_stiffness(ContactState::Stick, &mut a, n);
    }
    let stick = inverse(&a, n).expect("all-stick step matrix");
    let (hp, hc) = (product(&stick, &p, n), product(&stick, &sys.damping, n));
    let q: Vec<f64> = (0..n).map(|i| 1e-6 * (i as f64).cos()).collect();
    let v: Vec<f64> = (0..n).map(|i| 1e-3 * (i as f64).sin()).collect();
    let mut y = vec![0.0; n];
    let passes = 20_000;
    for (name, x, z) in [
        ("P, C", &p, &sys.damping),
        ("A_stick⁻¹P, A_stick⁻¹C", &hp, &hc),
    ] {
        let mut best = f64::INFINITY;
        for _ in 0..3 {
            let c0 = cpu_seconds();
            for _ in 0..passes {
                for (i, yi) in y.iter_mut().enumerate() {
                    *yi = dot(&x[i * n..(i + 1) * n], &q) - dot(&z[i * n..(i + 1) * n], &v);
                }
            }
            best = best.min((cpu_seconds() - c0) / passes as f64);
        }
        eprintln!(
            "pass over {name} (n = {n}, Δτ = {dt:.4e} s): {:.2} µs CPU ({:.3e})",
            best * 1e6,
            y[1]
        );
    }
}

fn bench(c: &mut Criterion) {
    if std::env::var_os("NLROM_BENCH_PASS").is_some() {
        product_passes();
    }
    let (damper, jenkins) = (damper(), jenkins());
    table(&damper);
    table(&jenkins);
    table(&jenkins_quasi_static());
    if std::env::var_os("NLROM_BENCH_SECTOR").is_some() {
        table(&sector());
    }
    if std::env::var_os("NLROM_BENCH_SECTOR_QS").is_some() {
        table(&sector_quasi_static());
    }
    if let Ok(factors) = std::env::var("NLROM_BENCH_SECTOR_STIFF") {
        for factor in factors.split(',') {
            let factor = factor
                .trim()
                .parse()
                .expect("NLROM_BENCH_SECTOR_STIFF: numbers");
            table(&sector_stiff(factor));
        }
    }
    if let Ok(modes) = std::env::var("NLROM_BENCH_SECTOR_MODES") {
        let m = modes
            .trim()
            .parse()
            .expect("NLROM_BENCH_SECTOR_MODES: a number of modes");
        table(&sector_modes(m));
    }
    for (group, model) in [
        ("damper_200hz_one_period", &damper),
        ("jenkins_oscillator_ten_periods", &jenkins),
    ] {
        let mut g = c.benchmark_group(group);
        g.sample_size(20);
        g.measurement_time(std::time::Duration::from_secs(2));
        for scheme in schemes() {
            let s = with_scheme(model, scheme);
            g.bench_function(scheme.as_str(), |b| {
                b.iter(|| march(&model.system, &s).expect("march"))
            });
        }
        g.finish();
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
