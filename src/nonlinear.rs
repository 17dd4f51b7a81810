//! Nonlinear systems r(x, λ) = 0 and their Newton solution, independent of harmonic balance:
//! [`ParameterSystem`] (the residual, its Jacobian ∂r/∂x and parameter derivative ∂r/∂λ at a point,
//! with memory carried from one converged point to the next), Newton–Raphson with the analytic
//! Jacobian (Battiato 2021, eqs. 20–21), dense LU (faer, partial pivoting) or the structured
//! solve of [`linsolve`] on a block-stored Jacobian, backtracking step damping (the trials
//! beyond the full step evaluate the residual alone), and convergence on both the scaled
//! residual and the increment.
//!
//! [`newton_core`] iterates on any square system g(z) = 0 given g and ∂g/∂z; [`solve_fixed`]
//! applies it to a [`ParameterSystem`] at a fixed parameter. The continuation corrector
//! ([`crate::continuation`]) uses the same core on the bordered system; the harmonic balance
//! ([`crate::hbm`]) implements [`ParameterSystem`].

use faer::Mat;

use crate::error::Result;

pub mod linsolve;
pub mod lu;

pub use crate::harmonics::{BlockJacobian, Jacobian};
pub use linsolve::{Factored, LinearSolver, SolverChoice};

/// The residual of a parameter-dependent system at one point, its Jacobian and its parameter
/// derivative.
#[derive(Clone, Debug)]
pub struct Linearization {
    /// r(x, λ), length `dim`.
    pub residual: Vec<f64>,
    /// ∂r/∂x, `dim` × `dim`, dense or block-stored ([`LinearSolver::linearization`]).
    pub jacobian: Jacobian,
    /// ∂r/∂λ, length `dim`.
    pub d_parameter: Vec<f64>,
}

impl Linearization {
    /// Zeroed storage for a system of `dim` unknowns (the Jacobian dense).
    pub fn zeros(dim: usize) -> Linearization {
        Linearization {
            residual: vec![0.0; dim],
            jacobian: Jacobian::Dense(Mat::zeros(dim, dim)),
            d_parameter: vec![0.0; dim],
        }
    }
}

/// A nonlinear system r(x, λ) = 0 in `dim` real unknowns x and one parameter λ, with memory
/// (`State`) carried from one converged point to the next. This is what Newton
/// ([`solve_fixed`]) and the continuation ([`crate::continuation`]) solve.
pub trait ParameterSystem: Sync {
    /// Memory of the nonlinear force (e.g. slider positions at the start of the period).
    type State: Clone + Send + Sync + std::fmt::Debug;

    /// Number of unknowns.
    fn dim(&self) -> usize;

    /// The force level the residual norm is compared with (N): Newton converges when
    /// ‖r‖₂ ≤ tolerance · `residual_scale()`.
    fn residual_scale(&self) -> f64;

    /// The state before the first point.
    fn initial_state(&self) -> Self::State;

    /// Fills `out` at (x, λ) starting from the memory `state`; returns the end-of-period memory.
    fn evaluate(
        &self,
        x: &[f64],
        lambda: f64,
        state: &Self::State,
        out: &mut Linearization,
    ) -> Result<Self::State>;

    /// r(x, λ) alone into `residual` (length `dim`), starting from the memory `state`; returns
    /// the end-of-period memory. The default evaluates everything ([`ParameterSystem::evaluate`]
    /// with a dense Jacobian); large systems skip the Jacobian.
    fn evaluate_residual(
        &self,
        x: &[f64],
        lambda: f64,
        state: &Self::State,
        residual: &mut [f64],
    ) -> Result<Self::State> {
        let mut lin = Linearization::zeros(self.dim());
        let end = self.evaluate(x, lambda, state, &mut lin)?;
        residual.copy_from_slice(&lin.residual);
        Ok(end)
    }

    /// Sizes of the leading diagonal blocks of ∂r/∂x (in order, summing to
    /// [`ParameterSystem::dim`]) outside which ∂r/∂x is sparse and of low rank, for the
    /// structured linear solve ([`LinearSolver`]); empty (the default): no such structure.
    fn jacobian_blocks(&self) -> Vec<usize> {
        Vec::new()
    }
}

