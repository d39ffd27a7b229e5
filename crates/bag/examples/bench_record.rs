//! Recording benchmark. Run with `--release`:
//!
//! `METROCELL_PYTHON=/path/to/python cargo run --release -p metrocell-bag --example bench_record -- [--seconds 3] [--load-seconds 20] [--dir DIR]`
//!
//! Part A (throughput): the same cell-like messages (1 kHz tracker ~200 B, 100 Hz joint
//! states, 30 Hz 1920x1080 mono8 images, 1 Hz temperatures; `--seconds` of log time) are
//! written by BagWriter, by the Python `mcap` writer (same chunk size and compression, fsync at
//! the end) and, as the disk's ceiling, by `dd conv=fdatasync` of the same byte count, all in
//! this run on the same directory. Prints MB/s, msgs/s and ratios.
//!
//! Part B (memory): `--load-seconds` of the same load written as fast as possible through one
//! BagWriter with default options (zstd level 1, 1 MiB chunks, 1 s flush with fdatasync); resident memory is sampled after every simulated
//! second and the peak (VmHWM, reset at the start) printed, to show it stays flat.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use metrocell_bag::{qos_profiles_yaml, BagWriter, ChunkCompression, QosProfile, WriterOptions};

const HEADER_DEFS: &str =
    "================================================================================\n\
MSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n\
================================================================================\n\
MSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n";

fn defs() -> Vec<(&'static str, &'static str, String)> {
    vec![
        (
            "/tracker/raw",
            "std_msgs/msg/UInt8MultiArray",
            "std_msgs/MultiArrayLayout layout\nuint8[] data\n\
================================================================================\n\
MSG: std_msgs/MultiArrayLayout\nstd_msgs/MultiArrayDimension[] dim\nuint32 data_offset\n\
================================================================================\n\
MSG: std_msgs/MultiArrayDimension\nstring label\nuint32 size\nuint32 stride\n"
                .to_string(),
        ),
        (
            "/joint_states",
            "sensor_msgs/msg/JointState",
            format!("std_msgs/Header header\nstring[] name\nfloat64[] position\nfloat64[] velocity\nfloat64[] effort\n{HEADER_DEFS}"),
        ),
        (
            "/camera/image_raw",
            "sensor_msgs/msg/Image",
            format!(
                "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\nuint8 is_bigendian\nuint32 step\nuint8[] data\n{HEADER_DEFS}"
            ),
        ),
        (
            "/temperature",
            "sensor_msgs/msg/Temperature",
            format!("std_msgs/Header header\nfloat64 temperature\nfloat64 variance\n{HEADER_DEFS}"),
        ),
    ]
}

/// Little-endian CDR builder (alignment from after the encapsulation header).
struct Cdr(Vec<u8>);
impl Cdr {
    fn new(cap: usize) -> Self {
        let mut v = Vec::with_capacity(cap + 64);
        v.extend_from_slice(&[0, 1, 0, 0]);
        Cdr(v)
    }
    fn align(&mut self, n: usize) {
        while (self.0.len() - 4) % n != 0 {
            self.0.push(0);
        }
    }
    fn u32(&mut self, x: u32) {
        self.align(4);
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn f64(&mut self, x: f64) {
        self.align(8);
        self.0.extend_from_slice(&x.to_le_bytes());
    }
    fn string(&mut self, s: &str) {
        self.u32(s.len() as u32 + 1);
        self.0.extend_from_slice(s.as_bytes());
        self.0.push(0);
    }
    fn header(&mut self, t: u64, frame: &str) {
        self.u32((t / 1_000_000_000) as u32);
        self.u32((t % 1_000_000_000) as u32);
        self.string(frame);
    }
}

struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
}

