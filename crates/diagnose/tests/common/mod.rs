//! Records made by the twin, in memory, as a recording would give them: the tracker's readings
//! (tracker frame, stated covariance), the commanded motion at each reading, the thermocouples'
//! *readings* (their noise included — the truth the twin computes with is not given), the
//! station's air of the reading and the time since power-on.
#![allow(dead_code)]

use std::collections::BTreeMap;

use metrocell_diagnose::{diagnose, DeclaredModel, DiagnoseOptions, Diagnosis};
use metrocell_estimation::{MeasurementRecord, RecordFrame, RecordKind, RecordSet};
use metrocell_physics::{Signals, TemperatureTimeline};
use metrocell_twin::{Cell, CellModel, Sample, Simulation};
use nalgebra::{Matrix3, Vector3};

/// The base cell: an XFYZ machine measured by a tracker over a serpentine 5 × 4 × 3 grid every
/// 20 minutes for `hours`, four thermocouples, a shop warming by about 2 K; `terms` are the true
/// error terms (YAML list items, indented by two spaces), `program` the grid section.
pub fn cell_yaml(terms: &str, hours: f64, extra_sensors: &str) -> String {
    format!(
        r#"
name: diagnose_test_cell
machine:
  family: cartesian
  stacking: XFYZ
  travel: {{x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 400 mm]}}
  tool_offset: [0 mm, 0 mm, -150 mm]
sensors:
  tracker:
    pose: {{translation: [-863.527 mm, 194.373 mm, 677.782 mm], euler_xyz: [0.0339 deg, 0.0343 deg, 59.4652 deg]}}
    rate: 10 Hz
    range_noise: {{constant: 4 um, per_metre: 0.8 um/m}}
    angular_noise: 3 urad
    powered_on_before_start: 4 h
{extra_sensors}  thermocouples:
    - {{name: x_left,  location: table,  noise: 0.02 K, rate: 1 Hz}}
    - {{name: x_right, location: ambient, noise: 0.02 K, rate: 1 Hz}}
    - {{name: column,  location: column, noise: 0.02 K, rate: 1 Hz}}
    - {{name: head,    location: head,   noise: 0.02 K, rate: 1 Hz}}
  machine_state: {{rate: 20 Hz}}
environment:
  ambient: {{mean: 20.3 degC, drift: 0.6 K/h}}
  heat_sources:
    - name: motors
      duty: [{{start: 0.2 h, end: 1.4 h, level: 0.8}}]
  nodes:
    - {{name: column, time_constant: 40 min, heating: {{motors: 2.0 K}}, initial: 20.3 degC}}
    - {{name: head,   time_constant: 15 min, heating: {{motors: 1.0 K}}, initial: 20.3 degC}}
    - {{name: table,  time_constant: 60 min, heating: {{motors: 1.5 K}}, initial: 20.3 degC}}
  air: {{pressure: 101.3 kPa, humidity: 45}}
program:
  grid:
    x: {{from: 0 mm, to: 800 mm, count: 5}}
    y: {{from: 0 mm, to: 500 mm, count: 4}}
    z: {{from: 0 mm, to: 400 mm, count: 3}}
  order: serpentine
  feed_rate: 50 mm/s
  dwell: 2 s
  cycle_interval: {cycle} min
  home: [0 mm, 0 mm, 400 mm]
terms:
  - id: squareness
    options: {{pair: xy}}
    params: {{s: 20 urad}}
{terms}"#,
        cycle = (hours * 60.0 / 6.0).round()
    )
}

pub struct TwinRecords {
    pub records: RecordSet,
    pub cell: Cell,
}

/// Options of [`twin_records`].
pub struct Take {
    /// Keep readings taken while moving (velocity ≠ 0).
    pub moving: bool,
    /// Keep every n-th reading.
    pub every: usize,
    /// Give each record the temperature histories (every 60 s) for lagged terms.
    pub histories: bool,
}

impl Default for Take {
    fn default() -> Self {
        Self {
            moving: false,
            every: 3,
            histories: false,
        }
    }
}

