//! Everything that can go wrong while loading or running a launch file.
//!
//! Problems in a launch file always name the file and the 1-based line, and the key path
//! (`node.respawn_delay`, `include.arg[1].name`, ...) the problem is about.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum LaunchError {
    /// The launch file (or an included one) could not be read.
    #[error("cannot read launch file {}: {source}", file.display())]
    Read {
        file: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// The text is not valid YAML.
    #[error("{}:{line}:{column}: YAML syntax error: {message}", file.display())]
    YamlSyntax {
        file: PathBuf,
        line: usize,
        column: usize,
        message: String,
    },

    /// Valid YAML that is not a valid launch description (unknown key, wrong type, missing
    /// required key, unknown substitution, include not found, executable not found, ...).
    #[error("{}:{line}: {key}: {message}", file.display())]
    Invalid {
        file: PathBuf,
        line: usize,
        key: String,
        message: String,
    },

    /// A command-line launch argument is not of the form `name:=value`.
    #[error("launch argument '{given}' is not of the form name:=value")]
    BadArgumentSyntax { given: String },

    /// A `name:=value` given on the command line matches no `arg` declared anywhere.
    #[error("launch argument '{name}' is not declared by the launch file (declared: {declared})")]
    UndeclaredArgument { name: String, declared: String },

    /// The launcher could not install its SIGINT/SIGTERM handlers.
    #[error("cannot install signal handlers: {0}")]
    Signals(String),

    /// A process could not be started at all (the executable vanished, permissions, ...).
    #[error("cannot start [{label}] ({program}): {source}", program = program.display())]
    Spawn {
        label: String,
        program: PathBuf,
        #[source]
        source: std::io::Error,
    },
}

impl LaunchError {
    pub(crate) fn invalid(
        file: &std::path::Path,
        line: usize,
        key: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        LaunchError::Invalid {
            file: file.to_path_buf(),
            line,
            key: key.into(),
            message: message.into(),
        }
    }
}
