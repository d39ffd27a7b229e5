//! `metrocell-probe`: touch-probe triggers → compensated measured points.
//!
//! Subscribes `probe/trigger` (sensor_msgs/JointState: the axis positions latched at the trigger
//! [m], header.stamp = trigger time; `velocity`, when present, gives the approach direction) and
//! `probe/nominal` (geometry_msgs/PointStamped: the nominal surface point of the next hit, optional).
//! Publishes `probe/hits` (metrocell_msgs/ProbeHit) for every trigger and `measured_points`
//! (metrocell_msgs/MeasuredPoint, source "probe") for triggers with a nominal.
//! Compensation: see `metrocell_probe_node::compensation`.
//!
//!   metrocell-probe --ros-args -p stylus_radius:=0.0015 -p pretravel:="[10e-6, 0.0, 0.0, 4e-6]"

use std::time::Duration;

use metrocell_msgs::geometry_msgs::msg::{Point, PointStamped, Vector3 as Vector3Msg};
use metrocell_msgs::msg::{MeasuredPoint, ProbeHit};
use metrocell_msgs::sensor_msgs::msg::JointState;
use metrocell_node::{qos, MetrocellNode, ParamDecl};
use metrocell_probe_node::compensation::{approach_direction, compensate, ProbeError, ProbeModel};
use nalgebra::Vector3;

fn declarations() -> Vec<ParamDecl> {
    vec![
        ParamDecl::new("probe_id", "probe".to_string(), "probe name written into ProbeHit"),
        ParamDecl::new("frame_id", "machine".to_string(), "machine frame of the axis readings"),
        ParamDecl::new("axes", vec!["x".to_string(), "y".to_string(), "z".to_string()], "JointState names of the X, Y, Z axes"),
        ParamDecl::new("stylus_radius", 0.0015, "effective ball radius [m]").with_range(0.0, 0.1),
        ParamDecl::new("stylus_radius_std", 0.5e-6, "its standard uncertainty [m]").with_range(0.0, 1e-3),
        ParamDecl::new("stylus_offset", vec![0.0, 0.0, 0.0], "axis readings → ball centre offset [m] (x, y, z)"),
        ParamDecl::new("pretravel", vec![0.0, 0.0, 0.0, 0.0], "probe_pretravel (p0, a, b, pz) [m]"),
        ParamDecl::new("pretravel_std", vec![1e-6, 1e-6, 1e-6, 1e-6], "their standard uncertainties [m]"),
        ParamDecl::new("lobes", 3i64, "pretravel lobe count"),
        ParamDecl::new("axis_std", 1e-6, "standard uncertainty of one axis reading [m]").with_range(0.0, 1e-3),
        ParamDecl::new("default_approach", vec![0.0, 0.0, -1.0], "approach direction when the trigger has no velocity"),
    ]
}

fn vec3(v: &[f64], name: &str) -> Result<Vector3<f64>, String> {
    (v.len() == 3).then(|| Vector3::new(v[0], v[1], v[2])).ok_or_else(|| format!("parameter {name}: expected 3 values, got {}", v.len()))
}

fn main() -> std::process::ExitCode {
    match run() {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("metrocell-probe: {e}");
            std::process::ExitCode::FAILURE
        }
    }
}

