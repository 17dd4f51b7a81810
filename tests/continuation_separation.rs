//! Continuation into contact separation (microslip paper, Cigeroglu, An & Menq 2007, §4.2: low preload + normal
//! load variation → separation → softening): two oscillators, x tangential and y normal at one
//! friction element (k_t = 1, k_n = 3, μ = 0.3, n0 = 0.2), x slipping, the y resonance bent by
//! separation. The separation onset is a sharp fold; before the corrector's step check, Newton
//! on the pseudo-arc-length hyperplane jumped there from the lower branch (|Y1| = 0.0235) to the
//! upper one (|Y1| = 0.114) in one step, skipping the segment in between. Asserted: no jump
//! between consecutive points, every point satisfies the residual.
//!
//! With the largest step 0.02 rad/s used here the corrector fails at the onset (ω ≈ 1.5633, a fold
//! sharper than 90° within a few AFT samples) even at the minimum step; the path passes it on
//! the orientation of the tangent (the sign of det [J; tᵀ]) and follows the unstable branch back
//! down in ω. The second test traces both turning points of a damped variant.

mod support;

use nlrom::contact::grounded::DofElements;
use nlrom::continuation::{trace, ContinuationOptions, Path, PathEnd};
use nlrom::harmonics::HarmonicLayout;
use nlrom::hbm::response::output_response;
use nlrom::hbm::{FrequencyPath, HbmSystem, LinearModel, ResponseOptions};
use nlrom::nonlinear::{norm, solve_dense, Linearization, ParameterSystem};
use nlrom::Result;
use support::hbm::{tangential_normal_element, two_oscillators};

fn model(h: usize) -> LinearModel {
    two_oscillators(0.005, [0.05, 0.03], h)
}

fn contact() -> DofElements {
    tangential_normal_element(0.2).unwrap()
}

/// The frequency path of `system` at the nominal excitation traced from `range.0` to `range.1`
/// rad/s with the initial and largest step (rad/s) `steps`.
fn traced<'s, 'a>(
    system: &'s HbmSystem<'a, DofElements>,
    range: (f64, f64),
    steps: (f64, f64),
) -> (FrequencyPath<'s, 'a, DofElements>, Path<Vec<f64>>) {
    let fp = FrequencyPath { system, level: 1.0 };
    let mut opts = ContinuationOptions::new(range.0, range.1, steps.0);
    opts.max_step = Some(steps.1);
    opts.max_points = 3000;
    let path = trace(&fp, &opts, &mut |_| {}).unwrap();
    (fp, path)
}

