//! A tool-mounted camera's reading of a part feature, and its analytic Jacobian.
//!
//! What a camera that sees a fiducial feature reads (the fiducial node measures both kinds):
//! * the camera pose: the tool's true pose followed by the mount
//!   ([`crate::instruments::CameraGeometry`]), `C = tool.truth · mount` (workpiece frame);
//! * the feature (nominal position f, workpiece frame) truly lies at f' = f + d_w(f), so in the
//!   camera frame it is x_c = R_Cᵀ(f' − t_C);
//! * **image point** (what a detector's corners are): the ideal normalised point
//!   (x, y) = (x_c/z_c, y_c/z_c), distorted by `lens_distortion` (Δ(x, y), Brown–Conrady),
//!   to pixels u = fx·(x + Δx) + cx, v = fy·(y + Δy) + cy;
//! * **camera point** (what a marker pose's translation is, metric): x_c + d_scale with
//!   `camera_scale`'s d_scale = s·x_c, i.e. (1 + s)·x_c. A scale error (a wrong marker size in
//!   the detector, a wrong focal length) changes no image point, so `camera_scale` is
//!   observable only through camera points, `lens_distortion` only through image points.
//!
//! The Jacobian goes through the tool's: ∂x_c = R_Cᵀ(∂d_w(f) − ∂t_tool − ω × (f' − t_tool)),
//! with ω the tool rotation's angular-velocity column (an arm's joint offsets turn the tool and
//! the camera with it; nothing else turns it).

use metrocell_physics::instrument::lens_distortion::image_point_jacobian;
use metrocell_physics::{PhysicsError, Signals};
use nalgebra::{DMatrix, Isometry3, Vector2, Vector3};

use crate::forward::{ForwardModel, KinematicTruth, ToolState};
use crate::instruments::{CameraGeometry, Instrument, InstrumentKind};
use crate::workspace::Workspace;

/// The predicted reading of a camera for one feature.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraPrediction {
    /// The feature's true position in the camera frame x_c, m.
    pub point: Vector3<f64>,
    /// The metric camera point (1 + s)·x_c (x_c without a `camera_scale` term), m.
    pub measured_point: Vector3<f64>,
    /// Ideal normalised image point (x_c/z_c, y_c/z_c).
    pub normalised: Vector2<f64>,
    /// Normalised image point after `lens_distortion` (the ideal one without it).
    pub distorted: Vector2<f64>,
    /// Pixel (u, v), OpenCV convention.
    pub pixel: Vector2<f64>,
}

/// Rows of [`ForwardModel::camera_jacobian`]: pixel u, v, then the camera point x, y, z.
pub const CAMERA_ROWS: usize = 5;

fn geometry_of(inst: &Instrument) -> Result<&CameraGeometry, PhysicsError> {
    inst.camera
        .as_ref()
        .ok_or_else(|| PhysicsError::InvalidInput {
            what: "forward model, camera reading".into(),
            reason: format!(
                "the {} has no geometry (mount and intrinsics): ForwardModel::with_camera",
                inst.describe()
            ),
        })
}

