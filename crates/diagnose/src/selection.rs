//! Naming what the model left out: greedy forward selection of candidate terms, judged on
//! held-out blocks.
//!
//! Each candidate is a catalog term the model lacks (or an empirical correction, which is never
//! given a physical name), given as the columns of its Jacobian at each residual row: how the
//! prediction moves per unit of each of its parameters. Around the declared fit the residual r is
//! then linear in the candidate's parameters, so each step solves, for every remaining candidate,
//! the weighted least-squares problem of the declared free parameters, the terms chosen so far and
//! the candidate together (rows whitened by σ, columns scaled to unit norm, solved by SVD so
//! candidates the data cannot separate from what is already there are recognised as such).
//!
//! A candidate is accepted when, at once:
//! * it lowers the held-out error — the sum of squared whitened residuals of each block predicted
//!   by a fit to the other blocks, over time blocks and workspace blocks — by at least
//!   `min_cv_gain` of what it was;
//! * its parameters are significant (Wald χ² on the full-data fit, Bonferroni-corrected for the
//!   candidates tried in the step);
//! * every parameter lies in the term's documented plausible range;
//! * the Bayesian information criterion falls.
//!
//! Among the acceptable, the lowest held-out error wins; physical terms are preferred, and an
//! empirical correction is only chosen when no physical term is acceptable. The loop stops when
//! nothing is acceptable or `max_terms` were added.

use nalgebra::{DMatrix, DVector};
use statrs::distribution::{ChiSquared, ContinuousCDF};

/// One candidate, as columns over the residual rows.
#[derive(Debug, Clone)]
pub struct Candidate {
    /// Instance label, e.g. `backlash[y]`.
    pub label: String,
    /// Catalog id, or `empirical` for a correction that carries no physical name.
    pub term: String,
    pub physical: bool,
    /// n × p: ∂prediction/∂parameter at each residual row (SI units).
    pub columns: DMatrix<f64>,
    pub parameter_names: Vec<String>,
    pub units: Vec<String>,
    /// Plausible range of each parameter (the term's documented range), SI.
    pub ranges: Vec<(f64, f64)>,
    /// Parameter values the columns were taken at (0 for a term the model lacks).
    pub base_values: Vec<f64>,
}

/// The data: residuals after the declared fit, their σ, the declared free parameters' Jacobian,
/// and fold assignments (one vector per blocking scheme, fold ids 0..k).
#[derive(Debug, Clone)]
pub struct SelectionData {
    pub residual: DVector<f64>,
    pub sigma: DVector<f64>,
    pub declared: DMatrix<f64>,
    pub folds: Vec<Vec<usize>>,
}

#[derive(Debug, Clone)]
pub struct SelectionOptions {
    pub alpha: f64,
    pub min_cv_gain: f64,
    pub max_terms: usize,
}

impl Default for SelectionOptions {
    fn default() -> Self {
        Self { alpha: 0.01, min_cv_gain: 0.02, max_terms: 3 }
    }
}

/// How one candidate fared in one step.
#[derive(Debug, Clone, PartialEq)]
pub struct CandidateScore {
    pub label: String,
    /// Held-out sum of squared whitened residuals with the candidate added.
    pub heldout_ssr: f64,
    pub wald_p_adjusted: f64,
    pub plausible: bool,
    pub separable: bool,
    pub delta_bic: f64,
    pub values: Vec<f64>,
    pub sigmas: Vec<f64>,
    pub accepted: bool,
}

/// One step of the forward selection.
#[derive(Debug, Clone, PartialEq)]
pub struct SelectionStep {
    pub heldout_ssr_before: f64,
    pub scores: Vec<CandidateScore>,
    /// Index into the candidates of the term added, if any.
    pub chosen: Option<usize>,
}

/// A chosen term with its fitted parameters.
#[derive(Debug, Clone, PartialEq)]
pub struct ChosenTerm {
    pub candidate: usize,
    pub label: String,
    pub term: String,
    pub physical: bool,
    /// (name, value, σ, unit).
    pub parameters: Vec<(String, f64, f64, String)>,
}

#[derive(Debug, Clone, PartialEq)]
pub struct Selection {
    pub chosen: Vec<ChosenTerm>,
    pub steps: Vec<SelectionStep>,
    /// Held-out RMS of the whitened residuals before and after (1 = the stated noise).
    pub heldout_rms_z_before: f64,
    pub heldout_rms_z_after: f64,
    /// Held-out RMS of the residuals (m) before and after.
    pub heldout_rms_m_before: f64,
    pub heldout_rms_m_after: f64,
    pub heldout_max_m_before: f64,
    pub heldout_max_m_after: f64,
    /// χ²/dof of the full-data fit after selection.
    pub chi2_per_dof_after: f64,
}

