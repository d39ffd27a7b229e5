//! `metrocell-fiducial`: detects fiducials in camera frames.
//!
//! Subscribes `image` (sensor_msgs/Image: mono8, mono16, rgb8, bgr8, rgba8, bgra8) and `camera_info`
//! (sensor_msgs/CameraInfo); publishes `fiducials` (metrocell_msgs/FiducialDetectionArray, header =
//! the image's) and `fiducials/pose` (geometry_msgs/PoseWithCovarianceStamped, one per target with a
//! pose; frame_id = the image's). Poses need camera_info and, for markers, `marker_size`.
//! A bad frame is a warning naming the problem; the node keeps running.
//!
//!   metrocell-fiducial --ros-args -p family:=DICT_4X4_50 -p marker_size:=0.02
//!   metrocell-fiducial --ros-args -p family:=checkerboard -p board_cols:=9 -p board_rows:=6 -p square_size:=0.01

use std::time::{Duration, Instant};

use metrocell_fiducial_node::{camera_info_msg, detection_msgs, frame};
use metrocell_msgs::geometry_msgs::msg::PoseWithCovarianceStamped;
use metrocell_msgs::msg::FiducialDetectionArray;
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image};
use metrocell_node::{qos, MetrocellNode, ParamDecl};
use metrocell_vision::aruco::DetectorParams;
use metrocell_vision::{detect_targets, PoseInputs, TargetFamily};

fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new("family", "DICT_4X4_50".to_string(), "OpenCV dictionary name (DICT_4X4_50, DICT_APRILTAG_36h11, ...) or checkerboard"),
        ParamDecl::new("marker_size", 0.0, "marker side [m] for marker poses; 0 = no marker pose").with_range(0.0, 10.0),
        ParamDecl::new("board_cols", 9i64, "checkerboard inner corners along a row"),
        ParamDecl::new("board_rows", 6i64, "checkerboard inner corners along a column"),
        ParamDecl::new("square_size", 0.01, "checkerboard square side [m]").with_range(0.0, 10.0),
        ParamDecl::new("corner_sigma_px", 0.1, "corner σ [px] where a corner has no covariance").with_range(1e-6, 100.0),
        ParamDecl::new("threads", 0i64, "detector worker threads; 0 = all cores"),
    ]
}

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-fiducial: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (mut node, _) = MetrocellNode::from_env_args("fiducial", declarations())?;
    let board = (node.param::<i64>("board_cols")?.max(0) as usize, node.param::<i64>("board_rows")?.max(0) as usize);
    let family = TargetFamily::parse(&node.param::<String>("family")?, Some(board), Some(node.param::<f64>("square_size")?))?;
    let marker_size = Some(node.param::<f64>("marker_size")?).filter(|s| *s > 0.0);
    let sigma = node.param::<f64>("corner_sigma_px")?;
    let params = DetectorParams { threads: node.param::<i64>("threads")?.max(0) as usize, ..Default::default() };
    let family_name = family.message_name();
    node.info(format!("detecting {family_name}, marker_size {marker_size:?} m"));

    let images = node.subscription::<Image>("image", qos::sensor_data())?;
    let infos = node.subscription::<CameraInfo>("camera_info", qos::sensor_data())?;
    let detections = node.publisher::<FiducialDetectionArray>("fiducials", qos::reliable())?;
    let poses = node.publisher::<PoseWithCovarianceStamped>("fiducials/pose", qos::reliable())?;

    let diagnostics = node.diagnostics();
    let token = node.shutdown_token();
    let mut camera = None;
    let mut latency_sum = 0.0;
    let mut processed = 0u64;
    while !token.is_triggered() {
        while let Ok(Some((info, _))) = infos.take() {
            match camera_info_msg::camera_model_from_msg(&info) {
                Ok(c) => camera = Some(c),
                Err(e) => {
                    diagnostics.add_count("bad_camera_info", 1);
                    node.warn(format!("camera_info ignored: {e}"));
                }
            }
        }
        // Only the newest frame matters for a live detector; older queued frames are counted as dropped.
        let mut newest = None;
        while let Ok(Some((img, _))) = images.take() {
            if newest.replace(img).is_some() {
                diagnostics.add_count("frames_dropped", 1);
            }
        }
        let Some(img) = newest else {
            token.wait_timeout(Duration::from_millis(1));
            continue;
        };
        let start = Instant::now();
        let stamp = format!("{}.{:09}", img.header.stamp.sec, img.header.stamp.nanosec);
        let gray = match frame::gray_from_image(&img) {
            Ok(g) => g,
            Err(e) => {
                diagnostics.add_count("frames_rejected", 1);
                node.warn(format!("frame {stamp} ({}): {e}", img.header.frame_id));
                continue;
            }
        };
        let pose_inputs = camera
            .as_ref()
            .filter(|c| c.width == gray.width() && c.height == gray.height())
            .map(|c| PoseInputs { camera: c, marker_side: marker_size, fallback_sigma_px: sigma });
        let targets = match detect_targets(&gray, &family, &params, pose_inputs) {
            Ok(t) => t,
            Err(e) => {
                diagnostics.add_count("frames_rejected", 1);
                node.warn(format!("frame {stamp}: {e}"));
                continue;
            }
        };
        let _ = detections.publish(detection_msgs::detection_array(&img.header, img.width, img.height, &family_name, &targets));
        for p in detection_msgs::pose_messages(&img.header, &targets) {
            let _ = poses.publish(p);
        }
        let latency = start.elapsed().as_secs_f64();
        processed += 1;
        latency_sum += latency;
        diagnostics.add_count("frames_processed", 1);
        diagnostics.add_count("targets_detected", targets.len() as u64);
        if targets.is_empty() {
            diagnostics.add_count("frames_without_targets", 1);
        }
        diagnostics.set_value("last_detection_latency_ms", format!("{:.2}", latency * 1e3));
        diagnostics.set_value("mean_detection_latency_ms", format!("{:.2}", latency_sum / processed as f64 * 1e3));
        diagnostics.ok(format!("{} targets in the last frame", targets.len()));
    }
    Ok(())
}
