//! Generated friction cases for the robustness corpus of the harmonic balance continuation
//! (`tests/hbm_robustness.rs` runs a fast subset, `benches/robustness_corpus.rs` the full set):
//! chains of 1–6 unit masses with Jenkins elements to the ground and between masses, and
//! tangential–normal oscillator pairs whose element has normal load variation and separates.
//! Every parameter is drawn by a fixed linear congruential generator, so a case number always
//! means the same case.
#![allow(dead_code)]

#[path = "../support/random.rs"]
mod random;

use faer::Mat;
pub use nlrom::case::Evaluation;
use nlrom::case::WeightedDofs;
use nlrom::contact::grounded::{DofElement, DofElements};
use nlrom::contact::law::ContactParams;
use nlrom::continuation::{ContinuationOptions, PathEnd};
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::frf::{frequency_response, Frf};
use nlrom::hbm::{HbmSystem, LinearModel, ResponseOptions};
use random::Lcg;

/// One generated case: a linear model, its friction elements and the continuation settings.
pub struct Case {
    pub label: String,
    pub model: LinearModel,
    pub force: DofElements,
    pub layout: HarmonicLayout,
    pub options: ContinuationOptions,
}

/// How one case ended.
pub struct Outcome {
    pub reached_end: bool,
    pub end: String,
    pub points: usize,
    pub iterations: usize,
    pub worst_residual: f64,
    pub seconds: f64,
    /// Jumps of the sweep (the path left its range on the start side and went on beyond it).
    pub jumps: usize,
    /// The longest stretch of frequency a jump left untraced, |to − from| (rad/s; 0 without
    /// jumps).
    pub largest_gap: f64,
}

fn jenkins(dofs: Vec<usize>, weights: Vec<f64>, params: ContactParams) -> DofElement {
    DofElement {
        tangential: WeightedDofs { dofs, weights },
        normal: None,
        params,
    }
}

/// Case number `i` of the corpus; `max_samples` caps N_t (the fast subset uses small ones).
pub fn case(i: u64, max_samples: usize) -> Case {
    let mut r = Lcg(0x9e3779b97f4a7c15 ^ (i.wrapping_mul(0x2545f4914f6cdd1d)));
    for _ in 0..3 {
        r.next();
    }
    let h = r.pick(&[1usize, 3, 5, 7, 15]);
    let samples = r
        .pick(&[2 * h + 2, 64, 256, 1024, 4096])
        .min(max_samples)
        .max(2 * h + 2);
    let zeta = r.log_uniform(0.001, 0.05);
    let ratio = r.log_uniform(0.01, 100.0);
    let step = r.pick(&[0.005, 0.02, 0.08]);
    let layout = HarmonicLayout::new(h, samples).expect("valid layout");
    if i % 4 == 3 {
        separating_pair(i, &mut r, layout, zeta, ratio, step)
    } else {
        chain(i, &mut r, layout, zeta, ratio, step)
    }
}

/// The case with every friction element evaluated as `evaluation` (the exact continuous-time
/// cycle with [`Evaluation::Analytic`]).
pub fn evaluated(case: Case, evaluation: Evaluation) -> Case {
    let n = case.force.evaluations().len();
    Case {
        force: case
            .force
            .with_evaluations(vec![evaluation; n])
            .expect("one evaluation per element"),
        ..case
    }
}

/// A chain ground –k– m1 –k– … –k– mn (–k– ground with probability ½), unit masses and springs,
/// stiffness-proportional damping with ratio ζ at 1 rad/s, a Jenkins element from m1 to the
/// ground and one between neighbours with probability ½, slip force 1 N, excited at the last mass
/// by `ratio` × the slip force.
fn chain(i: u64, r: &mut Lcg, layout: HarmonicLayout, zeta: f64, ratio: f64, step: f64) -> Case {
    let n = 1 + (r.next() * 6.0) as usize;
    let n = n.min(6);
    let grounded_end = r.next() < 0.5;
    let k = Mat::from_fn(n, n, |a, b| {
        if a == b {
            let right = if a + 1 < n || grounded_end { 1.0 } else { 0.0 };
            1.0 + right
        } else if a.abs_diff(b) == 1 {
            -1.0
        } else {
            0.0
        }
    });
    let m = Mat::from_fn(n, n, |a, b| if a == b { 1.0 } else { 0.0 });
    let c = &k * (2.0 * zeta);
    let mut force = vec![0.0; n];
    force[n - 1] = ratio;
    let kt = r.log_uniform(1.0, 40.0);
    let params = ContactParams::new(kt, 0.0, 1.0, 1.0, "corpus").expect("valid parameters");
    let mut elements = vec![jenkins(vec![0], vec![1.0], params)];
    for a in 0..n.saturating_sub(1) {
        if r.next() < 0.5 {
            elements.push(jenkins(vec![a, a + 1], vec![-1.0, 1.0], params));
        }
    }
    let dofs: Vec<usize> = (0..n).collect();
    let model = LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        Some(c.as_ref()),
        &force,
        dofs.clone(),
        dofs,
        layout.harmonics,
    )
    .expect("valid model");
    let count = elements.len();
    Case {
        label: format!(
            "#{i} chain n={n} H={} Nt={} kt={kt:.2} elements={count} F/Fs={ratio:.3} zeta={zeta:.4} step={step}",
            layout.harmonics, layout.time_samples
        ),
        model,
        force: DofElements::new(elements, n).expect("valid elements"),
        layout,
        options: ContinuationOptions::new(0.2, 2.5, step),
    }
}

