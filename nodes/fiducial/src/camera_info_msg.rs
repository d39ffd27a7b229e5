//! sensor_msgs/CameraInfo → camera model (K and distortion; the model is used on raw, unrectified
//! pixels). Errors name the field.

use metrocell_camera::{CameraModel, CameraInfo as CameraInfoYaml};
use metrocell_msgs::sensor_msgs::msg::CameraInfo;

/// The camera model of a CameraInfo message, through the same checks as the YAML loader.
pub fn camera_model_from_msg(msg: &CameraInfo) -> Result<CameraModel, metrocell_camera::CameraError> {
    let yaml = CameraInfoYaml {
        camera_name: msg.header.frame_id.clone(),
        image_width: msg.width,
        image_height: msg.height,
        camera_matrix: msg.k,
        distortion_model: msg.distortion_model.clone(),
        distortion_coefficients: msg.d.clone(),
        rectification_matrix: msg.r,
        projection_matrix: msg.p,
    };
    yaml.to_model()
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_camera::Distortion;

    #[test]
    fn camera_info_round_trips_through_the_message() {
        let cam = CameraModel::new(640, 480, 500.0, 501.0, 320.5, 240.5, Distortion::BrownConrady([-0.1, 0.02, 1e-3, -1e-3, 0.0])).unwrap();
        let y = CameraInfoYaml::from_model("cam", &cam);
        let msg = CameraInfo {
            height: y.image_height,
            width: y.image_width,
            distortion_model: y.distortion_model.clone(),
            d: y.distortion_coefficients.clone(),
            k: y.camera_matrix,
            r: y.rectification_matrix,
            p: y.projection_matrix,
            ..Default::default()
        };
        assert_eq!(msg.distortion_model, "plumb_bob");
        assert_eq!(camera_model_from_msg(&msg).unwrap(), cam);
        let mut bad = msg.clone();
        bad.distortion_model = "rational_polynomial".into();
        let e = camera_model_from_msg(&bad).unwrap_err();
        assert!(e.to_string().contains("distortion_model"), "{e}");
    }
}
