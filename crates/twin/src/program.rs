//! The measurement program: a volumetric-verification style visit of points (commanded axis
//! positions), with a dwell at each point, repeated in cycles over the shift.
//!
//! One cycle: move home → p₀, dwell, move → p₁, dwell, …, dwell at p_{N−1}, move → home.
//! Points are joint vectors (the family's, see [`crate::families`]; x y z for cartesian and
//! delta). Cartesian/delta moves are straight lines at constant path speed `feed_rate` (no
//! acceleration phase); five-axis and arm moves interpolate every joint linearly, the move
//! lasting as long as its slowest joint needs (`feed_rate` m/s for linear joints,
//! `rotary_rate` rad/s for rotary ones).
//! Cycle c starts at `start + c·max(cycle_interval, cycle length)`; between cycles and after the
//! last one the machine waits at home. The approach direction of an axis (for `backlash`) is
//! the sign of its last non-zero motion, +1 before any motion (homed from the negative side).

use metrocell_kinematics::serial::{IkSettings, IkTarget};
use nalgebra::{DVector, Isometry3, Translation3, UnitQuaternion, Vector3};

use crate::cell::{MachineGeometry, MachineKinematics};
use crate::cell_file::{GridSection, ProgramSection, VisitOrder};
use crate::error::CellError;
use crate::quantity::{vector3, Quantity};

/// One piece of a cycle (times relative to the cycle start).
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    pub start: f64,
    pub end: f64,
    pub from: DVector<f64>,
    pub to: DVector<f64>,
    /// `Some(point index)` for a dwell, `None` for a move.
    pub dwell_point: Option<usize>,
    /// Approach direction of each axis (±1) during this segment.
    pub approach: Vec<f64>,
}

/// Machine motion at one instant.
#[derive(Debug, Clone, PartialEq)]
pub struct MotionState {
    /// Commanded axis positions (m).
    pub q: DVector<f64>,
    /// Commanded axis velocity (m/s).
    pub velocity: DVector<f64>,
    /// Approach direction per axis (±1).
    pub approach: Vec<f64>,
    /// `Some(point index)` while dwelling at a program point.
    pub dwell_point: Option<usize>,
    /// Cycle number (0-based); `None` before the first and after the last cycle.
    pub cycle: Option<u32>,
}

/// A validated, time-indexed program.
#[derive(Debug, Clone, PartialEq)]
pub struct Program {
    pub points: Vec<DVector<f64>>,
    pub home: DVector<f64>,
    pub feed_rate: f64,
    pub dwell: f64,
    pub start: f64,
    pub cycles: Option<u32>,
    /// Start-to-start time of cycles (≥ the cycle length).
    pub cycle_period: f64,
    /// Segments of one cycle, relative to its start.
    pub segments: Vec<Segment>,
    /// Approach directions after a full cycle (= while waiting at home).
    pub idle_approach: Vec<f64>,
}

impl Program {
    pub fn from_section(s: &ProgramSection, m: &MachineGeometry) -> Result<Program, CellError> {
        Program::from_section_with(s, m, Vec::new())
    }

