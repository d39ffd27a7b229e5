//! Bad cell files give errors naming the key and the allowed values.

mod common;

use common::{assert_mentions, error_of};

use metrocell_twin::Cell;

/// The demo file with `from` replaced by `to` (exactly once).
fn edited(from: &str, to: &str) -> String {
    common::edited_example("quick_demo.yaml", from, to)
}

#[test]
fn the_examples_are_valid() {
    for f in [
        "quick_demo.yaml",
        "xfyz_shift.yaml",
        "delta_printer.yaml",
        "five_axis_table.yaml",
        "serial_arm_ur5.yaml",
    ] {
        Cell::from_path(common::cell_path(f)).unwrap_or_else(|e| panic!("{f}: {e}"));
    }
}

#[test]
fn unknown_term_id_lists_the_allowed_ids() {
    let msg = error_of(&edited("  - id: pitch_cyclic", "  - id: pitch_cycle"));
    assert_mentions(
        &msg,
        &[
            "terms[1]",
            "pitch_cycle",
            "allowed ids",
            "pitch_cyclic",
            "thermal_scale",
            "backlash",
        ],
    );
}

#[test]
fn missing_parameter_is_named_with_its_unit() {
    let msg = error_of(&edited(
        "    params: {alpha: 10.2e-6 1/K}",
        "    params: {}",
    ));
    assert_mentions(
        &msg,
        &[
            "terms[0]",
            "thermal_scale[x]",
            "missing parameter `alpha`",
            "1/K",
        ],
    );
}

#[test]
fn impossible_parameter_gives_the_possible_range() {
    let msg = error_of(&edited(
        "    params: {alpha: 10.2e-6 1/K}",
        "    params: {alpha: 500e-6 1/K}",
    ));
    assert_mentions(
        &msg,
        &[
            "terms[0]",
            "alpha",
            "physically impossible",
            "[-0.0001, 0.0001] 1/K",
        ],
    );
}

#[test]
fn unusual_but_possible_values_are_accepted() {
    // an over-compensated backlash (negative reversal) and a 5 mm reversal are unusual, not
    // impossible: a sign-free quantity has no possible bound
    for v in ["-9 um", "5 mm"] {
        let text = edited(
            "params: {reversal: 8 um}",
            &format!("params: {{reversal: {v}}}"),
        );
        Cell::from_yaml_str(&text, "unusual.yaml").unwrap_or_else(|e| panic!("reversal {v}: {e}"));
    }
}

#[test]
fn wrong_unit_in_a_term_names_the_parameter_and_the_unit() {
    let msg = error_of(&edited(
        "params: {a1: 3 um, b1: -2 um}",
        "params: {a1: 3 urad, b1: -2 um}",
    ));
    assert_mentions(&msg, &["terms[1]", "`a1`", "urad", "use `m`"]);
}

#[test]
fn wrong_unit_in_a_sensor_names_the_key() {
    let msg = error_of(&edited(
        "range_noise: {constant: 4 um,",
        "range_noise: {constant: 4 K,",
    ));
    assert_mentions(
        &msg,
        &["sensors.tracker.range_noise.constant", "`K`", "use `m`"],
    );
    let msg = error_of(&edited("    rate: 10 Hz", "    rate: 10 mm"));
    assert_mentions(&msg, &["sensors.tracker.rate", "Hz"]);
}

#[test]
fn unknown_key_is_rejected_with_the_expected_keys() {
    let msg = error_of(&edited(
        "    angular_noise: 3 urad",
        "    angular_noise: 3 urad\n    colour: red",
    ));
    assert_mentions(
        &msg,
        &[
            "bad.yaml",
            "unknown field `colour`",
            "expected one of",
            "range_noise",
            "warmup",
        ],
    );
}

#[test]
fn unknown_family_lists_the_families() {
    let msg = error_of(&edited("family: cartesian", "family: scara"));
    assert_mentions(
        &msg,
        &["scara", "cartesian", "five_axis", "delta", "serial_arm"],
    );
    let msg = error_of(&edited("family: cartesian", "family: five_axis"));
    assert_mentions(
        &msg,
        &[
            "machine.stacking",
            "family: cartesian",
            "five_axis machine takes machine.five_axis",
        ],
    );
    let msg = error_of(&edited("family: cartesian", "family: delta"));
    assert_mentions(&msg, &["machine.stacking", "machine.delta"]);
}

#[test]
fn bad_warmup_and_pretravel_are_reported_under_their_sensor() {
    let msg = error_of(&edited("time_constant: 30 min}", "time_constant: 30 m}"));
    assert_mentions(
        &msg,
        &["sensors.tracker.warmup", "time_constant", "use `s`"],
    );
    let msg = error_of(&edited("lobe_sin: 0 um", "lobe_sine: 0 um"));
    assert_mentions(
        &msg,
        &[
            "sensors.probe.pretravel",
            "lobe_sine",
            "allowed parameters",
            "lobe_sin",
        ],
    );
}

#[test]
fn sensor_terms_in_the_terms_list_are_redirected() {
    let msg = error_of(&edited("terms:\n", "terms:\n  - id: tracker_warmup\n    params: {offset: 0, amplitude: 1 um, time_constant: 1 h}\n"));
    assert_mentions(
        &msg,
        &["terms[0]", "tracker_warmup", "sensors.tracker.warmup"],
    );
}

#[test]
fn unknown_sensor_and_location_list_the_allowed_names() {
    let msg = error_of(&edited(
        "{name: x_right, position: 0.4 m}",
        "{name: x_rigth, position: 0.4 m}",
    ));
    assert_mentions(&msg, &["terms[0]", "x_rigth", "allowed: x_left, x_right"]);
    let msg = error_of(&edited(
        "{name: x_left,  location: table,",
        "{name: x_left,  location: tabel,",
    ));
    assert_mentions(
        &msg,
        &[
            "sensors.thermocouples[0].location",
            "tabel",
            "allowed: ambient, table",
        ],
    );
}

#[test]
fn program_outside_the_travel_is_rejected() {
    let msg = error_of(&edited(
        "x: {from: 0 mm, to: 400 mm, count: 3}",
        "x: {from: 0 mm, to: 450 mm, count: 3}",
    ));
    assert_mentions(&msg, &["program point", "machine.travel.x", "0.4"]);
}
