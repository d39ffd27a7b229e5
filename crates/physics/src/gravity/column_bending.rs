//! `column_bending` — a lifting column (prismatic, telescoping: one motor extends nested segments,
//! the others `<mimic>`s of it) tilts under the moment M of the weight it carries (everything after
//! its last segment), perpendicular to its axis:
//!
//! θ = M⊥·[c_foot + c_pads·Σ_i 1/o_i(e)² + c_flex·L(e)],
//!
//! three compliances, each a rotation (vector θ ∥ M⊥: the column leans towards the load) about its own
//! pivot:
//! * `foot` (rad/(N·m)) — its mounting on the base, about the column's foot (the origin of its first
//!   joint);
//! * `pads` (rad·m²/(N·m)) — each sliding overlap, whose guide pads a distance o_i apart turn by
//!   2M/(k·o_i²) (k the pads' stiffness: c_pads = 2/k), about that segment's joint origin; the overlap
//!   shortens as the column extends, o_i(e) = o_i(0) − m_i·e (m_i the segment's share of the extension
//!   e, its mimic multiplier), so the column softens as it rises;
//! * `flexure` (1/(N·m²)) — the tube's bending, 1/(E·I): under a uniform moment its top tilts by
//!   M·L/(EI), about the middle of its length L(e) = L(0) + Σ m_i·e.
//!
//! The tool point p moves by Σ θ_k × (p − pivot_k). Options: `joint` (the column's independent joint),
//! `overlaps` (o_i(0) of its segments in order, m; none: no overlap term), `length` (L(0), foot to
//! top, m; default: the chain's, from its first segment's joint to its last segment's frame). Effect:
//! kinematic (crates/model computes M⊥, the pivots and the overlaps from the chain at the reading).

use nalgebra::DMatrix;

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{EffectKind, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct ColumnBending {
    /// The column's independent (motor) joint.
    pub joint: String,
    /// Overlap of each sliding segment at zero extension, m (as many as segments; may be empty).
    pub overlaps: Vec<f64>,
    /// The column's length from its foot to its top at zero extension, m (None: the chain's own,
    /// from its first segment's joint to its last segment's child frame).
    pub length: Option<f64>,
}

impl ColumnBending {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        let joint = o.text("joint", None)?;
        let overlaps = match o.get_list("overlaps")? {
            None => Vec::new(),
            Some(items) => items
                .iter()
                .map(|v| crate::config::quantity("column_bending", "overlaps", v, "m"))
                .collect::<Result<Vec<_>, _>>()?,
        };
        if overlaps.iter().any(|v| !(*v > 0.0)) {
            return Err(o.bad("overlaps", "each overlap is a positive length"));
        }
        let length = if o.has("length") {
            Some(o.quantity("length", "m", None)?)
        } else {
            None
        };
        if length.is_some_and(|l| !(l > 0.0)) {
            return Err(o.bad("length", "must be positive"));
        }
        Ok(Self {
            joint,
            overlaps,
            length,
        })
    }
}

impl PhysicsTerm for ColumnBending {
    fn id(&self) -> TermId {
        TermId::ColumnBending
    }
    fn label(&self) -> String {
        format!("column_bending[{}]", self.joint)
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Kinematic
    }
    fn params(&self) -> Vec<ParamSpec> {
        let soft = "a negative compliance leans the column away from its load (a counterweight or a preload acting, or the load's masses in the URDF wrong); a larger one than usual is a column softer than a steel column of its size (worn guide pads, a loose foot) or a load heavier than the URDF says";
        vec![
            ParamSpec::new(
                "foot",
                "rad/(N m)",
                0.0,
                1e-4,
                0.0,
                "tilt of the column's foot per N·m of carried moment",
            )
            .unusual_means(soft),
            ParamSpec::new(
                "pads",
                "rad m^2/(N m)",
                0.0,
                1e-5,
                0.0,
                "c_pads = 2/k of the guide pads: an overlap o tilts by c_pads·M/o²",
            )
            .unusual_means(soft),
            ParamSpec::new(
                "flexure",
                "1/(N m^2)",
                0.0,
                1e-5,
                0.0,
                "1/(E·I) of the column's tube",
            )
            .unusual_means(soft),
        ]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::Gravity]
    }
    fn predict(&self, _p: &[f64], _s: &Signals) -> Result<Prediction, PhysicsError> {
        Err(PhysicsError::NeedsKinematics { term: self.label() })
    }
    fn jacobian(&self, _p: &[f64], _s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        Err(PhysicsError::NeedsKinematics { term: self.label() })
    }
}
