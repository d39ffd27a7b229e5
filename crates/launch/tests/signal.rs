//! SIGINT delivered to the launcher's process (what Ctrl-C does) stops every node.
//! Its own test binary, because it signals the whole test process.

mod common;

use std::thread;
use std::time::{Duration, Instant};

use common::{data_dir, group_alive, temp_dir, write_script, Captured};
use metrocell_launch::{parse_launch_arguments, run_launch, LaunchOptions};
use nix::sys::signal::{kill, Signal};
use nix::unistd::getpid;

#[test]
fn sigint_to_the_launcher_stops_both_nodes_within_two_seconds() {
    let dir = temp_dir("sigint");
    let forever = "while true; do sleep 0.1; done\n";
    write_script(&dir, "talker.sh", &format!("echo \"argv: $*\"\n{forever}"));
    write_script(
        &dir,
        "listener.sh",
        &format!("echo \"argv: $*\"\n{forever}"),
    );
    let out = Captured::default();
    let opts = LaunchOptions {
        handle_signals: true,
        output: out.sink(),
        environment: Some(Default::default()),
        ..LaunchOptions::default()
    };
    let args = parse_launch_arguments(&[format!("script_dir:={}", dir.display())]).unwrap();
    let file = data_dir().join("supervise.launch.yaml");
    let runner = thread::spawn(move || run_launch(&file, &args, &opts));

    out.wait_for(
        "[talker] argv: --ros-args -r __node:=talker -r __ns:=/demo -p greeting:=hello\n",
        Duration::from_secs(5),
    );
    out.wait_for(
        "[listener.sh] argv: --topic chatter\n",
        Duration::from_secs(5),
    );
    let pids = [out.pids_of("talker")[0], out.pids_of("listener.sh")[0]];

    let sent = Instant::now();
    kill(getpid(), Signal::SIGINT).unwrap();
    let outcome = runner.join().unwrap().unwrap();
    while pids.iter().any(|&p| group_alive(p)) {
        assert!(
            sent.elapsed() < Duration::from_secs(2),
            "a node outlived Ctrl-C; output:\n{}",
            out.text()
        );
        thread::sleep(Duration::from_millis(10));
    }
    assert!(sent.elapsed() < Duration::from_secs(2));
    assert!(outcome.interrupted);
    assert_eq!(outcome.exit_code(), 0);
    assert!(out
        .text()
        .contains("[launch] shutdown requested: sending SIGINT to every process\n"));
    std::fs::remove_dir_all(&dir).unwrap();
}
