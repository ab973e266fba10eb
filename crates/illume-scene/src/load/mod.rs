//! Scene loaders: glTF 2.0 (`.gltf`, `.glb`), Wavefront OBJ/MTL (`.obj`) and PLY
//! (`.ply`). Errors name the file and the place (node, accessor, line).
//!
//! Contract shared by every loader:
//!
//! * a loader never panics on any input; every failure is a [`LoadError`] whose message
//!   starts with the file and then the place (glTF: node/mesh/primitive/accessor/buffer/
//!   image index; OBJ/MTL and ASCII PLY: line number; binary PLY: element index and byte
//!   offset);
//! * the scene returned has passed [`Scene::validate`] and is evaluated at time 0;
//! * files without a camera (OBJ, PLY, glTF without a camera node) get the camera of
//!   [`default_camera_for_bounds`];
//! * non-fatal problems (a missing MTL, an ignored glTF feature) are listed in
//!   [`Scene::warnings`], never silently dropped.

mod gltf;
mod obj;
mod ply;
mod tangents;

use crate::animation::Trs;
use crate::model::{Camera, Node, NodeId, Scene, Texture, WrapMode};
use illume_core::image::srgb_decode;
use illume_core::{Affine3A, Rgb, Vec3};
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
    /// A file the scene refers to (glTF buffer or image, OBJ texture) could not be read.
    #[error("{path}: {place}: cannot read '{file}': {source}")]
    MissingFile {
        /// The scene (or material library) file that refers to it.
        path: PathBuf,
        /// Where the reference is (`buffer 0`, `image 2`, `line 16`…).
        place: String,
        /// The referenced file, as resolved on disk.
        file: PathBuf,
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

impl LoadError {
    /// A [`LoadError::Malformed`] at `place` in `path`.
    pub(crate) fn malformed(
        path: &Path,
        place: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self::Malformed {
            path: path.into(),
            place: place.into(),
            message: message.into(),
        }
    }

    /// A [`LoadError::Unsupported`] at `place` in `path`.
    pub(crate) fn unsupported(
        path: &Path,
        place: impl Into<String>,
        message: impl Into<String>,
    ) -> Self {
        Self::Unsupported {
            path: path.into(),
            place: place.into(),
            message: message.into(),
        }
    }
}

/// Loads a scene file, or a built-in scene named `builtin:NAME`, at time 0.
///
/// The format follows the extension (case-insensitive): `.gltf`/`.glb` (glTF 2.0),
/// `.obj` (Wavefront OBJ with its MTL libraries) or `.ply`. The scene's
/// [`Scene::source`] is `path`; it has passed [`Scene::validate`] (a failure is reported
/// as [`LoadError::Malformed`] at place `scene`).
pub fn load_scene(path: &Path) -> Result<Scene, LoadError> {
    let s = path.to_string_lossy();
    if let Some(name) = s.strip_prefix("builtin:") {
        return crate::builtin::load(name).map_err(|_| LoadError::Malformed {
            path: path.into(),
            place: "name".into(),
            message: format!(
                "no such built-in scene (have: {})",
                crate::builtin::NAMES.join(", ")
            ),
        });
    }
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    let mut scene = match ext.as_str() {
        "gltf" | "glb" => gltf::load(path)?,
        "obj" => obj::load(path)?,
        "ply" => ply::load(path)?,
        _ => return Err(LoadError::UnknownFormat { path: path.into() }),
    };
    scene.source = s.into_owned();
    scene
        .validate()
        .map_err(|message| LoadError::malformed(path, "scene", message))?;
    scene.set_time(0.0);
    Ok(scene)
}

/// Reads a whole file, mapping failure to [`LoadError::Io`].
/// Reads an equirectangular environment map (linear `.exr` or Radiance `.hdr`) as a sky:
/// radiance = `scale` × texel, turned by `rotation_deg` about +Y (the mapping is
/// [`crate::EnvMap`]'s). Errors name the file: unreadable, not an HDR format, a texel
/// that is not finite or negative, a scale that is not finite and ≥ 0.
pub fn load_envmap(path: &Path, scale: f32, rotation_deg: f32) -> Result<crate::Sky, LoadError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase())
        .unwrap_or_default();
    if ext != "exr" && ext != "hdr" {
        return Err(LoadError::unsupported(
            path,
            "environment map",
            format!("'.{ext}' is not an HDR image (use linear .exr or Radiance .hdr)"),
        ));
    }
    if !scale.is_finite() || scale < 0.0 {
        return Err(LoadError::malformed(
            path,
            "environment map",
            format!("scale {scale} must be finite and ≥ 0"),
        ));
    }
    if !rotation_deg.is_finite() {
        return Err(LoadError::malformed(
            path,
            "environment map",
            format!("rotation {rotation_deg}° is not finite"),
        ));
    }
    let image = illume_core::image::RgbImage::read(path)
        .map_err(|e| LoadError::malformed(path, "environment map", e.to_string()))?;
    let map = crate::EnvMap {
        name: path.display().to_string(),
        width: image.width(),
        height: image.height(),
        texels: image.pixels().iter().map(|t| *t * scale).collect(),
        rotation_deg,
    };
    map.validate()
        .map_err(|m| LoadError::malformed(path, "environment map", m))?;
    Ok(crate::Sky::Equirect(std::sync::Arc::new(map)))
}

