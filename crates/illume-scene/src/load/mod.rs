//! Scene loaders: glTF 2.0 (`.gltf`, `.glb`), Wavefront OBJ/MTL (`.obj`) and PLY
//! (`.ply`). Errors name the file and the place (node, accessor, line).

use crate::model::Scene;
use std::path::{Path, PathBuf};

/// Why a scene could not be loaded. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum LoadError {
    /// The file could not be opened or read.
    #[error("{path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The file's contents are malformed; `place` says where (line, node, accessor…).
    #[error("{path}: {place}: {message}")]
    Malformed {
        /// The file.
        path: PathBuf,
        /// Where in the file.
        place: String,
        /// What is wrong.
        message: String,
    },
    /// The file needs a feature illume does not have.
    #[error("{path}: {place}: unsupported: {message}")]
    Unsupported {
        /// The file.
        path: PathBuf,
        /// Where in the file.
        place: String,
        /// What is missing.
        message: String,
    },
    /// The extension is not one illume loads.
    #[error("{path}: unknown scene format (expected .gltf, .glb, .obj or .ply, or builtin:NAME)")]
    UnknownFormat {
        /// The file.
        path: PathBuf,
    },
}

/// Loads a scene file, or a built-in scene named `builtin:NAME`, at time 0.
pub fn load_scene(path: &Path) -> Result<Scene, LoadError> {
    let s = path.to_string_lossy();
    if let Some(name) = s.strip_prefix("builtin:") {
        return crate::builtin::load(name).map_err(|message| LoadError::Malformed { path: path.into(), place: "name".into(), message });
    }
    Err(LoadError::UnknownFormat { path: path.into() })
}
