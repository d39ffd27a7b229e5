//! Parameters of `metrocell-estimator` and the estimator they set up.

use std::path::Path;

use metrocell_estimation::{RecursiveEstimator, RecursiveOptions};
use metrocell_model::ParameterSetup;
use metrocell_node::{ParamDecl, Parameters};
use metrocell_physics::model::TermModel;
use metrocell_physics::{configure, SignalKind, TermConfig};
use metrocell_twin::Cell;

use crate::estimator_state::{EstimatorState, Settings};
use crate::signal_stream::SignalStream;
use crate::state_file::SavedState;

pub fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new("model", "", "model cell file (YAML, the twin's format): machine, `terms:` = the error model to estimate (their params are the start values), `estimation:` = free parameters and priors per term label"),
        ParamDecl::new("process_noise", Vec::<String>::new(), "random-walk intensity of drifting parameters, `label.param=q` with q in the parameter's SI unit per √s (e.g. positioning[z].c0=1e-7 for a Z offset that may drift 1 µm in ~3 h); others are constant"),
        ParamDecl::new("publish_every", 1i64, "publish the error model after this many accepted measurements (and on every alarm)").with_range(1.0, 1e9),
        ParamDecl::new("signal_wait", 5.0, "s of stamp time a measured point waits for a signal stream that has stopped (its last value then holds)").with_range(0.0, 86400.0),
        ParamDecl::new("predict_points", Vec::<f64>::new(), "joint vectors (machine family order, m/rad) at which the volumetric error is predicted, flattened: x1 y1 z1 x2 y2 z2 … for a cartesian machine"),
        ParamDecl::new("gate_probability", 1e-6, "a single measurement whose χ²(3) tail probability is below this is an outlier (not used)").with_range(1e-15, 0.5),
        ParamDecl::new("window", 10i64, "measurements in the moving normalised-innovation χ² test").with_range(2.0, 1e5),
        ParamDecl::new("alarm_probability", 1e-3, "the moving test alarms (the model stopped explaining the data) below this tail probability").with_range(1e-15, 0.5),
        ParamDecl::new("alarm_inflation", 100.0, "the covariance is multiplied by this on an alarm, so the estimate re-converges to the new state").with_range(1.0, 1e12),
        ParamDecl::new("state_file", "", "JSON file the last published state is kept in; at start the node goes on from it when it fits the model ('' = start from the model file)"),
        ParamDecl::new("power_on_time", 0.0, "when the instrument was switched on, s since the Unix epoch, for terms reading time_since_power_on (0 = unknown)").with_range(0.0, 1e11),
        ParamDecl::new("machine_id", "", "machine_id of the published ErrorModel"),
    ]
}

/// What the model reads: temperature sensors, and those read through a lag.
pub struct Inputs {
    pub sensors: Vec<String>,
    pub history_sensors: Vec<String>,
}

