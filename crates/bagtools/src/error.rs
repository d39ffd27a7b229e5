//! Errors of the bag tools; each names the file (and line/column or topic) it is about.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum ToolError {
    #[error(transparent)]
    Bag(#[from] metrocell_bag::BagError),
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },
    #[error("invalid regular expression '{pattern}': {reason}")]
    Regex { pattern: String, reason: String },
    #[error("{}: {reason}", path.display())]
    Mapping { path: PathBuf, reason: String },
    #[error("{}: line {line}, column {column}: {reason}", path.display())]
    Row {
        path: PathBuf,
        line: u64,
        column: String,
        reason: String,
    },
    #[error("topic {topic}: {reason}")]
    Topic { topic: String, reason: String },
    #[error("{0}")]
    Invalid(String),
}

pub type Result<T> = std::result::Result<T, ToolError>;

/// `map_err` adapter: an I/O error about `path`.
pub fn io(path: impl Into<PathBuf>) -> impl FnOnce(std::io::Error) -> ToolError {
    let path = path.into();
    move |source| ToolError::Io { path, source }
}
