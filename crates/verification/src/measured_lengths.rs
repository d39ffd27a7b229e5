//! The verification's readings as a length test: each visit of a mesh point averaged into one
//! measured point in the machine frame (the fit's registration of the tracker, its identified
//! instrument errors — warm-up, refraction — taken out), and the test's lengths measured from
//! them — as the machine is, and as it would be with the identified model compensated at that
//! visit's conditions (its temperatures: the thermal terms too) — with their expanded
//! uncertainty (k = 2).

use metrocell_estimation::residuals::predict;
use metrocell_estimation::{Fit, RecordFrame, RecordKind, RecordSet};
use metrocell_kinematics::transform::euler_xyz;
use metrocell_model::ForwardModel;
use nalgebra::{Matrix3, Vector3};

use crate::length_test::{length_error, Decision, LengthCase, Mpe};

/// The readings taken while the machine stood at a point: runs of at least `min_readings`
/// readings, consecutive in time, at one commanded position (to the micrometre). A tracker
/// streaming during moves also reads the target on its way; those readings are left out
/// (time-stamp skew between controller and tracker makes a moving reading's position
/// uncertain by feed × skew, which no reading's covariance states). Consecutive, not merely
/// shared: a program repeated on a fixed clock passes the same positions on the move in every
/// cycle, and those must not count as stops.
pub fn at_rest(records: &RecordSet, min_readings: usize) -> RecordSet {
    let mut order: Vec<usize> = (0..records.records.len()).collect();
    order.sort_by(|&a, &b| records.records[a].time.total_cmp(&records.records[b].time));
    let mut keep = vec![false; records.records.len()];
    let mut start = 0;
    while start < order.len() {
        let k = key(&records.records[order[start]].q);
        let mut end = start + 1;
        while end < order.len() && key(&records.records[order[end]].q) == k {
            end += 1;
        }
        if end - start >= min_readings {
            for &i in &order[start..end] {
                keep[i] = true;
            }
        }
        start = end;
    }
    RecordSet {
        frame: records.frame.clone(),
        records: records
            .records
            .iter()
            .zip(&keep)
            .filter(|(_, k)| **k)
            .map(|(r, _)| r.clone())
            .collect(),
        check: records.check.clone(),
        rejected: records.rejected.clone(),
        sources: records.sources.clone(),
    }
}

/// The distinct commanded positions of the readings the fit used, in first-visit order (the
/// verification's mesh), compared to the micrometre.
pub fn mesh_of(records: &RecordSet, f: &Fit) -> Vec<Vec<f64>> {
    let mut seen = std::collections::BTreeSet::new();
    let mut out = vec![];
    for &i in &f.used {
        let q = &records.records[i].q;
        if seen.insert(key(q)) {
            out.push(q.clone());
        }
    }
    out
}

/// A stop's identity: the mesh point and the target's offset from the model's tool (µm).
type Stop = (usize, Vec<i64>);

fn key(q: &[f64]) -> Vec<i64> {
    q.iter().map(|v| (v * 1e6).round() as i64).collect()
}

/// One stop at a mesh point: the mean of its readings in the machine frame, that mean's
/// covariance, and the error the identified model predicts there at the stop's conditions.
#[derive(Debug, Clone, PartialEq)]
pub struct Visit {
    pub point: usize,
    pub mean: Vector3<f64>,
    pub covariance: Matrix3<f64>,
    pub readings: usize,
    /// The identified model's error of the tool point over the stop's readings (their mean, m):
    /// what compensating the machine with the model removes at this stop — its geometric
    /// errors and, at the stop's temperatures, its thermal terms.
    pub compensation: Vector3<f64>,
    /// The sighted target's offset from the model's tool during the stop (m; zero: the model's
    /// tool — [`metrocell_physics::Signals::tool_offset_shift`]).
    pub tool_shift: Vector3<f64>,
}

/// The visits of one target, for a length test (ISO 10360-2 measures with one probe): those at
/// the model's tool when any are, else those of the target with the most visits. Returns them
/// and that target's offset from the model's tool (m).
pub fn visits_of_one_target(visits: &[Visit]) -> (Vec<Visit>, Vector3<f64>) {
    let mut counts: Vec<(Vec<i64>, Vector3<f64>, usize)> = vec![];
    for v in visits {
        let k = key(v.tool_shift.as_slice());
        match counts.iter_mut().find(|(c, _, _)| *c == k) {
            Some(c) => c.2 += 1,
            None => counts.push((k, v.tool_shift, 1)),
        }
    }
    let zero = key(&[0.0; 3]);
    let chosen = counts
        .iter()
        .find(|(k, _, _)| *k == zero)
        .or_else(|| counts.iter().max_by_key(|(_, _, n)| *n))
        .map(|(k, shift, _)| (k.clone(), *shift));
    match chosen {
        Some((k, shift)) => (
            visits
                .iter()
                .filter(|v| key(v.tool_shift.as_slice()) == k)
                .cloned()
                .collect(),
            shift,
        ),
        None => (vec![], Vector3::zeros()),
    }
}