/// A synthetic camera frame: smooth gradient plus 3 bits of noise (compresses like a real
/// grey image, roughly 2:1 with zstd).
fn frame(seed: u64) -> Vec<u8> {
    let (w, h) = (1920usize, 1080usize);
    let mut r = Rng(seed | 1);
    let mut v = Vec::with_capacity(w * h);
    for y in 0..h {
        for x in 0..w {
            let base = ((x / 8 + y / 6 + seed as usize * 7) % 224) as u8;
            v.push(base + (r.next() & 7) as u8);
        }
    }
    v
}

/// Time-ordered messages of one simulated second `s`: (topic index, log time, CDR).
fn second_of_load(
    s: u64,
    t0: u64,
    frames: &[Vec<u8>],
    rng: &mut Rng,
) -> Vec<(usize, u64, Vec<u8>)> {
    slice_of_load(s, 0..1000, t0, frames, rng)
}

/// Messages of milliseconds `ms` of simulated second `s`.
fn slice_of_load(
    s: u64,
    ms: std::ops::Range<u64>,
    t0: u64,
    frames: &[Vec<u8>],
    rng: &mut Rng,
) -> Vec<(usize, u64, Vec<u8>)> {
    let mut out = Vec::new();
    let base = t0 + s * 1_000_000_000;
    for k in ms {
        let t = base + k * 1_000_000;
        let mut c = Cdr::new(200);
        c.u32(0); // layout.dim: empty
        c.u32(0); // data_offset
        c.u32(184);
        for _ in 0..23 {
            c.0.extend_from_slice(&rng.next().to_le_bytes());
        }
        out.push((0, t, c.0));
        if k % 10 == 0 {
            let mut c = Cdr::new(300);
            c.header(t, "base_link");
            c.u32(6);
            for j in 0..6 {
                c.string(&format!("joint_{j}"));
            }
            for _ in 0..3 {
                c.u32(6);
                for _ in 0..6 {
                    c.f64((rng.next() % 10_000) as f64 * 1e-4);
                }
            }
            out.push((1, t + 1, c.0));
        }
        if k % 33 == 0 && k / 33 < 30 {
            let img = &frames[((s * 30 + k / 33) % frames.len() as u64) as usize];
            let mut c = Cdr::new(img.len());
            c.header(t, "camera");
            c.u32(1080);
            c.u32(1920);
            c.string("mono8");
            c.0.push(0);
            c.u32(1920);
            c.u32(img.len() as u32);
            c.0.extend_from_slice(img);
            out.push((2, t + 2, c.0));
        }
        if k == 500 {
            let mut c = Cdr::new(40);
            c.header(t, "spindle");
            c.f64(20.0 + (rng.next() % 1000) as f64 * 1e-3);
            c.f64(1e-4);
            out.push((3, t + 3, c.0));
        }
    }
    out
}

fn status_kib(field: &str) -> u64 {
    let s = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    s.lines()
        .find(|l| l.starts_with(field))
        .and_then(|l| l.split_whitespace().nth(1))
        .and_then(|v| v.parse().ok())
        .unwrap_or(0)
}

fn python() -> PathBuf {
    if let Ok(p) = std::env::var("METROCELL_PYTHON") {
        return p.into();
    }
    let venv = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../.venv/bin/python");
    assert!(
        venv.exists(),
        "set METROCELL_PYTHON or run tests/run to create .venv"
    );
    venv
}

fn dir_bytes(d: &Path) -> u64 {
    std::fs::read_dir(d)
        .map(|it| {
            it.filter_map(|e| e.ok()?.metadata().ok())
                .map(|m| m.len())
                .sum()
        })
        .unwrap_or(0)
}

/// The cell-like messages of a benchmark: channel index, log time (ns), CDR bytes.
type Messages = Vec<(usize, u64, Vec<u8>)>;

