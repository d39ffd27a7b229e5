//! Noticing a parameter changed at run time (`ros2 param set`, any client of the node's
//! `set_parameters` service): [`ParamWatch`] remembers the last value it saw and reports a new
//! one once. [`crate::MetrocellNode::watch_param`] starts one on a live node.

use super::{ParamError, ParamKind};

/// The last seen value of one parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct ParamWatch<T> {
    name: String,
    last: T,
}

impl<T: ParamKind + PartialEq + Clone> ParamWatch<T> {
    /// Watch `name`, whose value is `current` now.
    pub fn new(name: &str, current: T) -> Self {
        Self {
            name: name.to_string(),
            last: current,
        }
    }

    pub fn name(&self) -> &str {
        &self.name
    }

    /// The last value seen.
    pub fn last(&self) -> &T {
        &self.last
    }

    /// Record the parameter's `current` value: `Some(current)` if it differs from the last one
    /// seen (once per change), `None` otherwise.
    pub fn update(&mut self, current: T) -> Option<T> {
        if current == self.last {
            return None;
        }
        self.last = current.clone();
        Some(current)
    }

    /// [`Self::update`] with the value `read` returns for the watched name (e.g.
    /// `|n| node.param(n)`).
    pub fn poll(
        &mut self,
        read: impl FnOnce(&str) -> Result<T, ParamError>,
    ) -> Result<Option<T>, ParamError> {
        let current = read(&self.name)?;
        Ok(self.update(current))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reports_each_change_once() {
        let mut w = ParamWatch::new("reregister", false);
        assert_eq!(w.update(false), None);
        assert_eq!(w.update(true), Some(true));
        assert_eq!(w.update(true), None, "the same value again is no change");
        assert_eq!(w.update(false), Some(false));
        assert_eq!(w.last(), &false);
        let mut n = ParamWatch::new("count", 3i64);
        assert_eq!(
            n.poll(|name| {
                assert_eq!(name, "count");
                Ok(4)
            })
            .unwrap(),
            Some(4)
        );
        assert_eq!(n.poll(|_| Ok(4)).unwrap(), None);
        let e = n.poll(|name| {
            Err(ParamError::NotDeclared {
                name: name.to_string(),
            })
        });
        assert!(e.is_err());
        assert_eq!(n.last(), &4, "an error leaves the last value");
    }
}
