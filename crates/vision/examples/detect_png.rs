//! Detect ArUco markers in PNG files and print id and corners (px):
//!   cargo run --release -p metrocell-vision --example detect_png -- DICT_4X4_50 image.png [repeats]
//! (env THREADS=n sets DetectorParams::threads; default all cores)
use metrocell_vision::aruco::{detect_markers, DetectorParams, Dictionary};

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: detect_png DICT image.png [repeats]");
        std::process::exit(2);
    }
    let dict = Dictionary::predefined(&args[1]).unwrap_or_else(|e| {
        eprintln!("{e}");
        std::process::exit(2)
    });
    let img = image::open(&args[2]).unwrap_or_else(|e| {
        eprintln!("{}: {e}", args[2]);
        std::process::exit(2)
    });
    let img = img.to_luma8();
    let repeats: usize = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(1);
    let t0 = std::time::Instant::now();
    let mut found = Vec::new();
    for _ in 0..repeats {
        let threads = std::env::var("THREADS")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(0);
        found = detect_markers(
            &img,
            &dict,
            &DetectorParams {
                threads,
                ..Default::default()
            },
        )
        .unwrap();
    }
    eprintln!(
        "{:.1} ms per detection",
        t0.elapsed().as_secs_f64() * 1e3 / repeats as f64
    );
    for m in found {
        let c: Vec<String> = m
            .corners
            .iter()
            .map(|p| format!("({:.3}, {:.3})", p.x, p.y))
            .collect();
        println!(
            "id {} bit_errors {} corners {}",
            m.id,
            m.bit_errors,
            c.join(" ")
        );
    }
}
