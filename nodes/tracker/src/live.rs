//! The node on live DDS (backend topic or tcp).

use std::time::Duration;

use metrocell_laser_tracker::tcp_client::{
    DriverEvent, LineFormat, TcpClientConfig, TcpTrackerClient,
};
use metrocell_laser_tracker::total_station_gsi::{block_to_point, GsiBlock};
use metrocell_msgs::geometry_msgs::msg::PoseWithCovarianceStamped;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint, TrackerMeasurement};
use metrocell_msgs::sensor_msgs::msg::{FluidPressure, JointState, RelativeHumidity, Temperature};
use metrocell_msgs::std_msgs::msg::String as RosString;
use metrocell_msgs::tf2_msgs::msg::TFMessage;
use metrocell_node::{qos, MetrocellNode};
use metrocell_tracker_node::messages;
use metrocell_tracker_node::parameters::{self, TrackerConfig};
use metrocell_tracker_node::tracker_state::{Output, TrackerState};

pub fn run(mut node: MetrocellNode) -> Result<(), Box<dyn std::error::Error>> {
    let config = TrackerConfig::from_parameters(node.parameters())?;
    node.info(config.describe());
    let backend = node.param::<String>("backend")?;
    if config.total_station.is_some() && backend != "tcp" {
        return Err(format!("parameter {}:={}: a total station streams GSI blocks over TCP; set -p backend:=tcp -p tcp_address:=HOST:PORT (the topic backend reads tracker/measurements, which this instrument publishes)", parameters::INSTRUMENT, parameters::TOTAL_STATION_GSI).into());
    }
    let format = if config.total_station.is_some() {
        LineFormat::LeicaGsi
    } else {
        LineFormat::TrackerCsv
    };
    let mut state = TrackerState::new(config);
    let tcp = match backend.as_str() {
        "tcp" => Some(TcpTrackerClient::start_with(
            TcpClientConfig {
                address: node.param("tcp_address")?,
                initial_backoff: Duration::from_secs_f64(node.param("tcp_initial_backoff")?),
                max_backoff: Duration::from_secs_f64(node.param("tcp_max_backoff")?),
            },
            format,
        )),
        _ => None,
    };
    // a total station is a driver: its readings go out on tracker/measurements as they come
    let readings_out = match format {
        LineFormat::LeicaGsi => Some(node.publisher::<TrackerMeasurement>(
            "tracker/measurements",
            qos::stream(qos::reliable()),
        )?),
        LineFormat::TrackerCsv => None,
    };
    let measurements = match tcp {
        None => Some(node.subscription::<TrackerMeasurement>(
            "tracker/measurements",
            qos::stream(qos::reliable()),
        )?),
        Some(_) => None,
    };
    let weather = if state.config().air_from_topics {
        Some((
            node.subscription::<Temperature>("weather/temperature", qos::reliable())?,
            node.subscription::<FluidPressure>("weather/pressure", qos::reliable())?,
            node.subscription::<RelativeHumidity>("weather/humidity", qos::reliable())?,
        ))
    } else {
        None
    };
    // best effort matches any publisher; reliable lets DDS repair a network glitch (the
    // commanded positions of a pulled cable's seconds arrive late instead of never)
    let commanded = node.subscription::<JointState>(
        "machine/commanded_joint_states",
        qos::stream(if state.config().commanded_reliable {
            qos::reliable()
        } else {
            qos::sensor_data()
        }),
    )?;
    let reregister = node.subscription::<RosString>("tracker/reregister", qos::reliable())?;
    let points =
        node.publisher::<MeasuredPoint>("measured_points", qos::stream(qos::reliable()))?;
    let dwells = node.publisher::<TrackerMeasurement>("tracker/dwells", qos::reliable())?;
    let warmup = node.publisher::<ErrorModel>("tracker/warmup", qos::latched())?;
    let tf_static = node.publisher::<TFMessage>("/tf_static", qos::latched())?;
    let pose = node.publisher::<PoseWithCovarianceStamped>("tracker/pose", qos::latched())?;
    let (machine_frame, tracker_frame) = (
        state.config().machine_frame.clone(),
        state.config().tracker_frame.clone(),
    );

    let diagnostics = node.diagnostics();
    // the readings (when they come on a topic) and the machine's commanded positions
    let commanded_topic = node
        .watch_inputs(["machine/commanded_joint_states"])?
        .remove(0);
    let readings_topic = match &measurements {
        Some(_) => node.watch_inputs(["tracker/measurements"])?.remove(0),
        None => String::new(),
    };
    let mut reregister_param = node.watch_param::<bool>(parameters::REREGISTER)?;
    let token = node.shutdown_token();
    let mut outputs = Vec::new();
    while !token.is_triggered() {
        if let Some((t, p, h)) = &weather {
            while let Ok(Some((m, _))) = t.take() {
                state.station_air(Some(m.temperature), None, None);
            }
            while let Ok(Some((m, _))) = p.take() {
                state.station_air(None, Some(m.fluid_pressure), None);
            }
            while let Ok(Some((m, _))) = h.take() {
                state.station_air(None, None, Some(m.relative_humidity));
            }
        }
        while let Ok(Some((j, _))) = commanded.take() {
            diagnostics.input_seen(&commanded_topic);
            outputs.extend(state.commanded(&j));
        }
        if let Some(sub) = &measurements {
            while let Ok(Some((m, _))) = sub.take() {
                diagnostics.input_seen(&readings_topic);
                outputs.extend(state.measurement(&m));
            }
        }
        if let Some(client) = &tcp {
            while let Some(event) = client.try_next() {
                match event {
                    DriverEvent::Reading(l) => outputs.extend(state.line(&l)),
                    DriverEvent::TotalStation { received_ns, block } => {
                        match total_station_reading(&state, received_ns, &block) {
                            Ok(m) => {
                                diagnostics.add_count("total_station_readings", 1);
                                if let Some(p) = &readings_out {
                                    let _ = p.publish(m);
                                }
                            }
                            Err(e) => {
                                diagnostics.add_count("total_station_rejected", 1);
                                node.warn(format!(
                                    "total station: block of point '{}' rejected: {e}",
                                    block.point_id.as_deref().unwrap_or("")
                                ));
                            }
                        }
                    }
                    DriverEvent::Connected(a) => node.info(format!(
                        "connected to the {} at {a}",
                        if readings_out.is_some() {
                            "total station"
                        } else {
                            "tracker"
                        }
                    )),
                    DriverEvent::Disconnected { reason, retry_in } => {
                        diagnostics.add_count("tcp_disconnects", 1);
                        diagnostics
                            .warn(format!("tracker link: {reason}; retrying in {retry_in:?}"));
                    }
                    DriverEvent::Garbage(e) => {
                        diagnostics.add_count("tcp_garbage_lines", 1);
                        node.warn(format!(
                            "{} link: {e}",
                            if readings_out.is_some() {
                                "total station"
                            } else {
                                "tracker"
                            }
                        ));
                    }
                    DriverEvent::Repeat(_) => {
                        diagnostics.add_count("tcp_repeated_readings", 1);
                    }
                }
            }
        }
        while let Ok(Some((why, _))) = reregister.take() {
            node.info(format!(
                "re-registering the tracker pose (tracker/reregister): {}",
                why.data
            ));
            state.reregister();
            diagnostics.add_count("reregistrations", 1);
        }
        // `ros2 param set /tracker reregister true`: the same, then the parameter is reset
        match reregister_param.poll(|n| node.param(n)) {
            Ok(Some(true)) => {
                node.info(format!("re-registering the tracker pose (parameter {} set true); collecting {} targets", parameters::REREGISTER, state.config().registration_points));
                state.reregister();
                diagnostics.add_count("reregistrations", 1);
                if let Err(e) = node.set_param(parameters::REREGISTER, false) {
                    node.warn(format!(
                        "could not reset parameter {} to false: {e}",
                        parameters::REREGISTER
                    ));
                }
                reregister_param.update(false);
            }
            Ok(_) => {}
            Err(e) => node.warn(format!("parameter {}: {e}", parameters::REREGISTER)),
        }
        for o in outputs.drain(..) {
            match o {
                Output::Point(p) => {
                    let _ = points.publish(p);
                }
                Output::Dwell(d) => {
                    let _ = dwells.publish(d);
                }
                Output::Warmup(w) => {
                    let _ = warmup.publish(w);
                }
                Output::Pose(reg, stamp) => {
                    node.info(format!(
                        "tracker registered: rms {:.1} µm, χ²/dof {:.2}",
                        reg.rms * 1e6,
                        reg.chi2 / reg.dof.max(1) as f64
                    ));
                    diagnostics.ok("tracker registered");
                    let _ = tf_static.publish(messages::tf_static(
                        &reg,
                        stamp,
                        &machine_frame,
                        &tracker_frame,
                    ));
                    let _ =
                        pose.publish(messages::pose_with_covariance(&reg, stamp, &machine_frame));
                }
                Output::Warning(w) => {
                    diagnostics.warn(&w);
                    node.warn(w);
                }
            }
        }
        for (k, v) in state.diagnostics() {
            diagnostics.set_value(&k, v);
        }
        token.wait_timeout(Duration::from_millis(2));
    }
    // shutting down closes the open dwell, as the end of a bag does in a replay
    for o in state.finish() {
        match o {
            Output::Point(p) => {
                let _ = points.publish(p);
            }
            Output::Dwell(d) => {
                let _ = dwells.publish(d);
            }
            Output::Warning(w) => node.warn(w),
            _ => {}
        }
    }
    Ok(())
}

/// A total station's block as the reading it publishes (stamped when its line arrived).
fn total_station_reading(
    state: &TrackerState,
    received_ns: i64,
    block: &GsiBlock,
) -> Result<TrackerMeasurement, String> {
    let config = state.config();
    let noise = config
        .total_station
        .as_ref()
        .ok_or("no total-station noise configured (parameter instrument)")?;
    let (id, p) = block_to_point(block, noise).map_err(|e| e.to_string())?;
    Ok(messages::total_station_measurement(
        &id,
        received_ns,
        &p,
        &config.tracker_frame,
    ))
}
