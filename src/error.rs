//! The one error type of sgbem.
//!
//! Every failure a user can cause is an [`Error`] whose message names the file and the
//! offending key, group, node or element, and says how to fix it. The kind decides the
//! exit status of the command line (SPEC.md): input errors 2, numerical failures 3,
//! anything else (I/O) 1.

use std::fmt;
use std::path::Path;

/// What went wrong, with a message written for the user.
#[derive(Debug, Clone, PartialEq)]
pub enum Error {
    /// Invalid scene, mesh, or combination of both (exit 2).
    Input { file: String, message: String },
    /// Singular or ill-posed system, solver not converged (exit 3).
    Numerical { message: String },
    /// Reading or writing files failed (exit 1).
    Io { file: String, message: String },
}

impl Error {
    pub fn input(file: impl AsRef<Path>, message: impl Into<String>) -> Self {
        Error::Input {
            file: file.as_ref().display().to_string(),
            message: message.into(),
        }
    }

    pub fn numerical(message: impl Into<String>) -> Self {
        Error::Numerical {
            message: message.into(),
        }
    }

    pub fn io(file: impl AsRef<Path>, err: impl fmt::Display) -> Self {
        Error::Io {
            file: file.as_ref().display().to_string(),
            message: err.to_string(),
        }
    }

    /// Exit status for the command line, as SPEC.md fixes it.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Input { .. } => 2,
            Error::Numerical { .. } => 3,
            Error::Io { .. } => 1,
        }
    }

    /// The message without the file prefix.
    pub fn message(&self) -> &str {
        match self {
            Error::Input { message, .. }
            | Error::Numerical { message }
            | Error::Io { message, .. } => message,
        }
    }
}

impl fmt::Display for Error {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Error::Input { file, message } => write!(f, "{file}: {message}"),
            Error::Numerical { message } => write!(f, "numerical failure: {message}"),
            Error::Io { file, message } => write!(f, "{file}: {message}"),
        }
    }
}

impl std::error::Error for Error {}

pub type Result<T> = std::result::Result<T, Error>;
