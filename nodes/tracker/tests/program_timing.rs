//! Time alignment from the program's timing alone (thesis T_v = L_T/F + T_s(n − 1)):
//! the schedule reproduces the twin's dwell times, and the node run on a twin bag without
//! `machine/commanded_joint_states` still gives every dwell its program nominal.
//!
//! Run: `cargo test -p metrocell-tracker-node --test program_timing`

use std::process::Command;

use metrocell_bagtools::BagSource;
use metrocell_laser_tracker::ProgramSchedule;
use metrocell_msgs::msg::MeasuredPoint;
use metrocell_simulation::bag::{write_bag, BagOptions};
use metrocell_twin::Cell;
use nalgebra::Vector3;

const CELL: &str = concat!(
    env!("CARGO_MANIFEST_DIR"),
    "/tests/cells/tracker_quick.yaml"
);

#[test]
fn program_timing_matches_the_twin_and_gives_nominals_without_machine_state() {
    let cell = Cell::from_yaml_str(&std::fs::read_to_string(CELL).unwrap(), CELL).unwrap();
    let program = cell.program.clone();
    let v3 = |p: &nalgebra::DVector<f64>| Vector3::new(p[0], p[1], p[2]);
    let dwells: Vec<(usize, f64)> = program
        .segments
        .iter()
        .filter_map(|s| s.dwell_point.map(|i| (i, s.start)))
        .collect();
    let options = BagOptions {
        frames: None,
        clock_rate: None,
        ..BagOptions::default()
    };
    let schedule = ProgramSchedule {
        start_ns: options.start_ns as i64 + (program.start * 1e9).round() as i64,
        home: v3(&program.home),
        points: dwells
            .iter()
            .map(|(i, _)| v3(&program.points[*i]))
            .collect(),
        feed: program.feed_rate,
        stop_time: program.dwell,
    };
    for ((_, start), arrival) in dwells.iter().zip(schedule.arrivals()) {
        assert!(
            (start - arrival).abs() < 1e-9,
            "twin dwell at {start} s, T_v = {arrival} s"
        );
    }

    let dir =
        std::env::temp_dir().join(format!("metrocell-tracker-program-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let input = dir.join("input");
    let end = program
        .segments
        .iter()
        .filter(|s| s.dwell_point.is_some())
        .map(|s| s.end)
        .fold(0.0, f64::max);
    write_bag(cell, program.start + end + 5.0, 5, &input, &options, |_| {}).unwrap();
    let flat: Vec<String> = schedule
        .points
        .iter()
        .flat_map(|p| [p.x, p.y, p.z])
        .map(|v| format!("{v}"))
        .collect();
    let params = [
        "tool_offset:=[0.0, 0.0, -0.1]".to_string(),
        "registration_points:=12".into(),
        format!("program_points:=[{}]", flat.join(", ")),
        format!(
            "program_home:=[{}, {}, {}]",
            schedule.home.x, schedule.home.y, schedule.home.z
        ),
        format!("program_feed:={}", schedule.feed),
        format!("program_stop_time:={}", schedule.stop_time),
        format!("program_start_time:={}", schedule.start_ns as f64 * 1e-9),
    ];
    let mut args = vec![
        "--ros-args".to_string(),
        "-r".into(),
        "machine/commanded_joint_states:=/absent".into(),
    ];
    for p in &params {
        args.extend(["-p".to_string(), p.clone()]);
    }
    let output = dir.join("output");
    let run = Command::new(env!("CARGO_BIN_EXE_metrocell-tracker"))
        .arg("--bag")
        .arg(&input)
        .arg("--output")
        .arg(&output)
        .args(&args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let mut s = BagSource::open(&output).unwrap();
    s.subscribe::<MeasuredPoint>("/measured_points").unwrap();
    let points: Vec<MeasuredPoint> = s
        .messages()
        .unwrap()
        .map(|m| m.unwrap().decode().unwrap())
        .collect();
    assert_eq!(points.len(), dwells.len(), "{stderr}");
    for (p, (i, _)) in points.iter().zip(&dwells) {
        assert_eq!(p.point_id, format!("point_{i}"));
        let expected = v3(&program.points[*i]) + Vector3::new(0.0, 0.0, -0.1);
        assert!(
            (Vector3::new(p.nominal.x, p.nominal.y, p.nominal.z) - expected).norm() < 1e-12,
            "{}",
            p.point_id
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}
