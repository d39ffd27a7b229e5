//! A stationing program's waypoints (`program.stationing`): column levels × arm configurations
//! (solution spaces) = groups, level-major; in each group `fit_points + check_points` waypoints,
//! the column (the arm's first joint variable) at the level and every other joint at the
//! configuration's value plus a uniform draw within ±`spread`, clamped to the joint's limits
//! (a waypoint whose nominal tool point is below `min_tool_height` in the base frame is drawn
//! again). The `fit_points` fit waypoints are picked far apart (farthest-point sampling over the
//! nominal tool points, from the one farthest from the group's centroid), the others are check
//! points; the group keeps its draw order as its visiting order. Groups are measured from the
//! instrument's setups in turn, `groups_per_setup` consecutive groups each.
//!
//! The plan is a pure function of the section and its own `seed` (default 1): two recordings of
//! the cell (on flat ground and tilted, with different noise seeds) visit the same waypoints.

use metrocell_model::MachineGeometry;
use nalgebra::{DVector, Vector3};

use crate::cell_file::StationingSection;
use crate::error::CellError;
use crate::noise::{stream, NoiseStream};
use crate::sample::PointRole;
use crate::stationing::{arm_of, Placement};

/// One waypoint of the plan.
#[derive(Debug, Clone, PartialEq)]
pub struct Waypoint {
    /// `G<group>.<index>`, both 1-based (`G03.017`).
    pub point_id: String,
    /// Group index (0-based): level-major over (level, configuration).
    pub group: usize,
    /// Index of the setup (placement) it is measured from.
    pub setup: usize,
    pub role: PointRole,
    /// Commanded joint variables (the arm's, in chain order).
    pub q: DVector<f64>,
}

/// Draws on a uniform clamped perturbation give up after this many tries per waypoint.
const MAX_DRAWS: usize = 1000;

