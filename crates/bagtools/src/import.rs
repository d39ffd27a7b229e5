//! `bag import`: point-measurement logs (CSV) → a bag.
//!
//! # The metrocell point CSV layout
//! One row per measured point, a header row naming the columns (any order; unknown columns are
//! an error so typos do not go unnoticed). Units are SI unless a mapping converts them.
//!
//! | column | meaning | required |
//! |---|---|---|
//! | `timestamp` | seconds since the Unix epoch (`1714557600.125`) or UTC date-time `2024-05-01T10:00:00.125Z` (`T` or space; `Z` optional); a mapping's `scale`/`offset` apply (seconds since a job's start + `offset: <epoch start>`; a date-time takes an offset only) | yes |
//! | `point_id` | name of the point | yes |
//! | `measured_x`, `measured_y`, `measured_z` | measured coordinates [m] | yes |
//! | `u_x`, `u_y`, `u_z` | standard uncertainties (k = 1) of the measured coordinates [m] | all three, or |
//! | `u95` | expanded uncertainty, k = 2, same on each axis [m]: σ = U95 / 2 | `u_*`, or |
//! | | | `default_uncertainty` in the mapping |
//! | `nominal_x`, `nominal_y`, `nominal_z` | commanded tool point [m], machine frame: where the target should be (NaN in the message when absent); on cartesian and delta machines it gives the commanded axes as nominal − tool offset | no |
//! | `joint.<name>` | commanded joint value [rad or m], any family's joint names (`x y z`, `x y z b c`, `joint_1` …) | no |
//! | `velocity.<name>` | commanded velocity of joint/axis `<name>` [m/s or rad/s] | no |
//! | `approach.<axis>` | approach direction of axis `x`, `y` or `z`: `+1` or `-1` (the sign of its last motion, when the export knows it) | no |
//! | `instrument_on_time` | when the instrument was powered on: same forms as `timestamp`, and a mapping's `scale`/`offset` apply to it as to `timestamp` | no |
//! | `temperature.<name>` | temperature [°C] | no |
//! | `pressure` | air pressure [Pa] | no |
//! | `humidity` | relative humidity, 0..1 | no |
//! | `aux.<name>` | any other channel (accelerometer, ...), in its SI unit | no |
//! | `role` | what the row's point is for: `fit` (a point of the machine's program that fits the model, the default), `check` (a point of the program kept out of every fit, to judge the model's predictions), `reference` (a fixed reference nest re-measured through the shift, on the floor or on the table the instrument stands on: the machine does not move it; its nominal, when given, is the nest's position) | no |
//! | `setup` | the instrument's placement the row was measured from (`S1`, `north`, …): each distinct value is one placement, with its own pose — a nuisance of every fit | no |
//! | `tool_offset.x`, `.y`, `.z` | the active tool's (target's) offset from the spindle's gauge point [m, machine frame], e.g. the tracker reflector of a verification at several offsets; the row's nominal is the commanded axes plus it | all three |
//! | `accel.<sensor>.x`, `.y`, `.z` | an accelerometer's reading [m/s², its own frame]: the specific force, +9.81 m/s² along its up axis at rest; the model file's `sensors.accelerometers: [{name: <sensor>, link: <URDF link>}]` says where it sits | all three, per sensor |
//!
//! # Topics written (log time = publish time = the row's timestamp)
//! * `/measured_points` `metrocell_msgs/msg/MeasuredPoint` (covariance diagonal σ², off-diagonal 0)
//! * `/reference_points` `metrocell_msgs/msg/MeasuredPoint`: the rows whose `role` is
//!   `reference` (no joint state or approach is written for them: the machine did not put them
//!   there); `/check_points` the rows whose `role` is `check`
//! * with a `setup` column, each point's `header.frame_id` is `<frame_id>@<setup>` (the frame of
//!   the instrument at that placement)
//! * `/imu/<sensor>` `sensor_msgs/msg/Imu`: the `accel.<sensor>.*` cells as `linear_acceleration`
//!   (orientation and angular velocity not given: their covariances' first element −1, as ROS
//!   defines), `header.frame_id` the mapping's `imu_frames.<sensor>` (default `<sensor>`)
//! * `/machine/commanded_joint_states` `sensor_msgs/msg/JointState` (the topic `metrocell sim`
//!   and the nodes use): `name` = the `joint.<name>` columns then any `velocity.<name>` without
//!   a joint column, `position` from `joint.*` and `velocity` from `velocity.*` (NaN where a
//!   row has a velocity but no position or the reverse; an array is empty when no column feeds it)
//! * `/machine/approach_directions` `sensor_msgs/msg/JointState` used as a named-value vector:
//!   `name` = the axes of the row's `approach.<axis>` cells, `position` = ±1
//! * `/tracker/power_on` `sensor_msgs/msg/TimeReference` (`time_ref` = `instrument_on_time`,
//!   `source` = the mapping's `source`), written at the first row and whenever the value changes;
//!   latched QoS, as `metrocell sim` writes it
//! * `/machine/tool_offset` `geometry_msgs/msg/PointStamped` (`point` = the `tool_offset.*`
//!   cells, `header.frame_id` `machine`), written before the row's point at the first row and
//!   whenever the offset changes
//! * `/temperature/<name>` `sensor_msgs/msg/Temperature` (variance 0 = unknown, as ROS defines)
//! * `/air/pressure` `sensor_msgs/msg/FluidPressure`, `/air/humidity` `sensor_msgs/msg/RelativeHumidity`
//! * `/aux_channels` `sensor_msgs/msg/JointState` used as a named-value vector: `name` holds the
//!   channel names, `position` their values (ROS has no standard named-scalar array).
//!
//! # Mapping file (YAML)
//! For exports of other software, a mapping says which source column feeds which field above
//! and how to convert it to SI: `value_SI = raw * scale + offset`.
//! ```yaml
//! delimiter: ","            # optional, one character
//! frame_id: tracker         # header.frame_id of every message (default "import")
//! source: leica_at960       # MeasuredPoint.source (default "import")
//! default_uncertainty: 1.0e-5   # [m] σ per axis when the file has no uncertainty column
//! columns:
//!   timestamp: {column: "Timestamp"}
//!   point_id: {column: "Point Name"}
//!   measured_x: {column: "X", scale: 0.001}    # mm → m
//!   u95: {column: "U95", scale: 0.001}
//!   temperature.air: {column: "Temperature"}
//!   pressure: {column: "Pressure", scale: 100.0}   # hPa → Pa
//! ignore: ["Comment"]       # source columns to skip
//! imu_frames: {base: base_imu}   # the frame (a link of the robot's URDF) each accelerometer reads in
//! ```
//! Without a mapping the header names are the layout's names and every scale is 1.
//!
//! Bad rows (a cell that does not parse, a missing required value) are reported with file,
//! line and column and skipped; the other rows are imported.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metrocell_bag::{qos_profiles_yaml, BagWriter, QosProfile, WriterOptions};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::Vector3;
use metrocell_msgs::geometry_msgs::msg::{Point, PointStamped};
use metrocell_msgs::msg::MeasuredPoint;
use metrocell_msgs::sensor_msgs::msg::{
    FluidPressure, Imu, JointState, RelativeHumidity, Temperature, TimeReference,
};
use metrocell_msgs::std_msgs::msg::Header;
use rosmsg::RosMessage;
use serde::Deserialize;

