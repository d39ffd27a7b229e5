//! Helpers shared by the cross-process tests: where the binaries and the Python peers are, and
//! child processes that never outlive a failing test.

pub mod camera_recording;
pub mod hosts;
pub mod points_ramp;
pub mod roundtrip;

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// The repository root.
pub fn workspace_root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("tests/ has a parent")
        .to_path_buf()
}

/// A binary of the workspace (metrocell, metrocell-thermal, ...), from the same target directory
/// as the running test.
pub fn bin(name: &str) -> PathBuf {
    let exe = std::env::current_exe().expect("current_exe");
    // target/<profile>/deps/<test>-<hash>
    let dir = exe
        .parent()
        .and_then(Path::parent)
        .expect("test binary lives in target/<profile>/deps");
    let path = dir.join(name);
    assert!(
        path.exists(),
        "{} is not built; build the workspace binaries first (`cargo build --workspace --bins`, which tests/run does)",
        path.display()
    );
    path
}

/// The Python interpreter of the test venv holding the real peers (cyclonedds, rosbags, mcap).
pub fn python() -> PathBuf {
    if let Ok(p) = std::env::var("METROCELL_PYTHON") {
        return PathBuf::from(p);
    }
    let venv = workspace_root().join(".venv/bin/python");
    assert!(
        venv.exists(),
        "no Python peers: run tests/run, which creates .venv with cyclonedds, rosbags and mcap"
    );
    venv
}

/// The secured Cyclone DDS peer (tests/secure_cyclone/setup.sh, run by tests/run): its Python
/// interpreter and the directory of Cyclone's DDS-Security plugins (for LD_LIBRARY_PATH).
pub fn secure_cyclone_python() -> (PathBuf, PathBuf) {
    let venv = workspace_root().join(".venv-secure-cyclone");
    let plugins = std::fs::read_to_string(venv.join("plugins-dir"));
    let python = venv.join("bin/python");
    assert!(
        python.exists() && plugins.is_ok(),
        "no secured Cyclone DDS peer: run tests/run, or tests/secure_cyclone/setup.sh (it installs Debian's cyclonedds-dev and builds the binding against it)"
    );
    (python, PathBuf::from(plugins.unwrap().trim()))
}

/// The Cyclone DDS peer script.
pub fn ros2_peer() -> PathBuf {
    workspace_root().join("tests/py/ros2_peer.py")
}

pub use metrocell_node::testing::require_isolated_network;

/// A child process killed (SIGKILL) when dropped, so a failing assertion cannot leak it.
pub struct ChildGuard(pub Option<Child>);

impl ChildGuard {
    pub fn spawn(cmd: &mut Command) -> ChildGuard {
        ChildGuard(Some(
            cmd.spawn()
                .unwrap_or_else(|e| panic!("cannot start {cmd:?}: {e}")),
        ))
    }

    pub fn child(&mut self) -> &mut Child {
        self.0.as_mut().expect("child already taken")
    }

    pub fn pid(&self) -> i32 {
        self.0.as_ref().expect("child").id() as i32
    }

    /// Waits for the process to exit, at most `timeout`; returns its output or panics.
    pub fn wait_output(mut self, timeout: Duration) -> Output {
        // the pipes are read while the process runs: a child that writes more than a pipe holds
        // (64 KB: a diagnosis as JSON) would otherwise block on its write and never finish
        fn drain<R: std::io::Read + Send + 'static>(
            r: Option<R>,
        ) -> std::thread::JoinHandle<Vec<u8>> {
            std::thread::spawn(move || {
                let mut buf = Vec::new();
                if let Some(mut r) = r {
                    let _ = r.read_to_end(&mut buf);
                }
                buf
            })
        }
        let stdout = drain(self.child().stdout.take());
        let stderr = drain(self.child().stderr.take());
        let deadline = Instant::now() + timeout;
        let status = loop {
            match self.child().try_wait().expect("try_wait") {
                Some(status) => break Some(status),
                None if Instant::now() >= deadline => {
                    let _ = self.child().kill();
                    let _ = self.child().wait();
                    break None;
                }
                None => std::thread::sleep(Duration::from_millis(20)),
            }
        };
        let out = (
            stdout.join().unwrap_or_default(),
            stderr.join().unwrap_or_default(),
        );
        self.0.take();
        match status {
            Some(status) => Output {
                status,
                stdout: out.0,
                stderr: out.1,
            },
            None => panic!(
                "process did not finish within {timeout:?}\nstdout:\n{}\nstderr:\n{}",
                String::from_utf8_lossy(&out.0),
                String::from_utf8_lossy(&out.1)
            ),
        }
    }
}

