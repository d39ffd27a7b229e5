//! The merged message stream of the quick demo cell: time order, /clock ticks first at equal
//! times, one topic per sensor, and what each twin sample turns into.

use std::path::Path;

use metrocell_simulation::sim_time::{parse_start_time, DEFAULT_START_TIME};
use metrocell_simulation::{
    CameraIntrinsics, MessageConverter, MessageStream, TopicRole, TypedMessage,
};
use metrocell_twin::{Cell, Sample, Simulation};

fn demo() -> Cell {
    Cell::from_path(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/examples/cells/quick_demo.yaml"),
    )
    .unwrap()
}

#[test]
fn topic_map_of_the_demo_cell() {
    let c = MessageConverter::new(&demo(), 0, CameraIntrinsics::default()).unwrap();
    let names: Vec<&str> = c.topics.topics.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "/clock",
            "/machine/joint_states",
            "/machine/commanded_joint_states",
            "/temperature/x_left",
            "/temperature/x_right",
            "/tracker/measurements",
            "/tracker/power_on",
            "/probe/hits",
            "/camera/camera_info",
            "/camera/image_raw"
        ]
    );
    assert_eq!(
        c.topics.get(c.topics.temperature("x_right").unwrap()).role,
        TopicRole::Temperature("x_right".into())
    );
    assert_eq!(
        c.topics.get(c.topics.tracker.unwrap()).ros_type,
        "metrocell_msgs/msg/TrackerMeasurement"
    );
}

#[test]
fn stream_is_time_ordered_with_clock_ticks_first() {
    let start = parse_start_time(DEFAULT_START_TIME).unwrap();
    let conv = MessageConverter::new(&demo(), start, CameraIntrinsics::default()).unwrap();
    let sim = Simulation::new(demo(), 20.0, 5).unwrap();
    let msgs: Vec<_> = MessageStream::new(&sim, &conv, Some(0.5)).collect();
    assert!(msgs.windows(2).all(|w| w[0].t <= w[1].t));
    assert!(msgs
        .iter()
        .all(|m| m.stamp_ns == start + (m.t * 1e9).round() as u64));
    let clocks: Vec<f64> = msgs
        .iter()
        .filter(|m| m.topic == conv.topics.clock)
        .map(|m| m.t)
        .collect();
    assert_eq!(clocks.len(), 40);
    assert_eq!(clocks[3], 1.5);
    // At t = 1 s: the clock tick precedes the thermocouple and joint-state samples of that instant.
    let first_at_1 = msgs.iter().position(|m| m.t == 1.0).unwrap();
    assert_eq!(msgs[first_at_1].topic, conv.topics.clock);
    // Every machine-state sample gives actual then commanded.
    let (actual, commanded) = conv.topics.joint_states.unwrap();
    for (i, m) in msgs.iter().enumerate() {
        if m.topic == actual {
            assert_eq!(msgs[i + 1].topic, commanded);
            assert_eq!(msgs[i + 1].t, m.t);
        }
    }
    // Without ticks the stream is exactly the cell's states at t = 0 (here the tracker's
    // power-on time) then the converted samples.
    let plain: Vec<_> = MessageStream::new(&sim, &conv, None).collect();
    let initial = conv.initial_messages();
    assert_eq!(initial.len(), 1, "the demo cell has a tracker and no load");
    let TypedMessage::PowerOn(on) = &initial[0].message else {
        panic!("{:?}", initial[0])
    };
    let before = sim.cell().tracker.as_ref().unwrap().powered_on_before_start;
    assert_eq!(
        on.time_ref.nanos(),
        start as i64 - (before * 1e9).round() as i64
    );
    assert_eq!(
        (initial[0].t, initial[0].topic),
        (0.0, conv.topics.power_on.unwrap())
    );
    let direct: Vec<_> = initial
        .into_iter()
        .chain(sim.samples().flat_map(|s| conv.convert(&s)))
        .collect();
    assert_eq!(plain, direct);
    assert_eq!(plain.len() + 40, msgs.len());
}

#[test]
fn each_sample_kind_maps_to_its_topic_and_type() {
    let conv = MessageConverter::new(&demo(), 0, CameraIntrinsics::default()).unwrap();
    let sim = Simulation::new(demo(), 40.0, 5).unwrap();
    let mut seen = [false; 5];
    for s in sim.samples() {
        let out = conv.convert(&s);
        match &s {
            Sample::Tracker(_) => {
                seen[0] = true;
                assert!(
                    matches!(out[..], [ref m] if m.topic == conv.topics.tracker.unwrap() && matches!(m.message, TypedMessage::Tracker(_)))
                );
            }
            Sample::Temperature(t) => {
                seen[1] = true;
                assert!(
                    matches!(&out[..], [m] if m.topic == conv.topics.temperature(&t.sensor).unwrap())
                );
                assert_eq!(out[0].message.ros_type(), "sensor_msgs/msg/Temperature");
            }
            Sample::MachineState(_) => {
                seen[2] = true;
                assert_eq!(out.len(), 2);
            }
            Sample::ProbeHit(_) => {
                seen[3] = true;
                assert!(matches!(&out[..], [m] if matches!(m.message, TypedMessage::Probe(_))));
            }
            Sample::CameraFrameRequest(_) => {
                seen[4] = true;
                assert!(
                    matches!(&out[..], [m] if m.message.ros_type() == "sensor_msgs/msg/CameraInfo")
                );
            }
            Sample::StationPoint(_) | Sample::Acceleration(_) => {
                panic!("the demo cell has no stationing program")
            }
        }
        for m in &out {
            let bytes = m.message.encode().unwrap();
            assert_eq!(&bytes[..4], &[0, 1, 0, 0]);
            // The dynamic codec (built from the .msg text) accepts every byte of it.
            let v =
                rosmsg::decode(metrocell_msgs::registry(), m.message.ros_type(), &bytes).unwrap();
            assert_eq!(
                rosmsg::encode(metrocell_msgs::registry(), m.message.ros_type(), &v).unwrap(),
                bytes
            );
        }
    }
    assert_eq!(seen, [true; 5]);
}

