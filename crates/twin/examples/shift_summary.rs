//! Streams a cell with ground truth and prints, in mm/µm, how large each concealed effect is in
//! the data: temperatures, machine error per axis, tracker warm-up and refraction range errors,
//! scatter inside/outside turbulence, dropped samples.
//!
//! `cargo run --release -p metrocell-twin --example shift_summary [cell.yaml] [hours] [seed]`

use std::collections::BTreeMap;

use metrocell_twin::{Cell, Sample, SampleTruth, Simulation, TrackerStatus};

#[derive(Default)]
struct Range {
    min: f64,
    max: f64,
    n: usize,
}

impl Range {
    fn add(&mut self, v: f64) {
        if self.n == 0 {
            self.min = v;
            self.max = v;
        }
        self.min = self.min.min(v);
        self.max = self.max.max(v);
        self.n += 1;
    }
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
    let sim = match Cell::from_path(&path).and_then(|c| Simulation::new(c, hours * 3600.0, seed)) {
        Ok(s) => s,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    let mut temps: BTreeMap<String, Range> = BTreeMap::new();
    let mut err = [Range::default(), Range::default(), Range::default()];
    let (mut warm, mut refr) = (Range::default(), Range::default());
    let (mut broken, mut tracker) = (0usize, 0usize);
    let mut scatter: BTreeMap<bool, (f64, usize)> = BTreeMap::new();
    for (s, t) in sim.samples_with_truth() {
        match (s, t) {
            (Sample::Temperature(m), _) => {
                temps.entry(m.sensor.to_string()).or_default().add(m.value)
            }
            (Sample::MachineState(_), SampleTruth::MachineState { displacement }) => {
                (0..3).for_each(|k| err[k].add(displacement[k] * 1e6))
            }
            (Sample::Tracker(m), SampleTruth::Tracker(tt)) => {
                tracker += 1;
                warm.add(tt.warmup_range_error * 1e6);
                refr.add(tt.refraction_range_error / tt.range * 1e6);
                if m.status == TrackerStatus::BeamBroken {
                    broken += 1;
                } else {
                    let stated =
                        m.range - tt.range - tt.warmup_range_error - tt.refraction_range_error;
                    let inflated = tt.range_sigma
                        > 1.5
                            * (sim
                                .cell()
                                .tracker
                                .as_ref()
                                .map(|t| {
                                    t.range_noise_constant + t.range_noise_per_metre * tt.range
                                })
                                .unwrap_or(0.0));
                    let e = scatter.entry(inflated).or_default();
                    e.0 += stated * stated;
                    e.1 += 1;
                }
            }
            _ => {}
        }
    }
    println!("cell {path}, {hours} h, seed {seed}");
    for (name, r) in &temps {
        println!("  thermocouple {name:8}: {:.3} … {:.3} °C", r.min, r.max);
    }
    for (k, r) in err.iter().enumerate() {
        if r.n > 0 {
            println!(
                "  machine error {}: {:+.2} … {:+.2} µm",
                ["x", "y", "z"][k],
                r.min,
                r.max
            );
        }
    }
    if tracker > 0 {
        println!(
            "  tracker warm-up range error: {:+.2} … {:+.2} µm",
            warm.min, warm.max
        );
        println!(
            "  tracker refraction error: {:+.3} … {:+.3} ppm of range",
            refr.min, refr.max
        );
        for (inflated, (ss, n)) in &scatter {
            if *n > 0 {
                println!(
                    "  range noise RMS {}: {:.2} µm over {n} samples",
                    if *inflated { "in turbulence" } else { "quiet" },
                    (ss / *n as f64).sqrt() * 1e6
                );
            }
        }
        println!("  beam broken: {broken} of {tracker} samples");
    }
}
