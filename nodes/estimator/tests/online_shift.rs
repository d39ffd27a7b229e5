//! `metrocell-estimator` on recorded shifts: it tracks a parameter that thermal growth makes
//! drift within its reported uncertainty, flags a crash that shifts an axis by 20 µm within 20
//! measurements, restarts from its state file, and its `--bag` replay equals the live node fed by
//! `metrocell bag play` bit for bit.
//!
//! The shift (generated here, not by the twin, so the truth is known exactly): an XFYZ machine
//! measured at a 4 × 4 × 2 grid, one point every 10 s of stamp time for 4000 s; a column that
//! warms with τ = 20 min grows Z by 4 µm/K (the model has no thermal term: its
//! `positioning[z].c0` is declared drifting and must follow the growth); X scale 15 µm/m,
//! squareness 10 µrad; tracker noise 3 µm. Joint states bracket every point; log times are
//! compressed to 20 ms per point so `bag play` is quick, header stamps keep the 10 s spacing.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use metrocell_bag::{qos_profiles_yaml, BagWriter, QosProfile, WriterOptions};
use metrocell_bagtools::{encode_cdr, BagSource};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::geometry_msgs::msg::Point;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::{JointState, Temperature};
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::testing::KillOnDrop as Killed;
use metrocell_node::{qos, MetrocellNode};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rosmsg::RosMessage;

const MODEL: &str = r#"
name: online_model
machine:
  family: cartesian
  stacking: XFYZ
  travel: {x: [0 mm, 800 mm], y: [0 mm, 500 mm], z: [0 mm, 400 mm]}
sensors: {}
environment:
  ambient: {mean: 20 degC}
  air: {pressure: 101.3 kPa, humidity: 45}
program:
  grid:
    x: {from: 0 mm, to: 800 mm, count: 2}
    y: {from: 0 mm, to: 500 mm, count: 2}
    z: {from: 0 mm, to: 0 mm, count: 1}
  feed_rate: 100 mm/s
  dwell: 1 s
terms:
  - id: positioning
    options: {axis: x, order: 1, travel: [0 mm, 800 mm]}
    params: {c0: 0 um, c1: 0 um}
  - id: positioning
    options: {axis: y, order: 1, travel: [0 mm, 500 mm]}
    params: {c0: 0 um, c1: 0 um}
  - id: positioning
    options: {axis: z, order: 1, travel: [0 mm, 400 mm]}
    params: {c0: 0 um, c1: 0 um}
  - id: squareness
    options: {pair: xy}
    params: {s: 0 urad}
"#;

const T0_NS: i64 = 1_767_225_600_000_000_000;
const SIGMA: f64 = 3e-6;
const PERIOD_S: f64 = 10.0;
/// Log-time spacing of the points in the bag (bag play paces by it).
const LOG_STEP_NS: u64 = 20_000_000;
/// Z growth per kelvin of the column and its warming: ΔT(t) = 3 K·(1 − e^(−t/τ)).
const GROWTH_PER_K: f64 = 4e-6;
const TAU_S: f64 = 1200.0;

fn column_rise(t: f64) -> f64 {
    3.0 * (1.0 - (-t / TAU_S).exp())
}

fn stamp(ns: i64) -> Time {
    Time::from_nanos(ns)
}

/// The point of measurement i: (joints, true Z growth at its time).
fn grid(i: usize) -> [f64; 3] {
    let k = i % 32;
    [
        0.8 * (k % 4) as f64 / 3.0,
        0.5 * ((k / 4) % 4) as f64 / 3.0,
        0.4 * (k / 16) as f64,
    ]
}

