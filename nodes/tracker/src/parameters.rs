//! The node's declared parameters (units and ranges in each description) and the
//! configuration built from them.

use metrocell_compensation::{AirData, SphericalNoise};
use metrocell_laser_tracker::total_station_gsi::TotalStationNoise;
use metrocell_laser_tracker::{
    AirSource, EdlenForm, ProgramSchedule, ReadingProcessor, TurbulenceTest,
};
use metrocell_node::{ParamDecl, Parameters};
use nalgebra::Vector3;

/// The run-time trigger of a re-registration (live node).
pub const REREGISTER: &str = "reregister";
/// What streams on the TCP backend, and its values.
pub const INSTRUMENT: &str = "instrument";
pub const LASER_TRACKER: &str = "laser_tracker";
pub const TOTAL_STATION_GSI: &str = "total_station_gsi";

pub fn declarations() -> Vec<ParamDecl> {
    let s = |v: &str| v.to_string();
    vec![
        metrocell_node::diagnostics::input_timeout_param(),
        ParamDecl::new("backend", s("topic"), "where readings come from: topic (tracker/measurements, what the twin and other drivers publish) or tcp (an instrument streaming ASCII lines, see tcp_address)").with_allowed(["topic", "tcp"]),
        ParamDecl::new("tcp_address", s("127.0.0.1:5000"), "host:port of the instrument's line stream (backend tcp); framing: t_s,target,range_m,azimuth_rad,elevation_rad[,T_degC,p_Pa,RH_0_1] (instrument laser_tracker) or one Leica GSI-8/GSI-16 block per line (instrument total_station_gsi)"),
        ParamDecl::new(INSTRUMENT, s("laser_tracker"), "what streams on tcp_address (backend tcp): laser_tracker (ASCII readings → dwells, registration, measured_points) or total_station_gsi (Leica GSI blocks, words 11 point id, 21 Hz, 22 V, 31 slope distance: each block published as one reading on tracker/measurements, instrument frame x toward Hz = 0, y toward Hz = 300 gon, z up; azimuth = −Hz, elevation = 100 gon − V, face II mapped to face I)").with_allowed([LASER_TRACKER, TOTAL_STATION_GSI]),
        ParamDecl::new("total_station_angle_sigma", 0.5, "instrument total_station_gsi: standard deviation of Hz and of V [arc-seconds] (1″ = 0.309 mgon = 4.85 µrad; ISO 17123-3 figure of the instrument)").with_range(0.0, 600.0),
        ParamDecl::new("total_station_distance_sigma", 0.6e-3, "instrument total_station_gsi: a of the slope-distance σ = a + b·SD [m]").with_range(0.0, 0.1),
        ParamDecl::new("total_station_distance_ppm", 1.0, "instrument total_station_gsi: b of the slope-distance σ = a + b·SD [ppm = mm/km]").with_range(0.0, 1000.0),
        ParamDecl::new("tcp_initial_backoff", 0.1, "first wait before reconnecting to the instrument [s]; doubles per failed attempt").with_range(0.01, 60.0),
        ParamDecl::new("tcp_max_backoff", 5.0, "longest wait between reconnection attempts [s]").with_range(0.01, 600.0),
        ParamDecl::new("instrument_refractive_index", 0.0, "index the instrument divided TCP/CSV ranges by [1]; 0 = none (vacuum distance). Topic readings carry their own").with_range(0.0, 1.001),
        ParamDecl::new("range_noise_constant", 4e-6, "a of the radial noise a + b·range [m] (thesis P3: 4 µm)").with_range(0.0, 1e-3),
        ParamDecl::new("range_noise_per_metre", 0.8e-6, "b of the radial noise a + b·range [m/m] (thesis P3: 0.8 µm/m)").with_range(0.0, 1e-4),
        ParamDecl::new("angular_noise", 3e-6, "standard deviation of azimuth and elevation [rad]").with_range(0.0, 1e-3),
        ParamDecl::new("air_source", s("reading"), "air for the refraction re-correction: reading (each reading's own station air), topics (latest weather/temperature, weather/pressure, weather/humidity), configured (air_temperature/pressure/humidity)").with_allowed(["reading", "topics", "configured"]),
        ParamDecl::new("air_temperature", 20.0, "configured air temperature [°C]").with_range(-40.0, 80.0),
        ParamDecl::new("air_pressure", 101_325.0, "configured air pressure [Pa]").with_range(50e3, 120e3),
        ParamDecl::new("air_humidity", 0.5, "configured relative humidity [0..1]").with_range(0.0, 1.0),
        ParamDecl::new("edlen_form", s("shop_floor"), "Edlén equation: shop_floor (NIST simplified, thesis eq. 8) or full (Birch & Downs at `wavelength`)").with_allowed(["shop_floor", "full"]),
        ParamDecl::new("wavelength", 633e-9, "vacuum wavelength of the interferometer for edlen_form full [m]").with_range(300e-9, 2e-6),
        ParamDecl::new("max_range", 80.0, "longest plausible range [m]; longer readings are rejected as garbage").with_range(0.1, 1000.0),
        ParamDecl::new("dwell_gap", 0.5, "a silence longer than this ends a dwell [s]").with_range(0.001, 3600.0),
        ParamDecl::new("min_dwell_readings", 5i64, "dwells with fewer readings are dropped (counted)").with_range(2.0, 1e6),
        ParamDecl::new("turbulence_false_alarm", 0.001, "false-alarm rate of the χ² turbulence test per undisturbed dwell [1]").with_range(1e-9, 0.5),
        ParamDecl::new("warmup_target", s(""), "target id of the nest whose repeated dwells track the warm-up (A + B(1 − e^(−t/τ)) of its range); empty = off"),
        ParamDecl::new("power_on_time", 0.0, "ROS time at which the tracker was switched on [s since epoch]; 0 = first reading − warmup_elapsed_at_first_reading").with_range(0.0, 1e10),
        ParamDecl::new("warmup_elapsed_at_first_reading", 0.0, "time the tracker had been on at the first reading, used when power_on_time is 0 [s]").with_range(0.0, 1e6),
        ParamDecl::new("nominal_joints", vec![s("x"), s("y"), s("z")], "commanded JointState names giving the nominal X, Y, Z of the target [m] (Cartesian machines)"),
        ParamDecl::new("tool_offset", vec![0.0, 0.0, 0.0], "target (SMR) position relative to the commanded axis position [m], machine frame"),
        ParamDecl::new("commanded_reliable", false, "read machine/commanded_joint_states reliably: DDS then repairs what a network glitch held back (after a pulled cable no dwell goes without its nominal), but a publisher offering only best effort is not matched; false (best effort) matches every publisher and loses what the network loses"),
        ParamDecl::new("commanded_gap", 0.5, "longest gap between commanded joint states the node interpolates across [s]").with_range(0.001, 60.0),
        ParamDecl::new("program_points", Vec::<f64>::new(), "without machine/commanded_joint_states: the program's points in visiting order, x y z per point [m] (flat list); their time comes from T_v = L_T/F + T_s(n − 1)"),
        ParamDecl::new("program_home", vec![0.0, 0.0, 0.0], "where the program starts [m] (commanded axis position)"),
        ParamDecl::new("program_feed", 0.05, "feed rate F between program points [m/s]").with_range(1e-6, 10.0),
        ParamDecl::new("program_stop_time", 3.0, "stop time T_s at each program point [s]").with_range(0.0, 3600.0),
        ParamDecl::new("program_start_time", 0.0, "ROS time the program left home [s since epoch]; 0 = no program timing").with_range(0.0, 1e10),
        ParamDecl::new("registration_points", 12i64, "dwells (distinct targets) collected before the tracker pose is fitted; re-collected on a re-registration (parameter reregister, or topic tracker/reregister)").with_range(3.0, 1e5),
        ParamDecl::new(REREGISTER, false, "set true at run time (ros2 param set /tracker reregister true) when the tracker was moved: the pose is fitted again from the next registration_points targets; the node sets it back to false once done (live only; a message on tracker/reregister does the same)"),
        ParamDecl::new("machine_frame", s("machine"), "frame of nominal and measured points, parent of the tracker in /tf_static"),
        ParamDecl::new("tracker_frame", s("tracker"), "frame of the tracker's readings"),
    ]
}

