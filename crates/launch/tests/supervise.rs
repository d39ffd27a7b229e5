//! Running shell-script "nodes": prefixed output, parameter overrides reaching argv, shutdown
//! through the handle, respawn, and how the run ends on its own.

mod common;

use std::thread;
use std::time::{Duration, Instant};

use common::{data_dir, group_alive, temp_dir, write_script, Captured};
use metrocell_launch::{
    parse_launch_arguments, run_launch, ExitKind, LaunchOptions, ShutdownHandle,
};

const LOOP_FOREVER: &str = "while true; do sleep 0.1; done\n";

fn options(out: &Captured, shutdown: &ShutdownHandle) -> LaunchOptions {
    LaunchOptions {
        handle_signals: false,
        shutdown: shutdown.clone(),
        output: out.sink(),
        environment: Some(Default::default()),
        ..LaunchOptions::default()
    }
}

#[test]
fn two_nodes_prefixed_output_override_in_argv_and_shutdown_within_two_seconds() {
    let dir = temp_dir("two-nodes");
    write_script(
        &dir,
        "talker.sh",
        &format!("echo \"argv: $*\"\necho \"warming up\" >&2\n{LOOP_FOREVER}"),
    );
    write_script(
        &dir,
        "listener.sh",
        &format!("echo \"argv: $*\"\n{LOOP_FOREVER}"),
    );
    let out = Captured::default();
    let shutdown = ShutdownHandle::new();
    let opts = options(&out, &shutdown);
    let args = parse_launch_arguments(&[
        format!("script_dir:={}", dir.display()),
        "greeting:=bonjour".into(),
    ])
    .unwrap();
    let file = data_dir().join("supervise.launch.yaml");
    let runner = thread::spawn(move || run_launch(&file, &args, &opts));

    let wait = Duration::from_secs(5);
    out.wait_for(
        "[talker] argv: --ros-args -r __node:=talker -r __ns:=/demo -p greeting:=bonjour\n",
        wait,
    );
    out.wait_for("[listener.sh] argv: --topic chatter\n", wait);
    out.wait_for("[talker] warming up\n", wait);
    let pids: Vec<i32> = ["talker", "listener.sh"]
        .iter()
        .map(|l| out.pids_of(l)[0])
        .collect();
    assert!(
        pids.iter().all(|&p| group_alive(p)),
        "both nodes run before the shutdown"
    );

    let asked = Instant::now();
    shutdown.request();
    while !runner.is_finished() {
        assert!(
            asked.elapsed() < Duration::from_secs(3),
            "launcher did not return; output:\n{}",
            out.text()
        );
        thread::sleep(Duration::from_millis(10));
    }
    let outcome = runner.join().unwrap().unwrap();
    let took = asked.elapsed();
    // Children and their `sleep`s are gone within 2 s of the request (SIGINT ends them long before
    // the 2 s SIGKILL deadline).
    while pids.iter().any(|&p| group_alive(p)) {
        assert!(
            asked.elapsed() < Duration::from_secs(2),
            "a node's process group outlived the shutdown"
        );
        thread::sleep(Duration::from_millis(10));
    }
    assert!(took < Duration::from_secs(2), "shutdown took {took:?}");
    let text = out.text();
    eprintln!("{text}");
    assert!(
        !text.contains("SIGKILL"),
        "SIGINT alone should have been enough:\n{text}"
    );
    assert!(outcome.interrupted);
    assert!(
        outcome.success(),
        "exits caused by the shutdown are not failures: {outcome:?}"
    );
    assert_eq!(outcome.exit_code(), 0);
    assert_eq!(outcome.processes.len(), 2);
    for p in &outcome.processes {
        assert_eq!(p.starts, 1);
        assert!(
            matches!(p.last_exit, ExitKind::Signal(2) | ExitKind::Code(130)),
            "{} should have ended by SIGINT: {:?}",
            p.label,
            p.last_exit
        );
        assert!(text.contains(&format!("[launch] [{}] ", p.label)));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn respawning_node_is_restarted_until_its_retry_limit() {
    let dir = temp_dir("respawn");
    write_script(&dir, "flaky.sh", "echo run\nexit 3\n");
    let out = Captured::default();
    let shutdown = ShutdownHandle::new();
    let opts = options(&out, &shutdown);
    let args = parse_launch_arguments(&[format!("script_dir:={}", dir.display())]).unwrap();
    let started = Instant::now();
    let outcome = run_launch(&data_dir().join("respawn.launch.yaml"), &args, &opts).unwrap();
    let text = out.text();
    assert!(started.elapsed() < Duration::from_secs(5));
    assert_eq!(
        text.matches("[flaky] run\n").count(),
        4,
        "1 start + 3 restarts:\n{text}"
    );
    assert_eq!(
        text.matches("[launch] [flaky] exited with code 3\n")
            .count(),
        4
    );
    assert_eq!(
        text.matches("[launch] [flaky] respawning in 0.05 s\n")
            .count(),
        3
    );
    assert_eq!(out.pids_of("flaky").len(), 4);
    let flaky = &outcome.processes[0];
    assert_eq!(
        (flaky.starts, &flaky.last_exit, flaky.failed),
        (4, &ExitKind::Code(3), true)
    );
    assert!(!outcome.interrupted);
    assert_eq!(outcome.exit_code(), 1);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn run_ends_when_non_respawning_nodes_are_done_and_reports_failures() {
    let dir = temp_dir("ends");
    write_script(&dir, "once.sh", "echo done\nexit 0\n");
    write_script(&dir, "fails.sh", "echo oops >&2\nexit 5\n");
    write_script(&dir, "server.sh", &format!("echo serving\n{LOOP_FOREVER}"));
    let launch = |nodes: &str| {
        let file = dir.join("ends.launch.yaml");
        std::fs::write(&file, format!("launch:\n{nodes}")).unwrap();
        let out = Captured::default();
        let outcome = run_launch(&file, &[], &options(&out, &ShutdownHandle::new())).unwrap();
        (outcome, out.text())
    };
    let node = |script: &str, respawn: bool| {
        format!(
            "  - node:\n      exec: {}\n      respawn: {respawn}\n",
            dir.join(script).display()
        )
    };

    // A respawning server is stopped once the only non-respawning node has finished.
    let (outcome, text) = launch(&format!(
        "{}{}",
        node("once.sh", false),
        node("server.sh", true)
    ));
    assert!(text.contains("[once.sh] done\n"), "{text}");
    assert!(
        text.contains("all processes that do not respawn have exited"),
        "{text}"
    );
    assert_eq!(outcome.exit_code(), 0, "{outcome:?}");
    assert_eq!(outcome.processes[1].starts, 1);
    assert!(!outcome.interrupted);

    // A failing node makes the launcher's status non-zero; stderr lines are prefixed too.
    let (outcome, text) = launch(&format!(
        "{}{}",
        node("once.sh", false),
        node("fails.sh", false)
    ));
    assert!(text.contains("[fails.sh] oops\n"), "{text}");
    assert!(
        text.contains("[launch] [fails.sh] exited with code 5\n"),
        "{text}"
    );
    assert_eq!(outcome.exit_code(), 1);
    assert_eq!(outcome.processes[1].last_exit, ExitKind::Code(5));
    assert!(!outcome.processes[0].failed && outcome.processes[1].failed);
    std::fs::remove_dir_all(&dir).unwrap();
}

#[test]
fn stubborn_node_is_killed_after_the_grace_period() {
    let dir = temp_dir("stubborn");
    write_script(
        &dir,
        "stubborn.sh",
        &format!("trap '' INT\necho ready\n{LOOP_FOREVER}"),
    );
    let file = dir.join("stubborn.launch.yaml");
    std::fs::write(
        &file,
        format!(
            "launch:\n  - node:\n      exec: {}\n",
            dir.join("stubborn.sh").display()
        ),
    )
    .unwrap();
    let out = Captured::default();
    let shutdown = ShutdownHandle::new();
    let mut opts = options(&out, &shutdown);
    opts.grace_period = Duration::from_millis(400);
    let runner = thread::spawn(move || run_launch(&file, &[], &opts));
    out.wait_for("[stubborn.sh] ready\n", Duration::from_secs(5));
    let pid = out.pids_of("stubborn.sh")[0];
    let asked = Instant::now();
    shutdown.request();
    let outcome = runner.join().unwrap().unwrap();
    let took = asked.elapsed();
    assert!(
        took >= Duration::from_millis(400) && took < Duration::from_secs(2),
        "took {took:?}"
    );
    assert!(out
        .text()
        .contains("[launch] [stubborn.sh] still running: sending SIGKILL\n"));
    assert_eq!(outcome.processes[0].last_exit, ExitKind::Signal(9));
    assert!(outcome.success());
    let deadline = Instant::now() + Duration::from_secs(2);
    while group_alive(pid) {
        assert!(Instant::now() < deadline, "stubborn group survived SIGKILL");
        thread::sleep(Duration::from_millis(10));
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