/// Writes the shift bag; returns the true drifting c0 of Z at each measurement.
fn write_shift(dir: &Path, n: usize, step_at: Option<usize>, seed: u64) -> Vec<f64> {
    let mut w = BagWriter::create(dir, WriterOptions::default()).unwrap();
    let qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
    w.add_topic(
        "/machine/commanded_joint_states",
        JointState::ROS_TYPE,
        JointState::DEFINITION,
        &qos,
    )
    .unwrap();
    w.add_topic(
        "/measured_points",
        MeasuredPoint::ROS_TYPE,
        MeasuredPoint::DEFINITION,
        &qos,
    )
    .unwrap();
    w.add_topic(
        "/temperature/column",
        Temperature::ROS_TYPE,
        Temperature::DEFINITION,
        &qos,
    )
    .unwrap();
    let noise = Normal::new(0.0, SIGMA).unwrap();
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut truth = Vec::new();
    let mut log_ns = T0_NS as u64;
    for i in 0..n {
        let t = PERIOD_S * i as f64;
        let stamp_ns = T0_NS + (t * 1e9) as i64;
        let q = grid(i);
        let header = |ns: i64| Header {
            stamp: stamp(ns),
            frame_id: "machine".into(),
        };
        // the machine stands at the point from 1 s before to 1 s after the measurement (sampled
        // every second: the joint stream's longest interpolated gap is 1 s)
        for dt in [-1_000_000_000i64, 0, 1_000_000_000] {
            let js = JointState {
                header: header(stamp_ns + dt),
                name: vec!["x".into(), "y".into(), "z".into()],
                position: q.to_vec(),
                velocity: vec![0.0; 3],
                effort: vec![],
            };
            log_ns += LOG_STEP_NS / 4;
            w.write(
                "/machine/commanded_joint_states",
                log_ns,
                log_ns,
                &encode_cdr(&js).unwrap(),
            )
            .unwrap();
        }
        let temperature = Temperature {
            header: header(stamp_ns),
            temperature: 20.0 + column_rise(t),
            variance: 1e-4,
        };
        log_ns += LOG_STEP_NS / 4;
        w.write(
            "/temperature/column",
            log_ns,
            log_ns,
            &encode_cdr(&temperature).unwrap(),
        )
        .unwrap();
        let growth = GROWTH_PER_K * column_rise(t);
        // positioning's series is in u = 2x/travel − 1: a 15 µm/m X scale puts 6 µm into X's c0
        let mut p = [q[0] + 15e-6 * q[0] - 10e-6 * q[1], q[1], q[2] + growth];
        if step_at.is_some_and(|s| i >= s) {
            p[1] += 20e-6; // the crash: Y shifted 20 µm
        }
        let m = MeasuredPoint {
            header: header(stamp_ns),
            point_id: format!("p{}", i % 32),
            source: "tracker".into(),
            nominal: Point {
                x: q[0],
                y: q[1],
                z: q[2],
            },
            measured: Point {
                x: p[0] + noise.sample(&mut rng),
                y: p[1] + noise.sample(&mut rng),
                z: p[2] + noise.sample(&mut rng),
            },
            covariance: [
                SIGMA * SIGMA,
                0.0,
                0.0,
                0.0,
                SIGMA * SIGMA,
                0.0,
                0.0,
                0.0,
                SIGMA * SIGMA,
            ],
        };
        log_ns += LOG_STEP_NS / 2;
        w.write("/measured_points", log_ns, log_ns, &encode_cdr(&m).unwrap())
            .unwrap();
        truth.push(growth);
    }
    w.finish().unwrap();
    truth
}

struct Run {
    dir: PathBuf,
}

