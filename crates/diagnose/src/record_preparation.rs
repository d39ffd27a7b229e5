//! Records made ready for diagnosis: unusable ones set aside with the reason, repeated readings
//! of one stationary point averaged (a dwell of a tracker at 10 Hz is one measurement of that
//! point, with the scatter of its readings as evidence of the noise), and the pooled scatter of
//! those repeats against their stated covariance — the recording's own measure of whether the
//! stated uncertainties are right.

use metrocell_estimation::residuals::whitening;
use metrocell_estimation::{MeasurementRecord, Rejected};
use nalgebra::{Matrix3, Vector3};

/// What the preparation did.
#[derive(Debug, Clone, Default)]
pub struct Prepared {
    pub records: Vec<MeasurementRecord>,
    pub rejected: Vec<Rejected>,
    /// Readings in, records out (after averaging repeats).
    pub readings: usize,
    /// Number of averaged groups (each of ≥ 2 readings).
    pub groups: usize,
    /// √(pooled χ²/dof) of repeated readings about their group means: the factor by which the
    /// scatter of repeats exceeds (> 1) or falls short of (< 1) the stated covariance; with its
    /// degrees of freedom. None without repeats.
    pub repeatability_scale: Option<(f64, usize)>,
}

/// Longest stretch of time averaged into one record (s): a tracker's dwell at a point lasts a
/// few seconds; drifts (warm-up, temperature) over longer stays are kept.
pub const MAX_GROUP_SPAN: f64 = 10.0;

fn usable(r: &MeasurementRecord) -> Result<(), String> {
    if !r.measured.iter().all(|v| v.is_finite()) {
        return Err("measured point is not finite (NaN or infinite)".into());
    }
    if !r.time.is_finite() {
        return Err("time stamp is not finite".into());
    }
    // a reference nest is not where the machine is: it has no joints
    if !matches!(r.kind, metrocell_estimation::RecordKind::Reference { .. })
        && (r.q.is_empty() || !r.q.iter().all(|v| v.is_finite()))
    {
        return Err("commanded joint vector is missing or not finite".into());
    }
    if whitening(&r.covariance).is_none() {
        return Err("covariance is not finite and positive definite".into());
    }
    Ok(())
}

fn stationary(r: &MeasurementRecord) -> bool {
    r.signals
        .axis_velocity
        .iter()
        .all(|v| v.is_none_or(|v| v.abs() < 1e-9))
}

/// Set aside unusable records, and (if `average_repeats`) average runs of consecutive readings
/// of one channel at one stationary commanded position no more than `max_gap` s apart.
pub fn prepare(records: &[MeasurementRecord], average_repeats: bool, max_gap: f64) -> Prepared {
    let mut out = Prepared {
        readings: records.len(),
        ..Default::default()
    };
    let mut good: Vec<&MeasurementRecord> = Vec::with_capacity(records.len());
    for (i, r) in records.iter().enumerate() {
        match usable(r) {
            Ok(()) => good.push(r),
            Err(reason) => out.rejected.push(Rejected {
                at: format!("record {i} (t = {:.3} s, channel {})", r.time, r.channel),
                point_id: r.point_id.clone(),
                reason,
            }),
        }
    }
    good.sort_by(|a, b| a.time.total_cmp(&b.time));
    let (good, aside) =
        crate::signal_coverage::require_common_signals(good.into_iter().cloned().collect());
    out.rejected.extend(aside);
    let good: Vec<&MeasurementRecord> = good.iter().collect();
    if !average_repeats {
        out.records = good.into_iter().cloned().collect();
        with_times(&mut out.records);
        return out;
    }
    let (mut chi2, mut dof) = (0.0, 0usize);
    let mut i = 0;
    while i < good.len() {
        let first = good[i];
        let mut j = i + 1;
        if stationary(first) {
            while j < good.len() {
                let (prev, next) = (good[j - 1], good[j]);
                // a long stay at one place (a machine idling at home) is cut into pieces of
                // `MAX_GROUP_SPAN`, so drifts over the stay are kept; only readings of one thing
                // are averaged (a probe's hits in eight directions from one stand are eight)
                // (a point approached from the other side is another measurement: the turn of a
                // bidirectional run reads one target twice, a reversal error apart)
                let same = next.channel == first.channel
                    && next.kind == first.kind
                    && next.q.len() == first.q.len()
                    && next
                        .q
                        .iter()
                        .zip(&first.q)
                        .all(|(a, b)| (a - b).abs() <= 1e-9)
                    && next.signals.approach_direction == first.signals.approach_direction
                    && stationary(next)
                    && next.time - prev.time <= max_gap
                    && next.time - first.time <= MAX_GROUP_SPAN;
                if !same {
                    break;
                }
                j += 1;
            }
        }
        let group = &good[i..j];
        if group.len() == 1 {
            out.records.push(first.clone());
        } else {
            let n = group.len() as f64;
            let mean: Vector3<f64> = group.iter().map(|r| r.measured).sum::<Vector3<f64>>() / n;
            let mean_cov: Matrix3<f64> =
                group.iter().map(|r| r.covariance).sum::<Matrix3<f64>>() / n;
            for r in group {
                let w = whitening(&r.covariance).expect("checked usable");
                chi2 += (w * (r.measured - mean)).norm_squared();
            }
            dof += 3 * (group.len() - 1);
            // the middle reading's time and signals stand for the group
            let mut avg = group[group.len() / 2].clone();
            avg.measured = mean;
            avg.covariance = mean_cov / n;
            out.records.push(avg);
            out.groups += 1;
        }
        i = j;
    }
    if dof >= 3 {
        out.repeatability_scale = Some(((chi2 / dof as f64).sqrt(), dof));
    }
    with_times(&mut out.records);
    out
}

/// Every record's signals carry its time (terms that drift in time read it; a record built by
/// hand may give it only in `MeasurementRecord::time`).
fn with_times(records: &mut [MeasurementRecord]) {
    for r in records {
        if r.signals.time.is_none() {
            r.signals.time = Some(r.time);
        }
    }
}
