//! What the tool camera and the fiducial node did during the demo, read back from the bag: each
//! frame the twin rendered (`/camera/image_raw`) against the fiducial node's detections in it
//! (`/fiducials`, matched by the image's stamp, which the detections' header copies), and how
//! well the plate's markers repeat.
//!
//! The twin places the same plate at the same pose in front of the *nominal* camera at every
//! dwell (crates/model/src/fiducial_plate.rs), so each marker's measured position in the camera
//! frame differs from frame to frame only by the machine's error at that dwell (a few µm in
//! this cell) and the measurement's noise: its spread over the run is the camera's pose
//! repeatability, set here beside the σ the node states for each pose.

use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;

use metrocell_bagtools::BagSource;
use metrocell_model::PLATE_MARKERS;
use metrocell_msgs::msg::FiducialDetectionArray;
use metrocell_msgs::sensor_msgs::msg::Image;

/// The twin's frames (the shared topic list) and the fiducial node's detections of them (its
/// default output; the demo's launch file does not remap it).
pub use metrocell_msgs::topics::{CAMERA_IMAGE as IMAGE_TOPIC, FIDUCIALS as DETECTIONS_TOPIC};

/// Frames and detections of one recording.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct CameraSummary {
    /// Frames in the bag, and their size (px).
    pub frames: u64,
    pub frame_size: Option<(u32, u32)>,
    /// Frames with a detection message of the same stamp.
    pub measured: u64,
    /// Measured frames in which every marker of the plate was found with a pose.
    pub whole_plate: u64,
    /// Marker poses in all, and those whose covariance diagonal is not finite and positive.
    pub poses: u64,
    pub poses_without_finite_covariance: u64,
    /// Detection messages whose stamp matches no frame of the bag.
    pub unmatched_detections: u64,
    /// Over the markers, the RMS of each one's standard deviation over the run, per camera
    /// axis (x right, y down, z along the optical axis) [m].
    pub repeatability: Option<[f64; 3]>,
    /// Median of the σ the node states for a marker position, per axis [m].
    pub stated_sigma: Option<[f64; 3]>,
}

type Stamp = (i32, u32);

/// Reads the frames and detections of `bag` (a bag without them gives a summary of zeros).
pub fn summarise(bag: &Path) -> anyhow::Result<CameraSummary> {
    let mut source = BagSource::open(bag)?;
    source.subscribe::<Image>(IMAGE_TOPIC)?;
    source.subscribe::<FiducialDetectionArray>(DETECTIONS_TOPIC)?;
    let mut frames: BTreeSet<Stamp> = BTreeSet::new();
    let mut frame_size = None;
    let mut detections: BTreeMap<Stamp, FiducialDetectionArray> = BTreeMap::new();
    for m in source.messages()? {
        let m = m?;
        if m.topic == IMAGE_TOPIC {
            let image: Image = m.decode()?;
            frame_size = Some((image.width, image.height));
            frames.insert((image.header.stamp.sec, image.header.stamp.nanosec));
        } else {
            let d: FiducialDetectionArray = m.decode()?;
            detections.insert((d.header.stamp.sec, d.header.stamp.nanosec), d);
        }
    }
    let mut s = CameraSummary {
        frames: frames.len() as u64,
        frame_size,
        ..Default::default()
    };
    let mut positions: BTreeMap<i32, Vec<[f64; 3]>> = BTreeMap::new();
    let mut sigmas: [Vec<f64>; 3] = Default::default();
    for (stamp, d) in &detections {
        if !frames.contains(stamp) {
            s.unmatched_detections += 1;
            continue;
        }
        s.measured += 1;
        let posed: BTreeSet<i32> = d
            .detections
            .iter()
            .filter(|t| t.has_pose)
            .map(|t| t.id)
            .collect();
        if (0..PLATE_MARKERS as i32).all(|id| posed.contains(&id)) {
            s.whole_plate += 1;
        }
        for t in d.detections.iter().filter(|t| t.has_pose) {
            s.poses += 1;
            let c = &t.pose.covariance;
            let diagonal = [c[0], c[7], c[14]];
            if !c.iter().all(|v| v.is_finite()) || !diagonal.iter().all(|v| *v > 0.0) {
                s.poses_without_finite_covariance += 1;
                continue;
            }
            for (axis, v) in diagonal.iter().enumerate() {
                sigmas[axis].push(v.sqrt());
            }
            let p = &t.pose.pose.position;
            positions.entry(t.id).or_default().push([p.x, p.y, p.z]);
        }
    }
    s.repeatability = pooled_spread(positions.values());
    s.stated_sigma = sigmas
        .iter()
        .map(|v| median(v))
        .collect::<Option<Vec<f64>>>()
        .map(|v| [v[0], v[1], v[2]]);
    Ok(s)
}

/// RMS over the groups of each group's sample standard deviation, per axis (groups of fewer
/// than two positions have none and are left out).
fn pooled_spread<'a>(groups: impl Iterator<Item = &'a Vec<[f64; 3]>>) -> Option<[f64; 3]> {
    let mut sum = [0.0; 3];
    let mut n = 0;
    for g in groups.filter(|g| g.len() >= 2) {
        for (axis, total) in sum.iter_mut().enumerate() {
            let mean = g.iter().map(|p| p[axis]).sum::<f64>() / g.len() as f64;
            *total +=
                g.iter().map(|p| (p[axis] - mean).powi(2)).sum::<f64>() / (g.len() - 1) as f64;
        }
        n += 1;
    }
    (n > 0).then(|| sum.map(|v| (v / n as f64).sqrt()))
}

