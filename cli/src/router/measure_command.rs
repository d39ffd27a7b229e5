//! `metrocell router measure --camera camera_info.yaml --images 'plate*.png' -o holes.csv`:
//! photos of the drilled plate → each hole's position on the board, in machine millimetres, and
//! its error (reached − commanded) with its uncertainty: the table `router fit` reads.

use std::path::PathBuf;

use anyhow::{bail, Context};
use metrocell_vision::hole_plate::{measure_plate, PlateMeasurement};
use metrocell_vision::holes::HoleSearch;
use nalgebra::Matrix2;

use super::pattern_command::parse_point;
use crate::vision::image_input::{parse_length, parse_squares};
use crate::vision::photo_source::{Photo, PhotoArgs};

#[derive(clap::Args)]
#[command(
    after_help = "Each photo: the board's inner corners give its pose to the calibrated \
camera (`metrocell camera calibrate` writes --camera), every hole is found where its square's centre \
falls, and its centre is carried through the lens model onto the board plane. Photos are combined hole by \
hole (weighted mean; where the photos disagree by more than their σ, the σ is widened to their scatter).\n\n\
Orientation: photograph from above with the machine's back (+Y) at the top of the image, as `router \
pattern` prints it. A photo turned by 90° is recognised by the holes' colours and refused; one turned by \
180° cannot be told apart on a board with an even number of squares.\n\n\
Output: CSV hole,column,row,x_mm,y_mm,ex_mm,ey_mm,sigma_x_mm,sigma_y_mm — the nominal (commanded) \
machine position, the error e = measured − nominal, and its standard uncertainty.\n\n\
Example:\n  metrocell router measure --camera camera_info.yaml --images 'plate/*.png' --squares 6x6 \
--square 25mm --origin 20,20 -o holes.csv"
)]
pub struct MeasureArgs {
    /// Photos of the drilled plate (files, or frames in a recording) and the camera
    #[command(flatten)]
    photos: PhotoArgs,
    /// Squares along X and Y, as `router pattern` made them
    #[arg(long, default_value = "6x6", value_parser = parse_squares)]
    squares: (usize, usize),
    /// Side of a square, as printed (check the scale bar)
    #[arg(long, default_value = "25mm", value_parser = parse_length)]
    square: f64,
    /// Machine X,Y of the board's front-left corner (mm), as given to `router pattern`
    #[arg(long, default_value = "0,0", value_parser = parse_point)]
    origin: (f64, f64),
    /// Where to write the hole error table
    #[arg(short, long)]
    output: PathBuf,
}

/// Weighted sums of one hole's positions over photos (machine mm).
#[derive(Default, Clone)]
struct Combined {
    information: Matrix2<f64>,
    weighted: nalgebra::Vector2<f64>,
    positions: Vec<nalgebra::Vector2<f64>>,
}

pub fn run(a: MeasureArgs) -> anyhow::Result<i32> {
    let photos = a.photos.open()?;
    let cam = &photos.camera.model;
    let (sx, sy) = a.squares;
    let square_mm = a.square * 1e3;
    let mut holes: Vec<Combined> = vec![Combined::default(); sx * sy];
    let mut used = 0;
    let n = photos.len();
    photos.for_each(|k, Photo { label, image }| {
        let search = HoleSearch {
            window_half_px: 0,
            ..HoleSearch::default()
        };
        let Some(plate) =
            measure_plate(&image, cam, sx, sy, a.square, &search).with_context(|| label.clone())?
        else {
            println!(
                "[{}/{n}] {label}: no {sx}×{sy}-square board found — skipped",
                k + 1
            );
            return Ok(());
        };
        check_orientation(&plate, sy, &label)?;
        println!(
            "[{}/{n}] {label}: {} holes, {} squares without one; corners fit to {:.2} px; {:.4} mm/px",
            k + 1,
            plate.holes.len(),
            plate.rejected.len(),
            plate.corner_rms_px,
            plate.mm_per_px
        );
        for ((c, r), why) in &plate.rejected {
            println!("    square ({c}, {}): {why:?}", sy - 1 - r);
        }
        used += 1;
        let height = sy as f64 * square_mm;
        for h in &plate.holes {
            // machine: x along the columns, y up the image (rows counted from the front)
            let flip = Matrix2::new(1.0, 0.0, 0.0, -1.0);
            let p = nalgebra::Vector2::new(
                a.origin.0 + h.measured[0] * 1e3,
                a.origin.1 + height - h.measured[1] * 1e3,
            );
            let cov = flip * h.covariance * flip.transpose() * 1e6;
            let Some(inf) = cov.try_inverse() else {
                continue;
            };
            let slot = &mut holes[(sy - 1 - h.row) * sx + h.column];
            slot.information += inf;
            slot.weighted += inf * p;
            slot.positions.push(p);
        }
        Ok(())
    })?;
    if used == 0 {
        bail!(
            "no photo showed the {sx}×{sy}-square board: check --squares (squares, not inner \
             corners), the focus and that the whole board is in the picture"
        );
    }
    write_table(&a, &holes, used)
}

