//! Re-registration requested through the node's parameter service, over DDS: the twin's readings
//! and commanded states are fed to a live `metrocell-tracker` (as in `replay_equals_live`); once
//! the pose is registered from the first 4 targets, another participant sets `reregister` to
//! true through the real `rcl_interfaces/srv/SetParameters` service (what `ros2 param set
//! /tracker reregister true` sends). The node must fit the pose again from the next 4 targets:
//! a second pose on `tracker/pose` and `/tf_static`, `reregistrations` = 1 on `/diagnostics`,
//! the log line, and the parameter back at false (a second set to true is again a change). Each
//! of the two poses, fitted from different targets, lies within 3σ of its reported covariance of
//! the twin's true tracker pose (`sensors.tracker.pose` of the cell), in every translation and
//! rotation component.
//!
//! Run: `tests/isolated cargo test -p metrocell-tracker-node --test reregister_parameter`

use std::io::{BufRead, BufReader};
use std::process::{Command, Stdio};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::geometry_msgs::msg::PoseWithCovarianceStamped;
use metrocell_msgs::msg::TrackerMeasurement;
use metrocell_msgs::sensor_msgs::msg::JointState;
use metrocell_msgs::tf2_msgs::msg::TFMessage;
use metrocell_node::testing::{KillOnDrop, RemoteParameterClient};
use metrocell_node::{qos, MetrocellNode};
use nalgebra::{Matrix3, Quaternion, Rotation3, UnitQuaternion, Vector3};

mod common;
use common::{inputs, record_twin, wait_for_tracker, Input};

const ARGS: [&str; 5] = [
    "--ros-args",
    "-p",
    "tool_offset:=[0.0, 0.0, -0.1]",
    "-p",
    "registration_points:=4",
];

/// The tracker node's `reregistrations` counter in a /diagnostics message, if it is there.
fn reregistrations(d: &DiagnosticArray) -> Option<String> {
    d.status
        .iter()
        .filter(|s| s.name.contains("tracker"))
        .flat_map(|s| &s.values)
        .find(|kv| kv.key == "reregistrations")
        .map(|kv| kv.value.clone())
}

/// The pose's deviation from the truth, per component in units of its reported σ: (x, y, z)
/// translation, then the small rotation δθ with R = exp([δθ]×)·R_true (ROS covariance order).
fn deviation_in_sigma(
    p: &PoseWithCovarianceStamped,
    truth: (&Matrix3<f64>, &Vector3<f64>),
) -> [f64; 6] {
    let (position, o) = (&p.pose.pose.position, &p.pose.pose.orientation);
    let rotation = UnitQuaternion::from_quaternion(Quaternion::new(o.w, o.x, o.y, o.z));
    let true_rotation = Rotation3::from_matrix_unchecked(*truth.0);
    let turned = (rotation.to_rotation_matrix() * true_rotation.inverse()).scaled_axis();
    let off = [
        position.x - truth.1.x,
        position.y - truth.1.y,
        position.z - truth.1.z,
        turned.x,
        turned.y,
        turned.z,
    ];
    std::array::from_fn(|i| off[i] / p.pose.covariance[7 * i].sqrt())
}

