//! The validated cell: everything from the cell file in SI units, the physics terms configured
//! by the physics catalog, the thermal model as a physics [`ShiftThermalModel`], and the
//! measurement program. Built by [`Cell::from_yaml_str`] / [`Cell::from_path`]; fields are
//! public so tests and tools can adjust a loaded cell (e.g. zero the noise).

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use metrocell_camera_model::{CameraModel, Distortion};
use metrocell_kinematics::delta::DeltaGeometry;
use metrocell_model::{CameraGeometry, ForwardModel, KinematicTruth};
use metrocell_physics::config::ConfigValue;
use metrocell_physics::model::TermModel;
use metrocell_physics::thermal::shift_model::{
    AmbientCycle, DutySegment, HeatSource, SensorLocation, ShiftThermalModel, StructureNode,
    ThermalSensor,
};
use metrocell_physics::{configure, ConfiguredTerm, TermConfig};
use nalgebra::Vector3;

use crate::cell_file::*;
use crate::error::CellError;
use crate::fiducial_plate::FiducialPlate;
use crate::program::Program;
use crate::quantity::{si_or_zero as opt, vector3};
pub use metrocell_model::{InstrumentPose, MachineGeometry, MachineKinematics};
use metrocell_model_file::instrument_terms::{
    tracker_station, tracker_term_model, tracker_warmup, RefractionOffsets,
};
pub use metrocell_model_file::instrument_terms::{StationSpec, WarmupSpec};
use metrocell_model_file::machine_section::{machine, pose};
use metrocell_model_file::terms_section::terms;

/// A window of turbulent air: σ inflation coefficient c on [start, end).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TurbulenceSpec {
    pub start: f64,
    pub end: f64,
    pub coefficient: f64,
}

/// Poisson beam breaks.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BeamBreakSpec {
    /// Breaks per second.
    pub rate: f64,
    /// Mean duration (s), exponential.
    pub mean_duration: f64,
}

/// Laser tracker model parameters (see [`crate::tracker_model`]).
#[derive(Debug, Clone, PartialEq)]
pub struct TrackerSpec {
    pub pose: InstrumentPose,
    pub rate: f64,
    /// σ_ρ = range_noise_constant + range_noise_per_metre·ρ (m).
    pub range_noise_constant: f64,
    pub range_noise_per_metre: f64,
    /// σ of azimuth and elevation (rad).
    pub angular_noise: f64,
    pub warmup: Option<WarmupSpec>,
    pub powered_on_before_start: f64,
    pub station: StationSpec,
    pub turbulence: Vec<TurbulenceSpec>,
    pub beam_breaks: Option<BeamBreakSpec>,
}

/// A thermocouple: reads the true temperature of its location + offset + white noise.
#[derive(Debug, Clone, PartialEq)]
pub struct ThermocoupleSpec {
    pub name: String,
    /// `None` = ambient; `Some(node)` = a structure node.
    pub node: Option<String>,
    pub noise: f64,
    pub offset: f64,
    pub calibration_uncertainty: f64,
    pub rate: f64,
}

/// Touch probe: hits at each program point.
#[derive(Debug)]
pub struct ProbeSpec {
    pub directions: Vec<Vector3<f64>>,
    pub hit_interval: f64,
    pub noise: f64,
    /// The physics `probe_pretravel` term with its true parameters.
    pub pretravel: Option<ConfiguredTerm>,
}

/// Camera frame requests, once per dwell.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraSpec {
    /// Camera frame relative to the tool frame, `p_tool = rotation·p_cam + translation`, with
    /// the tool frame's axes of the family (workpiece axes on cartesian and delta machines,
    /// machine axes on a five-axis machine, the tool frame on an arm): the camera turns with
    /// the tool.
    pub mount: InstrumentPose,
    pub delay: f64,
    /// The lens the file states, if any (else [`default_camera_lens`]).
    pub intrinsics: Option<CameraModel>,
    /// The fiducial plate placed in front of the camera at each dwell.
    pub plate: FiducialPlate,
}

impl CameraSpec {
    /// The lens: the file's, or [`default_camera_lens`].
    pub fn lens(&self) -> CameraModel {
        self.intrinsics.unwrap_or_else(default_camera_lens)
    }
}

