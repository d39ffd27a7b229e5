//! `metrocell-dashboard`: the live dashboard of a cell, in a browser and in Foxglove.
//!
//! Reads every published topic (raw CDR; see `ingest`) and shows on a web page served on
//! localhost: the volumetric error per axis of `measured_points` and
//! `measured_points/thermal_compensated` with its drift rate, temperatures (`temperature/*`),
//! tracker status (`tracker/measurements`), the error models (`thermal/error_model`,
//! `estimator/error_model`) with σ, findings from `/diagnostics` (statuses named `diagnose…`)
//! and alerts. Alerts (thresholds on the predicted error [µm] and drift rate [µm/h]) are also
//! published on `/diagnostics`. The same topics are served over the Foxglove WebSocket protocol.
//!
//!   metrocell-dashboard --ros-args -p port:=8765 -p foxglove_port:=8766 -p error_warn_um:=20.0
//!
//! Works on a replayed bag (`metrocell bag play --clock`): times are message stamps and `/clock`.

mod foxglove_bridge;
mod ingest;
mod parameters;
mod routes;
mod web;

use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use metrocell_dashboard_state::alerts::to_statuses;
use metrocell_dashboard_state::{DashboardState, Level};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::{qos, MetrocellNode};

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-dashboard: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (mut node, _) = MetrocellNode::from_env_args("dashboard", parameters::declarations())?;
    let state = Arc::new(Mutex::new(DashboardState::new(parameters::state_config(
        node.parameters(),
    )?)));
    let address = node.param::<String>("bind_address")?;
    let port = u16::try_from(node.param::<i64>("port")?)?;
    let foxglove_port = node.param::<i64>("foxglove_port")?;

    let runtime = tokio::runtime::Builder::new_multi_thread()
        .worker_threads(2)
        .enable_all()
        .thread_name("dashboard-web")
        .build()?;
    let token = node.shutdown_token();
    let stop = token.clone();
    let (web_address, web_task) = runtime.block_on(web::serve(
        &address,
        port,
        state.clone(),
        Duration::from_secs_f64(node.param::<f64>("push_period")?),
        async move { stop.triggered().await },
    ))?;
    node.info(format!(
        "dashboard at http://{web_address}/ (state: /api/state, updates: /ws)"
    ));
    let mut bridge = match u16::try_from(foxglove_port) {
        Ok(p) => {
            let b = foxglove_bridge::FoxgloveBridge::start(runtime.handle(), &address, p)?;
            node.info(format!("Foxglove WebSocket at ws://{address}:{}", b.port()));
            Some(b)
        }
        Err(_) => None,
    };

    let alerts_pub = node.publisher::<DiagnosticArray>("/diagnostics", qos::reliable())?;
    let alert_period = Duration::from_secs_f64(node.param::<f64>("alert_period")?);
    let mut next_alert = Instant::now() + alert_period;
    let mut ingest = ingest::Ingest::new(routes::Routes::from_node(&node)?);
    let diagnostics = node.diagnostics();
    let fqn = node.fully_qualified_name();
    while !token.is_triggered() {
        ingest.scan(&mut node, bridge.as_mut())?;
        let received = ingest.drain(&state, bridge.as_ref(), &node);
        if Instant::now() >= next_alert {
            next_alert += alert_period;
            let (alerts, stamp) = {
                let s = state.lock().unwrap_or_else(|p| p.into_inner());
                (s.alerts(), s.cell_time())
            };
            if !alerts.is_empty() {
                let stamp_ns =
                    stamp.map_or_else(|| node.now().to_nanos(), |t| (t * 1e9).round() as i64);
                let _ = alerts_pub.publish(DiagnosticArray {
                    header: Header {
                        stamp: Time::from_nanos(stamp_ns),
                        frame_id: String::new(),
                    },
                    status: to_statuses(&fqn, &alerts),
                });
            }
            let worst = alerts.iter().map(|a| a.level).max().unwrap_or(Level::Ok);
            let words = alerts
                .iter()
                .filter(|a| a.level != Level::Ok)
                .map(|a| a.message.clone())
                .collect::<Vec<_>>()
                .join("; ");
            match worst {
                Level::Ok => diagnostics.ok("serving"),
                Level::Warn => diagnostics.warn(words),
                Level::Error => diagnostics.error(words),
            }
        }
        if received == 0 {
            token.wait_timeout(Duration::from_millis(5));
        }
    }
    drop(bridge);
    let _ = runtime.block_on(web_task);
    Ok(())
}
