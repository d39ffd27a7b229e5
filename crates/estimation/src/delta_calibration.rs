//! A delta printer's physical geometry identified from what it printed or probed, by least
//! squares over the full kinematics (rod length, radius, tower angle trims, endstop offsets) —
//! seed 002 corrects only the rod, one arm at a time (eq. 13); this fits every parameter the
//! measurements determine, together, with covariance.
//!
//! Model: the firmware (geometry `firmware`, endstops zero) turns a commanded position p into
//! carriage counts q = IKᶠʷ(p); the printer puts the nozzle at FK(q; θ), θ the physical geometry
//! (its `endstop` the physical-minus-counted carriage heights, see
//! [`metrocell_kinematics::delta_firmware`]). Three kinds of measurement:
//! - a printed feature's plan position (x, y) in the printed object's own frame (a camera over the
//!   print sees the object, not the printer): the object's placement on the bed — a plan rotation
//!   and translation — is estimated with θ (a rotation of all three towers together turns all the
//!   printer does about the bed's centre, so tower C's angle trim is always held at its firmware
//!   value);
//! - a probed height z at a commanded (x, y) (bed at z = 0, a probe's or a feeler's reading);
//! - a distance between two printed features (a bar of the star target): frame-free.
//!
//! Parameters with no measurement that can see them are held, and said to be: without heights
//! the common part of the endstops (it only raises the effector; tower C's endstop is held, so
//! A's and B's are relative to it) — the radius and the endstops' differences do move printed
//! features in plan, by the tilt and the curvature of the effector's path, and are fitted;
//! radius trims always (Marlin cannot set them at run time). Covariance: (JᵀWJ)⁻¹ from the stated σ, widened by
//! χ²/dof when that exceeds 1, never narrowed (the rule of `planar_field_fit` and the other fits).

use metrocell_kinematics::delta::{DeltaGeometry, DELTA_PARAMETER_COUNT, DELTA_PARAMETER_NAMES};
use metrocell_solver::{solve, NotEvaluable, Options, Problem};
use nalgebra::{DMatrix, Matrix2, Vector2, Vector3};

/// One measurement of what the printer did (SI: metres; σ the standard uncertainty).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DeltaMeasurement {
    /// A feature printed at `commanded`, found at `measured` (x, y) in the object's frame.
    PlanPosition {
        commanded: Vector3<f64>,
        measured: Vector2<f64>,
        sigma: f64,
        /// Where a camera that saw the feature from `viewpoint` put it: on the plane `plane_z`
        /// (see [`PlanView`]); None: a measurement without parallax (a probe, a CMM).
        view: Option<PlanView>,
    },
    /// The bed probed at commanded (x, y, z): the nozzle's true height there is `measured`.
    Height {
        commanded: Vector3<f64>,
        measured: f64,
        sigma: f64,
    },
    /// The distance between features printed at `from` and `to`.
    Distance {
        from: Vector3<f64>,
        to: Vector3<f64>,
        measured: f64,
        sigma: f64,
    },
}

impl DeltaMeasurement {
    /// Residual rows it gives (2 for a plan position, else 1), in the fit's residual order.
    pub fn rows(&self) -> usize {
        match self {
            DeltaMeasurement::PlanPosition { .. } => 2,
            _ => 1,
        }
    }

    /// Its standard uncertainty (m; per axis for a plan position).
    pub fn sigma(&self) -> f64 {
        match *self {
            DeltaMeasurement::PlanPosition { sigma, .. }
            | DeltaMeasurement::Height { sigma, .. }
            | DeltaMeasurement::Distance { sigma, .. } => sigma,
        }
    }
}

/// How a camera measured a plan position: from `viewpoint` (its centre, in the object's frame
/// with z up from the bed, m), the feature's image carried back onto the plane z = `plane_z`.
/// A feature whose top is not at `plane_z` — a printed dot stands as tall as the printer's z
/// error lets it — is seen displaced along the ray: X = V + (P − V)·(plane_z − V_z)/(P_z − V_z).
/// The fit models that parallax with the feature's true height, which the geometry predicts.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PlanView {
    pub viewpoint: Vector3<f64>,
    pub plane_z: f64,
}

/// Names of the object's placement parameters, after the 14 geometric ones.
pub const PLACEMENT_NAMES: [&str; 3] = ["object_rotation", "object_x", "object_y"];

