//! Records that miss a signal nearly every other record carries are set aside, so candidates
//! that read the signal can be tried at all. A recording's first readings come before the first
//! temperature sample or before an axis has moved (its approach direction is then unknown);
//! without this step those few records would veto every thermal and reversal candidate, since a
//! term is evaluated only where its signal exists (`SignalInventory` asks for it everywhere).

use std::collections::{BTreeMap, BTreeSet};

use metrocell_estimation::{MeasurementRecord, RecordKind, Rejected};

/// A signal carried by at least this share of the records is required of all of them.
pub const REQUIRED_SHARE: f64 = 0.9;

/// Names of the signals a record carries (finite values only), in the words a user reads.
fn carried(r: &MeasurementRecord) -> BTreeSet<String> {
    let s = &r.signals;
    let axes = ["x", "y", "z"];
    let mut out = BTreeSet::new();
    for k in 0..3 {
        if s.axis_position[k].is_some_and(f64::is_finite) {
            out.insert(format!("position of {}", axes[k]));
        }
        if s.approach_direction[k].is_some() {
            out.insert(format!(
                "approach direction of {} (known once the axis has moved)",
                axes[k]
            ));
        }
        if s.axis_velocity[k].is_some_and(f64::is_finite) {
            out.insert(format!("velocity of {}", axes[k]));
        }
        if s.rotary_position[k].is_some_and(f64::is_finite) {
            out.insert(format!("rotary position {}", ["A", "B", "C"][k]));
        }
    }
    for (name, v) in &s.temperatures {
        if v.is_finite() {
            out.insert(format!("temperature/{name}"));
        }
    }
    if s.air_temperature.is_some() && s.air_pressure.is_some() && s.air_humidity.is_some() {
        out.insert("station air".into());
    }
    if s.time_since_power_on.is_some_and(f64::is_finite) {
        out.insert("time since power-on".into());
    }
    if s.load_force.is_some() {
        out.insert("load force".into());
    }
    out
}

/// Split `records` into those carrying every signal that at least [`REQUIRED_SHARE`] of them
/// carry, and the rest, each set aside naming the signals it lacks.
pub fn require_common_signals(
    records: Vec<MeasurementRecord>,
) -> (Vec<MeasurementRecord>, Vec<Rejected>) {
    let sets: Vec<BTreeSet<String>> = records.iter().map(carried).collect();
    // the shares are the machine's points' (a reference nest is read with the machine anywhere,
    // and carries no axis signal: only the other signals are required of it)
    let reference = |r: &MeasurementRecord| matches!(r.kind, RecordKind::Reference { .. });
    let mut count: BTreeMap<&str, usize> = BTreeMap::new();
    let mut points = 0usize;
    for (r, s) in records.iter().zip(&sets) {
        if reference(r) {
            continue;
        }
        points += 1;
        for name in s {
            *count.entry(name).or_default() += 1;
        }
    }
    let need = (REQUIRED_SHARE * points as f64).ceil() as usize;
    let required: Vec<String> = count
        .into_iter()
        .filter(|&(_, n)| n >= need)
        .map(|(name, _)| name.to_string())
        .collect();
    let axis_signal = |n: &str| {
        [
            "position of ",
            "approach direction of ",
            "velocity of ",
            "rotary position ",
        ]
        .iter()
        .any(|p| n.starts_with(p))
    };
    let (mut kept, mut aside) = (Vec::with_capacity(records.len()), Vec::new());
    for (r, s) in records.into_iter().zip(&sets) {
        let is_reference = reference(&r);
        let missing: Vec<&str> = required
            .iter()
            .filter(|n| !(s.contains(*n) || is_reference && axis_signal(n)))
            .map(String::as_str)
            .collect();
        if missing.is_empty() {
            kept.push(r);
        } else {
            aside.push(Rejected {
                at: format!("t = {:.3} s, channel {}", r.time, r.channel),
                point_id: r.point_id.clone(),
                reason: format!("lacks {} (carried by at least {:.0} % of the records; set aside so the terms that read it can be tried)", missing.join(", "), REQUIRED_SHARE * 100.0),
            });
        }
    }
    (kept, aside)
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_estimation::RecordKind;
    use metrocell_physics::Signals;
    use nalgebra::{Matrix3, Vector3};

    fn record(i: usize, temperature: bool, approach: bool) -> MeasurementRecord {
        let mut signals = Signals::default();
        signals.axis_position[0] = Some(0.1 * i as f64);
        if approach {
            signals.approach_direction[0] = Some(1.0);
        }
        if temperature {
            signals.temperatures.insert("x_left".into(), 20.0);
        }
        MeasurementRecord {
            time: i as f64,
            point_id: format!("p{i}"),
            channel: "tracker".into(),
            q: vec![0.0; 3],
            measured: Vector3::zeros(),
            covariance: Matrix3::identity(),
            signals,
            kind: RecordKind::Point,
        }
    }

    #[test]
    fn the_few_records_before_a_signal_starts_are_set_aside_naming_it() {
        // 2 before the first temperature, 1 before the first motion, 97 with both
        let records: Vec<_> = (0..100)
            .map(|i| record(i, i >= 2, i != 0 && i != 2))
            .collect();
        let (kept, aside) = require_common_signals(records);
        assert_eq!(kept.len(), 97);
        assert_eq!(aside.len(), 3);
        assert!(
            aside[0].reason.contains("approach direction of x")
                && aside[0].reason.contains("temperature/x_left"),
            "{}",
            aside[0].reason
        );
        assert!(
            aside[1].reason.contains("temperature/x_left") && !aside[1].reason.contains("approach"),
            "{}",
            aside[1].reason
        );
    }

    #[test]
    fn a_signal_most_records_lack_is_not_required() {
        // a sensor that reported during the last 20 % only: nothing is set aside for it
        let records: Vec<_> = (0..100).map(|i| record(i, i >= 80, true)).collect();
        let (kept, aside) = require_common_signals(records);
        assert_eq!((kept.len(), aside.len()), (100, 0));
    }
}