/// The camera a cell without `sensors.camera.intrinsics` has: a 5 MP machine-vision camera
/// (2448 × 2048 px, 3.45 µm pixels) behind a 12 mm lens, i.e. f = 12 mm / 3.45 µm ≈ 3478 px,
/// principal point at the image centre ((w−1)/2, (h−1)/2, OpenCV's pixel convention), no
/// distortion.
pub fn default_camera_lens() -> CameraModel {
    let f = 12e-3 / 3.45e-6;
    CameraModel::new(2448, 2048, f, f, 1223.5, 1023.5, Distortion::none())
        .expect("the default lens is valid")
}

/// True air on the tracker beam.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AirSpec {
    pub pressure: f64,
    pub humidity: f64,
    pub beam_temperature_offset: f64,
}

/// A validated cell description.
#[derive(Debug)]
pub struct Cell {
    pub name: String,
    pub description: String,
    pub machine: MachineGeometry,
    pub tracker: Option<TrackerSpec>,
    pub thermocouples: Vec<ThermocoupleSpec>,
    pub machine_state_rate: Option<f64>,
    pub probe: Option<ProbeSpec>,
    pub camera: Option<CameraSpec>,
    /// Lumped thermal model; its sensors are the thermocouples (bias = offset, noise).
    pub thermal: ShiftThermalModel,
    pub thermal_step: f64,
    pub air: AirSpec,
    pub load_force: Option<Vector3<f64>>,
    pub program: Program,
    /// The machine's true error terms (machine-frame displacements).
    pub terms: TermModel,
    /// A stationing recording's instrument, accelerometers, ground tilt and waypoints
    /// (`program.stationing`, [`crate::stationing`]); its samples replace the periodic channels'.
    pub stationing: Option<crate::stationing::Stationing>,
    /// The term configs as written (for reports and for deriving nominal models).
    pub term_configs: Vec<TermConfig>,
    /// The file's `estimation` settings (free parameters, priors), checked against the terms.
    pub estimation: BTreeMap<String, metrocell_physics::EstimationConfig>,
    /// Test-only, non-physical disturbances ([`crate::disturbance`]); empty for real cells.
    pub disturbances: crate::disturbance::Disturbances,
    /// `machine.servo`: the axes following their command ([`crate::following_error`]).
    pub servo: Option<crate::following_error::FollowingAxes>,
}

impl Cell {
    /// Parse and validate a cell file's text; `file` names it in errors.
    pub fn from_yaml_str(text: &str, file: &str) -> Result<Cell, CellError> {
        Cell::from_yaml_str_in(text, file, Path::new("."))
    }

    /// As [`Cell::from_yaml_str`], with paths in the file (a URDF) relative to `base_dir`.
    pub fn from_yaml_str_in(text: &str, file: &str, base_dir: &Path) -> Result<Cell, CellError> {
        let raw: CellFile = serde_yaml::from_str(text).map_err(|e| CellError::Yaml {
            file: file.into(),
            message: e.to_string(),
        })?;
        Cell::from_file_in(&raw, base_dir)
    }

    /// Read, parse and validate a cell file.
    pub fn from_path(path: impl AsRef<Path>) -> Result<Cell, CellError> {
        let p = path.as_ref();
        let text = std::fs::read_to_string(p).map_err(|e| CellError::Io {
            file: p.display().to_string(),
            reason: e.to_string(),
        })?;
        Cell::from_yaml_str_in(
            &text,
            &p.display().to_string(),
            p.parent().unwrap_or(Path::new(".")),
        )
    }

    /// Validate a parsed file (relative paths from the current directory).
    pub fn from_file(f: &CellFile) -> Result<Cell, CellError> {
        Cell::from_file_in(f, Path::new("."))
    }

