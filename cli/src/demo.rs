//! `metrocell demo`: the main job on the built-in simulated cell.
//!
//! Starts `launch-configs/demo.launch.yaml` (the digital twin publishing live, the tracker,
//! fiducial, thermal compensation, estimator and diagnose nodes, the recorder and the dashboard)
//! on the demo cell (`demo_shift.yaml`: a compressed shift, by default 5 h of cell time at 60×
//! real time, five minutes; the time is the twin's `/clock`), watches the cell over DDS like a shift
//! supervisor would — tracker readings, beam breaks, the X-scale strain the thermal node computes
//! from its configured α (a handbook value, not an estimate), the error model the estimator fits
//! online — stops everything when the simulated run is over, and summarises the recorded bag. The
//! twin waits until the recorder subscribes to every topic before it publishes; at the end the
//! bag's count of each topic is checked against the twin's own (its `published/<topic>`
//! diagnostics), and the demo fails (exit 1) if any message is missing; what the camera and the
//! fiducial node did is read back from the bag ([`camera_summary`]). Last, `metrocell
//! diagnose` judges the bag's tracker readings against the demo's declared model, writes its HTML
//! report next to the bag, and the demo says which of the effects the cell conceals from that
//! model it named.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use std::collections::{BTreeMap, BTreeSet};

use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::msg::{ErrorModel, TrackerMeasurement};
use metrocell_msgs::rosgraph_msgs::msg::Clock;
use metrocell_node::{qos, MetrocellNode};

mod camera_summary;

#[derive(clap::Args)]
#[command(
    after_help = "Runs inside a private network namespace when started as\n  \
tests/isolated target/release/metrocell demo\n\nExamples:\n  metrocell demo\n  metrocell demo --duration 10800 --speed 30 --output /tmp/demo_bag\n  metrocell demo --quick"
)]
pub struct DemoArgs {
    /// Directory for the diagnosis report written at the end (default: the bag's path + `_report`)
    #[arg(long, value_name = "DIR")]
    report: Option<PathBuf>,
    /// Cell description (default: the built-in compressed-shift XFYZ cell, crates/twin/examples/cells/demo_shift.yaml)
    #[arg(long)]
    cell: Option<PathBuf>,
    /// Simulated seconds (default: a 5-hour shift)
    #[arg(long, default_value_t = 18000.0)]
    duration: f64,
    /// Simulated seconds per wall-clock second (default: 5 h of the cell in 5 minutes)
    #[arg(long, default_value_t = 60.0)]
    speed: f64,
    /// Random seed of the twin
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Bag directory to record into (must not exist)
    #[arg(long, short = 'o')]
    output: Option<PathBuf>,
    /// A short run for CI: the first hour of the shift at 60× real time, one minute (overrides
    /// --duration and --speed); long enough to find the column growth and the tracker warm-up
    #[arg(long)]
    quick: bool,
    /// TCP port of the live dashboard (web page; the Foxglove WebSocket takes the next one); 0 picks two free ports
    #[arg(long, default_value_t = 8765)]
    dashboard_port: u16,
    /// Seconds of cell time the live diagnose node looks back over (default: 8 h, the whole run);
    /// shorter than --duration, its window fills and then slides (the soak, tests/py/soak.py)
    #[arg(long, default_value_t = 28800.0, value_name = "S")]
    diagnose_window: f64,
    /// Run the cell with DDS Security: a new keystore next to the bag (`<bag>_keystore`), one
    /// enclave per node (the launch file's `enclave:`), every topic authenticated and encrypted
    #[arg(long)]
    secure: bool,
}

/// The error model the estimator starts from and the end-of-run diagnosis judges the recording
/// against (relative to the share directory).
const DEMO_MODEL: &str = "crates/twin/examples/cells/demo_model.yaml";

/// The cell the twin simulates unless `--cell` is given (the launch file's default too).
const DEMO_CELL: &str = "crates/twin/examples/cells/demo_shift.yaml";

/// The directory holding `launch-configs/`: next to the executable's build tree, or the cwd.
fn share_dir() -> Option<PathBuf> {
    if let Ok(dir) = std::env::var("METROCELL_SHARE") {
        return Some(PathBuf::from(dir));
    }
    let exe = std::env::current_exe().ok()?;
    let mut candidates: Vec<PathBuf> = exe.ancestors().map(Path::to_path_buf).collect();
    candidates.extend(std::env::current_dir().ok());
    candidates
        .into_iter()
        .find(|d| d.join("launch-configs/demo.launch.yaml").exists())
}

