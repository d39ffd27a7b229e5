//! A cell file read as the **model to estimate** (`metrocell calibrate`, `diagnose`, the
//! estimator): the same format as the twin's ([`crate::cell_file`]), with fewer requirements.
//!
//! What a model file needs, and what the loader makes of it:
//! * `machine` — required (family, geometry, travel): the [`MachineGeometry`].
//! * `terms` — the declared error model: the machine [`TermModel`]. Temperature sensors and the
//!   load a term reads are not checked against `sensors.thermocouples` / `environment`: the
//!   recording provides them, and building records names a missing one.
//! * `sensors.tracker` — optional, and its noise model (`rate`, `range_noise`,
//!   `angular_noise`) may be left out, and so may its `pose` (unknown: the identity start,
//!   registered from each recording's points, as without a tracker). Instrument terms, stacked
//!   after the machine terms:
//!   `tracker_pose` from `pose` (the start of the nuisance pose); `tracker_warmup` if `warmup` is
//!   given; `refraction` only if the file gives a weather-station bias (`station`) or
//!   `environment.air.beam_temperature_offset` (the path air minus the station reading).
//!   **Without a tracker** an identity `tracker_pose` is added: fixed by the fit when the records
//!   are in the machine frame, registered and free when they are in an instrument frame.
//! * `estimation` — free/fixed and priors per term label ([`ParameterSetup`]). Defaults: every
//!   parameter free, except `refraction` (a range scale is not separable from the axes' scale
//!   errors and the tracker's position unless the file frees it under `estimation.refraction`).
//! * `environment`, `program` — optional (needed to simulate, not to fit).
//! * `uncertainty` — standard uncertainties of a previous fit, per label and parameter
//!   ([`CellModel::uncertainty`]); `fit` — that fit's summary (ignored).
//!
//! Errors name the file and the key (`model.yaml: cell file: `terms[1] (id `backlash`)`: …`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metrocell_model::{ForwardModel, InstrumentPose, MachineGeometry, ParameterSetup};
use metrocell_physics::config::quantity;
use metrocell_physics::config::ConfigValue;
use metrocell_physics::model::TermModel;
use metrocell_physics::{configure, TermConfig, TermId};

use crate::cell::{
    machine, pose, terms, tracker_station, tracker_term_model, tracker_warmup, RefractionOffsets,
};
use crate::cell_file::CellFile;
use crate::error::CellError;

/// A validated model file.
#[derive(Debug, Clone)]
pub struct CellModel {
    /// The file as named to the loader (for messages).
    pub file: String,
    /// Relative paths in the file (a URDF) are relative to this directory.
    pub base_dir: PathBuf,
    /// The text as read: the writer ([`crate::model_writer`]) edits it, keeping what the user
    /// wrote around the values it changes.
    pub text: String,
    /// The parsed file.
    pub raw: CellFile,
    pub machine: MachineGeometry,
    pub machine_terms: TermModel,
    pub instrument_terms: TermModel,
    /// Free/fixed and priors of the stacked parameter vector (machine terms, then instrument
    /// terms, see [`ForwardModel`]).
    pub setup: ParameterSetup,
    /// True when the file has `sensors.tracker` (with or without `pose`: without one the
    /// loader starts the pose at the identity, as it does for a file without a tracker).
    pub declares_tracker: bool,
}

fn in_file(file: &str, e: CellError) -> CellError {
    CellError::InFile {
        file: file.to_string(),
        error: Box::new(e),
    }
}

impl CellModel {
    /// Read and validate a model file.
    pub fn from_path(path: impl AsRef<Path>) -> Result<CellModel, CellError> {
        let p = path.as_ref();
        let text = std::fs::read_to_string(p).map_err(|e| CellError::Io {
            file: p.display().to_string(),
            reason: e.to_string(),
        })?;
        CellModel::from_yaml_str_in(
            &text,
            &p.display().to_string(),
            p.parent().unwrap_or(Path::new(".")),
        )
    }

    /// Parse and validate a model file's text; `file` names it in errors, relative paths in it
    /// are relative to `base_dir`.
    pub fn from_yaml_str_in(
        text: &str,
        file: &str,
        base_dir: &Path,
    ) -> Result<CellModel, CellError> {
        let raw: CellFile = serde_yaml::from_str(text).map_err(|e| CellError::Yaml {
            file: file.into(),
            message: e.to_string(),
        })?;
        Self::from_parts(text, raw, file, base_dir).map_err(|e| in_file(file, e))
    }