impl Drop for ChildGuard {
    fn drop(&mut self) {
        if let Some(mut c) = self.0.take() {
            let _ = c.kill();
            let _ = c.wait();
        }
    }
}

/// A command with piped stdout/stderr and no stdin.
pub fn piped(program: impl AsRef<std::ffi::OsStr>) -> Command {
    let mut c = Command::new(program);
    c.stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped());
    c
}

/// Runs a command to completion (at most `timeout`).
pub fn run(cmd: &mut Command, timeout: Duration) -> Output {
    ChildGuard::spawn(cmd).wait_output(timeout)
}

/// Compares two JSON values, numbers by value (1 == 1.0) with a relative tolerance, so that
/// Python's and Rust's printing of the same number do not matter.
pub fn json_close(a: &serde_json::Value, b: &serde_json::Value, path: &str) -> Result<(), String> {
    use serde_json::Value as J;
    match (a, b) {
        (J::Number(x), J::Number(y)) => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            if x == y || (x - y).abs() <= 1e-12 * x.abs().max(y.abs()) {
                Ok(())
            } else {
                Err(format!("{path}: {x} != {y}"))
            }
        }
        (J::Array(x), J::Array(y)) => {
            if x.len() != y.len() {
                return Err(format!("{path}: length {} != {}", x.len(), y.len()));
            }
            x.iter()
                .zip(y)
                .enumerate()
                .try_for_each(|(i, (u, v))| json_close(u, v, &format!("{path}.{i}")))
        }
        (J::Object(x), J::Object(y)) => {
            let mut kx: Vec<_> = x.keys().collect();
            let mut ky: Vec<_> = y.keys().collect();
            kx.sort();
            ky.sort();
            if kx != ky {
                return Err(format!("{path}: fields {kx:?} != {ky:?}"));
            }
            x.iter()
                .try_for_each(|(k, v)| json_close(v, &y[k], &format!("{path}.{k}")))
        }
        _ if a == b => Ok(()),
        _ => Err(format!("{path}: {a} != {b}")),
    }
}

/// Sends SIGINT to a process.
pub fn interrupt(pid: i32) {
    nix::sys::signal::kill(
        nix::unistd::Pid::from_raw(pid),
        nix::sys::signal::Signal::SIGINT,
    )
    .expect("kill -INT");
}

/// Whether a process (not a zombie) with this pid exists.
pub fn alive(pid: i32) -> bool {
    match std::fs::read_to_string(format!("/proc/{pid}/stat")) {
        Ok(stat) => {
            // state is the field after the parenthesised command name
            let state = stat
                .rsplit(')')
                .next()
                .and_then(|s| s.split_whitespace().next());
            state != Some("Z")
        }
        Err(_) => false,
    }
}

/// Writes a distortion-free camera_info YAML (focal length `f` px, centre in the middle) — a
/// stand-in calibration for tests of what a command does with photos it cannot use.
pub fn write_pinhole_camera_info(path: &Path, width: u32, height: u32, f: f64) {
    let (cx, cy) = ((width as f64 - 1.0) / 2.0, (height as f64 - 1.0) / 2.0);
    std::fs::write(
        path,
        format!(
            "image_width: {width}\nimage_height: {height}\ncamera_name: pinhole\n\
             camera_matrix:\n  rows: 3\n  cols: 3\n  data: [{f}, 0, {cx}, 0, {f}, {cy}, 0, 0, 1]\n\
             distortion_model: plumb_bob\ndistortion_coefficients:\n  rows: 1\n  cols: 5\n  \
             data: [0, 0, 0, 0, 0]\nrectification_matrix:\n  rows: 3\n  cols: 3\n  \
             data: [1, 0, 0, 0, 1, 0, 0, 0, 1]\nprojection_matrix:\n  rows: 3\n  cols: 4\n  \
             data: [{f}, 0, {cx}, 0, 0, {f}, {cy}, 0, 0, 0, 1, 0]\n"
        ),
    )
    .unwrap();
}

