//! Issue 10, end to end over DDS: twin → tracker node → thermal node → recorder, as separate
//! processes from one launch file, on an 8-hour simulated shift (`xfyz_shift.yaml`) compressed
//! through `/clock` to a few minutes.
//!
//! Asserted on the recorded bag:
//! * every dwell of the twin's program (every cycle of the shift) appears exactly once on
//!   `/measured_points`, with its program point + tool offset as nominal, and once on
//!   `/measured_points/thermal_compensated`;
//! * the column of the cell grows 4 µm/K along −Z, lagging its sensor by 20 min. The thermal
//!   node is configured with that g and τ (known, not fitted). The Z drift of each fixed point —
//!   its Z error minus its mean Z error over hours 0–4 — is checked on the held-out hours 4–8:
//!   uncorrected it exceeds 5 µm, corrected every dwell stays within ±5 µm (the thesis's
//!   column-growth result).
//!
//! Why drift relative to each point's own hours 0–4, not the raw Z error: the tracker node
//! registers its pose on the first cycle, which absorbs that cycle's state (the column's growth
//! at the start, and a small tilt from the X errors the rigid fit spreads over the points). Those
//! are constant per point for the whole shift; only the change over time is thermal drift.
//!
//! The cell is xfyz_shift with what this test does not examine switched off: tracker warm-up
//! (the tracker node's own correction, tested on its own), beam breaks and the turbulence window
//! (dwells they cut would be missing by design), the camera. Sensor and machine-state rates are
//! lowered so the compressed shift stays within what one test may put on the wire.
//!
//! Run: `cargo build --workspace --bins && tests/isolated cargo test -p metrocell-system-tests --test tracker_thermal_chain -- --nocapture`

use std::collections::BTreeMap;
use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use metrocell_bagtools::BagSource;
use metrocell_msgs::msg::MeasuredPoint;
use metrocell_twin::Cell;
use nalgebra::Vector3;
use system_tests::{bin, piped, require_isolated_network, workspace_root, ChildGuard};

const HOUR: f64 = 3600.0;
const SHIFT: f64 = 8.0 * HOUR;
/// Simulated seconds per wall-clock second.
const SPEED: f64 = 160.0;
/// Hours whose dwells give each point's reference Z error; the rest are held out.
const REFERENCE_HOURS: f64 = 4.0;
/// The column growth the twin applies (xfyz_shift.yaml's thermal_growth term) and the thermal
/// node is configured with.
const GROWTH: f64 = 4e-6;
const LAG: f64 = 1200.0;

