//! Camera frames: a twin camera frame request rendered as a real image of a fiducial plate.
//!
//! What the camera sees. The cell file says where the camera is mounted on the tool, not what
//! it looks at, so the simulator places one fiducial plate per dwell point: a 2 × 2 board of
//! `DICT_4X4_50` ArUco markers (ids 0–3, side [`FramePlate::marker_side`], gap
//! [`FramePlate::gap`], one-cell border as OpenCV prints them) square to the *nominal* camera's
//! optical axis at [`FramePlate::standoff`] in front of it, its centre on that axis, its x/y
//! axes along the nominal camera's x/y. The camera turns with the tool: the nominal camera is
//! the mount applied to the commanded tool pose, the true camera the mount applied to the true
//! (displaced) tool pose (the twin computes both per machine family:
//! [`CameraFrameRequest::nominal_position`], [`CameraFrameRequest::position`]). So a perfect
//! machine sees the board centred, and the machine's displacement d moves the markers by
//! ≈ f·d/standoff pixels along the camera's axes, whatever the table or arm orientation —
//! the image carries the machine error as a real camera would.
//!
//! Frames (stated once): workpiece frame wp; camera optical frame c (x right, y down, z forward);
//! plate frame p (the renderer's target frame: plane z = 0, x right, y down as printed).
//! `p_wp = R_cam·p_c + c_cam` (the request's rotation/position), `p_wp = R_nom·p_p + o_plate`
//! with `o_plate = c_nom + R_nom·(0, 0, standoff)` (c_nom, R_nom: the request's nominal pose).
//! The render pose (plate → camera) is then `p_c = R_camᵀ·R_nom·p_p + R_camᵀ·(o_plate − c_cam)`.
//!
//! Determinism: noise comes from the renderer's seeded generator, seeded per frame from the
//! simulation seed and the frame's stamp ([`frame_seed`]).

use metrocell_twin::CameraFrameRequest;
use metrocell_vision::aruco::Dictionary;
use metrocell_vision::camera::CameraModel;
use metrocell_vision::render::{render_view, PlanarTarget, RenderSettings, RenderedView, TargetItem};
use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::camera_intrinsics::CameraIntrinsics;
use crate::error::SimError;

/// The fiducial plate in front of the camera (see the module doc). Lengths in metres.
#[derive(Debug, Clone, PartialEq)]
pub struct FramePlate {
    /// Distance from the nominal camera centre to the plate along the optical axis (m).
    pub standoff: f64,
    /// Outer side of each marker, border included (m).
    pub marker_side: f64,
    /// Gap between neighbouring markers (m).
    pub gap: f64,
}

impl Default for FramePlate {
    /// 150 mm standoff, 20 mm markers, 10 mm gap: with the default intrinsics each marker is
    /// ≈ 460 px wide and the 50 mm board fills about half the image height.
    fn default() -> Self {
        FramePlate { standoff: 0.150, marker_side: 0.020, gap: 0.010 }
    }
}

/// Dictionary of the plate's markers.
pub const PLATE_DICTIONARY: &str = "DICT_4X4_50";

impl FramePlate {
    /// The plate as the renderer's target: markers 0, 1 (top row, left to right), 2, 3.
    pub fn target(&self) -> Result<PlanarTarget, SimError> {
        let dictionary = Dictionary::predefined(PLATE_DICTIONARY).map_err(|e| SimError::invalid("camera plate dictionary", e.to_string()))?;
        let half = self.marker_side + self.gap / 2.0;
        let items = (0..4)
            .map(|k| TargetItem::Marker {
                dictionary,
                id: k,
                top_left: [-half + (k % 2) as f64 * (self.marker_side + self.gap), -half + (k / 2) as f64 * (self.marker_side + self.gap)],
                side: self.marker_side,
                border_bits: 1,
            })
            .collect();
        Ok(PlanarTarget { items })
    }
}

/// How camera frames are rendered.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameRendering {
    pub plate: FramePlate,
    /// Renderer settings (blur, noise, lighting); its `seed` is replaced per frame.
    pub settings: RenderSettings,
}

impl Default for FrameRendering {
    /// Optics blur 0.8 px, 1 grey level of sensor noise, supersampling 4 on edges.
    fn default() -> Self {
        FrameRendering { plate: FramePlate::default(), settings: RenderSettings { supersampling: 4, blur_sigma_px: 0.8, noise_sigma: 1.0, ..RenderSettings::default() } }
    }
}


/// Plate → camera pose of a request (module doc).
pub fn plate_to_camera(request: &CameraFrameRequest, plate: &FramePlate) -> Isometry3<f64> {
    let r_nom = &request.nominal_rotation;
    let o_plate = request.nominal_position + r_nom * Vector3::new(0.0, 0.0, plate.standoff);
    let r_cam_t = request.rotation.transpose();
    let r = Rotation3::from_matrix(&(r_cam_t * r_nom));
    let t = r_cam_t * (o_plate - request.position);
    Isometry3::from_parts(Translation3::from(t), UnitQuaternion::from_rotation_matrix(&r))
}

