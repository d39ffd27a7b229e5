//! `metrocell-sim`: the digital twin's sensor streams published live over DDS, at real time ×
//! `speed`, on the topics of `metrocell_simulation::topic_map` (the same bytes `metrocell sim` writes
//! into a bag). `/clock` is published `clock_rate` times per wall-clock second so other nodes
//! can run with `use_sim_time:=true`.
//!
//!   metrocell-sim --ros-args -p cell:=crates/twin/examples/cells/xfyz_shift.yaml \
//!       -p duration:=8h -p speed:=60 -p seed:=7
//!
//! With `wait_for_recorder`, the first message waits until the node named `recorder_node`
//! (default `recorder`) subscribes to every topic.
//! The messages published per topic are in the diagnostics (`published/<topic>`) and the last
//! log line, so a recording can be checked against them. At the end of a run the twin waits
//! (up to 30 s) until every reliable subscriber has acknowledged every message, then reports
//! `finished`.
//!
//! Exits 0 when the run ends (unless `loop`) or on Ctrl-C / SIGTERM.

mod parameters;
mod publishing;

/// How long a finished run waits for reliable subscribers to acknowledge its last messages:
/// ample for a reader a few seconds behind on a loaded machine, short enough that a reader
/// that has hung does not hold the twin up.
const ACKNOWLEDGMENT_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(30);

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-sim: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (mut node, _) =
        metrocell_node::MetrocellNode::from_env_args("sim", parameters::declarations())?;
    let settings = parameters::settings(&node)?;
    let mut sim = publishing::LiveSim::new(&mut node, &settings)?;
    node.info(format!(
        "simulating {} for {} s (seed {}) at {}x real time{}",
        settings.cell,
        settings.duration,
        settings.seed,
        settings.pacer.speed(),
        if settings.repeat { ", looping" } else { "" }
    ));
    let start_delay = node.param::<f64>("start_delay")?;
    if start_delay > 0.0
        && node
            .shutdown_token()
            .wait_timeout(std::time::Duration::from_secs_f64(start_delay))
    {
        return Ok(());
    }
    let wait_for_recorder = node.param::<f64>("wait_for_recorder")?;
    if wait_for_recorder > 0.0 {
        let recorder = node.param::<String>("recorder_node")?;
        if sim.wait_for_recorder(
            &node,
            &recorder,
            std::time::Duration::from_secs_f64(wait_for_recorder),
        )? {
            node.info(format!(
                "the recorder '{recorder}' subscribes to every topic: starting"
            ));
        } else if node.shutdown_token().is_triggered() {
            return Ok(());
        } else {
            node.warn(format!("the recorder '{recorder}' did not subscribe to every topic within {wait_for_recorder} s: starting anyway"));
        }
    }
    let finished = sim.run(&node, &settings)?;
    if finished {
        // The counts say "finished" only once every reliable reader holds every message (the
        // demo stops the recorder when it reads them).
        let unacknowledged = sim.wait_for_acknowledgments(ACKNOWLEDGMENT_TIMEOUT);
        if !unacknowledged.is_empty() {
            node.warn(format!(
                "after {} s some reliable subscriber still had not acknowledged every message on {}: a reader that slow may miss the end of the run",
                ACKNOWLEDGMENT_TIMEOUT.as_secs(),
                unacknowledged.join(", ")
            ));
        }
    }
    sim.report_counts(finished);
    let per_topic: Vec<String> = sim
        .published_per_topic()
        .iter()
        .map(|(t, n)| format!("{t} {n}"))
        .collect();
    if finished {
        node.info(format!(
            "simulation finished: {} messages published (per topic, /clock included: {})",
            sim.published(),
            per_topic.join(", ")
        ));
        // Let reliable subscribers acknowledge the last samples, and the final diagnostics
        // (published every second) go out, before the writers go away.
        node.shutdown_token()
            .wait_timeout(std::time::Duration::from_millis(1500));
    } else {
        node.info(format!(
            "shutting down; published per topic: {}",
            per_topic.join(", ")
        ));
    }
    Ok(())
}
