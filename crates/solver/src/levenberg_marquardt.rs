//! Levenberg–Marquardt with Moré's scaling, IRLS robust weights, projected box bounds, a
//! fixed-parameter mask and Gaussian priors.
//!
//! Each iteration solves (A + λ·D²)·δ = −g on the free parameters, where A = J̃ᵀWJ̃ and g = J̃ᵀWr̃
//! are built from the whitened residuals r̃ᵢ = rᵢ/σᵢ with the robust weights Wᵢ = ρ'(r̃ᵢ²) of the
//! current point (iteratively reweighted least squares; Triggs' second-order correction is left
//! out because with Cauchy's ρ'' < 0 it can make A indefinite, and the fixed point is the same).
//! D is Moré's scaling, the largest column norm of J̃ seen so far, which makes the steps invariant
//! to the parameters' units. λ follows Nielsen's gain-ratio rule. A bound is active when the
//! parameter sits on it and the gradient pushes outward; active parameters are held for the step
//! and the trial point is projected onto the box.

use crate::error::{check_finite, check_len, NotEvaluable, SolverError};
use crate::normal_equations::{
    accumulate_free, cholesky_solve_in_place, first_non_finite, free_inverse, gradient_free,
    scaled_free_block, scatter_free,
};
use crate::options::{NullSpace, Options};
use crate::problem::Problem;
use crate::solution::{Solution, Termination};
use crate::zeroed::{clear_column, zeroed_matrix};
use nalgebra::{DMatrix, DVector};

/// Largest damping (relative to the unit-diagonal scaled A) tried before giving up on a step.
const MAX_DAMPING: f64 = 1e16;

struct Workspace {
    /// Residuals at the current point as the problem returned them.
    raw: Vec<f64>,
    /// The same whitened and robust-weighted: √ρ'ᵢ·rᵢ/σᵢ.
    r: Vec<f64>,
    /// The Jacobian at the current point as the problem returned it (m × n; the columns of fixed
    /// parameters are never read).
    j: DMatrix<f64>,
    /// The parameters that are not fixed, in order: the columns the normal equations are built from.
    free: Vec<usize>,
    /// The same as a mask over all n parameters (the columns asked of the problem).
    wanted: Vec<bool>,
    /// The trial point's Jacobian, when trials are evaluated with it (swapped in on acceptance).
    trial_j: DMatrix<f64>,
    inv_sigma: Vec<f64>,
    row_scale: Vec<f64>,
    /// J̃ᵀJ̃ + the priors' information: the normal matrix of the steps.
    a: DMatrix<f64>,
    /// J̃ᵀJ̃ alone.
    normal: DMatrix<f64>,
    g: DVector<f64>,
    m: DMatrix<f64>,
    rhs: Vec<f64>,
}

/// ½·Σ ρ(r̃ᵢ²) + ½·Σ priors², or None if not finite.
fn cost(r: &[f64], inv_sigma: &[f64], x: &[f64], options: &Options) -> Option<f64> {
    let mut c = 0.0;
    for (ri, si) in r.iter().zip(inv_sigma) {
        let z = ri * si;
        c += options.loss.evaluate(z * z).0;
    }
    for p in &options.priors {
        let z = (x[p.index] - p.value) / p.sigma;
        c += z * z;
    }
    let c = 0.5 * c;
    c.is_finite().then_some(c)
}

/// r(x) and the free columns of J(x) into the buffers (`wanted`: the free mask), with
/// non-finite values reported as not evaluable.
fn evaluate<P: Problem + ?Sized>(
    problem: &P,
    x: &[f64],
    r: &mut [f64],
    j: &mut DMatrix<f64>,
    free: &[usize],
    wanted: &[bool],
) -> Result<(), NotEvaluable> {
    problem.residuals_and_jacobian_of(x, r, j, wanted)?;
    check_evaluated(r, j, free)
}

/// Every residual and every Jacobian entry of the free columns finite, or the first that is not.
fn check_evaluated(r: &[f64], j: &DMatrix<f64>, free: &[usize]) -> Result<(), NotEvaluable> {
    if let Some(i) = r.iter().position(|v| !v.is_finite()) {
        return Err(NotEvaluable(format!("residual {i} is {}", r[i])));
    }
    match first_non_finite(j, free) {
        Some((i, k)) => Err(NotEvaluable(format!(
            "Jacobian entry ({i}, {k}) is not finite"
        ))),
        None => Ok(()),
    }
}

