//! The printed star as solids to slice (ASCII STL, millimetres, bed centre origin): the dots in
//! one body, and each ArUco tile (a white quiet zone one cell wide around the marker, which a
//! detector needs to see its black border on a dark bed) as two bodies laid side by side in the
//! same layers — its black cells and its white cells — for a two-material print (or one material and a filament change
//! when the slicer merges them). Tiles are upright in the printer's frame: the marker's top edge
//! toward +Y.

use std::fmt::Write as _;

use crate::aruco::Dictionary;
use crate::error::Result;
use crate::printed_star::DeltaStar;

/// The three bodies' STL text: (dots, black tile cells, white tile cells).
pub fn star_solids(star: &DeltaStar) -> Result<(String, String, String)> {
    let mut dots = Solid::new("metrocell_star_dots");
    for d in &star.dots {
        dots.cylinder(
            d[0] * 1e3,
            d[1] * 1e3,
            star.dot_diameter * 0.5e3,
            star.dot_height * 1e3,
        );
    }
    let mut black = Solid::new("metrocell_star_tiles_black");
    let mut white = Solid::new("metrocell_star_tiles_white");
    for cell in tile_cells(star)? {
        let body = if cell.white { &mut white } else { &mut black };
        body.cuboid(
            cell.corner[0],
            cell.corner[1],
            cell.side,
            cell.side,
            star.marker_height * 1e3,
        );
    }
    Ok((dots.finish(), black.finish(), white.finish()))
}

/// One square cell of a tile, in millimetres: its lower-left corner (printer frame) and side.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TileCell {
    pub white: bool,
    pub corner: [f64; 2],
    pub side: f64,
}

/// Every cell of the star's tiles: a white quiet zone of one cell, the black border, the bits
/// (row 0 of a marker toward +Y, OpenCV's bit order).
pub fn tile_cells(star: &DeltaStar) -> Result<Vec<TileCell>> {
    let dict = Dictionary::predefined("DICT_4X4_50")?;
    let mut out = Vec::new();
    for (id, centre, side) in &star.markers {
        let bits = dict.bits(*id)?;
        let cells = bits.len() + 4;
        let cell = side * 1e3 / cells as f64;
        let (x0, y0) = (
            centre[0] * 1e3 - side * 0.5e3,
            centre[1] * 1e3 + side * 0.5e3,
        );
        for r in 0..cells {
            for c in 0..cells {
                let margin = |v: usize| v == 0 || v == cells - 1;
                let inner = |v: usize| v >= 2 && v < cells - 2;
                // row r counts down from the tile's top edge (+Y)
                out.push(TileCell {
                    white: margin(r) || margin(c) || (inner(r) && inner(c) && bits[r - 2][c - 2]),
                    corner: [x0 + c as f64 * cell, y0 - (r + 1) as f64 * cell],
                    side: cell,
                });
            }
        }
    }
    Ok(out)
}

/// An ASCII STL body being written.
struct Solid {
    name: &'static str,
    text: String,
}

impl Solid {
    fn new(name: &'static str) -> Self {
        Self {
            name,
            text: format!("solid {name}\n"),
        }
    }

