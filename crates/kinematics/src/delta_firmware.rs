//! A delta printer's firmware settings (Marlin `M665`/`M666`, Klipper `[printer]`/`[stepper_*]`)
//! and their correction from an identified physical geometry.
//!
//! Units here are the firmware's: millimetres and degrees (the rest of the crate is SI; the
//! conversion is in [`MarlinDelta::firmware_geometry`]).
//!
//! How the firmware homes, and so what an endstop offset means (Marlin `homeaxis()` for DELTA):
//! each carriage rises to its switch at physical height `S_T`, moves by its adjustment `adj_T`
//! (`M666`, ≤ 0: down, away from the switch) and is then counted at
//! `Q_T = H + √(D_T² − R_T²)` — the inverse kinematics of the effector centred at the delta height
//! `H` (`M665 H`). The physical carriage is therefore `e_T = S_T + adj_T − Q_T` above its count,
//! which is [`DeltaGeometry::endstop`] as estimated with these settings. New settings that make
//! every `e_T` zero with the identified rods and radii: `adj'_T = adj_T − e_T + (Q'_T − Q_T)`,
//! with `H'` chosen so that the largest `adj'_T` is 0 (Marlin applies only adjustments ≤ 0).
//!
//! Klipper counts each carriage at its switch as `position_endstop_T + √(arm_T² − R²)` (its
//! delta kinematics module), so the same homed state is `position_endstop_T = H − adj_T`.

use crate::delta::{DeltaGeometry, MARLIN_TOWER_BASE_ANGLES};
use crate::error::KinematicsError;

/// The delta settings a Marlin printer runs (`M503` prints them), in mm and degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MarlinDelta {
    /// `M665 L`: `DELTA_DIAGONAL_ROD`.
    pub diagonal_rod_mm: f64,
    /// `M665 R`: `DELTA_RADIUS`.
    pub radius_mm: f64,
    /// `M665 H`: the effector's height above the bed when homed.
    pub height_mm: f64,
    /// `M665 X Y Z`: tower angle trims A, B, C (degrees, counter-clockwise seen from above).
    pub tower_angle_trim_deg: [f64; 3],
    /// `M665 A B C`: diagonal-rod trims per tower.
    pub diagonal_rod_trim_mm: [f64; 3],
    /// `DELTA_RADIUS_TRIM_TOWER` (compile-time in Marlin: no G-code sets it).
    pub radius_trim_mm: [f64; 3],
    /// `M666 X Y Z`: endstop adjustments (≤ 0).
    pub endstop_adj_mm: [f64; 3],
}

impl MarlinDelta {
    /// Settings with no trims and no endstop adjustments.
    pub fn new(diagonal_rod_mm: f64, radius_mm: f64, height_mm: f64) -> Self {
        Self {
            diagonal_rod_mm,
            radius_mm,
            height_mm,
            tower_angle_trim_deg: [0.0; 3],
            diagonal_rod_trim_mm: [0.0; 3],
            radius_trim_mm: [0.0; 3],
            endstop_adj_mm: [0.0; 3],
        }
    }

    /// The geometry the firmware computes with (SI), endstop offsets zero: the firmware counts
    /// every carriage where its own model puts it.
    pub fn firmware_geometry(&self) -> Result<DeltaGeometry, KinematicsError> {
        let mut g = DeltaGeometry::new(self.diagonal_rod_mm * 1e-3, self.radius_mm * 1e-3)?;
        for t in 0..3 {
            g.tower_angle_trim[t] = self.tower_angle_trim_deg[t].to_radians();
            g.rod_trim[t] = self.diagonal_rod_trim_mm[t] * 1e-3;
            g.radius_trim[t] = self.radius_trim_mm[t] * 1e-3;
        }
        g.validate()?;
        Ok(g)
    }

    /// The endstop offsets `e_T = S_T + adj_T − Q_T` (m, [`DeltaGeometry::endstop`]) of a
    /// printer running these settings whose switches trip at carriage heights `switches_mm`.
    pub fn endstop_offsets(&self, switches_mm: [f64; 3]) -> Result<[f64; 3], KinematicsError> {
        let g = self.firmware_geometry()?;
        let mut e = [0.0; 3];
        for (t, e) in e.iter_mut().enumerate() {
            *e = (switches_mm[t] + self.endstop_adj_mm[t] - self.homed_count_mm(&g, t)?) * 1e-3;
        }
        Ok(e)
    }

