//! A **stationing recording** of a serial arm (issue 27): a levelled instrument (a total station
//! and a 360° prism on the tool) measures the tool point from several setups while the arm
//! visits the waypoints of a stationing program ([`crate::stationing_program`]), two or more
//! accelerometers and the thermocouples read at every waypoint; the ground under the base is
//! tilted per recording. What is validated here, and the truth it stands for:
//!
//! * `environment.ground_tilt: {roll, pitch}` — the base turned from level by
//!   R_tilt = Rx(roll)·Ry(pitch) (a point P of the base is R_tilt·P in the levelled frame), so
//!   gravity in the base is g_B = R_tiltᵀ·(0, 0, −g), g = 9.80665 m/s² ([`Signals::gravity`] of
//!   every waypoint), and the truth's `base_tilt` is (roll, pitch): the catalog term's own
//!   convention (crates/physics `instrument::base_tilt`), which a fitted model recovers.
//! * `sensors.tracker` with `setups` and `point_noise` — one `tracker_pose[<setup>]` per
//!   placement: its origin `translation` and `yaw` (δ) in the levelled frame as written, its
//!   residual tilt (α, β) drawn per recording from N(0, `tilt_sigma`) (default 50 µrad) with the
//!   simulation's seed; each reading is the true tool point in that frame plus N(0, σ²) on each
//!   axis, σ = `point_noise`, stated as the point's covariance. The instrument's frame is
//!   [`STATION_FRAME`].
//! * `sensors.accelerometers` — each sensor's frame is its link's, turned by its `misalignment`
//!   (a rotation vector, the link's axes); at rest it reads the specific force
//!   f = R_sᵀ·(−g_B) + bias + N(0, `noise`²) per axis, R_s the true sensor frame in the base. A
//!   sensor on a link fixed to the arm's root (the base IMU) has the link's constant rotation;
//!   one behind prismatic joints only (an IMU on a lifting column's top) too: the column's
//!   extension moves it without turning it. Modelled: its rotation at the nominal column —
//!   **not** the column's bending (a tilt of tens of µrad, below the sensor's noise over one
//!   reading) nor the arm's motion (the readings are taken at rest). A sensor behind a revolute
//!   joint is refused, naming the joint.
//!
//! The samples themselves come from [`crate::stationing_run`].

use std::path::Path;

use metrocell_kinematics::transform::{rx, ry};
use metrocell_kinematics::urdf_link_placement::{link_rotation, read_urdf_file, LinkRotation};
use metrocell_model::{InstrumentPose, MachineGeometry, MachineKinematics};
use metrocell_physics::config::ConfigValue;
use metrocell_physics::gravity::gravity_in_tilted_base;
use metrocell_physics::model::TermModel;
use metrocell_physics::{configure, TermConfig};
use nalgebra::{Matrix3, Rotation3, Vector3};

use crate::cell_file::{AccelerometerSection, CellFile, TrackerSection};
use crate::cell_model::DEFAULT_TILT_SIGMA;
use crate::error::CellError;
use crate::noise::{stream, NoiseStream};
use crate::quantity::vector3;
use crate::stationing_program::{plan, Waypoint};

/// `header.frame_id` of the instrument's points (with `@<setup>` appended, as `bag import`
/// writes a recording's `setup` column).
pub const STATION_FRAME: &str = "total_station";

/// One placement of the instrument: origin and yaw in the base's levelled frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Placement {
    pub name: String,
    pub translation: Vector3<f64>,
    pub yaw: f64,
}

/// An accelerometer as simulated (module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct AccelerometerSpec {
    pub name: String,
    pub link: String,
    /// The link's rotation in the arm's base frame.
    pub base_from_link: Matrix3<f64>,
    /// The true sensor frame in the link's (the mounting misalignment).
    pub misalignment: Matrix3<f64>,
    pub bias: Vector3<f64>,
    pub noise: f64,
}

impl AccelerometerSpec {
    /// The noise-free reading at rest under gravity `g` (base frame).
    pub fn reading(&self, g: &Vector3<f64>) -> Vector3<f64> {
        (self.base_from_link * self.misalignment).transpose() * -g + self.bias
    }
}

