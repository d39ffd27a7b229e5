//! Catalog completeness and config validation errors.

use metrocell_physics::catalog::{allowed_ids, configure, entries, example_config, lookup};
use metrocell_physics::{PhysicsError, TermConfig, TermId};

/// The ids of DESIGN.md "The physics vocabulary", verbatim, and `rotary_axis_location` (issue 13:
/// the catalog grows with the physics real machines need; its line goes into DESIGN.md's list),
/// `instrument_drift` (issue 26), the gravity terms of arms and columns and the levelled
/// instrument's `base_tilt` (issue 27).
const DESIGN_IDS: [&str; 33] = [
    "positioning",
    "straightness",
    "angular",
    "squareness",
    "pitch_cyclic",
    "backlash",
    "thermal_scale",
    "thermal_growth",
    "workpiece_expansion",
    "tracker_warmup",
    "refraction",
    "turbulence",
    "tracker_pose",
    "probe_pretravel",
    "lens_distortion",
    "camera_scale",
    "time_offset",
    "compliance",
    "tool_offset",
    "delta_rod_length",
    "delta_radius",
    "delta_tower_angle",
    "delta_endstop",
    "joint_offset",
    "link_length",
    "frame_misalignment",
    "rotary_axis_location",
    "instrument_drift",
    "joint_compliance",
    "joint_backlash",
    "column_bending",
    "link_thermal_expansion",
    "base_tilt",
];

#[test]
fn catalog_lists_every_design_id_with_docs() {
    let listed: Vec<&str> = entries().iter().map(|e| e.id.as_str()).collect();
    assert_eq!(listed.len(), DESIGN_IDS.len());
    for id in DESIGN_IDS {
        assert!(listed.contains(&id), "{id} missing");
        let t = lookup(id).unwrap();
        assert_eq!(t.as_str(), id);
        assert!(!t.summary().is_empty() && !t.equation().is_empty());
        // every example config builds, and every parameter has a unit, a usual range inside its
        // possible range, and a default inside both
        let built = configure(&example_config(t)).unwrap_or_else(|e| panic!("{id}: {e}"));
        assert_eq!(built.term.id(), t);
        for p in built.term.params() {
            assert!(
                p.usual.lo < p.usual.hi && p.usual.lo.is_finite() && p.usual.hi.is_finite(),
                "{id}.{}: usual range {:?}",
                p.name,
                p.usual
            );
            assert!(
                p.possible.lo <= p.usual.lo && p.possible.hi >= p.usual.hi,
                "{id}.{}: usual {:?} outside possible {:?}",
                p.name,
                p.usual,
                p.possible
            );
            assert!(
                p.usual.contains(p.default),
                "{id}.{}: default {} outside the usual range",
                p.name,
                p.default
            );
            metrocell_physics::units::parse_unit(p.unit)
                .unwrap_or_else(|e| panic!("{id}.{}: {e}", p.name));
        }
    }
}

fn yaml(text: &str) -> TermConfig {
    serde_yaml::from_str(text).unwrap()
}

#[test]
fn unknown_id_lists_the_allowed_ids() {
    let e = configure(&yaml("id: thermal_scal\n")).unwrap_err();
    match &e {
        PhysicsError::UnknownTerm { id, allowed } => {
            assert_eq!(id, "thermal_scal");
            assert_eq!(allowed, &allowed_ids());
            assert!(allowed.contains("thermal_scale") && allowed.contains("frame_misalignment"));
        }
        other => panic!("{other:?}"),
    }
    assert!(e
        .to_string()
        .contains("allowed ids: positioning, straightness"));
}

#[test]
fn a_full_yaml_config_with_unit_suffixes_is_read_in_si() {
    let c = configure(&yaml(
        "id: thermal_scale\noptions:\n  axis: x\n  sensors:\n    - {name: x_left, position: 0 mm}\n    - {name: x_right, position: 1200 mm}\n  reference_temperature: 293.15 K\nparams:\n  alpha: 11.5e-6 1/K\n",
    ))
    .unwrap();
    assert_eq!(c.term.label(), "thermal_scale[x]");
    assert!((c.params[0] - 11.5e-6).abs() < 1e-18);
    let c = configure(&yaml(
        "id: pitch_cyclic\noptions: {axis: y, lead: 5 mm}\nparams: {a1: 2 um, b1: -1.5e-6}\n",
    ))
    .unwrap();
    assert_eq!(c.params, vec![2e-6, -1.5e-6]);
    let c = configure(&yaml(
        "id: tracker_warmup\nparams: {offset: 0, amplitude: 19 um, time_constant: 30 min}\n",
    ))
    .unwrap();
    assert_eq!(c.params, vec![0.0, 19e-6, 1800.0]);
}

#[test]
fn missing_parameter_is_named() {
    let e = configure(&yaml("id: backlash\noptions: {axis: x}\n")).unwrap_err();
    assert_eq!(
        e,
        PhysicsError::MissingParameter {
            term: "backlash[x]".into(),
            param: "reversal".into(),
            unit: "m".into()
        }
    );
    // ... unless defaults were asked for
    let c = configure(&yaml(
        "id: backlash\noptions: {axis: x}\nuse_defaults: true\n",
    ))
    .unwrap();
    assert_eq!(c.params, vec![0.0]);
}

