//! Benchmark: measurement records from an 8-hour shift bag against a loop that only decodes
//! the same messages (the floor any reader of the bag pays), measured in the same run.
//!
//!   cargo run --release -p metrocell-records --example records_bench -- \
//!       [--cell crates/twin/examples/cells/xfyz_shift.yaml] [--duration 28800] [--bag DIR] [--runs 3]
//!
//! Without an existing `--bag` it first simulates the cell (no camera frames) into one, as
//! `metrocell sim --no-camera-frames` does. Prints both times (best of `--runs`, alternating),
//! their ratio, the records made and rejected, and the peak RSS of the process.

use std::path::PathBuf;
use std::time::Instant;

use metrocell_bagtools::BagSource;
use metrocell_msgs::geometry_msgs::msg::WrenchStamped;
use metrocell_msgs::msg::TrackerMeasurement;
use metrocell_msgs::sensor_msgs::msg::{
    FluidPressure, JointState, RelativeHumidity, Temperature, TimeReference,
};
use metrocell_records::recordings::{records_from_bags, RecordingOptions, TRACKER_TOPIC};
use metrocell_records::signal_topics::SignalTopic;
use metrocell_simulation::{write_bag, BagOptions};
use metrocell_twin::Cell;

fn arg(name: &str) -> Option<String> {
    let args: Vec<String> = std::env::args().collect();
    args.iter()
        .position(|a| a == name)
        .and_then(|i| args.get(i + 1).cloned())
}

fn peak_rss_mib() -> f64 {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse::<f64>().ok())
        .map_or(f64::NAN, |kb| kb / 1024.0)
}

/// Decode every message of the topics records are built from; returns how many were decoded.
fn decode_only(bag: &PathBuf) -> u64 {
    let mut source = BagSource::open(bag).expect("open the bag");
    let topics: Vec<(String, String)> = source
        .topics()
        .iter()
        .map(|t| (t.name.clone(), t.type_name.clone()))
        .collect();
    let mut kinds = std::collections::BTreeMap::new();
    for (name, ty) in &topics {
        if name == TRACKER_TOPIC || SignalTopic::of(name, ty).is_some() {
            source.subscribe_any(name);
            kinds.insert(name.clone(), ty.clone());
        }
    }
    let mut n = 0u64;
    let mut checksum = 0.0;
    for m in source.messages().expect("read") {
        let m = m.expect("message");
        checksum += match kinds[&m.topic].as_str() {
            "metrocell_msgs/msg/TrackerMeasurement" => {
                m.decode::<TrackerMeasurement>().unwrap().range
            }
            "sensor_msgs/msg/JointState" => m.decode::<JointState>().unwrap().position.len() as f64,
            "sensor_msgs/msg/Temperature" => m.decode::<Temperature>().unwrap().temperature,
            "sensor_msgs/msg/FluidPressure" => m.decode::<FluidPressure>().unwrap().fluid_pressure,
            "sensor_msgs/msg/RelativeHumidity" => {
                m.decode::<RelativeHumidity>().unwrap().relative_humidity
            }
            "sensor_msgs/msg/TimeReference" => {
                m.decode::<TimeReference>().unwrap().time_ref.sec as f64
            }
            "geometry_msgs/msg/WrenchStamped" => {
                m.decode::<WrenchStamped>().unwrap().wrench.force.z
            }
            other => panic!("unexpected type {other}"),
        };
        n += 1;
    }
    std::hint::black_box(checksum);
    n
}

fn main() {
    let cell_path = arg("--cell").unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../twin/examples/cells/xfyz_shift.yaml"
        )
        .into()
    });
    let duration: f64 =
        arg("--duration").map_or(8.0 * 3600.0, |d| d.parse().expect("--duration in seconds"));
    let runs: usize = arg("--runs").map_or(3, |r| r.parse().expect("--runs"));
    let bag = PathBuf::from(arg("--bag").unwrap_or_else(|| {
        std::env::temp_dir()
            .join("metrocell_records_bench_bag")
            .display()
            .to_string()
    }));
    if !bag.join("metadata.yaml").exists() {
        let _ = std::fs::remove_dir_all(&bag);
        let t = Instant::now();
        let cell = Cell::from_path(&cell_path).expect("cell");
        let summary = write_bag(
            cell,
            duration,
            1,
            &bag,
            &BagOptions {
                frames: None,
                ..BagOptions::default()
            },
            |_| {},
        )
        .expect("simulate");
        println!(
            "simulated {} s of {cell_path} into {} ({} messages) in {:.1} s",
            duration,
            bag.display(),
            summary.total_messages,
            t.elapsed().as_secs_f64()
        );
    }
    let cell = Cell::from_path(&cell_path).expect("cell");
    let instruments = cell.tracker_terms().expect("tracker terms");
    let model = cell.forward_model(&instruments).expect("model");
    let options = RecordingOptions::default();
    let (mut best_decode, mut best_records) = (f64::INFINITY, f64::INFINITY);
    let (mut decoded, mut made, mut rejected) = (0, 0, 0);
    for run in 0..runs {
        let t = Instant::now();
        decoded = decode_only(&bag);
        let d = t.elapsed().as_secs_f64();
        let t = Instant::now();
        let set = records_from_bags(&[&bag], &model, &options).expect("records");
        let r = t.elapsed().as_secs_f64();
        (made, rejected) = (set.records.len(), set.rejected.len());
        drop(set);
        println!(
            "run {run}: decode only {d:.2} s, records {r:.2} s ({:.2}×)",
            r / d
        );
        best_decode = best_decode.min(d);
        best_records = best_records.min(r);
    }
    println!(
        "best of {runs}: decode only {best_decode:.2} s ({decoded} messages, {:.0} k/s), records {best_records:.2} s ({made} records, {rejected} rejected): ratio {:.2}×; peak RSS {:.0} MiB",
        decoded as f64 / best_decode / 1e3,
        best_records / best_decode,
        peak_rss_mib()
    );
}
