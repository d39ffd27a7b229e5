//! `rotary_axis_location` — location errors of the rotary axes of a five-axis B/C table
//! (ISO 230-1 §3.4 / ISO 230-7: E_XOB, E_ZOB, E_AOB, E_COB, E_B0B and E_XOC, E_YOC, E_AOC,
//! E_BOC, E_C0C): each rotary axis turns about a line displaced and tilted from its nominal one,
//! from a zero that is slightly off.
//!
//! Nominal (crates/kinematics `five_axis`): machine ← workpiece
//! `W(B, C) = T(p_B)·Ry(B)·T(c)·Rz(C)·T(w)`. True: each rotary factor R(θ) becomes
//! `T(δ)·R(ε)·R(θ + θ₀)·R(ε)ᵀ·T(−δ)` — the turn about a line through δ (from the nominal point)
//! with direction tilted by the small rotation ε, from a zero offset θ₀:
//! * B (turning about +y, machine frame): δ_B = (x_ob, 0, z_ob), ε_B = (a_ob, 0, c_ob), θ₀ = b_ob;
//! * C (turning about +z, cradle frame at B): δ_C = (x_oc, y_oc, 0), ε_C = (a_oc, b_oc, 0), θ₀ = c_oc.
//!
//! To first order in the errors W' = W + δW with
//! `δW·p = δX_B(q_B) + Ry(B)·δX_C(q_C)`, q_C = w + p (table frame), q_B = c + Rz(C)·q_C,
//! `δX(y) = ε×(R y) − R(ε×y) + δ − R δ + θ₀·(e × R y)` (e = the axis: y for B, z for C).
//! The tool tip t (machine frame, signal `machine_point`) then
//! lands at the workpiece point W'⁻¹t ≈ W⁻¹(t − δW·p) with p = W⁻¹t, so in the convention of
//! every machine-frame term (`tip_wp = W⁻¹(t + d)`, crates/model):
//!
//! d = −δW·p
//!
//! Linear in the ten parameters (the Jacobian is exact). At B = C = 0 nothing moves: location
//! errors only show when the axes turn. Which combinations a set-up can separate (a zero offset
//! of C is a constant turn of the workpiece, the same as moving a tracker that rides on the
//! table) is for the estimator's identifiability analysis to say. Frame: machine. Options:
//! `b_pivot`, `c_offset`, `workpiece_offset` (m; the machine's five_axis geometry).

use nalgebra::{DMatrix, Matrix3, Vector3};

use crate::config::Options;
use crate::error::PhysicsError;
use crate::signals::{RotaryAxis, SignalKind, Signals};
use crate::term::{check_len, displacement, EffectKind, Frame, ParamSpec, PhysicsTerm, Prediction};
use crate::term_id::TermId;

#[derive(Debug, Clone)]
pub struct RotaryAxisLocation {
    pub b_pivot: Vector3<f64>,
    pub c_offset: Vector3<f64>,
    pub workpiece_offset: Vector3<f64>,
}

/// Parameter names in order (ISO 230-1 symbols in the docs).
const NAMES: [(&str, &str, f64, &str); 10] = [
    ("x_ob", "m", 2e-3, "E_XOB: B axis line offset along x"),
    ("z_ob", "m", 2e-3, "E_ZOB: B axis line offset along z"),
    ("a_ob", "rad", 2e-3, "E_AOB: B axis tilt about x"),
    ("c_ob", "rad", 2e-3, "E_COB: B axis tilt about z"),
    ("b_ob", "rad", 1e-2, "E_B0B: B zero-position error"),
    (
        "x_oc",
        "m",
        2e-3,
        "E_XOC: C axis line offset along x (cradle frame)",
    ),
    (
        "y_oc",
        "m",
        2e-3,
        "E_YOC: C axis line offset along y (cradle frame)",
    ),
    (
        "a_oc",
        "rad",
        2e-3,
        "E_AOC: C axis tilt about x (cradle frame)",
    ),
    (
        "b_oc",
        "rad",
        2e-3,
        "E_BOC: C axis tilt about y (cradle frame)",
    ),
    ("c_oc", "rad", 1e-2, "E_C0C: C zero-position error"),
];

fn rot_y(b: f64) -> Matrix3<f64> {
    let (s, c) = b.sin_cos();
    Matrix3::new(c, 0.0, s, 0.0, 1.0, 0.0, -s, 0.0, c)
}

fn rot_z(a: f64) -> Matrix3<f64> {
    let (s, c) = a.sin_cos();
    Matrix3::new(c, -s, 0.0, s, c, 0.0, 0.0, 0.0, 1.0)
}

impl RotaryAxisLocation {
    pub fn from_options(o: &Options) -> Result<Self, PhysicsError> {
        Ok(Self {
            b_pivot: o.vector3("b_pivot", "m", Some(Vector3::zeros()))?,
            c_offset: o.vector3("c_offset", "m", Some(Vector3::zeros()))?,
            workpiece_offset: o.vector3("workpiece_offset", "m", Some(Vector3::zeros()))?,
        })
    }