    fn from_parts(
        text: &str,
        raw: CellFile,
        file: &str,
        base_dir: &Path,
    ) -> Result<CellModel, CellError> {
        let machine = machine(&raw.machine, &raw.sensors.accelerometers, base_dir)?;
        let machine_terms = terms(&raw.terms, None, None, &machine)?;
        let (instrument_terms, declares_tracker) = match &raw.sensors.tracker {
            Some(t) => {
                // no pose: unknown, registered from each recording (the start is the identity,
                // as for a file without a tracker)
                let start = match &t.pose {
                    Some(p) => pose(p, "sensors.tracker.pose")?,
                    None => InstrumentPose::from_euler_xyz(nalgebra::Vector3::zeros(), [0.0; 3]),
                };
                let warmup = tracker_warmup(t)?;
                let beam = match &raw.environment {
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
                (
                    tracker_term_model(&start, warmup.as_ref(), refraction)?,
                    true,
                )
            }
            None => (
                tracker_term_model(
                    &InstrumentPose::from_euler_xyz(nalgebra::Vector3::zeros(), [0.0; 3]),
                    None,
                    None,
                )?,
                false,
            ),
        };
        // the probe's pretravel, when the file states it (as the twin reads it)
        let mut instrument_terms = instrument_terms;
        if let Some(pt) = raw
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
            instrument_terms
                .push(term)
                .map_err(|e| CellError::term(path, e))?;
        }
        let model = ForwardModel::new(&machine, &machine_terms, &instrument_terms)
            .map_err(|e| CellError::term("terms", e))?;
        let mut setup = ParameterSetup::new(&model, &raw.estimation)
            .map_err(|e| CellError::term("estimation", e))?;
        if !raw.estimation.contains_key("refraction") {
            if let Some(k) = model.instrument_param_start(TermId::Refraction) {
                setup.free[k..k + 2].iter_mut().for_each(|f| *f = false);
            }
        }
        let out = CellModel {
            file: file.to_string(),
            base_dir: base_dir.to_path_buf(),
            text: text.to_string(),
            raw,
            machine,
            machine_terms,
            instrument_terms,
            setup,
            declares_tracker,
        };
        out.uncertainty()?;
        Ok(out)
    }

    /// The shared forward model of the file (machine terms, then instrument terms).
    pub fn forward_model(&self) -> Result<ForwardModel<'_>, CellError> {
        ForwardModel::new(&self.machine, &self.machine_terms, &self.instrument_terms)
            .map_err(|e| in_file(&self.file, CellError::term("terms", e)))
    }

    /// `label.param` → standard uncertainty (canonical unit) of a previous fit, from the file's
    /// `uncertainty` section; every key is checked against the model's parameters.
    pub fn uncertainty(&self) -> Result<BTreeMap<String, f64>, CellError> {
        let model = ForwardModel::new(&self.machine, &self.machine_terms, &self.instrument_terms)
            .map_err(|e| CellError::term("terms", e))?;
        let specs: Vec<_> = self
            .machine_terms
            .param_specs()
            .into_iter()
            .chain(self.instrument_terms.param_specs())
            .collect();
        let names = model.param_names();
        let mut out = BTreeMap::new();
        for (label, params) in &self.raw.uncertainty {
            for (param, value) in params {
                let name = format!("{label}.{param}");
                let at = format!("uncertainty.{label}.{param}");
                let k = names.iter().position(|n| *n == name).ok_or_else(|| {
                    CellError::invalid(
                        &at,
                        format!(
                            "`{name}` is not a parameter of this model; parameters: {}",
                            names.join(", ")
                        ),
                    )
                })?;
                let u = quantity(label, &at, value, specs[k].unit)
                    .map_err(|e| CellError::term(&at, e))?;
                if !(u.is_finite() && u >= 0.0) {
                    return Err(CellError::OutOfRange {
                        path: at,
                        value: u,
                        reason: "a standard uncertainty is finite and ≥ 0".into(),
                    });
                }
                out.insert(name, u);
            }
        }
        Ok(out)
    }
}

/// The σ of a levelled instrument's residual tilt when the file gives none (a tracker's level).
pub const DEFAULT_TILT_SIGMA: f64 = 50e-6;

impl CellModel {
    /// Fit points a placement's pose needs: three for six free numbers, two for a levelled
    /// instrument's four (yaw and translation; its tilt held by the compensator's prior).
    pub fn placement_fit_points(&self) -> usize {
        if self
            .raw
            .sensors
            .tracker
            .as_ref()
            .is_some_and(|t| t.levelled)
        {
            2
        } else {
            3
        }
    }

