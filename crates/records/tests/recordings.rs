//! Signals and measurement records built from real bags: `metrocell sim` bags of the example
//! cells against the twin's own signals, an imported CSV export against its values, the
//! identity check through a bag, and bad input.
//!
//! How the twin's internal signals are obtained: `Simulation::samples_with_signals` yields, for
//! every tracker reading, the exact `Signals` the twin evaluated the shared model with. The twin
//! computes its physics from the *true* temperature at each thermocouple's location, while a
//! bag holds what the thermocouple read (true + offset + noise); so the cells here are the
//! examples with noise- and offset-free thermocouples (what is compared is the interpolation of
//! the recording, not the sensors' errors). A lagged term reads the twin's true temperature
//! sampled every 10 s (`HISTORY_STEP`), the bag's every 1 s: the two filtered values differ by
//! the filter's hold over a longer step, bounded below.

use std::path::{Path, PathBuf};

use metrocell_bag::{BagWriter, WriterOptions};
use metrocell_bagtools::import::{import_csv, Mapping};
use metrocell_estimation::residuals::PointResiduals;
use metrocell_model::SignalsBuilderOptions;
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::Point;
use metrocell_msgs::msg::MeasuredPoint;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_msgs::RosMessage;
use metrocell_records::recordings::{
    records_from_bags, signals_from_bag, PointSource, RecordingError, RecordingOptions,
};
use metrocell_simulation::sim_time::{parse_start_time, stamp_ns, DEFAULT_START_TIME};
use metrocell_simulation::{write_bag, BagOptions};
use metrocell_solver::Problem;
use metrocell_twin::{Cell, Sample, Simulation};

fn cells_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../twin/examples/cells")
}

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/fixtures")
        .join(name)
}

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "metrocell_recordings_{name}_{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// The example cell's text with noise- and offset-free thermocouples (see the module docs).
fn exact_thermocouples(text: &str) -> String {
    let noise = regex::Regex::new(r"\bnoise: [^,}]+").unwrap();
    let offset = regex::Regex::new(r",\s*offset: [^,}]+").unwrap();
    text.lines()
        .map(|l| {
            if l.contains("location:") {
                offset
                    .replace(&noise.replace(l, "noise: 0 K"), "")
                    .into_owned()
            } else {
                l.to_string()
            }
        })
        .collect::<Vec<_>>()
        .join("\n")
}

fn example(name: &str) -> String {
    std::fs::read_to_string(cells_dir().join(name)).unwrap()
}

fn cell(text: &str, name: &str) -> Cell {
    Cell::from_yaml_str_in(text, name, &cells_dir()).unwrap()
}

/// A `metrocell sim` bag (no camera frames) of `text`.
fn sim_bag(text: &str, name: &str, duration: f64, seed: u64) -> PathBuf {
    let dir = scratch(name);
    let options = BagOptions {
        frames: None,
        ..BagOptions::default()
    };
    write_bag(cell(text, name), duration, seed, &dir, &options, |_| {}).unwrap();
    dir
}

struct Worst {
    position: f64,
    temperature: f64,
    lag: f64,
    power_on: f64,
    readings: usize,
    approach_unknown: usize,
    past_last_temperature: usize,
}

