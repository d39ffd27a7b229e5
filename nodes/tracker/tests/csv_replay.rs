//! CSV export backend: a tracker export in the `bag import` layout (tracker-frame points,
//! commanded joints, air) replayed with `--bag FILE.csv`; bad rows (unparsable, NaN = beam
//! break, out of range) are reported and skipped, and every dwell gives one point in the
//! machine frame at its nominal. A NaN or unparsable cell is the importer's to reject (named
//! with line and column); an implausible range is the node's.
//!
//! Run: `cargo test -p metrocell-tracker-node --test csv_replay`

use std::fmt::Write as _;
use std::process::Command;

use metrocell_bagtools::BagSource;
use metrocell_compensation::AirData;
use metrocell_msgs::msg::MeasuredPoint;
use nalgebra::{Rotation3, Vector3};

#[test]
fn csv_export_replays_with_bad_rows_reported() {
    let dir =
        std::env::temp_dir().join(format!("metrocell-tracker-csv-test-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    // tracker pose in the machine frame: q = R p + t
    let r = Rotation3::from_euler_angles(0.001, -0.002, 0.7);
    let t = Vector3::new(-1.5, 0.3, 0.4);
    let air = AirData {
        temperature: 20.5,
        pressure: 100_500.0,
        humidity: 0.4,
    };
    let n = air.refractive_index();
    let nominals = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(0.4, 0.0, 0.1),
        Vector3::new(0.4, 0.3, 0.0),
        Vector3::new(0.0, 0.3, 0.2),
    ];
    let mut csv = String::from("timestamp,point_id,measured_x,measured_y,measured_z,u_x,u_y,u_z,joint.x,joint.y,joint.z,temperature.air,pressure,humidity\n");
    let mut time = 1_714_557_600.0;
    for (k, q) in nominals.iter().enumerate() {
        // the export holds vacuum distances (no index applied): the point scaled by n
        let p = r.inverse() * (q - t) * n;
        for i in 0..10 {
            time += 0.1;
            let (x, y, z) = match (k, i) {
                (1, 3) => (f64::NAN, f64::NAN, f64::NAN), // no value: the importer rejects the row
                (2, 5) => (p.x * 100.0, p.y * 100.0, p.z * 100.0), // beyond max_range
                _ => (p.x, p.y, p.z),
            };
            writeln!(
                csv,
                "{time:.3},point_{k},{x},{y},{z},1e-5,1e-5,1e-5,{},{},{},{},{},{}",
                q.x, q.y, q.z, air.temperature, air.pressure, air.humidity
            )
            .unwrap();
        }
        time += 5.0;
        writeln!(
            csv,
            "{time:.3},point_{k},garbage,0,0,1e-5,1e-5,1e-5,0,0,0,20,1e5,0.4"
        )
        .unwrap();
    }
    let path = dir.join("export.csv");
    std::fs::write(&path, csv).unwrap();
    let output = dir.join("out");
    let run = Command::new(env!("CARGO_BIN_EXE_metrocell-tracker"))
        .arg("--bag")
        .arg(&path)
        .arg("--output")
        .arg(&output)
        .args([
            "--ros-args",
            "-p",
            "registration_points:=4",
            "-p",
            "max_range:=50.0",
        ])
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(
        stderr.contains("rejected_readings=1") && stderr.contains("readings=39"),
        "{stderr}"
    );
    assert!(
        stderr.contains("range = ") && stderr.contains("outside"),
        "the out-of-range reading is named: {stderr}"
    );
    assert!(
        stderr.contains("'NaN' is not finite") && stderr.contains("'garbage' is not a number"),
        "the importer names bad cells: {stderr}"
    );
    let mut s = BagSource::open(&output).unwrap();
    s.subscribe::<MeasuredPoint>("/measured_points").unwrap();
    let points: Vec<MeasuredPoint> = s
        .messages()
        .unwrap()
        .map(|m| m.unwrap().decode().unwrap())
        .collect();
    assert_eq!(
        points
            .iter()
            .map(|p| p.point_id.as_str())
            .collect::<Vec<_>>(),
        ["point_0", "point_1", "point_2", "point_3"],
        "{stderr}"
    );
    for (p, q) in points.iter().zip(&nominals) {
        assert_eq!((p.nominal.x, p.nominal.y, p.nominal.z), (q.x, q.y, q.z));
        let m = Vector3::new(p.measured.x, p.measured.y, p.measured.z);
        // noise-free export: refraction re-corrected and registered back onto the nominal
        assert!((m - q).norm() < 1e-9, "{}: {m:?} vs {q:?}", p.point_id);
    }
    let _ = std::fs::remove_dir_all(&dir);
}
