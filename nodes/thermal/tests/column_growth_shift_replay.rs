//! Column growth with lag on twin data, through the node (`metrocell-thermal --bag`; thesis
//! Ch. 5.5.3 column-growth result). The twin's `xfyz_shift` cell grows its column by 4 µm/K
//! along −Z, lagging the column sensor by 20 min, over an 8-hour shift. The bag carries the
//! column thermocouple and the tracker's points at program points 0 and 1 as `MeasuredPoint`s
//! (measured = the tracker point in the workpiece frame, nominal = the commanded tool point,
//! covariance = the tracker's, rotated). After correction the Z drift of point 1 stays within
//! ±5 µm:
//!   * configured with the true g and τ: over the whole shift;
//!   * configured with wrong values (2 µm/K, 10 min) and fitting g and τ online from point 0's
//!     measurements, which the bag carries only for hours 0–4: on the held-out hours 4–8, and the
//!     fitted g and τ lie within 3 standard uncertainties of the truth.
//!
//! Z drift of one dwell = the mean of its ~30 readings (single readings scatter by ~4 µm, the
//! tracker's stated noise). The cell's tracker warm-up is switched off (a 75 µm range drift, the
//! tracker node's correction, not this one); no other term of the cell acts along Z, so the
//! points' static Z error is zero.

use std::path::Path;
use std::process::Command;

use metrocell_bag::{qos_profiles_yaml, BagWriter, QosProfile, WriterOptions};
use metrocell_bagtools::{encode_cdr, BagSource};
use metrocell_msgs::builtin_interfaces::msg::Time;
use metrocell_msgs::geometry_msgs::msg::Point;
use metrocell_msgs::msg::{ErrorModel, MeasuredPoint};
use metrocell_msgs::sensor_msgs::msg::Temperature;
use metrocell_msgs::std_msgs::msg::Header;
use metrocell_twin::{Cell, Sample, SampleTruth, Simulation, TrackerStatus};
use rosmsg::RosMessage;

const T0: u64 = 1_700_000_000_000_000_000;
const HOUR: f64 = 3600.0;

fn cell() -> Cell {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../crates/twin/examples/cells/xfyz_shift.yaml"
    );
    let text = std::fs::read_to_string(path).unwrap();
    let warm = "warmup: {offset: 0 um, amplitude: 75 um, time_constant: 90 min}";
    let state = "machine_state: {rate: 100 Hz}";
    assert!(
        text.contains(warm) && text.contains(state),
        "xfyz_shift.yaml changed; update this test"
    );
    let text = text
        .replace(
            warm,
            "warmup: {offset: 0 um, amplitude: 0 um, time_constant: 90 min}",
        )
        .replace(state, "machine_state: {rate: 1 Hz}");
    Cell::from_yaml_str(&text, path).unwrap()
}

fn stamp(t: f64) -> (u64, Header) {
    let ns = T0 + (t * 1e9).round() as u64;
    (
        ns,
        Header {
            stamp: Time::from_nanos(ns as i64),
            frame_id: "machine".into(),
        },
    )
}

