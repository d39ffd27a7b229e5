//! The dashboard node on a live simulated cell (metrocell-sim on quick_demo, the thermal node,
//! a peer publishing measured points with a known drift), all inside the isolation guard:
//! - `/api/state` reports the drift rate the peer put in, within its stated uncertainty, and the
//!   drift alert is raised on the page and on `/diagnostics`;
//! - headless Chromium (Debian's `chromium`, DevTools protocol) opens the page, sees live values
//!   change, finds no console errors, measures first paint and update latency, saves a screenshot
//!   to target/test-artifacts/dashboard/;
//! - a Foxglove WebSocket client receives the advertised channels with ros2msg schemas and
//!   decodes a message of every live topic with rosbags from those schemas.
//!
//! Each test runs its own cell on its own ROS_DOMAIN_ID so the two never see each other.

use std::io::{BufRead, BufReader, Read, Write};
use std::path::PathBuf;
use std::process::Command;
use std::sync::mpsc;
use std::time::{Duration, Instant};

use serde_json::Value;
use system_tests::{
    bin, piped, points_ramp, python, require_isolated_network, run, workspace_root, ChildGuard,
};

const CHROMIUM: &str = "/usr/bin/chromium";

struct Cell {
    _processes: Vec<ChildGuard>,
    web_port: u16,
    foxglove_port: u16,
    domain: &'static str,
}

fn node(name: &str, domain: &str) -> Command {
    let mut c = piped(bin(name));
    c.env("ROS_DOMAIN_ID", domain);
    c
}

/// Start the cell and the dashboard; wait for both ports from the dashboard's log.
fn start_cell(domain: &'static str) -> Cell {
    let root = workspace_root();
    let cell = root.join("crates/twin/examples/cells/quick_demo.yaml");
    let mut processes = Vec::new();
    let mut dashboard = node("metrocell-dashboard", domain);
    dashboard.args([
        "--ros-args",
        "-p",
        "port:=0",
        "-p",
        "foxglove_port:=0",
        "-p",
        "push_period:=0.2",
    ]);
    let mut d = ChildGuard::spawn(&mut dashboard);
    let stderr = d.child().stderr.take().unwrap();
    let (tx, rx) = mpsc::channel();
    std::thread::spawn(move || {
        for line in BufReader::new(stderr).lines().map_while(Result::ok) {
            let _ = tx.send(line);
        }
    });
    processes.push(d);
    processes.push(ChildGuard::spawn(node("metrocell-sim", domain).args([
        "--ros-args",
        "-p",
        &format!("cell:={}", cell.display()),
        "-p",
        "speed:=20",
        "-p",
        "duration:=2h",
        "-p",
        "camera_images:=false",
        "-p",
        "start_delay:=1.0",
    ])));
    processes.push(ChildGuard::spawn(
        node("metrocell-thermal", domain).args([
            "--ros-args",
            "--params-file",
            root.join("launch-configs/thermal.params.yaml")
                .to_str()
                .unwrap(),
        ]),
    ));
    processes.push(ChildGuard::spawn(node("points_ramp_peer", domain).args([
        "--ros-args",
        "-p",
        "rate_hz:=10.0",
    ])));
    let (mut web_port, mut foxglove_port) = (None, None);
    let deadline = Instant::now() + Duration::from_secs(30);
    let mut log = Vec::new();
    while (web_port.is_none() || foxglove_port.is_none()) && Instant::now() < deadline {
        let Ok(line) = rx.recv_timeout(Duration::from_millis(200)) else {
            continue;
        };
        let port_after = |marker: &str| {
            line.split(marker).nth(1).and_then(|r| {
                r.split(|c: char| !c.is_ascii_digit())
                    .next()?
                    .parse::<u16>()
                    .ok()
            })
        };
        web_port = web_port.or(port_after("dashboard at http://127.0.0.1:"));
        foxglove_port = foxglove_port.or(port_after("Foxglove WebSocket at ws://127.0.0.1:"));
        log.push(line);
    }
    let (Some(web_port), Some(foxglove_port)) = (web_port, foxglove_port) else {
        panic!(
            "the dashboard did not report its ports within 30 s; its log:\n{}",
            log.join("\n")
        )
    };
    // the rest of the log goes to the test's output (shown on failure)
    std::thread::spawn(move || rx.into_iter().for_each(|l| eprintln!("dashboard: {l}")));
    Cell {
        _processes: processes,
        web_port,
        foxglove_port,
        domain,
    }
}