/// What the fit found.
#[derive(Debug, Clone)]
pub struct DeltaFit {
    /// The physical geometry (held parameters at their firmware values).
    pub geometry: DeltaGeometry,
    /// The object's placement (rotation rad, x m, y m), when plan positions were measured.
    pub placement: Option<[f64; 3]>,
    /// Indices (into [`DELTA_PARAMETER_NAMES`] then [`PLACEMENT_NAMES`]) of the estimated
    /// parameters, and their covariance in that order.
    pub estimated: Vec<usize>,
    pub covariance: DMatrix<f64>,
    /// Held parameters and why.
    pub held: Vec<(&'static str, &'static str)>,
    pub chi_square: f64,
    pub degrees_of_freedom: usize,
    /// max(1, χ²/dof): the factor the covariance was widened by.
    pub covariance_scale: f64,
    /// Residual of each measurement row after the fit (m), in input order.
    pub residuals: Vec<f64>,
    /// Residual rows before the fit (the firmware's own geometry, placement fitted alone) (m).
    pub residuals_before: Vec<f64>,
}

impl DeltaFit {
    /// Standard uncertainty of parameter `index` (as in `estimated`), None if held.
    pub fn sigma_of(&self, index: usize) -> Option<f64> {
        let k = self.estimated.iter().position(|&i| i == index)?;
        Some(self.covariance[(k, k)].max(0.0).sqrt())
    }
}

/// Why the fit could not be made.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum DeltaFitError {
    #[error("measurement {index}: {what}")]
    BadMeasurement { index: usize, what: String },
    #[error("the firmware geometry is not valid: {0}")]
    Firmware(String),
    #[error(
        "{rows} measured values for {parameters} parameters ({names}): measure more features, or \
         hold some (--hold)"
    )]
    TooFew {
        rows: usize,
        parameters: usize,
        names: String,
    },
    #[error(
        "the measurements do not determine {0}: add measurements that move them (heights for the \
         radius and endstops, positions spread over the bed for the angles) or hold them (--hold)"
    )]
    NotIdentifiable(String),
    #[error("the least-squares solve failed: {0}")]
    Solver(String),
}

/// Parameter index of a name of [`DELTA_PARAMETER_NAMES`] or [`PLACEMENT_NAMES`].
pub fn parameter_index(name: &str) -> Option<usize> {
    DELTA_PARAMETER_NAMES
        .iter()
        .chain(PLACEMENT_NAMES.iter())
        .position(|n| *n == name)
}

/// Fits the physical geometry of a printer running `firmware` to `measurements`, holding the
/// parameters named in `hold` besides those the measurements cannot see (module docs).
pub fn fit_delta(
    firmware: &DeltaGeometry,
    measurements: &[DeltaMeasurement],
    hold: &[usize],
) -> Result<DeltaFit, DeltaFitError> {
    firmware
        .validate()
        .map_err(|e| DeltaFitError::Firmware(e.to_string()))?;
    check(measurements)?;
    check_reach(firmware, measurements)?;
    let problem = DeltaProblem {
        firmware: *firmware,
        measurements,
        rows: measurements.iter().map(DeltaMeasurement::rows).sum(),
    };
    let (fixed, held) = held_parameters(measurements, hold);
    let estimated: Vec<usize> = (0..PARAMETERS).filter(|&k| !fixed[k]).collect();
    if problem.rows < estimated.len() {
        return Err(DeltaFitError::TooFew {
            rows: problem.rows,
            parameters: estimated.len(),
            names: names_of(&estimated),
        });
    }
    let x0 = start(firmware, measurements);
    let sigmas: Vec<f64> = measurements
        .iter()
        .flat_map(|m| std::iter::repeat_n(m.sigma(), m.rows()))
        .collect();
    // before: the firmware's geometry, only the object's placement fitted
    let mut placement_only = vec![true; PARAMETERS];
    placement_only[DELTA_PARAMETER_COUNT..].copy_from_slice(&fixed[DELTA_PARAMETER_COUNT..]);
    let options = |fixed: Vec<bool>| Options {
        sigmas: Some(sigmas.clone()),
        fixed,
        max_iterations: 100,
        ..Options::default()
    };
    let before = solve(&problem, &x0, &options(placement_only))
        .map_err(|e| DeltaFitError::Solver(e.to_string()))?;
    let solution = solve(&problem, &before.x, &options(fixed.clone()))
        .map_err(|e| DeltaFitError::Solver(e.to_string()))?;
    let Some(unscaled) = solution.covariance_unscaled.as_ref() else {
        let labels: Vec<&str> = (0..PARAMETERS).map(name_of).collect();
        let what = solution
            .identifiability(&labels, None)
            .map(|i| i.describe().join("; "))
            .unwrap_or_else(|_| names_of(&estimated));
        return Err(DeltaFitError::NotIdentifiable(what));
    };
    let dof = problem.rows - estimated.len();
    let chi_square: f64 = solution
        .residuals
        .iter()
        .zip(&sigmas)
        .map(|(r, s)| (r / s).powi(2))
        .sum();
    let covariance_scale = if dof > 0 {
        (chi_square / dof as f64).max(1.0)
    } else {
        1.0
    };
    let covariance = unscaled.select_rows(&estimated).select_columns(&estimated) * covariance_scale;
    let geometry = geometry_of(&solution.x);
    let placement = has_plan(measurements).then(|| {
        [
            solution.x[DELTA_PARAMETER_COUNT],
            solution.x[DELTA_PARAMETER_COUNT + 1],
            solution.x[DELTA_PARAMETER_COUNT + 2],
        ]
    });
    Ok(DeltaFit {
        geometry,
        placement,
        estimated,
        covariance,
        held,
        chi_square,
        degrees_of_freedom: dof,
        covariance_scale,
        residuals: solution.residuals,
        residuals_before: before.residuals,
    })
}