struct Watch {
    sim_time_s: f64,
    /// Wall-clock seconds from the first /clock message to the last seen.
    wall_s: f64,
    tracker_readings: u64,
    beam_breaks: u64,
    last_strain: Option<(f64, f64)>,
    /// The twin's messages published per topic (its latest diagnostics), and whether it said it finished.
    twin_published: BTreeMap<String, u64>,
    twin_finished: bool,
    /// The recorder's messages recorded per topic (its latest diagnostics).
    recorded: BTreeMap<String, u64>,
    /// The estimator's latest error model.
    estimated: Option<ErrorModel>,
    /// What the live diagnose node found: status name (`diagnose: <term>`) → its sentence.
    live_findings: BTreeMap<String, String>,
    /// The findings of the diagnose node's latest completed run (a later run may replace an
    /// earlier run's term, e.g. one thermocouple's growth by a confounded one's).
    live_last_run: Option<BTreeSet<String>>,
    /// The fiducial node's latest counts (frames processed, skipped, rejected).
    fiducial: camera_summary::FiducialNodeCounts,
}

pub fn run(args: DemoArgs) -> i32 {
    match demo(args) {
        Ok(code) => code,
        Err(e) => {
            eprintln!("metrocell demo: {e:#}");
            2
        }
    }
}

fn demo(mut args: DemoArgs) -> anyhow::Result<i32> {
    if args.quick {
        (args.duration, args.speed) = (3600.0, 60.0);
    }
    if !(args.speed > 0.0 && args.duration > 0.0) {
        anyhow::bail!("--speed and --duration must be positive");
    }
    // the diagnose node's own range for `window` (nodes/diagnose parameters.rs)
    if !(60.0..=1e7).contains(&args.diagnose_window) {
        anyhow::bail!("--diagnose-window must lie within 60 s and 1e7 s");
    }
    let share = share_dir().ok_or_else(|| {
        anyhow::anyhow!("cannot find launch-configs/demo.launch.yaml; run from the repository or set METROCELL_SHARE")
    })?;
    let output = args.output.clone().unwrap_or_else(|| {
        std::env::temp_dir().join(format!("metrocell_demo_{}", std::process::id()))
    });
    if output.exists() {
        anyhow::bail!("{} exists; give a new --output directory", output.display());
    }
    let (dashboard_port, foxglove_port) = dashboard_ports(args.dashboard_port)?;
    let mut launch_args = vec![
        ("duration".to_string(), args.duration.to_string()),
        ("speed".to_string(), args.speed.to_string()),
        ("seed".to_string(), args.seed.to_string()),
        ("output".to_string(), output.display().to_string()),
        ("dashboard_port".to_string(), dashboard_port.to_string()),
        ("foxglove_port".to_string(), foxglove_port.to_string()),
        // the live diagnose node: about five diagnoses over the run, each of what it has seen so far
        (
            "diagnose_every".to_string(),
            (args.duration / 5.0).max(600.0).to_string(),
        ),
        (
            "diagnose_window".to_string(),
            args.diagnose_window.to_string(),
        ),
    ];
    let cell = match &args.cell {
        Some(cell) => std::fs::canonicalize(cell)?,
        None => share.join(DEMO_CELL),
    };
    launch_args.push(("cell".to_string(), cell.display().to_string()));
    sayln!(
        "metrocell demo: simulating {} of the cell ({}) at {}× real time, about {} of wall time; recording to {}",
        duration_text(args.duration),
        cell.file_name().map_or(String::new(), |n| n.to_string_lossy().into_owned()),
        args.speed,
        duration_text(args.duration / args.speed),
        output.display()
    );
    let dashboard = format!("http://127.0.0.1:{dashboard_port}");
    sayln!("live dashboard while it runs: {dashboard} (Foxglove WebSocket ws://127.0.0.1:{foxglove_port})");

    let options = metrocell_launch::LaunchOptions {
        share_dir: Some(share.clone()),
        ..Default::default()
    };
    let shutdown = options.shutdown.clone();
    let launch_file = share.join("launch-configs/demo.launch.yaml");
    let security = if args.secure {
        Some(secure_the_cell(
            &launch_file,
            &launch_args,
            &options,
            &output,
        )?)
    } else {
        None
    };
    let launcher = std::thread::spawn(move || {
        metrocell_launch::run_launch(&launch_file, &launch_args, &options)
    });

    let watch = watch_cell(&args, &shutdown, &launcher, security)?;
    // The watch has waited until the recorder holds every message of the twin. A moment more lets
    // the other nodes' last outputs, computed from the twin's last messages, reach the bag too;
    // then stop every node.
    std::thread::sleep(Duration::from_millis(800));
    shutdown.request();
    let outcome = launcher
        .join()
        .map_err(|_| anyhow::anyhow!("launcher thread panicked"))??;

    sayln!();
    sayln!(
        "watched: {} simulated in {} of wall time, {} tracker readings, {} beam breaks{}",
        duration_text(watch.sim_time_s),
        duration_text(watch.wall_s),
        watch.tracker_readings,
        watch.beam_breaks,
        match watch.last_strain {
            Some((e, var)) => format!(
                ", X-scale strain (configured α) {:+.2} ± {:.2} µm/m",
                e * 1e6,
                var.sqrt() * 1e6
            ),
            None => String::new(),
        }
    );
    if let Some(m) = &watch.estimated {
        sayln!("{}", describe_estimate(m));
    } else {
        sayln!("estimated online: no error model from the estimator (too few measured points)");
    }
    if !watch.live_findings.is_empty() {
        let in_last = |name: &String| {
            watch
                .live_last_run
                .as_ref()
                .is_none_or(|s| s.contains(name))
        };
        let (last, earlier): (Vec<_>, Vec<_>) = watch
            .live_findings
            .iter()
            .partition(|(name, _)| in_last(name));
        let sentences = |v: &[(&String, &String)]| {
            v.iter()
                .map(|(_, s)| s.as_str())
                .collect::<Vec<_>>()
                .join("; ")
        };
        sayln!(
            "the live diagnose node found, while the cell ran (its last run): {}",
            sentences(&last)
        );
        if !earlier.is_empty() {
            sayln!(
                "  named by an earlier run and replaced by its last: {}",
                sentences(&earlier)
            );
        }
    } else {
        sayln!("the live diagnose node found nothing while the cell ran (it diagnoses every fifth of the run)");
    }
    sayln!(
        "the dashboard was at {dashboard}; the bag is at {}",
        output.display()
    );
    match metrocell_bag::info(&output) {
        Ok(info) => sayln!("\nrecorded bag:\n{info}"),
        Err(e) => eprintln!("metrocell demo: the recorded bag cannot be read: {e}"),
    }
    let complete = check_recording(&output, &watch);
    match camera_summary::summarise(&output) {
        Ok(s) => sayln!(
            "{}",
            camera_summary::describe(
                &s,
                watch
                    .twin_published
                    .get(camera_summary::IMAGE_TOPIC)
                    .copied(),
                &watch.fiducial
            )
        ),
        Err(e) => sayln!("camera: the frames and detections in the bag cannot be read: {e:#}"),
    }
    diagnose_recording(&share, &cell, &output, args.report.clone());
    Ok(if outcome.success() && complete { 0 } else { 1 })
}