impl Run {
    fn new(name: &str) -> Run {
        let dir =
            std::env::temp_dir().join(format!("metrocell-estimator-{name}-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        std::fs::write(dir.join("model.yaml"), MODEL).unwrap();
        Run { dir }
    }
    fn args(&self, extra: &[String]) -> Vec<String> {
        let mut a: Vec<String> = ["--ros-args", "-p"].iter().map(|s| s.to_string()).collect();
        a.push(format!("model:={}", self.dir.join("model.yaml").display()));
        // the column's growth may move Z's offset ~10 nm/√s (1 µm in ~3 h of random walk)
        a.extend(
            [
                "-p",
                "process_noise:=['positioning[z].c0=1e-7']",
                "-p",
                "predict_points:=[0.4, 0.25, 0.2]",
            ]
            .iter()
            .map(|s| s.to_string()),
        );
        a.extend(extra.iter().cloned());
        a
    }
    /// `metrocell-estimator --bag input --output out`: (models, alarms).
    fn replay(
        &self,
        input: &Path,
        out: &str,
        extra: &[String],
    ) -> (Vec<ErrorModel>, Vec<DiagnosticArray>, Vec<MeasuredPoint>) {
        let output = self.dir.join(out);
        let o = Command::new(env!("CARGO_BIN_EXE_metrocell-estimator"))
            .arg("--bag")
            .arg(input)
            .arg("--output")
            .arg(&output)
            .args(self.args(extra))
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "metrocell-estimator --bag failed: {}\n{}",
            o.status,
            String::from_utf8_lossy(&o.stderr)
        );
        read_outputs(&output)
    }
}

impl Drop for Run {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

fn read_outputs(bag: &Path) -> (Vec<ErrorModel>, Vec<DiagnosticArray>, Vec<MeasuredPoint>) {
    let mut source = BagSource::open(bag).unwrap();
    source
        .subscribe::<ErrorModel>("/estimator/error_model")
        .unwrap();
    source.subscribe::<DiagnosticArray>("/diagnostics").unwrap();
    source
        .subscribe::<MeasuredPoint>("/estimator/predicted_error")
        .unwrap();
    let (mut models, mut alarms, mut predicted) = (Vec::new(), Vec::new(), Vec::new());
    for m in source.messages().unwrap() {
        let m = m.unwrap();
        match m.topic.as_str() {
            "/estimator/error_model" => models.push(m.decode().unwrap()),
            "/diagnostics" => alarms.push(m.decode().unwrap()),
            _ => predicted.push(m.decode().unwrap()),
        }
    }
    (models, alarms, predicted)
}

fn value_sigma(m: &ErrorModel, name: &str) -> (f64, f64) {
    let n = m.values.len();
    let i = m
        .parameter_names
        .iter()
        .position(|p| p == name)
        .unwrap_or_else(|| panic!("{name} not in {:?}", m.parameter_names));
    (m.values[i], m.covariance[i * n + i].sqrt())
}

#[test]
fn tracks_the_drifting_z_offset_within_its_uncertainty() {
    let run = Run::new("drift");
    let input = run.dir.join("shift");
    let truth = write_shift(&input, 400, None, 3);
    let (models, alarms, predicted) = run.replay(&input, "out", &[]);
    assert!(
        alarms.is_empty(),
        "false alarms on an honest shift: {:?}",
        alarms
            .iter()
            .map(|a| &a.status[0].message)
            .collect::<Vec<_>>()
    );
    assert_eq!(
        models.len(),
        400,
        "one model per accepted measurement (publish_every 1)"
    );
    // the message describes its terms so a consumer can rebuild them
    let m = &models[0];
    assert_eq!(
        m.term_labels,
        vec![
            "positioning[x]",
            "positioning[y]",
            "positioning[z]",
            "squareness[xy]"
        ]
    );
    assert_eq!(m.term_catalog_ids[3], "squareness");
    assert!(
        m.term_options[2].contains(r#""axis":"z""#),
        "options of positioning[z]: {}",
        m.term_options[2]
    );
    let c0 = m
        .parameter_names
        .iter()
        .position(|p| p == "positioning[z].c0")
        .unwrap();
    assert_eq!(m.units[c0], "m");
    let rebuilt = metrocell_physics::configure_described(
        &m.term_catalog_ids[2],
        &m.term_options[2],
        &m.values[4..6],
    )
    .unwrap();
    assert_eq!(rebuilt.term.label(), "positioning[z]");
    // after convergence the drifting offset follows the growth within its stated σ
    let z: Vec<f64> = models
        .iter()
        .zip(&truth)
        .skip(100)
        .map(|(m, g)| {
            let (v, s) = value_sigma(m, "positioning[z].c0");
            (v - g) / s
        })
        .collect();
    let within_2 = z.iter().filter(|v| v.abs() < 2.0).count() as f64 / z.len() as f64;
    let max = z.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    assert!(
        within_2 > 0.8 && max < 4.5,
        "drift tracked: {:.0} % within 2σ, max |z| {max:.2}",
        100.0 * within_2
    );
    let grown = truth.last().unwrap();
    assert!(
        *grown > 10e-6,
        "the growth ({:.1} µm) must be large against the noise for this to mean anything",
        grown * 1e6
    );
    // the X scale: 15 µm/m over the 0.8 m travel is c1 = 6 µm (u = 2x/travel − 1)
    let (c1, s1) = value_sigma(models.last().unwrap(), "positioning[x].c1");
    assert!(
        (c1 - 6e-6).abs() < 3.0 * s1 && s1 < 1e-6,
        "X scale c1 = {:.2} ± {:.2} µm",
        c1 * 1e6,
        s1 * 1e6
    );
    // predicted volumetric error at (0.4, 0.25, 0.2): Z carries the growth, with its σ
    let last = predicted.last().unwrap();
    let cov_zz = last.covariance[8].sqrt();
    assert!(
        ((last.measured.z - last.nominal.z) - grown).abs() < 3.0 * cov_zz,
        "predicted Z error {:.2} µm ± {:.2}, growth {:.2}",
        (last.measured.z - last.nominal.z) * 1e6,
        cov_zz * 1e6,
        grown * 1e6
    );
}

#[test]
fn flags_a_20_um_crash_within_20_measurements_and_restarts_from_its_state_file() {
    let run = Run::new("step");
    let input = run.dir.join("shift");
    let step = 250;
    write_shift(&input, 300, Some(step), 11);
    let (models, alarms, _) = run.replay(&input, "out", &[]);
    assert!(!alarms.is_empty(), "the 20 µm step was never flagged");
    let first = &alarms[0].status[0];
    assert_eq!(
        first.level,
        metrocell_msgs::diagnostic_msgs::msg::DiagnosticStatus::ERROR
    );
    let at: u64 = first
        .values
        .iter()
        .find(|kv| kv.key == "alarm_measurement")
        .unwrap()
        .value
        .parse()
        .unwrap();
    assert!(
        at >= step as u64,
        "alarm before the step, at measurement {at}: {}",
        first.message
    );
    assert!(
        at - (step as u64) < 20,
        "flagged {} measurements after the step",
        at - step as u64
    );
    assert!(
        first.message.contains("stopped explaining the data"),
        "{}",
        first.message
    );
    // after the alarm the estimate re-converges: Y's offset takes the 20 µm
    let (y0, sy) = value_sigma(models.last().unwrap(), "positioning[y].c0");
    assert!(
        (y0 - 20e-6).abs() < 4.0 * sy + 1e-6,
        "Y offset after the crash {:.2} ± {:.2} µm",
        y0 * 1e6,
        sy * 1e6
    );

    // restart: the first half with a state file, then the second half from it, ends where one
    // run over the whole shift ends (the filter's state is all it carries)
    let state = run.dir.join("state.json");
    let first_half = run.dir.join("first");
    let second_half = run.dir.join("second");
    let whole = run.dir.join("whole");
    write_shift(&whole, 200, None, 5);
    write_partial(&whole, &first_half, 0, 100);
    write_partial(&whole, &second_half, 100, 200);
    let state_arg = vec!["-p".to_string(), format!("state_file:={}", state.display())];
    let (all, _, _) = run.replay(&whole, "out_whole", &[]);
    run.replay(&first_half, "out_first", &state_arg);
    assert!(state.exists(), "no state file written");
    let (resumed, _, _) = run.replay(&second_half, "out_second", &state_arg);
    let (a, b) = (all.last().unwrap(), resumed.last().unwrap());
    assert_eq!(a.parameter_names, b.parameter_names);
    for (i, name) in a.parameter_names.iter().enumerate() {
        let n = a.values.len();
        let s = a.covariance[i * n + i].sqrt();
        assert!(
            (a.values[i] - b.values[i]).abs() < 0.05 * s.max(1e-9),
            "{name}: whole {} vs resumed {}",
            a.values[i],
            b.values[i]
        );
    }
    let fresh = run.replay(&second_half, "out_fresh", &[]).0;
    let (resumed_s, fresh_s) = (
        value_sigma(b, "positioning[x].c1").1,
        value_sigma(fresh.last().unwrap(), "positioning[x].c1").1,
    );
    assert!(
        resumed_s < 0.8 * fresh_s,
        "a resumed run keeps what the first half learnt: σ {resumed_s:e} vs {fresh_s:e} fresh"
    );
}

/// Messages of measurements [from, to) of a shift bag (each measurement writes 5 messages).
fn write_partial(whole: &Path, out: &Path, from: usize, to: usize) {
    let mut w = BagWriter::create(out, WriterOptions::default()).unwrap();
    let qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
    w.add_topic(
        "/machine/commanded_joint_states",
        JointState::ROS_TYPE,
        JointState::DEFINITION,
        &qos,
    )
    .unwrap();
    w.add_topic(
        "/measured_points",
        MeasuredPoint::ROS_TYPE,
        MeasuredPoint::DEFINITION,
        &qos,
    )
    .unwrap();
    w.add_topic(
        "/temperature/column",
        Temperature::ROS_TYPE,
        Temperature::DEFINITION,
        &qos,
    )
    .unwrap();
    let mut source = BagSource::open(whole).unwrap();
    source
        .subscribe::<JointState>("/machine/commanded_joint_states")
        .unwrap();
    source
        .subscribe::<MeasuredPoint>("/measured_points")
        .unwrap();
    source
        .subscribe::<Temperature>("/temperature/column")
        .unwrap();
    for (k, m) in source.messages().unwrap().enumerate() {
        let m = m.unwrap();
        if (from * 5..to * 5).contains(&k) {
            w.write(&m.topic, m.log_time_ns, m.publish_time_ns, &m.payload)
                .unwrap();
        }
    }
    w.finish().unwrap();
}

fn model_key(m: &ErrorModel) -> (i64, Vec<u64>, Vec<u64>) {
    (
        m.header.stamp.nanos(),
        m.values.iter().map(|v| v.to_bits()).collect(),
        m.covariance.iter().map(|v| v.to_bits()).collect(),
    )
}

#[test]
fn replay_from_bag_equals_live_run_over_dds() {
    metrocell_node::testing::require_isolated_network();
    let cli = PathBuf::from(env!("CARGO_BIN_EXE_metrocell-estimator")).with_file_name("metrocell");
    assert!(
        cli.exists(),
        "{} is not built: run `cargo build -p metrocell-cli` in the same target directory first",
        cli.display()
    );
    let run = Run::new("live");
    let input = run.dir.join("shift");
    // 90 measurements with a crash at 60: the sequence holds updates and an alarm
    write_shift(&input, 90, Some(60), 7);
    let (replay_models, replay_alarms, _) = run.replay(&input, "out", &[]);
    assert_eq!(replay_alarms.len(), 1, "one alarm in the replay");

    let mut listener = MetrocellNode::builder("estimator_test_listener")
        .handle_signals(false)
        .build()
        .unwrap();
    let models = listener
        .subscription::<ErrorModel>("/estimator/error_model", qos::stream(qos::reliable()))
        .unwrap();
    let diagnostics = listener
        .subscription::<DiagnosticArray>("/diagnostics", qos::stream(qos::reliable()))
        .unwrap();
    let _node = Killed(
        Command::new(env!("CARGO_BIN_EXE_metrocell-estimator"))
            .args(run.args(&[]))
            .stdout(Stdio::null())
            .spawn()
            .unwrap(),
    );
    std::thread::sleep(Duration::from_secs(3)); // discovery between the node, the listener and the player
    let mut play = Killed(
        Command::new(&cli)
            .args(["bag", "play"])
            .arg(&input)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .spawn()
            .unwrap(),
    );
    let (mut live_models, mut live_alarms) = (Vec::new(), Vec::new());
    let deadline = Instant::now() + Duration::from_secs(60);
    while Instant::now() < deadline && live_models.len() < replay_models.len() {
        while let Ok(Some((m, _))) = models.take() {
            live_models.push(m);
        }
        while let Ok(Some((d, _))) = diagnostics.take() {
            if d.status.iter().any(|s| {
                s.name == "/estimator" && s.values.iter().any(|kv| kv.key == "alarm_measurement")
            }) {
                live_alarms.push(d);
            }
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    let _ = play.0.wait();
    std::thread::sleep(Duration::from_millis(500));
    while let Ok(Some((d, _))) = diagnostics.take() {
        if d.status.iter().any(|s| {
            s.name == "/estimator" && s.values.iter().any(|kv| kv.key == "alarm_measurement")
        }) {
            live_alarms.push(d);
        }
    }
    assert_eq!(
        live_models.len(),
        replay_models.len(),
        "live run published {} models, replay {}",
        live_models.len(),
        replay_models.len()
    );
    for (k, (l, r)) in live_models.iter().zip(&replay_models).enumerate() {
        assert_eq!(
            model_key(l),
            model_key(r),
            "model {k}: live and replay differ"
        );
        assert_eq!(l, r, "model {k}: live and replay messages differ");
    }
    assert_eq!(live_alarms.len(), 1, "live alarms");
    assert_eq!(
        live_alarms[0].status, replay_alarms[0].status,
        "the alarm differs between live and replay"
    );
}