fn http_get(port: u16, path: &str) -> String {
    let mut s =
        std::net::TcpStream::connect(("127.0.0.1", port)).expect("connect to the dashboard");
    s.set_read_timeout(Some(Duration::from_secs(10))).unwrap();
    write!(
        s,
        "GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\nConnection: close\r\n\r\n"
    )
    .unwrap();
    let mut response = String::new();
    s.read_to_string(&mut response).unwrap();
    let (head, body) = response.split_once("\r\n\r\n").expect("an HTTP response");
    assert!(head.starts_with("HTTP/1.1 200"), "GET {path}: {head}");
    body.to_string()
}

/// Poll `/api/state` until `ready` holds for its `state` (at most `timeout`); returns that state.
fn state_when(port: u16, timeout: Duration, ready: impl Fn(&Value) -> bool) -> Value {
    let deadline = Instant::now() + timeout;
    loop {
        let body: Value =
            serde_json::from_str(&http_get(port, "/api/state")).expect("/api/state is JSON");
        let v = body["state"].clone();
        if ready(&v) || Instant::now() > deadline {
            return v;
        }
        std::thread::sleep(Duration::from_millis(300));
    }
}

fn artifacts() -> PathBuf {
    // target/<profile>/deps/<test> → target/test-artifacts/dashboard
    let exe = std::env::current_exe().unwrap();
    let dir = exe
        .ancestors()
        .nth(3)
        .unwrap()
        .join("test-artifacts/dashboard");
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

#[test]
fn drift_alert_and_the_page_in_headless_chromium() {
    require_isolated_network();
    let cell = start_cell("61");
    let has = |v: &Value, topic: &str| v["messages"][topic].as_u64().unwrap_or(0) > 0;
    let state = state_when(cell.web_port, Duration::from_secs(90), |v| {
        [
            "/clock",
            "/temperature/x_left",
            "/tracker/measurements",
            "/thermal/error_model",
        ]
        .iter()
        .all(|t| has(v, t))
            && v["volumetric"][0]["window_span"].as_f64().unwrap_or(0.0) >= 3599.0
    });
    // The peer's x error drifts 36 µm/h with ±0.5 µm alternating noise; y is constant.
    let raw = state["volumetric"]
        .as_array()
        .unwrap()
        .iter()
        .find(|s| s["topic"] == "/measured_points")
        .expect("/measured_points stream");
    let (dx, sx) = (
        raw["axes"][0]["drift"].as_f64().unwrap() * 3.6e9,
        raw["axes"][0]["drift_sigma"].as_f64().unwrap() * 3.6e9,
    );
    let (dy, sy) = (
        raw["axes"][1]["drift"].as_f64().unwrap() * 3.6e9,
        raw["axes"][1]["drift_sigma"].as_f64().unwrap() * 3.6e9,
    );
    println!(
        "drift x {dx:.3} ± {sx:.3} µm/h, y {dy:.3} ± {sy:.3} µm/h over {} s",
        raw["window_span"]
    );
    assert!(
        (dx - points_ramp::X_RATE_UM_PER_H).abs() <= 3.0 * sx.max(1e-3) && sx < 1.0,
        "x drift {dx} ± {sx} µm/h, expected {}",
        points_ramp::X_RATE_UM_PER_H
    );
    assert!(
        dy.abs() <= 1e-6,
        "y drift {dy} µm/h, expected 0 (constant error)"
    );
    let alert = state["alerts"]
        .as_array()
        .unwrap()
        .iter()
        .find(|a| a["name"] == "drift_rate /measured_points")
        .expect("drift alert");
    assert_eq!(
        alert["level"], "ERROR",
        "36 µm/h is above drift_error_um_per_h = 30: {alert}"
    );
    assert!(state["temperatures"]
        .as_array()
        .unwrap()
        .iter()
        .any(|t| t["sensor"] == "x_left" && (10.0..40.0).contains(&t["value"].as_f64().unwrap())));
    let thermal = state["error_models"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["topic"] == "/thermal/error_model")
        .expect("thermal model");
    assert!(
        thermal["parameters"][0]["sigma"].as_f64().unwrap() > 0.0,
        "the model is shown with its σ: {thermal}"
    );

    // The same alert on /diagnostics, as a DiagnosticStatus with level ERROR (2).
    let out = run(
        piped(bin("metrocell"))
            .env("ROS_DOMAIN_ID", cell.domain)
            .args([
                "topic",
                "echo",
                "/diagnostics",
                "--type",
                "diagnostic_msgs/msg/DiagnosticArray",
                "--json",
                "--count",
                "12",
            ]),
        Duration::from_secs(60),
    );
    assert!(
        out.status.success(),
        "topic echo: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let statuses: Vec<Value> = String::from_utf8_lossy(&out.stdout)
        .lines()
        .filter_map(|l| serde_json::from_str::<Value>(l).ok())
        .flat_map(|a| a["status"].as_array().cloned().unwrap_or_default())
        .collect();
    let published = statuses
        .iter()
        .find(|s| s["name"] == "/dashboard: drift_rate /measured_points")
        .expect("the drift alert on /diagnostics");
    assert_eq!(published["level"].as_u64(), Some(2), "{published}");
    assert_eq!(published["values"][0]["key"], "value [m/s]");

    assert!(std::path::Path::new(CHROMIUM).exists(), "{CHROMIUM} is missing: install Debian's chromium (`apt-get install chromium`; tests/run does it as root)");
    let shot = artifacts().join("dashboard.png");
    let _ = std::fs::remove_file(&shot);
    let out = run(
        piped(python())
            .arg(workspace_root().join("tests/py/dashboard_browser.py"))
            .arg(CHROMIUM)
            .arg(format!("http://127.0.0.1:{}/", cell.web_port))
            .arg(&shot)
            .args(["--watch", "6"]),
        Duration::from_secs(120),
    );
    assert!(
        out.status.success(),
        "browser driver failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&out.stdout).expect("driver prints JSON");
    let (first, second) = (&r["first"], &r["second"]);
    assert_eq!(
        r["console_errors"],
        serde_json::json!([]),
        "console errors: {}",
        r["console_errors"]
    );
    assert_eq!(second["page_errors"], serde_json::json!([]));
    assert_eq!(second["connection"], "live");
    // live: cell time advances, the tracker count grows, the page received several pushes
    assert_ne!(
        first["cell_time"], second["cell_time"],
        "cell time did not change on the page"
    );
    assert_ne!(first["cell_time"], "—");
    let count = |v: &Value| {
        v["tracker_count"]
            .as_str()
            .and_then(|s| s.parse::<u64>().ok())
            .unwrap_or(0)
    };
    assert!(
        count(second) > count(first),
        "tracker measurements did not grow: {} → {}",
        count(first),
        count(second)
    );
    assert!(
        second["updates"].as_u64().unwrap() >= first["updates"].as_u64().unwrap() + 10,
        "too few updates: {first} {second}"
    );
    assert!(second["temperatures"].as_array().unwrap().len() >= 2);
    assert!(
        second["drifts"]
            .as_array()
            .unwrap()
            .iter()
            .any(|d| d.as_str().unwrap().starts_with("+36.")),
        "drift shown: {}",
        second["drifts"]
    );
    assert!(second["alerts"].as_array().unwrap().iter().any(|a| a
        .as_str()
        .unwrap()
        .starts_with("ERROR · drift_rate /measured_points")));
    assert!(
        second["parameters"]
            .as_array()
            .unwrap()
            .iter()
            .any(|p| p.as_str().unwrap().contains('±')),
        "model with σ: {}",
        second["parameters"]
    );
    // responsiveness
    let fcp = second["fcp_ms"].as_f64().expect("first contentful paint");
    let mut lat: Vec<f64> = second["latencies_ms"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap())
        .collect();
    lat.sort_by(f64::total_cmp);
    let (p50, p95) = (lat[lat.len() / 2], lat[(lat.len() * 95) / 100]);
    println!(
        "first contentful paint {fcp:.0} ms, first update rendered {:.0} ms after navigation start, update latency p50 {p50:.1} ms p95 {p95:.1} ms over {} updates",
        second["first_update_ms"].as_f64().unwrap(),
        lat.len()
    );
    assert!(fcp < 3000.0, "first contentful paint {fcp} ms");
    assert!(p50 < 500.0, "update latency p50 {p50} ms");
    let png = std::fs::read(&shot).expect("screenshot written");
    assert!(
        png.starts_with(b"\x89PNG") && png.len() > 20_000,
        "screenshot of {} bytes",
        png.len()
    );
    println!("screenshot: {}", shot.display());
}

#[test]
fn foxglove_client_receives_channels_with_schemas_and_decodes_messages() {
    require_isolated_network();
    let cell = start_cell("62");
    let has = |v: &Value, topic: &str| v["messages"][topic].as_u64().unwrap_or(0) > 0;
    let topics = [
        "/clock",
        "/temperature/x_left",
        "/tracker/measurements",
        "/measured_points",
        "/thermal/error_model",
        "/machine/joint_states",
    ];
    // wait until the dashboard reads them all (it advertises what it reads)
    state_when(cell.web_port, Duration::from_secs(60), |v| {
        topics[..5].iter().all(|t| has(v, t))
    });
    let out = run(
        piped(python())
            .arg(workspace_root().join("tests/py/foxglove_client.py"))
            .arg(format!("ws://127.0.0.1:{}", cell.foxglove_port))
            .args(topics)
            .args(["--timeout", "30"]),
        Duration::from_secs(60),
    );
    assert!(
        out.status.success(),
        "foxglove client failed: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    let r: Value = serde_json::from_slice(&out.stdout).expect("client prints JSON");
    assert_eq!(r["server"], "metrocell-dashboard");
    let types = [
        ("/clock", "rosgraph_msgs/msg/Clock"),
        ("/temperature/x_left", "sensor_msgs/msg/Temperature"),
        (
            "/tracker/measurements",
            "metrocell_msgs/msg/TrackerMeasurement",
        ),
        ("/measured_points", "metrocell_msgs/msg/MeasuredPoint"),
        ("/thermal/error_model", "metrocell_msgs/msg/ErrorModel"),
        ("/machine/joint_states", "sensor_msgs/msg/JointState"),
    ];
    for (topic, ty) in types {
        let ch = &r["channels"][topic];
        assert_eq!(
            (
                ch["encoding"].as_str(),
                ch["schemaName"].as_str(),
                ch["schemaEncoding"].as_str()
            ),
            (Some("cdr"), Some(ty), Some("ros2msg")),
            "{topic}: {ch}"
        );
        assert!(
            r["messages"][topic].is_object(),
            "no message received on {topic}: {}",
            r["messages"]
        );
    }
    let m = &r["messages"];
    let temp = m["/temperature/x_left"]["fields"]["temperature"]
        .as_f64()
        .unwrap();
    assert!((10.0..40.0).contains(&temp), "x_left {temp} °C");
    assert!(
        m["/clock"]["fields"]["clock"]["sec"].as_i64().unwrap() > 1_000_000_000,
        "sim clock: {}",
        m["/clock"]
    );
    // the point decoded is the one the ramp generator made for its index and stamp, to a
    // picometre (the JSON's shortest round-trip decimals; the ramp's own σ is 0.5 µm)
    let p = &m["/measured_points"]["fields"];
    let k: i64 = p["point_id"]
        .as_str()
        .and_then(|id| id.strip_prefix('p'))
        .and_then(|k| k.parse().ok())
        .unwrap_or_else(|| panic!("point_id p<k>: {p}"));
    let stamp = &p["header"]["stamp"];
    assert_eq!(
        stamp["sec"].as_i64().unwrap() * 1_000_000_000 + stamp["nanosec"].as_i64().unwrap(),
        points_ramp::stamp_ns(k, points_ramp::DEFAULT_STEP),
        "stamp of p{k}"
    );
    let xyz = |v: &Value| ["x", "y", "z"].map(|a| v[a].as_f64().unwrap());
    let (nominal, measured) = (xyz(&p["nominal"]), xyz(&p["measured"]));
    let (want_nominal, want_measured) = (
        points_ramp::nominal(k),
        points_ramp::measured(k, points_ramp::DEFAULT_STEP),
    );
    for a in 0..3 {
        assert!(
            (nominal[a] - want_nominal[a]).abs() <= 1e-12
                && (measured[a] - want_measured[a]).abs() <= 1e-12,
            "p{k} axis {a}: nominal {} measured {} m decoded, the ramp made {} and {}",
            nominal[a],
            measured[a],
            want_nominal[a],
            want_measured[a]
        );
    }
    assert_eq!(p["source"], "simulation");
    let model = &m["/thermal/error_model"]["fields"];
    assert_eq!(model["term_ids"][0], "thermal_scale");
    assert_eq!(
        model["covariance"].as_array().unwrap().len(),
        model["values"].as_array().unwrap().len().pow(2)
    );
    let names = m["/machine/joint_states"]["fields"]["name"]
        .as_array()
        .unwrap();
    assert_eq!(
        names,
        &vec![Value::from("x"), Value::from("y"), Value::from("z")]
    );
}