/// Everything the node's logic needs, from the start-up parameters.
#[derive(Debug, Clone)]
pub struct TrackerConfig {
    pub processor: ReadingProcessor,
    pub turbulence: TurbulenceTest,
    pub instrument_index: f64,
    /// air from the weather-station topics instead of the readings
    pub air_from_topics: bool,
    pub dwell_gap_ns: i64,
    pub min_dwell_readings: usize,
    pub warmup_target: String,
    /// ns; None = first reading − elapsed
    pub power_on_ns: Option<i64>,
    pub warmup_elapsed_at_first_ns: i64,
    pub nominal_joints: Vec<String>,
    pub tool_offset: Vector3<f64>,
    pub commanded_gap_ns: i64,
    /// Read the commanded joint states reliably (parameter `commanded_reliable`).
    pub commanded_reliable: bool,
    pub registration_points: usize,
    /// program timing used when no commanded joint state covers a dwell
    pub schedule: Option<ProgramSchedule>,
    pub machine_frame: String,
    pub tracker_frame: String,
    /// Some when parameter instrument is total_station_gsi: the noise of its observations
    pub total_station: Option<TotalStationNoise>,
}

fn ns(s: f64) -> i64 {
    (s * 1e9).round() as i64
}

impl TrackerConfig {
    pub fn from_parameters(p: &Parameters) -> Result<Self, Box<dyn std::error::Error>> {
        let air = AirData {
            temperature: p.get("air_temperature")?,
            pressure: p.get("air_pressure")?,
            humidity: p.get("air_humidity")?,
        };
        let processor = ReadingProcessor {
            noise: SphericalNoise {
                radial_base: p.get("range_noise_constant")?,
                radial_per_metre: p.get("range_noise_per_metre")?,
                angular: p.get("angular_noise")?,
            },
            air: if p.get::<String>("air_source")? == "configured" {
                AirSource::Configured(air)
            } else {
                AirSource::Station
            },
            form: if p.get::<String>("edlen_form")? == "full" {
                EdlenForm::Full {
                    wavelength: p.get("wavelength")?,
                }
            } else {
                EdlenForm::ShopFloor
            },
            max_range: p.get("max_range")?,
        };
        let offset = p.get::<Vec<f64>>("tool_offset")?;
        if offset.len() != 3 || offset.iter().any(|v| !v.is_finite()) {
            return Err(format!(
                "parameter tool_offset: expected 3 finite values [m], got {offset:?}"
            )
            .into());
        }
        let joints = p.get::<Vec<String>>("nominal_joints")?;
        if joints.len() != 3 {
            return Err(format!(
                "parameter nominal_joints: expected the 3 joint names of X, Y, Z, got {joints:?}"
            )
            .into());
        }
        let power_on: f64 = p.get("power_on_time")?;
        let flat = p.get::<Vec<f64>>("program_points")?;
        let home = p.get::<Vec<f64>>("program_home")?;
        if flat.len() % 3 != 0
            || home.len() != 3
            || flat.iter().chain(&home).any(|v| !v.is_finite())
        {
            return Err(format!("parameters program_points ({} values) and program_home ({} values) must hold finite x y z triples", flat.len(), home.len()).into());
        }
        let start: f64 = p.get("program_start_time")?;
        let (feed, stop_time): (f64, f64) = (p.get("program_feed")?, p.get("program_stop_time")?);
        let schedule = (start > 0.0 && !flat.is_empty()).then(|| ProgramSchedule {
            start_ns: ns(start),
            home: Vector3::new(home[0], home[1], home[2]),
            points: flat
                .chunks(3)
                .map(|c| Vector3::new(c[0], c[1], c[2]))
                .collect(),
            feed,
            stop_time,
        });
        Ok(TrackerConfig {
            processor,
            turbulence: TurbulenceTest {
                false_alarm: p.get("turbulence_false_alarm")?,
            },
            instrument_index: p.get("instrument_refractive_index")?,
            air_from_topics: p.get::<String>("air_source")? == "topics",
            dwell_gap_ns: ns(p.get("dwell_gap")?),
            min_dwell_readings: p.get::<i64>("min_dwell_readings")? as usize,
            warmup_target: p.get("warmup_target")?,
            power_on_ns: (power_on > 0.0).then(|| ns(power_on)),
            warmup_elapsed_at_first_ns: ns(p.get("warmup_elapsed_at_first_reading")?),
            nominal_joints: joints,
            tool_offset: Vector3::new(offset[0], offset[1], offset[2]),
            commanded_gap_ns: ns(p.get("commanded_gap")?),
            commanded_reliable: p.get("commanded_reliable")?,
            registration_points: p.get::<i64>("registration_points")? as usize,
            schedule,
            machine_frame: p.get("machine_frame")?,
            tracker_frame: p.get("tracker_frame")?,
            total_station: (p.get::<String>(INSTRUMENT)? == TOTAL_STATION_GSI)
                .then(|| -> Result<_, Box<dyn std::error::Error>> {
                    Ok(TotalStationNoise {
                        angle: (p.get::<f64>("total_station_angle_sigma")? / 3600.0).to_radians(),
                        distance_constant: p.get("total_station_distance_sigma")?,
                        distance_ppm: p.get("total_station_distance_ppm")?,
                    })
                })
                .transpose()?,
        })
    }

