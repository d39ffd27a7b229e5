//! `tool_offset` — error of the tool (or probe, or reflector) offset vector T: length and
//! radius errors of the tool as mounted.
//!
//! d = (dx, dy, dz)  in the tool frame ([`Frame::Tool`]). On a 3-axis machine and a five-axis
//! spindle the tool frame is parallel to the machine frame, so d is a machine-frame
//! displacement; where the tool turns (an arm's flange) the caller turns it with the tool,
//! R_tool(q)·d (crates/twin does).

use nalgebra::{DMatrix, Vector3};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone, Default)]
pub struct ToolOffset;

impl ToolOffset {
    pub fn from_options(_o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self)
    }
}

impl PhysicsTerm for ToolOffset {
    fn id(&self) -> TermId {
        TermId::ToolOffset
    }
    fn label(&self) -> String {
        "tool_offset".into()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Tool)
    }
    fn params(&self) -> Vec<ParamSpec> {
        ["dx", "dy", "dz"]
            .iter()
            .map(|n| {
                ParamSpec::new(
                    *n,
                    "m",
                    -0.05,
                    0.05,
                    0.0,
                    format!("tool offset error along {}", &n[1..]),
                )
            })
            .collect()
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![]
    }
    fn predict(&self, p: &[f64], _s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 3)?;
        Ok(displacement(Frame::Tool, Vector3::new(p[0], p[1], p[2])))
    }
    fn jacobian(&self, p: &[f64], _s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 3)?;
        Ok(DMatrix::identity(3, 3))
    }
}
