//! The diagnose node on a recorded shift (`--bag`, no DDS): a two-hour recording of a machine
//! whose X axis has 10 µm of backlash the model does not declare. The node diagnoses its
//! sliding window at the cell instants its schedule says, names the backlash with a reversal
//! within 3σ of the truth, announces it once, and its window holds exactly the records
//! `metrocell diagnose` builds from the same bag.

use std::path::{Path, PathBuf};
use std::process::Command;

use metrocell_bagtools::BagSource;
use metrocell_diagnose_node::parameters::{self, Setup};
use metrocell_diagnose_node::session::Session;
use metrocell_model_file::CellModel;
use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::std_msgs::msg::String as StringMessage;
use metrocell_records::{records_from_bags, PointSource, RecordingOptions};
use metrocell_twin::Cell;

const HOURS: f64 = 2.0;
const REVERSAL_UM: f64 = 10.0;

fn cell_yaml(terms: &str) -> String {
    format!(
        r#"
name: diagnose_node_test
machine:
  family: cartesian
  stacking: XFYZ
  travel: {{x: [0 mm, 600 mm], y: [0 mm, 400 mm], z: [0 mm, 300 mm]}}
  tool_offset: [0 mm, 0 mm, -150 mm]
sensors:
  tracker:
    pose: {{translation: [-900 mm, 200 mm, 650 mm], euler_xyz: [0 deg, 0 deg, 55 deg]}}
    rate: 5 Hz
    range_noise: {{constant: 4 um, per_metre: 0.8 um/m}}
    angular_noise: 3 urad
    powered_on_before_start: 4 h
  thermocouples:
    - {{name: x_left,  location: ambient, noise: 0.02 K, rate: 1 Hz}}
  machine_state: {{rate: 10 Hz}}
environment:
  ambient: {{mean: 20.2 degC, drift: 0.2 K/h}}
  air: {{pressure: 101.3 kPa, humidity: 45}}
program:
  grid:
    x: {{from: 0 mm, to: 600 mm, count: 4}}
    y: {{from: 0 mm, to: 400 mm, count: 3}}
    z: {{from: 50 mm, to: 250 mm, count: 2}}
  order: serpentine
  feed_rate: 80 mm/s
  dwell: 2 s
  cycle_interval: 12 min
  home: [0 mm, 0 mm, 300 mm]
terms:
  - id: squareness
    options: {{pair: xy}}
    params: {{s: 20 urad}}
{terms}"#
    )
}

struct Recording {
    dir: PathBuf,
    bag: PathBuf,
    model: PathBuf,
}

