//! A travelling wave marched to steady state against the harmonic balance of the same case.
//!
//!     cargo run --release --example travelling_microslip -- CASE.toml HZ[,HZ...] [PERIODS]
//!
//! CASE is a sector case with `[cyclic]`, `[excitation] engine_order` m, `[[contact]]` and
//! `[march]` (e.g. `cases/sector8_travelling.toml`). For each frequency (Hz):
//! - the march: the real model of the sectors of one wave period
//!   (`nlrom::problem::travelling_wave`), the case's scheme and steps per period, from rest until
//!   the end-of-period state repeats within the case's `steady_tolerance` (at most PERIODS
//!   periods, default the case's `periods`); harmonic 1 of sector 0's output DOFs over the last
//!   period (trapezoidal rule, `docs/conventions.md` §4);
//! - the harmonic balance of the case (H and N_t of `[harmonic_balance]`, the same ROM): the
//!   curve of `[continuation]` (its peak printed: the vertex of the parabola through the largest
//!   point and its neighbours), then Newton (tolerance 1e-10) at the march's ω from the nearest
//!   point of the curve; harmonic 1 of the same DOFs recovered from the condensed solution.
//!
//! With three frequencies or more the march's peak is printed too (the same parabola).
//!
//! Printed per frequency: the largest first-harmonic amplitude over the output DOFs (m) of each,
//! their relative difference, the complex difference max_i |Q_march,i − Q_HB,i| / max_i |Q_HB,i|,
//! the periods to steady state, the steps, the march's CPU seconds per step and its state
//! iterations per step.
use std::f64::consts::PI;
use std::path::Path;
use std::time::Instant;

use faer::c64;
use nlrom::case::Case;
use nlrom::hbm::frf::frequency_response;
use nlrom::hbm::response::ResponseOptions;
use nlrom::hbm::{FrequencyPath, HbmSystem};
use nlrom::interface::build_interfaces;
use nlrom::march::march;
use nlrom::model;
use nlrom::nonlinear::{solve_fixed, NewtonOptions};
use nlrom::problem::march_case::case_march;
use nlrom::problem::sector::SectorProblem;
use nlrom::problem::settings::case_continuation;
use nlrom::reduction::reduce;

/// CPU time of this process (s), user + system.
fn cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    let fields: Vec<&str> = stat
        .rsplit(')')
        .next()
        .unwrap_or("")
        .split_whitespace()
        .collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|s| s.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    (ticks(11) + ticks(12)) / 100.0
}

