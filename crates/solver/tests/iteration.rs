//! How an iteration ends and what it reads: the predicted-reduction stop spends no confirming
//! evaluation, the columns of fixed parameters are never read (a problem may leave them
//! unwritten), and a non-finite Jacobian entry in a free column is named.

use metrocell_solver::{solve, solve_from, Evaluated, Options, Problem, SolverError, Termination};
use nalgebra::{DMatrix, DVector};

mod common;

use common::Linear;

/// A well-conditioned m × n linear problem.
fn linear(m: usize, n: usize) -> Linear {
    let a = DMatrix::from_fn(m, n, |i, k| {
        ((i * 7 + k * 13) % 17) as f64 / 17.0 - 0.4 + if i == k { 1.0 } else { 0.0 }
    });
    let y = (0..m).map(|i| (i as f64 * 0.37).sin()).collect();
    Linear::new(a, y)
}

#[test]
fn a_linear_problem_stops_after_one_exact_step_without_a_confirming_trial() {
    let problem = linear(40, 5);
    // gtol 0: the gradient test, which also ends a solve at an exact minimum, stays out of it
    let options = Options {
        initial_damping: 0.0,
        gtol: 0.0,
        ..Options::default()
    };
    let s = solve(&problem, &[0.0; 5], &options).unwrap();
    // the undamped first step lands on the minimum; at its linearisation the Gauss–Newton step
    // predicts no further reduction, so the solve ends there: the start and one trial
    assert_eq!(
        (s.iterations, s.evaluations, s.termination),
        (1, 2, Termination::Cost)
    );
    let x_ref = problem
        .a
        .clone()
        .svd(true, true)
        .solve(&DVector::from_column_slice(&problem.y), 1e-14)
        .unwrap();
    for k in 0..5 {
        assert!(
            (s.x[k] - x_ref[k]).abs() < 1e-12 * x_ref.amax(),
            "x[{k}] = {} against {}",
            s.x[k],
            x_ref[k]
        );
    }
}

#[test]
fn the_columns_of_fixed_parameters_are_never_read() {
    let mut problem = linear(40, 5);
    let fixed = vec![false, true, false, false, true];
    let start = [0.0, 0.25, 0.0, 0.0, -0.5];
    let options = Options {
        fixed: fixed.clone(),
        ..Options::default()
    };
    problem.unwanted = 0.0;
    let clean = solve(&problem, &start, &options).unwrap();
    problem.unwanted = f64::NAN;
    let poisoned =
        solve(&problem, &start, &options).expect("NaN in unwanted columns must not be read");
    assert_eq!(clean.x, poisoned.x);
    assert_eq!(clean.covariance_unscaled, poisoned.covariance_unscaled);
    assert_eq!(
        (poisoned.x[1], poisoned.x[4]),
        (0.25, -0.5),
        "fixed parameters keep their start"
    );
    // the identifiability analysis sees the free columns only; the fixed ones are zero
    for k in [1, 4] {
        assert!(poisoned
            .weighted_jacobian
            .column(k)
            .iter()
            .all(|v| *v == 0.0));
        assert!(poisoned.normal_matrix.column(k).iter().all(|v| *v == 0.0));
    }
    let id = poisoned
        .identifiability(&["a", "b", "c", "d", "e"], Some(1e-6))
        .unwrap();
    assert_eq!(id.rank, 3);
}

#[test]
fn a_non_finite_entry_of_a_free_column_is_named() {
    let mut problem = linear(40, 5);
    problem.nan_at = Some((17, 3));
    match solve(&problem, &[0.0; 5], &Options::default()) {
        Err(SolverError::StartNotEvaluable(why)) => {
            assert!(why.contains("Jacobian entry (17, 3)"), "{why}")
        }
        other => panic!("expected the start to be not evaluable, got {other:?}"),
    }
}

#[test]
fn a_solve_that_starts_at_its_minimum_reports_the_given_jacobian() {
    let problem = linear(40, 5);
    let options = Options {
        fixed: vec![false, false, true, false, false],
        ..Options::default()
    };
    let x_min = solve(&problem, &[0.0; 5], &options).unwrap().x;
    let (mut r, mut j) = (vec![0.0; 40], DMatrix::zeros(40, 5));
    problem
        .residuals_and_jacobian(&x_min, &mut r, &mut j)
        .unwrap();
    // given r and J at the minimum, no step is taken: the solution's weighted Jacobian must be
    // the given one (unit weights here)
    let s = solve_from(
        &problem,
        &x_min,
        Some(Evaluated {
            residuals: r,
            jacobian: j.clone(),
            normal_matrix: None,
        }),
        &options,
    )
    .unwrap();
    assert_eq!((s.iterations, s.evaluations), (0, 1), "{:?}", s.termination);
    for k in [0, 1, 3, 4] {
        assert_eq!(s.weighted_jacobian.column(k), j.column(k), "column {k}");
    }
    assert!(
        s.weighted_jacobian.column(2).iter().all(|v| *v == 0.0),
        "the fixed column is zero"
    );
    assert_eq!(
        s.identifiability(&["a", "b", "c", "d", "e"], None)
            .unwrap()
            .rank,
        4
    );
}

#[test]
fn a_given_normal_matrix_stands_in_for_the_first_product_only_under_unit_weights() {
    let problem = linear(40, 5);
    let fixed = vec![false, false, true, false, false];
    let free = [0, 1, 3, 4];
    let x0 = [0.0; 5];
    let (mut r, mut j) = (vec![0.0; 40], DMatrix::zeros(40, 5));
    problem.residuals_and_jacobian(&x0, &mut r, &mut j).unwrap();
    let normal = metrocell_solver::normal_matrix(&j, &free);
    let given = |normal: Option<DMatrix<f64>>| {
        Some(Evaluated {
            residuals: r.clone(),
            jacobian: j.clone(),
            normal_matrix: normal,
        })
    };
    // one undamped step from x0: its length is set by the first normal matrix
    let one_step = Options {
        fixed: fixed.clone(),
        max_iterations: 1,
        initial_damping: 0.0,
        ..Options::default()
    };
    let plain = solve(&problem, &x0, &one_step).unwrap();
    let known = solve_from(&problem, &x0, given(Some(normal.clone())), &one_step).unwrap();
    for k in 0..5 {
        assert!(
            (known.x[k] - plain.x[k]).abs()
                <= 1e-12 * plain.x.iter().fold(0.0f64, |a, v| a.max(v.abs())),
            "x[{k}]: {} against {}",
            known.x[k],
            plain.x[k]
        );
    }
    // the matrix given is the one used: twice JᵀJ halves the first step
    let doubled = solve_from(&problem, &x0, given(Some(&normal * 2.0)), &one_step).unwrap();
    for &k in &free {
        assert!(
            (doubled.x[k] - 0.5 * plain.x[k]).abs() <= 1e-9 * plain.x[k].abs().max(1e-12),
            "x[{k}]: {} against half of {}",
            doubled.x[k],
            plain.x[k]
        );
    }
    // with weights other than 1 (σ given) it was not formed for these rows, and is ignored
    let weighted = Options {
        sigmas: Some(vec![0.5; 40]),
        ..one_step.clone()
    };
    let plain = solve(&problem, &x0, &weighted).unwrap();
    let ignored = solve_from(&problem, &x0, given(Some(&normal * 2.0)), &weighted).unwrap();
    assert_eq!(ignored.x, plain.x);
}
