//! The tracker node on twin data, offline (`--bag`, no DDS):
//! * warm-up: a tracker switched on 20 min before the run (B = 75 µm, τ = 90 min); the node says
//!   "warming up" until the true 95 % settling time (within 10 %) and its fitted A, B, τ lie
//!   within their expanded (k = 2) uncertainty of the truth;
//! * turbulence: `xfyz_shift.yaml`'s heater window (3 h – 3.25 h): every dwell in it is flagged,
//!   under 1 % of the undisturbed dwells are; every dwell gives one measured point with its
//!   program nominal, where the twin's truth puts it: the dwell's noise-free reading (the true
//!   point in the tracker frame, the warm-up and refraction range errors along the beam) placed
//!   by the pose that registering the noise-free readings of the node's registration dwells
//!   gives — at most 1 % of the coordinates beyond 3σ of the point's reported covariance, none
//!   beyond 5σ.
//!
//! Run: `cargo test -p metrocell-tracker-node --test twin_replay`

use std::path::{Path, PathBuf};
use std::process::Command;

use metrocell_bagtools::BagSource;
use metrocell_laser_tracker::registration::{register, Correspondence};
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint, TrackerMeasurement};
use metrocell_simulation::bag::{write_bag, BagOptions};
use metrocell_twin::{Cell, Sample, SampleTruth, Simulation, TrackerStatus};
use nalgebra::{Matrix3, Vector3};

/// The seed `simulate_and_replay` runs the twin with, and the node's default dwell splitting.
const SEED: u64 = 7;
const DWELL_GAP: f64 = 0.5;
const MIN_DWELL_READINGS: usize = 5;

fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("metrocell-tracker-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn cell(path: &str) -> Cell {
    let text = std::fs::read_to_string(path).unwrap();
    Cell::from_yaml_str(&text, path).unwrap()
}

/// Simulate `cell` for `duration` s into `dir/input`, replay the node on it into `dir/output`.
fn simulate_and_replay(cell: Cell, duration: f64, dir: &Path, params: &[&str]) -> (u64, PathBuf) {
    let options = BagOptions {
        frames: None,
        clock_rate: None,
        ..BagOptions::default()
    };
    let start_ns = options.start_ns;
    let input = dir.join("input");
    write_bag(cell, duration, SEED, &input, &options, |_| {}).unwrap();
    let output = dir.join("output");
    let mut args = vec!["--ros-args"];
    for p in params {
        args.extend(["-p", p]);
    }
    let run = Command::new(env!("CARGO_BIN_EXE_metrocell-tracker"))
        .arg("--bag")
        .arg(&input)
        .arg("--output")
        .arg(&output)
        .args(&args)
        .output()
        .unwrap();
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    eprintln!(
        "{}",
        String::from_utf8_lossy(&run.stderr)
            .lines()
            .last()
            .unwrap_or_default()
    );
    (start_ns, output)
}

/// A dwell as the twin made it: its target, time span (s), readings, the mean of its noise-free
/// readings (tracker frame: the true point, the warm-up and refraction range errors along the
/// beam) and the stated covariance of that mean.
struct TrueDwell {
    target: u32,
    first: f64,
    last: f64,
    n: usize,
    free: Vector3<f64>,
    covariance: Matrix3<f64>,
}

impl TrueDwell {
    /// The middle of the dwell (s), where the node stamps its point.
    fn mid(&self) -> f64 {
        0.5 * (self.first + self.last)
    }
}

/// The twin's dwells of at least MIN_DWELL_READINGS unbroken readings, split as the node splits
/// them (another target, a reading without one, or a silence over DWELL_GAP ends a dwell).
fn true_dwells(cell: Cell, duration: f64) -> Vec<TrueDwell> {
    let sim = Simulation::new(cell, duration, SEED).unwrap();
    let mut dwells: Vec<TrueDwell> = Vec::new();
    let mut open = false;
    for (sample, truth) in sim.samples_with_truth() {
        let (Sample::Tracker(s), SampleTruth::Tracker(tr)) = (sample, truth) else {
            continue;
        };
        if s.status == TrackerStatus::BeamBroken {
            continue;
        }
        let Some(target) = s.target_id else {
            open = false;
            continue;
        };
        let continues = open
            && dwells
                .last()
                .is_some_and(|d| d.target == target && s.t - d.last <= DWELL_GAP);
        if !continues {
            dwells.push(TrueDwell {
                target,
                first: s.t,
                last: s.t,
                n: 0,
                free: Vector3::zeros(),
                covariance: Matrix3::zeros(),
            });
        }
        open = true;
        let d = dwells.last_mut().unwrap();
        let beam = tr.point / tr.point.norm();
        d.free += tr.point + beam * (tr.warmup_range_error + tr.refraction_range_error);
        d.covariance += s.covariance;
        d.n += 1;
        d.last = s.t;
    }
    dwells.retain(|d| d.n >= MIN_DWELL_READINGS);
    for d in &mut dwells {
        let n = d.n as f64;
        d.free /= n;
        d.covariance /= n * n;
    }
    dwells
}

