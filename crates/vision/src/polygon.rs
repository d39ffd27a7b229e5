//! Polygon approximation of closed contours (Douglas–Peucker, as OpenCV's `approxPolyDP`).

/// Approximate a closed polyline with tolerance `eps` (pixels); returns vertex indices into `pts`
/// in contour order.
pub fn approx_closed(pts: &[(i32, i32)], eps: f64) -> Vec<usize> {
    let n = pts.len();
    if n < 3 {
        return (0..n).collect();
    }
    // Split at the point farthest from pts[0], then at the one farthest from that.
    let d2 = |a: usize, b: usize| {
        let (dx, dy) = ((pts[a].0 - pts[b].0) as f64, (pts[a].1 - pts[b].1) as f64);
        dx * dx + dy * dy
    };
    let far1 = (0..n)
        .max_by(|&a, &b| d2(0, a).total_cmp(&d2(0, b)))
        .unwrap();
    let far2 = (0..n)
        .max_by(|&a, &b| d2(far1, a).total_cmp(&d2(far1, b)))
        .unwrap();
    let (a, b) = if far1 < far2 {
        (far1, far2)
    } else {
        (far2, far1)
    };
    if a == b {
        return vec![a];
    }
    let mut keep = vec![a];
    dp(pts, a, b, eps, &mut keep);
    keep.push(b);
    dp(pts, b, a + n, eps, &mut keep);
    keep
}

/// Recursive step on the open chain from index i to j (indices modulo n, j may exceed n).
fn dp(pts: &[(i32, i32)], i: usize, j: usize, eps: f64, keep: &mut Vec<usize>) {
    let n = pts.len();
    if j <= i + 1 {
        return;
    }
    let p = |k: usize| (pts[k % n].0 as f64, pts[k % n].1 as f64);
    let (ax, ay) = p(i);
    let (bx, by) = p(j);
    let (dx, dy) = (bx - ax, by - ay);
    let len = (dx * dx + dy * dy).sqrt().max(1e-12);
    let mut best = (0.0, i);
    for k in i + 1..j {
        let (x, y) = p(k);
        let dist = ((x - ax) * dy - (y - ay) * dx).abs() / len;
        if dist > best.0 {
            best = (dist, k);
        }
    }
    if best.0 > eps {
        dp(pts, i, best.1, eps, keep);
        keep.push(best.1 % n);
        dp(pts, best.1, j, eps, keep);
    }
}

/// True when the quadrilateral is strictly convex (all turns the same sign).
pub fn is_convex(q: &[[f64; 2]; 4]) -> bool {
    let mut sign = 0.0;
    for k in 0..4 {
        let (a, b, c) = (q[k], q[(k + 1) % 4], q[(k + 2) % 4]);
        let cross = (b[0] - a[0]) * (c[1] - b[1]) - (b[1] - a[1]) * (c[0] - b[0]);
        if cross == 0.0 || (sign != 0.0 && cross.signum() != sign) {
            return false;
        }
        sign = cross.signum();
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn square_contour_gives_four_vertices() {
        let mut pts = Vec::new();
        for x in 0..20 {
            pts.push((x, 0));
        }
        for y in 0..20 {
            pts.push((20, y));
        }
        for x in (1..=20).rev() {
            pts.push((x, 20));
        }
        for y in (1..=20).rev() {
            pts.push((0, y));
        }
        let v = approx_closed(&pts, 1.0);
        assert_eq!(v.len(), 4, "{v:?}");
        let mut corners: Vec<_> = v.iter().map(|&i| pts[i]).collect();
        corners.sort();
        assert_eq!(corners, vec![(0, 0), (0, 20), (20, 0), (20, 20)]);
    }
}