use crate::bag_sink::encode_cdr;
use crate::error::{io, Result, ToolError};

/// One mapped column: source column name and linear conversion to SI.
#[derive(Debug, Clone, Deserialize, PartialEq)]
#[serde(deny_unknown_fields)]
pub struct ColumnMap {
    pub column: String,
    #[serde(default = "one")]
    pub scale: f64,
    #[serde(default)]
    pub offset: f64,
}

fn one() -> f64 {
    1.0
}

/// The column-mapping file.
#[derive(Debug, Clone, Deserialize, Default)]
#[serde(deny_unknown_fields)]
pub struct Mapping {
    #[serde(default)]
    pub delimiter: Option<char>,
    #[serde(default)]
    pub frame_id: Option<String>,
    #[serde(default)]
    pub source: Option<String>,
    #[serde(default)]
    pub default_uncertainty: Option<f64>,
    #[serde(default)]
    pub columns: BTreeMap<String, ColumnMap>,
    #[serde(default)]
    pub ignore: Vec<String>,
    /// The frame each accelerometer (`accel.<sensor>.*` columns) reads in: `sensor → frame id`.
    #[serde(default)]
    pub imu_frames: BTreeMap<String, String>,
    /// The file it was read from (for messages); None when built in code.
    #[serde(skip)]
    pub path: Option<PathBuf>,
}

impl Mapping {
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(io(path))?;
        let mut m: Mapping = serde_yaml::from_str(&text).map_err(|e| ToolError::Mapping {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        m.path = Some(path.to_path_buf());
        Ok(m)
    }
}

/// Canonical field of the layout.
#[derive(Debug, Clone, PartialEq)]
enum Field {
    Timestamp,
    PointId,
    Measured(usize),
    Nominal(usize),
    U(usize),
    U95,
    Joint(String),
    Velocity(String),
    Approach(String),
    InstrumentOnTime,
    Temperature(String),
    Pressure,
    Humidity,
    Aux(String),
    Role,
    Setup,
    /// An accelerometer's reading: sensor, axis (0, 1, 2).
    Accel(String, usize),
    /// The active tool offset's coordinate (0, 1, 2).
    ToolOffset(usize),
}

/// What a row's point is for (`role` column).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Role {
    Fit,
    Check,
    Reference,
}

/// The topic reference nests' readings are written to (and read from).
pub const REFERENCE_POINTS_TOPIC: &str = metrocell_msgs::topics::REFERENCE_POINTS;

/// The topic check points (kept out of every fit, to judge predictions) are written to.
pub const CHECK_POINTS_TOPIC: &str = metrocell_msgs::topics::CHECK_POINTS;

/// The separator of an instrument frame and its setup in a point's `header.frame_id`.
pub const SETUP_SEPARATOR: char = metrocell_msgs::topics::SETUP_SEPARATOR;

fn parse_field(name: &str) -> Option<Field> {
    let axis = |s: &str| ["x", "y", "z"].iter().position(|a| *a == s);
    let named = |prefix: &str| {
        name.strip_prefix(prefix)
            .filter(|n| !n.is_empty() && n.chars().all(|c| c.is_ascii_alphanumeric() || c == '_'))
    };
    Some(match name {
        "timestamp" => Field::Timestamp,
        "point_id" => Field::PointId,
        "u95" => Field::U95,
        "pressure" => Field::Pressure,
        "humidity" => Field::Humidity,
        "instrument_on_time" => Field::InstrumentOnTime,
        "role" => Field::Role,
        "setup" => Field::Setup,
        _ => {
            if let Some(a) = name.strip_prefix("measured_").and_then(axis) {
                Field::Measured(a)
            } else if let Some(a) = name.strip_prefix("nominal_").and_then(axis) {
                Field::Nominal(a)
            } else if let Some(a) = name.strip_prefix("u_").and_then(axis) {
                Field::U(a)
            } else if let Some(n) = named("joint.") {
                Field::Joint(n.to_string())
            } else if let Some(n) = named("velocity.") {
                Field::Velocity(n.to_string())
            } else if let Some(a) = name.strip_prefix("approach.").filter(|a| axis(a).is_some()) {
                Field::Approach(a.to_string())
            } else if let Some(n) = named("temperature.") {
                Field::Temperature(n.to_string())
            } else if let Some(a) = name.strip_prefix("tool_offset.").and_then(axis) {
                Field::ToolOffset(a)
            } else if let Some(n) = named("aux.") {
                Field::Aux(n.to_string())
            } else if let Some((sensor, a)) = name
                .strip_prefix("accel.")
                .and_then(|r| r.rsplit_once('.'))
                .filter(|(s, _)| {
                    !s.is_empty() && s.chars().all(|c| c.is_ascii_alphanumeric() || c == '_')
                })
            {
                Field::Accel(sensor.to_string(), axis(a)?)
            } else {
                return None;
            }
        }
    })
}

