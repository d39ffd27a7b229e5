//! Every catalog term's analytic Jacobian matches 4th-order central finite differences to
//! 1e-6 relative (per column) on seeded random parameters and states.

mod common;

use metrocell_physics::catalog::{configure, example_config};
use metrocell_physics::{EffectKind, TermId};

#[test]
fn analytic_jacobians_match_finite_differences() {
    let mut r = common::rng(20_261_121);
    let mut checked = 0;
    for &id in TermId::ALL {
        let built = configure(&example_config(id)).unwrap_or_else(|e| panic!("{id}: {e}"));
        let term = built.term.as_ref();
        if term.effect() == EffectKind::Kinematic {
            continue;
        }
        for trial in 0..25 {
            let p = common::random_params(&mut r, &term.params());
            let s = common::random_signals(&mut r);
            let ja = term
                .jacobian(&p, &s)
                .unwrap_or_else(|e| panic!("{id}: {e}"));
            let jn = common::finite_difference_jacobian(term, &p, &s);
            assert_eq!(ja.shape(), jn.shape(), "{id}: Jacobian shape");
            assert_eq!(
                ja.nrows(),
                term.effect().dimension(),
                "{id}: rows = effect dimension"
            );
            // Absolute floor: a column whose effect over the whole plausible range is below
            // 1e-10 of the prediction's size (e.g. ∂/∂τ long after warm-up) is numerically zero.
            let out = term.predict(&p, &s).unwrap().value.amax().max(1e-300);
            for c in 0..ja.ncols() {
                let spec = &term.params()[c];
                let (a, n) = (ja.column(c), jn.column(c));
                let err = (a - n).norm();
                let scale = a.norm().max(n.norm());
                let floor = 1e-10 * out / spec.typical_scale();
                assert!(
                    err <= 1e-6 * scale + floor,
                    "{id} trial {trial} param {}: analytic {:?} vs numeric {:?} (err {err:e})",
                    spec.name,
                    a.iter().collect::<Vec<_>>(),
                    n.iter().collect::<Vec<_>>()
                );
            }
            checked += 1;
        }
    }
    // 23 non-kinematic ids × 25 states
    assert_eq!(checked, 23 * 25);
}

/// Parameters in which a term's documented equation (crates/physics/README.md) is NOT linear:
/// time constants of exponentials, rotation angles, Edlén's index of refraction and the
/// root-sum-square of the turbulence scatter. Every other parameter of every non-kinematic term
/// enters its prediction linearly.
fn nonlinear_params(id: &str) -> &'static [&'static str] {
    match id {
        "tracker_warmup" | "thermal_growth" => &["time_constant"],
        "tracker_pose" => &["alpha", "beta", "delta"],
        "base_tilt" => &["roll", "pitch"],
        "refraction" => &["path_pressure_offset", "path_temperature_offset"],
        "turbulence" => &["base_sigma", "proportional_sigma", "turbulence"],
        _ => &[],
    }
}

/// Dimension, and linearity checked exactly (not by a small step): moving every linear
/// parameter anywhere in its range changes the prediction by J·Δp, with J the analytic Jacobian
/// at the starting point. The exponential time constants and rotation angles must fail that test
/// (so the list above is not hiding a linear parameter, and the test can tell the difference).
#[test]
fn predictions_have_the_declared_dimension_and_are_linear_where_documented() {
    let mut r = common::rng(7);
    let (mut linear_checked, mut nonlinear_seen) = (0, std::collections::BTreeSet::new());
    for &id in TermId::ALL {
        let built = configure(&example_config(id)).unwrap();
        let term = built.term.as_ref();
        if term.effect() == EffectKind::Kinematic {
            continue;
        }
        let specs = term.params();
        let nonlinear = nonlinear_params(id.as_str());
        for n in nonlinear {
            assert!(
                specs.iter().any(|p| p.name == *n),
                "{id} has no parameter {n}"
            );
        }
        for _ in 0..10 {
            let p = common::random_params(&mut r, &specs);
            let s = common::random_signals(&mut r);
            let f0 = term.predict(&p, &s).unwrap().value;
            assert_eq!(f0.len(), term.effect().dimension(), "{id}");
            let j = term.jacobian(&p, &s).unwrap();
            let far = common::random_params(&mut r, &specs);
            // All linear parameters at once: no cross terms between them either.
            let mut q = p.clone();
            let mut step = nalgebra::DVector::zeros(p.len());
            for (k, spec) in specs.iter().enumerate() {
                if !nonlinear.contains(&spec.name.as_str()) {
                    q[k] = far[k];
                    step[k] = far[k] - p[k];
                }
            }
            let moved = term.predict(&q, &s).unwrap().value - &f0;
            let predicted = &j * &step;
            let err = (&moved - &predicted).norm();
            assert!(err <= 1e-9 * moved.norm().max(predicted.norm()) + 1e-15, "{id}: prediction not jointly linear in its linear parameters (moved {:?}, J·Δp {:?})", moved.as_slice(), predicted.as_slice());
            for (k, spec) in specs.iter().enumerate() {
                // Move one parameter across its range: exact for a linear one.
                let mut q = p.clone();
                q[k] = far[k];
                let moved = term.predict(&q, &s).unwrap().value - &f0;
                let predicted = j.column(k) * (q[k] - p[k]);
                let err = (&moved - &predicted).norm();
                let tol = 1e-9 * moved.norm().max(predicted.norm()) + 1e-15;
                if nonlinear.contains(&spec.name.as_str()) {
                    if err > 1e-6 * moved.norm().max(predicted.norm()) {
                        nonlinear_seen.insert(format!("{id}.{}", spec.name));
                    }
                } else {
                    assert!(
                        err <= tol,
                        "{id}: prediction not linear in {} (moved {:?}, J·Δp {:?})",
                        spec.name,
                        moved.as_slice(),
                        predicted.as_slice()
                    );
                    linear_checked += 1;
                }
            }
        }
    }
    assert!(
        linear_checked > 200,
        "only {linear_checked} linear parameter moves checked"
    );
    for must in [
        "tracker_warmup.time_constant",
        "thermal_growth.time_constant",
        "tracker_pose.alpha",
        "tracker_pose.beta",
        "tracker_pose.delta",
        "base_tilt.roll",
        "base_tilt.pitch",
    ] {
        assert!(
            nonlinear_seen.contains(must),
            "{must} behaved linearly: the documented nonlinearity is missing"
        );
    }
}