    /// Validate a parsed file; relative paths in it (a URDF) are relative to `base_dir`.
    pub fn from_file_in(f: &CellFile, base_dir: &Path) -> Result<Cell, CellError> {
        let machine = machine(&f.machine, &f.sensors.accelerometers, base_dir)?;
        let thermocouples = f
            .sensors
            .thermocouples
            .iter()
            .enumerate()
            .map(|(i, t)| thermocouple(i, t))
            .collect::<Result<Vec<_>, _>>()?;
        let env = f.environment.as_ref().ok_or_else(|| CellError::invalid("environment", "is required to simulate a cell: {ambient, air, ...} (only a model file for `metrocell calibrate` may leave it out)"))?;
        let program_section = f.program.as_ref().ok_or_else(|| CellError::invalid("program", "is required to simulate a cell: {grid | points | joints | poses, feed_rate, dwell, ...} (only a model file for `metrocell calibrate` may leave it out)"))?;
        let thermal = thermal_model(env, &f.sensors.thermocouples)?;
        // a stationing program's instrument is its own (setups, point noise), not a tracker
        let stationing = crate::stationing::Stationing::from_file(f, &machine, base_dir)?;
        let tracker = match stationing {
            Some(_) => None,
            None => f.sensors.tracker.as_ref().map(tracker).transpose()?,
        };
        let machine_state_rate = f
            .sensors
            .machine_state
            .as_ref()
            .map(|m| m.rate.positive("sensors.machine_state.rate", "1/s"))
            .transpose()?;
        let probe = f.sensors.probe.as_ref().map(probe).transpose()?;
        if probe.is_some() && machine.is_jointed() {
            return Err(CellError::invalid("sensors.probe", "is simulated for family: cartesian and delta only; a five_axis or serial_arm cell takes tracker, thermocouples, machine_state and camera"));
        }
        let camera = f.sensors.camera.as_ref().map(camera).transpose()?;
        let thermal_step = match &env.thermal_step {
            Some(q) => q.positive("environment.thermal_step", "s")?,
            None => 1.0,
        };
        let humidity = env.air.humidity;
        if !(0.0..=100.0).contains(&humidity) {
            return Err(CellError::OutOfRange {
                path: "environment.air.humidity".into(),
                value: humidity,
                reason: "must be in [0, 100] %RH".into(),
            });
        }
        let air = AirSpec {
            pressure: env
                .air
                .pressure
                .positive("environment.air.pressure", "Pa")?,
            humidity,
            beam_temperature_offset: opt(
                &env.air.beam_temperature_offset,
                "environment.air.beam_temperature_offset",
                "K",
            )?,
        };
        let load_force = env
            .load_force
            .as_ref()
            .map(|v| vector3(v, "environment.load_force", "N"))
            .transpose()?;
        let program = match &stationing {
            // one pass over the waypoints
            Some(st) => Program {
                cycles: Some(1),
                ..Program::from_section_with(
                    program_section,
                    &machine,
                    st.waypoints.iter().map(|w| w.q.clone()).collect(),
                )?
            },
            None => Program::from_section(program_section, &machine)?,
        };
        let sensor_names: BTreeSet<String> = thermocouples.iter().map(|t| t.name.clone()).collect();
        let terms = terms(
            &f.terms,
            Some(&sensor_names),
            Some(load_force.is_some()),
            &machine,
        )?;
        if let MachineKinematics::Delta(g) = &machine.kinematics {
            for (i, q) in program
                .points
                .iter()
                .chain(std::iter::once(&program.home))
                .enumerate()
            {
                g.inverse(&Vector3::new(q[0], q[1], q[2])).map_err(|e| {
                    CellError::invalid(
                        if i == program.points.len() {
                            "program.home".to_string()
                        } else {
                            format!("program point {i}")
                        },
                        format!("not reachable by the delta: {e}"),
                    )
                })?;
            }
        }
        let disturbances = crate::disturbance::Disturbances::from_section(
            &f.disturbances.clone().unwrap_or_default(),
            matches!(
                machine.kinematics,
                MachineKinematics::Cartesian(_) | MachineKinematics::Delta(_)
            ),
        )?;
        let servo = crate::following_error::FollowingAxes::from_section(
            f.machine.servo.as_ref(),
            matches!(
                machine.kinematics,
                MachineKinematics::Cartesian(_) | MachineKinematics::FiveAxis(_)
            ),
        )?;
        Ok(Cell {
            name: f.name.clone(),
            description: f.description.clone(),
            machine,
            tracker,
            thermocouples,
            machine_state_rate,
            probe,
            camera,
            thermal,
            thermal_step,
            air,
            load_force,
            program,
            terms,
            stationing,
            term_configs: f.terms.clone(),
            estimation: f.estimation.clone(),
            disturbances,
            servo,
        })
        .and_then(|cell: Cell| {
            cell.parameter_setup()?;
            Ok(cell)
        })
    }
}

impl Cell {
    /// How long a run of the cell lasts when nobody says: a stationing program's one pass
    /// (None for a cell whose program repeats through a shift: its duration is the caller's).
    pub fn natural_duration(&self) -> Option<f64> {
        self.stationing
            .as_ref()
            .map(|_| crate::stationing_run::stationing_length(&self.program))
    }

