//! `NODE --help` teaches and does nothing else: every node binary prints its usage and every
//! declared parameter, and exits 0 at once — before a DDS participant exists (the help is printed
//! while the command line is parsed, ahead of `NodeBuilder::build`).

use std::time::Duration;

use system_tests::{bin, piped, run};

#[test]
fn every_node_prints_help_and_exits_without_starting() {
    system_tests::require_isolated_network();
    // (binary, parameters its help must list, whether it replays bags)
    let nodes: [(&str, &[&str], bool); 12] = [
        ("metrocell-sim", &["cell", "duration", "seed"], false),
        ("metrocell-thermal", &["sensors", "alpha"], true),
        (
            "metrocell-recorder",
            &["output", "topics", "max_bag_size"],
            false,
        ),
        (
            "metrocell-camera",
            &["path", "device", "stamp_source"],
            false,
        ),
        ("metrocell-fiducial", &["family"], true),
        ("metrocell-probe", &["stylus_radius", "pretravel"], true),
        (
            "metrocell-dashboard",
            &[
                "port",
                "foxglove_port",
                "error_warn_um",
                "drift_warn_um_per_h",
            ],
            false,
        ),
        (
            "metrocell-estimator",
            &[
                "model",
                "process_noise",
                "predict_points",
                "state_file",
                "max_signal_gap",
            ],
            true,
        ),
        (
            "metrocell-diagnose",
            &["model", "window", "every", "points_type"],
            true,
        ),
        (
            "metrocell-tracker",
            &["backend", "registration_points"],
            true,
        ),
        (
            "metrocell-align",
            &["action", "move_length", "camera_sigma", "urdf", "cell_pose"],
            false,
        ),
        (
            "metrocell-robot-twin",
            &["camera_offset", "camera_rpy", "noise"],
            false,
        ),
    ];
    for (name, params, replays) in nodes {
        for flag in ["--help", "-h"] {
            // A node that ignored --help would start and run on: `run` kills it after 5 s and fails.
            let out = run(piped(bin(name)).arg(flag), Duration::from_secs(5));
            let text = String::from_utf8_lossy(&out.stdout);
            assert!(
                out.status.success(),
                "{name} {flag}: exit {:?}, stderr {}",
                out.status,
                String::from_utf8_lossy(&out.stderr)
            );
            assert!(
                text.contains("Usage:") && text.contains("--ros-args"),
                "{name} help: {text}"
            );
            for p in params {
                assert!(
                    text.contains(&format!("  {p} (")),
                    "{name} help does not list parameter {p}: {text}"
                );
            }
            assert_eq!(
                text.contains("--bag IN_BAG"),
                replays,
                "{name} help and --bag: {text}"
            );
        }
    }
}
