//! `metrocell-diagnose`: `metrocell diagnose`, continuously, over a sliding window of a shift.
//!
//! Reads the measured points (`measured_points`, metrocell_msgs/MeasuredPoint in the machine
//! frame — or raw tracker readings with `points_type:=tracker`), the commanded joints
//! (`/machine/commanded_joint_states`) and every signal topic it finds (`/temperature/<sensor>`,
//! `/tracker/power_on`, air, load: the table of crates/records `signal_topics`), turns them
//! into measurement records exactly as `metrocell diagnose` does from a bag, and every `every`
//! seconds of cell time diagnoses the last `window` seconds against the model file (`model`):
//! the declared parameters fitted, the residuals located, the missing physics named and its
//! held-out improvement measured. It publishes each diagnosis on `/diagnostics` (a status per
//! finding, named `diagnose: <term>`, which the dashboard shows; a summary status `diagnose`)
//! and as JSON on `diagnose/result` (std_msgs/String, latched: the fields of `metrocell
//! diagnose --json`), and logs a warning — its own status turning WARN — when a finding
//! appears that no earlier window had.
//!
//!   metrocell-diagnose --ros-args -p model:=crates/twin/examples/cells/demo_model.yaml \
//!       -p window:=14400.0 -p every:=1800.0
//!
//! Offline (no DDS): the same diagnoses from a bag, at the same cell instants, plus one of the
//! window as it stands at the end of the bag; outputs to OUT_BAG, or the findings as text:
//!
//!   metrocell-diagnose --bag SHIFT_BAG [--output OUT_BAG] --ros-args -p model:=...
//!
//! Live, a diagnosis runs on a worker thread; a window that falls due while one runs waits for
//! it (so live runs may cover slightly later windows than a replay's when the CPU is short).

use std::path::Path;
use std::sync::{mpsc, Arc};
use std::time::{Duration, Instant};

use metrocell_bagtools::{BagSource, ReplayOutput, SourcedMessage};
use metrocell_diagnose::{DiagnoseError, Diagnosis};
use metrocell_diagnose_node::findings_message::RunInfo;
use metrocell_diagnose_node::parameters;
use metrocell_diagnose_node::session::{run_job, Session};
use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::std_msgs::msg::String as StringMessage;
use metrocell_node::{qos, MetrocellNode, OfflineNode, RawSubscription, ReplayArgs};
use metrocell_records::signal_topics::{SignalTopic, POWER_ON_TOPIC};

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-diagnose: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (builder, rest) = MetrocellNode::builder("diagnose")
        .params(parameters::declarations())
        .node_argument(ReplayArgs::FLAG, ReplayArgs::HELP)
        .args(std::env::args())?;
    match ReplayArgs::parse(rest.get(1..).unwrap_or_default())? {
        Some(args) => replay(builder.build_offline()?, &args),
        None => live(builder.build()?),
    }
}

fn subscribe(
    node: &mut MetrocellNode,
    name: &str,
    ros_type: &str,
) -> Result<RawSubscription, metrocell_node::NodeError> {
    // a latched topic (the tracker's power-on time) is read latched, so a late start still gets it
    let profile = if name == POWER_ON_TOPIC {
        qos::latched()
    } else {
        qos::stream(qos::reliable())
    };
    node.raw_subscription(name, ros_type, profile)
}

type RunResult = (RunInfo, Result<Diagnosis, DiagnoseError>);

