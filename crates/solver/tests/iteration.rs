//! How an iteration ends and what it reads: the predicted-reduction stop spends no confirming
//! evaluation, the columns of fixed parameters are never read (a problem may leave them
//! unwritten), and a non-finite Jacobian entry in a free column is named.

use metrocell_solver::{solve, NotEvaluable, Options, Problem, SolverError, Termination};
use nalgebra::{DMatrix, DVector};

/// r = A·x − y, with `poison` written into the Jacobian columns the solver says it does not want
/// (and, with `poison_free`, into one free entry).
struct Linear {
    a: DMatrix<f64>,
    y: Vec<f64>,
    poison: f64,
    poison_free: Option<(usize, usize)>,
}

impl Linear {
    fn new(m: usize, n: usize) -> Self {
        let a = DMatrix::from_fn(m, n, |i, k| ((i * 7 + k * 13) % 17) as f64 / 17.0 - 0.4 + if i == k { 1.0 } else { 0.0 });
        let y = (0..m).map(|i| (i as f64 * 0.37).sin()).collect();
        Linear { a, y, poison: 0.0, poison_free: None }
    }
}

impl Problem for Linear {
    fn residual_count(&self) -> usize {
        self.a.nrows()
    }
    fn parameter_count(&self) -> usize {
        self.a.ncols()
    }
    fn residuals(&self, x: &[f64], r: &mut [f64]) -> Result<(), NotEvaluable> {
        let ax = &self.a * DVector::from_column_slice(x);
        for (ri, (axi, yi)) in r.iter_mut().zip(ax.iter().zip(&self.y)) {
            *ri = axi - yi;
        }
        Ok(())
    }
    fn residuals_and_jacobian(&self, x: &[f64], r: &mut [f64], j: &mut DMatrix<f64>) -> Result<(), NotEvaluable> {
        self.residuals_and_jacobian_of(x, r, j, &vec![true; self.a.ncols()])
    }
    fn residuals_and_jacobian_of(&self, x: &[f64], r: &mut [f64], j: &mut DMatrix<f64>, wanted: &[bool]) -> Result<(), NotEvaluable> {
        self.residuals(x, r)?;
        for k in 0..self.a.ncols() {
            if wanted[k] {
                j.column_mut(k).copy_from(&self.a.column(k));
            } else {
                j.column_mut(k).fill(self.poison);
            }
        }
        if let Some(entry) = self.poison_free {
            j[entry] = f64::NAN;
        }
        Ok(())
    }
}

#[test]
fn a_linear_problem_stops_after_one_exact_step_without_a_confirming_trial() {
    let problem = Linear::new(40, 5);
    // gtol 0: the gradient test, which also ends a solve at an exact minimum, stays out of it
    let options = Options { initial_damping: 0.0, gtol: 0.0, ..Options::default() };
    let s = solve(&problem, &[0.0; 5], &options).unwrap();
    // the undamped first step lands on the minimum; at its linearisation the Gauss–Newton step
    // predicts no further reduction, so the solve ends there: the start and one trial
    assert_eq!((s.iterations, s.evaluations, s.termination), (1, 2, Termination::Cost));
    let x_ref = problem.a.clone().svd(true, true).solve(&DVector::from_column_slice(&problem.y), 1e-14).unwrap();
    for k in 0..5 {
        assert!((s.x[k] - x_ref[k]).abs() < 1e-12 * x_ref.amax(), "x[{k}] = {} against {}", s.x[k], x_ref[k]);
    }
}

#[test]
fn the_columns_of_fixed_parameters_are_never_read() {
    let mut problem = Linear::new(40, 5);
    let fixed = vec![false, true, false, false, true];
    let start = [0.0, 0.25, 0.0, 0.0, -0.5];
    let options = Options { fixed: fixed.clone(), ..Options::default() };
    problem.poison = 0.0;
    let clean = solve(&problem, &start, &options).unwrap();
    problem.poison = f64::NAN;
    let poisoned = solve(&problem, &start, &options).expect("NaN in unwanted columns must not be read");
    assert_eq!(clean.x, poisoned.x);
    assert_eq!(clean.covariance_unscaled, poisoned.covariance_unscaled);
    assert_eq!((poisoned.x[1], poisoned.x[4]), (0.25, -0.5), "fixed parameters keep their start");
    // the identifiability analysis sees the free columns only; the fixed ones are zero
    for k in [1, 4] {
        assert!(poisoned.weighted_jacobian.column(k).iter().all(|v| *v == 0.0));
        assert!(poisoned.normal_matrix.column(k).iter().all(|v| *v == 0.0));
    }
    let id = poisoned.identifiability(&["a", "b", "c", "d", "e"], Some(1e-6)).unwrap();
    assert_eq!(id.rank, 3);
}

#[test]
fn a_non_finite_entry_of_a_free_column_is_named() {
    let mut problem = Linear::new(40, 5);
    problem.poison_free = Some((17, 3));
    match solve(&problem, &[0.0; 5], &Options::default()) {
        Err(SolverError::StartNotEvaluable(why)) => assert!(why.contains("Jacobian entry (17, 3)"), "{why}"),
        other => panic!("expected the start to be not evaluable, got {other:?}"),
    }
}
