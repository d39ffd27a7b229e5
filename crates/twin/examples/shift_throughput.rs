//! Streams the 8-hour example shift (`examples/cells/xfyz_shift.yaml`: 1 Hz thermocouples,
//! 10 Hz tracker, 100 Hz machine state) and prints samples/s and peak resident memory.
//!
//! `cargo run --release -p metrocell-twin --example shift_throughput [cell.yaml] [hours] [seed]`

use std::time::Instant;

use metrocell_twin::{Cell, Sample, Simulation};

fn peak_rss_kib() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    s.lines()
        .find(|l| l.starts_with("VmHWM:"))?
        .split_whitespace()
        .nth(1)?
        .parse()
        .ok()
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let path = args.get(1).cloned().unwrap_or_else(|| {
        concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/examples/cells/xfyz_shift.yaml"
        )
        .to_string()
    });
    let hours: f64 = args.get(2).and_then(|s| s.parse().ok()).unwrap_or(8.0);
    let seed: u64 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let cell = match Cell::from_path(&path) {
        Ok(c) => c,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let sim = match Simulation::new(cell, hours * 3600.0, seed) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let rss_before = peak_rss_kib();
    let start = Instant::now();
    let (mut n, mut tracker, mut temps, mut states, mut other) = (0u64, 0u64, 0u64, 0u64, 0u64);
    let mut last_t = 0.0;
    let mut stream = sim.samples();
    for s in &mut stream {
        n += 1;
        last_t = s.t();
        match s {
            Sample::Tracker(_) => tracker += 1,
            Sample::Temperature(_) => temps += 1,
            Sample::MachineState(_) => states += 1,
            _ => other += 1,
        }
        if n % 1_000_000 == 0 {
            eprintln!(
                "  {n} samples, t = {:.0} s, peak RSS {:?} KiB",
                last_t,
                peak_rss_kib()
            );
        }
    }
    if let Some(e) = stream.error() {
        eprintln!("stream stopped: {e}");
        std::process::exit(1);
    }
    let secs = start.elapsed().as_secs_f64();
    println!("cell {path}: {hours} h simulated, seed {seed}");
    println!("samples: {n} (tracker {tracker}, temperature {temps}, machine state {states}, other {other}); last t = {last_t:.1} s");
    println!(
        "wall time {secs:.2} s → {:.0} samples/s, {:.0}× real time",
        n as f64 / secs,
        hours * 3600.0 / secs
    );
    println!(
        "peak RSS: {:?} KiB before streaming, {:?} KiB after",
        rss_before,
        peak_rss_kib()
    );
}
