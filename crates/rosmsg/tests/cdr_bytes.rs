//! Hand-checked CDR bytes and codec error cases.

use rosmsg::{decode, encode, from_yaml_str, sample_value, to_json, Registry, Value};

fn registry() -> Registry {
    let mut r = Registry::new();
    r.add_msg("builtin_interfaces", "Time", "int32 sec\nuint32 nanosec\n")
        .unwrap();
    r.add_msg(
        "std_msgs",
        "Header",
        "builtin_interfaces/Time stamp\nstring frame_id\n",
    )
    .unwrap();
    r.add_msg(
        "sensor_msgs",
        "Temperature",
        "std_msgs/Header header\nfloat64 temperature\nfloat64 variance\n",
    )
    .unwrap();
    r.add_msg("t", "U8F64", "uint8 a\nfloat64 b\n").unwrap();
    r.add_msg("t", "Str", "string s\nuint16 u\n").unwrap();
    r.add_msg("t", "Seq", "int32[] v\nfloat64[2] f\n").unwrap();
    r.add_msg("t", "Nested", "uint8 x\nbuiltin_interfaces/Time t\n")
        .unwrap();
    r.add_msg("t", "Bounded", "string<=3 s\nint8[<=2] v\n")
        .unwrap();
    r.add_msg("t", "Wide", "wstring w\nfloat32 f 2.5\nbool b true\n")
        .unwrap();
    r.add_msg("t", "Items", "Nested[] items\nstring<=4 tag\n")
        .unwrap();
    r.check().unwrap();
    r
}

fn yaml(r: &Registry, ty: &str, text: &str) -> Value {
    from_yaml_str(r, ty, text).unwrap()
}

#[test]
fn uint8_then_float64_pads_to_8_after_the_header() {
    let r = registry();
    let v = yaml(&r, "t/U8F64", "{a: 1, b: 1.5}");
    let bytes = encode(&r, "t/U8F64", &v).unwrap();
    assert_eq!(
        bytes,
        [0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0xf8, 0x3f]
    );
    assert_eq!(decode(&r, "t/U8F64", &bytes).unwrap(), v);
}

#[test]
fn big_endian_payload_decodes() {
    let r = registry();
    let be = [
        0, 0, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 0x3f, 0xf8, 0, 0, 0, 0, 0, 0,
    ];
    assert_eq!(
        decode(&r, "t/U8F64", &be).unwrap(),
        yaml(&r, "t/U8F64", "{a: 1, b: 1.5}")
    );
    let be_str = [0, 0, 0, 0, 0, 0, 0, 3, b'a', b'b', 0, 0, 0x01, 0x02];
    assert_eq!(
        decode(&r, "t/Str", &be_str).unwrap(),
        yaml(&r, "t/Str", "{s: ab, u: 258}")
    );
}

#[test]
fn string_has_length_with_nul_then_padding() {
    let r = registry();
    let v = yaml(&r, "t/Str", "{s: ab, u: 258}");
    let bytes = encode(&r, "t/Str", &v).unwrap();
    assert_eq!(
        bytes,
        [0, 1, 0, 0, 3, 0, 0, 0, b'a', b'b', 0, 0, 0x02, 0x01]
    );
    assert_eq!(decode(&r, "t/Str", &bytes).unwrap(), v);
}

#[test]
fn sequence_has_count_fixed_array_has_none() {
    let r = registry();
    let v = yaml(&r, "t/Seq", "{v: [-1, 2], f: [0.5, 2]}");
    let bytes = encode(&r, "t/Seq", &v).unwrap();
    let mut expected = vec![
        0, 1, 0, 0, 2, 0, 0, 0, 0xff, 0xff, 0xff, 0xff, 2, 0, 0, 0, 0, 0, 0, 0,
    ];
    expected.extend_from_slice(&0.5f64.to_le_bytes());
    expected.extend_from_slice(&2.0f64.to_le_bytes());
    assert_eq!(bytes, expected);
    assert_eq!(decode(&r, "t/Seq", &bytes).unwrap(), v);
}

