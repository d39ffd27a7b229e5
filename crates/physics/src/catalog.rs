//! The catalog: stable term ids (DESIGN.md vocabulary), their documentation, and construction
//! of a term from a validated [`TermConfig`].

use std::collections::BTreeMap;

use crate::config::{quantity, ConfigValue, Options, TermConfig};
use crate::error::PhysicsError;
use crate::geometry::{
    angular::Angular, backlash::Backlash, frame_misalignment::FrameMisalignment,
    pitch_cyclic::PitchCyclic, positioning::Positioning, rotary_axis_location::RotaryAxisLocation,
    squareness::Squareness, straightness::Straightness,
};
use crate::gravity::{
    column_bending::ColumnBending, joint_backlash::JointBacklash,
    joint_compliance::JointCompliance, link_thermal_expansion::LinkThermalExpansion,
};
use crate::instrument::{
    base_tilt::BaseTilt, camera_scale::CameraScale, instrument_drift::InstrumentDrift,
    lens_distortion::LensDistortion, probe_pretravel::ProbePretravel, refraction::Refraction,
    time_offset::TimeOffset, tracker_pose::TrackerPose, tracker_warmup::TrackerWarmup,
    turbulence::Turbulence,
};
use crate::load::{compliance::Compliance, tool_offset::ToolOffset};
use crate::machine_family::KinematicParameters;
use crate::term::PhysicsTerm;
pub use crate::term_id::{Category, TermId};
use crate::thermal::{
    thermal_growth::ThermalGrowth, thermal_scale::ThermalScale,
    workpiece_expansion::WorkpieceExpansion,
};

