//! Held-out data means blocks of time or of workspace, never random rows: neighbouring
//! measurements share drift and local errors, so a random split would let a model that only
//! memorises them look good.

use nalgebra::Vector3;

/// Fold of each sample when time is cut into `k` consecutive blocks of equal sample count
/// (ordered by time; ties keep their order).
pub fn time_blocks(times: &[f64], k: usize) -> Vec<usize> {
    let mut order: Vec<usize> = (0..times.len()).collect();
    order.sort_by(|&a, &b| times[a].total_cmp(&times[b]));
    let mut fold = vec![0; times.len()];
    let n = times.len().max(1);
    for (rank, &i) in order.iter().enumerate() {
        fold[i] = (rank * k / n).min(k - 1);
    }
    fold
}

/// Fold of each sample when the workspace is cut into `k` slabs of equal sample count along the
/// axis of largest spread (so each slab holds out a whole region).
pub fn workspace_blocks(positions: &[Vector3<f64>], k: usize) -> Vec<usize> {
    let spread = |a: usize| {
        let (lo, hi) = positions
            .iter()
            .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), p| {
                (l.min(p[a]), h.max(p[a]))
            });
        hi - lo
    };
    let axis = (0..3)
        .max_by(|&a, &b| spread(a).total_cmp(&spread(b)))
        .unwrap_or(0);
    let coordinate: Vec<f64> = positions.iter().map(|p| p[axis]).collect();
    time_blocks(&coordinate, k)
}

/// `blocks` applied within each group of samples (an instrument's placement: `groups[i]` of
/// sample i), fold k of every group together. With one pose per placement, a fold that held
/// out a whole placement would leave its pose unfitted and judge every candidate on an
/// unplaced instrument; cut within each placement, every fold keeps each pose in training and
/// still holds out a contiguous block of it.
pub fn within_groups<G: PartialEq + Clone>(
    groups: &[G],
    blocks: impl Fn(&[usize]) -> Vec<usize>,
) -> Vec<usize> {
    let mut fold = vec![0; groups.len()];
    let mut seen: Vec<G> = Vec::new();
    for g in groups {
        if !seen.contains(g) {
            seen.push(g.clone());
        }
    }
    for g in &seen {
        let members: Vec<usize> = (0..groups.len()).filter(|&i| groups[i] == *g).collect();
        for (m, f) in members.iter().zip(blocks(&members)) {
            fold[*m] = f;
        }
    }
    fold
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blocks_are_contiguous_and_balanced() {
        let t: Vec<f64> = (0..10).rev().map(|i| i as f64).collect();
        let f = time_blocks(&t, 5);
        assert_eq!(f, vec![4, 4, 3, 3, 2, 2, 1, 1, 0, 0]);
        let p: Vec<Vector3<f64>> = (0..6)
            .map(|i| Vector3::new(0.0, i as f64, 0.1 * (i % 2) as f64))
            .collect();
        assert_eq!(workspace_blocks(&p, 3), vec![0, 0, 1, 1, 2, 2]);
    }

    #[test]
    fn folds_within_placements_keep_every_placement_in_training() {
        // two placements, one after the other in time: each fold holds out part of both
        let groups = ["S1", "S1", "S1", "S1", "S2", "S2", "S2", "S2"];
        let t: Vec<f64> = (0..8).map(|i| i as f64).collect();
        let f = within_groups(&groups, |m| {
            time_blocks(&m.iter().map(|&i| t[i]).collect::<Vec<_>>(), 2)
        });
        assert_eq!(f, vec![0, 0, 1, 1, 0, 0, 1, 1]);
    }
}
