//! A single-DOF oscillator with a Jenkins friction element to the ground, traced with the
//! library API: linear model → friction element → harmonic balance system → continuation.
//!
//!     cargo run --release --example jenkins_oscillator
//!
//! m q̈ + c q̇ + k q + f_J(q) = F cos ωt with m = k = 1, c = 0.1, F = 0.5 and a Jenkins element
//! (stiffness k_t = 1 in series with a slider of slip force F_s = μ n0 = 0.3). Its one-harmonic
//! balance has a closed form (docs/theory.md, "The friction contact element"): with
//! cos β = 1 − 2F_s/(k_t A), a₁ = (k_t A/π)(β − ½ sin 2β) and |b₁| = (4F_s/π)(1 − F_s/(k_t A)),
//! ((k + a₁/A − mω²)² + (cω + |b₁|/A)²) A² = F². The example prints the traced curve and, for each
//! point, that relation's relative residual: zero to round-off while the element sticks, and
//! below about 1e-5 in slip, the error of the 1024-sample time discretisation of the AFT.

use faer::Mat;
use nlrom::case::WeightedDofs;
use nlrom::contact::grounded::{DofElement, DofElements};
use nlrom::contact::law::ContactParams;
use nlrom::continuation::ContinuationOptions;
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::frf::frequency_response;
use nlrom::hbm::{HbmSystem, LinearModel, ResponseOptions};

fn main() -> nlrom::Result<()> {
    let (m, k, c, force) = (1.0, 1.0, 0.1, 0.5);
    let (kt, slip_force) = (1.0, 0.3);
    let harmonics = 1;

    // The linear part: 1×1 matrices K, M, C, the force on row 0, row 0 nonlinear and reported.
    let one = |v: f64| Mat::from_fn(1, 1, |_, _| v);
    let (km, mm, cm) = (one(k), one(m), one(c));
    let linear = LinearModel::from_real(
        km.as_ref(),
        mm.as_ref(),
        Some(cm.as_ref()),
        &[force],
        vec![0],
        vec![0],
        harmonics,
    )?;

    // The friction element on u_t = 1·q[0]: k_t, k_n = 0 (constant normal load), μ = 1, n0 = F_s.
    let element = DofElement {
        tangential: WeightedDofs {
            dofs: vec![0],
            weights: vec![1.0],
        },
        normal: None,
        params: ContactParams::new(kt, 0.0, 1.0, slip_force, "jenkins")?,
    };
    let friction = DofElements::new(vec![element], 1)?;

    // Harmonic balance with H harmonics and 1024 AFT samples, traced from 0.5 to 2 rad/s.
    let layout = HarmonicLayout::new(harmonics, 1024)?;
    let system = HbmSystem::new(layout, &linear, &friction)?;
    let options = ContinuationOptions::new(0.5, 2.0, 0.02);
    let frf = frequency_response(&system, &options, &ResponseOptions::default(), &mut |_| {})?;

    println!("{} points ({:?})", frf.points.len(), frf.end);
    println!("   ω (rad/s)   amplitude A (m)   closed-form residual");
    let mut peak = (0.0, 0.0);
    for p in &frf.points {
        let a = p.response.amplitude[0];
        if a > peak.1 {
            peak = (p.omega, a);
        }
        println!(
            "{:12.6} {:17.6} {:22.1e}",
            p.omega,
            a,
            closed_form_residual(p.omega, a, m, k, c, kt, slip_force, force)
        );
    }
    println!("resonance: A = {:.6} m at ω = {:.6} rad/s", peak.1, peak.0);
    Ok(())
}

/// ((k + a₁/A − mω²)² + (cω + |b₁|/A)²) A²/F² − 1 for the Jenkins oscillator at amplitude A.
#[allow(clippy::too_many_arguments)]
fn closed_form_residual(
    omega: f64,
    a: f64,
    m: f64,
    k: f64,
    c: f64,
    kt: f64,
    fs: f64,
    force: f64,
) -> f64 {
    let (a1, b1) = if kt * a <= fs {
        (kt * a, 0.0) // stuck: a linear spring
    } else {
        let beta = (1.0 - 2.0 * fs / (kt * a)).acos();
        (
            kt * a / std::f64::consts::PI * (beta - 0.5 * (2.0 * beta).sin()),
            4.0 * fs / std::f64::consts::PI * (1.0 - fs / (kt * a)),
        )
    };
    let re = k + a1 / a - m * omega * omega;
    let im = c * omega + b1 / a;
    (re * re + im * im) * a * a / (force * force) - 1.0
}
