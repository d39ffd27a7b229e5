//! Inverse kinematics of a serial chain on the shared least-squares solver (crates/solver).
//!
//! Residuals (stated once): r = [p(q) − p_t; w·φ(q)] with p the tool point, p_t the target point,
//! w the orientation weight (m per rad) and φ = log(R(q)·R_tᵀ) the rotation vector from the
//! target orientation to the tool's (orientation rows only for a pose target). Its Jacobian is
//! exact: ∂p/∂q is the geometric Jacobian's linear rows, and since a joint turns the tool by
//! R → exp([ω])·R with ω its angular-velocity column, ∂φ/∂q = J_l⁻¹(φ)·ω with the left
//! Jacobian of SO(3), J_l⁻¹(φ) = I − ½[φ]× + (1/θ² − cot(θ/2)/(2θ))·[φ]×², θ = |φ|. The first-order
//! ∂φ/∂q ≈ ω is wrong by O(θ) and stalls far from the target (a tool turned 180° from its start);
//! the exact form is well-defined up to θ = π, where cot(π/2) = 0.
//!
//! The log map flips its axis at θ = π, and a chain can have several solutions and local minima
//! of |r|: when the solve from `q0` does not meet the tolerances, it restarts from `q0` with one
//! revolute joint turned by ±90° at a time (deterministic order) and returns the first start that
//! converges, else the best. Revolute joints are returned within π of `q0` (a turn by 2π is the
//! same pose). Joint limits are not enforced (the caller checks them).

use metrocell_solver::{solve, NotEvaluable, NullSpace, Options, Problem};
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

use crate::error::KinematicsError;
use crate::serial::{IkReport, IkSettings, IkTarget, JointKind, SerialChain};

/// J_l⁻¹(φ), the inverse left Jacobian of SO(3) (module doc).
fn inverse_left_jacobian(phi: &Vector3<f64>) -> Matrix3<f64> {
    let theta = phi.norm();
    let k = phi.cross_matrix();
    // 1/θ² − cot(θ/2)/(2θ) → 1/12 + θ²/720 as θ → 0
    let c = if theta < 1e-4 {
        1.0 / 12.0 + theta * theta / 720.0
    } else {
        1.0 / (theta * theta) - 1.0 / (2.0 * theta * (theta / 2.0).tan())
    };
    Matrix3::identity() - k * 0.5 + k * k * c
}

struct IkProblem<'a> {
    chain: &'a SerialChain,
    target: &'a IkTarget,
    weight: f64,
}

impl IkProblem<'_> {
    /// Position error (m), orientation error φ (rad) at q.
    fn errors(&self, q: &[f64]) -> Result<(Vector3<f64>, Vector3<f64>), KinematicsError> {
        let pose = self.chain.tool_pose(q)?;
        Ok(match self.target {
            IkTarget::Position(p) => (pose.translation.vector - p, Vector3::zeros()),
            IkTarget::Pose(t) => (
                pose.translation.vector - t.translation.vector,
                (pose.rotation * t.rotation.inverse()).scaled_axis(),
            ),
        })
    }

    fn fill(&self, q: &[f64], r: &mut [f64]) -> Result<Vector3<f64>, NotEvaluable> {
        let (dp, phi) = self.errors(q).map_err(|e| NotEvaluable(e.to_string()))?;
        r[..3].copy_from_slice(dp.as_slice());
        if r.len() == 6 {
            r[3..].copy_from_slice((phi * self.weight).as_slice());
        }
        Ok(phi)
    }
}

impl Problem for IkProblem<'_> {
    fn residual_count(&self) -> usize {
        match self.target {
            IkTarget::Position(_) => 3,
            IkTarget::Pose(_) => 6,
        }
    }
    fn parameter_count(&self) -> usize {
        self.chain.dof()
    }
    fn residuals(&self, x: &[f64], residuals: &mut [f64]) -> Result<(), NotEvaluable> {
        self.fill(x, residuals).map(|_| ())
    }
    fn residuals_and_jacobian(
        &self,
        x: &[f64],
        residuals: &mut [f64],
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), NotEvaluable> {
        let phi = self.fill(x, residuals)?;
        let geometric = self
            .chain
            .jacobian(x)
            .map_err(|e| NotEvaluable(e.to_string()))?;
        jacobian.rows_mut(0, 3).copy_from(&geometric.rows(0, 3));
        if residuals.len() == 6 {
            let turn = inverse_left_jacobian(&phi) * self.weight;
            jacobian
                .rows_mut(3, 3)
                .copy_from(&(turn * geometric.rows(3, 3)));
        }
        // a joint whose column is round-off (a wrist turning the tool point about itself, for a
        // position target) does not move the residual: an exact zero column keeps the solver's
        // unit-invariant scaling from blowing that noise up into a step
        let largest = jacobian.column_iter().map(|c| c.norm()).fold(0.0, f64::max);
        for mut c in jacobian.column_iter_mut() {
            if c.norm() < 1e-12 * largest {
                c.fill(0.0);
            }
        }
        Ok(())
    }
}

