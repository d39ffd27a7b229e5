//! The measurement program: a volumetric-verification style visit of points (commanded axis
//! positions), with a dwell at each point, repeated in cycles over the shift.
//!
//! One cycle: move home → p₀, dwell, move → p₁, dwell, …, dwell at p_{N−1}, move → home.
//! Moves are straight lines at constant path speed `feed_rate` (no acceleration phase).
//! Cycle c starts at `start + c·max(cycle_interval, cycle length)`; between cycles and after the
//! last one the machine waits at home. The approach direction of an axis (for `backlash`) is
//! the sign of its last non-zero motion, +1 before any motion (homed from the negative side).

use nalgebra::Vector3;

use crate::cell::MachineGeometry;
use crate::cell_file::{ProgramSection, VisitOrder};
use crate::error::CellError;
use crate::quantity::vector3;

/// One piece of a cycle (times relative to the cycle start).
#[derive(Debug, Clone, PartialEq)]
pub struct Segment {
    pub start: f64,
    pub end: f64,
    pub from: Vector3<f64>,
    pub to: Vector3<f64>,
    /// `Some(point index)` for a dwell, `None` for a move.
    pub dwell_point: Option<usize>,
    /// Approach direction of each axis (±1) during this segment.
    pub approach: [f64; 3],
}

/// Machine motion at one instant.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionState {
    /// Commanded axis positions (m).
    pub q: Vector3<f64>,
    /// Commanded axis velocity (m/s).
    pub velocity: Vector3<f64>,
    /// Approach direction per axis (±1).
    pub approach: [f64; 3],
    /// `Some(point index)` while dwelling at a program point.
    pub dwell_point: Option<usize>,
    /// Cycle number (0-based); `None` before the first and after the last cycle.
    pub cycle: Option<u32>,
}

/// A validated, time-indexed program.
#[derive(Debug, Clone, PartialEq)]
pub struct Program {
    pub points: Vec<Vector3<f64>>,
    pub home: Vector3<f64>,
    pub feed_rate: f64,
    pub dwell: f64,
    pub start: f64,
    pub cycles: Option<u32>,
    /// Start-to-start time of cycles (≥ the cycle length).
    pub cycle_period: f64,
    /// Segments of one cycle, relative to its start.
    pub segments: Vec<Segment>,
    /// Approach directions after a full cycle (= while waiting at home).
    pub idle_approach: [f64; 3],
}

impl Program {
    pub fn from_section(s: &ProgramSection, m: &MachineGeometry) -> Result<Program, CellError> {
        let mut points = Vec::new();
        if let Some(g) = &s.grid {
            if !s.points.is_empty() {
                return Err(CellError::invalid("program", "give either `grid` or `points`, not both"));
            }
            let mut axes = Vec::new();
            for (name, a) in [("x", &g.x), ("y", &g.y), ("z", &g.z)] {
                let p = format!("program.grid.{name}");
                let from = a.from.to_si(&format!("{p}.from"), "m")?;
                let to = a.to.to_si(&format!("{p}.to"), "m")?;
                if a.count == 0 || a.count > 10_000 {
                    return Err(CellError::OutOfRange { path: format!("{p}.count"), value: a.count as f64, reason: "must be in 1..=10000".into() });
                }
                let n = a.count as usize;
                axes.push((0..n).map(|i| if n == 1 { from } else { from + (to - from) * i as f64 / (n - 1) as f64 }).collect::<Vec<f64>>());
            }
            // z outermost, then y, x innermost; serpentine reverses x on odd rows and y on odd layers.
            let mut row = 0usize;
            for (iz, z) in axes[2].iter().enumerate() {
                let ys: Vec<f64> = if s.order == VisitOrder::Serpentine && iz % 2 == 1 { axes[1].iter().rev().copied().collect() } else { axes[1].clone() };
                for y in ys {
                    let xs: Vec<f64> = if s.order == VisitOrder::Serpentine && row % 2 == 1 { axes[0].iter().rev().copied().collect() } else { axes[0].clone() };
                    for x in xs {
                        points.push(Vector3::new(x, y, *z));
                    }
                    row += 1;
                }
            }
        } else {
            for (i, p) in s.points.iter().enumerate() {
                points.push(vector3(p, &format!("program.points[{i}]"), "m")?);
            }
        }
        if points.is_empty() {
            return Err(CellError::invalid("program", "needs `grid` or a non-empty `points` list"));
        }
        if points.len() > 1_000_000 {
            return Err(CellError::invalid("program", "more than 1e6 points"));
        }
        let home = match &s.home {
            Some(h) => vector3(h, "program.home", "m")?,
            None => points[0],
        };
        for (i, p) in points.iter().chain(std::iter::once(&home)).enumerate() {
            let what = if i == points.len() { "program.home".to_string() } else { format!("program point {i}") };
            for (k, name) in ["x", "y", "z"].iter().enumerate() {
                let [lo, hi] = m.travel[k];
                if p[k] < lo - 1e-12 || p[k] > hi + 1e-12 {
                    return Err(CellError::OutOfRange { path: what.clone(), value: p[k], reason: format!("{name} outside machine.travel.{name} = [{lo}, {hi}] m") });
                }
            }
        }
        let feed_rate = s.feed_rate.positive("program.feed_rate", "m/s")?;
        let dwell = s.dwell.positive("program.dwell", "s")?;
        let start = s.start.as_ref().map(|q| q.non_negative("program.start", "s")).transpose()?.unwrap_or(0.0);
        let (segments, idle_approach) = build_cycle(&points, &home, feed_rate, dwell);
        let length = segments.last().map(|s| s.end).unwrap_or(0.0);
        let interval = s.cycle_interval.as_ref().map(|q| q.positive("program.cycle_interval", "s")).transpose()?.unwrap_or(length);
        Ok(Program { points, home, feed_rate, dwell, start, cycles: s.cycles, cycle_period: interval.max(length), segments, idle_approach })
    }

