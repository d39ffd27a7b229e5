//! Bad parameters stop the node before it touches any data, with an error naming the parameter.
//! Run on a bag path (`--bag`, no DDS): the parameters are checked before the bag is opened.

use std::process::Command;

fn run(params: &[&str]) -> (bool, String) {
    let mut args = vec![
        "--bag",
        "/nonexistent/metrocell-thermal-bad-parameters",
        "--ros-args",
    ];
    for p in params {
        args.extend(["-p", p]);
    }
    let out = Command::new(env!("CARGO_BIN_EXE_metrocell-thermal"))
        .args(&args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stderr).into_owned() + &String::from_utf8_lossy(&out.stdout),
    )
}

#[test]
fn each_bad_parameter_is_named() {
    let growth = [
        "growth_sensors:=[column]",
        "growth_directions:=[0.0, 0.0, -1.0]",
        "growth_coefficients:=[4e-6]",
        "growth_time_constants:=[1200.0]",
    ];
    let with_growth = |extra: &[&'static str]| -> Vec<&'static str> {
        growth
            .iter()
            .copied()
            .chain(extra.iter().copied())
            .collect()
    };
    let cases: Vec<(Vec<&str>, &[&str])> = vec![
        (
            vec![
                "sensors:=[a, b]",
                "sensor_axes:=[x]",
                "sensor_positions:=[0.0, 1.0]",
            ],
            &["sensor_axes", "same length"],
        ),
        (
            vec![
                "sensors:=[a]",
                "sensor_axes:=[w]",
                "sensor_positions:=[0.0]",
            ],
            &["sensor_axes", "'w'"],
        ),
        (vec!["alpha:=1.0"], &["alpha"]),
        (
            vec![
                "growth_sensors:=[column]",
                "growth_directions:=[0.0, 1.0]",
                "growth_coefficients:=[4e-6]",
            ],
            &["growth_directions", "3 numbers per growth sensor"],
        ),
        (
            vec![
                "growth_sensors:=[column]",
                "growth_directions:=[0.0, 0.0, 1.0]",
            ],
            &["growth_coefficients", "one per growth sensor"],
        ),
        (
            with_growth(&["growth_coefficients:=[1.0]"])
                .into_iter()
                .filter(|p| *p != "growth_coefficients:=[4e-6]")
                .collect(),
            &[
                "thermal_growth[column]",
                "coefficient",
                "physically impossible",
            ],
        ),
        (
            with_growth(&["growth_time_constants:=[-5.0]"])
                .into_iter()
                .filter(|p| *p != "growth_time_constants:=[1200.0]")
                .collect(),
            &["growth_time_constants", "≥ 0"],
        ),
        (
            vec!["temperature_limits:=[50.0, 10.0]"],
            &["temperature_limits", "min < max"],
        ),
        (
            vec!["workpiece_sensor:=plate", "workpiece_clamp:=[0.1]"],
            &["workpiece_clamp", "3 finite numbers"],
        ),
        (
            with_growth(&[
                "fit_reference_point:=[0.0, 0.0, 0.0]",
                "fit_growth_sensor:=spindle",
            ]),
            &["fit_growth_sensor", "'spindle'"],
        ),
        (
            vec!["fit_reference_point:=[0.0, 0.0, 0.0]"],
            &["fit_growth_sensor", "0 growth terms"],
        ),
        (
            with_growth(&[
                "fit_reference_point:=[0.0, 0.0, 0.0]",
                "fit_time_constant_range:=[600.0, 60.0]",
            ]),
            &["fit_time_constant_range", "min < max"],
        ),
    ];
    for (params, expected) in cases {
        let (ok, output) = run(&params);
        assert!(!ok, "{params:?} was accepted");
        for e in expected {
            assert!(
                output.contains(e),
                "{params:?}: the error does not say `{e}`:\n{output}"
            );
        }
        assert!(
            !output.contains("panicked"),
            "{params:?} panicked:\n{output}"
        );
    }
}
