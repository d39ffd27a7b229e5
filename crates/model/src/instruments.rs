//! The instruments of a forward model: the instrument terms grouped by instrument.
//!
//! Each instrument term belongs to a tracker (`tracker_pose`, `tracker_warmup`, `refraction`,
//! `turbulence`), a touch probe (`probe_pretravel`) or a camera (`camera_scale`,
//! `lens_distortion`). Terms are grouped by kind and by their `instrument` option: a cell with
//! one tracker writes none (labels `tracker_pose`, `refraction`, …); a cell with two names both
//! (`tracker_pose[lt1]`, `refraction[lt1]`, `tracker_pose[lt2]`, …), so every label is unique and
//! each instrument's readings depend on its own terms only. A prediction names its instrument
//! (`None` = the model's only instrument of that kind).
//!
//! A camera also needs its geometry ([`CameraGeometry`]: mount on the tool and pinhole
//! intrinsics), which is configuration rather than a fitted term: [`ForwardModel::with_camera`].

use metrocell_physics::{ConfiguredTerm, PhysicsError, TermId};

use crate::forward::ForwardModel;
use crate::instrument_pose::InstrumentPose;

/// What an instrument is.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum InstrumentKind {
    Tracker,
    Probe,
    Camera,
}

impl InstrumentKind {
    /// The kind an instrument term belongs to (None for machine terms).
    pub fn of(id: TermId) -> Option<Self> {
        match id {
            TermId::TrackerPose
            | TermId::BaseTilt
            | TermId::TrackerWarmup
            | TermId::Refraction
            | TermId::Turbulence
            | TermId::InstrumentDrift => Some(Self::Tracker),
            TermId::ProbePretravel => Some(Self::Probe),
            TermId::CameraScale | TermId::LensDistortion => Some(Self::Camera),
            _ => None,
        }
    }
    pub fn name(self) -> &'static str {
        match self {
            Self::Tracker => "tracker",
            Self::Probe => "probe",
            Self::Camera => "camera",
        }
    }
}

/// Geometry of a camera: where it sits on the tool and its pinhole intrinsics. Convention
/// (stated once): `mount` is the camera's optical frame (x right, y down, z along the optical
/// axis) in the tool frame of the family (see [`crate::machine`]): `p_tool = R·p_cam + T`; the
/// camera turns with the tool. Pixels as OpenCV: u = fx·x_d + cx, v = fy·y_d + cy, with
/// (x_d, y_d) the distorted normalised image point and the top-left pixel's centre at (0, 0).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraGeometry {
    pub mount: InstrumentPose,
    pub fx: f64,
    pub fy: f64,
    pub cx: f64,
    pub cy: f64,
}

/// One instrument: its kind, instance name and the (global) indices of its terms.
#[derive(Debug, Clone, PartialEq)]
pub struct Instrument {
    pub kind: InstrumentKind,
    /// The terms' `instrument` option (None: unnamed).
    pub name: Option<String>,
    /// The pose for every reading (a `tracker_pose` without option `setup`).
    pub(crate) pose: Option<usize>,
    /// The poses of the instrument's placements (`tracker_pose` with option `setup`), by setup.
    pub(crate) setup_poses: Vec<(String, usize)>,
    /// `base_tilt`: the base's tilt from level, for a levelled instrument.
    pub(crate) tilt: Option<usize>,
    pub(crate) warmup: Option<usize>,
    pub(crate) refraction: Option<usize>,
    /// `instrument_drift`: the pose's change in time.
    pub(crate) drift: Option<usize>,
    pub(crate) pretravel: Option<usize>,
    pub(crate) scale: Option<usize>,
    pub(crate) distortion: Option<usize>,
    pub(crate) camera: Option<CameraGeometry>,
}

impl Instrument {
    fn new(kind: InstrumentKind, name: Option<String>) -> Self {
        Self {
            kind,
            name,
            pose: None,
            setup_poses: Vec::new(),
            tilt: None,
            warmup: None,
            refraction: None,
            drift: None,
            pretravel: None,
            scale: None,
            distortion: None,
            camera: None,
        }
    }
    /// `tracker`, `tracker lt1`, … for messages.
    pub fn describe(&self) -> String {
        match &self.name {
            Some(n) => format!("{} `{n}`", self.kind.name()),
            None => self.kind.name().to_string(),
        }
    }
    /// The setups (placements) the instrument has a pose for, in the model's order.
    pub fn setups(&self) -> impl Iterator<Item = &str> {
        self.setup_poses.iter().map(|(s, _)| s.as_str())
    }
    /// The camera geometry, if this is a camera that has one.
    pub fn camera_geometry(&self) -> Option<&CameraGeometry> {
        self.camera.as_ref()
    }
}

