//! The library's error type. Every failure says which file, strand, line or key is at fault,
//! and sorts itself into "bad input" (exit code 2) or "something else went wrong" (exit code 1).
use std::path::{Path, PathBuf};

use crate::groom::GroomError;

pub type Result<T, E = Error> = std::result::Result<T, E>;

#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// The input file is malformed: wrong magic, truncated, inconsistent counts, bad numbers.
    #[error("{path}: {message}")]
    Format { path: PathBuf, message: String },

    /// The groom read fine but breaks an invariant of the groom model; `origin` says which curve
    /// of which prim or object the strand at fault is ([`crate::Groom::strand_origin`]), or how
    /// the file was read ([`Error::read_at_units`]).
    #[error("{path}: {source}{}", origin.as_ref().map_or(String::new(), |o| format!(" ({o})")))]
    InvalidGroom {
        path: PathBuf,
        #[source]
        source: GroomError,
        origin: Option<String>,
    },

    /// A groom built in memory (generated, simulated) breaks an invariant.
    #[error(transparent)]
    Groom(#[from] GroomError),

    /// The user asked for something that cannot be done (bad option value, unknown extension).
    #[error("{0}")]
    Usage(String),

    /// The operating system refused a read or write.
    #[error("{path}: {source}")]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// An external library or helper program failed.
    #[error("{0}")]
    External(String),

    /// A static solve did not reach its tolerance and the caller required it to.
    #[error("{0}")]
    NotConverged(String),
}

impl Error {
    pub fn format(path: &Path, message: impl Into<String>) -> Self {
        Error::Format { path: path.to_path_buf(), message: message.into() }
    }

    pub fn io(path: &Path, source: std::io::Error) -> Self {
        Error::Io { path: path.to_path_buf(), source }
    }

    /// An error from working on the groom read from `path`: a groom invariant it breaks is that
    /// file's (every other error already says where it comes from).
    pub fn in_file(self, path: &Path) -> Self {
        match self {
            Error::Groom(source) => Error::InvalidGroom { path: path.to_path_buf(), source, origin: None },
            other => other,
        }
    }

    /// An error from working on a groom read at `units` (metres per unit, given as `key`: the
    /// flag or the manifest's key): a size no hair has names them, as they may have scaled the
    /// strands there.
    pub fn read_at_units(self, key: &str, units: Option<f32>) -> Self {
        match (self, units) {
            (Error::InvalidGroom { path, source, origin }, Some(units)) if source.is_a_size() => {
                let flag = format!("read at {key} {}", crate::validate::shortest(f64::from(units)));
                let origin = Some(origin.map_or(flag.clone(), |o| format!("{o}; {flag}")));
                Error::InvalidGroom { path, source, origin }
            }
            (other, _) => other,
        }
    }

    /// The process exit code the CLI uses for this error: 2 for bad input or usage, 1 otherwise.
    pub fn exit_code(&self) -> i32 {
        match self {
            Error::Format { .. } | Error::InvalidGroom { .. } | Error::Groom(_) | Error::Usage(_) => 2,
            Error::Io { source, .. } if source.kind() == std::io::ErrorKind::NotFound => 2,
            Error::Io { .. } | Error::External(_) | Error::NotConverged(_) => 1,
        }
    }
}