/// Signals from the bag vs the twin's at every tracker reading (module docs).
fn compare_with_twin(text: &str, name: &str, duration: f64) -> Worst {
    let seed = 3;
    let bag = sim_bag(text, name, duration, seed);
    let c = cell(text, name);
    let start = parse_start_time(DEFAULT_START_TIME).unwrap();
    let (builder, refused) =
        signals_from_bag(&bag, &c.machine, &SignalsBuilderOptions::default()).unwrap();
    assert!(refused.is_empty(), "{name}: {refused:?}");
    let lagged: Vec<(String, f64)> = c
        .terms
        .terms
        .iter()
        .filter(|t| t.term.label().starts_with("thermal_growth") && t.params.len() == 2)
        .map(|t| {
            (
                t.term
                    .label()
                    .trim_start_matches("thermal_growth[")
                    .trim_end_matches(']')
                    .to_string(),
                t.params[1],
            )
        })
        .collect();
    let sim = Simulation::new(cell(text, name), duration, seed).unwrap();
    let n_joints = c.machine.joint_names().len();
    let mut first_move: Vec<Option<f64>> = vec![None; n_joints];
    let mut first_commanded: Option<Vec<f64>> = None;
    let mut w = Worst {
        position: 0.0,
        temperature: 0.0,
        lag: 0.0,
        power_on: 0.0,
        readings: 0,
        approach_unknown: 0,
        past_last_temperature: 0,
    };
    // thermocouples sample at 1 Hz from t = 0 (every example cell): the last at ⌈duration⌉ − 1
    let last_thermocouple_sample = duration.ceil() - 1.0;
    for (sample, twin) in sim.samples_with_signals() {
        if let Sample::MachineState(m) = &sample {
            let first = first_commanded.get_or_insert_with(|| m.commanded.clone());
            for j in 0..n_joints {
                if first_move[j].is_none()
                    && (m.commanded[j] != first[j] || m.commanded_velocity[j] != 0.0)
                {
                    first_move[j] = Some(m.t);
                }
            }
        }
        let (Sample::Tracker(r), Some(twin)) = (sample, twin) else {
            continue;
        };
        w.readings += 1;
        let t_ns = stamp_ns(start, r.t) as i64;
        let b = builder.signals_at(t_ns);
        let at = format!("{name} at t = {} s", r.t);
        assert!(
            (b.time.unwrap() - start as f64 / 1e9 - r.t).abs() < 1e-6,
            "{at}: time {:?}",
            b.time
        );
        for a in 0..3 {
            match (twin.axis_position[a], b.axis_position[a]) {
                (Some(x), Some(y)) => w.position = w.position.max((x - y).abs()),
                (None, None) => {}
                other => panic!("{at}: axis {a} position {other:?}"),
            }
            assert_eq!(
                twin.axis_velocity[a], b.axis_velocity[a],
                "{at}: axis {a} velocity"
            );
            match (twin.approach_direction[a], b.approach_direction[a]) {
                (Some(x), Some(y)) => assert_eq!(x, y, "{at}: axis {a} approach"),
                // the twin's program starts as if a previous cycle had run; a recording knows
                // an axis's approach only once it has moved
                (Some(_), None) => {
                    assert!(
                        first_move[a].is_none_or(|t0| r.t <= t0),
                        "{at}: axis {a} approach unknown after its first motion at {:?} s",
                        first_move[a]
                    );
                    w.approach_unknown += 1;
                }
                (None, None) => {}
                other => panic!("{at}: axis {a} approach {other:?}"),
            }
        }
        if r.t <= last_thermocouple_sample {
            assert_eq!(twin.rotary_position, b.rotary_position, "{at}: rotary axes");
            assert_eq!(
                twin.temperatures.len(),
                b.temperatures.len(),
                "{at}: sensors"
            );
            for (sensor, v) in &twin.temperatures {
                w.temperature = w.temperature.max((b.temperatures[sensor] - v).abs());
            }
        } else {
            // after the thermocouples' last sample nothing brackets the instant
            assert!(
                b.temperatures.is_empty(),
                "{at}: temperatures past the last sample {:?}",
                b.temperatures
            );
            w.past_last_temperature += 1;
        }
        for (sensor, tau) in &lagged {
            let label = format!("thermal_growth[{sensor}]");
            let (x, _) = twin.lagged_temperature(&label, sensor, *tau).unwrap();
            let (y, _) = b.lagged_temperature(&label, sensor, *tau).unwrap();
            w.lag = w.lag.max((x - y).abs());
        }
        w.power_on = w
            .power_on
            .max((twin.time_since_power_on.unwrap() - b.time_since_power_on.unwrap()).abs());
        assert_eq!(twin.load_force, b.load_force, "{at}: load");
    }
    println!(
        "{name}: {} tracker readings; worst |Δ| position {:.1e} m, temperature {:.1e} K, lagged temperature {:.1e} K, time since power-on {:.1e} s; approach not yet known at {} axis-readings; {} readings after the thermocouples' last sample",
        w.readings, w.position, w.temperature, w.lag, w.power_on, w.approach_unknown, w.past_last_temperature
    );
    assert!(w.readings > 0, "{name}: no tracker readings");
    assert!(
        w.position <= 1e-9,
        "{name}: positions differ by {:e} m",
        w.position
    );
    assert!(
        w.temperature <= 1e-6,
        "{name}: temperatures differ by {:e} K",
        w.temperature
    );
    assert!(
        w.power_on <= 1e-6,
        "{name}: time since power-on differs by {:e} s",
        w.power_on
    );
    // the twin's lag holds each true sample for 10 s, the bag's for 1 s: they differ by about
    // dT/dt·(10 − 1)/2 s, under 5 mK for the ≤ 2.5 K/h of the example shifts
    assert!(
        w.lag <= 5e-3,
        "{name}: lagged temperatures differ by {:e} K",
        w.lag
    );
    let _ = std::fs::remove_dir_all(&bag);
    w
}

#[test]
fn signals_from_sim_bags_equal_the_twins_at_every_tracker_reading() {
    // xfyz_shift with a load, so the load topic is exercised too
    let xfyz = exact_thermocouples(&example("xfyz_shift.yaml")).replace(
        "  thermal_step: 1 s",
        "  thermal_step: 1 s\n  load_force: [0 N, 0 N, -196.2 N]",
    );
    let w = compare_with_twin(&xfyz, "xfyz_shift", 300.0);
    assert!(w.lag > 0.0, "the lagged column growth was compared");
    compare_with_twin(
        &exact_thermocouples(&example("quick_demo.yaml")),
        "quick_demo",
        120.0,
    );
    compare_with_twin(
        &exact_thermocouples(&example("five_axis_table.yaml")),
        "five_axis_table",
        90.0,
    );
    compare_with_twin(
        &exact_thermocouples(&example("serial_arm_ur5.yaml")),
        "serial_arm_ur5",
        60.0,
    );
    // the delta example has no tracker: give it one, so there are readings to compare at
    let tracker = "sensors:\n  tracker:\n    pose: {translation: [-1.2 m, 0.2 m, 0.6 m], euler_xyz: [0 deg, 0 deg, 30 deg]}\n    rate: 10 Hz\n    range_noise: {constant: 4 um, per_metre: 0.8 um/m}\n    angular_noise: 3 urad\n    powered_on_before_start: 5 min\n";
    compare_with_twin(
        &exact_thermocouples(&example("delta_printer.yaml")).replacen("sensors:\n", tracker, 1),
        "delta_printer",
        60.0,
    );
}

