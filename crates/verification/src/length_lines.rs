//! Points that give a verification the full length test of ISO 10360-2: five lengths in each of
//! seven directions (the three axes and the four space diagonals), three times over.
//!
//! A regular mesh holds few distinct lengths along its short axis and its diagonals: the
//! thesis's 400 × 400 × 200 mm mesh at 100 mm has two along Z and two along each diagonal, so
//! its length test has 18 lengths, not 35. Here each direction gets a line of six equally
//! spaced points through the mesh's centre, spanning as much of the volume as the direction
//! allows (the full travel along an axis; along a diagonal, the smallest travel on each axis) —
//! the five lengths from its first point are k/5 of that span, k = 1…5 (ISO 10360-2 asks for
//! five lengths with the longest at least 66 % of the range in that direction). The visits of
//! each cycle give the repetitions.
//!
//! Positions are rounded to the micrometre, so a program written in mm repeats them exactly,
//! and a line point that is already a grid point is not added twice.

use crate::mesh::{Mesh, MeshError};

/// How many points each line has: five lengths from the first.
pub const POINTS_PER_LINE: usize = 6;

/// The grid of `mesh` and, after it, the points of the seven length lines the grid does not
/// already hold (module docs). Directions along an axis the mesh does not span (a plane) are
/// left out.
pub fn with_length_lines(mesh: &Mesh) -> Result<Vec<[f64; 3]>, MeshError> {
    let mut points = mesh.points()?;
    let round = |v: f64| (v * 1e6).round() / 1e6;
    let key = |p: &[f64; 3]| p.map(|v| (v * 1e6).round() as i64);
    let mut seen: std::collections::BTreeSet<[i64; 3]> = points.iter().map(key).collect();
    let centre: [f64; 3] = std::array::from_fn(|a| (mesh.min[a] + mesh.max[a]) / 2.0);
    let span: [f64; 3] = std::array::from_fn(|a| mesh.max[a] - mesh.min[a]);
    let spanned: Vec<usize> = (0..3).filter(|&a| span[a] > 1e-9).collect();
    let mut directions: Vec<[f64; 3]> = spanned
        .iter()
        .map(|&a| std::array::from_fn(|k| if k == a { 1.0 } else { 0.0 }))
        .collect();
    let signs: &[[f64; 3]] = match spanned.len() {
        3 => &[[1., 1., 1.], [-1., 1., 1.], [1., -1., 1.], [1., 1., -1.]],
        2 => &[[1., 1., 0.], [-1., 1., 0.]],
        _ => &[],
    };
    for s in signs {
        // the signs are of the spanned axes, in order
        let mut d = [0.0; 3];
        for (k, &a) in spanned.iter().enumerate() {
            d[a] = s[k];
        }
        directions.push(d);
    }
    for d in directions {
        // the component extent: the travel along an axis, the smallest travel on a diagonal
        let extent = (0..3)
            .filter(|&a| d[a] != 0.0)
            .map(|a| span[a])
            .fold(f64::MAX, f64::min);
        for k in 0..POINTS_PER_LINE {
            let t = k as f64 / (POINTS_PER_LINE - 1) as f64 - 0.5;
            let p: [f64; 3] = std::array::from_fn(|a| round(centre[a] + d[a] * extent * t));
            if seen.insert(key(&p)) {
                points.push(p);
            }
        }
    }
    Ok(points)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::length_test::length_cases;

    fn thesis() -> Mesh {
        Mesh {
            min: [0.8, 0.1, 0.2],
            max: [1.2, 0.5, 0.4],
            step: 0.1,
        }
    }

    /// The thesis's mesh holds 18 of the test's 35 lengths; with the lines, all 35 (× 3 visits:
    /// ISO 10360-2's 105), inside the volume, the grid kept first and in its order.
    #[test]
    fn the_lines_give_the_thesis_mesh_five_lengths_in_seven_directions() {
        let m = thesis();
        let grid = m.points().unwrap();
        assert_eq!(length_cases(&grid).len(), 18);
        let all = with_length_lines(&m).unwrap();
        assert_eq!(&all[..grid.len()], &grid[..]);
        let cases = length_cases(&all);
        assert_eq!(cases.len(), 35, "{cases:#?}");
        for dir in ["X", "Y", "Z"] {
            let n = cases.iter().filter(|c| c.direction == dir).count();
            assert_eq!(n, 5, "{dir}");
        }
        assert!(all
            .iter()
            .all(|p| (0..3).all(|a| p[a] >= m.min[a] - 1e-9 && p[a] <= m.max[a] + 1e-9)));
        // the longest along Z spans its travel; along a diagonal √3 × the smallest travel
        let longest = |dir: &str| {
            cases
                .iter()
                .filter(|c| c.direction == dir)
                .map(|c| c.nominal)
                .fold(0.0, f64::max)
        };
        assert!((longest("Z") - 0.2).abs() < 1e-9);
        assert!((longest("diagonal +X+Y+Z") - 3f64.sqrt() * 0.2).abs() < 1e-9);
        // no point twice
        let mut keys: Vec<[i64; 3]> = all
            .iter()
            .map(|p| p.map(|v| (v * 1e6).round() as i64))
            .collect();
        keys.sort();
        keys.dedup();
        assert_eq!(keys.len(), all.len());
    }

    /// A plane (the thesis's plate at one Z): two axes and two diagonals.
    #[test]
    fn a_plane_gets_four_directions() {
        let m = Mesh {
            min: [0.0, 0.0, 0.1],
            max: [0.4, 0.4, 0.1],
            step: 0.1,
        };
        let cases = length_cases(&with_length_lines(&m).unwrap());
        let directions: std::collections::BTreeSet<&str> =
            cases.iter().map(|c| c.direction.as_str()).collect();
        assert_eq!(directions.len(), 4, "{directions:?}");
        assert_eq!(cases.len(), 20);
    }
}
