//! `metrocell verify plate`: a calibrated hole plate measured on the machine in the XY plane
//! (seed 001 part 2 §1.7) → the six XY error components, the squareness in the thesis's mrad,
//! and what correcting them compensates.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use metrocell_verification::hole_plate::{plate_components, ring_centre, PlateMeasurement};
use nalgebra::Vector2;

#[derive(clap::Args)]
#[command(after_long_help = HELP)]
pub struct PlateArgs {
    /// The plate's calibration: CSV `hole,x_mm,y_mm` (ring centres in the plate's frame at 20 °C;
    /// the first hole is the origin)
    #[arg(long)]
    nominal: PathBuf,
    /// A measurement of the plate: CSV `hole,x_mm,y_mm` in machine coordinates — one row per
    /// ring centre, or several per hole (the probe points: the centre is the circle through
    /// them); `FILE@TEMP` gives the plate's temperature in °C (default --temperature). Give the
    /// plate at two heights (the thesis's parallel measurements) to cancel rotations over the height
    #[arg(long = "measured", required = true)]
    measured: Vec<String>,
    /// The plate's temperature during the measurements, °C
    #[arg(long, default_value_t = 20.0)]
    temperature: f64,
    /// The plate's clamping point in its frame, x,y in mm (the thesis's: 200,250)
    #[arg(long, default_value = "200,250")]
    clamp: String,
    /// The plate's expansion coefficient, 1/K (the thesis's aluminium plate: 24e-6)
    #[arg(long, default_value_t = 24e-6)]
    alpha: f64,
    /// Write the numbers as JSON to this file
    #[arg(long)]
    json: Option<PathBuf>,
}

const HELP: &str = "\
Components (ISO 230-1 names; the machine's motion error, probe position − command):
  xPx, yPy   positioning of X and of Y (cubic, zero at the origin hole)
  xTy, yTx   straightness of X in Y and of Y in X (quadratic and cubic parts)
  xRz        yaw of X as it moves (its constant part is the plate's own rotation)
  xWy        squareness of X and Y in mrad: > 0 when the angle between +X and +Y exceeds 90°
The plate's misalignment (a rotation and shift per measurement) and its expansion about the
clamp at --temperature are removed first.

Examples:
  metrocell verify plate --nominal plate_cal.csv --measured z50.csv@20.6 --measured z250.csv@20.8
  metrocell verify plate --nominal plate_cal.csv --measured probe_points.csv --temperature 21.3 --json plate.json";

fn read_points(path: &Path) -> Result<Vec<(String, Vector2<f64>)>> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let mut out = vec![];
    for (n, line) in text.lines().enumerate() {
        let cells: Vec<&str> = line.split(',').map(str::trim).collect();
        if n == 0
            && cells
                .first()
                .is_some_and(|c| c.eq_ignore_ascii_case("hole"))
        {
            continue;
        }
        if line.trim().is_empty() {
            continue;
        }
        let parse = |k: usize| -> Result<f64> {
            let v: f64 = cells
                .get(k)
                .with_context(|| format!("{}:{}: expected hole,x_mm,y_mm", path.display(), n + 1))?
                .parse()
                .with_context(|| {
                    format!(
                        "{}:{}: `{}` is not a number (mm)",
                        path.display(),
                        n + 1,
                        cells[k]
                    )
                })?;
            if !v.is_finite() {
                bail!("{}:{}: not a finite number", path.display(), n + 1);
            }
            Ok(v * 1e-3)
        };
        out.push((cells[0].to_string(), Vector2::new(parse(1)?, parse(2)?)));
    }
    Ok(out)
}

