//! What the node does with each input, shared by the live run and the bag replay so both give
//! the same numbers: parameters → [`ProbeProcessor`]; a trigger (JointState) becomes a ProbeHit
//! and, when a nominal (PointStamped) belongs to it, a MeasuredPoint (point_id `<probe_id>_<n>`,
//! n counting accepted triggers from 1).
//!
//! Pairing is by header stamp, not by arrival, so a live node (which may take a cycle's nominals
//! and triggers in either order) pairs exactly as a replay in log-time order does: a trigger at
//! stamp t takes the newest held nominal stamped ≤ t; older held nominals were never used and are
//! dropped; nominals stamped after t wait for a later trigger. A rejected trigger uses up its
//! nominal too, so the next trigger can never be measured against another point's nominal.
//! Header of both outputs: the trigger's stamp, frame_id = the `frame_id` parameter.

use std::collections::VecDeque;

use metrocell_msgs::geometry_msgs::msg::{Point, PointStamped, Vector3 as Vector3Msg};
use metrocell_msgs::msg::{MeasuredPoint, ProbeHit};
use metrocell_msgs::sensor_msgs::msg::JointState;
use metrocell_node::{ParamDecl, Parameters};
use nalgebra::Vector3;

use crate::compensation::{approach_direction, compensate, ProbeError, ProbeModel};

pub fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new(
            "probe_id",
            "probe".to_string(),
            "probe name written into ProbeHit",
        ),
        ParamDecl::new(
            "frame_id",
            "machine".to_string(),
            "machine frame of the axis readings",
        ),
        ParamDecl::new(
            "axes",
            vec!["x".to_string(), "y".to_string(), "z".to_string()],
            "JointState names of the X, Y, Z axes",
        ),
        ParamDecl::new("stylus_radius", 0.0015, "effective ball radius [m]").with_range(0.0, 0.1),
        ParamDecl::new("stylus_radius_std", 0.5e-6, "its standard uncertainty [m]")
            .with_range(0.0, 1e-3),
        ParamDecl::new(
            "stylus_offset",
            vec![0.0, 0.0, 0.0],
            "axis readings → ball centre offset [m] (x, y, z)",
        ),
        ParamDecl::new(
            "pretravel",
            vec![0.0, 0.0, 0.0, 0.0],
            "probe_pretravel (p0, a, b, pz) [m]",
        ),
        ParamDecl::new(
            "pretravel_std",
            vec![1e-6, 1e-6, 1e-6, 1e-6],
            "their standard uncertainties [m]",
        ),
        ParamDecl::new("lobes", 3i64, "pretravel lobe count").with_range(1.0, 12.0),
        ParamDecl::new(
            "axis_std",
            1e-6,
            "standard uncertainty of one axis reading [m]",
        )
        .with_range(0.0, 1e-3),
        ParamDecl::new(
            "default_approach",
            vec![0.0, 0.0, -1.0],
            "approach direction when the trigger has no velocity",
        ),
    ]
}

fn vec3(v: &[f64], name: &str) -> Result<Vector3<f64>, String> {
    (v.len() == 3)
        .then(|| Vector3::new(v[0], v[1], v[2]))
        .ok_or_else(|| format!("parameter {name}: expected 3 values, got {}", v.len()))
}

pub struct ProbeProcessor {
    model: ProbeModel,
    axes: Vec<String>,
    fallback: Vector3<f64>,
    probe_id: String,
    frame_id: String,
    /// Nominals not yet paired, in arrival order (at most [`MAX_HELD_NOMINALS`]).
    nominals: VecDeque<PointStamped>,
    count: u64,
}

/// Nominals held without a trigger beyond this many are dropped oldest first (a nominal stream
/// without triggers must not grow the node's memory).
const MAX_HELD_NOMINALS: usize = 256;

