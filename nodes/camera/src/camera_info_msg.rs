//! Loaded camera_info YAML → sensor_msgs/CameraInfo (header left for the caller).

use metrocell_camera::CameraInfo as CameraInfoYaml;
use metrocell_msgs::sensor_msgs::msg::CameraInfo;

pub fn camera_info_msg(info: &CameraInfoYaml) -> CameraInfo {
    CameraInfo {
        height: info.image_height,
        width: info.image_width,
        distortion_model: info.distortion_model.clone(),
        d: info.distortion_coefficients.clone(),
        k: info.camera_matrix,
        r: info.rectification_matrix,
        p: info.projection_matrix,
        ..Default::default()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_camera::{CameraModel, Distortion};

    #[test]
    fn the_message_carries_the_yaml_and_reads_back_to_the_same_model() {
        let cam = CameraModel::new(640, 480, 500.0, 501.0, 320.5, 240.5, Distortion::Fisheye([0.01, -0.002, 0.0, 0.0])).unwrap();
        let msg = camera_info_msg(&CameraInfoYaml::from_model("cam", &cam));
        assert_eq!(msg.distortion_model, "equidistant");
        assert_eq!(metrocell_fiducial_node::camera_info_msg::camera_model_from_msg(&msg).unwrap(), cam);
    }
}
