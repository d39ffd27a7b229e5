//! `metrocell delta target -o DIR`: the calibration star to print — its solids and the table of
//! its dots' commanded positions that `delta measure` matches the photos against.

use std::path::PathBuf;

use anyhow::Context;
use metrocell_vision::printed_star::DeltaStar;
use metrocell_vision::printed_star_solid::star_solids;

#[derive(clap::Args)]
#[command(
    after_help = "Writes DIR/dots.csv (each dot's commanded x, y and the height of its top, mm), \
DIR/star_dots.stl (85 dots of 3 mm, 1 mm tall: the centre and 12 arms every 30° at 20 … 80 mm; print them \
in a light colour), DIR/star_tiles_black.stl and DIR/star_tiles_white.stl (three ArUco tiles, ids 1, 2, 3 of \
DICT_4X4_50, 14 mm, 0.6 mm tall, 15° counter-clockwise of the arms toward towers A, B, C: the same layers \
in two colours, black and white — a two-material print, or a filament change). All in the printer's frame \
(bed centre origin): place the STLs at their own coordinates, do not let the slicer centre or arrange them.\n\n\
Then: leave the print on the bed, lay a paper checkerboard card (its squares measured with a ruler) flat \
beside it, photograph both from above with a calibrated camera, and run `metrocell delta measure`.\n\n\
Example:\n  metrocell delta target -o star/"
)]
pub struct TargetArgs {
    /// Directory to write the files to
    #[arg(short, long)]
    output: PathBuf,
}

pub fn run(a: TargetArgs) -> anyhow::Result<i32> {
    let star = DeltaStar::standard();
    let (dots, black, white) = star_solids(&star).context("making the star's solids")?;
    std::fs::create_dir_all(&a.output)
        .with_context(|| format!("creating {}", a.output.display()))?;
    for (name, text) in [
        ("dots.csv", star.dots_csv()),
        ("star_dots.stl", dots),
        ("star_tiles_black.stl", black),
        ("star_tiles_white.stl", white),
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
    Ok(0)
}