/// Comma-separated list of all ids (for error messages and help).
pub fn allowed_ids() -> String {
    TermId::ALL
        .iter()
        .map(|t| t.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// Look an id up, with an error listing the allowed ids.
pub fn lookup(id: &str) -> Result<TermId, PhysicsError> {
    TermId::parse(id).ok_or_else(|| PhysicsError::UnknownTerm {
        id: id.to_string(),
        allowed: allowed_ids(),
    })
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
    TermId::ALL
        .iter()
        .map(|&id| CatalogEntry {
            id,
            category: id.category(),
            summary: id.summary(),
            equation: id.equation(),
        })
        .collect()
}

/// A term built from a config, with its validated parameter values (canonical units).
#[derive(Debug, Clone)]
pub struct ConfiguredTerm {
    pub term: Box<dyn PhysicsTerm>,
    pub params: Vec<f64>,
    /// The structural options it was built from (as a cell file's `options:` holds them), so
    /// the term can be described to a consumer that rebuilds it ([`build_term`]), e.g. in an
    /// `ErrorModel` message.
    pub options: BTreeMap<String, ConfigValue>,
}

/// Build the structural part of a term (options only).
pub fn build_term(
    id: TermId,
    options: &BTreeMap<String, ConfigValue>,
) -> Result<Box<dyn PhysicsTerm>, PhysicsError> {
    let o = Options::new(id.as_str(), options);
    let term: Box<dyn PhysicsTerm> = match id {
        TermId::Positioning => Box::new(Positioning::from_options(&o)?),
        TermId::Straightness => Box::new(Straightness::from_options(&o)?),
        TermId::Angular => Box::new(Angular::from_options(&o)?),
        TermId::Squareness => Box::new(Squareness::from_options(&o)?),
        TermId::PitchCyclic => Box::new(PitchCyclic::from_options(&o)?),
        TermId::Backlash => Box::new(Backlash::from_options(&o)?),
        TermId::RotaryAxisLocation => Box::new(RotaryAxisLocation::from_options(&o)?),
        TermId::ThermalScale => Box::new(ThermalScale::from_options(&o)?),
        TermId::ThermalGrowth => Box::new(ThermalGrowth::from_options(&o)?),
        TermId::WorkpieceExpansion => Box::new(WorkpieceExpansion::from_options(&o)?),
        TermId::TrackerWarmup => Box::new(TrackerWarmup::from_options(&o)?),
        TermId::InstrumentDrift => Box::new(InstrumentDrift::from_options(&o)?),
        TermId::Refraction => Box::new(Refraction::from_options(&o)?),
        TermId::Turbulence => Box::new(Turbulence::from_options(&o)?),
        TermId::TrackerPose => Box::new(TrackerPose::from_options(&o)?),
        TermId::BaseTilt => Box::new(BaseTilt::from_options(&o)?),
        TermId::ProbePretravel => Box::new(ProbePretravel::from_options(&o)?),
        TermId::LensDistortion => Box::new(LensDistortion::from_options(&o)?),
        TermId::CameraScale => Box::new(CameraScale::from_options(&o)?),
        TermId::TimeOffset => Box::new(TimeOffset::from_options(&o)?),
        TermId::Compliance => Box::new(Compliance::from_options(&o)?),
        TermId::ToolOffset => Box::new(ToolOffset::from_options(&o)?),
        TermId::FrameMisalignment => Box::new(FrameMisalignment::from_options(&o)?),
        TermId::JointCompliance => Box::new(JointCompliance::from_options(&o)?),
        TermId::JointBacklash => Box::new(JointBacklash::from_options(&o)?),
        TermId::ColumnBending => Box::new(ColumnBending::from_options(&o)?),
        TermId::LinkThermalExpansion => Box::new(LinkThermalExpansion::from_options(&o)?),
        TermId::DeltaRodLength
        | TermId::DeltaRadius
        | TermId::DeltaTowerAngle
        | TermId::DeltaEndstop
        | TermId::JointOffset
        | TermId::LinkLength => Box::new(KinematicParameters::from_options(id, &o)?),
    };
    o.finish()?;
    Ok(term)
}

impl ConfiguredTerm {
    /// Its options as a JSON object: the `term_options` entry of an `ErrorModel` message, read
    /// back by [`configure_described`].
    pub fn options_json(&self) -> String {
        serde_json::to_string(&self.options).unwrap_or_else(|_| "{}".to_string())
    }
}

/// Rebuild a term a message described: its catalog id, its options as a JSON object (as
/// [`ConfiguredTerm::options_json`] writes them) and its parameter values in catalog order,
/// canonical units. Errors name the term and what is wrong (unknown id, bad JSON, an option
/// the term rejects, the wrong number of values).
pub fn configure_described(
    id: &str,
    options_json: &str,
    params: &[f64],
) -> Result<ConfiguredTerm, PhysicsError> {
    let term_id = lookup(id)?;
    let options: BTreeMap<String, ConfigValue> =
        serde_json::from_str(options_json).map_err(|e| PhysicsError::InvalidInput {
            what: format!("options of term {id}"),
            reason: format!("not a JSON object of options ({e}): {options_json}"),
        })?;
    let term = build_term(term_id, &options)?;
    let expected = term.params().len();
    if params.len() != expected {
        return Err(PhysicsError::InvalidInput {
            what: format!("parameters of {}", term.label()),
            reason: format!("{} values given, the term has {expected}", params.len()),
        });
    }
    Ok(ConfiguredTerm {
        term,
        params: params.to_vec(),
        options,
    })
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
            return Err(PhysicsError::UnknownParameter {
                term: label,
                param: key.clone(),
                allowed: specs
                    .iter()
                    .map(|s| s.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
            });
        }
    }
    let mut params = Vec::with_capacity(specs.len());
    for spec in &specs {
        let value = match config.params.get(&spec.name) {
            Some(v) => quantity(&label, &spec.name, v, spec.unit)?,
            None if config.use_defaults => spec.default,
            None => {
                return Err(PhysicsError::MissingParameter {
                    term: label,
                    param: spec.name.clone(),
                    unit: spec.unit.into(),
                })
            }
        };
        if !spec.possible.contains(value) {
            return Err(PhysicsError::OutOfRange {
                term: label,
                param: spec.name.clone(),
                value,
                unit: spec.unit.into(),
                min: spec.possible.lo,
                max: spec.possible.hi,
            });
        }
        params.push(value);
    }
    Ok(ConfiguredTerm {
        term,
        params,
        options: config.options.clone(),
    })
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
        ConfigValue::Map(
            [
                ("name".to_string(), t(name)),
                ("position".to_string(), n(pos)),
            ]
            .into_iter()
            .collect(),
        )
    }
    let opts: Vec<(&str, ConfigValue)> = match id {
        TermId::Positioning => vec![
            ("axis", t("x")),
            ("order", n(2.0)),
            ("travel", l(vec![n(0.0), t("800 mm")])),
        ],
        TermId::Straightness => vec![
            ("axis", t("x")),
            ("direction", t("y")),
            ("order", n(2.0)),
            ("travel", l(vec![n(0.0), n(0.8)])),
        ],
        TermId::Angular => vec![
            ("axis", t("y")),
            ("about", t("x")),
            ("lever_axes", l(vec![t("z")])),
            ("abbe_offset", l(vec![n(0.0), n(0.0), t("-150 mm")])),
            ("travel", l(vec![n(0.0), n(0.5)])),
        ],
        TermId::Squareness => vec![("pair", t("xy"))],
        TermId::PitchCyclic => vec![
            ("axis", t("x")),
            ("lead", t("10 mm")),
            ("harmonics", n(2.0)),
        ],
        TermId::Backlash => vec![("axis", t("y"))],
        TermId::RotaryAxisLocation => vec![
            ("b_pivot", l(vec![t("500 mm"), t("500 mm"), t("150 mm")])),
            ("c_offset", l(vec![n(0.0), n(0.0), t("50 mm")])),
        ],
        TermId::ThermalScale => vec![
            ("axis", t("x")),
            (
                "sensors",
                l(vec![sensor("x_left", 0.0), sensor("x_right", 1.2)]),
            ),
        ],
        TermId::ThermalGrowth => vec![
            ("sensor", t("column")),
            ("direction", l(vec![n(0.0), n(0.0), n(-1.0)])),
            ("lag", ConfigValue::Bool(true)),
        ],
        TermId::WorkpieceExpansion => vec![
            ("sensor", t("plate")),
            ("clamp", l(vec![t("200 mm"), t("250 mm"), n(0.0)])),
        ],
        TermId::Compliance => vec![("extension_axis", t("z"))],
        TermId::JointOffset => vec![("joints", n(6.0))],
        TermId::LinkLength => vec![("links", n(6.0))],
        TermId::InstrumentDrift => vec![("order", n(1.0)), ("span", l(vec![n(0.0), t("5 h")]))],
        TermId::JointCompliance | TermId::JointBacklash => {
            vec![("joints", l(vec![t("shoulder_lift"), t("elbow")]))]
        }
        TermId::ColumnBending => vec![
            ("joint", t("column_lower")),
            ("overlaps", l(vec![t("800 mm"), t("900 mm")])),
            ("length", t("950 mm")),
        ],
        TermId::LinkThermalExpansion => vec![("sensor", t("ambient"))],
        _ => vec![],
    };
    TermConfig {
        id: id.as_str().into(),
        options: opts.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
        params: BTreeMap::new(),
        use_defaults: true,
    }
}