fn scratch() -> PathBuf {
    let d = std::env::temp_dir().join(format!("metrocell-chain-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// xfyz_shift.yaml with the effects this test does not examine switched off (see the module doc).
fn cell_text() -> String {
    let path = workspace_root().join("launch-configs/cells/xfyz_shift.yaml");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut out = String::new();
    let mut in_turbulence = false;
    for line in text.lines() {
        let trimmed = line.trim_start();
        if in_turbulence && trimmed.starts_with("- {start:") {
            continue;
        }
        in_turbulence = trimmed.starts_with("turbulence:");
        if in_turbulence
            || ["beam_breaks:", "camera:", "mount:", "delay:"]
                .iter()
                .any(|k| trimmed.starts_with(k))
        {
            continue;
        }
        let line = line
            .replace("amplitude: 75 um", "amplitude: 0 um")
            .replace(
                "machine_state: {rate: 100 Hz}",
                "machine_state: {rate: 2 Hz}",
            )
            .replace("rate: 1 Hz,", "rate: 0.2 Hz,");
        out.push_str(&line);
        out.push('\n');
    }
    for (gone, what) in [
        ("turbulence:", "the turbulence window"),
        ("beam_breaks:", "beam breaks"),
        ("camera:", "the camera"),
        ("amplitude: 75 um", "the warm-up"),
        ("rate: 100 Hz", "100 Hz machine state"),
        ("rate: 1 Hz,", "1 Hz thermocouples"),
    ] {
        assert!(
            !out.contains(gone),
            "xfyz_shift.yaml changed: {what} is still in the test's cell; update this test"
        );
    }
    let growth = format!(
        "params: {{coefficient: {} um/K, time_constant: {} min}}",
        GROWTH * 1e6,
        LAG / 60.0
    );
    assert!(
        out.contains(&growth),
        "xfyz_shift.yaml's column growth is no longer {growth}; update GROWTH and LAG"
    );
    out
}

fn launch_file(
    dir: &Path,
    cell: &Path,
    bag: &Path,
    tool_offset_z: f64,
    registration_points: usize,
) -> PathBuf {
    let text = format!(
        r#"launch:
- node:
    pkg: metrocell
    exec: metrocell-sim
    name: sim
    param:
    - {{name: cell, value: "{cell}"}}
    - {{name: duration, value: "{SHIFT}s"}}
    - {{name: speed, value: {SPEED:.1}}}
    - {{name: seed, value: 5}}
    - {{name: start_delay, value: 2.0}}
    - {{name: wait_for_recorder, value: 60.0}}
    - {{name: camera_images, value: false}}
- node:
    pkg: metrocell
    exec: metrocell-tracker
    name: tracker
    param:
    - {{name: tool_offset, value: [0.0, 0.0, {tool_offset_z}]}}
    - {{name: registration_points, value: {registration_points}}}
    - {{name: commanded_gap, value: 1.0}}
- node:
    pkg: metrocell
    exec: metrocell-thermal
    name: thermal
    param:
    - {{name: growth_sensors, value: [column]}}
    - {{name: growth_directions, value: [0.0, 0.0, -1.0]}}
    - {{name: growth_coefficients, value: [{GROWTH:e}]}}
    - {{name: growth_time_constants, value: [{LAG:.1}]}}
- node:
    pkg: metrocell
    exec: metrocell-recorder
    name: recorder
    param:
    - {{name: output, value: "{bag}"}}
    - {{name: flush_interval, value: 0.5}}
"#,
        cell = cell.display(),
        bag = bag.display()
    );
    let p = dir.join("chain.launch.yaml");
    std::fs::write(&p, text).unwrap();
    p
}

/// A MeasuredPoint as the test uses it.
struct Point {
    id: String,
    /// header stamp, s of simulated time
    t: f64,
    nominal: Vector3<f64>,
    measured: Vector3<f64>,
}

fn points(bag: &Path, topic: &str) -> Vec<Point> {
    let mut source = BagSource::open(bag).unwrap_or_else(|e| panic!("{}: {e}", bag.display()));
    assert!(
        source.subscribe::<MeasuredPoint>(topic).unwrap(),
        "the bag has no {topic}"
    );
    source
        .messages()
        .unwrap()
        .map(|m| {
            let p: MeasuredPoint = m.unwrap().decode().unwrap();
            Point {
                id: p.point_id,
                t: p.header.stamp.sec as f64 + p.header.stamp.nanosec as f64 * 1e-9,
                nominal: Vector3::new(p.nominal.x, p.nominal.y, p.nominal.z),
                measured: Vector3::new(p.measured.x, p.measured.y, p.measured.z),
            }
        })
        .collect()
}

/// Runs the launch until the twin has played the shift, then stops it (SIGINT: the recorder
/// finishes the bag). Returns the launch's output.
fn run_launch(launch: &Path) -> String {
    let mut cmd = piped(bin("metrocell"));
    cmd.arg("launch")
        .arg(launch)
        .env("ROS_DOMAIN_ID", "31")
        .stdin(Stdio::null());
    let mut launcher = ChildGuard::spawn(&mut cmd);
    // output drained by threads, so a full pipe cannot stall the nodes
    let (tx, rx) = mpsc::channel::<String>();
    let pipes: [Box<dyn std::io::Read + Send>; 2] = [
        Box::new(launcher.child().stdout.take().unwrap()),
        Box::new(launcher.child().stderr.take().unwrap()),
    ];
    let readers: Vec<_> = pipes
        .into_iter()
        .map(|pipe| {
            let tx = tx.clone();
            std::thread::spawn(move || {
                for line in BufReader::new(pipe).lines().map_while(Result::ok) {
                    let _ = tx.send(line);
                }
            })
        })
        .collect();
    drop(tx);
    let mut log = String::new();
    let budget = Duration::from_secs_f64(SHIFT / SPEED + 240.0);
    let deadline = Instant::now() + budget;
    loop {
        match rx.recv_timeout(deadline.saturating_duration_since(Instant::now())) {
            Ok(line) => {
                let done = line.contains("[sim]") && line.contains("exited with code");
                log.push_str(&line);
                log.push('\n');
                if done {
                    break;
                }
            }
            Err(_) => panic!("the twin did not finish the shift within {budget:?}:\n{log}"),
        }
    }
    // the tracker closes the last dwell, the thermal node compensates it, the recorder takes it
    std::thread::sleep(Duration::from_secs(3));
    system_tests::interrupt(launcher.pid());
    let status = launcher.child().wait().unwrap();
    for r in readers {
        let _ = r.join();
    }
    log.extend(rx.try_iter().map(|l| l + "\n"));
    assert!(status.success(), "launch exit {status}:\n{log}");
    log
}

/// Per point id: (hours, Z error m) of each dwell; Z error = measured − nominal.
fn z_errors(points: &[Point], t0: f64) -> BTreeMap<String, Vec<(f64, f64)>> {
    let mut out: BTreeMap<String, Vec<(f64, f64)>> = BTreeMap::new();
    for p in points {
        out.entry(p.id.clone())
            .or_default()
            .push(((p.t - t0) / HOUR, p.measured.z - p.nominal.z));
    }
    out
}

/// Held-out drift of every dwell after REFERENCE_HOURS: its Z error minus the mean Z error of
/// the same point before REFERENCE_HOURS.
fn held_out_drift(errors: &BTreeMap<String, Vec<(f64, f64)>>) -> Vec<(String, f64, f64)> {
    let mut out = Vec::new();
    for (id, dwells) in errors {
        let reference: Vec<f64> = dwells
            .iter()
            .filter(|d| d.0 < REFERENCE_HOURS)
            .map(|d| d.1)
            .collect();
        assert!(
            reference.len() >= 6,
            "{id}: {} dwells in hours 0–{REFERENCE_HOURS}",
            reference.len()
        );
        let mean = reference.iter().sum::<f64>() / reference.len() as f64;
        out.extend(
            dwells
                .iter()
                .filter(|d| d.0 >= REFERENCE_HOURS)
                .map(|&(h, z)| (id.clone(), h, z - mean)),
        );
    }
    out
}

#[test]
fn twin_tracker_thermal_recorder_over_dds_on_an_eight_hour_shift() {
    require_isolated_network();
    let dir = scratch();
    let text = cell_text();
    let cell_path = dir.join("chain_cell.yaml");
    std::fs::write(&cell_path, &text).unwrap();
    // What the twin will do: every dwell of every cycle that ends within the shift.
    let cell = Cell::from_yaml_str(&text, &cell_path.display().to_string()).unwrap();
    let program = &cell.program;
    let cycles = (0..)
        .take_while(|&c| {
            program
                .cycle_start(c)
                .is_some_and(|s| s + program.cycle_length() <= SHIFT)
        })
        .count();
    let dwells_per_cycle = program
        .segments
        .iter()
        .filter(|s| s.dwell_point.is_some())
        .count();
    assert_eq!(
        dwells_per_cycle,
        program.points.len(),
        "one dwell per program point"
    );
    let nominal = |i: usize| {
        cell.machine.nominal_tool_point(&Vector3::new(
            program.points[i][0],
            program.points[i][1],
            program.points[i][2],
        ))
    };
    let tool_offset_z = cell.machine.tool_offset.z;

    let bag = dir.join("bag");
    let launch = launch_file(&dir, &cell_path, &bag, tool_offset_z, dwells_per_cycle);
    let started = Instant::now();
    let log = run_launch(&launch);
    eprintln!(
        "launch ran {:.0} s for {} h simulated ({cycles} cycles of {dwells_per_cycle} dwells)",
        started.elapsed().as_secs_f64(),
        SHIFT / HOUR
    );
    assert!(
        log.contains("'recorder' subscribes to every topic: starting"),
        "the twin started before the recorder read every topic:\n{log}"
    );

    // every dwell exactly once, with its program point as nominal, on both topics
    let measured = points(&bag, "/measured_points");
    let compensated = points(&bag, "/measured_points/thermal_compensated");
    let mut per_point: BTreeMap<usize, usize> = BTreeMap::new();
    for p in &measured {
        let i: usize =
            p.id.strip_prefix("point_")
                .and_then(|s| s.parse().ok())
                .unwrap_or_else(|| panic!("point id {:?}", p.id));
        assert!(i < program.points.len(), "{}: not a program point", p.id);
        assert!(
            (p.nominal - nominal(i)).norm() < 1e-12,
            "{}: nominal {:?}, program point + tool offset {:?}",
            p.id,
            p.nominal,
            nominal(i)
        );
        *per_point.entry(i).or_default() += 1;
    }
    let wrong: Vec<_> = (0..program.points.len())
        .filter(|i| per_point.get(i).copied().unwrap_or(0) != cycles)
        .map(|i| (i, per_point.get(&i).copied().unwrap_or(0)))
        .collect();
    assert!(
        wrong.is_empty(),
        "points not seen exactly once per cycle ({cycles}): {wrong:?} (point, times)\n{log}"
    );
    assert_eq!(measured.len(), cycles * dwells_per_cycle);
    let mut stamps: Vec<(i64, &str)> = measured
        .iter()
        .map(|p| ((p.t * 1e9).round() as i64, p.id.as_str()))
        .collect();
    stamps.sort();
    stamps.dedup();
    assert_eq!(stamps.len(), measured.len(), "a dwell published twice");
    let key = |p: &Point| ((p.t * 1e9).round() as i64, p.id.clone());
    let mut compensated_keys: Vec<_> = compensated.iter().map(key).collect();
    let mut measured_keys: Vec<_> = measured.iter().map(key).collect();
    compensated_keys.sort();
    measured_keys.sort();
    assert_eq!(
        compensated_keys, measured_keys,
        "the thermal node compensates every point once"
    );

    // the column growth: uncorrected drift visible, corrected drift within ±5 µm on hours 4–8
    let t0 = measured.iter().map(|p| p.t).fold(f64::INFINITY, f64::min);
    let raw = held_out_drift(&z_errors(&measured, t0));
    let fixed = held_out_drift(&z_errors(&compensated, t0));
    assert_eq!(raw.len(), fixed.len());
    assert!(
        fixed.len() >= (cycles / 2 - 1) * dwells_per_cycle,
        "{} held-out dwells",
        fixed.len()
    );
    let worst = |v: &[(String, f64, f64)]| v.iter().map(|d| d.2.abs()).fold(0.0, f64::max);
    let rms = |v: &[(String, f64, f64)]| {
        (v.iter().map(|d| d.2 * d.2).sum::<f64>() / v.len() as f64).sqrt()
    };
    // per cycle, for the record: mean drift uncorrected and corrected
    let mut by_cycle: BTreeMap<i64, (f64, f64, usize)> = BTreeMap::new();
    for (r, f) in raw.iter().zip(&fixed) {
        let e = by_cycle.entry((r.1 * 2.0).floor() as i64).or_default();
        (e.0, e.1, e.2) = (e.0 + r.2, e.1 + f.2, e.2 + 1);
    }
    for (half_hour, (r, f, n)) in by_cycle {
        eprintln!(
            "  {:.1} h: mean Z drift uncorrected {:+.2} µm, corrected {:+.2} µm ({n} dwells)",
            half_hour as f64 / 2.0,
            r / n as f64 * 1e6,
            f / n as f64 * 1e6
        );
    }
    eprintln!(
        "held-out hours {REFERENCE_HOURS}–8, {} dwells: Z drift uncorrected worst {:.2} µm (rms {:.2}), corrected worst {:.2} µm (rms {:.2})",
        fixed.len(),
        worst(&raw) * 1e6,
        rms(&raw) * 1e6,
        worst(&fixed) * 1e6,
        rms(&fixed) * 1e6
    );
    assert!(worst(&raw) > 5e-6, "the column growth must show uncorrected on the held-out hours (else this test proves nothing): worst {:.2} µm", worst(&raw) * 1e6);
    let (id, h, z) = fixed
        .iter()
        .max_by(|a, b| a.2.abs().total_cmp(&b.2.abs()))
        .unwrap();
    assert!(
        z.abs() <= 5e-6,
        "held-out: {id} at {h:.2} h drifts {:.2} µm after thermal correction",
        z * 1e6
    );
    let _ = std::fs::remove_dir_all(&dir);
}