/// The fit's tracker pose (p_machine = R·p_tracker + T), identity for machine-frame records.
fn registration(
    model: &ForwardModel,
    records: &RecordSet,
    f: &Fit,
) -> (Matrix3<f64>, Vector3<f64>) {
    let names = model.param_names();
    match (
        &records.frame,
        names.iter().position(|n| n == "tracker_pose.tx"),
    ) {
        (RecordFrame::Instrument(_), Some(i)) => (
            euler_xyz(f.x[i + 3], f.x[i + 4], f.x[i + 5]),
            Vector3::new(f.x[i], f.x[i + 1], f.x[i + 2]),
        ),
        _ => (Matrix3::identity(), Vector3::zeros()),
    }
}

/// The visits of `mesh` in the order they happened: consecutive used readings at one
/// commanded position form a visit.
pub fn visits(model: &ForwardModel, records: &RecordSet, f: &Fit, mesh: &[Vec<f64>]) -> Vec<Visit> {
    let (r, t) = registration(model, records, f);
    let index: std::collections::BTreeMap<Vec<i64>, usize> =
        mesh.iter().enumerate().map(|(k, q)| (key(q), k)).collect();
    let mut order: Vec<usize> = f.used.clone();
    order.sort_by(|&a, &b| records.records[a].time.total_cmp(&records.records[b].time));
    let mut out: Vec<Visit> = vec![];
    // a stop: consecutive readings at one point with one target
    let mut current: Option<(Stop, Vec<usize>)> = None;
    let kin = model.kinematic_truth(&f.x).ok();
    // a reading in the machine frame with the identified instrument errors taken out: the
    // model's true tool point plus the reading's residual, turned into the machine frame; and
    // the model's error of the tool point there. Where the model cannot say (no kinematics at
    // these parameters, a signal missing), the registered reading and no compensation.
    let corrected = |i: usize| -> (Vector3<f64>, Vector3<f64>) {
        let rec = &records.records[i];
        let registered = r * rec.measured + t;
        let Some(kin) = &kin else {
            return (registered, Vector3::zeros());
        };
        let mut s = rec.signals.clone();
        let Ok(tool) = model.tool_state(&f.x, kin, &rec.q, &mut s, None) else {
            return (registered, Vector3::zeros());
        };
        // a tracker reading predicted from the tool state just computed; other kinds as the
        // fit predicts them
        let predicted = match rec.kind {
            RecordKind::Point => model
                .tracker(&f.x, &tool, &mut s)
                .map(|t| t.measured_point()),
            _ => predict(model, &f.x, kin, rec, &mut rec.signals.clone()),
        };
        match predicted {
            Ok(predicted) => (tool.target() + r * (rec.measured - predicted), tool.d),
            Err(_) => (registered, Vector3::zeros()),
        }
    };
    let shift = |i: usize| {
        records.records[i]
            .signals
            .tool_offset_shift
            .unwrap_or_default()
    };
    let close = |group: Option<(Stop, Vec<usize>)>, out: &mut Vec<Visit>| {
        if let Some(((point, _), members)) = group {
            let n = members.len() as f64;
            let (sum, comp) = members
                .iter()
                .map(|&i| corrected(i))
                .fold((Vector3::zeros(), Vector3::zeros()), |(a, b), (p, e)| {
                    (a + p, b + e)
                });
            let cov = members
                .iter()
                .map(|&i| r * records.records[i].covariance * r.transpose())
                .sum::<Matrix3<f64>>()
                / (n * n);
            out.push(Visit {
                point,
                mean: sum / n,
                covariance: cov,
                readings: members.len(),
                compensation: comp / n,
                tool_shift: shift(members[0]),
            });
        }
    };
    for i in order {
        let Some(&point) = index.get(&key(&records.records[i].q)) else {
            continue;
        };
        let stop = (point, key(shift(i).as_slice()));
        match &mut current {
            Some((p, members)) if *p == stop => members.push(i),
            _ => {
                close(current.take(), &mut out);
                current = Some((stop, vec![i]));
            }
        }
    }
    close(current, &mut out);
    out
}

/// One measured length of the test.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredLength {
    pub case: LengthCase,
    pub repetition: usize,
    /// E as the machine is, and with the fitted map compensated (m).
    pub error_before: f64,
    pub error_after: f64,
    /// Expanded uncertainty (k = 2) of each (m).
    pub u_before: f64,
    pub u_after: f64,
    pub decision_before: Option<Decision>,
    pub decision_after: Option<Decision>,
}

