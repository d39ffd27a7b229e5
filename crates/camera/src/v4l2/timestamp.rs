//! Which clock a dequeued buffer's `timestamp` is on, and the frame stamp (ns since the epoch,
//! system clock = ROS wall time) that follows from it.
//!
//! `struct v4l2_buffer.flags & V4L2_BUF_FLAG_TIMESTAMP_MASK` says (linux/videodev2.h):
//! - `MONOTONIC`: the driver stamped the buffer on CLOCK_MONOTONIC (uvcvideo, most capture
//!   drivers). Moved to CLOCK_REALTIME by the offset REALTIME − MONOTONIC sampled at dequeue, so
//!   the stamp is the capture instant, not the (later) dequeue instant.
//! - `COPY`: the timestamp was copied from an output buffer by a memory-to-memory device; on a
//!   capture queue it is whatever the application wrote there, on no known clock.
//! - `UNKNOWN` (0) or the undefined value 0x6000: no clock is promised.
//!
//! For COPY, UNKNOWN and undefined the frame is stamped with CLOCK_REALTIME at dequeue (late by
//! the driver's pipeline latency, typically about one frame period) and [`StampOrigin`] says so,
//! so the node can warn once instead of publishing stamps that may be hours or years off (taking
//! such a value as monotonic would). A MONOTONIC timestamp that is zero or later than the
//! dequeue instant is not a capture instant either (a driver that does not fill it in) and gets
//! the same fallback.

use super::ioctl::{
    BUF_FLAG_TIMESTAMP_COPY, BUF_FLAG_TIMESTAMP_MASK, BUF_FLAG_TIMESTAMP_MONOTONIC,
    BUF_FLAG_TIMESTAMP_UNKNOWN,
};

/// CLOCK_REALTIME and CLOCK_MONOTONIC read back to back at dequeue (ns).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ClockSample {
    pub realtime_ns: i64,
    pub monotonic_ns: i64,
}

/// Where a frame's stamp came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum StampOrigin {
    /// The driver's CLOCK_MONOTONIC capture instant, moved to the system clock.
    DriverMonotonic,
    /// The dequeue instant: the driver's timestamp is on no usable clock (the reason, for a
    /// warning: "timestamp flag COPY", "timestamp flag UNKNOWN", ...).
    Dequeue { reason: &'static str },
}

/// The stamp (ns since the epoch) of a buffer with `flags` and driver timestamp `driver_ns`
/// (`timeval` as ns), given the clocks sampled at dequeue.
pub fn capture_stamp(flags: u32, driver_ns: i64, at_dequeue: ClockSample) -> (i64, StampOrigin) {
    let dequeue = |reason| (at_dequeue.realtime_ns, StampOrigin::Dequeue { reason });
    match flags & BUF_FLAG_TIMESTAMP_MASK {
        BUF_FLAG_TIMESTAMP_MONOTONIC if driver_ns <= 0 => dequeue("MONOTONIC timestamp is zero"),
        BUF_FLAG_TIMESTAMP_MONOTONIC if driver_ns > at_dequeue.monotonic_ns => {
            dequeue("MONOTONIC timestamp is in the future")
        }
        BUF_FLAG_TIMESTAMP_MONOTONIC => (
            at_dequeue.realtime_ns - (at_dequeue.monotonic_ns - driver_ns),
            StampOrigin::DriverMonotonic,
        ),
        BUF_FLAG_TIMESTAMP_COPY => dequeue("timestamp flag COPY (not a capture clock)"),
        BUF_FLAG_TIMESTAMP_UNKNOWN => dequeue("timestamp flag UNKNOWN"),
        _ => dequeue("undefined timestamp flag 0x6000"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const AT: ClockSample = ClockSample {
        realtime_ns: 1_700_000_000_000_000_000,
        monotonic_ns: 5_000_000_000_000,
    };

    #[test]
    fn monotonic_timestamps_move_to_the_system_clock() {
        // Exposed 33 ms before dequeue on CLOCK_MONOTONIC → 33 ms before dequeue on the system clock.
        let (t, o) = capture_stamp(
            BUF_FLAG_TIMESTAMP_MONOTONIC,
            AT.monotonic_ns - 33_000_000,
            AT,
        );
        assert_eq!(
            (t, o),
            (AT.realtime_ns - 33_000_000, StampOrigin::DriverMonotonic)
        );
        // Other flag bits (ERROR, timestamp source SOE 0x10000, MAPPED 0x1, DONE 0x4) do not matter.
        let (t, _) = capture_stamp(
            BUF_FLAG_TIMESTAMP_MONOTONIC | 0x1_0045,
            AT.monotonic_ns - 1,
            AT,
        );
        assert_eq!(t, AT.realtime_ns - 1);
    }

    #[test]
    fn copy_unknown_and_implausible_timestamps_fall_back_to_the_dequeue_instant() {
        // A COPY/UNKNOWN timestamp is on no known clock: the old code took every timestamp as
        // monotonic and stamped this frame 1 h 23 min before it was captured.
        let driver_ns = AT.monotonic_ns - 5_000_000_000_000;
        for flags in [
            BUF_FLAG_TIMESTAMP_COPY,
            0,
            0x6000,
            0x40, /* ERROR, clock UNKNOWN */
        ] {
            let (t, o) = capture_stamp(flags, driver_ns, AT);
            assert_eq!(t, AT.realtime_ns, "flags {flags:#x}");
            assert!(
                matches!(o, StampOrigin::Dequeue { .. }),
                "flags {flags:#x}: {o:?}"
            );
        }
        assert!(
            matches!(capture_stamp(BUF_FLAG_TIMESTAMP_COPY, driver_ns, AT).1, StampOrigin::Dequeue { reason } if reason.contains("COPY"))
        );
        assert!(
            matches!(capture_stamp(0, driver_ns, AT).1, StampOrigin::Dequeue { reason } if reason.contains("UNKNOWN"))
        );
        for bad in [0, AT.monotonic_ns + 1] {
            assert_eq!(
                capture_stamp(BUF_FLAG_TIMESTAMP_MONOTONIC, bad, AT).0,
                AT.realtime_ns,
                "driver timestamp {bad}"
            );
        }
    }
}
