//! DDS Security (issue 31, item 1): nodes secured from SROS2 keystores made by `metrocell
//! security`, through RustDDS's builtin plugins (PKI-DH authentication, permissions, AES-GCM),
//! with sros2's governance (no unauthenticated participant; discovery, liveliness, every RTPS
//! message and every payload encrypted; every topic read- and write-controlled).
//!
//! Checked, each against a positive control that shows the attacker's own side works:
//! - secured node processes exchange every metrocell message type, field for field (payloads of
//!   every size: RustDDS needed a patch for those not a multiple of 4 bytes long);
//! - on the wire, a passive eavesdropper finds the cell's payload nowhere in clear text (and the
//!   plain participants' everywhere);
//! - a participant without credentials, one whose certificate comes from another CA (a rogue
//!   keystore), and one whose certificate was altered can neither read nor inject on a protected
//!   topic; the secured node says why in its log (unprotected messages dropped, a handshake whose
//!   certificate does not verify, a participant with incompatible security turned down), the
//!   altered one refuses to start saying why;
//! - an enclave whose permissions name other topics only can neither read nor write the
//!   protected one (refused when it tries, naming the topic) and can use the ones it is granted;
//! - `ROS_SECURITY_STRATEGY=Enforce` refuses a node whose enclave is missing, Permissive runs it
//!   unsecured and says so;
//! - a secured Cyclone DDS peer (Debian's Cyclone DDS with its DDS-Security plugins,
//!   tests/secure_cyclone) and a secured metrocell node exchange messages both ways from the same
//!   keystore, and a Cyclone peer with a certificate of another CA reaches nothing (the vendored
//!   RustDDS needed three fixes for it: third_party/rustdds/README.metrocell.md).
//!
//! Every DDS process runs inside tests/isolated. Run:
//! `cargo build --workspace --bins && tests/isolated cargo test -p metrocell-system-tests --test security`

use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::time::Duration;

use metrocell_node::{DdsEnvironment, DiscoveryRange, MetrocellNode};
use metrocell_security::SecurityEnvironment;
use system_tests::roundtrip::roundtrip_every_type;
use system_tests::{
    bin, piped, python, require_isolated_network, ros2_peer, run, secure_cyclone_python,
    workspace_root, ChildGuard,
};