/// Runs `cmd` to completion within `timeout`, prints its stdout (shown with --nocapture) and
/// returns it; fails the test with both outputs when it does not succeed.
pub fn run_ok(cmd: &mut Command, timeout: Duration) -> String {
    let what = format!("{cmd:?}");
    let out = run(cmd, timeout);
    let stdout = String::from_utf8_lossy(&out.stdout).to_string();
    println!("{stdout}");
    assert!(
        out.status.success(),
        "{what} failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    stdout
}

/// A 640×480 photo (metrocell's renderer, a distortion-free 500 px lens: the camera of
/// [`write_pinhole_camera_info`]) of a bare checkerboard of `squares` of `square` m, its first
/// corner at `at` (m, camera frame), written to `path` — for tests of what a command does with a
/// board that lacks what it looks for.
pub fn write_checkerboard_photo(path: &Path, squares: (u32, u32), square: f64, at: [f64; 3]) {
    let board = metrocell_vision::PlanarTarget {
        items: vec![metrocell_vision::TargetItem::Checkerboard {
            top_left: [0.0, 0.0],
            square,
            squares_x: squares.0,
            squares_y: squares.1,
            top_left_black: true,
        }],
    };
    let camera = metrocell_vision::CameraModel::new(
        640,
        480,
        500.0,
        500.0,
        319.5,
        239.5,
        metrocell_vision::Distortion::none(),
    )
    .unwrap();
    let view = metrocell_vision::render_view(
        &camera,
        &nalgebra::Isometry3::translation(at[0], at[1], at[2]),
        &board,
        &metrocell_vision::RenderSettings::default(),
    )
    .unwrap();
    view.image.save(path).unwrap();
}

/// The twin's own per-topic counts from its final log line ("simulation finished: N messages
/// published (per topic, /clock included: /a n, /b m)"), found anywhere in `log`; panics naming
/// the log when the line is not there.
pub fn twin_published_counts(log: &str) -> std::collections::BTreeMap<String, u64> {
    log.lines()
        .find_map(|l| l.split("per topic, /clock included: ").nth(1))
        .unwrap_or_else(|| panic!("no twin counts (\"per topic, /clock included: …\") in:\n{log}"))
        .trim_end_matches(')')
        .split(", ")
        .filter_map(|kv| {
            let (t, n) = kv.rsplit_once(' ')?;
            Some((t.to_string(), n.parse().ok()?))
        })
        .collect()
}

/// One node of a launch file a test writes: the executable (package `metrocell`), its name,
/// node keys such as `("respawn", "true")`, and its parameters as (name, YAML value) — quote
/// strings and paths with [`yaml_string`].
pub struct LaunchNode<'a> {
    pub exec: &'a str,
    pub name: &'a str,
    pub keys: &'a [(&'a str, &'a str)],
    pub params: &'a [(&'a str, String)],
}

/// A launch file (ROS 2 YAML launch format) of `nodes`.
pub fn launch_yaml(nodes: &[LaunchNode]) -> String {
    let mut s = String::from("launch:\n");
    for n in nodes {
        s += &format!(
            "- node:\n    pkg: metrocell\n    exec: {}\n    name: {}\n",
            n.exec, n.name
        );
        for (k, v) in n.keys {
            s += &format!("    {k}: {v}\n");
        }
        if !n.params.is_empty() {
            s += "    param:\n";
            for (k, v) in n.params {
                s += &format!("    - {{name: {k}, value: {v}}}\n");
            }
        }
    }
    s
}

/// `s` as a double-quoted YAML string (paths, durations with units).
pub fn yaml_string(s: impl std::fmt::Display) -> String {
    format!("{:?}", s.to_string())
}

/// The parameters of the twin (`metrocell-sim`) running quick_demo.yaml for `cell_seconds` at 30×
/// without camera frames, waiting for the node named `recorder` before it publishes.
pub fn quick_demo_twin_params(cell_seconds: u32) -> Vec<(&'static str, String)> {
    vec![
        (
            "cell",
            yaml_string(
                workspace_root()
                    .join("launch-configs/cells/quick_demo.yaml")
                    .display(),
            ),
        ),
        ("duration", yaml_string(format!("{cell_seconds}s"))),
        ("speed", "30.0".into()),
        ("wait_for_recorder", "60.0".into()),
        ("recorder_node", "recorder".into()),
        ("camera_images", "false".into()),
    ]
}