    /// Length of one cycle (s).
    pub fn cycle_length(&self) -> f64 {
        self.segments.last().map(|s| s.end).unwrap_or(0.0)
    }

    /// Start time of cycle `c`, or `None` if the program has fewer cycles.
    pub fn cycle_start(&self, c: u32) -> Option<f64> {
        match self.cycles {
            Some(n) if c >= n => None,
            _ => Some(self.start + c as f64 * self.cycle_period),
        }
    }

    /// Motion at time t (s from the start of the simulation).
    pub fn state_at(&self, t: f64) -> MotionState {
        let idle = |approach: [f64; 3]| MotionState { q: self.home, velocity: Vector3::zeros(), approach, dwell_point: None, cycle: None };
        if t < self.start {
            return idle([1.0; 3]);
        }
        let c = ((t - self.start) / self.cycle_period).floor() as u64;
        if let Some(n) = self.cycles {
            if c >= n as u64 {
                return idle(self.idle_approach);
            }
        }
        let c = c.min(u32::MAX as u64) as u32;
        let tc = t - self.start - c as f64 * self.cycle_period;
        if tc >= self.cycle_length() {
            return idle(self.idle_approach);
        }
        let i = self.segments.partition_point(|s| s.end <= tc).min(self.segments.len() - 1);
        let s = &self.segments[i];
        let dur = s.end - s.start;
        let (q, velocity) = if s.dwell_point.is_some() || dur <= 0.0 {
            (s.to, Vector3::zeros())
        } else {
            let f = ((tc - s.start) / dur).clamp(0.0, 1.0);
            (s.from + (s.to - s.from) * f, (s.to - s.from) / dur)
        };
        MotionState { q, velocity, approach: s.approach, dwell_point: s.dwell_point, cycle: Some(c) }
    }
}

fn build_cycle(points: &[Vector3<f64>], home: &Vector3<f64>, feed: f64, dwell: f64) -> (Vec<Segment>, [f64; 3]) {
    // Two passes: the second starts with the approach directions the first ended with (the
    // previous cycle's return home), so every cycle is identical.
    let mut approach = [1.0; 3];
    let mut segs = Vec::new();
    for _pass in 0..2 {
        segs.clear();
        let mut t = 0.0;
        let mut at = *home;
        let targets = points.iter().enumerate().map(|(i, p)| (*p, Some(i))).chain(std::iter::once((*home, None)));
        for (p, idx) in targets {
            let d = p - at;
            for k in 0..3 {
                if d[k] != 0.0 {
                    approach[k] = d[k].signum();
                }
            }
            let dur = d.norm() / feed;
            if dur > 0.0 {
                segs.push(Segment { start: t, end: t + dur, from: at, to: p, dwell_point: None, approach });
                t += dur;
            }
            if let Some(i) = idx {
                segs.push(Segment { start: t, end: t + dwell, from: p, to: p, dwell_point: Some(i), approach });
                t += dwell;
            }
            at = p;
        }
    }
    (segs, approach)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn program(points: Vec<Vector3<f64>>) -> Program {
        let home = points[0];
        let (segments, idle_approach) = build_cycle(&points, &home, 0.1, 2.0);
        Program { points, home, feed_rate: 0.1, dwell: 2.0, start: 10.0, cycles: Some(2), cycle_period: 100.0, segments, idle_approach }
    }

    #[test]
    fn timeline_moves_dwells_and_approach_directions() {
        let p = program(vec![Vector3::new(0.0, 0.0, 0.0), Vector3::new(0.2, 0.0, 0.0), Vector3::new(0.2, 0.1, 0.0)]);
        // cycle: dwell p0 [0,2), move 2 s [2,4), dwell p1 [4,6), move 1 s [6,7), dwell p2 [7,9), move home √5 s
        assert!((p.cycle_length() - (9.0 + 0.05f64.sqrt() / 0.1)).abs() < 1e-12);
        let s = p.state_at(10.0 + 3.0);
        assert!((s.q - Vector3::new(0.1, 0.0, 0.0)).norm() < 1e-12 && s.dwell_point.is_none());
        assert!((s.velocity.x - 0.1).abs() < 1e-12);
        assert_eq!(p.state_at(10.0 + 5.0).dwell_point, Some(1));
        assert_eq!(p.state_at(10.0 + 5.0).approach[0], 1.0);
        // the return home moves x negative, so the next cycle starts with x approached from +
        assert_eq!(p.state_at(110.0 + 1.0).approach[0], -1.0);
        assert_eq!(p.state_at(110.0 + 1.0).cycle, Some(1));
        // before the start and after the last cycle: idle at home
        assert_eq!(p.state_at(5.0).cycle, None);
        assert_eq!(p.state_at(250.0).cycle, None);
        assert_eq!(p.state_at(250.0).q, p.home);
        assert_eq!(p.cycle_start(2), None);
    }
}