/// The test's lengths from the first `repetitions` visits of each point: E before (the
/// measured points) and after (each point less the model's error at that visit, its
/// [`Visit::compensation`]; the map's standard uncertainty at the point, `map_sd`, joins the
/// readings' in U). The points' errors are taken as independent in U — conservative where the
/// map's errors at two points are correlated, as a smooth map's are.
pub fn measured_lengths(
    cases: &[LengthCase],
    visits: &[Visit],
    map_sd: &[Vector3<f64>],
    repetitions: usize,
    mpe: Option<Mpe>,
) -> Vec<MeasuredLength> {
    let mut by_point: Vec<Vec<&Visit>> = vec![vec![]; map_sd.len()];
    for v in visits {
        by_point[v.point].push(v);
    }
    let mut out = vec![];
    for rep in 0..repetitions {
        for c in cases {
            let (Some(a), Some(b)) = (by_point[c.from].get(rep), by_point[c.to].get(rep)) else {
                continue;
            };
            let d = (b.mean - a.mean).normalize();
            let var_readings = (d.transpose() * (a.covariance + b.covariance) * d)[(0, 0)];
            let var_map = (map_sd[c.from].component_mul(&d)).norm_squared()
                + (map_sd[c.to].component_mul(&d)).norm_squared();
            let mut measured = vec![Vector3::zeros(); map_sd.len()];
            measured[c.from] = a.mean;
            measured[c.to] = b.mean;
            let before = length_error(c, &measured);
            measured[c.from] -= a.compensation;
            measured[c.to] -= b.compensation;
            let after = length_error(c, &measured);
            let (u_before, u_after) = (
                2.0 * var_readings.sqrt(),
                2.0 * (var_readings + var_map).sqrt(),
            );
            out.push(MeasuredLength {
                case: c.clone(),
                repetition: rep + 1,
                error_before: before,
                error_after: after,
                u_before,
                u_after,
                decision_before: mpe.map(|m| Decision::judge(before, u_before, m.at(c.nominal))),
                decision_after: mpe.map(|m| Decision::judge(after, u_after, m.at(c.nominal))),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_estimation::MeasurementRecord;

    fn reading(time: f64, x: f64) -> MeasurementRecord {
        MeasurementRecord {
            time,
            point_id: format!("t{time}"),
            channel: "tracker".into(),
            q: vec![x, 0.2, 0.3],
            measured: Vector3::new(x, 0.2, 0.3),
            covariance: Matrix3::identity() * 1e-12,
            signals: Default::default(),
            kind: RecordKind::Point,
        }
    }

    /// Two cycles of one program on a fixed clock: the stops (four readings each) are kept; the
    /// positions passed on the move, the same in both cycles, are not — though three readings
    /// share each of them when a third cycle passes too.
    #[test]
    fn only_consecutive_readings_at_one_position_are_a_stop() {
        let mut records = vec![];
        let mut t = 0.0;
        for _cycle in 0..3 {
            for stop in [0.8, 1.0] {
                for _ in 0..4 {
                    records.push(reading(t, stop));
                    t += 1.0;
                }
                // on the move to the next stop: the same positions every cycle
                for k in 1..4 {
                    records.push(reading(t, stop + 0.05 * k as f64));
                    t += 1.0;
                }
            }
        }
        let set = RecordSet {
            frame: RecordFrame::Machine,
            records,
            check: vec![],
            rejected: vec![],
            sources: vec![],
        };
        let kept = at_rest(&set, 3);
        assert_eq!(kept.records.len(), 3 * 2 * 4);
        assert!(kept.records.iter().all(|r| r.q[0] == 0.8 || r.q[0] == 1.0));
    }

    fn visit(point: usize, shift: Vector3<f64>) -> Visit {
        Visit {
            point,
            mean: Vector3::zeros(),
            covariance: Matrix3::identity(),
            readings: 4,
            compensation: Vector3::zeros(),
            tool_shift: shift,
        }
    }

    /// The length test measures with one target: the model's tool when it was measured, else
    /// the target with the most visits.
    #[test]
    fn the_length_test_takes_one_targets_visits() {
        let (tool, across, down) = (
            Vector3::zeros(),
            Vector3::new(0.15, 0.0, 0.0),
            Vector3::new(0.0, 0.0, -0.15),
        );
        let all = vec![
            visit(0, across),
            visit(0, tool),
            visit(1, down),
            visit(1, tool),
            visit(2, across),
        ];
        let (kept, shift) = visits_of_one_target(&all);
        assert_eq!(shift, tool);
        assert_eq!(kept.iter().map(|v| v.point).collect::<Vec<_>>(), [0, 1]);
        let (kept, shift) = visits_of_one_target(&all[2..]);
        assert_eq!((kept.len(), kept[0].point, shift), (1, 1, tool));
        let (kept, shift) = visits_of_one_target(&[all[0].clone(), all[4].clone(), all[2].clone()]);
        assert_eq!((kept.len(), shift), (2, across), "the most visited");
        assert!(visits_of_one_target(&[]).0.is_empty());
    }
}
