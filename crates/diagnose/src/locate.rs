//! Where structure lives. For each channel and axis, the normalised residuals are split into
//! subsets — terciles of each machine axis's position (workspace regions), equal windows of time,
//! the two directions each axis approached from, terciles of each recorded condition — and each
//! subset's mean is tested against zero (two-sided normal test of √n·z̄/s), and each condition's
//! correlation with the residual against none. Every p-value is then corrected for the number of
//! tests made (Holm), and what stays significant is reported with its effect size in metres.
//!
//! The scale s is the stated σ (s = 1 for z) unless the residuals scatter more than it says:
//! then s = 1.4826·MAD(z), a robust scatter that a structure confined to part of the data
//! hardly moves, so an understated noise level does not pass for structure everywhere.

use crate::outliers::robust_scale;
use std::collections::BTreeMap;

use statrs::distribution::{ContinuousCDF, Normal};

use crate::multiple_testing::holm;
use crate::residual::{axis_name, ResidualSample};

/// Where a subset lives.
#[derive(Debug, Clone, PartialEq)]
pub enum Place {
    /// Machine axis `axis` between `from` and `to` (m).
    Region { axis: usize, from: f64, to: f64 },
    /// Time window [from, to) (s).
    TimeWindow { from: f64, to: f64 },
    /// Samples where machine axis `axis` approached with sign `sign`.
    Direction { axis: usize, sign: f64 },
    /// Condition `name` between `from` and `to`.
    ConditionRange { name: String, from: f64, to: f64 },
    /// The residual correlates with condition `name` (effect = slope × the condition's spread).
    Correlation { name: String },
}

/// A significant structure.
#[derive(Debug, Clone, PartialEq)]
pub struct Finding {
    pub channel: String,
    pub axis: usize,
    pub place: Place,
    pub count: usize,
    /// Mean residual of the subset (m), or for a correlation the change across one standard
    /// deviation of the condition (m); and its standard error (m).
    pub effect_m: f64,
    pub effect_sigma_m: f64,
    pub p_value: f64,
    pub p_adjusted: f64,
}

impl Finding {
    /// One sentence in µm and mm.
    pub fn describe(&self) -> String {
        let what = format!(
            "{} {} residual {:+.1} ± {:.1} µm",
            self.channel,
            axis_name(self.axis),
            self.effect_m * 1e6,
            self.effect_sigma_m * 1e6
        );
        let place = match &self.place {
            Place::Region { axis, from, to } => format!(
                "where {} is {:.0}–{:.0} mm",
                axis_name(*axis),
                from * 1e3,
                to * 1e3
            ),
            Place::TimeWindow { from, to } => format!("between t = {:.0} s and {:.0} s", from, to),
            Place::Direction { axis, sign } => format!(
                "when {} approaches from {}",
                axis_name(*axis),
                if *sign > 0.0 {
                    "below (moving +)"
                } else {
                    "above (moving −)"
                }
            ),
            Place::ConditionRange { name, from, to } => format!("when {name} is {from:.3}–{to:.3}"),
            Place::Correlation { name } => format!("per standard deviation of {name}"),
        };
        format!(
            "{what} {place} (n = {}, p {} after correction for the tests made)",
            self.count,
            p_value_text(self.p_adjusted)
        )
    }
}

/// A p-value as a person reads it: "= 0.042", "= 3.2e-5", and "< 1e-300" where the tail of the
/// test's distribution underflows (p computed as 0), never "0.0e0".
pub fn p_value_text(p: f64) -> String {
    if !(p > 1e-300) {
        "< 1e-300".into()
    } else if p < 1e-3 {
        format!("= {p:.1e}")
    } else {
        format!("= {p:.3}")
    }
}

/// Options of [`locate`].
#[derive(Debug, Clone)]
pub struct LocateOptions {
    /// Family-wise significance level after correction.
    pub alpha: f64,
    /// Number of equal time windows.
    pub time_windows: usize,
    /// Smallest subset tested.
    pub min_subset: usize,
}

