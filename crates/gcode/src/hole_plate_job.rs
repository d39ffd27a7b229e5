//! Seed 000's measurement job: a printed checkerboard laid on the machine's table, one hole
//! drilled at the centre of every square, photographed (`vision::hole_plate`) and fitted
//! (`planar_field_fit`). This module writes what the user prints and what the machine runs: the
//! board and its inverse (the backing that makes a hole through a white square show black) as
//! SVG and PDF at exact scale with a scale bar, the nominal hole table, and the drilling program.
//!
//! Layout, in machine millimetres: square (column c, row r) spans X ∈ [x₀ + c·s, x₀ + (c+1)·s],
//! Y ∈ [y₀ + r·s, y₀ + (r+1)·s]; row 0 is the front (lowest Y), square (0, 0) is black, holes at
//! the square centres. On paper the page's top is the machine's back (+Y): lay the print with
//! its bottom-left board corner on (x₀, y₀).

use std::fmt::Write as _;

use crate::number_format::format_coordinate;

/// The plate: squares, pitch, where it lies on the table and the drill.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HolePlate {
    pub squares_x: usize,
    pub squares_y: usize,
    pub square_mm: f64,
    /// Machine X, Y of the board's front-left corner.
    pub origin_mm: (f64, f64),
    pub hole_diameter_mm: f64,
}

/// One hole of the nominal table.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct NominalHole {
    /// 1-based, row-major from the front-left square.
    pub id: usize,
    pub column: usize,
    pub row: usize,
    /// Machine X, Y (mm).
    pub x_mm: f64,
    pub y_mm: f64,
}

/// How the drill plunges.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DrillCycle {
    /// Z of the plate's top surface (mm).
    pub surface_z_mm: f64,
    /// Depth below the surface (mm).
    pub depth_mm: f64,
    /// Clearance above the surface for moves between holes (mm).
    pub clearance_mm: f64,
    /// Plunge feed (mm/min).
    pub feed_mm_per_min: f64,
    pub spindle_rpm: f64,
}

impl Default for DrillCycle {
    fn default() -> Self {
        Self {
            surface_z_mm: 0.0,
            depth_mm: 1.0,
            clearance_mm: 3.0,
            feed_mm_per_min: 100.0,
            spindle_rpm: 10_000.0,
        }
    }
}

/// Why a plate cannot be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlateError {
    #[error("{what} is {value}: {why}")]
    Invalid {
        what: &'static str,
        value: f64,
        why: &'static str,
    },
}

impl HolePlate {
    /// Seed 000's plate: 6 × 6 squares of 25 mm, 1 mm holes, at the table's origin.
    pub fn seed000() -> Self {
        Self {
            squares_x: 6,
            squares_y: 6,
            square_mm: 25.0,
            origin_mm: (0.0, 0.0),
            hole_diameter_mm: 1.0,
        }
    }

    /// Checks the plate can be printed, detected and drilled.
    pub fn validate(&self) -> Result<(), PlateError> {
        let bad = |what, value: f64, why| Err(PlateError::Invalid { what, value, why });
        if self.squares_x < 3 || self.squares_y < 3 {
            return bad(
                "the board",
                (self.squares_x * self.squares_y) as f64,
                "needs at least 3 × 3 squares (2 × 2 inner corners) to be found in a photo",
            );
        }
        if !(self.square_mm > 0.0 && self.square_mm.is_finite()) {
            return bad(
                "the square",
                self.square_mm,
                "must be a positive size in mm",
            );
        }
        if !(self.hole_diameter_mm > 0.0 && self.hole_diameter_mm <= 0.3 * self.square_mm) {
            return bad(
                "the hole diameter",
                self.hole_diameter_mm,
                "must be positive and at most 0.3 × the square, so a hole misplaced by the \
                 machine still lies inside its square",
            );
        }
        if !(self.origin_mm.0.is_finite() && self.origin_mm.1.is_finite()) {
            return bad("the origin", f64::NAN, "must be finite machine coordinates");
        }
        Ok(())
    }