impl Workspace {
    /// Evaluates r and J at x, then linearises (see [`Workspace::weigh`]).
    fn linearise<P: Problem + ?Sized>(
        &mut self,
        problem: &P,
        x: &[f64],
        options: &Options,
    ) -> Result<f64, NotEvaluable> {
        evaluate(
            problem,
            x,
            &mut self.r,
            &mut self.j,
            &self.free,
            &self.wanted,
        )?;
        self.weigh_own(x, options)
    }

    /// [`Workspace::weigh`] of the workspace's own Jacobian `j`.
    fn weigh_own(&mut self, x: &[f64], options: &Options) -> Result<f64, NotEvaluable> {
        self.weigh_own_knowing(x, options, None)
    }

    /// [`Workspace::weigh_own`], with the free columns' JᵀJ already formed (`known_normal`, see
    /// [`Evaluated::normal_matrix`]).
    fn weigh_own_knowing(
        &mut self,
        x: &[f64],
        options: &Options,
        known_normal: Option<&DMatrix<f64>>,
    ) -> Result<f64, NotEvaluable> {
        let j = std::mem::replace(&mut self.j, DMatrix::zeros(0, 0));
        let f = self.weigh(&j, x, options, known_normal);
        self.j = j;
        f
    }

    /// With r (in `self.r`) and the Jacobian `j` evaluated at x, both checked finite: whitens
    /// and robust-weights r in place, and forms A, g from the weighted free columns of J (zero
    /// in the rows and columns of fixed parameters). Returns the cost at x. A `known_normal`
    /// (the unweighted free columns' JᵀJ) stands in for A's product when every row's weight is
    /// exactly 1, the case it was formed for; otherwise it is ignored.
    fn weigh(
        &mut self,
        j: &DMatrix<f64>,
        x: &[f64],
        options: &Options,
        known_normal: Option<&DMatrix<f64>>,
    ) -> Result<f64, NotEvaluable> {
        self.raw.copy_from_slice(&self.r);
        let f = cost(&self.raw, &self.inv_sigma, x, options)
            .ok_or_else(|| NotEvaluable("cost is not finite".into()))?;
        for ((q, ri), si) in self.row_scale.iter_mut().zip(&self.r).zip(&self.inv_sigma) {
            let z = ri * si;
            *q = si * options.loss.evaluate(z * z).1.sqrt();
        }
        for (v, s) in self.r.iter_mut().zip(&self.row_scale) {
            *v *= s;
        }
        let nf = self.free.len();
        match known_normal
            .filter(|a| a.shape() == (nf, nf) && self.row_scale.iter().all(|s| *s == 1.0))
        {
            Some(known) => {
                scatter_free(known, &self.free, &mut self.a);
                gradient_free(j, &self.free, &self.r, &mut self.g);
            }
            None => accumulate_free(
                j,
                &self.free,
                &self.row_scale,
                Some(&self.r),
                &mut self.a,
                &mut self.g,
            ),
        }
        // J̃ᵀJ̃ as the measurements alone give it, for the identifiability analysis
        self.normal.copy_from(&self.a);
        for p in &options.priors {
            let k = p.index;
            self.a[(k, k)] += 1.0 / (p.sigma * p.sigma);
            self.g[k] += (x[k] - p.value) / (p.sigma * p.sigma);
        }
        Ok(f)
    }
}

/// The most λ falls after one accepted step, ×1/10: Marquardt's own factor. Nielsen's update
/// (1 − (2ρ − 1)³) reaches its usual floor of 1/3 whenever the quadratic model predicts the
/// step well (ρ ≈ 1); on a nearly linear calibration problem (the 21 geometric errors of an XFYZ
/// machine, 10 000 tracker readings) that floor spent five extra iterations walking λ down from
/// its start at 1e-3 while every step was already accepted with ρ > 0.99. A rejected step still
/// raises λ by ν = 2, 4, 8, …, so a too-bold decrease costs one extra evaluation at worst.
const DAMPING_DECREASE_FLOOR: f64 = 0.1;

/// Minimises the problem's cost from `x0`. See the module docs for the method.
pub fn solve<P: Problem + ?Sized>(
    problem: &P,
    x0: &[f64],
    options: &Options,
) -> Result<Solution, SolverError> {
    solve_from(problem, x0, None, options)
}