/// Run the forward selection.
pub fn select(data: &SelectionData, candidates: &[Candidate], options: &SelectionOptions) -> Selection {
    let n = data.residual.len();
    let b = data.residual.component_div(&data.sigma);
    let whiten = |m: &DMatrix<f64>| {
        let mut w = m.clone();
        for (i, mut row) in w.row_iter_mut().enumerate() {
            row /= data.sigma[i];
        }
        w
    };
    let declared = whiten(&data.declared);
    let cand_w: Vec<DMatrix<f64>> = candidates.iter().map(|c| whiten(&c.columns)).collect();
    let mut chosen_idx: Vec<usize> = Vec::new();
    let mut steps = Vec::new();
    let design = |chosen: &[usize], extra: Option<usize>| {
        let mut blocks: Vec<&DMatrix<f64>> = vec![&declared];
        blocks.extend(chosen.iter().map(|&i| &cand_w[i]));
        if let Some(e) = extra {
            blocks.push(&cand_w[e]);
        }
        hstack(n, &blocks)
    };
    let (mut current_cv, before_pred) = heldout(&design(&[], None), &b, &data.folds);
    let mut current_fit = fit(&design(&[], None), &b);
    while chosen_idx.len() < options.max_terms {
        let remaining: Vec<usize> = (0..candidates.len()).filter(|i| !chosen_idx.contains(i)).collect();
        if remaining.is_empty() {
            break;
        }
        let tried = remaining.len() as f64;
        let mut scores = Vec::new();
        let mut best: Option<(usize, f64, bool)> = None;
        for &ci in &remaining {
            let c = &candidates[ci];
            let a = design(&chosen_idx, Some(ci));
            let f = fit(&a, &b);
            let p_k = c.columns.ncols();
            let start = a.ncols() - p_k;
            let separable = f.rank >= current_fit.rank + p_k;
            let values: Vec<f64> = (0..p_k).map(|j| c.base_values[j] + f.x[start + j]).collect();
            let sigmas: Vec<f64> = (0..p_k).map(|j| f.cov[(start + j, start + j)].max(0.0).sqrt()).collect();
            let wald_p = if separable { wald(&f, start, p_k) } else { 1.0 };
            let wald_p_adjusted = (wald_p * tried).min(1.0);
            let plausible = values.iter().zip(&c.ranges).all(|(v, (lo, hi))| *v >= *lo && *v <= *hi);
            let (cv, _) = heldout(&a, &b, &data.folds);
            let delta_bic = (f.ssr - current_fit.ssr) + (p_k as f64) * (n as f64).ln();
            let accepted = separable && plausible && wald_p_adjusted <= options.alpha && delta_bic < 0.0 && cv <= current_cv * (1.0 - options.min_cv_gain);
            if accepted {
                let better = match best {
                    None => true,
                    Some((_, bcv, bphys)) => (c.physical && !bphys) || (c.physical == bphys && cv < bcv),
                };
                if better {
                    best = Some((ci, cv, c.physical));
                }
            }
            scores.push(CandidateScore { label: c.label.clone(), heldout_ssr: cv, wald_p_adjusted, plausible, separable, delta_bic, values, sigmas, accepted });
        }
        let step = SelectionStep { heldout_ssr_before: current_cv, scores, chosen: best.map(|b| b.0) };
        steps.push(step);
        match best {
            Some((ci, cv, _)) => {
                chosen_idx.push(ci);
                current_cv = cv;
                current_fit = fit(&design(&chosen_idx, None), &b);
            }
            None => break,
        }
    }
    // final parameters from the full-data fit of everything chosen
    let a = design(&chosen_idx, None);
    let f = fit(&a, &b);
    let mut col = declared.ncols();
    let mut chosen = Vec::new();
    for &ci in &chosen_idx {
        let c = &candidates[ci];
        let p_k = c.columns.ncols();
        let parameters = (0..p_k).map(|j| (c.parameter_names[j].clone(), c.base_values[j] + f.x[col + j], f.cov[(col + j, col + j)].max(0.0).sqrt(), c.units[j].clone())).collect();
        chosen.push(ChosenTerm { candidate: ci, label: c.label.clone(), term: c.term.clone(), physical: c.physical, parameters });
        col += p_k;
    }
    let (_, after_pred) = heldout(&a, &b, &data.folds);
    let stats = |pred: &DVector<f64>| {
        // pred holds the held-out predictions of the whitened residual; back to metres
        let e_z = &b - pred;
        let e_m = e_z.component_mul(&data.sigma);
        ((e_z.norm_squared() / n as f64).sqrt(), (e_m.norm_squared() / n as f64).sqrt(), e_m.amax())
    };
    let (z0, m0, max0) = stats(&before_pred);
    let (z1, m1, max1) = stats(&after_pred);
    let dof = (n as f64 - f.rank as f64).max(1.0);
    Selection { chosen, steps, heldout_rms_z_before: z0, heldout_rms_z_after: z1, heldout_rms_m_before: m0, heldout_rms_m_after: m1, heldout_max_m_before: max0, heldout_max_m_after: max1, chi2_per_dof_after: f.ssr / dof }
}

