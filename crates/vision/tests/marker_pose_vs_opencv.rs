//! Marker pose from detected corners against the rendered truth and against OpenCV
//! (detectMarkers with CORNER_REFINE_SUBPIX + solvePnP(SOLVEPNP_IPPE_SQUARE)).
mod common;

use metrocell_vision::aruco::{detect_markers, DetectorParams, Dictionary};
use metrocell_vision::marker_pose::estimate_marker_pose;
use metrocell_vision::{render_view, RenderSettings, TargetItem};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// Four poses, blur 1 px and noise 2 grey levels, 16 marker poses: our translation and rotation
/// errors vs truth (RMS) are no worse than OpenCV's, and the reported covariance is consistent.
#[test]
fn marker_poses_match_truth_at_least_as_well_as_opencv() {
    let dir = common::temp_dir("marker-pose");
    let cam = common::test_camera();
    let target = common::four_marker_target();
    let dict = Dictionary::predefined("DICT_4X4_50").unwrap();
    let settings = RenderSettings {
        blur_sigma_px: 1.0,
        noise_sigma: 2.0,
        seed: 21,
        ..Default::default()
    };
    let side = 0.04;
    let (mut ours_t, mut ours_r, mut cv_t, mut cv_r, mut mahal) =
        (vec![], vec![], vec![], vec![], vec![]);
    let mut paths = Vec::new();
    let mut truths: Vec<Vec<(usize, Isometry3<f64>)>> = Vec::new();
    for (k, pose) in common::test_poses().iter().enumerate() {
        let view = render_view(&cam, pose, &target, &settings).unwrap();
        let p = dir.join(format!("pose{k}.png"));
        common::save_png(&view.image, &p);
        // Truth: marker frame (x right, y up, z out of the face) in the target frame (y down, z in).
        let truth: Vec<(usize, Isometry3<f64>)> = target
            .items
            .iter()
            .map(|it| match it {
                TargetItem::Marker {
                    id, top_left, side, ..
                } => {
                    let t_target_marker = Isometry3::from_parts(
                        Translation3::new(top_left[0] + side / 2.0, top_left[1] + side / 2.0, 0.0),
                        UnitQuaternion::from_axis_angle(&Vector3::x_axis(), std::f64::consts::PI),
                    );
                    (*id, pose * t_target_marker)
                }
                _ => unreachable!(),
            })
            .collect();
        let found = detect_markers(
            &image::open(&p).unwrap().to_luma8(),
            &dict,
            &DetectorParams::default(),
        )
        .unwrap();
        assert_eq!(found.len(), 4);
        for m in &found {
            let est =
                estimate_marker_pose(&cam, &m.corners, &m.corner_covariance, side, 0.1).unwrap();
            let tr = truth.iter().find(|t| t.0 == m.id).unwrap().1;
            let dt = est.camera_from_marker.translation.vector - tr.translation.vector;
            let dr = (est.camera_from_marker.rotation * tr.rotation.inverse()).scaled_axis();
            ours_t.push(dt.norm_squared());
            ours_r.push(dr.norm_squared());
            let e = nalgebra::SVector::<f64, 6>::from_column_slice(&[
                dt.x, dt.y, dt.z, dr.x, dr.y, dr.z,
            ]);
            mahal.push((e.transpose() * est.covariance.try_inverse().unwrap() * e)[(0, 0)]);
            assert!(
                est.reprojection_rms_px < 0.2,
                "reprojection {}",
                est.reprojection_rms_px
            );
        }
        paths.push(p.to_str().unwrap().to_string());
        truths.push(truth);
    }
    let metrocell_vision::Distortion::BrownConrady(d) = cam.distortion else {
        panic!("the test camera is Brown–Conrady");
    };
    let nums: Vec<String> = [
        side, cam.fx, cam.fy, cam.cx, cam.cy, d[0], d[1], d[2], d[3], d[4],
    ]
    .iter()
    .map(|v| v.to_string())
    .collect();
    let mut args = vec!["pose", "DICT_4X4_50"];
    args.extend(nums.iter().map(|s| s.as_str()));
    args.extend(paths.iter().map(|s| s.as_str()));
    let cv = common::run_py("aruco_reference.py", &args);
    for (k, truth) in truths.iter().enumerate() {
        let list = cv[k].as_array().unwrap();
        assert_eq!(list.len(), 4, "OpenCV poses in {}", paths[k]);
        for m in list {
            let v = |key: &str| {
                Vector3::new(
                    m[key][0].as_f64().unwrap(),
                    m[key][1].as_f64().unwrap(),
                    m[key][2].as_f64().unwrap(),
                )
            };
            let tr = truth
                .iter()
                .find(|t| t.0 == m["id"].as_u64().unwrap() as usize)
                .unwrap()
                .1;
            cv_t.push((v("tvec") - tr.translation.vector).norm_squared());
            cv_r.push(
                (UnitQuaternion::from_scaled_axis(v("rvec")) * tr.rotation.inverse())
                    .scaled_axis()
                    .norm_squared(),
            );
        }
    }
    let (ot, or, ct, cr) = (
        common::rms(&ours_t),
        common::rms(&ours_r),
        common::rms(&cv_t),
        common::rms(&cv_r),
    );
    let m6 = mahal.iter().sum::<f64>() / mahal.len() as f64;
    eprintln!(
        "marker pose RMS error vs truth: ours {:.3} mm / {:.4} deg, OpenCV {:.3} mm / {:.4} deg; mean e'C^-1e {m6:.2} (6 if calibrated)",
        ot * 1e3,
        or.to_degrees(),
        ct * 1e3,
        cr.to_degrees()
    );
    assert!(
        ot <= ct && or <= cr,
        "ours {ot} m / {or} rad vs OpenCV {ct} m / {cr} rad"
    );
    assert!(
        m6 > 1.0 && m6 < 30.0,
        "pose covariance inconsistent: mean e'C^-1e = {m6:.2}"
    );
}