#[test]
fn records_carry_the_readings_air_and_the_builders_signals() {
    let text = exact_thermocouples(&example("quick_demo.yaml"));
    let bag = sim_bag(&text, "quick_demo_records", 60.0, 5);
    let c = cell(&text, "quick_demo");
    let instruments = c.tracker_terms().unwrap();
    let model = c.forward_model(&instruments).unwrap();
    let set = records_from_bags(&[&bag], &model, &RecordingOptions::default()).unwrap();
    let sim = Simulation::new(cell(&text, "quick_demo"), 60.0, 5).unwrap();
    let readings: Vec<_> = sim
        .samples_with_signals()
        .filter_map(|(s, sig)| {
            if let Sample::Tracker(r) = s {
                Some((r, sig.unwrap()))
            } else {
                None
            }
        })
        .collect();
    assert_eq!(
        set.records.len() + set.rejected.len(),
        readings.len(),
        "every reading is a record or a rejection"
    );
    // the records were made streaming (a bounded joint window, each measurement resolved as soon
    // as the streams around it were read): their signals are those of the whole bag read at once
    let (whole, _) = signals_from_bag(&bag, &c.machine, &SignalsBuilderOptions::default()).unwrap();
    let start_ns = parse_start_time(DEFAULT_START_TIME).unwrap();
    let mut streamed_records = set.records.iter();
    for (r, _) in readings.iter().filter(|(r, _)| {
        set.records
            .iter()
            .any(|rec| (rec.time - start_ns as f64 / 1e9 - r.t).abs() < 1e-6)
    }) {
        let offline = whole.signals_at(stamp_ns(start_ns, r.t) as i64);
        let streamed = &streamed_records.next().unwrap().signals;
        assert_eq!(
            (
                streamed.time,
                streamed.axis_position,
                streamed.axis_velocity,
                streamed.approach_direction
            ),
            (
                offline.time,
                offline.axis_position,
                offline.axis_velocity,
                offline.approach_direction
            )
        );
        assert_eq!(
            (
                &streamed.temperatures,
                streamed.time_since_power_on,
                streamed.load_force
            ),
            (
                &offline.temperatures,
                offline.time_since_power_on,
                offline.load_force
            )
        );
    }
    assert_eq!(
        set.frame,
        metrocell_estimation::RecordFrame::Instrument("tracker".into())
    );
    let start = parse_start_time(DEFAULT_START_TIME).unwrap() as f64 / 1e9;
    let mut records = set.records.iter().peekable();
    let (mut broken, mut late, mut unmoved) = (0, 0, 0);
    let mut x_moved = false;
    for (r, twin) in &readings {
        x_moved |= twin.axis_velocity[0] != Some(0.0)
            || twin.axis_position[0] != readings[0].1.axis_position[0];
        match records.peek() {
            Some(rec) if (rec.time - start - r.t).abs() < 1e-6 => {
                assert!(
                    r.range.is_finite(),
                    "a beam break became a record at {} s",
                    r.t
                );
                assert_eq!(
                    (rec.signals.air_temperature, rec.signals.air_pressure),
                    (twin.air_temperature, twin.air_pressure)
                );
                assert!(
                    (rec.signals.air_humidity.unwrap() - twin.air_humidity.unwrap()).abs() < 1e-12
                );
                assert_eq!(
                    rec.q,
                    twin.axis_position
                        .iter()
                        .map(|v| v.unwrap())
                        .collect::<Vec<_>>()
                );
                assert_eq!(rec.measured, r.point);
                assert_eq!(rec.covariance, r.covariance);
                records.next();
            }
            // rejected: a beam break; before x first moves (the model's backlash needs its
            // approach); or after the thermocouples' last sample (59 s), which the model's
            // thermal_scale needs
            _ if !r.range.is_finite() => broken += 1,
            _ if !x_moved => unmoved += 1,
            _ => {
                assert!(r.t > 59.0, "reading at {} s rejected", r.t);
                late += 1;
            }
        }
    }
    assert_eq!(broken + late + unmoved, set.rejected.len());
    assert_eq!(
        set.rejected
            .iter()
            .filter(|r| r.reason.contains("BEAM_BREAK"))
            .count(),
        broken
    );
    assert_eq!(
        set.rejected
            .iter()
            .filter(|r| r.reason.contains("approach_direction[x]")
                && r.reason.contains("has not moved yet"))
            .count(),
        unmoved
    );
    assert!(
        late > 0 && late <= 9 && set.records.len() > 400,
        "{} records, {late} late",
        set.records.len()
    );
    println!("{} records; rejected: {broken} beam breaks, {unmoved} before x first moved, {late} after the last temperature sample", set.records.len());
    let _ = std::fs::remove_dir_all(&bag);
}

