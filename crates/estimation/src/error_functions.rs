//! The fitted machine's error functions with their uncertainty: the error vector e(q) (true −
//! nominal tool point, machine terms only) along each axis, and its standard uncertainty from
//! the fit's parameter covariance, u_e = √diag(J·C·Jᵀ) with J = ∂e/∂p the model's analytic
//! Jacobian. What a report plots as "per-axis error functions with uncertainty bands".

use metrocell_model::{ForwardModel, MachineKinematics};
use metrocell_physics::{PhysicsError, Signals};
use nalgebra::{DMatrix, Vector3};

/// e along one axis.
#[derive(Debug, Clone, PartialEq)]
pub struct AxisErrorFunction {
    /// 0, 1, 2 for x, y, z.
    pub axis: usize,
    /// Axis positions, m (the other axes at `reference`).
    pub positions: Vec<f64>,
    /// e at each position (approaching in +), m.
    pub errors: Vec<Vector3<f64>>,
    /// Standard uncertainty of each component, m.
    pub sigmas: Vec<Vector3<f64>>,
    pub reference: Vector3<f64>,
}

/// e and u_e along each axis of a cartesian or delta machine at `samples` positions over the
/// travel, the other axes at the travel's middle; `conditions` carries the signals besides the
/// axes (temperatures, time, load: e.g. a record's). `covariance`: of the stacked parameters
/// (None: zero uncertainty). Other families: empty (their errors are not per-axis functions).
pub fn axis_error_functions(
    model: &ForwardModel,
    p: &[f64],
    covariance: Option<&DMatrix<f64>>,
    conditions: &Signals,
    samples: usize,
) -> Result<Vec<AxisErrorFunction>, PhysicsError> {
    if !matches!(
        model.machine.kinematics,
        MachineKinematics::Cartesian(_) | MachineKinematics::Delta(_)
    ) {
        return Ok(vec![]);
    }
    let kin = model.kinematic_truth(p)?;
    let t = model.machine.travel;
    let reference = Vector3::new(
        (t[0][0] + t[0][1]) / 2.0,
        (t[1][0] + t[1][1]) / 2.0,
        (t[2][0] + t[2][1]) / 2.0,
    );
    let mut jac = DMatrix::zeros(3, model.param_count());
    let samples = samples.max(2);
    let mut out = vec![];
    for a in 0..3 {
        let mut f = AxisErrorFunction {
            axis: a,
            positions: vec![],
            errors: vec![],
            sigmas: vec![],
            reference,
        };
        for k in 0..samples {
            let mut q = reference;
            q[a] = t[a][0] + (t[a][1] - t[a][0]) * k as f64 / (samples - 1) as f64;
            let qs = [q.x, q.y, q.z];
            let mut s = conditions.clone();
            model.set_motion(&mut s, &qs, &[0.0; 3], &[1.0; 3]);
            let point = model.tool_point_jacobian(p, &kin, &qs, &mut s, &mut jac)?;
            let e = point - model.machine.nominal_tool_point(&q);
            let u = match covariance {
                Some(c) => {
                    let jc = &jac * c;
                    Vector3::from_fn(|i, _| (jc.row(i).dot(&jac.row(i))).max(0.0).sqrt())
                }
                None => Vector3::zeros(),
            };
            f.positions.push(q[a]);
            f.errors.push(e);
            f.sigmas.push(u);
        }
        out.push(f);
    }
    Ok(out)
}
