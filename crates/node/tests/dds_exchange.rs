//! DDS tests: two nodes (two participants) in one process exchange messages over loopback.
//! Must run inside a private network namespace: `tests/isolated cargo test -p metrocell-node`.

use std::time::{Duration, Instant};

use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::diagnostic_msgs::msg::DiagnosticArray;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_node::{qos, testing::require_isolated_network, MetrocellNode, ParamDecl, TopicInfo};

fn node(name: &str, argv: &[&str]) -> MetrocellNode {
    require_isolated_network();
    let mut full = vec!["test"];
    full.extend_from_slice(argv);
    let (b, _) = MetrocellNode::builder(name)
        .handle_signals(false)
        .args(full)
        .unwrap();
    b.build().unwrap()
}

/// Hand-written CDR (little-endian, with encapsulation header) of std_msgs/Header.
fn header_payload(sec: i32, nanosec: u32, frame: &str) -> Vec<u8> {
    let mut v = vec![0x00, 0x01, 0x00, 0x00];
    v.extend_from_slice(&sec.to_le_bytes());
    v.extend_from_slice(&nanosec.to_le_bytes());
    v.extend_from_slice(&((frame.len() + 1) as u32).to_le_bytes());
    v.extend_from_slice(frame.as_bytes());
    v.push(0);
    v
}

/// Repeat `publish` until `take` yields something or `timeout` passes (volatile QoS: samples sent
/// before discovery completes are lost, so keep sending).
fn exchange<T>(
    timeout: Duration,
    mut publish: impl FnMut(),
    mut take: impl FnMut() -> Option<T>,
) -> Option<T> {
    let start = Instant::now();
    let mut last_pub = None::<Instant>;
    while start.elapsed() < timeout {
        if last_pub.is_none_or(|t| t.elapsed() > Duration::from_millis(100)) {
            publish();
            last_pub = Some(Instant::now());
        }
        if let Some(x) = take() {
            return Some(x);
        }
        std::thread::sleep(Duration::from_millis(10));
    }
    None
}

#[test]
fn typed_publisher_to_typed_subscription_with_remap() {
    let mut a = node(
        "typed_talker",
        &["--ros-args", "-r", "chatter:=/metrocell_test/typed"],
    );
    let mut b = node("typed_listener", &[]);
    assert_eq!(a.resolve_topic("chatter").unwrap(), "/metrocell_test/typed");
    let p = a.publisher::<Header>("chatter", qos::reliable()).unwrap();
    let s = b
        .subscription::<Header>("/metrocell_test/typed", qos::reliable())
        .unwrap();
    let sent = Header {
        stamp: Time {
            sec: 12,
            nanosec: 345,
        },
        frame_id: "tracker".into(),
    };
    let got = exchange(
        Duration::from_secs(10),
        || {
            p.publish(sent.clone()).unwrap();
        },
        || s.take().unwrap().map(|(m, _)| m),
    );
    assert_eq!(got, Some(sent));
}

#[test]
fn raw_publisher_to_typed_subscription() {
    let mut a = node("raw_talker", &[]);
    let mut b = node("raw_to_typed_listener", &[]);
    let p = a
        .raw_publisher(
            "/metrocell_test/raw_in",
            "std_msgs/msg/Header",
            qos::reliable(),
        )
        .unwrap();
    let s = b
        .subscription::<Header>("/metrocell_test/raw_in", qos::reliable())
        .unwrap();
    let payload = header_payload(-3, 999_999_999, "cell");
    let got = exchange(
        Duration::from_secs(10),
        || p.publish(&payload).unwrap(),
        || s.take().unwrap().map(|(m, _)| m),
    );
    assert_eq!(
        got,
        Some(Header {
            stamp: Time {
                sec: -3,
                nanosec: 999_999_999
            },
            frame_id: "cell".into()
        })
    );
    // A payload without the CDR_LE header is refused with a message naming the topic.
    let e = p
        .publish(&[0, 0, 0, 0, 1, 2, 3, 4])
        .unwrap_err()
        .to_string();
    assert!(
        e.contains("/metrocell_test/raw_in") && e.contains("little-endian"),
        "{e}"
    );
}