pub fn run(a: PlateArgs) -> Result<i32> {
    let nominal = read_points(&a.nominal)?;
    if nominal.len() < 8 {
        bail!(
            "{}: {} holes; the six components need at least 8 rings around the plate",
            a.nominal.display(),
            nominal.len()
        );
    }
    let clamp: Vec<f64> = a
        .clamp
        .split(',')
        .map(|v| v.trim().parse::<f64>().map(|x| x * 1e-3))
        .collect::<Result<_, _>>()
        .map_err(|_| anyhow::anyhow!("--clamp `{}`: give x,y in mm", a.clamp))?;
    if clamp.len() != 2 {
        bail!("--clamp `{}`: give x,y in mm", a.clamp);
    }
    let mut measurements = vec![];
    for m in &a.measured {
        let (file, temperature) = match m.rsplit_once('@') {
            Some((f, t)) => (
                f,
                t.parse::<f64>().map_err(|_| {
                    anyhow::anyhow!("--measured {m}: `{t}` is not a temperature in °C")
                })?,
            ),
            None => (m.as_str(), a.temperature),
        };
        let rows = read_points(Path::new(file))?;
        let mut nom = vec![];
        let mut meas = vec![];
        for (hole, n) in &nominal {
            let pts: Vec<Vector2<f64>> = rows
                .iter()
                .filter(|(h, _)| h == hole)
                .map(|(_, p)| *p)
                .collect();
            let centre = match pts.len() {
                0 => continue,
                1 => pts[0],
                _ => ring_centre(&pts).with_context(|| {
                    format!("{file}: hole {hole}: its probe points do not define a circle")
                })?,
            };
            nom.push(*n);
            meas.push(centre);
        }
        if nom.len() < 8 || nom[0] != nominal[0].1 {
            bail!("{file}: {} of the calibrated holes measured{}; measure the origin hole ({}) and at least 8 rings", nom.len(), if nom.first() != Some(&nominal[0].1) { ", not the origin hole" } else { "" }, nominal[0].0);
        }
        measurements.push(PlateMeasurement {
            nominal: nom,
            measured: meas,
            temperature,
        });
    }
    let c = plate_components(&measurements, Vector2::new(clamp[0], clamp[1]), a.alpha).context(
        "the plate's rings do not determine the six components (are they all on one line?)",
    )?;
    println!(
        "hole plate: {} measurement(s), {} rings; misalignment and expansion (α {:e} /K about ({:.0}, {:.0}) mm) removed",
        measurements.len(),
        measurements.iter().map(|m| m.nominal.len()).sum::<usize>(),
        a.alpha,
        clamp[0] * 1e3,
        clamp[1] * 1e3
    );
    println!(
        "  xWy = {:.5} ± {:.5} mrad (k = 1)",
        c.squareness.0 * 1e3,
        c.squareness.1 * 1e3
    );
    for (n, (v, s)) in c.names.iter().zip(c.values.iter().zip(&c.sigmas)).take(12) {
        let (scale, unit) = if n.starts_with("xRz") {
            (1e6, "µrad")
        } else {
            (1e6, "µm")
        };
        println!("  {n:8} = {:9.3} ± {:.3} {unit}", v * scale, s * scale);
    }
    println!(
        "  mean deviation {:.2} µm before, {:.2} µm after correcting the six components: {:.2} % compensated (the thesis: 94.39 %); residual RMS {:.2} µm",
        c.mean_before * 1e6,
        c.mean_after * 1e6,
        c.compensated_percent,
        c.residual_rms * 1e6
    );
    println!(
        "  (series coefficients are at the plate's extent from the origin hole: value at u = 1)"
    );
    if let Some(path) = &a.json {
        let j = serde_json::json!({
            "squareness_mrad": {"value": c.squareness.0 * 1e3, "sigma": c.squareness.1 * 1e3},
            "components": c.names.iter().zip(c.values.iter().zip(&c.sigmas)).map(|(n, (v, s))| serde_json::json!({"name": n, "value": v, "sigma": s})).collect::<Vec<_>>(),
            "mean_deviation_um": {"before": c.mean_before * 1e6, "after": c.mean_after * 1e6},
            "compensated_percent": c.compensated_percent,
        });
        std::fs::write(path, serde_json::to_string_pretty(&j)?)
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    Ok(0)
}
