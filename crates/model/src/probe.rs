//! The touch probe's reading and its analytic Jacobian.
//!
//! Convention (stated once): the probe approaches the nominal surface point f (workpiece frame)
//! along the unit direction u (travel towards the surface, machine axes: the probe frame is
//! parallel to them, as on a 3-axis machine with the stylus along z) with a ball of radius r.
//! * The part's surface point truly lies at f + d_w(f) (workpiece terms, see [`crate::forward`]).
//! * The ball touches when its true centre is one radius short of it: f + d_w(f) − r·u.
//! * The machine reads that centre through its nominal kinematics, i.e. minus its displacement
//!   d at the trigger's axes q (machine- and tool-frame terms, a delta's trims).
//! * The trigger comes pt(u) after contact (`probe_pretravel`, lobing), so the axes have moved
//!   pt(u) further along u.
//!
//! The reading is the stylus-centre position the machine reports at the trigger:
//!   c = f + d_w(f) − r·u − d(q) + pt(u)·u
//! (a probe node's compensated surface point is c − pt_node(u)·u + r·u). At the trigger every
//! axis that moves along u approaches in the sign of u's component: the model sets those
//! `approach_direction` signals (the others keep theirs), so `backlash` sees the probing move.
//! Probe readings are modelled on cartesian and delta machines.

use metrocell_physics::{PhysicsError, Signals};
use nalgebra::{DMatrix, Vector3};

use crate::forward::{v3, ForwardModel, KinematicTruth};
use crate::instruments::InstrumentKind;
use crate::machine::MachineKinematics;
use crate::workspace::Workspace;

/// One probing: the nominal surface point, the approach direction and the ball radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbeTarget {
    /// Nominal surface point f, workpiece frame, m.
    pub surface: Vector3<f64>,
    /// Unit approach direction u (travel towards the surface), machine axes.
    pub approach: Vector3<f64>,
    /// Effective ball radius r, m (0 when the reading is of the contact point itself).
    pub stylus_radius: f64,
}

/// The predicted reading of a touch probe.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ProbePrediction {
    /// The stylus-centre reading c at the trigger (workpiece frame), m.
    pub centre: Vector3<f64>,
    /// The true surface point f + d_w(f), m.
    pub contact: Vector3<f64>,
    /// The machine's displacement d at the trigger's axes, m.
    pub machine: Vector3<f64>,
    /// The pretravel vector pt(u)·u (zero without a `probe_pretravel` term), m.
    pub pretravel: Vector3<f64>,
}

/// Rows of [`ForwardModel::probe_jacobian`]: the stylus-centre reading x, y, z.
pub const PROBE_ROWS: usize = 3;

impl ForwardModel<'_> {
    fn probe_setup(
        &self,
        instrument: Option<&str>,
        hit: &ProbeTarget,
        s: &mut Signals,
    ) -> Result<Option<usize>, PhysicsError> {
        if !matches!(
            self.machine.kinematics,
            MachineKinematics::Cartesian(_) | MachineKinematics::Delta(_)
        ) {
            return Err(PhysicsError::InvalidInput { what: "forward model, probe reading".into(), reason: "touch-probe readings are modelled on cartesian and delta machines (probe frame parallel to the machine axes)".into() });
        }
        let u = hit.approach;
        let valid = (u.norm() - 1.0).abs() < 1e-9
            && hit.stylus_radius >= 0.0
            && hit.stylus_radius.is_finite()
            && hit.surface.iter().all(|v| v.is_finite());
        if !valid {
            return Err(PhysicsError::InvalidInput { what: "forward model, probe reading".into(), reason: format!("needs a finite surface point, a unit approach direction and a radius ≥ 0; got surface {:?}, |u| = {}, r = {}", hit.surface.as_slice(), u.norm(), hit.stylus_radius) });
        }
        for k in 0..3 {
            if u[k] != 0.0 {
                s.approach_direction[k] = Some(u[k].signum());
            }
        }
        s.probe_direction = Some(u);
        let pretravel = match self.instrument(InstrumentKind::Probe, instrument)? {
            Some(k) => self.instruments[k].pretravel,
            None => None,
        };
        Ok(pretravel)
    }

    /// The reading of probe `instrument` (None: the only one; a probe without terms has no
    /// pretravel) for the probing `hit` at the trigger's commanded joint vector `q` (see the
    /// module doc). `s` carries the axis signals ([`Self::set_motion`]) and the rest; its
    /// approach directions of the probing axes, `probe_direction` and `workpiece_point` are set
    /// here.
    pub fn probe_hit(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        kin: &KinematicTruth,
        q: &[f64],
        s: &mut Signals,
        hit: &ProbeTarget,
    ) -> Result<ProbePrediction, PhysicsError> {
        self.check(p)?;
        let pretravel = self.probe_setup(instrument, hit, s)?;
        let d = self.tool_state(p, kin, q, s, None)?.d;
        let contact = hit.surface + self.workpiece_displacement(p, s, hit.surface, None, 1.0)?;
        let pt = match pretravel {
            Some(i) => v3(&self.term(i).term.predict(self.part(i, p), s)?.value),
            None => Vector3::zeros(),
        };
        Ok(ProbePrediction {
            centre: contact - hit.approach * hit.stylus_radius - d + pt,
            contact,
            machine: d,
            pretravel: pt,
        })
    }

    /// [`Self::probe_hit`] and its Jacobian w.r.t. the stacked parameters into `out`
    /// ([`PROBE_ROWS`] × [`Self::param_count`]); the prediction is `probe_hit`'s bit for bit.
    #[allow(clippy::too_many_arguments)]
    pub fn probe_jacobian(
        &self,
        instrument: Option<&str>,
        p: &[f64],
        kin: &KinematicTruth,
        q: &[f64],
        s: &mut Signals,
        hit: &ProbeTarget,
        work: &mut Workspace,
        out: &mut DMatrix<f64>,
    ) -> Result<ProbePrediction, PhysicsError> {
        self.check(p)?;
        self.check_buffer("probe Jacobian", out, PROBE_ROWS)?;
        work.check(self)?;
        let pretravel = self.probe_setup(instrument, hit, s)?;
        let d = self.tool_jacobian(p, kin, q, s, &mut work.tool, None)?.d;
        work.feature.fill(0.0);
        let contact = hit.surface
            + self.workpiece_displacement(p, s, hit.surface, Some(&mut work.feature), 1.0)?;
        // ∂c = ∂d_w(f) − ∂d + u·∂pt
        out.copy_from(&work.feature);
        *out -= &work.tool;
        let pt = match pretravel {
            Some(i) => {
                let sl = self.slots[i];
                let mut v = [0.0; 3];
                self.term(i).term.evaluate_into(
                    self.part(i, p),
                    s,
                    &mut v,
                    work.term.view_mut((0, 0), (3, sl.len)),
                )?;
                out.columns_mut(sl.start, sl.len)
                    .copy_from(&work.term.columns(0, sl.len));
                Vector3::new(v[0], v[1], v[2])
            }
            None => Vector3::zeros(),
        };
        Ok(ProbePrediction {
            centre: contact - hit.approach * hit.stylus_radius - d + pt,
            contact,
            machine: d,
            pretravel: pt,
        })
    }
}
