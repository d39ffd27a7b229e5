//! The catalog: stable term ids (DESIGN.md vocabulary), their documentation, and construction
//! of a term from a validated [`TermConfig`].

use std::collections::BTreeMap;
use std::fmt;

use crate::config::{quantity, ConfigValue, Options, TermConfig};
use crate::error::PhysicsError;
use crate::geometry::{angular::Angular, backlash::Backlash, frame_misalignment::FrameMisalignment, pitch_cyclic::PitchCyclic, positioning::Positioning, squareness::Squareness, straightness::Straightness};
use crate::instrument::{camera_scale::CameraScale, lens_distortion::LensDistortion, probe_pretravel::ProbePretravel, refraction::Refraction, time_offset::TimeOffset, tracker_pose::TrackerPose, tracker_warmup::TrackerWarmup, turbulence::Turbulence};
use crate::load::{compliance::Compliance, tool_offset::ToolOffset};
use crate::machine_family::KinematicParameters;
use crate::term::PhysicsTerm;
use crate::thermal::{thermal_growth::ThermalGrowth, thermal_scale::ThermalScale, workpiece_expansion::WorkpieceExpansion};

macro_rules! term_ids {
    ($($variant:ident => $id:literal, $cat:ident, $summary:literal, $eq:literal;)*) => {
        /// Stable id of a catalog term.
        #[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
        pub enum TermId { $($variant),* }
        impl TermId {
            /// Every id, in catalog order.
            pub const ALL: &'static [TermId] = &[$(TermId::$variant),*];
            /// The stable string id.
            pub fn as_str(self) -> &'static str { match self { $(TermId::$variant => $id),* } }
            /// Look an id up; `None` if unknown.
            pub fn parse(s: &str) -> Option<TermId> { match s { $($id => Some(TermId::$variant),)* _ => None } }
            pub fn category(self) -> Category { match self { $(TermId::$variant => Category::$cat),* } }
            /// One-line description.
            pub fn summary(self) -> &'static str { match self { $(TermId::$variant => $summary),* } }
            /// The equation the term implements (same as its module docs).
            pub fn equation(self) -> &'static str { match self { $(TermId::$variant => $eq),* } }
        }
    };
}

term_ids! {
    Positioning => "positioning", Geometry, "linear positioning error of an axis (ISO 230-1 E_XX, VDI xTx)", "d = δ_k(q_k)·e_k, δ_k a Legendre/polynomial series over the travel";
    Straightness => "straightness", Geometry, "straightness error of an axis in a perpendicular direction (VDI xTy)", "d = δ_j(q_k)·e_j, j ≠ k";
    Angular => "angular", Geometry, "roll/pitch/yaw of an axis with its Abbe lever (VDI xRx, xRy, xRz)", "d = ε(q_k)·e_a × (r_abbe + Σ_{j∈lever_axes} q_j·e_j)";
    Squareness => "squareness", Geometry, "out-of-squareness of an axis pair (VDI xWy, xWz, yWz; P5 s_xy, s_xz, s_yz)", "xy: d = (−y·s,0,0); xz: d = (−z·s,0,0); yz: d = (0,−z·s,0)";
    PitchCyclic => "pitch_cyclic", Geometry, "periodic ball-screw error repeating every lead", "d = e_k·Σ_h [a_h cos(2πh q/P) + b_h sin(2πh q/P)]";
    Backlash => "backlash", Geometry, "reversal error by sign of approach", "d = −(β/2)·s_k·e_k, s_k = ±1 direction of approach";
    ThermalScale => "thermal_scale", Thermal, "thermal expansion of an axis scale, temperature interpolated between sensors", "d = e_k·α·q_k·(T(q_k) − 20 °C)";
    ThermalGrowth => "thermal_growth", Thermal, "growth of a structural element with its (optionally lagged) temperature", "d = n̂·g·(T_f − 20 °C), T_f = first-order lag (τ) of the sensor history";
    WorkpieceExpansion => "workpiece_expansion", Thermal, "expansion of the workpiece/artefact about its clamp point", "d = α·(T_w − 20 °C)·(p − c)";
    TrackerWarmup => "tracker_warmup", Instrument, "laser-tracker range drift during warm-up", "Δρ = A + B·(1 − e^(−t/τ))";
    Refraction => "refraction", Instrument, "range error from air on the beam differing from the weather station (Edlén)", "Δρ = ρ·(n(t+ΔT, p+Δp, h+Δh)/n(t, p, h) − 1), n = shop-floor Edlén, Δh a fixed option";
    Turbulence => "turbulence", Instrument, "range scatter inflated by turbulence (flagged, not fitted as bias)", "σ = √((σ₀ + s·ρ)² + (c·ρ)²)";
    TrackerPose => "tracker_pose", Instrument, "6-dof pose of the tracker in the frame tool points are reported in (workpiece; an arm's cell frame)", "X_LT = (Rx(α)Ry(β)Rz(δ))ᵀ·(p − T_LT)";
    ProbePretravel => "probe_pretravel", Instrument, "direction-dependent touch-probe pretravel (n-lobe)", "d = [(1−u_z²)(p₀ + a cos nφ + b sin nφ) + u_z² p_z]·u";
    LensDistortion => "lens_distortion", Instrument, "Brown–Conrady radial/tangential lens distortion", "Δx = x(k1r²+k2r⁴+k3r⁶) + 2p1xy + p2(r²+2x²); Δy = y(…) + p1(r²+2y²) + 2p2xy";
    CameraScale => "camera_scale", Instrument, "metric scale error of a camera measurement", "d = s·p (camera frame)";
    TimeOffset => "time_offset", Instrument, "latency between streams", "d = −Δt·v";
    Compliance => "compliance", Load, "deflection under load, growing with moment and extension", "d = F·(c₀ + c_θ e² + c_b e³), e = q_k − e₀";
    ToolOffset => "tool_offset", Load, "error of the tool/probe offset vector", "d = (dx, dy, dz)";
    DeltaRodLength => "delta_rod_length", MachineFamily, "delta diagonal-rod length trims (kinematic term)", "rod length per tower L + ΔL_T; effect via crates/kinematics";
    DeltaRadius => "delta_radius", MachineFamily, "delta radius trims (kinematic term)", "tower radius R + ΔR_T; effect via crates/kinematics";
    DeltaTowerAngle => "delta_tower_angle", MachineFamily, "delta tower angle trims (kinematic term)", "tower angle φ_T + Δφ_T (210°, 330°, 90°); effect via crates/kinematics";
    DeltaEndstop => "delta_endstop", MachineFamily, "delta endstop offsets (kinematic term)", "carriage height h_T + Δh_T; effect via crates/kinematics";
    JointOffset => "joint_offset", MachineFamily, "serial-arm joint zero offsets (kinematic term)", "θ_i + Δθ_i; effect via crates/kinematics";
    LinkLength => "link_length", MachineFamily, "serial-arm link length errors (kinematic term)", "l_i + Δl_i; effect via crates/kinematics";
    FrameMisalignment => "frame_misalignment", Frame, "small rigid misalignment between two frames", "d = ω × (p − o) + t";
}