#[test]
fn beam_breaks_are_flagged_with_nan_points_and_keep_air_data() {
    let mut cell = demo();
    // One break every 20 s on average, 2 s long: about 10 % of the samples.
    cell.tracker.as_mut().unwrap().beam_breaks = Some(metrocell_twin::cell::BeamBreakSpec {
        rate: 0.05,
        mean_duration: 2.0,
    });
    let conv = MessageConverter::new(&cell, 0, CameraIntrinsics::default()).unwrap();
    let sim = Simulation::new(cell, 180.0, 8).unwrap();
    let (mut ok, mut broken) = (0, 0);
    for m in MessageStream::new(&sim, &conv, None) {
        if let TypedMessage::Tracker(t) = m.message {
            if t.status == metrocell_msgs::msg::TrackerMeasurement::STATUS_BEAM_BREAK {
                broken += 1;
                assert!(
                    t.point.x.is_nan()
                        && t.range.is_nan()
                        && t.covariance.iter().all(|c| c.is_nan())
                );
                assert!(
                    t.air_temperature.is_finite()
                        && t.air_pressure > 100_000.0
                        && t.refractive_index > 1.0
                );
            } else {
                assert_eq!(t.status, 0);
                assert!(t.point.x.is_finite());
                ok += 1;
            }
        }
    }
    assert_eq!(ok + broken, 1800);
    assert!(
        broken > 0 && broken < 600,
        "{broken} of 1800 samples beam-broken"
    );
}

fn mobile_manipulator(tilt: Option<[f64; 2]>) -> Cell {
    metrocell_simulation::cell_options::load_cell(
        &Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../twin/examples/cells/mobile_manipulator.yaml"),
        tilt,
    )
    .unwrap()
}

/// A stationing program writes `bag import`'s layout: per waypoint the joint states, the point on
/// /measured_points (fit) or /check_points (check) in `total_station@<setup>`, /imu/<sensor> in
/// the sensor's link, the temperature — one stamp.
#[test]
fn a_stationing_program_writes_the_import_layout() {
    let cell = mobile_manipulator(Some([0.0, 0.015]));
    let conv = MessageConverter::new(&cell, 0, CameraIntrinsics::default()).unwrap();
    let names: Vec<&str> = conv.topics.topics.iter().map(|t| t.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "/clock",
            "/machine/joint_states",
            "/machine/commanded_joint_states",
            "/temperature/ambient",
            "/measured_points",
            "/check_points",
            "/imu/base",
            "/imu/tip"
        ]
    );
    assert_eq!(
        conv.topics.get(conv.topics.imu("tip").unwrap()).role,
        TopicRole::Imu("tip".into())
    );
    let duration = cell.natural_duration().unwrap();
    let sim = Simulation::new(cell, duration, 3).unwrap();
    let msgs: Vec<_> = MessageStream::new(&sim, &conv, None).collect();
    let on = |topic: &str| {
        msgs.iter()
            .filter(|m| conv.topics.get(m.topic).name == topic)
            .collect::<Vec<_>>()
    };
    let (fit, check) = (on("/measured_points"), on("/check_points"));
    assert_eq!((fit.len(), check.len()), (12 * 8, 12 * 30));
    for m in fit.iter().chain(&check) {
        let TypedMessage::Point(p) = &m.message else {
            panic!("{m:?}")
        };
        assert!(
            ["total_station@S1", "total_station@S2", "total_station@S3"]
                .contains(&p.header.frame_id.as_str()),
            "{}",
            p.header.frame_id
        );
        assert!(p.point_id.starts_with('G') && p.covariance[0] > 0.0);
        // its row: the commanded joints and both accelerometers at the same stamp
        let row: Vec<&str> = msgs
            .iter()
            .filter(|o| o.stamp_ns == m.stamp_ns)
            .map(|o| conv.topics.get(o.topic).name.as_str())
            .collect();
        assert_eq!(row.len(), 6, "{row:?}");
        assert!(
            row.contains(&"/machine/commanded_joint_states")
                && row.contains(&"/imu/base")
                && row.contains(&"/imu/tip"),
            "{row:?}"
        );
    }
    let TypedMessage::Imu(base) = &on("/imu/base")[0].message else {
        panic!()
    };
    assert_eq!(
        (
            base.header.frame_id.as_str(),
            base.orientation_covariance[0]
        ),
        ("base_imu", -1.0)
    );
    // 15 mrad nose down: the specific force leans to −x in the base (the sensor is not turned)
    assert!(
        (base.linear_acceleration.x + 9.80665 * 0.015).abs() < 0.06,
        "{:?}",
        base.linear_acceleration
    );
    // another ground, the same plan: the same joints, other points
    let flat = mobile_manipulator(None);
    let sim_flat = Simulation::new(flat, duration, 3).unwrap();
    let flat_msgs: Vec<_> = MessageStream::new(&sim_flat, &conv, None).collect();
    assert_eq!(flat_msgs.len(), msgs.len());
    let joints = |v: &[metrocell_simulation::SimMessage]| {
        v.iter()
            .filter_map(|m| {
                if let TypedMessage::JointState(j) = &m.message {
                    Some(j.position.clone())
                } else {
                    None
                }
            })
            .collect::<Vec<_>>()
    };
    assert_eq!(joints(&flat_msgs), joints(&msgs));
    assert_ne!(flat_msgs, msgs);
}