#[test]
fn typed_publisher_to_raw_subscription() {
    let mut a = node("typed_to_raw_talker", &[]);
    let mut b = node("raw_listener", &[]);
    let p = a
        .publisher::<Header>("/metrocell_test/raw_out", qos::reliable())
        .unwrap();
    let s = b
        .raw_subscription(
            "/metrocell_test/raw_out",
            "std_msgs/msg/Header",
            qos::reliable(),
        )
        .unwrap();
    let before = metrocell_node::logging::system_time_ns();
    let msg = Header {
        stamp: Time { sec: 7, nanosec: 8 },
        frame_id: "probe".into(),
    };
    let got = exchange(
        Duration::from_secs(10),
        || p.publish(msg.clone()).unwrap(),
        || s.take().unwrap(),
    )
    .expect("no raw message");
    let expected = header_payload(7, 8, "probe");
    // RustDDS may pad the body to a multiple of 4; the message itself must match byte for byte.
    assert_eq!(&got.payload[..expected.len()], &expected[..]);
    assert!(
        got.payload.len() - expected.len() < 4,
        "unexpected trailing bytes: {:?}",
        got.payload
    );
    assert_eq!(got.publisher_gid, p.gid());
    let stamp = got.source_time_ns.expect("source timestamp");
    assert!(
        stamp >= before - 1_000_000 && stamp <= got.receive_time_ns + 1_000_000,
        "stamp {stamp} before {before}"
    );
}

#[test]
fn discovered_topics_and_diagnostics_heartbeat() {
    let mut a = node(
        "listed_talker",
        &["--ros-args", "-r", "__ns:=/metrocell_test"],
    );
    assert_eq!(a.fully_qualified_name(), "/metrocell_test/listed_talker");
    a.diagnostics().set_value("answer", 42);
    a.diagnostics().warn("testing");
    let p = a.publisher::<Header>("listing", qos::reliable()).unwrap();
    let mut b = node("lister", &[]);
    let s = b
        .subscription::<DiagnosticArray>("/diagnostics", qos::reliable())
        .unwrap();

    let start = Instant::now();
    let mut topics: Vec<TopicInfo> = Vec::new();
    let mut heartbeat = None;
    while start.elapsed() < Duration::from_secs(10)
        && (heartbeat.is_none() || !topics.iter().any(|t| t.name == "/metrocell_test/listing"))
    {
        let _ = p.publish(Header::default());
        topics = b.discovered_topics();
        while let Some((m, _)) = s.take().unwrap() {
            if let Some(st) = m
                .status
                .iter()
                .find(|st| st.name == "/metrocell_test/listed_talker")
            {
                heartbeat = Some(st.clone());
            }
        }
        std::thread::sleep(Duration::from_millis(50));
    }
    assert!(
        topics.contains(&TopicInfo {
            name: "/metrocell_test/listing".into(),
            type_name: "std_msgs/msg/Header".into()
        }),
        "{topics:?}"
    );
    let settled = b.discovered_topics_settled(Duration::from_millis(300), Duration::from_secs(3));
    assert!(
        settled.iter().any(|t| t.name == "/metrocell_test/listing"),
        "{settled:?}"
    );
    assert!(topics.contains(&TopicInfo {
        name: "/diagnostics".into(),
        type_name: "diagnostic_msgs/msg/DiagnosticArray".into()
    }));
    let hb = heartbeat.expect("no heartbeat from /metrocell_test/listed_talker within 10 s");
    assert_eq!((hb.level, hb.message.as_str()), (1, "testing"));
    assert!(hb
        .values
        .iter()
        .any(|kv| kv.key == "answer" && kv.value == "42"));
}

