//! Shared test helpers: the Python interpreter, hand-encoded CDR for two standard types, and
//! their ros2msg definitions (upstream .msg texts, comments included).
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// ros2msg schema of sensor_msgs/msg/Temperature with its dependencies, as rosbag2 stores it.
pub const TEMPERATURE_DEF: &str = "\
# Single temperature reading.

std_msgs/Header header # timestamp is the time the temperature was measured
                             # frame_id is the location of the temperature reading

float64 temperature # Measurement of the Temperature in Degrees Celsius.

float64 variance # 0 is interpreted as variance unknown.
================================================================================
MSG: std_msgs/Header
# Standard metadata for higher-level stamped data types.
# This is generally used to communicate timestamped data
# in a particular coordinate frame.

# Two-integer timestamp that is expressed as seconds and nanoseconds.
builtin_interfaces/Time stamp

# Transform frame with which this data is associated.
string frame_id
================================================================================
MSG: builtin_interfaces/Time
# This message communicates ROS Time defined here:
# https://design.ros2.org/articles/clock_and_time.html

# The seconds component, valid over all int32 values.
int32 sec

# The nanoseconds component, valid in the range [0, 1e9), to be added to the seconds component.
# e.g.
# The time -1.7 seconds is represented as {sec: -2, nanosec: 3e8}
# The time 1.7 seconds is represented as {sec: 1, nanosec: 7e8}
uint32 nanosec
";

pub const STRING_DEF: &str = "# This was originally provided as an example message.\nstring data\n";

#[derive(Debug, Clone, PartialEq)]
pub struct Temperature {
    pub sec: i32,
    pub nanosec: u32,
    pub frame_id: String,
    pub temperature: f64,
    pub variance: f64,
}

/// Plain little-endian CDR (XCDR1) writer; alignment counts from after the 4-byte header.
struct Cdr(Vec<u8>);
impl Cdr {
    fn new() -> Self {
        Cdr(vec![0x00, 0x01, 0x00, 0x00])
    }
    fn align(&mut self, n: usize) {
        while (self.0.len() - 4) % n != 0 {
            self.0.push(0);
        }
    }
    fn i32(&mut self, v: i32) {
        self.align(4);
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn u32(&mut self, v: u32) {
        self.align(4);
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn f64(&mut self, v: f64) {
        self.align(8);
        self.0.extend_from_slice(&v.to_le_bytes());
    }
    fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.0.extend_from_slice(s.as_bytes());
        self.0.push(0);
    }
}

struct CdrIn<'a> {
    b: &'a [u8],
    p: usize,
}
impl<'a> CdrIn<'a> {
    fn new(b: &'a [u8]) -> Self {
        assert_eq!(&b[..2], &[0, 1], "little-endian CDR header");
        CdrIn { b, p: 4 }
    }
    fn align(&mut self, n: usize) {
        while (self.p - 4) % n != 0 {
            self.p += 1;
        }
    }
    fn take<const N: usize>(&mut self, align: usize) -> [u8; N] {
        self.align(align);
        let v = self.b[self.p..self.p + N].try_into().unwrap();
        self.p += N;
        v
    }
    fn string(&mut self) -> String {
        let n = u32::from_le_bytes(self.take::<4>(4)) as usize;
        let s = std::str::from_utf8(&self.b[self.p..self.p + n - 1])
            .unwrap()
            .to_string();
        self.p += n;
        s
    }
}

impl Temperature {
    /// The i-th test reading (values exactly reproducible in JSON).
    pub fn nth(i: u64) -> Self {
        Temperature {
            sec: 1000 + i as i32,
            nanosec: (i as u32) * 1000,
            frame_id: format!("probe{}", i % 3),
            temperature: 20.0 + 0.25 * i as f64,
            variance: 0.01 * i as f64,
        }
    }
    pub fn encode(&self) -> Vec<u8> {
        let mut c = Cdr::new();
        c.i32(self.sec);
        c.u32(self.nanosec);
        c.string(&self.frame_id);
        c.f64(self.temperature);
        c.f64(self.variance);
        c.0
    }
    pub fn decode(b: &[u8]) -> Self {
        let mut c = CdrIn::new(b);
        let sec = i32::from_le_bytes(c.take::<4>(4));
        let nanosec = u32::from_le_bytes(c.take::<4>(4));
        let frame_id = c.string();
        let temperature = f64::from_le_bytes(c.take::<8>(8));
        let variance = f64::from_le_bytes(c.take::<8>(8));
        Temperature {
            sec,
            nanosec,
            frame_id,
            temperature,
            variance,
        }
    }
    /// Compare with a JSON object decoded by Python (field names of the ROS type).
    pub fn assert_json(&self, v: &serde_json::Value) {
        assert_eq!(
            v["header"]["stamp"]["sec"].as_i64(),
            Some(self.sec as i64),
            "{v}"
        );
        assert_eq!(
            v["header"]["stamp"]["nanosec"].as_u64(),
            Some(self.nanosec as u64),
            "{v}"
        );
        assert_eq!(
            v["header"]["frame_id"].as_str(),
            Some(self.frame_id.as_str()),
            "{v}"
        );
        assert_eq!(v["temperature"].as_f64(), Some(self.temperature), "{v}");
        assert_eq!(v["variance"].as_f64(), Some(self.variance), "{v}");
    }
}

pub fn encode_string(s: &str) -> Vec<u8> {
    let mut c = Cdr::new();
    c.string(s);
    c.0
}

pub fn decode_string(b: &[u8]) -> String {
    CdrIn::new(b).string()
}

/// The project's Python: METROCELL_PYTHON, else <workspace>/.venv/bin/python; fails loudly.
pub fn python() -> PathBuf {
    if let Ok(p) = std::env::var("METROCELL_PYTHON") {
        return PathBuf::from(p);
    }
    let ws = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let venv = ws.join(".venv/bin/python");
    if venv.exists() {
        return venv;
    }
    panic!("no Python with rosbags/mcap: set METROCELL_PYTHON or run tests/run to create .venv");
}

/// Run `tests/py/<script>` with args and parse its JSON stdout.
pub fn run_py(script: &str, args: &[&Path]) -> serde_json::Value {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py");
    let out = Command::new(python())
        .arg(dir.join(script))
        .args(args)
        .current_dir(&dir)
        .output()
        .expect("start python");
    assert!(
        out.status.success(),
        "{script} {args:?} failed:\n{}",
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("script prints JSON")
}

/// A fresh empty scratch directory under the target dir.
pub fn scratch(name: &str) -> PathBuf {
    let base = option_env!("CARGO_TARGET_TMPDIR")
        .map(PathBuf::from)
        .unwrap_or_else(std::env::temp_dir);
    let d = base.join(format!("bag-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}
