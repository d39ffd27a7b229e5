//! Every generated type's DEFINITION equals the full definition regenerated from the `.msg`
//! files on disk, and the type layout matches the registry.

mod common;

use metrocell_msgs::RosMessage;

#[test]
fn every_definition_matches_the_msg_files() {
    let files = common::registry_from_files();
    let mut checked = Vec::new();
    macro_rules! check {
        ($t:ty) => {{
            let expected = files.full_definition(<$t>::ROS_TYPE).unwrap();
            assert_eq!(<$t>::DEFINITION, expected, "{}", <$t>::ROS_TYPE);
            assert_eq!(
                <$t>::ROS_TYPE,
                format!("{}/msg/{}", <$t>::PACKAGE, <$t>::NAME)
            );
            assert_eq!(
                <$t>::DDS_TYPE,
                format!("{}::msg::dds_::{}_", <$t>::PACKAGE, <$t>::NAME)
            );
            checked.push(<$t>::ROS_TYPE.to_string());
        }};
    }
    metrocell_msgs::for_each_message!(check);
    checked.sort();
    assert_eq!(checked, files.ros_type_names());
    assert_eq!(checked, metrocell_msgs::type_names());
    // The standard types the nodes use plus metrocell's own six.
    for t in [
        "std_msgs/msg/Header",
        "std_msgs/msg/String",
        "builtin_interfaces/msg/Time",
        "builtin_interfaces/msg/Duration",
        "sensor_msgs/msg/Image",
        "sensor_msgs/msg/CameraInfo",
        "sensor_msgs/msg/RegionOfInterest",
        "sensor_msgs/msg/JointState",
        "sensor_msgs/msg/Temperature",
        "sensor_msgs/msg/RelativeHumidity",
        "sensor_msgs/msg/FluidPressure",
        "geometry_msgs/msg/Point",
        "geometry_msgs/msg/PointStamped",
        "geometry_msgs/msg/Vector3",
        "geometry_msgs/msg/Quaternion",
        "geometry_msgs/msg/Pose",
        "geometry_msgs/msg/PoseWithCovariance",
        "geometry_msgs/msg/PoseWithCovarianceStamped",
        "geometry_msgs/msg/Transform",
        "geometry_msgs/msg/TransformStamped",
        "tf2_msgs/msg/TFMessage",
        "diagnostic_msgs/msg/DiagnosticArray",
        "diagnostic_msgs/msg/DiagnosticStatus",
        "diagnostic_msgs/msg/KeyValue",
        "rosgraph_msgs/msg/Clock",
        "metrocell_msgs/msg/ErrorModel",
        "metrocell_msgs/msg/FiducialDetection",
        "metrocell_msgs/msg/FiducialDetectionArray",
        "metrocell_msgs/msg/MeasuredPoint",
        "metrocell_msgs/msg/ProbeHit",
        "metrocell_msgs/msg/TrackerMeasurement",
    ] {
        assert!(checked.iter().any(|c| c == t), "{t} missing");
    }
}

#[test]
fn tracker_measurement_definition_layout() {
    use metrocell_msgs::msg::TrackerMeasurement;
    let own = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/msg/TrackerMeasurement.msg"
    ))
    .unwrap();
    let def = TrackerMeasurement::DEFINITION;
    assert!(def.starts_with(&own));
    let sep = "=".repeat(80);
    let blocks: Vec<&str> = def.lines().filter(|l| l.starts_with("MSG: ")).collect();
    // rosbag2 order: direct dependencies sorted by name, each followed by its own.
    assert_eq!(
        blocks,
        [
            "MSG: geometry_msgs/Point",
            "MSG: std_msgs/Header",
            "MSG: builtin_interfaces/Time"
        ]
    );
    assert_eq!(def.matches(&format!("\n{sep}\nMSG: ")).count(), 3);
    assert!(def.ends_with("uint32 nanosec\n"));
}

#[test]
fn defaults_and_constants_follow_the_msg() {
    use metrocell_msgs::geometry_msgs::msg::{PoseWithCovariance, Quaternion};
    use metrocell_msgs::msg::{MeasuredPoint, TrackerMeasurement};
    // geometry_msgs/Quaternion declares `float64 w 1`.
    assert_eq!(
        Quaternion::default(),
        Quaternion {
            x: 0.0,
            y: 0.0,
            z: 0.0,
            w: 1.0
        }
    );
    assert_eq!(PoseWithCovariance::default().pose.orientation.w, 1.0);
    assert_eq!(PoseWithCovariance::default().covariance, [0.0; 36]);
    assert_eq!(TrackerMeasurement::STATUS_REJECTED, 16u8);
    assert_eq!(MeasuredPoint::SOURCE_TRACKER, "tracker");
    assert_eq!(
        metrocell_msgs::diagnostic_msgs::msg::DiagnosticStatus::STALE,
        3u8
    );
    // The dynamic default agrees with the typed default.
    let dynamic =
        rosmsg::default_value(metrocell_msgs::registry(), "geometry_msgs/Quaternion").unwrap();
    assert_eq!(
        rosmsg::to_json(&dynamic),
        serde_json::to_value(Quaternion::default()).unwrap()
    );
}