/// The 14 geometric parameters and the object's placement.
const PARAMETERS: usize = DELTA_PARAMETER_COUNT + 3;

/// Name of parameter `k` of the fit's vector.
pub fn name_of(k: usize) -> &'static str {
    if k < DELTA_PARAMETER_COUNT {
        DELTA_PARAMETER_NAMES[k]
    } else {
        PLACEMENT_NAMES[k - DELTA_PARAMETER_COUNT]
    }
}

fn names_of(idx: &[usize]) -> String {
    idx.iter()
        .map(|&k| name_of(k))
        .collect::<Vec<_>>()
        .join(", ")
}

fn has_plan(measurements: &[DeltaMeasurement]) -> bool {
    measurements
        .iter()
        .any(|m| matches!(m, DeltaMeasurement::PlanPosition { .. }))
}

fn check(measurements: &[DeltaMeasurement]) -> Result<(), DeltaFitError> {
    for (index, m) in measurements.iter().enumerate() {
        let bad = |what: &str| DeltaFitError::BadMeasurement {
            index,
            what: what.to_string(),
        };
        let (points, value): (Vec<&Vector3<f64>>, Vec<f64>) = match m {
            DeltaMeasurement::PlanPosition {
                commanded,
                measured,
                view,
                ..
            } => {
                if let Some(w) = view {
                    if !(w.viewpoint.iter().all(|v| v.is_finite()) && w.plane_z.is_finite()) {
                        return Err(bad("the camera's viewpoint is not finite"));
                    }
                    if w.viewpoint.z <= commanded.z {
                        return Err(bad("the camera's viewpoint is not above the feature"));
                    }
                }
                (vec![commanded], vec![measured.x, measured.y])
            }
            DeltaMeasurement::Height {
                commanded,
                measured,
                ..
            } => (vec![commanded], vec![*measured]),
            DeltaMeasurement::Distance {
                from, to, measured, ..
            } => {
                if (from - to).norm() <= 0.0 {
                    return Err(bad("the two features of a distance are at the same place"));
                }
                (vec![from, to], vec![*measured])
            }
        };
        if points.iter().any(|p| p.iter().any(|v| !v.is_finite()))
            || value.iter().any(|v| !v.is_finite())
        {
            return Err(bad("a coordinate is not a finite number"));
        }
        if !(m.sigma() > 0.0 && m.sigma().is_finite()) {
            return Err(bad("σ must be a positive number"));
        }
    }
    Ok(())
}

/// Every commanded point must be one the firmware can reach (a table in inches, or of another
/// printer, is caught here rather than as a failed solve).
fn check_reach(
    firmware: &DeltaGeometry,
    measurements: &[DeltaMeasurement],
) -> Result<(), DeltaFitError> {
    for (index, m) in measurements.iter().enumerate() {
        let points = match m {
            DeltaMeasurement::PlanPosition { commanded, .. }
            | DeltaMeasurement::Height { commanded, .. } => vec![*commanded],
            DeltaMeasurement::Distance { from, to, .. } => vec![*from, *to],
        };
        for p in points {
            if let Err(e) = firmware.inverse(&p) {
                return Err(DeltaFitError::BadMeasurement {
                    index,
                    what: format!(
                        "commanded ({:.3}, {:.3}, {:.3}) mm is outside this printer's reach ({e}): \
                         are the coordinates in mm, from the bed's centre, and of this printer?",
                        p.x * 1e3,
                        p.y * 1e3,
                        p.z * 1e3
                    ),
                });
            }
        }
    }
    Ok(())
}

