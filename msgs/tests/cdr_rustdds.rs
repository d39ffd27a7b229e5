//! For every generated type: a sample value with every field non-default, serialised by
//! RustDDS's CDR serializer from the typed struct, is byte-identical to the dynamic codec's
//! encoding of the same value, and both decode back to equal values.

use byteorder::LittleEndian;
use metrocell_msgs::RosMessage;

fn check<T: RosMessage>() -> usize {
    let registry = metrocell_msgs::registry();
    // Seed 7, or the next seed whose sample is not the default (a lone bool can draw false).
    let default = rosmsg::default_value(registry, T::ROS_TYPE).unwrap();
    let sample = (7..40)
        .map(|seed| rosmsg::sample_value(registry, T::ROS_TYPE, seed).unwrap())
        .find(|v| *v != default)
        .unwrap_or(default);
    if registry
        .get(T::ROS_TYPE)
        .is_some_and(|spec| spec.fields.is_empty())
    {
        // No fields (std_msgs/Empty, rcl_interfaces/ParameterType): no non-default sample
        // exists; the typed struct's rosidl placeholder byte must equal the dynamic encoding.
        let dynamic = rosmsg::encode(registry, T::ROS_TYPE, &sample).unwrap();
        let mut rustdds_bytes = rosmsg::cdr::CDR_LE_HEADER.to_vec();
        rustdds_bytes
            .extend(rustdds::serialization::to_vec::<T, LittleEndian>(&T::default()).unwrap());
        assert_eq!(
            (rustdds_bytes.as_slice(), dynamic.len()),
            (dynamic.as_slice(), 5),
            "{}: one placeholder byte",
            T::ROS_TYPE
        );
        assert_eq!(
            rosmsg::decode(registry, T::ROS_TYPE, &rustdds_bytes).unwrap(),
            sample,
            "{}",
            T::ROS_TYPE
        );
        return dynamic.len();
    }
    // Dynamic value → typed struct through JSON (exercises the serde field mapping too).
    let typed: T = serde_json::from_value(rosmsg::to_json(&sample)).unwrap_or_else(|e| {
        panic!(
            "{}: JSON of the sample does not fit the struct: {e}",
            T::ROS_TYPE
        )
    });
    assert_ne!(
        typed,
        T::default(),
        "{}: sample equals the default",
        T::ROS_TYPE
    );

    let dynamic = rosmsg::encode(registry, T::ROS_TYPE, &sample).unwrap();
    let mut rustdds_bytes = rosmsg::cdr::CDR_LE_HEADER.to_vec();
    rustdds_bytes.extend(rustdds::serialization::to_vec::<T, LittleEndian>(&typed).unwrap());
    assert_eq!(
        rustdds_bytes,
        dynamic,
        "{}: RustDDS and dynamic CDR differ",
        T::ROS_TYPE
    );

    let (back, used) =
        rustdds::serialization::from_bytes::<T, LittleEndian>(&dynamic[4..]).unwrap();
    assert_eq!(back, typed, "{}", T::ROS_TYPE);
    assert_eq!(used, dynamic.len() - 4, "{}", T::ROS_TYPE);
    assert_eq!(
        rosmsg::decode(registry, T::ROS_TYPE, &rustdds_bytes).unwrap(),
        sample,
        "{}",
        T::ROS_TYPE
    );
    // Big-endian: RustDDS's bytes behind a CDR_BE header decode to the same value.
    let mut be = rosmsg::cdr::CDR_BE_HEADER.to_vec();
    be.extend(rustdds::serialization::to_vec::<T, byteorder::BigEndian>(&typed).unwrap());
    assert_eq!(
        rosmsg::decode(registry, T::ROS_TYPE, &be).unwrap(),
        sample,
        "{} (big-endian)",
        T::ROS_TYPE
    );
    // Typed → JSON → dynamic gives the same value as well.
    let json = serde_json::to_value(&typed).unwrap();
    assert_eq!(
        rosmsg::from_json(registry, T::ROS_TYPE, &json).unwrap(),
        sample,
        "{}",
        T::ROS_TYPE
    );
    dynamic.len()
}

#[test]
fn rustdds_and_dynamic_codec_agree_for_every_type() {
    let mut n = 0;
    macro_rules! each {
        ($t:ty) => {{
            check::<$t>();
            n += 1;
        }};
    }
    metrocell_msgs::for_each_message!(each);
    assert_eq!(n, metrocell_msgs::type_names().len());
}

#[test]
fn image_data_goes_through_serialize_bytes_with_the_same_bytes() {
    use metrocell_msgs::sensor_msgs::msg::Image;
    let img = Image {
        height: 1,
        width: 3,
        encoding: "mono8".into(),
        step: 3,
        data: vec![1, 2, 3],
        ..Default::default()
    };
    let bytes = rustdds::serialization::to_vec::<Image, LittleEndian>(&img).unwrap();
    // ... step (u32) at the end of the fixed part, then u32 count 3 and the raw bytes.
    assert_eq!(&bytes[bytes.len() - 7..], &[3, 0, 0, 0, 1, 2, 3]);
    assert_eq!(
        serde_json::to_value(&img).unwrap()["data"],
        serde_json::json!([1, 2, 3])
    );
}