#[test]
fn separation_onset_is_followed_without_a_jump() {
    let lin = model(5);
    let force = contact();
    let layout = HarmonicLayout::new(5, 256).unwrap();
    let system = HbmSystem::new(layout, &lin, &force).unwrap();
    let (fp, path) = traced(&system, (0.8, 2.4), (0.01, 0.02));
    let amplitude: Vec<f64> = path
        .points
        .iter()
        .map(|p| {
            output_response(&system, &p.x, p.parameter, 1.0, &ResponseOptions::default())
                .unwrap()
                .amplitude[1]
        })
        .collect();
    // the path reaches the separation onset (|Y1| ≈ 0.0235 at ω ≈ 1.562) ...
    assert!(amplitude.iter().any(|&a| a > 0.025), "{amplitude:?}");
    // ... passes it (the onset is the largest ω before the unstable branch) and follows the
    // unstable branch back down in ω through the amplitudes between the lower and the upper
    // branch — which a jump would skip
    let onset = path
        .points
        .iter()
        .zip(&amplitude)
        .take_while(|(_, &a)| a < 0.03)
        .map(|(p, _)| p.parameter)
        .fold(f64::NEG_INFINITY, f64::max);
    assert!((onset - 1.5633).abs() < 1e-3, "onset at {onset}");
    let unstable = path
        .points
        .iter()
        .zip(&amplitude)
        .filter(|(p, &a)| p.parameter < 1.5 && p.parameter > 1.4 && a > 0.05 && a < 0.1)
        .count();
    assert!(
        unstable >= 2,
        "{unstable} points on the unstable branch at 1.4–1.5 rad/s"
    );
    assert!(
        matches!(path.end, PathEnd::ReachedEnd | PathEnd::Failed(_)),
        "{:?}",
        path.end
    );
    // no jump: from one point to the next ω moves by at most the largest step, and up to the
    // middle of the unstable branch (|Y1| < 0.07) |Y1| by at most 0.02 — the jump from the
    // lower to the upper branch this guards against was 0.09; along the unstable branch the
    // changes grow smoothly as it steepens (0.0075, 0.009, 0.0113, 0.015, 0.021 per largest
    // step from ω = 1.52 down to 1.44). Near the peak (|Y1| ≈ 4.3) a step of the path moves
    // |Y1| by up to 0.05.
    for (i, w) in path.points.windows(2).enumerate() {
        assert!(
            (w[1].parameter - w[0].parameter).abs() <= 0.02 + 1e-12,
            "ω jumps from {} to {}",
            w[0].parameter,
            w[1].parameter
        );
        if amplitude[..=i].iter().all(|&a| a < 0.07) {
            assert!(
                (amplitude[i + 1] - amplitude[i]).abs() <= 0.02,
                "|Y1| jumps from {} to {} at ω {}",
                amplitude[i],
                amplitude[i + 1],
                w[0].parameter
            );
        }
    }
    // every point is a solution (from the previous point's memory, as the path computed it)
    for w in path.points.windows(2) {
        let mut lin = Linearization::zeros(fp.dim());
        fp.evaluate(&w[1].x, w[1].parameter, &w[0].state, &mut lin)
            .unwrap();
        assert!(norm(&lin.residual) <= 1e-7 * fp.residual_scale());
    }
}

/// |Y1|, the first-harmonic amplitude of the normal DOF (DOF 1 of 2) in the HB unknowns x.
fn normal_amplitude(layout: &HarmonicLayout, x: &[f64]) -> f64 {
    let c = layout.cos_index(1, 1, 2);
    x[c].hypot(x[c + 1])
}

/// Fixed-amplitude HB solution (the independent fold check): Newton on r(x, ω) = 0 and
/// (|Y1|² − a²)/a = 0 for (x, ω) from `guess`, the friction memory starting from `state`.
/// Returns the solution and its end state.
fn solve_at_amplitude<S: ParameterSystem>(
    system: &S,
    layout: &HarmonicLayout,
    a: f64,
    guess: (&[f64], f64),
    state: &S::State,
) -> Result<(Vec<f64>, f64, S::State)> {
    let n = system.dim();
    let c = layout.cos_index(1, 1, 2);
    let (mut x, mut omega) = (guess.0.to_vec(), guess.1);
    let scale = system.residual_scale();
    for _ in 0..40 {
        let mut lin = Linearization::zeros(n);
        let end = system.evaluate(&x, omega, state, &mut lin)?;
        let g = (x[c] * x[c] + x[c + 1] * x[c + 1] - a * a) / a;
        if norm(&lin.residual) <= 1e-10 * scale && g.abs() <= 1e-12 {
            return Ok((x, omega, end));
        }
        let m = faer::Mat::from_fn(n + 1, n + 1, |i, j| match (i < n, j < n) {
            (true, true) => lin.jacobian[(i, j)],
            (true, false) => lin.d_parameter[i],
            (false, true) if j == c || j == c + 1 => 2.0 * x[j] / a,
            _ => 0.0,
        });
        let mut rhs: Vec<f64> = lin.residual.iter().map(|r| -r).collect();
        rhs.push(-g);
        let dz = solve_dense(&m, &rhs).ok_or_else(|| {
            nlrom::Error::Compute(format!("singular fixed-amplitude system at a = {a}"))
        })?;
        x.iter_mut().zip(&dz).for_each(|(v, d)| *v += d);
        omega += dz[n];
    }
    Err(nlrom::Error::Compute(format!(
        "fixed-amplitude Newton did not converge at a = {a}"
    )))
}