/// Parse a timestamp cell: epoch seconds, or `YYYY-MM-DD[T ]HH:MM:SS[.f][Z]` in UTC. → ns.
pub fn parse_timestamp(s: &str) -> std::result::Result<u64, String> {
    let s = s.trim();
    if let Ok(secs) = s.parse::<f64>() {
        if secs.is_finite() && secs >= 0.0 {
            // split to keep ns precision for values like 1714557600.125
            let (int, frac) = s.split_once('.').unwrap_or((s, ""));
            let whole: u64 = int
                .parse()
                .map_err(|_| format!("timestamp '{s}' is not a number of seconds"))?;
            return epoch_ns(i128::from(whole), frac_ns(frac)?)
                .ok_or_else(|| format!("timestamp '{s}' is beyond the year 2554 (u64 ns)"));
        }
        return Err(format!("timestamp '{s}' is negative or not finite"));
    }
    let bad =
        || format!("timestamp '{s}' is neither epoch seconds nor YYYY-MM-DD HH:MM:SS[.fff][Z]");
    let s2 = s.strip_suffix('Z').unwrap_or(s);
    let (date, time) = s2.split_once(['T', ' ']).ok_or_else(bad)?;
    let d: Vec<&str> = date.split('-').collect();
    let (hms, frac) = time.split_once('.').unwrap_or((time, ""));
    let t: Vec<&str> = hms.split(':').collect();
    if d.len() != 3 || t.len() != 3 {
        return Err(bad());
    }
    let num = |x: &str| x.parse::<i64>().map_err(|_| bad());
    let (y, mo, da, h, mi, se) = (
        num(d[0])?,
        num(d[1])?,
        num(d[2])?,
        num(t[0])?,
        num(t[1])?,
        num(t[2])?,
    );
    if !(1..=12).contains(&mo)
        || !(1..=31).contains(&da)
        || !(0..=23).contains(&h)
        || !(0..=59).contains(&mi)
        || !(0..=60).contains(&se)
        || !(1970..=9999).contains(&y)
    {
        return Err(bad());
    }
    // days from civil (Howard Hinnant's algorithm), proleptic Gregorian, UTC.
    let yy = if mo <= 2 { y - 1 } else { y };
    let era = yy.div_euclid(400);
    let yoe = yy - era * 400;
    let doy = (153 * (if mo > 2 { mo - 3 } else { mo + 9 }) + 2) / 5 + da - 1;
    let doe = yoe * 365 + yoe / 4 - yoe / 100 + doy;
    let days = era * 146_097 + doe - 719_468;
    let secs = i128::from(days) * 86_400 + i128::from(h * 3600 + mi * 60 + se);
    epoch_ns(secs, frac_ns(frac).map_err(|_| bad())?)
        .ok_or_else(|| format!("timestamp '{s}' is beyond the year 2554 (u64 ns)"))
}

/// Seconds and nanoseconds since the epoch as u64 ns, None when they do not fit (a bag's time
/// is u64 nanoseconds: up to the year 2554).
fn epoch_ns(secs: i128, ns: u64) -> Option<u64> {
    u64::try_from(secs.checked_mul(1_000_000_000)? + i128::from(ns)).ok()
}

/// A timestamp cell through its mapping: `seconds·scale + offset` for a number of seconds (so
/// `{column: t_s, offset: 1767225600}` turns seconds since the start of a job into epoch time —
/// negative seconds, before the job's start, included — and `scale: 0.001` reads
/// milliseconds), `date-time + offset` for a date-time (a time-zone shift; a scale other than 1
/// makes no sense there and is an error). Exact to the nanosecond when the scale is 1; the
/// result must not fall before 1970. → ns since the epoch.
pub fn mapped_timestamp(cell: &str, scale: f64, offset: f64) -> std::result::Result<u64, String> {
    let text = cell.trim();
    let offset_ns = (offset * 1e9).round() as i128;
    let base_ns: i128 = match text.parse::<f64>() {
        Ok(v) if !v.is_finite() => return Err(format!("timestamp '{cell}' is not finite")),
        // exact when the scale is 1: integer nanoseconds of the decimal text
        Ok(_) if scale == 1.0 => match text.strip_prefix('-') {
            Some(magnitude) => -(parse_timestamp(magnitude)? as i128),
            None => parse_timestamp(text.strip_prefix('+').unwrap_or(text))? as i128,
        },
        Ok(v) => (v * scale * 1e9).round() as i128,
        Err(_) if scale != 1.0 => return Err(format!("timestamp '{cell}' is a date-time: its mapping may shift it (offset, s) but not scale it (scale {scale})")),
        Err(_) => parse_timestamp(text)? as i128,
    };
    let t = base_ns + offset_ns;
    if !(0..18_000_000_000_000_000_000i128).contains(&t) {
        return Err(format!("timestamp '{cell}' with scale {scale} and offset {offset} s falls at {:.3} s, before 1970 or past 2540", t as f64 / 1e9));
    }
    Ok(t as u64)
}

/// `raw * scale`, exact to the nearest f64 when `scale` is a power of ten (mm → m): the
/// decimal text is re-parsed with a shifted exponent, so "1250.1234" mm gives the f64 nearest
/// to 1.2501234, not 1250.1234 × 0.001 = 1.2501233999999999.
fn scale_decimal(text: &str, raw: f64, scale: f64) -> f64 {
    let k = scale.log10().round() as i32;
    if (-18..=18).contains(&k) && 10f64.powi(k) == scale && !text.contains(['e', 'E']) {
        if let Ok(v) = format!("{text}e{k}").parse::<f64>() {
            return v;
        }
    }
    raw * scale
}