#[test]
fn records_from_a_sim_bag_are_standard_normal_at_the_true_parameters() {
    // xfyz_shift for 40 min (warm-up, lagged column growth, backlash, refraction with a biased
    // station; before the 3 h turbulence window), thermocouple offsets removed (module docs)
    let text = exact_thermocouples(&example("xfyz_shift.yaml"));
    let bag = sim_bag(&text, "xfyz_identity", 2400.0, 11);
    let c = cell(&text, "xfyz_shift");
    let instruments = c.tracker_terms().unwrap();
    let model = c.forward_model(&instruments).unwrap();
    let set = records_from_bags(
        &[&bag],
        &model,
        &RecordingOptions {
            points: PointSource::TrackerMeasurements,
            ..Default::default()
        },
    )
    .unwrap();
    // beam breaks; readings before x first moves (backlash needs its approach); and the
    // readings of the last second, after the thermocouples' last sample
    let start = parse_start_time(DEFAULT_START_TIME).unwrap() as f64 / 1e9;
    let at = |reason: &str| {
        reason
            .split(" at ")
            .nth(1)
            .and_then(|t| t.split(' ').next())
            .and_then(|t| t.trim_end_matches(':').parse::<f64>().ok())
            .map(|t| t - start)
    };
    for r in &set.rejected {
        let before_motion =
            r.reason.contains("approach_direction[x]") && at(&r.reason).is_some_and(|t| t < 60.0);
        let late = r.reason.contains("temperature[") && at(&r.reason).is_some_and(|t| t > 2399.0);
        assert!(
            r.reason.contains("BEAM_BREAK") || before_motion || late,
            "{r:?}"
        );
    }
    let problem = PointResiduals::new(&model, &set.records).unwrap();
    let mut z = vec![0.0; problem.residual_count()];
    problem.residuals(&model.params(), &mut z).unwrap();
    let n = z.len() as f64;
    let mean = z.iter().sum::<f64>() / n;
    let sd = (z.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    println!(
        "{} records ({} rejected), whitened residual mean {mean:.4} (bound {:.4}), sd {sd:.4}",
        set.records.len(),
        set.rejected.len(),
        3.0 / n.sqrt()
    );
    assert!(set.records.len() > 20_000, "{} records", set.records.len());
    assert!(mean.abs() < 3.0 / n.sqrt(), "mean {mean}");
    assert!((sd - 1.0).abs() < 0.05, "sd {sd}");
    let _ = std::fs::remove_dir_all(&bag);
}

/// The model of the CSV fixture: a cartesian machine whose terms read every signal the export
/// carries (backlash on x: the approach column; time_offset: velocity; lagged growth: the
/// temperature history; the tracker's warm-up and refraction: time since power-on and the air).
/// (No reversal term on y or z: their approach is unknown until they first move, which would
/// reject the first rows.)
const CSV_MODEL: &str = r#"
name: csv_model
machine:
  family: cartesian
  stacking: XFYZ
  travel: {x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 500 mm]}
  tool_offset: [0 mm, 0 mm, -150 mm]
sensors:
  tracker:
    pose: {translation: [0 m, 0 m, 0 m], euler_xyz: [0 deg, 0 deg, 0 deg]}
    rate: 1 Hz
    range_noise: {constant: 4 um, per_metre: 0.8 um/m}
    angular_noise: 3 urad
    warmup: {offset: 0 um, amplitude: 20 um, time_constant: 30 min}
  thermocouples:
    - {name: column, location: ambient, noise: 0.02 K, rate: 1 Hz}
environment:
  ambient: {mean: 20 degC}
  air: {pressure: 101.3 kPa, humidity: 45}
program:
  points: [[100 mm, 50 mm, 450 mm]]
  feed_rate: 50 mm/s
  dwell: 1 s
terms:
  - id: backlash
    options: {axis: x}
    params: {reversal: 5 um}
  - id: time_offset
    params: {latency: 1 ms}
  - id: thermal_growth
    options: {sensor: column, direction: [0, 0, -1], lag: true}
    params: {coefficient: 4 um/K, time_constant: 20 min}
"#;

/// The fixture's rows as numbers (SI).
struct Row {
    t: f64,
    point: String,
    measured: [f64; 3],
    u: f64,
    joints: [f64; 3],
    velocity: [f64; 3],
    approach_x: f64,
    on: f64,
    column: f64,
    air: (f64, f64, f64),
}

