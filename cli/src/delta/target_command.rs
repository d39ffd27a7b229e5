//! `metrocell delta target -o DIR`: the calibration star to print — its solids and the table of
//! its dots' commanded positions that `delta measure` matches the photos against.

use std::path::PathBuf;

use anyhow::Context;
use metrocell_gcode::fdm_toolpath::{fdm_program, FdmFeature, FdmSettings, FdmShape};
use metrocell_vision::printed_star::DeltaStar;
use metrocell_vision::printed_star_solid::{star_solids, tile_cells};

use crate::vision::image_input::parse_length;

#[derive(clap::Args)]
#[command(
    after_help = "Writes DIR/dots.csv (each dot's commanded x, y and the height of its top, mm), \
DIR/star_dots.stl (85 dots of 3 mm, 1 mm tall: the centre and 12 arms every 30° at 20 … 80 mm; print them \
in a light colour), DIR/star_tiles_black.stl and DIR/star_tiles_white.stl (three ArUco tiles, ids 1, 2, 3 of \
DICT_4X4_50, 14 mm, 0.6 mm tall, 15° counter-clockwise of the arms toward towers A, B, C: the same layers \
in two colours, black and white — a two-material print, or a filament change). All in the printer's frame \
(bed centre origin): place the STLs at their own coordinates, do not let the slicer centre or arrange them.\n\n\
Or print DIR/star.gcode directly (no slicer; --nozzle, --layer, --filament, --temperatures): light filament \
on a dark bed for the dots and the tiles' white base (0.4 mm), then a filament change (M600) to black for \
the tiles' black cells on top (to 0.6 mm). Do the paper test (nozzle touching the bed's centre at Z0) \
before printing.\n\n\
Then: leave the print on the bed, lay a paper checkerboard card (its squares measured with a ruler) flat \
beside it, photograph both from above with a calibrated camera, and run `metrocell delta measure`.\n\n\
Example:\n  metrocell delta target -o star/"
)]
pub struct TargetArgs {
    /// star.gcode: nozzle diameter (its lines are 1.125 × as wide)
    #[arg(long, default_value = "0.4mm", value_parser = parse_length)]
    nozzle: f64,
    /// star.gcode: layer height
    #[arg(long, default_value = "0.2mm", value_parser = parse_length)]
    layer: f64,
    /// star.gcode: filament diameter
    #[arg(long, default_value = "1.75mm", value_parser = parse_length)]
    filament: f64,
    /// star.gcode: nozzle and bed temperatures (°C), NOZZLE,BED
    #[arg(long, default_value = "210,60", value_parser = parse_temperatures)]
    temperatures: (f64, f64),
    /// Directory to write the files to
    #[arg(short, long)]
    output: PathBuf,
}

fn parse_temperatures(s: &str) -> Result<(f64, f64), String> {
    let (n, b) = s
        .split_once(',')
        .ok_or_else(|| format!("`{s}`: expected NOZZLE,BED in °C, e.g. 210,60"))?;
    let parse = |v: &str| {
        v.trim()
            .parse::<f64>()
            .ok()
            .filter(|t| (0.0..=500.0).contains(t))
            .ok_or_else(|| format!("`{s}`: `{v}` is not a temperature in °C (0…500)"))
    };
    Ok((parse(n)?, parse(b)?))
}

/// The star as features to print without a slicer (the module docs of gcode::fdm_toolpath).
fn star_features(star: &DeltaStar, layer_mm: f64) -> anyhow::Result<Vec<FdmFeature>> {
    let top = star.marker_height * 1e3;
    // the white base up to the last whole layer below the tile's top; black cells above it
    let base = ((top / layer_mm).round() - 1.0).max(1.0) * layer_mm;
    let mut features: Vec<FdmFeature> = star
        .dots
        .iter()
        .map(|d| FdmFeature {
            shape: FdmShape::Disc {
                centre: [d[0] * 1e3, d[1] * 1e3],
                diameter: star.dot_diameter * 1e3,
            },
            bottom_mm: 0.0,
            top_mm: star.dot_height * 1e3,
            colour: 0,
        })
        .collect();
    for (_, centre, side) in &star.markers {
        let s = side * 1e3;
        features.push(FdmFeature {
            shape: FdmShape::Rectangle {
                corner: [centre[0] * 1e3 - s / 2.0, centre[1] * 1e3 - s / 2.0],
                size: [s, s],
            },
            bottom_mm: 0.0,
            top_mm: base,
            colour: 0,
        });
    }
    for cell in tile_cells(star)?.into_iter().filter(|c| !c.white) {
        features.push(FdmFeature {
            shape: FdmShape::Rectangle {
                corner: cell.corner,
                size: [cell.side, cell.side],
            },
            bottom_mm: base,
            top_mm: base + layer_mm,
            colour: 1,
        });
    }
    Ok(features)
}

pub fn run(a: TargetArgs) -> anyhow::Result<i32> {
    let star = DeltaStar::standard();
    let (dots, black, white) = star_solids(&star).context("making the star's solids")?;
    let settings = FdmSettings {
        nozzle_mm: a.nozzle * 1e3,
        line_width_mm: 1.125 * a.nozzle * 1e3,
        layer_height_mm: a.layer * 1e3,
        filament_diameter_mm: a.filament * 1e3,
        nozzle_temperature_c: a.temperatures.0,
        bed_temperature_c: a.temperatures.1,
        ..FdmSettings::default()
    };
    if settings.layer_height_mm > 0.8 * settings.nozzle_mm {
        anyhow::bail!(
            "--layer {} mm is too thick for a {} mm nozzle: at most 0.8 × the nozzle",
            settings.layer_height_mm,
            settings.nozzle_mm
        );
    }
    let (gcode, summary) = fdm_program(
        &star_features(&star, settings.layer_height_mm)?,
        &settings,
        &[
            "metrocell delta target: seed 002's calibration star, bed centre origin".into(),
            "light filament on a dark bed; M600 changes to black for the tiles' cells".into(),
            "do the paper test (nozzle touching the bed's centre at Z0) before printing".into(),
        ],
    );
    std::fs::create_dir_all(&a.output)
        .with_context(|| format!("creating {}", a.output.display()))?;
    for (name, text) in [
        ("dots.csv", star.dots_csv()),
        ("star_dots.stl", dots),
        ("star_tiles_black.stl", black),
        ("star_tiles_white.stl", white),
        ("star.gcode", gcode),
    ] {
        let path = a.output.join(name);
        std::fs::write(&path, text).with_context(|| format!("writing {}", path.display()))?;
        println!("wrote {}", path.display());
    }
    println!(
        "{} dots of {} mm, {} mm tall, within {} mm of the bed's centre; tiles {:?}",
        star.dots.len(),
        star.dot_diameter * 1e3,
        star.dot_height * 1e3,
        star.dots
            .iter()
            .map(|d| d[0].hypot(d[1]))
            .fold(0.0, f64::max)
            * 1e3,
        star.markers.iter().map(|m| m.0).collect::<Vec<_>>()
    );
    println!(
        "star.gcode: {} layers, {:.0} mm of filament, {} filament change",
        summary.layers, summary.filament_mm, summary.colour_changes
    );
    Ok(0)
}
