//! CDR encoding of typed messages exactly as ROS 2 puts them on the wire and rosbag2 stores
//! them: the 4-byte encapsulation header `00 01 00 00` (CDR little-endian, XCDR1) followed by
//! the plain CDR body (RustDDS's serializer; alignment counts from the start of the body).

use byteorder::LittleEndian;
use serde::Serialize;

use crate::error::SimError;

/// Encapsulation header of CDR little-endian.
pub const CDR_LE_HEADER: [u8; 4] = [0x00, 0x01, 0x00, 0x00];

/// Header + CDR body of a message.
pub fn encode_cdr<T: Serialize>(message: &T, ros_type: &'static str) -> Result<Vec<u8>, SimError> {
    let mut out = Vec::with_capacity(128);
    out.extend_from_slice(&CDR_LE_HEADER);
    rustdds::serialization::to_writer::<T, LittleEndian, _>(&mut out, message).map_err(|e| {
        SimError::Encode {
            ros_type,
            reason: e.to_string(),
        }
    })?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use metrocell_msgs::builtin_interfaces::msg::Time;
    use metrocell_msgs::sensor_msgs::msg::Temperature;
    use metrocell_msgs::std_msgs::msg::Header;
    use rosmsg::RosMessage;

    use super::*;

    #[test]
    fn bytes_match_hand_layout_and_the_dynamic_codec() {
        let m = Temperature {
            header: Header {
                stamp: Time { sec: 7, nanosec: 9 },
                frame_id: "ab".into(),
            },
            temperature: 20.5,
            variance: 0.0025,
        };
        let bytes = encode_cdr(&m, Temperature::ROS_TYPE).unwrap();
        // header | sec | nanosec | len 3 | "ab\0" | pad to 8 (body offset 15 → 16) | f64 | f64
        let mut expected = vec![
            0, 1, 0, 0, 7, 0, 0, 0, 9, 0, 0, 0, 3, 0, 0, 0, b'a', b'b', 0, 0,
        ];
        expected.extend_from_slice(&20.5f64.to_le_bytes());
        expected.extend_from_slice(&0.0025f64.to_le_bytes());
        assert_eq!(bytes, expected);
        let value =
            rosmsg::decode(metrocell_msgs::registry(), Temperature::ROS_TYPE, &bytes).unwrap();
        assert_eq!(
            rosmsg::encode(metrocell_msgs::registry(), Temperature::ROS_TYPE, &value).unwrap(),
            bytes
        );
    }
}