fn median(v: &[f64]) -> Option<f64> {
    let mut v = v.to_vec();
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied()
}

/// The fiducial node's own counts (its `/diagnostics` values), which say why a frame has no
/// detection: a live detector measures only the newest frame and counts the older ones it
/// skipped as dropped.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FiducialNodeCounts {
    pub processed: Option<u64>,
    pub dropped: Option<u64>,
    pub rejected: Option<u64>,
    pub mean_latency_ms: Option<f64>,
}

impl FiducialNodeCounts {
    /// Takes the values of one of the node's diagnostics statuses (key, value).
    pub fn update<'a>(&mut self, values: impl Iterator<Item = (&'a str, &'a str)>) {
        for (key, value) in values {
            match key {
                "frames_processed" => self.processed = value.parse().ok(),
                "frames_dropped" => self.dropped = value.parse().ok(),
                "frames_rejected" => self.rejected = value.parse().ok(),
                "mean_detection_latency_ms" => self.mean_latency_ms = value.parse().ok(),
                _ => {}
            }
        }
    }
}

/// The summary in words, against the `published` frames of the twin (its own count).
pub fn describe(s: &CameraSummary, published: Option<u64>, node: &FiducialNodeCounts) -> String {
    let size = s
        .frame_size
        .map_or(String::new(), |(w, h)| format!(" ({w}×{h})"));
    if published.is_none() && s.frames == 0 {
        return "camera: the cell has none (or its frames were not rendered)".to_string();
    }
    let mut text = match published {
        Some(n) if n == s.frames => {
            format!("camera: the twin rendered {n} frames{size}, all in the bag")
        }
        Some(n) => format!(
            "camera: the twin rendered {n} frames{size}, {} in the bag",
            s.frames
        ),
        None => format!("camera: {} frames{size} in the bag", s.frames),
    };
    if s.frames == 0 {
        return text;
    }
    let missed = s.frames - s.measured;
    text.push_str(&format!(
        "; the fiducial node measured {} of them{}, {} with all {PLATE_MARKERS} plate markers ({} marker poses, {})",
        s.measured,
        node.mean_latency_ms.map_or(String::new(), |ms| format!(" in {ms:.1} ms each on average")),
        s.whole_plate,
        s.poses,
        match s.poses_without_finite_covariance {
            0 => "each with a finite covariance".to_string(),
            n => format!("{n} without a finite covariance"),
        }
    ));
    if missed > 0 {
        let (dropped, rejected) = (node.dropped.unwrap_or(0), node.rejected.unwrap_or(0));
        let mut why = Vec::new();
        if dropped > 0 {
            why.push(format!("the node skipped {dropped} queued behind a newer frame (it measures the newest only)"));
        }
        if rejected > 0 {
            why.push(format!("rejected {rejected}"));
        }
        let unexplained = missed.saturating_sub(dropped + rejected);
        if unexplained > 0 {
            why.push(format!(
                "{unexplained} never reached it (it reads frames best effort, keeping the last 5)"
            ));
        }
        text.push_str(&format!("; missed {missed}: {}", why.join(", ")));
    }
    if s.unmatched_detections > 0 {
        text.push_str(&format!(
            "; {} detections match no recorded frame",
            s.unmatched_detections
        ));
    }
    if let (Some(r), Some(sigma)) = (s.repeatability, s.stated_sigma) {
        let um = |v: [f64; 3]| {
            format!(
                "x {:.1}, y {:.1}, z {:.1} µm",
                v[0] * 1e6,
                v[1] * 1e6,
                v[2] * 1e6
            )
        };
        text.push_str(&format!(
            "; a marker's position repeats to {} (1σ over the run; the node states σ {})",
            um(r),
            um(sigma)
        ));
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_pools_the_markers_and_needs_two_positions() {
        // marker a: x 1, 3 → sd √2; marker b: x 5, 5 → sd 0; pooled √((2 + 0)/2) = 1
        let a = vec![[1.0, 0.0, 2.0], [3.0, 0.0, 2.0]];
        let b = vec![[5.0, 1.0, 0.0], [5.0, 1.0, 0.0]];
        let single = vec![[100.0, 100.0, 100.0]];
        let r = pooled_spread([&a, &b, &single].into_iter()).unwrap();
        assert!(
            (r[0] - 1.0).abs() < 1e-12 && r[1] == 0.0 && r[2] == 0.0,
            "{r:?}"
        );
        assert_eq!(pooled_spread([&single].into_iter()), None);
    }

    #[test]
    fn missed_frames_are_counted_and_explained() {
        let s = CameraSummary {
            frames: 10,
            frame_size: Some((640, 480)),
            measured: 8,
            whole_plate: 8,
            poses: 32,
            ..Default::default()
        };
        let node = FiducialNodeCounts {
            processed: Some(8),
            dropped: Some(2),
            rejected: Some(0),
            mean_latency_ms: Some(5.0),
        };
        let text = describe(&s, Some(10), &node);
        assert!(text.starts_with("camera: the twin rendered 10 frames (640×480), all in the bag; the fiducial node measured 8 of them in 5.0 ms each"), "{text}");
        assert!(
            text.contains("missed 2: the node skipped 2 queued behind a newer frame"),
            "{text}"
        );
        let text = describe(
            &CameraSummary {
                measured: 10,
                ..s.clone()
            },
            Some(12),
            &node,
        );
        assert!(
            text.contains("12 frames (640×480), 10 in the bag") && !text.contains("missed"),
            "{text}"
        );
    }
}
