//! Online update rate of the estimator node's logic at about 70 parameters, against a bare loop
//! that only decodes the same messages (the floor any node pays), measured in the same run on
//! one core.
//!
//! Model: the 21 geometric errors of an XFYZ machine (3 positioning and 6 straightness errors of
//! order 3, 9 angular errors of order 2 with an Abbe lever, 3 squareness), backlash on X, Y, Z
//! and a cyclic screw error on X: 66 + 3 + 2 = 71 free parameters (the machine-frame tracker
//! pose is fixed). Input: 20 000 measured points, each bracketed by two commanded joint states
//! (60 000 CDR messages), decoded exactly as the `--bag` replay decodes them.
//!
//! `cargo bench -p metrocell-estimator-node --bench update_rate`

use std::time::Instant;

use metrocell_bagtools::{encode_cdr, SourcedMessage};
use metrocell_estimator_node::parameters;
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::Point;
use metrocell_msgs::msg::MeasuredPoint;
use metrocell_msgs::sensor_msgs::msg::JointState;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::MetrocellNode;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

const POINTS: usize = 20_000;

fn model_yaml() -> String {
    let mut terms = String::new();
    let travel = "travel: [0 m, 1 m]";
    for a in ["x", "y", "z"] {
        terms += &format!("  - {{id: positioning, options: {{axis: {a}, order: 3, {travel}}}, params: {{c0: 0 um, c1: 0 um, c2: 0 um, c3: 0 um}}}}\n");
        for d in ["x", "y", "z"].iter().filter(|d| **d != a) {
            terms += &format!("  - {{id: straightness, options: {{axis: {a}, direction: {d}, order: 3, {travel}}}, params: {{c0: 0 um, c1: 0 um, c2: 0 um, c3: 0 um}}}}\n");
        }
        for about in ["x", "y", "z"] {
            terms += &format!("  - {{id: angular, options: {{axis: {a}, about: {about}, lever_axes: [z], abbe_offset: [0 m, 0 m, -0.15 m], order: 2, {travel}}}, params: {{c0: 0 urad, c1: 0 urad, c2: 0 urad}}}}\n");
        }
        terms +=
            &format!("  - {{id: backlash, options: {{axis: {a}}}, params: {{reversal: 0 um}}}}\n");
    }
    for pair in ["xy", "xz", "yz"] {
        terms +=
            &format!("  - {{id: squareness, options: {{pair: {pair}}}, params: {{s: 0 urad}}}}\n");
    }
    terms +=
        "  - {id: pitch_cyclic, options: {axis: x, lead: 10 mm}, params: {a1: 0 um, b1: 0 um}}\n";
    format!(
        "name: bench_model
machine:
  family: cartesian
  stacking: XFYZ
  travel: {{x: [0 m, 1 m], y: [0 m, 1 m], z: [0 m, 1 m]}}
sensors: {{}}
environment:
  ambient: {{mean: 20 degC}}
  air: {{pressure: 101.3 kPa, humidity: 45}}
program:
  grid:
    x: {{from: 0 m, to: 1 m, count: 2}}
    y: {{from: 0 m, to: 1 m, count: 2}}
    z: {{from: 0 m, to: 0 m, count: 1}}
  feed_rate: 100 mm/s
  dwell: 1 s
terms:
{terms}"
    )
}

fn message(topic: &str, ns: i64, payload: Vec<u8>) -> SourcedMessage {
    SourcedMessage {
        topic: topic.into(),
        log_time_ns: ns as u64,
        publish_time_ns: ns as u64,
        payload,
    }
}

