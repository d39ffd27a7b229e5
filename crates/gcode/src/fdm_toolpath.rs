//! Flat features printed layer by layer by a filament printer (FDM): discs as concentric
//! perimeters, rectangles as an outline and a zigzag fill — enough to print a calibration object
//! such as seed 002's star without a slicer, with every feature where it was designed (a slicer
//! may centre or arrange parts; a calibration print must not move).
//!
//! Conventions, stated once: millimetres, absolute coordinates in the printer's own frame (a
//! delta's bed centre is the origin), absolute extrusion (M82) in millimetres of filament. A line
//! of width w and layer height h extrudes the cross-section (w − h)·h + π·h²/4 (Slic3r's flow
//! model: a rectangle with rounded sides) per millimetre of travel, divided by the filament's
//! cross-section. Features of a second colour are printed after all first-colour ones, behind a
//! filament change (M600), starting at the layer they are given: e.g. black cells on top of a
//! white tile base.

use std::f64::consts::PI;
use std::fmt::Write as _;

/// What the printer and the material need.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FdmSettings {
    pub nozzle_mm: f64,
    pub line_width_mm: f64,
    pub layer_height_mm: f64,
    pub filament_diameter_mm: f64,
    pub nozzle_temperature_c: f64,
    pub bed_temperature_c: f64,
    /// Printing and travel feeds (mm/min).
    pub print_feed: f64,
    pub travel_feed: f64,
    /// Filament pulled back on travel (mm) and the nozzle's lift (mm).
    pub retract_mm: f64,
    pub hop_mm: f64,
}

impl Default for FdmSettings {
    /// A 0.4 mm nozzle, 0.45 mm lines at 0.2 mm layers, 1.75 mm PLA at 210/60 °C.
    fn default() -> Self {
        Self {
            nozzle_mm: 0.4,
            line_width_mm: 0.45,
            layer_height_mm: 0.2,
            filament_diameter_mm: 1.75,
            nozzle_temperature_c: 210.0,
            bed_temperature_c: 60.0,
            print_feed: 1200.0,
            travel_feed: 6000.0,
            retract_mm: 1.0,
            hop_mm: 0.4,
        }
    }
}

/// One flat feature, its top at `top_mm`, its bottom at `bottom_mm` (0: on the bed).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FdmShape {
    Disc {
        centre: [f64; 2],
        diameter: f64,
    },
    /// Lower-left corner (x, y) and size (w, h).
    Rectangle {
        corner: [f64; 2],
        size: [f64; 2],
    },
}

#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FdmFeature {
    pub shape: FdmShape,
    pub bottom_mm: f64,
    pub top_mm: f64,
    /// 0: the first filament; 1: after the change (M600).
    pub colour: usize,
}

/// Filament (mm) per mm of line.
fn filament_per_mm(s: &FdmSettings) -> f64 {
    let (w, h) = (s.line_width_mm, s.layer_height_mm);
    let line = (w - h) * h + PI * h * h / 4.0;
    line / (PI * s.filament_diameter_mm * s.filament_diameter_mm / 4.0)
}

/// The closed and open polylines that fill `shape` in one layer (mm).
fn paths(shape: &FdmShape, w: f64) -> Vec<Vec<[f64; 2]>> {
    match *shape {
        FdmShape::Disc { centre, diameter } => {
            let mut out = Vec::new();
            let mut r = diameter / 2.0 - w / 2.0;
            while r > w / 4.0 {
                // chords of at most 0.25 mm, at least 12
                let n = ((2.0 * PI * r / 0.25).ceil() as usize).max(12);
                out.push(
                    (0..=n)
                        .map(|k| {
                            let a = 2.0 * PI * k as f64 / n as f64;
                            [centre[0] + r * a.cos(), centre[1] + r * a.sin()]
                        })
                        .collect(),
                );
                r -= w;
            }
            if out.is_empty() {
                // smaller than two lines: one dab at the centre
                out.push(vec![centre, [centre[0] + 0.01, centre[1]]]);
            }
            out
        }
        FdmShape::Rectangle { corner, size } => {
            let (x0, y0) = (corner[0] + w / 2.0, corner[1] + w / 2.0);
            let (x1, y1) = (corner[0] + size[0] - w / 2.0, corner[1] + size[1] - w / 2.0);
            if x1 <= x0 || y1 <= y0 {
                let c = [corner[0] + size[0] / 2.0, corner[1] + size[1] / 2.0];
                return vec![vec![c, [c[0] + 0.01, c[1]]]];
            }
            let mut out = vec![vec![[x0, y0], [x1, y0], [x1, y1], [x0, y1], [x0, y0]]];
            // zigzag inside the outline, lines along y, w apart
            let (fx0, fx1, fy0, fy1) = (x0 + w, x1 - w, y0 + w / 2.0, y1 - w / 2.0);
            if fx1 >= fx0 && fy1 > fy0 {
                let n = ((fx1 - fx0) / w).round() as usize + 1;
                let step = if n > 1 {
                    (fx1 - fx0) / (n - 1) as f64
                } else {
                    0.0
                };
                let zig = (0..n)
                    .flat_map(|k| {
                        let x = fx0 + k as f64 * step;
                        if k % 2 == 0 {
                            [[x, fy0], [x, fy1]]
                        } else {
                            [[x, fy1], [x, fy0]]
                        }
                    })
                    .collect();
                out.push(zig);
            }
            out
        }
    }
}

