//! Errors of the bag library. Every variant names the file and, for corrupt input, the byte
//! offset and the MCAP record kind where reading stopped.

use std::path::PathBuf;

/// Everything that can go wrong writing, reading or recovering a bag.
#[derive(Debug, thiserror::Error)]
pub enum BagError {
    /// An operating-system I/O error on a named file (open, write, fsync, rename, ...).
    #[error("{op} {}: {source}", path.display())]
    Io {
        op: &'static str,
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// Writing failed part-way (e.g. disk full). The writer stopped; the file was cut back to
    /// the end of the last completed flush and sealed, so the bag still holds `kept_messages`.
    #[error(
        "write to {} failed: {source}; recording stopped, bag sealed with the {kept_messages} \
         message(s) flushed before the failure ({lost_messages} unflushed message(s) lost)",
        path.display()
    )]
    WriteFailed {
        path: PathBuf,
        #[source]
        source: std::io::Error,
        kept_messages: u64,
        lost_messages: u64,
    },

    /// The MCAP library refused an operation (after the file itself was written fine).
    #[error("mcap error in {}: {source}", path.display())]
    Mcap {
        path: PathBuf,
        #[source]
        source: mcap::McapError,
    },

    /// The input is not a well-formed bag at a known place.
    #[error("{}: corrupt {record} record at byte offset {offset}: {reason}", path.display())]
    Corrupt {
        path: PathBuf,
        offset: u64,
        /// MCAP record kind ("Chunk", "Message", "Schema", ...) or "file" / "magic".
        record: &'static str,
        reason: String,
    },

    /// A strict reader met damage ([`BagError::Corrupt`]: a crash, a cut or overwritten file)
    /// in the bag it was asked to read: the damage, and the user's next step.
    #[error(
        "{damage}\n  the bag is damaged (cut short by a crash or a full disk?): run `metrocell bag recover {}`, which \
         rebuilds it from every chunk that reached the disk intact, then read it again",
        bag.display()
    )]
    Damaged {
        /// The bag as the reader was given it (directory or .mcap file): what to recover.
        bag: PathBuf,
        damage: Box<BagError>,
    },

    /// metadata.yaml is missing a field, has the wrong type, or does not parse.
    #[error("{}: invalid rosbag2 metadata: {reason}", path.display())]
    Metadata { path: PathBuf, reason: String },

    /// A message definition (ros2msg schema) does not parse.
    #[error("schema {type_name} line {line}: {reason}")]
    Schema {
        type_name: String,
        line: usize,
        reason: String,
    },

    /// A bad argument from the caller (unknown topic, bad type name, bad QoS YAML, ...).
    #[error("{0}")]
    InvalidArgument(String),

    /// The writer already stopped after an earlier failure or `finish()`.
    #[error("bag writer for {} is closed: {reason}", path.display())]
    Closed { path: PathBuf, reason: String },
}

impl BagError {
    /// The damage itself for [`BagError::Damaged`], the error otherwise.
    pub fn damage(&self) -> &BagError {
        match self {
            BagError::Damaged { damage, .. } => damage,
            other => other,
        }
    }

    /// Corrupt input met while reading `bag` strictly becomes [`BagError::Damaged`], which tells
    /// the user to recover it; other errors (a missing file, bad metadata) stay as they are.
    pub(crate) fn in_bag(self, bag: &std::path::Path) -> BagError {
        match self {
            BagError::Corrupt { .. } => BagError::Damaged {
                bag: bag.to_path_buf(),
                damage: Box::new(self),
            },
            other => other,
        }
    }
}

pub type Result<T, E = BagError> = std::result::Result<T, E>;

/// Attach a path and an operation name to an `io::Error`.
pub(crate) fn io_err<'a>(
    op: &'static str,
    path: &'a std::path::Path,
) -> impl FnOnce(std::io::Error) -> BagError + 'a {
    move |source| BagError::Io {
        op,
        path: path.to_path_buf(),
        source,
    }
}