/// The residuals r(x0) and Jacobian J(x0) a caller already has (e.g. from checking what the
/// design identifies before solving), so that [`solve_from`] need not evaluate them again.
/// Handed over rather than lent: the solver works in the given buffers, so a solve from a given
/// start allocates (and the kernel faults in) one m × n Jacobian fewer. Only the columns of
/// free parameters are read.
pub struct Evaluated {
    pub residuals: Vec<f64>,
    pub jacobian: DMatrix<f64>,
    /// JᵀJ of the Jacobian's free columns as [`crate::normal_matrix`] forms it (unit weights,
    /// the columns the options leave free, in order), when the caller has formed it already
    /// (to judge what the design identifies): the solver's first normal matrix is then not
    /// formed twice. Used only when every residual's weight is exactly 1 (no σ given, and a
    /// linear loss or none of the residuals beyond a robust loss's threshold).
    pub normal_matrix: Option<DMatrix<f64>>,
}

/// [`solve`], starting from r and J already evaluated at `x0` (used as given when `x0` lies
/// within the bounds and the shapes fit; otherwise the clamped start is evaluated afresh).
///
/// Each iteration: Moré's scaling and the active bounds updated (`scale_and_activity`), the
/// stopping tests (gradient, the Gauss–Newton step's predicted reduction, iterations), damped
/// trial steps until one lowers the cost (`try_steps`), and the accepted point linearised.
pub fn solve_from<P: Problem + ?Sized>(
    problem: &P,
    x0: &[f64],
    at_start: Option<Evaluated>,
    options: &Options,
) -> Result<Solution, SolverError> {
    let (m, n) = (problem.residual_count(), problem.parameter_count());
    check_len("start x0", n, x0.len())?;
    check_finite("start x0", x0)?;
    options.validate(m, n)?;
    let (lower, upper) = match &options.bounds {
        Some((lo, hi)) => (lo.clone(), hi.clone()),
        None => (vec![f64::NEG_INFINITY; n], vec![f64::INFINITY; n]),
    };
    let bounds = Bounds { lower, upper };
    let mut x: Vec<f64> = (0..n)
        .map(|k| x0[k].clamp(bounds.lower[k], bounds.upper[k]))
        .collect();
    let given = at_start
        .filter(|e| x.as_slice() == x0 && e.residuals.len() == m && e.jacobian.shape() == (m, n));
    let evaluate_start = given.is_none();
    let (mut ws, known_normal) = Workspace::at_start(given, m, n, options);
    let mut trial = Trial {
        x: vec![0.0; n],
        r: vec![0.0; m],
        delta: vec![0.0; n],
        ad: vec![0.0; n],
    };
    let mut active = vec![false; n];
    let mut d = vec![0.0f64; n];

    let mut f = if evaluate_start {
        ws.linearise(problem, &x, options)
    } else {
        check_evaluated(&ws.r, &ws.j, &ws.free)
            .and_then(|()| ws.weigh_own_knowing(&x, options, known_normal.as_ref()))
    }
    .map_err(|e| SolverError::StartNotEvaluable(e.0))?;
    let mut damping = Damping {
        lambda: options.initial_damping,
        nu: 2.0,
    };
    let mut iterations = 0;
    let mut evaluations = 1;
    let termination = loop {
        scale_and_activity(&ws, &x, &bounds, options, &mut d, &mut active);
        // Cosine between the residual vector and each free column of J̃.
        let rnorm = (2.0 * f).sqrt();
        let gmax = (0..n)
            .filter(|&k| !active[k])
            .map(|k| ws.g[k].abs() / (ws.a[(k, k)].sqrt() * rnorm).max(f64::MIN_POSITIVE))
            .fold(0.0, f64::max);
        if f == 0.0 || gmax <= options.gtol {
            break Termination::Gradient;
        }
        // the most any step can lower the cost here, by the quadratic model: the undamped
        // (Gauss–Newton) step's predicted reduction ½·gᵀA⁻¹g. When it is under ftol of the cost,
        // the point is the minimum to the tolerance and a trial would only confirm it at the
        // price of an evaluation. Not taken when A is singular
        // on the free parameters with undamped steps (the step is then not defined).
        if damped_step(
            &mut ws,
            &d,
            &active,
            0.0,
            options.null_space,
            &mut trial.delta,
        ) {
            let predicted = predicted_reduction(&ws, &trial.delta, &mut trial.ad);
            if (0.0..=options.ftol * f).contains(&predicted) {
                break Termination::Cost;
            }
        }
        if iterations >= options.max_iterations {
            break Termination::MaxIterations;
        }
        iterations += 1;
        let step = Step {
            x: &x,
            f,
            d: &d,
            active: &active,
        };
        let outcome = try_steps(
            problem,
            &mut ws,
            &step,
            &bounds,
            options,
            &mut damping,
            &mut trial,
            &mut evaluations,
        );
        let (ft, rho, small_step) = match outcome {
            StepOutcome::Accepted {
                cost,
                rho,
                small_step,
            } => (cost, rho, small_step),
            StepOutcome::Converged => break Termination::Cost,
            StepOutcome::Failed => {
                break if damping.lambda > MAX_DAMPING {
                    Termination::NoDescent
                } else {
                    Termination::Step
                };
            }
        };
        std::mem::swap(&mut x, &mut trial.x);
        let reduction = f - ft;
        // The cost is recomputed from the accepted point's residuals (the same as the trial's)
        // so that f always matches ws.
        f = if options.jacobian_on_trials {
            std::mem::swap(&mut ws.r, &mut trial.r);
            std::mem::swap(&mut ws.j, &mut ws.trial_j);
            ws.weigh_own(&x, options)
        } else {
            ws.linearise(problem, &x, options)
        }
        .map_err(|e| SolverError::SolutionNotEvaluable(e.0))?;
        if reduction <= options.ftol * (f + reduction) && rho > 0.25 {
            break Termination::Cost;
        }
        if small_step {
            break Termination::Step;
        }
    };
    finish(
        ws,
        x,
        f,
        iterations,
        evaluations,
        termination,
        damping.lambda,
        options,
    )
}

