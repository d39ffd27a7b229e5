//! Load terms: compliance under gravity/load, tool offset.
pub mod compliance;
pub mod tool_offset;