/// The dashboard's web and Foxglove WebSocket ports: `requested` and the next one, or for 0 two
/// free ports picked here — bound together so they differ, then released for the dashboard
/// node to bind a moment later — so that the addresses the demo prints are the real ones.
fn dashboard_ports(requested: u16) -> anyhow::Result<(u16, u16)> {
    if requested != 0 {
        let next = requested.checked_add(1).ok_or_else(|| anyhow::anyhow!("--dashboard-port {requested}: the Foxglove WebSocket takes the next port; give at most 65534 (0: any free ports)"))?;
        return Ok((requested, next));
    }
    let web = std::net::TcpListener::bind(("127.0.0.1", 0))?;
    let ws = std::net::TcpListener::bind(("127.0.0.1", 0))?;
    Ok((web.local_addr()?.port(), ws.local_addr()?.port()))
}

/// `metrocell diagnose` on the recorded bag against the model the estimator started from (the
/// demo's declared error model), the report written next to the bag. What it finds is printed
/// in words, then set against what the cell conceals from that model; a diagnosis that cannot be
/// made (too short a run) is said, not hidden, and does not fail the demo (the recording is its
/// product).
///
/// The records are the tracker's raw readings (`/tracker/measurements`, in the tracker's frame,
/// its pose fitted with the model), not the tracker node's registered `/measured_points`: in
/// the machine frame the tracker's position is gone, and with it the line of sight along which
/// its warm-up moves the readings.
///
/// The camera's marker poses (`/fiducials`, in the bag too) are left out on purpose:
/// `diagnose_bags_from` builds records with `camera_points` off. The declared model has no
/// camera (no mount, no lens) to predict them with, and a marker's position from a 640×480
/// frame at 150 mm carries σ ≈ 1 µm across the optical axis and ≈ 10 µm along it, against
/// 14400 tracker readings an hour at ~1.5 µm per dwell. Adding the camera to the cell changed
/// no tracker reading (crates/twin/tests/determinism.rs), so the diagnosis is the one the demo
/// gave without it.
fn diagnose_recording(share: &Path, cell: &Path, bag: &Path, report: Option<PathBuf>) {
    let model = share.join(DEMO_MODEL);
    let report = report.unwrap_or_else(|| PathBuf::from(format!("{}_report", bag.display())));
    sayln!("\ndiagnosing the recording (the tracker's readings) against the demo's declared model ({DEMO_MODEL}) …");
    let outcome = crate::diagnose_command::diagnose_bags_from(
        &model,
        &[bag.to_path_buf()],
        &metrocell_diagnose::DiagnoseOptions::default(),
        metrocell_records::PointSource::TrackerMeasurements,
    )
    .and_then(|(m, d)| {
        crate::diagnose_command::write_report(
            &report,
            &m,
            &d,
            "metrocell demo: diagnosis of the recorded shift",
        )
        .map(|index| (d, index))
    });
    match outcome {
        Ok((d, index)) => {
            say!("{}", crate::diagnose_command::summary_text(&d));
            sayln!(
                "report: {} (the model with what was found added: {})",
                index.display(),
                report.join("model.yaml").display()
            );
            let found: Vec<String> = d.report.findings.iter().map(|f| f.term.clone()).collect();
            match concealed_effects(cell, &model) {
                Ok(concealed) => sayln!("{}", compare_findings(&concealed, &found)),
                Err(e) => sayln!("(cannot say what the cell conceals: {e:#})"),
            }
        }
        Err(e) => sayln!("diagnose could not judge this recording: {e:#}"),
    }
}

