//! Parameters of `metrocell-estimator` and the estimator they set up.

use std::path::Path;

use metrocell_estimation::{RecursiveEstimator, RecursiveOptions};
use metrocell_model::{ForwardModel, SignalsBuilderOptions};
use metrocell_model_file::{CellError, CellModel};
use metrocell_node::{ParamDecl, Parameters};
use metrocell_records::{PointSource, RecordStream, RecordingOptions};

use crate::estimator_state::{EstimatorState, Settings};
use crate::state_file::SavedState;

pub fn declarations() -> Vec<ParamDecl> {
    vec![
        metrocell_node::diagnostics::input_timeout_param(),
        ParamDecl::new("model", "", "model cell file (YAML, read by crates/model_file): machine, `terms:` = the error model to estimate (their params are the start values), `estimation:` = free parameters and priors per term label"),
        ParamDecl::new("process_noise", Vec::<String>::new(), "random-walk intensity of drifting parameters, `label.param=q` with q in the parameter's SI unit per √s (e.g. positioning[z].c0=1e-7 for a Z offset that may drift 1 µm in ~3 h); others are constant"),
        ParamDecl::new("publish_every", 1i64, "publish the error model after this many accepted measurements (and on every alarm)").with_range(1.0, 1e9),
        ParamDecl::new("max_signal_gap", 600.0, "s of stamp time a measured point waits for a temperature (or other slow) stream to bracket it, and the longest gap between two of its samples that is interpolated; a point inside a longer gap is not used (the log says which signal)").with_range(1.0, 86400.0),
        ParamDecl::new("max_joint_gap", 1.0, "longest interval [s] between two commanded joint states that is interpolated (a longer one is a gap in the stream: points inside it are not used)").with_range(1e-3, 3600.0),
        ParamDecl::new("predict_points", Vec::<f64>::new(), "joint vectors (machine family order, m/rad) at which the volumetric error is predicted, flattened: x1 y1 z1 x2 y2 z2 … for a cartesian machine"),
        ParamDecl::new("gate_probability", 1e-6, "a single measurement whose χ²(3) tail probability is below this is an outlier (not used)").with_range(1e-15, 0.5),
        ParamDecl::new("window", 10i64, "measurements in the moving normalised-innovation χ² test").with_range(2.0, 1e5),
        ParamDecl::new("alarm_probability", 1e-3, "the moving test alarms (the model stopped explaining the data) below this tail probability").with_range(1e-15, 0.5),
        ParamDecl::new("alarm_inflation", 100.0, "on an alarm the data's information is divided by this, so the estimate re-converges to the new state: a well-measured parameter's variance grows by about this factor, none beyond its prior (the model's prior σ, else half its range) and no parameter the data do not inform").with_range(1.0, 1e12),
        ParamDecl::new("state_file", "", "JSON file the last published state is kept in; at start the node goes on from it when it fits the model ('' = start from the model file)"),
        ParamDecl::new("machine_id", "", "machine_id of the published ErrorModel"),
    ]
}

/// The model and how its records are read, before the input topics are known. The node keeps
/// it for its whole life and borrows the forward model from it ([`Model::forward_model`]).
pub struct Model {
    pub recording: RecordingOptions,
    pub path: String,
    /// The model file as this node reads it: points registered into the machine frame
    /// (crates/model_file `CellModel::for_registered_points`).
    file: CellModel,
    /// What of the model file the node does not use, for the log.
    pub set_aside: Vec<String>,
}

impl Model {
    /// The shared forward model of the file's machine terms and the identity instrument pose.
    pub fn forward_model(&self) -> Result<ForwardModel<'_>, CellError> {
        self.file.forward_model()
    }
}

/// The model file, and the recording options from the parameters; `points_topic` is the
/// resolved name of the measured points' topic.
pub fn model(p: &Parameters, points_topic: &str) -> Result<Model, Box<dyn std::error::Error>> {
    let path = p.get::<String>("model")?;
    if path.trim().is_empty() {
        return Err("parameter model is empty: give a model cell file, e.g. --ros-args -p model:=launch-configs/cells/demo_model.yaml".into());
    }
    // the model-file loader calibrate and diagnose use: a model file need not be a cell the
    // twin simulates (no environment, program or tracker pose needed)
    let declared = CellModel::from_path(&path)?;
    let signals = SignalsBuilderOptions {
        max_slow_gap: p.get::<f64>("max_signal_gap")?,
        max_joint_gap: p.get::<f64>("max_joint_gap")?,
        // bounded memory over a long run: the records are taken as they come, so the lags are
        // asked about recent instants only (older history coarsened)
        temperature_full_rate: Some(metrocell_records::LAG_FULL_RATE_MARGIN_S),
        ..SignalsBuilderOptions::default()
    };
    let recording = RecordingOptions {
        points: PointSource::MeasuredPoints,
        measured_points_topic: points_topic.to_string(),
        signals,
        ..RecordingOptions::default()
    };
    // the instrument terms (a tracker's warm-up or refraction, a probe's pretravel) act on the
    // instruments' raw readings; the measured points this node reads are registered into the
    // machine frame already, so it estimates the machine terms only, and says so
    let instrument_labels: Vec<String> = declared
        .instrument_terms
        .terms
        .iter()
        .map(|t| t.term.label())
        .filter(|l| l != "tracker_pose")
        .collect();
    let mut set_aside = Vec::new();
    if !instrument_labels.is_empty() {
        set_aside.push(format!(
            "the model's instrument terms ({}) are not estimated here: they act on the instruments' raw readings, and the measured points this node reads are in the machine frame",
            instrument_labels.join(", ")
        ));
    }
    Ok(Model {
        recording,
        path,
        file: declared.for_registered_points()?,
        set_aside,
    })
}