/// A term that says it is `linear_in_params` is, in the stronger sense a cache relies on:
/// prediction = J·p with no intercept, and J the same at any two parameter vectors of an
/// instant. The geometric series terms say so; the terms with a nonlinear parameter must not.
#[test]
fn terms_that_say_they_are_linear_predict_by_their_jacobian() {
    let mut r = common::rng(11);
    let mut linear = std::collections::BTreeSet::new();
    for &id in TermId::ALL {
        let built = configure(&example_config(id)).unwrap();
        let term = built.term.as_ref();
        if !term.linear_in_params() {
            continue;
        }
        assert!(
            nonlinear_params(id.as_str()).is_empty(),
            "{id} says it is linear but has a nonlinear parameter"
        );
        linear.insert(id.as_str());
        for _ in 0..10 {
            let (p, far) = (
                common::random_params(&mut r, &term.params()),
                common::random_params(&mut r, &term.params()),
            );
            let s = common::random_signals(&mut r);
            let j = term.jacobian(&p, &s).unwrap();
            assert_eq!(
                j,
                term.jacobian(&far, &s).unwrap(),
                "{id}: Jacobian depends on the parameters"
            );
            let value = term.predict(&p, &s).unwrap().value;
            let product = &j * nalgebra::DVector::from_column_slice(&p);
            assert!(
                (&value - &product).norm() <= 1e-12 * value.norm() + 1e-300,
                "{id}: prediction {:?} is not J·p {:?}",
                value.as_slice(),
                product.as_slice()
            );
        }
    }
    assert_eq!(
        linear.into_iter().collect::<Vec<_>>(),
        [
            "angular",
            "instrument_drift",
            "positioning",
            "squareness",
            "straightness"
        ]
    );
}

/// `evaluate_into` (the allocation-free path estimators use) gives `predict`'s value and
/// `jacobian`'s matrix bit for bit, for every term, whether it overrides the method or not.
#[test]
fn evaluate_into_is_predict_and_jacobian_bit_for_bit() {
    let mut r = common::rng(7);
    for &id in TermId::ALL {
        let built = configure(&example_config(id)).unwrap_or_else(|e| panic!("{id}: {e}"));
        let term = built.term.as_ref();
        if term.effect() == EffectKind::Kinematic {
            continue;
        }
        for _ in 0..10 {
            let p = common::random_params(&mut r, &term.params());
            let s = common::random_signals(&mut r);
            let dim = term.effect().dimension();
            // the largest prediction is a pose change (6)
            let mut value = [f64::NAN; 6];
            let mut jac = nalgebra::DMatrix::from_element(dim, p.len(), f64::NAN);
            term.evaluate_into(&p, &s, &mut value, jac.view_mut((0, 0), (dim, p.len())))
                .unwrap_or_else(|e| panic!("{id}: {e}"));
            let v = term.predict(&p, &s).unwrap().value;
            for k in 0..dim {
                assert_eq!(value[k].to_bits(), v[k].to_bits(), "{id}: value {k}");
            }
            assert_eq!(jac, term.jacobian(&p, &s).unwrap(), "{id}: Jacobian");
        }
        // a missing signal is still an error naming the term, not a panic
        if !term.signals().is_empty() {
            let mut value = [0.0; 3];
            let mut jac = nalgebra::DMatrix::zeros(term.effect().dimension(), term.params().len());
            let dim = term.effect().dimension();
            let err = term
                .evaluate_into(
                    &term.defaults(),
                    &metrocell_physics::Signals::default(),
                    &mut value,
                    jac.view_mut((0, 0), (dim, term.params().len())),
                )
                .unwrap_err();
            assert!(err.to_string().contains(&term.label()), "{id}: {err}");
        }
    }
}
