//! Bulk message types: those carrying a variable-length byte array at top level
//! (`sensor_msgs/Image` data, `CompressedImage`, `PointCloud2`), megabytes per message, which
//! readers give short queues (the recorder's `bulk_queue_depth`, the dashboard's frames).

/// Whether `ros_type` (`pkg/msg/Type`, known to metrocell) is a bulk type (module doc).
pub fn is_bulk_type(ros_type: &str) -> bool {
    use rosmsg::{ArrayKind, BaseType, Primitive};
    metrocell_msgs::registry()
        .get(ros_type)
        .is_some_and(|spec| {
            spec.fields.iter().any(|f| {
                matches!(
                    f.ty.base,
                    BaseType::Primitive(Primitive::UInt8 | Primitive::Byte | Primitive::Int8)
                ) && matches!(f.ty.array, ArrayKind::Unbounded | ArrayKind::Bounded(_))
            })
        })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn images_are_bulk_and_measurements_are_not() {
        assert!(is_bulk_type("sensor_msgs/msg/Image"));
        assert!(
            !is_bulk_type("sensor_msgs/msg/CameraInfo")
                && !is_bulk_type("metrocell_msgs/msg/TrackerMeasurement")
        );
        assert!(!is_bulk_type("no_such/msg/Type"));
    }
}
