//! Shared helpers for the integration tests: seeded random states and a 4th-order
//! finite-difference Jacobian.
#![allow(dead_code)]

use metrocell_physics::{ParamSpec, PhysicsTerm, Signals, TemperatureHistory, TemperatureTimeline};
use metrocell_solver::numeric_jacobian::{central_difference, Order};
use nalgebra::{DMatrix, Vector2, Vector3};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

pub fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn uni(r: &mut ChaCha8Rng, a: f64, b: f64) -> f64 {
    a + (b - a) * r.random::<f64>()
}

/// A random instant with every signal the example configs need.
pub fn random_signals(r: &mut ChaCha8Rng) -> Signals {
    let mut s = Signals::default();
    for i in 0..3 {
        s.axis_position[i] = Some(uni(r, 0.0, 0.8));
        s.approach_direction[i] = Some(if r.random::<bool>() { 1.0 } else { -1.0 });
        s.axis_velocity[i] = Some(uni(r, -0.5, 0.5));
    }
    for name in [
        "x_left", "x_right", "column", "plate", "head", "table", "ambient",
    ] {
        s.temperatures.insert(name.into(), uni(r, 17.0, 26.0));
    }
    let mut t = 0.0;
    let mut samples = Vec::new();
    for _ in 0..40 {
        t += uni(r, 10.0, 600.0);
        samples.push((t, uni(r, 19.0, 25.0)));
    }
    let history = TemperatureHistory { samples };
    // the instant: the history's last sample (a lagged term sees the whole history)
    s.time = Some(t);
    s.timeline = Some(std::sync::Arc::new(
        TemperatureTimeline::from_histories([("column", &history)]).unwrap(),
    ));
    s.air_temperature = Some(uni(r, 18.0, 24.0));
    s.air_pressure = Some(uni(r, 95_000.0, 103_000.0));
    s.air_humidity = Some(uni(r, 20.0, 80.0));
    s.time_since_power_on = Some(uni(r, 0.0, 5.0 * 3600.0));
    s.load_force = Some(Vector3::new(
        uni(r, -200.0, 200.0),
        uni(r, -200.0, 200.0),
        uni(r, -200.0, 200.0),
    ));
    s.tracker_range = Some(uni(r, 0.5, 15.0));
    s.image_point = Some(Vector2::new(uni(r, -0.6, 0.6), uni(r, -0.6, 0.6)));
    s.machine_point = Some(Vector3::new(
        uni(r, -1.0, 1.0),
        uni(r, -1.0, 1.0),
        uni(r, -1.0, 1.0),
    ));
    s.workpiece_point = Some(Vector3::new(
        uni(r, -1.0, 1.0),
        uni(r, -1.0, 1.0),
        uni(r, -1.0, 1.0),
    ));
    s.target_point = Some(Vector3::new(
        uni(r, -3.0, 3.0),
        uni(r, -3.0, 3.0),
        uni(r, -1.0, 1.0),
    ));
    s.camera_point = Some(Vector3::new(
        uni(r, -0.1, 0.1),
        uni(r, -0.1, 0.1),
        uni(r, 0.1, 0.5),
    ));
    let u = Vector3::new(uni(r, -1.0, 1.0), uni(r, -1.0, 1.0), uni(r, -1.0, 1.0));
    s.probe_direction = Some(u.normalize());
    s.rotary_position = [None, Some(uni(r, -1.5, 1.5)), Some(uni(r, -3.0, 3.0))];
    s.machine_point = Some(Vector3::new(
        uni(r, -0.5, 0.5),
        uni(r, -0.5, 0.5),
        uni(r, -0.2, 0.4),
    ));
    s
}

/// Random parameters inside the usual ranges.
pub fn random_params(r: &mut ChaCha8Rng, specs: &[ParamSpec]) -> Vec<f64> {
    specs
        .iter()
        .map(|p| uni(r, p.usual.lo, p.usual.hi))
        .collect()
}

/// 4th-order central differences, step h_i = 1e-4·(|p_i| + 1e-3·(width of the usual range)).
pub fn finite_difference_jacobian(term: &dyn PhysicsTerm, p: &[f64], s: &Signals) -> DMatrix<f64> {
    let steps: Vec<f64> = term
        .params()
        .iter()
        .zip(p)
        .map(|(spec, v)| 1e-4 * (v.abs() + 1e-3 * spec.typical_scale()))
        .collect();
    central_difference(
        |q: &[f64]| Some(term.predict(q, s).unwrap().value),
        p,
        &steps,
        Order::Fourth,
    )
    .unwrap()
}