    /// The configuration of the declared defaults (tests, benchmarks).
    pub fn defaults() -> Self {
        let p = Parameters::resolve(
            &declarations(),
            &metrocell_node::RosArgs::default(),
            "/tracker",
            "tracker",
        )
        .expect("the declared defaults resolve");
        Self::from_parameters(&p).expect("the declared defaults form a configuration")
    }

    /// One log line describing the configuration.
    pub fn describe(&self) -> String {
        if let Some(t) = &self.total_station {
            return format!(
                "total station (Leica GSI): σ Hz = σ V = {:.2}″, σ SD = {:.2} mm + {:.1} ppm; each block → tracker/measurements in frame '{}'",
                t.angle.to_degrees() * 3600.0,
                t.distance_constant * 1e3,
                t.distance_ppm,
                self.tracker_frame
            );
        }
        let n = &self.processor.noise;
        format!(
            "noise σr = {:.1} µm + {:.2} µm/m, σ angle = {:.1} µrad; air {:?}; {:?}; dwell gap {} ms, ≥ {} readings; turbulence α = {}; warm-up nest '{}'; registration after {} targets",
            n.radial_base * 1e6,
            n.radial_per_metre * 1e6,
            n.angular * 1e6,
            self.processor.air,
            self.processor.form,
            self.dwell_gap_ns / 1_000_000,
            self.min_dwell_readings,
            self.turbulence.false_alarm,
            self.warmup_target,
            self.registration_points
        )
    }
}