/// The fixed mask, and each held geometric parameter with the reason.
fn held_parameters(
    measurements: &[DeltaMeasurement],
    hold: &[usize],
) -> (Vec<bool>, Vec<(&'static str, &'static str)>) {
    let plan = has_plan(measurements);
    let heights = measurements
        .iter()
        .any(|m| matches!(m, DeltaMeasurement::Height { .. }));
    let mut fixed = vec![false; PARAMETERS];
    let mut held = Vec::new();
    let mut hold_it = |k: usize, why: &'static str| {
        if !fixed[k] {
            fixed[k] = true;
            if k < DELTA_PARAMETER_COUNT {
                held.push((DELTA_PARAMETER_NAMES[k], why));
            }
        }
    };
    for &k in hold {
        hold_it(k, "held as asked");
    }
    for k in 5..8 {
        hold_it(k, "Marlin cannot set radius trims at run time");
    }
    // rod trims: one rod length and three trims are four numbers for three rods
    for k in 8..11 {
        hold_it(k, "per-rod trims are held unless asked for");
    }
    hold_it(
        4,
        "a rotation of all three towers together turns everything the printer does about the \
         bed's centre: the prints' orientation, not an error",
    );
    if !heights {
        hold_it(
            13,
            "no heights measured: raising all three endstops together only raises the \
             effector, which plan measurements cannot see — A's and B's are relative to C's; \
             set the height (M665 H) by probing or a paper test after applying",
        );
    }
    if !plan {
        for k in DELTA_PARAMETER_COUNT..PARAMETERS {
            fixed[k] = true;
        }
    }
    (fixed, held)
}

/// The firmware geometry, and the object's placement from the plan positions' centroids and
/// their mean rotation.
fn start(firmware: &DeltaGeometry, measurements: &[DeltaMeasurement]) -> Vec<f64> {
    let mut x: Vec<f64> = firmware.to_vector().iter().copied().collect();
    x[11..14].copy_from_slice(&[0.0; 3]);
    let pairs: Vec<(Vector2<f64>, Vector2<f64>)> = measurements
        .iter()
        .filter_map(|m| match m {
            DeltaMeasurement::PlanPosition {
                commanded,
                measured,
                ..
            } => Some((commanded.xy(), *measured)),
            _ => None,
        })
        .collect();
    let (mut theta, mut t) = (0.0, Vector2::zeros());
    if !pairs.is_empty() {
        let n = pairs.len() as f64;
        let ca = pairs.iter().map(|p| p.0).sum::<Vector2<f64>>() / n;
        let cb = pairs.iter().map(|p| p.1).sum::<Vector2<f64>>() / n;
        let (mut s, mut c) = (0.0, 0.0);
        for (a, b) in &pairs {
            let (a, b) = (a - ca, b - cb);
            s += a.x * b.y - a.y * b.x;
            c += a.dot(&b);
        }
        theta = s.atan2(c);
        t = cb - rotation(theta) * ca;
    }
    x.extend([theta, t.x, t.y]);
    x
}

fn rotation(theta: f64) -> Matrix2<f64> {
    let (s, c) = theta.sin_cos();
    Matrix2::new(c, -s, s, c)
}

fn geometry_of(x: &[f64]) -> DeltaGeometry {
    let v = nalgebra::SMatrix::<f64, DELTA_PARAMETER_COUNT, 1>::from_iterator(
        x[..DELTA_PARAMETER_COUNT].iter().copied(),
    );
    DeltaGeometry::from_vector(&v)
}

/// The least-squares problem: residuals measured − predicted, in measurement order.
struct DeltaProblem<'a> {
    firmware: DeltaGeometry,
    measurements: &'a [DeltaMeasurement],
    rows: usize,
}

