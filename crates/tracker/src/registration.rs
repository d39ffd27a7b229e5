//! Frame registration: the tracker's pose in the machine frame from tracker points of targets
//! whose nominal machine coordinates are known. The implementation is the workspace's one rigid
//! registration, [`metrocell_kinematics::rigid_registration`] (convention, covariance order
//! (δt, δθ) and method are documented there); this module names it for the tracker and holds the
//! tests against the tracker's spherical noise.

pub use metrocell_kinematics::rigid_registration::{
    register, Correspondence, Registration, RegistrationError,
};

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_noise::normal;
    use metrocell_compensation::{spherical_to_cartesian, SphericalNoise};
    use nalgebra::Vector6;
    use nalgebra::{Matrix3, Rotation3, Vector3};
    use rand::SeedableRng;
    use rand_chacha::ChaCha8Rng;

    /// Thesis P3 pose: translation (−863.527, 194.373, 677.782) mm, Euler XYZ (0.0339°, 0.0343°, 59.4652°).
    fn thesis_pose() -> (Rotation3<f64>, Vector3<f64>) {
        let d = std::f64::consts::PI / 180.0;
        let r = Rotation3::from_axis_angle(&Vector3::x_axis(), 0.0339 * d)
            * Rotation3::from_axis_angle(&Vector3::y_axis(), 0.0343 * d)
            * Rotation3::from_axis_angle(&Vector3::z_axis(), 59.4652 * d);
        (r, Vector3::new(-0.863527, 0.194373, 0.677782))
    }

    /// A 5×4×3 grid in the machine frame seen by the tracker with its spherical noise.
    fn simulated(rng: &mut ChaCha8Rng) -> Vec<Correspondence> {
        let (r, t) = thesis_pose();
        let noise = SphericalNoise {
            radial_base: 4e-6,
            radial_per_metre: 0.8e-6,
            angular: 3e-6,
        };
        let mut v = Vec::new();
        for i in 0..5 {
            for j in 0..4 {
                for k in 0..3 {
                    let q = Vector3::new(0.2 * i as f64, 0.5 / 3.0 * j as f64, 0.2 * k as f64);
                    let p = r.inverse() * (q - t);
                    let (rho, az, el) = (p.norm(), p.y.atan2(p.x), p.z.atan2(p.x.hypot(p.y)));
                    let (pm, cov) = spherical_to_cartesian(
                        rho + noise.radial_sigma(rho) * normal(rng),
                        az + noise.angular * normal(rng),
                        el + noise.angular * normal(rng),
                        &noise,
                    );
                    v.push(Correspondence {
                        tracker: pm,
                        tracker_covariance: cov,
                        machine: q,
                        machine_covariance: Matrix3::zeros(),
                    });
                }
            }
        }
        v
    }

    #[test]
    fn noise_free_points_give_the_thesis_pose_exactly() {
        let (r, t) = thesis_pose();
        let pts: Vec<Correspondence> = [
            [0.0, 0.0, 0.0],
            [0.4, 0.0, 0.0],
            [0.0, 0.4, 0.0],
            [0.4, 0.4, 0.1],
        ]
        .iter()
        .map(|q| {
            let q = Vector3::from(*q);
            Correspondence {
                tracker: r.inverse() * (q - t),
                tracker_covariance: Matrix3::identity() * 1e-12,
                machine: q,
                machine_covariance: Matrix3::zeros(),
            }
        })
        .collect();
        let reg = register(&pts).unwrap();
        assert!((reg.translation - t).norm() < 1e-12);
        assert!((reg.rotation.matrix() - r.matrix()).norm() < 1e-12);
        assert!(reg.rms < 1e-12);
    }

    #[test]
    fn recovered_pose_is_within_its_covariance_over_seeds() {
        // Mahalanobis² of the true pose error ~ χ²(6): inside the 95 % quantile (12.59) in ~95 % of runs
        let (r, t) = thesis_pose();
        let runs = 400;
        let mut inside = 0;
        for seed in 0..runs {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            let reg = register(&simulated(&mut rng)).unwrap();
            let dtheta = (r * reg.rotation.inverse()).scaled_axis();
            let e = Vector6::new(
                t.x - reg.translation.x,
                t.y - reg.translation.y,
                t.z - reg.translation.z,
                dtheta.x,
                dtheta.y,
                dtheta.z,
            );
            let m2 = (e.transpose() * reg.covariance.try_inverse().unwrap() * e)[(0, 0)];
            if m2 < 12.59 {
                inside += 1;
            }
            // translation σ of a few µm: the registration is worth having
            assert!(reg.covariance[(0, 0)].sqrt() < 20e-6);
        }
        let frac = inside as f64 / runs as f64;
        assert!(
            (0.91..=0.99).contains(&frac),
            "{frac} of runs inside the 95 % region"
        );
    }

    #[test]
    fn degenerate_and_bad_inputs_are_named() {
        let c = |x: f64| Correspondence {
            tracker: Vector3::new(x, 0.0, 0.0),
            tracker_covariance: Matrix3::identity() * 1e-12,
            machine: Vector3::new(x, 0.0, 0.0),
            machine_covariance: Matrix3::zeros(),
        };
        assert_eq!(
            register(&[c(0.0), c(1.0)]),
            Err(RegistrationError::TooFew(2))
        );
        assert_eq!(
            register(&[c(0.0), c(1.0), c(2.0)]),
            Err(RegistrationError::Degenerate)
        );
        assert_eq!(
            register(&[c(0.0), c(f64::NAN), c(2.0)]),
            Err(RegistrationError::NotFinite(1))
        );
    }

    #[test]
    fn machine_point_covariance_includes_the_pose() {
        let mut rng = ChaCha8Rng::seed_from_u64(3);
        let reg = register(&simulated(&mut rng)).unwrap();
        let cov = Matrix3::identity() * 1e-12;
        let (_, out) = reg.to_machine(&Vector3::new(1.0, 0.5, 0.2), &cov);
        assert!(out.trace() > cov.trace(), "pose uncertainty adds");
        // translation first: at the machine origin (R p = 0) the pose adds exactly the
        // translation block
        let (_, at_origin) = reg.to_machine(&Vector3::zeros(), &Matrix3::zeros());
        assert_eq!(
            at_origin,
            reg.covariance.fixed_view::<3, 3>(0, 0).into_owned()
        );
    }
}
