//! `camera_scale` — metric scale error of a camera measurement (wrong marker size, focal length
//! or working distance): a camera-frame point is reported at (1 + s)·p.
//!
//! d = s·p,  p = signal `camera_point` (camera frame). Frame: camera.

use nalgebra::DMatrix;

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone, Default)]
pub struct CameraScale {
    /// Instance name (option `instrument`), see [`super::instance`].
    pub instrument: Option<String>,
}

impl CameraScale {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            instrument: super::instance(o)?,
        })
    }
}

impl PhysicsTerm for CameraScale {
    fn id(&self) -> TermId {
        TermId::CameraScale
    }
    fn label(&self) -> String {
        super::instance_label("camera_scale", &self.instrument)
    }
    fn instrument(&self) -> Option<&str> {
        self.instrument.as_deref()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Camera)
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![ParamSpec::new(
            "scale",
            "1",
            -0.05,
            0.05,
            0.0,
            "relative scale error s",
        )]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::CameraPoint]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 1)?;
        Ok(displacement(Frame::Camera, s.camera(self)? * p[0]))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 1)?;
        Ok(DMatrix::from_column_slice(3, 1, s.camera(self)?.as_slice()))
    }
}
