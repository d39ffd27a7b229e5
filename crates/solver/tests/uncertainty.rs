//! Honest uncertainty: robust fits ignore gross outliers, rank deficiency is named, and the
//! reported covariance covers the truth as often as a Gaussian says (a coverage test).

mod common;

use common::{normal, rng, Decay, Linear};
use metrocell_solver::{
    monte_carlo, solve, Loss, Noise, NullSpace, Options, Prior, SolverError, Termination,
};
use nalgebra::{DMatrix, DVector};
use rand::Rng;

/// Fraction of (trial, parameter) pairs with |x̂ − x| ≤ kσ̂, for k = 1 and 3.
fn coverage(hits: &[(f64, f64)]) -> (f64, f64) {
    let n = hits.len() as f64;
    let within = |k: f64| hits.iter().filter(|(err, s)| err.abs() <= k * s).count() as f64 / n;
    (within(1.0), within(3.0))
}

#[test]
fn reported_covariance_covers_the_truth_linear_gaussian() {
    let mut r = rng(2024);
    let truth = [1.5, -0.7, 0.02, 3.0];
    let mut hits = Vec::new();
    for _ in 0..250 {
        let a = DMatrix::from_fn(25, 4, |_, _| r.random::<f64>() * 2.0 - 1.0);
        let sigma = 0.05;
        let ax = &a * DVector::from_column_slice(&truth);
        let y = ax.iter().map(|v| v + sigma * normal(&mut r)).collect();
        let s = solve(&Linear::new(a, y), &[0.0; 4], &Options::default()).unwrap();
        let u = s.standard_uncertainties().unwrap();
        hits.extend((0..4).map(|k| (s.x[k] - truth[k], u[k])));
    }
    let (one, three) = coverage(&hits);
    assert!((0.60..=0.76).contains(&one), "1σ coverage {one}");
    assert!(three >= 0.95, "3σ coverage {three}");
}

#[test]
fn reported_covariance_covers_the_truth_nonlinear() {
    let truth = [0.5, 2.0, 1.7];
    let mut hits = Vec::new();
    let mut variance_factors = Vec::new();
    for seed in 0..250 {
        // σ given to the solver is 3× the true noise: σ̂₀² must rescale the covariance.
        let d = Decay::simulate(1000 + seed, 40, &truth, 0.02);
        let options = Options {
            sigmas: Some(vec![0.06; 40]),
            ..Options::default()
        };
        let s = solve(&d, &[0.0, 1.0, 1.0], &options).unwrap();
        assert!(
            s.termination.converged(),
            "seed {seed}: {:?}",
            s.termination
        );
        variance_factors.push(s.variance_factor.unwrap());
        let u = s.standard_uncertainties().unwrap();
        hits.extend((0..3).map(|k| (s.x[k] - truth[k], u[k])));
    }
    let (one, three) = coverage(&hits);
    assert!((0.60..=0.76).contains(&one), "1σ coverage {one}");
    assert!(three >= 0.95, "3σ coverage {three}");
    let mean_vf = variance_factors.iter().sum::<f64>() / variance_factors.len() as f64;
    assert!(
        (mean_vf - 1.0 / 9.0).abs() < 0.01,
        "mean σ̂₀² {mean_vf}, expected (0.02/0.06)² = 0.111"
    );
}

#[test]
fn monte_carlo_covariance_agrees_with_the_reported_one_and_repeats() {
    let truth = [0.5, 2.0, 1.7];
    let clean = Decay::simulate(7, 50, &truth, 0.0);
    let sigma = 0.02;
    let options = Options {
        sigmas: Some(vec![sigma; 50]),
        ..Options::default()
    };
    // Linearised covariance at the truth with the σ given (unscaled: σ is known here).
    let reference = solve(&clean, &truth, &options)
        .unwrap()
        .covariance_unscaled
        .unwrap();
    let run = || {
        monte_carlo(400, 99, &Noise::Independent(vec![sigma; 50]), |e| {
            let mut d = clean.clone();
            d.y.iter_mut().zip(e.iter()).for_each(|(y, n)| *y += n);
            solve(&d, &truth, &options)
                .ok()
                .map(|s| DVector::from_vec(s.x))
        })
        .unwrap()
    };
    let mc = run();
    assert_eq!(mc.failures, 0);
    for k in 0..3 {
        let ratio = mc.covariance[(k, k)] / reference[(k, k)];
        assert!(
            (0.8..1.25).contains(&ratio),
            "param {k}: Monte Carlo/linearised variance {ratio}"
        );
        assert!(
            (mc.mean[k] - truth[k]).abs() < 4.0 * (reference[(k, k)] / 400.0).sqrt(),
            "param {k} mean {}",
            mc.mean[k]
        );
    }
    assert_eq!(run(), mc, "seeded Monte Carlo repeats bit for bit");
    // Correlated noise draws with the given covariance.
    let cov = DMatrix::from_row_slice(2, 2, &[4.0, 1.2, 1.2, 1.0]);
    let draws = monte_carlo(4000, 3, &Noise::Correlated(cov.clone()), |e| {
        Some(e.clone())
    })
    .unwrap();
    assert!(
        (draws.covariance - cov).amax() < 0.25,
        "empirical noise covariance"
    );
}

