//! `metrocell verify probe-tip`: the probe-tip check before a plate or sphere measurement
//! (seed 001 part 2 §1.6) — a sphere's centre at head angles every 15° → range and
//! repeatability per axis (the thesis's Tables 5.3/5.4), the tip's eccentricity and the
//! three-lobe pretravel pattern, each said to be significant or not.

use std::path::PathBuf;

use anyhow::{bail, Context, Result};
use metrocell_verification::probe_tip::probe_tip_check;
use nalgebra::Vector3;

#[derive(clap::Args)]
#[command(
    after_long_help = "Input: CSV angle_deg,x_mm,y_mm,z_mm — the sphere's measured centre at each head angle \
(the thesis turned the head every 15°: 24 rows).\n\nA bent or off-axis tip moves the centre round a circle once \
per turn (eccentricity; the thesis's uncorrected tip: range 0.61 mm); the probe's three-point seating makes its \
pretravel vary with direction, three lobes 120° apart (after the correction, ~30 µm). Correct a significant \
eccentricity before measuring (probe a flat, turn the probe 180°, probe again, adjust the screws); the lobes are \
the probe's and enter the uncertainty through the repeatability.\n\nExample:\n  metrocell verify probe-tip sphere_centres.csv"
)]
pub struct ProbeTipArgs {
    /// CSV angle_deg,x_mm,y_mm,z_mm
    centres: PathBuf,
}

/// The head angles (rad) and sphere centres (m) of a CSV angle_deg,x_mm,y_mm,z_mm.
pub fn read_centres(path: &std::path::Path) -> Result<(Vec<f64>, Vec<Vector3<f64>>)> {
    let text =
        std::fs::read_to_string(path).with_context(|| format!("cannot read {}", path.display()))?;
    let (mut angles, mut centres) = (vec![], vec![]);
    for (n, line) in text.lines().enumerate() {
        if line.trim().is_empty() || (n == 0 && line.to_ascii_lowercase().starts_with("angle")) {
            continue;
        }
        let v: Vec<f64> = line
            .split(',')
            .map(|c| c.trim().parse::<f64>())
            .collect::<Result<_, _>>()
            .map_err(|_| {
                anyhow::anyhow!(
                    "{}:{}: expected angle_deg,x_mm,y_mm,z_mm, got `{line}`",
                    path.display(),
                    n + 1
                )
            })?;
        if v.len() != 4 || v.iter().any(|x| !x.is_finite()) {
            bail!(
                "{}:{}: expected four finite numbers angle_deg,x_mm,y_mm,z_mm",
                path.display(),
                n + 1
            );
        }
        angles.push(v[0].to_radians());
        centres.push(Vector3::new(v[1], v[2], v[3]) * 1e-3);
    }
    Ok((angles, centres))
}

pub fn run(a: ProbeTipArgs) -> Result<i32> {
    let (angles, centres) = read_centres(&a.centres)?;
    let c = probe_tip_check(&angles, &centres).with_context(|| {
        format!(
            "{}: {} angles; the check needs 8 or more, spread round the turn",
            a.centres.display(),
            angles.len()
        )
    })?;
    println!("probe-tip check over {} head angles (Table 5.3/5.4 of the thesis: range, repeatability = 4σ):", angles.len());
    println!("  axis  range [mm]  repeatability [mm]");
    for (k, axis) in ["X", "Y", "Z"].iter().enumerate() {
        println!(
            "  {axis}     {:.3}       {:.3}",
            c.range[k] * 1e3,
            c.repeatability[k] * 1e3
        );
    }
    let say = |name: &str, h: &metrocell_verification::probe_tip::Harmonic, meaning: &str| {
        println!(
            "  {name}: {:.1} ± {:.1} µm — {}",
            h.amplitude * 1e6,
            h.sigma * 1e6,
            if h.significant() {
                meaning.to_string()
            } else {
                "not significant (within the noise at 1 % false alarm)".to_string()
            }
        );
    };
    say(
        "tip eccentricity (once per turn)",
        &c.eccentricity,
        "significant: the tip is off the spindle axis; correct it before measuring",
    );
    say(
        "three-lobe pattern (3 per turn, 120° apart)",
        &c.three_lobe,
        "significant: the probe's kinematic seating (direction-dependent pretravel)",
    );
    println!(
        "  centre noise after harmonics 1–3: {:.1} µm per coordinate",
        c.residual_sigma * 1e6
    );
    Ok(0)
}