/// The catalog ids of what the cell puts in its readings and the model does not declare: its
/// `terms:` ids the model lacks, and `tracker_warmup` when the cell's tracker warms up and the
/// model gives it no warm-up. (Instrument noise and biases beyond these are not counted.)
pub fn concealed_effects(cell: &Path, model: &Path) -> anyhow::Result<Vec<String>> {
    let read = |p: &Path| -> anyhow::Result<serde_yaml::Value> {
        let text =
            std::fs::read_to_string(p).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))?;
        serde_yaml::from_str(&text).map_err(|e| anyhow::anyhow!("{}: {e}", p.display()))
    };
    let (cell, model) = (read(cell)?, read(model)?);
    let ids = |v: &serde_yaml::Value| -> Vec<String> {
        v["terms"].as_sequence().map_or(Vec::new(), |t| {
            t.iter()
                .filter_map(|t| t["id"].as_str().map(str::to_string))
                .collect()
        })
    };
    let declared = ids(&model);
    let mut concealed: Vec<String> = ids(&cell)
        .into_iter()
        .filter(|id| !declared.contains(id))
        .collect();
    if !cell["sensors"]["tracker"]["warmup"].is_null()
        && model["sensors"]["tracker"]["warmup"].is_null()
    {
        concealed.push("tracker_warmup".into());
    }
    concealed.sort();
    concealed.dedup();
    Ok(concealed)
}

/// What the diagnosis named against what the cell concealed, in words.
fn compare_findings(concealed: &[String], found: &[String]) -> String {
    let named: Vec<&String> = concealed.iter().filter(|c| found.contains(c)).collect();
    let missed: Vec<&String> = concealed.iter().filter(|c| !found.contains(c)).collect();
    let extra: Vec<&String> = found.iter().filter(|f| !concealed.contains(f)).collect();
    let list = |v: &[&String]| v.iter().map(|s| s.as_str()).collect::<Vec<_>>().join(", ");
    let mut s = format!(
        "the cell concealed {} effect(s) from the declared model ({}): ",
        concealed.len(),
        concealed.join(", ")
    );
    if missed.is_empty() {
        s.push_str(&format!(
            "diagnose named {}",
            if named.len() == 1 {
                "it".to_string()
            } else {
                format!("all {}", named.len())
            }
        ));
    } else {
        s.push_str(&format!(
            "diagnose named {} of them ({}) and missed {}",
            named.len(),
            list(&named),
            list(&missed)
        ));
    }
    if !extra.is_empty() {
        s.push_str(&format!(
            "; it also named {}, which the cell does not conceal",
            list(&extra)
        ));
    }
    s
}

