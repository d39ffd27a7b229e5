//! Physical behaviour of individual terms: signs, symmetries, interpolation, lag.

use metrocell_physics::catalog::{configure, example_config};
use metrocell_physics::machine_family::{predict_through_kinematics, KinematicParameters};
use metrocell_physics::thermal::thermal_growth::first_order_lag;
use metrocell_physics::thermal::thermal_scale::interpolate_temperature;
use metrocell_physics::{
    Axis, PhysicsTerm, Signals, TemperatureHistory, TemperatureTimeline, TermId,
};
use nalgebra::{Vector2, Vector3};

fn term(id: TermId) -> Box<dyn PhysicsTerm> {
    configure(&example_config(id)).unwrap().term
}

#[test]
fn backlash_sign_by_direction_of_approach() {
    let t = term(TermId::Backlash); // axis y
    let mut s = Signals::default();
    s.approach_direction[1] = Some(1.0);
    let up = t.predict(&[10e-6], &s).unwrap().value;
    s.approach_direction[1] = Some(-1.0);
    let down = t.predict(&[10e-6], &s).unwrap().value;
    assert_eq!((up[1], down[1]), (-5e-6, 5e-6));
    assert!(
        (down[1] - up[1] - 10e-6).abs() < 1e-18,
        "reversal value = difference of the two approaches"
    );
    s.approach_direction[1] = Some(0.3);
    assert!(t.predict(&[10e-6], &s).is_err());
}

#[test]
fn pitch_cyclic_repeats_every_lead() {
    let t = term(TermId::PitchCyclic); // x, lead 10 mm, 2 harmonics
    let p = [3e-6, -1e-6, 0.5e-6, 0.2e-6];
    let at = |x: f64| {
        t.predict(
            &p,
            &Signals::default().with_positions(Vector3::new(x, 0.0, 0.0)),
        )
        .unwrap()
        .value[0]
    };
    for x in [0.0123, 0.2, 0.4567] {
        assert!((at(x) - at(x + 0.010)).abs() < 1e-15 && (at(x) - at(x + 0.5)).abs() < 1e-14);
    }
    assert!((at(0.0) - (3e-6 + 0.5e-6)).abs() < 1e-18);
}

#[test]
fn thermal_scale_interpolates_between_sensors() {
    let sensors = [(0.0, 20.0), (1.0, 22.0)];
    assert_eq!(interpolate_temperature(&sensors, 0.25), 20.5);
    assert_eq!(interpolate_temperature(&sensors, -1.0), 20.0);
    assert_eq!(interpolate_temperature(&sensors, 3.0), 22.0);
    let t = term(TermId::ThermalScale); // sensors x_left at 0, x_right at 1.2 m
    let mut s = Signals::default().with_positions(Vector3::new(0.6, 0.0, 0.0));
    s.temperatures.insert("x_left".into(), 21.0);
    s.temperatures.insert("x_right".into(), 23.0);
    // T(0.6) = 22 °C → d = 11.5e-6 · 0.6 · 2 = 13.8 µm along +x
    let d = t.predict(&[11.5e-6], &s).unwrap().value;
    assert!((d[0] - 13.8e-6).abs() < 1e-15 && d[1] == 0.0 && d[2] == 0.0);
}

#[test]
fn thermal_growth_lag_follows_a_first_order_step_response() {
    // sensor rises 20 → 21 °C over the second before t = 0 (readings 1 s apart: the lag sees
    // the ramp between them) and stays; τ later the structure has 1 − e⁻¹ of the rest
    let tau = 600.0;
    let mut samples = vec![(-1.0, 20.0)];
    samples.extend((0..=600).map(|k| (k as f64, 21.0)));
    let (tf, _) = first_order_lag(&TemperatureHistory { samples }, tau);
    let after_ramp = 21.0 - tau + tau * (-1.0f64 / tau).exp();
    assert!(
        (tf - (21.0 - (21.0 - after_ramp) * (-1.0f64).exp())).abs() < 1e-12,
        "{tf}"
    );
    let t = term(TermId::ThermalGrowth); // lag, direction −z
    let mut s = Signals::default();
    let settled = TemperatureHistory {
        samples: vec![(0.0, 20.0), (1e6, 22.0)],
    };
    s.timeline = Some(std::sync::Arc::new(
        TemperatureTimeline::from_histories([("column", &settled)]).unwrap(),
    ));
    // τ ≪ Δt: settled on the ramp between the readings, behind it by τ·slope
    let d = t.predict(&[10e-6, 1.0], &s).unwrap().value;
    assert!(
        (d[2] + 10e-6 * (2.0 - 1.0 * 2.0 / 1e6)).abs() < 1e-15,
        "{}",
        d[2]
    );
    let repeated = TemperatureHistory {
        samples: vec![(0.0, 20.0), (0.0, 22.0)],
    };
    assert!(
        TemperatureTimeline::from_histories([("column", &repeated)]).is_err(),
        "non-increasing times are rejected"
    );
    // at a time before the sensor's first sample there is nothing to lag
    s.time = Some(-1.0);
    assert!(
        t.predict(&[10e-6, 1.0], &s).is_err(),
        "no sample at or before the instant"
    );
}