impl Default for LocateOptions {
    fn default() -> Self {
        Self {
            alpha: 0.01,
            time_windows: 8,
            min_subset: 8,
        }
    }
}

struct Candidate {
    channel: String,
    axis: usize,
    place: Place,
    count: usize,
    effect_m: f64,
    effect_sigma_m: f64,
    p_value: f64,
}

/// Significant structures, strongest (smallest corrected p, then largest effect) first.
pub fn locate(samples: &[ResidualSample], options: &LocateOptions) -> Vec<Finding> {
    let mut groups: BTreeMap<(String, usize), Vec<&ResidualSample>> = BTreeMap::new();
    for s in samples
        .iter()
        .filter(|s| s.residual.is_finite() && s.sigma > 0.0 && s.time.is_finite())
    {
        groups
            .entry((s.channel.clone(), s.axis))
            .or_default()
            .push(s);
    }
    let mut candidates = Vec::new();
    for ((channel, axis), g) in &groups {
        candidates.extend(group_candidates(channel, *axis, g, options));
    }
    let adjusted = holm(&candidates.iter().map(|c| c.p_value).collect::<Vec<_>>());
    let mut findings: Vec<Finding> = candidates
        .into_iter()
        .zip(adjusted)
        .filter(|(_, p)| *p <= options.alpha)
        .map(|(c, p_adjusted)| Finding {
            channel: c.channel,
            axis: c.axis,
            place: c.place,
            count: c.count,
            effect_m: c.effect_m,
            effect_sigma_m: c.effect_sigma_m,
            p_value: c.p_value,
            p_adjusted,
        })
        .collect();
    findings.sort_by(|a, b| {
        a.p_adjusted
            .total_cmp(&b.p_adjusted)
            .then(b.effect_m.abs().total_cmp(&a.effect_m.abs()))
    });
    findings
}

fn group_candidates(
    channel: &str,
    axis: usize,
    g: &[&ResidualSample],
    options: &LocateOptions,
) -> Vec<Candidate> {
    let z: Vec<f64> = g.iter().map(|s| s.z()).collect();
    let scale = robust_scale(&z).max(1.0);
    let mean_sigma = g.iter().map(|s| s.sigma).sum::<f64>() / g.len() as f64;
    let normal = Normal::new(0.0, 1.0).expect("unit normal");
    let mut out = Vec::new();
    let mut test_subset = |place: Place, idx: &[usize]| {
        if idx.len() < options.min_subset {
            return;
        }
        let n = idx.len() as f64;
        let zbar = idx.iter().map(|&i| z[i]).sum::<f64>() / n;
        let stat = zbar * n.sqrt() / scale;
        let effect = idx.iter().map(|&i| g[i].residual).sum::<f64>() / n;
        out.push(Candidate {
            channel: channel.into(),
            axis,
            place,
            count: idx.len(),
            effect_m: effect,
            effect_sigma_m: scale * mean_sigma / n.sqrt(),
            p_value: 2.0 * normal.sf(stat.abs()),
        });
    };
    // workspace regions: terciles of each machine axis's position
    for k in 0..3 {
        let values: Vec<f64> = g.iter().map(|s| s.position[k]).collect();
        for (from, to, idx) in terciles(&values) {
            test_subset(Place::Region { axis: k, from, to }, &idx);
        }
    }
    // time windows
    let (t0, t1) = g
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), s| {
            (a.min(s.time), b.max(s.time))
        });
    if t1 > t0 && options.time_windows > 1 {
        let w = (t1 - t0) / options.time_windows as f64;
        for k in 0..options.time_windows {
            let (from, to) = (
                t0 + w * k as f64,
                if k + 1 == options.time_windows {
                    t1 + 1e-9
                } else {
                    t0 + w * (k + 1) as f64
                },
            );
            let idx: Vec<usize> = (0..g.len())
                .filter(|&i| g[i].time >= from && g[i].time < to)
                .collect();
            test_subset(
                Place::TimeWindow {
                    from,
                    to: to.min(t1),
                },
                &idx,
            );
        }
    }
    // directions of approach
    for k in 0..3 {
        for sign in [1.0, -1.0] {
            let idx: Vec<usize> = (0..g.len())
                .filter(|&i| g[i].approach[k] == Some(sign))
                .collect();
            let other = (0..g.len())
                .filter(|&i| g[i].approach[k] == Some(-sign))
                .count();
            if other >= options.min_subset {
                test_subset(Place::Direction { axis: k, sign }, &idx);
            }
        }
    }
    // conditions: terciles and correlation
    let mut correlations = Vec::new();
    let mut names: Vec<&str> = g
        .iter()
        .flat_map(|s| s.conditions.iter().map(|(n, _)| n.as_str()))
        .collect();
    names.sort_unstable();
    names.dedup();
    for name in names {
        let present: Vec<(usize, f64)> = (0..g.len())
            .filter_map(|i| {
                g[i].condition(name)
                    .filter(|v| v.is_finite())
                    .map(|v| (i, v))
            })
            .collect();
        if present.len() < 3 * options.min_subset {
            continue;
        }
        let values: Vec<f64> = present.iter().map(|p| p.1).collect();
        for (from, to, sub) in terciles(&values) {
            let idx: Vec<usize> = sub.iter().map(|&j| present[j].0).collect();
            test_subset(
                Place::ConditionRange {
                    name: name.to_string(),
                    from,
                    to,
                },
                &idx,
            );
        }
        if let Some((effect, se, p)) = correlation(&present, &z, scale, mean_sigma) {
            correlations.push(Candidate {
                channel: channel.into(),
                axis,
                place: Place::Correlation {
                    name: name.to_string(),
                },
                count: present.len(),
                effect_m: effect,
                effect_sigma_m: se,
                p_value: p,
            });
        }
    }
    out.extend(correlations);
    out
}