/// Seconds as a person reads a duration: `45 s`, `12 min 30 s`, `5 h`, `1 h 30 min`.
fn duration_text(s: f64) -> String {
    let s = s.max(0.0).round() as u64;
    let (h, m, sec) = (s / 3600, (s % 3600) / 60, s % 60);
    match (h, m, sec) {
        (0, 0, sec) => format!("{sec} s"),
        (0, m, 0) => format!("{m} min"),
        (0, m, sec) => format!("{m} min {sec} s"),
        (h, 0, _) => format!("{h} h"),
        (h, m, _) => format!("{h} h {m} min"),
    }
}

/// The bag's count of each topic against the twin's; prints the verdict, true when complete.
fn check_recording(output: &Path, watch: &Watch) -> bool {
    if watch.twin_published.is_empty() || !watch.twin_finished {
        sayln!("recording check: the twin's final counts never arrived (no diagnostics from /sim); cannot say whether the bag is complete");
        return false;
    }
    let recorded: BTreeMap<String, u64> = match metrocell_bag::BagReader::open(output) {
        Ok(r) => r
            .topics()
            .iter()
            .map(|t| (t.name.clone(), t.message_count))
            .collect(),
        Err(e) => {
            sayln!("recording check: the bag cannot be read: {e}");
            return false;
        }
    };
    let published: u64 = watch.twin_published.values().sum();
    let mismatches = metrocell_bagtools::compare_counts(&watch.twin_published, &recorded);
    if mismatches.is_empty() {
        sayln!("recording check: complete — the bag holds every message the twin published ({published} on {} topics, 0 missing)", watch.twin_published.len());
        true
    } else {
        sayln!("recording check: INCOMPLETE — {} of {} topics differ from the twin's count (the recorder's last log line gives the causes):", mismatches.len(), watch.twin_published.len());
        for m in &mismatches {
            sayln!("  {m}");
        }
        false
    }
}

/// The enclave of the demo's own watching node.
const WATCH_ENCLAVE: &str = "/metrocell_demo/watch";

/// `--secure`: a keystore next to the bag with an enclave for every node of the launch file (its
/// `enclave:`) and for the demo's watching node, and the ROS 2 security environment the launched
/// nodes inherit (Enforce: a node without its enclave would not start). Returns the watching
/// node's security environment.
fn secure_the_cell(
    launch_file: &std::path::Path,
    launch_args: &[(String, String)],
    options: &metrocell_launch::LaunchOptions,
    output: &std::path::Path,
) -> anyhow::Result<metrocell_security::SecurityEnvironment> {
    let keystore = PathBuf::from(format!("{}_keystore", output.display()));
    if keystore.exists() {
        anyhow::bail!(
            "{} exists; give a new --output directory",
            keystore.display()
        );
    }
    // The domain the nodes will join, read as they read it (an invalid value is refused here).
    let domain = metrocell_node::DdsEnvironment::from_env()?.domain_id;
    metrocell_security::keystore::create_keystore(&keystore, domain)?;
    let plan = metrocell_launch::load_launch_plan(launch_file, launch_args, options)?;
    let mut enclaves: BTreeSet<String> = plan
        .processes
        .iter()
        .filter_map(|p| {
            p.args
                .windows(2)
                .find(|w| w[0] == "--enclave")
                .map(|w| w[1].clone())
        })
        .collect();
    enclaves.insert(WATCH_ENCLAVE.to_string());
    for e in &enclaves {
        metrocell_security::keystore::create_enclave(&keystore, e)?;
    }
    // Set before any thread starts: the launched nodes inherit it.
    std::env::set_var("ROS_SECURITY_ENABLE", "true");
    std::env::set_var("ROS_SECURITY_STRATEGY", "Enforce");
    std::env::set_var("ROS_SECURITY_KEYSTORE", &keystore);
    std::env::remove_var("ROS_SECURITY_ENCLAVE_OVERRIDE");
    sayln!(
        "DDS Security on: keystore {} (ROS domain {domain}), {} enclaves, every topic authenticated and encrypted",
        keystore.display(),
        enclaves.len()
    );
    Ok(metrocell_security::SecurityEnvironment {
        enabled: true,
        enforce: true,
        keystore: Some(keystore),
        enclave_override: Some(WATCH_ENCLAVE.to_string()),
    })
}

