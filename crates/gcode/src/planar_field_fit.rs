//! Identifying seed 000's planar error field (eq. 7) from measured hole errors: the nine
//! coefficients A–I by weighted linear least squares, with their covariance.
//!
//! Only these nine combinations are identifiable from holes in one plane (X3 held constant): the
//! paper's 12 kinematic parameters enter eq. 7 through them (digest §2.3 a, and
//! `crates/estimation/tests/seed000_identifiability.rs` for the 12-parameter form and its null
//! space). So the fit is of A–I directly, and says so.
//!
//! e_x depends on A–D only and e_y on E–I only, so the two blocks are separate least-squares
//! problems; each hole's σ weights its row. Covariance: (UᵀWU)⁻¹ from the stated σ, widened by
//! χ²/dof when that exceeds 1 (the holes scatter more than their σ says: the σ understate, or the
//! field is not the whole story — both reported, never hidden), never narrowed below the stated σ.

use nalgebra::{DMatrix, DVector};

use crate::planar_quadratic::PlanarQuadraticField;

/// One measured hole (mm): where it was meant to be, reached − commanded, and that error's σ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HoleError {
    pub nominal_mm: (f64, f64),
    pub error_mm: (f64, f64),
    pub sigma_mm: (f64, f64),
}

/// The identified field and what supports it.
#[derive(Debug, Clone, PartialEq)]
pub struct PlanarFieldFit {
    pub field: PlanarQuadraticField,
    /// 9 × 9 covariance of A–I (the x and y blocks are uncorrelated).
    pub covariance: DMatrix<f64>,
    /// χ² of the weighted residuals and its degrees of freedom (2·holes − 9).
    pub chi_square: f64,
    pub degrees_of_freedom: usize,
    /// The factor the covariance was widened by: max(1, χ²/dof).
    pub covariance_scale: f64,
    /// Residual (e_x, e_y) of each hole after the fit (mm).
    pub residuals_mm: Vec<(f64, f64)>,
}

/// Names of A–I with their regressors, for reports.
pub const COEFFICIENTS: [(&str, &str); 9] = [
    ("A", "X2² in e_x"),
    ("B", "X2 in e_x"),
    ("C", "X1 in e_x"),
    ("D", "X3 in e_x"),
    ("E", "X1 in e_y"),
    ("F", "X2 in e_y"),
    ("G", "X3 in e_y"),
    ("H", "X1·X2 in e_y"),
    ("I", "X1² in e_y"),
];

/// Why the field could not be identified.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlanarFitError {
    #[error("hole {index}: {what} is not a finite number (σ must also be > 0)")]
    BadHole { index: usize, what: &'static str },
    #[error(
        "{holes} holes give {rows} equations for 9 coefficients (at least 4 of e_x and 5 of \
         e_y are needed): measure at least 5 holes (the paper's rule of thumb asks for twice as \
         many equations as parameters)"
    )]
    TooFewHoles { holes: usize, rows: usize },
    #[error(
        "the holes do not determine {block}: {reason}; spread them over at least 3 columns and \
         3 rows of the plate"
    )]
    Degenerate { block: &'static str, reason: String },
}

/// Fit A–I to `holes`, with X3 held at `x3` (1 in seed 000).
pub fn fit_planar_field(holes: &[HoleError], x3: f64) -> Result<PlanarFieldFit, PlanarFitError> {
    let all = vec![true; holes.len()];
    fit_planar_field_rows(holes, x3, &all, &all)
}

/// The regressors of eq. 7 at (x1, x2) mm: e_x's (A–D) and e_y's (E–I).
pub fn regressors(x1: f64, x2: f64, x3: f64) -> ([f64; 4], [f64; 5]) {
    ([x2 * x2, x2, x1, x3], [x1, x2, x3, x1 * x2, x1 * x1])
}