    /// The shared forward model of this cell's machine and terms, with `instruments` as its
    /// instrument terms (e.g. [`Cell::tracker_terms`], [`Cell::instrument_terms`]) and, if the
    /// cell has a camera, its geometry (mount and the lens's pinhole intrinsics).
    pub fn forward_model<'a>(
        &'a self,
        instruments: &'a TermModel,
    ) -> Result<ForwardModel<'a>, metrocell_physics::PhysicsError> {
        let model = ForwardModel::new(&self.machine, &self.terms, instruments)?;
        match &self.camera {
            Some(c) => {
                let lens = c.lens();
                model.with_camera(
                    None,
                    CameraGeometry {
                        mount: c.mount,
                        fx: lens.fx,
                        fy: lens.fy,
                        cx: lens.cx,
                        cy: lens.cy,
                    },
                )
            }
            None => Ok(model),
        }
    }

    /// Every instrument's effects as catalog terms with their true parameters: the tracker's
    /// ([`Cell::tracker_terms`]), the probe's `probe_pretravel` (`sensors.probe.pretravel`), and
    /// the camera's `lens_distortion` when `sensors.camera.intrinsics` states a Brown–Conrady
    /// lens (OpenCV k1 k2 p1 p2 k3 → the term's k1 k2 k3 p1 p2). A stationing program's
    /// instrument is not among them: its setups' tilts are drawn per seed
    /// ([`crate::stationing::Stationing::instrument_terms`], the truth of [`crate::Simulation`]).
    pub fn instrument_terms(&self) -> Result<TermModel, CellError> {
        let mut m = self.tracker_terms()?;
        if let Some(pt) = self.probe.as_ref().and_then(|p| p.pretravel.clone()) {
            m.push(pt)
                .map_err(|e| CellError::term("sensors.probe.pretravel", e))?;
        }
        if let Some(Distortion::BrownConrady(k)) = self
            .camera
            .as_ref()
            .and_then(|c| c.intrinsics.as_ref())
            .map(|l| l.distortion)
        {
            let path = "sensors.camera.intrinsics.distortion";
            let params = [
                ("k1", k[0]),
                ("k2", k[1]),
                ("k3", k[4]),
                ("p1", k[2]),
                ("p2", k[3]),
            ]
            .into_iter()
            .map(|(n, v)| (n.to_string(), ConfigValue::Number(v)))
            .collect();
            let t = configure(&TermConfig {
                id: "lens_distortion".into(),
                options: Default::default(),
                params,
                use_defaults: false,
            })
            .map_err(|e| CellError::term(path, e))?;
            m.push(t).map_err(|e| CellError::term(path, e))?;
        }
        Ok(m)
    }

    fn kinematic_truth(&self) -> Option<KinematicTruth> {
        let none = TermModel::default();
        let m = self.forward_model(&none).ok()?;
        m.kinematic_truth(&m.params()).ok()
    }

    /// For a delta: the true geometry, the nominal one plus the trims of the `delta_*` terms
    /// (tower order A, B, C). `None` for other families.
    pub fn true_delta_geometry(&self) -> Option<DeltaGeometry> {
        match self.kinematic_truth()? {
            KinematicTruth::Delta { truth, .. } => Some(truth),
            _ => None,
        }
    }

    /// For a serial arm: the true chain, the nominal one with the `joint_offset` and
    /// `link_length` terms applied (see [`metrocell_model::machine`]). `None` for other families.
    pub fn true_arm_chain(&self) -> Option<metrocell_kinematics::serial::SerialChain> {
        match self.kinematic_truth()? {
            KinematicTruth::Arm { chain, .. } => Some(chain),
            _ => None,
        }
    }

    /// The free parameters and priors of the `estimation` section over the forward model of the
    /// machine terms and every instrument's terms ([`Cell::instrument_terms`], stacked in that
    /// order).
    pub fn parameter_setup(&self) -> Result<metrocell_model::ParameterSetup, CellError> {
        let instruments = self.instrument_terms()?;
        let model = self
            .forward_model(&instruments)
            .map_err(|e| CellError::term("terms", e))?;
        metrocell_model::ParameterSetup::new(&model, &self.estimation)
            .map_err(|e| CellError::term("estimation", e))
    }

    /// The tracker's instrument effects as catalog terms with their true parameters: the
    /// `tracker_pose` of `sensors.tracker.pose`, the `tracker_warmup` of `sensors.tracker.warmup`
    /// (if given), and the `refraction` of the air on the beam against the weather station:
    /// path temperature offset = `environment.air.beam_temperature_offset` − station temperature
    /// bias, path pressure offset = −station pressure bias, option `path_humidity_offset` =
    /// −station humidity bias. Empty without a tracker. Built from the (adjustable) fields of
    /// the cell, so it follows a test's edits of `tracker`.
    pub fn tracker_terms(&self) -> Result<TermModel, CellError> {
        let Some(tr) = &self.tracker else {
            return Ok(TermModel::default());
        };
        let st = &tr.station;
        let refraction = RefractionOffsets {
            temperature: self.air.beam_temperature_offset - st.temperature_bias,
            pressure: -st.pressure_bias,
            humidity: -st.humidity_bias,
        };
        tracker_term_model(&tr.pose, tr.warmup.as_ref(), Some(refraction))
    }
}

