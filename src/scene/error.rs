//! Why a scene could not be loaded: the kind (for callers that act on it: a file that is
//! missing is not one that is malformed), the file at fault and its line where it has one, and
//! the whole message for people (it names the file and line too).

use std::path::{Path, PathBuf};

/// What went wrong.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// A file (the scene, or a mesh, material library or image it names) is missing or cannot
    /// be read.
    Io,
    /// A file is not valid in its format (TOML, OBJ or MTL, glTF or GLB, an image, gzip).
    Syntax,
    /// Well-formed, but not a scene hyrt can render: a required part is missing, a value is
    /// out of range, a vertex is NaN, there are no triangles, the camera has no extent.
    Invalid,
    /// Valid, but it needs what hyrt does not support (a glTF extension, a mesh format).
    Unsupported,
    /// The name is neither a built-in scene nor a file of a known kind.
    UnknownScene,
}

/// A scene that could not be loaded ([`super::load`]).
#[derive(Clone, Debug, thiserror::Error)]
#[error("{message}")]
pub struct SceneError {
    pub kind: ErrorKind,
    /// The file at fault, where one is (not for built-in scenes).
    pub file: Option<PathBuf>,
    /// Its line (from 1), where the format has lines and the fault has one.
    pub line: Option<usize>,
    message: String,
}

impl SceneError {
    /// An error of `kind` in `file` (at `line`), with the message people read.
    pub fn new(
        kind: ErrorKind,
        file: Option<&Path>,
        line: Option<usize>,
        message: impl Into<String>,
    ) -> Self {
        Self { kind, file: file.map(Path::to_path_buf), line, message: message.into() }
    }

    /// The typed error behind `e` (the innermost [`SceneError`] of its chain, with the whole
    /// chain as its message); where the chain has none, an I/O error's kind is [`ErrorKind::Io`]
    /// and anything else [`ErrorKind::Invalid`], at `file` (the file that was being loaded).
    pub(crate) fn from_chain(e: &anyhow::Error, file: Option<&Path>) -> Self {
        let message = format!("{e:#}");
        if let Some(s) = e.chain().filter_map(|c| c.downcast_ref::<SceneError>()).last() {
            return Self { message, ..s.clone() };
        }
        let io = e.chain().any(|c| c.is::<std::io::Error>());
        Self::new(if io { ErrorKind::Io } else { ErrorKind::Invalid }, file, None, message)
    }
}