    /// The switch heights (mm) at which these settings home a printer of geometry `physical`
    /// with its effector exactly at `H`: `S_T = H + √(D_T² − R_T²) − adj_T` with its rods and radii.
    pub fn switches_homing_at_height(
        &self,
        physical: &DeltaGeometry,
    ) -> Result<[f64; 3], KinematicsError> {
        let mut s = [0.0; 3];
        for (t, s) in s.iter_mut().enumerate() {
            *s = self.homed_count_mm(physical, t)? - self.endstop_adj_mm[t];
        }
        Ok(s)
    }

    /// `Q_T` (mm): where tower `t`'s carriage is counted when homed.
    fn homed_count_mm(&self, g: &DeltaGeometry, t: usize) -> Result<f64, KinematicsError> {
        let (rod, radius) = (g.rod(t), g.radius + g.radius_trim[t]);
        let rad = rod * rod - radius * radius;
        if rad <= 0.0 {
            return Err(KinematicsError::InvalidValue {
                field: format!("tower {} rod and radius", tower_letter(t)),
                value: rod,
                reason: format!("the rod ({rod} m) must be longer than the radius ({radius} m)"),
            });
        }
        Ok(self.height_mm + rad.sqrt() * 1e3)
    }

    /// The settings that make the firmware's model the `physical` geometry (identified while
    /// these settings ran; its `endstop` are the `e_T` of the module docs, SI). Radius trims
    /// keep their values: Marlin cannot set them at run time.
    pub fn corrected(&self, physical: &DeltaGeometry) -> Result<MarlinDelta, KinematicsError> {
        physical.validate()?;
        let old = self.firmware_geometry()?;
        let mut new = *self;
        new.diagonal_rod_mm = physical.rod_length * 1e3;
        new.radius_mm = physical.radius * 1e3;
        for t in 0..3 {
            new.tower_angle_trim_deg[t] = physical.tower_angle_trim[t].to_degrees();
            new.diagonal_rod_trim_mm[t] = physical.rod_trim[t] * 1e3;
        }
        let target = new.firmware_geometry()?;
        // adj'_T with H' = H, then H' lowered so that the largest is 0
        let mut adj = [0.0; 3];
        for (t, a) in adj.iter_mut().enumerate() {
            *a = self.endstop_adj_mm[t] - physical.endstop[t] * 1e3
                + (new.homed_count_mm(&target, t)? - self.homed_count_mm(&old, t)?);
        }
        let top = adj.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        new.height_mm = self.height_mm - top;
        new.endstop_adj_mm = adj.map(|a| a - top);
        Ok(new)
    }

    /// The Marlin commands that set these values (then `M500` stores them).
    pub fn marlin_commands(&self) -> String {
        let [x, y, z] = self.tower_angle_trim_deg;
        let [a, b, c] = self.diagonal_rod_trim_mm;
        let [ex, ey, ez] = self.endstop_adj_mm;
        format!(
            "M665 L{:.3} R{:.3} H{:.3} X{x:.3} Y{y:.3} Z{z:.3} A{a:.3} B{b:.3} C{c:.3}\n\
             M666 X{ex:.3} Y{ey:.3} Z{ez:.3}\n\
             M500\n",
            self.diagonal_rod_mm, self.radius_mm, self.height_mm
        )
    }

    /// The same state as Klipper's printer.cfg sections (`angle` absolute, `arm_length` and
    /// `position_endstop` per stepper). Klipper has no radius trims: a non-zero one is named in
    /// a comment rather than silently dropped.
    pub fn klipper_sections(&self) -> String {
        let mut s = format!(
            "[printer]\nkinematics: delta\ndelta_radius: {:.3}\n",
            self.radius_mm
        );
        if self.radius_trim_mm.iter().any(|r| *r != 0.0) {
            s.push_str(&format!(
                "# radius trims {:?} mm have no Klipper setting: fold them into the tower angles \
                 and arm lengths, or re-identify with them held at zero\n",
                self.radius_trim_mm
            ));
        }
        for t in 0..3 {
            s.push_str(&format!(
                "\n[stepper_{}]\nangle: {:.3}\narm_length: {:.3}\nposition_endstop: {:.3}\n",
                tower_letter(t).to_ascii_lowercase(),
                MARLIN_TOWER_BASE_ANGLES[t].to_degrees() + self.tower_angle_trim_deg[t],
                self.diagonal_rod_mm + self.diagonal_rod_trim_mm[t],
                self.height_mm - self.endstop_adj_mm[t],
            ));
        }
        s
    }
}

