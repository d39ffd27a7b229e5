//! The error type of node set-up and DDS operations.

use crate::{environment::EnvError, names::NameError, params::ParamError, ros_args::RosArgsError};

#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    #[error(transparent)]
    Args(#[from] RosArgsError),
    #[error(transparent)]
    Params(#[from] ParamError),
    #[error(transparent)]
    Env(#[from] EnvError),
    #[error(transparent)]
    Name(#[from] NameError),
    /// Creating a DDS entity (participant, topic, reader, writer) failed.
    #[error("DDS: cannot create {what}: {message}")]
    Create { what: String, message: String },
    /// Writing a sample failed.
    #[error("DDS: cannot publish on '{topic}': {message}")]
    Write { topic: String, message: String },
    /// Reading a sample failed.
    #[error("DDS: cannot read from '{topic}': {message}")]
    Read { topic: String, message: String },
    /// A raw payload that is not CDR little-endian with a 4-byte encapsulation header.
    #[error("raw payload for '{topic}': {message}")]
    Payload { topic: String, message: String },
}

pub(crate) fn create_error(what: impl Into<String>, e: impl std::fmt::Display) -> NodeError {
    NodeError::Create {
        what: what.into(),
        message: e.to_string(),
    }
}