    /// The nominal hole table (where the program drills).
    pub fn holes(&self) -> Vec<NominalHole> {
        let mut out = Vec::with_capacity(self.squares_x * self.squares_y);
        for row in 0..self.squares_y {
            for column in 0..self.squares_x {
                out.push(NominalHole {
                    id: out.len() + 1,
                    column,
                    row,
                    x_mm: self.origin_mm.0 + (column as f64 + 0.5) * self.square_mm,
                    y_mm: self.origin_mm.1 + (row as f64 + 0.5) * self.square_mm,
                });
            }
        }
        out
    }

    /// The nominal table as CSV (the columns `router fit` and `router measure` read).
    pub fn holes_csv(&self) -> String {
        let mut s = String::from("hole,column,row,x_mm,y_mm\n");
        for h in self.holes() {
            let _ = writeln!(
                s,
                "{},{},{},{},{}",
                h.id,
                h.column,
                h.row,
                format_coordinate(h.x_mm, 4),
                format_coordinate(h.y_mm, 4)
            );
        }
        s
    }

    /// The drilling program (G21 G90, G0 between holes at clearance, G1 plunge, G0 retract), in
    /// serpentine order along the rows so the table travels least.
    pub fn drilling_program(&self, cycle: &DrillCycle) -> String {
        let (top, safe) = (cycle.surface_z_mm, cycle.surface_z_mm + cycle.clearance_mm);
        let bottom = top - cycle.depth_mm;
        let f = |v: f64| format_coordinate(v, 4);
        let mut s = String::new();
        let _ = writeln!(
            s,
            "(metrocell router pattern: {} x {} holes, {} mm pitch, {} mm drill)",
            self.squares_x, self.squares_y, self.square_mm, self.hole_diameter_mm
        );
        let _ = writeln!(s, "G21 G90 G17");
        let _ = writeln!(s, "G0 Z{}", f(safe));
        let _ = writeln!(s, "M3 S{}", cycle.spindle_rpm.round());
        let mut holes = self.holes();
        for row in holes.chunks_mut(self.squares_x) {
            if row[0].row % 2 == 1 {
                row.reverse();
            }
        }
        for h in holes {
            let _ = writeln!(s, "(hole {})", h.id);
            let _ = writeln!(s, "G0 X{} Y{}", f(h.x_mm), f(h.y_mm));
            let _ = writeln!(s, "G1 Z{} F{}", f(bottom), f(cycle.feed_mm_per_min));
            let _ = writeln!(s, "G0 Z{}", f(safe));
        }
        let _ = writeln!(s, "M5");
        let _ = writeln!(s, "M30");
        s
    }

    /// The page (mm): the board with a margin, a scale bar and a caption below it.
    fn page_mm(&self) -> (f64, f64) {
        let w = self.squares_x as f64 * self.square_mm;
        let h = self.squares_y as f64 * self.square_mm;
        (
            (w + 2.0 * MARGIN_MM).max(SCALE_BAR_MM + 2.0 * MARGIN_MM),
            h + 2.0 * MARGIN_MM + 25.0,
        )
    }

    /// Every black rectangle on the page (x, y from the page's top-left, w, h; mm): the board
    /// (inverted: its backing) and the scale bar's alternate centimetres.
    fn black_rectangles(&self, inverse: bool) -> Vec<[f64; 4]> {
        let s = self.square_mm;
        let mut out = Vec::new();
        for row in 0..self.squares_y {
            for column in 0..self.squares_x {
                let black = (row + column) % 2 == 0;
                if black != inverse {
                    let top = MARGIN_MM + (self.squares_y - 1 - row) as f64 * s;
                    out.push([MARGIN_MM + column as f64 * s, top, s, s]);
                }
            }
        }
        let y = MARGIN_MM + self.squares_y as f64 * s + 8.0;
        for cm in (0..(SCALE_BAR_MM / 10.0) as usize).step_by(2) {
            out.push([MARGIN_MM + cm as f64 * 10.0, y, 10.0, 3.0]);
        }
        out
    }

