//! The one rule for the **instrument terms** a model loaded from a file carries, stated here
//! and nowhere else ([`instrument_terms`]; every user — `metrocell calibrate`, `diagnose`, the
//! diagnose and estimator nodes, `compensate`, the twin's model half — goes through it):
//!
//! | term | carried when | start value |
//! |---|---|---|
//! | `tracker_pose` | always, first | `sensors.tracker.pose`; the identity when the file has no tracker or no pose (unknown: registered from each recording) |
//! | `tracker_warmup` | `sensors.tracker.warmup` is given | its A, B, τ |
//! | `refraction` | `sensors.tracker.station` or `environment.air.beam_temperature_offset` is given | path air − station reading ([`RefractionOffsets`]) |
//! | `probe_pretravel` | `sensors.probe.pretravel` is given | its parameters |
//! | `turbulence`, `instrument_drift`, `lens_distortion`, `camera_scale` | never: turbulence inflates scatter (flagged by `diagnose`, not a bias), a drift belongs to one recording, the camera's lens is configuration | — |
//!
//! Order of the stacked parameter vector: pose, warm-up, refraction (the tracker's, see
//! [`tracker_term_model`]), then pretravel. Every parameter is free by default except
//! `refraction`'s ([`default_fixed`]). Points already **registered into the machine frame**
//! (the estimator node's measured points) carry the identity pose only, fixed
//! ([`registered_point_instruments`]): the other instrument terms act on raw readings.
//! Placements of one instrument (`tracker_pose[<setup>]`) and a levelled instrument's
//! `base_tilt` are added per recording by [`crate::CellModel::with_setups`].

use std::collections::BTreeMap;

use metrocell_model::{ForwardModel, InstrumentPose, ParameterSetup};
use metrocell_physics::config::ConfigValue;
use metrocell_physics::model::TermModel;
use metrocell_physics::{configure, ConfiguredTerm, EstimationConfig, TermConfig, TermId};

use crate::cell_file::{CellFile, TrackerSection};
use crate::error::CellError;
use crate::machine_section::pose;
use crate::quantity::si_or_zero;

/// A file's instrument terms by [the rule](self).
#[derive(Debug, Clone)]
pub struct InstrumentTerms {
    pub terms: TermModel,
    /// True when the file has `sensors.tracker` (with or without `pose`).
    pub declares_tracker: bool,
}

/// The instrument terms a model loaded from `file` carries: [the rule](self).
pub fn instrument_terms(file: &CellFile) -> Result<InstrumentTerms, CellError> {
    let mut terms = match &file.sensors.tracker {
        Some(t) => {
            // no pose: unknown, registered from each recording (the start is the identity,
            // as for a file without a tracker)
            let start = match &t.pose {
                Some(p) => pose(p, "sensors.tracker.pose")?,
                None => identity(),
            };
            let warmup = tracker_warmup(t)?;
            let beam = match &file.environment {
                Some(env) => env
                    .air
                    .beam_temperature_offset
                    .as_ref()
                    .map(|q| q.to_si("environment.air.beam_temperature_offset", "K"))
                    .transpose()?,
                None => None,
            };
            let refraction = if t.station.is_some() || beam.is_some() {
                let st = tracker_station(t)?;
                Some(RefractionOffsets {
                    temperature: beam.unwrap_or(0.0) - st.temperature_bias,
                    pressure: -st.pressure_bias,
                    humidity: -st.humidity_bias,
                })
            } else {
                None
            };
            tracker_term_model(&start, warmup.as_ref(), refraction)?
        }
        None => tracker_term_model(&identity(), None, None)?,
    };
    if let Some(pt) = file
        .sensors
        .probe
        .as_ref()
        .and_then(|p| p.pretravel.as_ref())
    {
        let path = "sensors.probe.pretravel";
        let term = configure(&TermConfig {
            id: "probe_pretravel".into(),
            options: pt.options.clone(),
            params: pt.params.clone(),
            use_defaults: false,
        })
        .map_err(|e| CellError::term(path, e))?;
        terms.push(term).map_err(|e| CellError::term(path, e))?;
    }
    Ok(InstrumentTerms {
        terms,
        declares_tracker: file.sensors.tracker.is_some(),
    })
}

/// The instrument terms of points registered into the machine frame: the identity
/// `tracker_pose` alone (fixed by [`crate::CellModel::for_registered_points`]).
pub fn registered_point_instruments() -> Result<TermModel, CellError> {
    tracker_term_model(&identity(), None, None)
}

/// The start of an unknown instrument pose.
fn identity() -> InstrumentPose {
    InstrumentPose::from_euler_xyz(nalgebra::Vector3::zeros(), [0.0; 3])
}

