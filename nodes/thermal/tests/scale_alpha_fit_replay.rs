//! Online fit of the axis scales' α on twin data, through the node (`metrocell-thermal --bag`),
//! mirroring `column_growth_shift_replay`. The twin's `xfyz_shift` cell is changed so that its X
//! scale is not the handbook steel the node is configured with: true α = 20e-6 1/K against the
//! configured 11.5e-6, and the shop warms faster (ambient drift 0.5 K/h instead of 0.1 K/h) so
//! that the X scale's temperature spans several kelvin over the 8-hour shift. The bag carries the
//! scale thermocouples x_left/x_right and the tracker's points at x = 800 mm as `MeasuredPoint`s
//! (measured = the tracker point in the workpiece frame, nominal = the commanded tool point).
//! Reference points: the six at y = 0 and y = 167 mm, which the bag carries only for hours 0–4;
//! held out: the six at y = 333 mm and 500 mm, over hours 4–8.
//!
//! The X error of a point at x = 800 mm varies in time only through the thermal scale (the cell's
//! other X errors — cyclic pitch, backlash, squareness — are static at a point, and are what the
//! fit's per-point offsets absorb), so the spread of each held-out point's dwell means about
//! their mean is the thermal error the correction leaves. With the configured α it is several
//! µm; with α fitted online it must drop to the dwell noise, and the fitted α must lie within 3
//! standard uncertainties of the truth.

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
use nalgebra::Vector3;
use rosmsg::RosMessage;

const T0: u64 = 1_700_000_000_000_000_000;
const HOUR: f64 = 3600.0;
const ALPHA_TRUE: f64 = 20e-6;

fn cell() -> Cell {
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../../crates/twin/examples/cells/xfyz_shift.yaml"
    );
    let text = std::fs::read_to_string(path).unwrap();
    let replace = [
        (
            "warmup: {offset: 0 um, amplitude: 75 um, time_constant: 90 min}",
            "warmup: {offset: 0 um, amplitude: 0 um, time_constant: 90 min}",
        ),
        (
            "machine_state: {rate: 100 Hz}",
            "machine_state: {rate: 1 Hz}",
        ),
        ("params: {alpha: 11.5e-6 1/K}", "params: {alpha: 20e-6 1/K}"),
        ("drift: 0.1 K/h", "drift: 0.5 K/h"),
    ];
    let mut text = text;
    for (from, to) in replace {
        assert!(
            text.contains(from),
            "xfyz_shift.yaml changed ({from}); update this test"
        );
        text = text.replace(from, to);
    }
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