fn frac_ns(frac: &str) -> std::result::Result<u64, String> {
    if frac.is_empty() {
        return Ok(0);
    }
    if !frac.chars().all(|c| c.is_ascii_digit()) {
        return Err(format!("fraction '{frac}' is not digits"));
    }
    let digits: String = frac.chars().chain(std::iter::repeat('0')).take(9).collect();
    Ok(digits.parse().expect("nine digits"))
}

/// The topics an import writes signals to: the ones `metrocell sim` publishes (crates/msgs `topics`).
pub use metrocell_msgs::topics::{
    APPROACH as APPROACH_TOPIC, COMMANDED_JOINTS as COMMANDED_JOINTS_TOPIC,
    POWER_ON as POWER_ON_TOPIC, TOOL_OFFSET as TOOL_OFFSET_TOPIC,
};

/// The commanded joint state of a row: the joint columns' names, then velocity-only names;
/// positions and velocities aligned with the names, NaN where one of the pair is missing,
/// an array left empty when no column feeds it (as ROS allows).
fn commanded_joint_state(
    header: Header,
    joints: &[(String, f64)],
    velocities: &[(String, f64)],
) -> JointState {
    let mut name: Vec<String> = joints.iter().map(|j| j.0.clone()).collect();
    name.extend(
        velocities
            .iter()
            .filter(|v| !joints.iter().any(|j| j.0 == v.0))
            .map(|v| v.0.clone()),
    );
    let value = |list: &[(String, f64)], n: &String| {
        list.iter().find(|x| &x.0 == n).map_or(f64::NAN, |x| x.1)
    };
    let position = if joints.is_empty() {
        Vec::new()
    } else {
        name.iter().map(|n| value(joints, n)).collect()
    };
    let velocity = if velocities.is_empty() {
        Vec::new()
    } else {
        name.iter().map(|n| value(velocities, n)).collect()
    };
    JointState {
        header,
        name,
        position,
        velocity,
        effort: Vec::new(),
    }
}

/// Counts of an import.
#[derive(Debug, Default)]
pub struct ImportReport {
    pub rows_read: u64,
    pub rows_imported: u64,
    /// One error per bad cell (a row with several bad cells lists each), naming file/line/column.
    pub errors: Vec<ToolError>,
    pub messages_per_topic: BTreeMap<String, u64>,
}

impl ImportReport {
    pub fn rows_rejected(&self) -> u64 {
        self.rows_read - self.rows_imported
    }
}

struct Bound {
    index: usize,
    source_name: String,
    field: Field,
    scale: f64,
    offset: f64,
}

fn stamp(ns: u64) -> Time {
    Time::from_nanos(ns as i64)
}

/// Import `csv_path` into the new bag `bag_dir` using `mapping` (None: the file uses the
/// layout's own column names).
///
/// The header is bound to the layout's fields (`bind_columns`) and checked for the required
/// ones (`check_required_fields`); each row is then read cell by cell (`read_row`: a bad cell is
/// an error naming file, line and column, and the row is skipped) and written as its messages
/// (`row_messages`).
pub fn import_csv(
    csv_path: &Path,
    bag_dir: &Path,
    mapping: Option<&Mapping>,
    options: WriterOptions,
) -> Result<ImportReport> {
    let default_mapping = Mapping::default();
    let mapping = mapping.unwrap_or(&default_mapping);
    let file = std::fs::File::open(csv_path).map_err(io(csv_path))?;
    let mut rdr = csv::ReaderBuilder::new()
        .delimiter(mapping.delimiter.unwrap_or(',') as u8)
        .flexible(true)
        .trim(csv::Trim::All)
        .from_reader(std::io::BufReader::new(file));
    let header_err = |reason: String| ToolError::Row {
        path: csv_path.to_path_buf(),
        line: 1,
        column: "header".into(),
        reason,
    };
    let headers = rdr
        .headers()
        .map_err(|e| header_err(e.to_string()))?
        .clone();
    let bound = bind_columns(&headers, mapping, &header_err)?;
    check_required_fields(&bound, mapping, &header_err)?;
    let frame_id = mapping.frame_id.clone().unwrap_or_else(|| "import".into());
    let source = mapping.source.clone().unwrap_or_else(|| "import".into());

    let mut writer = TopicWriter::create(bag_dir, options)?;
    let mut last_on_time: Option<u64> = None;
    let mut last_tool_offset: Option<[f64; 3]> = None;
    let mut report = ImportReport::default();
    let mut record = csv::StringRecord::new();
    loop {
        let line = rdr.position().line();
        match rdr.read_record(&mut record) {
            Ok(false) => break,
            Ok(true) => {}
            Err(e) => {
                report.rows_read += 1;
                report.errors.push(ToolError::Row {
                    path: csv_path.to_path_buf(),
                    line: line.max(2),
                    column: "-".into(),
                    reason: e.to_string(),
                });
                continue;
            }
        }
        let line = record.position().map_or(line, |p| p.line());
        if record.iter().all(|c| c.is_empty()) {
            continue;
        }
        report.rows_read += 1;
        let row = match read_row(&record, &bound, mapping) {
            Ok(row) => row,
            Err(bad) => {
                report
                    .errors
                    .extend(bad.into_iter().map(|(column, reason)| ToolError::Row {
                        path: csv_path.to_path_buf(),
                        line,
                        column,
                        reason,
                    }));
                continue;
            }
        };
        let t = row.t_ns.expect("required column bound and parsed");
        // the power-on time and the tool offset are written at the first row and whenever they
        // change
        let on_time = row.on_time.filter(|on| last_on_time != Some(*on));
        if on_time.is_some() {
            last_on_time = on_time;
        }
        let tool_offset = match row.tool_offset.iter().filter(|v| v.is_finite()).count() {
            0 => None,
            3 => Some(row.tool_offset).filter(|o| last_tool_offset != Some(*o)),
            _ => {
                report.errors.push(ToolError::Row {
                    path: csv_path.to_path_buf(),
                    line,
                    column: "tool_offset.*".into(),
                    reason: "a row gives some of tool_offset.x, .y, .z but not all three".into(),
                });
                continue;
            }
        };
        if tool_offset.is_some() {
            last_tool_offset = tool_offset;
        }
        let names = RowNames {
            frame_id: &frame_id,
            source: &source,
            imu_frames: &mapping.imu_frames,
        };
        for (topic, ty, def, bytes) in row_messages(row, t, on_time, tool_offset, &names)? {
            writer.write(&topic, ty, def, t, &bytes)?;
            *report.messages_per_topic.entry(topic).or_default() += 1;
        }
        report.rows_imported += 1;
    }
    writer.finish()?;
    Ok(report)
}