/// Family a term belongs to (DESIGN.md grouping).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Category {
    Geometry,
    Thermal,
    Instrument,
    Load,
    MachineFamily,
    Frame,
}

impl fmt::Display for TermId {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.as_str())
    }
}

/// Comma-separated list of all ids (for error messages and help).
pub fn allowed_ids() -> String {
    TermId::ALL.iter().map(|t| t.as_str()).collect::<Vec<_>>().join(", ")
}

/// Look an id up, with an error listing the allowed ids.
pub fn lookup(id: &str) -> Result<TermId, PhysicsError> {
    TermId::parse(id).ok_or_else(|| PhysicsError::UnknownTerm { id: id.to_string(), allowed: allowed_ids() })
}

/// Documentation line of one catalog entry.
#[derive(Debug, Clone, PartialEq)]
pub struct CatalogEntry {
    pub id: TermId,
    pub category: Category,
    pub summary: &'static str,
    pub equation: &'static str,
}

/// Every term with its docs, in catalog order.
pub fn entries() -> Vec<CatalogEntry> {
    TermId::ALL.iter().map(|&id| CatalogEntry { id, category: id.category(), summary: id.summary(), equation: id.equation() }).collect()
}

/// A term built from a config, with its validated parameter values (canonical units).
#[derive(Debug)]
pub struct ConfiguredTerm {
    pub term: Box<dyn PhysicsTerm>,
    pub params: Vec<f64>,
}

/// Build the structural part of a term (options only).
pub fn build_term(id: TermId, options: &BTreeMap<String, ConfigValue>) -> Result<Box<dyn PhysicsTerm>, PhysicsError> {
    let o = Options::new(id.as_str(), options);
    let term: Box<dyn PhysicsTerm> = match id {
        TermId::Positioning => Box::new(Positioning::from_options(&o)?),
        TermId::Straightness => Box::new(Straightness::from_options(&o)?),
        TermId::Angular => Box::new(Angular::from_options(&o)?),
        TermId::Squareness => Box::new(Squareness::from_options(&o)?),
        TermId::PitchCyclic => Box::new(PitchCyclic::from_options(&o)?),
        TermId::Backlash => Box::new(Backlash::from_options(&o)?),
        TermId::ThermalScale => Box::new(ThermalScale::from_options(&o)?),
        TermId::ThermalGrowth => Box::new(ThermalGrowth::from_options(&o)?),
        TermId::WorkpieceExpansion => Box::new(WorkpieceExpansion::from_options(&o)?),
        TermId::TrackerWarmup => Box::new(TrackerWarmup::from_options(&o)?),
        TermId::Refraction => Box::new(Refraction::from_options(&o)?),
        TermId::Turbulence => Box::new(Turbulence::from_options(&o)?),
        TermId::TrackerPose => Box::new(TrackerPose::from_options(&o)?),
        TermId::ProbePretravel => Box::new(ProbePretravel::from_options(&o)?),
        TermId::LensDistortion => Box::new(LensDistortion::from_options(&o)?),
        TermId::CameraScale => Box::new(CameraScale::from_options(&o)?),
        TermId::TimeOffset => Box::new(TimeOffset::from_options(&o)?),
        TermId::Compliance => Box::new(Compliance::from_options(&o)?),
        TermId::ToolOffset => Box::new(ToolOffset::from_options(&o)?),
        TermId::FrameMisalignment => Box::new(FrameMisalignment::from_options(&o)?),
        TermId::DeltaRodLength | TermId::DeltaRadius | TermId::DeltaTowerAngle | TermId::DeltaEndstop | TermId::JointOffset | TermId::LinkLength => Box::new(KinematicParameters::from_options(id, &o)?),
    };
    o.finish()?;
    Ok(term)
}

