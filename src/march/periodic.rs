//! Steady-state detection and the harmonics of the last period: what lets a march be compared
//! with a harmonic-balance point.
//!
//! Periodicity: the state at the end of period p is compared with the end of period p − 1,
//! e_p = max(|Δq|_∞ / A, |Δq̇|_∞ / (ω A)) with A the largest half peak-to-peak displacement of a DOF
//! in period p. Harmonics: Q⁽⁰⁾ = (1/T)∫q dt, Q⁽ⁿ⁾ = (2/T)∫q e^{−inωt} dt (n ≥ 1), so that
//! q(t) = Re Σ Q⁽ⁿ⁾ e^{inωt} (`docs/conventions.md` §4); the integrals by the trapezoidal rule over the
//! recorded (possibly non-uniform) instants.

use super::integrate::{MarchHistory, PeriodSummary};
use super::system::MarchSystem;

/// The running extremes of every DOF over a period's records (m), the scratch of [`summarize`],
/// sized once for the model so that a period's summary allocates nothing.
#[derive(Clone, Debug)]
pub struct Extremes {
    lo: Vec<f64>,
    hi: Vec<f64>,
}

impl Extremes {
    /// For `n` DOF.
    pub fn new(n: usize) -> Self {
        Extremes {
            lo: vec![0.0; n],
            hi: vec![0.0; n],
        }
    }

    /// The largest half peak-to-peak displacement of a DOF over the instants `first..=last` of
    /// `h` (m), read instant by instant (each a run of n values; read DOF by DOF, a sector's
    /// period of records cost a cache miss per value).
    fn amplitude(&mut self, h: &MarchHistory, first: usize, last: usize) -> f64 {
        let n = self.lo.len();
        self.lo.copy_from_slice(&h.q[first * n..(first + 1) * n]);
        self.hi.copy_from_slice(&self.lo);
        for k in first + 1..=last {
            let row = &h.q[k * n..(k + 1) * n];
            for ((lo, hi), &x) in self.lo.iter_mut().zip(&mut self.hi).zip(row) {
                *lo = lo.min(x);
                *hi = hi.max(x);
            }
        }
        self.lo
            .iter()
            .zip(&self.hi)
            .fold(0.0, |a, (lo, hi)| a.max(0.5 * (hi - lo)))
    }
}

/// The summary of the period recorded at history indices `first..=last` (`first` is the previous
/// period's end; `extremes` the scratch of its amplitude). `prev_end` is (q, q̇) at `first`,
/// `end_v` q̇ at `last` (the history records q̇ only when asked); `compare` is false for the
/// first period.
#[allow(clippy::too_many_arguments)]
pub fn summarize(
    h: &MarchHistory,
    sys: &MarchSystem,
    extremes: &mut Extremes,
    omega: f64,
    first: usize,
    last: usize,
    prev_end: (&[f64], &[f64]),
    end_v: &[f64],
    compare: bool,
) -> PeriodSummary {
    let n = sys.n;
    let ne = sys.elements.len();
    let amp = extremes.amplitude(h, first, last);
    let amp = if amp > 0.0 {
        amp
    } else {
        sys.displacement_scale
    };
    let periodicity_error = compare.then(|| {
        let q = &h.q[last * n..(last + 1) * n];
        let dq = max_difference(q, prev_end.0);
        let dv = max_difference(end_v, prev_end.1);
        (dq / amp).max(dv / (omega * amp))
    });
    let state_changes = (first + 1..=last)
        .filter(|&k| h.state[k * ne..(k + 1) * ne] != h.state[(k - 1) * ne..k * ne])
        .count();
    PeriodSummary {
        end_index: last,
        periodicity_error,
        state_changes,
        steps: last - first,
    }
}

/// max_i |a_i − b_i|.
fn max_difference(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).fold(0.0, |m, (x, y)| m.max((x - y).abs()))
}

/// Harmonics 0..=`harmonics` of every DOF over the instants `first..=last` (one period), as
/// (Re, Im) pairs: `[dof][n]`.
pub fn harmonics(
    h: &MarchHistory,
    n_dof: usize,
    omega: f64,
    first: usize,
    last: usize,
    harmonics: usize,
) -> Vec<Vec<(f64, f64)>> {
    let span = h.time[last] - h.time[first];
    let mut out = vec![vec![(0.0, 0.0); harmonics + 1]; n_dof];
    // trapezoidal weights of the instants, and e^{−imωt_k} per instant (one sin_cos each)
    let weight = |k: usize| {
        let before = if k > first {
            h.time[k] - h.time[k - 1]
        } else {
            0.0
        };
        let after = if k < last {
            h.time[k + 1] - h.time[k]
        } else {
            0.0
        };
        0.5 * (before + after)
    };
    let mut wc = vec![0.0; last + 1 - first];
    let mut ws = vec![0.0; last + 1 - first];
    // row by row (each instant's n DOF in one run), every DOF's sums in the order of the instants
    let (mut re, mut im) = (vec![0.0; n_dof], vec![0.0; n_dof]);
    for m in 0..=harmonics {
        for (j, k) in (first..=last).enumerate() {
            let (s, c) = (m as f64 * omega * h.time[k]).sin_cos();
            let w = weight(k);
            (wc[j], ws[j]) = (w * c, -w * s);
        }
        re.iter_mut().for_each(|x| *x = 0.0);
        im.iter_mut().for_each(|x| *x = 0.0);
        for (j, k) in (first..=last).enumerate() {
            let row = &h.q[k * n_dof..(k + 1) * n_dof];
            for ((r, i), &q) in re.iter_mut().zip(&mut im).zip(row) {
                *r += wc[j] * q;
                *i += ws[j] * q;
            }
        }
        let scale = if m == 0 { 1.0 } else { 2.0 } / span;
        for ((row, r), i) in out.iter_mut().zip(&re).zip(&im) {
            row[m] = (r * scale, i * scale);
        }
    }
    out
}
