//! The tracker node's `/diagnostics`, read directly over DDS, against what went through its
//! topics. The twin (`quick_demo.yaml` plus frequent beam breaks and a turbulence window) feeds
//! `metrocell-tracker`; this test subscribes to the node's inputs and outputs and to
//! `/diagnostics`, and requires every counter the node reports to equal the count made here:
//! * `readings` = the readings on `tracker/measurements` (= what the twin says it published);
//! * `beam_breaks` = the readings flagged `STATUS_BEAM_BREAK` (and there are some);
//! * `dwells` and `short_dwells` = the runs of unbroken readings of one target (a silence over
//!   `dwell_gap` or another target ends a run) with at least / fewer than `min_dwell_readings`;
//!   `dwells` also = the messages on `tracker/dwells`;
//! * `turbulence_flags` = the dwells published with `STATUS_TURBULENCE` (and the cell's
//!   turbulence window makes some);
//! * `measured_points` = the messages on `measured_points`; `rejected_readings` and
//!   `dwells_without_nominal` = 0 (the twin sends no bad values and commands every dwell);
//! * `registration_rms` = what the twin's truth makes it: the same twin run again here gives the
//!   first dwell of each target the node registers on, its noise-free reading and the stated
//!   covariance of its mean; registering those gives the machine errors' share of the residual,
//!   and the readings' noise adds (3n − 6) degrees of freedom of χ² to its square sum: the
//!   reported RMS must lie within three standard deviations of that expectation.
//!
//! Run: `cargo build --workspace --bins && tests/isolated cargo test -p metrocell-system-tests --test tracker_diagnostics -- --nocapture`

use std::collections::BTreeMap;
use std::process::Stdio;
use std::time::{Duration, Instant};

use metrocell_laser_tracker::registration::{register, Correspondence};
use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::msg::{MeasuredPoint, TrackerMeasurement};
use metrocell_node::{qos, MetrocellNode};
use metrocell_twin::{Cell, Sample, SampleTruth, Simulation, TrackerStatus};
use nalgebra::{Matrix3, Vector3};
use system_tests::{bin, piped, require_isolated_network, workspace_root, ChildGuard};

const DWELL_GAP_NS: i64 = 500_000_000;
const MIN_DWELL_READINGS: usize = 5;
const REGISTRATION_POINTS: usize = 6;
/// The twin's run (the sim node's parameters below).
const DURATION: f64 = 180.0;
const SEED: u64 = 3;

fn cell_text() -> String {
    let text =
        std::fs::read_to_string(workspace_root().join("launch-configs/cells/quick_demo.yaml"))
            .unwrap();
    let anchor = "    station: {temperature_bias: 0.3 K}\n";
    assert!(
        text.contains(anchor),
        "quick_demo.yaml changed; update this test"
    );
    text.replace(
        anchor,
        &format!(
            "{anchor}    beam_breaks: {{per_hour: 600, mean_duration: 0.4 s}}\n    turbulence:\n      - {{start: 60 s, end: 100 s, coefficient: 40 um/m}}\n"
        ),
    )
}

/// The tracker's own status in a DiagnosticArray: key → value.
fn tracker_values(a: &DiagnosticArray) -> Option<BTreeMap<String, String>> {
    let s = a.status.iter().find(|s| s.name == "/tracker")?;
    Some(
        s.values
            .iter()
            .map(|kv| (kv.key.clone(), kv.value.clone()))
            .collect(),
    )
}

fn counter(values: &BTreeMap<String, String>, key: &str) -> u64 {
    let v = values
        .get(key)
        .unwrap_or_else(|| panic!("no {key} in the tracker's diagnostics: {values:?}"));
    v.parse()
        .unwrap_or_else(|_| panic!("{key} = {v:?} is not a count"))
}

/// Runs of unbroken readings of one target with no silence over the dwell gap: (target,
/// readings). A reading without a target (the machine is moving) ends a run.
fn runs(readings: &[TrackerMeasurement]) -> Vec<(String, usize)> {
    let mut out: Vec<(String, usize)> = Vec::new();
    let mut last: Option<(i64, &str)> = None;
    for r in readings
        .iter()
        .filter(|r| r.status & TrackerMeasurement::STATUS_BEAM_BREAK == 0)
    {
        let t = r.header.stamp.nanos();
        let continues =
            last.is_some_and(|(lt, target)| target == r.target_id && t - lt <= DWELL_GAP_NS);
        if r.target_id.is_empty() {
            last = None;
            continue;
        }
        if !continues {
            out.push((r.target_id.clone(), 0));
        }
        out.last_mut().unwrap().1 += 1;
        last = Some((t, &r.target_id));
    }
    out
}

