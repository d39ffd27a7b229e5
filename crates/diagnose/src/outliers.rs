//! Gross outliers (a beam break that slipped through, a mistyped row): a record whose whitened
//! residual is far outside the robust scatter of all records *and* far from what its neighbours
//! in time and in the workspace show. The second condition keeps a real, local structure (a bump
//! several points wide, a drift over a window) out of the outlier list: its neighbours share it.

use nalgebra::Vector3;

/// Robust scale of values: 1.4826 · median |v − median v|.
pub fn robust_scale(values: &[f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let med = v[v.len() / 2];
    let mut dev: Vec<f64> = v.iter().map(|x| (x - med).abs()).collect();
    dev.sort_by(f64::total_cmp);
    1.4826 * dev[dev.len() / 2]
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Indices of outlying records. `z[i]` is record i's whitened residual (3 components), `times`
/// and `positions` its time and commanded position; `threshold` in robust scale units.
pub fn outliers(
    z: &[Vector3<f64>],
    times: &[f64],
    positions: &[Vector3<f64>],
    threshold: f64,
) -> Vec<usize> {
    let n = z.len();
    if n < 8 {
        return Vec::new();
    }
    let all: Vec<f64> = z.iter().flat_map(|v| v.iter().copied()).collect();
    let scale = robust_scale(&all).max(1e-12);
    let mut by_time: Vec<usize> = (0..n).collect();
    by_time.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
    let mut rank = vec![0; n];
    for (k, &i) in by_time.iter().enumerate() {
        rank[i] = k;
    }
    let candidates: Vec<usize> = (0..n)
        .filter(|&i| z[i].amax() > threshold * scale)
        .collect();
    let mut out = Vec::new();
    for i in candidates {
        // two neighbours either side in time, four nearest in the workspace
        let k = rank[i];
        let time_nb: Vec<usize> = (k.saturating_sub(2)..(k + 3).min(n))
            .filter(|&m| m != k)
            .map(|m| by_time[m])
            .collect();
        let mut near: Vec<(f64, usize)> = (0..n)
            .filter(|&j| j != i)
            .map(|j| ((positions[j] - positions[i]).norm_squared(), j))
            .collect();
        near.sort_by(|a, b| a.0.total_cmp(&b.0));
        let space_nb: Vec<usize> = near.iter().take(4).map(|p| p.1).collect();
        let isolated = |nb: &[usize]| {
            (0..3).any(|c| {
                (z[i][c] - median(nb.iter().map(|&j| z[j][c]).collect())).abs() > threshold * scale
            })
        };
        if isolated(&time_nb) && isolated(&space_nb) {
            out.push(i);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn isolated_spikes_are_outliers_shared_bumps_are_not() {
        let n = 100;
        let times: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let positions: Vec<Vector3<f64>> = (0..n)
            .map(|i| Vector3::new((i % 10) as f64 * 0.1, (i / 10) as f64 * 0.1, 0.0))
            .collect();
        let mut z: Vec<Vector3<f64>> = (0..n)
            .map(|i| {
                Vector3::new(
                    ((i * 37) % 17) as f64 / 8.5 - 1.0,
                    ((i * 11) % 13) as f64 / 6.5 - 1.0,
                    0.0,
                )
            })
            .collect();
        z[42].x += 40.0;
        // a bump over a 3 × 3 patch of neighbours
        for i in [66, 67, 68, 76, 77, 78, 86, 87, 88] {
            z[i].y += 25.0;
        }
        let o = outliers(&z, &times, &positions, 10.0);
        assert_eq!(o, vec![42]);
    }
}
