//! The step caches of the march (src/march/schemes.rs) against the plain computation on a chain of
//! ten masses with four friction elements (tangential and normal directions over several DOF,
//! prescribed harmonic motions, non-proportional damping, a shared normal force):
//! - the premultiplied piecewise-linear Newmark step (`Cache::use_premultiplied`: y₀ from the
//!   all-stick operators A_stick⁻¹P, A_stick⁻¹C and the low-rank correction of the non-stick
//!   elements) equals the step from b = f + P q* − C v* and A(states)⁻¹ to rounding, through
//!   stick, slip and separation;
//! - the memory cap of all the step sizes (`MAX_CACHED_TOTAL_BYTES`, here a smaller limit by
//!   `Cache::with_total_limit`) bounds what the cache holds and changes no result;
//! - the products of the passes (`dense::dot`) give the baseline kernel's bits.

use nlrom::march::dense;
use nlrom::march::element::{Direction, Element};
use nlrom::march::law::FrictionParams;
use nlrom::march::schemes::{self, Cache, Excitation, Snapshot, StepContext, Workspace};
use nlrom::march::signal::Harmonic;
use nlrom::march::{InitialCondition, MarchSystem};

const N: usize = 10;

fn direction(weights: &[(usize, f64)], prescribed: Harmonic) -> Direction {
    Direction {
        weights: weights.to_vec(),
        prescribed,
    }
}

/// Masses 1 + 0.1 i kg on springs of 100 N/m (a chain fixed at its first end), damping
/// 0.02 s × K plus 0.3 N·s/m between DOF 0 and 5 (not proportional), 3 cos ωt + sin ωt + 0.2 N on
/// the last DOF and a damping force 0.1 cos ωt N on DOF 4; two pairs of friction elements (k_t =
/// 50 N/m, k_n = 40 N/m, μ = 0.3, n0 = 0.5 N), the second of each pair on the first's normal
/// direction without applying its normal force, with prescribed tangential and normal motions.
fn chain() -> MarchSystem {
    let mut k = vec![0.0; N * N];
    for i in 0..N {
        k[i * N + i] = if i + 1 == N { 100.0 } else { 200.0 };
        if i + 1 < N {
            k[i * N + i + 1] = -100.0;
            k[(i + 1) * N + i] = -100.0;
        }
    }
    let mut c: Vec<f64> = k.iter().map(|x| 0.02 * x).collect();
    for (i, j) in [(0, 0), (5, 5)] {
        c[i * N + j] += 0.3;
    }
    c[5] -= 0.3;
    c[5 * N] -= 0.3;
    let mut mass = vec![0.0; N * N];
    for i in 0..N {
        mass[i * N + i] = 1.0 + 0.1 * i as f64;
    }
    let params = FrictionParams {
        kt: 50.0,
        kn: 40.0,
        mu: 0.3,
        n0: 0.5,
    };
    let pt = Harmonic {
        mean: 0.001,
        cos: 0.02,
        sin: 0.01,
    };
    let pn = Harmonic {
        mean: 0.0,
        cos: 0.01,
        sin: -0.005,
    };
    let normal_a = direction(&[(4, 0.8), (5, 0.3)], pn);
    let normal_b = direction(&[(8, 1.0)], Harmonic::default());
    let element = |name: &str, t: Direction, normal: &Direction, applies: bool| Element {
        name: name.into(),
        tangential: t,
        normal: Some(normal.clone()),
        params,
        applies_normal: applies,
    };
    let elements = vec![
        element("a1", direction(&[(2, 1.0), (3, -0.7)], pt), &normal_a, true),
        element(
            "a2",
            direction(&[(3, 1.0), (6, 0.5)], Harmonic::default()),
            &normal_a,
            false,
        ),
        element("b1", direction(&[(7, 1.0)], pt), &normal_b, true),
        element(
            "b2",
            direction(&[(8, -1.0), (9, 0.4)], Harmonic::default()),
            &normal_b,
            false,
        ),
    ];
    let mut force = vec![Harmonic::default(); N];
    force[N - 1] = Harmonic {
        mean: 0.2,
        cos: 3.0,
        sin: 1.0,
    };
    let mut damping_force = vec![Harmonic::default(); N];
    damping_force[4] = Harmonic::cosine(0.1, 0.0);
    let mut sys = MarchSystem {
        n: N,
        mass,
        damping: c,
        stiffness: k,
        force,
        damping_force,
        elements,
        dof_names: (0..N).map(|i| format!("q{i}")).collect(),
        initial: InitialCondition::Rest,
        displacement_scale: 1.0,
    };
    sys.displacement_scale = sys.default_displacement_scale();
    sys
}