/// Both turning points of a softening-by-separation resonance (friction with separation produces a
/// fold; microslip paper, Cigeroglu, An & Menq 2007, §4.2 and Fig. 13: low preload, normal
/// load variation → separation → softening, two jumps with an unstable branch between them).
///
/// Case: the two oscillators with damping c = 0.1 N·s/m, forces 0.05 N (tangential) and
/// 0.015 N (normal) on harmonic 1, the friction element of the first test (k_t = 1, k_n = 3 N/m,
/// μ = 0.3, n0 = 0.2 N; x slips as the normal load drops), H = 5, N_t = 256, ω 1.3 → 2.2 rad/s,
/// steps ≤ 0.005 rad/s. Measured: the lower branch turns at the separation onset
/// (ω_A ≈ 1.7760, |Y1| ≈ 0.0186 m), ω decreases along the unstable branch to the peak's fold
/// (ω_B ≈ 1.5268, |Y1| ≈ 0.091 m), then rises along the upper branch to the end.
///
/// Asserted: the path reaches the end; ω_A − ω_B > 0.2 rad/s; between the turning points ω
/// never rises by more than 5e-5 rad/s from one point to the next (the AFT's sample switching
/// makes zigzags of ≈ 2e-5 rad/s where the path is vertical) and falls overall; consecutive
/// points are at most one largest step apart in arc length and in ω; every point solves the
/// residual; and the folds' ω equal those of an independent fixed-amplitude scan (|Y1| fixed
/// in steps of 2e-4 m, ω solved for; the folds are the extrema of ω(|Y1|)) within 2e-4 rad/s.
#[test]
fn separation_fold_both_turning_points() {
    let h = 5;
    let lin = two_oscillators(0.1, [0.05, 0.015], h);
    let force = contact();
    let layout = HarmonicLayout::new(h, 256).unwrap();
    let system = HbmSystem::new(layout, &lin, &force).unwrap();
    let max_step = 0.005;
    let (fp, path) = traced(&system, (1.3, 2.2), (max_step, max_step));
    assert_eq!(path.end, PathEnd::ReachedEnd, "{:?}", path.end);
    let omega: Vec<f64> = path.points.iter().map(|p| p.parameter).collect();
    let amp: Vec<f64> = path
        .points
        .iter()
        .map(|p| normal_amplitude(&layout, &p.x))
        .collect();
    // turning point A: the largest ω before the unstable branch (|Y1| < 0.05 m);
    // B: the smallest ω after A up to the peak amplitude
    let peak = (0..amp.len())
        .max_by(|&i, &j| amp[i].total_cmp(&amp[j]))
        .unwrap();
    let lower = amp.iter().position(|&a| a > 0.05).unwrap();
    let ia = (0..lower)
        .max_by(|&i, &j| omega[i].total_cmp(&omega[j]))
        .unwrap();
    let ib = (ia..=peak)
        .min_by(|&i, &j| omega[i].total_cmp(&omega[j]))
        .unwrap();
    let (wa, wb) = (omega[ia], omega[ib]);
    eprintln!(
        "{} points, {} retries; A: ω {wa:.6} |Y1| {:.5}; B: ω {wb:.6} |Y1| {:.5}; peak |Y1| {:.5}",
        omega.len(),
        path.retries,
        amp[ia],
        amp[ib],
        amp[peak]
    );
    assert!(wa - wb > 0.2, "turning points {wa} and {wb}");
    // both are turning points: ω comes up to A and back; down to B and back up
    assert!(omega[..ia].iter().any(|&w| w < wa - 0.1));
    assert!(omega[ib..].iter().any(|&w| w > wb + 0.1));
    assert!(path.points[ia + 1].tangent_parameter < 0.0);
    for i in ia..ib {
        assert!(
            omega[i + 1] <= omega[i] + 5e-5,
            "ω rises from {} to {} between the turning points",
            omega[i],
            omega[i + 1]
        );
    }
    let range = 2.2 - 1.3;
    for w in path.points.windows(2) {
        assert!(w[1].arc_length - w[0].arc_length <= max_step / range * (1.0 + 1e-12));
        assert!((w[1].parameter - w[0].parameter).abs() <= max_step * (1.0 + 1e-9));
        let mut lin = Linearization::zeros(fp.dim());
        fp.evaluate(&w[1].x, w[1].parameter, &w[0].state, &mut lin)
            .unwrap();
        assert!(norm(&lin.residual) <= 1e-7 * fp.residual_scale());
    }
    // independent check: the extrema of ω(|Y1|) at fixed amplitudes
    let start = (0..ia)
        .rev()
        .find(|&i| amp[i] < 0.018)
        .expect("a lower-branch point below 0.018 m");
    let (mut x, mut w) = (path.points[start].x.clone(), omega[start]);
    let mut state = path.points[start].state.clone();
    let (mut scan_max, mut scan_min) = (f64::NEG_INFINITY, f64::INFINITY);
    let mut a = 0.018;
    while a < amp[peak] - 2e-3 {
        let (xs, ws, end) = solve_at_amplitude(&fp, &layout, a, (&x, w), &state).unwrap();
        scan_max = scan_max.max(ws);
        if a > 0.05 {
            scan_min = scan_min.min(ws);
        }
        (x, w, state) = (xs, ws, end);
        a += 2e-4;
    }
    eprintln!("fixed-amplitude scan: ω_A {scan_max:.6}, ω_B {scan_min:.6}");
    assert!((wa - scan_max).abs() <= 2e-4, "A: {wa} vs scan {scan_max}");
    assert!((wb - scan_min).abs() <= 2e-4, "B: {wb} vs scan {scan_min}");
}

