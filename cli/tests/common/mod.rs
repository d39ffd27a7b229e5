#![allow(dead_code)]
//! Helpers of the CLI's tests: a fresh scratch directory, and the `metrocell` binary run in it.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A new, empty directory for one test (removed first if a previous run left it).
pub fn scratch(prefix: &str, name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("metrocell_{prefix}_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Run `metrocell ARGS` in `cwd`: exit code, stdout, stderr.
pub fn metrocell(args: &[&str], cwd: &Path) -> (i32, String, String) {
    let o = Command::new(env!("CARGO_BIN_EXE_metrocell"))
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap();
    (
        o.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&o.stdout).into(),
        String::from_utf8_lossy(&o.stderr).into(),
    )
}