/// 1.4826·median |z − median z|.
/// Index sets of the lower, middle and upper third of `values` with their ranges; empty when the
/// values do not vary.
fn terciles(values: &[f64]) -> Vec<(f64, f64, Vec<usize>)> {
    let mut sorted = values.to_vec();
    sorted.sort_by(f64::total_cmp);
    let (lo, hi) = (sorted[0], sorted[sorted.len() - 1]);
    if hi - lo <= 1e-12 * (1.0 + hi.abs()) {
        return Vec::new();
    }
    let c1 = sorted[sorted.len() / 3];
    let c2 = sorted[2 * sorted.len() / 3];
    let mut out = Vec::new();
    for (from, to) in [(lo, c1), (c1, c2), (c2, hi)] {
        let last = to == hi;
        let idx: Vec<usize> = (0..values.len())
            .filter(|&i| values[i] >= from && (values[i] < to || (last && values[i] <= to)))
            .collect();
        if !idx.is_empty() && idx.len() < values.len() {
            out.push((from, to, idx));
        }
    }
    out
}

/// Slope of z on the condition, as the residual change (m) across one standard deviation of the
/// condition, its standard error, and the two-sided p-value.
fn correlation(
    present: &[(usize, f64)],
    z: &[f64],
    scale: f64,
    mean_sigma: f64,
) -> Option<(f64, f64, f64)> {
    let n = present.len() as f64;
    let mx = present.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = present.iter().map(|p| (p.1 - mx).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let sxz: f64 = present.iter().map(|p| (p.1 - mx) * z[p.0]).sum();
    let slope = sxz / sxx;
    let se = scale / sxx.sqrt();
    let spread = (sxx / n).sqrt();
    let normal = Normal::new(0.0, 1.0).expect("unit normal");
    Some((
        slope * spread * mean_sigma,
        se * spread * mean_sigma,
        2.0 * normal.sf((slope / se).abs()),
    ))
}
