//! Time alignment: which commanded machine position a measurement belongs to.
//!
//! Measurements and machine state arrive on independent clocks and rates. With the commanded
//! joint states streamed (`machine/commanded_joint_states`), the position at a measurement's
//! time is interpolated linearly between the two samples around it. When only the program's
//! timing is known, the thesis's rule (P5 eq. 4) gives the time of the n-th point:
//! T_v = L_T/F + T_s·(n − 1).

use std::collections::VecDeque;

/// T_v (s) of the n-th measured point (n ≥ 1): `path_length` L_T the machine travelled (m),
/// `feed` F (m/s), `stop_time` T_s per point (s).
pub fn program_point_time(path_length: f64, feed: f64, stop_time: f64, n: u32) -> f64 {
    path_length / feed + stop_time * (n.max(1) - 1) as f64
}

/// The program's timing when no machine state is streamed: the machine leaves `home` at
/// `start_ns`, travels at `feed` between points and stops `stop_time` at each; point n (1-based)
/// is reached at start + T_v(n) with L_T the path length from home through points 1..n.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramSchedule {
    pub start_ns: i64,
    pub home: nalgebra::Vector3<f64>,
    pub points: Vec<nalgebra::Vector3<f64>>,
    /// m/s
    pub feed: f64,
    /// s
    pub stop_time: f64,
}

impl ProgramSchedule {
    /// Arrival times (s after start) at each point.
    pub fn arrivals(&self) -> Vec<f64> {
        let mut path = 0.0;
        let mut at = self.home;
        self.points
            .iter()
            .enumerate()
            .map(|(k, p)| {
                path += (p - at).norm();
                at = *p;
                program_point_time(path, self.feed, self.stop_time, k as u32 + 1)
            })
            .collect()
    }

