//! Known nonlinear problems solved here and by scipy.optimize.least_squares (method "trf",
//! analytic Jacobian, tolerances 1e-15): the same solution to 1e-6 relative.
//! Needs `$METROCELL_PYTHON` (a Python with scipy) or the workspace's `.venv`.

mod common;

use common::{scipy, Circle, Decay, Rosenbrock, INF};
use metrocell_solver::{solve, Options, Problem};

fn assert_same(what: &str, ours: &[f64], reference: &[f64], rel: f64) {
    for (k, (a, b)) in ours.iter().zip(reference).enumerate() {
        assert!(
            (a - b).abs() <= rel * b.abs(),
            "{what} x[{k}]: ours {a} vs scipy {b} (rel {:e})",
            (a - b).abs() / b.abs()
        );
    }
}

fn check<P: Problem>(
    name: &str,
    problem: &P,
    x0: &[f64],
    data: &[f64],
    options: &Options,
) -> Vec<f64> {
    let n = x0.len();
    let (lo, hi) = options
        .bounds
        .clone()
        .unwrap_or((vec![-INF; n], vec![INF; n]));
    let ours = solve(problem, x0, options).unwrap();
    assert!(
        ours.termination.converged(),
        "{name}: {:?}",
        ours.termination
    );
    let reference = scipy(name, x0, &lo, &hi, data);
    assert_same(name, &ours.x, &reference.x, 1e-6);
    ours.x
}

#[test]
fn rosenbrock_reaches_its_minimum_like_scipy() {
    let x = check(
        "rosenbrock",
        &Rosenbrock,
        &[-1.2, 1.0],
        &[],
        &Options::default(),
    );
    assert_same("rosenbrock vs (1, 1)", &x, &[1.0, 1.0], 1e-10);
}

#[test]
fn noisy_exponential_decay_matches_scipy() {
    let truth = [0.5, 2.0, 1.7];
    let d = Decay::simulate(11, 60, &truth, 0.03);
    let x = check(
        "decay",
        &d,
        &[0.0, 1.0, 0.5],
        &d.data(),
        &Options::default(),
    );
    // Trials evaluated without their Jacobian take the same path to the same point.
    let lean = Options {
        jacobian_on_trials: false,
        ..Options::default()
    };
    let y = check("decay", &d, &[0.0, 1.0, 0.5], &d.data(), &lean);
    assert_eq!(x, y);
    // And the fit is where the noise allows: within 4σ of the truth.
    let s = solve(&d, &[0.0, 1.0, 0.5], &Options::default()).unwrap();
    let u = s.standard_uncertainties().unwrap();
    for k in 0..3 {
        assert!(
            (x[k] - truth[k]).abs() < 4.0 * u[k],
            "x[{k}] = {} ± {} vs {}",
            x[k],
            u[k],
            truth[k]
        );
    }
}

#[test]
fn circle_fit_on_a_short_arc_matches_scipy() {
    let d = Circle::simulate(5, 40, &[0.3, -0.2, 1.5], 2.0, 0.01);
    check(
        "circle",
        &d,
        &[0.0, 0.0, 1.0],
        &d.data(),
        &Options::default(),
    );
}

#[test]
fn bounded_decay_matches_scipy_with_the_bound_active() {
    // τ's true value 1.7 lies above the upper bound 1.2: the constrained minimum sits on it.
    let d = Decay::simulate(12, 60, &[0.5, 2.0, 1.7], 0.03);
    let bounds = (vec![-1.0, 0.0, 0.1], vec![1.0, 5.0, 1.2]);
    let options = Options {
        bounds: Some(bounds.clone()),
        ..Options::default()
    };
    let x = check("decay", &d, &[0.0, 1.0, 0.5], &d.data(), &options);
    assert_eq!(x[2], 1.2, "τ on its upper bound");
    for k in 0..3 {
        assert!(
            x[k] >= bounds.0[k] && x[k] <= bounds.1[k],
            "x[{k}] = {} outside the box",
            x[k]
        );
    }
}