/// A board photographed turned by 90° puts white squares where the pattern has black ones: the
/// holes (the backing's colour shows through) say so.
fn check_orientation(
    plate: &PlateMeasurement,
    squares_y: usize,
    photo: &str,
) -> anyhow::Result<()> {
    let agree = plate
        .holes
        .iter()
        .filter(|h| {
            let black_square = (h.column + (squares_y - 1 - h.row)).is_multiple_of(2);
            // a hole through a black square shows the white backing
            black_square != h.dark
        })
        .count();
    if plate.holes.len() >= 4 && 2 * agree < plate.holes.len() {
        bail!(
            "{}: the holes' colours say the board is turned by 90° ({} of {} holes show the \
             colour their square's would behind it): photograph with the machine's back (+Y) \
             at the top of the image",
            photo,
            plate.holes.len() - agree,
            plate.holes.len()
        );
    }
    Ok(())
}

fn write_table(a: &MeasureArgs, holes: &[Combined], photos: usize) -> anyhow::Result<i32> {
    let (sx, _) = a.squares;
    let square_mm = a.square * 1e3;
    let mut csv = String::from("hole,column,row,x_mm,y_mm,ex_mm,ey_mm,sigma_x_mm,sigma_y_mm\n");
    let (mut written, mut widened, mut missing) = (0, 0, Vec::new());
    for (k, h) in holes.iter().enumerate() {
        let (column, row) = (k % sx, k / sx);
        let Some(cov) = h
            .information
            .try_inverse()
            .filter(|_| !h.positions.is_empty())
        else {
            missing.push((column, row));
            continue;
        };
        let mean = cov * h.weighted;
        let mut sigma = [cov[(0, 0)].sqrt(), cov[(1, 1)].sqrt()];
        let n = h.positions.len();
        if n >= 2 {
            // the photos' scatter about their mean, as a σ of the mean
            for (axis, s) in sigma.iter_mut().enumerate() {
                let var = h
                    .positions
                    .iter()
                    .map(|p| (p[axis] - mean[axis]).powi(2))
                    .sum::<f64>()
                    / ((n - 1) * n) as f64;
                if var.sqrt() > *s {
                    *s = var.sqrt();
                    widened += 1;
                }
            }
        }
        let nominal = (
            a.origin.0 + (column as f64 + 0.5) * square_mm,
            a.origin.1 + (row as f64 + 0.5) * square_mm,
        );
        csv.push_str(&format!(
            "{},{column},{row},{:.4},{:.4},{:.5},{:.5},{:.5},{:.5}\n",
            k + 1,
            nominal.0,
            nominal.1,
            mean[0] - nominal.0,
            mean[1] - nominal.1,
            sigma[0],
            sigma[1]
        ));
        written += 1;
    }
    std::fs::write(&a.output, csv).with_context(|| format!("writing {}", a.output.display()))?;
    println!(
        "{}: {written} holes from {photos} photos{}{}",
        a.output.display(),
        if widened > 0 {
            format!("; {widened} σ widened to the photos' scatter")
        } else {
            String::new()
        },
        if missing.is_empty() {
            String::new()
        } else {
            format!("; no hole found in squares {missing:?} (column, row from the front-left)")
        }
    );
    if written < 5 {
        bail!(
            "only {written} holes measured: `router fit` needs at least 5; check the lighting \
             (a hole must contrast with its square) and --square"
        );
    }
    Ok(0)
}