fn live(mut node: MetrocellNode) -> Result<(), Box<dyn std::error::Error>> {
    let setup = parameters::setup(node.parameters(), &|t| {
        node.resolve_topic(t).map_err(|e| e.to_string())
    })?;
    for line in &setup.describe {
        node.info(line);
    }
    // the points, the commanded joints and every signal a declared term reads (more are added
    // as discovery finds them)
    let model = Arc::clone(&setup.model);
    let forward = model.forward_model()?;
    let mut topics = metrocell_records::declared_topics(&forward, &setup.recording);
    let mut session = Session::new(setup, &forward, Path::new("live DDS"), &topics)?;
    let mut subscriptions = Vec::new();
    for topic in session.stream.topics() {
        let ty = topics
            .iter()
            .find(|(n, _)| *n == topic)
            .map(|(_, t)| t.clone())
            .expect("the stream reads only topics it was given");
        subscriptions.push(subscribe(&mut node, &topic, &ty)?);
    }
    let statuses_pub = node.publisher::<DiagnosticArray>("/diagnostics", qos::reliable())?;
    let result_pub = node.publisher::<StringMessage>("diagnose/result", qos::latched())?;
    let fqn = node.fully_qualified_name();
    let diagnostics = node.diagnostics();
    diagnostics.ok("waiting for measured points");
    let (tx, rx) = mpsc::channel::<RunResult>();
    let mut running = false;
    let mut last_discovery = Instant::now();
    let token = node.shutdown_token();
    while !token.is_triggered() {
        // signal topics that appeared since (a sensor started late): read them from now on
        if last_discovery.elapsed() > Duration::from_secs(1) {
            last_discovery = Instant::now();
            for t in node.discovered_publications() {
                if topics.iter().any(|(n, _)| *n == t.name) {
                    continue;
                }
                if let Some(which) = SignalTopic::of(&t.name, &t.type_name) {
                    subscriptions.push(subscribe(&mut node, &t.name, &t.type_name)?);
                    session.stream.add_signal_topic(t.name.clone(), which);
                    node.logger()
                        .debug(format!("reading {} ({})", t.name, t.type_name));
                    topics.push((t.name, t.type_name));
                }
            }
        }
        for sub in &subscriptions {
            while let Ok(Some(m)) = sub.take() {
                let message = SourcedMessage {
                    topic: sub.topic().to_string(),
                    log_time_ns: m.receive_time_ns.max(0) as u64,
                    publish_time_ns: m.source_time_ns.unwrap_or(m.receive_time_ns).max(0) as u64,
                    payload: m.payload,
                };
                if let Err(e) = session.push(&message) {
                    node.warn(format!("{e}"));
                    diagnostics.error(e.to_string());
                }
            }
        }
        if !running {
            if let Some(job) = session.due_job() {
                running = true;
                diagnostics.set_value("runs", job.info.run);
                let (model, options, tx) = (
                    Arc::clone(&session.setup.model),
                    session.setup.options.clone(),
                    tx.clone(),
                );
                std::thread::spawn(move || {
                    let _ = tx.send(run_job(&parameters::declared(&model), &options, job));
                });
            }
        }
        if let Ok((info, result)) = rx.try_recv() {
            running = false;
            let stamp = (info.to * 1e9) as i64;
            let out = session.outcome(&info, &result, stamp, &fqn);
            node.info(&out.summary);
            for f in &out.new_findings {
                node.warn(format!("new effect found: {f}"));
                diagnostics.warn(format!("new effect found: {f}"));
            }
            let _ = statuses_pub.publish(out.statuses);
            let _ = result_pub.publish(out.result);
            // the diagnosis was made in the worker's allocator arena and is freed here, after the
            // worker's trim: trim again, or what it held stays resident until the next run
            drop(result);
            metrocell_diagnose_node::session::release_freed_memory();
        }
        let w = &session.window;
        diagnostics.set_value("records_in_window", w.len());
        diagnostics.set_value("records_taken", w.taken);
        diagnostics.set_value("points_waiting_for_signals", session.stream.waiting());
        token.wait_timeout(Duration::from_millis(5));
    }
    node.info(format!(
        "stopping: {} records taken, {} in the window",
        session.window.taken,
        session.window.len()
    ));
    Ok(())
}

fn replay(node: OfflineNode, args: &ReplayArgs) -> Result<(), Box<dyn std::error::Error>> {
    let setup = parameters::setup(node.parameters(), &|t| {
        node.resolve_topic(t).map_err(|e| e.to_string())
    })?;
    for line in &setup.describe {
        node.logger().info(line);
    }
    let mut source = BagSource::open(&args.bag)?;
    let topics: Vec<(String, String)> = source
        .topics()
        .iter()
        .map(|t| (t.name.clone(), t.type_name.clone()))
        .collect();
    let model = Arc::clone(&setup.model);
    let forward = model.forward_model()?;
    let mut session = Session::new(setup, &forward, &args.bag, &topics)?;
    for topic in session.stream.topics() {
        source.subscribe_any(&topic);
    }
    let statuses_topic = node.resolve_topic("/diagnostics")?;
    let result_topic = node.resolve_topic("diagnose/result")?;
    let mut output = ReplayOutput::open(args.output.as_deref())?;
    output.advertise::<DiagnosticArray>(&statuses_topic)?;
    output.advertise::<StringMessage>(&result_topic)?;
    let fqn = node.fully_qualified_name();
    let run_and_write = |session: &mut Session,
                         log_time_ns: u64,
                         output: &mut ReplayOutput|
     -> Result<(), Box<dyn std::error::Error>> {
        let job = session.job();
        let (info, result) = run_job(&session.setup.declared(), &session.setup.options, job);
        let out = session.outcome(&info, &result, (info.to * 1e9) as i64, &fqn);
        node.logger().info(&out.summary);
        for f in &out.new_findings {
            node.logger().warn(format!("new effect found: {f}"));
        }
        output.write(&statuses_topic, &out.statuses, log_time_ns)?;
        output.write(&result_topic, &out.result, log_time_ns)?;
        Ok(())
    };
    let mut last_log_time = 0u64;
    let stopped = source.replay::<Box<dyn std::error::Error>>(
        || node.interrupted(),
        |m| {
            last_log_time = m.log_time_ns;
            session.push(&m)?;
            if session.window.due() {
                run_and_write(&mut session, m.log_time_ns, &mut output)?;
            }
            Ok(())
        },
    )?;
    // the end of the bag: measurements still waiting for signals are answered as they stand,
    // and the window is diagnosed once more if records came in since the last run
    session.flush();
    if stopped.is_none() && session.window.has_new_records() {
        run_and_write(&mut session, last_log_time, &mut output)?;
    }
    output.finish()?;
    node.logger().info(format!(
        "replayed {}: {} records taken, {} diagnoses",
        args.bag.display(),
        session.window.taken,
        session.runs()
    ));
    Ok(node.finish_replay(stopped)?)
}