/// Every layout field bound to its source column: the header's own names (a name not in the
/// layout is an error) or, with a mapping's columns, the mapped ones.
fn bind_columns(
    headers: &csv::StringRecord,
    mapping: &Mapping,
    header_err: &dyn Fn(String) -> ToolError,
) -> Result<Vec<Bound>> {
    let find = |name: &str| headers.iter().position(|h| h == name);
    let mut bound: Vec<Bound> = Vec::new();
    if mapping.columns.is_empty() {
        for (i, h) in headers.iter().enumerate() {
            if mapping.ignore.iter().any(|x| x == h) {
                continue;
            }
            let field = parse_field(h).ok_or_else(|| header_err(format!("column '{h}' is not part of the point CSV layout (see `metrocell bag import --help`)")))?;
            bound.push(Bound {
                index: i,
                source_name: h.to_string(),
                field,
                scale: 1.0,
                offset: 0.0,
            });
        }
    } else {
        for (target, cm) in &mapping.columns {
            let field = parse_field(target).ok_or_else(|| ToolError::Mapping { path: mapping.path.clone().unwrap_or_else(|| PathBuf::from("column mapping")), reason: format!("columns.{target}: '{target}' is not a field of the point CSV layout (see `metrocell bag import --help`)") })?;
            let index = find(&cm.column).ok_or_else(|| {
                header_err(format!(
                    "mapped column '{}' (for {target}) is not in the header",
                    cm.column
                ))
            })?;
            bound.push(Bound {
                index,
                source_name: cm.column.clone(),
                field,
                scale: cm.scale,
                offset: cm.offset,
            });
        }
    }
    Ok(bound)
}

/// Err naming what is missing unless the columns give the required fields, an uncertainty on
/// every axis, and every accelerometer's three axes.
fn check_required_fields(
    bound: &[Bound],
    mapping: &Mapping,
    header_err: &dyn Fn(String) -> ToolError,
) -> Result<()> {
    let has = |f: &dyn Fn(&Field) -> bool| bound.iter().any(|b| f(&b.field));
    for (need, what) in [
        (
            &(|f: &Field| *f == Field::Timestamp) as &dyn Fn(&Field) -> bool,
            "timestamp",
        ),
        (&|f: &Field| *f == Field::PointId, "point_id"),
        (&|f: &Field| *f == Field::Measured(0), "measured_x"),
        (&|f: &Field| *f == Field::Measured(1), "measured_y"),
        (&|f: &Field| *f == Field::Measured(2), "measured_z"),
    ] {
        if !has(need) {
            return Err(header_err(format!(
                "no column for the required field {what}"
            )));
        }
    }
    // Every axis needs an uncertainty: from u95, its own u_<axis> column, or the mapping's default.
    if !has(&|f| matches!(f, Field::U95)) && mapping.default_uncertainty.is_none() {
        let missing: Vec<&str> = ["u_x", "u_y", "u_z"]
            .into_iter()
            .enumerate()
            .filter(|&(a, _)| !has(&|f| matches!(f, Field::U(b) if *b == a)))
            .map(|(_, n)| n)
            .collect();
        if !missing.is_empty() {
            return Err(header_err(format!(
                "no uncertainty column for {} (give u_x, u_y and u_z, or u95, or a default_uncertainty in a mapping): \
                 a measured point needs its uncertainty on every axis",
                missing.join(", ")
            )));
        }
    }
    // an accelerometer is read on all three of its axes
    let mut sensors: BTreeMap<&str, [bool; 3]> = BTreeMap::new();
    for b in bound {
        if let Field::Accel(sensor, a) = &b.field {
            sensors.entry(sensor.as_str()).or_default()[*a] = true;
        }
    }
    if let Some((sensor, axes)) = sensors.iter().find(|(_, axes)| !axes.iter().all(|a| *a)) {
        let missing: Vec<&str> = (0..3)
            .filter(|&a| !axes[a])
            .map(|a| ["x", "y", "z"][a])
            .collect();
        return Err(header_err(format!("accelerometer `{sensor}` has no column for accel.{sensor}.{}: an accelerometer is read on its three axes", missing.join(format!(", accel.{sensor}.").as_str()))));
    }
    Ok(())
}

/// The bag being written, each topic added at its first message (the power-on topic latched, as
/// `metrocell sim` writes it).
struct TopicWriter {
    writer: BagWriter,
    added: BTreeMap<String, ()>,
    qos: String,
    latched: String,
}

impl TopicWriter {
    fn create(bag_dir: &Path, options: WriterOptions) -> Result<Self> {
        Ok(Self {
            writer: BagWriter::create(bag_dir, options)?,
            added: BTreeMap::new(),
            qos: qos_profiles_yaml(&[QosProfile::default_publisher()]),
            latched: qos_profiles_yaml(&[QosProfile {
                keep_last: true,
                depth: 1,
                reliable: true,
                transient_local: true,
            }]),
        })
    }