#[test]
fn parameters_from_command_line_and_clean_shutdown() {
    let decls = vec![
        ParamDecl::new("rate_hz", 10.0, "rate").with_range(0.1, 100.0),
        ParamDecl::new("label", "x", "label"),
    ];
    let (b, rest) = MetrocellNode::builder("param_node")
        .handle_signals(false)
        .params(decls)
        .args([
            "prog",
            "input",
            "--ros-args",
            "-p",
            "rate_hz:=25",
            "-p",
            "label:=cell_a",
            "--",
            "-v",
        ])
        .unwrap();
    require_isolated_network();
    assert_eq!(rest, vec!["prog", "input", "-v"]);
    let n = b.build().unwrap();
    assert_eq!(n.param::<f64>("rate_hz").unwrap(), 25.0);
    assert_eq!(n.param::<String>("label").unwrap(), "cell_a");
    assert!(!n.param::<bool>("use_sim_time").unwrap());
    // Remote-style sets go through the declarations: out of range is refused, in range is seen.
    let mut n = n;
    let mut watch = n.watch_param::<f64>("rate_hz").unwrap();
    assert_eq!(
        watch.poll(|name| n.param(name)).unwrap(),
        None,
        "no change yet"
    );
    let e = n
        .ros_node()
        .set_parameter(
            "rate_hz",
            metrocell_node::ParamValue::Double(500.0).to_ros(),
        )
        .unwrap_err();
    assert!(
        e.contains("rate_hz") && e.contains("[0.1, 100]") && e.contains("set_parameters"),
        "{e}"
    );
    n.ros_node()
        .set_parameter("rate_hz", metrocell_node::ParamValue::Double(50.0).to_ros())
        .unwrap();
    assert_eq!(n.param::<f64>("rate_hz").unwrap(), 50.0);
    assert_eq!(
        watch.poll(|name| n.param(name)).unwrap(),
        Some(50.0),
        "the watch sees the change once"
    );
    assert_eq!(watch.poll(|name| n.param(name)).unwrap(), None);
    assert!(
        n.set_param("rate_hz", 0.01)
            .unwrap_err()
            .contains("[0.1, 100]"),
        "set_param is checked too"
    );
    n.set_param("rate_hz", 60.0).unwrap();
    assert_eq!(watch.poll(|name| n.param(name)).unwrap(), Some(60.0));
    assert_eq!(
        n.parameters().get::<f64>("rate_hz").unwrap(),
        25.0,
        "start-up resolution is kept"
    );
    let token = n.shutdown_token();
    let t0 = Instant::now();
    drop(n);
    assert!(
        t0.elapsed() < Duration::from_secs(1),
        "drop took {:?}",
        t0.elapsed()
    );
    assert!(token.is_triggered());
}

#[test]
fn sim_time_follows_clock_topic() {
    use metrocell_msgs::rosgraph_msgs::msg::Clock;
    let n = node("sim_timed", &["--ros-args", "-p", "use_sim_time:=true"]);
    assert!(n.use_sim_time());
    assert_eq!(
        n.now().to_nanos(),
        0,
        "before the first /clock message time is zero, as in rclcpp"
    );
    let mut sim = node("clock_source", &[]);
    let p = sim
        .publisher::<Clock>("/clock", qos::sensor_data())
        .unwrap();
    let t = Clock {
        clock: Time {
            sec: 1000,
            nanosec: 500,
        },
    };
    let got = exchange(
        Duration::from_secs(10),
        || p.publish(t.clone()).unwrap(),
        || Some(n.now().to_nanos()).filter(|&ns| ns != 0),
    );
    assert_eq!(got, Some(1_000_000_000_500));
}

/// Issue 32: every node reads `/clock` (ros2-client's Spinner keeps a sim-time reader, and
/// `use_sim_time` adds the node's own) as `rosgraph_msgs/msg/Clock`, the one type ROS 2 tools
/// expect there — never `builtin_interfaces/msg/Time`, which made `topic list -t` show two types.
#[test]
fn clock_is_advertised_as_rosgraph_clock_only() {
    let _plain = node("clock_reader_plain", &[]);
    let _sim = node(
        "clock_reader_sim",
        &["--ros-args", "-p", "use_sim_time:=true"],
    );
    let observer = node("clock_observer", &[]);
    let start = Instant::now();
    let clock_types = |topics: Vec<TopicInfo>| {
        topics
            .into_iter()
            .filter(|t| t.name == "/clock")
            .map(|t| t.type_name)
            .collect::<Vec<_>>()
    };
    while start.elapsed() < Duration::from_secs(10)
        && clock_types(observer.discovered_topics()).is_empty()
    {
        std::thread::sleep(Duration::from_millis(50));
    }
    let types = clock_types(
        observer.discovered_topics_settled(Duration::from_millis(1000), Duration::from_secs(5)),
    );
    assert_eq!(
        types,
        ["rosgraph_msgs/msg/Clock"],
        "the types other participants read /clock as"
    );
}