#[test]
fn robust_losses_ignore_ten_percent_gross_outliers_and_count_them() {
    let truth = [0.5, 2.0, 1.7];
    let sigma = 0.02;
    let clean = Decay::simulate(21, 200, &truth, sigma);
    let options = Options {
        sigmas: Some(vec![sigma; 200]),
        ..Options::default()
    };
    let fit_clean = solve(&clean, &[0.0, 1.0, 1.0], &options).unwrap();
    let u = fit_clean.standard_uncertainties().unwrap();
    // Every tenth sample replaced by a gross error of 20–60σ of either sign (beam breaks).
    let mut dirty = clean.clone();
    let mut r = rng(22);
    for i in (5..200).step_by(10) {
        let sign = if r.random::<bool>() { 1.0 } else { -1.0 };
        dirty.y[i] += sign * sigma * (20.0 + 40.0 * r.random::<f64>());
    }
    let plain = solve(&dirty, &[0.0, 1.0, 1.0], &options).unwrap();
    let off = (0..3)
        .map(|k| ((plain.x[k] - fit_clean.x[k]) / u[k]).abs())
        .fold(0.0, f64::max);
    assert!(
        off > 5.0,
        "without a robust loss the outliers pull the fit ({off:.1}σ)"
    );
    // Cauchy's influence vanishes for gross errors: the outliers are ignored (within 1σ of the
    // clean fit). Huber's stays bounded at c per outlier: a residual pull remains (within 2σ).
    for (loss, within) in [(Loss::Cauchy(3.0), 1.0), (Loss::Huber(3.0), 2.0)] {
        let s = solve(
            &dirty,
            &[0.0, 1.0, 1.0],
            &Options {
                loss,
                ..options.clone()
            },
        )
        .unwrap();
        assert!(s.termination.converged(), "{loss:?}: {:?}", s.termination);
        for k in 0..3 {
            let dev = ((s.x[k] - fit_clean.x[k]) / u[k]).abs();
            assert!(
                dev <= within,
                "{loss:?} x[{k}] {dev:.2}σ from the clean fit (plain fit: {off:.1}σ)"
            );
        }
        // 20 outliers, plus the inliers beyond 3σ (expected 0.5 of 180).
        assert!(
            (20..=22).contains(&s.downweighted),
            "{loss:?}: {} down-weighted",
            s.downweighted
        );
        // σ̂₀² of the inliers stays near 1 (the σ given is the true noise).
        let vf = s.variance_factor.unwrap();
        assert!((0.7..1.4).contains(&vf), "{loss:?}: σ̂₀² = {vf}");
    }
    assert_eq!(fit_clean.downweighted, 0);
}

#[test]
fn rank_deficiency_is_found_and_named() {
    // y = (a + 2b)·t + c·t²; d affects nothing: a and b are not separable, d is not identifiable.
    let t: Vec<f64> = (0..30).map(|i| i as f64 / 10.0).collect();
    let a = DMatrix::from_fn(30, 4, |i, k| match k {
        0 => t[i],
        1 => 2.0 * t[i],
        2 => t[i] * t[i],
        _ => 0.0,
    });
    let y: Vec<f64> = t.iter().map(|t| 0.9 * t - 0.3 * t * t).collect();
    let problem = Linear::new(a, y);
    let s = solve(&problem, &[0.0; 4], &Options::default()).unwrap();
    assert!(
        s.covariance_unscaled.is_none(),
        "no covariance for unidentifiable parameters"
    );
    let id = s.identifiability(&["a", "b", "c", "d"], None).unwrap();
    assert_eq!(id.rank, 2);
    assert!(
        id.condition_number > 1e12,
        "condition {}",
        id.condition_number
    );
    let words = id.describe();
    assert_eq!(words.len(), 2, "{words:?}");
    assert!(
        words.contains(&"a and b are not separable: a − 0.5·b".to_string()),
        "{words:?}"
    );
    assert!(
        words.contains(&"d is not identifiable: no measurement depends on it".to_string()),
        "{words:?}"
    );
    // The truncated-SVD step stays on the identifiable subspace: from 0 it gives the
    // minimum-norm solution in column-scaled units (|a|·‖t‖ = |b|·‖2t‖, so a = 2b), d untouched.
    let tsvd = Options {
        null_space: NullSpace::Truncated { rcond: 1e-9 },
        ..Options::default()
    };
    let m = solve(&problem, &[0.0; 4], &tsvd).unwrap();
    assert!(m.termination.converged(), "{:?}", m.termination);
    assert!(
        (m.x[0] - 0.45).abs() < 1e-9 && (m.x[1] - 0.225).abs() < 1e-9,
        "{:?}",
        m.x
    );
    assert!((m.x[2] + 0.3).abs() < 1e-9 && m.x[3] == 0.0, "{:?}", m.x);
    // Fixing b and d makes the rest identifiable, with zero covariance for the fixed ones.
    let fixed = Options {
        fixed: vec![false, true, false, true],
        ..Options::default()
    };
    let f = solve(&problem, &[0.0; 4], &fixed).unwrap();
    assert!((f.x[0] - 0.9).abs() < 1e-9);
    let c = f.covariance_unscaled.clone().unwrap();
    assert_eq!((c[(1, 1)], c[(3, 3)]), (0.0, 0.0));
    assert!(c[(0, 0)] > 0.0);
    assert_eq!(
        f.identifiability(&["a", "b", "c", "d"], None).unwrap().rank,
        2
    );
}

