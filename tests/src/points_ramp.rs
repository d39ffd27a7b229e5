//! The measured points `points_ramp_peer` publishes for the dashboard tests, written once so the
//! tests compare what they decode with the generator itself, not with a copy of its numbers.
//! Point k is stamped `step`·k seconds after 2026-01-01T00:00:00Z; its error at stamp hour h is
//! x = 2 µm + 36 µm/h · h ± 0.5 µm (+ for even k, − for odd), y = −3 µm, z = 0.

/// 2026-01-01T00:00:00Z.
pub const START_NS: i64 = 1_767_225_600_000_000_000;
/// The drift of the x error.
pub const X_RATE_UM_PER_H: f64 = 36.0;
/// The peer's default stamp seconds between two points.
pub const DEFAULT_STEP: f64 = 60.0;

/// Stamp of point `k` (ns since the epoch).
pub fn stamp_ns(k: i64, step: f64) -> i64 {
    START_NS + (step * k as f64 * 1e9).round() as i64
}

/// Nominal position of point `k` (m): eight x positions 50 mm apart.
pub fn nominal(k: i64) -> [f64; 3] {
    [0.1 + 0.05 * (k % 8) as f64, 0.2, 0.1]
}

/// Measured position of point `k` (m): the nominal plus the ramp's error.
pub fn measured(k: i64, step: f64) -> [f64; 3] {
    let h = step * k as f64 / 3600.0;
    let noise = if k % 2 == 0 { 0.5e-6 } else { -0.5e-6 };
    let n = nominal(k);
    [
        n[0] + 2e-6 + X_RATE_UM_PER_H * 1e-6 * h + noise,
        n[1] - 3e-6,
        n[2],
    ]
}

/// Variance of every coordinate (m²): (0.5 µm)², the alternation's.
pub const VARIANCE: f64 = 0.25e-12;