    /// As [`Program::from_section`], visiting `generated` joint targets (a stationing program's
    /// waypoints, [`crate::stationing_program`]) instead of `joints` or `poses`.
    ///
    /// The keys are checked against the family, the points made (joint targets and solved
    /// poses, a grid, or a list), checked against the joint limits with the home, and the cycle
    /// timed from the feed rates and the dwell.
    pub fn from_section_with(
        s: &ProgramSection,
        m: &MachineGeometry,
        generated: Vec<DVector<f64>>,
    ) -> Result<Program, CellError> {
        let jointed = m.is_jointed();
        check_family_keys(s, jointed)?;
        let mut points = generated;
        let limits = m.joint_limits();
        let home_joints = s
            .home_joints
            .as_ref()
            .map(|h| joint_vector(h, "program.home_joints", &limits))
            .transpose()?;
        if jointed {
            push_joint_targets(s, m, &limits, home_joints.as_ref(), &mut points)?;
        } else if let Some(g) = &s.grid {
            if !s.points.is_empty() {
                return Err(CellError::invalid(
                    "program",
                    "give either `grid` or `points`, not both",
                ));
            }
            points.extend(grid_points(g, s.order)?);
        } else {
            for (i, p) in s.points.iter().enumerate() {
                points.push(dv(vector3(p, &format!("program.points[{i}]"), "m")?));
            }
        }
        if points.is_empty() {
            return Err(CellError::invalid(
                "program",
                if jointed {
                    "needs a non-empty `joints` or `poses` list"
                } else {
                    "needs `grid` or a non-empty `points` list"
                },
            ));
        }
        if points.len() > 1_000_000 {
            return Err(CellError::invalid("program", "more than 1e6 points"));
        }
        let home = match (&s.home, home_joints) {
            (Some(h), _) => dv(vector3(h, "program.home", "m")?),
            (None, Some(h)) => h,
            (None, None) => points[0].clone(),
        };
        check_within_limits(&points, &home, m, &limits)?;
        let feed_rate = s.feed_rate.positive("program.feed_rate", "m/s")?;
        let rotary_rate = s
            .rotary_rate
            .as_ref()
            .map(|q| q.positive("program.rotary_rate", "rad/s"))
            .transpose()?
            .unwrap_or(30f64.to_radians());
        // Per joint speed for jointed families; None = Euclidean path speed (cartesian, delta).
        let speeds: Option<Vec<f64>> = jointed.then(|| {
            limits
                .iter()
                .map(|(_, u)| if *u == "rad" { rotary_rate } else { feed_rate })
                .collect()
        });
        let dwell = s.dwell.positive("program.dwell", "s")?;
        let start = s
            .start
            .as_ref()
            .map(|q| q.non_negative("program.start", "s"))
            .transpose()?
            .unwrap_or(0.0);
        let (segments, idle_approach) =
            build_cycle(&points, &home, feed_rate, speeds.as_deref(), dwell);
        let length = segments.last().map(|s| s.end).unwrap_or(0.0);
        let interval = s
            .cycle_interval
            .as_ref()
            .map(|q| q.positive("program.cycle_interval", "s"))
            .transpose()?
            .unwrap_or(length);
        Ok(Program {
            points,
            home,
            feed_rate,
            dwell,
            start,
            cycles: s.cycles,
            cycle_period: interval.max(length),
            segments,
            idle_approach,
        })
    }

    /// Length of one cycle (s).
    pub fn cycle_length(&self) -> f64 {
        self.segments.last().map(|s| s.end).unwrap_or(0.0)
    }

    /// Start time of cycle `c`, or `None` if the program has fewer cycles.
    pub fn cycle_start(&self, c: u32) -> Option<f64> {
        match self.cycles {
            Some(n) if c >= n => None,
            _ => Some(self.start + c as f64 * self.cycle_period),
        }
    }

    /// Motion at time t (s from the start of the simulation).
    pub fn state_at(&self, t: f64) -> MotionState {
        let n = self.home.len();
        let idle = |approach: Vec<f64>| MotionState {
            q: self.home.clone(),
            velocity: DVector::zeros(n),
            approach,
            dwell_point: None,
            cycle: None,
        };
        if t < self.start {
            return idle(vec![1.0; n]);
        }
        let c = ((t - self.start) / self.cycle_period).floor() as u64;
        if let Some(n) = self.cycles {
            if c >= n as u64 {
                return idle(self.idle_approach.clone());
            }
        }
        let c = c.min(u32::MAX as u64) as u32;
        let tc = t - self.start - c as f64 * self.cycle_period;
        if tc >= self.cycle_length() {
            return idle(self.idle_approach.clone());
        }
        let i = self
            .segments
            .partition_point(|s| s.end <= tc)
            .min(self.segments.len() - 1);
        let s = &self.segments[i];
        let dur = s.end - s.start;
        let (q, velocity) = if s.dwell_point.is_some() || dur <= 0.0 {
            (s.to.clone(), DVector::zeros(n))
        } else {
            let f = ((tc - s.start) / dur).clamp(0.0, 1.0);
            (&s.from + (&s.to - &s.from) * f, (&s.to - &s.from) / dur)
        };
        MotionState {
            q,
            velocity,
            approach: s.approach.clone(),
            dwell_point: s.dwell_point,
            cycle: Some(c),
        }
    }
}