/// Group instrument terms (global term index = `first` + their index) by kind and name.
pub(crate) fn group_instruments(
    first: usize,
    terms: &[ConfiguredTerm],
) -> Result<Vec<Instrument>, PhysicsError> {
    let mut out: Vec<Instrument> = Vec::new();
    for (k, t) in terms.iter().enumerate() {
        let id = t.term.id();
        let label = t.term.label();
        let kind = InstrumentKind::of(id).ok_or_else(|| PhysicsError::InvalidInput {
            what: format!("forward model, term `{label}`"),
            reason: "is not an instrument term (tracker: tracker_pose, base_tilt, tracker_warmup, refraction, turbulence, instrument_drift; probe: probe_pretravel; camera: camera_scale, lens_distortion)".into(),
        })?;
        let name = t.term.instrument().map(str::to_string);
        let at = match out.iter().position(|i| i.kind == kind && i.name == name) {
            Some(at) => at,
            None => {
                out.push(Instrument::new(kind, name));
                out.len() - 1
            }
        };
        let inst = &mut out[at];
        if let (TermId::TrackerPose, Some(setup)) = (id, t.term.setup()) {
            if inst.setup_poses.iter().any(|(s, _)| s == setup) {
                return Err(PhysicsError::InvalidInput {
                    what: format!("forward model, term `{label}`"),
                    reason: format!(
                        "is given twice for setup `{setup}` of the {}",
                        inst.describe()
                    ),
                });
            }
            inst.setup_poses.push((setup.to_string(), first + k));
            continue;
        }
        let slot = match id {
            TermId::TrackerPose => &mut inst.pose,
            TermId::BaseTilt => &mut inst.tilt,
            TermId::TrackerWarmup => &mut inst.warmup,
            TermId::Refraction => &mut inst.refraction,
            TermId::InstrumentDrift => &mut inst.drift,
            TermId::ProbePretravel => &mut inst.pretravel,
            TermId::CameraScale => &mut inst.scale,
            TermId::LensDistortion => &mut inst.distortion,
            // turbulence is a scatter: it never enters a prediction
            _ => continue,
        };
        if slot.replace(first + k).is_some() {
            return Err(PhysicsError::InvalidInput {
                what: format!("forward model, term `{label}`"),
                reason: format!("is given twice for the {}", inst.describe()),
            });
        }
    }
    Ok(out)
}

impl<'a> ForwardModel<'a> {
    /// The model's instruments (grouped instrument terms, and cameras given geometry).
    pub fn instruments(&self) -> &[Instrument] {
        &self.instruments
    }

    /// Index into [`Self::instruments`] of the `kind` instrument named `name` (None: the only
    /// one of that kind). `Ok(None)` if there is none; an error if `name` is None and there are
    /// several.
    pub fn instrument(
        &self,
        kind: InstrumentKind,
        name: Option<&str>,
    ) -> Result<Option<usize>, PhysicsError> {
        let mut found = self
            .instruments
            .iter()
            .enumerate()
            .filter(|(_, i)| i.kind == kind && (name.is_none() || i.name.as_deref() == name));
        let first = found.next().map(|(k, _)| k);
        if name.is_none() && found.next().is_some() {
            let names: Vec<String> = self
                .instruments
                .iter()
                .filter(|i| i.kind == kind)
                .map(|i| i.name.clone().unwrap_or_else(|| "(unnamed)".into()))
                .collect();
            return Err(PhysicsError::InvalidInput {
                what: format!("forward model, {} reading", kind.name()),
                reason: format!(
                    "the model has {} {}s ({}): name the instrument",
                    names.len(),
                    kind.name(),
                    names.join(", ")
                ),
            });
        }
        Ok(first)
    }

    /// The instrument a reading needs, or an error naming what is missing.
    pub(crate) fn require(
        &self,
        kind: InstrumentKind,
        name: Option<&str>,
    ) -> Result<&Instrument, PhysicsError> {
        let k = self
            .instrument(kind, name)?
            .ok_or_else(|| PhysicsError::InvalidInput {
                what: format!("forward model, {} reading", kind.name()),
                reason: match name {
                    Some(n) => format!("the model has no {} named `{n}`", kind.name()),
                    None => format!("the model has no {}", kind.name()),
                },
            })?;
        Ok(&self.instruments[k])
    }

    /// Give the camera `name` (None: unnamed) its geometry; a camera without terms is added.
    /// Errors on non-positive or non-finite intrinsics.
    pub fn with_camera(
        mut self,
        name: Option<&str>,
        geometry: CameraGeometry,
    ) -> Result<Self, PhysicsError> {
        let g = &geometry;
        if !(g.fx > 0.0
            && g.fy > 0.0
            && g.fx.is_finite()
            && g.fy.is_finite()
            && g.cx.is_finite()
            && g.cy.is_finite())
        {
            return Err(PhysicsError::InvalidInput {
                what: "forward model, camera geometry".into(),
                reason: format!(
                    "needs fx, fy > 0 and finite cx, cy (px), got fx {}, fy {}, cx {}, cy {}",
                    g.fx, g.fy, g.cx, g.cy
                ),
            });
        }
        let name = name.map(str::to_string);
        match self
            .instruments
            .iter_mut()
            .find(|i| i.kind == InstrumentKind::Camera && i.name == name)
        {
            Some(i) => i.camera = Some(geometry),
            None => {
                let mut i = Instrument::new(InstrumentKind::Camera, name);
                i.camera = Some(geometry);
                self.instruments.push(i);
            }
        }
        Ok(self)
    }
}
