//! The soak (issue 31, item 3) in bounded form: `metrocell demo` with every node running for a
//! 6-h shift at 150× (about two and a half minutes), the live diagnose node's window 1 h (full
//! from the first hour on; the node's memory full from its first diagnosis after 2 h, the window
//! and the temperatures' hour at full rate before it), through `tests/py/soak.py` (which samples
//! every node's memory, reads the logs and the demo's recording check). Asserted: every node's
//! memory flat within 10 % of its value at the end of its warm-up (the first 4 h of cell time:
//! the twin's DDS histories are full by 3 h; the recorder's creep, below 10 % over 8 h, is held
//! to the same 2 h after it as in the 5-h form) — except the diagnose node's level between
//! diagnoses, printed, not asserted (see the test; its diagnosis peak is asserted); the twin's
//! messages all in the bag (0 missing), and no ERROR/FATAL line or panic in any node's
//! log. The full 8-h soak and its figures: BENCHMARKS.md, *The soak*.
//!
//! Run: `cargo build --workspace --bins && METROCELL_PYTHON=$PWD/.venv/bin/python tests/isolated cargo test -p metrocell-system-tests --test soak -- --nocapture`

use std::time::{Duration, Instant};

use system_tests::{bin, piped, python, require_isolated_network, workspace_root, ChildGuard};

/// The shortened shift: cell time, speed-up, the diagnose node's window (the demo diagnoses
/// every fifth of the shift: 1.2 h, so the first run already covers a full window), and the
/// others' warm-up in hours of cell time (an hour past soak.py's default: the module docs say why).
const DURATION_S: f64 = 21600.0;
const SPEED: f64 = 150.0;
const DIAGNOSE_WINDOW_S: f64 = 3600.0;
const WARMUP_H: f64 = 4.0;

/// Every process the demo starts, each judged on its own.
const NODES: [&str; 9] = [
    "metrocell",
    "metrocell-sim",
    "metrocell-tracker",
    "metrocell-fiducial",
    "metrocell-thermal",
    "metrocell-estimator",
    "metrocell-diagnose",
    "metrocell-recorder",
    "metrocell-dashboard",
];

#[test]
fn a_shortened_shift_keeps_every_nodes_memory_flat_and_loses_nothing() {
    require_isolated_network();
    let json = std::env::temp_dir().join(format!("soak_{}.json", std::process::id()));
    let started = Instant::now();
    let out = ChildGuard::spawn(
        piped(python())
            .arg(workspace_root().join("tests/py/soak.py"))
            .arg(bin("metrocell"))
            .args(["--duration", &DURATION_S.to_string()])
            .args(["--speed", &SPEED.to_string()])
            .args(["--diagnose-window", &DIAGNOSE_WINDOW_S.to_string()])
            .args(["--warmup-h", &WARMUP_H.to_string()])
            .args(["--period", "1"])
            .arg("--json")
            .arg(&json)
            .env("METROCELL_SHARE", workspace_root())
            // its own domain: nothing else in the namespace is taken for one of its nodes
            .env("ROS_DOMAIN_ID", "96"),
    )
    .wait_output(Duration::from_secs(600));
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    eprintln!(
        "{stdout}\nsoak wall time {:.0} s",
        started.elapsed().as_secs_f64()
    );
    let text = std::fs::read_to_string(&json)
        .unwrap_or_else(|e| panic!("soak.py wrote no figures ({e}):\n{stdout}\n{stderr}"));
    let _ = std::fs::remove_file(&json);
    let r: serde_json::Value = serde_json::from_str(&text).unwrap();

    assert_eq!(
        r["missing"].as_u64(),
        Some(0),
        "the twin's messages against the bag: {}\n{}",
        r["recording_check"],
        r["recorder_gaps"]
    );
    assert!(
        r["twin_messages"].as_u64().is_some_and(|n| n > 0),
        "{}",
        r["recording_check"]
    );
    let errors = r["log_errors"].as_array().expect("log_errors");
    assert!(
        errors.is_empty(),
        "error lines in the nodes' logs:\n{}",
        errors
            .iter()
            .map(|l| l.as_str().unwrap_or_default())
            .collect::<Vec<_>>()
            .join("\n")
    );
    let memory = r["memory"].as_array().expect("memory figures");
    for name in NODES {
        let n = memory
            .iter()
            .find(|n| n["node"] == name)
            .unwrap_or_else(|| panic!("{name} was not sampled: {memory:?}"));
        assert!(n.get("error").is_none(), "{name}: {}", n["error"]);
        if name == "metrocell-diagnose" {
            // Its level between diagnoses is printed, not asserted: after some diagnoses glibc
            // leaves the node 20–40 MB higher, for the rest of a suite run or until a later
            // diagnosis (settled levels [44.8, 62.4] and [63.6, 68.5] MB against 43–45 MB in
            // suite runs; 79, 72, 109, 72 MB in an 8-h one), a step the size of the leak this
            // test was written for could not be told from. Its flatness is measured where the run
            // is long enough to see both: the 8-h soak, BENCHMARKS.md (−0.07 MB per cell hour).
            // Asserted here: a diagnosis's peak does not grow (the window and its working copies).
            let settled: Vec<f64> = r["diagnoses"]
                .as_array()
                .expect("diagnoses")
                .iter()
                .filter_map(|d| d["rest_after_mb"].as_f64())
                .collect();
            eprintln!(
                "metrocell-diagnose (not asserted): settled after each diagnosis at {settled:?} MB, {} MB at its warm-up; largest deviation {} %",
                n["warmup_end_mb"], n["deviation_pct"]
            );
            let hwm = n["hwm_growth_pct"].as_f64().expect("hwm_growth_pct");
            assert!(
                hwm <= 10.0,
                "the diagnose node's diagnosis peak grew by {hwm} % after its warm-up: {n}"
            );
            continue;
        }
        assert!(
            n["flat"].as_bool() == Some(true),
            "{name} not flat within 10 % after its warm-up: {n}"
        );
    }
    // the window slid: full-window diagnoses after the first one (the warm-up's end)
    let diagnose = memory
        .iter()
        .find(|n| n["node"] == "metrocell-diagnose")
        .unwrap();
    assert!(
        diagnose["full_window_diagnoses_after_warmup"]
            .as_u64()
            .is_some_and(|k| k >= 2),
        "the diagnose node's window was full for too short a stretch: {diagnose}\n{}",
        r["diagnoses"]
    );
    // soak.py's own verdict (its exit status) judges the diagnose node by its level too; the
    // figures above are judged one by one instead
}