/// One dwell as the twin made it: its target, readings, and the sums of its noise-free reading
/// and of the readings' stated covariance (tracker frame), and its nominal (machine frame).
struct TrueDwell {
    target: u32,
    n: usize,
    free_sum: Vector3<f64>,
    covariance_sum: Matrix3<f64>,
    nominal: Vector3<f64>,
}

/// The dwells the node registers on, from the twin's truth: the first run of at least
/// MIN_DWELL_READINGS unbroken readings of each target (runs split as [`runs`] splits them), for
/// the first REGISTRATION_POINTS targets, as correspondences of their noise-free mean reading
/// (the true point in the tracker frame, the warm-up and refraction range errors along the beam)
/// with the stated covariance of the mean.
fn true_registration_dwells(cell: Cell) -> Vec<Correspondence> {
    let sim = Simulation::new(cell, DURATION, SEED).unwrap();
    let machine = &sim.cell().machine;
    let (mut runs, mut last): (Vec<TrueDwell>, Option<(f64, u32)>) = (Vec::new(), None);
    for (sample, truth) in sim.samples_with_truth() {
        let (Sample::Tracker(s), SampleTruth::Tracker(tr)) = (sample, truth) else {
            continue;
        };
        if s.status == TrackerStatus::BeamBroken {
            continue;
        }
        let Some(target) = s.target_id else {
            last = None;
            continue;
        };
        let continues =
            last.is_some_and(|(lt, lid)| lid == target && s.t - lt <= DWELL_GAP_NS as f64 * 1e-9);
        if !continues {
            runs.push(TrueDwell {
                target,
                n: 0,
                free_sum: Vector3::zeros(),
                covariance_sum: Matrix3::zeros(),
                nominal: machine.nominal_tool_point(&tr.commanded),
            });
        }
        let run = runs.last_mut().unwrap();
        run.n += 1;
        let beam = tr.point / tr.point.norm();
        run.free_sum += tr.point + beam * (tr.warmup_range_error + tr.refraction_range_error);
        run.covariance_sum += s.covariance;
        last = Some((s.t, target));
    }
    let mut taken: Vec<Correspondence> = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for r in runs.iter().filter(|r| r.n >= MIN_DWELL_READINGS) {
        if seen.len() < REGISTRATION_POINTS && seen.insert(r.target) {
            let n = r.n as f64;
            taken.push(Correspondence {
                tracker: r.free_sum / n,
                tracker_covariance: r.covariance_sum / (n * n),
                machine: r.nominal,
                machine_covariance: Matrix3::zeros(),
            });
        }
    }
    assert_eq!(taken.len(), REGISTRATION_POINTS, "the twin's first dwells");
    taken
}

/// The registration RMS the twin's truth gives (m), and the band three standard deviations of
/// its square sum wide: the noise-free dwells' residual square sum S₀ after their own fit, plus
/// the noise's Σ tr Σᵢ · (3n − 6)/3n; variance 2 Σ tr Σᵢ² · (3n − 6)/3n for the noise's square
/// sum and 4 Σ rᵢᵀ Σᵢ rᵢ for its cross term with the residuals rᵢ.
fn expected_registration_rms(cell: Cell) -> (f64, f64, f64) {
    let dwells = true_registration_dwells(cell);
    let fit = register(&dwells).unwrap();
    let n = dwells.len() as f64;
    let share = (3.0 * n - 6.0) / (3.0 * n);
    let (mut s0, mut noise, mut variance) = (0.0, 0.0, 0.0);
    for d in &dwells {
        let r = fit.rotation * d.tracker + fit.translation - d.machine;
        let c = fit.rotation.matrix() * d.tracker_covariance * fit.rotation.matrix().transpose();
        s0 += r.norm_squared();
        noise += c.trace() * share;
        variance += 2.0 * (c * c).trace() * share + 4.0 * (r.transpose() * c * r)[(0, 0)];
    }
    let (mean, sd) = (s0 + noise, variance.sqrt());
    eprintln!(
        "registration from the truth: machine errors' RMS {:.2} µm, noise adds {:.2} µm² to the mean square",
        (s0 / n).sqrt() * 1e6,
        noise / n * 1e12
    );
    (
        (mean / n).sqrt(),
        ((mean - 3.0 * sd).max(0.0) / n).sqrt(),
        ((mean + 3.0 * sd) / n).sqrt(),
    )
}

