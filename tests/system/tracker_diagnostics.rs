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
//!   `registration_rms` is reported.
//!
//! Run: `cargo build --workspace --bins && tests/isolated cargo test -p metrocell-system-tests --test tracker_diagnostics -- --nocapture`

use std::collections::BTreeMap;
use std::process::Stdio;
use std::time::{Duration, Instant};

use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::msg::{MeasuredPoint, TrackerMeasurement};
use metrocell_node::{qos, MetrocellNode};
use system_tests::{bin, piped, require_isolated_network, workspace_root, ChildGuard};

const DWELL_GAP_NS: i64 = 500_000_000;
const MIN_DWELL_READINGS: usize = 5;

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
            "registration_points:=6",
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
            "duration:=180s",
            "-p",
            "speed:=10.0",
            "-p",
            "seed:=3",
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
    assert!(rms > 0.0 && rms < 50.0, "registration_rms {rms} µm");
    eprintln!(
        "{published} readings ({breaks} beam breaks), {long} dwells + {short} short, {flagged} turbulent, {points} points, registration rms {rms} µm"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