fn inputs() -> Vec<SourcedMessage> {
    let mut rng = ChaCha8Rng::seed_from_u64(1);
    let t0: i64 = 1_767_225_600_000_000_000;
    let mut out = Vec::with_capacity(3 * POINTS);
    for i in 0..POINTS as i64 {
        let ns = t0 + i * 100_000_000;
        let q: Vec<f64> = (0..3).map(|_| rng.random::<f64>()).collect();
        let header = |ns: i64| Header {
            stamp: Time::from_nanos(ns),
            frame_id: "machine".into(),
        };
        for dt in [-20_000_000, 20_000_000] {
            let js = JointState {
                header: header(ns + dt),
                name: vec!["x".into(), "y".into(), "z".into()],
                position: q.clone(),
                velocity: vec![0.0; 3],
                effort: vec![],
            };
            out.push(message(
                "/machine/commanded_joint_states",
                ns + dt,
                encode_cdr(&js).unwrap(),
            ));
        }
        let s = 3e-6;
        let p = MeasuredPoint {
            header: header(ns),
            point_id: format!("p{i}"),
            source: "tracker".into(),
            nominal: Point {
                x: q[0],
                y: q[1],
                z: q[2],
            },
            measured: Point {
                x: q[0] + rng.random::<f64>() * 1e-5,
                y: q[1] + rng.random::<f64>() * 1e-5,
                z: q[2] + rng.random::<f64>() * 1e-5,
            },
            covariance: [s * s, 0.0, 0.0, 0.0, s * s, 0.0, 0.0, 0.0, s * s],
        };
        out.push(message(
            "/measured_points",
            ns + 30_000_000,
            encode_cdr(&p).unwrap(),
        ));
    }
    out.sort_by_key(|m| m.log_time_ns);
    out
}

fn main() {
    let dir = std::env::temp_dir().join(format!("estimator-bench-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let model = dir.join("model.yaml");
    std::fs::write(&model, model_yaml()).unwrap();
    let node = MetrocellNode::builder("estimator_bench")
        .params(parameters::declarations())
        .handle_signals(false)
        .args(
            [
                "bench",
                "--ros-args",
                "-p",
                &format!("model:={}", model.display()),
                "-p",
                "publish_every:=1000",
            ]
            .map(String::from),
        )
        .unwrap()
        .0
        .build_offline()
        .unwrap();
    let model = parameters::model(node.parameters(), "/measured_points").unwrap();
    let forward = model.forward_model().unwrap();
    let topics = metrocell_records::declared_topics(&forward, &model.recording);
    let (mut state, log) =
        parameters::estimator(node.parameters(), &model, &forward, &topics).unwrap();
    let free = state.filter().free_indices().len();
    println!("{}", log[0]);
    let messages = inputs();

    // the floor: decode every message, nothing else
    let start = Instant::now();
    let mut checksum = 0.0;
    for m in &messages {
        if m.topic == "/measured_points" {
            checksum += m.decode::<MeasuredPoint>().unwrap().measured.x;
        } else {
            checksum += m.decode::<JointState>().unwrap().position[0];
        }
    }
    let decode_s = start.elapsed().as_secs_f64();

    // the node's work: decode, build the records (signals interpolated), update the filter, publish every 1000
    let start = Instant::now();
    let mut models = 0;
    for m in &messages {
        state.message(m).unwrap();
        models += state.process().iter().filter(|o| o.model.is_some()).count();
    }
    let update_s = start.elapsed().as_secs_f64();
    let c = &state.counters;
    // every point is taken or said why not (the first: no motion yet gives no approach direction for the backlash terms)
    let not_used: u64 = c.points_not_used.values().sum();
    assert_eq!(
        c.accepted + c.outliers + not_used,
        POINTS as u64 - state.pending() as u64,
        "every point taken: {}",
        c.summary()
    );
    assert!(not_used <= 1, "{}", c.summary());
    println!("{free} free parameters, {POINTS} measured points ({} messages), {models} models built (checksum {checksum:.3})", messages.len());
    println!(
        "decode only:      {:>9.0} points/s ({decode_s:.3} s)",
        POINTS as f64 / decode_s
    );
    println!(
        "estimator update: {:>9.0} points/s ({update_s:.3} s)",
        POINTS as f64 / update_s
    );
    println!(
        "ratio update/decode time: {:.1}× (target: ≥ 10 000 points/s)",
        update_s / decode_s
    );
    let _ = std::fs::remove_dir_all(&dir);
}