    /// Write one message at `t` (ns), logged and published then.
    fn write(&mut self, topic: &str, ty: &str, def: &str, t: u64, bytes: &[u8]) -> Result<()> {
        if self.added.insert(topic.to_string(), ()).is_none() {
            // states published on change: latched, so a late joiner has the current one
            let qos = if topic == POWER_ON_TOPIC || topic == TOOL_OFFSET_TOPIC {
                &self.latched
            } else {
                &self.qos
            };
            self.writer.add_topic(topic, ty, def, qos)?;
        }
        self.writer.write(topic, t, t, bytes)?;
        Ok(())
    }

    fn finish(self) -> Result<()> {
        self.writer.finish()?;
        Ok(())
    }
}

/// The values of one row, in SI.
struct Row {
    t_ns: Option<u64>,
    point_id: Option<String>,
    measured: [f64; 3],
    nominal: [f64; 3],
    u: [f64; 3],
    joints: Vec<(String, f64)>,
    velocities: Vec<(String, f64)>,
    approach: Vec<(String, f64)>,
    on_time: Option<u64>,
    temps: Vec<(String, f64)>,
    aux: Vec<(String, f64)>,
    pressure: Option<f64>,
    humidity: Option<f64>,
    role: Role,
    setup: Option<String>,
    accel: BTreeMap<String, [f64; 3]>,
    tool_offset: [f64; 3],
}

/// The row's values, or each bad cell's source column and reason.
fn read_row(
    record: &csv::StringRecord,
    bound: &[Bound],
    mapping: &Mapping,
) -> std::result::Result<Row, Vec<(String, String)>> {
    let mut row = Row {
        t_ns: None,
        point_id: None,
        measured: [f64::NAN; 3],
        nominal: [f64::NAN; 3],
        u: [mapping.default_uncertainty.unwrap_or(f64::NAN); 3],
        joints: Vec::new(),
        velocities: Vec::new(),
        approach: Vec::new(),
        on_time: None,
        temps: Vec::new(),
        aux: Vec::new(),
        pressure: None,
        humidity: None,
        role: Role::Fit,
        setup: None,
        accel: BTreeMap::new(),
        tool_offset: [f64::NAN; 3],
    };
    let mut bad = Vec::new();
    for b in bound {
        let cell = record.get(b.index).unwrap_or("");
        if let Err(reason) = row.read_cell(b, cell) {
            bad.push((b.source_name.clone(), reason));
        }
    }
    if bad.is_empty() {
        Ok(row)
    } else {
        Err(bad)
    }
}

impl Row {
    /// Read `cell` into the field `b` binds it to; Err with the reason when it is not valid.
    fn read_cell(&mut self, b: &Bound, cell: &str) -> std::result::Result<(), String> {
        let number = || -> std::result::Result<f64, String> {
            let v: f64 = cell
                .parse()
                .map_err(|_| format!("'{cell}' is not a number"))?;
            if !v.is_finite() {
                return Err(format!("'{cell}' is not finite"));
            }
            Ok(scale_decimal(cell, v, b.scale) + b.offset)
        };
        match &b.field {
            Field::Timestamp => self.t_ns = Some(mapped_timestamp(cell, b.scale, b.offset)?),
            Field::PointId if cell.is_empty() => return Err("empty point id".into()),
            Field::PointId => self.point_id = Some(cell.to_string()),
            Field::Measured(a) => self.measured[*a] = number()?,
            Field::Nominal(a) if cell.is_empty() => self.nominal[*a] = f64::NAN,
            Field::Nominal(a) => self.nominal[*a] = number()?,
            Field::U(a) => match number()? {
                v if v > 0.0 => self.u[*a] = v,
                v => return Err(format!("uncertainty {v} m is not positive")),
            },
            Field::U95 => match number()? {
                v if v > 0.0 => self.u = [v / 2.0; 3],
                v => return Err(format!("U95 {v} m is not positive")),
            },
            Field::Joint(n) => self.joints.push((n.clone(), number()?)),
            Field::Velocity(_) | Field::Approach(_) | Field::InstrumentOnTime if cell.is_empty() => {}
            Field::Velocity(n) => self.velocities.push((n.clone(), number()?)),
            Field::Approach(a) => match number()? {
                v if v == 1.0 || v == -1.0 => self.approach.push((a.clone(), v)),
                v => return Err(format!("approach direction {v} is neither +1 nor -1")),
            },
            Field::InstrumentOnTime => match mapped_timestamp(cell, b.scale, b.offset) {
                Ok(t) => self.on_time = Some(t),
                Err(e) => return Err(format!("instrument_on_time: {e}")),
            },
            Field::Temperature(_) | Field::Pressure | Field::Humidity | Field::Aux(_) if cell.is_empty() => {}
            Field::Temperature(n) => self.temps.push((n.clone(), number()?)),
            Field::Pressure => self.pressure = Some(number()?),
            Field::Humidity => match number()? {
                v if (0.0..=1.0).contains(&v) => self.humidity = Some(v),
                v => return Err(format!("relative humidity {v} is outside 0..1 (a %RH column needs scale: 0.01)")),
            },
            Field::Aux(n) => self.aux.push((n.clone(), number()?)),
            Field::Role => match cell.trim().to_ascii_lowercase().as_str() {
                "" | "fit" => self.role = Role::Fit,
                "check" => self.role = Role::Check,
                "reference" | "ref" => self.role = Role::Reference,
                other => return Err(format!("role '{other}' is not one of: fit (a point of the machine's program), check (kept out of the fits, to judge predictions), reference (a fixed reference nest)")),
            },
            Field::Setup if cell.trim().is_empty() => {}
            Field::Setup => match cell.trim() {
                c if c.chars().all(|ch| ch.is_ascii_alphanumeric() || ch == '_' || ch == '-') => self.setup = Some(c.to_string()),
                c => return Err(format!("setup '{c}' is not a placement name: use letters, digits, `_` or `-`")),
            },
            Field::ToolOffset(_) if cell.is_empty() => {}
            Field::ToolOffset(a) => self.tool_offset[*a] = number()?,
            Field::Accel(..) if cell.is_empty() => {}
            Field::Accel(sensor, a) => {
                let v = number()?;
                self.accel.entry(sensor.clone()).or_insert([f64::NAN; 3])[*a] = v;
            }
        }
        Ok(())
    }
}

