//! The patent's whole procedure (seed 003, claims 1–9) against a rig that moves and measures:
//! the camera's rotation from pure translations (Kabsch over a move each way along three axes; the
//! patent's TRIAD of two moves is `frame_alignment::rotation_from_two_moves`), then the xy offset from rotations about
//! z through two axes, then z from rotations about x (solved exactly, not by the patent's ratio
//! equations: see `offset_pass`) — each stage repeated,
//! the working frame moved by each estimate, until the estimate falls to the camera's noise floor
//! or the stage has run `max_passes` times.
//!
//! [`AlignmentRig`] is what a robot driver implements (and the twin, for tests): a pure
//! translation and a rotation about an axis through a point, each answered with what the camera
//! saw. Conventions are [`crate::frame_alignment`]'s: `R_rc` maps camera vectors into robot
//! vectors; the camera's origin is `r` from the tool origin (robot axes), so a rotation about an
//! axis through `a` moves it by `(R(θ) − I)(r − a)`, which the camera reads as `R_rcᵀ` of that.

use crate::error::KinematicsError;
use crate::frame_alignment::rotation_kabsch;
use nalgebra::{Matrix3, Rotation3, Unit, UnitQuaternion, Vector2, Vector3};

/// What the procedure asks of the robot and its camera.
pub trait AlignmentRig {
    /// Translate the tool by `v` (robot axes, m) and back; the camera's reading of the move
    /// (camera axes).
    fn translate(&mut self, v: &Vector3<f64>) -> Result<Vector3<f64>, KinematicsError>;
    /// Turn the tool by `angle` about the robot axis `axis` through the point `through` (tool
    /// frame, robot axes, m) and back; the camera's reading of its own displacement (camera axes).
    fn rotate(
        &mut self,
        axis: &Unit<Vector3<f64>>,
        angle: f64,
        through: &Vector3<f64>,
    ) -> Result<Vector3<f64>, KinematicsError>;
    /// The camera's rotation `R_rc` as the rotation stage found it, told before the offset
    /// stages: a rig whose camera measures positions can turn its readings with it (a target
    /// pose's orientation is much noisier than its position).
    fn rotation_estimate(&mut self, _r_rc: &Matrix3<f64>) {}
}

/// How the procedure moves and when it stops.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AlignmentPlan {
    /// Length of the rotation stage's translations, one each way along each axis (m).
    pub move_length: f64,
    /// Rotation angle of the offset stages (rad).
    pub angle: f64,
    /// Offset between the two axes of each offset stage (m): in x and y for the xy stage, in z
    /// for the z stage. The stages turn by ±`angle` about each axis.
    pub axis_offset: f64,
    /// The camera's noise per reading component (m): a stage stops when its estimate is within
    /// three times what that noise alone would give.
    pub camera_sigma: f64,
    pub max_passes: usize,
}

impl Default for AlignmentPlan {
    fn default() -> Self {
        Self {
            move_length: 0.1,
            angle: 30f64.to_radians(),
            axis_offset: 0.1,
            camera_sigma: 1e-5,
            max_passes: 5,
        }
    }
}

/// The result: the camera's frame in the tool's, its uncertainty, and how each stage went.
#[derive(Debug, Clone, PartialEq)]
pub struct Alignment {
    /// `R_rc`: camera axes → robot axes.
    pub rotation: Matrix3<f64>,
    /// The camera origin from the tool origin (robot axes, m).
    pub offset: Vector3<f64>,
    /// Standard uncertainty of the rotation about each robot axis (rad): each rotation pass
    /// measures all that is left, so one pass's noise, `camera_sigma / (2·move_length)`, over √2
    /// when the stage converged after two or more passes (the last two estimates averaged).
    pub rotation_sigma: f64,
    /// Covariance of `offset` (m²): x from the xy stage's last pass, y and z from the z stage's
    /// (which measures y again), each `σ²(AᵀA)⁻¹` of its least squares with σ² the camera's
    /// noise (halved when the last two passes are averaged) plus the rotation's uncertainty
    /// carried through the largest displacement read (common to both passes: not halved).
    pub offset_covariance: Matrix3<f64>,
    /// Passes each stage took (rotation, xy, z), and each pass's correction size (rad or m).
    pub passes: [Vec<f64>; 3],
}