#[test]
fn probe_pretravel_has_trigonal_symmetry() {
    let t = term(TermId::ProbePretravel); // 3 lobes
    let p = [10e-6, 4e-6, -2e-6, 5e-6];
    let mag = |phi: f64| {
        let s = Signals {
            probe_direction: Some(Vector3::new(phi.cos(), phi.sin(), 0.0)),
            ..Default::default()
        };
        t.predict(&p, &s).unwrap().value.norm()
    };
    let third = std::f64::consts::TAU / 3.0;
    for phi in [0.1, 0.7, 2.0] {
        assert!((mag(phi) - mag(phi + third)).abs() < 1e-18);
    }
    assert!((mag(0.0) - 14e-6).abs() < 1e-18, "p0 + a at φ = 0");
    let s = Signals {
        probe_direction: Some(Vector3::new(0.0, 0.0, -1.0)),
        ..Default::default()
    };
    let d = t.predict(&p, &s).unwrap().value;
    assert!(
        (d[2] + 5e-6).abs() < 1e-18,
        "vertical pretravel along the approach (−z)"
    );
}

#[test]
fn time_offset_is_minus_velocity_times_latency() {
    let t = term(TermId::TimeOffset);
    let s = Signals {
        axis_velocity: [Some(0.1), Some(-0.2), Some(0.0)],
        ..Default::default()
    };
    let d = t.predict(&[0.004], &s).unwrap().value;
    assert!((d[0] + 0.4e-3).abs() < 1e-15 && (d[1] - 0.8e-3).abs() < 1e-15);
}

#[test]
fn lens_distortion_matches_brown_conrady_by_hand() {
    let t = term(TermId::LensDistortion);
    let (x, y) = (0.3, -0.2);
    let (k1, k2, k3, p1, p2) = (-0.2, 0.05, 0.01, 1e-3, -2e-3);
    let r2: f64 = x * x + y * y;
    let radial = k1 * r2 + k2 * r2 * r2 + k3 * r2 * r2 * r2;
    let ex = x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x);
    let ey = y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y;
    let d = t
        .predict(
            &[k1, k2, k3, p1, p2],
            &Signals {
                image_point: Some(Vector2::new(x, y)),
                ..Default::default()
            },
        )
        .unwrap()
        .value;
    assert!((d[0] - ex).abs() < 1e-16 && (d[1] - ey).abs() < 1e-16);
}

#[test]
fn compliance_grows_with_extension() {
    let t = term(TermId::Compliance); // extension along z
    let p = [1e-8, 2e-7, 5e-7];
    let at = |z: f64| {
        t.predict(
            &p,
            &Signals {
                load_force: Some(Vector3::new(0.0, 0.0, -100.0)),
                ..Signals::default().with_positions(Vector3::new(0.0, 0.0, z))
            },
        )
        .unwrap()
        .value[2]
    };
    // −100 N · (1e-8 + 2e-7·0.25 + 5e-7·0.125) = −100 · 1.225e-7
    assert!((at(0.5) + 1.225e-5).abs() < 1e-18);
    assert!(at(0.8).abs() > at(0.5).abs());
}

#[test]
fn frame_misalignment_rotates_about_its_origin() {
    let t = term(TermId::FrameMisalignment);
    let s = Signals {
        workpiece_point: Some(Vector3::new(0.3, 0.0, 0.0)),
        ..Default::default()
    };
    let d = t
        .predict(&[0.0, 0.0, 1e-4, 0.0, 0.0, 0.0], &s)
        .unwrap()
        .value;
    assert!((d[1] - 3e-5).abs() < 1e-18 && d[0] == 0.0);
}

/// A kinematic term evaluated through a forward-kinematics closure: a toy planar 2-link arm
/// (0.4 m, 0.3 m) at θ = (0.3, 0.5) with link-length errors; the numeric Jacobian matches the
/// analytic one of the toy arm.
#[test]
fn kinematic_term_through_a_forward_closure() {
    let o = std::collections::BTreeMap::from([(
        "links".to_string(),
        metrocell_physics::ConfigValue::Number(2.0),
    )]);
    let term = metrocell_physics::catalog::build_term(TermId::LinkLength, &o).unwrap();
    assert_eq!(term.params().len(), 2);
    let (t1, t2) = (0.3f64, 0.5f64);
    let fk = |dl: &[f64]| {
        Vector3::new(
            (0.4 + dl[0]) * t1.cos() + (0.3 + dl[1]) * (t1 + t2).cos(),
            (0.4 + dl[0]) * t1.sin() + (0.3 + dl[1]) * (t1 + t2).sin(),
            0.0,
        )
    };
    let (d, j) = predict_through_kinematics(term.as_ref(), &[1e-3, -2e-3], &fk).unwrap();
    assert!(
        (d - Vector3::new(
            1e-3 * t1.cos() - 2e-3 * (t1 + t2).cos(),
            1e-3 * t1.sin() - 2e-3 * (t1 + t2).sin(),
            0.0
        ))
        .amax()
            < 1e-15
    );
    assert!((j[(0, 0)] - t1.cos()).abs() < 1e-9 && (j[(1, 1)] - (t1 + t2).sin()).abs() < 1e-9);
    let k = KinematicParameters {
        id: TermId::DeltaTowerAngle,
        count: 3,
    };
    assert_eq!(
        k.params()
            .iter()
            .map(|p| p.name.as_str())
            .collect::<Vec<_>>(),
        ["angle_a", "angle_b", "angle_c"]
    );
    let _ = Axis::X;
}
