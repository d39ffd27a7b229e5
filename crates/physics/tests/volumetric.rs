//! 21-error XFYZ synthesis (thesis P5 chain): first-order accuracy against the exact chain
//! (crates/kinematics `cartesian_error_chain`, the project's one copy), agreement with the sum of
//! catalog terms, and the squareness figure.

mod common;
/// P5's first-order synthesis, the oracle these tests hold the library to.
#[path = "support/xfyz_first_order.rs"]
mod xfyz_first_order;

use metrocell_kinematics::cartesian_error_chain::{
    workpiece_point, AxisErrors, MachineErrors, Squareness as ChainSquareness,
};
use metrocell_physics::geometry::angular::Angular;
use metrocell_physics::geometry::error_series::{ErrorSeries, SeriesBasis};
use metrocell_physics::geometry::positioning::Positioning;
use metrocell_physics::geometry::squareness::Squareness;
use metrocell_physics::geometry::straightness::Straightness;
use metrocell_physics::{Axis, PhysicsTerm, Signals};
use nalgebra::Vector3;
use rand::Rng;
use xfyz_first_order::*;

fn random_model(r: &mut impl Rng, scale_t: f64, scale_r: f64) -> GeometricErrorModel {
    let s = ErrorSeries::new(SeriesBasis::Legendre, 2, (0.0, 0.8)).unwrap();
    let mut coef = |k: f64| {
        (
            s,
            (0..3)
                .map(|_| k * (2.0 * r.random::<f64>() - 1.0))
                .collect::<Vec<_>>(),
        )
    };
    let translation = std::array::from_fn(|_| std::array::from_fn(|_| coef(scale_t)));
    let rotation = std::array::from_fn(|_| std::array::from_fn(|_| coef(scale_r)));
    let mut sq = || scale_r * (2.0 * r.random::<f64>() - 1.0);
    GeometricErrorModel {
        translation,
        rotation,
        squareness: SquarenessValues {
            xy: sq(),
            xz: sq(),
            yz: sq(),
        },
    }
}

/// The exact P5 chain (crates/kinematics) for the model's errors at q: the tool point in the
/// workpiece frame.
fn exact_chain(m: &GeometricErrorModel, q: &Vector3<f64>, tool: &Vector3<f64>) -> Vector3<f64> {
    let mut e = MachineErrors {
        squareness: ChainSquareness {
            xy: m.squareness.xy,
            xz: m.squareness.xz,
            yz: m.squareness.yz,
        },
        ..MachineErrors::default()
    };
    for a in Axis::ALL {
        let v = m.axis_errors(a, q[a.index()]);
        e.axes[a.index()] = AxisErrors {
            translation: v.translation,
            rotation: v.rotation,
        };
    }
    workpiece_point(&"XFYZ".parse().unwrap(), q, tool, &e).unwrap()
}

#[test]
fn zero_errors_give_the_nominal_tool_point() {
    let series = ErrorSeries::new(SeriesBasis::Legendre, 2, (0.0, 0.8)).unwrap();
    let zero = GeometricErrorModel::zeros([series; 3]);
    let q = Vector3::new(0.3, 0.2, 0.1);
    let tool = Vector3::new(0.0, 0.0, -0.15);
    assert!((exact_chain(&zero, &q, &tool) - (tool + q)).amax() < 1e-16);
    let f = |a: Axis, x: f64| zero.axis_errors(a, x);
    assert_eq!(
        xfyz_volumetric_error_first_order(&q, &tool, &f, &zero.squareness),
        Vector3::zeros()
    );
}

#[test]
fn first_order_model_matches_full_chain_to_second_order() {
    let mut r = common::rng(5);
    for scale in [1e-4, 1e-5] {
        let m = random_model(&mut r, scale, scale);
        m.validate().unwrap();
        let f = |a: Axis, q: f64| m.axis_errors(a, q);
        let mut worst: f64 = 0.0;
        for _ in 0..50 {
            let q = Vector3::new(
                0.8 * r.random::<f64>(),
                0.8 * r.random::<f64>(),
                0.8 * r.random::<f64>(),
            );
            let tool = Vector3::new(0.05, -0.02, -0.2);
            let exact = exact_chain(&m, &q, &tool) - (tool + q);
            let lin = xfyz_volumetric_error_first_order(&q, &tool, &f, &m.squareness);
            worst = worst.max((exact - lin).amax());
        }
        // errors are O(scale); the neglected products O(scale²)·(lever ≤ 2 m) — a few × scale²
        assert!(
            worst < 20.0 * scale * scale,
            "scale {scale}: worst difference {worst:e}"
        );
    }
}

/// The 21 catalog terms of P5's errors `m` (X on the workpiece side, the P5 levers), their
/// Abbe offsets at `tool`, with their parameters.
fn catalog_terms(
    m: &GeometricErrorModel,
    tool: Vector3<f64>,
) -> Vec<(Box<dyn PhysicsTerm>, Vec<f64>)> {
    // X is on the workpiece side: the relative (catalog) errors of X are minus P5's table errors.
    let side = |a: Axis| if a == Axis::X { -1.0 } else { 1.0 };
    let lever = |a: Axis| match a {
        Axis::X => vec![Axis::X, Axis::Y, Axis::Z],
        Axis::Y => vec![Axis::Z],
        Axis::Z => vec![],
    };
    let mut terms: Vec<(Box<dyn PhysicsTerm>, Vec<f64>)> = Vec::new();
    for a in Axis::ALL {
        for c in Axis::ALL {
            let (series, k) = &m.translation[a.index()][c.index()];
            let p: Vec<f64> = k.iter().map(|v| side(a) * v).collect();
            if c == a {
                terms.push((
                    Box::new(Positioning {
                        axis: a,
                        series: *series,
                    }),
                    p,
                ));
            } else {
                terms.push((
                    Box::new(Straightness {
                        axis: a,
                        direction: c,
                        series: *series,
                    }),
                    p,
                ));
            }
            let (series, k) = &m.rotation[a.index()][c.index()];
            let p: Vec<f64> = k.iter().map(|v| side(a) * v).collect();
            terms.push((
                Box::new(Angular {
                    axis: a,
                    about: c,
                    lever_axes: lever(a),
                    abbe_offset: tool,
                    series: *series,
                }),
                p,
            ));
        }
    }
    for (affected, driver, s) in [
        (Axis::X, Axis::Y, m.squareness.xy),
        (Axis::X, Axis::Z, m.squareness.xz),
        (Axis::Y, Axis::Z, m.squareness.yz),
    ] {
        terms.push((Box::new(Squareness { affected, driver }), vec![s]));
    }
    terms
}

