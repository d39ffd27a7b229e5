//! Where to put the tracker (seed 001, P5: "the position where the LT must be placed so that
//! error and uncertainty are minimized"): candidate stations, which of them see every planned
//! point, and the standard uncertainty of the identified error map each would give.
//!
//! Visibility: the range to each point within the tracker's limits (P5: 0.5–15 m), and the beam's
//! incidence on the reflector within its acceptance half-angle (P5 evaluates incidence angles
//! up to ±15°). The reflector is aimed at the station from the mesh's centre, as an operator
//! sets an SMR in its nest, unless a fixed facing is given.
//!
//! Uncertainty: the identification's covariance (JᵀWJ)⁻¹ at noise-free readings of the plan
//! from that station, W from the tracker's noise model (range a + b·ρ, angles σ), the tracker's
//! pose identified with the errors as the model declares; the error map's σ at each point is
//! √diag(J_e·C·J_eᵀ) (`error_map_sd`). A station is scored by the largest 3-D σ over the mesh.
//! Stations are ranked by what they leave unidentified first ([`ranked`]).
//! This is the linearised uncertainty that `metrocell verify report`'s Monte Carlo samples; it
//! ranks stations in milliseconds each.
//!
//! Station pose convention: the tracker stands upright (its z up, the model's `tracker_pose`
//! with α = β = 0) and its x axis points at the mesh centre (yaw δ); positions in the frame the
//! model reports tool points in (the workpiece frame).

use metrocell_estimation::simulated_records::{records, Planned, TrackerNoise};
use metrocell_estimation::volumetric_monte_carlo::error_map_sd;
use metrocell_estimation::{fit, FitOptions};
use metrocell_model::{ForwardModel, ParameterSetup};
use metrocell_physics::Signals;
use nalgebra::{Rotation3, Vector3};

/// A place for the tracker: position (m) and yaw (rad) about z.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Station {
    pub position: Vector3<f64>,
    pub yaw: f64,
}

/// The tracker's and the reflector's limits.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SightLimits {
    /// m
    pub min_range: f64,
    /// m
    pub max_range: f64,
    /// Reflector acceptance half-angle (rad).
    pub acceptance: f64,
    /// Fixed reflector facing (unit vector in the workpiece frame); None: aimed at the station
    /// from the mesh centre.
    pub reflector_facing: Option<Vector3<f64>>,
}

/// Why a point cannot be measured from a station.
#[derive(Debug, Clone, PartialEq)]
pub enum Blocked {
    TooClose {
        point: usize,
        range: f64,
    },
    TooFar {
        point: usize,
        range: f64,
    },
    /// The beam meets the reflector at `angle` (rad) off its axis.
    OffReflector {
        point: usize,
        angle: f64,
    },
}

impl std::fmt::Display for Blocked {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Blocked::TooClose { point, range } => write!(
                f,
                "p{point} is {:.3} m away, closer than the tracker measures",
                range
            ),
            Blocked::TooFar { point, range } => write!(
                f,
                "p{point} is {:.3} m away, beyond the tracker's range",
                range
            ),
            Blocked::OffReflector { point, angle } => write!(
                f,
                "p{point} is seen {:.1}° off the reflector's axis, beyond its acceptance",
                angle.to_degrees()
            ),
        }
    }
}

/// A station judged.
#[derive(Debug, Clone, PartialEq)]
pub struct StationAssessment {
    pub station: Station,
    /// Points the station cannot measure, and why (empty: it sees all).
    pub blocked: Vec<Blocked>,
    /// Shortest and longest range (m).
    pub ranges: (f64, f64),
    /// Largest incidence on the reflector (rad).
    pub max_incidence: f64,
    /// Largest and mean 3-D standard uncertainty of the identified error map over the points
    /// (m); NaN when the station does not see every point (not evaluated).
    pub max_sd: f64,
    pub mean_sd: f64,
    /// Per point, the standard uncertainty of each component of the identified error (m).
    pub sd: Vec<Vector3<f64>>,
    /// Parameters the identification could not separate from this station (held).
    pub held: Vec<String>,
}

impl StationAssessment {
    pub fn sees_all(&self) -> bool {
        self.blocked.is_empty()
    }
}

/// The stations from best to worst: those that see every point first; among them those whose
/// readings leave fewest parameters unidentifiable (a station in the mesh's own plane, say,
/// cannot separate some errors from its height: holding them would make its stated σ look
/// small, not its verification good); then by the largest σ of the error map.
pub fn ranked(assessed: &[StationAssessment]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..assessed.len()).collect();
    order.sort_by(|&a, &b| {
        let (a, b) = (&assessed[a], &assessed[b]);
        (!a.sees_all())
            .cmp(&!b.sees_all())
            .then(a.held.len().cmp(&b.held.len()))
            .then(a.max_sd.total_cmp(&b.max_sd))
    });
    order
}

/// Stations on circles of `radii` (m) about `centre` at `heights` above it, `per_circle` of
/// them evenly in azimuth, each facing the centre.
pub fn candidate_ring(
    centre: Vector3<f64>,
    radii: &[f64],
    heights: &[f64],
    per_circle: usize,
) -> Vec<Station> {
    let mut out = vec![];
    for &r in radii {
        for &h in heights {
            for k in 0..per_circle {
                let a = std::f64::consts::TAU * k as f64 / per_circle as f64;
                let position = centre + Vector3::new(r * a.cos(), r * a.sin(), h);
                out.push(facing(position, centre));
            }
        }
    }
    out
}

