#![allow(dead_code, unused_imports)]
//! Helpers of the identification tests; the simulated records themselves are library code
//! (`metrocell_estimation::simulated_records`), which planning uses too.

pub use metrocell_estimation::simulated_records::{
    records, signals, Planned, TrackerNoise, THESIS_TRACKER,
};
use metrocell_model::ForwardModel;

/// Index of a parameter by name.
pub fn index(model: &ForwardModel, name: &str) -> usize {
    model
        .param_names()
        .iter()
        .position(|n| n == name)
        .unwrap_or_else(|| panic!("no parameter {name}"))
}

/// Fraction of |z| ≤ k.
pub fn within(z: &[f64], k: f64) -> f64 {
    z.iter().filter(|v| v.abs() <= k).count() as f64 / z.len() as f64
}

/// The 21 geometric errors of an XFYZ machine of travel 800 × 500 × 400 mm as `terms:` items:
/// positioning and straightness series of order 3, angular series of order 2 about each axis
/// with the Abbe lever `lever_axes` and offset `abbe_offset`, three squareness terms — all at 0.
pub fn xfyz_geometric_terms(lever_axes: &str, abbe_offset: &str) -> String {
    let mut terms = String::new();
    let travels = [
        ("x", "[0 mm, 800 mm]"),
        ("y", "[0 mm, 500 mm]"),
        ("z", "[0 mm, 400 mm]"),
    ];
    for (a, t) in travels {
        terms += &format!("  - {{id: positioning, options: {{axis: {a}, order: 3, travel: {t}}}, params: {{c0: 0 um, c1: 0 um, c2: 0 um, c3: 0 um}}}}\n");
        for d in ["x", "y", "z"].iter().filter(|d| **d != a) {
            terms += &format!("  - {{id: straightness, options: {{axis: {a}, direction: {d}, order: 3, travel: {t}}}, params: {{c0: 0 um, c1: 0 um, c2: 0 um, c3: 0 um}}}}\n");
        }
        for about in ["x", "y", "z"] {
            terms += &format!("  - {{id: angular, options: {{axis: {a}, about: {about}, lever_axes: {lever_axes}, abbe_offset: {abbe_offset}, order: 2, travel: {t}}}, params: {{c0: 0 urad, c1: 0 urad, c2: 0 urad}}}}\n");
        }
    }
    for pair in ["xy", "xz", "yz"] {
        terms +=
            &format!("  - {{id: squareness, options: {{pair: {pair}}}, params: {{s: 0 urad}}}}\n");
    }
    terms
}
