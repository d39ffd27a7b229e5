//! `metrocell delta simulate --firmware m503.txt -o DIR`: the twin prints `delta target`'s star
//! with a printer whose physical geometry differs from the settings it runs (rod, radius, tower
//! angles, switch heights: known truth) and its workflow camera photographs the star beside a
//! paper checkerboard card — photos and camera_info to try `delta measure` and `delta fit` on,
//! and to check their settings by simulating again with them.

use std::path::PathBuf;

use anyhow::Context;
use metrocell_kinematics::delta::DeltaGeometry;
use metrocell_kinematics::delta_firmware::MarlinDelta;
use metrocell_simulation::workflow_photos::{
    distance_for, photograph_star, star_extent, workflow_camera, PrintedStar,
};
use metrocell_vision::printed_star::DeltaStar;
use nalgebra::Vector3;

use crate::vision::simulated_photos::write_photos;

#[derive(clap::Args)]
#[command(
    after_help = "The physical printer: --rod, --radius, --tower-angles (A, B trims; C is the \
frame's orientation) and --switches (the carriage height where each tower's switch trips, mm — \
homing follows Marlin: rise to the switch, move by M666, count at M665 H). Defaults: a printer \
whose rod is 1 mm longer and tower A turned 0.5° against the settings given, its switches where they \
home its effector at H. The command prints the flags that name this printer: give the same ones with the \
new settings to see what they print.\n\n\
Before printing, the paper test a user does (M665 H set so the nozzle touches the bed's centre at \
z = 0) unless --no-paper-test. Writes DIR/photo_K.png, DIR/camera_info.yaml (the twin's workflow camera, \
crates/sim workflow_photos), DIR/m503.txt (the settings the star was printed with) and DIR/printer.txt \
(the physical geometry and the flags).\n\n\
Example:\n  metrocell delta simulate --firmware m503.txt -o sim/\n  metrocell delta measure --camera \
sim/camera_info.yaml --images 'sim/photo_*.png' -o star.csv\n  metrocell delta fit --firmware sim/m503.txt \
--measurements star.csv -o new.gcode\n  metrocell delta simulate --firmware new.gcode <the flags printer.txt \
names> -o round2/   # then measure, and fit with --firmware round2/m503.txt --round 2"
)]
pub struct SimulateArgs {
    /// The settings the printer runs (an M503 reply or M665/M666 lines)
    #[arg(long)]
    firmware: PathBuf,
    /// Physical rod length (mm); default: M665 L + 1
    #[arg(long)]
    rod: Option<f64>,
    /// Physical radius (mm); default: M665 R
    #[arg(long)]
    radius: Option<f64>,
    /// Physical tower angle trims A,B (degrees)
    #[arg(long, default_value = "0.5,0", value_parser = parse_pair, allow_hyphen_values = true)]
    tower_angles: (f64, f64),
    /// Carriage heights where the switches trip, A,B,C (mm); default: where they home the
    /// physical effector at M665 H
    #[arg(long, value_parser = parse_triple, allow_hyphen_values = true)]
    switches: Option<[f64; 3]>,
    /// Skip the paper test before printing (it sets M665 H so the nozzle touches the bed at
    /// its centre at z = 0, as a user does after loading new settings)
    #[arg(long)]
    no_paper_test: bool,
    /// Photos to take
    #[arg(long, default_value_t = 1, value_parser = clap::value_parser!(u64).range(1..=100))]
    photos: u64,
    /// Seed of the photos' viewpoints and noise
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Directory to write to
    #[arg(short, long)]
    output: PathBuf,
}

fn parse_numbers(s: &str, n: usize) -> Result<Vec<f64>, String> {
    let v: Vec<f64> = s
        .split(',')
        .map(|t| t.trim().parse::<f64>())
        .collect::<Result<_, _>>()
        .map_err(|_| format!("`{s}`: expected {n} comma-separated numbers"))?;
    if v.len() != n || v.iter().any(|x| !x.is_finite()) {
        return Err(format!(
            "`{s}`: expected {n} finite comma-separated numbers"
        ));
    }
    Ok(v)
}

fn parse_pair(s: &str) -> Result<(f64, f64), String> {
    let v = parse_numbers(s, 2)?;
    Ok((v[0], v[1]))
}

fn parse_triple(s: &str) -> Result<[f64; 3], String> {
    let v = parse_numbers(s, 3)?;
    Ok([v[0], v[1], v[2]])
}

/// The physical printer running `settings`: what it prints where.
struct PhysicalPrinter {
    firmware: DeltaGeometry,
    physical: DeltaGeometry,
}

impl PhysicalPrinter {
    fn new(
        settings: &MarlinDelta,
        mut physical: DeltaGeometry,
        switches: [f64; 3],
    ) -> anyhow::Result<Self> {
        let firmware = settings.firmware_geometry()?;
        physical.endstop = settings.endstop_offsets(switches)?;
        physical.validate()?;
        Ok(Self { firmware, physical })
    }