/// A validated stationing recording (module doc): the instrument, the accelerometers, the
/// ground's tilt and the waypoints.
#[derive(Debug, Clone, PartialEq)]
pub struct Stationing {
    pub placements: Vec<Placement>,
    pub tilt_sigma: f64,
    pub point_noise: f64,
    /// (roll, pitch) of the ground (rad); `metrocell sim --ground-tilt` sets it.
    pub ground_tilt: [f64; 2],
    pub accelerometers: Vec<AccelerometerSpec>,
    pub waypoints: Vec<Waypoint>,
}

impl Stationing {
    /// The stationing recording of a cell file whose program is `program.stationing` (None
    /// otherwise); a file that gives the instrument's `setups`, its `point_noise` or the ground's
    /// tilt without one is refused, naming the key.
    pub fn from_file(
        f: &CellFile,
        machine: &MachineGeometry,
        base_dir: &Path,
    ) -> Result<Option<Stationing>, CellError> {
        let section = f.program.as_ref().and_then(|p| p.stationing.as_ref());
        let tracker = f.sensors.tracker.as_ref();
        let Some(section) = section else {
            let stray = [
                (
                    "sensors.tracker.setups",
                    tracker.is_some_and(|t| !t.setups.is_empty()),
                ),
                (
                    "sensors.tracker.point_noise",
                    tracker.is_some_and(|t| t.point_noise.is_some()),
                ),
                (
                    "environment.ground_tilt",
                    f.environment
                        .as_ref()
                        .is_some_and(|e| e.ground_tilt.is_some()),
                ),
            ];
            return match stray.iter().find(|(_, given)| *given) {
                Some((key, _)) => Err(CellError::invalid(
                    *key,
                    "is simulated with a stationing program (`program.stationing`) only",
                )),
                None => Ok(None),
            };
        };
        let tracker = tracker.ok_or_else(|| CellError::invalid("sensors.tracker", "is required by `program.stationing`: the levelled instrument, {levelled: true, tilt_sigma, point_noise, setups: [{name, translation, yaw}]}"))?;
        let (placements, tilt_sigma, point_noise) = instrument(tracker)?;
        let ground_tilt = match f.environment.as_ref().and_then(|e| e.ground_tilt.as_ref()) {
            Some(g) => {
                let angle = |q: &Option<crate::quantity::Quantity>, key: &str| {
                    q.as_ref()
                        .map(|q| q.to_si(&format!("environment.ground_tilt.{key}"), "rad"))
                        .transpose()
                        .map(|v| v.unwrap_or(0.0))
                };
                [angle(&g.roll, "roll")?, angle(&g.pitch, "pitch")?]
            }
            None => [0.0, 0.0],
        };
        check_tilt(ground_tilt, "environment.ground_tilt")?;
        let accelerometers = accelerometers(&f.sensors.accelerometers, f, base_dir)?;
        let waypoints = plan(section, machine, &placements)?;
        Ok(Some(Stationing {
            placements,
            tilt_sigma,
            point_noise,
            ground_tilt,
            accelerometers,
            waypoints,
        }))
    }

    /// R_tilt = Rx(roll)·Ry(pitch): the base's points in the levelled frame.
    pub fn levelling(&self) -> Matrix3<f64> {
        rx(self.ground_tilt[0]) * ry(self.ground_tilt[1])
    }

    /// Gravity in the base frame, g_B = R_tiltᵀ·(0, 0, −g) (m/s²).
    pub fn gravity(&self) -> Vector3<f64> {
        gravity_in_tilted_base(self.ground_tilt[0], self.ground_tilt[1])
    }

    /// Each placement's true pose in the levelled frame: its translation and yaw, and a residual
    /// tilt drawn from N(0, tilt_sigma²) per axis with `seed` (the same for every run of a seed).
    pub fn true_poses(&self, seed: u64) -> Vec<InstrumentPose> {
        let mut rng = NoiseStream::new(seed, stream::SETUP_TILT);
        self.placements
            .iter()
            .map(|p| {
                InstrumentPose::from_euler_xyz(
                    p.translation,
                    [
                        self.tilt_sigma * rng.normal(),
                        self.tilt_sigma * rng.normal(),
                        p.yaw,
                    ],
                )
            })
            .collect()
    }

