//! The independent suite (`bags/independent/`, issue 26): tracker exports no metrocell code made —
//! numpy, written from the ISO 230-1/-2/-3 definitions and from how a laser tracker measures
//! (spherical readings, the index of refraction it applied, its warm-up, its stand) — imported
//! with `metrocell bag import` through their own mappings and diagnosed with the user's model.
//!
//! On the CI sample (one seed, every category: singles at the usual size, with the sign
//! reversed, at 3× the usual range and at half magnitude; a pair; nulls; an out-of-catalog
//! drift; the confounded stand-vs-column case with its reference nests) the targets of issue 26
//! hold, judged by `bags/independent/score_suite.py --require-targets` from the answer key and
//! diagnose's JSON only; `metrocell calibrate` returns the over-compensated (negative) reversal
//! within 3σ. The whole suite over three seeds is a documented command whose figures are in
//! BENCHMARKS.md (bags/independent/README.md).
//! Run: `METROCELL_PYTHON=.venv/bin/python cargo test -p metrocell-system-tests --test independent_suite`
//! (needs `cargo build -p metrocell-cli`).

use std::ffi::OsStr;
use std::path::PathBuf;
use std::time::Duration;

use system_tests::{bin, piped, python, run, workspace_root};

fn os(s: &str) -> &OsStr {
    s.as_ref()
}

fn temp_dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!(
        "metrocell_independent_{name}_{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn py(args: &[&OsStr], timeout: Duration) -> std::process::Output {
    let out = run(
        piped(python()).args(args).current_dir(workspace_root()),
        timeout,
    );
    println!("{}", String::from_utf8_lossy(&out.stdout));
    eprintln!("{}", String::from_utf8_lossy(&out.stderr));
    out
}

#[test]
fn diagnose_meets_issue_26_targets_on_the_independent_sample() {
    let dir = temp_dir("sample");
    let suite = dir.join("suite");
    let o = py(
        &[
            os("bags/independent/generate_suite.py"),
            os("--out"),
            suite.as_os_str(),
            os("--seeds"),
            os("1"),
            os("--sample"),
        ],
        Duration::from_secs(300),
    );
    assert!(o.status.success(), "generate_suite.py failed");
    let results = dir.join("results.json");
    let metrocell = bin("metrocell");
    let o = py(
        &[
            os("bags/independent/score_suite.py"),
            os("--metrocell"),
            metrocell.as_os_str(),
            os("--suite"),
            suite.as_os_str(),
            os("--out"),
            results.as_os_str(),
            os("--require-targets"),
        ],
        Duration::from_secs(1800),
    );
    let text = String::from_utf8_lossy(&o.stdout);
    assert!(
        text.contains("category") && results.exists(),
        "score_suite.py printed no table: {text}"
    );
    assert!(
        o.status.success(),
        "issue 26 targets missed on the independent sample (table above)"
    );
    let _ = std::fs::remove_dir_all(&dir);
}