/// Largest file illume reads as a scene, buffer or texture \[bytes\].
pub const MAX_FILE_BYTES: u64 = 4 << 30;

/// Reads a whole file: only regular files (a pipe would block, a device never ends) of
/// at most [`MAX_FILE_BYTES`].
pub(crate) fn read_file(path: &Path) -> Result<Vec<u8>, LoadError> {
    check_regular_file(path)?;
    std::fs::read(path).map_err(|source| LoadError::Io {
        path: path.into(),
        source,
    })
}

/// `Ok` for a regular file of at most [`MAX_FILE_BYTES`]; otherwise an error naming it.
pub(crate) fn check_regular_file(path: &Path) -> Result<(), LoadError> {
    let meta = std::fs::metadata(path).map_err(|source| LoadError::Io {
        path: path.into(),
        source,
    })?;
    if !meta.is_file() {
        return Err(LoadError::malformed(
            path,
            "file",
            "not a regular file (a folder, pipe or device)",
        ));
    }
    if meta.len() > MAX_FILE_BYTES {
        return Err(LoadError::malformed(
            path,
            "file",
            format!(
                "{} bytes is more than the {} bytes illume reads",
                meta.len(),
                MAX_FILE_BYTES
            ),
        ));
    }
    Ok(())
}

/// Vertical field of view of [`default_camera_for_bounds`]'s camera, in degrees.
pub const DEFAULT_CAMERA_YFOV_DEG: f32 = 40.0;

/// Adds a root node `default_camera` and makes it the scene's camera: it looks down −Z
/// at the centre of the scene's current world bounds, far enough in front of the bounds'
/// +Z face that the whole box is in view for any aspect ratio ≥ 1 (5 % margin), with a
/// vertical field of view of [`DEFAULT_CAMERA_YFOV_DEG`]. An empty scene gets a camera
/// at (0, 0, 1) looking at the origin. World transforms are up to date on return.
pub fn default_camera_for_bounds(scene: &mut Scene) {
    scene.update_world_transforms();
    let bounds = scene.bounds();
    let yfov_rad = DEFAULT_CAMERA_YFOV_DEG.to_radians();
    let eye = if bounds.is_empty() || !bounds.min.is_finite() || !bounds.max.is_finite() {
        Vec3::Z
    } else {
        let half = bounds.extent() * 0.5;
        // The +Z face of the box is the nearest and so subtends the widest angle: fitting
        // it vertically (and horizontally, since the horizontal fov is at least as wide)
        // fits everything behind it.
        let radius = half.x.max(half.y).max(1e-3) * 1.05;
        let distance = radius / (0.5 * yfov_rad).tan();
        let c = bounds.center();
        Vec3::new(c.x, c.y, bounds.max.z + distance)
    };
    scene.nodes.push(Node {
        name: "default_camera".into(),
        parent: None,
        local: Trs::from_translation(eye),
        world_from_node: Affine3A::IDENTITY,
    });
    let node = NodeId(scene.nodes.len() as u32 - 1);
    scene.camera = Camera {
        name: "default_camera".into(),
        yfov_rad,
        node,
        world_from_camera: Affine3A::IDENTITY,
    };
    scene.update_world_transforms();
}

/// Decodes an 8-bit sRGB-encoded image (PNG, JPEG or GIF; the alpha channel is
/// dropped) into a linear-RGB [`Texture`]. The message of an error is the decoder's.
pub(crate) fn decode_srgb_texture(
    bytes: &[u8],
    name: String,
    wrap_u: WrapMode,
    wrap_v: WrapMode,
) -> Result<Texture, String> {
    decode_texture(bytes, name, wrap_u, wrap_v, true)
}

/// [`decode_srgb_texture`], or with `srgb` false an image of linear data (glTF's
/// metallic-roughness texture): 8-bit codes divided by 255.
pub(crate) fn decode_texture(
    bytes: &[u8],
    name: String,
    wrap_u: WrapMode,
    wrap_v: WrapMode,
    srgb: bool,
) -> Result<Texture, String> {
    let img = image::load_from_memory(bytes)
        .map_err(|e| e.to_string())?
        .to_rgb8();
    let lut: [f32; 256] = std::array::from_fn(|i| {
        if srgb {
            srgb_decode(i as f32 / 255.0)
        } else {
            i as f32 / 255.0
        }
    });
    let texels = img
        .pixels()
        .map(|p| Rgb::new(lut[p[0] as usize], lut[p[1] as usize], lut[p[2] as usize]))
        .collect();
    Ok(Texture {
        name,
        width: img.width(),
        height: img.height(),
        texels,
        wrap_u,
        wrap_v,
    })
}