impl Alignment {
    /// The camera's frame in the tool's as a fixed URDF joint (metres; `rpy` in URDF's
    /// convention, R = Rz(yaw)·Ry(pitch)·Rx(roll)), for a robot description.
    pub fn urdf_joint(&self, name: &str, tool_link: &str, camera_link: &str) -> String {
        let (roll, pitch, yaw) = Rotation3::from_matrix_unchecked(self.rotation).euler_angles();
        let o = self.offset;
        format!(
            "<joint name=\"{name}\" type=\"fixed\">\n  <parent link=\"{tool_link}\"/>\n  \
             <child link=\"{camera_link}\"/>\n  <origin xyz=\"{:.6} {:.6} {:.6}\" \
             rpy=\"{roll:.9} {pitch:.9} {yaw:.9}\"/>\n</joint>\n",
            o.x, o.y, o.z
        )
    }
}

/// One pass of an offset stage: turns by ±`angle` about `axis` through the offset so far and
/// through it plus `apart` (the patent's two axes), and solves the four displacements for what
/// is left of the offset in the plane the turns move it in, by least squares on
/// `(R(±θ) − I)(e − a) = Δ`: exact at any angle (the patent's ratio equations are biased by the
/// finite angle, P3–P4, and use half the readings).
fn offset_pass(
    rig: &mut dyn AlignmentRig,
    rotation: &Matrix3<f64>,
    axis: &Unit<Vector3<f64>>,
    angle: f64,
    offset: &Vector3<f64>,
    apart: &Vector3<f64>,
    plane: [usize; 2],
) -> Result<(Vector2<f64>, nalgebra::Matrix2<f64>, f64), KinematicsError> {
    let (mut ata, mut atb) = (nalgebra::Matrix2::zeros(), Vector2::zeros());
    let mut largest: f64 = 0.0;
    for shift in [Vector3::zeros(), *apart] {
        for sign in [1.0, -1.0] {
            let through = offset + shift;
            let seen = rotation * rig.rotate(axis, sign * angle, &through)?;
            largest = largest.max(seen.norm());
            let m =
                Rotation3::from_axis_angle(axis, sign * angle).into_inner() - Matrix3::identity();
            // (R − I)(e − shift) = Δ in the plane: A e = Δ + (R − I) shift
            let a = nalgebra::Matrix2::new(
                m[(plane[0], plane[0])],
                m[(plane[0], plane[1])],
                m[(plane[1], plane[0])],
                m[(plane[1], plane[1])],
            );
            let rhs = Vector2::new(seen[plane[0]], seen[plane[1]])
                + a * Vector2::new(shift[plane[0]], shift[plane[1]]);
            ata += a.transpose() * a;
            atb += a.transpose() * rhs;
        }
    }
    ata.try_inverse()
        .map(|inv| (inv * atb, inv, largest))
        .ok_or_else(|| KinematicsError::Degenerate {
            reason: "the rotation angle is zero: no displacement to read the offset from".into(),
        })
}

/// The standard uncertainty of one rotation pass about each axis (rad): the small-angle least
/// squares of six moves ±L along three axes has normal matrix Σ[v]×ᵀ[v]× = 4L²·I.
fn rotation_sigma_of(plan: &AlignmentPlan) -> f64 {
    plan.camera_sigma / (2.0 * plan.move_length)
}