#[test]
fn setting_the_reregister_parameter_through_the_service_fits_the_pose_again() {
    metrocell_node::testing::require_isolated_network();
    let tmp = std::env::temp_dir().join(format!(
        "metrocell-tracker-reregister-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let input = tmp.join("input");
    let cell = record_twin(&input);
    let true_pose = &cell.tracker.as_ref().expect("the cell has a tracker").pose;
    let inputs = inputs(&input);

    let mut child = Command::new(env!("CARGO_BIN_EXE_metrocell-tracker"))
        .args(ARGS)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let log = Arc::new(Mutex::new(String::new()));
    let stderr = child.stderr.take().unwrap();
    let log_writer = Arc::clone(&log);
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let mut l = log_writer.lock().unwrap();
            l.push_str(&line);
            l.push('\n');
        }
    });
    let _node = KillOnDrop(child);

    let mut peer = MetrocellNode::builder("tracker_test_peer")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let readings = peer
        .publisher::<TrackerMeasurement>("/tracker/measurements", qos::reliable())
        .unwrap();
    let commanded = peer
        .publisher::<JointState>("/machine/commanded_joint_states", qos::sensor_data())
        .unwrap();
    let pose_sub = peer
        .subscription::<PoseWithCovarianceStamped>("/tracker/pose", qos::latched())
        .unwrap();
    let tf_sub = peer
        .subscription::<TFMessage>("/tf_static", qos::latched())
        .unwrap();
    let diag_sub = peer
        .subscription::<DiagnosticArray>("/diagnostics", qos::reliable())
        .unwrap();
    wait_for_tracker(&peer);

    let (mut poses, mut tfs, mut counter) = (Vec::new(), 0usize, None);
    let collect = |poses: &mut Vec<PoseWithCovarianceStamped>,
                   tfs: &mut usize,
                   counter: &mut Option<String>| {
        while let Ok(Some((p, _))) = pose_sub.take() {
            poses.push(p);
        }
        while let Ok(Some(_)) = tf_sub.take() {
            *tfs += 1;
        }
        while let Ok(Some((d, _))) = diag_sub.take() {
            if let Some(c) = reregistrations(&d) {
                *counter = Some(c);
            }
        }
    };
    // one client for both requests (crates/node testing.rs: a fresh client per request races
    // the service's discovery of its answer reader)
    let mut parameters = RemoteParameterClient::new(&mut peer, "/tracker")
        .expect("a client of /tracker/set_parameters");
    let mut set_at = None;
    for (k, i) in inputs.iter().enumerate() {
        match i {
            Input::Reading(m) => {
                let _ = readings.publish(m.clone());
            }
            Input::Commanded(j) => {
                let _ = commanded.publish(j.clone());
            }
        }
        std::thread::sleep(Duration::from_millis(3));
        collect(&mut poses, &mut tfs, &mut counter);
        if set_at.is_none() && !poses.is_empty() {
            // registered from the first 4 targets: the tracker "was moved"
            parameters
                .set(
                    &mut peer,
                    "reregister",
                    true.into(),
                    Duration::from_secs(20),
                )
                .expect("set reregister through the service");
            set_at = Some(k);
        }
    }
    let set_at = set_at.expect("no pose registered from the first targets");
    eprintln!(
        "first pose after input {set_at} of {}; reregister set through the service",
        inputs.len()
    );
    let deadline = Instant::now() + Duration::from_secs(10);
    while (poses.len() < 2 || counter.as_deref() != Some("1")) && Instant::now() < deadline {
        collect(&mut poses, &mut tfs, &mut counter);
        std::thread::sleep(Duration::from_millis(20));
    }
    let log_text = log.lock().unwrap().clone();
    assert_eq!(
        poses.len(),
        2,
        "a second pose after the re-registration; log:\n{log_text}"
    );
    assert_eq!(tfs, 2, "and a second /tf_static");
    assert!(poses[1].header.stamp.nanos() > poses[0].header.stamp.nanos());
    // the tracker did not move: both fits, from different targets, find the true pose
    for (k, pose) in poses.iter().enumerate() {
        let z = deviation_in_sigma(pose, (&true_pose.rotation, &true_pose.translation));
        let p = &pose.pose.pose.position;
        eprintln!(
            "pose {k}: ({:.6}, {:.6}, {:.6}) m; off the truth in σ (x y z, rot x y z): {z:.2?}",
            p.x, p.y, p.z
        );
        assert!(
            z.iter().all(|z| z.abs() <= 3.0),
            "pose {k} is more than 3σ off the twin's tracker pose: {z:?} σ ({pose:?})"
        );
    }
    assert_eq!(
        counter.as_deref(),
        Some("1"),
        "/diagnostics reregistrations"
    );
    assert!(
        log_text.contains("re-registering the tracker pose (parameter reregister set true)"),
        "{log_text}"
    );
    // the node reset the parameter: setting it true again is a change, and is acted on again
    let deadline = Instant::now() + Duration::from_secs(10);
    parameters
        .set(
            &mut peer,
            "reregister",
            true.into(),
            Duration::from_secs(20),
        )
        .unwrap();
    while counter.as_deref() != Some("2") && Instant::now() < deadline {
        collect(&mut poses, &mut tfs, &mut counter);
        std::thread::sleep(Duration::from_millis(20));
    }
    assert_eq!(
        counter.as_deref(),
        Some("2"),
        "a second request after the reset is acted on"
    );
    let _ = std::fs::remove_dir_all(&tmp);
}