/// The parameters' box: lower and upper bounds (infinite where unbounded).
struct Bounds {
    lower: Vec<f64>,
    upper: Vec<f64>,
}

/// λ and its growth factor ν (Nielsen).
struct Damping {
    lambda: f64,
    nu: f64,
}

impl Damping {
    /// Damp harder after a failed step: λ ×ν, ν doubled; true once λ exceeds its maximum (the
    /// step is given up).
    fn raise_past_max(&mut self) -> bool {
        self.lambda *= self.nu;
        self.nu *= 2.0;
        self.lambda > MAX_DAMPING
    }
}

/// Scratch of the trial steps: the trial point, its residuals, the step δ, and Aδ.
struct Trial {
    x: Vec<f64>,
    r: Vec<f64>,
    delta: Vec<f64>,
    ad: Vec<f64>,
}

/// The point the trials start from: x, its cost f, Moré's scaling d, the parameters held for
/// the step (fixed or on an active bound).
struct Step<'s> {
    x: &'s [f64],
    f: f64,
    d: &'s [f64],
    active: &'s [bool],
}

/// What the damped trials from one point came to.
enum StepOutcome {
    /// A step lowered the cost: the trial's cost, the gain ratio ρ, whether the step was below
    /// xtol.
    Accepted {
        cost: f64,
        rho: f64,
        small_step: bool,
    },
    /// At the minimum to the tolerance: a rejection there is round-off.
    Converged,
    /// No step lowered the cost (λ beyond its maximum, or the step below xtol).
    Failed,
}

impl Workspace {
    /// The workspace at the start: the caller's r and J (and JᵀJ when formed) when `given`,
    /// else zeroed buffers the first linearisation fills.
    fn at_start(
        given: Option<Evaluated>,
        m: usize,
        n: usize,
        options: &Options,
    ) -> (Self, Option<DMatrix<f64>>) {
        let (r, j, known_normal) = match given {
            Some(e) => (e.residuals, e.jacobian, e.normal_matrix),
            None => (vec![0.0; m], zeroed_matrix(m, n), None),
        };
        let inv_sigma: Vec<f64> = match &options.sigmas {
            Some(s) => s.iter().map(|v| 1.0 / v).collect(),
            None => vec![1.0; m],
        };
        let ws = Workspace {
            raw: vec![0.0; m],
            r,
            j,
            wanted: (0..n).map(|k| !options.is_fixed(k)).collect(),
            free: (0..n).filter(|&k| !options.is_fixed(k)).collect(),
            trial_j: if options.jacobian_on_trials {
                zeroed_matrix(m, n)
            } else {
                DMatrix::zeros(0, 0)
            },
            inv_sigma,
            row_scale: vec![1.0; m],
            a: DMatrix::zeros(n, n),
            normal: DMatrix::zeros(n, n),
            g: DVector::zeros(n),
            m: DMatrix::zeros(n, n),
            rhs: vec![0.0; n],
        };
        (ws, known_normal)
    }
}