fn tracker(t: &TrackerSection) -> Result<TrackerSpec, CellError> {
    let p = "sensors.tracker";
    let pose_section = t.pose.as_ref().ok_or_else(|| {
        CellError::invalid(
            format!("{p}.pose"),
            "is required to simulate the tracker: give where it stands in the workpiece frame, {translation: [x, y, z], euler_xyz: [a, b, c]}, and its noise model (rate, range_noise, angular_noise) (a model file may leave the pose out: it is then unknown and registered from each recording, which is how `metrocell diagnose` writes a tracker whose warm-up or refraction it found)",
        )
    })?;
    let warmup = tracker_warmup(t)?;
    let station = tracker_station(t)?;
    let needed = |what: &str| {
        CellError::invalid(format!("{p}.{what}"), "is required to simulate the tracker (only a model file for `metrocell calibrate` may leave the noise model out)")
    };
    let rate = t.rate.as_ref().ok_or_else(|| needed("rate"))?;
    let range_noise = t
        .range_noise
        .as_ref()
        .ok_or_else(|| needed("range_noise"))?;
    let angular_noise = t
        .angular_noise
        .as_ref()
        .ok_or_else(|| needed("angular_noise"))?;
    let mut turbulence = Vec::new();
    for (i, w) in t.turbulence.iter().enumerate() {
        let wp = format!("{p}.turbulence[{i}]");
        let start = w.start.non_negative(&format!("{wp}.start"), "s")?;
        let end = w.end.to_si(&format!("{wp}.end"), "s")?;
        if !(end > start) {
            return Err(CellError::invalid(
                &wp,
                format!("needs start < end, got [{start}, {end}] s"),
            ));
        }
        let coefficient = w
            .coefficient
            .non_negative(&format!("{wp}.coefficient"), "1")?;
        if coefficient > 1e-3 {
            return Err(CellError::OutOfRange {
                path: format!("{wp}.coefficient"),
                value: coefficient,
                reason: "plausible range is [0, 1e-3] (physics `turbulence.turbulence`)".into(),
            });
        }
        turbulence.push(TurbulenceSpec {
            start,
            end,
            coefficient,
        });
    }
    let beam_breaks = match &t.beam_breaks {
        None => None,
        Some(b) => {
            if !(b.per_hour >= 0.0 && b.per_hour <= 3600.0) {
                return Err(CellError::OutOfRange {
                    path: format!("{p}.beam_breaks.per_hour"),
                    value: b.per_hour,
                    reason: "must be in [0, 3600]".into(),
                });
            }
            Some(BeamBreakSpec {
                rate: b.per_hour / 3600.0,
                mean_duration: b
                    .mean_duration
                    .positive(&format!("{p}.beam_breaks.mean_duration"), "s")?,
            })
        }
    };
    Ok(TrackerSpec {
        pose: pose(pose_section, &format!("{p}.pose"))?,
        rate: rate.positive(&format!("{p}.rate"), "1/s")?,
        range_noise_constant: range_noise
            .constant
            .non_negative(&format!("{p}.range_noise.constant"), "m")?,
        range_noise_per_metre: range_noise
            .per_metre
            .non_negative(&format!("{p}.range_noise.per_metre"), "1")?,
        angular_noise: angular_noise.non_negative(&format!("{p}.angular_noise"), "rad")?,
        warmup,
        powered_on_before_start: t
            .powered_on_before_start
            .as_ref()
            .map(|q| q.non_negative(&format!("{p}.powered_on_before_start"), "s"))
            .transpose()?
            .unwrap_or(0.0),
        station,
        turbulence,
        beam_breaks,
    })
}