impl ProbeProcessor {
    pub fn from_parameters(p: &Parameters) -> Result<Self, Box<dyn std::error::Error>> {
        let four = |name: &str| -> Result<[f64; 4], Box<dyn std::error::Error>> {
            let v = p.get::<Vec<f64>>(name)?;
            v.clone()
                .try_into()
                .map_err(|_| format!("parameter {name}: expected 4 values, got {}", v.len()).into())
        };
        let model = ProbeModel {
            stylus_radius: p.get("stylus_radius")?,
            stylus_radius_std: p.get("stylus_radius_std")?,
            stylus_offset: vec3(&p.get::<Vec<f64>>("stylus_offset")?, "stylus_offset")?,
            pretravel: four("pretravel")?,
            pretravel_std: four("pretravel_std")?,
            lobes: p.get::<i64>("lobes")? as usize,
            axis_std: p.get("axis_std")?,
        };
        let axes: Vec<String> = p.get("axes")?;
        if axes.len() != 3 {
            return Err(format!("parameter axes: expected 3 names (X, Y, Z), got {axes:?}").into());
        }
        Ok(ProbeProcessor {
            model,
            axes,
            fallback: vec3(&p.get::<Vec<f64>>("default_approach")?, "default_approach")?,
            probe_id: p.get("probe_id")?,
            frame_id: p.get("frame_id")?,
            nominals: VecDeque::new(),
            count: 0,
        })
    }

    /// Accepted triggers so far.
    pub fn count(&self) -> u64 {
        self.count
    }

    /// Hold `n` for the trigger it belongs to (see the module doc).
    pub fn nominal(&mut self, n: PointStamped) {
        if self.nominals.len() == MAX_HELD_NOMINALS {
            self.nominals.pop_front();
        }
        self.nominals.push_back(n);
    }

    /// The newest held nominal stamped at or before `stamp_ns`; it and every older one leave.
    fn take_nominal(&mut self, stamp_ns: i64) -> Option<PointStamped> {
        let newest = self
            .nominals
            .iter()
            .enumerate()
            .filter(|(_, n)| n.header.stamp.nanos() <= stamp_ns)
            .max_by_key(|(_, n)| n.header.stamp.nanos())
            .map(|(i, _)| i);
        let taken = newest.and_then(|i| self.nominals.remove(i));
        self.nominals.retain(|n| n.header.stamp.nanos() > stamp_ns);
        taken
    }

    /// One trigger → its ProbeHit and, if a nominal belongs to it, the MeasuredPoint. A rejected
    /// trigger uses up its nominal as well; the error names the trigger's stamp.
    pub fn trigger(&mut self, t: &JointState) -> Result<(ProbeHit, Option<MeasuredPoint>), String> {
        let nominal = self.take_nominal(t.header.stamp.nanos());
        let result = (|| -> Result<_, ProbeError> {
            let mut pos = [0.0; 3];
            let mut vel = [0.0; 3];
            for (k, name) in self.axes.iter().enumerate() {
                let i = t
                    .name
                    .iter()
                    .position(|n| n == name)
                    .ok_or_else(|| ProbeError::MissingAxis(name.clone(), t.name.clone()))?;
                let value = *t
                    .position
                    .get(i)
                    .ok_or_else(|| ProbeError::MissingAxis(name.clone(), t.name.clone()))?;
                if !value.is_finite() {
                    return Err(ProbeError::NonFinite {
                        axis: name.clone(),
                        value,
                    });
                }
                pos[k] = value;
                vel[k] = t.velocity.get(i).copied().unwrap_or(0.0);
            }
            let u = approach_direction(Some(Vector3::from(vel)), self.fallback)?;
            Ok((pos, compensate(&self.model, Vector3::from(pos), u)?))
        })();
        let (pos, hit) = result.map_err(|e| {
            format!(
                "trigger at {}.{:09}: {e}",
                t.header.stamp.sec, t.header.stamp.nanosec
            )
        })?;
        self.count += 1;
        let mut header = t.header.clone();
        header.frame_id = self.frame_id.clone();
        let p = |v: Vector3<f64>| Point {
            x: v.x,
            y: v.y,
            z: v.z,
        };
        let mut cov = [0.0; 9];
        cov.copy_from_slice(hit.covariance.transpose().as_slice());
        let probe_hit = ProbeHit {
            header: header.clone(),
            probe_id: self.probe_id.clone(),
            axis_names: self.axes.clone(),
            axis_positions: pos.to_vec(),
            stylus_centre: p(hit.stylus_centre),
            approach_direction: Vector3Msg {
                x: hit.approach.x,
                y: hit.approach.y,
                z: hit.approach.z,
            },
            stylus_radius: self.model.stylus_radius,
            pretravel: hit.pretravel,
            surface_point: p(hit.surface_point),
            covariance: cov,
        };
        let point = nominal.map(|n| MeasuredPoint {
            header,
            point_id: format!("{}_{}", self.probe_id, self.count),
            source: "probe".into(),
            nominal: n.point,
            measured: p(hit.surface_point),
            covariance: cov,
        });
        Ok((probe_hit, point))
    }
}