    /// The truth's instrument terms for `seed`: `tracker_pose[<setup>]` per placement
    /// ([`Self::true_poses`]), then `base_tilt` at the ground's tilt.
    pub fn instrument_terms(&self, seed: u64) -> Result<TermModel, CellError> {
        let mut m = TermModel::default();
        let path = "sensors.tracker.setups";
        let push = |m: &mut TermModel, c: TermConfig| -> Result<(), CellError> {
            m.push(configure(&c).map_err(|e| CellError::term(path, e))?)
                .map_err(|e| CellError::term(path, e))
        };
        let number = |pairs: &[(&str, f64)]| {
            pairs
                .iter()
                .map(|(n, v)| (n.to_string(), ConfigValue::Number(*v)))
                .collect()
        };
        for (p, pose) in self.placements.iter().zip(self.true_poses(seed)) {
            let [tx, ty, tz, alpha, beta, delta] = pose.term_params();
            let options = [("setup".to_string(), ConfigValue::Text(p.name.clone()))]
                .into_iter()
                .collect();
            push(
                &mut m,
                TermConfig {
                    id: "tracker_pose".into(),
                    options,
                    params: number(&[
                        ("tx", tx),
                        ("ty", ty),
                        ("tz", tz),
                        ("alpha", alpha),
                        ("beta", beta),
                        ("delta", delta),
                    ]),
                    use_defaults: false,
                },
            )?;
        }
        push(
            &mut m,
            TermConfig {
                id: "base_tilt".into(),
                options: Default::default(),
                params: number(&[
                    ("roll", self.ground_tilt[0]),
                    ("pitch", self.ground_tilt[1]),
                ]),
                use_defaults: false,
            },
        )?;
        Ok(m)
    }
}

/// A ground tilt beyond 0.2 rad (11°) is not a robot standing on something: a unit mistake.
pub fn check_tilt(tilt: [f64; 2], key: &str) -> Result<(), CellError> {
    for (v, name) in tilt.iter().zip(["roll", "pitch"]) {
        if !(v.abs() <= 0.2) {
            return Err(CellError::OutOfRange {
                path: format!("{key}.{name}"),
                value: *v,
                reason: "a ground tilt is within ±0.2 rad (give a unit: `12 mrad`, `0.5 deg`)"
                    .into(),
            });
        }
    }
    Ok(())
}

/// The stationing instrument: placements, tilt σ and point noise.
fn instrument(t: &TrackerSection) -> Result<(Vec<Placement>, f64, f64), CellError> {
    let p = "sensors.tracker";
    if !t.levelled {
        return Err(CellError::invalid(format!("{p}.levelled"), "must be true for a stationing program: the instrument levels itself (a total station's compensator), each setup a yaw and a translation"));
    }
    if t.pose.is_some()
        || t.rate.is_some()
        || t.range_noise.is_some()
        || t.angular_noise.is_some()
        || t.warmup.is_some()
        || t.station.is_some()
        || !t.turbulence.is_empty()
        || t.beam_breaks.is_some()
    {
        return Err(CellError::invalid(p, "of a stationing program takes levelled, tilt_sigma, point_noise and setups (the tracker's pose, rate, noise model, warm-up, station, turbulence and beam breaks are for a tracker sampling a running program)"));
    }
    let tilt_sigma = match &t.tilt_sigma {
        Some(q) => q.positive(&format!("{p}.tilt_sigma"), "rad")?,
        None => DEFAULT_TILT_SIGMA,
    };
    let point_noise = t.point_noise.as_ref().ok_or_else(|| CellError::invalid(format!("{p}.point_noise"), "is required by a stationing program: σ of the instrument's point on each axis, e.g. 0.75 mm"))?.non_negative(&format!("{p}.point_noise"), "m")?;
    if t.setups.is_empty() {
        return Err(CellError::invalid(
            format!("{p}.setups"),
            "needs at least one placement {name, translation: [x, y, z], yaw}",
        ));
    }
    let mut placements: Vec<Placement> = Vec::new();
    for (i, s) in t.setups.iter().enumerate() {
        let sp = format!("{p}.setups[{i}]");
        let valid = !s.name.is_empty()
            && s.name
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || c == '_' || c == '-');
        if !valid || placements.iter().any(|o| o.name == s.name) {
            return Err(CellError::invalid(format!("{sp}.name"), format!("`{}` must be a name no other setup has, of letters, digits, `_` or `-` (it is the import layout's `setup`)", s.name)));
        }
        let yaw = s
            .yaw
            .as_ref()
            .map(|q| q.to_si(&format!("{sp}.yaw"), "rad"))
            .transpose()?
            .unwrap_or(0.0);
        placements.push(Placement {
            name: s.name.clone(),
            translation: vector3(&s.translation, &format!("{sp}.translation"), "m")?,
            yaw,
        });
    }
    Ok((placements, tilt_sigma, point_noise))
}