/// What every message of an import names: the instrument's frame, the points' source, each
/// accelerometer's frame.
struct RowNames<'a> {
    frame_id: &'a str,
    source: &'a str,
    imu_frames: &'a BTreeMap<String, String>,
}

/// A message to write: topic, ROS type, definition, CDR bytes.
type Message = (String, &'static str, &'static str, Vec<u8>);

/// The messages of one row at `t` (ns), in the order they are written: the tool offset
/// (`tool_offset`: when it changed; before the point, whose nominal includes it), its point, its
/// accelerometers, the machine's joints and approach (not for a reference nest), the power-on
/// time (`on_time`: when it changed), temperatures, air, auxiliary channels.
fn row_messages(
    row: Row,
    t: u64,
    on_time: Option<u64>,
    tool_offset: Option<[f64; 3]>,
    names: &RowNames,
) -> Result<Vec<Message>> {
    // a point's frame: the instrument's, at its placement when the row names one
    let point_frame = match &row.setup {
        Some(s) => format!("{}{SETUP_SEPARATOR}{s}", names.frame_id),
        None => names.frame_id.to_string(),
    };
    let header = Header {
        stamp: stamp(t),
        frame_id: point_frame,
    };
    let mut out: Vec<Message> = Vec::new();
    if let Some([x, y, z]) = tool_offset {
        let m = PointStamped {
            header: Header {
                stamp: stamp(t),
                frame_id: "machine".into(),
            },
            point: Point { x, y, z },
        };
        out.push(message(TOOL_OFFSET_TOPIC.into(), &m)?);
    }
    out.push(point_message(&row, &header, names.source)?);
    for (sensor, a) in &row.accel {
        if a.iter().any(|v| !v.is_finite()) {
            continue;
        }
        let frame = names
            .imu_frames
            .get(sensor)
            .cloned()
            .unwrap_or_else(|| sensor.clone());
        out.push(imu_message(sensor, frame, a, t)?);
    }
    // the machine's motion belongs to its own points, not to a nest's reading
    if row.role != Role::Reference {
        out.extend(machine_messages(&row, &header)?);
    }
    if let Some(on) = on_time {
        let m = TimeReference {
            header: header.clone(),
            time_ref: stamp(on),
            source: names.source.to_string(),
        };
        out.push(message(POWER_ON_TOPIC.into(), &m)?);
    }
    out.extend(signal_messages(row, t, &header)?);
    Ok(out)
}

/// The row's encoded message `m` on `topic`.
fn message<M: RosMessage>(topic: String, m: &M) -> Result<Message> {
    Ok((topic, M::ROS_TYPE, M::DEFINITION, encode_cdr(m)?))
}

/// The row's measured point, on the topic of its role.
fn point_message(row: &Row, header: &Header, source: &str) -> Result<Message> {
    let mut cov = [0.0; 9];
    for a in 0..3 {
        cov[a * 4] = row.u[a] * row.u[a];
    }
    let p = MeasuredPoint {
        header: header.clone(),
        point_id: row.point_id.clone().expect("required"),
        source: source.to_string(),
        nominal: Point {
            x: row.nominal[0],
            y: row.nominal[1],
            z: row.nominal[2],
        },
        measured: Point {
            x: row.measured[0],
            y: row.measured[1],
            z: row.measured[2],
        },
        covariance: cov,
    };
    let points_topic = match row.role {
        // a nest the machine did not put there: its point alone, and the row's signals
        Role::Reference => REFERENCE_POINTS_TOPIC,
        Role::Check => CHECK_POINTS_TOPIC,
        Role::Fit => "/measured_points",
    };
    message(points_topic.into(), &p)
}

/// An accelerometer's reading `a` in `frame`.
fn imu_message(sensor: &str, frame: String, a: &[f64; 3], t: u64) -> Result<Message> {
    let mut imu = Imu {
        header: Header {
            stamp: stamp(t),
            frame_id: frame,
        },
        linear_acceleration: Vector3 {
            x: a[0],
            y: a[1],
            z: a[2],
        },
        ..Default::default()
    };
    // orientation and angular velocity are not given (ROS: −1 in the first element)
    imu.orientation_covariance[0] = -1.0;
    imu.angular_velocity_covariance[0] = -1.0;
    message(format!("/imu/{sensor}"), &imu)
}

/// The machine's commanded joints and velocities, and its approach directions, when the row
/// has them.
fn machine_messages(row: &Row, header: &Header) -> Result<Vec<Message>> {
    let mut out = Vec::new();
    if !row.joints.is_empty() || !row.velocities.is_empty() {
        let js = commanded_joint_state(header.clone(), &row.joints, &row.velocities);
        out.push(message(COMMANDED_JOINTS_TOPIC.into(), &js)?);
    }
    if !row.approach.is_empty() {
        let js = JointState {
            header: header.clone(),
            name: row.approach.iter().map(|a| a.0.clone()).collect(),
            position: row.approach.iter().map(|a| a.1).collect(),
            ..Default::default()
        };
        out.push(message(APPROACH_TOPIC.into(), &js)?);
    }
    Ok(out)
}

