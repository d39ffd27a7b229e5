//! Detected targets → ROS messages. The array's header copies the image header; each pose is a
//! PoseWithCovarianceStamped with the same header (frame_id = the image's optical frame), pose and
//! covariance in the convention of `metrocell_vision::targets`.

use metrocell_msgs::geometry_msgs::msg::{
    Point, Pose, PoseWithCovariance, PoseWithCovarianceStamped, Quaternion,
};
use metrocell_msgs::msg::{FiducialDetection, FiducialDetectionArray};
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_vision::{Target, TargetPose};

fn pose_msg(p: &TargetPose) -> PoseWithCovariance {
    let [x, y, z] = p.position;
    let [qx, qy, qz, qw] = p.orientation;
    PoseWithCovariance {
        pose: Pose {
            position: Point { x, y, z },
            orientation: Quaternion {
                x: qx,
                y: qy,
                z: qz,
                w: qw,
            },
        },
        covariance: p.covariance,
    }
}

/// One FiducialDetection per target.
pub fn detection_array(
    header: &Header,
    width: u32,
    height: u32,
    family: &str,
    targets: &[Target],
) -> FiducialDetectionArray {
    FiducialDetectionArray {
        header: header.clone(),
        image_width: width,
        image_height: height,
        detections: targets
            .iter()
            .map(|t| FiducialDetection {
                family: family.to_string(),
                id: t.id as i32,
                corners: t.corners.iter().flat_map(|c| [c.x, c.y]).collect(),
                corner_covariance: t
                    .corner_covariance
                    .iter()
                    .flat_map(|c| [c[(0, 0)], c[(0, 1)], c[(1, 0)], c[(1, 1)]])
                    .collect(),
                decision_margin: t.decision_margin,
                has_pose: t.pose.is_some(),
                pose: t.pose.as_ref().map(pose_msg).unwrap_or_default(),
            })
            .collect(),
    }
}

/// The stamped poses of the targets that have one, in target order.
pub fn pose_messages(header: &Header, targets: &[Target]) -> Vec<PoseWithCovarianceStamped> {
    targets
        .iter()
        .filter_map(|t| t.pose.as_ref())
        .map(|p| PoseWithCovarianceStamped {
            header: header.clone(),
            pose: pose_msg(p),
        })
        .collect()
}