/// Build a term and validate its parameters: unknown id (error lists the allowed ids), unknown
/// option or parameter, missing parameter (unless `use_defaults`), unit of the wrong dimension
/// (error names the key and the allowed unit), value outside the plausible range.
pub fn configure(config: &TermConfig) -> Result<ConfiguredTerm, PhysicsError> {
    let id = lookup(&config.id)?;
    let term = build_term(id, &config.options)?;
    let specs = term.params();
    let label = term.label();
    for key in config.params.keys() {
        if !specs.iter().any(|s| &s.name == key) {
            return Err(PhysicsError::UnknownParameter { term: label, param: key.clone(), allowed: specs.iter().map(|s| s.name.as_str()).collect::<Vec<_>>().join(", ") });
        }
    }
    let mut params = Vec::with_capacity(specs.len());
    for spec in &specs {
        let value = match config.params.get(&spec.name) {
            Some(v) => quantity(&label, &spec.name, v, spec.unit)?,
            None if config.use_defaults => spec.default,
            None => return Err(PhysicsError::MissingParameter { term: label, param: spec.name.clone(), unit: spec.unit.into() }),
        };
        if !(value >= spec.min && value <= spec.max) {
            return Err(PhysicsError::OutOfRange { term: label, param: spec.name.clone(), value, unit: spec.unit.into(), min: spec.min, max: spec.max });
        }
        params.push(value);
    }
    Ok(ConfiguredTerm { term, params })
}

/// A representative config of each id (used by docs, tests and `metrocell` help output).
pub fn example_config(id: TermId) -> TermConfig {
    fn t(s: &str) -> ConfigValue {
        ConfigValue::Text(s.into())
    }
    fn n(x: f64) -> ConfigValue {
        ConfigValue::Number(x)
    }
    fn l(v: Vec<ConfigValue>) -> ConfigValue {
        ConfigValue::List(v)
    }
    fn sensor(name: &str, pos: f64) -> ConfigValue {
        ConfigValue::Map([("name".to_string(), t(name)), ("position".to_string(), n(pos))].into_iter().collect())
    }
    let opts: Vec<(&str, ConfigValue)> = match id {
        TermId::Positioning => vec![("axis", t("x")), ("order", n(2.0)), ("travel", l(vec![n(0.0), t("800 mm")]))],
        TermId::Straightness => vec![("axis", t("x")), ("direction", t("y")), ("order", n(2.0)), ("travel", l(vec![n(0.0), n(0.8)]))],
        TermId::Angular => vec![("axis", t("y")), ("about", t("x")), ("lever_axes", l(vec![t("z")])), ("abbe_offset", l(vec![n(0.0), n(0.0), t("-150 mm")])), ("travel", l(vec![n(0.0), n(0.5)]))],
        TermId::Squareness => vec![("pair", t("xy"))],
        TermId::PitchCyclic => vec![("axis", t("x")), ("lead", t("10 mm")), ("harmonics", n(2.0))],
        TermId::Backlash => vec![("axis", t("y"))],
        TermId::ThermalScale => vec![("axis", t("x")), ("sensors", l(vec![sensor("x_left", 0.0), sensor("x_right", 1.2)]))],
        TermId::ThermalGrowth => vec![("sensor", t("column")), ("direction", l(vec![n(0.0), n(0.0), n(-1.0)])), ("lag", ConfigValue::Bool(true))],
        TermId::WorkpieceExpansion => vec![("sensor", t("plate")), ("clamp", l(vec![t("200 mm"), t("250 mm"), n(0.0)]))],
        TermId::Compliance => vec![("extension_axis", t("z"))],
        TermId::JointOffset => vec![("joints", n(6.0))],
        TermId::LinkLength => vec![("links", n(6.0))],
        _ => vec![],
    };
    TermConfig { id: id.as_str().into(), options: opts.into_iter().map(|(k, v)| (k.to_string(), v)).collect(), params: BTreeMap::new(), use_defaults: true }
}
