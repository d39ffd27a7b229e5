//! `disturbances:` — deliberately **non-physical** structures added to the true tool position,
//! for testing `diagnose` only (the concealed-effect suite in `bags/`).
//!
//! `diagnose` must say "unexplained, and here is where it lives" when the data hold a structure
//! that no catalog term models, rather than giving it a physical name. To make such recordings
//! the twin needs a way to put one in that is, by construction, *not* a catalog term. That is all
//! this section is: never use it to describe a real machine, and never add a catalog term for
//! it (the catalog is `crates/physics`). A cell without the section simulates exactly as before.
//!
//! ```yaml
//! disturbances:            # test-only, not physics
//!   time_cycles:           # δ(t) = a·sin(2π t/period + phase), t = shift time (s)
//!     - {amplitude: [0 um, 0 um, 12 um], period: 47 min, phase: 30 deg}
//!   workspace_bumps:       # δ(q) = a·exp(−|q − centre|² / (2 width²)), q = commanded x, y, z
//!     - {amplitude: [0 um, 15 um, 0 um], centre: [600 mm, 350 mm, 100 mm], width: 90 mm}
//! ```
//!
//! Convention (stated once, here): δ is a displacement of the tool relative to the workpiece,
//! realised − commanded, in the workpiece frame (for cartesian and delta machines, the frame
//! tool points are reported in), added to the machine's true terms at every instant: the
//! tracker sees it, the probe and the camera see it, and `SampleTruth`'s displacement includes
//! it. Implemented for the cartesian and delta families (whose commanded `q` is the tool point
//! less the tool offset); other families reject the section.

use nalgebra::Vector3;

use crate::error::CellError;
use crate::quantity::vector3;

pub use metrocell_model_file::cell_file::{
    DisturbanceSection, TimeCycleSection, WorkspaceBumpSection,
};

#[derive(Debug, Clone, Copy, PartialEq)]
struct TimeCycle {
    amplitude: Vector3<f64>,
    period: f64,
    phase: f64,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct WorkspaceBump {
    amplitude: Vector3<f64>,
    centre: Vector3<f64>,
    width: f64,
}

/// The validated disturbances of a cell (empty: none).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Disturbances {
    time_cycles: Vec<TimeCycle>,
    workspace_bumps: Vec<WorkspaceBump>,
}

impl Disturbances {
    /// Validate the section (`section_allowed` false: the family does not support it).
    pub fn from_section(
        s: &DisturbanceSection,
        section_allowed: bool,
    ) -> Result<Disturbances, CellError> {
        let p = "disturbances";
        if !section_allowed && (!s.time_cycles.is_empty() || !s.workspace_bumps.is_empty()) {
            return Err(CellError::invalid(p, "is implemented for family: cartesian and delta only (a test-only section; see crates/twin/src/disturbance.rs)"));
        }
        let mut d = Disturbances::default();
        for (i, c) in s.time_cycles.iter().enumerate() {
            let cp = format!("{p}.time_cycles[{i}]");
            d.time_cycles.push(TimeCycle {
                amplitude: vector3(&c.amplitude, &format!("{cp}.amplitude"), "m")?,
                period: c.period.positive(&format!("{cp}.period"), "s")?,
                phase: c
                    .phase
                    .as_ref()
                    .map(|q| q.to_si(&format!("{cp}.phase"), "rad"))
                    .transpose()?
                    .unwrap_or(0.0),
            });
        }
        for (i, b) in s.workspace_bumps.iter().enumerate() {
            let bp = format!("{p}.workspace_bumps[{i}]");
            d.workspace_bumps.push(WorkspaceBump {
                amplitude: vector3(&b.amplitude, &format!("{bp}.amplitude"), "m")?,
                centre: vector3(&b.centre, &format!("{bp}.centre"), "m")?,
                width: b.width.positive(&format!("{bp}.width"), "m")?,
            });
        }
        Ok(d)
    }

    pub fn is_empty(&self) -> bool {
        self.time_cycles.is_empty() && self.workspace_bumps.is_empty()
    }

    /// δ at shift time `t` (s) and commanded axis position `q` (m), workpiece frame (m).
    pub fn displacement(&self, t: f64, q: &Vector3<f64>) -> Vector3<f64> {
        let cycles = self
            .time_cycles
            .iter()
            .map(|c| c.amplitude * (std::f64::consts::TAU * t / c.period + c.phase).sin());
        let bumps = self.workspace_bumps.iter().map(|b| {
            b.amplitude * (-(q - b.centre).norm_squared() / (2.0 * b.width * b.width)).exp()
        });
        cycles.chain(bumps).fold(Vector3::zeros(), |acc, v| acc + v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(yaml: &str) -> Result<Disturbances, CellError> {
        Disturbances::from_section(&serde_yaml::from_str(yaml).unwrap(), true)
    }

    #[test]
    fn cycle_and_bump_values() {
        let d = parse(
            "time_cycles: [{amplitude: [0 um, 0 um, 10 um], period: 100 s, phase: 90 deg}]\n\
             workspace_bumps: [{amplitude: [0 um, 20 um, 0 um], centre: [0.1, 0.2, 0.3], width: 50 mm}]",
        )
        .unwrap();
        // at the bump's centre and t = 0: the cycle at its peak (sin 90° = 1), the bump at its peak
        let v = d.displacement(0.0, &Vector3::new(0.1, 0.2, 0.3));
        assert!(
            (v - Vector3::new(0.0, 20e-6, 10e-6)).norm() < 1e-15,
            "{v:?}"
        );
        // a quarter period later the cycle is at 0; one width off the centre the bump is e^(−1/2)
        let v = d.displacement(25.0, &Vector3::new(0.15, 0.2, 0.3));
        assert!(
            (v.y - 20e-6 * (-0.5f64).exp()).abs() < 1e-15 && v.z.abs() < 1e-18,
            "{v:?}"
        );
        // far from the bump and half a period on: only the cycle, reversed
        let v = d.displacement(50.0, &Vector3::new(2.0, 2.0, 2.0));
        assert!((v.z + 10e-6).abs() < 1e-15 && v.y.abs() < 1e-20, "{v:?}");
    }

    #[test]
    fn bad_values_name_the_key() {
        let e = parse("time_cycles: [{amplitude: [0, 0, 1 um], period: 0 s}]")
            .unwrap_err()
            .to_string();
        assert!(e.contains("disturbances.time_cycles[0].period"), "{e}");
        let e =
            parse("workspace_bumps: [{amplitude: [0, 0, 1 um], centre: [0, 0, 0], width: 3 K}]")
                .unwrap_err()
                .to_string();
        assert!(e.contains("disturbances.workspace_bumps[0].width"), "{e}");
        let e = Disturbances::from_section(
            &serde_yaml::from_str("time_cycles: [{amplitude: [0, 0, 1 um], period: 1 s}]").unwrap(),
            false,
        )
        .unwrap_err()
        .to_string();
        assert!(e.contains("cartesian and delta"), "{e}");
        assert!(
            serde_yaml::from_str::<DisturbanceSection>("time_cycle: []").is_err(),
            "unknown keys are errors"
        );
    }
}