/// [`fit_planar_field`] on some of the equations only: hole i's e_x where `use_x[i]`, its e_y
/// where `use_y[i]` (a designed subset, seed 000's B12: the rest are left for validation).
/// Residuals are still given for every hole.
pub fn fit_planar_field_rows(
    holes: &[HoleError],
    x3: f64,
    use_x: &[bool],
    use_y: &[bool],
) -> Result<PlanarFieldFit, PlanarFitError> {
    for (index, h) in holes.iter().enumerate() {
        let finite = [h.nominal_mm.0, h.nominal_mm.1, h.error_mm.0, h.error_mm.1]
            .iter()
            .all(|v| v.is_finite());
        if !finite {
            return Err(PlanarFitError::BadHole {
                index,
                what: "a position or error",
            });
        }
        if !(h.sigma_mm.0 > 0.0
            && h.sigma_mm.1 > 0.0
            && h.sigma_mm.0.is_finite()
            && h.sigma_mm.1.is_finite())
        {
            return Err(PlanarFitError::BadHole { index, what: "σ" });
        }
    }
    let pick = |mask: &[bool]| -> Vec<HoleError> {
        holes
            .iter()
            .zip(mask.iter().chain(std::iter::repeat(&false)))
            .filter(|(_, &u)| u)
            .map(|(h, _)| *h)
            .collect()
    };
    let (x_holes, y_holes) = (pick(use_x), pick(use_y));
    let rows = x_holes.len() + y_holes.len();
    if rows < 10 || x_holes.len() < 4 || y_holes.len() < 5 {
        return Err(PlanarFitError::TooFewHoles {
            holes: holes.len(),
            rows,
        });
    }
    let x_rows = |h: &HoleError| regressors(h.nominal_mm.0, h.nominal_mm.1, x3).0.to_vec();
    let y_rows = |h: &HoleError| regressors(h.nominal_mm.0, h.nominal_mm.1, x3).1.to_vec();
    let bx = solve_block(&x_holes, "A–D (e_x)", x_rows, |h| {
        (h.error_mm.0, h.sigma_mm.0)
    })?;
    let by = solve_block(&y_holes, "E–I (e_y)", y_rows, |h| {
        (h.error_mm.1, h.sigma_mm.1)
    })?;
    let mut coefficients = [0.0; 9];
    coefficients[..4].copy_from_slice(bx.values.as_slice());
    coefficients[4..].copy_from_slice(by.values.as_slice());
    let field = PlanarQuadraticField {
        coefficients,
        x3,
        region: None,
    };
    let chi_square = bx.chi_square + by.chi_square;
    let degrees_of_freedom = rows - 9;
    let covariance_scale = if degrees_of_freedom > 0 {
        (chi_square / degrees_of_freedom as f64).max(1.0)
    } else {
        1.0
    };
    let mut covariance = DMatrix::zeros(9, 9);
    covariance
        .view_mut((0, 0), (4, 4))
        .copy_from(&(bx.covariance * covariance_scale));
    covariance
        .view_mut((4, 4), (5, 5))
        .copy_from(&(by.covariance * covariance_scale));
    let residuals_mm = holes
        .iter()
        .map(|h| {
            let (ex, ey) = field.error_mm(h.nominal_mm.0, h.nominal_mm.1);
            (h.error_mm.0 - ex, h.error_mm.1 - ey)
        })
        .collect();
    Ok(PlanarFieldFit {
        field,
        covariance,
        chi_square,
        degrees_of_freedom,
        covariance_scale,
        residuals_mm,
    })
}

impl PlanarFieldFit {
    /// σ of each coefficient (A–I).
    pub fn sigmas(&self) -> [f64; 9] {
        std::array::from_fn(|k| self.covariance[(k, k)].sqrt())
    }

    /// The predicted error at (x1, x2) mm and its standard uncertainty per axis (mm), from the
    /// coefficients' covariance.
    pub fn predict_mm(&self, x1: f64, x2: f64) -> ((f64, f64), (f64, f64)) {
        let x3 = self.field.x3;
        let gx = DVector::from_vec(vec![x2 * x2, x2, x1, x3]);
        let gy = DVector::from_vec(vec![x1, x2, x3, x1 * x2, x1 * x1]);
        let cx = self.covariance.view((0, 0), (4, 4));
        let cy = self.covariance.view((4, 4), (5, 5));
        let ux = (gx.transpose() * cx * &gx)[(0, 0)].sqrt();
        let uy = (gy.transpose() * cy * &gy)[(0, 0)].sqrt();
        (self.field.error_mm(x1, x2), (ux, uy))
    }
}

/// One hole predicted by a fit that did not see its block of the plate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeldOutHole {
    pub hole: HoleError,
    /// The block (a column of holes: one X1 position) it was held out with.
    pub block: usize,
    /// Measured − predicted (mm): what compensation with that fit would leave.
    pub residual_mm: (f64, f64),
    /// The prediction's standard uncertainty (mm).
    pub prediction_sigma_mm: (f64, f64),
}

/// Blocked cross-validation: the holes are grouped into columns (equal X1 to 1 µm); each column
/// is predicted by the field fitted to all the others. Blocks of the workspace, never random
/// holes, so a hole's neighbours cannot vouch for it. Columns whose removal leaves the field
/// undetermined (fewer than 3 columns left) are an error.
pub fn cross_validate_by_columns(
    holes: &[HoleError],
    x3: f64,
) -> Result<Vec<HeldOutHole>, PlanarFitError> {
    let mut columns: Vec<f64> = Vec::new();
    for h in holes {
        if !columns.iter().any(|c| (c - h.nominal_mm.0).abs() < 1e-3) {
            columns.push(h.nominal_mm.0);
        }
    }
    columns.sort_by(f64::total_cmp);
    if columns.len() < 4 {
        return Err(PlanarFitError::Degenerate {
            block: "a held-out column",
            reason: format!(
                "{} columns leave fewer than 3 to fit when one is held out",
                columns.len()
            ),
        });
    }
    let mut out = Vec::with_capacity(holes.len());
    for (block, c) in columns.iter().enumerate() {
        let in_block = |h: &HoleError| (h.nominal_mm.0 - c).abs() < 1e-3;
        let train: Vec<HoleError> = holes.iter().filter(|h| !in_block(h)).copied().collect();
        let fit = fit_planar_field(&train, x3)?;
        for h in holes.iter().filter(|h| in_block(h)) {
            let ((ex, ey), sigma) = fit.predict_mm(h.nominal_mm.0, h.nominal_mm.1);
            out.push(HeldOutHole {
                hole: *h,
                block,
                residual_mm: (h.error_mm.0 - ex, h.error_mm.1 - ey),
                prediction_sigma_mm: sigma,
            });
        }
    }
    Ok(out)
}

