//! Camera frames: a twin camera frame request rendered as a real image of a fiducial plate.
//!
//! What the camera sees: the twin's fiducial plate (crates/twin `fiducial_plate`: a 2 × 2 board
//! of `DICT_4X4_50` ArUco markers, ids 0–3, one-cell border as OpenCV prints them), placed by the
//! twin square to the *nominal* camera's optical axis at its standoff, and moved with the part
//! (the request's `plate_position`/`plate_rotation`). The camera turns with the tool: the request
//! carries the true camera pose (the twin's shared model). So a perfect machine sees the board
//! centred, and the machine's displacement d moves the markers by ≈ f·d/standoff pixels along
//! the camera's axes, whatever the table or arm orientation — the image carries the machine
//! error as a real camera would, and the markers' true corners are the twin's predicted
//! `corners` (crates/sim tests hold the two equal).
//!
//! Frames (stated once): workpiece frame wp; camera optical frame c (x right, y down, z forward);
//! plate frame p (the renderer's target frame: plane z = 0, x right, y down as printed).
//! `p_wp = R_cam·p_c + c_cam` (the request's rotation/position), `p_wp = R_pl·p_p + o_pl` (the
//! request's plate pose). The render pose (plate → camera) is `p_c = R_camᵀ·R_pl·p_p + R_camᵀ·(o_pl − c_cam)`.
//!
//! Determinism: noise comes from the renderer's seeded generator, seeded per frame from the
//! simulation seed and the frame's stamp ([`frame_seed`]).

use metrocell_twin::CameraFrameRequest;
use metrocell_vision::aruco::Dictionary;
use metrocell_vision::camera::CameraModel;
use metrocell_vision::render::{
    render_view, PlanarTarget, RenderSettings, RenderedView, TargetItem,
};
use nalgebra::{Isometry3, Rotation3, Translation3, UnitQuaternion};

use crate::camera_intrinsics::CameraIntrinsics;
use crate::error::SimError;

/// The plate's layout is the twin's (the cell's `CameraSpec::plate`).
pub use metrocell_twin::FiducialPlate as FramePlate;

/// Dictionary of the plate's markers.
pub const PLATE_DICTIONARY: &str = "DICT_4X4_50";

/// The plate as the renderer's target: markers 0, 1 (top row, left to right), 2, 3.
pub fn plate_target(plate: &FramePlate) -> Result<PlanarTarget, SimError> {
    let dictionary = Dictionary::predefined(PLATE_DICTIONARY)
        .map_err(|e| SimError::invalid("camera plate dictionary", e.to_string()))?;
    let items = (0..metrocell_twin::fiducial_plate::PLATE_MARKERS)
        .map(|k| TargetItem::Marker {
            dictionary,
            id: k,
            top_left: plate.marker_top_left(k),
            side: plate.marker_side,
            border_bits: 1,
        })
        .collect();
    Ok(PlanarTarget { items })
}

/// How camera frames are rendered.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameRendering {
    /// Renderer settings (blur, noise, lighting); its `seed` is replaced per frame.
    pub settings: RenderSettings,
}

impl Default for FrameRendering {
    /// Optics blur 0.8 px, 1 grey level of sensor noise, supersampling 4 on edges.
    fn default() -> Self {
        FrameRendering {
            settings: RenderSettings {
                supersampling: 4,
                blur_sigma_px: 0.8,
                noise_sigma: 1.0,
                ..RenderSettings::default()
            },
        }
    }
}

