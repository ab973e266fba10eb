//! Scene loaders: glTF 2.0 (`.gltf`, `.glb`), Wavefront OBJ/MTL (`.obj`) and PLY
//! (`.ply`). Errors name the file and the place (node, accessor, line).
//!
//! Contract shared by every loader:
//!
//! * a loader never panics on any input; every failure is a [`LoadError`] whose message
//!   starts with the file and then the place (glTF: node/mesh/primitive/accessor/buffer/
//!   image index; OBJ/MTL and ASCII PLY: line number; binary PLY: element index and byte
//!   offset); names and tokens quoted from the input are cut to an [`excerpt`];
//! * every file read — the scene and the buffers, libraries and textures it refers to —
//!   must be a regular file (a pipe would block, a device never ends) of at most
//!   [`MAX_FILE_BYTES`]; the malformed-input corpus (`apps/illume/tests/corpus.rs`,
//!   `docs/robustness.md`) holds every loader to this contract;
//! * the scene returned has passed [`Scene::validate`] and is evaluated at time 0;
//! * files without a camera (OBJ, PLY, glTF without a camera node) get the camera of
//!   [`default_camera_for_bounds`];
//! * non-fatal problems (a missing MTL, an ignored glTF feature) are listed in
//!   [`Scene::warnings`], never silently dropped.

mod gltf;
mod obj;
mod ply;
mod tangents;

use crate::animation::PropertyTarget;
use crate::animation::Trs;
use crate::model::{Camera, LightKind, Node, NodeId, Scene, Texture, WrapMode};
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
    load_scene_with(path, &LoadOptions::default())
}

/// How lenient loading is.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct LoadOptions {
    /// A texture file that is missing or cannot be decoded is an error. By default it is
    /// a warning naming the file (in [`Scene::warnings`]) and the material is rendered
    /// with its factors alone.
    pub strict: bool,
    /// How a glTF file's light intensities and emission are read.
    pub units: Units,
    /// Most memory the scene's textures may take once decoded \[bytes\] (12 a texel, as
    /// linear RGB, plus 1 for an alpha channel); `None`: [`MAX_SCENE_TEXTURE_BYTES`]. A
    /// texture that would pass it is an error naming the file, strict or not.
    pub max_texture_bytes: Option<u64>,
}

/// Most memory a scene's decoded textures may take by default \[bytes\]: 8 GiB. Each
/// image is also checked on its header against
/// [`illume_core::image::MAX_DECODED_IMAGE_BYTES`] (1 GiB) before it is decoded, so a
/// load stops within 1 GiB of this. The renderer adds ⅓ for mip levels and small
/// copies for photons: ≈ 11 GiB at the limit, within the 24 GiB machines the project
/// runs on with room for the frame; a scene beyond it gets a clear error instead of an
/// allocation failure that aborts the process.
pub const MAX_SCENE_TEXTURE_BYTES: u64 = 8 << 30;

/// `Ok` when `texture` fits beside the `used` bytes of the textures loaded before it
/// within `limit` ([`LoadOptions::max_texture_bytes`]); otherwise the message, with
/// both sizes and the limit.
pub(crate) fn check_texture_budget(used: u64, texture: &Texture, limit: u64) -> Result<(), String> {
    let bytes = texture.memory_bytes();
    if used.saturating_add(bytes) > limit {
        return Err(format!(
            "the scene's textures would take {} MiB with this one ({} MiB, {}×{} texels), \
             more than the {} MiB illume keeps for a scene's textures",
            (used + bytes) >> 20,
            bytes >> 20,
            texture.width,
            texture.height,
            limit >> 20
        ));
    }
    Ok(())
}

/// How glTF light intensities and emission strengths are read.
///
/// glTF's `KHR_lights_punctual` states photometric units (point and spot lights in
/// candela, directional lights in lux) and `KHR_materials_emissive_strength` luminance
/// (nits, cd/m²); Blender's exporter writes them so. illume renders radiometric
/// quantities (W/sr, W/m², W/(m²·sr)), and by default takes the numbers as such (files
/// written for illume and the shared test scenes do). `Photometric` converts with the
/// luminous efficacy of 683 lm/W (the definition of the candela at 555 nm): every
/// quantity is divided by 683 — a flat spectrum's efficacy is lower, so this is the
/// standard convention, not a physical spectral conversion.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Units {
    /// The numbers are W/sr, W/m² and W/(m²·sr) (the default).
    #[default]
    Radiometric,
    /// The numbers are cd, lx and cd/m² (glTF's own units), divided by 683 lm/W.
    Photometric,
}

/// Luminous efficacy of the photometric conversion \[lm/W\].
pub const LUMENS_PER_WATT: f32 = 683.0;