#[test]
fn nested_struct_adds_no_padding_of_its_own() {
    let r = registry();
    let v = yaml(&r, "t/Nested", "{x: 7, t: {sec: -2, nanosec: 300000000}}");
    let bytes = encode(&r, "t/Nested", &v).unwrap();
    let mut expected = vec![0, 1, 0, 0, 7, 0, 0, 0];
    expected.extend_from_slice(&(-2i32).to_le_bytes());
    expected.extend_from_slice(&300_000_000u32.to_le_bytes());
    assert_eq!(bytes, expected);
    assert_eq!(decode(&r, "t/Nested", &bytes).unwrap(), v);
}

#[test]
fn temperature_bytes() {
    let r = registry();
    let v = yaml(
        &r,
        "sensor_msgs/msg/Temperature",
        "{header: {stamp: {sec: 1, nanosec: 2}, frame_id: ab}, temperature: 20.5}",
    );
    let bytes = encode(&r, "sensor_msgs/Temperature", &v).unwrap();
    let mut expected = vec![
        0, 1, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0, 3, 0, 0, 0, b'a', b'b', 0, 0,
    ];
    expected.extend_from_slice(&20.5f64.to_le_bytes());
    expected.extend_from_slice(&0.0f64.to_le_bytes());
    assert_eq!(bytes, expected);
}

#[test]
fn wstring_and_defaults() {
    let r = registry();
    let v = yaml(&r, "t/Wide", "{w: \"hé\"}");
    assert_eq!(v.at_path("f"), Some(&Value::Float(2.5)));
    assert_eq!(v.at_path("b"), Some(&Value::Bool(true)));
    let bytes = encode(&r, "t/Wide", &v).unwrap();
    let mut expected = vec![0, 1, 0, 0, 2, 0, 0, 0, b'h', 0, 0xe9, 0];
    expected.extend_from_slice(&2.5f32.to_le_bytes());
    expected.push(1);
    assert_eq!(bytes, expected);
    assert_eq!(decode(&r, "t/Wide", &bytes).unwrap(), v);
    // float32 input is rounded to f32 on conversion, so decode(encode(v)) == v.
    let v = yaml(&r, "t/Wide", "{f: 0.1}");
    assert_eq!(v.at_path("f"), Some(&Value::Float(0.1f32 as f64)));
    assert_eq!(
        decode(&r, "t/Wide", &encode(&r, "t/Wide", &v).unwrap()).unwrap(),
        v
    );
}

#[test]
fn truncated_input_is_an_error_at_every_length() {
    let r = registry();
    for ty in [
        "t/Items",
        "sensor_msgs/Temperature",
        "t/Seq",
        "t/Wide",
        "t/Bounded",
    ] {
        let v = sample_value(&r, ty, 3).unwrap();
        let bytes = encode(&r, ty, &v).unwrap();
        assert_eq!(decode(&r, ty, &bytes).unwrap(), v, "{ty}");
        for n in 0..bytes.len() {
            let e = decode(&r, ty, &bytes[..n]);
            assert!(
                e.is_err(),
                "{ty}: {n} of {} bytes decoded: {e:?}",
                bytes.len()
            );
        }
    }
    let r = registry();
    let v = yaml(
        &r,
        "t/Items",
        "{items: [{x: 1}, {x: 2, t: {sec: 5}}], tag: abcd}",
    );
    let bytes = encode(&r, "t/Items", &v).unwrap();
    let e = decode(&r, "t/Items", &bytes[..bytes.len() - 3]).unwrap_err();
    assert_eq!(e.path, "tag");
    assert!(e.message.contains("truncated"), "{e}");
    // Header 4 + count 4 + item 0 (x, 3 pad, sec, nanosec) 12 = 20; item 1's x is byte 20.
    let e = decode(&r, "t/Items", &bytes[..20]).unwrap_err();
    assert_eq!((e.path.as_str(), e.offset), ("items.1.x", 20), "{e}");
    let e = decode(&r, "t/Items", &bytes[..21]).unwrap_err();
    assert_eq!((e.path.as_str(), e.offset), ("items.1.t.sec", 21), "{e}");
}

