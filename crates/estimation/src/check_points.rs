//! Check points: points of the program kept out of every fit (bag import `role: check`), and
//! how well a model predicts them — per placement of the instrument and over all.
//!
//! Error convention (stated once): e = predicted − measured, in the instrument's frame (the
//! frame the points were measured in; for a levelled instrument its z is straight up, so `xy` is
//! the horizontal error and `z` the vertical). Statistics: `rms_m` of the 3-D error norms,
//! `p50_xy_m` and `p95_xy_m` percentiles of √(e_x² + e_y²), `p95_z_m` of |e_z|, `max_m` the
//! largest 3-D norm; percentiles by linear interpolation between order statistics (numpy's
//! default), so that other tools reproduce them.

use std::collections::BTreeMap;

use metrocell_model::ForwardModel;
use nalgebra::Vector3;

use crate::records::{MeasurementRecord, RecordSet};
use crate::residuals::predict;

/// How well check points are predicted (serialised as `{n, rms_m, p50_xy_m, p95_xy_m, p95_z_m,
/// max_m}`, NaN as null).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct CheckStatistics {
    pub n: usize,
    pub rms_m: f64,
    pub p50_xy_m: f64,
    pub p95_xy_m: f64,
    pub p95_z_m: f64,
    pub max_m: f64,
}

/// The `q`-quantile (0…1) of `v` by linear interpolation (numpy's default); NaN when empty.
pub fn quantile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let h = (s.len() - 1) as f64 * q.clamp(0.0, 1.0);
    let (lo, hi) = (h.floor() as usize, h.ceil() as usize);
    s[lo] + (h - lo as f64) * (s[hi] - s[lo])
}

/// The statistics of errors (predicted − measured).
pub fn check_statistics(errors: &[Vector3<f64>]) -> CheckStatistics {
    let xy: Vec<f64> = errors.iter().map(|e| e.x.hypot(e.y)).collect();
    let z: Vec<f64> = errors.iter().map(|e| e.z.abs()).collect();
    let norms: Vec<f64> = errors.iter().map(|e| e.norm()).collect();
    let rms = if errors.is_empty() {
        f64::NAN
    } else {
        (norms.iter().map(|n| n * n).sum::<f64>() / norms.len() as f64).sqrt()
    };
    CheckStatistics {
        n: errors.len(),
        rms_m: rms,
        p50_xy_m: quantile(&xy, 0.5),
        p95_xy_m: quantile(&xy, 0.95),
        p95_z_m: quantile(&z, 0.95),
        max_m: norms.iter().cloned().fold(f64::NAN, f64::max),
    }
}

/// A check point the model could not predict, and why (its setup has no fitted pose, a signal
/// is missing…).
#[derive(Debug, Clone, PartialEq)]
pub struct Unpredicted {
    pub point_id: String,
    pub setup: Option<String>,
    pub reason: String,
}

/// The check points' statistics over all, per setup, and the points left unpredicted.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckReport {
    pub overall: CheckStatistics,
    pub setups: BTreeMap<String, CheckStatistics>,
    pub unpredicted: Vec<Unpredicted>,
}

/// Predict every check point of `records` with `model` at `x`.
pub fn check_report(model: &ForwardModel, x: &[f64], records: &RecordSet) -> CheckReport {
    check_report_of(model, x, &records.check)
}

