//! `probe_pretravel` — direction-dependent pretravel of a touch-trigger probe (lobing).
//!
//! With u the unit probing direction in the probe frame, φ = atan2(u_y, u_x), h = 1 − u_z²:
//!   pt(u) = h·(p₀ + a·cos(nφ) + b·sin(nφ)) + u_z²·p_z
//!   d = pt(u)·u
//! The probe triggers only after the stylus has deflected by pt beyond the contact, so the
//! recorded point lies pt further along the approach direction. n = `lobes` (default 3: the
//! kinematic three-point seat gives the trigonal pattern 120° apart seen in thesis Ch. 5.4).
//! Frame: probe. Options: `lobes`.

use nalgebra::{DMatrix, Vector3};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct ProbePretravel {
    pub lobes: usize,
    /// Instance name (option `instrument`), see [`super::instance`].
    pub instrument: Option<String>,
}

impl ProbePretravel {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        let lobes = o.count("lobes", 3, 12)?;
        if lobes == 0 {
            return Err(o.bad("lobes", "must be at least 1"));
        }
        Ok(Self {
            lobes,
            instrument: super::instance(o)?,
        })
    }
    /// The term of an unnamed probe with `lobes` lobes.
    pub fn new(lobes: usize) -> Self {
        Self {
            lobes,
            instrument: None,
        }
    }
    /// ∂pt/∂(p0, a, b, pz) and the direction.
    fn row(&self, s: &Signals) -> Result<([f64; 4], Vector3<f64>), PhysicsError> {
        let u = s.probe_dir(self)?;
        let phi = u.y.atan2(u.x);
        let h = 1.0 - u.z * u.z;
        let n = self.lobes as f64;
        Ok(([h, h * (n * phi).cos(), h * (n * phi).sin(), u.z * u.z], u))
    }
}

impl PhysicsTerm for ProbePretravel {
    fn id(&self) -> TermId {
        TermId::ProbePretravel
    }
    fn label(&self) -> String {
        super::instance_label("probe_pretravel", &self.instrument)
    }
    fn instrument(&self) -> Option<&str> {
        self.instrument.as_deref()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Probe)
    }
    fn params(&self) -> Vec<ParamSpec> {
        vec![
            ParamSpec::new(
                "mean",
                "m",
                -20e-6,
                100e-6,
                0.0,
                "p₀: mean lateral pretravel",
            )
            .unusual_means(
                "a negative mean pretravel: the stylus radius or probe qualification over-corrects",
            ),
            ParamSpec::new(
                "lobe_cos",
                "m",
                -50e-6,
                50e-6,
                0.0,
                "a: lobing amplitude, cosine part",
            ),
            ParamSpec::new(
                "lobe_sin",
                "m",
                -50e-6,
                50e-6,
                0.0,
                "b: lobing amplitude, sine part",
            ),
            ParamSpec::new(
                "vertical",
                "m",
                -20e-6,
                100e-6,
                0.0,
                "p_z: pretravel along the stylus axis",
            ),
        ]
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![SignalKind::ProbeDirection]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 4)?;
        let (r, u) = self.row(s)?;
        let pt: f64 = r.iter().zip(p).map(|(a, b)| a * b).sum();
        Ok(displacement(Frame::Probe, u * pt))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 4)?;
        let (r, u) = self.row(s)?;
        let mut j = DMatrix::zeros(3, 4);
        for (k, v) in r.iter().enumerate() {
            j.set_column(k, &(u * *v));
        }
        Ok(j)
    }
}