    /// The model for records read from several placements of the instrument (a recording's
    /// `setup` column): the file's `tracker_pose` becomes one `tracker_pose[<setup>]` per setup,
    /// each starting where the file's starts, each a nuisance of the fit; the `estimation`
    /// settings of `tracker_pose` hold for each. A levelled instrument (`sensors.tracker.levelled`)
    /// gets the base's tilt (`base_tilt`, free) and, on every pose, a prior of `tilt_sigma` on
    /// its tilt about level (α and β: the tilt of R = Rx(α)·Ry(β)·Rz(δ)'s z axis is theirs
    /// alone). No setups and not levelled: the model as it is.
    pub fn with_setups(&self, setups: &[String]) -> Result<CellModel, CellError> {
        let levelled = self
            .raw
            .sensors
            .tracker
            .as_ref()
            .is_some_and(|t| t.levelled);
        if setups.is_empty() && !levelled {
            return Ok(self.clone());
        }
        let tilt_sigma = match self
            .raw
            .sensors
            .tracker
            .as_ref()
            .and_then(|t| t.tilt_sigma.as_ref())
        {
            Some(q) => q
                .to_si("sensors.tracker.tilt_sigma", "rad")
                .map_err(|e| in_file(&self.file, e))?,
            None => DEFAULT_TILT_SIGMA,
        };
        if !(tilt_sigma > 0.0 && tilt_sigma.is_finite()) {
            return Err(in_file(
                &self.file,
                CellError::invalid(
                    "sensors.tracker.tilt_sigma",
                    format!("must be > 0, got {tilt_sigma} rad"),
                ),
            ));
        }
        let model = self.forward_model()?;
        let values = model.params();
        let mut instruments = TermModel::default();
        let mut offset = model.param_count()
            - self
                .instrument_terms
                .terms
                .iter()
                .map(|t| t.params.len())
                .sum::<usize>();
        for t in &self.instrument_terms.terms {
            let n = t.params.len();
            let own = &values[offset..offset + n];
            offset += n;
            let is_pose = t.term.id() == TermId::TrackerPose && t.term.setup().is_none();
            if !is_pose || setups.is_empty() {
                instruments
                    .push(t.clone())
                    .map_err(|e| in_file(&self.file, CellError::term("sensors.tracker", e)))?;
                continue;
            }
            for setup in setups {
                let mut options = BTreeMap::new();
                options.insert("setup".to_string(), ConfigValue::Text(setup.clone()));
                if let Some(i) = t.term.instrument() {
                    options.insert("instrument".to_string(), ConfigValue::Text(i.to_string()));
                }
                let params = t
                    .term
                    .params()
                    .iter()
                    .zip(own)
                    .map(|(s, v)| (s.name.clone(), ConfigValue::Number(*v)))
                    .collect();
                let term = configure(&TermConfig {
                    id: "tracker_pose".into(),
                    options,
                    params,
                    use_defaults: false,
                })
                .map_err(|e| in_file(&self.file, CellError::term(format!("setup `{setup}`"), e)))?;
                instruments.push(term).map_err(|e| {
                    in_file(&self.file, CellError::term(format!("setup `{setup}`"), e))
                })?;
            }
        }
        if levelled
            && !instruments
                .terms
                .iter()
                .any(|t| t.term.id() == TermId::BaseTilt)
        {
            let term = configure(&TermConfig {
                id: "base_tilt".into(),
                use_defaults: true,
                ..Default::default()
            })
            .map_err(|e| in_file(&self.file, CellError::term("sensors.tracker.levelled", e)))?;
            instruments
                .push(term)
                .map_err(|e| in_file(&self.file, CellError::term("sensors.tracker.levelled", e)))?;
        }
        // the file's settings, those of `tracker_pose` for every setup's pose
        let mut estimation = BTreeMap::new();
        for (label, cfg) in &self.raw.estimation {
            match (label.as_str(), setups.is_empty()) {
                ("tracker_pose", false) => {
                    for s in setups {
                        estimation.insert(format!("tracker_pose[{s}]"), cfg.clone());
                    }
                }
                _ => {
                    estimation.insert(label.clone(), cfg.clone());
                }
            }
        }
        let mut out = CellModel {
            instrument_terms: instruments,
            ..self.clone()
        };
        let fm = out.forward_model()?;
        let mut setup = ParameterSetup::new(&fm, &estimation)
            .map_err(|e| in_file(&self.file, CellError::term("estimation", e)))?;
        // what the file held fixed stays fixed (refraction unless freed)
        for (k, name) in setup.names.iter().enumerate() {
            if let Some(j) = self.setup.names.iter().position(|n| n == name) {
                setup.free[k] = self.setup.free[j];
                setup.priors[k] = setup.priors[k].or(self.setup.priors[j]);
            }
        }
        if levelled {
            for (_, start) in fm.pose_param_starts() {
                for k in [start + 3, start + 4] {
                    setup.priors[k] = Some(metrocell_model::Prior {
                        value: 0.0,
                        sigma: tilt_sigma,
                    });
                }
            }
        }
        drop(fm);
        out.setup = setup;
        Ok(out)
    }
}