/// The accelerometers as simulated: each link's rotation in the base frame (fixed to the root,
/// or behind prismatic joints only), misalignment, bias and noise.
fn accelerometers(
    sensors: &[AccelerometerSection],
    f: &CellFile,
    base_dir: &Path,
) -> Result<Vec<AccelerometerSpec>, CellError> {
    if sensors.is_empty() {
        return Ok(Vec::new());
    }
    // the section was validated with the machine: an arm from a URDF
    let arm = f
        .machine
        .serial_arm
        .as_ref()
        .ok_or_else(|| CellError::invalid("sensors.accelerometers", "needs a serial arm"))?;
    let urdf = arm
        .urdf
        .as_ref()
        .ok_or_else(|| CellError::invalid("sensors.accelerometers", "needs an arm from a URDF"))?;
    let path = base_dir.join(&urdf.path);
    let robot = read_urdf_file(&path)
        .map_err(|e| CellError::invalid("machine.serial_arm.urdf", e.to_string()))?;
    let base = match &arm.base {
        Some(b) => {
            metrocell_model_file::machine_section::pose(b, "machine.serial_arm.base")?.rotation
        }
        None => Matrix3::identity(),
    };
    let mut out = Vec::new();
    for (i, a) in sensors.iter().enumerate() {
        let p = format!("sensors.accelerometers[{i}]");
        let r = match link_rotation(&robot, &urdf.root_link, &a.link).map_err(|e| CellError::invalid(format!("{p}.link"), e.to_string()))? {
            LinkRotation::Fixed(r) => r,
            LinkRotation::Turns { joint } => {
                return Err(CellError::invalid(format!("{p}.link"), format!("`{}` is turned by joint `{joint}`: the twin simulates accelerometers fixed to the base or behind prismatic joints only (a column's top)", a.link)))
            }
        };
        let misalignment = match &a.misalignment {
            Some(v) => {
                Rotation3::new(vector3(v, &format!("{p}.misalignment"), "rad")?).into_inner()
            }
            None => Matrix3::identity(),
        };
        let bias = a
            .bias
            .as_ref()
            .map(|v| vector3(v, &format!("{p}.bias"), "m/s^2"))
            .transpose()?
            .unwrap_or_else(Vector3::zeros);
        let noise = a
            .noise
            .as_ref()
            .map(|q| q.non_negative(&format!("{p}.noise"), "m/s^2"))
            .transpose()?
            .unwrap_or(0.0);
        out.push(AccelerometerSpec {
            name: a.name.clone(),
            link: a.link.clone(),
            base_from_link: base * r,
            misalignment,
            bias,
            noise,
        });
    }
    Ok(out)
}

/// The arm of a stationing program (its family checked by the plan).
pub(crate) fn arm_of(machine: &MachineGeometry) -> Option<&metrocell_model::SerialArm> {
    match &machine.kinematics {
        MachineKinematics::SerialArm(a) => Some(a),
        _ => None,
    }
}