/// Why a settings text could not be read.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SettingsError {
    #[error("line {line}: `{word}` is not a number in `{text}`")]
    NotANumber {
        line: usize,
        word: String,
        text: String,
    },
    #[error(
        "no M665 line with {0}: give the printer's current settings (send M503 and save its \
         reply, or write `M665 L<rod> R<radius> H<height>` and `M666 X Y Z`)"
    )]
    Missing(&'static str),
}

impl MarlinDelta {
    /// The settings in G-code text: `M665`/`M666` lines as written, or as `M503` echoes them
    /// (`echo:  M665 L215.00 …`); the last value of each word counts, text after `;` is a
    /// comment. `M665 B` is the rod trim of tower B when the line also has `A` or `C` (Marlin
    /// 2.x), else Marlin 1.1's calibration radius, which is not a geometric setting and is
    /// ignored.
    pub fn from_gcode(text: &str) -> Result<MarlinDelta, SettingsError> {
        let mut m = MarlinDelta::new(f64::NAN, f64::NAN, f64::NAN);
        for (number, raw) in text.lines().enumerate() {
            let line = raw.split(';').next().unwrap_or("");
            let line = line.trim_start_matches(|c: char| c != 'M' && c != 'm');
            let mut words = line.split_whitespace();
            let code = words.next().unwrap_or("").to_ascii_uppercase();
            if code != "M665" && code != "M666" {
                continue;
            }
            let mut pairs = Vec::new();
            for w in words {
                let (letter, value) = w.split_at(w.chars().next().map_or(0, char::len_utf8));
                let v: f64 = value.parse().map_err(|_| SettingsError::NotANumber {
                    line: number + 1,
                    word: w.to_string(),
                    text: raw.trim().to_string(),
                })?;
                pairs.push((letter.to_ascii_uppercase(), v));
            }
            let rod_trims = pairs.iter().any(|(l, _)| l == "A" || l == "C");
            for (letter, v) in pairs {
                match (code.as_str(), letter.as_str()) {
                    ("M665", "L") => m.diagonal_rod_mm = v,
                    ("M665", "R") => m.radius_mm = v,
                    ("M665", "H") => m.height_mm = v,
                    ("M665", "X") => m.tower_angle_trim_deg[0] = v,
                    ("M665", "Y") => m.tower_angle_trim_deg[1] = v,
                    ("M665", "Z") => m.tower_angle_trim_deg[2] = v,
                    ("M665", "A") => m.diagonal_rod_trim_mm[0] = v,
                    ("M665", "B") if rod_trims => m.diagonal_rod_trim_mm[1] = v,
                    ("M665", "C") => m.diagonal_rod_trim_mm[2] = v,
                    ("M666", "X") => m.endstop_adj_mm[0] = v,
                    ("M666", "Y") => m.endstop_adj_mm[1] = v,
                    ("M666", "Z") => m.endstop_adj_mm[2] = v,
                    _ => {}
                }
            }
        }
        for (value, what) in [
            (m.diagonal_rod_mm, "L (diagonal rod)"),
            (m.radius_mm, "R (delta radius)"),
            (m.height_mm, "H (delta height)"),
        ] {
            if !value.is_finite() {
                return Err(SettingsError::Missing(what));
            }
        }
        Ok(m)
    }
}