fn read<T: metrocell_msgs::RosMessage>(bag: &Path, topic: &str) -> Vec<T> {
    let mut s = BagSource::open(bag).unwrap();
    assert!(s.subscribe::<T>(topic).unwrap(), "output has no {topic}");
    s.messages()
        .unwrap()
        .map(|m| m.unwrap().decode::<T>().unwrap())
        .collect()
}

#[test]
fn warmup_is_tracked_until_the_true_settling_time() {
    let dir = scratch("warmup");
    let c = cell(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/tests/cells/tracker_warmup.yaml"
    ));
    // truth: the nest's range (point_0 + tool offset, seen from the tracker)
    let tracker = c.tracker.as_ref().unwrap();
    let nest = c.machine.nominal_tool_point(&Vector3::new(
        c.program.points[0][0],
        c.program.points[0][1],
        c.program.points[0][2],
    ));
    let true_a = tracker.pose.to_instrument(&nest).norm();
    let (true_b, true_tau, on_before) = (75e-6, 5400.0, 1200.0);
    let (start_ns, out) = simulate_and_replay(
        c,
        5.0 * 3600.0,
        &dir,
        &[
            "warmup_target:=point_0",
            "warmup_elapsed_at_first_reading:=1200.0",
            "tool_offset:=[0.0, 0.0, -0.1]",
            "registration_points:=4",
        ],
    );
    let dwells: Vec<TrackerMeasurement> = read(&out, "/tracker/dwells");
    assert!(dwells.len() > 350, "{} dwells", dwells.len());
    let t_on = |d: &TrackerMeasurement| {
        (d.header.stamp.nanos() - start_ns as i64) as f64 * 1e-9 + on_before
    };
    let warming = |d: &TrackerMeasurement| d.status & TrackerMeasurement::STATUS_WARMING_UP != 0;
    let first_stable = dwells
        .iter()
        .position(|d| !warming(d))
        .expect("never stable");
    let settled = t_on(&dwells[first_stable]);
    let truth = true_tau * 20f64.ln();
    println!(
        "stable from {:.1} min after power-on; true settling {:.1} min",
        settled / 60.0,
        truth / 60.0
    );
    assert!(
        (settled / truth - 1.0).abs() < 0.10,
        "stable at {settled} s vs true settling {truth} s"
    );
    let later_warming = dwells[first_stable..].iter().filter(|d| warming(d)).count();
    assert!(
        later_warming * 100 <= dwells.len() - first_stable,
        "{later_warming} dwells flip back to warming up"
    );

    let fit = read::<ErrorModel>(&out, "/tracker/warmup")
        .pop()
        .expect("no warm-up fit");
    let sigma: Vec<f64> = (0..3).map(|i| fit.covariance[4 * i].sqrt()).collect();
    for (k, (name, truth)) in [("A", true_a), ("B", true_b), ("tau", true_tau)]
        .into_iter()
        .enumerate()
    {
        println!("{name}: {} ± {} (truth {truth})", fit.values[k], sigma[k]);
        assert!(
            (fit.values[k] - truth).abs() < 2.0 * sigma[k],
            "{name} = {} ± {} vs truth {truth}",
            fit.values[k],
            sigma[k]
        );
    }
    assert!(
        sigma[2] < 0.05 * true_tau,
        "τ determined to better than 5 %"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn turbulence_window_is_flagged_and_every_dwell_is_measured_once() {
    let dir = scratch("turbulence");
    let c = cell(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../crates/twin/examples/cells/xfyz_shift.yaml"
    ));
    let points: Vec<Vector3<f64>> = c
        .program
        .points
        .iter()
        .map(|p| {
            c.machine
                .nominal_tool_point(&Vector3::new(p[0], p[1], p[2]))
        })
        .collect();
    let duration = 3.5 * 3600.0;
    let truth = true_dwells(
        cell(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/../../crates/twin/examples/cells/xfyz_shift.yaml"
        )),
        duration,
    );
    let (start_ns, out) = simulate_and_replay(
        c,
        duration,
        &dir,
        &["tool_offset:=[0.0, 0.0, -0.15]", "registration_points:=12"],
    );
    let dwells: Vec<TrackerMeasurement> = read(&out, "/tracker/dwells");
    let t = |d: &TrackerMeasurement| (d.header.stamp.nanos() - start_ns as i64) as f64 * 1e-9;
    let flagged = |d: &TrackerMeasurement| d.status & TrackerMeasurement::STATUS_TURBULENCE != 0;
    // a dwell lasts 3 s: those within 5 s of an edge of the window are neither in nor out
    let inside: Vec<&TrackerMeasurement> = dwells
        .iter()
        .filter(|d| t(d) > 3.0 * 3600.0 + 5.0 && t(d) < 3.25 * 3600.0 - 5.0)
        .collect();
    let outside: Vec<&TrackerMeasurement> = dwells
        .iter()
        .filter(|d| t(d) < 3.0 * 3600.0 - 5.0 || t(d) > 3.25 * 3600.0 + 5.0)
        .collect();
    let (fi, fo) = (
        inside.iter().filter(|d| flagged(d)).count(),
        outside.iter().filter(|d| flagged(d)).count(),
    );
    println!(
        "turbulence: {fi}/{} dwells flagged in the window, {fo}/{} outside",
        inside.len(),
        outside.len()
    );
    assert!(
        inside.len() >= 20,
        "only {} dwells in the window",
        inside.len()
    );
    assert_eq!(fi, inside.len(), "every disturbed dwell is flagged");
    assert!(
        (fo as f64) < 0.01 * outside.len() as f64,
        "{fo} of {} undisturbed dwells flagged",
        outside.len()
    );

    // every dwell → one measured point with its program nominal
    let measured: Vec<MeasuredPoint> = read(&out, "/measured_points");
    assert_eq!(measured.len(), dwells.len());
    let mut stamps: Vec<i64> = measured.iter().map(|m| m.header.stamp.nanos()).collect();
    stamps.sort();
    stamps.dedup();
    assert_eq!(stamps.len(), measured.len(), "a dwell published twice");
    // each measured point's dwell in the twin: its target's dwell of the nearest mid time
    let dwell_of = |m: &MeasuredPoint, i: usize| -> (Vector3<f64>, Matrix3<f64>) {
        let t = (m.header.stamp.nanos() - start_ns as i64) as f64 * 1e-9;
        let d = truth
            .iter()
            .filter(|d| d.target as usize == i)
            .min_by(|a, b| (a.mid() - t).abs().total_cmp(&(b.mid() - t).abs()))
            .unwrap();
        assert!(
            (d.mid() - t).abs() < 0.2,
            "{} at {t} s: no dwell of the twin there",
            m.point_id
        );
        (d.free, d.covariance)
    };
    // the pose the node's registration dwells (the first dwell of each of the 12 targets) give
    // without noise
    let mut registration: Vec<Correspondence> = Vec::new();
    for m in &measured {
        let i: usize = m.point_id.strip_prefix("point_").unwrap().parse().unwrap();
        if registration.len() < 12 && !registration.iter().any(|c| c.machine == points[i]) {
            let (free, covariance) = dwell_of(m, i);
            registration.push(Correspondence {
                tracker: free,
                tracker_covariance: covariance,
                machine: points[i],
                machine_covariance: Matrix3::zeros(),
            });
        }
    }
    let pose = register(&registration).unwrap();
    let (mut coordinates, mut beyond3, mut worst) = (0usize, 0usize, (0.0f64, String::new()));
    let mut largest_error = 0.0f64;
    for m in &measured {
        let i: usize = m.point_id.strip_prefix("point_").unwrap().parse().unwrap();
        let n = Vector3::new(m.nominal.x, m.nominal.y, m.nominal.z);
        assert!(
            (n - points[i]).norm() < 1e-9,
            "{}: nominal {n:?} vs program {:?}",
            m.point_id,
            points[i]
        );
        let got = Vector3::new(m.measured.x, m.measured.y, m.measured.z);
        largest_error = largest_error.max((got - n).norm());
        let want = pose.rotation * dwell_of(m, i).0 + pose.translation;
        for a in 0..3 {
            let z = (got[a] - want[a]) / m.covariance[4 * a].sqrt();
            coordinates += 1;
            beyond3 += (z.abs() > 3.0) as usize;
            if z.abs() > worst.0 {
                worst = (
                    z.abs(),
                    format!(
                        "{} at {} ns axis {a}: {} m vs truth {} m, σ {:e} m",
                        m.point_id,
                        m.header.stamp.nanos(),
                        got[a],
                        want[a],
                        m.covariance[4 * a].sqrt()
                    ),
                );
            }
        }
    }
    println!(
        "measured points: {beyond3} of {coordinates} coordinates beyond 3σ of the twin's truth, worst {:.2}σ ({}); largest |measured − nominal| {:.1} µm",
        worst.0,
        worst.1,
        largest_error * 1e6
    );
    assert!(
        beyond3 * 100 <= coordinates && worst.0 <= 5.0,
        "measured points against the twin's truth: {beyond3} of {coordinates} beyond 3σ, worst {:.2}σ: {}",
        worst.0,
        worst.1
    );
    let _ = std::fs::remove_dir_all(&dir);
}
