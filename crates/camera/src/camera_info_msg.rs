//! camera_info YAML ⇄ sensor_msgs/CameraInfo, both ways in one place: the camera node
//! publishes a loaded calibration, the fiducial node turns a received one into the camera model
//! (through the same checks as the YAML loader; errors name the field). The model is used on
//! raw, unrectified pixels; the header is left for the caller.

use metrocell_msgs::sensor_msgs::msg::CameraInfo as CameraInfoMsg;

use crate::camera_info::CameraInfo;
use crate::error::Result;
use crate::model::CameraModel;

impl CameraInfo {
    /// The message of this calibration (header, binning and ROI left at their defaults).
    pub fn to_msg(&self) -> CameraInfoMsg {
        CameraInfoMsg {
            height: self.image_height,
            width: self.image_width,
            distortion_model: self.distortion_model.clone(),
            d: self.distortion_coefficients.clone(),
            k: self.camera_matrix,
            r: self.rectification_matrix,
            p: self.projection_matrix,
            ..Default::default()
        }
    }

    /// The calibration a message carries (camera name: the header's frame_id).
    pub fn from_msg(msg: &CameraInfoMsg) -> Self {
        CameraInfo {
            camera_name: msg.header.frame_id.clone(),
            image_width: msg.width,
            image_height: msg.height,
            camera_matrix: msg.k,
            distortion_model: msg.distortion_model.clone(),
            distortion_coefficients: msg.d.clone(),
            rectification_matrix: msg.r,
            projection_matrix: msg.p,
            // sensor_msgs/CameraInfo has no place for it
            intrinsics_covariance: None,
        }
    }
}

/// The camera model of a CameraInfo message.
pub fn camera_model_from_msg(msg: &CameraInfoMsg) -> Result<CameraModel> {
    CameraInfo::from_msg(msg).to_model()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::distortion::Distortion;

    #[test]
    fn both_lens_models_round_trip_through_the_message() {
        for (cam, name) in [
            (
                CameraModel::new(
                    640,
                    480,
                    500.0,
                    501.0,
                    320.5,
                    240.5,
                    Distortion::BrownConrady([-0.1, 0.02, 1e-3, -1e-3, 0.0]),
                )
                .unwrap(),
                "plumb_bob",
            ),
            (
                CameraModel::new(
                    640,
                    480,
                    500.0,
                    501.0,
                    320.5,
                    240.5,
                    Distortion::Fisheye([0.01, -0.002, 0.0, 0.0]),
                )
                .unwrap(),
                "equidistant",
            ),
        ] {
            let msg = CameraInfo::from_model("cam", &cam).to_msg();
            assert_eq!(msg.distortion_model, name);
            assert_eq!(camera_model_from_msg(&msg).unwrap(), cam);
        }
    }

    #[test]
    fn an_unsupported_distortion_model_is_named() {
        let cam =
            CameraModel::new(640, 480, 500.0, 501.0, 320.5, 240.5, Distortion::none()).unwrap();
        let mut msg = CameraInfo::from_model("cam", &cam).to_msg();
        msg.distortion_model = "rational_polynomial".into();
        let e = camera_model_from_msg(&msg).unwrap_err();
        assert!(e.to_string().contains("distortion_model"), "{e}");
    }
}
