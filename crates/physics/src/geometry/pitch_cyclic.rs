//! `pitch_cyclic` — periodic (cyclic) error of a ball screw, repeating every screw lead.
//!
//! d = e_k · Σ_{h=1..H} [a_h·cos(2π·h·q_k/P) + b_h·sin(2π·h·q_k/P)]
//!
//! P is the screw lead (option `lead`, m), H the number of harmonics (option `harmonics`,
//! default 1). Frame: machine, tool relative to workpiece. Options: `axis`, `lead`, `harmonics`.

use nalgebra::DMatrix;
use std::f64::consts::TAU;

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{Axis, SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct PitchCyclic {
    pub axis: Axis,
    pub lead: f64,
    pub harmonics: usize,
}

impl PitchCyclic {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        let lead = o.quantity("lead", "m", None)?;
        if !(lead > 0.0) {
            return Err(o.bad("lead", format!("must be positive, got {lead} m")));
        }
        let harmonics = o.count("harmonics", 1, 8)?;
        if harmonics == 0 {
            return Err(o.bad("harmonics", "must be at least 1"));
        }
        Ok(Self {
            axis: o.axis("axis", None)?,
            lead,
            harmonics,
        })
    }
    fn row(&self, q: f64) -> Vec<f64> {
        let mut r = Vec::with_capacity(2 * self.harmonics);
        for h in 1..=self.harmonics {
            let ph = TAU * h as f64 * q / self.lead;
            r.push(ph.cos());
            r.push(ph.sin());
        }
        r
    }
}

impl PhysicsTerm for PitchCyclic {
    fn id(&self) -> TermId {
        TermId::PitchCyclic
    }
    fn label(&self) -> String {
        format!("pitch_cyclic[{}]", self.axis)
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Machine)
    }
    fn params(&self) -> Vec<ParamSpec> {
        let mut v = Vec::new();
        for h in 1..=self.harmonics {
            v.push(ParamSpec::new(
                format!("a{h}"),
                "m",
                -50e-6,
                50e-6,
                0.0,
                format!("cosine amplitude of harmonic {h}"),
            ));
            v.push(ParamSpec::new(
                format!("b{h}"),
                "m",
                -50e-6,
                50e-6,
                0.0,
                format!("sine amplitude of harmonic {h}"),
            ));
        }
        v
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::AxisPosition(self.axis)]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 2 * self.harmonics)?;
        let q = s.position(self, self.axis)?;
        let v: f64 = self.row(q).iter().zip(p).map(|(a, b)| a * b).sum();
        Ok(displacement(Frame::Machine, self.axis.unit() * v))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 2 * self.harmonics)?;
        let q = s.position(self, self.axis)?;
        let mut j = DMatrix::zeros(3, p.len());
        for (i, r) in self.row(q).into_iter().enumerate() {
            j[(self.axis.index(), i)] = r;
        }
        Ok(j)
    }
}