/// Writes the bag; returns the nominals of the reference points.
fn write_shift_bag(dir: &Path) -> Vec<Vector3<f64>> {
    let cell = cell();
    let pose = cell.tracker.clone().unwrap().pose;
    let tool = cell.machine.tool_offset;
    let sim = Simulation::new(cell, 8.0 * HOUR, 17).unwrap();
    let mut w = BagWriter::create(dir, WriterOptions::default()).unwrap();
    let qos = qos_profiles_yaml(&[QosProfile::default_publisher()]);
    for s in ["x_left", "x_right"] {
        w.add_topic(
            &format!("/cg/temperature/{s}"),
            Temperature::ROS_TYPE,
            Temperature::DEFINITION,
            &qos,
        )
        .unwrap();
    }
    w.add_topic(
        "/cg/measured_points",
        MeasuredPoint::ROS_TYPE,
        MeasuredPoint::DEFINITION,
        &qos,
    )
    .unwrap();
    let mut references: Vec<Vector3<f64>> = Vec::new();
    let mut k = 0;
    for (s, truth) in sim.samples_with_truth() {
        match (s, truth) {
            (Sample::Temperature(t), _) if &*t.sensor == "x_left" || &*t.sensor == "x_right" => {
                let (ns, header) = stamp(t.t);
                w.write(
                    &format!("/cg/temperature/{}", t.sensor),
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
                    && m.target_id.is_some()
                    && tt.commanded.x > 0.79 =>
            {
                let reference = tt.commanded.y < 0.2;
                if reference && m.t >= 4.0 * HOUR {
                    continue;
                }
                let measured = pose.rotation * m.point + pose.translation;
                let nominal = tt.commanded + tool;
                if reference && !references.iter().any(|r| (r - nominal).norm() < 1e-9) {
                    references.push(nominal);
                }
                let cov = pose.rotation * m.covariance * pose.rotation.transpose();
                let (ns, header) = stamp(m.t);
                let mut covariance = [0.0; 9];
                covariance.copy_from_slice(cov.transpose().as_slice());
                let p = MeasuredPoint {
                    header,
                    point_id: format!(
                        "{}{}_{k}",
                        if reference { "r" } else { "e" },
                        m.target_id.unwrap()
                    ),
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
    references
}

/// Runs the node on the bag; returns (the RMS spread of the held-out points' X dwell means over
/// hours 4–8 about each point's mean (m), the last error model, the log).
fn run(input: &Path, output: &Path, params: &[String]) -> (f64, ErrorModel, String) {
    let mut args = vec!["--ros-args".to_string(), "-r".into(), "__ns:=/cg".into()];
    for p in [
        "sensors:=[x_left, x_right]",
        "sensor_axes:=[x, x]",
        "sensor_positions:=[0.0, 0.8]",
    ]
    .iter()
    .map(|s| s.to_string())
    .chain(params.iter().cloned())
    {
        args.extend(["-p".to_string(), p]);
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
    // per held-out point (keyed by its nominal y, z in mm): (time, X error) of its readings
    let mut series: std::collections::BTreeMap<(i64, i64), Vec<(f64, f64)>> = Default::default();
    let mut model = None;
    for m in source.messages().unwrap() {
        let m = m.unwrap();
        if m.topic.ends_with("thermal_compensated") {
            let p: MeasuredPoint = m.decode().unwrap();
            let t = (m.log_time_ns - T0) as f64 * 1e-9;
            if p.point_id.starts_with('e') && t >= 4.0 * HOUR {
                series
                    .entry((
                        (p.nominal.y * 1e3).round() as i64,
                        (p.nominal.z * 1e3).round() as i64,
                    ))
                    .or_default()
                    .push((t, p.measured.x - p.nominal.x));
            }
        } else {
            model = Some(m.decode::<ErrorModel>().unwrap());
        }
    }
    assert_eq!(series.len(), 6, "six held-out points");
    let (mut sum2, mut n) = (0.0, 0);
    for v in series.values() {
        let means = dwell_means(v);
        assert_eq!(means.len(), 8, "one dwell per 30-min cycle in hours 4–8");
        let mean = means.iter().map(|d| d.1).sum::<f64>() / means.len() as f64;
        for d in &means {
            sum2 += (d.1 - mean).powi(2);
            n += 1;
        }
    }
    ((sum2 / n as f64).sqrt(), model.unwrap(), log)
}

/// Mean per dwell (readings closer than 60 s belong to one dwell).
fn dwell_means(v: &[(f64, f64)]) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64, usize)> = Vec::new();
    let mut last = f64::NEG_INFINITY;
    for &(t, x) in v {
        if t - last > 60.0 {
            out.push((t, 0.0, 0));
        }
        let d = out.last_mut().unwrap();
        (d.1, d.2) = (d.1 + x, d.2 + 1);
        last = t;
    }
    out.into_iter().map(|(t, s, n)| (t, s / n as f64)).collect()
}

#[test]
fn fitted_alpha_removes_the_thermal_x_error_the_configured_alpha_leaves() {
    let tmp = std::env::temp_dir().join(format!(
        "metrocell-thermal-alpha-fit-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&tmp);
    std::fs::create_dir_all(&tmp).unwrap();
    let input = tmp.join("input");
    let references = write_shift_bag(&input);
    assert_eq!(
        references.len(),
        6,
        "x = 800 mm, y = 0 and 167 mm, three heights"
    );

    // uncorrected, for scale: α = 0 (the catalog's range allows it)
    let (raw, _, _) = run(&input, &tmp.join("raw"), &["alpha:=0.0".into()]);
    // configured with the handbook steel α
    let (configured, _, _) = run(&input, &tmp.join("configured"), &[]);
    // fitted online from the reference points in hours 0–4
    let flat: Vec<String> = references
        .iter()
        .flat_map(|r| [r.x, r.y, r.z])
        .map(|v| format!("{v}"))
        .collect();
    let params = vec![
        format!("fit_alpha_points:=[{}]", flat.join(", ")),
        "fit_alpha_axis:=x".into(),
        "fit_alpha_min_observations:=200".into(),
    ];
    let (fitted, model, log) = run(&input, &tmp.join("fitted"), &params);
    assert!(log.contains("using the fitted alpha"), "{log}");
    let i = model
        .parameter_names
        .iter()
        .position(|n| n == "thermal_scale[x].alpha")
        .unwrap();
    let n = model.values.len();
    let (alpha, u) = (model.values[i], model.covariance[i * n + i].sqrt());
    eprintln!(
        "fitted α = {:.3} ± {:.3} µm/(m·K) (truth {:.3}, configured 11.5)",
        alpha * 1e6,
        u * 1e6,
        ALPHA_TRUE * 1e6
    );
    eprintln!(
        "held-out hours 4–8, RMS of the X dwell means about each point's mean: uncorrected {:.2} µm, configured α {:.2} µm, fitted α {:.2} µm",
        raw * 1e6,
        configured * 1e6,
        fitted * 1e6
    );
    assert!((alpha - ALPHA_TRUE).abs() <= 3.0 * u, "α {alpha} ± {u}");
    assert!(u < 1e-6, "u(α) {u} is informative");
    assert!(
        configured > 2e-6,
        "the wrong α leaves a visible thermal error: {configured:e} m"
    );
    assert!(
        fitted < 0.5 * configured,
        "the fitted α removes most of it: {fitted:e} vs {configured:e} m"
    );
    assert!(fitted < 1.5e-6, "down to the dwell noise: {fitted:e} m");
    let _ = std::fs::remove_dir_all(&tmp);
}