/// Converts the lights, emissive factors and their animation channels of a glTF scene
/// read in photometric units to watts ([`Units::Photometric`]).
fn photometric_to_radiometric(scene: &mut Scene) {
    let k = 1.0 / LUMENS_PER_WATT;
    for light in &mut scene.lights {
        match &mut light.kind {
            LightKind::Point { intensity } | LightKind::Spot { intensity, .. } => *intensity *= k,
            LightKind::Directional { irradiance } => *irradiance *= k,
        }
    }
    for m in &mut scene.materials {
        m.emission *= k;
    }
    for a in &mut scene.animations {
        for p in &mut a.properties {
            match &mut p.target {
                PropertyTarget::LightIntensity { colour, .. } => *colour *= k,
                PropertyTarget::LightColour { intensity, .. } => *intensity *= k,
                PropertyTarget::Emissive { strength, .. } => *strength *= k,
                _ => {}
            }
        }
    }
}

/// [`load_scene`] with options.
pub fn load_scene_with(path: &Path, options: &LoadOptions) -> Result<Scene, LoadError> {
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
    let texture_limit = options.max_texture_bytes.unwrap_or(MAX_SCENE_TEXTURE_BYTES);
    let mut scene = match ext.as_str() {
        "gltf" | "glb" => {
            let mut scene = gltf::load(path, options.strict, texture_limit)?;
            if options.units == Units::Photometric {
                photometric_to_radiometric(&mut scene);
            }
            scene
        }
        "obj" => obj::load(path, options.strict, texture_limit)?,
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
    let image = illume_core::image::RgbImage::read(path).map_err(|e| {
        // The image error names the file too: only its message is kept.
        let message = match e {
            illume_core::image::ImageError::Read { message, .. } => message,
            other => other.to_string(),
        };
        LoadError::malformed(path, "environment map", message)
    })?;
    // Scaled in place: the decoded image becomes the map's texels (a copy would hold
    // twice the decoded size, 800 MiB for an 8192 × 4096 map, while it is made).
    let (width, height) = (image.width(), image.height());
    let mut texels = image.into_pixels();
    for t in &mut texels {
        *t *= scale;
    }
    let map = crate::EnvMap {
        name: path.display().to_string(),
        width,
        height,
        texels: texels.into(),
        scale: 1.0,
        rotation_deg,
        sampling: Default::default(),
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
    illume_core::files::read_regular(path, MAX_FILE_BYTES).map_err(|source| LoadError::Io {
        path: path.into(),
        source,
    })
}

/// Reads a file a scene refers to (glTF buffer or image, MTL library, texture) as
/// [`read_file`] does, an error naming the scene file `path`, the `place` of the
/// reference and the file.
pub(crate) fn read_referenced_file(
    path: &Path,
    place: &str,
    file: &Path,
) -> Result<Vec<u8>, LoadError> {
    check_file_name(path, place, file)?;
    illume_core::files::read_regular(file, MAX_FILE_BYTES).map_err(|source| {
        LoadError::MissingFile {
            path: path.into(),
            place: place.into(),
            file: file.into(),
            source,
        }
    })
}

/// Longest path of a file a scene refers to \[bytes\] (Linux's `PATH_MAX`): a longer
/// one cannot be opened, and is not quoted in the message.
pub const MAX_PATH_BYTES: usize = 4096;

/// `Ok` when the path of `file`, referred to at `place` of `path`, is at most
/// [`MAX_PATH_BYTES`] long; otherwise an error that does not quote it.
pub(crate) fn check_file_name(path: &Path, place: &str, file: &Path) -> Result<(), LoadError> {
    let n = file.as_os_str().len();
    if n > MAX_PATH_BYTES {
        return Err(LoadError::malformed(
            path,
            place,
            format!(
                "a file name of {n} bytes ('{}'), longer than the {MAX_PATH_BYTES} a path may have",
                excerpt(&file.to_string_lossy())
            ),
        ));
    }
    Ok(())
}

/// `text` as quoted in a message (a name or token from the input): at most
/// [`EXCERPT_CHARS`] characters, then `…`.
pub fn excerpt(text: &str) -> String {
    match text.char_indices().nth(EXCERPT_CHARS) {
        Some((end, _)) => format!("{}…", &text[..end]),
        None => text.to_owned(),
    }
}

/// Longest piece of input quoted in a message \[characters\].
pub const EXCERPT_CHARS: usize = 40;

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

/// Decodes image bytes, the format found from their content or, for formats without a
/// signature (TGA), from the extension of `name`. A header claiming more than illume
/// keeps of one image as linear RGB ([`illume_core::image::check_decoded_size`]) is
/// refused before anything is decoded, and the `image` crate refuses one beyond its own
/// limit (512 MiB in the file's pixel format); either message says what the header
/// claims.
fn decode_image(bytes: &[u8], name: &str) -> Result<image::DynamicImage, String> {
    // A texture is kept as linear RGB (12 bytes a texel): its size is checked on the
    // header first, the same limit as any image illume reads.
    if let Some((w, h)) = claimed_size(bytes, name) {
        illume_core::image::check_decoded_size(w, h)?;
    }
    let decoded = match image::load_from_memory(bytes) {
        Ok(decoded) => return Ok(decoded),
        Err(e) => match image::ImageFormat::from_path(name) {
            Ok(format) => image::load_from_memory_with_format(bytes, format),
            Err(_) => Err(e),
        },
    };
    decoded.map_err(|e| match e {
        image::ImageError::Limits(_) => match claimed_size(bytes, name) {
            Some((w, h)) => format!(
                "its header claims {w}×{h} pixels, more than the {} MiB illume decodes ({e})",
                image::Limits::default().max_alloc.unwrap_or(0) >> 20
            ),
            None => e.to_string(),
        },
        e => e.to_string(),
    })
}

/// The size an image's header claims (`None` when it has no header the `image` crate
/// reads); formats without a magic number (TGA) are known by the file's name.
fn claimed_size(bytes: &[u8], name: &str) -> Option<(u32, u32)> {
    let reader = || image::ImageReader::new(std::io::Cursor::new(bytes));
    reader()
        .with_guessed_format()
        .ok()
        .and_then(|r| r.into_dimensions().ok())
        .or_else(|| {
            let format = image::ImageFormat::from_path(name).ok()?;
            let mut r = reader();
            r.set_format(format);
            r.into_dimensions().ok()
        })
}

/// An image read as a coverage (opacity) map, MTL `map_d`: its alpha channel when it
/// has one, else its first channel (a grey image), 8-bit codes divided by 255, into
/// [`Texture::alpha`]; the colour texels are 1.
pub(crate) fn decode_coverage_texture(
    bytes: &[u8],
    name: String,
    wrap_u: WrapMode,
    wrap_v: WrapMode,
) -> Result<Texture, String> {
    let decoded = decode_image(bytes, &name)?;
    let channel = if decoded.color().has_alpha() { 3 } else { 0 };
    let alpha: Vec<u8> = decoded.to_rgba8().pixels().map(|p| p[channel]).collect();
    Ok(Texture {
        name,
        width: decoded.width(),
        height: decoded.height(),
        texels: vec![Rgb::ONE; alpha.len()],
        wrap_u,
        wrap_v,
        alpha,
    })
}

/// A tangent-space normal map (glTF encoding, texel = n·½ + ½, +x along +u, +y along
/// +v) from a height map (MTL `bump`): heights are the texels' luminance in [0, 1]
/// times `texels_per_unit` texels, slopes central differences between neighbouring
/// texels (wrapping as the texture does), n = normalize(−∂h/∂u, −∂h/∂v, 1) per texel.
pub(crate) fn normal_map_from_height(height: &Texture, texels_per_unit: f32) -> Texture {
    let (w, h) = (height.width as i64, height.height as i64);
    let at = |x: i64, y: i64| {
        let cx = height.wrap_u.wrap(x, height.width);
        let cy = height.wrap_v.wrap(y, height.height);
        illume_core::luminance(height.texels[cy * height.width as usize + cx]) * texels_per_unit
    };
    let mut texels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            let du = 0.5 * (at(x + 1, y) - at(x - 1, y));
            let dv = 0.5 * (at(x, y + 1) - at(x, y - 1));
            let n = illume_core::Vec3::new(-du, -dv, 1.0).normalize();
            texels.push(n * 0.5 + illume_core::Vec3::splat(0.5));
        }
    }
    Texture {
        name: format!("{} (normals from heights)", height.name),
        width: height.width,
        height: height.height,
        texels,
        wrap_u: height.wrap_u,
        wrap_v: height.wrap_v,
        alpha: Vec::new(),
    }
}

/// Decodes an image (any format the `image` crate reads: PNG, JPEG, TGA, BMP, GIF…) into a
/// linear-RGB [`Texture`]: with `srgb` 8-bit sRGB codes are decoded, without it (data:
/// glTF's metallic-roughness and normal textures) codes are divided by 255. An alpha
/// channel that is not opaque everywhere is kept in [`Texture::alpha`]. The message of an
/// error is the decoder's.
pub(crate) fn decode_texture(
    bytes: &[u8],
    name: String,
    wrap_u: WrapMode,
    wrap_v: WrapMode,
    srgb: bool,
) -> Result<Texture, String> {
    let decoded = decode_image(bytes, &name)?;
    let alpha = if decoded.color().has_alpha() {
        let a: Vec<u8> = decoded.to_rgba8().pixels().map(|p| p[3]).collect();
        if a.iter().all(|&v| v == 255) {
            Vec::new()
        } else {
            a
        }
    } else {
        Vec::new()
    };
    let img = decoded.to_rgb8();
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
        alpha,
    })
}