/// The waypoints of `s` for the arm of `machine`, measured from `placements` (module doc).
pub fn plan(
    s: &StationingSection,
    machine: &MachineGeometry,
    placements: &[Placement],
) -> Result<Vec<Waypoint>, CellError> {
    let p = "program.stationing";
    let arm = arm_of(machine).ok_or_else(|| {
        CellError::invalid(
            p,
            "is for a serial_arm (a lifting column and an arm from a URDF)",
        )
    })?;
    // the cell's joint limits, within the URDF's `<limit>`s
    let urdf_limits = arm
        .chain
        .joints
        .iter()
        .filter(|j| j.is_variable())
        .map(|j| j.limits);
    let limits: Vec<([f64; 2], &str)> = machine
        .joint_limits()
        .into_iter()
        .zip(urdf_limits)
        .map(|(([lo, hi], unit), u)| (u.map_or([lo, hi], |[a, b]| [lo.max(a), hi.min(b)]), unit))
        .collect();
    let names = machine.joint_names();
    let dof = names.len();
    if dof < 2 {
        return Err(CellError::invalid(
            p,
            format!(
                "needs an arm with a column and at least one more joint; this one has {}",
                names.join(", ")
            ),
        ));
    }
    let levels = s
        .levels
        .iter()
        .enumerate()
        .map(|(i, q)| q.to_si(&format!("{p}.levels[{i}]"), limits[0].1))
        .collect::<Result<Vec<_>, _>>()?;
    let spread = joints(&s.spread, &format!("{p}.spread"), &limits[1..], &names[1..])?;
    let mut configurations = Vec::new();
    for (i, c) in s.configurations.iter().enumerate() {
        configurations.push(joints(
            &c.joints,
            &format!("{p}.configurations[{i}].joints"),
            &limits[1..],
            &names[1..],
        )?);
    }
    if levels.is_empty() || configurations.is_empty() {
        return Err(CellError::invalid(p, "needs at least one of `levels` (the column's) and one of `configurations` ({name, joints})"));
    }
    let (fit, check) = (s.fit_points as usize, s.check_points as usize);
    if fit < 2 || fit + check > 10_000 {
        return Err(CellError::invalid(format!("{p}.fit_points"), format!("needs at least 2 fit points per group (a levelled setup's pose needs 2) and at most 10000 waypoints per group; got {fit} + {check}")));
    }
    let per_setup = s.groups_per_setup.unwrap_or(1) as usize;
    if per_setup == 0 {
        return Err(CellError::invalid(
            format!("{p}.groups_per_setup"),
            "must be at least 1",
        ));
    }
    let min_height = s
        .min_tool_height
        .as_ref()
        .map(|q| q.to_si(&format!("{p}.min_tool_height"), "m"))
        .transpose()?
        .unwrap_or(f64::NEG_INFINITY);
    let tool = |q: &DVector<f64>| {
        arm.chain
            .tool_pose(q.as_slice())
            .map(|t| t.translation.vector)
    };
    let mut rng = NoiseStream::new(s.seed.unwrap_or(1), stream::STATIONING_PLAN);
    let mut out = Vec::new();
    for (li, level) in levels.iter().enumerate() {
        let [lo, hi] = limits[0].0;
        if !(*level >= lo && *level <= hi) {
            return Err(CellError::OutOfRange {
                path: format!("{p}.levels[{li}]"),
                value: *level,
                reason: format!(
                    "{} outside its limits [{lo}, {hi}] {}",
                    names[0], limits[0].1
                ),
            });
        }
        for (ci, centre) in configurations.iter().enumerate() {
            let group = out.last().map_or(0, |w: &Waypoint| w.group + 1);
            let mut qs = Vec::with_capacity(fit + check);
            let mut points = Vec::with_capacity(fit + check);
            while qs.len() < fit + check {
                let mut drawn = None;
                for _ in 0..MAX_DRAWS {
                    let mut q = DVector::from_element(dof, *level);
                    for k in 1..dof {
                        let [lo, hi] = limits[k].0;
                        q[k] = (centre[k - 1] + spread[k - 1] * (2.0 * rng.uniform() - 1.0))
                            .clamp(lo, hi);
                    }
                    let point = tool(&q).map_err(|e| CellError::invalid(p, e.to_string()))?;
                    if point.z >= min_height {
                        drawn = Some((q, point));
                        break;
                    }
                }
                let (q, point) = drawn.ok_or_else(|| CellError::invalid(format!("{p}.configurations[{ci}]"), format!("at level {level}: no waypoint with the tool above min_tool_height {min_height} m in {MAX_DRAWS} draws; lower it or change the configuration")))?;
                qs.push(q);
                points.push(point);
            }
            let fits = farthest_points(&points, fit);
            let setup = (group / per_setup) % placements.len();
            for (k, q) in qs.into_iter().enumerate() {
                let role = if fits.contains(&k) {
                    PointRole::Fit
                } else {
                    PointRole::Check
                };
                out.push(Waypoint {
                    point_id: format!("G{:02}.{:03}", group + 1, k + 1),
                    group,
                    setup,
                    role,
                    q,
                });
            }
        }
    }
    Ok(out)
}

/// Joint values of the arm's joints after the column, in their units, `names` for messages.
fn joints(
    values: &[crate::quantity::Quantity],
    path: &str,
    limits: &[([f64; 2], &str)],
    names: &[String],
) -> Result<Vec<f64>, CellError> {
    if values.len() != limits.len() {
        return Err(CellError::invalid(
            path,
            format!(
                "has {} values; it needs one per joint after the column: {}",
                values.len(),
                names.join(", ")
            ),
        ));
    }
    values
        .iter()
        .zip(limits)
        .enumerate()
        .map(|(i, (v, (_, unit)))| v.to_si(&format!("{path}[{i}]"), unit))
        .collect()
}

/// Indices of `n` points picked far apart: the one farthest from the centroid first, then each
/// time the one farthest from those picked.
pub fn farthest_points(points: &[Vector3<f64>], n: usize) -> Vec<usize> {
    if points.is_empty() {
        return Vec::new();
    }
    let centroid = points.iter().sum::<Vector3<f64>>() / points.len() as f64;
    let far = |d: &dyn Fn(&Vector3<f64>) -> f64| {
        (0..points.len())
            .max_by(|a, b| d(&points[*a]).total_cmp(&d(&points[*b])))
            .expect("not empty")
    };
    let mut picked = vec![far(&|p| (p - centroid).norm())];
    let mut nearest: Vec<f64> = points
        .iter()
        .map(|p| (p - points[picked[0]]).norm())
        .collect();
    while picked.len() < n.min(points.len()) {
        let next = (0..points.len())
            .max_by(|a, b| nearest[*a].total_cmp(&nearest[*b]))
            .expect("not empty");
        picked.push(next);
        for (k, p) in points.iter().enumerate() {
            nearest[k] = nearest[k].min((p - points[next]).norm());
        }
    }
    picked
}
