//! The node on a bag (`--bag IN_BAG`): no DDS. `image` and `camera_info` are read in log-time
//! order and every frame is processed (a live node drops frames it cannot keep up with; a replay
//! has the time). Outputs are written at the log time of their frame; their headers are the
//! frame's, as live.

use metrocell_bagtools::{BagSource, ReplayOutput};
use metrocell_fiducial_node::processing::FiducialProcessor;
use metrocell_msgs::geometry_msgs::msg::PoseWithCovarianceStamped;
use metrocell_msgs::msg::FiducialDetectionArray;
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image};
use metrocell_node::{OfflineNode, ReplayArgs};

pub fn run(node: OfflineNode, args: &ReplayArgs) -> Result<(), Box<dyn std::error::Error>> {
    let mut processor = FiducialProcessor::from_parameters(node.parameters())?;
    node.logger().info(processor.describe());
    let image_topic = node.resolve_topic("image")?;
    let info_topic = node.resolve_topic("camera_info")?;
    let mut source = BagSource::open(&args.bag)?;
    if !source.subscribe::<Image>(&image_topic)? {
        node.logger().warn(source.missing_topic_hint(&image_topic));
    }
    // Optional: without camera_info there are detections but no poses, as live.
    source.subscribe::<CameraInfo>(&info_topic)?;
    let detections_topic = node.resolve_topic("fiducials")?;
    let poses_topic = node.resolve_topic("fiducials/pose")?;
    let mut output = ReplayOutput::open(args.output.as_deref())?;
    output.advertise::<FiducialDetectionArray>(&detections_topic)?;
    output.advertise::<PoseWithCovarianceStamped>(&poses_topic)?;

    let (mut frames, mut rejected) = (0u64, 0u64);
    // SIGINT/SIGTERM stop it between messages, and the output below is still finished
    let stopped = source.replay::<Box<dyn std::error::Error>>(
        || node.interrupted(),
        |m| {
            if m.topic == info_topic {
                match m.decode::<CameraInfo>() {
                    Ok(info) => match processor.camera_info(&info) {
                        Ok(Some(warning)) => node.logger().warn(warning),
                        Ok(None) => {}
                        Err(e) => node.logger().warn(format!(
                            "{} at log time {} ns ignored: {e}",
                            m.topic, m.log_time_ns
                        )),
                    },
                    Err(e) => node.logger().warn(format!("ignored: {e}")),
                }
                return Ok(());
            }
            frames += 1;
            // A malformed message is reported and skipped, like a frame the detector rejects.
            let image = match m.decode::<Image>() {
                Ok(image) => image,
                Err(e) => {
                    rejected += 1;
                    node.logger().warn(format!("skipped: {e}"));
                    return Ok(());
                }
            };
            match processor.frame(&image) {
                Ok(out) => {
                    output.write(&detections_topic, &out.detections, m.log_time_ns)?;
                    for p in &out.poses {
                        output.write(&poses_topic, p, m.log_time_ns)?;
                    }
                }
                Err(e) => {
                    rejected += 1;
                    node.logger()
                        .warn(format!("{e} (log time {} ns)", m.log_time_ns));
                }
            }
            Ok(())
        },
    )?;
    output.finish()?;
    node.logger().info(format!(
        "replayed {frames} frames from {}: {rejected} rejected",
        args.bag.display()
    ));
    Ok(node.finish_replay(stopped)?)
}