/// The state at rest (sliders at zero).
fn at_rest(sys: &MarchSystem) -> Snapshot {
    let mut s = Snapshot::new(sys.n, sys.elements.len());
    let w = vec![0.0; sys.elements.len()];
    schemes::evaluate_law(sys, 1.0, 0.0, &vec![0.0; sys.n], &w, &mut s.samples);
    s
}

/// One marcher of its own: cache, workspace, current and next state.
struct Stepper {
    cache: Cache,
    ws: Workspace,
    cur: Snapshot,
    next: Snapshot,
}

impl Stepper {
    fn new(sys: &MarchSystem, cache: Cache) -> Self {
        Stepper {
            cache,
            ws: Workspace::new(sys),
            cur: at_rest(sys),
            next: at_rest(sys),
        }
    }

    /// One step of `dt` to `t1` with the piecewise-linear (`piecewise`) or the standard Newmark
    /// step; returns the iterations.
    fn step(&mut self, sys: &MarchSystem, omega: f64, t1: f64, dt: f64, piecewise: bool) -> u32 {
        let exc = Excitation::at(sys, omega, t1, true);
        let ctx = StepContext {
            sys,
            omega,
            t1,
            dt,
            tolerance: 1e-13 * sys.displacement_scale,
            max_iterations: 500,
            excitation: exc.view(),
            one_off: false,
        };
        let its = if piecewise {
            schemes::piecewise_linear_step(
                &ctx,
                &self.cur,
                &mut self.cache,
                &mut self.ws,
                &mut self.next,
            )
        } else {
            schemes::standard_step(
                &ctx,
                &self.cur,
                &mut self.cache,
                &mut self.ws,
                &mut self.next,
            )
        }
        .expect("step");
        std::mem::swap(&mut self.cur, &mut self.next);
        its
    }
}

/// Three periods at 200 steps per period from rest, stepped by both piecewise-linear paths: the
/// displacements agree within 1e-10 of their largest value (9.7e-13 measured) at every step and the contact states
/// are the same, through stick, both slips and separation.
#[test]
fn premultiplied_piecewise_linear_step_equals_the_right_hand_side_one() {
    let sys = chain();
    let omega = 5.0;
    let dt = 2.0 * std::f64::consts::PI / omega / 200.0;
    let mut premultiplied = Cache::default();
    assert!(premultiplied.use_premultiplied(&sys, true));
    let mut a = Stepper::new(&sys, premultiplied);
    let mut b = Stepper::new(&sys, Cache::default());
    let (mut worst, mut scale) = (0.0f64, 0.0f64);
    let mut seen = [0usize; 4];
    for j in 1..=600 {
        let t1 = j as f64 * dt;
        a.step(&sys, omega, t1, dt, true);
        b.step(&sys, omega, t1, dt, true);
        for (x, y) in a.cur.kin.q.iter().zip(&b.cur.kin.q) {
            worst = worst.max((x - y).abs());
            scale = scale.max(y.abs());
        }
        for (sa, sb) in a.cur.samples.iter().zip(&b.cur.samples) {
            assert_eq!(sa.state, sb.state, "states differ at step {j}");
            seen[usize::from(sa.state.code())] += 1;
        }
    }
    eprintln!(
        "max |q_premultiplied − q| = {worst:.2e} of max |q| = {scale:.3e}; element-steps separated, stick, slip+, slip−: {seen:?}"
    );
    assert!(worst <= 1e-10 * scale, "{worst:e} of {scale:e}");
    assert!(
        seen.iter().all(|&c| c >= 20),
        "every contact state should be met: {seen:?}"
    );
}

