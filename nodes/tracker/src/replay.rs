//! The node on a bag (`--bag IN`): no DDS. Inputs are read in log-time order; the logic runs on
//! the messages' own stamps as live, so the outputs equal the live node's fed by `bag play`.
//! Outputs are written at the log time of the input that caused them; the end of the input
//! closes the open dwell, as a live node's shutdown does.
//!
//! `IN` ending in `.csv` is a CSV export: it is first imported with `bag import`'s importer
//! (layout and mapping file: parameter `csv_mapping`) into a scratch bag, whose
//! `/measured_points` (tracker-frame points), `/machine/commanded_joint_states`, `/temperature/air`,
//! `/air/pressure` and `/air/humidity` are then replayed. With `air_source:=topics` the
//! weather-station topics `weather/temperature`, `weather/pressure`, `weather/humidity` are read.

use std::path::{Path, PathBuf};

use metrocell_bag::WriterOptions;
use metrocell_bagtools::import::{import_csv, Mapping};
use metrocell_bagtools::{BagSource, ReplayOutput, SourcedMessage};
use metrocell_msgs::geometry_msgs::msg::PoseWithCovarianceStamped;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint, TrackerMeasurement};
use metrocell_msgs::sensor_msgs::msg::{FluidPressure, JointState, RelativeHumidity, Temperature};
use metrocell_msgs::std_msgs::msg::String as RosString;
use metrocell_msgs::tf2_msgs::msg::TFMessage;
use metrocell_node::{OfflineNode, ReplayArgs};
use metrocell_tracker_node::messages;
use metrocell_tracker_node::parameters::TrackerConfig;
use metrocell_tracker_node::tracker_state::{Output, TrackerState};

/// Input topics.
struct Inputs {
    readings: String,
    commanded: String,
    reregister: String,
    /// weather station: temperature, pressure, humidity (empty when the air comes otherwise)
    air: [String; 3],
    csv: bool,
}