/// Tower A, B or C.
pub fn tower_letter(t: usize) -> char {
    ['A', 'B', 'C'][t.min(2)]
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn printer() -> MarlinDelta {
        let mut m = MarlinDelta::new(215.0, 105.6, 250.0);
        m.endstop_adj_mm = [-0.4, 0.0, -0.1];
        m.tower_angle_trim_deg = [0.2, -0.1, 0.0];
        m
    }

    /// The homed state a Marlin printer reaches with settings `m` and switches at `s` (mm): each
    /// carriage's physical height minus its count (mm).
    fn offsets(m: &MarlinDelta, switches: [f64; 3]) -> [f64; 3] {
        m.endstop_offsets(switches).unwrap().map(|e| e * 1e3)
    }

    #[test]
    fn switches_that_home_the_physical_effector_at_h_leave_the_rod_difference_as_offset() {
        let m = printer();
        // the firmware's own geometry: no offset at all
        let fw = m.firmware_geometry().unwrap();
        let s = m.switches_homing_at_height(&fw).unwrap();
        assert!(
            offsets(&m, s).iter().all(|e| e.abs() < 1e-9),
            "{:?}",
            offsets(&m, s)
        );
        // a rod 1 mm longer: each carriage sits √(D'² − R²) − √(D² − R²) above its count
        let mut physical = fw;
        physical.rod_length += 1e-3;
        let s = m.switches_homing_at_height(&physical).unwrap();
        let r = 105.6f64;
        let expected = (216.0f64 * 216.0 - r * r).sqrt() - (215.0f64 * 215.0 - r * r).sqrt();
        for e in offsets(&m, s) {
            assert!((e - expected).abs() < 1e-9, "{e} vs {expected}");
        }
    }

    #[test]
    fn corrected_settings_home_every_carriage_where_the_true_geometry_counts_it() {
        let m = printer();
        let switches = [520.0, 520.7, 519.6];
        let mut truth = m.firmware_geometry().unwrap();
        truth.rod_length += 1.0e-3;
        truth.radius -= 0.3e-3;
        truth.tower_angle_trim[1] += 0.5f64.to_radians();
        truth.endstop = offsets(&m, switches).map(|e| e * 1e-3);
        let new = m.corrected(&truth).unwrap();
        // with the new settings the firmware's model is the truth and counts every carriage right
        let e = offsets(&new, switches);
        let mut model = new.firmware_geometry().unwrap();
        assert!(e.iter().all(|e| e.abs() < 1e-9), "{e:?}");
        assert!(new.endstop_adj_mm.iter().all(|a| *a <= 0.0));
        assert!(new.endstop_adj_mm.contains(&0.0));
        model.endstop = [0.0; 3];
        let mut physical = truth;
        physical.endstop = [0.0; 3];
        let p = Vector3::new(0.03, -0.02, 0.01);
        let q = model.inverse(&p).unwrap();
        assert!((physical.forward(&q).unwrap() - p).norm() < 1e-12);
    }

    #[test]
    fn settings_already_right_are_returned_unchanged() {
        let m = printer();
        let g = m.firmware_geometry().unwrap();
        let new = m.corrected(&g).unwrap();
        assert!((new.height_mm - m.height_mm).abs() < 1e-9);
        for t in 0..3 {
            assert!((new.endstop_adj_mm[t] - m.endstop_adj_mm[t]).abs() < 1e-9);
            assert!((new.tower_angle_trim_deg[t] - m.tower_angle_trim_deg[t]).abs() < 1e-12);
        }
    }

    #[test]
    fn settings_are_read_back_from_what_they_write_and_from_m503_echoes() {
        let m = printer();
        assert_eq!(MarlinDelta::from_gcode(&m.marlin_commands()).unwrap(), m);
        let echo = "echo:; Delta settings: L<diagonal rod> R<radius> H<height> S<seg/s> XYZ<tower \
                    angle trim>\necho:  M665 L215.00 R105.60 H250.00 S200.00 B90.0 X0.20 Y-0.10 \
                    Z0.00\necho:  M666 X-0.40 Y0.00 Z-0.10\n";
        let read = MarlinDelta::from_gcode(echo).unwrap();
        assert_eq!(
            read.diagonal_rod_trim_mm, [0.0; 3],
            "B is the calibration radius here"
        );
        assert_eq!(read.endstop_adj_mm, [-0.4, 0.0, -0.1]);
        let e = MarlinDelta::from_gcode("M666 X0 Y0 Z0\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("L (diagonal rod)") && e.contains("M503"), "{e}");
        let e = MarlinDelta::from_gcode("M665 L2x5 R100 H200\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 1") && e.contains("L2x5"), "{e}");
    }

    #[test]
    fn firmware_text_names_every_setting() {
        let m = printer();
        let marlin = m.marlin_commands();
        assert!(marlin.starts_with("M665 L215.000 R105.600 H250.000 X0.200 Y-0.100 Z0.000"));
        assert!(marlin.contains("M666 X-0.400 Y0.000 Z-0.100"));
        let klipper = m.klipper_sections();
        assert!(klipper.contains("delta_radius: 105.600"));
        assert!(klipper.contains(
            "[stepper_a]\nangle: 210.200\narm_length: 215.000\nposition_endstop: 250.400"
        ));
        assert!(klipper.contains("[stepper_c]\nangle: 90.000"));
    }
}