/// What a job prints, for its header and for checks.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct FdmSummary {
    pub layers: usize,
    pub filament_mm: f64,
    pub colour_changes: usize,
}

/// The G-code that prints `features`; `header` lines go first as comments.
pub fn fdm_program(
    features: &[FdmFeature],
    s: &FdmSettings,
    header: &[String],
) -> (String, FdmSummary) {
    let mut g = String::new();
    for line in header {
        let _ = writeln!(g, "; {line}");
    }
    let _ = writeln!(
        g,
        "; nozzle {:.3} mm, lines {:.3} mm, layers {:.3} mm, filament {:.3} mm; absolute coordinates, bed centre origin\n\
         G21 ; millimetres\nG90 ; absolute\nM82 ; absolute extrusion\n\
         M140 S{:.0}\nM104 S{:.0}\nM190 S{:.0}\nM109 S{:.0}\nG28 ; home\nG92 E0",
        s.nozzle_mm,
        s.line_width_mm,
        s.layer_height_mm,
        s.filament_diameter_mm,
        s.bed_temperature_c,
        s.nozzle_temperature_c,
        s.bed_temperature_c,
        s.nozzle_temperature_c
    );
    let per_mm = filament_per_mm(s);
    let tallest = features.iter().map(|f| f.top_mm).fold(0.0, f64::max);
    let mut e = 0.0;
    let mut summary = FdmSummary::default();
    let colours = features.iter().map(|f| f.colour).max().map_or(0, |c| c + 1);
    let mut printed_top: f64 = 0.0;
    for colour in 0..colours {
        if colour > 0 {
            // park above everything printed, change, resume
            let _ = writeln!(
                g,
                "G1 E{:.5} F2400\nG0 Z{:.3} F{:.0}\nM600 ; filament change: load colour {}\nG92 E{e:.5}",
                e - s.retract_mm,
                printed_top + 5.0,
                s.travel_feed,
                colour + 1
            );
            summary.colour_changes += 1;
        }
        let mine: Vec<&FdmFeature> = features.iter().filter(|f| f.colour == colour).collect();
        let lowest = mine
            .iter()
            .map(|f| f.bottom_mm)
            .fold(f64::INFINITY, f64::min);
        let highest = mine.iter().map(|f| f.top_mm).fold(0.0, f64::max);
        let mut z = if lowest.is_finite() { lowest } else { highest };
        while z + 1e-9 < highest {
            let layer_top = z + s.layer_height_mm;
            summary.layers += 1;
            let _ = writeln!(g, "; layer at Z{layer_top:.3} (colour {})", colour + 1);
            for f in mine
                .iter()
                .filter(|f| f.bottom_mm <= z + 1e-9 && f.top_mm >= layer_top - 1e-9)
            {
                for path in paths(&f.shape, s.line_width_mm) {
                    let start = path[0];
                    // travel: retract, lift clear of everything printed so far, go, lower
                    let clear = printed_top.max(layer_top) + s.hop_mm;
                    let _ = writeln!(
                        g,
                        "G1 E{:.5} F2400\nG0 Z{clear:.3} F{:.0}\nG0 X{:.3} Y{:.3}\nG0 Z{layer_top:.3}\nG1 E{e:.5} F2400",
                        e - s.retract_mm,
                        s.travel_feed,
                        start[0],
                        start[1]
                    );
                    let mut prev = start;
                    for p in &path[1..] {
                        let len = (p[0] - prev[0]).hypot(p[1] - prev[1]);
                        e += len * per_mm;
                        let _ = writeln!(
                            g,
                            "G1 X{:.3} Y{:.3} E{e:.5} F{:.0}",
                            p[0], p[1], s.print_feed
                        );
                        prev = *p;
                    }
                }
            }
            printed_top = printed_top.max(layer_top);
            z = layer_top;
        }
    }
    let _ = writeln!(
        g,
        "G1 E{:.5} F2400\nG0 Z{:.3} F{:.0}\nM104 S0\nM140 S0\nM84 ; done",
        e - s.retract_mm,
        tallest + 10.0,
        s.travel_feed
    );
    summary.filament_mm = e;
    (g, summary)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// (x, y, e) of every extruding move, parsed back with the crate's block parser.
    fn extrusions(program: &str) -> Vec<([f64; 2], [f64; 2], f64, f64)> {
        let (mut x, mut y, mut z, mut e) = (0.0, 0.0, 0.0, 0.0);
        let mut out = Vec::new();
        for line in program.lines() {
            let b = crate::block::parse_block(line).unwrap();
            if b.value('G') == Some(92.0) {
                e = b.value('E').unwrap_or(e);
                continue;
            }
            let (nx, ny) = (b.value('X').unwrap_or(x), b.value('Y').unwrap_or(y));
            z = b.value('Z').unwrap_or(z);
            if let Some(ne) = b.value('E') {
                if b.value('G') == Some(1.0) && ne > e && (nx != x || ny != y) {
                    out.push(([x, y], [nx, ny], ne - e, z));
                }
                e = ne;
            }
            (x, y) = (nx, ny);
        }
        out
    }

    #[test]
    fn a_disc_is_printed_where_designed_with_its_volume() {
        let s = FdmSettings::default();
        let disc = FdmFeature {
            shape: FdmShape::Disc {
                centre: [40.0, -20.0],
                diameter: 3.0,
            },
            bottom_mm: 0.0,
            top_mm: 1.0,
            colour: 0,
        };
        let (program, summary) = fdm_program(&[disc], &s, &["test".into()]);
        assert_eq!(summary.layers, 5);
        let moves = extrusions(&program);
        // the extruded path's centroid is the disc's centre; every line inside the disc
        let (mut cx, mut cy, mut len) = (0.0, 0.0, 0.0);
        for (a, b, _, _) in &moves {
            let l = (b[0] - a[0]).hypot(b[1] - a[1]);
            cx += l * (a[0] + b[0]) / 2.0;
            cy += l * (a[1] + b[1]) / 2.0;
            len += l;
            for p in [a, b] {
                // coordinates are written to 0.001 mm
                assert!((p[0] - 40.0).hypot(p[1] + 20.0) <= 1.5 - s.line_width_mm / 2.0 + 1e-3);
            }
        }
        assert!((cx / len - 40.0).abs() < 1e-3 && (cy / len + 20.0).abs() < 1e-3);
        // the material laid down is the disc's volume to within what concentric lines leave
        let filament: f64 = moves.iter().map(|m| m.2).sum();
        let volume = filament * PI * 1.75f64.powi(2) / 4.0;
        let design = PI * 1.5f64.powi(2) * 1.0;
        assert!((volume / design - 1.0).abs() < 0.15, "{volume} vs {design}");
        // layers at 0.2 … 1.0 mm
        let zs: std::collections::BTreeSet<i64> = moves
            .iter()
            .map(|m| (m.3 * 1000.0).round() as i64)
            .collect();
        assert_eq!(
            zs.into_iter().collect::<Vec<_>>(),
            vec![200, 400, 600, 800, 1000]
        );
    }

    #[test]
    fn a_second_colour_comes_after_a_change_on_top_of_the_first() {
        let s = FdmSettings::default();
        let base = FdmFeature {
            shape: FdmShape::Rectangle {
                corner: [0.0, 0.0],
                size: [14.0, 14.0],
            },
            bottom_mm: 0.0,
            top_mm: 0.4,
            colour: 0,
        };
        let cell = FdmFeature {
            shape: FdmShape::Rectangle {
                corner: [3.5, 3.5],
                size: [1.75, 1.75],
            },
            bottom_mm: 0.4,
            top_mm: 0.6,
            colour: 1,
        };
        let (program, summary) = fdm_program(&[base, cell], &s, &[]);
        assert_eq!((summary.layers, summary.colour_changes), (3, 1));
        let change = program.find("M600").unwrap();
        let moves = extrusions(&program);
        let before = extrusions(&program[..change]);
        assert!(before.iter().all(|m| m.3 <= 0.4 + 1e-9));
        let after = &moves[before.len()..];
        assert!(!after.is_empty());
        for (a, b, _, z) in after {
            assert!((z - 0.6).abs() < 1e-9);
            for p in [a, b] {
                assert!(
                    (3.5..=5.25).contains(&p[0]) && (3.5..=5.25).contains(&p[1]),
                    "{p:?}"
                );
            }
        }
    }
}
