//! A launch file using every action and substitution resolves to exactly the expected
//! command lines (tests/data/share_root/launch/rich.launch.yaml).

use std::collections::BTreeMap;
use std::os::unix::fs::PermissionsExt;
use std::path::{Path, PathBuf};
use std::time::Duration;

use metrocell_launch::{load_launch_plan, parse_launch_arguments, LaunchOptions, OutputMode};

fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data")
}

/// A directory holding fake executables named like the nodes the test file runs.
fn fake_bin_dir(tag: &str) -> PathBuf {
    let dir =
        std::env::temp_dir().join(format!("metrocell-launch-bin-{tag}-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    for name in [
        "camera_node",
        "tracker_node",
        "probe_node",
        "thermo_node",
        "tool",
    ] {
        let path = dir.join(name);
        std::fs::write(&path, "#!/bin/sh\nexit 0\n").unwrap();
        std::fs::set_permissions(&path, std::fs::Permissions::from_mode(0o755)).unwrap();
    }
    dir
}

fn options(bin: &Path) -> LaunchOptions {
    let environment: BTreeMap<String, String> = [("HOME_DIR", "/home/op")]
        .into_iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
    LaunchOptions {
        executable_search_path: Some(vec![PathBuf::from("/nonexistent-dir"), bin.to_path_buf()]),
        environment: Some(environment),
        ..LaunchOptions::default()
    }
}

#[test]
fn rich_file_gives_exact_command_lines() {
    let bin = fake_bin_dir("rich");
    let file = data_dir().join("share_root/launch/rich.launch.yaml");
    let share = data_dir().join("share_root").canonicalize().unwrap();
    let args = parse_launch_arguments(&["rate:=10", "sample_period:=0.25"]).unwrap();
    let plan = load_launch_plan(&file, &args, &options(&bin)).unwrap();
    let b = |name: &str| bin.join(name).display().to_string();

    let lines: Vec<(String, Vec<String>)> = plan
        .processes
        .iter()
        .map(|p| (p.label.clone(), p.command_line()))
        .collect();
    let expected = expected_command_lines(&b, &share);
    assert_eq!(
        lines.len(),
        expected.len(),
        "labels: {:?}",
        lines.iter().map(|l| &l.0).collect::<Vec<_>>()
    );
    for (got, want) in lines.iter().zip(&expected) {
        assert_eq!(got, want);
    }

    let cam = &plan.processes[0];
    assert!(cam.respawn);
    assert_eq!(cam.respawn_delay, Duration::from_millis(1500));
    assert_eq!(cam.respawn_max_retries, None);
    assert_eq!(cam.output, OutputMode::Screen);
    assert_eq!(cam.env, vec![("CELL".to_string(), "cell_a".to_string())]);
    assert!(
        cam.origin.ends_with("rich.launch.yaml:19"),
        "{}",
        cam.origin
    );
    assert!(!plan.processes[1].respawn);

    let declared: Vec<(&str, &str)> = plan
        .arguments
        .iter()
        .map(|a| (a.name.as_str(), a.value.as_str()))
        .collect();
    assert_eq!(
        declared,
        [
            ("cell", "cell_a"),
            ("rate", "10"),
            ("with_probe", "false"),
            ("sensor", "thermo_cell_a"),
            ("sample_period", "0.25")
        ]
    );
    assert_eq!(
        plan.arguments[0].description.as_deref(),
        Some("Which cell this launch runs")
    );
    assert_eq!(plan.arguments[1].default.as_deref(), Some("30"));
    std::fs::remove_dir_all(&bin).unwrap();
}

/// The command lines rich.launch.yaml resolves to, by process label (`b`: a fake executable's
/// path, `share`: the package's share directory).
fn expected_command_lines(b: &dyn Fn(&str) -> String, share: &Path) -> Vec<(String, Vec<String>)> {
    vec![
        ("cam0".into(), expected_cam0(b, share)),
        (
            "tracker".into(),
            vec![
                b("tracker_node"),
                "--ros-args".into(),
                "-r".into(),
                "__node:=tracker".into(),
                "-r".into(),
                "__ns:=/metrology/tracker".into(),
                "-p".into(),
                "home:=/home/op".into(),
                "-p".into(),
                "station:=unknown".into(),
                "-p".into(),
                "opt:=x".into(),
                "-p".into(),
                "cell:=inner_cell".into(),
            ],
        ),
        (
            "probe_node".into(),
            vec![
                b("probe_node"),
                "--ros-args".into(),
                "-r".into(),
                "__ns:=/absolute".into(),
            ],
        ),
        (
            "probe_unless".into(),
            vec![
                b("probe_node"),
                "--ros-args".into(),
                "-r".into(),
                "__node:=probe_unless".into(),
                "-r".into(),
                "__ns:=/metrology".into(),
            ],
        ),
        (
            "thermo_cell_a".into(),
            vec![
                b("thermo_node"),
                "--ros-args".into(),
                "-r".into(),
                "__node:=thermo_cell_a".into(),
                "-r".into(),
                "__ns:=/metrology".into(),
                "-p".into(),
                "period:=0.25".into(),
                "-p".into(),
                "cell:=cell_a".into(),
            ],
        ),
        (
            "logger".into(),
            vec![b("tool"), "--log".into(), "rich.launch.yaml".into()],
        ),
        (
            "sh".into(),
            vec!["/bin/sh".into(), "-c".into(), "echo hello cell_a".into()],
        ),
    ]
}

/// The camera's command line: its arguments, name and namespace, every parameter form, the
/// params file and the remapping.
fn expected_cam0(b: &dyn Fn(&str) -> String, share: &Path) -> Vec<String> {
    vec![
        b("camera_node"),
        "--device".into(),
        "/dev/video 0".into(),
        "--verbose".into(),
        "--ros-args".into(),
        "-r".into(),
        "__node:=cam0".into(),
        "-r".into(),
        "__ns:=/metrology/cell_a".into(),
        "-p".into(),
        "rate:=10".into(),
        "-p".into(),
        "exposure_s:=0.004".into(),
        "-p".into(),
        "frame_id:=cam0_optical".into(),
        "-p".into(),
        "serial:='0042'".into(),
        "-p".into(),
        "rate_quoted:=10".into(),
        "-p".into(),
        "roi:=[0, 0, 640, 480]".into(),
        "-p".into(),
        "labels:=[a, 'b, c', '1']".into(),
        "-p".into(),
        "intrinsics.fx:=812.5".into(),
        "-p".into(),
        "intrinsics.model:={kind: pinhole, k: [0.1, -0.02]}".into(),
        "--params-file".into(),
        format!("{}/launch-configs/params/cam.yaml", share.display()),
        "-p".into(),
        "enabled:=true".into(),
        "-r".into(),
        "image:=/cell_a/sensors/image".into(),
    ]
}

#[test]
fn overriding_a_condition_argument_switches_nodes() {
    let bin = fake_bin_dir("cond");
    let file = data_dir().join("share_root/launch/rich.launch.yaml");
    let args = parse_launch_arguments(&["with_probe:=true", "cell:=cell_b"]).unwrap();
    let plan = load_launch_plan(&file, &args, &options(&bin)).unwrap();
    let labels: Vec<&str> = plan.processes.iter().map(|p| p.label.as_str()).collect();
    assert_eq!(
        labels,
        [
            "cam0",
            "tracker",
            "probe_node",
            "skipped_by_if",
            "thermo_cell_b",
            "logger",
            "sh"
        ]
    );
    std::fs::remove_dir_all(&bin).unwrap();
}

#[test]
fn share_dir_comes_from_option_then_environment() {
    let bin = fake_bin_dir("share");
    let dir = std::env::temp_dir().join(format!("metrocell-launch-share-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("s.launch.yaml");
    std::fs::write(
        &file,
        "launch:\n  - node:\n      exec: tool\n      args: $(find-pkg-share metrocell_msgs)\n",
    )
    .unwrap();

    let mut opts = options(&bin);
    opts.environment
        .as_mut()
        .unwrap()
        .insert("METROCELL_SHARE".into(), "/from/env".into());
    let plan = load_launch_plan(&file, &[], &opts).unwrap();
    assert_eq!(plan.processes[0].args, ["/from/env"]);

    opts.share_dir = Some(PathBuf::from("/from/option"));
    let plan = load_launch_plan(&file, &[], &opts).unwrap();
    assert_eq!(plan.processes[0].args, ["/from/option"]);
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&bin).unwrap();
}

#[test]
fn duplicate_labels_are_numbered() {
    let bin = fake_bin_dir("dup");
    let dir = std::env::temp_dir().join(format!("metrocell-launch-dup-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("d.launch.yaml");
    std::fs::write(
        &file,
        "launch:\n  - node: {exec: tool}\n  - node: {exec: tool}\n  - node: {exec: tool}\n",
    )
    .unwrap();
    let plan = load_launch_plan(&file, &[], &options(&bin)).unwrap();
    let labels: Vec<&str> = plan.processes.iter().map(|p| p.label.as_str()).collect();
    assert_eq!(labels, ["tool", "tool-2", "tool-3"]);
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&bin).unwrap();
}

#[test]
fn a_nodes_enclave_becomes_its_enclave_argument() {
    let bin = fake_bin_dir("enclave");
    let dir = std::env::temp_dir().join(format!("metrocell-launch-enclave-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let file = dir.join("e.launch.yaml");
    std::fs::write(
        &file,
        "launch:\n  - arg: {name: cell, default: cell_a}\n  - node: {exec: tool, name: twin, enclave: '/$(var cell)/twin'}\n  - node: {exec: tool, name: plain}\n",
    )
    .unwrap();
    let plan = load_launch_plan(&file, &[], &options(&bin)).unwrap();
    assert_eq!(
        plan.processes[0].args,
        [
            "--ros-args",
            "-r",
            "__node:=twin",
            "--enclave",
            "/cell_a/twin"
        ]
    );
    assert!(!plan.processes[1].args.iter().any(|a| a == "--enclave"));
    std::fs::remove_dir_all(&dir).unwrap();
    std::fs::remove_dir_all(&bin).unwrap();
}
