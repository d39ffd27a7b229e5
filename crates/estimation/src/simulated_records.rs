//! Measurement records simulated from the shared model at known parameters, with a laser
//! tracker's spherical noise (range a + b·ρ, angles σ) and its stated covariance — the data a
//! recording of `metrocell sim` would give, built in memory. Used to plan a verification
//! (the uncertainty a tracker placement would give, before anything is measured) and by the
//! identification tests.

use crate::{MeasurementRecord, RecordFrame, RecordKind, RecordSet};
use metrocell_model::ForwardModel;
use metrocell_physics::instrument::spherical::{from_spherical, point_covariance, to_spherical};
use metrocell_physics::Signals;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};

/// A tracker's noise model (thesis P3 values: 4 µm + 0.8 µm/m, 3 µrad).
#[derive(Debug, Clone, Copy)]
pub struct TrackerNoise {
    pub constant: f64,
    pub per_metre: f64,
    pub angular: f64,
}

pub const THESIS_TRACKER: TrackerNoise = TrackerNoise {
    constant: 4e-6,
    per_metre: 0.8e-6,
    angular: 3e-6,
};

/// One planned measurement.
#[derive(Debug, Clone)]
pub struct Planned {
    pub q: Vec<f64>,
    pub approach: [f64; 3],
    /// Temperatures (sensor, °C) at the instant.
    pub temperatures: Vec<(String, f64)>,
    /// Time since the tracker was powered on, s.
    pub time_on: f64,
    /// The target's offset from the model's tool (a reflector elsewhere on the spindle, m;
    /// `Signals::tool_offset_shift`), None: the model's tool.
    pub tool_offset_shift: Option<nalgebra::Vector3<f64>>,
}

/// The readings of `plan` at parameters `p` plus noise (seeded; None: no noise, the same stated
/// covariance), with their stated covariance, in the tracker's frame.
pub fn records(
    model: &ForwardModel,
    p: &[f64],
    plan: &[Planned],
    noise: TrackerNoise,
    seed: Option<u64>,
) -> RecordSet {
    let kin = model.kinematic_truth(p).expect("kinematics at the truth");
    let mut rng = ChaCha8Rng::seed_from_u64(seed.unwrap_or(0));
    let scale = if seed.is_some() { 1.0 } else { 0.0 };
    let mut n = || -> f64 {
        let v: f64 = StandardNormal.sample(&mut rng);
        scale * v
    };
    let out = plan
        .iter()
        .enumerate()
        .map(|(i, d)| {
            let mut s = signals(model, d);
            let tool = model
                .tool_state(p, &kin, &d.q, &mut s, None)
                .expect("tool state");
            let y = model.tracker(p, &tool, &mut s).expect("tracker reading");
            let (rho, az, el) = to_spherical(&y.measured_point());
            let sr = noise.constant + noise.per_metre * rho;
            let measured = from_spherical(
                rho + sr * n(),
                az + noise.angular * n(),
                el + noise.angular * n(),
            );
            let (r2, a2, e2) = to_spherical(&measured);
            MeasurementRecord {
                time: i as f64,
                point_id: format!("p{i}"),
                channel: "tracker".into(),
                q: d.q.clone(),
                measured,
                covariance: point_covariance(
                    r2,
                    a2,
                    e2,
                    noise.constant + noise.per_metre * r2,
                    noise.angular,
                    noise.angular,
                ),
                signals: signals(model, d),
                kind: RecordKind::Point,
            }
        })
        .collect();
    RecordSet {
        check: Vec::new(),
        frame: RecordFrame::Instrument("tracker".into()),
        records: out,
        rejected: vec![],
        sources: vec![],
    }
}

/// The signals of a planned measurement (what a recording gives at its time).
pub fn signals(model: &ForwardModel, d: &Planned) -> Signals {
    let mut s = Signals::default();
    if d.q.len() >= 3 {
        model.set_motion(&mut s, &d.q, &[0.0; 3], &d.approach);
    }
    for (name, t) in &d.temperatures {
        s.temperatures.insert(name.clone(), *t);
    }
    s.time_since_power_on = Some(d.time_on);
    s.tool_offset_shift = d.tool_offset_shift;
    s
}