/// The filter over the model file, restored from the state file when it fits, reading a
/// recording that holds `topics` ((name, type): a bag's, or the live subscriptions); description
/// lines for the log. `model` is `m`'s forward model ([`Model::forward_model`]): the state
/// borrows it.
pub fn estimator<'m>(
    p: &Parameters,
    m: &Model,
    model: &'m ForwardModel<'m>,
    topics: &[(String, String)],
) -> Result<(EstimatorState<'m>, Vec<String>), Box<dyn std::error::Error>> {
    let (file, path) = (&m.file, &m.path);
    let stream = RecordStream::new(std::path::Path::new("input"), topics, model, &m.recording)
        .map_err(|e| format!("model {path}: {e}"))?;
    // measured points come in the machine frame: the instrument pose is the identity, fixed
    let setup = &file.setup;
    let names = model.param_names();
    let n = model.param_count();
    let mut options = RecursiveOptions::constant(n);
    options.gate_probability = p.get::<f64>("gate_probability")?;
    options.window = p.get::<i64>("window")? as usize;
    let options_window = options.window;
    options.alarm_probability = p.get::<f64>("alarm_probability")?;
    options.alarm_inflation = p.get::<f64>("alarm_inflation")?;
    for entry in p.get::<Vec<String>>("process_noise")? {
        let (name, q) = entry
            .split_once('=')
            .ok_or_else(|| format!("process_noise entry `{entry}`: expected label.param=q"))?;
        let k = names.iter().position(|x| x == name.trim()).ok_or_else(|| {
            format!(
                "process_noise entry `{entry}`: no parameter `{}` in the model; parameters: {}",
                name.trim(),
                names.join(", ")
            )
        })?;
        let q: f64 = q.trim().parse().ok().filter(|v: &f64| v.is_finite() && *v >= 0.0).ok_or_else(|| format!("process_noise entry `{entry}`: q must be a number ≥ 0 (unit of the parameter per √s)"))?;
        options.process_noise[k] = q;
    }
    let mut x0 = model.params();
    for (k, prior) in setup.priors.iter().enumerate() {
        if let Some(prior) = prior {
            x0[k] = prior.value;
        }
    }
    let mut p0 = RecursiveEstimator::initial_covariance(model, setup);
    let mut log = vec![format!(
        "model {path}: {} parameters, {} free ({}); reading {}",
        n,
        setup.free_indices().len(),
        setup
            .free_indices()
            .iter()
            .map(|&k| names[k].as_str())
            .collect::<Vec<_>>()
            .join(", "),
        stream.topics().join(", ")
    )];
    log.extend(m.set_aside.iter().cloned());
    let state_file = p.get::<String>("state_file")?;
    if !state_file.is_empty() {
        match SavedState::load(Path::new(&state_file))? {
            Some(saved) => match saved.start_for(&names, &setup.free_indices()) {
                Ok((x, cov)) => {
                    (x0, p0) = (x, cov);
                    log.push(format!(
                        "restarting from the state saved in {state_file} (stamp {} ns)",
                        saved.stamp_ns
                    ));
                }
                Err(why) => log.push(format!(
                    "state file {state_file} not used: {why}; starting from the model file"
                )),
            },
            None => log.push(format!(
                "no state file {state_file} yet: starting from the model file"
            )),
        }
    }
    let free_count = setup.free_indices().len();
    let filter = RecursiveEstimator::new(model, setup, x0, p0, options)?;
    let predict = p.get::<Vec<f64>>("predict_points")?;
    let joints = file.machine.joint_names().len();
    if predict.len() % joints != 0 {
        return Err(format!(
            "predict_points has {} numbers, not a multiple of the machine's {joints} joints",
            predict.len()
        )
        .into());
    }
    let settings = Settings {
        publish_every: p.get::<i64>("publish_every")? as u64,
        predict_joints: predict.chunks(joints).map(<[f64]>::to_vec).collect(),
        machine_id: p.get::<String>("machine_id")?,
        // before that the program's first points may not have reached every direction yet
        quiet_until: options_window.max(3 * free_count) as u64,
    };
    Ok((
        EstimatorState::new(
            model,
            filter,
            stream,
            m.recording.measured_points_topic.clone(),
            settings,
        ),
        log,
    ))
}
