//! `metrocell-fiducial --bag` gives the same outputs as the live node over DDS. The input bag:
//! a CameraInfo, then 4 rendered frames of one 4x4_50 marker at different poses. Live, this test
//! plays the camera: it publishes each frame and waits for its detections before the next, so the
//! live node drops none. Detections and poses must be bit-identical, keyed by frame stamp.
//!
//! Run: `tests/isolated cargo test -p metrocell-fiducial-node --test replay_equals_live`

use std::collections::BTreeMap;
use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use metrocell_bag::{qos_profiles_yaml, BagWriter, QosProfile, WriterOptions};
use metrocell_bagtools::{encode_cdr, BagSource};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::PoseWithCovarianceStamped;
use metrocell_msgs::msg::FiducialDetectionArray;
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image};
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::testing::KillOnDrop as Killed;
use metrocell_node::{qos, MetrocellNode};
use metrocell_vision::aruco::Dictionary;
use metrocell_vision::{
    render_view, CameraModel, Distortion, PlanarTarget, RenderSettings, TargetItem,
};
use nalgebra::{Isometry3, Translation3, UnitQuaternion};
use rosmsg::RosMessage;

const T0: u64 = 1_700_000_000_000_000_000;
const MS: u64 = 1_000_000;
const W: u32 = 480;
const H: u32 = 360;

fn header(ns: u64) -> Header {
    Header {
        stamp: Time::from_nanos(ns as i64),
        frame_id: "cam_optical".into(),
    }
}

fn stamp_ns(h: &Header) -> u64 {
    h.stamp.nanos() as u64
}

fn camera() -> CameraModel {
    CameraModel::new(W, H, 600.0, 600.0, 239.5, 179.5, Distortion::none()).unwrap()
}

/// The calibration of the camera the frames are rendered with.
fn camera_info() -> CameraInfo {
    CameraInfo {
        header: header(T0),
        ..metrocell_camera_model::CameraInfo::from_model("cam", &camera()).to_msg()
    }
}

fn frames() -> Vec<Image> {
    let cam = camera();
    let target = PlanarTarget {
        items: vec![TargetItem::Marker {
            dictionary: Dictionary::predefined("DICT_4X4_50").unwrap(),
            id: 3,
            top_left: [0.0, 0.0],
            side: 0.04,
            border_bits: 1,
        }],
    };
    (0..4u64)
        .map(|k| {
            let kf = k as f64;
            let pose = Isometry3::from_parts(
                Translation3::new(-0.03 + 0.01 * kf, -0.02, 0.3 + 0.02 * kf),
                UnitQuaternion::from_euler_angles(0.1 * kf, -0.1, 0.05 * kf),
            );
            let settings = RenderSettings {
                noise_sigma: 1.0,
                seed: k,
                supersampling: 4,
                ..Default::default()
            };
            let view = render_view(&cam, &pose, &target, &settings).unwrap();
            Image {
                header: header(T0 + (k + 1) * 100 * MS),
                height: H,
                width: W,
                encoding: "mono8".into(),
                is_bigendian: 0,
                step: W,
                data: view.image.into_raw(),
            }
        })
        .collect()
}

fn write_input_bag(dir: &Path, info: &CameraInfo, frames: &[Image]) {
    let mut w = BagWriter::create(dir, WriterOptions::default()).unwrap();
    let qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
    w.add_topic(
        "/replay/camera_info",
        CameraInfo::ROS_TYPE,
        CameraInfo::DEFINITION,
        &qos,
    )
    .unwrap();
    w.add_topic("/replay/image", Image::ROS_TYPE, Image::DEFINITION, &qos)
        .unwrap();
    w.write("/replay/camera_info", T0, T0, &encode_cdr(info).unwrap())
        .unwrap();
    for f in frames {
        let t = stamp_ns(&f.header);
        w.write("/replay/image", t, t, &encode_cdr(f).unwrap())
            .unwrap();
    }
    w.finish().unwrap();
}

const ARGS: [&str; 7] = [
    "--ros-args",
    "-r",
    "__ns:=/replay",
    "-p",
    "family:=DICT_4X4_50",
    "-p",
    "marker_size:=0.04",
];

