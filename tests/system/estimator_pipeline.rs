//! Issue 32, items 4 and 12, through the node processes a user runs on a recording (no DDS:
//! every node replays a bag; run it inside tests/isolated all the same):
//! `metrocell sim` of quick_demo.yaml for 2 h → `metrocell-tracker --bag` → `metrocell bag
//! merge` → `metrocell-estimator --bag` with quick_demo.yaml as the model.
//! * The tracker with its default `registration_points` (12) on the 6-target program writes no
//!   measured point, and says so at WARN with what to set; with `registration_points:=6` it writes
//!   one per dwell.
//! * The estimator's every published ErrorModel holds each parameter inside its term's possible
//!   range (the old filter published `pitch_cyclic[x].b1` = −1.4e10 m here), the parameter the
//!   program cannot observe is held at its start value and named at WARN and on /diagnostics.
//!
//! Run: `cargo build --workspace --bins && tests/isolated cargo test -p metrocell-system-tests --test estimator_pipeline`

use std::path::Path;
use std::time::Duration;

use system_tests::{bin, piped, run, workspace_root};

fn ok(out: &std::process::Output, what: &str) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        out.status.success(),
        "{what} failed ({}):\n{stderr}",
        out.status
    );
    stderr
}

/// The possible range of each parameter of quick_demo.yaml's terms (crates/physics catalog).
/// Each parameter's possible range, from the catalog (what the estimator must never publish
/// outside), by `label.param` of quick_demo.yaml's model.
fn possible_ranges() -> std::collections::BTreeMap<String, (f64, f64)> {
    let cell = metrocell_twin::CellModel::from_path(
        workspace_root().join("crates/twin/examples/cells/quick_demo.yaml"),
    )
    .unwrap();
    let terms = cell
        .machine_terms
        .terms
        .iter()
        .chain(&cell.instrument_terms.terms);
    terms
        .flat_map(|t| {
            t.term.params().into_iter().map(move |s| {
                (
                    format!("{}.{}", t.term.label(), s.name),
                    (s.possible.lo, s.possible.hi),
                )
            })
        })
        .collect()
}

#[test]
fn quick_demo_shift_through_tracker_and_estimator_nodes() {
    let dir = std::env::temp_dir().join(format!(
        "metrocell-estimator-pipeline-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    let cell = workspace_root().join("crates/twin/examples/cells/quick_demo.yaml");
    let long = Duration::from_secs(600);
    let bag = dir.join("shift");
    ok(
        &run(
            piped(bin("metrocell"))
                .args(["sim", "--cell"])
                .arg(&cell)
                .args(["--duration", "2h", "--no-camera-frames", "--quiet", "-o"])
                .arg(&bag),
            long,
        ),
        "metrocell sim",
    );

    // item 12: the default registration_points never completes on six targets, and says why
    let tracker = |out: &Path, extra: &[&str]| {
        let mut c = piped(bin("metrocell-tracker"));
        c.arg("--bag")
            .arg(&bag)
            .arg("--output")
            .arg(out)
            .args(["--ros-args", "-p", "tool_offset:=[0.0, 0.0, -0.1]"])
            .args(extra);
        ok(&run(&mut c, long), "metrocell-tracker --bag")
    };
    let log = tracker(&dir.join("points_default"), &[]);
    let warn = log
        .lines()
        .find(|l| l.contains("[WARN]") && l.contains("registration needs 12 distinct targets"))
        .unwrap_or_else(|| panic!("no WARN about the registration:\n{log}"));
    assert!(
        warn.contains("the program has visited 6") && warn.contains("set registration_points:=6"),
        "{warn}"
    );
    assert!(log.contains("measured_points=0"), "{log}");
    let log = tracker(&dir.join("points"), &["-p", "registration_points:=6"]);
    assert!(
        log.contains("measured_points=1440") && !log.contains("[WARN]"),
        "{log}"
    );

    let merged = dir.join("merged");
    ok(
        &run(
            piped(bin("metrocell"))
                .args(["bag", "merge"])
                .arg(&merged)
                .arg(&bag)
                .arg(dir.join("points")),
            long,
        ),
        "metrocell bag merge",
    );
    // item 4: without --output the replay writes its messages as JSON lines on stdout (megabytes:
    // into a file, not a pipe)
    let lines = dir.join("estimator.jsonl");
    let mut estimator = piped(bin("metrocell-estimator"));
    estimator
        .arg("--bag")
        .arg(&merged)
        .args(["--ros-args", "-p"])
        .arg(format!("model:={}", cell.display()))
        .stdout(std::fs::File::create(&lines).unwrap());
    let log = ok(&run(&mut estimator, long), "metrocell-estimator --bag");
    let ranges = possible_ranges();
    let mut models = 0;
    let mut held_named = false;
    for line in std::fs::read_to_string(&lines).unwrap().lines() {
        let v: serde_json::Value = serde_json::from_str(line).unwrap();
        let m = &v["message"];
        match v["topic"].as_str().unwrap() {
            "/estimator/error_model" => {
                models += 1;
                let names = m["parameter_names"].as_array().unwrap();
                for (name, value) in names.iter().zip(m["values"].as_array().unwrap()) {
                    let (name, value) = (name.as_str().unwrap(), value.as_f64().unwrap());
                    let (lo, hi) = *ranges
                        .get(name)
                        .unwrap_or_else(|| panic!("{name}: not a parameter of quick_demo.yaml"));
                    assert!(
                        value >= lo && value <= hi,
                        "published {name} = {value:e} outside [{lo:e}, {hi:e}]"
                    );
                    if name == "pitch_cyclic[x].b1" {
                        assert_eq!(value, -2e-6, "b1 is held at its start value");
                    }
                }
            }
            "/diagnostics" => {
                let status = &m["status"][0];
                if status["level"].as_u64() == Some(1) {
                    let unobservable = status["values"]
                        .as_array()
                        .unwrap()
                        .iter()
                        .find(|kv| kv["key"] == "unobservable")
                        .unwrap();
                    held_named |= unobservable["value"] == "pitch_cyclic[x].b1";
                }
            }
            _ => {}
        }
    }
    assert!(models > 1000, "{models} models published");
    assert!(
        held_named,
        "no WARN on /diagnostics naming pitch_cyclic[x].b1"
    );
    assert!(log.lines().any(|l| l.contains("[WARN]") && l.contains("at the end: not observable by the measurements so far, held at their start values: pitch_cyclic[x].b1")), "{log}");
    assert!(log.contains("alarms"), "{log}");
    let _ = std::fs::remove_dir_all(&dir);
}