/// What both parts write: the topics, their QoS, the image frames and the start time (ns).
struct Load {
    defs: Vec<(&'static str, &'static str, String)>,
    qos: String,
    frames: Vec<Vec<u8>>,
    t0: u64,
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let arg = |name: &str, default: &str| -> String {
        args.iter()
            .position(|a| a == name)
            .and_then(|i| args.get(i + 1))
            .cloned()
            .unwrap_or_else(|| default.to_string())
    };
    let seconds: u64 = arg("--seconds", "3").parse().expect("--seconds N");
    let load_seconds: u64 = arg("--load-seconds", "20")
        .parse()
        .expect("--load-seconds N");
    let root = PathBuf::from(arg(
        "--dir",
        &std::env::temp_dir()
            .join("metrocell-bag-bench")
            .to_string_lossy(),
    ));
    let _ = std::fs::remove_dir_all(&root);
    std::fs::create_dir_all(&root).unwrap();
    let load = Load {
        t0: 1_700_000_000_000_000_000u64,
        frames: (0..8).map(frame).collect(),
        defs: defs(),
        qos: qos_profiles_yaml(&[QosProfile::sensor_data()]),
    };
    let mut rng = Rng(0x5EED);
    part_a_throughput(&root, &load, seconds, &mut rng);
    part_b_memory(&root, &load, load_seconds, &mut rng);
    let _ = std::fs::remove_dir_all(&root);
}