impl DeltaProblem<'_> {
    /// Where the printer puts the nozzle for a commanded p under geometry g, and ∂/∂θ (3 × 14).
    fn printed(
        &self,
        g: &DeltaGeometry,
        p: &Vector3<f64>,
    ) -> Result<
        (
            Vector3<f64>,
            nalgebra::SMatrix<f64, 3, DELTA_PARAMETER_COUNT>,
        ),
        NotEvaluable,
    > {
        let fail = |e: metrocell_kinematics::KinematicsError| NotEvaluable(e.to_string());
        let q = self.firmware.inverse(p).map_err(fail)?;
        Ok((
            g.forward(&q).map_err(fail)?,
            g.forward_parameter_jacobian(&q).map_err(fail)?,
        ))
    }

    fn evaluate(
        &self,
        x: &[f64],
        residuals: &mut [f64],
        mut jacobian: Option<&mut DMatrix<f64>>,
    ) -> Result<(), NotEvaluable> {
        let g = geometry_of(x);
        let theta = x[DELTA_PARAMETER_COUNT];
        let t = Vector2::new(x[DELTA_PARAMETER_COUNT + 1], x[DELTA_PARAMETER_COUNT + 2]);
        let (r, dr) = (
            rotation(theta),
            rotation(theta + std::f64::consts::FRAC_PI_2),
        );
        if let Some(j) = jacobian.as_deref_mut() {
            j.fill(0.0);
        }
        let mut row = 0;
        for m in self.measurements {
            match m {
                DeltaMeasurement::PlanPosition {
                    commanded,
                    measured,
                    view,
                    ..
                } => {
                    let (p, jp) = self.printed(&g, commanded)?;
                    let q = r * p.xy() + t;
                    // seen through the camera: scale s about the viewpoint, and its change with
                    // the feature's height (identity without a view)
                    let (predicted, s, ds_dz, v) = match view {
                        Some(w) => {
                            let v = w.viewpoint;
                            let depth = p.z - v.z;
                            if depth.abs() < 1e-9 {
                                return Err(NotEvaluable(
                                    "a plan position's viewpoint is at the feature's height".into(),
                                ));
                            }
                            let s = (w.plane_z - v.z) / depth;
                            (v.xy() + (q - v.xy()) * s, s, -s / depth, v.xy())
                        }
                        None => (q, 1.0, 0.0, Vector2::zeros()),
                    };
                    residuals[row] = measured.x - predicted.x;
                    residuals[row + 1] = measured.y - predicted.y;
                    if let Some(j) = jacobian.as_deref_mut() {
                        let d_theta = dr * p.xy() * s;
                        let lever = (q - v) * ds_dz;
                        for axis in 0..2 {
                            for k in 0..DELTA_PARAMETER_COUNT {
                                j[(row + axis, k)] = -(s
                                    * (r[(axis, 0)] * jp[(0, k)] + r[(axis, 1)] * jp[(1, k)])
                                    + lever[axis] * jp[(2, k)]);
                            }
                            j[(row + axis, DELTA_PARAMETER_COUNT)] = -d_theta[axis];
                            j[(row + axis, DELTA_PARAMETER_COUNT + 1 + axis)] = -s;
                        }
                    }
                }
                DeltaMeasurement::Height {
                    commanded,
                    measured,
                    ..
                } => {
                    let (p, jp) = self.printed(&g, commanded)?;
                    residuals[row] = measured - p.z;
                    if let Some(j) = jacobian.as_deref_mut() {
                        for k in 0..DELTA_PARAMETER_COUNT {
                            j[(row, k)] = -jp[(2, k)];
                        }
                    }
                }
                DeltaMeasurement::Distance {
                    from, to, measured, ..
                } => {
                    let ((a, ja), (b, jb)) = (self.printed(&g, from)?, self.printed(&g, to)?);
                    let d = a - b;
                    residuals[row] = measured - d.norm();
                    if let Some(j) = jacobian.as_deref_mut() {
                        let u = d / d.norm();
                        let grad = u.transpose() * (ja - jb);
                        for k in 0..DELTA_PARAMETER_COUNT {
                            j[(row, k)] = -grad[k];
                        }
                    }
                }
            }
            row += m.rows();
        }
        Ok(())
    }
}