#[test]
fn priors_bounds_and_termination_reasons() {
    let truth = [0.5, 2.0, 1.7];
    let d = Decay::simulate(31, 40, &truth, 0.02);
    // A tight prior pins A; a loose one changes nothing visible.
    let tight = Options {
        priors: vec![Prior {
            index: 0,
            value: 0.45,
            sigma: 1e-9,
        }],
        ..Options::default()
    };
    let s = solve(&d, &[0.0, 1.0, 1.0], &tight).unwrap();
    assert!((s.x[0] - 0.45).abs() < 1e-8, "A = {}", s.x[0]);
    assert_eq!(s.degrees_of_freedom, 40 + 1 - 3);
    let free = solve(&d, &[0.0, 1.0, 1.0], &Options::default()).unwrap();
    let loose = Options {
        priors: vec![Prior {
            index: 0,
            value: 0.45,
            sigma: 1e3,
        }],
        ..Options::default()
    };
    let l = solve(&d, &[0.0, 1.0, 1.0], &loose).unwrap();
    assert!((l.x[0] - free.x[0]).abs() < 1e-6);
    // Correlations: symmetric, unit diagonal, bounded by 1.
    let c = free.correlations().unwrap();
    for i in 0..3 {
        assert_eq!(c[(i, i)], 1.0);
        for j in 0..3 {
            assert!((c[(i, j)] - c[(j, i)]).abs() < 1e-12 && c[(i, j)].abs() <= 1.0);
        }
    }
    assert!(
        c[(1, 2)].abs() > 0.1,
        "B and τ are correlated in this design: {}",
        c[(1, 2)]
    );
    // An iteration limit is reported as such.
    let short = solve(
        &d,
        &[0.0, 1.0, 1.0],
        &Options {
            max_iterations: 1,
            ..Options::default()
        },
    )
    .unwrap();
    assert_eq!(short.termination, Termination::MaxIterations);
    assert!(!short.termination.converged());
    // A start outside the box is projected into it.
    let boxed = Options {
        bounds: Some((vec![0.0, 0.0, 2.0], vec![1.0, 5.0, 3.0])),
        ..Options::default()
    };
    let b = solve(&d, &[0.0, 1.0, 1.0], &boxed).unwrap();
    assert_eq!(b.x[2], 2.0);
}

#[test]
fn bad_input_is_named() {
    let d = Decay::simulate(1, 10, &[0.5, 2.0, 1.7], 0.0);
    let err = solve(&d, &[0.0, f64::NAN, 1.0], &Options::default()).unwrap_err();
    assert_eq!(err.to_string(), "start x0[1] is not finite (NaN)");
    let err = solve(&d, &[0.0, 1.0], &Options::default()).unwrap_err();
    assert_eq!(err.to_string(), "start x0: expected 3 values, got 2");
    let mut sig = vec![1.0; 10];
    sig[3] = -1.0;
    let err = solve(
        &d,
        &[0.0, 1.0, 1.0],
        &Options {
            sigmas: Some(sig),
            ..Options::default()
        },
    )
    .unwrap_err();
    assert_eq!(
        err.to_string(),
        "sigmas[3]: must be finite and positive, got -1"
    );
    let bad_box = Options {
        bounds: Some((vec![0.0, 2.0, 0.0], vec![1.0, 1.0, 1.0])),
        ..Options::default()
    };
    assert!(
        matches!(solve(&d, &[0.0, 1.0, 1.0], &bad_box), Err(SolverError::Invalid { what, .. }) if what == "bounds[1]")
    );
    // τ ≤ 0: the problem says why it cannot be evaluated.
    let err = solve(&d, &[0.0, 1.0, -1.0], &Options::default()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "the problem cannot be evaluated at the start: time constant τ = -1 must be positive"
    );
    // A NaN measurement at the start is named by index.
    let mut nan = d.clone();
    nan.y[4] = f64::NAN;
    let err = solve(&nan, &[0.0, 1.0, 1.0], &Options::default()).unwrap_err();
    assert_eq!(
        err.to_string(),
        "the problem cannot be evaluated at the start: residual 4 is NaN"
    );
    let err = solve(
        &d,
        &[0.0, 1.0, 1.0],
        &Options {
            loss: Loss::Huber(0.0),
            ..Options::default()
        },
    )
    .unwrap_err();
    assert_eq!(
        err.to_string(),
        "loss scale: must be finite and positive, got 0"
    );
}