fn hstack(n: usize, blocks: &[&DMatrix<f64>]) -> DMatrix<f64> {
    let p: usize = blocks.iter().map(|b| b.ncols()).sum();
    let mut m = DMatrix::zeros(n, p);
    let mut at = 0;
    for b in blocks {
        m.view_mut((0, at), (n, b.ncols())).copy_from(b);
        at += b.ncols();
    }
    m
}

struct Fit {
    x: DVector<f64>,
    cov: DMatrix<f64>,
    ssr: f64,
    rank: usize,
}

/// Whitened least squares by SVD of the column-scaled design; the covariance is scaled by the
/// a-posteriori variance factor when the residuals scatter more than stated (never below 1).
fn fit(a: &DMatrix<f64>, b: &DVector<f64>) -> Fit {
    let p = a.ncols();
    if p == 0 {
        return Fit { x: DVector::zeros(0), cov: DMatrix::zeros(0, 0), ssr: b.norm_squared(), rank: 0 };
    }
    let scale: Vec<f64> = (0..p).map(|j| a.column(j).norm().max(f64::MIN_POSITIVE)).collect();
    let mut s = a.clone();
    for (j, mut c) in s.column_iter_mut().enumerate() {
        c /= scale[j];
    }
    let svd = s.clone().svd(true, true);
    let tol = 1e-9 * svd.singular_values.max();
    let rank = svd.singular_values.iter().filter(|v| **v > tol).count();
    let y = svd.solve(b, tol).unwrap_or_else(|_| DVector::zeros(p));
    let r = b - &s * &y;
    let ssr = r.norm_squared();
    let n = a.nrows() as f64;
    let factor = (ssr / (n - rank as f64).max(1.0)).max(1.0);
    let v_t = svd.v_t.as_ref().expect("V computed");
    let mut cov = DMatrix::zeros(p, p);
    for (k, sv) in svd.singular_values.iter().enumerate() {
        if *sv > tol {
            let v = v_t.row(k).transpose();
            cov += &v * v.transpose() / (sv * sv);
        }
    }
    let x = DVector::from_iterator(p, (0..p).map(|j| y[j] / scale[j]));
    for i in 0..p {
        for j in 0..p {
            cov[(i, j)] *= factor / (scale[i] * scale[j]);
        }
    }
    Fit { x, cov, ssr, rank }
}

/// Wald test that parameters start..start+k are zero.
fn wald(f: &Fit, start: usize, k: usize) -> f64 {
    let xk = f.x.rows(start, k).into_owned();
    let ck = f.cov.view((start, start), (k, k)).into_owned();
    match ck.try_inverse() {
        Some(inv) => {
            let stat = (xk.transpose() * inv * &xk)[0];
            ChiSquared::new(k as f64).map(|d| d.sf(stat)).unwrap_or(1.0)
        }
        None => 1.0,
    }
}

/// Held-out SSR summed over every blocking scheme, and the held-out prediction of each row from
/// the first scheme (for RMS and max reporting).
fn heldout(a: &DMatrix<f64>, b: &DVector<f64>, folds: &[Vec<usize>]) -> (f64, DVector<f64>) {
    let n = b.len();
    let mut total = 0.0;
    let mut first_pred = DVector::zeros(n);
    for (scheme, assignment) in folds.iter().enumerate() {
        let k = assignment.iter().copied().max().map(|m| m + 1).unwrap_or(0);
        for fold in 0..k {
            let train: Vec<usize> = (0..n).filter(|&i| assignment[i] != fold).collect();
            let test: Vec<usize> = (0..n).filter(|&i| assignment[i] == fold).collect();
            if test.is_empty() {
                continue;
            }
            let a_train = a.select_rows(&train);
            let b_train = b.select_rows(&train);
            let f = fit(&a_train, &b_train);
            for &i in &test {
                let pred = if a.ncols() == 0 { 0.0 } else { a.row(i).dot(&f.x.transpose()) };
                total += (b[i] - pred).powi(2);
                if scheme == 0 {
                    first_pred[i] = pred;
                }
            }
        }
    }
    (total, first_pred)
}
