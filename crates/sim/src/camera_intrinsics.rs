//! The simulated camera's intrinsics, published as `sensor_msgs/CameraInfo`.
//!
//! The lens is the cell's: `sensors.camera.intrinsics`, or the twin's documented default when the
//! file states none (crates/twin `cell::default_camera_lens`: a 5 MP machine-vision camera,
//! 2448 × 2048 px, 3.45 µm pixels, 12 mm lens, f ≈ 3478 px, principal point at the image centre,
//! no distortion), so the rendered images and the twin's predicted corners (the shared model's
//! camera reading) come from one lens. Pixel convention is OpenCV's (centre of the top-left
//! pixel at (0, 0)).

use metrocell_camera_model::CameraModel;

/// The simulated camera: its lens (pinhole, distortion) and the frame id of its messages.
#[derive(Debug, Clone, PartialEq)]
pub struct CameraIntrinsics {
    pub lens: CameraModel,
    /// `header.frame_id` of camera messages (optical frame: x right, y down, z forward).
    pub frame_id: String,
}

impl Default for CameraIntrinsics {
    /// The twin's default lens ([`metrocell_twin::cell::default_camera_lens`]).
    fn default() -> Self {
        CameraIntrinsics {
            lens: metrocell_twin::cell::default_camera_lens(),
            frame_id: "camera_optical".into(),
        }
    }
}

impl CameraIntrinsics {
    /// The lens of the cell's camera (its `sensors.camera.intrinsics`, else the twin's default)
    /// with `fallback`'s frame id; `fallback` itself for a cell without a camera.
    pub fn for_cell(cell: &metrocell_twin::Cell, fallback: CameraIntrinsics) -> CameraIntrinsics {
        match &cell.camera {
            Some(c) => CameraIntrinsics {
                lens: c.lens(),
                frame_id: fallback.frame_id,
            },
            None => fallback,
        }
    }
}
