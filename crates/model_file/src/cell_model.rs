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
//!   registered from each recording's points, as without a tracker). The instrument terms,
//!   stacked after the machine terms, are those of the rule in [`crate::instrument_terms`]
//!   (a `tracker_pose` always: fixed by the fit when the records are in the machine frame,
//!   registered and free when they are in an instrument frame).
//! * `estimation` — free/fixed and priors per term label ([`ParameterSetup`]). Defaults: every
//!   parameter free, except those of [`crate::instrument_terms::default_fixed`].
//! * `environment`, `program` — optional (needed to simulate, not to fit).
//! * `uncertainty` — standard uncertainties of a previous fit, per label and parameter
//!   ([`CellModel::uncertainty`]); `fit` — that fit's summary (ignored).
//!
//! Errors name the file and the key (`model.yaml: cell file: `terms[1] (id `backlash`)`: …`).

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use metrocell_model::{ForwardModel, MachineGeometry, ParameterSetup};
use metrocell_physics::config::quantity;
use metrocell_physics::config::ConfigValue;
use metrocell_physics::model::TermModel;
use metrocell_physics::{configure, TermConfig, TermId};

use crate::cell_file::CellFile;
use crate::error::CellError;
use crate::instrument_terms::{
    default_fixed, instrument_terms, registered_point_instruments, InstrumentTerms,
};
use crate::machine_section::machine;
use crate::terms_section::terms;

/// A validated model file. It owns the machine and the terms; [`CellModel::forward_model`]
/// borrows them, so a program that keeps one model for its life keeps this and the forward
/// model side by side (nothing leaked).
#[derive(Debug, Clone)]
pub struct CellModel {
    /// The file as named to the loader (for messages).
    pub file: String,
    /// Relative paths in the file (a URDF) are relative to this directory.
    pub base_dir: PathBuf,
    /// The text as read: the writer (crates/twin `model_writer`) edits it, keeping what the user
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
        let InstrumentTerms {
            terms: instrument_terms,
            declares_tracker,
        } = instrument_terms(&raw)?;
        let model = ForwardModel::new(&machine, &machine_terms, &instrument_terms)
            .map_err(|e| CellError::term("terms", e))?;
        let mut setup = ParameterSetup::new(&model, &raw.estimation)
            .map_err(|e| CellError::term("estimation", e))?;
        default_fixed(&model, &raw.estimation, &mut setup);
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

    /// The model for points registered into the machine frame already (the estimator node's
    /// measured points): the machine terms as declared, the instrument terms of
    /// [`registered_point_instruments`] (the identity pose, fixed: the file's other instrument
    /// terms act on the instruments' raw readings), and the file's `estimation` settings of the
    /// machine terms (those of its instrument terms set aside with them).
    pub fn for_registered_points(&self) -> Result<CellModel, CellError> {
        let labels: Vec<String> = self
            .machine_terms
            .terms
            .iter()
            .map(|t| t.term.label())
            .collect();
        let estimation: BTreeMap<_, _> = self
            .raw
            .estimation
            .iter()
            .filter(|(label, _)| labels.contains(label))
            .map(|(k, v)| (k.clone(), v.clone()))
            .collect();
        let mut out = CellModel {
            instrument_terms: registered_point_instruments()?,
            ..self.clone()
        };
        let fm = out.forward_model()?;
        let mut setup = ParameterSetup::new(&fm, &estimation)
            .map_err(|e| in_file(&self.file, CellError::term("estimation", e)))?;
        let pose = fm
            .instrument_param_start(TermId::TrackerPose)
            .expect("the rule's identity pose");
        setup.free[pose..pose + 6]
            .iter_mut()
            .for_each(|f| *f = false);
        drop(fm);
        out.setup = setup;
        Ok(out)
    }
}
