//! Relative kinematics of a contact pair in the real harmonic layout, including the inter-sector
//! rotation and per-harmonic phase of cyclic symmetry (`docs/conventions.md` §2–3; SAMA paper eq. 33
//! and the relative-to-absolute transformation of eqs 26–27).
//!
//! For temporal harmonic n the target displacement seen from the contact node's sector is
//! e^{iθ_n} R^σ Q_t⁽ⁿ⁾ with θ_n = σ·φ_{k_n} (φ_k = 2πk/N, k_n the harmonic index of harmonic n),
//! R = R_α the sector rotation and σ ∈ {−1, 0, 1}. The local relative harmonics are
//! r⁽ⁿ⁾ = F (Q_c⁽ⁿ⁾ − e^{iθ_n} R^σ Q_t⁽ⁿ⁾) for a 3×3 matrix F of local directions (rows). In the
//! real layout the pair (Re, Im) of the target is rotated by θ_n:
//! (Re, Im) → (cos θ_n Re − sin θ_n Im, sin θ_n Re + cos θ_n Im).
//!
//! Node values are stored component by component, each in the signal order of
//! [`super::aft`]: `[x coefficients; y coefficients; z coefficients]`, 3·(2H+1) numbers. The
//! transpose ([`relative_transpose`]) maps local force coefficients back to the two nodes
//! (contact: Fᵀ g; target: −e^{−iθ_n} (F R^σ)ᵀ g), the Galerkin counterpart of the complex
//! cyclic transformation (Hermitian transpose).

use crate::error::{Error, Result};
use crate::vec3::Mat3;

/// cos θ_n, sin θ_n of the inter-sector phase for n = 0..=H.
#[derive(Clone, Debug, PartialEq)]
pub struct Phases {
    cos: Vec<f64>,
    sin: Vec<f64>,
}

impl Phases {
    /// No phase (contact inside one sector, σ = 0, or k_n = 0 for all n) for H harmonics.
    pub fn zero(harmonics: usize) -> Self {
        Phases {
            cos: vec![1.0; harmonics + 1],
            sin: vec![0.0; harmonics + 1],
        }
    }

    /// θ_n = σ·2πk_n/N for the harmonic indices `k` (entry n = k_n, n = 0..=H) of an N-sector
    /// structure. k_0 must be 0 (the static part is real).
    pub fn cyclic(sigma: i32, k: &[usize], sectors: usize) -> Result<Self> {
        if k.first().is_some_and(|&k0| k0 != 0) || k.iter().any(|&kn| kn >= sectors.max(1)) {
            return Err(Error::input(format!(
                "inter-sector phase: harmonic indices {k:?} must start with k_0 = 0 and lie in 0..{sectors} (conventions §2)"
            )));
        }
        let (cos, sin) = k
            .iter()
            .map(|&kn| {
                let theta = sigma as f64 * 2.0 * std::f64::consts::PI * kn as f64 / sectors as f64;
                let (s, c) = theta.sin_cos();
                (c, s)
            })
            .unzip();
        Ok(Phases { cos, sin })
    }

    /// Highest harmonic H covered.
    pub fn harmonics(&self) -> usize {
        self.cos.len() - 1
    }
}

/// Local relative harmonics `out` = F (Q_c − e^{iθ} R^σ Q_t) (3·m, component-major) from the
/// contact node's `qc` and, unless the target is the ground, the target's `qt` (3·m each).
/// `frame` is F (rows: local directions) and `target_frame` = F R^σ.
pub fn relative_local(
    frame: &Mat3,
    target_frame: &Mat3,
    phases: &Phases,
    qc: &[f64],
    qt: Option<&[f64]>,
    out: &mut [f64],
) {
    let m = qc.len() / 3;
    for a in 0..3 {
        let o = &mut out[a * m..(a + 1) * m];
        o.fill(0.0);
        for i in 0..3 {
            let fa = frame[a][i];
            if fa != 0.0 {
                for (ov, qv) in o.iter_mut().zip(&qc[i * m..(i + 1) * m]) {
                    *ov += fa * qv;
                }
            }
        }
    }
    let Some(qt) = qt else { return };
    let h = (m - 1) / 2;
    for i in 0..3 {
        let t = &qt[i * m..(i + 1) * m];
        for a in 0..3 {
            let g = target_frame[a][i];
            if g == 0.0 {
                continue;
            }
            subtract_phased(g, phases, 1.0, t, &mut out[a * m..(a + 1) * m], h);
        }
    }
}