/// Runs the three stages on `rig`.
pub fn align(
    rig: &mut dyn AlignmentRig,
    plan: &AlignmentPlan,
) -> Result<Alignment, KinematicsError> {
    let mut passes: [Vec<f64>; 3] = Default::default();
    // rotation: a move each way along each of the camera's estimated axes, Kabsch; each pass
    // measures what is left in the frame turned by the estimate so far. Six moves, not the
    // patent's two: the rotation's error turns every later turn's reading of a target |t| away
    // (the offset stages' largest error through a camera), and ± moves along three axes leave
    // σ/(2L) about every axis where two moves leave σ/L
    let mut rotation = Matrix3::identity();
    let floor = 3.0 * rotation_sigma_of(plan);
    // the estimate before the last pass: once a pass finds only noise left, it and the last are
    // two independent measurements of the same frame (each pass measures all that is left), and
    // their mean halves the variance
    let mut previous: Option<Matrix3<f64>> = None;
    let mut converged = false;
    for _ in 0..plan.max_passes {
        let mut moves = Vec::with_capacity(6);
        let mut readings = Vec::with_capacity(6);
        for axis in [Vector3::x(), Vector3::y(), Vector3::z()] {
            for sign in [1.0, -1.0] {
                let v = rotation * axis * (sign * plan.move_length);
                readings.push(rig.translate(&v)?);
                // what is left: the readings against the moves as the current estimate
                // predicts them
                moves.push(rotation.transpose() * v);
            }
        }
        let left = rotation_kabsch(&moves, &readings)?;
        previous = Some(rotation);
        rotation *= left;
        let size = Rotation3::from_matrix_unchecked(left).angle();
        passes[0].push(size);
        if size < floor {
            converged = true;
            break;
        }
    }
    let mut rotation_sigma = rotation_sigma_of(plan);
    if let (true, Some(before)) = (converged && passes[0].len() >= 2, previous) {
        // halfway from the one to the other (the normalised mean of the quaternions, on one
        // hemisphere: at one half the same as the slerp)
        let q = |m: &Matrix3<f64>| {
            UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*m))
        };
        let (a, mut b) = (q(&before), q(&rotation));
        if a.coords.dot(&b.coords) < 0.0 {
            b = UnitQuaternion::new_unchecked(-b.into_inner());
        }
        rotation = *a.nlerp(&b, 0.5).to_rotation_matrix().matrix();
        rotation_sigma /= 2f64.sqrt();
    }
    rig.rotation_estimate(&rotation);
    // the offset stages: displacements read in robot axes through the estimated rotation
    let mut offset = Vector3::zeros();
    let floor = 3.0 * plan.camera_sigma / (2.0 * (plan.angle / 2.0).sin());
    let d = plan.axis_offset;
    let stages = [
        // (axis, the second axis's offset, the plane the displacement lies in)
        (Vector3::z_axis(), Vector3::new(d, d, 0.0), [0, 1]),
        (Vector3::x_axis(), Vector3::new(0.0, 0.0, d), [1, 2]),
    ];
    let mut offset_covariance = Matrix3::zeros();
    for (k, (axis, apart, plane)) in stages.iter().enumerate() {
        for pass in 0..plan.max_passes {
            let before = offset;
            let (correction, inverse, largest) =
                offset_pass(rig, &rotation, axis, plan.angle, &offset, apart, *plane)?;
            for (i, c) in plane.iter().zip(correction.iter()) {
                offset[*i] += c;
            }
            let converged = correction.norm() < floor;
            // the last two estimates when this pass found only noise left: their mean (as the
            // rotation's above); the rotation's error is common to both and does not average
            let averaged = converged && pass >= 1;
            if averaged {
                for &i in plane {
                    offset[i] = 0.5 * (before[i] + offset[i]);
                }
            }
            // what the last pass leaves: its own noise (the rotation's error turns every
            // displacement read, by up to rotation_sigma × its length)
            let camera = plan.camera_sigma.powi(2) / if averaged { 2.0 } else { 1.0 };
            let variance = camera + (rotation_sigma * largest).powi(2);
            for (a, &i) in plane.iter().enumerate() {
                for (b, &j) in plane.iter().enumerate() {
                    offset_covariance[(i, j)] = variance * inverse[(a, b)];
                }
                // the z stage measures y again: the xy stage's y/x correlation no longer holds
                for other in 0..3 {
                    if !plane.contains(&other) {
                        offset_covariance[(i, other)] = 0.0;
                        offset_covariance[(other, i)] = 0.0;
                    }
                }
            }
            passes[k + 1].push(correction.norm());
            if converged {
                break;
            }
        }
    }
    Ok(Alignment {
        rotation,
        offset,
        rotation_sigma,
        offset_covariance,
        passes,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::UnitQuaternion;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// The twin's rig: a camera turned by `r_rc` at `r` from the tool origin, each reading
    /// component with Gaussian noise of σ.
    struct TwinRig {
        r_rc: Matrix3<f64>,
        r: Vector3<f64>,
        sigma: f64,
        rng: ChaCha8Rng,
    }

    impl TwinRig {
        fn noise(&mut self) -> Vector3<f64> {
            // Box–Muller, to keep the dependencies to rand's core
            Vector3::from_fn(|_, _| {
                let (u1, u2): (f64, f64) = (self.rng.random(), self.rng.random());
                (-2.0 * (1.0 - u1).ln()).sqrt() * (std::f64::consts::TAU * u2).cos() * self.sigma
            })
        }
    }

    impl AlignmentRig for TwinRig {
        fn translate(&mut self, v: &Vector3<f64>) -> Result<Vector3<f64>, KinematicsError> {
            Ok(self.r_rc.transpose() * v + self.noise())
        }
        fn rotate(
            &mut self,
            axis: &Unit<Vector3<f64>>,
            angle: f64,
            through: &Vector3<f64>,
        ) -> Result<Vector3<f64>, KinematicsError> {
            let d = UnitQuaternion::from_axis_angle(axis, angle) * (self.r - through)
                - (self.r - through);
            Ok(self.r_rc.transpose() * d + self.noise())
        }
    }

    /// Seed 003 P12: random rotations up to 10°, offsets up to 100 mm, 0.01 mm camera noise: the
    /// composed transform within 0.05 mm and 0.05° after at most five passes per stage.
    #[test]
    fn p12_noisy_end_to_end_reaches_the_tolerance_in_five_passes() {
        let mut rng = ChaCha8Rng::seed_from_u64(2026);
        let (mut worst_mm, mut worst_deg, mut most_passes) = (0.0f64, 0.0f64, 0usize);
        // |z| of each offset and rotation component against the σ the result states
        let mut z = Vec::new();
        for trial in 0..200 {
            let axis = Unit::new_normalize(Vector3::from_fn(|_, _| rng.random::<f64>() - 0.5));
            let r_rc =
                *UnitQuaternion::from_axis_angle(&axis, rng.random::<f64>() * 10f64.to_radians())
                    .to_rotation_matrix()
                    .matrix();
            let r = Vector3::from_fn(|_, _| (rng.random::<f64>() - 0.5) * 0.2);
            let mut rig = TwinRig {
                r_rc,
                r,
                sigma: 1e-5,
                rng: ChaCha8Rng::seed_from_u64(trial),
            };
            let a = align(&mut rig, &AlignmentPlan::default()).unwrap();
            let mm = (a.offset - r).norm() * 1e3;
            let deg = Rotation3::from_matrix_unchecked(a.rotation.transpose() * r_rc)
                .angle()
                .to_degrees();
            for i in 0..3 {
                z.push(((a.offset - r)[i] / a.offset_covariance[(i, i)].sqrt()).abs());
            }
            let turn =
                Rotation3::from_matrix_unchecked(r_rc * a.rotation.transpose()).scaled_axis();
            z.extend(turn.iter().map(|t| (t / a.rotation_sigma).abs()));
            worst_mm = worst_mm.max(mm);
            worst_deg = worst_deg.max(deg);
            most_passes = most_passes.max(a.passes.iter().map(Vec::len).max().unwrap());
        }
        println!("worst {worst_mm:.4} mm, {worst_deg:.4}°, {most_passes} passes");
        let within = |k: f64| z.iter().filter(|v| **v < k).count() as f64 / z.len() as f64;
        println!(
            "stated σ: within 1σ {:.3}, 2σ {:.3}, 3σ {:.3} of {} components",
            within(1.0),
            within(2.0),
            within(3.0),
            z.len()
        );
        // Gaussian: 0.683, 0.954, 0.997
        assert!((0.60..0.78).contains(&within(1.0)), "{}", within(1.0));
        assert!(
            within(2.0) > 0.92 && within(3.0) > 0.985,
            "{} {}",
            within(2.0),
            within(3.0)
        );
        assert!(
            worst_mm < 0.05 && worst_deg < 0.05,
            "{worst_mm} mm, {worst_deg}°"
        );
        assert!(most_passes <= 5);
    }

    #[test]
    fn the_result_as_a_urdf_joint_reads_back_as_the_same_transform() {
        let rotation = *UnitQuaternion::from_euler_angles(0.03, -0.02, 0.08)
            .to_rotation_matrix()
            .matrix();
        let a = Alignment {
            rotation,
            offset: Vector3::new(0.04, -0.025, 0.06),
            rotation_sigma: 1e-4,
            offset_covariance: Matrix3::identity() * 1e-10,
            passes: Default::default(),
        };
        let urdf = format!(
            "<robot name=\"r\"><link name=\"tool0\"/><link name=\"camera\"/>{}</robot>",
            a.urdf_joint("tool0_to_camera", "tool0", "camera")
        );
        let chain = crate::urdf_chain::chain_from_urdf_str(&urdf, "tool0", "camera").unwrap();
        let pose = chain.forward(&[]).unwrap().tool;
        assert!((pose.translation.vector - a.offset).norm() < 1e-6);
        assert!((pose.rotation.to_rotation_matrix().matrix() - rotation).norm() < 1e-8);
    }

    #[test]
    fn noise_free_rig_is_recovered_exactly_and_stops_early() {
        let r_rc = *UnitQuaternion::from_euler_angles(
            -3f64.to_radians(),
            2f64.to_radians(),
            5f64.to_radians(),
        )
        .to_rotation_matrix()
        .matrix();
        let r = Vector3::new(0.040, -0.025, 0.060);
        let mut rig = TwinRig {
            r_rc,
            r,
            sigma: 0.0,
            rng: ChaCha8Rng::seed_from_u64(1),
        };
        let plan = AlignmentPlan {
            camera_sigma: 1e-9,
            ..AlignmentPlan::default()
        };
        let a = align(&mut rig, &plan).unwrap();
        assert!((a.offset - r).norm() < 1e-8, "{:?}", a.offset - r);
        assert!((a.rotation - r_rc).norm() < 1e-12);
        assert_eq!(
            a.passes[0].len(),
            2,
            "the second pass finds nothing left: {:?}",
            a.passes
        );
    }
}