fn main() -> nlrom::error::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: travelling_microslip CASE.toml HZ[,HZ...] [PERIODS]");
        std::process::exit(2);
    }
    let case = Case::load(Path::new(&args[1]))?;
    let freqs: Vec<f64> = args[2]
        .split(',')
        .map(|s| s.parse().expect("frequency (Hz)"))
        .collect();
    let mut log = |l: &str| eprintln!("{l}");
    let mut cm = case_march(&case, None, &mut log)?;
    if let Some(p) = args.get(3) {
        cm.settings.periods = p.parse().expect("periods");
    }
    cm.settings.stop_at_steady = true;

    // the harmonic balance on a ROM of every harmonic index
    let sm = model::build(&case, &mut log)?;
    let mut all = case.clone();
    all.harmonic_balance.harmonics = all.cyclic.as_ref().map_or(1, |c| c.sectors - 1);
    let rom = reduce(&all, &sm, &mut log)?;
    let mesh = sm.mesh.as_ref().expect("a mesh case");
    let interfaces = build_interfaces(&case, mesh, rom.cyclic.as_ref())?;
    let problem = SectorProblem::build(&case, &rom, mesh, &interfaces)?;
    let system = HbmSystem::new(problem.layout, &problem.linear, &problem.contact)?;
    let path = FrequencyPath {
        system: &system,
        level: 1.0,
    };
    let opts = NewtonOptions {
        tolerance: 1e-10,
        max_iterations: 60,
        ..NewtonOptions::default()
    };
    let nd = problem.linear.n_condensed();
    let frf = frequency_response(
        &system,
        &case_continuation(&case)?,
        &ResponseOptions::default(),
        &mut |_| {},
    )?;
    let curve: Vec<(f64, f64)> = frf
        .points
        .iter()
        .map(|p| {
            let a = p.response.amplitude.iter().copied().fold(0.0, f64::max);
            (p.omega / (2.0 * PI), a)
        })
        .collect();
    if let Some((f, a)) = peak(&curve) {
        println!(
            "harmonic balance: {} points, end {:?}, peak of max|Q1| {a:.6e} m at {f:.3} Hz",
            curve.len(),
            frf.end
        );
    }

    println!(
        "{} coordinates, {} elements, {} steps per period, scheme {}, H = {}",
        cm.system.n,
        cm.system.elements.len(),
        cm.settings.steps_per_period,
        cm.settings.scheme,
        case.harmonic_balance.harmonics
    );
    let mut marched_curve = Vec::new();
    println!("Hz | march max|Q1| (m) | HB max|Q1| (m) | amplitude diff | complex diff | steady period | steps | CPU s/step | iterations/step");
    for hz in freqs {
        let omega = 2.0 * PI * hz;
        // Newton at ω from the nearest point of the traced curve
        let near = frf
            .points
            .iter()
            .min_by(|a, b| (a.omega - omega).abs().total_cmp(&(b.omega - omega).abs()))
            .expect("a traced point");
        let x = solve_fixed(&path, &near.q, omega, &near.state, &opts)
            .map_err(|e| nlrom::error::Error::Compute(format!("HB at {hz} Hz: {e:?}")))?
            .x;
        let q1: Vec<c64> = (0..nd)
            .map(|i| {
                let r = problem.layout.cos_index(1, i, nd);
                c64::new(x[r], x[r + 1])
            })
            .collect();
        let hb = problem.linear.condense(1, omega)?.recover(&q1);

        cm.settings.omega = omega;
        cm.settings.time_step = Some(1.0 / (hz * cm.settings.steps_per_period as f64));
        let (cpu0, wall0) = (cpu_seconds(), Instant::now());
        let out = march(&cm.system, &cm.settings)?;
        let cpu = cpu_seconds() - cpu0;
        let marched: Vec<c64> = cm
            .response
            .iter()
            .map(|&d| {
                let (re, im) = out.harmonics[d][1];
                c64::new(re, im)
            })
            .collect();
        let amp = |v: &[c64]| v.iter().map(|z| z.norm()).fold(0.0, f64::max);
        let (am, ah) = (amp(&marched), amp(&hb));
        let diff = marched
            .iter()
            .zip(&hb)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max)
            / ah;
        println!(
            "{hz} | {am:.6e} | {ah:.6e} | {:+.2e} | {diff:.2e} | {} | {} | {:.4} | {:.2}   (wall {:.1} s)",
            am / ah - 1.0,
            out.steady_period
                .map_or("not reached".to_string(), |p| p.to_string()),
            out.steps,
            cpu / out.steps as f64,
            out.total_iterations as f64 / out.steps as f64,
            wall0.elapsed().as_secs_f64()
        );
        marched_curve.push((hz, am));
    }
    if marched_curve.len() >= 3 {
        if let Some((f, a)) = peak(&marched_curve) {
            println!("march: peak of max|Q1| {a:.6e} m at {f:.3} Hz (parabola through the three largest)");
        }
    }
    Ok(())
}

/// The vertex (frequency, amplitude) of the parabola through the largest sample of `curve`
/// (frequency, amplitude) and its two neighbours in frequency.
fn peak(curve: &[(f64, f64)]) -> Option<(f64, f64)> {
    let mut c = curve.to_vec();
    c.sort_by(|a, b| a.0.total_cmp(&b.0));
    let i = (0..c.len()).max_by(|&a, &b| c[a].1.total_cmp(&c[b].1))?;
    let i = i.clamp(1, c.len().checked_sub(2)?);
    let ((x0, y0), (x1, y1), (x2, y2)) = (c[i - 1], c[i], c[i + 1]);
    // Newton's divided differences: y = y0 + d1 (x − x0) + d2 (x − x0)(x − x1)
    let d1 = (y1 - y0) / (x1 - x0);
    let d2 = ((y2 - y1) / (x2 - x1) - d1) / (x2 - x0);
    if d2 >= 0.0 {
        return Some(c[i]);
    }
    let x = 0.5 * (x0 + x1) - d1 / (2.0 * d2);
    Some((x, y0 + d1 * (x - x0) + d2 * (x - x0) * (x - x1)))
}
