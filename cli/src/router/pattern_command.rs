//! `metrocell router pattern -o DIR`: seed 000's measurement job — the checkerboard and its
//! inverse to print (SVG and PDF at exact scale), the nominal hole table and the drilling program.

use std::path::PathBuf;

use anyhow::Context;
use metrocell_gcode::hole_plate_job::{DrillCycle, HolePlate};

use crate::vision::image_input::{parse_length, parse_squares};

#[derive(clap::Args)]
#[command(
    after_help = "Writes DIR/pattern.svg and DIR/pattern.pdf (the board: print it at 100 %, \
no fit to page, and check the 100 mm scale bar with a ruler), DIR/pattern_inverse.svg and .pdf (the same \
board with black and white swapped: the backing under the drilled print, so a hole through a white square \
shows black), DIR/holes.csv (the nominal hole table, machine mm) and DIR/drill.nc (G21 G90: G0 to each hole \
at the clearance height, G1 plunge, G0 retract, serpentine along the rows).\n\n\
Lay the print on the table with the page's top toward the machine's back (+Y) and the board's front-left \
corner at --origin; drill; put the inverse print under it; photograph it from above with the machine's back \
at the top of the image; then `metrocell router measure`.\n\n\
Example:\n  metrocell router pattern --squares 6x6 --square 25mm --hole 1mm --origin 20,20 -o plate/"
)]
pub struct PatternArgs {
    #[command(flatten)]
    plate: PlateLayout,
    /// Z of the plate's surface (mm)
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    surface_z: f64,
    /// Drilling depth below the surface (mm)
    #[arg(long, default_value_t = 1.0)]
    depth: f64,
    /// Clearance above the surface between holes (mm)
    #[arg(long, default_value_t = 3.0)]
    clearance: f64,
    /// Plunge feed (mm/min)
    #[arg(long, default_value_t = 100.0)]
    feed: f64,
    /// Spindle speed (rpm)
    #[arg(long, default_value_t = 10000.0)]
    spindle: f64,
    /// Directory to write the files to
    #[arg(short, long)]
    output: PathBuf,
}

/// The plate as `router pattern` lays it out (and `router simulate` drills it).
#[derive(clap::Args, Debug, Clone, Copy)]
pub struct PlateLayout {
    /// Squares along X and Y (seed 000: 6x6, one hole per square)
    #[arg(long, default_value = "6x6", value_parser = parse_squares)]
    pub squares: (usize, usize),
    /// Side of a square (seed 000: 25 mm)
    #[arg(long, default_value = "25mm", value_parser = parse_length)]
    pub square: f64,
    /// Drill diameter (seed 000: 1 mm)
    #[arg(long, default_value = "1mm", value_parser = parse_length)]
    pub hole: f64,
    /// Machine X,Y of the board's front-left corner (mm)
    #[arg(long, default_value = "0,0", value_parser = parse_point)]
    pub origin: (f64, f64),
}

/// "20,20" → (20.0, 20.0) mm.
pub fn parse_point(s: &str) -> Result<(f64, f64), String> {
    let (a, b) = s
        .split_once(',')
        .ok_or_else(|| format!("`{s}`: expected X,Y in mm, e.g. 20,20"))?;
    let v = |t: &str| {
        t.trim()
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| format!("`{s}`: `{t}` is not a number of mm"))
    };
    Ok((v(a)?, v(b)?))
}

pub fn run(a: PatternArgs) -> anyhow::Result<i32> {
    let plate = HolePlate {
        squares_x: a.plate.squares.0,
        squares_y: a.plate.squares.1,
        square_mm: a.plate.square * 1e3,
        origin_mm: a.plate.origin,
        hole_diameter_mm: a.plate.hole * 1e3,
    };
    plate.validate().context("the pattern")?;
    let cycle = DrillCycle {
        surface_z_mm: a.surface_z,
        depth_mm: a.depth,
        clearance_mm: a.clearance,
        feed_mm_per_min: a.feed,
        spindle_rpm: a.spindle,
    };
    std::fs::create_dir_all(&a.output)
        .with_context(|| format!("creating {}", a.output.display()))?;
    let files: [(&str, Vec<u8>); 6] = [
        ("pattern.svg", plate.svg(false).into_bytes()),
        ("pattern.pdf", plate.pdf(false)),
        ("pattern_inverse.svg", plate.svg(true).into_bytes()),
        ("pattern_inverse.pdf", plate.pdf(true)),
        ("holes.csv", plate.holes_csv().into_bytes()),
        ("drill.nc", plate.drilling_program(&cycle).into_bytes()),
    ];
    for (name, bytes) in files {
        let path = a.output.join(name);
        std::fs::write(&path, bytes).with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    let holes = plate.holes();
    let (first, last) = (holes[0], holes[holes.len() - 1]);
    println!(
        "{} holes of {} mm, from ({}, {}) to ({}, {}) mm; board {} × {} mm",
        holes.len(),
        plate.hole_diameter_mm,
        first.x_mm,
        first.y_mm,
        last.x_mm,
        last.y_mm,
        plate.squares_x as f64 * plate.square_mm,
        plate.squares_y as f64 * plate.square_mm
    );
    Ok(0)
}