/// Newton settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct NewtonOptions {
    /// Converged when ‖r‖₂ ≤ `tolerance` · (force level), see
    /// [`ParameterSystem::residual_scale`] ...
    pub tolerance: f64,
    /// ... and the last increment ‖Δx‖₂ ≤ `increment_tolerance` · max(‖x‖₂, floor).
    pub increment_tolerance: f64,
    /// Most Newton steps (linear solves).
    pub max_iterations: usize,
    /// Most step halvings per iteration when the residual grows.
    pub max_halvings: usize,
    /// The linear solver of the steps and tangents ([`linsolve`]).
    pub linear_solver: SolverChoice,
}

impl Default for NewtonOptions {
    fn default() -> Self {
        NewtonOptions {
            tolerance: 1e-8,
            increment_tolerance: 1e-6,
            max_iterations: 20,
            max_halvings: 4,
            linear_solver: SolverChoice::Auto,
        }
    }
}

/// One evaluated iterate of [`newton_core`].
#[derive(Clone, Debug)]
pub struct Iterate<E> {
    /// The unknowns z.
    pub z: Vec<f64>,
    /// g(z), already scaled so that convergence means ‖g‖₂ ≤ tolerance.
    pub g: Vec<f64>,
    /// ∂(`g_scale` · g)/∂z, when the evaluation formed it (the damping trials beyond the full
    /// step do not).
    pub matrix: Option<Jacobian>,
    /// The factor between g and the equations of `matrix`: the Newton step solves
    /// `matrix` Δ = `g_scale` · g (so that an unscaled Jacobian needs no scaled copy).
    pub g_scale: f64,
    /// Whatever else the evaluation produced (state, unscaled linearization).
    pub extra: E,
}

impl<E> Iterate<E> {
    /// ‖g‖₂.
    pub fn norm(&self) -> f64 {
        norm(&self.g)
    }
}

/// A converged [`newton_core`]: the iterate, the steps taken and the factors of the last
/// factorised step matrix (at an earlier iterate: the last when every step was factorised; the
/// initial factors when no step was), to solve nearby systems with
/// ([`LinearSolver::solve_near`]: the continuation tangent).
pub struct NewtonOutcome<E> {
    /// The converged iterate.
    pub iterate: Iterate<E>,
    /// Newton steps taken.
    pub iterations: usize,
    /// Factors of the last factorised step matrix (or the initial ones).
    pub factors: Factored,
}

/// Why Newton stopped without converging.
#[derive(Clone, Debug, PartialEq)]
pub struct NewtonFailure {
    /// What happened, for the user.
    pub message: String,
    /// Steps taken.
    pub iterations: usize,
}

/// The evaluation of [`newton_core`]: the iterate at z, with its matrix when the flag is set.
pub type Evaluate<'a, E> = dyn FnMut(&[f64], bool) -> Result<Iterate<E>> + 'a;