/// Follows the run over DDS until the simulated clock reaches the end (or the nodes stop).
fn watch_cell(
    args: &DemoArgs,
    shutdown: &metrocell_launch::ShutdownHandle,
    launcher: &std::thread::JoinHandle<
        Result<metrocell_launch::LaunchOutcome, metrocell_launch::LaunchError>,
    >,
    security: Option<metrocell_security::SecurityEnvironment>,
) -> anyhow::Result<Watch> {
    let mut builder = MetrocellNode::builder("demo_watch")
        .diagnostics_period(None)
        .handle_signals(false);
    if let Some(security) = security {
        builder = builder.security(security);
    }
    let mut node = builder.build()?;
    let clock = node.subscription::<Clock>("/clock", qos::sensor_data())?;
    let tracker =
        node.subscription::<TrackerMeasurement>("/tracker/measurements", qos::sensor_data())?;
    let model = node.subscription::<ErrorModel>("/thermal/error_model", qos::sensor_data())?;
    let estimated = node.subscription::<ErrorModel>("/estimator/error_model", qos::latched())?;
    let diagnostics = node.subscription::<DiagnosticArray>(
        "/diagnostics",
        qos::reliable().history(ros2_client::qos::History::KeepLast { depth: 100 }),
    )?;
    let mut w = Watch {
        sim_time_s: 0.0,
        wall_s: 0.0,
        tracker_readings: 0,
        beam_breaks: 0,
        last_strain: None,
        twin_published: BTreeMap::new(),
        twin_finished: false,
        recorded: BTreeMap::new(),
        estimated: None,
        live_findings: BTreeMap::new(),
        live_last_run: None,
        fiducial: Default::default(),
    };
    // about twenty progress lines over the run, at whole minutes of cell time
    let print_every = if args.duration <= 600.0 {
        30.0
    } else {
        ((args.duration / 20.0) / 60.0).round().max(1.0) * 60.0
    };
    let mut first_clock: Option<Instant> = None;
    let mut start_ns: Option<i64> = None;
    let mut next_print = 0.0;
    // The run is over when the simulated clock, once started, stops advancing.
    let mut last_advance = Instant::now();
    // Wall-clock budget: the run at speed, plus start-up, plus slack for a loaded machine.
    let deadline =
        Instant::now() + Duration::from_secs_f64(args.duration / args.speed * 3.0 + 30.0);
    while !shutdown.is_requested() && !launcher.is_finished() {
        while let Ok(Some((c, _))) = clock.take() {
            let ns = c.clock.nanos();
            let s = *start_ns.get_or_insert_with(|| {
                last_advance = Instant::now();
                first_clock = Some(last_advance);
                ns
            });
            let t = (ns - s) as f64 * 1e-9;
            if t > w.sim_time_s {
                w.sim_time_s = t;
                last_advance = Instant::now();
                w.wall_s = first_clock.map_or(0.0, |t0| t0.elapsed().as_secs_f64());
            }
        }
        while let Ok(Some((m, _))) = tracker.take() {
            if m.status & TrackerMeasurement::STATUS_BEAM_BREAK != 0 {
                w.beam_breaks += 1;
            } else {
                w.tracker_readings += 1;
            }
        }
        while let Ok(Some((m, _))) = model.take() {
            if let Some(i) = m
                .parameter_names
                .iter()
                .position(|p| p == "thermal_scale[x].strain")
            {
                let n = m.values.len();
                w.last_strain = m
                    .values
                    .get(i)
                    .map(|&v| (v, m.covariance.get(i * n + i).copied().unwrap_or(f64::NAN)));
            }
        }
        while let Ok(Some((d, _))) = diagnostics.take() {
            take_twin_counts(&d, &mut w);
            take_recorder_counts(&d, &mut w);
            for status in d.status.iter().filter(|s| s.name == "/fiducial") {
                w.fiducial.update(
                    status
                        .values
                        .iter()
                        .map(|kv| (kv.key.as_str(), kv.value.as_str())),
                );
            }
            if let Some(names) = completed_run_findings(&d) {
                w.live_last_run = Some(names);
            }
            for (name, statement) in new_live_findings(&d, &mut w) {
                let t = w.sim_time_s.max(0.0) as u64;
                sayln!(
                    "  cell time {}:{:02}:{:02}   the diagnose node found {}: {statement}",
                    t / 3600,
                    t / 60 % 60,
                    t % 60,
                    name.trim_start_matches("diagnose: ")
                );
            }
        }
        while let Ok(Some((m, _))) = estimated.take() {
            w.estimated = Some(m);
        }
        if w.sim_time_s >= next_print {
            next_print += print_every;
            let t = w.sim_time_s.round() as u64;
            sayln!(
                "  cell time {}:{:02}:{:02}   tracker readings {:>6}   beam breaks {:>3}   X-scale strain (configured α) {}{}",
                t / 3600,
                (t % 3600) / 60,
                t % 60,
                w.tracker_readings,
                w.beam_breaks,
                w.last_strain.map_or("(waiting for thermocouples)".to_string(), |(e, v)| format!("{:+.2} ± {:.2} µm/m", e * 1e6, v.sqrt() * 1e6)),
                w.estimated.as_ref().and_then(|m| estimated_value(m, "positioning[z].c0")).map_or(String::new(), |(v, sd)| format!("   Z offset (estimator) {:+.1} ± {:.1} µm", v * 1e6, sd * 1e6))
            );
        }
        let clock_done = w.sim_time_s >= args.duration - 0.5
            || (start_ns.is_some() && last_advance.elapsed() > Duration::from_secs(2));
        // Wait for the twin's final counts too: it publishes them once every reliable reader
        // (the recorder) has acknowledged its last message, within ~1 s of its end on an idle
        // machine, at most 30 s later on a loaded one.
        if clock_done && (w.twin_finished || last_advance.elapsed() > Duration::from_secs(40)) {
            break;
        }
        if Instant::now() > deadline {
            eprintln!(
                "metrocell demo: the simulated clock stopped at {:.1} s; stopping",
                w.sim_time_s
            );
            break;
        }
        std::thread::sleep(Duration::from_millis(5));
    }
    if w.twin_finished {
        let behind = wait_for_recorder(&diagnostics, &mut w, RECORDER_CATCH_UP);
        if behind > 0 {
            eprintln!("metrocell demo: after {} s the recorder was still {behind} messages behind the twin; stopping it anyway", RECORDER_CATCH_UP.as_secs());
        }
    }
    Ok(w)
}