    fn caption(&self, inverse: bool) -> [String; 2] {
        [
            format!(
                "metrocell router pattern{}: {} x {} squares of {} mm; scale bar {} mm",
                if inverse {
                    " (inverse: the backing)"
                } else {
                    ""
                },
                self.squares_x,
                self.squares_y,
                self.square_mm,
                SCALE_BAR_MM
            ),
            "Print at 100 % (no fit to page) and check the bar with a ruler; page top = machine +Y"
                .to_string(),
        ]
    }

    /// The board (or its inverse) as SVG in millimetres.
    pub fn svg(&self, inverse: bool) -> String {
        let (w, h) = self.page_mm();
        let mut s = format!(
            "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{w}mm\" height=\"{h}mm\" \
             viewBox=\"0 0 {w} {h}\">\n<rect x=\"0\" y=\"0\" width=\"{w}\" height=\"{h}\" \
             fill=\"white\"/>\n"
        );
        for [x, y, rw, rh] in self.black_rectangles(inverse) {
            let _ = writeln!(
                s,
                "<rect x=\"{x}\" y=\"{y}\" width=\"{rw}\" height=\"{rh}\" fill=\"black\"/>"
            );
        }
        let y = MARGIN_MM + self.squares_y as f64 * self.square_mm + 8.0;
        let _ = writeln!(
            s,
            "<rect x=\"{MARGIN_MM}\" y=\"{y}\" width=\"{SCALE_BAR_MM}\" height=\"3\" fill=\"none\" \
             stroke=\"black\" stroke-width=\"0.2\"/>"
        );
        for (k, line) in self.caption(inverse).iter().enumerate() {
            let _ = writeln!(
                s,
                "<text x=\"{MARGIN_MM}\" y=\"{}\" font-family=\"Helvetica\" font-size=\"3.5\">{}</text>",
                y + 9.0 + 5.0 * k as f64,
                line
            );
        }
        s.push_str("</svg>\n");
        s
    }

    /// The board (or its inverse) as a one-page PDF at exact scale (PDF 1.4, vector rectangles,
    /// the standard Helvetica font).
    pub fn pdf(&self, inverse: bool) -> Vec<u8> {
        let (w, h) = self.page_mm();
        let pt = 72.0 / 25.4;
        // content stream in points, origin bottom-left
        let mut c = String::from("0 g\n");
        for [x, y, rw, rh] in self.black_rectangles(inverse) {
            let _ = writeln!(
                c,
                "{:.4} {:.4} {:.4} {:.4} re f",
                x * pt,
                (h - y - rh) * pt,
                rw * pt,
                rh * pt
            );
        }
        let y = MARGIN_MM + self.squares_y as f64 * self.square_mm + 8.0;
        let _ = writeln!(
            c,
            "0.5669 w {:.4} {:.4} {:.4} {:.4} re S",
            MARGIN_MM * pt,
            (h - y - 3.0) * pt,
            SCALE_BAR_MM * pt,
            3.0 * pt
        );
        for (k, line) in self.caption(inverse).iter().enumerate() {
            let _ = writeln!(
                c,
                "BT /F1 10 Tf {:.4} {:.4} Td ({}) Tj ET",
                MARGIN_MM * pt,
                (h - y - 9.0 - 5.0 * k as f64) * pt,
                line.replace('\\', "\\\\")
                    .replace('(', "\\(")
                    .replace(')', "\\)")
            );
        }
        let objects = [
            "<< /Type /Catalog /Pages 2 0 R >>".to_string(),
            "<< /Type /Pages /Kids [3 0 R] /Count 1 >>".to_string(),
            format!(
                "<< /Type /Page /Parent 2 0 R /MediaBox [0 0 {:.4} {:.4}] /Contents 4 0 R \
                 /Resources << /Font << /F1 5 0 R >> >> >>",
                w * pt,
                h * pt
            ),
            format!("<< /Length {} >>\nstream\n{c}endstream", c.len()),
            "<< /Type /Font /Subtype /Type1 /BaseFont /Helvetica >>".to_string(),
        ];
        let mut out = String::from("%PDF-1.4\n");
        let mut offsets = Vec::new();
        for (k, o) in objects.iter().enumerate() {
            offsets.push(out.len());
            let _ = write!(out, "{} 0 obj\n{o}\nendobj\n", k + 1);
        }
        let xref = out.len();
        let _ = write!(out, "xref\n0 {}\n0000000000 65535 f \n", objects.len() + 1);
        for o in offsets {
            let _ = writeln!(out, "{o:010} 00000 n ");
        }
        let _ = write!(
            out,
            "trailer\n<< /Size {} /Root 1 0 R >>\nstartxref\n{xref}\n%%EOF\n",
            objects.len() + 1
        );
        out.into_bytes()
    }
}