struct Block {
    values: DVector<f64>,
    covariance: DMatrix<f64>,
    chi_square: f64,
}

fn solve_block(
    holes: &[HoleError],
    block: &'static str,
    regressors: impl Fn(&HoleError) -> Vec<f64>,
    observed: impl Fn(&HoleError) -> (f64, f64),
) -> Result<Block, PlanarFitError> {
    let p = regressors(&holes[0]).len();
    let mut u = DMatrix::zeros(holes.len(), p);
    let mut y = DVector::zeros(holes.len());
    for (i, h) in holes.iter().enumerate() {
        let (value, sigma) = observed(h);
        for (j, r) in regressors(h).into_iter().enumerate() {
            u[(i, j)] = r / sigma;
        }
        y[i] = value / sigma;
    }
    // column scaling: X2² (mm²) and X3 (1) differ by 10⁴ and more
    let norms: Vec<f64> = (0..p)
        .map(|j| u.column(j).norm().max(f64::MIN_POSITIVE))
        .collect();
    let mut scaled = u.clone();
    for (j, n) in norms.iter().enumerate() {
        scaled.column_mut(j).scale_mut(1.0 / n);
    }
    let svd = scaled.svd(true, true);
    let (smax, smin) = (svd.singular_values.max(), svd.singular_values.min());
    if smin <= smax * 1e-10 {
        return Err(PlanarFitError::Degenerate {
            block,
            reason: format!(
                "their regressors are dependent (condition number {:.1e})",
                smax / smin
            ),
        });
    }
    let beta_scaled = svd.solve(&y, 0.0).expect("U and Vᵀ were computed");
    let vt = svd.v_t.as_ref().expect("Vᵀ was computed");
    let inv_s2 = DMatrix::from_diagonal(&svd.singular_values.map(|s| 1.0 / (s * s)));
    let cov_scaled = vt.transpose() * inv_s2 * vt;
    let values = DVector::from_fn(p, |j, _| beta_scaled[j] / norms[j]);
    let covariance = DMatrix::from_fn(p, p, |a, b| cov_scaled[(a, b)] / (norms[a] * norms[b]));
    let chi_square = (&y - &u * &values).norm_squared();
    Ok(Block {
        values,
        covariance,
        chi_square,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grid(field: &PlanarQuadraticField, sigma: f64) -> Vec<HoleError> {
        let mut holes = Vec::new();
        for i in 0..6 {
            for j in 0..6 {
                let (x1, x2) = (12.5 + 25.0 * i as f64, 12.5 + 25.0 * j as f64);
                holes.push(HoleError {
                    nominal_mm: (x1, x2),
                    error_mm: field.error_mm(x1, x2),
                    sigma_mm: (sigma, sigma),
                });
            }
        }
        holes
    }

    #[test]
    fn exact_errors_give_back_the_field() {
        let truth = PlanarQuadraticField::seed000_b72();
        let fit = fit_planar_field(&grid(&truth, 0.02), 1.0).unwrap();
        for (got, want) in fit.field.coefficients.iter().zip(truth.coefficients) {
            assert!(
                (got - want).abs() <= 1e-9 * want.abs().max(1e-6),
                "{got} vs {want}"
            );
        }
        assert_eq!(fit.degrees_of_freedom, 63);
        assert_eq!(fit.covariance_scale, 1.0);
    }

    #[test]
    fn a_single_row_of_holes_is_degenerate_and_says_what_to_do() {
        let truth = PlanarQuadraticField::seed000_b72();
        let line: Vec<HoleError> = grid(&truth, 0.02)
            .into_iter()
            .filter(|h| h.nominal_mm.1 == 12.5)
            .collect();
        let e = fit_planar_field(&line, 1.0).unwrap_err().to_string();
        assert!(e.contains("3 columns and 3 rows"), "{e}");
        let mut bad = grid(&truth, 0.02);
        bad[3].sigma_mm.1 = 0.0;
        assert_eq!(
            fit_planar_field(&bad, 1.0).unwrap_err(),
            PlanarFitError::BadHole {
                index: 3,
                what: "σ"
            }
        );
    }
}
