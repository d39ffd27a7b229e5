//! The web side (axum on tokio): `/` the page (self-contained HTML, served from the binary),
//! `/api/state` a JSON snapshot, `/ws` a WebSocket that pushes a snapshot every `push_period`
//! as `{"sent_unix_ms": …, "state": …}` (the page measures its update latency from it).

use std::net::SocketAddr;
use std::sync::{Arc, Mutex};
use std::time::Duration;

use axum::extract::ws::{Message, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::http::header;
use axum::response::{Html, IntoResponse, Response};
use axum::routing::get;
use axum::Router;
use metrocell_dashboard_state::DashboardState;
use tokio::sync::watch;

const PAGE: &str = include_str!("../assets/dashboard.html");

#[derive(Clone)]
struct Shared {
    state: Arc<Mutex<DashboardState>>,
    pushes: watch::Receiver<Arc<String>>,
}

fn unix_ms() -> f64 {
    std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0.0, |d| d.as_secs_f64() * 1e3)
}

fn snapshot_json(state: &Mutex<DashboardState>) -> String {
    let snapshot = state.lock().unwrap_or_else(|p| p.into_inner()).snapshot();
    serde_json::json!({ "sent_unix_ms": unix_ms(), "state": snapshot }).to_string()
}

/// Bind `address:port` and serve until `shutdown` resolves; returns the bound address.
pub async fn serve(
    address: &str,
    port: u16,
    state: Arc<Mutex<DashboardState>>,
    push_period: Duration,
    shutdown: impl std::future::Future<Output = ()> + Send + 'static,
) -> Result<(SocketAddr, tokio::task::JoinHandle<()>), String> {
    let listener = tokio::net::TcpListener::bind((address, port))
        .await
        .map_err(|e| format!("web page on {address}:{port}: {e}"))?;
    let bound = listener.local_addr().map_err(|e| e.to_string())?;
    let (tx, rx) = watch::channel(Arc::new(snapshot_json(&state)));
    let pusher_state = state.clone();
    tokio::spawn(async move {
        let mut tick = tokio::time::interval(push_period);
        tick.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Skip);
        loop {
            tick.tick().await;
            if tx.send(Arc::new(snapshot_json(&pusher_state))).is_err() {
                return;
            }
        }
    });
    let app = Router::new()
        .route("/", get(page))
        .route("/api/state", get(api_state))
        .route("/ws", get(ws))
        .with_state(Shared { state, pushes: rx });
    let task = tokio::spawn(async move {
        if let Err(e) = axum::serve(listener, app)
            .with_graceful_shutdown(shutdown)
            .await
        {
            eprintln!("metrocell-dashboard: web server stopped: {e}");
        }
    });
    Ok((bound, task))
}

async fn page() -> Html<&'static str> {
    Html(PAGE)
}

async fn api_state(State(s): State<Shared>) -> Response {
    (
        [(header::CONTENT_TYPE, "application/json")],
        snapshot_json(&s.state),
    )
        .into_response()
}

async fn ws(upgrade: WebSocketUpgrade, State(s): State<Shared>) -> Response {
    upgrade.on_upgrade(move |socket| push(socket, s.pushes))
}

/// Send the newest snapshot at once and then every time a new one is made; stop when the page
/// goes away. A slow page skips snapshots instead of queueing them (watch keeps only the newest).
async fn push(mut socket: WebSocket, mut pushes: watch::Receiver<Arc<String>>) {
    loop {
        let text = pushes.borrow_and_update().clone();
        if socket
            .send(Message::Text(text.as_str().into()))
            .await
            .is_err()
        {
            return;
        }
        tokio::select! {
            changed = pushes.changed() => if changed.is_err() { return },
            incoming = socket.recv() => match incoming {
                Some(Ok(Message::Close(_))) | None | Some(Err(_)) => return,
                Some(Ok(_)) => {}
            },
        }
    }
}
