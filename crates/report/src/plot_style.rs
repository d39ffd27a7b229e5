//! What the plots share: the error type, the canvas size, the palette and axis ranges.

use plotters::style::RGBColor;

/// A plot could not be drawn (no data, non-finite values, or plotters' own error).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum PlotError {
    #[error("plot `{plot}`: {reason}")]
    Data { plot: String, reason: String },
    #[error("plot `{plot}`: drawing failed: {reason}")]
    Drawing { plot: String, reason: String },
}

pub(crate) fn drawing(plot: &str, e: impl std::fmt::Display) -> PlotError {
    PlotError::Drawing {
        plot: plot.into(),
        reason: e.to_string(),
    }
}

pub(crate) fn data(plot: &str, reason: impl Into<String>) -> PlotError {
    PlotError::Data {
        plot: plot.into(),
        reason: reason.into(),
    }
}

/// Canvas size in SVG user units (px).
pub(crate) const SIZE: (u32, u32) = (720, 420);

/// Colour-blind-safe categorical palette (Okabe–Ito), one colour per series in order.
pub(crate) const PALETTE: [RGBColor; 7] = [
    RGBColor(0, 114, 178),
    RGBColor(213, 94, 0),
    RGBColor(0, 158, 115),
    RGBColor(204, 121, 167),
    RGBColor(230, 159, 0),
    RGBColor(86, 180, 233),
    RGBColor(0, 0, 0),
];

pub(crate) fn palette(i: usize) -> RGBColor {
    PALETTE[i % PALETTE.len()]
}

/// [min, max] of finite values padded by 5 % (a zero-width range is widened to ±0.5 or ±5 %).
pub(crate) fn padded_range(values: impl Iterator<Item = f64>) -> Option<(f64, f64)> {
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in values {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return None;
    }
    if hi - lo <= f64::EPSILON * hi.abs().max(lo.abs()) {
        let w = if lo == 0.0 { 0.5 } else { 0.05 * lo.abs() };
        return Some((lo - w, hi + w));
    }
    let pad = 0.05 * (hi - lo);
    Some((lo - pad, hi + pad))
}

/// Viridis (matplotlib's, sampled at nine stops) at t ∈ [0, 1], linearly interpolated.
pub(crate) fn viridis(t: f64) -> RGBColor {
    const STOPS: [(u8, u8, u8); 9] = [
        (68, 1, 84),
        (71, 44, 122),
        (59, 81, 139),
        (44, 113, 142),
        (33, 144, 141),
        (39, 173, 129),
        (92, 200, 99),
        (170, 220, 50),
        (253, 231, 37),
    ];
    let t = if t.is_finite() {
        t.clamp(0.0, 1.0)
    } else {
        0.0
    };
    let x = t * (STOPS.len() - 1) as f64;
    let i = (x.floor() as usize).min(STOPS.len() - 2);
    let f = x - i as f64;
    let mix = |a: u8, b: u8| (a as f64 + f * (b as f64 - a as f64)).round() as u8;
    let (a, b) = (STOPS[i], STOPS[i + 1]);
    RGBColor(mix(a.0, b.0), mix(a.1, b.1), mix(a.2, b.2))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_and_colours() {
        assert_eq!(padded_range([0.0, 10.0].into_iter()), Some((-0.5, 10.5)));
        assert_eq!(padded_range([2.0, 2.0].into_iter()), Some((1.9, 2.1)));
        assert_eq!(padded_range([f64::NAN].into_iter()), None);
        assert_eq!(viridis(0.0), RGBColor(68, 1, 84));
        assert_eq!(viridis(1.0), RGBColor(253, 231, 37));
        assert_eq!(viridis(0.5), RGBColor(33, 144, 141));
    }
}
