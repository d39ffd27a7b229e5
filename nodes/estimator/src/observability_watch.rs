//! Saying what the measurements cannot tell the estimator: the parameters it holds at their
//! start values because no measurement so far informs them (alone or apart from others), and
//! those held at an edge of their possible range (crates/estimation `recursive::observability`).
//!
//! The analysis costs an eigen-decomposition over the free parameters, so it is redone only
//! when it may have changed: the cheap per-parameter sets (held, at a bound) changed, an alarm,
//! or the accepted count reached a power of two or a multiple of 256. A change is said once the
//! filter has accepted `quiet_until` measurements (before that every parameter is still being
//! reached by the program's first points, which is no news).

use metrocell_estimation::recursive::Observability;
use metrocell_estimation::RecursiveEstimator;

/// A change in what the estimator holds, for the log and `/diagnostics`.
#[derive(Debug, Clone, PartialEq)]
pub struct ObservabilityNote {
    pub stamp_ns: i64,
    /// The sentence; None: every free parameter is observed again.
    pub text: Option<String>,
    /// Names of the parameters held because the data do not observe them.
    pub unobservable: Vec<String>,
    /// Names of the parameters held at an edge of their possible range.
    pub at_bound: Vec<String>,
}

pub struct ObservabilityWatch {
    names: Vec<String>,
    quiet_until: u64,
    held: Vec<usize>,
    at_bound: Vec<usize>,
    current: Observability,
    said: Option<String>,
}

impl ObservabilityWatch {
    pub fn new(names: Vec<String>, quiet_until: u64) -> Self {
        Self {
            names,
            quiet_until,
            held: Vec::new(),
            at_bound: Vec::new(),
            current: Observability::default(),
            said: None,
        }
    }

    /// After an update: the note to publish when what is held changed.
    pub fn after_update(
        &mut self,
        filter: &RecursiveEstimator,
        alarm: bool,
        stamp_ns: i64,
    ) -> Option<ObservabilityNote> {
        let accepted = filter.counts().0;
        let (held, at_bound) = (filter.held(), filter.at_bound());
        let due = alarm
            || held != self.held
            || at_bound != self.at_bound
            || accepted.is_power_of_two()
            || accepted.is_multiple_of(256);
        if !due {
            return None;
        }
        (self.held, self.at_bound) = (held, at_bound);
        self.current = filter.observability();
        if accepted < self.quiet_until {
            return None;
        }
        let text = self.current.describe(&self.names);
        if text == self.said {
            return None;
        }
        self.said = text.clone();
        Some(self.note(stamp_ns))
    }

    /// The latest analysis as a note (for the end of a run), whether or not it changed.
    pub fn final_note(&mut self, filter: &RecursiveEstimator, stamp_ns: i64) -> ObservabilityNote {
        self.current = filter.observability();
        self.said = self.current.describe(&self.names);
        self.note(stamp_ns)
    }

    fn note(&self, stamp_ns: i64) -> ObservabilityNote {
        let name = |k: &usize| self.names[*k].clone();
        ObservabilityNote {
            stamp_ns,
            text: self.current.describe(&self.names),
            unobservable: self
                .current
                .unobserved_parameters()
                .iter()
                .map(name)
                .collect(),
            at_bound: self.current.at_bound.iter().map(name).collect(),
        }
    }

    /// Directions of the free parameters the latest analysis counts as not observed.
    pub fn unobserved_directions(&self) -> usize {
        self.current.unobserved.len()
    }
}