/// How long the demo waits, once the twin has finished, for the recorder's counts to reach the
/// twin's before it stops the nodes. The recorder refreshes its counts once a second.
const RECORDER_CATCH_UP: Duration = Duration::from_secs(30);

/// The findings of a completed diagnosis (an array whose summary status `diagnose` carries its
/// `run` number): their status names. `None` for anything else (another node's statuses, a
/// window still waiting for records).
fn completed_run_findings(d: &DiagnosticArray) -> Option<BTreeSet<String>> {
    d.status
        .iter()
        .any(|s| s.name == "diagnose" && s.values.iter().any(|kv| kv.key == "run"))
        .then(|| {
            d.status
                .iter()
                .filter(|s| s.name.starts_with("diagnose: "))
                .map(|s| s.name.clone())
                .collect()
        })
}

/// The diagnose node's findings (statuses named `diagnose: <term>`) not seen before, kept in
/// the watch.
fn new_live_findings(d: &DiagnosticArray, w: &mut Watch) -> Vec<(String, String)> {
    let mut new = Vec::new();
    for s in d.status.iter().filter(|s| s.name.starts_with("diagnose: ")) {
        if w.live_findings
            .insert(s.name.clone(), s.message.clone())
            .is_none()
        {
            new.push((s.name.clone(), s.message.clone()));
        }
    }
    new
}

/// The recorder's `<topic>/messages` values from a diagnostics message.
fn take_recorder_counts(d: &DiagnosticArray, w: &mut Watch) {
    for status in d.status.iter().filter(|s| s.name == "/recorder") {
        for kv in &status.values {
            if let (Some(topic), Ok(n)) =
                (kv.key.strip_suffix("/messages"), kv.value.parse::<u64>())
            {
                w.recorded.insert(topic.to_string(), n);
            }
        }
    }
}

/// Messages the twin published that the recorder has not recorded yet, over all topics.
fn recorder_behind(w: &Watch) -> u64 {
    w.twin_published
        .iter()
        .map(|(t, n)| n.saturating_sub(w.recorded.get(t).copied().unwrap_or(0)))
        .sum()
}

/// After the twin finished: wait (at most `timeout`) until the recorder's counts reach the twin's,
/// so the recorder is not stopped while a busy machine still has it catching up. Returns how many
/// messages it was still behind.
fn wait_for_recorder(
    diagnostics: &metrocell_node::Subscription<DiagnosticArray>,
    w: &mut Watch,
    timeout: Duration,
) -> u64 {
    let started = Instant::now();
    let mut told = false;
    loop {
        while let Ok(Some((d, _))) = diagnostics.take() {
            take_twin_counts(&d, w);
            take_recorder_counts(&d, w);
        }
        let behind = recorder_behind(w);
        if behind == 0 || started.elapsed() >= timeout {
            return behind;
        }
        if !told && started.elapsed() > Duration::from_secs(3) {
            sayln!("  waiting for the recorder to catch up ({behind} messages behind the twin)");
            told = true;
        }
        std::thread::sleep(Duration::from_millis(50));
    }
}

