#![allow(dead_code)]
//! Measurement records simulated from the shared model at known parameters, with a laser
//! tracker's spherical noise (range a + b·ρ, angles σ) and its stated covariance — the data a
//! recording of `metrocell sim` would give, built in memory.

use metrocell_estimation::{MeasurementRecord, RecordFrame, RecordKind, RecordSet};
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
    s
}

/// Index of a parameter by name.
pub fn index(model: &ForwardModel, name: &str) -> usize {
    model
        .param_names()
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no parameter {name}"))
}

/// Fraction of |z| ≤ k.
pub fn within(z: &[f64], k: f64) -> f64 {
    z.iter().filter(|v| v.abs() <= k).count() as f64 / z.len() as f64
}

/// The 21 geometric errors of an XFYZ machine of travel 800 × 500 × 400 mm as `terms:` items:
/// positioning and straightness series of order 3, angular series of order 2 about each axis
/// with the Abbe lever `lever_axes` and offset `abbe_offset`, three squareness terms — all at 0.
pub fn xfyz_geometric_terms(lever_axes: &str, abbe_offset: &str) -> String {
    let mut terms = String::new();
    let travels = [
        ("x", "[0 mm, 800 mm]"),
        ("y", "[0 mm, 500 mm]"),
        ("z", "[0 mm, 400 mm]"),
    ];
    for (a, t) in travels {
        terms += &format!("  - {{id: positioning, options: {{axis: {a}, order: 3, travel: {t}}}, params: {{c0: 0 um, c1: 0 um, c2: 0 um, c3: 0 um}}}}\n");
        for d in ["x", "y", "z"].iter().filter(|d| **d != a) {
            terms += &format!("  - {{id: straightness, options: {{axis: {a}, direction: {d}, order: 3, travel: {t}}}, params: {{c0: 0 um, c1: 0 um, c2: 0 um, c3: 0 um}}}}\n");
        }
        for about in ["x", "y", "z"] {
            terms += &format!("  - {{id: angular, options: {{axis: {a}, about: {about}, lever_axes: {lever_axes}, abbe_offset: {abbe_offset}, order: 2, travel: {t}}}, params: {{c0: 0 urad, c1: 0 urad, c2: 0 urad}}}}\n");
        }
    }
    for pair in ["xy", "xz", "yz"] {
        terms +=
            &format!("  - {{id: squareness, options: {{pair: {pair}}}, params: {{s: 0 urad}}}}\n");
    }
    terms
}
