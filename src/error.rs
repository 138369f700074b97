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

    /// The io error is the cause (`source()`); the CLI prints the chain in full.
    #[error("cannot read {}", path.display())]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },

    #[error("cannot write {}: {message}", path.display())]
    Write { path: PathBuf, message: String },

    /// A Blender (or bpy) was found but could not be used, or a run in it failed. `log` is
    /// the file that holds its output; `command` the shell-quoted command to rerun it.
    #[error("{}", blender_display(message, log.as_deref(), command.as_deref()))]
    Blender {
        message: String,
        log: Option<PathBuf>,
        command: Option<String>,
    },

    /// A rendered EXR could not be read back.
    #[error(transparent)]
    Exr(#[from] ExrError),

    /// No usable Blender: the message says where gloffuse looked and how to point at one.
    #[error("{0}")]
    BlenderNotFound(String),

    /// The user interrupted a Blender run (Ctrl-C): it was stopped, and nothing written.
    #[error("interrupted: Blender was stopped and nothing was written{}", log.as_ref().map(|l| format!(" (its log: {})", l.display())).unwrap_or_default())]
    Interrupted { log: Option<PathBuf> },
}

/// A one-line message gets `; log: …; command: …` appended; a multi-line one (quoted
/// output) gets them on lines of their own, so the path and command are easy to copy.
fn blender_display(message: &str, log: Option<&std::path::Path>, command: Option<&str>) -> String {
    let sep = if message.contains('\n') { "\n  " } else { "; " };
    let mut s = message.trim_end().to_string();
    if let Some(log) = log {
        s.push_str(&format!("{sep}log: {}", log.display()));
    }
    if let Some(command) = command {
        s.push_str(&format!("{sep}command: {command}"));
    }
    s
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

/// Why an EXR could not be used; each names the file.
#[derive(Debug, thiserror::Error)]
pub enum ExrError {
    #[error("EXR {} does not exist (Blender did not write it; see the log)", path.display())]
    Missing { path: PathBuf },
    #[error("EXR {} is truncated or corrupt: {why}", path.display())]
    Corrupt { path: PathBuf, why: String },
    #[error("EXR {} uses a feature gloffuse cannot read ({why}); write single-layer OPEN_EXR, 32-bit float, ZIP", path.display())]
    Unsupported { path: PathBuf, why: String },
    #[error("EXR {} has no {channel} channel (found: {found}); gloffuse needs R, G, B and A", path.display())]
    MissingChannel {
        path: PathBuf,
        channel: &'static str,
        found: String,
    },
}