#[test]
fn hostile_lengths_and_headers_are_errors() {
    let r = registry();
    // A sequence claiming 2^32-1 elements.
    let e = decode(&r, "t/Seq", &[0, 1, 0, 0, 0xff, 0xff, 0xff, 0xff]).unwrap_err();
    assert_eq!(e.path, "v");
    // Unknown encapsulation (XCDR2).
    let e = decode(&r, "t/U8F64", &[0, 7, 0, 0, 1]).unwrap_err();
    assert!(e.message.contains("encapsulation"), "{e}");
    // String without its NUL.
    let e = decode(
        &r,
        "t/Str",
        &[0, 1, 0, 0, 2, 0, 0, 0, b'a', b'b', 0, 0, 1, 0],
    )
    .unwrap_err();
    assert!(e.message.contains("NUL"), "{e}");
    // Bounded sequence over its bound.
    let e = decode(
        &r,
        "t/Bounded",
        &[0, 1, 0, 0, 1, 0, 0, 0, 0, 0, 0, 0, 3, 0, 0, 0, 1, 2, 3],
    )
    .unwrap_err();
    assert_eq!(e.path, "v");
    assert!(e.message.contains("bound"), "{e}");
}

#[test]
fn encode_errors_name_the_field() {
    let r = registry();
    let mut v = yaml(&r, "sensor_msgs/Temperature", "{}");
    if let Value::Struct(s) = &mut v {
        if let Some(Value::Struct(h)) = s.get_mut("header") {
            if let Some(Value::Struct(t)) = h.get_mut("stamp") {
                *t.get_mut("sec").unwrap() = Value::String("x".into());
            }
        }
    }
    let e = encode(&r, "sensor_msgs/Temperature", &v).unwrap_err();
    assert_eq!(e.path, "header.stamp.sec");
    assert!(e.to_string().contains("expected int32"), "{e}");
    let v = Value::Struct(rosmsg::StructValue {
        type_name: "t/Bounded".into(),
        fields: vec![
            ("s".into(), Value::String("abcd".into())),
            ("v".into(), Value::Array(vec![])),
        ],
    });
    let e = encode(&r, "t/Bounded", &v).unwrap_err();
    assert_eq!(e.path, "s");
    let v = Value::Struct(rosmsg::StructValue {
        type_name: "t/Nested".into(),
        fields: vec![("x".into(), Value::UInt(300))],
    });
    let e = encode(&r, "t/Nested", &v).unwrap_err();
    assert!(e.message.contains("out of range"), "{e}");
}

#[test]
fn yaml_conversion_like_ros2_topic_pub() {
    let r = registry();
    let v = yaml(
        &r,
        "sensor_msgs/msg/Temperature",
        "{header: {frame_id: a}, temperature: 21}",
    );
    assert_eq!(v.at_path("temperature"), Some(&Value::Float(21.0)));
    assert_eq!(
        v.at_path("header.frame_id"),
        Some(&Value::String("a".into()))
    );
    assert_eq!(v.at_path("header.stamp.sec"), Some(&Value::Int(0)));
    assert_eq!(
        to_json(&v),
        serde_json::json!({"header": {"stamp": {"sec": 0, "nanosec": 0}, "frame_id": "a"}, "temperature": 21.0, "variance": 0.0})
    );
    let e = from_yaml_str(&r, "sensor_msgs/Temperature", "{header: {frame: a}}").unwrap_err();
    assert_eq!(e.path, "header.frame");
    assert!(e.expected.contains("stamp, frame_id"), "{e}");
    let e = from_yaml_str(&r, "sensor_msgs/Temperature", "{temperature: hot}").unwrap_err();
    assert_eq!(e.path, "temperature");
    assert!(
        e.to_string()
            .contains("expected a number (float64), got string \"hot\""),
        "{e}"
    );
    let e = from_yaml_str(&r, "t/Nested", "{x: 1.5}").unwrap_err();
    assert!(e.to_string().contains("an integer (uint8)"), "{e}");
    let e = from_yaml_str(&r, "t/Nested", "{x: 256}").unwrap_err();
    assert!(e.to_string().contains("0..=255"), "{e}");
    let e = from_yaml_str(&r, "t/Seq", "{f: [1, 2, 3]}").unwrap_err();
    assert!(e.to_string().contains("exactly 2"), "{e}");
    let e = from_yaml_str(&r, "t/Bounded", "{s: abcd}").unwrap_err();
    assert!(e.to_string().contains("at most 3"), "{e}");
    // Round trip through JSON.
    let s = sample_value(&r, "t/Items", 9).unwrap();
    assert_eq!(rosmsg::from_json(&r, "t/Items", &to_json(&s)).unwrap(), s);
    let y = rosmsg::to_yaml_string(&s);
    assert_eq!(from_yaml_str(&r, "t/Items", &y).unwrap(), s, "{y}");
}
