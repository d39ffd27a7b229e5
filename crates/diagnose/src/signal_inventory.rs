//! What a recording can inform: which signals every record carries, and whether they vary
//! enough to tell a term apart. Candidate terms are made only for signals that are there —
//! whatever wrote the recording — and the terms that cannot be tried are named with the signal
//! they miss.

use std::collections::BTreeSet;

use metrocell_estimation::{MeasurementRecord, RecordKind};

/// Signals present in every record (a term evaluated on a record without its signal would be an
/// error, so "present" means present everywhere).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SignalInventory {
    /// Commanded position of each linear axis.
    pub positions: [bool; 3],
    /// Both directions of approach occur on the axis.
    pub approach_both: [bool; 3],
    /// Axis velocities are present and some records were taken while moving (|v| > 1 µm/s).
    pub moving: bool,
    /// Temperature sensors with a latest reading in every record.
    pub temperatures: Vec<String>,
    /// Temperature sensors with a history in every record (for lagged terms).
    pub histories: Vec<String>,
    /// Station air (temperature, pressure, humidity) in every record.
    pub air: bool,
    /// Time since the instrument was powered on, and its spread over the records (s).
    pub power_on: Option<(f64, f64)>,
    /// A load force in every record, non-zero somewhere.
    pub load: bool,
    /// Rotary axis positions (A, B, C) in every record.
    pub rotary: [bool; 3],
    /// Some records are touch-probe hits (their pretravel is a candidate).
    pub probe_hits: bool,
    /// Every record has a time, and they span this interval (s, the recording's clock).
    pub time_span: Option<(f64, f64)>,
    /// Some records are instrument readings of points (a tracker's): an instrument that can drift.
    pub point_readings: bool,
    /// An arm's gravity torque about each of its joint variables, RMS over the records (N·m;
    /// empty for other machines or an arm without masses): which joints gravity loads.
    pub gravity_torque_rms: Vec<f64>,
    /// Every record carries the base's measured gravity (an accelerometer fixed to the base).
    pub gravity_measured: bool,
}

/// The RMS over `records` of the gravity torque about each joint variable of `arm` (URDF
/// inertials, each record's gravity or level); empty when the arm has no masses.
pub fn gravity_torque_rms(
    arm: &metrocell_model::SerialArm,
    records: &[MeasurementRecord],
) -> Vec<f64> {
    if !arm.chain.joints.iter().any(|j| j.inertial.is_some()) || records.is_empty() {
        return Vec::new();
    }
    let level = nalgebra::Vector3::new(0.0, 0.0, -metrocell_physics::gravity::STANDARD_GRAVITY);
    let mut sum = vec![0.0; arm.chain.dof()];
    let mut n = 0usize;
    for r in records {
        if let Ok(tau) = metrocell_kinematics::gravity::gravity_torques(
            &arm.chain,
            &r.q,
            &r.signals.gravity.unwrap_or(level),
        ) {
            for (s, t) in sum.iter_mut().zip(tau) {
                *s += t * t;
            }
            n += 1;
        }
    }
    if n == 0 {
        return Vec::new();
    }
    sum.iter().map(|s| (s / n as f64).sqrt()).collect()
}

impl SignalInventory {
    pub fn of(records: &[MeasurementRecord]) -> Self {
        let mut inv = SignalInventory::default();
        if records.is_empty() {
            return inv;
        }
        let all = |f: &dyn Fn(&MeasurementRecord) -> bool| records.iter().all(f);
        for k in 0..3 {
            inv.positions[k] = all(&|r| r.signals.axis_position[k].is_some_and(f64::is_finite));
            let has = |sign: f64| {
                records
                    .iter()
                    .any(|r| r.signals.approach_direction[k] == Some(sign))
            };
            inv.approach_both[k] =
                all(&|r| r.signals.approach_direction[k].is_some()) && has(1.0) && has(-1.0);
            inv.rotary[k] = all(&|r| r.signals.rotary_position[k].is_some_and(f64::is_finite));
        }
        inv.gravity_measured = all(&|r| r.signals.gravity.is_some());
        inv.moving = all(&|r| {
            r.signals
                .axis_velocity
                .iter()
                .all(|v| v.is_some_and(f64::is_finite))
        }) && records.iter().any(|r| {
            r.signals
                .axis_velocity
                .iter()
                .any(|v| v.is_some_and(|v| v.abs() > 1e-6))
        });
        let names = |f: &dyn Fn(&MeasurementRecord) -> BTreeSet<String>| -> Vec<String> {
            let mut common = f(&records[0]);
            for r in &records[1..] {
                let here = f(r);
                common.retain(|n| here.contains(n));
            }
            common.into_iter().collect()
        };
        inv.temperatures = names(&|r| {
            r.signals
                .temperatures
                .iter()
                .filter(|(_, v)| v.is_finite())
                .map(|(n, _)| n.clone())
                .collect()
        });
        // a history is there when the timeline has a sample of the sensor at or before the instant
        inv.histories = names(&|r| match &r.signals.timeline {
            Some(tl) => tl
                .sensors()
                .into_iter()
                .filter(|n| {
                    tl.time_span(n)
                        .is_some_and(|(first, _)| r.signals.time.is_none_or(|t| first <= t))
                })
                .collect(),
            None => BTreeSet::new(),
        });
        inv.air = all(&|r| {
            r.signals.air_temperature.is_some()
                && r.signals.air_pressure.is_some()
                && r.signals.air_humidity.is_some()
        });
        if all(&|r| r.signals.time_since_power_on.is_some_and(f64::is_finite)) {
            let (lo, hi) = records
                .iter()
                .filter_map(|r| r.signals.time_since_power_on)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                    (a.min(t), b.max(t))
                });
            inv.power_on = Some((lo, hi));
        }
        inv.probe_hits = records
            .iter()
            .any(|r| matches!(r.kind, RecordKind::ProbeHit { .. }));
        inv.point_readings = records.iter().any(|r| matches!(r.kind, RecordKind::Point));
        if all(&|r| r.signals.time.is_some_and(f64::is_finite)) {
            let (lo, hi) = records
                .iter()
                .filter_map(|r| r.signals.time)
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), t| {
                    (a.min(t), b.max(t))
                });
            if hi > lo {
                inv.time_span = Some((lo, hi));
            }
        }
        inv.load = all(&|r| r.signals.load_force.is_some())
            && records
                .iter()
                .any(|r| r.signals.load_force.is_some_and(|f| f.norm() > 0.0));
        inv
    }
}