/// Standard Newmark steps of twelve step sizes, cycled three times: with a limit of three sizes'
/// matrices the cache never holds more than the limit plus one size, drops sizes (so the limit
/// acts), and gives the same displacements, bit for bit, as the unlimited cache that holds all
/// twelve.
#[test]
fn the_memory_cap_of_the_step_sizes_bounds_the_cache_and_changes_no_result() {
    let sys = chain();
    let omega = 5.0;
    let base = 2.0 * std::f64::consts::PI / omega / 400.0;
    let mut free = Stepper::new(&sys, Cache::default());
    free.step(&sys, omega, base, base, false);
    let per_size = free.cache.held_bytes();
    assert!(per_size > 0);
    let limit = 3 * per_size;
    let mut capped = Stepper::new(&sys, Cache::with_total_limit(limit));
    capped.step(&sys, omega, base, base, false);
    let (mut t, mut fewest, mut most) = (base, usize::MAX, 0usize);
    for j in 0..36 {
        let dt = base * (1.0 + 0.05 * (j % 12) as f64);
        t += dt;
        free.step(&sys, omega, t, dt, false);
        capped.step(&sys, omega, t, dt, false);
        assert_eq!(free.cur.kin.q, capped.cur.kin.q, "step {j}");
        let held = capped.cache.held_bytes();
        assert!(held <= limit + per_size, "{held} bytes held, limit {limit}");
        fewest = fewest.min(capped.cache.step_sizes());
        most = most.max(held);
    }
    eprintln!(
        "{per_size} bytes per step size; capped at {limit}: at most {most} held, down to {fewest} sizes; unlimited: {} sizes, {} bytes",
        free.cache.step_sizes(),
        free.cache.held_bytes()
    );
    assert_eq!(free.cache.step_sizes(), 12);
    assert!(fewest <= 2, "the limit never dropped a step size");
}

/// The products of the step's passes ([`dense::dot`]: VEX-encoded from 64 entries on where the
/// CPU has AVX) give the baseline kernel's result to the bit for every length up to 700 (tails
/// of 0 to 7 entries, entries of mixed signs over twelve decades), and that result equals a plain
/// left-to-right sum within the rounding bound of the two sums, 2 n ε Σ|x_i y_i|.
#[test]
fn the_dot_kernels_give_the_same_bits() {
    let entry =
        |i: usize, k: f64| ((i as f64 * k).sin() * 37.0).sin() * 10f64.powi((i % 13) as i32 - 6);
    for len in 0..=700 {
        let x: Vec<f64> = (0..len).map(|i| entry(i, 0.7)).collect();
        let y: Vec<f64> = (0..len).map(|i| entry(i + 5, 1.3)).collect();
        let (fast, base) = (dense::dot(&x, &y), dense::dot_baseline(&x, &y));
        assert_eq!(
            fast.to_bits(),
            base.to_bits(),
            "length {len}: {fast:e} against {base:e}"
        );
        let plain: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
        let scale: f64 = x.iter().zip(&y).map(|(a, b)| (a * b).abs()).sum();
        let bound = 2.0 * len as f64 * f64::EPSILON * scale;
        assert!((fast - plain).abs() <= bound, "length {len}");
    }
}

/// The low-rank correction's x ← x + Σ_a s_a z_a, four columns per pass over x
/// ([`dense::add_scaled_columns`], VEX-encoded from 64 entries on where the CPU has AVX), gives
/// one plain pass x ← x + s_a z_a per column to the bit, for lengths up to 300 and 0 to 11
/// columns (groups of four and the rest).
#[test]
fn the_column_kernel_gives_the_bits_of_one_pass_per_column() {
    let entry =
        |i: usize, k: f64| ((i as f64 * k).sin() * 37.0).sin() * 10f64.powi((i % 13) as i32 - 6);
    for len in [0, 1, 7, 63, 64, 65, 289, 300] {
        for r in 0..12 {
            let z: Vec<Vec<f64>> = (0..r)
                .map(|a| (0..len).map(|i| entry(i + 31 * a, 0.9)).collect())
                .collect();
            let s: Vec<f64> = (0..r).map(|a| entry(a + 3, 2.1)).collect();
            let x0: Vec<f64> = (0..len).map(|i| entry(i + 11, 1.7)).collect();
            let mut fast = x0.clone();
            dense::add_scaled_columns(&mut fast, &s, |a| &z[a]);
            let mut plain = x0;
            for (za, &sa) in z.iter().zip(&s) {
                for (xj, zj) in plain.iter_mut().zip(za) {
                    *xj += sa * zj;
                }
            }
            for (j, (f, p)) in fast.iter().zip(&plain).enumerate() {
                assert_eq!(
                    f.to_bits(),
                    p.to_bits(),
                    "length {len}, {r} columns, entry {j}"
                );
            }
        }
    }
}