/// A scratch directory of this test process.
fn scratch(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("metrocell-security-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn metrocell_ok(args: &[&str]) -> String {
    let out = run(piped(bin("metrocell")).args(args), Duration::from_secs(60));
    let text = format!(
        "{}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out.status.success(), "metrocell {args:?} failed:\n{text}");
    text
}

/// A keystore for `domain` with these enclaves, made by `metrocell security`.
fn keystore(dir: &Path, domain: u16, enclaves: &[&str]) -> PathBuf {
    let ks = dir.join("keystore");
    let ks_s = ks.to_str().unwrap();
    metrocell_ok(&[
        "security",
        "create-keystore",
        ks_s,
        "--domain-id",
        &domain.to_string(),
    ]);
    for e in enclaves {
        metrocell_ok(&["security", "create-enclave", ks_s, e]);
    }
    ks
}

/// How a process joins the test's domain: secured with an enclave of a keystore, or plain.
enum Credentials<'a> {
    Secured {
        keystore: &'a Path,
        enclave: &'a str,
    },
    Plain,
}

/// `metrocell ARGS`, stopped (SIGINT) after `seconds`, in `domain` with `credentials`.
fn metrocell_for(seconds: u32, domain: u16, credentials: &Credentials, args: &[&str]) -> Command {
    let mut c = piped("timeout");
    c.args(["-s", "INT", &seconds.to_string()])
        .arg(bin("metrocell"))
        .args(args)
        .env("ROS_DOMAIN_ID", domain.to_string())
        .env_remove("METROCELL_DDS_LOG");
    match credentials {
        Credentials::Secured { keystore, enclave } => {
            c.env("ROS_SECURITY_ENABLE", "true")
                .env("ROS_SECURITY_STRATEGY", "Enforce")
                .env("ROS_SECURITY_KEYSTORE", keystore)
                .env("ROS_SECURITY_ENCLAVE_OVERRIDE", enclave);
        }
        Credentials::Plain => {
            for k in [
                "ROS_SECURITY_ENABLE",
                "ROS_SECURITY_STRATEGY",
                "ROS_SECURITY_KEYSTORE",
                "ROS_SECURITY_ENCLAVE_OVERRIDE",
            ] {
                c.env_remove(k);
            }
        }
    }
    c
}

fn talker(seconds: u32, domain: u16, who: &Credentials, topic: &str, data: &str) -> ChildGuard {
    ChildGuard::spawn(&mut metrocell_for(
        seconds,
        domain,
        who,
        &[
            "topic",
            "pub",
            topic,
            "std_msgs/msg/String",
            &format!("{{data: {data}}}"),
            "--rate",
            "5",
        ],
    ))
}

fn listener(seconds: u32, domain: u16, who: &Credentials, topic: &str) -> ChildGuard {
    ChildGuard::spawn(&mut metrocell_for(
        seconds,
        domain,
        who,
        &[
            "topic",
            "echo",
            topic,
            "--type",
            "std_msgs/msg/String",
            "--qos",
            "reliable",
        ],
    ))
}

fn text(out: &Output) -> (String, String) {
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

/// How many messages with `data` an echo printed.
fn received(stdout: &str, data: &str) -> usize {
    stdout
        .lines()
        .filter(|l| l.trim() == format!("data: {data}"))
        .count()
}

/// A node in this test process, secured with an enclave of `keystore` (Enforce).
fn secured_node(name: &str, domain: u16, keystore: &Path, enclave: &str) -> MetrocellNode {
    MetrocellNode::builder(name)
        .diagnostics_period(None)
        .handle_signals(false)
        .environment(DdsEnvironment {
            domain_id: domain,
            discovery_range: DiscoveryRange::Localhost,
        })
        .security(SecurityEnvironment {
            enabled: true,
            enforce: true,
            keystore: Some(keystore.to_path_buf()),
            enclave_override: Some(enclave.into()),
        })
        .build()
        .unwrap()
}

#[test]
fn secured_nodes_exchange_every_message_type() {
    require_isolated_network();
    const DOMAIN: u16 = 97;
    let dir = scratch("roundtrip");
    let ks = keystore(&dir, DOMAIN, &["/cell/peer", "/cell/test"]);
    let mut peer_cmd = Command::new(bin("roundtrip_peer"));
    peer_cmd
        .env("ROS_DOMAIN_ID", DOMAIN.to_string())
        .env("ROS_SECURITY_ENABLE", "true")
        .env("ROS_SECURITY_STRATEGY", "Enforce")
        .env("ROS_SECURITY_KEYSTORE", &ks)
        .env("ROS_SECURITY_ENCLAVE_OVERRIDE", "/cell/peer");
    let _peer = ChildGuard::spawn(&mut peer_cmd);
    let mut node = secured_node("secured_roundtrip_test", DOMAIN, &ks, "/cell/test");
    let (failures, checked) = roundtrip_every_type(&mut node, 23);
    assert!(checked >= 31, "only {checked} types checked");
    assert!(
        failures.is_empty(),
        "{} of {checked} types failed through secured DDS:\n{}",
        failures.len(),
        failures.join("\n")
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Alter one byte of a PEM certificate's subject (its signature no longer matches).
fn tamper_certificate(path: &Path, from: &str, to: &str) {
    let cert = openssl::x509::X509::from_pem(&std::fs::read(path).unwrap()).unwrap();
    let mut der = cert.to_der().unwrap();
    let at = der
        .windows(from.len())
        .position(|w| w == from.as_bytes())
        .expect("subject in the certificate");
    der[at..at + to.len()].copy_from_slice(to.as_bytes());
    let altered = openssl::x509::X509::from_der(&der).unwrap();
    std::fs::write(path, altered.to_pem().unwrap()).unwrap();
}

#[test]
fn participants_without_valid_credentials_can_neither_read_nor_inject() {
    require_isolated_network();
    const DOMAIN: u16 = 98;
    let dir = scratch("outsiders");
    let ks = keystore(
        &dir,
        DOMAIN,
        &["/cell/talker", "/cell/listener", "/cell/altered"],
    );
    // A rogue keystore: its own CA, the same enclave names — a participant with a valid chain to
    // the wrong CA.
    let rogue = keystore(&dir.join("rogue"), DOMAIN, &["/cell/talker"]);
    // An identity whose subject was changed after the CA signed it.
    tamper_certificate(
        &ks.join("enclaves/cell/altered/cert.pem"),
        "/cell/altered",
        "/cell/Altered",
    );

    let secured = |enclave| Credentials::Secured {
        keystore: &ks,
        enclave,
    };
    let rogue_id = Credentials::Secured {
        keystore: &rogue,
        enclave: "/cell/talker",
    };
    let t = 14;
    // A passive eavesdropper on the network (a raw socket on the namespace's loopback).
    let sniffer = ChildGuard::spawn(
        piped(python())
            .arg(workspace_root().join("tests/py/sniff_udp.py"))
            .args([&(t - 2).to_string(), "from_talker", "plain_injection"]),
    );
    std::thread::sleep(Duration::from_millis(500));
    let listener_secured = listener(t, DOMAIN, &secured("/cell/listener"), "/secret");
    let listener_plain = listener(t, DOMAIN, &Credentials::Plain, "/secret");
    let listener_rogue = listener(t, DOMAIN, &rogue_id, "/secret");
    let _talker = talker(
        t - 2,
        DOMAIN,
        &secured("/cell/talker"),
        "/secret",
        "from_talker",
    );
    let _plain = talker(
        t - 2,
        DOMAIN,
        &Credentials::Plain,
        "/secret",
        "plain_injection",
    );
    let _rogue = talker(t - 2, DOMAIN, &rogue_id, "/secret", "rogue_injection");
    let altered = talker(
        t - 2,
        DOMAIN,
        &secured("/cell/altered"),
        "/secret",
        "altered_injection",
    );

    let wait = Duration::from_secs(u64::from(t) + 30);
    let (secured_out, secured_log) = text(&listener_secured.wait_output(wait));
    let (plain_out, _) = text(&listener_plain.wait_output(wait));
    let (rogue_out, _) = text(&listener_rogue.wait_output(wait));
    let altered_run = altered.wait_output(wait);
    let (_, altered_log) = text(&altered_run);
    let sniffed = sniffer.wait_output(wait);
    let (sniffed_out, sniffed_log) = text(&sniffed);
    assert!(
        sniffed.status.success(),
        "the eavesdropper failed: {sniffed_log}"
    );
    let sniffed: serde_json::Value = serde_json::from_str(sniffed_out.trim()).unwrap();

    // The secured pair talks; nothing else reaches the secured listener.
    let n = received(&secured_out, "from_talker");
    assert!(
        n >= 10,
        "the secured listener got {n} messages:\n{secured_out}\n{secured_log}"
    );
    assert!(
        !secured_out.contains("injection"),
        "something was injected:\n{secured_out}"
    );
    // The attackers' own side works (the plain pair, the rogue pair talk to each other) but
    // reads nothing of the cell.
    assert!(
        received(&plain_out, "plain_injection") >= 5,
        "plain control:\n{plain_out}"
    );
    assert!(
        received(&rogue_out, "rogue_injection") >= 5,
        "rogue control:\n{rogue_out}"
    );
    for (who, out) in [("plain", &plain_out), ("rogue", &rogue_out)] {
        assert_eq!(
            received(out, "from_talker"),
            0,
            "the {who} participant read the cell"
        );
    }
    // On the wire: the cell's payload never in clear text (encrypted), the plain pair's is.
    let on_wire = |m: &str| sniffed["with_marker"][m].as_u64().unwrap();
    assert!(sniffed["datagrams"].as_u64().unwrap() > 100, "{sniffed}");
    assert_eq!(
        on_wire("from_talker"),
        0,
        "the cell's data in clear text: {sniffed}"
    );
    assert!(
        on_wire("plain_injection") > 0,
        "the eavesdropper saw nothing: {sniffed}"
    );
    // Why, in the secured node's log.
    let security_lines: Vec<&str> = secured_log
        .lines()
        .filter(|l| l.contains(".dds_security]"))
        .collect();
    assert!(
        security_lines
            .iter()
            .any(|l| l.contains("handshake") && l.contains("Certificate signature verification")),
        "no handshake refusal of the rogue certificate in the log:\n{secured_log}"
    );
    // The plain participant: its announcement is turned down ("incompatible Security, not
    // matching"), and whatever it sends after is dropped ("unprotected message").
    assert!(
        security_lines
            .iter()
            .any(|l| l.contains("incompatible Security") || l.contains("unprotected message")),
        "no word of the plain participant in the log:\n{secured_log}"
    );
    // The altered certificate: the participant refuses to start, saying why.
    assert!(!altered_run.status.success(), "{altered_log}");
    assert!(
        altered_log.contains("does not verify against identity CA"),
        "{altered_log}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn permissions_for_other_topics_allow_neither_reading_nor_writing_a_protected_one() {
    require_isolated_network();
    const DOMAIN: u16 = 99;
    let dir = scratch("permissions");
    let ks = keystore(
        &dir,
        DOMAIN,
        &["/cell/talker", "/cell/listener", "/cell/outsider"],
    );
    // What any node needs (its log, parameter events and parameter services) and one topic of
    // its own, /other — not /secret.
    let policy = dir.join("outsider_policy.xml");
    std::fs::write(
        &policy,
        r#"<?xml version="1.0" encoding="UTF-8"?>
<policy version="0.2.0">
  <enclaves>
    <enclave path="/cell/outsider">
      <profiles>
        <profile ns="/" node="outsider">
          <topics publish="ALLOW" subscribe="ALLOW"><topic>other</topic></topics>
          <topics publish="ALLOW"><topic>rosout</topic><topic>parameter_events</topic></topics>
          <topics subscribe="ALLOW"><topic>clock</topic></topics>
          <services reply="ALLOW"><service>/*</service></services>
        </profile>
      </profiles>
    </enclave>
  </enclaves>
</policy>
"#,
    )
    .unwrap();
    let out = metrocell_ok(&[
        "security",
        "create-permission",
        ks.to_str().unwrap(),
        "/cell/outsider",
        policy.to_str().unwrap(),
    ]);
    assert!(out.contains("permissions from"), "{out}");

    let secured = |enclave| Credentials::Secured {
        keystore: &ks,
        enclave,
    };
    let t = 12;
    let on_secret = listener(t, DOMAIN, &secured("/cell/listener"), "/secret");
    let on_other = listener(t, DOMAIN, &secured("/cell/listener"), "/other");
    let _talker = talker(
        t - 2,
        DOMAIN,
        &secured("/cell/talker"),
        "/secret",
        "from_talker",
    );
    let outsider_reads = listener(t, DOMAIN, &secured("/cell/outsider"), "/secret");
    let outsider_writes = talker(
        t - 2,
        DOMAIN,
        &secured("/cell/outsider"),
        "/secret",
        "outsider_injection",
    );
    let _outsider_own = talker(
        t - 2,
        DOMAIN,
        &secured("/cell/outsider"),
        "/other",
        "outsider_own",
    );

    let wait = Duration::from_secs(u64::from(t) + 30);
    let (secret_out, secret_log) = text(&on_secret.wait_output(wait));
    let (other_out, other_log) = text(&on_other.wait_output(wait));
    let reads = outsider_reads.wait_output(wait);
    let writes = outsider_writes.wait_output(wait);
    let (reads_out, reads_log) = text(&reads);
    let (_, writes_log) = text(&writes);

    assert!(
        received(&secret_out, "from_talker") >= 10,
        "the cell's own pair:\n{secret_out}\n{secret_log}"
    );
    assert!(!secret_out.contains("outsider"), "{secret_out}");
    // Positive control: the outsider's enclave is valid and may use what it is granted.
    assert!(
        received(&other_out, "outsider_own") >= 5,
        "the outsider's granted topic:\n{other_out}\n{other_log}"
    );
    // Refused where it tries, naming the DDS topic.
    for (what, run, log) in [
        ("read", &reads, &reads_log),
        ("write", &writes, &writes_log),
    ] {
        assert!(
            !run.status.success(),
            "the outsider could {what} /secret:\n{log}"
        );
        assert!(
            log.to_lowercase().contains("not allowed by security") && log.contains("rt/secret"),
            "{what}: {log}"
        );
    }
    assert_eq!(received(&reads_out, "from_talker"), 0);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn enforce_refuses_a_missing_enclave_and_permissive_runs_unsecured_saying_so() {
    require_isolated_network();
    const DOMAIN: u16 = 100;
    let dir = scratch("strategy");
    let ks = keystore(&dir, DOMAIN, &["/cell/talker"]);
    let args = [
        "topic",
        "pub",
        "/x",
        "std_msgs/msg/String",
        "{data: x}",
        "--times",
        "1",
        "-w",
        "0",
    ];
    let ghost = Credentials::Secured {
        keystore: &ks,
        enclave: "/cell/ghost",
    };
    let enforced = run(
        &mut metrocell_for(20, DOMAIN, &ghost, &args),
        Duration::from_secs(40),
    );
    let (_, log) = text(&enforced);
    assert!(!enforced.status.success(), "{log}");
    assert!(
        log.contains("Enforce") && log.contains("'/cell/ghost'") && log.contains("create-enclave"),
        "{log}"
    );
    let mut permissive = metrocell_for(20, DOMAIN, &ghost, &args);
    permissive.env("ROS_SECURITY_STRATEGY", "Permissive");
    let out = run(&mut permissive, Duration::from_secs(40));
    let (_, log) = text(&out);
    assert!(out.status.success(), "{log}");
    assert!(log.contains("WITHOUT security"), "{log}");
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_secured_demo_cell_records_everything_and_finds_its_concealed_effects() {
    require_isolated_network();
    const DOMAIN: u16 = 101;
    let dir = scratch("demo");
    let bag = dir.join("bag");
    let out = run(
        piped(bin("metrocell"))
            .args([
                "demo",
                "--quick",
                "--secure",
                "--dashboard-port",
                "0",
                "--output",
            ])
            .arg(&bag)
            .env("ROS_DOMAIN_ID", DOMAIN.to_string())
            .env_remove("METROCELL_DDS_LOG"),
        Duration::from_secs(900),
    );
    let (stdout, stderr) = text(&out);
    // The demo fails when its recording check finds a message missing.
    assert!(out.status.success(), "{stdout}\n{stderr}");
    assert!(
        stdout.contains("DDS Security on:") && stdout.contains("9 enclaves"),
        "{stdout}"
    );
    assert!(stdout.contains("recording check: complete"), "{stdout}");
    // Camera frames (640×480, over 64 KB: sent as fragments) crossed too, every one measured.
    assert!(
        stdout.contains("camera: the twin rendered") && stdout.contains("all in the bag"),
        "{stdout}"
    );
    assert!(stdout.contains("diagnose named all 3"), "{stdout}");
    // Every node ran secured: each said so with its own enclave.
    for node in [
        "sim",
        "tracker",
        "fiducial",
        "thermal",
        "estimator",
        "diagnose",
        "recorder",
        "dashboard",
    ] {
        let said = format!("enclave '/metrocell_demo/{node}'");
        assert!(
            stdout.contains(&said) || stderr.contains(&said),
            "{node} did not run secured"
        );
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

/// Messages with `data` a secured listener got from a secured talker on `topic` (type `ty`,
/// values `values`, sensor-data QoS) in 10 s.
fn secured_exchange(domain: u16, topic: &str, ty: &str, values: &str, marker: &str) -> usize {
    let dir = scratch(&format!("exchange-{domain}"));
    let ks = keystore(&dir, domain, &["/cell/talker", "/cell/listener"]);
    let who = |enclave| Credentials::Secured {
        keystore: &ks,
        enclave,
    };
    let l = ChildGuard::spawn(&mut metrocell_for(
        12,
        domain,
        &who("/cell/listener"),
        &["topic", "echo", topic, "--type", ty],
    ));
    // Nobody reads this talker's output: it echoes each message, and a full pipe would stall it.
    let _t = ChildGuard::spawn(
        metrocell_for(
            10,
            domain,
            &who("/cell/talker"),
            &[
                "topic",
                "pub",
                topic,
                ty,
                values,
                "--rate",
                "5",
                "--qos",
                "sensor-data",
            ],
        )
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null()),
    );
    let (out, _) = text(&l.wait_output(Duration::from_secs(40)));
    std::fs::remove_dir_all(&dir).unwrap();
    out.lines().filter(|l| l.contains(marker)).count()
}

/// Fixed in the vendored RustDDS (third_party/rustdds/README.metrocell.md): a run of encrypted
/// fragments overflowed UDP's 65 507 bytes, and its encoded payload was held to the plain bound.
#[test]
fn a_message_over_64_kb_crosses_a_secured_domain() {
    require_isolated_network();
    let big = "x".repeat(100_000);
    let n = secured_exchange(
        102,
        "/big",
        "std_msgs/msg/String",
        &format!("{{data: {big}}}"),
        "xxxx",
    );
    assert!(n >= 10, "{n} of ~50 arrived");
}

/// Every node's participant also read `/clock` through ros2-client's Spinner: with the echo's own
/// reader, two readers of one topic in one participant (see the two-readers test below); the
/// Spinner no longer reads it in metrocell's nodes (third_party/ros2-client/README.metrocell.md).
#[test]
fn the_clock_crosses_a_secured_domain() {
    require_isolated_network();
    let n = secured_exchange(
        103,
        "/clock",
        "rosgraph_msgs/msg/Clock",
        "{clock: {sec: 7}}",
        "sec: 7",
    );
    assert!(n >= 10, "{n} of ~50 arrived");
}

#[test]
fn a_small_message_on_another_topic_of_the_same_type_crosses_a_secured_domain() {
    // The control of the clock's test: same type, QoS and size, another topic.
    require_isolated_network();
    let n = secured_exchange(
        104,
        "/clock2",
        "rosgraph_msgs/msg/Clock",
        "{clock: {sec: 7}}",
        "sec: 7",
    );
    assert!(n >= 10, "{n} of ~50 arrived");
}

/// Fixed in the vendored RustDDS (third_party/rustdds/README.metrocell.md): the writer's
/// crypto plugin gave a participant's second reader the first one's handle, its registration
/// failed, and neither reader received anything.
#[test]
fn two_readers_of_a_topic_in_one_participant_both_receive_a_secured_writer() {
    use metrocell_msgs::std_msgs::msg::String as RosString;
    require_isolated_network();
    const DOMAIN: u16 = 105;
    let dir = scratch("two-readers");
    let ks = keystore(&dir, DOMAIN, &["/cell/talker", "/cell/listener"]);
    let mut node = secured_node("two_readers", DOMAIN, &ks, "/cell/listener");
    let first = node
        .subscription::<RosString>("/twice", metrocell_node::qos::sensor_data())
        .unwrap();
    let second = node
        .subscription::<RosString>("/twice", metrocell_node::qos::sensor_data())
        .unwrap();
    let talker_id = Credentials::Secured {
        keystore: &ks,
        enclave: "/cell/talker",
    };
    let _talker = talker(12, DOMAIN, &talker_id, "/twice", "both");
    let (mut a, mut b) = (0, 0);
    let end = std::time::Instant::now() + Duration::from_secs(12);
    while std::time::Instant::now() < end {
        while let Ok(Some(_)) = first.take() {
            a += 1;
        }
        while let Ok(Some(_)) = second.take() {
            b += 1;
        }
        std::thread::sleep(Duration::from_millis(20));
    }
    println!("first reader {a}, second {b} of ~55");
    assert!(a >= 10 && b >= 10, "first reader {a}, second {b} of ~55");
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A Cyclone DDS configuration that secures its participant with `enclave` of `keystore`, as a
/// ROS 2 node with rmw_cyclonedds_cpp would be from the same SROS2 keystore.
fn cyclone_security_config(dir: &Path, keystore: &Path, enclave: &str) -> PathBuf {
    let e = keystore
        .join("enclaves")
        .join(enclave.trim_start_matches('/'));
    let ca = keystore.join("public/ca.cert.pem");
    let governance = keystore.join("enclaves/governance.p7s");
    let xml = format!(
        r#"<CycloneDDS xmlns="https://cdds.io/config"><Domain id="any">
  <General><Interfaces><NetworkInterface name="lo" multicast="true"/></Interfaces></General>
  <Security>
    <Authentication>
      <IdentityCertificate>file:{cert}</IdentityCertificate>
      <IdentityCA>file:{ca}</IdentityCA>
      <PrivateKey>file:{key}</PrivateKey>
    </Authentication>
    <AccessControl>
      <Governance>file:{governance}</Governance>
      <PermissionsCA>file:{ca}</PermissionsCA>
      <Permissions>file:{permissions}</Permissions>
    </AccessControl>
  </Security>
</Domain></CycloneDDS>"#,
        cert = e.join("cert.pem").display(),
        key = e.join("key.pem").display(),
        permissions = e.join("permissions.p7s").display(),
        ca = ca.display(),
        governance = governance.display(),
    );
    let path = dir.join(format!("cyclone{}.xml", enclave.replace('/', "_")));
    std::fs::write(&path, xml).unwrap();
    path
}

/// The secured Cyclone peer (tests/py/ros2_peer.py on the binding built against Debian's Cyclone
/// DDS) with `config`, on `domain`.
fn secured_cyclone(config: &Path, domain: u16, args: &[&str]) -> Command {
    let (python, plugins) = secure_cyclone_python();
    let mut c = piped(python);
    c.arg(ros2_peer())
        .args(args)
        .args(["--domain", &domain.to_string()])
        .env("LD_LIBRARY_PATH", plugins)
        .env("CYCLONEDDS_URI", format!("file://{}", config.display()));
    c
}

/// The secured Cyclone peer publishing `count` std_msgs/String `data` on `topic` at 5 Hz, after
/// 3 s for the readers to match (the older binding cannot list them).
fn cyclone_talker(config: &Path, domain: u16, topic: &str, data: &str, count: u32) -> ChildGuard {
    let json = format!(r#"{{"data": "{data}"}}"#);
    let count = count.to_string();
    ChildGuard::spawn(&mut secured_cyclone(
        config,
        domain,
        &[
            "publish",
            "--topic",
            topic,
            "--type",
            "std_msgs/msg/String",
            "--json",
            &json,
            "--count",
            &count,
            "--rate",
            "5",
            "--settle",
            "3",
        ],
    ))
}

#[test]
fn a_secured_cyclone_dds_peer_and_a_secured_node_exchange_messages_both_ways() {
    require_isolated_network();
    const DOMAIN: u16 = 106;
    let dir = scratch("cyclone");
    let ks = keystore(&dir, DOMAIN, &["/cell/metrocell", "/cell/cyclone"]);
    let cyclone = cyclone_security_config(&dir, &ks, "/cell/cyclone");
    let node = Credentials::Secured {
        keystore: &ks,
        enclave: "/cell/metrocell",
    };
    // metrocell → Cyclone
    let cyclone_listener = ChildGuard::spawn(&mut secured_cyclone(
        &cyclone,
        DOMAIN,
        &[
            "listen",
            "--topic",
            "/to_cyclone",
            "--type",
            "std_msgs/msg/String",
            "--count",
            "20",
            "--timeout",
            "14",
        ],
    ));
    let _talker = talker(14, DOMAIN, &node, "/to_cyclone", "from_metrocell");
    let (heard, cyclone_log) = text(&cyclone_listener.wait_output(Duration::from_secs(40)));
    let from_metrocell = heard.matches("from_metrocell").count();
    // Cyclone → metrocell
    let echo = listener(16, DOMAIN, &node, "/from_cyclone");
    let publisher = cyclone_talker(&cyclone, DOMAIN, "/from_cyclone", "from_cyclone", 50);
    let (_, publisher_log) = text(&publisher.wait_output(Duration::from_secs(40)));
    let (echoed, echo_log) = text(&echo.wait_output(Duration::from_secs(40)));
    let from_cyclone = echoed.matches("from_cyclone").count();
    println!("secured Cyclone DDS heard {from_metrocell} of 20 from metrocell; metrocell heard {from_cyclone} of 50 from Cyclone");
    assert!(
        from_metrocell >= 10,
        "metrocell → secured Cyclone: {from_metrocell} of 20\nCyclone's log:\n{cyclone_log}"
    );
    assert!(
        from_cyclone >= 10,
        "secured Cyclone → metrocell: {from_cyclone} of 50\nCyclone's log:\n{publisher_log}\nmetrocell's log:\n{echo_log}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn a_cyclone_dds_peer_with_a_certificate_of_another_ca_reaches_no_secured_node() {
    require_isolated_network();
    const DOMAIN: u16 = 107;
    let dir = scratch("cyclone-rogue");
    let ks = keystore(&dir, DOMAIN, &["/cell/metrocell", "/cell/cyclone"]);
    let rogue_dir = dir.join("rogue");
    std::fs::create_dir_all(&rogue_dir).unwrap();
    let rogue = keystore(&rogue_dir, DOMAIN, &["/cell/cyclone"]);
    let node = Credentials::Secured {
        keystore: &ks,
        enclave: "/cell/metrocell",
    };
    let publish = |config: &Path, marker: &str| {
        let echo = listener(12, DOMAIN, &node, "/guarded");
        let _p = cyclone_talker(config, DOMAIN, "/guarded", marker, 40);
        let (out, log) = text(&echo.wait_output(Duration::from_secs(40)));
        (out.matches(marker).count(), log)
    };
    let (rogue_heard, rogue_log) = publish(
        &cyclone_security_config(&rogue_dir, &rogue, "/cell/cyclone"),
        "rogue_cyclone",
    );
    let (heard, _) = publish(
        &cyclone_security_config(&dir, &ks, "/cell/cyclone"),
        "trusted_cyclone",
    );
    println!("metrocell heard {rogue_heard} of 40 from the rogue Cyclone peer, {heard} of 40 from the trusted one (control)");
    assert!(
        heard >= 10,
        "control: the trusted Cyclone peer reaches the node ({heard} of 40)"
    );
    assert_eq!(
        rogue_heard, 0,
        "a Cyclone peer whose certificate another CA signed reaches nothing\n{rogue_log}"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}