/// Moré's scaling `d` (the largest column norm of J̃ seen so far, 1 for a nil column) and the
/// parameters held for the step: fixed, or on a bound the gradient pushes them out of.
fn scale_and_activity(
    ws: &Workspace,
    x: &[f64],
    bounds: &Bounds,
    options: &Options,
    d: &mut [f64],
    active: &mut [bool],
) {
    for k in 0..d.len() {
        d[k] = d[k].max(ws.a[(k, k)].sqrt());
        if d[k] == 0.0 {
            d[k] = 1.0;
        }
        active[k] = options.is_fixed(k)
            || (x[k] <= bounds.lower[k] && ws.g[k] > 0.0)
            || (x[k] >= bounds.upper[k] && ws.g[k] < 0.0);
    }
}

/// Damped steps from `step`, projected onto the box, until one lowers the cost (λ lowered after
/// it by the gain ratio), the point is the minimum to the tolerance, or none can.
#[allow(clippy::too_many_arguments)]
fn try_steps<P: Problem + ?Sized>(
    problem: &P,
    ws: &mut Workspace,
    step: &Step,
    bounds: &Bounds,
    options: &Options,
    damping: &mut Damping,
    trial: &mut Trial,
    evaluations: &mut usize,
) -> StepOutcome {
    let (n, f) = (step.x.len(), step.f);
    loop {
        if !damped_step(
            ws,
            step.d,
            step.active,
            damping.lambda,
            options.null_space,
            &mut trial.delta,
        ) {
            if damping.raise_past_max() {
                return StepOutcome::Failed;
            }
            continue;
        }
        problem.retract(step.x, &trial.delta, &mut trial.x);
        for k in 0..n {
            let clamped = trial.x[k].clamp(bounds.lower[k], bounds.upper[k]);
            trial.delta[k] += clamped - trial.x[k];
            trial.x[k] = clamped;
        }
        let (mut step_norm, mut x_norm) = (0.0, 0.0);
        for k in 0..n {
            step_norm += (step.d[k] * trial.delta[k]).powi(2);
            x_norm += (step.d[k] * step.x[k]).powi(2);
        }
        let small_step = step_norm.sqrt() <= options.xtol * (options.xtol + x_norm.sqrt());
        let predicted = predicted_reduction(ws, &trial.delta, &mut trial.ad);
        *evaluations += 1;
        let evaluated = if options.jacobian_on_trials {
            evaluate(
                problem,
                &trial.x,
                &mut trial.r,
                &mut ws.trial_j,
                &ws.free,
                &ws.wanted,
            )
        } else {
            problem.residuals(&trial.x, &mut trial.r)
        };
        let trial_cost = match evaluated {
            Ok(()) => cost(&trial.r, &ws.inv_sigma, &trial.x, options),
            Err(_) => None,
        };
        match trial_cost {
            Some(ft) if ft < f && predicted > 0.0 => {
                let rho = (f - ft) / predicted;
                damping.lambda *= DAMPING_DECREASE_FLOOR.max(1.0 - (2.0 * rho - 1.0).powi(3));
                damping.nu = 2.0;
                return StepOutcome::Accepted {
                    cost: ft,
                    rho,
                    small_step,
                };
            }
            _ => {
                // at the minimum the quadratic model predicts a reduction below ftol of the
                // cost and the trial's cost differs from it only by round-off, either way: a
                // rejection there is noise, not a sign to damp harder (MINPACK's test on
                // actual and predicted reduction, info = 1)
                if let Some(ft) = trial_cost {
                    let tiny = options.ftol * f;
                    if (0.0..=tiny).contains(&predicted) && (ft - f).abs() <= tiny {
                        return StepOutcome::Converged;
                    }
                }
                if small_step || damping.raise_past_max() {
                    return StepOutcome::Failed;
                }
            }
        }
    }
}

/// The quadratic model's reduction of the cost by the step δ: −gᵀδ − ½δᵀAδ (`ad`: scratch for Aδ).
fn predicted_reduction(ws: &Workspace, delta: &[f64], ad: &mut [f64]) -> f64 {
    let n = delta.len();
    for (i, adi) in ad.iter_mut().enumerate() {
        *adi = (0..n).map(|k| ws.a[(i, k)] * delta[k]).sum();
    }
    (0..n)
        .map(|k| -ws.g[k] * delta[k] - 0.5 * delta[k] * ad[k])
        .sum()
}