/// Per-frame noise seed from the simulation seed and the frame stamp (SplitMix64 mix).
pub fn frame_seed(sim_seed: u64, stamp_ns: u64) -> u64 {
    let mut z = sim_seed ^ stamp_ns.wrapping_mul(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Renders the frames of one cell (pure given its fields).
#[derive(Debug, Clone)]
pub struct FrameRenderer {
    pub camera: CameraModel,
    pub rendering: FrameRendering,
    target: PlanarTarget,
    sim_seed: u64,
}

impl FrameRenderer {
    pub fn new(intrinsics: &CameraIntrinsics, rendering: FrameRendering, sim_seed: u64) -> Result<FrameRenderer, SimError> {
        let camera = intrinsics.lens.clone();
        let target = rendering.plate.target()?;
        Ok(FrameRenderer { camera, rendering, target, sim_seed })
    }

    /// The frame of `request` stamped `stamp_ns`, with the markers' true corners (pixels,
    /// OpenCV order) — the ground truth the image was drawn from.
    pub fn render(&self, request: &CameraFrameRequest, stamp_ns: u64) -> Result<RenderedView, SimError> {
        let pose = plate_to_camera(request, &self.rendering.plate);
        let settings = RenderSettings { seed: frame_seed(self.sim_seed, stamp_ns), ..self.rendering.settings };
        render_view(&self.camera, &pose, &self.target, &settings).map_err(|e| SimError::invalid("camera frame rendering", e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    fn request(d: Vector3<f64>) -> CameraFrameRequest {
        let nominal = Vector3::new(0.15, 0.2, 0.05);
        let down = Rotation3::from_euler_angles(std::f64::consts::PI, 0.0, 0.0).into_inner();
        CameraFrameRequest { t: 1.0, target_id: 0, cycle: 0, position: nominal + d, rotation: down, nominal_position: nominal, nominal_rotation: down }
    }

    #[test]
    fn nominal_camera_sees_the_plate_centred_at_the_standoff() {
        let r = request(Vector3::zeros());
        let plate = FramePlate::default();
        let pose = plate_to_camera(&r, &plate);
        let c = pose * Point3::origin();
        assert!((c.coords - Vector3::new(0.0, 0.0, 0.150)).norm() < 1e-12, "{c}");
        assert!((pose.rotation.angle()).abs() < 1e-12);
    }

    #[test]
    fn a_machine_displacement_moves_the_plate_opposite_in_the_camera() {
        // Tool displaced +10 µm along workpiece x; camera x = workpiece x (Rx(π)), so the plate
        // appears 10 µm towards −x in the camera frame.
        let r = request(Vector3::new(10e-6, 0.0, 0.0));
        let pose = plate_to_camera(&r, &FramePlate::default());
        let c = pose * Point3::origin();
        assert!((c.x + 10e-6).abs() < 1e-12 && c.y.abs() < 1e-12, "{c}");
    }

    #[test]
    fn a_camera_turned_about_its_axis_sees_the_plate_turned_back_in_any_nominal_orientation() {
        // a tilted nominal camera (as on a turned table or an arm), the true one turned a
        // further 1 mrad about its optical axis at the same place
        let nominal = Rotation3::from_euler_angles(0.3, -0.5, 1.0);
        let r = CameraFrameRequest {
            t: 0.0,
            target_id: 0,
            cycle: 0,
            position: Vector3::new(0.1, -0.2, 0.3),
            rotation: (nominal * Rotation3::from_axis_angle(&Vector3::z_axis(), 1e-3)).into_inner(),
            nominal_position: Vector3::new(0.1, -0.2, 0.3),
            nominal_rotation: nominal.into_inner(),
        };
        let pose = plate_to_camera(&r, &FramePlate::default());
        assert!(((pose * Point3::origin()).coords - Vector3::new(0.0, 0.0, 0.150)).norm() < 1e-12);
        let (axis, angle) = pose.rotation.axis_angle().unwrap();
        assert!((angle - 1e-3).abs() < 1e-12 && (axis.into_inner() + Vector3::z()).norm() < 1e-9, "{axis:?} {angle}");
    }

    #[test]
    fn frame_seeds_differ_per_stamp_and_repeat_per_input() {
        assert_eq!(frame_seed(3, 1_000), frame_seed(3, 1_000));
        assert_ne!(frame_seed(3, 1_000), frame_seed(3, 1_001));
        assert_ne!(frame_seed(3, 1_000), frame_seed(4, 1_000));
    }
}