/// Newton on g(z) = 0 from `z0`. `eval(z, matrix)` returns the iterate at z, with ∂g/∂z when
/// `matrix` (an `Err` counts as a failed iteration, e.g. a singular condensation); `floor` is
/// the smallest ‖z‖ the increment test is relative to; `solver` solves the steps. The first
/// step factorises its matrix; when [`LinearSolver::reuses_factors`], the later ones are solved
/// by GMRES on the last factors ([`LinearSolver::solve_krylov`], to the backward error of a
/// direct solve) and factorise only when that fails or the step before needed more than
/// [`linsolve::KRYLOV_REFRESH`] iterations. `initial` are factors of a nearby matrix to start
/// from (e.g. those of the previous continuation point): then the first step is solved on them
/// by GMRES as well. Each matrix is handed back to the solver after its step
/// ([`LinearSolver::recycle`]).
pub fn newton_core<E>(
    z0: Vec<f64>,
    eval: &mut Evaluate<'_, E>,
    floor: f64,
    opts: &NewtonOptions,
    solver: &LinearSolver,
    initial: Option<Factored>,
) -> std::result::Result<NewtonOutcome<E>, NewtonFailure> {
    let fail = |message: String, iterations: usize| NewtonFailure {
        message,
        iterations,
    };
    let mut current = eval(&z0, true).map_err(|e| fail(e.to_string(), 0))?;
    if !current.norm().is_finite() {
        return Err(fail("the residual at the start is not finite".into(), 0));
    }
    // the last factorisation, and whether the next step must factorise
    let mut refresh = initial.is_none();
    let mut factors: Option<Factored> = initial;
    for it in 1..=opts.max_iterations {
        if current.matrix.is_none() {
            current =
                eval(&current.z, true).map_err(|e| fail(format!("iteration {it}: {e}"), it))?;
        }
        let mut matrix = current
            .matrix
            .take()
            .ok_or_else(|| fail(format!("no Jacobian at iteration {it}"), it))?;
        let rhs: Vec<f64> = current.g.iter().map(|g| g * current.g_scale).collect();
        let krylov = match &factors {
            Some(f) if !refresh && solver.reuses_factors(matrix.dim()) => {
                solver.solve_krylov(f, &matrix, &rhs)
            }
            _ => None,
        };
        let step = match krylov {
            Some((step, iterations)) => {
                refresh = iterations > linsolve::KRYLOV_REFRESH;
                step
            }
            None => {
                // the older factors are not needed any more: dropped before the new ones exist
                drop(factors.take());
                let (step, f) = solver
                    .factor_solve(&mut matrix, &rhs)
                    .ok_or_else(|| fail(format!("singular Jacobian at iteration {it}"), it))?;
                factors = Some(f);
                refresh = false;
                step
            }
        };
        solver.recycle(matrix);
        let (next, taken) = damped_step(&current, &step, eval, opts)
            .map_err(|e| fail(format!("iteration {it}: {e}"), it))?;
        let z_norm = norm(&next.z).max(floor);
        let converged = next.norm() <= opts.tolerance && taken <= opts.increment_tolerance * z_norm;
        current = next;
        if converged {
            if let Some(factors) = factors {
                return Ok(NewtonOutcome {
                    iterate: current,
                    iterations: it,
                    factors,
                });
            }
        }
        if !current.norm().is_finite() || current.norm() > 1e12 {
            return Err(fail(
                format!(
                    "diverged (scaled residual {:.3e} at iteration {it})",
                    current.norm()
                ),
                it,
            ));
        }
    }
    Err(fail(
        format!(
            "no convergence in {} iterations (scaled residual {:.3e}, tolerance {:.1e})",
            opts.max_iterations,
            current.norm(),
            opts.tolerance
        ),
        opts.max_iterations,
    ))
}

/// z − α Δ with α = 1, ½, ¼, … (at most `max_halvings` halvings) until the residual decreases
/// or is within the tolerance; the best trial when none does. The full step is evaluated with
/// its matrix (it is accepted almost always), the halved ones without. Returns the iterate and
/// ‖α Δ‖.
fn damped_step<E>(
    current: &Iterate<E>,
    step: &[f64],
    eval: &mut Evaluate<'_, E>,
    opts: &NewtonOptions,
) -> Result<(Iterate<E>, f64)> {
    let max_halvings = opts.max_halvings;
    let r0 = current.norm();
    let mut alpha = 1.0;
    let mut best: Option<(Iterate<E>, f64)> = None;
    for k in 0..=max_halvings {
        let z: Vec<f64> = current
            .z
            .iter()
            .zip(step)
            .map(|(z, d)| z - alpha * d)
            .collect();
        let trial = eval(&z, k == 0)?;
        let taken = alpha * norm(step);
        let better = trial.norm() < r0 || trial.norm() <= opts.tolerance;
        let best_so_far = best.as_ref().is_none_or(|(b, _)| trial.norm() < b.norm());
        if better {
            return Ok((trial, taken));
        }
        if best_so_far && trial.norm().is_finite() {
            best = Some((trial, taken));
        }
        alpha *= 0.5;
    }
    best.ok_or_else(|| {
        crate::error::Error::Compute("the residual is not finite along the Newton step".into())
    })
}

/// Solves A x = b by dense LU with partial pivoting; `None` when A is (numerically) singular
/// (smallest pivot ≤ 1e-15 × the largest) or the solution is not finite.
pub fn solve_dense(a: &Mat<f64>, b: &[f64]) -> Option<Vec<f64>> {
    solve_dense_signed(a, b).map(|(x, _)| x)
}

/// Solves a x = b as [`solve_dense`] and returns the sign of det a as well (±1), from the
/// partial-pivoting LU factors: sign det P · Π sign u_ii. The sign of the determinant of the
/// bordered Jacobian orients a continuation tangent (Allgower & Georg 1990, §2.1).
pub fn solve_dense_signed(a: &Mat<f64>, b: &[f64]) -> Option<(Vec<f64>, f64)> {
    solve_dense_signed_ref(a.as_ref(), b)
}