/// The parameters a loaded model holds fixed unless the file's `estimation:` frees them:
/// `refraction`'s two path offsets (a range scale is not separable from the axes' scale errors
/// and the tracker's position).
pub fn default_fixed(
    model: &ForwardModel,
    estimation: &BTreeMap<String, EstimationConfig>,
    setup: &mut ParameterSetup,
) {
    if !estimation.contains_key("refraction") {
        if let Some(k) = model.instrument_param_start(TermId::Refraction) {
            setup.free[k..k + 2].iter_mut().for_each(|f| *f = false);
        }
    }
}

/// Warm-up drift of the range, Δρ = A + B·(1 − e^(−t/τ)).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WarmupSpec {
    pub offset: f64,
    pub amplitude: f64,
    pub time_constant: f64,
}

/// Errors of the tracker's weather station (reading − truth, and white noise σ).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct StationSpec {
    pub temperature_bias: f64,
    pub pressure_bias: f64,
    pub humidity_bias: f64,
    pub temperature_noise: f64,
    pub pressure_noise: f64,
    pub humidity_noise: f64,
}

/// The path air minus the weather station's reading (the `refraction` term's parameters and
/// option): temperature K, pressure Pa, humidity %RH.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RefractionOffsets {
    pub temperature: f64,
    pub pressure: f64,
    pub humidity: f64,
}

/// The tracker's instrument terms: `tracker_pose`, then `tracker_warmup` and `refraction` if
/// given (the order of the stacked parameter vector).
pub fn tracker_term_model(
    pose: &InstrumentPose,
    warmup: Option<&WarmupSpec>,
    refraction: Option<RefractionOffsets>,
) -> Result<TermModel, CellError> {
    let mut m = TermModel::default();
    let path = "sensors.tracker";
    let term = |id: &str,
                names: &[&str],
                values: &[f64],
                options: Vec<(&str, f64)>|
     -> Result<ConfiguredTerm, CellError> {
        let params = names
            .iter()
            .zip(values)
            .map(|(n, v)| (n.to_string(), ConfigValue::Number(*v)))
            .collect();
        let options = options
            .into_iter()
            .map(|(k, v)| (k.to_string(), ConfigValue::Number(v)))
            .collect();
        configure(&TermConfig {
            id: id.into(),
            options,
            params,
            use_defaults: false,
        })
        .map_err(|e| CellError::term(path, e))
    };
    let push =
        |m: &mut TermModel, t: ConfiguredTerm| m.push(t).map_err(|e| CellError::term(path, e));
    push(
        &mut m,
        term(
            "tracker_pose",
            &["tx", "ty", "tz", "alpha", "beta", "delta"],
            &pose.term_params(),
            vec![],
        )?,
    )?;
    if let Some(w) = warmup {
        push(
            &mut m,
            term(
                "tracker_warmup",
                &["offset", "amplitude", "time_constant"],
                &[w.offset, w.amplitude, w.time_constant],
                vec![],
            )?,
        )?;
    }
    if let Some(r) = refraction {
        push(
            &mut m,
            term(
                "refraction",
                &["path_temperature_offset", "path_pressure_offset"],
                &[r.temperature, r.pressure],
                vec![("path_humidity_offset", r.humidity)],
            )?,
        )?;
    }
    Ok(m)
}

/// `sensors.tracker.warmup` as the `tracker_warmup` parameters.
pub fn tracker_warmup(t: &TrackerSection) -> Result<Option<WarmupSpec>, CellError> {
    let Some(params) = &t.warmup else {
        return Ok(None);
    };
    let c = configure(&TermConfig {
        id: "tracker_warmup".into(),
        options: BTreeMap::new(),
        params: params.clone(),
        use_defaults: false,
    })
    .map_err(|e| CellError::term("sensors.tracker.warmup", e))?;
    Ok(Some(WarmupSpec {
        offset: c.params[0],
        amplitude: c.params[1],
        time_constant: c.params[2],
    }))
}

/// `sensors.tracker.station` (biases and noise; absent: none).
pub fn tracker_station(t: &TrackerSection) -> Result<StationSpec, CellError> {
    let s = t.station.clone().unwrap_or_default();
    let sp = "sensors.tracker.station";
    Ok(StationSpec {
        temperature_bias: si_or_zero(&s.temperature_bias, &format!("{sp}.temperature_bias"), "K")?,
        pressure_bias: si_or_zero(&s.pressure_bias, &format!("{sp}.pressure_bias"), "Pa")?,
        humidity_bias: si_or_zero(&s.humidity_bias, &format!("{sp}.humidity_bias"), "1")?,
        temperature_noise: s
            .temperature_noise
            .as_ref()
            .map(|q| q.non_negative(&format!("{sp}.temperature_noise"), "K"))
            .transpose()?
            .unwrap_or(0.0),
        pressure_noise: s
            .pressure_noise
            .as_ref()
            .map(|q| q.non_negative(&format!("{sp}.pressure_noise"), "Pa"))
            .transpose()?
            .unwrap_or(0.0),
        humidity_noise: s
            .humidity_noise
            .as_ref()
            .map(|q| q.non_negative(&format!("{sp}.humidity_noise"), "1"))
            .transpose()?
            .unwrap_or(0.0),
    })
}
