//! Simulated time: the twin's seconds-from-shift-start `t` mapped onto ROS time.
//!
//! Convention (stated once, here): every message of a simulation is stamped
//! `start_time + t`, where `start_time` is a fixed epoch (nanoseconds since the Unix epoch,
//! UTC) taken from the command line, [`DEFAULT_START_TIME`] otherwise — never the wall
//! clock, so the same cell and seed always give the same stamps and byte-identical bags.
//! `t` is rounded to the nearest nanosecond. ROS `builtin_interfaces/Time` holds seconds in an
//! `int32`, so the last stamp of a run must be before 2038-01-19T03:14:08Z
//! ([`check_span`]).

use metrocell_msgs::builtin_interfaces::msg::Time;

use crate::error::SimError;

/// Default start of simulated time: Monday 2026-01-05, 06:00 UTC (start of an early shift).
pub const DEFAULT_START_TIME: &str = "2026-01-05T06:00:00Z";

/// Largest stamp `builtin_interfaces/Time` can hold (i32::MAX s, 999_999_999 ns).
pub const MAX_STAMP_NS: u64 = i32::MAX as u64 * 1_000_000_000 + 999_999_999;

/// Nanoseconds since the Unix epoch of an RFC 3339 date-time (`2026-01-05T06:00:00Z`,
/// `2026-01-05T07:00:00+01:00`, fractional seconds allowed). Times before 1970 are rejected.
pub fn parse_start_time(text: &str) -> Result<u64, SimError> {
    let what = format!("start time {text:?}");
    let dt = chrono::DateTime::parse_from_rfc3339(text.trim()).map_err(|e| {
        SimError::invalid(
            &what,
            format!("not an RFC 3339 date-time ({e}); example: {DEFAULT_START_TIME}"),
        )
    })?;
    let ns = dt
        .timestamp_nanos_opt()
        .ok_or_else(|| SimError::invalid(&what, "outside the range of 64-bit nanoseconds"))?;
    let ns =
        u64::try_from(ns).map_err(|_| SimError::invalid(&what, "before 1970-01-01T00:00:00Z"))?;
    if ns > MAX_STAMP_NS {
        return Err(SimError::invalid(
            &what,
            "after 2038-01-19T03:14:07Z, the last time a ROS stamp (int32 seconds) can hold",
        ));
    }
    Ok(ns)
}

/// Stamp of simulation time `t` (s from the start): `start_ns + round(t·1e9)`.
/// `t` is clamped at 0 (the twin never produces negative times).
pub fn stamp_ns(start_ns: u64, t: f64) -> u64 {
    start_ns.saturating_add((t.max(0.0) * 1e9).round() as u64)
}

/// ROS `Time` of a stamp in nanoseconds since the Unix epoch (saturates at [`MAX_STAMP_NS`];
/// [`check_span`] keeps real runs below it).
pub fn ros_time(ns: u64) -> Time {
    let ns = ns.min(MAX_STAMP_NS);
    Time::from_nanos(ns as i64)
}

/// Check that a run of `duration_s` seconds starting at `start_ns` stays inside ROS time.
pub fn check_span(start_ns: u64, duration_s: f64) -> Result<(), SimError> {
    if !(duration_s > 0.0 && duration_s.is_finite()) {
        return Err(SimError::invalid(
            "duration",
            format!("must be > 0 s and finite, got {duration_s}"),
        ));
    }
    if stamp_ns(start_ns, duration_s) > MAX_STAMP_NS {
        return Err(SimError::invalid(
            "start time + duration",
            "ends after 2038-01-19T03:14:07Z, which int32-second ROS stamps cannot hold",
        ));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_start_is_the_documented_instant() {
        // 2026-01-05T06:00:00Z = 20458 days after 1970-01-01, plus 6 h.
        let ns = parse_start_time(DEFAULT_START_TIME).unwrap();
        assert_eq!(ns, (20_458 * 86_400 + 6 * 3_600) * 1_000_000_000);
    }

    #[test]
    fn offsets_and_fractions_are_honoured() {
        let z = parse_start_time("2026-01-05T06:00:00Z").unwrap();
        assert_eq!(parse_start_time("2026-01-05T07:00:00+01:00").unwrap(), z);
        assert_eq!(
            parse_start_time("2026-01-05T06:00:00.25Z").unwrap(),
            z + 250_000_000
        );
    }

    #[test]
    fn bad_start_times_are_errors_naming_the_text() {
        for bad in [
            "yesterday",
            "2026-01-05",
            "1969-12-31T23:59:59Z",
            "2040-01-01T00:00:00Z",
        ] {
            let e = parse_start_time(bad).unwrap_err().to_string();
            assert!(e.contains(bad), "{e}");
        }
    }

    #[test]
    fn stamps_round_to_the_nanosecond_and_split_into_sec_nanosec() {
        let start = 1_767_592_800_000_000_000; // 2026-01-05T06:00:00Z
        assert_eq!(stamp_ns(start, 0.0), start);
        assert_eq!(stamp_ns(start, 0.1), start + 100_000_000);
        // 8 h at 100 Hz: sample k = 2_879_999 lands on its exact nanosecond.
        assert_eq!(
            stamp_ns(start, 2_879_999.0 / 100.0),
            start + 28_799_990_000_000
        );
        let t = ros_time(start + 1_500_000_001);
        assert_eq!((t.sec, t.nanosec), (1_767_592_801, 500_000_001));
    }

    #[test]
    fn span_check_rejects_runs_past_2038() {
        let start = parse_start_time("2038-01-19T03:00:00Z").unwrap();
        assert!(check_span(start, 600.0).is_ok());
        assert!(check_span(start, 3_600.0).is_err());
        assert!(check_span(start, 0.0).is_err());
    }
}