fn csv_rows() -> Vec<Row> {
    let text = std::fs::read_to_string(fixture("recordings_export.csv")).unwrap();
    text.lines()
        .skip(1)
        .map(|l| {
            let c: Vec<&str> = l.split(',').collect();
            let f = |i: usize| c[i].parse::<f64>().unwrap();
            let mm = |i: usize| format!("{}e-3", c[i]).parse::<f64>().unwrap();
            Row {
                t: f(0),
                point: c[1].to_string(),
                measured: [mm(2), mm(3), mm(4)],
                u: mm(5) / 2.0,
                joints: [mm(6), mm(7), mm(8)],
                velocity: [mm(9), mm(10), mm(11)],
                approach_x: f(12),
                on: f(13),
                column: f(14),
                // as the importer converts: the decimal text with a shifted exponent
                air: (
                    f(15),
                    format!("{}e2", c[16]).parse::<f64>().unwrap(),
                    format!("{}e-2", c[17]).parse::<f64>().unwrap() * 100.0,
                ),
            }
        })
        .collect()
}

#[test]
fn signals_of_an_imported_export_equal_its_values() {
    let bag = scratch("csv_import");
    let mapping = Mapping::load(&fixture("recordings_mapping.yaml")).unwrap();
    let report = import_csv(
        &fixture("recordings_export.csv"),
        &bag,
        Some(&mapping),
        WriterOptions::default(),
    )
    .unwrap();
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    let c = cell(CSV_MODEL, "csv_model");
    let instruments = c.tracker_terms().unwrap();
    let model = c.forward_model(&instruments).unwrap();
    let set = records_from_bags(&[&bag], &model, &RecordingOptions::default()).unwrap();
    let rows = csv_rows();
    assert!(set.rejected.is_empty(), "{:?}", set.rejected);
    assert_eq!(set.records.len(), rows.len());
    assert_eq!(set.frame, metrocell_estimation::RecordFrame::Machine);
    let job_start = 1_767_258_000.0;
    // y and z carry no approach column: the rule (sign of the last motion) on the joints
    let mut last = [rows[0].joints[1], rows[0].joints[2]];
    let mut derived: [Option<f64>; 2] = [None, None];
    for (rec, row) in set.records.iter().zip(&rows) {
        let s = &rec.signals;
        assert_eq!(rec.point_id, row.point);
        assert_eq!(rec.channel, "fixture_export");
        assert!(
            (rec.time - (job_start + row.t)).abs() < 1e-6,
            "{}: time {}",
            row.point,
            rec.time
        );
        assert_eq!(rec.q, row.joints.to_vec(), "{}", row.point);
        assert_eq!(
            rec.measured.as_slice(),
            row.measured.as_slice(),
            "{}",
            row.point
        );
        assert_eq!(rec.covariance[(0, 0)], row.u * row.u);
        assert_eq!(s.axis_position, row.joints.map(Some), "{}", row.point);
        assert_eq!(s.axis_velocity, row.velocity.map(Some), "{}", row.point);
        for (k, axis) in [1, 2].into_iter().enumerate() {
            let q = row.joints[axis];
            if q != last[k] {
                derived[k] = Some((q - last[k]).signum());
                last[k] = q;
            }
        }
        assert_eq!(
            s.approach_direction,
            [Some(row.approach_x), derived[0], derived[1]],
            "{}",
            row.point
        );
        assert_eq!(s.temperatures["column"], row.column);
        assert_eq!(s.temperatures["air"], row.air.0);
        assert_eq!(
            (s.air_temperature, s.air_pressure),
            (Some(row.air.0), Some(row.air.1))
        );
        assert!((s.air_humidity.unwrap() - row.air.2).abs() < 1e-12);
        assert!(
            (s.time_since_power_on.unwrap() - (row.t - row.on)).abs() < 1e-9,
            "{}: {:?}",
            row.point,
            s.time_since_power_on
        );
        // the lag reads exactly the export's column readings up to the row
        let history = s
            .timeline
            .as_ref()
            .unwrap()
            .history("column", s.time)
            .unwrap();
        assert_eq!(
            history.samples.iter().map(|x| x.1).collect::<Vec<_>>(),
            rows.iter()
                .take_while(|r| r.t <= row.t)
                .map(|r| r.column)
                .collect::<Vec<_>>()
        );
    }
    assert!(
        derived.iter().all(|d| d.is_some()),
        "both rule-derived axes moved"
    );
    let _ = std::fs::remove_dir_all(&bag);
}

/// `csv` imported with the fixture's mapping, its joint columns read as nominals (and `extra`
/// mapping lines), into `dir`; the records the CSV model builds from it.
fn import_as_nominals(dir: &Path, csv: &Path, extra: &str) -> metrocell_estimation::RecordSet {
    let mapping_text = std::fs::read_to_string(fixture("recordings_mapping.yaml"))
        .unwrap()
        .replace("  joint.x:", "  nominal_x:")
        .replace("  joint.y:", "  nominal_y:")
        .replace("  joint.z:", "  nominal_z:")
        + extra;
    std::fs::write(dir.join("mapping.yaml"), mapping_text).unwrap();
    let bag = dir.join("bag");
    let report = import_csv(
        csv,
        &bag,
        Some(&Mapping::load(&dir.join("mapping.yaml")).unwrap()),
        WriterOptions::default(),
    )
    .unwrap();
    assert!(report.errors.is_empty(), "{:?}", report.errors);
    let c = cell(CSV_MODEL, "csv_model");
    let instruments = c.tracker_terms().unwrap();
    let model = c.forward_model(&instruments).unwrap();
    records_from_bags(&[&bag], &model, &RecordingOptions::default()).unwrap()
}