pub fn run(node: OfflineNode, args: &ReplayArgs) -> Result<(), Box<dyn std::error::Error>> {
    let config = TrackerConfig::from_parameters(node.parameters())?;
    if config.total_station.is_some() {
        return Err("parameter instrument:=total_station_gsi drives a live total station (backend tcp); a recorded total station's tracker/measurements already are its points: read the bag with `metrocell calibrate` or `metrocell diagnose` (points_type tracker) instead of replaying it here".into());
    }
    node.logger().info(config.describe());
    let mut state = TrackerState::new(config);
    let (machine_frame, tracker_frame) = (
        state.config().machine_frame.clone(),
        state.config().tracker_frame.clone(),
    );

    let csv = args
        .bag
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("csv"));
    let scratch = scratch_dir();
    let bag: PathBuf = if csv {
        let mapping_path: String = node.param("csv_mapping")?;
        let mapping = if mapping_path.is_empty() {
            None
        } else {
            Some(Mapping::load(Path::new(&mapping_path))?)
        };
        let report = import_csv(
            &args.bag,
            &scratch,
            mapping.as_ref(),
            WriterOptions::default(),
        )?;
        node.logger()
            .info(format!("imported {}: {report:?}", args.bag.display()));
        scratch.clone()
    } else {
        args.bag.clone()
    };
    let mut source = BagSource::open(&bag)?;
    let inputs = if csv {
        Inputs {
            readings: "/measured_points".into(),
            commanded: metrocell_bagtools::import::COMMANDED_JOINTS_TOPIC.into(),
            reregister: String::new(),
            air: [
                "/temperature/air".into(),
                "/air/pressure".into(),
                "/air/humidity".into(),
            ],
            csv: true,
        }
    } else {
        let air = if state.config().air_from_topics {
            [
                node.resolve_topic("weather/temperature")?,
                node.resolve_topic("weather/pressure")?,
                node.resolve_topic("weather/humidity")?,
            ]
        } else {
            Default::default()
        };
        Inputs {
            readings: node.resolve_topic("tracker/measurements")?,
            commanded: node.resolve_topic("machine/commanded_joint_states")?,
            reregister: node.resolve_topic("tracker/reregister")?,
            air,
            csv: false,
        }
    };
    let found = if csv {
        source.subscribe::<MeasuredPoint>(&inputs.readings)?
    } else {
        source.subscribe::<TrackerMeasurement>(&inputs.readings)?
    };
    if !found {
        node.logger()
            .warn(source.missing_topic_hint(&inputs.readings));
    }
    if !source.subscribe::<JointState>(&inputs.commanded)? {
        node.logger()
            .warn(source.missing_topic_hint(&inputs.commanded));
    }
    if !inputs.air[0].is_empty() {
        for (topic, found) in inputs.air.iter().zip([
            source.subscribe::<Temperature>(&inputs.air[0])?,
            source.subscribe::<FluidPressure>(&inputs.air[1])?,
            source.subscribe::<RelativeHumidity>(&inputs.air[2])?,
        ]) {
            if !found {
                node.logger().warn(source.missing_topic_hint(topic));
            }
        }
    }
    if !csv {
        source.subscribe::<RosString>(&inputs.reregister)?;
    }

    let points_topic = node.resolve_topic("measured_points")?;
    let dwells_topic = node.resolve_topic("tracker/dwells")?;
    let warmup_topic = node.resolve_topic("tracker/warmup")?;
    let pose_topic = node.resolve_topic("tracker/pose")?;
    let mut output = ReplayOutput::open(args.output.as_deref())?;
    output.advertise::<MeasuredPoint>(&points_topic)?;
    output.advertise::<TrackerMeasurement>(&dwells_topic)?;
    output.advertise::<ErrorModel>(&warmup_topic)?;
    output.advertise::<TFMessage>("/tf_static")?;
    output.advertise::<PoseWithCovarianceStamped>(&pose_topic)?;

    let mut write =
        |outputs: Vec<Output>, log_time_ns: u64| -> Result<(), Box<dyn std::error::Error>> {
            for o in outputs {
                match o {
                    Output::Point(p) => output.write(&points_topic, &p, log_time_ns)?,
                    Output::Dwell(d) => output.write(&dwells_topic, &d, log_time_ns)?,
                    Output::Warmup(w) => output.write(&warmup_topic, &w, log_time_ns)?,
                    Output::Pose(reg, stamp) => {
                        output.write(
                            "/tf_static",
                            &messages::tf_static(&reg, stamp, &machine_frame, &tracker_frame),
                            log_time_ns,
                        )?;
                        output.write(
                            &pose_topic,
                            &messages::pose_with_covariance(&reg, stamp, &machine_frame),
                            log_time_ns,
                        )?;
                    }
                    Output::Warning(w) => node.logger().warn(w),
                }
            }
            Ok(())
        };
    // An imported CSV row is several messages at one log time, the point first: the point waits
    // until the row's joints and air have been taken.
    let mut row_point: Option<(MeasuredPoint, u64)> = None;
    // SIGINT/SIGTERM stop it between messages, and the output below is still finished
    let mut last_log_time = 0u64;
    let stopped = source.replay::<Box<dyn std::error::Error>>(
        || node.interrupted(),
        |m| {
            last_log_time = m.log_time_ns;
            if let Some((p, t)) = row_point.take_if(|(_, t)| *t != m.log_time_ns) {
                write(state.imported_point(&p), t)?;
            }
            if inputs.csv && m.topic == inputs.readings {
                match m.decode::<MeasuredPoint>() {
                    Ok(p) => row_point = Some((p, m.log_time_ns)),
                    Err(e) => node.logger().warn(format!(
                        "skipped {} at log time {} ns: {e}",
                        m.topic, m.log_time_ns
                    )),
                }
                return Ok(());
            }
            match input(&mut state, &inputs, &m) {
                Ok(o) => write(o, m.log_time_ns),
                Err(e) => {
                    // a malformed message is reported and skipped; the replay goes on
                    node.logger().warn(format!(
                        "skipped {} at log time {} ns: {e}",
                        m.topic, m.log_time_ns
                    ));
                    Ok(())
                }
            }
        },
    )?;
    if let Some((p, t)) = row_point.take() {
        write(state.imported_point(&p), t)?;
    }
    // the end of the input closes the open dwell (stamped at its last log time)
    if stopped.is_none() {
        write(state.finish(), last_log_time)?;
    }
    output.finish()?;
    if csv {
        let _ = std::fs::remove_dir_all(&scratch);
    }
    let summary = state
        .diagnostics()
        .into_iter()
        .map(|(k, v)| format!("{k}={v}"))
        .collect::<Vec<_>>()
        .join(", ");
    node.logger()
        .info(format!("replayed {}: {summary}", args.bag.display()));
    Ok(node.finish_replay(stopped)?)
}

fn input(
    state: &mut TrackerState,
    inputs: &Inputs,
    m: &SourcedMessage,
) -> Result<Vec<Output>, Box<dyn std::error::Error>> {
    Ok(if m.topic == inputs.readings {
        state.measurement(&m.decode::<TrackerMeasurement>()?)
    } else if m.topic == inputs.commanded {
        state.commanded(&m.decode::<JointState>()?)
    } else if !inputs.csv && m.topic == inputs.reregister {
        m.decode::<RosString>()?;
        state.reregister();
        Vec::new()
    } else if m.topic == inputs.air[0] {
        state.station_air(Some(m.decode::<Temperature>()?.temperature), None, None);
        Vec::new()
    } else if m.topic == inputs.air[1] {
        state.station_air(
            None,
            Some(m.decode::<FluidPressure>()?.fluid_pressure),
            None,
        );
        Vec::new()
    } else if m.topic == inputs.air[2] {
        state.station_air(
            None,
            None,
            Some(m.decode::<RelativeHumidity>()?.relative_humidity),
        );
        Vec::new()
    } else {
        Vec::new()
    })
}

/// A scratch directory for the imported CSV (removed after the replay).
fn scratch_dir() -> PathBuf {
    std::env::temp_dir().join(format!("metrocell-tracker-csv-{}", std::process::id()))
}