/// (A + λ·D²)·δ = −g with the active parameters held (δₖ = 0), into `delta`. False if the
/// damped matrix is not positive definite (the caller raises λ).
fn damped_step(
    ws: &mut Workspace,
    d: &[f64],
    active: &[bool],
    lambda: f64,
    null_space: NullSpace,
    delta: &mut [f64],
) -> bool {
    let n = delta.len();
    if let NullSpace::Truncated { rcond } = null_space {
        let free: Vec<bool> = active.iter().map(|a| !a).collect();
        let (s, idx, dk) = scaled_free_block(&ws.a, &free);
        delta.fill(0.0);
        if idx.is_empty() {
            return true;
        }
        let eig = s.symmetric_eigen();
        let cut = rcond * rcond * eig.eigenvalues.max();
        let gs: Vec<f64> = idx.iter().zip(&dk).map(|(&k, dk)| ws.g[k] / dk).collect();
        for e in 0..idx.len() {
            let l = eig.eigenvalues[e];
            if l <= cut {
                continue;
            }
            let v = eig.eigenvectors.column(e);
            let coef = -(0..idx.len()).map(|i| v[i] * gs[i]).sum::<f64>() / (l + lambda);
            for (i, &k) in idx.iter().enumerate() {
                delta[k] += coef * v[i] / dk[i];
            }
        }
        return delta.iter().all(|v| v.is_finite());
    }
    ws.m.copy_from(&ws.a);
    for k in 0..n {
        if active[k] {
            ws.m.row_mut(k).fill(0.0);
            ws.m.column_mut(k).fill(0.0);
            ws.m[(k, k)] = 1.0;
            ws.rhs[k] = 0.0;
        } else {
            ws.m[(k, k)] += lambda * d[k] * d[k];
            ws.rhs[k] = -ws.g[k];
        }
    }
    if !cholesky_solve_in_place(&mut ws.m, &mut ws.rhs) {
        return false;
    }
    delta.copy_from_slice(&ws.rhs);
    true
}

#[allow(clippy::too_many_arguments)]
fn finish(
    ws: Workspace,
    x: Vec<f64>,
    cost: f64,
    iterations: usize,
    evaluations: usize,
    termination: Termination,
    damping: f64,
    options: &Options,
) -> Result<Solution, SolverError> {
    let (m, n) = ws.j.shape();
    let free: Vec<bool> = (0..n).map(|k| !options.is_fixed(k)).collect();
    // √W·J at x for the identifiability analysis, the columns of fixed parameters zero: J is
    // weighted in place (a new m × n buffer is one more allocation, zeroing and pass)
    let mut weighted_jacobian = ws.j;
    // (unit weights, the linear loss without σ, leave J as it is: no pass over it)
    let weighted = ws.row_scale.iter().any(|s| *s != 1.0);
    for k in 0..n {
        if free[k] {
            if weighted {
                weighted_jacobian
                    .column_mut(k)
                    .iter_mut()
                    .zip(&ws.row_scale)
                    .for_each(|(v, s)| *v *= s);
            }
        } else {
            clear_column(&mut weighted_jacobian, k);
        }
    }
    let n_free = free.iter().filter(|f| **f).count();
    // σ̂₀² from the whitened residuals the loss keeps quadratic (all of them for the linear
    // loss): the down-weighted ones are the outliers the robust fit set aside, and counting them
    // (even with their small weights) would inflate σ̂₀² by their size. Leaving out the inliers
    // beyond c lowers σ̂₀² by under 3 % for c ≥ 3.
    let residuals = ws.raw;
    let mut weighted_ss = 0.0;
    let mut downweighted = 0;
    for (r, s) in residuals.iter().zip(&ws.inv_sigma) {
        let z2 = (r * s).powi(2);
        if options.loss.is_downweighted(z2) {
            downweighted += 1;
        } else {
            weighted_ss += z2;
        }
    }
    for p in &options.priors {
        weighted_ss += ((x[p.index] - p.value) / p.sigma).powi(2);
    }
    let observations = m - downweighted + options.priors.len();
    let dof = observations.saturating_sub(n_free);
    let residual_rms = if m > 0 {
        (residuals.iter().map(|v| v * v).sum::<f64>() / m as f64).sqrt()
    } else {
        0.0
    };
    Ok(Solution {
        covariance_unscaled: free_inverse(&ws.a, &free),
        variance_factor: (dof > 0).then(|| weighted_ss / dof as f64),
        x,
        cost,
        iterations,
        evaluations,
        termination,
        damping,
        residuals,
        residual_rms,
        degrees_of_freedom: dof,
        downweighted,
        weighted_jacobian,
        normal_matrix: ws.normal,
        free,
    })
}
