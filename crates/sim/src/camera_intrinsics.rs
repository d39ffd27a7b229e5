//! The simulated camera's intrinsics, published as `sensor_msgs/CameraInfo`.
//!
//! A cell file may state the lens (`sensors.camera.intrinsics`); then [`CameraIntrinsics::for_cell`]
//! takes it (the cell describes the camera; the simulator option is only the fallback). Otherwise
//! the intrinsics are a simulator option with a documented default: a 5 MP machine-vision camera (2448 × 2048 px,
//! 3.45 µm pixels) behind a 12 mm lens, i.e. f = 12 mm / 3.45 µm ≈ 3478 px, principal point at
//! the image centre, no distortion (`plumb_bob` with zero coefficients). Pixel convention is
//! OpenCV's (centre of the top-left pixel at (0, 0)), so the centre is ((w−1)/2, (h−1)/2).

pub use metrocell_twin::cell::LensDistortion;

/// Pinhole intrinsics with a lens distortion model (`plumb_bob` Brown–Conrady or `equidistant`
/// fisheye, coefficients in OpenCV order).
#[derive(Debug, Clone, PartialEq)]
pub struct CameraIntrinsics {
    pub width: u32,
    pub height: u32,
    /// Focal lengths and principal point (px).
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
    pub distortion: LensDistortion,
    /// `header.frame_id` of camera messages (optical frame: x right, y down, z forward).
    pub frame_id: String,
}

impl Default for CameraIntrinsics {
    fn default() -> Self {
        let f = 12e-3 / 3.45e-6;
        CameraIntrinsics { width: 2448, height: 2048, fx: f, fy: f, cx: 1223.5, cy: 1023.5, distortion: LensDistortion::PlumbBob([0.0; 5]), frame_id: "camera_optical".into() }
    }
}

impl CameraIntrinsics {
    /// The cell's `sensors.camera.intrinsics` if it states them (keeping `fallback`'s frame id),
    /// else `fallback`.
    pub fn for_cell(cell: &metrocell_twin::Cell, fallback: CameraIntrinsics) -> CameraIntrinsics {
        match cell.camera.as_ref().and_then(|c| c.intrinsics.as_ref()) {
            Some(l) => CameraIntrinsics { width: l.width, height: l.height, fx: l.fx, fy: l.fy, cx: l.cx, cy: l.cy, distortion: l.distortion, frame_id: fallback.frame_id },
            None => fallback,
        }
    }
}