/// The transpose of [`relative_local`]: node force coefficients `fc` = Fᵀ g and, if given,
/// `ft` = −e^{−iθ} (F R^σ)ᵀ g from local force coefficients `g` (all 3·m, overwritten).
pub fn relative_transpose(
    frame: &Mat3,
    target_frame: &Mat3,
    phases: &Phases,
    g: &[f64],
    fc: &mut [f64],
    ft: Option<&mut [f64]>,
) {
    let m = g.len() / 3;
    for i in 0..3 {
        let o = &mut fc[i * m..(i + 1) * m];
        o.fill(0.0);
        for a in 0..3 {
            let fa = frame[a][i];
            if fa != 0.0 {
                for (ov, gv) in o.iter_mut().zip(&g[a * m..(a + 1) * m]) {
                    *ov += fa * gv;
                }
            }
        }
    }
    let Some(ft) = ft else { return };
    let h = (m - 1) / 2;
    for i in 0..3 {
        let o = &mut ft[i * m..(i + 1) * m];
        o.fill(0.0);
        for a in 0..3 {
            let t = target_frame[a][i];
            if t == 0.0 {
                continue;
            }
            subtract_phased(t, phases, -1.0, &g[a * m..(a + 1) * m], o, h);
        }
    }
}

/// `out` −= `scale`·e^{±iθ_n}·`signal` for every harmonic (sign `direction` = ±1 of the phase).
fn subtract_phased(
    scale: f64,
    phases: &Phases,
    direction: f64,
    signal: &[f64],
    out: &mut [f64],
    h: usize,
) {
    out[0] -= scale * signal[0];
    for n in 1..=h {
        let (c, s) = (phases.cos[n], direction * phases.sin[n]);
        let (re, im) = (signal[2 * n - 1], signal[2 * n]);
        out[2 * n - 1] -= scale * (c * re - s * im);
        out[2 * n] -= scale * (s * re + c * im);
    }
}

/// Errors unless `frame` has orthonormal rows forming a right-handed frame (t1 × t2 = n), to
/// 1e-9; `context` names the pair.
pub fn check_frame(frame: &Mat3, context: &str) -> Result<()> {
    let dot = |a: &[f64; 3], b: &[f64; 3]| a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    let mut worst: f64 = 0.0;
    for i in 0..3 {
        for j in 0..3 {
            let target = if i == j { 1.0 } else { 0.0 };
            let d = dot(&frame[i], &frame[j]);
            worst = worst.max(if d.is_finite() {
                (d - target).abs()
            } else {
                f64::INFINITY
            });
        }
    }
    let (t1, t2, n) = (frame[0], frame[1], frame[2]);
    let cross = [
        t1[1] * t2[2] - t1[2] * t2[1],
        t1[2] * t2[0] - t1[0] * t2[2],
        t1[0] * t2[1] - t1[1] * t2[0],
    ];
    if worst > 1e-9 || dot(&cross, &n) < 0.0 {
        return Err(Error::input(format!(
            "{context}: the local frame rows t1 = {t1:?}, t2 = {t2:?}, n = {n:?} are not an orthonormal right-handed frame (t1 × t2 = n, conventions §3)"
        )));
    }
    Ok(())
}