/// White border around the board on the page (mm).
const MARGIN_MM: f64 = 15.0;
/// The scale bar's length (mm): alternate black centimetres.
const SCALE_BAR_MM: f64 = 100.0;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn seed000_plate_has_its_36_holes_at_the_square_centres() {
        let p = HolePlate::seed000();
        p.validate().unwrap();
        let h = p.holes();
        assert_eq!(h.len(), 36);
        assert_eq!((h[0].x_mm, h[0].y_mm), (12.5, 12.5));
        assert_eq!((h[35].x_mm, h[35].y_mm), (137.5, 137.5));
        // the appendix test point (62.5, 62.5) is the centre of the third square
        assert!(h.iter().any(|h| h.x_mm == 62.5 && h.y_mm == 62.5));
        assert!(p.holes_csv().lines().nth(1).unwrap() == "1,0,0,12.5,12.5");
    }

    #[test]
    fn program_drills_every_hole_once_in_serpentine_order() {
        let p = HolePlate::seed000();
        let g = p.drilling_program(&DrillCycle::default());
        let plunges = g.lines().filter(|l| l.starts_with("G1 Z-1")).count();
        assert_eq!(plunges, 36);
        let moves: Vec<&str> = g.lines().filter(|l| l.starts_with("G0 X")).collect();
        assert_eq!(moves[5], "G0 X137.5 Y12.5");
        assert_eq!(moves[6], "G0 X137.5 Y37.5", "row 1 runs back");
        assert!(g.trim_end().ends_with("M30"));
    }

    #[test]
    fn print_files_hold_the_board_at_exact_scale_and_its_inverse_swaps_colours() {
        let p = HolePlate::seed000();
        let svg = p.svg(false);
        assert!(svg.contains("width=\"180mm\"") && svg.contains("viewBox=\"0 0 180 205\""));
        // front-left square (row 0, column 0) is black and sits at the bottom of the board
        assert!(
            svg.contains("<rect x=\"15\" y=\"140\" width=\"25\" height=\"25\" fill=\"black\"/>")
        );
        let inverse = p.svg(true);
        assert!(!inverse.contains("<rect x=\"15\" y=\"140\" width=\"25\""));
        assert!(inverse
            .contains("<rect x=\"40\" y=\"140\" width=\"25\" height=\"25\" fill=\"black\"/>"));
        let pdf = String::from_utf8(p.pdf(false)).unwrap();
        assert!(pdf.starts_with("%PDF-1.4") && pdf.ends_with("%%EOF\n"));
        // 180 mm = 510.2362 pt
        assert!(pdf.contains("/MediaBox [0 0 510.2362 581.1024]"));
        // the cross-reference offsets point at the objects
        let xref = pdf.find("xref\n").unwrap();
        for (k, line) in pdf[xref..].lines().skip(3).take(5).enumerate() {
            let at: usize = line[..10].parse().unwrap();
            assert!(pdf[at..].starts_with(&format!("{} 0 obj", k + 1)), "{line}");
        }
        let bad = HolePlate {
            hole_diameter_mm: 10.0,
            ..p
        };
        assert!(bad
            .validate()
            .unwrap_err()
            .to_string()
            .contains("0.3 × the square"));
    }
}