fn build_cycle(
    points: &[DVector<f64>],
    home: &DVector<f64>,
    feed: f64,
    speeds: Option<&[f64]>,
    dwell: f64,
) -> (Vec<Segment>, Vec<f64>) {
    // Two passes: the second starts with the approach directions the first ended with (the
    // previous cycle's return home), so every cycle is identical.
    let mut approach = vec![1.0; home.len()];
    let mut segs = Vec::new();
    for _pass in 0..2 {
        segs.clear();
        let mut t = 0.0;
        let mut at = home.clone();
        let targets = points
            .iter()
            .enumerate()
            .map(|(i, p)| (p.clone(), Some(i)))
            .chain(std::iter::once((home.clone(), None)));
        for (p, idx) in targets {
            let d = &p - &at;
            for k in 0..d.len() {
                if d[k] != 0.0 {
                    approach[k] = d[k].signum();
                }
            }
            let dur = match speeds {
                None => d.norm() / feed,
                Some(v) => d
                    .iter()
                    .zip(v)
                    .map(|(x, s)| x.abs() / s)
                    .fold(0.0, f64::max),
            };
            if dur > 0.0 {
                segs.push(Segment {
                    start: t,
                    end: t + dur,
                    from: at.clone(),
                    to: p.clone(),
                    dwell_point: None,
                    approach: approach.clone(),
                });
                t += dur;
            }
            if let Some(i) = idx {
                segs.push(Segment {
                    start: t,
                    end: t + dwell,
                    from: p.clone(),
                    to: p.clone(),
                    dwell_point: Some(i),
                    approach: approach.clone(),
                });
                t += dwell;
            }
            at = p;
        }
    }
    (segs, approach)
}

/// Err naming the key when the program section gives keys of another family (a jointed family
/// takes `joints` or `poses` and `home_joints`; cartesian and delta `grid` or `points` and
/// `home`), or a stationing program with its own waypoints.
fn check_family_keys(s: &ProgramSection, jointed: bool) -> Result<(), CellError> {
    if s.stationing.is_some() && (!s.joints.is_empty() || !s.poses.is_empty()) {
        return Err(CellError::invalid(
            "program.stationing",
            "generates the program's waypoints; give it without `joints` or `poses`",
        ));
    }
    if jointed {
        if s.grid.is_some() || !s.points.is_empty() || s.home.is_some() {
            let key = if s.grid.is_some() {
                "grid"
            } else if !s.points.is_empty() {
                "points"
            } else {
                "home"
            };
            return Err(CellError::invalid(format!("program.{key}"), "is for family: cartesian and delta; a five_axis or serial_arm program takes `joints` (joint targets) or `poses` (tool poses), and `home_joints`"));
        }
    } else {
        for (key, given) in [
            ("joints", !s.joints.is_empty()),
            ("poses", !s.poses.is_empty()),
            ("home_joints", s.home_joints.is_some()),
            ("rotary_rate", s.rotary_rate.is_some()),
        ] {
            if given {
                return Err(CellError::invalid(format!("program.{key}"), "is for family: five_axis and serial_arm; a cartesian or delta program takes `grid` or `points` (x, y, z) and `home`"));
            }
        }
    }
    Ok(())
}