/// An export with nominals and velocities but no joint columns (issue 26): on a cartesian machine
/// the nominals give the commanded axes (nominal − tool offset) and the velocity columns the
/// axis velocities; nothing is set aside.
#[test]
fn nominals_give_the_axes_when_an_export_has_velocities_but_no_joints() {
    let dir = scratch("csv_nominal_velocity");
    std::fs::create_dir_all(&dir).unwrap();
    let set = import_as_nominals(&dir, &fixture("recordings_export.csv"), "");
    let rows = csv_rows();
    assert!(set.rejected.is_empty(), "{:?}", set.rejected);
    assert_eq!(set.records.len(), rows.len());
    for (rec, row) in set.records.iter().zip(&rows) {
        // the tool offset is (0, 0, −150 mm): the axes are the nominal minus it
        let q = [row.joints[0], row.joints[1], row.joints[2] + 0.150];
        for k in 0..3 {
            assert!(
                (rec.q[k] - q[k]).abs() < 1e-12,
                "{}: q {:?} vs {q:?}",
                row.point,
                rec.q
            );
            assert!((rec.signals.axis_position[k].unwrap() - q[k]).abs() < 1e-12);
        }
        assert_eq!(
            rec.signals.axis_velocity,
            row.velocity.map(Some),
            "{}",
            row.point
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// The same export with the reflector moved between readings (columns `tool_offset.*`, bag
/// import's /machine/tool_offset): each reading's axes are its nominal minus the tool offset
/// active then, and its signals carry that offset's difference from the model's tool.
#[test]
fn a_reading_of_a_moved_reflector_carries_its_tool_offset() {
    let dir = scratch("csv_tool_offset");
    std::fs::create_dir_all(&dir).unwrap();
    // the first half at the model's tool (0, 0, −150 mm), the rest 100 mm along X from it
    let reflector = |k: usize| {
        if k < 5 {
            [0.0, 0.0, -0.150]
        } else {
            [0.100, 0.0, -0.150]
        }
    };
    let export = std::fs::read_to_string(fixture("recordings_export.csv")).unwrap();
    let mut text = String::new();
    for (k, line) in export.lines().enumerate() {
        let extra = match k {
            0 => ",tool_x_mm,tool_y_mm,tool_z_mm".to_string(),
            _ => {
                let r = reflector(k - 1);
                format!(",{},{},{}", r[0] * 1e3, r[1] * 1e3, r[2] * 1e3)
            }
        };
        text += &format!("{line}{extra}\n");
    }
    std::fs::write(dir.join("export.csv"), text).unwrap();
    let set = import_as_nominals(
        &dir,
        &dir.join("export.csv"),
        "  tool_offset.x: {column: tool_x_mm, scale: 0.001}\n  tool_offset.y: {column: tool_y_mm, scale: 0.001}\n  tool_offset.z: {column: tool_z_mm, scale: 0.001}\n",
    );
    let tool_offsets = metrocell_bag::BagReader::open(dir.join("bag"))
        .unwrap()
        .messages(&metrocell_bag::MessageFilter::default())
        .unwrap()
        .filter(|m| m.as_ref().unwrap().topic == "/machine/tool_offset")
        .count();
    assert_eq!(tool_offsets, 2, "written when it changes");
    let rows = csv_rows();
    assert!(set.rejected.is_empty(), "{:?}", set.rejected);
    assert_eq!(set.records.len(), rows.len());
    for (k, (rec, row)) in set.records.iter().zip(&rows).enumerate() {
        let r = reflector(k);
        let q = [
            row.joints[0] - r[0],
            row.joints[1] - r[1],
            row.joints[2] - r[2],
        ];
        for a in 0..3 {
            assert!(
                (rec.q[a] - q[a]).abs() < 1e-12,
                "{}: q {:?} vs {q:?}",
                row.point,
                rec.q
            );
        }
        let shift = rec.signals.tool_offset_shift.expect("recorded");
        assert!(
            (shift - nalgebra::Vector3::new(r[0], r[1], r[2] + 0.150)).norm() < 1e-12,
            "{}: shift {shift:?}",
            row.point
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_lagged_growth_on_a_missing_sensor_names_term_signal_topic_and_column() {
    let text = exact_thermocouples(&example("quick_demo.yaml"));
    let bag = sim_bag(&text, "quick_demo_missing", 10.0, 1);
    let model_text = text.replace("    - {name: x_right", "    - {name: spindle, location: ambient, noise: 0 K, rate: 1 Hz}\n    - {name: x_right")
        + "\n  - id: thermal_growth\n    options: {sensor: spindle, direction: [0, 0, -1], lag: true}\n    params: {coefficient: 4 um/K, time_constant: 20 min}\n";
    let c = cell(&model_text, "model");
    let instruments = c.tracker_terms().unwrap();
    let model = c.forward_model(&instruments).unwrap();
    let e = records_from_bags(&[&bag], &model, &RecordingOptions::default()).unwrap_err();
    let msg = e.to_string();
    println!("{msg}");
    assert!(matches!(e, RecordingError::MissingSignal { .. }));
    for needle in [
        "thermal_growth[spindle]",
        "temperature_history[spindle]",
        "/temperature/spindle",
        "temperature.spindle",
        &bag.display().to_string(),
    ] {
        assert!(msg.contains(needle), "`{needle}` not in: {msg}");
    }
    let _ = std::fs::remove_dir_all(&bag);
}

/// A point to write: stamp (ns), frame, target, position (m), covariance (m², row-major).
type PointRow<'a> = (u64, &'a str, &'a str, [f64; 3], [f64; 9]);

fn write_points(dir: &Path, points: &[PointRow]) {
    let mut w = BagWriter::create(dir, WriterOptions::default()).unwrap();
    w.add_topic(
        "/measured_points",
        MeasuredPoint::ROS_TYPE,
        MeasuredPoint::DEFINITION,
        "",
    )
    .unwrap();
    for (t, id, frame, p, cov) in points {
        let m = MeasuredPoint {
            header: Header {
                stamp: Time::from_nanos(*t as i64),
                frame_id: frame.to_string(),
            },
            point_id: id.to_string(),
            source: "test".into(),
            nominal: Point {
                x: p[0],
                y: p[1],
                z: p[2] + 0.15,
            },
            measured: Point {
                x: p[0],
                y: p[1],
                z: p[2],
            },
            covariance: *cov,
        };
        w.write(
            "/measured_points",
            *t,
            *t,
            &metrocell_bagtools::encode_cdr(&m).unwrap(),
        )
        .unwrap();
    }
    w.finish().unwrap();
}

#[test]
fn bad_measurements_are_rejected_with_where_and_bad_bags_name_their_file() {
    // nominal-only points on a cartesian machine (q = nominal − tool offset), and three bad ones
    let text = r#"
name: plain
machine: {family: cartesian, stacking: XFYZ, travel: {x: [0 mm, 400 mm], y: [0 mm, 300 mm], z: [0 mm, 200 mm]}, tool_offset: [0 mm, 0 mm, -150 mm]}
sensors: {}
environment: {ambient: {mean: 20 degC}, air: {pressure: 101.3 kPa, humidity: 45}}
program: {points: [[0 mm, 0 mm, 0 mm]], feed_rate: 50 mm/s, dwell: 1 s}
terms:
  - id: positioning
    options: {axis: x, order: 1}
    params: {c0: 0 um, c1: 10 um}
"#;
    let c = cell(text, "plain");
    let instruments = c.tracker_terms().unwrap();
    let model = c.forward_model(&instruments).unwrap();
    let good = [1e-10, 0.0, 0.0, 0.0, 1e-10, 0.0, 0.0, 0.0, 1e-10];
    let mut nan_cov = good;
    nan_cov[4] = f64::NAN;
    let not_pd = [1e-10, 2e-10, 0.0, 2e-10, 1e-10, 0.0, 0.0, 0.0, 1e-10];
    let dir = scratch("bad_points");
    write_points(
        &dir,
        &[
            (1_000_000_000, "a", "machine", [0.1, 0.1, 0.1], good),
            (
                2_000_000_000,
                "nan_point",
                "machine",
                [f64::NAN, 0.1, 0.1],
                good,
            ),
            (
                3_000_000_000,
                "nan_cov",
                "machine",
                [0.2, 0.1, 0.1],
                nan_cov,
            ),
            (4_000_000_000, "not_pd", "machine", [0.3, 0.1, 0.1], not_pd),
            (5_000_000_000, "b", "", [0.3, 0.2, 0.1], good),
        ],
    );
    let set = records_from_bags(&[&dir], &model, &RecordingOptions::default()).unwrap();
    assert_eq!(
        set.records
            .iter()
            .map(|r| r.point_id.as_str())
            .collect::<Vec<_>>(),
        ["a", "b"]
    );
    assert_eq!(
        set.frame,
        metrocell_estimation::RecordFrame::Machine,
        "`machine` and an empty frame are the machine frame"
    );
    // nominal z = 0.1 + 0.15 m, tool offset z = −0.15 m
    assert!(
        (set.records[1].q[2] - 0.4).abs() < 1e-15,
        "q = nominal − tool offset: {:?}",
        set.records[1].q
    );
    let reasons: Vec<(&str, &str)> = set
        .rejected
        .iter()
        .map(|r| (r.point_id.as_str(), r.reason.as_str()))
        .collect();
    assert_eq!(reasons.len(), 3, "{reasons:?}");
    assert!(reasons[0].0 == "nan_point" && reasons[0].1.contains("not finite"));
    assert!(reasons[1].0 == "nan_cov" && reasons[1].1.contains("covariance is not finite"));
    assert!(reasons[2].0 == "not_pd" && reasons[2].1.contains("not positive definite"));
    assert!(
        set.rejected
            .iter()
            .all(|r| r.at.contains(&dir.display().to_string())
                && r.at.contains("/measured_points message")),
        "{:?}",
        set.rejected
    );

    // two frames in one set
    let other = scratch("other_frame");
    write_points(
        &other,
        &[(1_000_000_000, "c", "tracker", [0.1, 0.1, 0.1], good)],
    );
    let e = records_from_bags(&[&dir, &other], &model, &RecordingOptions::default())
        .unwrap_err()
        .to_string();
    assert!(e.contains("`machine`") && e.contains("`tracker`"), "{e}");

    // a five-axis model needs the joints: the nominal is not enough
    let five = cell(&example("five_axis_table.yaml"), "five");
    let five_instruments = five.tracker_terms().unwrap();
    let five_model = five.forward_model(&five_instruments).unwrap();
    let e = records_from_bags(&[&dir], &five_model, &RecordingOptions::default())
        .unwrap_err()
        .to_string();
    for needle in [
        "five_axis",
        "/machine/commanded_joint_states",
        "joint.b",
        "joint.c",
    ] {
        assert!(e.contains(needle), "`{needle}` not in: {e}");
    }

    // a truncated bag: the reader's error, with the file
    let mcap = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .find(|p| p.extension().is_some_and(|x| x == "mcap"))
        .unwrap();
    let bytes = std::fs::read(&mcap).unwrap();
    std::fs::write(&mcap, &bytes[..bytes.len() / 2]).unwrap();
    let e = records_from_bags(&[&dir], &model, &RecordingOptions::default()).unwrap_err();
    let msg = e.to_string();
    println!("{msg}");
    assert!(
        matches!(e, RecordingError::Bag { .. }) && msg.contains(&dir.display().to_string()),
        "{msg}"
    );

    // a bag without points
    let empty = scratch("no_points");
    let mut w = BagWriter::create(&empty, WriterOptions::default()).unwrap();
    w.add_topic(
        "/temperature/x",
        "sensor_msgs/msg/Temperature",
        metrocell_msgs::sensor_msgs::msg::Temperature::DEFINITION,
        "",
    )
    .unwrap();
    w.finish().unwrap();
    let e = records_from_bags(&[&empty], &model, &RecordingOptions::default())
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("/measured_points")
            && e.contains("/tracker/measurements")
            && e.contains("/temperature/x"),
        "{e}"
    );
    for d in [dir, other, empty] {
        let _ = std::fs::remove_dir_all(d);
    }
}

/// A bag recorded live from a twin running faster than real time: log times are the wall clock
/// (here years after the stamps), the stamps simulated time. The records are those of the same
/// messages logged at their stamps: readiness is judged on the stamps, so no reading is resolved
/// before the thermocouple samples that bracket it were read (the log time would declare every
/// reading ready at once and set most aside "after the last temperature sample").
#[test]
fn records_of_a_live_bag_whose_log_times_run_ahead_of_the_stamps_equal_the_offline_ones() {
    let text = exact_thermocouples(&example("demo_shift.yaml"));
    let offline = sim_bag(&text, "live_log_times_offline", 600.0, 3);
    let live = scratch("live_log_times_live");
    {
        let reader = metrocell_bag::BagReader::open(&offline).unwrap();
        let mut w = BagWriter::create(&live, WriterOptions::default()).unwrap();
        for t in reader.topics() {
            w.add_topic(
                &t.name,
                &t.type_name,
                &t.definition,
                &t.offered_qos_profiles,
            )
            .unwrap();
        }
        // the wall clock of a run at 60×, starting ~10 months after the simulated start
        let (wall0, sim0) = (
            1_795_654_543_000_000_000u64,
            parse_start_time(DEFAULT_START_TIME).unwrap() as u64,
        );
        for m in reader
            .read_all(&metrocell_bag::MessageFilter::default())
            .unwrap()
        {
            let wall = wall0 + (m.log_time - sim0) / 60;
            w.write(&m.topic, wall, wall, &m.data).unwrap();
        }
        w.finish().unwrap();
    }
    let c = cell(&text, "demo_shift");
    let instruments = c.tracker_terms().unwrap();
    let model = c.forward_model(&instruments).unwrap();
    let options = RecordingOptions {
        points: PointSource::TrackerMeasurements,
        ..Default::default()
    };
    let a = records_from_bags(&[&offline], &model, &options).unwrap();
    let b = records_from_bags(&[&live], &model, &options).unwrap();
    assert!(
        a.records.len() > 2000,
        "{} records offline, {} set aside",
        a.records.len(),
        a.rejected.len()
    );
    assert_eq!(
        (b.records.len(), b.rejected.len()),
        (a.records.len(), a.rejected.len()),
        "live: {:?}",
        b.rejected.iter().take(3).collect::<Vec<_>>()
    );
    for (x, y) in a.records.iter().zip(&b.records) {
        assert_eq!((x.time, x.measured, &x.q), (y.time, y.measured, &y.q));
        assert_eq!(
            format!("{:?}", x.signals.temperatures),
            format!("{:?}", y.signals.temperatures)
        );
    }
    let _ = std::fs::remove_dir_all(&offline);
    let _ = std::fs::remove_dir_all(&live);
}