/// Simulate `cell_text` for `hours` with `seed` and build the records.
pub fn twin_records(cell_text: &str, hours: f64, seed: u64, take: Take) -> TwinRecords {
    let cell = Cell::from_yaml_str(cell_text, "test cell").expect("test cell");
    let truth_for_records = Cell::from_yaml_str(cell_text, "test cell").unwrap();
    let sim = Simulation::new(cell, hours * 3600.0, seed).expect("simulation");
    let powered = sim
        .cell()
        .tracker
        .as_ref()
        .map(|t| t.powered_on_before_start)
        .unwrap_or(0.0);
    let mut latest: BTreeMap<String, f64> = BTreeMap::new();
    // one timeline shared by every record; each record reads it up to its own time
    let history = std::sync::Arc::new(TemperatureTimeline::new());
    let mut last_history_t: BTreeMap<String, f64> = BTreeMap::new();
    let model = sim.forward_model();
    let mut out = Vec::new();
    let mut count = 0usize;
    for sample in sim.samples() {
        match sample {
            Sample::Temperature(t) => {
                latest.insert(t.sensor.to_string(), t.value);
                let last = last_history_t
                    .entry(t.sensor.to_string())
                    .or_insert(f64::NEG_INFINITY);
                if t.t - *last >= 60.0 {
                    *last = t.t;
                    history
                        .push(&t.sensor, t.t, t.value)
                        .expect("the twin's samples advance in time");
                }
            }
            Sample::Tracker(s) => {
                if s.status != metrocell_twin::TrackerStatus::Ok
                    || !s.point.iter().all(|v| v.is_finite())
                {
                    continue;
                }
                let ms = sim.cell().program.state_at(s.t);
                let moving = ms.velocity.iter().any(|v| v.abs() > 0.0);
                if moving && !take.moving {
                    continue;
                }
                if latest.len() < sim.cell().thermocouples.len() {
                    continue;
                }
                count += 1;
                if !count.is_multiple_of(take.every) {
                    continue;
                }
                let mut sig = Signals {
                    air_temperature: Some(s.air_temperature),
                    air_pressure: Some(s.air_pressure),
                    air_humidity: Some(s.air_humidity),
                    time_since_power_on: Some(s.t + powered),
                    ..Default::default()
                };
                model.set_motion(
                    &mut sig,
                    ms.q.as_slice(),
                    ms.velocity.as_slice(),
                    &ms.approach,
                );
                sig.temperatures = latest.clone();
                if take.histories {
                    sig.timeline = Some(history.clone());
                    sig.time = Some(s.t);
                }
                out.push(MeasurementRecord {
                    time: s.t,
                    point_id: s.target_id.map(|t| format!("p{t}")).unwrap_or_default(),
                    channel: "tracker".into(),
                    q: ms.q.iter().copied().collect(),
                    measured: s.point,
                    covariance: s.covariance,
                    signals: sig,
                    kind: RecordKind::Point,
                });
            }
            _ => {}
        }
    }
    TwinRecords {
        records: RecordSet {
            check: Vec::new(),
            frame: RecordFrame::Instrument("tracker".into()),
            records: out,
            rejected: vec![],
            sources: vec![],
        },
        cell: truth_for_records,
    }
}

/// Diagnose `records` against the model file `model_text` (read as `metrocell diagnose` reads
/// a model: crates/twin `CellModel`).
pub fn try_run(
    model_text: &str,
    records: &RecordSet,
    options: &DiagnoseOptions,
) -> Result<Diagnosis, metrocell_diagnose::DiagnoseError> {
    let m = CellModel::from_yaml_str_in(model_text, "model.yaml", std::path::Path::new("."))
        .expect("model file");
    let declared = DeclaredModel {
        machine: &m.machine,
        machine_terms: &m.machine_terms,
        instrument_terms: &m.instrument_terms,
        setup: &m.setup,
    };
    diagnose(&declared, records, options)
}

pub fn run(model_text: &str, records: &RecordSet, options: &DiagnoseOptions) -> Diagnosis {
    try_run(model_text, records, options).unwrap_or_else(|e| panic!("diagnose: {e}"))
}

/// Add a workpiece-frame displacement `f(t, commanded position)` to every measured point (in the
/// tracker frame of the records): structure from outside the catalog.
pub fn add_structure(
    records: &mut RecordSet,
    cell: &Cell,
    f: impl Fn(f64, &Vector3<f64>) -> Vector3<f64>,
) {
    let r: Matrix3<f64> = cell.tracker.as_ref().unwrap().pose.rotation;
    for rec in &mut records.records {
        let p = Vector3::new(rec.q[0], rec.q[1], rec.q[2]);
        rec.measured += r.transpose() * f(rec.time, &p);
    }
}

/// The true value of `name` (`label.param`) in a cell.
pub fn truth(cell: &Cell, name: &str) -> f64 {
    let instruments = cell.tracker_terms().unwrap();
    let m = cell.forward_model(&instruments).unwrap();
    let k = m
        .param_names()
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("{name} not in the truth"));
    m.params()[k]
}

/// Print the report's essentials (for test logs).
pub fn show(d: &Diagnosis) {
    let r = &d.report;
    eprintln!("{}", r.summary);
    for f in &r.findings {
        eprintln!(
            "  finding {} [{}]: {:?}",
            f.label,
            f.variant,
            f.parameters
                .iter()
                .map(|(k, v)| format!("{k}={:.3e}±{:.1e}", v.value, v.sigma.unwrap_or(f64::NAN)))
                .collect::<Vec<_>>()
        );
    }
    for u in &r.unexplained {
        eprintln!("  unexplained: {}", u.statement);
    }
    for s in &r.selection {
        eprintln!(
            "  step chose {:?}; top: {:?}",
            s.chosen,
            s.top
                .iter()
                .take(4)
                .map(|t| format!(
                    "{}[{}] gain {:.3} p {:.1e} dBIC {:.0} acc {}",
                    t.label, t.variant, t.heldout_gain, t.p_adjusted, t.delta_bic, t.accepted
                ))
                .collect::<Vec<_>>()
        );
    }
    eprintln!(
        "  noise: {}; remaining: {:?}",
        r.noise.statement, r.remaining
    );
}
