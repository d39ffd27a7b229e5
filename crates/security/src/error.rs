//! What can go wrong with a keystore, naming the file or setting.

use std::path::{Path, PathBuf};

#[derive(Debug, thiserror::Error)]
pub enum SecurityError {
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: {why}")]
    Invalid { path: PathBuf, why: String },
    #[error("OpenSSL failed making the {what}: {source}")]
    Ssl {
        what: &'static str,
        source: openssl::error::ErrorStack,
    },
    #[error("{0}")]
    Usage(String),
}

pub(crate) fn io_error(path: &Path) -> impl Fn(std::io::Error) -> SecurityError + '_ {
    move |source| SecurityError::Io {
        path: path.to_path_buf(),
        source,
    }
}

pub(crate) fn ssl_error(
    what: &'static str,
) -> impl Fn(openssl::error::ErrorStack) -> SecurityError {
    move |source| SecurityError::Ssl { what, source }
}