/// [`solve_dense_signed`] on a view.
pub fn solve_dense_signed_ref(a: faer::MatRef<'_, f64>, b: &[f64]) -> Option<(Vec<f64>, f64)> {
    let lu = lu::PackedLu::new(a);
    let sign = linsolve::lu_sign(&lu)?;
    let mut x = Mat::from_fn(b.len(), 1, |i, _| b[i]);
    lu.solve_in_place(x.as_mut());
    let x: Vec<f64> = (0..b.len()).map(|i| x[(i, 0)]).collect();
    x.iter().all(|v| v.is_finite()).then_some((x, sign))
}

/// The sign (±1) of a permutation given as the image of 0..n: (−1)^(n − number of cycles).
fn permutation_sign(perm: &[usize]) -> f64 {
    let mut seen = vec![false; perm.len()];
    let mut transpositions = 0usize;
    for start in 0..perm.len() {
        let mut i = start;
        let mut length = 0usize;
        while !seen[i] {
            seen[i] = true;
            i = perm[i];
            length += 1;
        }
        transpositions += length.saturating_sub(1);
    }
    if transpositions.is_multiple_of(2) {
        1.0
    } else {
        -1.0
    }
}

/// Euclidean norm.
pub fn norm(v: &[f64]) -> f64 {
    v.iter().map(|x| x * x).sum::<f64>().sqrt()
}

/// A converged point of a [`ParameterSystem`].
#[derive(Clone, Debug)]
pub struct NewtonSolution<S> {
    /// The unknowns x.
    pub x: Vec<f64>,
    /// The parameter λ.
    pub parameter: f64,
    /// The force memory at the end of the converged period.
    pub state: S,
    /// Newton steps taken.
    pub iterations: usize,
    /// ‖r‖₂ / residual scale at the solution.
    pub residual: f64,
    /// r, ∂r/∂x, ∂r/∂λ at the solution (unscaled; from the continuation corrector the
    /// Jacobian is left empty, of order 0).
    pub linearization: Linearization,
}