/// The example talker exits cleanly within a second of SIGINT and of SIGTERM.
#[test]
fn example_talker_stops_on_signals_within_one_second() {
    require_isolated_network();
    // Examples are built by `cargo test` next to the test binaries: target/<profile>/examples/.
    let exe = std::env::current_exe().unwrap();
    let talker = exe
        .parent()
        .unwrap()
        .parent()
        .unwrap()
        .join("examples")
        .join("talker");
    assert!(
        talker.exists(),
        "{} not built: run the whole `cargo test -p metrocell-node`, which builds the examples",
        talker.display()
    );
    for signal in ["-INT", "-TERM"] {
        let mut child = std::process::Command::new(&talker)
            .args([
                "--ros-args",
                "-p",
                "rate_hz:=20",
                "-r",
                "__node:=signal_talker",
            ])
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(1500));
        assert!(child.try_wait().unwrap().is_none(), "talker exited early");
        let t0 = Instant::now();
        assert!(std::process::Command::new("kill")
            .args([signal, &child.id().to_string()])
            .status()
            .unwrap()
            .success());
        let status = loop {
            if let Some(s) = child.try_wait().unwrap() {
                break s;
            }
            assert!(
                t0.elapsed() < Duration::from_secs(1),
                "talker still running 1 s after SIG{}",
                &signal[1..]
            );
            std::thread::sleep(Duration::from_millis(10));
        };
        let mut err = String::new();
        std::io::Read::read_to_string(child.stderr.as_mut().unwrap(), &mut err).unwrap();
        assert!(status.success(), "exit {status:?}; stderr:\n{err}");
        assert!(
            err.contains("[INFO]") && err.contains("[signal_talker]: shutting down"),
            "{err}"
        );
    }
}

#[test]
fn log_messages_reach_rosout() {
    let a = node("logger", &["--ros-args", "-r", "__ns:=/metrocell_test"]);
    let mut b = node("rosout_reader", &[]);
    let s = b
        .raw_subscription("/rosout", "rcl_interfaces/msg/Log", qos::reliable())
        .unwrap();
    let got = exchange(
        Duration::from_secs(10),
        || a.warn("calibration drift 12 um"),
        || loop {
            match s.take().unwrap() {
                Some(m)
                    if m.payload
                        .windows(23)
                        .any(|w| w == b"calibration drift 12 um") =>
                {
                    break Some(m)
                }
                Some(_) => continue,
                None => break None,
            }
        },
    )
    .expect("no /rosout message from the logger node");
    // rcl_interfaces/Log: stamp (8 bytes), level (byte) = WARN (30), then name = rcl logger name.
    assert_eq!(got.payload[4 + 8], 30);
    assert!(got
        .payload
        .windows(20)
        .any(|w| w == b"metrocell_test.logge"));
}

#[test]
fn a_parameter_set_through_the_set_parameters_service_is_seen_by_a_watch() {
    require_isolated_network();
    let decls = vec![
        ParamDecl::new("flag", false, "a trigger"),
        ParamDecl::new("rate_hz", 10.0, "rate").with_range(0.1, 100.0),
    ];
    let target = MetrocellNode::builder("remote_param_target")
        .handle_signals(false)
        .diagnostics_period(None)
        .params(decls)
        .build()
        .unwrap();
    let mut flag = target.watch_param::<bool>("flag").unwrap();
    let mut client = node("remote_param_client", &[]);
    metrocell_node::testing::set_remote_parameter(
        &mut client,
        "/remote_param_target",
        "flag",
        true.into(),
        Duration::from_secs(20),
    )
    .unwrap();
    assert_eq!(flag.poll(|n| target.param(n)).unwrap(), Some(true));
    let e = metrocell_node::testing::set_remote_parameter(
        &mut client,
        "/remote_param_target",
        "rate_hz",
        500.0.into(),
        Duration::from_secs(20),
    )
    .unwrap_err();
    assert!(
        e.contains("rate_hz") && e.contains("[0.1, 100]"),
        "refused with the declaration's reason: {e}"
    );
    assert_eq!(target.param::<f64>("rate_hz").unwrap(), 10.0);
}