#[test]
fn replay_from_bag_equals_live_run_over_dds() {
    metrocell_node::testing::require_isolated_network();
    let tmp =
        std::env::temp_dir().join(format!("metrocell-fiducial-replay-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let (info, frames) = (camera_info(), frames());
    let input = tmp.join("input");
    write_input_bag(&input, &info, &frames);

    // --- live
    let _node = Killed(
        Command::new(env!("CARGO_BIN_EXE_metrocell-fiducial"))
            .args(ARGS)
            .stdout(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let mut camera = MetrocellNode::builder("replay_test_camera")
        .namespace("/replay")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let image_pub = camera
        .publisher::<Image>("image", qos::sensor_data())
        .unwrap();
    let info_pub = camera
        .publisher::<CameraInfo>("camera_info", qos::sensor_data())
        .unwrap();
    let det_sub = camera
        .subscription::<FiducialDetectionArray>("fiducials", qos::reliable())
        .unwrap();
    let pose_sub = camera
        .subscription::<PoseWithCovarianceStamped>("fiducials/pose", qos::reliable())
        .unwrap();
    let mut live: BTreeMap<u64, FiducialDetectionArray> = BTreeMap::new();
    let mut live_poses: BTreeMap<u64, PoseWithCovarianceStamped> = BTreeMap::new();
    let deadline = Instant::now() + Duration::from_secs(60);
    for f in &frames {
        let s = stamp_ns(&f.header);
        // Best-effort frames may be lost, and a frame that overtakes the first camera_info comes
        // back without a pose: resend until the answer has one.
        while !live
            .get(&s)
            .is_some_and(|d| d.detections.iter().all(|m| m.has_pose))
        {
            assert!(
                Instant::now() < deadline,
                "live node did not answer frame {s} within 60 s"
            );
            let _ = info_pub.publish(info.clone());
            std::thread::sleep(Duration::from_millis(20));
            let _ = image_pub.publish(f.clone());
            let wait = Instant::now() + Duration::from_millis(1500);
            while Instant::now() < wait && !live.contains_key(&s) {
                while let Ok(Some((d, _))) = det_sub.take() {
                    live.insert(stamp_ns(&d.header), d);
                }
                std::thread::sleep(Duration::from_millis(5));
            }
        }
    }
    std::thread::sleep(Duration::from_millis(300));
    while let Ok(Some((p, _))) = pose_sub.take() {
        live_poses.insert(stamp_ns(&p.header), p);
    }

    // --- offline
    let output = tmp.join("output");
    let status = Command::new(env!("CARGO_BIN_EXE_metrocell-fiducial"))
        .arg("--bag")
        .arg(&input)
        .arg("--output")
        .arg(&output)
        .args(ARGS)
        .status()
        .unwrap();
    assert!(
        status.success(),
        "metrocell-fiducial --bag failed: {status}"
    );
    let mut source = BagSource::open(&output).unwrap();
    source
        .subscribe::<FiducialDetectionArray>("/replay/fiducials")
        .unwrap();
    source
        .subscribe::<PoseWithCovarianceStamped>("/replay/fiducials/pose")
        .unwrap();
    let (mut replay, mut replay_poses) = (BTreeMap::new(), BTreeMap::new());
    for m in source.messages().unwrap() {
        let m = m.unwrap();
        if m.topic == "/replay/fiducials" {
            let d: FiducialDetectionArray = m.decode().unwrap();
            assert_eq!(
                m.log_time_ns,
                stamp_ns(&d.header),
                "written at the frame's log time"
            );
            replay.insert(stamp_ns(&d.header), d);
        } else {
            let p: PoseWithCovarianceStamped = m.decode().unwrap();
            replay_poses.insert(stamp_ns(&p.header), p);
        }
    }

    assert_eq!(
        replay.len(),
        frames.len(),
        "replay answered {:?}",
        replay.keys()
    );
    for (s, d) in &replay {
        assert_eq!(d.detections.len(), 1, "frame {s}");
        assert!(
            d.detections[0].has_pose && d.detections[0].id == 3,
            "frame {s}: {:?}",
            d.detections[0]
        );
        assert_eq!(
            live.get(s),
            Some(d),
            "frame {s}: live and replay detections differ"
        );
        assert_eq!(
            live_poses.get(s),
            replay_poses.get(s),
            "frame {s}: live and replay poses differ"
        );
    }
    assert_eq!(replay_poses.len(), frames.len());
    let _ = std::fs::remove_dir_all(&tmp);
}