/// Writes the bag; returns the nominal of program point 0 (the reference point).
fn write_shift_bag(dir: &Path) -> [f64; 3] {
    let cell = cell();
    let pose = cell.tracker.clone().unwrap().pose;
    let tool = cell.machine.tool_offset;
    let sim = Simulation::new(cell, 8.0 * HOUR, 11).unwrap();
    let mut w = BagWriter::create(dir, WriterOptions::default()).unwrap();
    let qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
    w.add_topic(
        "/cg/temperature/column",
        Temperature::ROS_TYPE,
        Temperature::DEFINITION,
        &qos,
    )
    .unwrap();
    w.add_topic(
        "/cg/measured_points",
        MeasuredPoint::ROS_TYPE,
        MeasuredPoint::DEFINITION,
        &qos,
    )
    .unwrap();
    let mut reference = [f64::NAN; 3];
    let mut k = 0;
    for (s, truth) in sim.samples_with_truth() {
        match (s, truth) {
            (Sample::Temperature(t), _) if &*t.sensor == "column" => {
                let (ns, header) = stamp(t.t);
                w.write(
                    "/cg/temperature/column",
                    ns,
                    ns,
                    &encode_cdr(&Temperature {
                        header,
                        temperature: t.value,
                        variance: t.variance,
                    })
                    .unwrap(),
                )
                .unwrap();
            }
            (Sample::Tracker(m), SampleTruth::Tracker(tt))
                if m.status == TrackerStatus::Ok
                    && (m.target_id == Some(1) || (m.target_id == Some(0) && m.t < 4.0 * HOUR)) =>
            {
                let measured = pose.rotation * m.point + pose.translation;
                let nominal = tt.commanded + tool;
                let cov = pose.rotation * m.covariance * pose.rotation.transpose();
                if m.target_id == Some(0) {
                    reference = [nominal.x, nominal.y, nominal.z];
                }
                let (ns, header) = stamp(m.t);
                let mut covariance = [0.0; 9];
                covariance.copy_from_slice(cov.transpose().as_slice());
                let p = MeasuredPoint {
                    header,
                    point_id: format!("t{}_{k}", m.target_id.unwrap()),
                    source: "tracker".into(),
                    nominal: Point {
                        x: nominal.x,
                        y: nominal.y,
                        z: nominal.z,
                    },
                    measured: Point {
                        x: measured.x,
                        y: measured.y,
                        z: measured.z,
                    },
                    covariance,
                };
                k += 1;
                w.write("/cg/measured_points", ns, ns, &encode_cdr(&p).unwrap())
                    .unwrap();
            }
            _ => {}
        }
    }
    w.finish().unwrap();
    reference
}

/// (time s, Z error m) per dwell.
type Dwells = Vec<(f64, f64)>;

/// Runs the node on the bag; returns (point 1's dwell means of the Z error (s, m) uncorrected and
/// corrected, the last error model, the log).
fn run(input: &Path, output: &Path, params: &[String]) -> (Dwells, Dwells, ErrorModel, String) {
    let mut args = vec!["--ros-args".to_string(), "-r".into(), "__ns:=/cg".into()];
    for p in params {
        args.extend(["-p".to_string(), p.clone()]);
    }
    let out = Command::new(env!("CARGO_BIN_EXE_metrocell-thermal"))
        .arg("--bag")
        .arg(input)
        .arg("--output")
        .arg(output)
        .args(&args)
        .output()
        .unwrap();
    let log =
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{log}");
    let mut source = BagSource::open(output).unwrap();
    source
        .subscribe::<MeasuredPoint>("/cg/measured_points/thermal_compensated")
        .unwrap();
    source
        .subscribe::<ErrorModel>("/cg/thermal/error_model")
        .unwrap();
    let (mut raw, mut corrected, mut model) = (Vec::new(), Vec::new(), None);
    for m in source.messages().unwrap() {
        let m = m.unwrap();
        if m.topic.ends_with("thermal_compensated") {
            let p: MeasuredPoint = m.decode().unwrap();
            if p.point_id.starts_with("t1_") {
                let t = (m.log_time_ns - T0) as f64 * 1e-9;
                corrected.push((t, p.measured.z - p.nominal.z));
            }
        } else {
            model = Some(m.decode::<ErrorModel>().unwrap());
        }
    }
    // the uncorrected values, from the input bag
    let mut source = BagSource::open(input).unwrap();
    source
        .subscribe::<MeasuredPoint>("/cg/measured_points")
        .unwrap();
    for m in source.messages().unwrap() {
        let p: MeasuredPoint = m.unwrap().decode().unwrap();
        if p.point_id.starts_with("t1_") {
            raw.push((0.0, p.measured.z - p.nominal.z));
        }
    }
    (
        dwell_means(&raw_with_times(&raw, &corrected)),
        dwell_means(&corrected),
        model.unwrap(),
        log,
    )
}

/// The input's values with the times of the outputs (every point 1 reading is compensated).
fn raw_with_times(raw: &[(f64, f64)], corrected: &[(f64, f64)]) -> Vec<(f64, f64)> {
    assert_eq!(
        raw.len(),
        corrected.len(),
        "every reading of point 1 is compensated"
    );
    corrected.iter().zip(raw).map(|(c, r)| (c.0, r.1)).collect()
}

