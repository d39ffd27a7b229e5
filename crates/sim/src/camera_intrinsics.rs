//! The simulated camera's intrinsics, published as `sensor_msgs/CameraInfo`.
//!
//! A cell file may state the lens (`sensors.camera.intrinsics`); then [`CameraIntrinsics::for_cell`]
//! takes it (the cell describes the camera; the simulator option is only the fallback). Otherwise
//! the intrinsics are a simulator option with a documented default: a 5 MP machine-vision camera (2448 × 2048 px,
//! 3.45 µm pixels) behind a 12 mm lens, i.e. f = 12 mm / 3.45 µm ≈ 3478 px, principal point at
//! the image centre, no distortion (`plumb_bob` with zero coefficients). Pixel convention is
//! OpenCV's (centre of the top-left pixel at (0, 0)), so the centre is ((w−1)/2, (h−1)/2).

use metrocell_camera_model::{CameraModel, Distortion};

/// The simulated camera: its lens (pinhole, distortion) and the frame id of its messages.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraIntrinsics {
    pub lens: CameraModel,
    /// `header.frame_id` of camera messages (optical frame: x right, y down, z forward).
    pub frame_id: String,
}

impl Default for CameraIntrinsics {
    fn default() -> Self {
        let f = 12e-3 / 3.45e-6;
        let lens = CameraModel::new(2448, 2048, f, f, 1223.5, 1023.5, Distortion::none()).expect("the default lens is valid");
        CameraIntrinsics { lens, frame_id: "camera_optical".into() }
    }
}

impl CameraIntrinsics {
    /// The cell's `sensors.camera.intrinsics` if it states them (keeping `fallback`'s frame id),
    /// else `fallback`.
    pub fn for_cell(cell: &metrocell_twin::Cell, fallback: CameraIntrinsics) -> CameraIntrinsics {
        match cell.camera.as_ref().and_then(|c| c.intrinsics.as_ref()) {
            Some(lens) => CameraIntrinsics { lens: lens.clone(), frame_id: fallback.frame_id },
            None => fallback,
        }
    }
}