/// Two unit oscillators, DOF 0 tangential and DOF 1 normal at one element with normal stiffness
/// k_n and preload n0 = 1 N (μ = 0.5): the normal force varies and the contact separates when
/// k_n |v| exceeds n0. Both DOFs are excited.
fn separating_pair(
    i: u64,
    r: &mut Lcg,
    layout: HarmonicLayout,
    zeta: f64,
    ratio: f64,
    step: f64,
) -> Case {
    let kt = r.log_uniform(1.0, 20.0);
    let kn = r.log_uniform(1.0, 20.0);
    let normal_ratio = r.log_uniform(0.1, 3.0);
    let k = Mat::from_fn(2, 2, |a, b| if a == b { 1.0 } else { 0.0 });
    let m = k.clone();
    let c = &k * (2.0 * zeta);
    let force = [0.5 * ratio, normal_ratio];
    let params = ContactParams::new(kt, kn, 0.5, 1.0, "corpus").expect("valid parameters");
    let element = DofElement {
        tangential: WeightedDofs {
            dofs: vec![0],
            weights: vec![1.0],
        },
        normal: Some(WeightedDofs {
            dofs: vec![1],
            weights: vec![1.0],
        }),
        params,
    };
    let model = LinearModel::from_real(
        k.as_ref(),
        m.as_ref(),
        Some(c.as_ref()),
        &force,
        vec![0, 1],
        vec![0, 1],
        layout.harmonics,
    )
    .expect("valid model");
    Case {
        label: format!(
            "#{i} pair H={} Nt={} kt={kt:.2} kn={kn:.2} Ft/Fs={ratio:.3} Fn/n0={normal_ratio:.3} zeta={zeta:.4} step={step}",
            layout.harmonics, layout.time_samples
        ),
        model,
        force: DofElements::new(vec![element], 2).expect("valid element"),
        layout,
        options: ContinuationOptions::new(0.2, 2.5, step),
    }
}

/// The case's frequency response (the path, or why its start failed).
pub fn trace(case: &Case) -> nlrom::error::Result<Frf<Vec<f64>>> {
    let system = HbmSystem::new(case.layout, &case.model, &case.force).expect("valid system");
    frequency_response(
        &system,
        &case.options,
        &ResponseOptions::default(),
        &mut |_| {},
    )
}

/// Traces the case's frequency response.
pub fn run(case: &Case) -> Outcome {
    let t0 = std::time::Instant::now();
    let frf = trace(case);
    let seconds = t0.elapsed().as_secs_f64();
    match frf {
        Ok(frf) => Outcome {
            reached_end: frf.end == PathEnd::ReachedEnd,
            end: format!("{:?}", frf.end),
            points: frf.points.len(),
            iterations: frf.points.iter().map(|p| p.iterations).sum(),
            worst_residual: frf.points.iter().map(|p| p.residual).fold(0.0, f64::max),
            seconds,
            jumps: frf.jumps.len(),
            largest_gap: frf
                .jumps
                .iter()
                .map(|j| (j.to - j.from).abs())
                .fold(0.0, f64::max),
        },
        Err(e) => Outcome {
            reached_end: false,
            end: e.to_string(),
            points: 0,
            iterations: 0,
            worst_residual: f64::NAN,
            seconds,
            jumps: 0,
            largest_gap: 0.0,
        },
    }
}