/// Newton at the fixed parameter λ from `x0`, every evaluation starting from the memory `state`.
/// The solution's linearization is complete (the Jacobian stored as the solver chooses,
/// [`LinearSolver::linearization`]).
pub fn solve_fixed<S: ParameterSystem>(
    system: &S,
    x0: &[f64],
    lambda: f64,
    state: &S::State,
    opts: &NewtonOptions,
) -> std::result::Result<NewtonSolution<S::State>, NewtonFailure> {
    let scale = system.residual_scale();
    let n = system.dim();
    let solver = LinearSolver::new(system.jacobian_blocks(), opts.linear_solver);
    let mut eval = |z: &[f64], with_matrix: bool| -> Result<Iterate<(Linearization, S::State)>> {
        let (mut lin, end) = if with_matrix {
            let mut lin = solver.linearization(n);
            let end = system.evaluate(z, lambda, state, &mut lin)?;
            (lin, end)
        } else {
            let mut residual = vec![0.0; n];
            let end = system.evaluate_residual(z, lambda, state, &mut residual)?;
            let lin = Linearization {
                residual,
                jacobian: Jacobian::default(),
                d_parameter: Vec::new(),
            };
            (lin, end)
        };
        let matrix = with_matrix.then(|| std::mem::take(&mut lin.jacobian));
        Ok(Iterate {
            z: z.to_vec(),
            g: lin.residual.iter().map(|r| r / scale).collect(),
            matrix,
            g_scale: scale,
            extra: (lin, end),
        })
    };
    let floor = norm(x0).max(f64::MIN_POSITIVE);
    let NewtonOutcome {
        iterate: mut it,
        iterations,
        factors,
    } = newton_core(x0.to_vec(), &mut eval, floor, opts, &solver, None)?;
    // the solution carries no factors: they are released before its Jacobian is completed
    drop(factors);
    if it.matrix.is_none() {
        // converged on a halved step: the Jacobian at the solution
        it = eval(&it.z, true).map_err(|e| NewtonFailure {
            message: e.to_string(),
            iterations,
        })?;
    }
    let residual = it.norm();
    let (mut linearization, end) = it.extra;
    linearization.jacobian = it.matrix.unwrap_or_default();
    linearization.jacobian.materialize();
    Ok(NewtonSolution {
        x: it.z,
        parameter: lambda,
        state: end,
        iterations,
        residual,
        linearization,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// det by Laplace expansion along the first row (independent of the LU).
    fn laplace(a: &[Vec<f64>]) -> f64 {
        if a.len() == 1 {
            return a[0][0];
        }
        (0..a.len())
            .map(|j| {
                let minor: Vec<Vec<f64>> = a[1..]
                    .iter()
                    .map(|row| [&row[..j], &row[j + 1..]].concat())
                    .collect();
                let sign = if j % 2 == 0 { 1.0 } else { -1.0 };
                sign * a[0][j] * laplace(&minor)
            })
            .collect::<Vec<f64>>()
            .iter()
            .sum()
    }

    /// The sign of det from the LU factors equals the sign of the Laplace expansion on 200
    /// pseudo-random 5×5 matrices (pivoting in every pattern), and the solution solves a x = b.
    #[test]
    fn determinant_sign_matches_laplace_expansion() {
        let mut seed = 12345u64;
        let mut next = || {
            seed = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((seed >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
        };
        let n = 5;
        for _ in 0..200 {
            let rows: Vec<Vec<f64>> = (0..n).map(|_| (0..n).map(|_| next()).collect()).collect();
            let a = Mat::from_fn(n, n, |i, j| rows[i][j]);
            let b: Vec<f64> = (0..n).map(|_| next()).collect();
            let det = laplace(&rows);
            let (x, sign) = solve_dense_signed(&a, &b).unwrap();
            assert_eq!(sign, det.signum(), "det {det}");
            for i in 0..n {
                let ax: f64 = (0..n).map(|j| rows[i][j] * x[j]).sum();
                assert!((ax - b[i]).abs() <= 1e-10, "{ax} vs {}", b[i]);
            }
        }
    }

    /// Permutation signs: identity +1, one transposition −1, a 3-cycle +1, a 4-cycle −1.
    #[test]
    fn permutation_signs() {
        assert_eq!(permutation_sign(&[0, 1, 2, 3]), 1.0);
        assert_eq!(permutation_sign(&[1, 0, 2, 3]), -1.0);
        assert_eq!(permutation_sign(&[1, 2, 0, 3]), 1.0);
        assert_eq!(permutation_sign(&[1, 2, 3, 0]), -1.0);
    }

    /// r(x) = atan(x): Newton from x = 3 overshoots (the full step lands at −9.49, where |r|
    /// grows), so the step is halved twice (−3.25, then −0.12 where |r| has decreased).
    struct Atan {
        calls: std::sync::Mutex<Vec<(char, f64)>>,
    }

    impl ParameterSystem for Atan {
        type State = ();
        fn dim(&self) -> usize {
            1
        }
        fn residual_scale(&self) -> f64 {
            1.0
        }
        fn initial_state(&self) {}
        fn evaluate(&self, x: &[f64], _: f64, _: &(), out: &mut Linearization) -> Result<()> {
            self.calls.lock().unwrap().push(('J', x[0]));
            out.residual[0] = x[0].atan();
            out.jacobian[(0, 0)] = 1.0 / (1.0 + x[0] * x[0]);
            Ok(())
        }
        fn evaluate_residual(&self, x: &[f64], _: f64, _: &(), r: &mut [f64]) -> Result<()> {
            self.calls.lock().unwrap().push(('r', x[0]));
            r[0] = x[0].atan();
            Ok(())
        }
    }

    /// The damping trials beyond the full step evaluate the residual alone; the Jacobian is
    /// evaluated at the accepted halved step before the next step, and the solution is the root
    /// x = 0 (to the tolerance, |atan x| ≤ 1e-8).
    #[test]
    fn damping_trials_evaluate_the_residual_alone() {
        let system = Atan {
            calls: std::sync::Mutex::new(Vec::new()),
        };
        let sol = solve_fixed(&system, &[3.0], 0.0, &(), &NewtonOptions::default()).unwrap();
        assert!(sol.x[0].abs() <= 1e-8, "{}", sol.x[0]);
        let calls = system.calls.lock().unwrap().clone();
        let kinds: String = calls.iter().map(|c| c.0).collect();
        assert!(kinds.starts_with("JJrrJ"), "{calls:?}");
        let x1 = 3.0 - 3.0_f64.atan() * 10.0;
        assert!(
            (calls[1].1 - x1).abs() <= 1e-12
                && (calls[3].1 - (3.0 + 0.25 * (x1 - 3.0))).abs() <= 1e-12
        );
        assert_eq!(calls[4].1, calls[3].1);
        // every residual-only evaluation is a halved trial: the full step of each iteration
        // (the evaluation after a Jacobian one, or the first) carries the Jacobian
        assert_eq!(kinds.matches('r').count(), 2, "{kinds}");
        assert_eq!(
            sol.linearization.jacobian[(0, 0)],
            1.0 / (1.0 + sol.x[0] * sol.x[0])
        );
    }
}