/// A jointed family's points: the `joints` targets, or the `poses` solved in turn (each from the
/// previous solution, the first from the home joints).
fn push_joint_targets(
    s: &ProgramSection,
    m: &MachineGeometry,
    limits: &[([f64; 2], &'static str)],
    home_joints: Option<&DVector<f64>>,
    points: &mut Vec<DVector<f64>>,
) -> Result<(), CellError> {
    if !s.joints.is_empty() && !s.poses.is_empty() {
        return Err(CellError::invalid(
            "program",
            "give either `joints` or `poses`, not both",
        ));
    }
    for (i, j) in s.joints.iter().enumerate() {
        points.push(joint_vector(j, &format!("program.joints[{i}]"), limits)?);
    }
    let mut previous = home_joints.cloned();
    for (i, p) in s.poses.iter().enumerate() {
        let q = solve_pose(p, &format!("program.poses[{i}]"), m, previous.as_ref())?;
        previous = Some(q.clone());
        points.push(q);
    }
    Ok(())
}

/// The points of a grid: z outermost, then y, x innermost; serpentine reverses x on odd rows and
/// y on odd layers.
fn grid_points(g: &GridSection, order: VisitOrder) -> Result<Vec<DVector<f64>>, CellError> {
    let mut axes = Vec::new();
    for (name, a) in [("x", &g.x), ("y", &g.y), ("z", &g.z)] {
        let p = format!("program.grid.{name}");
        let from = a.from.to_si(&format!("{p}.from"), "m")?;
        let to = a.to.to_si(&format!("{p}.to"), "m")?;
        if a.count == 0 || a.count > 10_000 {
            return Err(CellError::OutOfRange {
                path: format!("{p}.count"),
                value: a.count as f64,
                reason: "must be in 1..=10000".into(),
            });
        }
        let n = a.count as usize;
        axes.push(
            (0..n)
                .map(|i| {
                    if n == 1 {
                        from
                    } else {
                        from + (to - from) * i as f64 / (n - 1) as f64
                    }
                })
                .collect::<Vec<f64>>(),
        );
    }
    let mut points = Vec::new();
    let mut row = 0usize;
    for (iz, z) in axes[2].iter().enumerate() {
        let ys: Vec<f64> = if order == VisitOrder::Serpentine && iz % 2 == 1 {
            axes[1].iter().rev().copied().collect()
        } else {
            axes[1].clone()
        };
        for y in ys {
            let xs: Vec<f64> = if order == VisitOrder::Serpentine && row % 2 == 1 {
                axes[0].iter().rev().copied().collect()
            } else {
                axes[0].clone()
            };
            for x in xs {
                points.push(DVector::from_vec(vec![x, y, *z]));
            }
            row += 1;
        }
    }
    Ok(points)
}

/// Err naming the point (or the home), the joint and the limit's key when a point is outside
/// the machine's joint limits.
fn check_within_limits(
    points: &[DVector<f64>],
    home: &DVector<f64>,
    m: &MachineGeometry,
    limits: &[([f64; 2], &'static str)],
) -> Result<(), CellError> {
    let names = m.joint_names();
    for (i, p) in points.iter().chain(std::iter::once(home)).enumerate() {
        let what = if i == points.len() {
            "program.home".to_string()
        } else {
            format!("program point {i}")
        };
        for (k, name) in names.iter().enumerate() {
            let ([lo, hi], unit) = limits[k];
            if p[k] < lo - 1e-12 || p[k] > hi + 1e-12 {
                let key = match &m.kinematics {
                    MachineKinematics::SerialArm(_) => {
                        format!("machine.serial_arm.joint_limits[{k}]")
                    }
                    MachineKinematics::FiveAxis(_) if k == 3 => "machine.five_axis.b_limits".into(),
                    MachineKinematics::FiveAxis(_) if k == 4 => "machine.five_axis.c_limits".into(),
                    _ => format!("machine.travel.{name}"),
                };
                return Err(CellError::OutOfRange {
                    path: what.clone(),
                    value: p[k],
                    reason: format!("{name} outside {key} = [{lo}, {hi}] {unit}"),
                });
            }
        }
    }
    Ok(())
}

fn dv(v: Vector3<f64>) -> DVector<f64> {
    DVector::from_column_slice(v.as_slice())
}

/// A joint vector from the file, each value in its joint's unit.
fn joint_vector(
    v: &[Quantity],
    path: &str,
    limits: &[([f64; 2], &'static str)],
) -> Result<DVector<f64>, CellError> {
    if v.len() != limits.len() {
        return Err(CellError::invalid(
            path,
            format!(
                "has {} values; the machine has {} joints",
                v.len(),
                limits.len()
            ),
        ));
    }
    let mut out = DVector::zeros(v.len());
    for (k, (q, (_, unit))) in v.iter().zip(limits).enumerate() {
        out[k] = q.to_si(&format!("{path}[{k}]"), unit)?;
    }
    Ok(out)
}

/// Joint vector of a tool-pose target: five-axis closed-form inverse (the branch within the
/// limits nearest the previous target), arm damped-least-squares IK from the previous target.
fn solve_pose(
    p: &crate::cell_file::PoseTargetSection,
    path: &str,
    m: &MachineGeometry,
    previous: Option<&DVector<f64>>,
) -> Result<DVector<f64>, CellError> {
    let position = vector3(&p.position, &format!("{path}.position"), "m")?;
    match &m.kinematics {
        MachineKinematics::FiveAxis(f) => {
            if p.euler_xyz.is_some() {
                return Err(CellError::invalid(format!("{path}.euler_xyz"), "is for family: serial_arm; a five_axis pose takes `position` (tool tip) and `axis` (tool axis, workpiece frame)"));
            }
            let axis = p
                .axis
                .map(|a| Vector3::new(a[0], a[1], a[2]))
                .unwrap_or_else(Vector3::z);
            let c_hint = previous.map(|q| q[4]).unwrap_or(0.0);
            let pose = metrocell_kinematics::five_axis::ToolPose {
                tip: position,
                axis,
            };
            let sols = f
                .geometry
                .inverse(&pose, c_hint)
                .map_err(|e| CellError::invalid(path, format!("no five-axis solution: {e}")))?;
            let limits = m.joint_limits();
            let q_of = |s: &metrocell_kinematics::five_axis::FiveAxisSolution| {
                DVector::from_vec(vec![
                    s.joints.d2,
                    s.joints.d1,
                    -s.joints.d3,
                    s.joints.b,
                    s.joints.c,
                ])
            };
            let inside = |q: &DVector<f64>| {
                q.iter()
                    .zip(&limits)
                    .all(|(v, ([lo, hi], _))| *v >= lo - 1e-12 && *v <= hi + 1e-12)
            };
            let dist = |q: &DVector<f64>| previous.map(|pq| (q - pq).norm()).unwrap_or(0.0);
            sols.iter()
                .map(q_of)
                .filter(|q| inside(q))
                .min_by(|a, b| dist(a).total_cmp(&dist(b)))
                .ok_or_else(|| {
                    CellError::invalid(
                        path,
                        format!(
                            "every five-axis solution ({}) is outside the axis limits",
                            sols.iter()
                                .map(|s| format!("{:?}", q_of(s).as_slice()))
                                .collect::<Vec<_>>()
                                .join(", ")
                        ),
                    )
                })
        }
        MachineKinematics::SerialArm(arm) => {
            if p.axis.is_some() {
                return Err(CellError::invalid(format!("{path}.axis"), "is for family: five_axis; a serial_arm pose takes `position` and optional `euler_xyz`"));
            }
            let target = match &p.euler_xyz {
                None => IkTarget::Position(position),
                Some(e) => {
                    let e = vector3(e, &format!("{path}.euler_xyz"), "rad")?;
                    let r = metrocell_physics::instrument::tracker_pose::euler_xyz(e.x, e.y, e.z);
                    let r = UnitQuaternion::from_rotation_matrix(
                        &nalgebra::Rotation3::from_matrix_unchecked(r),
                    );
                    IkTarget::Pose(Isometry3::from_parts(Translation3::from(position), r))
                }
            };
            let q0 = previous
                .cloned()
                .unwrap_or_else(|| DVector::zeros(arm.chain.dof()));
            let settings = IkSettings {
                max_iterations: 2000,
                position_tolerance: 1e-10,
                orientation_tolerance: 1e-10,
                ..IkSettings::default()
            };
            let rep = arm
                .chain
                .inverse(&target, q0.as_slice(), &settings)
                .map_err(|e| CellError::invalid(path, format!("inverse kinematics failed: {e}")))?;
            if !rep.converged {
                return Err(CellError::invalid(
                    path,
                    format!(
                        "inverse kinematics did not converge after {} iterations (position error {:.3} mm, orientation error {:.3} mrad): the pose is probably out of reach; move it or give joint targets in program.joints",
                        rep.iterations,
                        rep.position_error * 1e3,
                        rep.orientation_error * 1e3
                    ),
                ));
            }
            Ok(rep.q)
        }
        _ => Err(CellError::invalid(
            path,
            "poses are for family: five_axis and serial_arm",
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn program(points: Vec<DVector<f64>>) -> Program {
        let home = points[0].clone();
        let (segments, idle_approach) = build_cycle(&points, &home, 0.1, None, 2.0);
        Program {
            points,
            home,
            feed_rate: 0.1,
            dwell: 2.0,
            start: 10.0,
            cycles: Some(2),
            cycle_period: 100.0,
            segments,
            idle_approach,
        }
    }

    #[test]
    fn jointed_moves_last_as_long_as_the_slowest_joint() {
        // one linear joint (0.1 m/s) and one rotary joint (0.5 rad/s): 0.1 m takes 1 s, 1 rad 2 s
        let points = vec![
            DVector::from_row_slice(&[0.0, 0.0]),
            DVector::from_row_slice(&[0.1, -1.0]),
        ];
        let (segs, approach) = build_cycle(&points, &points[0], 0.1, Some(&[0.1, 0.5]), 3.0);
        let moves: Vec<&Segment> = segs.iter().filter(|s| s.dwell_point.is_none()).collect();
        assert_eq!(moves.len(), 2);
        assert!((moves[0].end - moves[0].start - 2.0).abs() < 1e-12);
        assert_eq!(moves[0].approach, [1.0, -1.0]);
        assert_eq!(
            approach,
            [-1.0, 1.0],
            "the return home reverses both joints"
        );
    }

    #[test]
    fn timeline_moves_dwells_and_approach_directions() {
        let p = program(vec![
            DVector::from_row_slice(&[0.0, 0.0, 0.0]),
            DVector::from_row_slice(&[0.2, 0.0, 0.0]),
            DVector::from_row_slice(&[0.2, 0.1, 0.0]),
        ]);
        // cycle: dwell p0 [0,2), move 2 s [2,4), dwell p1 [4,6), move 1 s [6,7), dwell p2 [7,9), move home √5 s
        assert!((p.cycle_length() - (9.0 + 0.05f64.sqrt() / 0.1)).abs() < 1e-12);
        let s = p.state_at(10.0 + 3.0);
        assert!(
            (&s.q - DVector::from_row_slice(&[0.1, 0.0, 0.0])).norm() < 1e-12
                && s.dwell_point.is_none()
        );
        assert!((s.velocity[0] - 0.1).abs() < 1e-12);
        assert_eq!(p.state_at(10.0 + 5.0).dwell_point, Some(1));
        assert_eq!(p.state_at(10.0 + 5.0).approach[0], 1.0);
        // the return home moves x negative, so the next cycle starts with x approached from +
        assert_eq!(p.state_at(110.0 + 1.0).approach[0], -1.0);
        assert_eq!(p.state_at(110.0 + 1.0).cycle, Some(1));
        // before the start and after the last cycle: idle at home
        assert_eq!(p.state_at(5.0).cycle, None);
        assert_eq!(p.state_at(250.0).cycle, None);
        assert_eq!(p.state_at(250.0).q, p.home);
        assert_eq!(p.cycle_start(2), None);
    }
}