/// Plate → camera pose of a request (module doc).
pub fn plate_to_camera(request: &CameraFrameRequest) -> Isometry3<f64> {
    let r_cam_t = request.rotation.transpose();
    let r = Rotation3::from_matrix(&(r_cam_t * request.plate_rotation));
    let t = r_cam_t * (request.plate_position - request.position);
    Isometry3::from_parts(
        Translation3::from(t),
        UnitQuaternion::from_rotation_matrix(&r),
    )
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
    /// Frames of the cell's camera (`intrinsics`) looking at `plate` (the cell's).
    pub fn new(
        intrinsics: &CameraIntrinsics,
        plate: &FramePlate,
        rendering: FrameRendering,
        sim_seed: u64,
    ) -> Result<FrameRenderer, SimError> {
        let camera = intrinsics.lens;
        let target = plate_target(plate)?;
        Ok(FrameRenderer {
            camera,
            rendering,
            target,
            sim_seed,
        })
    }

    /// The frame of `request` stamped `stamp_ns`, with the markers' true corners (pixels,
    /// OpenCV order) — the ground truth the image was drawn from.
    pub fn render(
        &self,
        request: &CameraFrameRequest,
        stamp_ns: u64,
    ) -> Result<RenderedView, SimError> {
        let pose = plate_to_camera(request);
        let settings = RenderSettings {
            seed: frame_seed(self.sim_seed, stamp_ns),
            ..self.rendering.settings
        };
        render_view(&self.camera, &pose, &self.target, &settings)
            .map_err(|e| SimError::invalid("camera frame rendering", e.to_string()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Point3;

    use nalgebra::{Matrix3, Vector3};

    /// A request with the twin's default plate in front of the nominal camera.
    fn with_plate(
        position: Vector3<f64>,
        rotation: Matrix3<f64>,
        nominal_position: Vector3<f64>,
        nominal_rotation: Matrix3<f64>,
    ) -> CameraFrameRequest {
        let nominal = Isometry3::from_parts(
            Translation3::from(nominal_position),
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&nominal_rotation)),
        );
        let plate = FramePlate::default().pose(&nominal);
        CameraFrameRequest {
            t: 1.0,
            target_id: 0,
            cycle: 0,
            position,
            rotation,
            nominal_position,
            nominal_rotation,
            plate_position: plate.translation.vector,
            plate_rotation: plate.rotation.to_rotation_matrix().into_inner(),
            corners: None,
            marker_points: vec![],
        }
    }

    fn request(d: Vector3<f64>) -> CameraFrameRequest {
        let nominal = Vector3::new(0.15, 0.2, 0.05);
        let down = Rotation3::from_euler_angles(std::f64::consts::PI, 0.0, 0.0).into_inner();
        with_plate(nominal + d, down, nominal, down)
    }

    #[test]
    fn nominal_camera_sees_the_plate_centred_at_the_standoff() {
        let r = request(Vector3::zeros());
        let pose = plate_to_camera(&r);
        let c = pose * Point3::origin();
        assert!(
            (c.coords - Vector3::new(0.0, 0.0, 0.150)).norm() < 1e-12,
            "{c}"
        );
        assert!((pose.rotation.angle()).abs() < 1e-12);
    }

    #[test]
    fn a_machine_displacement_moves_the_plate_opposite_in_the_camera() {
        // Tool displaced +10 µm along workpiece x; camera x = workpiece x (Rx(π)), so the plate
        // appears 10 µm towards −x in the camera frame.
        let r = request(Vector3::new(10e-6, 0.0, 0.0));
        let pose = plate_to_camera(&r);
        let c = pose * Point3::origin();
        assert!((c.x + 10e-6).abs() < 1e-12 && c.y.abs() < 1e-12, "{c}");
    }

    #[test]
    fn a_camera_turned_about_its_axis_sees_the_plate_turned_back_in_any_nominal_orientation() {
        // a tilted nominal camera (as on a turned table or an arm), the true one turned a
        // further 1 mrad about its optical axis at the same place
        let nominal = Rotation3::from_euler_angles(0.3, -0.5, 1.0);
        let r = with_plate(
            Vector3::new(0.1, -0.2, 0.3),
            (nominal * Rotation3::from_axis_angle(&Vector3::z_axis(), 1e-3)).into_inner(),
            Vector3::new(0.1, -0.2, 0.3),
            nominal.into_inner(),
        );
        let pose = plate_to_camera(&r);
        assert!(((pose * Point3::origin()).coords - Vector3::new(0.0, 0.0, 0.150)).norm() < 1e-12);
        let (axis, angle) = pose.rotation.axis_angle().unwrap();
        assert!(
            (angle - 1e-3).abs() < 1e-12 && (axis.into_inner() + Vector3::z()).norm() < 1e-9,
            "{axis:?} {angle}"
        );
    }

    #[test]
    fn frame_seeds_differ_per_stamp_and_repeat_per_input() {
        assert_eq!(frame_seed(3, 1_000), frame_seed(3, 1_000));
        assert_ne!(frame_seed(3, 1_000), frame_seed(3, 1_001));
        assert_ne!(frame_seed(3, 1_000), frame_seed(4, 1_000));
    }
}
