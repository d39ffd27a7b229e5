//! The verification's readings as a length test: each visit of a mesh point averaged into one
//! measured point in the machine frame (the fit's registration of the tracker), and the test's
//! lengths measured from them — as the machine is, and as it would be with the fitted error
//! map compensated — with their expanded uncertainty (k = 2).

use metrocell_estimation::{Fit, RecordFrame, RecordSet};
use metrocell_kinematics::transform::euler_xyz;
use metrocell_model::ForwardModel;
use nalgebra::{Matrix3, Vector3};

use crate::length_test::{length_error, Decision, LengthCase, Mpe};

/// The readings taken while the machine stood at a point: those whose commanded position (to
/// the micrometre) at least `min_readings` readings share. A tracker streaming during moves
/// also reads the target on its way, at positions no other reading has; those are left out
/// (time-stamp skew between controller and tracker makes a moving reading's position
/// uncertain by feed × skew, which no reading's covariance states).
pub fn at_rest(records: &RecordSet, min_readings: usize) -> RecordSet {
    let mut count: std::collections::BTreeMap<Vec<i64>, usize> = Default::default();
    for r in &records.records {
        *count.entry(key(&r.q)).or_default() += 1;
    }
    RecordSet {
        frame: records.frame.clone(),
        records: records
            .records
            .iter()
            .filter(|r| count[&key(&r.q)] >= min_readings)
            .cloned()
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

fn key(q: &[f64]) -> Vec<i64> {
    q.iter().map(|v| (v * 1e6).round() as i64).collect()
}

/// One stop at a mesh point: the mean of its readings in the machine frame, and that mean's
/// covariance.
#[derive(Debug, Clone, PartialEq)]
pub struct Visit {
    pub point: usize,
    pub mean: Vector3<f64>,
    pub covariance: Matrix3<f64>,
    pub readings: usize,
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
    let mut current: Option<(usize, Vec<usize>)> = None;
    let close = |group: Option<(usize, Vec<usize>)>, out: &mut Vec<Visit>| {
        if let Some((point, members)) = group {
            let n = members.len() as f64;
            let mean = members
                .iter()
                .map(|&i| r * records.records[i].measured + t)
                .sum::<Vector3<f64>>()
                / n;
            let cov = members
                .iter()
                .map(|&i| r * records.records[i].covariance * r.transpose())
                .sum::<Matrix3<f64>>()
                / (n * n);
            out.push(Visit {
                point,
                mean,
                covariance: cov,
                readings: members.len(),
            });
        }
    };
    for i in order {
        let Some(&point) = index.get(&key(&records.records[i].q)) else {
            continue;
        };
        match &mut current {
            Some((p, members)) if *p == point => members.push(i),
            _ => {
                close(current.take(), &mut out);
                current = Some((point, vec![i]));
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
/// measured points) and after (each point less the fitted error `map` there, whose standard
/// uncertainty `map_sd` joins the readings' in U). The points' errors are taken as
/// independent in U — conservative where the map's errors at two points are correlated, as a
/// smooth map's are.
pub fn measured_lengths(
    cases: &[LengthCase],
    visits: &[Visit],
    map: &[Vector3<f64>],
    map_sd: &[Vector3<f64>],
    repetitions: usize,
    mpe: Option<Mpe>,
) -> Vec<MeasuredLength> {
    let mut by_point: Vec<Vec<&Visit>> = vec![vec![]; map.len()];
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
            let mut measured = vec![Vector3::zeros(); map.len()];
            measured[c.from] = a.mean;
            measured[c.to] = b.mean;
            let before = length_error(c, &measured);
            measured[c.from] -= map[c.from];
            measured[c.to] -= map[c.to];
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