impl Problem for DeltaProblem<'_> {
    fn residual_count(&self) -> usize {
        self.rows
    }
    fn parameter_count(&self) -> usize {
        PARAMETERS
    }
    fn residuals(&self, x: &[f64], residuals: &mut [f64]) -> Result<(), NotEvaluable> {
        self.evaluate(x, residuals, None)
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        residuals: &mut [f64],
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable> {
        self.evaluate(x, residuals, Some(jacobian))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::SeedableRng;
    use rand_distr::{Distribution, Normal};

    fn firmware() -> DeltaGeometry {
        DeltaGeometry::new(0.215, 0.1056).unwrap()
    }

    /// A star of features: the centre, and points along each tower's direction and between.
    fn layout() -> Vec<Vector3<f64>> {
        let mut v = vec![Vector3::new(0.0, 0.0, 0.0002)];
        for k in 0..12 {
            let a = k as f64 * std::f64::consts::PI / 6.0;
            for r in [0.025, 0.05] {
                v.push(Vector3::new(r * a.cos(), r * a.sin(), 0.0002));
            }
        }
        v
    }

    fn measure(truth: &DeltaGeometry, sigma: f64, seed: u64) -> Vec<DeltaMeasurement> {
        let fw = firmware();
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        let noise = Normal::new(0.0, sigma).unwrap();
        let place = |p: Vector2<f64>| rotation(0.3) * p + Vector2::new(0.01, -0.02);
        layout()
            .iter()
            .map(|c| {
                let p = truth.forward(&fw.inverse(c).unwrap()).unwrap();
                let m = place(p.xy());
                DeltaMeasurement::PlanPosition {
                    commanded: *c,
                    measured: Vector2::new(
                        m.x + noise.sample(&mut rng),
                        m.y + noise.sample(&mut rng),
                    ),
                    sigma,
                    view: None,
                }
            })
            .collect()
    }

    #[test]
    fn rod_and_tower_angle_errors_are_recovered_within_their_uncertainty() {
        let mut truth = firmware();
        truth.rod_length += 1.0e-3;
        truth.tower_angle_trim[0] = 0.5f64.to_radians();
        let sigma = 20e-6;
        let mut worst: f64 = 0.0;
        for seed in 0..20 {
            let fit = fit_delta(&firmware(), &measure(&truth, sigma, seed), &[]).unwrap();
            for (k, want) in [
                (0, truth.rod_length),
                (2, truth.tower_angle_trim[0]),
                (3, 0.0),
            ] {
                let got = fit.geometry.to_vector()[k];
                let z = (got - want) / fit.sigma_of(k).unwrap();
                worst = worst.max(z.abs());
            }
            let rms = (fit.residuals.iter().map(|r| r * r).sum::<f64>()
                / fit.residuals.len() as f64)
                .sqrt();
            assert!(rms < 1.3 * sigma, "seed {seed}: rms {rms}");
        }
        assert!(worst < 4.0, "largest |error|/σ over 20 seeds: {worst}");
    }

    #[test]
    fn heights_free_the_radius_and_endstops_and_they_are_recovered() {
        let mut truth = firmware();
        truth.radius += 0.4e-3;
        truth.endstop = [0.3e-3, -0.2e-3, 0.1e-3];
        truth.rod_length -= 0.5e-3;
        let fw = firmware();
        let mut m = measure(&truth, 10e-6, 7);
        for c in layout() {
            let p = truth.forward(&fw.inverse(&c).unwrap()).unwrap();
            m.push(DeltaMeasurement::Height {
                commanded: c,
                measured: p.z,
                sigma: 10e-6,
            });
        }
        let fit = fit_delta(&fw, &m, &[]).unwrap();
        assert!(fit.held.iter().all(|(n, _)| !n.contains("endstop")));
        for (k, want) in [(0, truth.rod_length), (1, truth.radius), (11, 0.3e-3)] {
            let got = fit.geometry.to_vector()[k];
            assert!(
                (got - want).abs() < 4.0 * fit.sigma_of(k).unwrap() + 1e-9,
                "{}: {got} vs {want} ± {:?}",
                name_of(k),
                fit.sigma_of(k)
            );
        }
    }

    #[test]
    fn bad_measurements_are_named() {
        let m = vec![DeltaMeasurement::Height {
            commanded: Vector3::new(0.0, f64::NAN, 0.0),
            measured: 0.0,
            sigma: 1e-5,
        }];
        let e = fit_delta(&firmware(), &m, &[]).unwrap_err().to_string();
        assert!(e.contains("measurement 0") && e.contains("finite"), "{e}");
        let mut far = measure(&firmware(), 1e-5, 1);
        if let DeltaMeasurement::PlanPosition { commanded, .. } = &mut far[3] {
            commanded.x = 0.3;
        }
        let e = fit_delta(&firmware(), &far, &[]).unwrap_err().to_string();
        assert!(
            e.contains("measurement 3") && e.contains("outside this printer's reach"),
            "{e}"
        );
        let few = measure(&firmware(), 1e-5, 1)[..2].to_vec();
        let e = fit_delta(&firmware(), &few, &[]).unwrap_err().to_string();
        assert!(e.contains("4 measured values for 9 parameters"), "{e}");
    }
}