/// The twin's `published/<topic>` values and `finished` flag from a diagnostics message.
fn take_twin_counts(d: &DiagnosticArray, w: &mut Watch) {
    for status in d.status.iter().filter(|s| s.name == "/sim") {
        for kv in &status.values {
            if let Some(topic) = kv.key.strip_prefix("published") {
                if let (true, Ok(n)) = (topic.starts_with('/'), kv.value.parse::<u64>()) {
                    w.twin_published.insert(topic.to_string(), n);
                }
            } else if kv.key == "finished" {
                w.twin_finished = kv.value == "true";
            }
        }
    }
}

/// One parameter of the estimator's model: value and σ.
fn estimated_value(m: &ErrorModel, name: &str) -> Option<(f64, f64)> {
    let n = m.values.len();
    let i = m.parameter_names.iter().position(|p| p == name)?;
    Some((
        m.values[i],
        m.covariance
            .get(i * n + i)
            .copied()
            .unwrap_or(f64::NAN)
            .max(0.0)
            .sqrt(),
    ))
}

/// The estimator's model in words: each free parameter (non-zero variance) with its σ, in the
/// units a metrologist reads (µm, µrad, µm/m/K).
fn describe_estimate(m: &ErrorModel) -> String {
    let n = m.values.len();
    let mut parts = Vec::new();
    for i in 0..n {
        let var = m.covariance.get(i * n + i).copied().unwrap_or(0.0);
        if !(var > 0.0) {
            continue;
        }
        let (scale, unit) = match m.units[i].as_str() {
            "m" => (1e6, "µm"),
            "rad" => (1e6, "µrad"),
            "1/K" => (1e6, "µm/m/K"),
            other => (1.0, other),
        };
        parts.push(format!(
            "{} = {:.2} ± {:.2} {unit}",
            m.parameter_names[i],
            m.values[i] * scale,
            var.sqrt() * scale
        ));
    }
    format!(
        "estimated online from {} measured points (innovation rms {:.2} µm): {}",
        m.observation_count,
        m.residual_rms * 1e6,
        parts.join(", ")
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use metrocell_msgs::diagnostic_msgs::msg::{DiagnosticStatus, KeyValue};

    fn status(name: &str, values: &[(&str, &str)]) -> DiagnosticStatus {
        DiagnosticStatus {
            name: name.into(),
            values: values
                .iter()
                .map(|(k, v)| KeyValue {
                    key: k.to_string(),
                    value: v.to_string(),
                })
                .collect(),
            ..Default::default()
        }
    }

    /// A completed run's findings replace the last run's; a waiting summary (no `run`) and other
    /// nodes' arrays leave them alone.
    #[test]
    fn the_last_completed_run_names_the_current_findings() {
        let run = |findings: &[&str]| DiagnosticArray {
            status: std::iter::once(status("diagnose", &[("run", "2")]))
                .chain(
                    findings
                        .iter()
                        .map(|f| status(&format!("diagnose: {f}"), &[])),
                )
                .collect(),
            ..Default::default()
        };
        let names = completed_run_findings(&run(&["backlash[x]", "thermal_growth[x_left]"]));
        assert_eq!(
            names.unwrap().into_iter().collect::<Vec<_>>(),
            ["diagnose: backlash[x]", "diagnose: thermal_growth[x_left]"]
        );
        let waiting = DiagnosticArray {
            status: vec![status("diagnose", &[])],
            ..Default::default()
        };
        assert_eq!(completed_run_findings(&waiting), None);
        let other = DiagnosticArray {
            status: vec![status("/recorder", &[("run", "1")])],
            ..Default::default()
        };
        assert_eq!(completed_run_findings(&other), None);
    }

    /// Issue 32: `--dashboard-port 0` gives two real, different ports (not 0 and 1); a port gives
    /// itself and the next; the last port has no next.
    #[test]
    fn dashboard_port_zero_picks_two_free_ports() {
        let (web, ws) = dashboard_ports(0).unwrap();
        assert!(web > 1 && ws > 1 && web != ws, "{web} {ws}");
        assert_eq!(dashboard_ports(8765).unwrap(), (8765, 8766));
        assert!(dashboard_ports(65535)
            .unwrap_err()
            .to_string()
            .contains("at most 65534"));
    }
}