/// Part A: throughput of BagWriter against python mcap and dd on `seconds` of cell load.
fn part_a_throughput(root: &Path, load: &Load, seconds: u64, rng: &mut Rng) {
    let msgs: Messages = (0..seconds)
        .flat_map(|s| second_of_load(s, load.t0, &load.frames, rng))
        .collect();
    let bytes_in: u64 = msgs.iter().map(|m| m.2.len() as u64).sum();
    let n = msgs.len() as u64;
    let bin = root.join("messages.bin");
    write_messages_bin(&bin, &load.defs, &msgs);
    println!(
        "Part A: {n} messages, {:.1} MB of CDR ({seconds} s of cell load), dir {}",
        bytes_in as f64 / 1e6,
        root.display()
    );
    let dd_mbs = dd_ceiling(root, bytes_in);
    for (label, comp) in [
        ("none", ChunkCompression::None),
        ("zstd", ChunkCompression::Zstd),
        ("lz4", ChunkCompression::Lz4),
    ] {
        let dir = root.join(format!("rust_{label}"));
        // zstd at level 3, the level python-mcap (zstandard's default) uses.
        let opts = WriterOptions {
            compression: comp,
            compression_level: 3,
            ..Default::default()
        }; // level: zstd only
        let rust_s = write_with_bag_writer(&dir, opts, load, &msgs);
        let rust_file = dir_bytes(&dir);
        let py_out = root.join(format!("py_{label}.mcap"));
        let (py_s, py_file) = write_with_python(&bin, &py_out, label);
        let (rm, pm) = (bytes_in as f64 / 1e6 / rust_s, bytes_in as f64 / 1e6 / py_s);
        println!(
            "  {label:4}: BagWriter {rm:8.1} MB/s {:9.0} msg/s (file {:.1} MB) | python mcap {pm:8.1} MB/s {:9.0} msg/s (file {:.1} MB) | BagWriter/python = {:.2}x, BagWriter/dd = {:.2}",
            n as f64 / rust_s,
            rust_file as f64 / 1e6,
            n as f64 / py_s,
            py_file as f64 / 1e6,
            rm / pm,
            rm / dd_mbs
        );
        let _ = std::fs::remove_dir_all(&dir);
        let _ = std::fs::remove_file(&py_out);
    }
    {
        let dir = root.join("rust_zstd1");
        let opts = WriterOptions {
            compression: ChunkCompression::Zstd,
            compression_level: 1,
            ..Default::default()
        };
        let s = write_with_bag_writer(&dir, opts, load, &msgs);
        println!(
            "  zstd level 1 (default): BagWriter {:8.1} MB/s {:9.0} msg/s (file {:.1} MB)",
            bytes_in as f64 / 1e6 / s,
            n as f64 / s,
            dir_bytes(&dir) as f64 / 1e6
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
    let _ = std::fs::remove_file(&bin);
}

/// The messages and their topics in the binary form tests/py/bench_mcap_writer.py reads.
fn write_messages_bin(bin: &Path, defs: &[(&str, &str, String)], msgs: &Messages) {
    let mut f = std::io::BufWriter::new(std::fs::File::create(bin).unwrap());
    f.write_all(&(defs.len() as u32).to_le_bytes()).unwrap();
    for (name, ty, def) in defs {
        f.write_all(&(name.len() as u16).to_le_bytes()).unwrap();
        f.write_all(name.as_bytes()).unwrap();
        f.write_all(&(ty.len() as u16).to_le_bytes()).unwrap();
        f.write_all(ty.as_bytes()).unwrap();
        f.write_all(&(def.len() as u32).to_le_bytes()).unwrap();
        f.write_all(def.as_bytes()).unwrap();
    }
    for (ch, t, d) in msgs {
        f.write_all(&(*ch as u16).to_le_bytes()).unwrap();
        f.write_all(&t.to_le_bytes()).unwrap();
        f.write_all(&(d.len() as u32).to_le_bytes()).unwrap();
        f.write_all(d).unwrap();
    }
}

/// The disk's ceiling for `bytes_in` bytes (MB/s): the median of three `dd conv=fdatasync`
/// runs (the virtual disk's speed varies run to run), printed.
fn dd_ceiling(root: &Path, bytes_in: u64) -> f64 {
    let dd_out = root.join("dd.bin");
    let dd_run = || -> f64 {
        let dd = Command::new("dd")
            .arg("if=/dev/zero")
            .arg(format!("of={}", dd_out.display()))
            .arg("bs=1M")
            .arg(format!("count={}", bytes_in.div_ceil(1 << 20)))
            .arg("conv=fdatasync")
            .output()
            .expect("run dd");
        let dd_text = String::from_utf8_lossy(&dd.stderr).to_string();
        let dd_secs: f64 = dd_text
            .lines()
            .last()
            .and_then(|l| l.split(", ").nth(2))
            .and_then(|s| s.split_whitespace().next())
            .and_then(|s| s.parse().ok())
            .expect("dd reports seconds");
        let _ = std::fs::remove_file(&dd_out);
        (bytes_in.div_ceil(1 << 20) * (1 << 20)) as f64 / 1e6 / dd_secs
    };
    let mut dds = [dd_run(), dd_run(), dd_run()];
    dds.sort_by(|a, b| a.total_cmp(b));
    let dd_mbs = dds[1];
    println!(
        "  dd conv=fdatasync          {dd_mbs:8.1} MB/s (median of {:.1}, {:.1}, {:.1})",
        dds[0], dds[1], dds[2]
    );
    dd_mbs
}

/// Write `msgs` to a new bag in `dir` with BagWriter; the seconds it took.
fn write_with_bag_writer(dir: &Path, opts: WriterOptions, load: &Load, msgs: &Messages) -> f64 {
    let start = Instant::now();
    let mut w = BagWriter::create(dir, opts).unwrap();
    for (name, ty, def) in &load.defs {
        w.add_topic(name, ty, def, &load.qos).unwrap();
    }
    for (ch, t, d) in msgs {
        w.write(load.defs[*ch].0, *t, *t, d).unwrap();
    }
    w.finish().unwrap();
    start.elapsed().as_secs_f64()
}

/// Write the messages of `bin` with Python's `mcap` writer (compression `label`, 1 MiB chunks);
/// the seconds it took and the file's size.
fn write_with_python(bin: &Path, py_out: &Path, label: &str) -> (f64, u64) {
    let out = Command::new(python())
        .arg(Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py/bench_mcap_writer.py"))
        .arg(bin)
        .arg(py_out)
        .arg(label)
        .arg((1u64 << 20).to_string())
        .output()
        .expect("run python");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v = String::from_utf8_lossy(&out.stdout).to_string();
    let py_s: f64 = v
        .split("\"seconds\": ")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .and_then(|s| s.parse().ok())
        .unwrap();
    let py_file: u64 = v
        .split("\"file_bytes\": ")
        .nth(1)
        .and_then(|s| s.trim_end_matches(['}', '\n']).trim().parse().ok())
        .unwrap();
    (py_s, py_file)
}

/// Part B: resident memory while `load_seconds` of the load are written as fast as possible
/// through one BagWriter with default options, then the bag read back.
fn part_b_memory(root: &Path, load: &Load, load_seconds: u64, rng: &mut Rng) {
    let _ = std::fs::write("/proc/self/clear_refs", "5"); // reset VmHWM to current RSS
    let dir = root.join("load");
    let mut w = BagWriter::create(&dir, WriterOptions::default()).unwrap();
    for (name, ty, def) in &load.defs {
        w.add_topic(name, ty, def, &load.qos).unwrap();
    }
    let start = Instant::now();
    let mut rss = Vec::new();
    let mut written = 0u64;
    let mut nmsg = 0u64;
    let rss0 = status_kib("VmRSS:");
    for s in 0..load_seconds {
        // Generate 10 ms at a time so the benchmark's own buffers stay small (one image).
        for k in (0..1000).step_by(10) {
            for (ch, t, d) in slice_of_load(s, k..k + 10, load.t0, &load.frames, rng) {
                w.write(load.defs[ch].0, t, t, &d).unwrap();
                written += d.len() as u64;
                nmsg += 1;
            }
        }
        rss.push(status_kib("VmRSS:"));
    }
    w.finish().unwrap();
    let secs = start.elapsed().as_secs_f64();
    // VmHWM is updated lazily by the kernel; report the larger of it and the samples.
    let peak = status_kib("VmHWM:").max(rss.iter().copied().max().unwrap_or(0));
    let pick = |i: usize| rss.get(i).copied().unwrap_or(0) as f64 / 1024.0;
    println!(
        "Part B: {load_seconds} s of cell load ({nmsg} msgs, {:.0} MB) written in {secs:.1} s ({:.0} MB/s, {:.0} msg/s), bag {:.0} MB",
        written as f64 / 1e6,
        written as f64 / 1e6 / secs,
        nmsg as f64 / secs,
        dir_bytes(&dir) as f64 / 1e6
    );
    println!(
        "  RSS before {:.1} MiB; after 1 s {:.1} MiB, after {} s {:.1} MiB, after {} s {:.1} MiB; peak (VmHWM) {:.1} MiB",
        rss0 as f64 / 1024.0,
        pick(0),
        load_seconds / 2,
        pick(load_seconds as usize / 2 - 1),
        load_seconds,
        pick(load_seconds as usize - 1),
        peak as f64 / 1024.0
    );
    read_back(&dir, nmsg);
}

/// Read the load bag back (log-time order, all topics) for a replay figure.
fn read_back(dir: &Path, nmsg: u64) {
    let start = Instant::now();
    let r = metrocell_bag::BagReader::open(dir).unwrap();
    let mut read_bytes = 0u64;
    let mut read_n = 0u64;
    for m in r
        .messages(&metrocell_bag::MessageFilter::default())
        .unwrap()
    {
        read_bytes += m.unwrap().data.len() as u64;
        read_n += 1;
    }
    let rs = start.elapsed().as_secs_f64();
    assert_eq!(read_n, nmsg);
    println!(
        "  read back: {read_n} msgs in {rs:.1} s ({:.0} MB/s, {:.0} msg/s); peak RSS now {:.1} MiB",
        read_bytes as f64 / 1e6 / rs,
        read_n as f64 / rs,
        status_kib("VmHWM:") as f64 / 1024.0
    );
}
