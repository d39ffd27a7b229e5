//! The `diagnose` node's pure parts: the sliding window of records and its schedule
//! ([`sliding_window`]), the diagnosis as `/diagnostics` statuses ([`findings_message`]), and
//! the node's parameters ([`parameters`]). The node (src/main.rs) feeds messages — live from
//! DDS or from a bag — into a `metrocell_records::RecordStream`, the window, and
//! `metrocell_diagnose::diagnose`.

pub mod findings_message;
pub mod parameters;
pub mod session;
pub mod sliding_window;