fn thermocouple(i: usize, t: &ThermocoupleSection) -> Result<ThermocoupleSpec, CellError> {
    let p = format!("sensors.thermocouples[{i}]");
    Ok(ThermocoupleSpec {
        name: t.name.clone(),
        node: if t.location == "ambient" {
            None
        } else {
            Some(t.location.clone())
        },
        noise: t.noise.non_negative(&format!("{p}.noise"), "K")?,
        offset: opt(&t.offset, &format!("{p}.offset"), "K")?,
        calibration_uncertainty: t
            .calibration_uncertainty
            .as_ref()
            .map(|q| q.non_negative(&format!("{p}.calibration_uncertainty"), "K"))
            .transpose()?
            .unwrap_or(0.0),
        rate: t.rate.positive(&format!("{p}.rate"), "1/s")?,
    })
}

fn probe(s: &ProbeSection) -> Result<ProbeSpec, CellError> {
    let p = "sensors.probe";
    if s.directions.is_empty() {
        return Err(CellError::invalid(
            format!("{p}.directions"),
            "needs at least one direction",
        ));
    }
    let mut directions = Vec::new();
    for (i, d) in s.directions.iter().enumerate() {
        let v = Vector3::new(d[0], d[1], d[2]);
        let n = v.norm();
        if !(n.is_finite() && n > 0.0) {
            return Err(CellError::invalid(
                format!("{p}.directions[{i}]"),
                "must be a non-zero vector",
            ));
        }
        directions.push(v / n);
    }
    let pretravel = match &s.pretravel {
        None => None,
        Some(pt) => Some(
            configure(&TermConfig {
                id: "probe_pretravel".into(),
                options: pt.options.clone(),
                params: pt.params.clone(),
                use_defaults: false,
            })
            .map_err(|e| CellError::term(format!("{p}.pretravel"), e))?,
        ),
    };
    let hit_interval = s.hit_interval.positive(&format!("{p}.hit_interval"), "s")?;
    Ok(ProbeSpec {
        directions,
        hit_interval,
        noise: s.noise.non_negative(&format!("{p}.noise"), "m")?,
        pretravel,
    })
}

fn camera(c: &CameraSection) -> Result<CameraSpec, CellError> {
    let intrinsics = match &c.intrinsics {
        None => None,
        Some(i) => {
            let p = "sensors.camera.intrinsics";
            for (key, v) in [("width", i.width), ("height", i.height)] {
                if v == 0 || v > 65_536 {
                    return Err(CellError::OutOfRange {
                        path: format!("{p}.{key}"),
                        value: v as f64,
                        reason: "must be in 1..=65536 px".into(),
                    });
                }
            }
            let (fx, fy) = (
                i.fx.positive(&format!("{p}.fx"), "px")?,
                i.fy.positive(&format!("{p}.fy"), "px")?,
            );
            let (cx, cy) = (
                i.cx.to_si(&format!("{p}.cx"), "px")?,
                i.cy.to_si(&format!("{p}.cy"), "px")?,
            );
            for (key, v, n) in [("cx", cx, i.width), ("cy", cy, i.height)] {
                if !(v >= 0.0 && v <= n as f64) {
                    return Err(CellError::OutOfRange {
                        path: format!("{p}.{key}"),
                        value: v,
                        reason: format!("the principal point must lie on the image, [0, {n}] px"),
                    });
                }
            }
            let (n, names) = match i.model.as_deref().unwrap_or("plumb_bob") {
                "plumb_bob" => (5, "k1, k2, p1, p2, k3"),
                "equidistant" => (4, "k1, k2, k3, k4"),
                other => return Err(CellError::invalid(format!("{p}.model"), format!("`{other}` is not a lens model here; allowed: plumb_bob (Brown-Conrady), equidistant (fisheye)"))),
            };
            if i.distortion.len() > n || i.distortion.iter().any(|d| !d.is_finite()) {
                return Err(CellError::invalid(
                    format!("{p}.distortion"),
                    format!("takes at most {n} finite coefficients: {names} (OpenCV order)"),
                ));
            }
            let mut k = [0.0; 5];
            k[..i.distortion.len()].copy_from_slice(&i.distortion);
            let distortion = if n == 5 {
                Distortion::BrownConrady(k)
            } else {
                Distortion::Fisheye([k[0], k[1], k[2], k[3]])
            };
            Some(
                CameraModel::new(i.width, i.height, fx, fy, cx, cy, distortion)
                    .map_err(|e| CellError::invalid(p, e.to_string()))?,
            )
        }
    };
    Ok(CameraSpec {
        mount: pose(&c.mount, "sensors.camera.mount")?,
        delay: c
            .delay
            .as_ref()
            .map(|q| q.non_negative("sensors.camera.delay", "s"))
            .transpose()?
            .unwrap_or(0.0),
        intrinsics,
        plate: FiducialPlate::default(),
    })
}