impl SerialChain {
    /// Inverse kinematics from the initial guess `q0` (module doc): Levenberg–Marquardt on the
    /// shared solver, restarted from turned starts when the first solve does not converge.
    pub fn inverse(
        &self,
        target: &IkTarget,
        q0: &[f64],
        settings: &IkSettings,
    ) -> Result<IkReport, KinematicsError> {
        self.check_q(q0)?;
        let problem = IkProblem {
            chain: self,
            target,
            weight: settings.orientation_weight,
        };
        let with_orientation = matches!(target, IkTarget::Pose(_));
        let done = |pe: f64, oe: f64| {
            pe <= settings.position_tolerance
                && (!with_orientation || oe <= settings.orientation_tolerance)
        };
        // converged means the tolerances are met, so the solver's own tests are set to round-off;
        // a redundant chain (a position target of a 6-axis arm, a wrist joint that only turns the
        // tool about its point) has directions the residuals do not see: truncated-SVD steps leave
        // them at the start (a minimum-norm step, as damped least squares takes)
        let options = Options {
            max_iterations: settings.max_iterations,
            ftol: 0.0,
            gtol: 0.0,
            xtol: 1e-15,
            initial_damping: settings.initial_damping,
            null_space: NullSpace::Truncated { rcond: 1e-10 },
            ..Options::default()
        };
        let mut starts = vec![q0.to_vec()];
        for (k, j) in self
            .joints
            .iter()
            .filter(|j| j.kind != JointKind::Fixed)
            .enumerate()
        {
            if j.kind == JointKind::Revolute {
                for turn in [std::f64::consts::FRAC_PI_2, -std::f64::consts::FRAC_PI_2] {
                    let mut q = q0.to_vec();
                    q[k] += turn;
                    starts.push(q);
                }
            }
        }
        let mut best: Option<IkReport> = None;
        let mut iterations = 0;
        for start in starts {
            let solution =
                solve(&problem, &start, &options).map_err(|e| KinematicsError::InvalidValue {
                    field: "inverse kinematics".into(),
                    value: f64::NAN,
                    reason: e.to_string(),
                })?;
            iterations += solution.iterations;
            // a revolute joint turned by 2π gives the same pose: return the turn nearest q0
            let mut x = solution.x;
            for (k, j) in self
                .joints
                .iter()
                .filter(|j| j.kind != JointKind::Fixed)
                .enumerate()
            {
                if j.kind == JointKind::Revolute {
                    let turns = ((x[k] - q0[k]) / std::f64::consts::TAU).round();
                    x[k] -= turns * std::f64::consts::TAU;
                }
            }
            let (dp, phi) = problem.errors(&x)?;
            let report = IkReport {
                converged: done(dp.norm(), phi.norm()),
                q: DVector::from_vec(x),
                iterations,
                position_error: dp.norm(),
                orientation_error: phi.norm(),
                damping: solution.damping,
            };
            let score =
                |r: &IkReport| r.position_error + settings.orientation_weight * r.orientation_error;
            if report.converged {
                return Ok(report);
            }
            if best.as_ref().is_none_or(|b| score(&report) < score(b)) {
                best = Some(report);
            }
        }
        let mut report = best.expect("at least the start q0 was solved");
        report.iterations = iterations;
        Ok(report)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// J_l⁻¹(φ)·J_l(φ) = I, with J_l = I + (1 − cos θ)/θ²·[φ]× + (θ − sin θ)/θ³·[φ]×² (the textbook
    /// left Jacobian), up to θ = π.
    #[test]
    fn inverse_left_jacobian_inverts_the_left_jacobian() {
        for phi in [
            Vector3::new(1e-6, 2e-6, -1e-6),
            Vector3::new(0.3, -0.2, 0.5),
            Vector3::new(0.0, 0.0, 3.0),
            Vector3::new(1.0, 2.0, 2.0).normalize() * std::f64::consts::PI,
        ] {
            let t = phi.norm();
            let k = phi.cross_matrix();
            let jl = Matrix3::identity()
                + k * ((1.0 - t.cos()) / (t * t))
                + k * k * ((t - t.sin()) / (t * t * t));
            let err = (inverse_left_jacobian(&phi) * jl - Matrix3::identity()).amax();
            assert!(err < 1e-9, "φ = {phi:?}: {err:e}");
        }
    }
}