/// Corners of the path are passed at the minimum step (continuation: up to one initial step from
/// the prediction accepted there). Hardening by contact closing at a gap (n0 = −0.3 N: the gap
/// v = 0.1 m closes when the normal oscillator's motion exceeds it; |Y1| peaks at ≈ 0.39 m near
/// ω ≈ 1.25 rad/s) with friction on the tangential DOF (forces 0.01 N each, c = 0.02 N·s/m,
/// H = 5, N_t = 256): stick–slip while the contact closes for part of the period makes corners
/// where the path turns by more than 45° within one sample pattern; with the one-step limit the
/// corrector stopped at ω ≈ 1.2507 rad/s ("moved 8.7e-5 from the prediction, farther than the
/// step 4.9e-5"). Asserted: the end is reached, the peak is past the gap, consecutive points
/// differ by at most the largest step in ω and 0.01 m in |Y1| (no skipped segment), every point
/// solves the residual.
#[test]
fn corners_at_a_closing_gap_are_passed() {
    let h = 5;
    let lin = two_oscillators(0.02, [0.01, 0.01], h);
    let force = tangential_normal_element(-0.3).unwrap();
    let layout = HarmonicLayout::new(h, 256).unwrap();
    let system = HbmSystem::new(layout, &lin, &force).unwrap();
    let (fp, path) = traced(&system, (0.8, 2.4), (0.01, 0.02));
    assert_eq!(path.end, PathEnd::ReachedEnd, "{:?}", path.end);
    let amp: Vec<f64> = path
        .points
        .iter()
        .map(|p| normal_amplitude(&layout, &p.x))
        .collect();
    let peak = amp.iter().cloned().fold(0.0, f64::max);
    eprintln!(
        "{} points, {} retries, peak |Y1| {peak:.4}",
        amp.len(),
        path.retries
    );
    assert!(peak > 0.3, "{peak}");
    for (i, w) in path.points.windows(2).enumerate() {
        assert!((w[1].parameter - w[0].parameter).abs() <= 0.02 + 1e-12);
        assert!(
            (amp[i + 1] - amp[i]).abs() <= 0.01,
            "|Y1| jumps from {} to {} at ω {}",
            amp[i],
            amp[i + 1],
            w[0].parameter
        );
        let mut lin = Linearization::zeros(fp.dim());
        fp.evaluate(&w[1].x, w[1].parameter, &w[0].state, &mut lin)
            .unwrap();
        assert!(norm(&lin.residual) <= 1e-7 * fp.residual_scale());
    }
}
