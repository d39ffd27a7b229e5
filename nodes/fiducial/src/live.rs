//! The node on live DDS. Only the newest frame matters for a live detector: older queued frames
//! are counted as dropped.

use std::time::{Duration, Instant};

use metrocell_fiducial_node::processing::FiducialProcessor;
use metrocell_msgs::geometry_msgs::msg::PoseWithCovarianceStamped;
use metrocell_msgs::msg::FiducialDetectionArray;
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image};
use metrocell_node::{qos, MetrocellNode};

pub fn run(mut node: MetrocellNode) -> Result<(), Box<dyn std::error::Error>> {
    let mut processor = FiducialProcessor::from_parameters(node.parameters())?;
    node.info(processor.describe());

    let images = node.subscription::<Image>("image", qos::sensor_data())?;
    let infos = node.subscription::<CameraInfo>("camera_info", qos::sensor_data())?;
    let detections = node.publisher::<FiducialDetectionArray>("fiducials", qos::reliable())?;
    let poses = node.publisher::<PoseWithCovarianceStamped>("fiducials/pose", qos::reliable())?;

    let diagnostics = node.diagnostics();
    let token = node.shutdown_token();
    let mut latency_sum = 0.0;
    let mut processed = 0u64;
    while !token.is_triggered() {
        while let Ok(Some((info, _))) = infos.take() {
            match processor.camera_info(&info) {
                Ok(Some(warning)) => node.warn(warning),
                Ok(None) => {}
                Err(e) => {
                    diagnostics.add_count("bad_camera_info", 1);
                    node.warn(format!("camera_info ignored: {e}"));
                }
            }
        }
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
        let out = match processor.frame(&img) {
            Ok(o) => o,
            Err(e) => {
                diagnostics.add_count("frames_rejected", 1);
                node.warn(e);
                continue;
            }
        };
        let targets = out.detections.detections.len();
        let _ = detections.publish(out.detections);
        for p in out.poses {
            let _ = poses.publish(p);
        }
        let latency = start.elapsed().as_secs_f64();
        processed += 1;
        latency_sum += latency;
        diagnostics.add_count("frames_processed", 1);
        diagnostics.add_count("targets_detected", targets as u64);
        if targets == 0 {
            diagnostics.add_count("frames_without_targets", 1);
        }
        diagnostics.set_value("last_detection_latency_ms", format!("{:.2}", latency * 1e3));
        diagnostics.set_value(
            "mean_detection_latency_ms",
            format!("{:.2}", latency_sum / processed as f64 * 1e3),
        );
        diagnostics.ok(format!("{targets} targets in the last frame"));
    }
    Ok(())
}
