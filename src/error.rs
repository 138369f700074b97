//! The library's one error type. Every variant names the input or file that was wrong and,
//! where it can, what would be right.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// A value given on the command line or in a file is not acceptable.
    #[error("invalid {what} '{value}': expected {expected}")]
    Input {
        what: String,
        value: String,
        expected: String,
    },

    /// A fit cannot be made from the points given.
    #[error("cannot fit: {0}")]
    Fit(String),

    /// A coefficients file (or preset name) is malformed or inconsistent.
    #[error("coefficients {source_name}: {message}")]
    Coefficients {
        source_name: String,
        message: String,
    },

    #[error("cannot read {}: {source}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },

    #[error("cannot write {}: {message}", path.display())]
    Write { path: PathBuf, message: String },
}

impl Error {
    pub fn input(what: &str, value: &str, expected: &str) -> Self {
        Error::Input {
            what: what.to_string(),
            value: value.to_string(),
            expected: expected.to_string(),
        }
    }
}

pub type Result<T, E = Error> = std::result::Result<T, E>;