#[test]
fn impossible_parameter_is_rejected_and_unusual_accepted() {
    // a sign-free quantity has no possible bound: an over-compensated backlash and a worn one
    for v in ["-9 um", "5 mm"] {
        configure(&yaml(&format!(
            "id: backlash\noptions: {{axis: z}}\nparams: {{reversal: {v}}}\n"
        )))
        .unwrap_or_else(|e| panic!("{v}: {e}"));
    }
    let e = configure(&yaml("id: thermal_scale\noptions: {axis: x, sensors: [{name: t, position: 0 m}]}\nparams: {alpha: 500e-6 1/K}\n")).unwrap_err();
    match e {
        PhysicsError::OutOfRange {
            term,
            param,
            value,
            min,
            max,
            ..
        } => {
            assert_eq!(
                (term.as_str(), param.as_str()),
                ("thermal_scale[x]", "alpha")
            );
            assert!((value - 500e-6).abs() < 1e-15 && min == -100e-6 && max == 100e-6);
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn wrong_unit_names_key_and_allowed_unit() {
    let e = configure(&yaml(
        "id: thermal_growth\noptions: {sensor: column}\nparams: {coefficient: 12 um}\n",
    ))
    .unwrap_err();
    match &e {
        PhysicsError::WrongUnit {
            term,
            key,
            given,
            allowed,
            ..
        } => {
            assert_eq!(
                (
                    term.as_str(),
                    key.as_str(),
                    given.as_str(),
                    allowed.as_str()
                ),
                ("thermal_growth[column]", "coefficient", "um", "m/K")
            );
        }
        other => panic!("{other:?}"),
    }
    assert!(e.to_string().contains("length per kelvin"), "{e}");
    let e = configure(&yaml(
        "id: squareness\noptions: {pair: xy}\nparams: {s: 12 um}\n",
    ))
    .unwrap_err();
    assert!(
        matches!(e, PhysicsError::WrongUnit { ref key, ref allowed, .. } if key == "s" && allowed == "rad"),
        "{e}"
    );
    // options are unit-checked too
    let e = configure(&yaml(
        "id: pitch_cyclic\noptions: {axis: x, lead: 5 s}\nuse_defaults: true\n",
    ))
    .unwrap_err();
    assert!(
        matches!(e, PhysicsError::WrongUnit { ref key, .. } if key == "lead"),
        "{e}"
    );
}

#[test]
fn unknown_parameter_option_and_bad_option_values() {
    let e = configure(&yaml(
        "id: backlash\noptions: {axis: x}\nparams: {reversal: 1 um, extra: 2}\n",
    ))
    .unwrap_err();
    assert!(
        matches!(e, PhysicsError::UnknownParameter { ref param, ref allowed, .. } if param == "extra" && allowed == "reversal"),
        "{e}"
    );
    let e = configure(&yaml(
        "id: backlash\noptions: {axis: x, colour: red}\nuse_defaults: true\n",
    ))
    .unwrap_err();
    assert!(
        matches!(e, PhysicsError::UnknownOption { ref key, .. } if key == "colour"),
        "{e}"
    );
    let e = configure(&yaml(
        "id: backlash\noptions: {axis: w}\nuse_defaults: true\n",
    ))
    .unwrap_err();
    assert!(e.to_string().contains("`w` is not an axis"), "{e}");
    let e = configure(&yaml(
        "id: straightness\noptions: {axis: x, direction: x}\nuse_defaults: true\n",
    ))
    .unwrap_err();
    assert!(
        matches!(e, PhysicsError::BadOption { ref key, .. } if key == "direction"),
        "{e}"
    );
    let e = configure(&yaml(
        "id: positioning\noptions: {axis: x, travel: [1 m, 0 m]}\nuse_defaults: true\n",
    ))
    .unwrap_err();
    assert!(
        matches!(e, PhysicsError::BadOption { ref key, .. } if key == "travel"),
        "{e}"
    );
    let e = configure(&yaml(
        "id: thermal_scale\noptions: {axis: x}\nuse_defaults: true\n",
    ))
    .unwrap_err();
    assert!(
        matches!(e, PhysicsError::BadOption { ref key, .. } if key == "sensors"),
        "{e}"
    );
    let e = configure(&yaml(
        "id: backlash\noptions: {axis: x}\nparams: {reversal: lots}\n",
    ))
    .unwrap_err();
    assert!(
        matches!(e, PhysicsError::BadValue { ref key, .. } if key == "reversal"),
        "{e}"
    );
}

#[test]
fn missing_signals_and_wrong_parameter_count_are_errors_not_panics() {
    let c = configure(&example_config(TermId::ThermalScale)).unwrap();
    let e = c
        .term
        .predict(&c.params, &metrocell_physics::Signals::default())
        .unwrap_err();
    assert!(e.to_string().contains("axis_position[x]"), "{e}");
    let e = c
        .term
        .predict(&[1.0, 2.0], &metrocell_physics::Signals::default())
        .unwrap_err();
    assert!(matches!(
        e,
        PhysicsError::ParameterCount {
            expected: 1,
            got: 2,
            ..
        }
    ));
    let k = configure(&example_config(TermId::DeltaRadius)).unwrap();
    assert!(matches!(
        k.term.predict(&k.params, &Default::default()),
        Err(PhysicsError::NeedsKinematics { .. })
    ));
}

#[test]
fn readme_documents_every_id_with_its_equation() {
    let readme =
        std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/README.md")).unwrap();
    for e in entries() {
        assert!(
            readme.contains(&format!("| `{}` |", e.id.as_str())),
            "{} missing from README",
            e.id
        );
        assert!(
            readme.contains(e.equation),
            "equation of {} out of date in README",
            e.id
        );
    }
}