/// The row's temperatures, station air and auxiliary channels.
fn signal_messages(row: Row, t: u64, header: &Header) -> Result<Vec<Message>> {
    let mut out = Vec::new();
    for (n, v) in row.temps {
        let m = Temperature {
            header: Header {
                stamp: stamp(t),
                frame_id: n.clone(),
            },
            temperature: v,
            variance: 0.0,
        };
        out.push(message(format!("/temperature/{n}"), &m)?);
    }
    if let Some(v) = row.pressure {
        let m = FluidPressure {
            header: header.clone(),
            fluid_pressure: v,
            variance: 0.0,
        };
        out.push(message("/air/pressure".into(), &m)?);
    }
    if let Some(v) = row.humidity {
        let m = RelativeHumidity {
            header: header.clone(),
            relative_humidity: v,
            variance: 0.0,
        };
        out.push(message("/air/humidity".into(), &m)?);
    }
    if !row.aux.is_empty() {
        let m = JointState {
            header: header.clone(),
            name: row.aux.iter().map(|j| j.0.clone()).collect(),
            position: row.aux.iter().map(|j| j.1).collect(),
            ..Default::default()
        };
        out.push(message("/aux_channels".into(), &m)?);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn timestamps_past_what_a_bag_holds_are_errors_not_overflows() {
        // found by tests/fuzz (csv_import): these multiplied past u64 and panicked
        for text in [
            "99999999999",
            "2600-01-01 00:00:00",
            "99999999999-01-01T00:00:00",
            "2020-01-01 -5:00:00",
        ] {
            assert!(parse_timestamp(text).is_err(), "{text}");
        }
        assert!(
            parse_timestamp("18446744073").is_ok(),
            "2554-07-21: the last second that fits"
        );
    }

    #[test]
    fn timestamps_parse_to_utc_nanoseconds() {
        assert_eq!(
            parse_timestamp("1714557600.125").unwrap(),
            1_714_557_600_125_000_000
        );
        assert_eq!(
            parse_timestamp("2024-05-01T10:00:00.125Z").unwrap(),
            1_714_557_600_125_000_000
        );
        assert_eq!(
            parse_timestamp("2024-05-01 10:00:00").unwrap(),
            1_714_557_600_000_000_000
        );
        assert_eq!(parse_timestamp("1970-01-01 00:00:00").unwrap(), 0);
        assert!(parse_timestamp("01/05/2024 10:00").is_err());
        assert!(parse_timestamp("2024-13-01 10:00:00").is_err());
    }

    /// Issue 12: a mapping's scale and offset apply to the timestamp column too.
    #[test]
    fn timestamp_mapping_scales_and_offsets() {
        // seconds since the start of a job + the job's epoch start
        assert_eq!(
            mapped_timestamp("12.5", 1.0, 1_767_225_600.0).unwrap(),
            1_767_225_612_500_000_000
        );
        // milliseconds since the start
        assert_eq!(
            mapped_timestamp("12500", 0.001, 1_767_225_600.0).unwrap(),
            1_767_225_612_500_000_000
        );
        // a local date-time one hour ahead of UTC
        assert_eq!(
            mapped_timestamp("2024-05-01 11:00:00.125", 1.0, -3600.0).unwrap(),
            1_714_557_600_125_000_000
        );
        assert_eq!(
            mapped_timestamp("1714557600.125", 1.0, 0.0).unwrap(),
            1_714_557_600_125_000_000
        );
        assert!(mapped_timestamp("2024-05-01 11:00:00", 0.001, 0.0)
            .unwrap_err()
            .contains("date-time"));
        assert!(mapped_timestamp("5", 1.0, -10.0)
            .unwrap_err()
            .contains("before 1970"));
        // an instrument switched on 20 min before the job started
        assert_eq!(
            mapped_timestamp("-1200", 1.0, 1_767_225_600.0).unwrap(),
            1_767_224_400_000_000_000
        );
        assert_eq!(mapped_timestamp("-0.5", 1.0, 10.0).unwrap(), 9_500_000_000);
        assert!(mapped_timestamp("-5", 1.0, 0.0)
            .unwrap_err()
            .contains("before 1970"));
    }

    #[test]
    fn power_of_ten_scales_are_exact() {
        assert_eq!(scale_decimal("1250.1234", 1250.1234, 0.001), 1.2501234);
        assert_eq!(scale_decimal("-240.4988", -240.4988, 0.001), -0.2404988);
        assert_eq!(scale_decimal("1013.25", 1013.25, 100.0), 101325.0);
        assert_eq!(scale_decimal("2.5", 2.5, 0.3), 2.5 * 0.3);
    }

    #[test]
    fn commanded_joints_pair_positions_and_velocities_by_name() {
        let h = Header::default();
        let js = commanded_joint_state(
            h.clone(),
            &[("x".into(), 0.1), ("y".into(), 0.2)],
            &[("y".into(), -0.05), ("z".into(), 0.01)],
        );
        assert_eq!(js.name, ["x", "y", "z"]);
        assert!(js.position[..2] == [0.1, 0.2] && js.position[2].is_nan());
        assert!(js.velocity[0].is_nan() && js.velocity[1..] == [-0.05, 0.01]);
        let only_positions = commanded_joint_state(h, &[("x".into(), 0.1)], &[]);
        assert!(only_positions.velocity.is_empty());
    }

    #[test]
    fn layout_fields_parse() {
        assert_eq!(parse_field("velocity.x"), Some(Field::Velocity("x".into())));
        assert_eq!(parse_field("approach.z"), Some(Field::Approach("z".into())));
        assert_eq!(parse_field("approach.b"), None);
        assert_eq!(
            parse_field("instrument_on_time"),
            Some(Field::InstrumentOnTime)
        );
        assert_eq!(parse_field("measured_y"), Some(Field::Measured(1)));
        assert_eq!(
            parse_field("temperature.air"),
            Some(Field::Temperature("air".into()))
        );
        assert_eq!(parse_field("temperature."), None);
        assert_eq!(parse_field("tool_offset.z"), Some(Field::ToolOffset(2)));
        assert_eq!(parse_field("tool_offset.b"), None);
        assert_eq!(parse_field("X"), None);
    }
}