    /// The point the machine stands at `t_ns` (index, position), if it is in a stop.
    pub fn point_at(&self, t_ns: i64) -> Option<(usize, nalgebra::Vector3<f64>)> {
        let t = (t_ns - self.start_ns) as f64 * 1e-9;
        self.arrivals()
            .into_iter()
            .position(|a| t >= a && t <= a + self.stop_time)
            .map(|k| (k, self.points[k]))
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AlignmentError {
    #[error("commanded joint state has {names} names but {positions} positions")]
    LengthMismatch { names: usize, positions: usize },
    #[error("commanded joint state: position of '{0}' is not finite")]
    NotFinite(String),
    #[error("commanded joint state at {0} ns is older than the previous one; ignored")]
    OutOfOrder(i64),
    #[error("commanded joint names changed from {0:?} to {1:?}")]
    NamesChanged(Vec<String>, Vec<String>),
    #[error("commanded joint state lacks joint '{0}'")]
    MissingJoint(String),
    #[error("no commanded position at {0} ns: no machine state received around that time")]
    NoState(i64),
    #[error("no commanded position at {t} ns: the nearest states are {gap} ns apart (more than the allowed gap)")]
    Gap { t: i64, gap: i64 },
}

/// The recent commanded joint states, for interpolation.
#[derive(Debug, Clone)]
pub struct CommandedTrajectory {
    names: Vec<String>,
    samples: VecDeque<(i64, Vec<f64>)>,
    keep_ns: i64,
    max_gap_ns: i64,
}

impl CommandedTrajectory {
    /// Keeps `keep_ns` of history; refuses to interpolate across gaps longer than `max_gap_ns`.
    pub fn new(keep_ns: i64, max_gap_ns: i64) -> Self {
        Self {
            names: Vec::new(),
            samples: VecDeque::new(),
            keep_ns,
            max_gap_ns,
        }
    }

    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Add a commanded state at `t_ns`.
    pub fn push(
        &mut self,
        t_ns: i64,
        names: &[String],
        positions: &[f64],
    ) -> Result<(), AlignmentError> {
        if names.len() != positions.len() {
            return Err(AlignmentError::LengthMismatch {
                names: names.len(),
                positions: positions.len(),
            });
        }
        if let Some(i) = positions.iter().position(|p| !p.is_finite()) {
            return Err(AlignmentError::NotFinite(names[i].clone()));
        }
        if self.samples.back().is_some_and(|(t, _)| t_ns < *t) {
            return Err(AlignmentError::OutOfOrder(t_ns));
        }
        if self.names.is_empty() {
            self.names = names.to_vec();
        } else if self.names != names {
            return Err(AlignmentError::NamesChanged(
                self.names.clone(),
                names.to_vec(),
            ));
        }
        self.samples.push_back((t_ns, positions.to_vec()));
        while self
            .samples
            .front()
            .is_some_and(|(t, _)| t_ns - *t > self.keep_ns)
        {
            self.samples.pop_front();
        }
        Ok(())
    }

    /// Time of the newest commanded state, if any.
    pub fn latest_ns(&self) -> Option<i64> {
        self.samples.back().map(|(t, _)| *t)
    }

    /// Commanded positions at `t_ns` (same order as `names()`).
    pub fn at(&self, t_ns: i64) -> Result<Vec<f64>, AlignmentError> {
        let i = self.samples.partition_point(|(t, _)| *t <= t_ns);
        if i == 0 {
            return Err(AlignmentError::NoState(t_ns));
        }
        let (t0, q0) = &self.samples[i - 1];
        if *t0 == t_ns {
            return Ok(q0.clone());
        }
        let (t1, q1) = self.samples.get(i).ok_or(AlignmentError::NoState(t_ns))?;
        if t1 - t0 > self.max_gap_ns {
            return Err(AlignmentError::Gap {
                t: t_ns,
                gap: t1 - t0,
            });
        }
        let f = (t_ns - t0) as f64 / (t1 - t0) as f64;
        Ok(q0.iter().zip(q1).map(|(a, b)| a + f * (b - a)).collect())
    }

    /// The positions of `joints` at `t_ns`, in that order.
    pub fn joints_at(&self, t_ns: i64, joints: &[String]) -> Result<Vec<f64>, AlignmentError> {
        let q = self.at(t_ns)?;
        joints
            .iter()
            .map(|j| {
                self.names
                    .iter()
                    .position(|n| n == j)
                    .map(|k| q[k])
                    .ok_or_else(|| AlignmentError::MissingJoint(j.clone()))
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn names() -> Vec<String> {
        vec!["x".into(), "y".into(), "z".into()]
    }

    #[test]
    fn interpolates_between_states() {
        let mut c = CommandedTrajectory::new(10_000_000_000, 100_000_000);
        c.push(0, &names(), &[0.0, 1.0, 2.0]).unwrap();
        c.push(10_000_000, &names(), &[0.01, 1.0, 2.0]).unwrap();
        assert_eq!(c.at(2_500_000).unwrap(), vec![0.0025, 1.0, 2.0]);
        assert_eq!(c.at(10_000_000).unwrap(), vec![0.01, 1.0, 2.0]);
        assert_eq!(
            c.joints_at(5_000_000, &["z".into(), "x".into()]).unwrap(),
            vec![2.0, 0.005]
        );
        assert_eq!(c.at(-1), Err(AlignmentError::NoState(-1)));
        assert_eq!(c.at(10_000_001), Err(AlignmentError::NoState(10_000_001)));
        assert_eq!(
            c.joints_at(1, &["b".into()]),
            Err(AlignmentError::MissingJoint("b".into()))
        );
    }

    #[test]
    fn gaps_disorder_and_bad_states_are_refused() {
        let mut c = CommandedTrajectory::new(10_000_000_000, 100_000_000);
        c.push(0, &names(), &[0.0, 0.0, 0.0]).unwrap();
        c.push(500_000_000, &names(), &[1.0, 0.0, 0.0]).unwrap();
        assert_eq!(
            c.at(250_000_000),
            Err(AlignmentError::Gap {
                t: 250_000_000,
                gap: 500_000_000
            })
        );
        assert_eq!(
            c.push(400_000_000, &names(), &[0.0; 3]),
            Err(AlignmentError::OutOfOrder(400_000_000))
        );
        assert!(
            matches!(c.push(600_000_000, &names(), &[0.0, f64::NAN, 0.0]), Err(AlignmentError::NotFinite(n)) if n == "y")
        );
        assert!(matches!(
            c.push(600_000_000, &names(), &[0.0]),
            Err(AlignmentError::LengthMismatch { .. })
        ));
        assert!(matches!(
            c.push(
                600_000_000,
                &["a".into(), "b".into(), "c".into()],
                &[0.0; 3]
            ),
            Err(AlignmentError::NamesChanged(..))
        ));
    }

    #[test]
    fn history_is_bounded() {
        let mut c = CommandedTrajectory::new(1_000, 10);
        for k in 0..10_000 {
            c.push(k * 10, &names(), &[k as f64, 0.0, 0.0]).unwrap();
        }
        assert!(c.samples.len() <= 101);
        assert_eq!(c.at(0), Err(AlignmentError::NoState(0)));
    }

    #[test]
    fn schedule_finds_the_stop_of_a_time() {
        use nalgebra::Vector3;
        let s = ProgramSchedule {
            start_ns: 1_000_000_000,
            home: Vector3::zeros(),
            points: vec![Vector3::new(0.1, 0.0, 0.0), Vector3::new(0.1, 0.2, 0.0)],
            feed: 0.05,
            stop_time: 3.0,
        };
        // 0.1 m at 50 mm/s: point 1 at 2 s; then 0.2 m more: 6 s of travel + 3 s stop → 9 s
        assert_eq!(s.arrivals(), vec![2.0, 9.0]);
        assert_eq!(
            s.point_at(1_000_000_000 + 3_500_000_000).map(|p| p.0),
            Some(0)
        );
        assert_eq!(
            s.point_at(1_000_000_000 + 10_000_000_000).map(|p| p.0),
            Some(1)
        );
        assert_eq!(s.point_at(1_000_000_000 + 6_000_000_000), None, "moving");
    }

    #[test]
    fn thesis_program_timing() {
        // 1.2 m of travel at 50 mm/s, 3 s stops: the 10th point is measured 24 + 27 = 51 s in
        assert!((program_point_time(1.2, 0.05, 3.0, 10) - 51.0).abs() < 1e-12);
        assert!((program_point_time(1.2, 0.05, 3.0, 1) - 24.0).abs() < 1e-12);
    }
}
