//! Issue 32 items 6 and 7: a command whose stdout closes early (`| head`, `| true`) ends quietly
//! with its files written — no panic, no exit status 101 — and `calibrate --json -` keeps stdout
//! for the JSON alone, its words going to stderr.

mod common;

use std::os::unix::process::ExitStatusExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use common::metrocell;

fn cell(name: &str) -> String {
    format!(
        "{}/../launch-configs/cells/{name}",
        env!("CARGO_MANIFEST_DIR")
    )
}

/// A 5-minute recording of the quick demo cell in `d/bag`.
fn quick_bag(d: &Path) -> PathBuf {
    let (code, out, err) = metrocell(
        &[
            "sim",
            "--cell",
            &cell("quick_demo.yaml"),
            "--duration",
            "5min",
            "--no-camera-frames",
            "--quiet",
            "-o",
            "bag",
        ],
        d,
    );
    assert_eq!(code, 0, "{out}{err}");
    d.join("bag")
}

/// Run `metrocell ARGS` in `cwd` with its stdout a pipe closed before it writes: (status, stderr).
fn with_stdout_closed(args: &[&str], cwd: &Path) -> (std::process::ExitStatus, String) {
    let mut child = Command::new(env!("CARGO_BIN_EXE_metrocell"))
        .args(args)
        .current_dir(cwd)
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    drop(child.stdout.take());
    let out = child.wait_with_output().unwrap();
    (
        out.status,
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

#[test]
fn a_closed_stdout_ends_calibrate_quietly_after_its_files() {
    let d = common::scratch("closed_stdout", "calibrate");
    quick_bag(&d);
    let (status, err) = with_stdout_closed(
        &[
            "calibrate",
            "--model",
            &cell("quick_demo.yaml"),
            "bag",
            "-o",
            "y.yaml",
            "--report",
            "report",
            "--json",
            "r.json",
        ],
        &d,
    );
    assert!(
        !err.contains("panicked") && !err.contains("Broken pipe"),
        "no panic on a closed stdout:\n{err}"
    );
    assert_ne!(status.code(), Some(101), "{err}");
    // ended by SIGPIPE, as `cat` or `grep` are, or finished before writing (0)
    assert!(
        status.signal() == Some(13) || status.success(),
        "{status:?}\n{err}"
    );
    let fitted = std::fs::read_to_string(d.join("y.yaml"))
        .expect("the fitted model is written whatever stdout does");
    assert!(fitted.contains("uncertainty:"), "{fitted}");
    assert!(
        d.join("report/index.html").exists() && d.join("r.json").exists(),
        "the report and the JSON are written too"
    );

    // a quick command too: bag info
    let (status, err) = with_stdout_closed(&["bag", "info", "bag"], &d);
    assert!(
        !err.contains("panicked") && status.code() != Some(101),
        "{status:?}\n{err}"
    );
}

#[test]
fn calibrate_json_to_stdout_is_json_alone() {
    let d = common::scratch("closed_stdout", "json");
    quick_bag(&d);
    let (code, out, err) = metrocell(
        &[
            "calibrate",
            "--model",
            &cell("quick_demo.yaml"),
            "bag",
            "-o",
            "y.yaml",
            "--json",
            "-",
        ],
        &d,
    );
    assert_eq!(code, 0, "{err}");
    let json: serde_json::Value = serde_json::from_str(&out)
        .unwrap_or_else(|e| panic!("stdout is not JSON alone ({e}):\n{out}"));
    assert_eq!(json["model"], "y.yaml");
    assert!(
        json["parameters"].as_array().is_some_and(|p| !p.is_empty()),
        "{json}"
    );
    // the words went to stderr, and say the iterations and why the fit stopped in words
    assert!(
        err.contains("Fitted ") && err.contains("fitted model written to y.yaml"),
        "{err}"
    );
    let fitted_line = err
        .lines()
        .find(|l| l.starts_with("fitted in "))
        .unwrap_or_else(|| panic!("{err}"));
    assert!(
        fitted_line.contains(" iteration")
            && fitted_line.contains("; converged: ")
            && !fitted_line.contains("Cost"),
        "{fitted_line}"
    );
    assert!(!fitted_line.contains("(1 iterations"), "{fitted_line}");
    assert!(d.join("y.yaml").exists());
}