fn run() -> Result<(), Box<dyn std::error::Error>> {
    let (mut node, _) = MetrocellNode::from_env_args("probe", declarations())?;
    let four = |name: &str| -> Result<[f64; 4], Box<dyn std::error::Error>> {
        let v = node.param::<Vec<f64>>(name)?;
        v.clone().try_into().map_err(|_| format!("parameter {name}: expected 4 values, got {}", v.len()).into())
    };
    let model = ProbeModel {
        stylus_radius: node.param("stylus_radius")?,
        stylus_radius_std: node.param("stylus_radius_std")?,
        stylus_offset: vec3(&node.param::<Vec<f64>>("stylus_offset")?, "stylus_offset")?,
        pretravel: four("pretravel")?,
        pretravel_std: four("pretravel_std")?,
        lobes: node.param::<i64>("lobes")?.clamp(1, 12) as usize,
        axis_std: node.param("axis_std")?,
    };
    let axes: Vec<String> = node.param("axes")?;
    if axes.len() != 3 {
        return Err(format!("parameter axes: expected 3 names (X, Y, Z), got {axes:?}").into());
    }
    let fallback = vec3(&node.param::<Vec<f64>>("default_approach")?, "default_approach")?;
    let probe_id: String = node.param("probe_id")?;
    let frame_id: String = node.param("frame_id")?;

    let triggers = node.subscription::<JointState>("probe/trigger", qos::reliable())?;
    let nominals = node.subscription::<PointStamped>("probe/nominal", qos::reliable())?;
    let hits = node.publisher::<ProbeHit>("probe/hits", qos::reliable())?;
    let points = node.publisher::<MeasuredPoint>("measured_points", qos::reliable())?;
    let diagnostics = node.diagnostics();
    let token = node.shutdown_token();
    let mut nominal: Option<PointStamped> = None;
    let mut count = 0u64;
    while !token.is_triggered() {
        while let Ok(Some((n, _))) = nominals.take() {
            nominal = Some(n);
        }
        while let Ok(Some((t, _))) = triggers.take() {
            let result = (|| -> Result<_, ProbeError> {
                let mut pos = [0.0; 3];
                let mut vel = [0.0; 3];
                for (k, name) in axes.iter().enumerate() {
                    let i = t.name.iter().position(|n| n == name).ok_or_else(|| ProbeError::MissingAxis(name.clone(), t.name.clone()))?;
                    let value = *t.position.get(i).ok_or_else(|| ProbeError::MissingAxis(name.clone(), t.name.clone()))?;
                    if !value.is_finite() {
                        return Err(ProbeError::NonFinite { axis: name.clone(), value });
                    }
                    pos[k] = value;
                    vel[k] = t.velocity.get(i).copied().unwrap_or(0.0);
                }
                let u = approach_direction(Some(Vector3::from(vel)), fallback)?;
                Ok((pos, compensate(&model, Vector3::from(pos), u)?))
            })();
            let (pos, hit) = match result {
                Ok(r) => r,
                Err(e) => {
                    diagnostics.add_count("triggers_rejected", 1);
                    node.warn(format!("trigger at {}.{:09}: {e}", t.header.stamp.sec, t.header.stamp.nanosec));
                    continue;
                }
            };
            count += 1;
            let mut header = t.header.clone();
            header.frame_id = frame_id.clone();
            let p = |v: Vector3<f64>| Point { x: v.x, y: v.y, z: v.z };
            let mut cov = [0.0; 9];
            cov.copy_from_slice(hit.covariance.transpose().as_slice());
            let _ = hits.publish(ProbeHit {
                header: header.clone(),
                probe_id: probe_id.clone(),
                axis_names: axes.clone(),
                axis_positions: pos.to_vec(),
                stylus_centre: p(hit.stylus_centre),
                approach_direction: Vector3Msg { x: hit.approach.x, y: hit.approach.y, z: hit.approach.z },
                stylus_radius: model.stylus_radius,
                pretravel: hit.pretravel,
                surface_point: p(hit.surface_point),
                covariance: cov,
            });
            if let Some(n) = nominal.take() {
                let _ = points.publish(MeasuredPoint {
                    header,
                    point_id: format!("{probe_id}_{count}"),
                    source: "probe".into(),
                    nominal: n.point,
                    measured: p(hit.surface_point),
                    covariance: cov,
                });
                diagnostics.add_count("points_published", 1);
            }
            diagnostics.add_count("triggers", 1);
            diagnostics.ok(format!("{count} hits"));
        }
        token.wait_timeout(Duration::from_millis(2));
    }
    Ok(())
}
