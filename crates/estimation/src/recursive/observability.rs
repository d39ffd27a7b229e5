//! What the measurements so far cannot tell the online filter, in words.
//!
//! The filter keeps the information of every measurement it accepted about its free parameters
//! in prior-whitened form, M = Σ D·Hᵀ·R⁻¹·H·D (D = diag of the prior σ). An alarm re-opens the
//! covariance but leaves M alone: M says what the program has measured at all. A direction v of
//! the parameters is *not observed* when vᵀMv is below [`MIN_INFORMATION`]: all the data carry
//! less than a thousandth of what the prior knew along it, so its estimate is the prior's and
//! the filter holds it there. Two kinds:
//! * a parameter no accepted measurement has depended on (its column of H was zero, or below
//!   the rounding of its neighbours' columns: a sine of a screw's pitch sampled only at whole
//!   turns) — held exactly at its start value;
//! * a combination of parameters the design cannot separate (a constant offset declared twice):
//!   only their combination is measured; the named ones trade against each other.

use nalgebra::DMatrix;

/// Information (in units of the prior's) below which a direction counts as not observed.
pub const MIN_INFORMATION: f64 = 1e-3;

/// A set of parameters (stacked indices) whose combination the data have not observed.
#[derive(Debug, Clone, PartialEq)]
pub struct Unobserved {
    /// Stacked parameter indices; one entry = that parameter alone.
    pub parameters: Vec<usize>,
}

/// The filter's free parameters the data leave at their prior.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Observability {
    pub unobserved: Vec<Unobserved>,
    /// Parameters (stacked indices) held at an edge of their possible range.
    pub at_bound: Vec<usize>,
}

impl Observability {
    /// The stacked indices of every parameter in an unobserved direction.
    pub fn unobserved_parameters(&self) -> Vec<usize> {
        let mut v: Vec<usize> = self
            .unobserved
            .iter()
            .flat_map(|u| u.parameters.iter().copied())
            .collect();
        v.sort_unstable();
        v.dedup();
        v
    }

    /// One phrase per unobserved direction, e.g. `pitch_cyclic[x].b1` or
    /// `pitch_cyclic[x].a1 with positioning[x].c0 (only their combination is measured)`.
    pub fn phrases(&self, names: &[String]) -> Vec<String> {
        self.unobserved
            .iter()
            .map(|u| match u.parameters.as_slice() {
                [k] => names[*k].clone(),
                ks => format!(
                    "{} (only their combination is measured)",
                    ks.iter()
                        .map(|&k| names[k].as_str())
                        .collect::<Vec<_>>()
                        .join(" with ")
                ),
            })
            .collect()
    }

    /// "not observable by the measurements so far (held at their start values): …; at the
    /// edge of the possible range: …", or None when there is nothing to say.
    pub fn describe(&self, names: &[String]) -> Option<String> {
        let mut parts = Vec::new();
        if !self.unobserved.is_empty() {
            parts.push(format!(
                "not observable by the measurements so far, held at their start values: {}",
                self.phrases(names).join("; ")
            ));
        }
        if !self.at_bound.is_empty() {
            parts.push(format!(
                "held at the edge of their possible range: {}",
                self.at_bound
                    .iter()
                    .map(|&k| names[k].as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        (!parts.is_empty()).then(|| parts.join("; "))
    }
}

/// The unobserved directions of `information` (prior-whitened, over the free parameters
/// `free`, stacked indices): parameters whose row is zero one by one, then the null space of
/// the rest, each basis vector of it in reduced row-echelon form (so each names as few
/// parameters as it can, the first free one of each leading).
pub fn unobserved(information: &DMatrix<f64>, free: &[usize]) -> Vec<Unobserved> {
    let k = free.len();
    let mut out = Vec::new();
    let mut rest = Vec::new();
    for i in 0..k {
        if information[(i, i)] < MIN_INFORMATION {
            out.push(Unobserved {
                parameters: vec![free[i]],
            });
        } else {
            rest.push(i);
        }
    }
    if rest.is_empty() {
        return out;
    }
    let m = DMatrix::from_fn(rest.len(), rest.len(), |a, b| {
        information[(rest[a], rest[b])]
    });
    let eigen = m.symmetric_eigen();
    let null: Vec<usize> = (0..rest.len())
        .filter(|&c| eigen.eigenvalues[c] < MIN_INFORMATION)
        .collect();
    if null.is_empty() {
        return out;
    }
    // rows = null vectors; reduced row echelon form makes each as sparse as the space allows
    let mut basis = DMatrix::from_fn(null.len(), rest.len(), |r, c| {
        eigen.eigenvectors[(c, null[r])]
    });
    reduce_rows(&mut basis);
    for r in 0..basis.nrows() {
        let row = basis.row(r);
        let scale = row.iter().fold(0.0f64, |m, v| m.max(v.abs()));
        let parameters: Vec<usize> = (0..rest.len())
            .filter(|&c| row[c].abs() > 0.05 * scale)
            .map(|c| free[rest[c]])
            .collect();
        if !parameters.is_empty() {
            out.push(Unobserved { parameters });
        }
    }
    out.sort_by_key(|u| u.parameters[0]);
    out
}

/// Gauss–Jordan elimination with partial pivoting, in place.
fn reduce_rows(a: &mut DMatrix<f64>) {
    let (rows, cols) = a.shape();
    let mut lead = 0;
    for c in 0..cols {
        if lead == rows {
            break;
        }
        let (pivot, value) = (lead..rows)
            .map(|r| (r, a[(r, c)].abs()))
            .fold((lead, 0.0), |best, x| if x.1 > best.1 { x } else { best });
        if value < 1e-9 {
            continue;
        }
        a.swap_rows(lead, pivot);
        let p = a[(lead, c)];
        for j in 0..cols {
            a[(lead, j)] /= p;
        }
        for r in 0..rows {
            if r != lead {
                let f = a[(r, c)];
                if f != 0.0 {
                    for j in 0..cols {
                        a[(r, j)] -= f * a[(lead, j)];
                    }
                }
            }
        }
        lead += 1;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_a_parameter_alone_and_an_aliased_pair() {
        // four free parameters (stacked 3, 5, 6, 9): 5 never measured, 6 and 9 measured only
        // as their sum, 3 measured on its own
        let free = [3, 5, 6, 9];
        let h = DMatrix::from_row_slice(2, 4, &[1.0, 0.0, 0.0, 0.0, 0.0, 0.0, 2.0, 2.0]);
        let info = h.transpose() * &h * 50.0;
        let u = unobserved(&info, &free);
        assert_eq!(
            u,
            vec![
                Unobserved {
                    parameters: vec![5]
                },
                Unobserved {
                    parameters: vec![6, 9]
                }
            ]
        );
        let names: Vec<String> = (0..10).map(|i| format!("p{i}")).collect();
        let o = Observability {
            unobserved: u,
            at_bound: vec![3],
        };
        assert_eq!(
            o.describe(&names).unwrap(),
            "not observable by the measurements so far, held at their start values: p5; p6 with p9 (only their combination is measured); held at the edge of their possible range: p3"
        );
        assert_eq!(o.unobserved_parameters(), vec![5, 6, 9]);
        // fully measured: nothing to say
        let full = DMatrix::<f64>::identity(4, 4) * 10.0;
        assert!(unobserved(&full, &free).is_empty());
        assert_eq!(Observability::default().describe(&names), None);
    }
}
