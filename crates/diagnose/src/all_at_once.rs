//! The baseline strategy `all-at-once`: every physical candidate's first variant and every
//! declared column in one plain least-squares fit, terms claimed where their parameters are
//! jointly significant — what the selection is compared with (it claims false effects where the
//! selection does not; BENCHMARKS.md).

use nalgebra::{DMatrix, DVector};

use crate::blocked_least_squares::{pseudo_inverse, BaseFit, BlockedRows};
use crate::selection::{Family, FamilySelection, WhitenedData};

/// The baseline: every physical family's first variant and every declared column in one plain
/// least-squares fit; a term is claimed when its parameters are jointly significant (F test at
/// `alpha`, no correction for the number of terms), ordered by p-value.
pub fn all_at_once(data: &WhitenedData, families: &[Family], alpha: f64) -> FamilySelection {
    let physical: Vec<usize> = (0..families.len())
        .filter(|&f| families[f].physical)
        .collect();
    let n = data.b.len();
    let mut widths = Vec::new();
    let total: usize = data.declared.ncols()
        + physical
            .iter()
            .map(|&f| families[f].variants[0].columns.ncols())
            .sum::<usize>();
    let mut a = DMatrix::zeros(n, total);
    a.columns_mut(0, data.declared.ncols())
        .copy_from(&data.declared);
    let mut at = data.declared.ncols();
    for &f in &physical {
        let c = &families[f].variants[0].columns;
        a.columns_mut(at, c.ncols()).copy_from(c);
        widths.push((f, at, c.ncols()));
        at += c.ncols();
    }
    let rows = BlockedRows::new(&data.folds, n);
    let everything = BaseFit::new(&rows, rows.arrange(&a), rows.arrange_vector(&data.b));
    let before = BaseFit::new(
        &rows,
        rows.arrange(&data.declared),
        rows.arrange_vector(&data.b),
    );
    let x = everything.solution();
    let cov = everything.unscaled_covariance();
    let dof = (n as f64 - everything.rank() as f64).max(1.0);
    let sigma2 = everything.ssr() / dof;
    let mut claimed: Vec<(f64, crate::selection::ChosenTerm)> = Vec::new();
    for &(f, start, k) in &widths {
        let xk = x.rows(start, k).into_owned();
        let ck = cov.view((start, start), (k, k)).into_owned() * sigma2;
        let (inv, rank) = pseudo_inverse(&ck);
        if rank < k {
            continue;
        }
        let stat = (xk.transpose() * inv * &xk)[0] / k as f64;
        let p = statrs::distribution::FisherSnedecor::new(k as f64, dof)
            .map(|d| statrs::distribution::ContinuousCDF::sf(&d, stat))
            .unwrap_or(1.0);
        if p <= alpha {
            let v = &families[f].variants[0];
            let parameters = (0..k)
                .map(|j| {
                    (
                        v.parameter_names[j].clone(),
                        v.base_values[j] + xk[j],
                        ck[(j, j)].max(0.0).sqrt(),
                        v.units[j].clone(),
                    )
                })
                .collect();
            claimed.push((
                p,
                crate::selection::ChosenTerm {
                    candidate: f,
                    variant: 0,
                    label: families[f].label.clone(),
                    term: families[f].term.clone(),
                    physical: true,
                    parameters,
                },
            ));
        }
    }
    claimed.sort_by(|a, b| a.0.total_cmp(&b.0));
    let restore =
        |v: Vec<DVector<f64>>| v.iter().map(|e| rows.restore_vector(e)).collect::<Vec<_>>();
    FamilySelection {
        chosen: claimed.into_iter().map(|c| c.1).collect(),
        steps: Vec::new(),
        dropped: Vec::new(),
        swapped: Vec::new(),
        heldout_before: restore(before.heldout_residuals(&rows)),
        heldout_after: restore(everything.heldout_residuals(&rows)),
        residual_after: rows.restore_vector(&everything.residuals()),
        chi2_per_dof_before: before.ssr() / (n as f64 - before.rank() as f64).max(1.0),
        chi2_per_dof_after: everything.ssr() / dof,
        declared_increment: x.rows(0, data.declared.ncols()).into_owned(),
    }
}