/// Mean per dwell (readings closer than 60 s belong to one dwell).
fn dwell_means(v: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64, usize)> = Vec::new();
    let mut last = f64::NEG_INFINITY;
    for &(t, z) in v {
        if t - last > 60.0 {
            out.push((t, 0.0, 0));
        }
        let d = out.last_mut().unwrap();
        (d.1, d.2) = (d.1 + z, d.2 + 1);
        last = t;
    }
    out.into_iter().map(|(t, s, n)| (t, s / n as f64)).collect()
}

fn growth_params(g: f64, tau: f64) -> Vec<String> {
    [
        "growth_sensors:=[column]".to_string(),
        "growth_directions:=[0.0, 0.0, -1.0]".into(),
        format!("growth_coefficients:=[{g:e}]"),
        format!("growth_time_constants:=[{tau:.1}]"),
    ]
    .into()
}

#[test]
fn z_drift_of_a_fixed_point_stays_within_5_um_after_correction() {
    let tmp = std::env::temp_dir().join(format!(
        "metrocell-thermal-column-growth-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let input = tmp.join("input");
    let reference = write_shift_bag(&input);

    // known g and τ: every dwell of point 1 within ±5 µm
    let (raw, known, _, _) = run(&input, &tmp.join("known"), &growth_params(4e-6, 1200.0));
    assert_eq!(known.len(), 16, "point 1 is visited once per 30-min cycle");
    let span = raw.iter().map(|d| d.1).fold(f64::NEG_INFINITY, f64::max)
        - raw.iter().map(|d| d.1).fold(f64::INFINITY, f64::min);
    eprintln!("uncorrected Z drift of point 1 spans {:.2} µm", span * 1e6);
    assert!(
        span > 8e-6,
        "the column growth must be visible uncorrected: {span:e} m"
    );
    for (t, z) in &known {
        eprintln!("known   {:.2} h: corrected Z {:+.2} µm", t / HOUR, z * 1e6);
        assert!(
            z.abs() <= 5e-6,
            "{:.2} h: corrected Z {:.2} µm",
            t / HOUR,
            z * 1e6
        );
    }

    // wrong configuration, fitted online from point 0 in hours 0–4; held-out hours 4–8
    let mut params = growth_params(2e-6, 600.0);
    params.push(format!(
        "fit_reference_point:=[{}, {}, {}]",
        reference[0], reference[1], reference[2]
    ));
    params.push("fit_min_observations:=60".into());
    let (_, fitted, model, log) = run(&input, &tmp.join("fitted"), &params);
    assert!(log.contains("using the fitted values"), "{log}");
    let i = model
        .parameter_names
        .iter()
        .position(|n| n == "thermal_growth[column].coefficient")
        .unwrap();
    let n = model.values.len();
    let (g, tau) = (model.values[i], model.values[i + 1]);
    let (ug, utau) = (
        model.covariance[i * n + i].sqrt(),
        model.covariance[(i + 1) * n + i + 1].sqrt(),
    );
    eprintln!(
        "fitted g = {:.3} ± {:.3} µm/K, τ = {tau:.0} ± {utau:.0} s",
        g * 1e6,
        ug * 1e6
    );
    assert!((g - 4e-6).abs() <= 3.0 * ug, "g {g} ± {ug}");
    assert!((tau - 1200.0).abs() <= 3.0 * utau, "τ {tau} ± {utau}");
    let held_out: Vec<_> = fitted.iter().filter(|d| d.0 >= 4.0 * HOUR).collect();
    assert_eq!(held_out.len(), 8);
    for (t, z) in held_out {
        eprintln!("fitted  {:.2} h: corrected Z {:+.2} µm", t / HOUR, z * 1e6);
        assert!(
            z.abs() <= 5e-6,
            "held-out {:.2} h: corrected Z {:.2} µm",
            t / HOUR,
            z * 1e6
        );
    }
    let _ = std::fs::remove_dir_all(&tmp);
}