fn record() -> Recording {
    static NEXT: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);
    let dir = std::env::temp_dir().join(format!(
        "diagnose_node_it_{}_{}",
        std::process::id(),
        NEXT.fetch_add(1, std::sync::atomic::Ordering::Relaxed)
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let truth = cell_yaml(&format!(
        "  - id: backlash\n    options: {{axis: x}}\n    params: {{reversal: {REVERSAL_UM} um}}\n"
    ));
    let cell = Cell::from_yaml_str(&truth, "truth").expect("truth cell");
    let bag = dir.join("shift");
    metrocell_simulation::bag::write_bag(
        cell,
        HOURS * 3600.0,
        7,
        &bag,
        &Default::default(),
        |_| {},
    )
    .expect("simulated bag");
    let model = dir.join("model.yaml");
    std::fs::write(&model, cell_yaml("")).unwrap();
    Recording { dir, bag, model }
}

impl Drop for Recording {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn node_setup(model: &Path, window: f64) -> Setup {
    let (model, window) = (
        format!("model:={}", model.display()),
        format!("window:={window:?}"),
    );
    let args = [
        "node",
        "--ros-args",
        "-p",
        &model,
        "-p",
        "points:=/tracker/measurements",
        "-p",
        "points_type:=tracker",
        "-p",
        &window,
    ];
    let cl = metrocell_node::parse_command_line(args).unwrap();
    let p = metrocell_node::Parameters::resolve(
        &parameters::declarations(),
        &cl.ros,
        "/diagnose",
        "diagnose",
    )
    .unwrap();
    parameters::setup(&p, &|t| Ok(format!("/{}", t.trim_start_matches('/')))).expect("setup")
}

#[test]
fn replay_names_the_concealed_backlash_on_schedule_and_announces_it_once() {
    let rec = record();
    let out = rec.dir.join("out");
    let run = Command::new(env!("CARGO_BIN_EXE_metrocell-diagnose"))
        .args([
            "--bag",
            &rec.bag.display().to_string(),
            "--output",
            &out.display().to_string(),
            "--ros-args",
        ])
        .args([
            "-p",
            &format!("model:={}", rec.model.display()),
            "-p",
            "points:=/tracker/measurements",
            "-p",
            "points_type:=tracker",
        ])
        .args([
            "-p",
            "window:=7200.0",
            "-p",
            "every:=2400.0",
            "-p",
            "min_records:=30",
        ])
        .output()
        .expect("run metrocell-diagnose");
    let log =
        String::from_utf8_lossy(&run.stderr).to_string() + &String::from_utf8_lossy(&run.stdout);
    eprintln!("{log}");
    assert!(run.status.success(), "{log}");

    let mut source = BagSource::open(&out).expect("output bag");
    assert!(source
        .subscribe::<StringMessage>("/diagnose/result")
        .unwrap());
    assert!(source.subscribe::<DiagnosticArray>("/diagnostics").unwrap());
    let (mut results, mut statuses) = (Vec::new(), Vec::new());
    for m in source.messages().unwrap() {
        let m = m.unwrap();
        if m.topic == "/diagnose/result" {
            results.push(
                serde_json::from_str::<serde_json::Value>(
                    &m.decode::<StringMessage>().unwrap().data,
                )
                .unwrap(),
            );
        } else {
            statuses.push(m.decode::<DiagnosticArray>().unwrap());
        }
    }
    // every 40 min of cell time over 2 h: at ~40 and ~80 min, then the window at the end
    assert_eq!(results.len(), 3, "{results:#?}");
    assert_eq!(statuses.len(), 3);
    let last = &results[2];
    let findings = last["findings"].as_array().expect("findings");
    assert_eq!(findings.len(), 1, "{last:#}");
    assert_eq!(findings[0]["term"], "backlash");
    let p = &findings[0]["parameters"]["reversal"];
    let (value, sigma) = (p["value"].as_f64().unwrap(), p["sigma"].as_f64().unwrap());
    let (value_um, sigma_um) = match p["unit"].as_str().unwrap() {
        "um" | "µm" => (value, sigma),
        "m" => (value * 1e6, sigma * 1e6),
        other => panic!("unit {other}"),
    };
    assert!(
        (value_um - REVERSAL_UM).abs() <= 3.0 * sigma_um,
        "reversal {value_um} ± {sigma_um} µm vs {REVERSAL_UM} µm"
    );
    assert!(
        statuses[2]
            .status
            .iter()
            .any(|s| s.name == "diagnose: backlash[x]" && s.level == 1),
        "{:#?}",
        statuses[2]
    );
    // announced once, however many windows find it again
    assert_eq!(
        log.matches("new effect found: backlash[x]").count(),
        1,
        "{log}"
    );
}

#[test]
fn the_window_holds_the_records_diagnose_builds_from_the_bag() {
    let rec = record();
    let setup = node_setup(&rec.model, 1e7);
    let mut source = BagSource::open(&rec.bag).unwrap();
    let topics: Vec<(String, String)> = source
        .topics()
        .iter()
        .map(|t| (t.name.clone(), t.type_name.clone()))
        .collect();
    let node_model = std::sync::Arc::clone(&setup.model);
    let node_forward = node_model.forward_model().unwrap();
    let mut session = Session::new(setup, &node_forward, &rec.bag, &topics).unwrap();
    for t in session.stream.topics() {
        source.subscribe_any(&t);
    }
    for m in source.messages().unwrap() {
        session.push(&m.unwrap()).unwrap();
    }
    session.flush();
    let streamed = session.job().records;

    let model = CellModel::from_path(&rec.model).unwrap();
    let forward = model.forward_model().unwrap();
    let whole = records_from_bags(
        &[&rec.bag],
        &forward,
        &RecordingOptions {
            points: PointSource::TrackerMeasurements,
            ..Default::default()
        },
    )
    .unwrap();
    assert!(
        whole.records.len() > 1000,
        "{} records",
        whole.records.len()
    );
    assert_eq!(streamed.records.len(), whole.records.len());
    assert_eq!(streamed.frame, whole.frame);
    for (a, b) in streamed.records.iter().zip(&whole.records) {
        assert_eq!(
            (a.time, &a.point_id, &a.q, a.measured),
            (b.time, &b.point_id, &b.q, b.measured)
        );
        assert_eq!(a.signals.temperatures, b.signals.temperatures);
    }
}