    fn triangle(&mut self, a: [f64; 3], b: [f64; 3], c: [f64; 3]) {
        let u = [b[0] - a[0], b[1] - a[1], b[2] - a[2]];
        let v = [c[0] - a[0], c[1] - a[1], c[2] - a[2]];
        let n = [
            u[1] * v[2] - u[2] * v[1],
            u[2] * v[0] - u[0] * v[2],
            u[0] * v[1] - u[1] * v[0],
        ];
        let l = (n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
            .sqrt()
            .max(f64::MIN_POSITIVE);
        let _ = writeln!(
            self.text,
            " facet normal {:e} {:e} {:e}\n  outer loop",
            n[0] / l,
            n[1] / l,
            n[2] / l
        );
        for p in [a, b, c] {
            let _ = writeln!(self.text, "   vertex {:.5} {:.5} {:.5}", p[0], p[1], p[2]);
        }
        let _ = writeln!(self.text, "  endloop\n endfacet");
    }

    /// A quad a-b-c-d (counter-clockwise seen from outside) as two triangles.
    fn quad(&mut self, a: [f64; 3], b: [f64; 3], c: [f64; 3], d: [f64; 3]) {
        self.triangle(a, b, c);
        self.triangle(a, c, d);
    }

    /// A box from (x, y, 0) of size w × h × height.
    fn cuboid(&mut self, x: f64, y: f64, w: f64, h: f64, height: f64) {
        let p = |i: f64, j: f64, k: f64| [x + i * w, y + j * h, k * height];
        let [a, b, c, d] = [p(0., 0., 0.), p(1., 0., 0.), p(1., 1., 0.), p(0., 1., 0.)];
        let [e, f, g, hh] = [p(0., 0., 1.), p(1., 0., 1.), p(1., 1., 1.), p(0., 1., 1.)];
        self.quad(a, d, c, b); // bottom, facing −z
        self.quad(e, f, g, hh); // top
        self.quad(a, b, f, e);
        self.quad(b, c, g, f);
        self.quad(c, d, hh, g);
        self.quad(d, a, e, hh);
    }

    /// A 32-sided prism around (x, y) of radius r, from z = 0 to `height`.
    fn cylinder(&mut self, x: f64, y: f64, r: f64, height: f64) {
        const SIDES: usize = 32;
        let at = |k: usize, z: f64| {
            let a = std::f64::consts::TAU * k as f64 / SIDES as f64;
            [x + r * a.cos(), y + r * a.sin(), z]
        };
        let (bottom, top) = ([x, y, 0.0], [x, y, height]);
        for k in 0..SIDES {
            let (a0, a1) = (at(k, 0.0), at(k + 1, 0.0));
            let (b0, b1) = (at(k, height), at(k + 1, height));
            self.triangle(bottom, a1, a0);
            self.triangle(top, b0, b1);
            self.quad(a0, a1, b1, b0);
        }
    }

    fn finish(mut self) -> String {
        let _ = writeln!(self.text, "endsolid {}", self.name);
        self.text
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Volume of a closed, outward-oriented triangle mesh (divergence theorem).
    fn volume(stl: &str) -> f64 {
        let v: Vec<[f64; 3]> = stl
            .lines()
            .filter_map(|l| l.trim().strip_prefix("vertex "))
            .map(|l| {
                let n: Vec<f64> = l.split_whitespace().map(|w| w.parse().unwrap()).collect();
                [n[0], n[1], n[2]]
            })
            .collect();
        v.chunks(3)
            .map(|t| {
                let (a, b, c) = (t[0], t[1], t[2]);
                (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
                    + a[2] * (b[0] * c[1] - b[1] * c[0]))
                    / 6.0
            })
            .sum()
    }

    #[test]
    fn solids_are_closed_with_the_designed_volumes() {
        let star = DeltaStar::standard();
        let (dots, black, white) = star_solids(&star).unwrap();
        // 85 dots of ~π·1.5²·1 mm³ (a 32-gon: 0.6 % less than the circle)
        let polygon = 0.5 * 32.0 * (std::f64::consts::TAU / 32.0).sin() * 1.5 * 1.5;
        // (vertices written to 10 nm)
        assert!(
            (volume(&dots) - 85.0 * polygon).abs() < 0.01,
            "{}",
            volume(&dots)
        );
        // the three tiles: 14 × 14 × 0.6 mm each, shared between the two colours
        let tiles = volume(&black) + volume(&white);
        assert!((tiles - 3.0 * 14.0 * 14.0 * 0.6).abs() < 0.01, "{tiles}");
        assert!(volume(&white) > 0.1 * tiles && volume(&black) > 0.3 * tiles);
        assert!(dots.starts_with("solid metrocell_star_dots\n"));
    }
}
