//! `builtin_interfaces/msg/Time` ↔ nanoseconds since the epoch.
//!
//! Convention (rclcpp's `rclcpp::Time`): `sec = floor(ns / 1e9)`, `nanosec = ns − sec·1e9`, so
//! `nanosec` is always in `[0, 1e9)` and times before the epoch keep a non-negative `nanosec`.

use crate::builtin_interfaces::msg::Time;

impl Time {
    /// The stamp of `ns` nanoseconds since the epoch (`sec` saturates outside the i32 range,
    /// years 1901–2038, as ROS 2's own `Time` message does).
    pub fn from_nanos(ns: i64) -> Time {
        let sec = ns
            .div_euclid(1_000_000_000)
            .clamp(i32::MIN as i64, i32::MAX as i64);
        Time {
            sec: sec as i32,
            nanosec: (ns - sec * 1_000_000_000).clamp(0, 999_999_999) as u32,
        }
    }

    /// Nanoseconds since the epoch.
    pub fn nanos(&self) -> i64 {
        self.sec as i64 * 1_000_000_000 + self.nanosec as i64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nanoseconds_round_trip_with_nanosec_in_range() {
        for ns in [
            0i64,
            1,
            999_999_999,
            1_000_000_000,
            1_700_000_000_123_456_789,
            -1,
            -1_500_000_000,
        ] {
            let t = Time::from_nanos(ns);
            assert!(t.nanosec < 1_000_000_000, "{ns}: {t:?}");
            assert_eq!(t.nanos(), ns);
        }
        assert_eq!(
            Time::from_nanos(-1),
            Time {
                sec: -1,
                nanosec: 999_999_999
            }
        );
        assert_eq!(
            Time::from_nanos(1_700_000_000_123_456_789),
            Time {
                sec: 1_700_000_000,
                nanosec: 123_456_789
            }
        );
    }
}