    /// Where the nozzle goes when `p` (m) is commanded.
    fn print(&self, p: Vector3<f64>) -> anyhow::Result<Vector3<f64>> {
        let q = self
            .firmware
            .inverse(&p)
            .with_context(|| format!("{p:?} is outside the printer's reach"))?;
        Ok(self.physical.forward(&q)?)
    }
}

pub fn run(a: SimulateArgs) -> anyhow::Result<i32> {
    let text = std::fs::read_to_string(&a.firmware)
        .with_context(|| format!("reading {}", a.firmware.display()))?;
    let settings =
        MarlinDelta::from_gcode(&text).with_context(|| a.firmware.display().to_string())?;
    let rod = a.rod.unwrap_or(settings.diagonal_rod_mm + 1.0);
    let radius = a.radius.unwrap_or(settings.radius_mm);
    let mut physical = DeltaGeometry::new(rod * 1e-3, radius * 1e-3)?;
    physical.tower_angle_trim = [a.tower_angles.0, a.tower_angles.1, 0.0].map(f64::to_radians);
    // by default the switches home the physical effector at H (a printer whose first layer was
    // levelled by hand): what is left is the geometry's bowl and tilt
    let switches = match a.switches {
        Some(s) => s,
        None => settings.switches_homing_at_height(&physical)?,
    };
    let mut settings = settings;
    let mut printer = PhysicalPrinter::new(&settings, physical, switches)?;
    let centre = printer.print(Vector3::zeros())?.z * 1e3;
    if !a.no_paper_test && centre.abs() > 1e-9 {
        // the nozzle `centre` mm above the bed at z = 0: a higher H counts every carriage
        // higher, so the same commands put the effector lower by as much
        let before = settings.height_mm;
        settings.height_mm += centre;
        printer = PhysicalPrinter::new(&settings, physical, switches)?;
        println!(
            "paper test: the nozzle was {centre:+.3} mm above the bed's centre at z = 0; M665 H \
             {before:.3} → {:.3}",
            settings.height_mm
        );
    }
    let physical = printer.physical;
    let print = |p: Vector3<f64>| printer.print(p);
    let design = DeltaStar::standard();
    let dots = design
        .dots
        .iter()
        .map(|d| print(Vector3::new(d[0], d[1], design.dot_height)))
        .collect::<anyhow::Result<Vec<_>>>()?;
    let tiles = design
        .markers
        .iter()
        .map(|(id, c, side)| {
            Ok((
                *id,
                print(Vector3::new(c[0], c[1], design.marker_height))?,
                *side,
            ))
        })
        .collect::<anyhow::Result<Vec<_>>>()?;
    let star = PrintedStar {
        dots,
        dot_diameter: design.dot_diameter,
        tiles,
        // `delta measure`'s default card: 9 × 6 inner corners of 10 mm, right of the star
        card_squares: (10, 7),
        card_square: 0.010,
        card_corner: [0.090, 0.035],
    };
    let camera = workflow_camera();
    let distance = distance_for(&camera, star_extent(&star));
    write_photos(&a.output, &camera, a.photos, |k| {
        photograph_star(&star, &camera, distance, a.seed, k)
    })?;
    let flags = format!(
        "--rod {rod} --radius {radius} --tower-angles {},{} --switches {},{},{}",
        a.tower_angles.0, a.tower_angles.1, switches[0], switches[1], switches[2]
    );
    let heights: Vec<f64> = star.dots.iter().map(|d| d.z * 1e3).collect();
    let (lo, hi) = heights
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &z| {
            (l.min(z), h.max(z))
        });
    let summary = format!(
        "physical printer: rod {rod} mm, radius {radius} mm, tower angle trims A {} B {} C 0 °, \
         switches {switches:?} mm\nendstop offsets under {} (physical − counted carriage height): \
         {:.4}, {:.4}, {:.4} mm\ndot tops printed at {lo:.3}…{hi:.3} mm (designed {:.3})\n\
         flags: {flags}\n",
        a.tower_angles.0,
        a.tower_angles.1,
        a.firmware.display(),
        physical.endstop[0] * 1e3,
        physical.endstop[1] * 1e3,
        physical.endstop[2] * 1e3,
        design.dot_height * 1e3
    );
    std::fs::write(a.output.join("printer.txt"), &summary).context("writing printer.txt")?;
    // what `M503` would answer: the settings the star was printed with
    std::fs::write(a.output.join("m503.txt"), settings.marlin_commands())
        .context("writing m503.txt")?;
    print!("{summary}");
    println!(
        "{}: {} photos from {:.0} mm ({:.3} mm/px), camera_info.yaml, printer.txt, m503.txt (the \
         settings it printed with: give them to `delta fit --firmware`)",
        a.output.display(),
        a.photos,
        distance * 1e3,
        distance / camera.fx * 1e3
    );
    Ok(0)
}
