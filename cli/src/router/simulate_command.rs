//! `metrocell router simulate -o DIR`: the twin drills `router pattern`'s plate with a known
//! planar error field (seed 000's eq. 7; the paper's B72 coefficients unless told) and its
//! workflow camera photographs it — photos, the camera's calibration and the truth, to try
//! `router measure` and `router fit` on before a machine is at hand, or to check them.

use std::path::PathBuf;

use anyhow::Context;
use metrocell_gcode::PlanarQuadraticField;
use metrocell_simulation::workflow_photos::{
    distance_for, photograph_plate, workflow_camera, DrilledPlate,
};

use super::pattern_command::PlateLayout;
use crate::vision::simulated_photos::write_photos;

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
    /// The plate, as for `router pattern`
    #[command(flatten)]
    plate: PlateLayout,
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
    let PlateLayout {
        squares: (sx, sy),
        square,
        hole,
        origin,
    } = a.plate;
    let s_mm = square * 1e3;
    let height_mm = sy as f64 * s_mm;
    let mut truth = String::from("hole,x_mm,y_mm,ex_mm,ey_mm\n");
    let mut holes = vec![[0.0; 2]; sx * sy];
    for row in 0..sy {
        for column in 0..sx {
            let x = origin.0 + (column as f64 + 0.5) * s_mm;
            let y = origin.1 + (row as f64 + 0.5) * s_mm;
            let (ex, ey) = a.field.error_mm(x, y);
            truth.push_str(&format!(
                "{},{x:.4},{y:.4},{ex:.6},{ey:.6}\n",
                row * sx + column + 1
            ));
            // board frame: x right, y down from the back edge (m)
            holes[(sy - 1 - row) * sx + column] = [
                (x + ex - origin.0) * 1e-3,
                (height_mm - (y + ey - origin.1)) * 1e-3,
            ];
        }
    }
    let plate = DrilledPlate {
        squares: (sx as u32, sy as u32),
        square,
        hole,
        holes,
    };
    let camera = workflow_camera();
    let extent = square * sx.max(sy) as f64;
    let distance = distance_for(&camera, extent);
    write_photos(&a.output, &camera, a.photos, |k| {
        photograph_plate(&plate, &camera, distance, a.seed, k)
    })?;
    std::fs::write(a.output.join("truth.csv"), truth).context("writing truth.csv")?;
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
