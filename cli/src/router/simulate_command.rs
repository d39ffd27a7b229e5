//! `metrocell router simulate -o DIR`: the twin drills `router pattern`'s plate with a known
//! planar error field (seed 000's eq. 7; the paper's B72 coefficients unless told) and its
//! workflow camera photographs it — photos, the camera's calibration and the truth, to try
//! `router measure` and `router fit` on before a machine is at hand, or to check them.

use std::path::PathBuf;

use anyhow::Context;
use metrocell_camera_model::CameraInfo;
use metrocell_gcode::PlanarQuadraticField;
use metrocell_simulation::workflow_photos::{photograph_plate, workflow_camera, DrilledPlate};

use super::pattern_command::parse_point;
use crate::vision::image_input::{parse_length, parse_squares};

#[derive(clap::Args)]
#[command(
    after_help = "Writes DIR/photo_K.png (K = 0…), DIR/camera_info.yaml (the workflow camera: \
2048×1536 px, f 3400 px, Brown–Conrady distortion; 0.8 px blur, 1 grey level of noise — crates/sim \
workflow_photos) and DIR/truth.csv (hole,x_mm,y_mm,ex_mm,ey_mm: where each hole was drilled, machine mm, \
holes numbered row by row from the front-left as `router measure` numbers them).\n\n\
Example (the whole workflow on the twin):\n  metrocell router simulate --photos 2 -o sim/\n  \
metrocell router measure --camera sim/camera_info.yaml --images 'sim/photo_*.png' -o holes.csv\n  \
metrocell router fit --errors holes.csv"
)]
pub struct SimulateArgs {
    /// Squares along X and Y, as for `router pattern`
    #[arg(long, default_value = "6x6", value_parser = parse_squares)]
    squares: (usize, usize),
    /// Side of a square
    #[arg(long, default_value = "25mm", value_parser = parse_length)]
    square: f64,
    /// Drill diameter
    #[arg(long, default_value = "1mm", value_parser = parse_length)]
    hole: f64,
    /// Machine X,Y of the board's front-left corner (mm)
    #[arg(long, default_value = "0,0", value_parser = parse_point)]
    origin: (f64, f64),
    /// The router's error field: `b72` (seed 000's Table 2) or eq. 7's nine coefficients
    /// A,B,C,D,E,F,G,H,I (mm units, X3 = 1)
    #[arg(long, default_value = "b72", value_parser = parse_field, allow_hyphen_values = true)]
    field: PlanarQuadraticField,
    /// Photos to take
    #[arg(long, default_value_t = 2, value_parser = clap::value_parser!(u64).range(1..=100))]
    photos: u64,
    /// Seed of the photos' viewpoints and noise
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Directory to write to
    #[arg(short, long)]
    output: PathBuf,
}

/// `b72` or nine comma-separated coefficients.
fn parse_field(s: &str) -> Result<PlanarQuadraticField, String> {
    if s.eq_ignore_ascii_case("b72") {
        return Ok(PlanarQuadraticField::seed000_b72());
    }
    let values: Vec<f64> = s
        .split(',')
        .map(|v| v.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("`{s}`: expected b72 or nine numbers A,B,C,D,E,F,G,H,I"))?;
    let coefficients: [f64; 9] = values
        .try_into()
        .map_err(|v: Vec<f64>| format!("`{s}`: {} numbers, eq. 7 has nine (A…I)", v.len()))?;
    if coefficients.iter().any(|c| !c.is_finite()) {
        return Err(format!("`{s}`: every coefficient must be finite"));
    }
    Ok(PlanarQuadraticField {
        coefficients,
        ..PlanarQuadraticField::seed000_b72()
    })
}

pub fn run(a: SimulateArgs) -> anyhow::Result<i32> {
    let (sx, sy) = a.squares;
    let s_mm = a.square * 1e3;
    let height_mm = sy as f64 * s_mm;
    let mut truth = String::from("hole,x_mm,y_mm,ex_mm,ey_mm\n");
    let mut holes = vec![[0.0; 2]; sx * sy];
    for row in 0..sy {
        for column in 0..sx {
            let x = a.origin.0 + (column as f64 + 0.5) * s_mm;
            let y = a.origin.1 + (row as f64 + 0.5) * s_mm;
            let (ex, ey) = a.field.error_mm(x, y);
            truth.push_str(&format!(
                "{},{x:.4},{y:.4},{ex:.6},{ey:.6}\n",
                row * sx + column + 1
            ));
            // board frame: x right, y down from the back edge (m)
            holes[(sy - 1 - row) * sx + column] = [
                (x + ex - a.origin.0) * 1e-3,
                (height_mm - (y + ey - a.origin.1)) * 1e-3,
            ];
        }
    }
    let plate = DrilledPlate {
        squares: (sx as u32, sy as u32),
        square: a.square,
        hole: a.hole,
        holes,
    };
    let camera = workflow_camera();
    // the board's larger side across 80 % of the image's shorter side
    let extent = a.square * sx.max(sy) as f64;
    let distance = camera.fx * extent / (0.8 * camera.height.min(camera.width) as f64);
    std::fs::create_dir_all(&a.output)
        .with_context(|| format!("creating {}", a.output.display()))?;
    let info_path = a.output.join("camera_info.yaml");
    CameraInfo::from_model("workflow_camera", &camera)
        .save(&info_path)
        .with_context(|| format!("writing {}", info_path.display()))?;
    std::fs::write(a.output.join("truth.csv"), truth).context("writing truth.csv")?;
    for k in 0..a.photos {
        let image = photograph_plate(&plate, &camera, distance, a.seed, k)?;
        let path = a.output.join(format!("photo_{k}.png"));
        image
            .save(&path)
            .with_context(|| format!("writing {}", path.display()))?;
        println!("[{}/{}] {}", k + 1, a.photos, path.display());
    }
    println!(
        "{}: {} photos of the {sx}×{sy} plate from {:.0} mm ({:.3} mm/px), camera_info.yaml, truth.csv",
        a.output.display(),
        a.photos,
        distance * 1e3,
        distance / camera.fx * 1e3
    );
    Ok(0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn field_is_b72_or_nine_finite_numbers() {
        assert_eq!(
            parse_field("B72").unwrap(),
            PlanarQuadraticField::seed000_b72()
        );
        let f = parse_field("1e-5, 0,0,0.01,0,0,0,0,-2e-5").unwrap();
        assert_eq!(f.coefficients[3], 0.01);
        assert!(parse_field("1,2,3").unwrap_err().contains("3 numbers"));
        assert!(parse_field("1,2,3,4,5,6,7,8,nan").is_err());
        assert!(parse_field("b27").unwrap_err().contains("nine numbers"));
    }
}