    /// The columns −∂(δW·p)/∂θ (3 × 10) at the instant `s`.
    fn columns(&self, s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        let t = s.machine(self)?;
        let b = s.rotary(self, RotaryAxis::B)?;
        let c = s.rotary(self, RotaryAxis::C)?;
        let (ry, rz) = (rot_y(b), rot_z(c));
        // nominal workpiece point p = W⁻¹t, and the points each rotary factor acts on
        let q_c = rz.transpose() * (ry.transpose() * (t - self.b_pivot) - self.c_offset);
        let q_b = self.c_offset + rz * q_c;
        let (ey, ez) = (Vector3::y(), Vector3::z());
        let mut j = DMatrix::zeros(3, 10);
        let mut set = |k: usize, v: Vector3<f64>| j.set_column(k, &(-v));
        // B: δX_B(q_B) for unit δ, ε, θ₀
        let ryq = ry * q_b;
        set(0, Vector3::x() - ry * Vector3::x());
        set(1, ez - ry * ez);
        set(2, Vector3::x().cross(&ryq) - ry * Vector3::x().cross(&q_b));
        set(3, ez.cross(&ryq) - ry * ez.cross(&q_b));
        set(4, ey.cross(&ryq));
        // C: Ry·δX_C(q_C)
        let rzq = rz * q_c;
        set(5, ry * (Vector3::x() - rz * Vector3::x()));
        set(6, ry * (ey - rz * ey));
        set(
            7,
            ry * (Vector3::x().cross(&rzq) - rz * Vector3::x().cross(&q_c)),
        );
        set(8, ry * (ey.cross(&rzq) - rz * ey.cross(&q_c)));
        set(9, ry * ez.cross(&rzq));
        Ok(j)
    }
}

impl PhysicsTerm for RotaryAxisLocation {
    fn id(&self) -> TermId {
        TermId::RotaryAxisLocation
    }
    fn label(&self) -> String {
        "rotary_axis_location".into()
    }
    fn effect(&self) -> EffectKind {
        EffectKind::Displacement(Frame::Machine)
    }
    fn params(&self) -> Vec<ParamSpec> {
        NAMES
            .iter()
            .map(|(n, unit, bound, doc)| ParamSpec::new(*n, unit, -bound, *bound, 0.0, *doc))
            .collect()
    }
    fn signals(&self) -> Vec<SignalKind> {
        vec![
            SignalKind::MachinePoint,
            SignalKind::RotaryPosition(RotaryAxis::B),
            SignalKind::RotaryPosition(RotaryAxis::C),
        ]
    }
    fn predict(&self, p: &[f64], s: &Signals) -> Result<Prediction, PhysicsError> {
        check_len(self, p, 10)?;
        let j = self.columns(s)?;
        let d = &j * nalgebra::DVector::from_column_slice(p);
        Ok(displacement(Frame::Machine, Vector3::new(d[0], d[1], d[2])))
    }
    fn jacobian(&self, p: &[f64], s: &Signals) -> Result<DMatrix<f64>, PhysicsError> {
        check_len(self, p, 10)?;
        self.columns(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Isometry3, Point3, Rotation3, Translation3, UnitQuaternion};

    /// The exact perturbed chain (small rotations as rotation vectors) against the first-order
    /// term: the difference is second order in the errors.
    #[test]
    fn first_order_displacement_matches_the_exact_perturbed_chain() {
        let term = RotaryAxisLocation {
            b_pivot: Vector3::new(0.5, 0.5, 0.15),
            c_offset: Vector3::new(0.0, 0.0, 0.05),
            workpiece_offset: Vector3::new(0.01, -0.02, 0.0),
        };
        let e = [
            20e-6, -15e-6, 40e-6, -30e-6, 50e-6, 10e-6, 25e-6, -35e-6, 45e-6, -60e-6,
        ];
        let iso = |r: Matrix3<f64>| {
            Isometry3::from_parts(
                Translation3::identity(),
                UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r)),
            )
        };
        let tr = |v: Vector3<f64>| {
            Isometry3::from_parts(Translation3::from(v), UnitQuaternion::identity())
        };
        let small = |v: Vector3<f64>| {
            Isometry3::from_parts(
                Translation3::identity(),
                UnitQuaternion::from_scaled_axis(v),
            )
        };
        for (b, c, t) in [
            (0.3, -0.7, Vector3::new(0.6, 0.4, 0.3)),
            (-1.2, 2.0, Vector3::new(0.45, 0.62, 0.21)),
            (0.0, 0.0, Vector3::new(0.5, 0.5, 0.5)),
        ] {
            let nominal = tr(term.b_pivot)
                * iso(rot_y(b))
                * tr(term.c_offset)
                * iso(rot_z(c))
                * tr(term.workpiece_offset);
            let (db, eb) = (Vector3::new(e[0], 0.0, e[1]), Vector3::new(e[2], 0.0, e[3]));
            let (dc, ec) = (Vector3::new(e[5], e[6], 0.0), Vector3::new(e[7], e[8], 0.0));
            let xb = tr(db) * small(eb) * iso(rot_y(b + e[4])) * small(eb).inverse() * tr(-db);
            let xc = tr(dc) * small(ec) * iso(rot_z(c + e[9])) * small(ec).inverse() * tr(-dc);
            let truth = tr(term.b_pivot) * xb * tr(term.c_offset) * xc * tr(term.workpiece_offset);
            let exact_wp = truth.inverse() * Point3::from(t);
            let s = Signals {
                machine_point: Some(t),
                rotary_position: [None, Some(b), Some(c)],
                ..Default::default()
            };
            let d = term.predict(&e, &s).unwrap().value;
            let model_wp = nominal.inverse() * Point3::from(t + Vector3::new(d[0], d[1], d[2]));
            let gap = (exact_wp - model_wp).norm();
            let size = (exact_wp - nominal.inverse() * Point3::from(t)).norm();
            assert!(
                gap < 1e-3 * size.max(1e-9) + 1e-12,
                "B {b} C {c}: exact vs first order differ by {gap:e} m on an effect of {size:e} m"
            );
            if b == 0.0 && c == 0.0 {
                // the zero offsets still turn the table about its axes; offsets and tilts do not
                assert!(size < 1e-3 && size > 0.0);
            } else {
                assert!(size > 1e-5, "B {b} C {c}: effect {size:e}");
            }
        }
    }
}
