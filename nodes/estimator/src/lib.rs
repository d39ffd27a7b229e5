//! `metrocell-estimator`'s logic as a library, so its benchmark and tests drive the same code
//! the binary runs: the state (messages in through a record stream, outputs out), the messages, the
//! state file and the parameters.

pub mod estimator_state;
pub mod model_message;
pub mod observability_watch;
pub mod parameters;
pub mod state_file;