#[test]
fn tracker_diagnostics_count_exactly_what_went_through_its_topics() {
    require_isolated_network();
    let dir = std::env::temp_dir().join(format!("metrocell-tracker-diag-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let cell = dir.join("cell.yaml");
    std::fs::write(&cell, cell_text()).unwrap();
    let domain = "32";

    let mut tracker_cmd = piped(bin("metrocell-tracker"));
    tracker_cmd
        .args([
            "--ros-args",
            "-p",
            "tool_offset:=[0.0, 0.0, -0.1]",
            "-p",
            &format!("registration_points:={REGISTRATION_POINTS}"),
            "-p",
            &format!("min_dwell_readings:={MIN_DWELL_READINGS}"),
        ])
        .args(["-p", &format!("dwell_gap:={}", DWELL_GAP_NS as f64 * 1e-9)])
        .env("ROS_DOMAIN_ID", domain)
        .stdout(Stdio::null())
        .stderr(Stdio::null());
    let _tracker = ChildGuard::spawn(&mut tracker_cmd);

    std::env::set_var("ROS_DOMAIN_ID", domain);
    let mut node = MetrocellNode::builder("tracker_diagnostics_test")
        .diagnostics_period(None)
        .handle_signals(false)
        .build()
        .unwrap();
    let diagnostics = node
        .subscription::<DiagnosticArray>("/diagnostics", qos::stream(qos::reliable()))
        .unwrap();
    let readings_sub = node
        .subscription::<TrackerMeasurement>("/tracker/measurements", qos::stream(qos::reliable()))
        .unwrap();
    let dwells_sub = node
        .subscription::<TrackerMeasurement>("/tracker/dwells", qos::stream(qos::reliable()))
        .unwrap();
    let points_sub = node
        .subscription::<MeasuredPoint>("/measured_points", qos::stream(qos::reliable()))
        .unwrap();
    let (mut readings, mut dwells, mut points, mut latest) = (Vec::new(), Vec::new(), 0usize, None);
    let collect = |latest: &mut Option<BTreeMap<String, String>>,
                   readings: &mut Vec<TrackerMeasurement>,
                   dwells: &mut Vec<TrackerMeasurement>,
                   points: &mut usize| {
        while let Ok(Some((a, _))) = diagnostics.take() {
            if let Some(v) = tracker_values(&a) {
                *latest = Some(v);
            }
        }
        while let Ok(Some((r, _))) = readings_sub.take() {
            readings.push(r);
        }
        while let Ok(Some((d, _))) = dwells_sub.take() {
            dwells.push(d);
        }
        while let Ok(Some(_)) = points_sub.take() {
            *points += 1;
        }
    };
    // the node is up (its heartbeat arrives) before the twin starts
    let deadline = Instant::now() + Duration::from_secs(30);
    while latest.is_none() {
        assert!(
            Instant::now() < deadline,
            "no /diagnostics from the tracker node within 30 s"
        );
        collect(&mut latest, &mut readings, &mut dwells, &mut points);
        std::thread::sleep(Duration::from_millis(20));
    }
    let before = latest.clone().unwrap();
    assert_eq!(
        counter(&before, "readings"),
        0,
        "no reading before the twin starts: {before:?}"
    );

    let mut sim_cmd = piped(bin("metrocell-sim"));
    sim_cmd
        .args([
            "--ros-args",
            "-p",
            &format!("cell:={}", cell.display()),
            "-p",
            &format!("duration:={DURATION}s"),
            "-p",
            "speed:=10.0",
            "-p",
            &format!("seed:={SEED}"),
        ])
        .args(["-p", "camera_images:=false", "-p", "start_delay:=2.0"])
        .env("ROS_DOMAIN_ID", domain)
        .stdout(Stdio::null());
    let mut sim = ChildGuard::spawn(&mut sim_cmd);
    let sim_stderr = sim.child().stderr.take().unwrap();
    let sim_log =
        std::thread::spawn(move || std::io::read_to_string(sim_stderr).unwrap_or_default());
    let deadline = Instant::now() + Duration::from_secs(120);
    while sim.child().try_wait().unwrap().is_none() {
        assert!(
            Instant::now() < deadline,
            "the twin did not finish 180 s at 10x within 120 s"
        );
        collect(&mut latest, &mut readings, &mut dwells, &mut points);
        std::thread::sleep(Duration::from_millis(5));
    }
    let sim_log = sim_log.join().unwrap();
    // the last dwell closes after a silence; the heartbeat is once a second: wait until the
    // counters stop changing over three heartbeats
    let mut stable_since = Instant::now();
    let mut previous = latest.clone();
    let deadline = Instant::now() + Duration::from_secs(20);
    while stable_since.elapsed() < Duration::from_millis(3500) {
        assert!(
            Instant::now() < deadline,
            "the tracker's counters kept changing"
        );
        collect(&mut latest, &mut readings, &mut dwells, &mut points);
        if latest != previous {
            previous = latest.clone();
            stable_since = Instant::now();
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    let d = latest.unwrap();
    eprintln!("tracker diagnostics: {d:?}");

    // what the twin published on tracker/measurements, from its last log line
    let published: usize = sim_log
        .split("/tracker/measurements ")
        .nth(1)
        .and_then(|s| s.split(|c: char| !c.is_ascii_digit()).next())
        .and_then(|n| n.parse().ok())
        .unwrap_or_else(|| {
            panic!("the twin's published count for /tracker/measurements in its log:\n{sim_log}")
        });
    assert_eq!(
        readings.len(),
        published,
        "this test received every reading the twin published"
    );
    assert_eq!(counter(&d, "readings") as usize, published, "readings");

    let breaks = readings
        .iter()
        .filter(|r| r.status & TrackerMeasurement::STATUS_BEAM_BREAK != 0)
        .count();
    assert!(breaks > 0, "the cell's beam breaks cut some readings");
    assert_eq!(counter(&d, "beam_breaks") as usize, breaks, "beam_breaks");
    assert_eq!(counter(&d, "rejected_readings"), 0, "rejected_readings");

    let runs = runs(&readings);
    let long = runs.iter().filter(|r| r.1 >= MIN_DWELL_READINGS).count();
    let short = runs.len() - long;
    assert_eq!(
        counter(&d, "dwells") as usize,
        long,
        "dwells: runs of ≥ {MIN_DWELL_READINGS} readings"
    );
    assert_eq!(
        counter(&d, "short_dwells") as usize,
        short,
        "short_dwells: runs of < {MIN_DWELL_READINGS} readings"
    );
    assert_eq!(dwells.len(), long, "one tracker/dwells message per dwell");

    let flagged = dwells
        .iter()
        .filter(|m| m.status & TrackerMeasurement::STATUS_TURBULENCE != 0)
        .count();
    assert!(flagged > 0, "the turbulence window flags some dwells");
    assert_eq!(
        counter(&d, "turbulence_flags") as usize,
        flagged,
        "turbulence_flags"
    );

    assert!(points > 0, "measured points published");
    assert_eq!(
        counter(&d, "measured_points") as usize,
        points,
        "measured_points"
    );
    assert_eq!(
        counter(&d, "dwells_without_nominal"),
        0,
        "dwells_without_nominal"
    );
    // "12.3 µm"
    let rms: f64 = d
        .get("registration_rms")
        .and_then(|v| v.strip_suffix(" µm"))
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("registration_rms in µm in {d:?}"));
    let cell = Cell::from_yaml_str(&cell_text(), "cell.yaml").unwrap();
    let (expected, low, high) = expected_registration_rms(cell);
    eprintln!(
        "registration_rms {rms} µm; the truth gives {:.2} µm, 3σ band [{:.2}, {:.2}] µm",
        expected * 1e6,
        low * 1e6,
        high * 1e6
    );
    // the node prints one decimal: the band is widened by its rounding
    assert!(
        rms >= low * 1e6 - 0.05 && rms <= high * 1e6 + 0.05,
        "registration_rms {rms} µm, the twin's truth gives {:.2} µm (3σ band [{:.2}, {:.2}] µm)",
        expected * 1e6,
        low * 1e6,
        high * 1e6
    );
    eprintln!(
        "{published} readings ({breaks} beam breaks), {long} dwells + {short} short, {flagged} turbulent, {points} points, registration rms {rms} µm"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