/// The filter over the model file, restored from the state file when it fits; description lines
/// for the log.
pub fn estimator(p: &Parameters) -> Result<(EstimatorState, Inputs, Vec<String>), Box<dyn std::error::Error>> {
    let path = p.get::<String>("model")?;
    if path.trim().is_empty() {
        return Err("parameter model is empty: give a model cell file, e.g. --ros-args -p model:=launch-configs/cells/demo_model.yaml".into());
    }
    // The node keeps one model for its whole life; leaking it gives the forward model the
    // 'static borrow it needs without a self-referential struct.
    let cell: &'static Cell = Box::leak(Box::new(Cell::from_path(&path)?));
    let instruments: &'static TermModel = Box::leak(Box::new(identity_tracker_pose()?));
    let model = cell.forward_model(instruments).map_err(|e| format!("model {path}: {e}"))?;
    let inputs = inputs_of(cell, &path, p.get::<f64>("power_on_time")? > 0.0)?;
    let mut setup = ParameterSetup::new(&model, &cell.estimation).map_err(|e| format!("model {path}: {e}"))?;
    let names = model.param_names();
    let pose = model.instrument_param_start(metrocell_physics::TermId::TrackerPose).expect("identity pose added above");
    // measured points come in the machine frame: the instrument pose is the identity, fixed
    setup.free[pose..pose + 6].iter_mut().for_each(|f| *f = false);
    let n = model.param_count();
    let mut options = RecursiveOptions::constant(n);
    options.gate_probability = p.get::<f64>("gate_probability")?;
    options.window = p.get::<i64>("window")? as usize;
    options.alarm_probability = p.get::<f64>("alarm_probability")?;
    options.alarm_inflation = p.get::<f64>("alarm_inflation")?;
    for entry in p.get::<Vec<String>>("process_noise")? {
        let (name, q) = entry.split_once('=').ok_or_else(|| format!("process_noise entry `{entry}`: expected label.param=q"))?;
        let k = names.iter().position(|x| x == name.trim()).ok_or_else(|| format!("process_noise entry `{entry}`: no parameter `{}` in the model; parameters: {}", name.trim(), names.join(", ")))?;
        let q: f64 = q.trim().parse().ok().filter(|v: &f64| v.is_finite() && *v >= 0.0).ok_or_else(|| format!("process_noise entry `{entry}`: q must be a number ≥ 0 (unit of the parameter per √s)"))?;
        options.process_noise[k] = q;
    }
    let mut x0 = model.params();
    for (k, prior) in setup.priors.iter().enumerate() {
        if let Some(prior) = prior {
            x0[k] = prior.value;
        }
    }
    let mut p0 = RecursiveEstimator::initial_covariance(&model, &setup);
    let mut log = vec![format!(
        "model {path}: {} parameters, {} free ({}); temperatures read: {}",
        n,
        setup.free_indices().len(),
        setup.free_indices().iter().map(|&k| names[k].as_str()).collect::<Vec<_>>().join(", "),
        if inputs.sensors.is_empty() { "none".to_string() } else { inputs.sensors.join(", ") }
    )];
    let state_file = p.get::<String>("state_file")?;
    if !state_file.is_empty() {
        match SavedState::load(Path::new(&state_file))? {
            Some(saved) => match saved.start_for(&names, &setup.free_indices()) {
                Ok((x, cov)) => {
                    (x0, p0) = (x, cov);
                    log.push(format!("restarting from the state saved in {state_file} (stamp {} ns)", saved.stamp_ns));
                }
                Err(why) => log.push(format!("state file {state_file} not used: {why}; starting from the model file")),
            },
            None => log.push(format!("no state file {state_file} yet: starting from the model file")),
        }
    }
    let filter = RecursiveEstimator::new(&model, &setup, x0, p0, options)?;
    let power_on = Some(p.get::<f64>("power_on_time")?).filter(|t| *t > 0.0);
    let stream = SignalStream::new(cell.machine.joint_names().len(), &inputs.sensors, &inputs.history_sensors, power_on);
    let predict = p.get::<Vec<f64>>("predict_points")?;
    let joints = cell.machine.joint_names().len();
    if predict.len() % joints != 0 {
        return Err(format!("predict_points has {} numbers, not a multiple of the machine's {joints} joints", predict.len()).into());
    }
    let settings = Settings {
        publish_every: p.get::<i64>("publish_every")? as u64,
        signal_wait: p.get::<f64>("signal_wait")?,
        predict_joints: predict.chunks(joints).map(<[f64]>::to_vec).collect(),
        machine_id: p.get::<String>("machine_id")?,
    };
    Ok((EstimatorState::new(model, filter, stream, settings), inputs, log))
}

/// The measured points are in the machine frame: the tracker pose is the identity.
fn identity_tracker_pose() -> Result<TermModel, metrocell_physics::PhysicsError> {
    let mut m = TermModel::default();
    let params = ["tx", "ty", "tz", "alpha", "beta", "delta"].iter().map(|k| (k.to_string(), metrocell_physics::ConfigValue::Number(0.0))).collect();
    m.push(configure(&TermConfig { id: "tracker_pose".into(), options: Default::default(), params, use_defaults: false })?)?;
    Ok(m)
}

/// The signals the model's terms read, checked against what the node can provide.
fn inputs_of(cell: &Cell, path: &str, power_on_known: bool) -> Result<Inputs, String> {
    let (mut sensors, mut history_sensors) = (Vec::new(), Vec::new());
    for t in &cell.terms.terms {
        for s in t.term.signals() {
            match s {
                SignalKind::AxisPosition(_) | SignalKind::ApproachDirection(_) | SignalKind::AxisVelocity(_) | SignalKind::RotaryPosition(_) => {}
                k if k.is_computed_by_model() => {}
                SignalKind::Temperature(name) => sensors.push(name),
                SignalKind::TemperatureHistory(name) => {
                    sensors.push(name.clone());
                    history_sensors.push(name);
                }
                SignalKind::TimeSincePowerOn if power_on_known => {}
                other => {
                    return Err(format!(
                        "model {path}: term {} reads {other}, which the estimator node does not take from its topics (it reads commanded joints and temperature/<sensor>{}); remove the term or give the signal",
                        t.term.label(),
                        if other == SignalKind::TimeSincePowerOn { "; set power_on_time" } else { "" }
                    ))
                }
            }
        }
    }
    sensors.sort();
    sensors.dedup();
    history_sensors.sort();
    history_sensors.dedup();
    Ok(Inputs { sensors, history_sensors })
}
