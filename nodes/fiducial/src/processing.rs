//! What the node does with each input, shared by the live run and the bag replay so both give
//! the same numbers: parameters → [`FiducialProcessor`]; a CameraInfo updates the camera model;
//! an Image becomes a FiducialDetectionArray (header = the image's: its stamp and frame_id) and
//! one PoseWithCovarianceStamped per target with a pose.

use metrocell_camera_model::CameraModel;
use metrocell_msgs::geometry_msgs::msg::PoseWithCovarianceStamped;
use metrocell_msgs::msg::FiducialDetectionArray;
use metrocell_msgs::sensor_msgs::msg::{CameraInfo, Image};
use metrocell_node::{ParamDecl, Parameters};
use metrocell_vision::aruco::DetectorParams;
use metrocell_vision::{detect_targets, PoseInputs, TargetFamily};

use crate::{detection_msgs, frame};

pub fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new("family", "DICT_4X4_50".to_string(), "OpenCV dictionary name (DICT_4X4_50, DICT_APRILTAG_36h11, ...), checkerboard, or drilled_holes"),
        ParamDecl::new("marker_size", 0.0, "marker side [m] for marker poses; 0 = no marker pose").with_range(0.0, 10.0),
        // ≥ 2: the checkerboard detector needs a 2×2 inner grid, and so does the hole plate's
        // corner extrapolation; ≤ 1000 only catches typos.
        ParamDecl::new("board_cols", 9i64, "checkerboard / hole plate: inner corners along a row (squares − 1)").with_range(2.0, 1000.0),
        ParamDecl::new("board_rows", 6i64, "checkerboard / hole plate: inner corners along a column (squares − 1)").with_range(2.0, 1000.0),
        ParamDecl::new("square_size", 0.01, "checkerboard square side [m]").with_range(0.0, 10.0),
        ParamDecl::new("corner_sigma_px", 0.1, "corner σ [px] where a corner has no covariance").with_range(1e-6, 100.0),
        ParamDecl::new("threads", 0i64, "detector worker threads; 0 = all cores").with_range(0.0, 1024.0),
    ]
}

/// Outputs of one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameOutputs {
    pub detections: FiducialDetectionArray,
    pub poses: Vec<PoseWithCovarianceStamped>,
}

pub struct FiducialProcessor {
    family: TargetFamily,
    family_name: String,
    marker_size: Option<f64>,
    sigma: f64,
    params: DetectorParams,
    camera: Option<CameraModel>,
}

impl FiducialProcessor {
    pub fn from_parameters(p: &Parameters) -> Result<Self, Box<dyn std::error::Error>> {
        // Non-negative by the declared ranges, so the conversions cannot fail.
        let count = |name: &str| -> Result<usize, Box<dyn std::error::Error>> { Ok(usize::try_from(p.get::<i64>(name)?)?) };
        let board = (count("board_cols")?, count("board_rows")?);
        let family = TargetFamily::parse(&p.get::<String>("family")?, Some(board), Some(p.get::<f64>("square_size")?))?;
        Ok(FiducialProcessor {
            family_name: family.message_name(),
            family,
            marker_size: Some(p.get::<f64>("marker_size")?).filter(|s| *s > 0.0),
            sigma: p.get::<f64>("corner_sigma_px")?,
            params: DetectorParams { threads: count("threads")?, ..Default::default() },
            camera: None,
        })
    }

    pub fn describe(&self) -> String {
        format!("detecting {}, marker_size {:?} m", self.family_name, self.marker_size)
    }

    /// Use this camera for poses from now on; a bad message keeps the previous camera.
    pub fn camera_info(&mut self, info: &CameraInfo) -> Result<(), metrocell_camera_model::CameraError> {
        self.camera = Some(metrocell_camera_model::camera_model_from_msg(info)?);
        Ok(())
    }

    /// Detect in one frame. Errors name the frame (stamp, frame_id) and the problem.
    pub fn frame(&self, img: &Image) -> Result<FrameOutputs, String> {
        let name = || format!("frame {}.{:09} ({})", img.header.stamp.sec, img.header.stamp.nanosec, img.header.frame_id);
        let gray = frame::gray_from_image(img).map_err(|e| format!("{}: {e}", name()))?;
        let pose_inputs = self
            .camera
            .as_ref()
            .filter(|c| c.width == gray.width() && c.height == gray.height())
            .map(|c| PoseInputs { camera: c, marker_side: self.marker_size, fallback_sigma_px: self.sigma, intrinsics_covariance: None });
        let targets = detect_targets(&gray, &self.family, &self.params, pose_inputs).map_err(|e| format!("{}: {e}", name()))?;
        Ok(FrameOutputs {
            detections: detection_msgs::detection_array(&img.header, img.width, img.height, &self.family_name, &targets),
            poses: detection_msgs::pose_messages(&img.header, &targets),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_node::parse_command_line;

    fn resolve(args: &[&str]) -> Result<Parameters, String> {
        let cl = parse_command_line(["metrocell-fiducial", "--ros-args"].iter().chain(args).copied()).map_err(|e| e.to_string())?;
        Parameters::resolve(&declarations(), &cl.ros, "/fiducial", "fiducial").map_err(|e| e.to_string())
    }

    #[test]
    fn counts_out_of_range_are_errors_naming_the_range() {
        let p = resolve(&["-p", "family:=checkerboard", "-p", "board_cols:=2", "-p", "board_rows:=1000", "-p", "threads:=4"]).unwrap();
        assert!(FiducialProcessor::from_parameters(&p).is_ok());
        // These were clamped (−1 → 0 columns, −3 → 0 = all cores) or passed on to fail per frame.
        for (arg, name, range) in [("board_cols:=-1", "'board_cols'", "[2, 1000]"), ("board_rows:=1", "'board_rows'", "[2, 1000]"), ("threads:=-3", "'threads'", "[0, 1024]")] {
            let e = resolve(&["-p", arg]).err().unwrap_or_else(|| panic!("{arg} accepted"));
            assert!(e.contains(name) && e.contains(range), "{arg}: {e}");
        }
    }
}
