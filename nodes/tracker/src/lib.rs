//! The pure part of the `metrocell-tracker` node:
//! - [`parameters`]: declared parameters and the configuration built from them;
//! - [`tracker_state`]: the per-message logic shared by the live run and the bag replay;
//! - [`messages`]: the published messages built from the library's results.

pub mod messages;
pub mod parameters;
pub mod tracker_state;
