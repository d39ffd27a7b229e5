//! Parameters of `metrocell-diagnose` and the session they set up.

use std::sync::Arc;

use metrocell_diagnose::{DeclaredModel, DiagnoseOptions};
use metrocell_model_file::CellModel;
use metrocell_node::{ParamDecl, Parameters};
use metrocell_records::{PointSource, RecordingOptions};

use crate::sliding_window::WindowSettings;

pub fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new("model", "", "model cell file (YAML, as `metrocell diagnose --model` reads it): machine, sensors, the declared `terms:` and `estimation:` settings; the recording is judged against it"),
        ParamDecl::new("points", "measured_points", "the measured points' topic: metrocell_msgs/MeasuredPoint (the tracker node's output, machine frame) — or, with points_type tracker, raw metrocell_msgs/TrackerMeasurement readings in the tracker frame"),
        ParamDecl::new("points_type", "measured_point", "measured_point or tracker: the type of the points topic"),
        ParamDecl::new("probe_hits", false, "also judge the model on the probe hits (probe/hits, metrocell_msgs/ProbeHit); the model must declare sensors.probe"),
        ParamDecl::new("window", 14400.0, "s of cell time the diagnosis looks back over (a sliding window; the default is half a shift)").with_range(60.0, 1e7),
        ParamDecl::new("every", 1800.0, "s of cell time between two diagnoses of the window").with_range(1.0, 1e7),
        ParamDecl::new("min_records", 60i64, "fewest records in the window worth diagnosing (too few cannot tell candidates apart; diagnose says how many it needs)").with_range(3.0, 1e9),
        ParamDecl::new("max_terms", 3i64, "most catalog terms the selection adds in one diagnosis").with_range(1.0, 20.0),
        ParamDecl::new("alpha", 0.01, "family-wise significance level of the tests, after correction for the number made").with_range(1e-9, 0.5),
        ParamDecl::new("empirical", true, "try empirical smooth corrections for structure no catalog term explains (labelled empirical, never given a physical name)"),
    ]
}

/// What the parameters set up: the model (kept for the node's life, shared with the worker
/// thread that runs a diagnosis; the record stream borrows its forward model), how records are
/// read, how diagnoses are run and the window.
pub struct Setup {
    pub model: Arc<CellModel>,
    pub points_topic: String,
    pub recording: RecordingOptions,
    pub options: DiagnoseOptions,
    pub window: WindowSettings,
    pub describe: Vec<String>,
}

impl Setup {
    pub fn declared(&self) -> DeclaredModel<'_> {
        declared(&self.model)
    }
}

/// The model as `diagnose` takes it.
pub fn declared(m: &CellModel) -> DeclaredModel<'_> {
    DeclaredModel {
        machine: &m.machine,
        machine_terms: &m.machine_terms,
        instrument_terms: &m.instrument_terms,
        setup: &m.setup,
    }
}

/// The setup from the parameters; `resolve` turns a relative topic name into the node's.
pub fn setup(
    p: &Parameters,
    resolve: &dyn Fn(&str) -> Result<String, String>,
) -> Result<Setup, String> {
    let path = p.get::<String>("model").map_err(|e| e.to_string())?;
    if path.trim().is_empty() {
        return Err("parameter model is empty: give the model cell file to judge the recording against, e.g. --ros-args -p model:=crates/twin/examples/cells/demo_model.yaml".into());
    }
    let model = Arc::new(CellModel::from_path(&path).map_err(|e| e.to_string())?);
    let get_f = |k: &str| p.get::<f64>(k).map_err(|e| e.to_string());
    let get_i = |k: &str| p.get::<i64>(k).map_err(|e| e.to_string());
    let points_topic = resolve(&p.get::<String>("points").map_err(|e| e.to_string())?)?;
    let points = match p
        .get::<String>("points_type")
        .map_err(|e| e.to_string())?
        .as_str()
    {
        "measured_point" => PointSource::MeasuredPoints,
        "tracker" => PointSource::TrackerMeasurements,
        other => {
            return Err(format!(
                "points_type `{other}`: expected measured_point or tracker"
            ))
        }
    };
    let probe_hits = p.get::<bool>("probe_hits").map_err(|e| e.to_string())?;
    if probe_hits && model.raw.sensors.probe.is_none() {
        return Err(format!("probe_hits is true but the model {path} declares no sensors.probe: declare the probe (its directions and noise) or set probe_hits:=false"));
    }
    let mut recording = RecordingOptions {
        points,
        measured_points_topic: points_topic.clone(),
        tracker_topic: points_topic.clone(),
        probe_hits,
        probe_topic: resolve("probe/hits")?,
        ..RecordingOptions::default()
    };
    // bounded memory over a long run: full-rate temperatures for the window and a margin before
    // it, older history coarsened (the lags the window's records ask for barely move)
    recording.signals.temperature_full_rate =
        Some(get_f("window")? + metrocell_records::LAG_FULL_RATE_MARGIN_S);
    let mut options = DiagnoseOptions {
        empirical: p.get::<bool>("empirical").map_err(|e| e.to_string())?,
        ..DiagnoseOptions::default()
    };
    options.selection.max_terms = get_i("max_terms")? as usize;
    options.selection.alpha = get_f("alpha")?;
    let window = WindowSettings {
        window_s: get_f("window")?,
        every_s: get_f("every")?,
        min_records: get_i("min_records")? as usize,
    };
    let free: Vec<&str> = model
        .setup
        .free_indices()
        .iter()
        .map(|&k| model.setup.names[k].as_str())
        .collect();
    let describe = vec![format!(
        "model {path}: {} declared terms, {} free parameters ({}); diagnosing the last {:.1} h of cell time every {:.0} min from {points_topic}{}",
        model.machine_terms.terms.len() + model.instrument_terms.terms.len(),
        free.len(),
        if free.is_empty() { "none".to_string() } else { free.join(", ") },
        window.window_s / 3600.0,
        window.every_s / 60.0,
        if probe_hits { " and the probe hits" } else { "" }
    )];
    Ok(Setup {
        model,
        points_topic,
        recording,
        options,
        window,
        describe,
    })
}