/// [`check_report`] of the records `check`.
pub fn check_report_of(
    model: &ForwardModel,
    x: &[f64],
    check: &[MeasurementRecord],
) -> CheckReport {
    let mut all = Vec::new();
    let mut by_setup: BTreeMap<String, Vec<Vector3<f64>>> = BTreeMap::new();
    let mut unpredicted = Vec::new();
    let kin = match model.kinematic_truth(x) {
        Ok(k) => k,
        Err(e) => {
            let unpredicted = check
                .iter()
                .map(|r| Unpredicted {
                    point_id: r.point_id.clone(),
                    setup: r.signals.setup.as_deref().map(str::to_string),
                    reason: e.to_string(),
                })
                .collect();
            return CheckReport {
                overall: check_statistics(&[]),
                setups: BTreeMap::new(),
                unpredicted,
            };
        }
    };
    for r in check {
        let setup = r.signals.setup.as_deref().map(str::to_string);
        let mut s = r.signals.clone();
        match predict(model, x, &kin, r, &mut s) {
            Ok(p) => {
                let e = p - r.measured;
                all.push(e);
                if let Some(name) = setup {
                    by_setup.entry(name).or_default().push(e);
                }
            }
            Err(e) => unpredicted.push(Unpredicted {
                point_id: r.point_id.clone(),
                setup,
                reason: e.to_string(),
            }),
        }
    }
    CheckReport {
        overall: check_statistics(&all),
        setups: by_setup
            .iter()
            .map(|(k, v)| (k.clone(), check_statistics(v)))
            .collect(),
        unpredicted,
    }
}

/// The placements of the instrument the records name (`signals.setup`), in order of first
/// appearance, with their numbers of fit and check points.
pub fn setups_of(records: &RecordSet) -> Vec<(String, usize, usize)> {
    let mut out: Vec<(String, usize, usize)> = Vec::new();
    for (r, check) in records
        .records
        .iter()
        .map(|r| (r, false))
        .chain(records.check.iter().map(|r| (r, true)))
    {
        let Some(s) = r.signals.setup.as_deref() else {
            continue;
        };
        let k = match out.iter().position(|(n, _, _)| n == s) {
            Some(k) => k,
            None => {
                out.push((s.to_string(), 0, 0));
                out.len() - 1
            }
        };
        if check {
            out[k].2 += 1;
        } else {
            out[k].1 += 1;
        }
    }
    out
}

/// The setups with at least `needed` fit points (a pose's worth), and the words for those
/// without: their fit points are taken out of `records` (nothing could place them), their check
/// points stay (they are reported unpredicted).
pub fn usable_setups(records: &mut RecordSet, needed: usize) -> (Vec<String>, Vec<String>) {
    let mut usable = Vec::new();
    let mut notes = Vec::new();
    for (name, fit_points, check_points) in setups_of(records) {
        if fit_points >= needed {
            usable.push(name);
        } else {
            notes.push(format!("setup `{name}` has {fit_points} fit point(s), fewer than the {needed} its pose needs: left out of the fit, its {check_points} check point(s) unpredicted (measure at least {needed} fit points from every placement)"));
            records
                .records
                .retain(|r| r.signals.setup.as_deref() != Some(name.as_str()));
        }
    }
    (usable, notes)
}

/// Whether stacked parameter `name` is a placement's (a nuisance of every fit, per recording):
/// an instrument pose (`tracker_pose.*`, `tracker_pose[…].*`) or the base's tilt (`base_tilt*`).
pub fn is_placement_parameter(name: &str) -> bool {
    name.starts_with("tracker_pose.")
        || name.starts_with("tracker_pose[")
        || name.starts_with("base_tilt")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_interpolate_like_numpy() {
        // numpy.percentile([1, 2, 3, 4, 10], [50, 95]) = [3.0, 8.8]
        let v = [4.0, 1.0, 10.0, 3.0, 2.0];
        assert_eq!(quantile(&v, 0.5), 3.0);
        assert!((quantile(&v, 0.95) - 8.8).abs() < 1e-12);
        assert!(quantile(&[], 0.5).is_nan());
    }

    #[test]
    fn statistics_split_horizontal_and_vertical() {
        let e = [Vector3::new(3e-3, 4e-3, 0.0), Vector3::new(0.0, 0.0, -2e-3)];
        let s = check_statistics(&e);
        assert_eq!(s.n, 2);
        assert!((s.max_m - 5e-3).abs() < 1e-15);
        assert!((s.p50_xy_m - 2.5e-3).abs() < 1e-15);
        assert!((s.p95_z_m - 1.9e-3).abs() < 1e-15);
        assert!((s.rms_m - ((25e-6 + 4e-6) / 2.0f64).sqrt()).abs() < 1e-15);
    }
}
