//! `metrocell delta measure --camera camera_info.yaml --images 'star*.png' -o star.csv`: photos
//! of the printed star beside a paper checkerboard card → each dot's position on the bed, in the
//! card's millimetres, as the plan rows `delta fit` reads.

use std::path::PathBuf;

use anyhow::{bail, Context};
use metrocell_vision::printed_star::{measure_star, DeltaStar, ScaleCard};

use crate::vision::image_input::{parse_board, parse_length};
use crate::vision::photo_source::{Photo, PhotoArgs};

#[derive(clap::Args)]
#[command(
    after_help = "Each photo: the card's inner corners give the bed plane's pose and scale to \
the calibrated camera; the star's three tiles tell its arms apart; each dot's top is found and carried back \
onto the plane of the dots' designed tops, 1 mm above the bed. A dot's top stands where the printer's z \
error put it, and seen from 30 cm a top 0.5 mm off its design 80 mm from the view's axis moves by 0.13 mm: so \
each row carries the camera's centre, and `delta fit` models that parallax with the height the geometry \
predicts. Keep the star and the card still between photos (move the camera if you like).\n\n\
Output: the measurements CSV of `delta fit` — one `plan` row per dot and photo (commanded x, y, z of its \
top; the measured position in the card's frame, turned right-handed; σ; the camera's centre; the plane).\n\n\
Example:\n  metrocell delta measure --camera camera_info.yaml --images 'photos/*.png' --card 9x6 --square 10mm \
-o star.csv"
)]
pub struct MeasureArgs {
    /// Photos of the star and the card (files, or frames in a recording) and the camera
    #[command(flatten)]
    photos: PhotoArgs,
    /// The card's inner corners, COLSxROWS
    #[arg(long, default_value = "9x6", value_parser = parse_board)]
    card: (usize, usize),
    /// The card's square side, as measured on the card
    #[arg(long, default_value = "10mm", value_parser = parse_length)]
    square: f64,
    /// Where to write the measurements
    #[arg(short, long)]
    output: PathBuf,
}

pub fn run(a: MeasureArgs) -> anyhow::Result<i32> {
    let photos = a.photos.open()?;
    let cam = &photos.camera.model;
    let n = photos.len();
    let star = DeltaStar::standard();
    let card = ScaleCard {
        cols: a.card.0,
        rows: a.card.1,
        square: a.square,
    };
    let mut csv = String::from(
        "kind,x_mm,y_mm,z_mm,to_x_mm,to_y_mm,to_z_mm,measured_x_mm,measured_y_mm,measured_mm,\
         sigma_mm,view_x_mm,view_y_mm,view_z_mm,plane_z_mm\n",
    );
    let (mut written, mut used) = (0, 0);
    photos.for_each(|k, Photo { label, image }| {
        let m = measure_star(&image, cam, &star, &card).with_context(|| label.clone())?;
        used += 1;
        println!(
            "[{}/{n}] {label}: {} dots, {} not found; tiles {:?}; card corners fit to {:.2} px; \
             {:.4} mm/px; camera {:.0} mm above the bed",
            k + 1,
            m.dots.len(),
            m.rejected.len(),
            m.markers,
            m.card_rms_px,
            m.mm_per_px,
            m.viewpoint.z * 1e3
        );
        for (dot, why) in &m.rejected {
            println!("    dot {}: {why:?}", dot + 1);
        }
        let v = m.viewpoint * 1e3;
        for d in &m.dots {
            let c = star.dots[d.dot];
            let sigma = (0.5 * d.covariance.trace()).sqrt() * 1e3;
            csv.push_str(&format!(
                "plan,{:.4},{:.4},{:.4},,,,{:.5},{:.5},,{sigma:.5},{:.3},{:.3},{:.3},{:.4}\n",
                c[0] * 1e3,
                c[1] * 1e3,
                star.dot_height * 1e3,
                d.position[0] * 1e3,
                d.position[1] * 1e3,
                v.x,
                v.y,
                v.z,
                star.dot_height * 1e3
            ));
            written += 1;
        }
        Ok(())
    })?;
    std::fs::write(&a.output, csv).with_context(|| format!("writing {}", a.output.display()))?;
    println!(
        "{}: {written} dot positions ({} dots × {} photos)",
        a.output.display(),
        star.dots.len(),
        used
    );
    if written < 10 {
        bail!(
            "only {written} dots measured: `delta fit` needs the star spread over the bed; check \
             the lighting (light dots on a dark bed) and the focus"
        );
    }
    Ok(0)
}