/// The node-space Jacobian Lᵀ J L of a pair (SAMA paper eq. 26, with the kinematic map L of
/// [`relative_local`]: L = [F ⊗ I, −(F R^σ) ⊗ P], P the per-harmonic rotation by θ_n).
///
/// `jac` is the local Jacobian, row-major with `cols` columns of which the first 3·m are the
/// local coefficients (u1, u2, v); `out` receives the node Jacobian column-major, np × np with
/// np = 3m (ground target) or 6m, node index (side, component, coefficient). Built from the
/// 3×3 block contractions G^Y_{a,i'} = Σ_b J_ab Y_bi' and Σ_a X_ai G^Y_{a,i'} for X, Y ∈ {F, F R^σ}
/// (m × m blocks), then the phase: K P for target columns, Pᵀ K for target rows, with sign
/// (−1) per target side. `work` is scratch.
#[allow(clippy::too_many_arguments)]
pub fn node_jacobian(
    frame: &Mat3,
    target_frame: &Mat3,
    phases: &Phases,
    jac: &[f64],
    cols: usize,
    m: usize,
    target: bool,
    work: &mut Vec<f64>,
    out: &mut [f64],
) {
    let sides = if target { 2 } else { 1 };
    let np = 3 * m * sides;
    let mm = m * m;
    let h = (m - 1) / 2;
    let maps = [frame, target_frame];
    work.clear();
    work.resize(sides * 9 * mm + mm, 0.0);
    let (g, block) = work.split_at_mut(sides * 9 * mm);
    // G^Y_{a,i'}[k][l] = Σ_b J[(a,k),(b,l)] Y_{b,i'}.
    for (y, map) in maps.iter().enumerate().take(sides) {
        for a in 0..3 {
            for b in 0..3 {
                for i in 0..3 {
                    let coef = map[b][i];
                    if coef == 0.0 {
                        continue;
                    }
                    let gb = &mut g[((y * 3 + a) * 3 + i) * mm..((y * 3 + a) * 3 + i + 1) * mm];
                    for k in 0..m {
                        let src =
                            &jac[(a * m + k) * cols + b * m..(a * m + k) * cols + (b + 1) * m];
                        for (o, s) in gb[k * m..(k + 1) * m].iter_mut().zip(src) {
                            *o += coef * s;
                        }
                    }
                }
            }
        }
    }
    for (x, xmap) in maps.iter().enumerate().take(sides) {
        for (y, _) in maps.iter().enumerate().take(sides) {
            let sign = if x == y { 1.0 } else { -1.0 };
            for i in 0..3 {
                for ip in 0..3 {
                    block.fill(0.0);
                    for a in 0..3 {
                        let coef = sign * xmap[a][i];
                        if coef == 0.0 {
                            continue;
                        }
                        let gb = &g[((y * 3 + a) * 3 + ip) * mm..((y * 3 + a) * 3 + ip + 1) * mm];
                        for (o, s) in block.iter_mut().zip(gb) {
                            *o += coef * s;
                        }
                    }
                    if y == 1 {
                        rotate_columns(block, phases, m, h);
                    }
                    if x == 1 {
                        rotate_rows(block, phases, m, h);
                    }
                    let row0 = x * 3 * m + i * m;
                    let col0 = y * 3 * m + ip * m;
                    for l in 0..m {
                        let column = &mut out[(col0 + l) * np + row0..(col0 + l) * np + row0 + m];
                        for (k, o) in column.iter_mut().enumerate() {
                            *o = block[k * m + l];
                        }
                    }
                }
            }
        }
    }
}

/// `block` (m × m, row-major) ← block · P: the (Re, Im) columns of harmonic n mixed by
/// P_n = [[cos θ_n, −sin θ_n], [sin θ_n, cos θ_n]].
fn rotate_columns(block: &mut [f64], phases: &Phases, m: usize, h: usize) {
    for row in block.chunks_exact_mut(m) {
        for n in 1..=h {
            let (c, s) = (phases.cos[n], phases.sin[n]);
            let (re, im) = (row[2 * n - 1], row[2 * n]);
            row[2 * n - 1] = re * c + im * s;
            row[2 * n] = -re * s + im * c;
        }
    }
}

/// `block` (m × m, row-major) ← Pᵀ · block.
fn rotate_rows(block: &mut [f64], phases: &Phases, m: usize, h: usize) {
    for n in 1..=h {
        let (c, s) = (phases.cos[n], phases.sin[n]);
        let (re, im) = block[(2 * n - 1) * m..(2 * n + 1) * m].split_at_mut(m);
        for (r, i) in re.iter_mut().zip(im.iter_mut()) {
            let (a, b) = (*r, *i);
            *r = c * a + s * b;
            *i = -s * a + c * b;
        }
    }
}