/// A station at `position` turned to face `target` in azimuth.
pub fn facing(position: Vector3<f64>, target: Vector3<f64>) -> Station {
    let d = target - position;
    Station {
        position,
        yaw: d.y.atan2(d.x),
    }
}

/// The model's parameters with the tracker at `station`.
fn placed(model: &ForwardModel, at: &[f64], station: &Station) -> Result<Vec<f64>, String> {
    let names = model.param_names();
    let i = names.iter().position(|n| n == "tracker_pose.tx").ok_or(
        "the model has no tracker pose to place (declare sensors.tracker.pose in the model file)",
    )?;
    let mut p = at.to_vec();
    p[i..i + 3].copy_from_slice(station.position.as_slice());
    p[i + 3] = 0.0;
    p[i + 4] = 0.0;
    p[i + 5] = station.yaw;
    Ok(p)
}

/// The planned readings: the commanded points, at rest, approached in +, long after power-on —
/// with the model's tool, or (`targets`, each a reflector's offset from the model's tool, m) every
/// point with each target in turn, a pass per target.
pub fn planned(points: &[[f64; 3]], targets: &[Vector3<f64>]) -> Vec<Planned> {
    let shifts: Vec<Option<Vector3<f64>>> = if targets.is_empty() {
        vec![None]
    } else {
        targets.iter().map(|t| Some(*t)).collect()
    };
    shifts
        .iter()
        .flat_map(|shift| {
            points.iter().map(|p| Planned {
                q: p.to_vec(),
                approach: [1.0; 3],
                temperatures: vec![],
                time_on: 24.0 * 3600.0,
                tool_offset_shift: *shift,
            })
        })
        .collect()
}

/// Where the target is at each point in the model's frame (m): the nominal readings from a
/// tracker at the origin.
pub fn target_points(
    model: &ForwardModel,
    at: &[f64],
    points: &[[f64; 3]],
) -> Result<Vec<Vector3<f64>>, String> {
    let origin = Station {
        position: Vector3::zeros(),
        yaw: 0.0,
    };
    let p = placed(model, at, &origin)?;
    let noise = TrackerNoise {
        constant: 1e-6,
        per_metre: 0.0,
        angular: 1e-6,
    };
    Ok(records(model, &p, &planned(points, &[]), noise, None)
        .records
        .into_iter()
        .map(|r| r.measured)
        .collect())
}

/// Judge `station` for measuring `points` (commanded axis positions, m) with a tracker of
/// `noise` — with the model's tool, or each of `targets` (reflector offsets from the model's
/// tool, m; [`planned`]) — : visibility, then (if it sees all) the identified error map's
/// uncertainty with the model's free parameters linearised at `at`, for the model's tool.
#[allow(clippy::too_many_arguments)]
pub fn assess(
    model: &ForwardModel,
    setup: &ParameterSetup,
    at: &[f64],
    points: &[[f64; 3]],
    targets: &[Vector3<f64>],
    station: &Station,
    limits: &SightLimits,
    noise: TrackerNoise,
) -> Result<StationAssessment, String> {
    let p = placed(model, at, station)?;
    let plan = planned(points, targets);
    let data = records(model, &p, &plan, noise, None);
    let r = Rotation3::from_axis_angle(&Vector3::z_axis(), station.yaw);
    let world: Vec<Vector3<f64>> = data
        .records
        .iter()
        .map(|rec| station.position + r * rec.measured)
        .collect();
    let centre = world.iter().sum::<Vector3<f64>>() / world.len().max(1) as f64;
    let facing = limits
        .reflector_facing
        .unwrap_or_else(|| station.position - centre)
        .normalize();
    let mut blocked = vec![];
    let (mut near, mut far, mut worst) = (f64::INFINITY, 0.0f64, 0.0f64);
    for (k, w) in world.iter().enumerate() {
        // the point (a pass per target visits every point)
        let i = k % points.len().max(1);
        let to_tracker = station.position - w;
        let range = to_tracker.norm();
        let angle = to_tracker.angle(&facing);
        near = near.min(range);
        far = far.max(range);
        worst = worst.max(angle);
        if range < limits.min_range {
            blocked.push(Blocked::TooClose { point: i, range });
        } else if range > limits.max_range {
            blocked.push(Blocked::TooFar { point: i, range });
        } else if angle > limits.acceptance {
            blocked.push(Blocked::OffReflector { point: i, angle });
        }
    }
    let mut out = StationAssessment {
        station: *station,
        blocked,
        ranges: (near, far),
        max_incidence: worst,
        max_sd: f64::NAN,
        mean_sd: f64::NAN,
        sd: vec![],
        held: vec![],
    };
    if !out.sees_all() {
        return Ok(out);
    }
    // The fit registers the tracker from the readings, as the report's will (started at the
    // exact placement instead, it held different parameters and stated a near-singular map).
    let f = fit(model, setup, &data, None, &FitOptions::default()).map_err(|e| e.to_string())?;
    let q: Vec<Vec<f64>> = points.iter().map(|p| p.to_vec()).collect();
    let sd = error_map_sd(
        model,
        &f.x,
        f.solution.covariance_unscaled.as_ref(),
        &q,
        &Signals::default(),
    )
    .map_err(|e| e.to_string())?;
    let norms: Vec<f64> = sd.iter().map(|s| s.norm()).collect();
    out.max_sd = norms.iter().copied().fold(0.0, f64::max);
    out.mean_sd = norms.iter().sum::<f64>() / norms.len().max(1) as f64;
    out.sd = sd;
    out.held = f.held.iter().map(|h| h.name.clone()).collect();
    Ok(out)
}