fn thermal_model(
    env: &EnvironmentSection,
    tcs: &[ThermocoupleSection],
) -> Result<ShiftThermalModel, CellError> {
    let a = &env.ambient;
    let ap = "environment.ambient";
    let ambient = AmbientCycle {
        mean: a.mean.to_si(&format!("{ap}.mean"), "degC")?,
        amplitude: opt(&a.amplitude, &format!("{ap}.amplitude"), "K")?,
        period: a
            .period
            .as_ref()
            .map(|q| q.positive(&format!("{ap}.period"), "s"))
            .transpose()?
            .unwrap_or(86_400.0),
        phase: opt(&a.phase, &format!("{ap}.phase"), "rad")?,
        drift: opt(&a.drift, &format!("{ap}.drift"), "K/s")?,
        walk_std: a.walk_std.unwrap_or(0.0),
    };
    if !(ambient.walk_std >= 0.0 && ambient.walk_std.is_finite()) {
        return Err(CellError::OutOfRange {
            path: format!("{ap}.walk_std"),
            value: ambient.walk_std,
            reason: "must be ≥ 0 K/√s".into(),
        });
    }
    let mut sources = Vec::new();
    for (i, s) in env.heat_sources.iter().enumerate() {
        let mut duty = Vec::new();
        for (j, d) in s.duty.iter().enumerate() {
            let dp = format!("environment.heat_sources[{i}].duty[{j}]");
            duty.push(DutySegment {
                start: d.start.to_si(&format!("{dp}.start"), "s")?,
                end: d.end.to_si(&format!("{dp}.end"), "s")?,
                level: d.level,
            });
        }
        sources.push(HeatSource {
            name: s.name.clone(),
            duty,
        });
    }
    let mut nodes = Vec::new();
    for (i, n) in env.nodes.iter().enumerate() {
        let np = format!("environment.nodes[{i}]");
        let mut heating = Vec::new();
        for (src, g) in &n.heating {
            heating.push((src.clone(), g.to_si(&format!("{np}.heating.{src}"), "K")?));
        }
        nodes.push(StructureNode {
            name: n.name.clone(),
            time_constant: n
                .time_constant
                .positive(&format!("{np}.time_constant"), "s")?,
            heating,
            initial: n
                .initial
                .as_ref()
                .map(|q| q.to_si(&format!("{np}.initial"), "degC"))
                .transpose()?,
        });
    }
    let node_names: Vec<&str> = nodes.iter().map(|n| n.name.as_str()).collect();
    let mut sensors = Vec::new();
    for (i, t) in tcs.iter().enumerate() {
        let location = if t.location == "ambient" {
            SensorLocation::Ambient
        } else if node_names.contains(&t.location.as_str()) {
            SensorLocation::Node(t.location.clone())
        } else {
            let mut allowed = vec!["ambient"];
            allowed.extend(&node_names);
            return Err(CellError::invalid(
                format!("sensors.thermocouples[{i}].location"),
                format!(
                    "`{}` is not a location; allowed: {}",
                    t.location,
                    allowed.join(", ")
                ),
            ));
        };
        sensors.push(ThermalSensor {
            name: t.name.clone(),
            location,
            bias: opt(&t.offset, "offset", "K")?,
            noise_std: t.noise.non_negative("noise", "K")?,
        });
    }
    let model = ShiftThermalModel {
        ambient,
        sources,
        nodes,
        sensors,
    };
    model
        .validate()
        .map_err(|e| CellError::term("environment", e))?;
    Ok(model)
}