fn sum_of(terms: &[(Box<dyn PhysicsTerm>, Vec<f64>)], s: &Signals) -> Vector3<f64> {
    let mut sum = Vector3::zeros();
    for (t, p) in terms {
        let v = t.predict(p, s).unwrap().value;
        sum += Vector3::new(v[0], v[1], v[2]);
    }
    sum
}

#[test]
fn sum_of_catalog_terms_equals_first_order_synthesis() {
    let mut r = common::rng(11);
    let m = random_model(&mut r, 5e-5, 5e-5);
    let f = |a: Axis, q: f64| m.axis_errors(a, q);
    let tool = Vector3::new(0.03, 0.01, -0.18);
    let terms = catalog_terms(&m, tool);
    assert_eq!(
        terms.len(),
        21,
        "the 21 geometric errors of a 3-axis machine"
    );
    for _ in 0..30 {
        let q = Vector3::new(
            0.8 * r.random::<f64>(),
            0.8 * r.random::<f64>(),
            0.8 * r.random::<f64>(),
        );
        let sum = sum_of(&terms, &Signals::default().with_positions(q));
        let synth = xfyz_volumetric_error_first_order(&q, &tool, &f, &m.squareness);
        assert!(
            (sum - synth).amax() < 1e-15,
            "terms {sum:?} vs synthesis {synth:?}"
        );
    }
}

/// A reflector moved on the spindle by δ (a reading's `tool_offset_shift`): the terms declared
/// for the tool predict P5's error of the point at tool + δ — the angular errors through the
/// longer arms, translations unchanged — and the difference from the tool's error is ε × δ, so
/// readings at several offsets see the angles apart from the straightnesses.
#[test]
fn a_reflector_moved_on_the_spindle_is_seen_through_longer_abbe_arms() {
    let mut r = common::rng(12);
    let m = random_model(&mut r, 5e-5, 5e-5);
    let f = |a: Axis, q: f64| m.axis_errors(a, q);
    let tool = Vector3::new(0.0, 0.0, -0.12);
    let terms = catalog_terms(&m, tool);
    for shift in [
        Vector3::new(0.15, 0.0, 0.0),
        Vector3::new(0.0, 0.0, -0.15),
        Vector3::new(-0.05, 0.1, 0.02),
    ] {
        for _ in 0..10 {
            let q = Vector3::new(
                0.8 * r.random::<f64>(),
                0.8 * r.random::<f64>(),
                0.8 * r.random::<f64>(),
            );
            let mut s = Signals::default().with_positions(q);
            let at_tool = sum_of(&terms, &s);
            s.tool_offset_shift = Some(shift);
            let moved = sum_of(&terms, &s);
            let synth = xfyz_volumetric_error_first_order(&q, &(tool + shift), &f, &m.squareness);
            assert!(
                (moved - synth).amax() < 1e-15,
                "shift {shift:?}: terms {moved:?} vs synthesis {synth:?}"
            );
            assert!(
                (moved - at_tool).norm() > 1e-8,
                "a 150 mm move with 50 µrad angles changes the error"
            );
        }
    }
}

/// Thesis Ch. 5.5: xWy = 0.20448 mrad; over 400 mm of Y it displaces X by ≈81.8 µm.
#[test]
fn squareness_figure() {
    let zero = |_: Axis, _: f64| AxisErrorValues::default();
    let sq = SquarenessValues {
        xy: 0.20448e-3,
        xz: 0.0,
        yz: 0.0,
    };
    let e = xfyz_volumetric_error_first_order(
        &Vector3::new(0.0, 0.4, 0.0),
        &Vector3::zeros(),
        &zero,
        &sq,
    );
    assert!((e.x.abs() * 1e6 - 81.792).abs() < 1e-6, "{} µm", e.x * 1e6);
    assert!(e.x < 0.0, "P5 sign: Y's x-component is −y·s_xy");
}

#[test]
fn abbe_error_of_pitch_grows_with_tool_offset() {
    // Pitch of Y (rotation about X) of 20 µrad with a 150 mm probe below the spindle: 3 µm in y.
    let s = ErrorSeries::new(SeriesBasis::Polynomial, 0, (0.0, 1.0)).unwrap();
    let t = Angular {
        axis: Axis::Y,
        about: Axis::X,
        lever_axes: vec![],
        abbe_offset: Vector3::new(0.0, 0.0, -0.15),
        series: s,
    };
    let d = t
        .predict(
            &[20e-6],
            &Signals::default().with_positions(Vector3::new(0.0, 0.3, 0.0)),
        )
        .unwrap()
        .value;
    assert!((d[1] - 3e-6).abs() < 1e-15 && d[0] == 0.0 && d[2] == 0.0);
}