impl ForwardModel<'_> {
    /// Nominal and true pose of camera `instrument` (None: the only one) in the workpiece
    /// frame for the tool state `tool`: `tool.nominal · mount`, `tool.truth · mount`.
    pub fn camera_pose(
        &self,
        instrument: Option<&str>,
        tool: &ToolState,
    ) -> Result<(Isometry3<f64>, Isometry3<f64>), PhysicsError> {
        let mount = geometry_of(self.require(InstrumentKind::Camera, instrument)?)?
            .mount
            .isometry();
        Ok((tool.nominal * mount, tool.truth * mount))
    }

    /// Everything after the feature's camera-frame position: scale, projection, lens.
    fn camera_reading(
        &self,
        inst: &Instrument,
        g: &CameraGeometry,
        p: &[f64],
        s: &mut Signals,
        x_c: Vector3<f64>,
    ) -> Result<CameraPrediction, PhysicsError> {
        if !(x_c.z > 0.0) {
            return Err(PhysicsError::InvalidInput {
                what: "forward model, camera reading".into(),
                reason: format!(
                    "the feature is not in front of the {} (camera-frame z = {} m)",
                    inst.describe(),
                    x_c.z
                ),
            });
        }
        s.camera_point = Some(x_c);
        let measured_point = match inst.scale {
            Some(i) => {
                let v = self.term(i).term.predict(self.part(i, p), s)?.value;
                x_c + Vector3::new(v[0], v[1], v[2])
            }
            None => x_c,
        };
        let normalised = Vector2::new(x_c.x / x_c.z, x_c.y / x_c.z);
        s.image_point = Some(normalised);
        let distorted = match inst.distortion {
            Some(i) => {
                let v = self.term(i).term.predict(self.part(i, p), s)?.value;
                normalised + Vector2::new(v[0], v[1])
            }
            None => normalised,
        };
        let pixel = Vector2::new(g.fx * distorted.x + g.cx, g.fy * distorted.y + g.cy);
        Ok(CameraPrediction {
            point: x_c,
            measured_point,
            normalised,
            distorted,
            pixel,
        })
    }

    /// The reading of camera `instrument` (None: the only one) of the part feature with
    /// nominal position `feature` (workpiece frame) for the tool state `tool` (see the module
    /// doc). `s` carries what the workpiece terms read; its `workpiece_point`, `camera_point`
    /// and `image_point` are set here.
    pub fn camera(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        tool: &ToolState,
        s: &mut Signals,
        feature: &Vector3<f64>,
    ) -> Result<CameraPrediction, PhysicsError> {
        self.check(p)?;
        let inst = self.require(InstrumentKind::Camera, instrument)?;
        let g = geometry_of(inst)?;
        let f = feature + self.workpiece_displacement(p, s, *feature, None, 1.0)?;
        let camera = tool.truth * g.mount.isometry();
        let r = camera.rotation.to_rotation_matrix().into_inner();
        let x_c = r.transpose() * (f - camera.translation.vector);
        self.camera_reading(inst, g, p, s, x_c)
    }

    /// [`Self::camera`] at joint vector `q` and its Jacobian w.r.t. the stacked parameters into
    /// `out` ([`CAMERA_ROWS`] × [`Self::param_count`]); the prediction is `camera`'s (of
    /// `tool_state` at `q`) bit for bit.
    #[allow(clippy::too_many_arguments)]
    pub fn camera_jacobian(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        kin: &KinematicTruth,
        q: &[f64],
        s: &mut Signals,
        feature: &Vector3<f64>,
        work: &mut Workspace,
        out: &mut DMatrix<f64>,
    ) -> Result<CameraPrediction, PhysicsError> {
        self.check(p)?;
        self.check_buffer("camera Jacobian", out, CAMERA_ROWS)?;
        work.check(self)?;
        let inst = self.require(InstrumentKind::Camera, instrument)?;
        let g = geometry_of(inst)?;
        let tool = self.tool_jacobian(p, kin, q, s, &mut work.tool, Some(&mut work.ang))?;
        work.feature.fill(0.0);
        let f =
            feature + self.workpiece_displacement(p, s, *feature, Some(&mut work.feature), 1.0)?;
        let camera = tool.truth * g.mount.isometry();
        let r = camera.rotation.to_rotation_matrix().into_inner();
        let x_c = r.transpose() * (f - camera.translation.vector);
        let pred = self.camera_reading(inst, g, p, s, x_c)?;
        // ∂x_c = R_Cᵀ(∂d_w(f) − ∂t_tool − ω × (f' − t_tool))
        let lever = f - tool.truth.translation.vector;
        let rt = r.transpose();
        for c in 0..self.n_params {
            let w = work.ang.fixed_view::<3, 1>(0, c).into_owned();
            let dx = rt
                * (work.feature.fixed_view::<3, 1>(0, c)
                    - work.tool.fixed_view::<3, 1>(0, c)
                    - w.cross(&lever));
            work.point.fixed_view_mut::<3, 1>(0, c).copy_from(&dx);
        }
        // camera point: x_c + s·x_c, so ∂ = (1 + s)·∂x_c, plus x_c in the scale's own column
        let gain = inst.scale.map(|i| 1.0 + self.part(i, p)[0]).unwrap_or(1.0);
        for c in 0..self.n_params {
            let dx = work.point.fixed_view::<3, 1>(0, c) * gain;
            out.fixed_view_mut::<3, 1>(2, c).copy_from(&dx);
        }
        if let Some(i) = inst.scale {
            out.fixed_view_mut::<3, 1>(2, self.slots[i].start)
                .copy_from(&x_c);
        }
        // image point: ∂x = (∂X − x ∂Z)/Z, through the lens: ∂x_d = (I + ∂Δ/∂(x, y))·∂(x, y)
        let (x, y, z) = (pred.normalised.x, pred.normalised.y, x_c.z);
        let lens = match inst.distortion {
            Some(i) => image_point_jacobian(self.part(i, p), x, y),
            None => [[0.0; 2]; 2],
        };
        for c in 0..self.n_params {
            let d = work.point.fixed_view::<3, 1>(0, c);
            let (dx, dy) = ((d[0] - x * d[2]) / z, (d[1] - y * d[2]) / z);
            let dxd = dx + lens[0][0] * dx + lens[0][1] * dy;
            let dyd = dy + lens[1][0] * dx + lens[1][1] * dy;
            out[(0, c)] = g.fx * dxd;
            out[(1, c)] = g.fy * dyd;
        }
        if let Some(i) = inst.distortion {
            let sl = self.slots[i];
            let j = self.term(i).term.jacobian(self.part(i, p), s)?;
            for k in 0..sl.len {
                out[(0, sl.start + k)] = g.fx * j[(0, k)];
                out[(1, sl.start + k)] = g.fy * j[(1, k)];
            }
        }
        Ok(pred)
    }
}
