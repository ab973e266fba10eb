//! glTF 2.0 loader (`.gltf` with external or data-URI buffers, `.glb`).
//!
//! Parsing and schema validation are the `gltf` crate's:
//! `Gltf::from_slice_without_validation`, then the same `Validate` pass `Gltf::from_slice`
//! runs, preceded by our own checks of `extensionsRequired` (a clearer message) and of
//! the GLB header and the POSITION accessor indices (on which the crate would panic). Not
//! `gltf::import`: buffers and images are resolved here so that a missing or short file
//! is reported as *this* scene's error naming the buffer or image index. The document is
//! then read through its JSON (`gltf::json`) with every index and byte range checked, so
//! no input can make the loader panic.
//!
//! Mapping (see DESIGN.md "Conventions"):
//!
//! * the default scene (else scene 0, else every root node) is walked depth first;
//!   each glTF node becomes a [`crate::Node`] (parents before children). The whole
//!   document's hierarchy must be a forest, reachable from the scene or not: a node with
//!   two parents, a cycle or a root listed twice is an error naming the node; a node
//!   with a mesh places an [`crate::Instance`], `dynamic` when the node or an ancestor
//!   is the target of any animation channel;
//! * one illume [`Mesh`] per glTF mesh (shared by every node that uses it): its primitives
//!   are concatenated with per-triangle materials; only `TRIANGLES` primitives, indexed
//!   or not; `POSITION`, `NORMAL` (per primitive: a primitive without it is shaded flat,
//!   its vertices getting zero normals, which select the geometric normal) and one
//!   texture coordinate set, the one the primitive's material's textures ask for
//!   (`texCoord`, or `KHR_texture_transform`'s override; when slots disagree, the first
//!   slot's set is read with a warning; zero-filled when the primitive lacks it);
//! * materials (metallic-roughness): base colour = `baseColorFactor` rgb (×
//!   `baseColorTexture`, decoded sRGB → linear, wrap modes from its sampler),
//!   `metallicFactor` and `roughnessFactor` (default 1 each, as the spec; outside
//!   [0, 1] is an error), emitted radiance = `emissiveFactor` ×
//!   `KHR_materials_emissive_strength` (× `emissiveTexture`, sRGB), `doubleSided`;
//!   `metallicRoughnessTexture`
//!   (decoded linearly; blue × metallicFactor, green × roughnessFactor); `normalTexture`
//!   (linear, with `scale`; MikkTSpace tangents are computed for its meshes, which need
//!   NORMAL and texture coordinates — the file's TANGENT is not read);
//!   `KHR_texture_transform` on each of these slots; `alphaMode` MASK with `alphaCutoff`
//!   (cut-outs: [`crate::MeshCutout`]) and BLEND as MASK at 0.5 with a warning, the
//!   opacity being `baseColorFactor`'s alpha × the base-colour texture's; an image file
//!   that is missing or does not decode is a warning (the slot is dropped) unless loading
//!   is strict ([`crate::LoadOptions`]); primitives
//!   without a material get a grey (0.8) Lambertian default;
//! * camera: the lowest-index scene node with a perspective camera (`yfov`); without
//!   one, [`super::default_camera_for_bounds`];
//! * `KHR_lights_punctual`: point/spot intensity × colour = radiant intensity [W/sr],
//!   directional intensity × colour = irradiance [W/m²]; `range` is ignored with a
//!   warning;
//! * animations: translation/rotation/scale channels with `LINEAR`, `STEP` and
//!   `CUBICSPLINE`, each checked with [`Channel::validate`]; morph-target weights are
//!   ignored with a warning. The first animation is the active one.
//!   `KHR_animation_pointer` channels (taken out of the JSON before the `gltf` crate
//!   reads it) drive light intensity, colour and spot cone angles and material
//!   `baseColorFactor`, `emissiveFactor`, `metallicFactor`, `roughnessFactor`
//!   ([`PropertyChannel`]); other pointers are warnings.
//!
//! Material extensions illume does not read (`KHR_materials_transmission`, `_volume`,
//! `_clearcoat`, `_sheen`, `_specular`, `_ior`, …) are one warning per material, naming
//! the material and what it is rendered as instead; other `extensionsUsed` entries it
//! does not read are one warning per file.
//!
//! Any `extensionsRequired` entry other than `KHR_lights_punctual`,
//! `KHR_materials_emissive_strength` and `KHR_animation_pointer` is
//! [`LoadError::Unsupported`], as is an `asset.version` other than 2.x. Non-finite
//! numbers in transforms, vertex data or key values are [`LoadError::Malformed`] naming
//! the node or accessor, and so are what the specification forbids: an accessor with
//! `count` 0, a component type the use does not allow (POSITION, NORMAL and key times
//! FLOAT; TEXCOORD FLOAT, UNSIGNED_BYTE or UNSIGNED_SHORT; indices unsigned integers),
//! an animation channel targeting a node that does not exist, a `baseColorFactor`
//! outside [0, 1], a negative or non-finite emission, a camera with `znear` ≤ 0, `zfar`
//! ≤ `znear` or `aspectRatio` ≤ 0 (illume clips nothing and takes the aspect ratio from
//! the image, but such a file is broken). Buffer and image files must be regular files
//! (not pipes or devices) with paths of at most [`super::MAX_PATH_BYTES`]; names quoted
//! in messages are cut to [`super::excerpt`]s. Skins, morph targets, sparse accessors
//! and orthographic cameras are not supported (sparse accessors are an error, the rest
//! warnings).

use super::{
    LoadError, decode_texture, default_camera_for_bounds, excerpt, read_file, read_referenced_file,
};
use crate::animation::{
    Animation, Channel, ChannelValues, Interpolation, PropertyChannel, PropertyTarget, Trs,
};
use crate::builtin::SceneBuilder;
use crate::model::{
    LightId, LightKind, Material, MaterialId, Mesh, MeshId, NodeId, Scene, Sky, TextureId,
    UvTransform, WrapMode,
};
use ::gltf::json;
use illume_core::{Affine3A, Mat4, Quat, Rgb, Vec2, Vec3, Vec4};
use json::extensions::texture::TextureTransform;
use json::validation::{Checked, Validate};
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Extensions a file may list in `extensionsRequired`.
pub const SUPPORTED_REQUIRED_EXTENSIONS: [&str; 4] = [
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_animation_pointer",
    "KHR_texture_transform",
];

/// What a material looks like when the named extension, which illume does not read, is
/// ignored (for the warning).
fn unsupported_material_extension_effect(name: &str) -> &'static str {
    match name {
        "KHR_materials_transmission"
        | "KHR_materials_volume"
        | "KHR_materials_diffuse_transmission" => "rendered opaque (no light passes through)",
        "KHR_materials_ior" => "the metallic-roughness model's IOR 1.5 (F0 = 0.04) is used",
        "KHR_materials_clearcoat" => "rendered without its clear coat",
        "KHR_materials_sheen" => "rendered without sheen",
        "KHR_materials_specular" => {
            "the specular layer follows metallic-roughness (F0 = 0.04, white)"
        }
        "KHR_materials_iridescence" => "rendered without iridescence",
        "KHR_materials_anisotropy" => "rendered with isotropic roughness",
        "KHR_materials_unlit" => "shaded as lit by the scene (not unlit)",
        "KHR_materials_pbrSpecularGlossiness" => {
            "its metallic-roughness values (or their defaults) are used"
        }
        "KHR_materials_dispersion" => "rendered without dispersion",
        _ => "rendered from its core metallic-roughness values",
    }
}

/// Largest number of values (elements × components) of an accessor *without* a buffer
/// view (all zeros) accepted: guards memory against absurd counts. Accessors with data
/// are bounded by their buffer's size instead.
const MAX_ZERO_ACCESSOR_VALUES: u64 = 1 << 26;

/// Everything needed while converting one document.
struct Ctx<'a> {
    path: &'a Path,
    folder: PathBuf,
    root: &'a json::Root,
    buffers: Vec<Vec<u8>>,
    builder: SceneBuilder,
    materials: Vec<MaterialId>,
    default_material: Option<MaterialId>,
    textures: HashMap<(usize, u8, u8, bool), TextureId>,
    /// Missing or undecodable images are errors rather than warnings.
    strict: bool,
    /// The texture coordinate set each material (by glTF index) reads, for those with
    /// textures.
    uv_sets: HashMap<usize, u32>,
    meshes: HashMap<usize, MeshId>,
    camera_set: bool,
    /// `KHR_animation_pointer` channels, taken out of the document before `gltf-json`
    /// reads it (it knows only node paths).
    pointers: Vec<PointerChannel>,
    /// The illume lights made from each `KHR_lights_punctual` light (one per node).
    light_ids: HashMap<usize, Vec<LightId>>,
}

/// A `KHR_texture_transform` as illume's [`UvTransform`] and its `texCoord` override.
fn transform_of(t: Option<&TextureTransform>) -> (Option<UvTransform>, Option<u32>) {
    match t {
        Some(t) => (
            Some(UvTransform {
                offset: Vec2::from(t.offset.0),
                rotation: t.rotation.0,
                scale: Vec2::from(t.scale.0),
            }),
            t.tex_coord,
        ),
        None => (None, None),
    }
}

/// Why a texture could not be made.
enum ImageFailure {
    /// The document is wrong (a missing texture or image index, a bad data URI): an error.
    Document(LoadError),
    /// The image file is missing or does not decode: a warning unless loading is strict.
    Image(LoadError),
}

/// An animation channel whose target is a JSON pointer (`KHR_animation_pointer`).
#[derive(Clone, Debug)]
struct PointerChannel {
    animation: usize,
    channel: usize,
    sampler: usize,
    pointer: String,
}

/// Takes the `KHR_animation_pointer` channels (target path `"pointer"`) out of the
/// document's JSON, returning the document without them (re-encoded, GLB container
/// rebuilt) and the channels. A document without such channels comes back unchanged;
/// one whose JSON does not parse too (the `gltf` crate reports that error).
fn split_pointer_channels(bytes: Vec<u8>, is_glb: bool) -> (Vec<u8>, Vec<PointerChannel>) {
    let word = |b: &[u8], at: usize| {
        b.get(at..at + 4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]) as usize)
    };
    let json_range = if is_glb {
        match (word(&bytes, 12), bytes.get(16..20)) {
            (Some(len), Some(b"JSON")) if 20 + len <= bytes.len() => 20..20 + len,
            _ => return (bytes, Vec::new()),
        }
    } else {
        0..bytes.len()
    };
    let Ok(mut doc) = serde_json::from_slice::<serde_json::Value>(&bytes[json_range.clone()])
    else {
        return (bytes, Vec::new());
    };
    let mut found = Vec::new();
    if let Some(animations) = doc.get_mut("animations").and_then(|a| a.as_array_mut()) {
        for (ai, a) in animations.iter_mut().enumerate() {
            let Some(channels) = a.get_mut("channels").and_then(|c| c.as_array_mut()) else {
                continue;
            };
            let mut ci = 0;
            channels.retain(|c| {
                let target = &c["target"];
                let keep = target["path"] != "pointer";
                if !keep {
                    found.push(PointerChannel {
                        animation: ai,
                        channel: ci,
                        sampler: c["sampler"].as_u64().unwrap_or(u64::MAX) as usize,
                        pointer: target["extensions"]["KHR_animation_pointer"]["pointer"]
                            .as_str()
                            .unwrap_or("")
                            .to_owned(),
                    });
                }
                ci += 1;
                keep
            });
        }
    }
    if found.is_empty() {
        return (bytes, found);
    }
    let Ok(mut json) = serde_json::to_vec(&doc) else {
        return (bytes, Vec::new());
    };
    if !is_glb {
        return (json, found);
    }
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let rest = &bytes[json_range.end..];
    let mut out = Vec::with_capacity(20 + json.len() + rest.len());
    out.extend_from_slice(&bytes[0..8]);
    out.extend_from_slice(&((20 + json.len() + rest.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(rest);
    (out, found)
}

pub(super) fn load(path: &Path, strict: bool) -> Result<Scene, LoadError> {
    let bytes = read_file(path)?;
    let is_glb = bytes.starts_with(b"glTF");
    if is_glb {
        check_glb_header(path, &bytes)?;
    }
    let (bytes, pointers) = split_pointer_channels(bytes, is_glb);
    let document = ::gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| {
        LoadError::malformed(
            path,
            if is_glb { "GLB container" } else { "JSON" },
            e.to_string(),
        )
    })?;
    let root = document.document.as_json();
    let version = &root.asset.version;
    if version.split('.').next() != Some("2") {
        return Err(LoadError::unsupported(
            path,
            "asset.version",
            format!("glTF '{}' (illume reads glTF 2.x)", excerpt(version)),
        ));
    }
    for (i, ext) in root.extensions_required.iter().enumerate() {
        if !SUPPORTED_REQUIRED_EXTENSIONS.contains(&ext.as_str()) {
            return Err(LoadError::unsupported(
                path,
                format!("extensionsRequired[{i}]"),
                format!("required extension '{ext}'"),
            ));
        }
    }
    // gltf-json's validation indexes `accessors` with a primitive's POSITION index
    // unchecked: check every attribute reference first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            for (semantic, a) in &prim.attributes {
                if a.value() >= root.accessors.len() {
                    let name = match semantic {
                        Checked::Valid(s) => s.to_string(),
                        Checked::Invalid => "(invalid)".into(),
                    };
                    return Err(LoadError::malformed(
                        path,
                        format!("mesh {m} primitive {p}"),
                        format!(
                            "attribute {name} uses accessor {}, which does not exist ({} accessors)",
                            a.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    // The same schema validation `Gltf::from_slice` runs, reported with its JSON paths.
    let mut problems = Vec::new();
    root.validate(root, json::Path::new, &mut |p, e| {
        problems.push(format!("{}: {e}", p()))
    });
    if !problems.is_empty() {
        let n = problems.len();
        problems.truncate(5);
        let more = if n > 5 {
            format!(" (and {} more)", n - 5)
        } else {
            String::new()
        };
        return Err(LoadError::malformed(
            path,
            "validation",
            format!("{}{more}", problems.join("; ")),
        ));
    }
    let folder = path
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_else(|| PathBuf::from("."));
    let buffers = load_buffers(path, &folder, root, document.blob.as_deref())?;
    let ctx = Ctx {
        path,
        folder,
        root,
        buffers,
        builder: SceneBuilder::new(),
        materials: Vec::new(),
        default_material: None,
        textures: HashMap::new(),
        strict,
        uv_sets: HashMap::new(),
        meshes: HashMap::new(),
        camera_set: false,
        pointers,
        light_ids: HashMap::new(),
    };
    let sky = sky_from_extras(path, root)?;
    let mut scene = ctx.convert()?;
    scene.sky = sky;
    // Extensions used (not required) that illume does not read at all; material
    // extensions are named per material by `convert`.
    for ext in &root.extensions_used {
        let read = SUPPORTED_REQUIRED_EXTENSIONS.contains(&ext.as_str())
            || ext.starts_with("KHR_materials_");
        if !read {
            scene.warnings.push(format!(
                "{}: extension {} is not supported, ignored (the file says it can be read without it)",
                path.display(),
                excerpt(ext)
            ));
        }
    }
    Ok(scene)
}

/// The sky declared in the document's root `extras` (no standard glTF extension holds
/// a renderable sky), exactly one of `{"illume_sky": {"radiance": [R, G, B]}}`
/// [W/(m²·sr)] or `{"illume_sky": {"equirect": "FILE", "scale": S, "rotation_deg": A}}`
/// (FILE relative to the glTF, linear `.exr`/`.hdr`; S defaults to 1, A to 0). Anything
/// else under `illume_sky` is an error naming the field.
fn sky_from_extras(path: &Path, root: &json::Root) -> Result<Option<Sky>, LoadError> {
    let Some(raw) = &root.extras else {
        return Ok(None);
    };
    let place = "extras.illume_sky";
    let value: serde_json::Value = serde_json::from_str(raw.get())
        .map_err(|e| LoadError::malformed(path, "extras", e.to_string()))?;
    let Some(sky) = value.get("illume_sky") else {
        return Ok(None);
    };
    let Some(table) = sky.as_object() else {
        return Err(LoadError::malformed(path, place, "must be an object"));
    };
    const KEYS: [&str; 4] = ["radiance", "equirect", "scale", "rotation_deg"];
    if let Some(key) = table.keys().find(|k| !KEYS.contains(&k.as_str())) {
        return Err(LoadError::malformed(
            path,
            place,
            format!("unknown key '{key}' (have: {})", KEYS.join(", ")),
        ));
    }
    let number = |key: &str, default: f32| -> Result<f32, LoadError> {
        match table.get(key) {
            None => Ok(default),
            Some(v) => v
                .as_f64()
                .map(|v| v as f32)
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    LoadError::malformed(path, format!("{place}.{key}"), "must be a finite number")
                }),
        }
    };
    match (table.get("radiance"), table.get("equirect")) {
        (Some(_), Some(_)) => Err(LoadError::malformed(
            path,
            place,
            "give exactly one of `radiance` and `equirect`",
        )),
        (None, None) => Err(LoadError::malformed(
            path,
            place,
            "needs `radiance` [R, G, B] or `equirect` \"FILE\"",
        )),
        (Some(radiance), None) => {
            if table.contains_key("scale") || table.contains_key("rotation_deg") {
                return Err(LoadError::malformed(
                    path,
                    place,
                    "`scale` and `rotation_deg` belong to `equirect`",
                ));
            }
            let bad = || {
                LoadError::malformed(
                    path,
                    format!("{place}.radiance"),
                    "must be three finite numbers ≥ 0 [W/(m²·sr)]",
                )
            };
            let list = radiance.as_array().ok_or_else(bad)?;
            let c: Vec<f32> = list
                .iter()
                .filter_map(|v| v.as_f64())
                .map(|v| v as f32)
                .collect();
            if list.len() != 3 || c.len() != 3 || c.iter().any(|v| !v.is_finite() || *v < 0.0) {
                return Err(bad());
            }
            Ok(Some(Sky::Uniform {
                radiance: Rgb::new(c[0], c[1], c[2]),
            }))
        }
        (None, Some(file)) => {
            let file = file.as_str().ok_or_else(|| {
                LoadError::malformed(path, format!("{place}.equirect"), "must be a file name")
            })?;
            let scale = number("scale", 1.0)?;
            let rotation = number("rotation_deg", 0.0)?;
            let folder = path.parent().unwrap_or(Path::new("."));
            super::load_envmap(&folder.join(file), scale, rotation)
                .map(Some)
                .map_err(|e| LoadError::malformed(path, format!("{place}.equirect"), e.to_string()))
        }
    }
}

/// Checks the 12-byte GLB header before the `gltf` crate reads it (it subtracts 12 from
/// the declared length without checking, which overflows on a corrupt header).
fn check_glb_header(path: &Path, bytes: &[u8]) -> Result<(), LoadError> {
    let place = "GLB header";
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(LoadError::malformed(
            path,
            place,
            format!(
                "file has {} bytes, the header needs 12 (truncated)",
                bytes.len()
            ),
        ));
    };
    if version != 2 {
        return Err(LoadError::unsupported(
            path,
            place,
            format!("GLB version {version} (only 2)"),
        ));
    }
    if length < 20 {
        return Err(LoadError::malformed(
            path,
            place,
            format!("declared length {length} is too small for a JSON chunk"),
        ));
    }
    if length as usize > bytes.len() {
        return Err(LoadError::malformed(
            path,
            place,
            format!(
                "declared length {length} but the file has {} bytes (truncated)",
                bytes.len()
            ),
        ));
    }
    Ok(())
}

/// Reads every buffer: the GLB binary chunk, a data URI or a file next to the glTF.
fn load_buffers(
    path: &Path,
    folder: &Path,
    root: &json::Root,
    blob: Option<&[u8]>,
) -> Result<Vec<Vec<u8>>, LoadError> {
    let mut out = Vec::with_capacity(root.buffers.len());
    for (i, b) in root.buffers.iter().enumerate() {
        let place = format!("buffer {i}");
        let data = match b.uri.as_deref() {
            None => blob
                .ok_or_else(|| {
                    LoadError::malformed(path, &place, "no uri and no GLB binary chunk")
                })?
                .to_vec(),
            Some(uri) if uri.starts_with("data:") => {
                decode_data_uri(uri).map_err(|m| LoadError::malformed(path, &place, m))?
            }
            Some(uri) => read_referenced_file(path, &place, &folder.join(decode_uri_path(uri)))?,
        };
        let need = b.byte_length.0;
        if (data.len() as u64) < need {
            return Err(LoadError::malformed(
                path,
                place,
                format!(
                    "has {} bytes but byteLength is {need} (truncated?)",
                    data.len()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// Decodes `data:[<media type>][;base64],<data>`.
fn decode_data_uri(uri: &str) -> Result<Vec<u8>, String> {
    let (header, data) = uri.split_once(',').ok_or("data URI without ','")?;
    if header.ends_with(";base64") {
        base64::decode(data.trim()).map_err(|e| format!("bad base64 in data URI: {e}"))
    } else {
        Ok(urlencoding::decode_binary(data.as_bytes()).into_owned())
    }
}

/// A relative URI as a file path (percent-decoded).
fn decode_uri_path(uri: &str) -> String {
    urlencoding::decode(uri)
        .map(|s| s.into_owned())
        .unwrap_or_else(|_| uri.to_string())
}

fn wrap_mode(m: &Checked<json::texture::WrappingMode>) -> WrapMode {
    use json::texture::WrappingMode as W;
    match m {
        Checked::Valid(W::ClampToEdge) => WrapMode::Clamp,
        Checked::Valid(W::MirroredRepeat) => WrapMode::Mirror,
        _ => WrapMode::Repeat,
    }
}

fn component_size(c: json::accessor::ComponentType) -> usize {
    use json::accessor::ComponentType as C;
    match c {
        C::I8 | C::U8 => 1,
        C::I16 | C::U16 => 2,
        C::U32 | C::F32 => 4,
    }
}

fn components(t: json::accessor::Type) -> usize {
    use json::accessor::Type as T;
    match t {
        T::Scalar => 1,
        T::Vec2 => 2,
        T::Vec3 => 3,
        T::Vec4 | T::Mat2 => 4,
        T::Mat3 => 9,
        T::Mat4 => 16,
    }
}

impl Ctx<'_> {
    fn malformed(&self, place: impl Into<String>, message: impl Into<String>) -> LoadError {
        LoadError::malformed(self.path, place, message)
    }

    fn warn(&mut self, w: String) {
        let msg = format!("{}: {w}", self.path.display());
        self.builder.warn(msg);
    }

    /// The bytes of buffer view `index`, bounds-checked against its buffer.
    fn view_bytes(&self, index: usize) -> Result<&[u8], LoadError> {
        let place = format!("bufferView {index}");
        let view = self
            .root
            .buffer_views
            .get(index)
            .ok_or_else(|| self.malformed(&place, "does not exist"))?;
        let b = view.buffer.value();
        let buffer = self
            .buffers
            .get(b)
            .ok_or_else(|| self.malformed(&place, format!("buffer {b} does not exist")))?;
        let start = view.byte_offset.map(|o| o.0).unwrap_or(0);
        let end = start.saturating_add(view.byte_length.0);
        if end > buffer.len() as u64 {
            return Err(self.malformed(
                place,
                format!(
                    "bytes {start}..{end} exceed buffer {b} ({} bytes)",
                    buffer.len()
                ),
            ));
        }
        Ok(&buffer[start as usize..end as usize])
    }

    /// Reads accessor `index` as `f64`s (`count × components`, row by row; normalized
    /// integers mapped to [0, 1] or [−1, 1]) and returns them with the component count.
    /// `what` names the use for messages. Non-finite values are an error.
    fn read_accessor(&self, index: usize, what: &str) -> Result<(Vec<f64>, usize), LoadError> {
        let place = format!("accessor {index} ({what})");
        let acc = self
            .root
            .accessors
            .get(index)
            .ok_or_else(|| self.malformed(&place, "does not exist"))?;
        let (Checked::Valid(ty), Checked::Valid(json::accessor::GenericComponentType(ct))) =
            (&acc.type_, &acc.component_type)
        else {
            return Err(self.malformed(place, "invalid type or componentType"));
        };
        if acc.sparse.is_some() {
            return Err(LoadError::unsupported(self.path, place, "sparse accessors"));
        }
        let n_comp = components(*ty);
        let count = acc.count.0;
        if count == 0 {
            return Err(self.malformed(place, "count 0 (glTF requires at least 1)"));
        }
        let Some(view_index) = acc.buffer_view.map(|v| v.value()) else {
            if count.saturating_mul(n_comp as u64) > MAX_ZERO_ACCESSOR_VALUES {
                return Err(self.malformed(place, format!("count {count} is too large")));
            }
            // glTF: an accessor without a buffer view is all zeros.
            return Ok((vec![0.0; count as usize * n_comp], n_comp));
        };
        let count = usize::try_from(count)
            .map_err(|_| self.malformed(&place, format!("count {count} is too large")))?;
        let bytes = self.view_bytes(view_index)?;
        let csize = component_size(*ct);
        let elem = (csize * n_comp) as u64;
        let stride = self
            .root
            .buffer_views
            .get(view_index)
            .and_then(|v| v.byte_stride)
            .map(|s| s.0 as u64)
            .unwrap_or(elem);
        let offset = acc.byte_offset.map(|o| o.0).unwrap_or(0);
        if count > 0 {
            let end = (count as u64 - 1)
                .checked_mul(stride)
                .and_then(|x| x.checked_add(offset))
                .and_then(|x| x.checked_add(elem));
            if end.is_none_or(|e| e > bytes.len() as u64) {
                return Err(self.malformed(
                    place,
                    format!("{count} elements of {elem} bytes (stride {stride}) from offset {offset} exceed bufferView {view_index} ({} bytes)", bytes.len()),
                ));
            }
        }
        use json::accessor::ComponentType as C;
        let normalized = acc.normalized;
        let mut out = Vec::with_capacity(count * n_comp);
        for i in 0..count {
            let base = offset as usize + i * stride as usize;
            for c in 0..n_comp {
                let at = base + c * csize;
                let b = bytes
                    .get(at..at + csize)
                    .ok_or_else(|| self.malformed(&place, format!("element {i} out of bounds")))?;
                let x = match ct {
                    C::I8 => {
                        let v = b[0] as i8 as f64;
                        if normalized { (v / 127.0).max(-1.0) } else { v }
                    }
                    C::U8 => {
                        let v = b[0] as f64;
                        if normalized { v / 255.0 } else { v }
                    }
                    C::I16 => {
                        let v = i16::from_le_bytes([b[0], b[1]]) as f64;
                        if normalized {
                            (v / 32767.0).max(-1.0)
                        } else {
                            v
                        }
                    }
                    C::U16 => {
                        let v = u16::from_le_bytes([b[0], b[1]]) as f64;
                        if normalized { v / 65535.0 } else { v }
                    }
                    C::U32 => u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                    C::F32 => f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64,
                };
                if !x.is_finite() {
                    return Err(self.malformed(
                        place,
                        format!("element {i} component {c} is not finite ({x})"),
                    ));
                }
                out.push(x);
            }
        }
        Ok((out, n_comp))
    }

    /// Checks that accessor `index` (used as `what`) has one of the component types glTF
    /// allows for that use (`allowed`, named `names` in the message). A missing accessor
    /// is left to [`Ctx::read_accessor`] to report.
    fn check_component_type(
        &self,
        index: usize,
        what: &str,
        allowed: &[json::accessor::ComponentType],
        names: &str,
    ) -> Result<(), LoadError> {
        if let Some(acc) = self.root.accessors.get(index)
            && let Checked::Valid(json::accessor::GenericComponentType(ct)) = acc.component_type
            && !allowed.contains(&ct)
        {
            return Err(self.malformed(
                format!("accessor {index} ({what})"),
                format!("componentType {ct:?} is not allowed here (only {names})"),
            ));
        }
        Ok(())
    }

    /// Reads an accessor that must have `n` components per element, as `f32` arrays.
    fn read_vecs<const N: usize>(
        &self,
        index: usize,
        what: &str,
    ) -> Result<Vec<[f32; N]>, LoadError> {
        let (v, n) = self.read_accessor(index, what)?;
        if n != N {
            return Err(self.malformed(
                format!("accessor {index} ({what})"),
                format!("has {n} components per element, expected {N}"),
            ));
        }
        Ok(v.chunks_exact(N)
            .map(|c| std::array::from_fn(|k| c[k] as f32))
            .collect())
    }

    fn convert(mut self) -> Result<Scene, LoadError> {
        self.convert_materials()?;
        self.check_hierarchy()?;
        let roots = self.scene_roots()?;
        let order = self.walk(&roots)?;
        // glTF node index → illume node, in walk order (parents first).
        let mut node_ids: Vec<Option<NodeId>> = vec![None; self.root.nodes.len()];
        let mut placements = Vec::new();
        for &(g, parent) in &order {
            let node = &self.root.nodes[g];
            let name = node.name.clone().unwrap_or_else(|| format!("node {g}"));
            let local = self.node_trs(g)?;
            let parent_id = parent.and_then(|p| node_ids[p]);
            let id = self.builder.node(&name, parent_id, local);
            node_ids[g] = Some(id);
            if let Some(mesh) = node.mesh {
                let mesh_id = self.mesh(mesh.value())?;
                placements.push((name.clone(), mesh_id, id));
            }
            let shown = excerpt(&name);
            if node.skin.is_some() {
                self.warn(format!(
                    "node {g} '{shown}': skin ignored (rendered in bind pose)"
                ));
            }
            if node.weights.is_some() {
                self.warn(format!("node {g} '{shown}': morph weights ignored"));
            }
            self.light(g, &name, id)?;
        }
        self.camera(&order, &node_ids)?;
        let targeted = self.animations(&node_ids)?;
        // Moving = targeted itself or through an ancestor (parents come first).
        let nodes = &self.builder.scene().nodes;
        let mut moving = vec![false; nodes.len()];
        for id in targeted {
            if let Some(m) = moving.get_mut(id.index()) {
                *m = true;
            }
        }
        for i in 0..nodes.len() {
            if let Some(p) = nodes[i].parent {
                moving[i] |= moving.get(p.index()).copied().unwrap_or(false);
            }
        }
        for (name, mesh, node) in placements {
            let dynamic = moving.get(node.index()).copied().unwrap_or(false);
            self.builder.instance(&name, mesh, node, dynamic);
        }
        let mut scene = self.builder.finish(&self.path.to_string_lossy());
        if !self.camera_set {
            default_camera_for_bounds(&mut scene);
        }
        Ok(scene)
    }

    /// Root nodes of the scene to load: `scene`, else scene 0, else every node that is
    /// nobody's child.
    fn scene_roots(&self) -> Result<Vec<usize>, LoadError> {
        let chosen = self
            .root
            .scene
            .map(|s| s.value())
            .or(if self.root.scenes.is_empty() {
                None
            } else {
                Some(0)
            });
        match chosen {
            Some(s) => {
                let scene =
                    self.root.scenes.get(s).ok_or_else(|| {
                        self.malformed("scene", format!("scene {s} does not exist"))
                    })?;
                Ok(scene.nodes.iter().map(|n| n.value()).collect())
            }
            None => {
                let mut is_child = vec![false; self.root.nodes.len()];
                for n in &self.root.nodes {
                    for c in n.children.iter().flatten() {
                        if let Some(flag) = is_child.get_mut(c.value()) {
                            *flag = true;
                        }
                    }
                }
                Ok((0..self.root.nodes.len())
                    .filter(|&i| !is_child[i])
                    .collect())
            }
        }
    }

    /// The whole document's node hierarchy (reachable from the scene or not) must be a
    /// forest, as glTF requires: every child exists, no node has two parents and no node
    /// is its own ancestor. The error names the node.
    fn check_hierarchy(&self) -> Result<(), LoadError> {
        let n = self.root.nodes.len();
        let mut parent: Vec<Option<usize>> = vec![None; n];
        for (p, node) in self.root.nodes.iter().enumerate() {
            for c in node.children.iter().flatten().map(|c| c.value()) {
                let Some(slot) = parent.get_mut(c) else {
                    return Err(self.malformed(
                        format!("node {p}"),
                        format!("child {c} does not exist ({n} nodes)"),
                    ));
                };
                if let Some(first) = slot.replace(p) {
                    return Err(self.malformed(
                        format!("node {c}"),
                        format!(
                            "is a child of node {first} and of node {p} (a node has at most one parent)"
                        ),
                    ));
                }
            }
        }
        // One parent each: follow parents from every node, each node walked once.
        let mut walked_from = vec![usize::MAX; n];
        let mut done = vec![false; n];
        for start in 0..n {
            let mut at = start;
            while !done[at] {
                if walked_from[at] == start {
                    return Err(self.malformed(
                        format!("node {at}"),
                        "is its own ancestor (a cycle in the node hierarchy)",
                    ));
                }
                walked_from[at] = start;
                match parent[at] {
                    Some(p) => at = p,
                    None => break,
                }
            }
            let mut at = start;
            while walked_from[at] == start && !done[at] {
                done[at] = true;
                match parent[at] {
                    Some(p) => at = p,
                    None => break,
                }
            }
        }
        Ok(())
    }

    /// Depth-first order of the nodes under `roots` as `(node, parent)`; parents come
    /// before their children. A node reached twice is an error.
    fn walk(&self, roots: &[usize]) -> Result<Vec<(usize, Option<usize>)>, LoadError> {
        let mut seen = vec![false; self.root.nodes.len()];
        let mut order = Vec::new();
        let mut stack: Vec<(usize, Option<usize>)> =
            roots.iter().rev().map(|&r| (r, None)).collect();
        while let Some((n, parent)) = stack.pop() {
            let place = format!("node {n}");
            let node = self
                .root
                .nodes
                .get(n)
                .ok_or_else(|| self.malformed(&place, "does not exist"))?;
            if std::mem::replace(&mut seen[n], true) {
                return Err(self.malformed(
                    place,
                    "reached twice in the hierarchy (a cycle, two parents or a repeated root)",
                ));
            }
            order.push((n, parent));
            for c in node.children.iter().flatten().rev() {
                stack.push((c.value(), Some(n)));
            }
        }
        Ok(order)
    }

    /// The local transform of node `g`; non-finite values are an error.
    fn node_trs(&self, g: usize) -> Result<Trs, LoadError> {
        let node = &self.root.nodes[g];
        let place = format!("node {g} '{}'", excerpt(node.name.as_deref().unwrap_or("")));
        if let Some(m) = node.matrix {
            if m.iter().any(|x| !x.is_finite()) {
                return Err(self.malformed(place, format!("matrix is not finite: {m:?}")));
            }
            let trs = Trs::from_affine(&Affine3A::from_mat4(Mat4::from_cols_array(&m)));
            if !trs.is_finite() {
                return Err(self.malformed(
                    place,
                    "matrix cannot be decomposed into translation, rotation and scale",
                ));
            }
            return Ok(trs);
        }
        let t = node.translation.unwrap_or([0.0; 3]);
        let r = node.rotation.map(|q| q.0).unwrap_or([0.0, 0.0, 0.0, 1.0]);
        let s = node.scale.unwrap_or([1.0; 3]);
        if t.iter().chain(&r).chain(&s).any(|x| !x.is_finite()) {
            return Err(self.malformed(
                place,
                format!("transform is not finite: translation {t:?}, rotation {r:?}, scale {s:?}"),
            ));
        }
        let q = Quat::from_array(r);
        if q.length_squared() == 0.0 {
            return Err(self.malformed(place, "rotation quaternion is zero"));
        }
        Ok(Trs {
            translation: Vec3::from(t),
            rotation: q.normalize(),
            scale: Vec3::from(s),
        })
    }

    fn convert_materials(&mut self) -> Result<(), LoadError> {
        for (i, m) in self.root.materials.iter().enumerate() {
            let name = m.name.clone().unwrap_or_else(|| format!("material {i}"));
            let pbr = &m.pbr_metallic_roughness;
            let [r, g, b, alpha] = pbr.base_color_factor.0;
            let strength = m
                .extensions
                .as_ref()
                .and_then(|e| e.emissive_strength.as_ref())
                .map(|s| s.emissive_strength.0)
                .unwrap_or(1.0);
            let user = format!("material {i} '{}'", excerpt(&name));
            if ![r, g, b].iter().all(|v| (0.0..=1.0).contains(v)) {
                return Err(self.malformed(
                    &user,
                    format!("baseColorFactor {:?} is not in [0, 1]", [r, g, b]),
                ));
            }
            let emissive = m.emissive_factor.0;
            if !emissive.iter().all(|v| v.is_finite() && *v >= 0.0) {
                return Err(self.malformed(
                    &user,
                    format!("emissiveFactor {emissive:?} must be finite and ≥ 0"),
                ));
            }
            if !(strength.is_finite() && strength >= 0.0) {
                return Err(self.malformed(
                    &user,
                    format!(
                        "KHR_materials_emissive_strength emissiveStrength {strength} must be finite and ≥ 0"
                    ),
                ));
            }
            let (base_color_texture, base_color_transform) = self.info_slot(
                pbr.base_color_texture.as_ref(),
                &user,
                "baseColorTexture",
                true,
            )?;
            // glTF's defaults are 1 for both factors (a rough metal), as the spec says.
            let (metallic, roughness) = (pbr.metallic_factor.0, pbr.roughness_factor.0);
            for (field, v) in [("metallicFactor", metallic), ("roughnessFactor", roughness)] {
                if !(0.0..=1.0).contains(&v) {
                    return Err(self.malformed(&user, format!("{field} {v} is not in [0, 1]")));
                }
            }
            let (metallic_roughness_texture, metallic_roughness_transform) = self.info_slot(
                pbr.metallic_roughness_texture.as_ref(),
                &user,
                "metallicRoughnessTexture",
                false,
            )?;
            let (emissive_texture, emissive_transform) =
                self.info_slot(m.emissive_texture.as_ref(), &user, "emissiveTexture", true)?;
            let (normal_texture, normal_transform, normal_scale) = match &m.normal_texture {
                Some(info) => {
                    if !info.scale.is_finite() {
                        return Err(self.malformed(&user, "normalTexture.scale is not finite"));
                    }
                    // `gltf` types this slot's extensions as an open map.
                    let parsed = info
                        .extensions
                        .as_ref()
                        .and_then(|e| e.others.get("KHR_texture_transform"))
                        .map(|v| serde_json::from_value::<TextureTransform>(v.clone()));
                    let parsed = match parsed {
                        Some(Ok(t)) => Some(t),
                        Some(Err(e)) => {
                            return Err(self.malformed(
                                &user,
                                format!("normalTexture KHR_texture_transform: {e}"),
                            ));
                        }
                        None => None,
                    };
                    let (texture, transform) = self.texture_slot(
                        info.index.value(),
                        info.tex_coord,
                        transform_of(parsed.as_ref()),
                        &user,
                        "normalTexture",
                        false,
                    )?;
                    (texture, transform, info.scale)
                }
                None => (None, None, 1.0),
            };
            // Material extensions illume does not read: one warning each, saying what the
            // material is rendered as instead.
            if let Some(ext) = &m.extensions {
                let mut names: Vec<&String> = ext.others.keys().collect();
                names.sort();
                for name in names {
                    self.warn(format!(
                        "{user}: extension {} is not supported, ignored: {}",
                        excerpt(name),
                        unsupported_material_extension_effect(name)
                    ));
                }
            }
            let alpha_cutoff = match m.alpha_mode {
                Checked::Valid(json::material::AlphaMode::Opaque) => None,
                Checked::Valid(json::material::AlphaMode::Mask) => {
                    let cutoff = m.alpha_cutoff.map_or(0.5, |c| c.0);
                    if !(cutoff.is_finite() && cutoff >= 0.0) {
                        return Err(self.malformed(
                            &user,
                            format!("alphaCutoff {cutoff} is not a finite number ≥ 0"),
                        ));
                    }
                    Some(cutoff)
                }
                Checked::Valid(json::material::AlphaMode::Blend) => {
                    self.warn(format!(
                        "{user}: alphaMode BLEND is rendered as MASK with alphaCutoff 0.5 (no partial transparency)"
                    ));
                    Some(0.5)
                }
                Checked::Invalid => {
                    return Err(self.malformed(&user, "alphaMode is not OPAQUE, MASK or BLEND"));
                }
            };
            if !(alpha.is_finite() && (0.0..=1.0).contains(&alpha)) {
                return Err(self.malformed(
                    &user,
                    format!("baseColorFactor alpha {alpha} is not in [0, 1]"),
                ));
            }
            let material = Material {
                name,
                alpha,
                alpha_texture: base_color_texture,
                alpha_cutoff,
                base_color: Rgb::new(r, g, b),
                base_color_transform,
                metallic_roughness_transform,
                normal_transform,
                emissive_transform,
                normal_texture,
                normal_scale,
                base_color_texture,
                emission: Rgb::from(m.emissive_factor.0) * strength,
                emissive_texture,
                metallic,
                roughness,
                metallic_roughness_texture,
                double_sided: m.double_sided,
            };
            let id = self.builder.material(material);
            self.materials.push(id);
        }
        Ok(())
    }

    /// [`Ctx::texture_slot`] for a slot given as a glTF texture info (all but the normal
    /// map), `(None, None)` without one.
    fn info_slot(
        &mut self,
        info: Option<&json::texture::Info>,
        user: &str,
        slot: &str,
        srgb: bool,
    ) -> Result<(Option<TextureId>, Option<UvTransform>), LoadError> {
        let Some(info) = info else {
            return Ok((None, None));
        };
        let transform = transform_of(
            info.extensions
                .as_ref()
                .and_then(|e| e.texture_transform.as_ref()),
        );
        self.texture_slot(
            info.index.value(),
            info.tex_coord,
            transform,
            user,
            slot,
            srgb,
        )
    }

    /// [`Ctx::texture`] for a material's texture slot `slot` (`baseColorTexture`…) read at
    /// texture coordinate set `tex_coord` with `KHR_texture_transform` `transform`
    /// (`(transform, its texCoord override)`), checked: the transform's values must be
    /// finite. Records the set the material reads ([`Ctx::uv_sets`]), warning when its
    /// slots ask for different sets (the first one asked for is read for all).
    #[allow(clippy::too_many_arguments)]
    fn texture_slot(
        &mut self,
        index: usize,
        tex_coord: u32,
        transform: (Option<UvTransform>, Option<u32>),
        user: &str,
        slot: &str,
        srgb: bool,
    ) -> Result<(Option<TextureId>, Option<UvTransform>), LoadError> {
        let (transform, set_override) = transform;
        if transform.is_some_and(|t| !t.is_finite()) {
            return Err(self.malformed(
                user,
                format!("{slot}: KHR_texture_transform values are not finite"),
            ));
        }
        let set = set_override.unwrap_or(tex_coord);
        let material = self.materials.len();
        match self.uv_sets.get(&material) {
            Some(&first) if first != set => self.warn(format!(
                "{user}: {slot} uses TEXCOORD_{set} but another texture TEXCOORD_{first}; TEXCOORD_{first} is read for all"
            )),
            Some(_) => {}
            None => {
                self.uv_sets.insert(material, set);
            }
        }
        Ok((self.texture(index, user, srgb)?, transform))
    }

    /// The illume texture for glTF texture `index` (image decoded once per wrap mode and
    /// colour space: `srgb` for colours, linear for data). An image file that is missing
    /// or cannot be decoded is a warning and `None` (the material keeps its factors), or
    /// with `strict` an error.
    fn texture(
        &mut self,
        index: usize,
        user: &str,
        srgb: bool,
    ) -> Result<Option<TextureId>, LoadError> {
        match self.decoded_texture(index, user, srgb) {
            Ok(id) => Ok(Some(id)),
            Err(ImageFailure::Image(e)) if !self.strict => {
                // The error starts with the scene file: not prefixed again.
                self.builder
                    .warn(format!("{e} (the material is rendered without it)"));
                Ok(None)
            }
            Err(ImageFailure::Image(e) | ImageFailure::Document(e)) => Err(e),
        }
    }

    /// [`Ctx::texture`], failing on any problem.
    fn decoded_texture(
        &mut self,
        index: usize,
        user: &str,
        srgb: bool,
    ) -> Result<TextureId, ImageFailure> {
        let root = self.root;
        let texture = root.textures.get(index).ok_or_else(|| {
            ImageFailure::Document(self.malformed(user, format!("texture {index} does not exist")))
        })?;
        let (wrap_u, wrap_v) = match texture.sampler.and_then(|s| root.samplers.get(s.value())) {
            Some(s) => (wrap_mode(&s.wrap_s), wrap_mode(&s.wrap_t)),
            None => (WrapMode::Repeat, WrapMode::Repeat),
        };
        let image_index = texture.source.value();
        if let Some(&id) = self
            .textures
            .get(&(image_index, wrap_u as u8, wrap_v as u8, srgb))
        {
            return Ok(id);
        }
        let place = format!("image {image_index}");
        let image = root
            .images
            .get(image_index)
            .ok_or_else(|| ImageFailure::Document(self.malformed(&place, "does not exist")))?;
        let (bytes, name) = match (&image.buffer_view, image.uri.as_deref()) {
            (Some(view), _) => (
                self.view_bytes(view.value())
                    .map_err(ImageFailure::Document)?
                    .to_vec(),
                image.name.clone().unwrap_or_else(|| place.clone()),
            ),
            (None, Some(uri)) if uri.starts_with("data:") => (
                decode_data_uri(uri)
                    .map_err(|m| ImageFailure::Document(self.malformed(&place, m)))?,
                image.name.clone().unwrap_or_else(|| place.clone()),
            ),
            (None, Some(uri)) => {
                let file = self.folder.join(decode_uri_path(uri));
                let bytes =
                    read_referenced_file(self.path, &place, &file).map_err(ImageFailure::Image)?;
                (bytes, file.to_string_lossy().into_owned())
            }
            (None, None) => {
                return Err(ImageFailure::Document(
                    self.malformed(place, "neither uri nor bufferView"),
                ));
            }
        };
        // A file is named in full (its path was short enough to read), a name from the
        // document by an excerpt.
        let shown = if image.buffer_view.is_none()
            && !image.uri.as_deref().unwrap_or("").starts_with("data:")
        {
            name.clone()
        } else {
            excerpt(&name)
        };
        let tex = decode_texture(&bytes, name.clone(), wrap_u, wrap_v, srgb).map_err(|e| {
            ImageFailure::Image(self.malformed(&place, format!("cannot decode '{shown}': {e}")))
        })?;
        let id = self.builder.texture(tex);
        self.textures
            .insert((image_index, wrap_u as u8, wrap_v as u8, srgb), id);
        Ok(id)
    }

    fn default_material(&mut self) -> MaterialId {
        if let Some(m) = self.default_material {
            return m;
        }
        let m = self.builder.material(Material {
            name: "gltf_default".into(),
            double_sided: false,
            ..Material::default()
        });
        self.default_material = Some(m);
        m
    }

    /// The illume mesh of glTF mesh `index`, converted on first use.
    fn mesh(&mut self, index: usize) -> Result<MeshId, LoadError> {
        if let Some(&id) = self.meshes.get(&index) {
            return Ok(id);
        }
        let root = self.root;
        let gm = root
            .meshes
            .get(index)
            .ok_or_else(|| self.malformed(format!("mesh {index}"), "does not exist"))?;
        let name = gm.name.clone().unwrap_or_else(|| format!("mesh {index}"));
        let mut mesh = Mesh {
            name: name.clone(),
            ..Default::default()
        };
        let shown = excerpt(&name);
        let mut with_normals = 0;
        let mut prim_normals: Vec<Vec<Vec3>> = Vec::new();
        for (p, prim) in gm.primitives.iter().enumerate() {
            let place = format!("mesh {index} '{shown}' primitive {p}");
            use json::mesh::{Mode, Semantic};
            match prim.mode {
                Checked::Valid(Mode::Triangles) => {}
                Checked::Valid(other) => {
                    return Err(LoadError::unsupported(
                        self.path,
                        place,
                        format!("primitive mode {other:?} (only TRIANGLES)"),
                    ));
                }
                Checked::Invalid => return Err(self.malformed(place, "invalid primitive mode")),
            }
            if prim.targets.as_ref().is_some_and(|t| !t.is_empty()) {
                self.warn(format!("{place}: morph targets ignored"));
            }
            let attr = |s: Semantic| prim.attributes.get(&Checked::Valid(s)).map(|a| a.value());
            use json::accessor::ComponentType as C;
            let pos_acc = attr(Semantic::Positions)
                .ok_or_else(|| self.malformed(&place, "no POSITION attribute"))?;
            self.check_component_type(pos_acc, &format!("{place} POSITION"), &[C::F32], "FLOAT")?;
            let positions: Vec<Vec3> = self
                .read_vecs::<3>(pos_acc, &format!("{place} POSITION"))?
                .into_iter()
                .map(Vec3::from)
                .collect();
            let n = positions.len();
            let normals = match attr(Semantic::Normals) {
                Some(a) => {
                    self.check_component_type(a, &format!("{place} NORMAL"), &[C::F32], "FLOAT")?;
                    let v: Vec<Vec3> = self
                        .read_vecs::<3>(a, &format!("{place} NORMAL"))?
                        .into_iter()
                        .map(|x| Vec3::from(x).normalize_or(Vec3::Y))
                        .collect();
                    if v.len() != n {
                        return Err(self.malformed(
                            format!("accessor {a} ({place} NORMAL)"),
                            format!("{} normals for {n} positions", v.len()),
                        ));
                    }
                    with_normals += 1;
                    v
                }
                // Zero normals mark flat shading (the geometric normal is used where the
                // interpolated normal is zero), used when another primitive has normals.
                None => vec![Vec3::ZERO; n],
            };
            // The set the primitive's material reads its textures at.
            let set = prim
                .material
                .and_then(|m| self.uv_sets.get(&m.value()).copied())
                .unwrap_or(0);
            let uvs: Vec<Vec2> = match attr(Semantic::TexCoords(set)) {
                Some(a) => {
                    self.check_component_type(
                        a,
                        &format!("{place} TEXCOORD_{set}"),
                        &[C::F32, C::U8, C::U16],
                        "FLOAT, UNSIGNED_BYTE, UNSIGNED_SHORT",
                    )?;
                    let v: Vec<Vec2> = self
                        .read_vecs::<2>(a, &format!("{place} TEXCOORD_{set}"))?
                        .into_iter()
                        .map(Vec2::from)
                        .collect();
                    if v.len() != n {
                        return Err(self.malformed(
                            format!("accessor {a} ({place} TEXCOORD_{set})"),
                            format!("{} UVs for {n} positions", v.len()),
                        ));
                    }
                    v
                }
                None => vec![Vec2::ZERO; n],
            };
            let indices: Vec<u32> = match prim.indices {
                Some(a) => {
                    let a = a.value();
                    let what = format!("{place} indices");
                    self.check_component_type(
                        a,
                        &what,
                        &[C::U8, C::U16, C::U32],
                        "UNSIGNED_BYTE, UNSIGNED_SHORT, UNSIGNED_INT",
                    )?;
                    let (v, comps) = self.read_accessor(a, &what)?;
                    if comps != 1 {
                        return Err(self.malformed(
                            format!("accessor {a} ({what})"),
                            "indices must be SCALAR",
                        ));
                    }
                    let mut out = Vec::with_capacity(v.len());
                    for (k, &i) in v.iter().enumerate() {
                        if i < 0.0 || i >= n as f64 || i.fract() != 0.0 {
                            return Err(self.malformed(
                                format!("accessor {a} ({what})"),
                                format!("index {k} = {i} out of range ({n} vertices)"),
                            ));
                        }
                        out.push(i as u32);
                    }
                    out
                }
                None => (0..n as u32).collect(),
            };
            if !indices.len().is_multiple_of(3) {
                return Err(self.malformed(
                    place,
                    format!("{} indices is not a multiple of 3", indices.len()),
                ));
            }
            let material = match prim.material {
                Some(m) => *self.materials.get(m.value()).ok_or_else(|| {
                    self.malformed(&place, format!("material {} does not exist", m.value()))
                })?,
                None => self.default_material(),
            };
            let base = mesh.positions.len() as u32;
            mesh.positions.extend(positions);
            mesh.uvs.extend(uvs);
            prim_normals.push(normals);
            for t in indices.chunks_exact(3) {
                mesh.indices.push([base + t[0], base + t[1], base + t[2]]);
                mesh.triangle_materials.push(material);
            }
        }
        // Each primitive keeps its own attributes: with normals smooth, without flat
        // (zero normals select the geometric normal).
        if with_normals > 0 {
            mesh.normals = prim_normals.into_iter().flatten().collect();
        }
        let normal_mapped = mesh.triangle_materials.iter().any(|m| {
            self.builder.scene().materials[m.index()]
                .normal_texture
                .is_some()
        });
        if normal_mapped {
            if mesh.normals.is_empty() || mesh.uvs.is_empty() {
                self.warn(format!("mesh {index} '{shown}': a normal map needs normals and TEXCOORD_0; it is not applied"));
            } else if !super::tangents::generate(&mut mesh) {
                self.warn(format!("mesh {index} '{shown}': MikkTSpace found no tangents; the normal map is not applied"));
            }
        }
        let id = self.builder.mesh(mesh);
        self.meshes.insert(index, id);
        Ok(id)
    }

    /// Adds the `KHR_lights_punctual` light of glTF node `g`, if any, at `node`.
    fn light(&mut self, g: usize, node_name: &str, node: NodeId) -> Result<(), LoadError> {
        use json::extensions::scene::khr_lights_punctual::Type;
        let root = self.root;
        let Some(index) = root.nodes[g]
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .map(|l| l.light.value())
        else {
            return Ok(());
        };
        let place = format!("node {g} '{}' light {index}", excerpt(node_name));
        let light = root
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .and_then(|l| l.lights.get(index))
            .ok_or_else(|| self.malformed(&place, "light does not exist"))?;
        let colour = Rgb::from(light.color);
        let value = colour * light.intensity;
        if !value.is_finite() || value.min_element() < 0.0 {
            return Err(self.malformed(
                place,
                format!("intensity × colour {value} is not finite and non-negative"),
            ));
        }
        if let Some(range) = light.range {
            self.warn(format!(
                "{place}: range {range} ignored (pure inverse-square falloff)"
            ));
        }
        let kind = match light.type_ {
            Checked::Valid(Type::Point) => LightKind::Point { intensity: value },
            Checked::Valid(Type::Directional) => LightKind::Directional { irradiance: value },
            Checked::Valid(Type::Spot) => {
                let spot = light.spot.as_ref().ok_or_else(|| {
                    self.malformed(&place, "spot light without 'spot' cone angles")
                })?;
                let (inner, outer) = (spot.inner_cone_angle, spot.outer_cone_angle);
                if !(inner.is_finite()
                    && outer.is_finite()
                    && 0.0 <= inner
                    && inner < outer
                    && outer <= std::f32::consts::FRAC_PI_2)
                {
                    return Err(self.malformed(place, format!("spot cone angles inner {inner}, outer {outer} must satisfy 0 ≤ inner < outer ≤ π/2")));
                }
                LightKind::Spot {
                    intensity: value,
                    inner_cone_rad: inner,
                    outer_cone_rad: outer,
                }
            }
            Checked::Invalid => return Err(self.malformed(place, "invalid light type")),
        };
        let name = light.name.clone().unwrap_or_else(|| node_name.to_string());
        let id = self.builder.light(&name, kind, node);
        self.light_ids.entry(index).or_default().push(id);
        Ok(())
    }

    /// Sets the camera from the lowest-index scene node with a perspective camera.
    fn camera(
        &mut self,
        order: &[(usize, Option<usize>)],
        node_ids: &[Option<NodeId>],
    ) -> Result<(), LoadError> {
        use json::camera::Type;
        let root = self.root;
        let mut with_camera: Vec<usize> = order
            .iter()
            .map(|&(g, _)| g)
            .filter(|&g| root.nodes[g].camera.is_some())
            .collect();
        with_camera.sort_unstable();
        for g in with_camera {
            let Some(c) = root.nodes[g].camera.map(|c| c.value()) else {
                continue;
            };
            let place = format!("node {g} camera {c}");
            let cam = root
                .cameras
                .get(c)
                .ok_or_else(|| self.malformed(&place, "camera does not exist"))?;
            match (&cam.type_, &cam.perspective) {
                (Checked::Valid(Type::Perspective), Some(p)) => {
                    if !(p.yfov.is_finite() && p.yfov > 0.0 && p.yfov < std::f32::consts::PI) {
                        return Err(
                            self.malformed(place, format!("yfov {} is not in (0, π)", p.yfov))
                        );
                    }
                    // illume clips nothing and takes the aspect ratio from the image, but a
                    // camera the glTF specification forbids is a broken file.
                    if !(p.znear.is_finite() && p.znear > 0.0) {
                        return Err(self.malformed(
                            place,
                            format!("znear {} must be finite and > 0", p.znear),
                        ));
                    }
                    if let Some(zfar) = p.zfar
                        && (zfar.is_nan() || zfar <= p.znear)
                    {
                        return Err(self.malformed(
                            place,
                            format!("zfar {zfar} must be greater than znear {}", p.znear),
                        ));
                    }
                    if let Some(a) = p.aspect_ratio
                        && !(a.is_finite() && a > 0.0)
                    {
                        return Err(self
                            .malformed(place, format!("aspectRatio {a} must be finite and > 0")));
                    }
                    let Some(node) = node_ids.get(g).copied().flatten() else {
                        continue;
                    };
                    let name = cam.name.clone().unwrap_or_else(|| format!("camera {c}"));
                    self.builder.camera(&name, p.yfov, node);
                    self.camera_set = true;
                    return Ok(());
                }
                _ => self.warn(format!("{place}: not a perspective camera, ignored")),
            }
        }
        Ok(())
    }

    /// Converts every animation; returns the illume nodes any channel targets.
    /// An animation sampler's interpolation and key times (its input accessor, SCALAR).
    fn sampler_keys(
        &self,
        sampler: &json::animation::Sampler,
        place: &str,
    ) -> Result<(Interpolation, Vec<f32>), LoadError> {
        use json::animation::Interpolation as I;
        let interpolation = match sampler.interpolation {
            Checked::Valid(I::Linear) => Interpolation::Linear,
            Checked::Valid(I::Step) => Interpolation::Step,
            Checked::Valid(I::CubicSpline) => Interpolation::CubicSpline,
            Checked::Invalid => return Err(self.malformed(place, "invalid interpolation")),
        };
        let input = sampler.input.value();
        let what = format!("{place} input");
        self.check_component_type(input, &what, &[json::accessor::ComponentType::F32], "FLOAT")?;
        let (times, comps) = self.read_accessor(input, &what)?;
        if comps != 1 {
            return Err(self.malformed(
                format!("accessor {input} ({place} input)"),
                "key times must be SCALAR",
            ));
        }
        Ok((interpolation, times.into_iter().map(|t| t as f32).collect()))
    }

    /// The `KHR_animation_pointer` channels of animation `ai`: light intensity, colour and
    /// spot cone angles, material base colour, emissive factor, metallic and roughness.
    /// Other pointers are warnings (ignored); bad samplers and accessors are errors.
    fn pointer_channels(
        &mut self,
        ai: usize,
        name: &str,
    ) -> Result<Vec<PropertyChannel>, LoadError> {
        let root = self.root;
        let mut out = Vec::new();
        let pointers: Vec<PointerChannel> = self
            .pointers
            .iter()
            .filter(|p| p.animation == ai)
            .cloned()
            .collect();
        for p in pointers {
            let place = format!(
                "animation {ai} '{}' channel {} (pointer '{}')",
                excerpt(name),
                p.channel,
                excerpt(&p.pointer)
            );
            let parts: Vec<&str> = p.pointer.trim_start_matches('/').split('/').collect();
            let index = |s: &str| s.parse::<usize>().ok();
            let lights = root
                .extensions
                .as_ref()
                .and_then(|e| e.khr_lights_punctual.as_ref());
            let mut targets = Vec::new();
            match parts[..] {
                [
                    "extensions",
                    "KHR_lights_punctual",
                    "lights",
                    i,
                    ref rest @ ..,
                ] => {
                    let Some(l) = index(i).and_then(|i| lights.and_then(|ls| ls.lights.get(i)))
                    else {
                        return Err(self.malformed(place, "the light does not exist"));
                    };
                    let ids = self
                        .light_ids
                        .get(&index(i).unwrap_or(0))
                        .cloned()
                        .unwrap_or_default();
                    for light in ids {
                        match rest {
                            ["intensity"] => targets.push(PropertyTarget::LightIntensity {
                                light,
                                colour: Rgb::from(l.color),
                            }),
                            ["color"] => targets.push(PropertyTarget::LightColour {
                                light,
                                intensity: l.intensity,
                            }),
                            ["spot", "innerConeAngle"] => {
                                targets.push(PropertyTarget::SpotInnerCone { light })
                            }
                            ["spot", "outerConeAngle"] => {
                                targets.push(PropertyTarget::SpotOuterCone { light })
                            }
                            _ => {}
                        }
                    }
                    if !matches!(
                        rest,
                        ["intensity"]
                            | ["color"]
                            | ["spot", "innerConeAngle"]
                            | ["spot", "outerConeAngle"]
                    ) {
                        self.warn(format!(
                            "{place}: this light property is not animated; ignored"
                        ));
                        continue;
                    }
                }
                ["materials", m, ref rest @ ..] => {
                    let Some((gm, &material)) = index(m)
                        .and_then(|m| Some((root.materials.get(m)?, self.materials.get(m)?)))
                    else {
                        return Err(self.malformed(place, "the material does not exist"));
                    };
                    let strength = gm
                        .extensions
                        .as_ref()
                        .and_then(|e| e.emissive_strength.as_ref())
                        .map(|s| s.emissive_strength.0)
                        .unwrap_or(1.0);
                    targets.push(match rest {
                        ["pbrMetallicRoughness", "baseColorFactor"] => {
                            PropertyTarget::BaseColour { material }
                        }
                        ["pbrMetallicRoughness", "metallicFactor"] => {
                            PropertyTarget::Metallic { material }
                        }
                        ["pbrMetallicRoughness", "roughnessFactor"] => {
                            PropertyTarget::Roughness { material }
                        }
                        ["emissiveFactor"] => PropertyTarget::Emissive { material, strength },
                        _ => {
                            self.warn(format!(
                                "{place}: this material property is not animated; ignored"
                            ));
                            continue;
                        }
                    });
                }
                _ => {
                    self.warn(format!("{place}: unsupported pointer target; ignored"));
                    continue;
                }
            }
            let a = &root.animations[ai];
            let sampler = a.samplers.get(p.sampler).ok_or_else(|| {
                self.malformed(&place, format!("sampler {} does not exist", p.sampler))
            })?;
            let (interpolation, times) = self.sampler_keys(sampler, &place)?;
            let (input, output) = (sampler.input.value(), sampler.output.value());
            let (values, _) = self.read_accessor(output, &format!("{place} output"))?;
            for target in targets {
                let channel = PropertyChannel {
                    target,
                    times: times.clone(),
                    values: values.iter().map(|&v| v as f32).collect(),
                    interpolation,
                };
                channel.validate().map_err(|m| {
                    self.malformed(format!("{place} (accessors {input}/{output})"), m)
                })?;
                out.push(channel);
            }
        }
        Ok(out)
    }

    fn animations(&mut self, node_ids: &[Option<NodeId>]) -> Result<Vec<NodeId>, LoadError> {
        use json::animation::Property as P;
        let root = self.root;
        let mut targeted = Vec::new();
        for (ai, a) in root.animations.iter().enumerate() {
            let name = a.name.clone().unwrap_or_else(|| format!("animation {ai}"));
            let mut channels = Vec::new();
            for (ci, ch) in a.channels.iter().enumerate() {
                let place = format!("animation {ai} '{}' channel {ci}", excerpt(&name));
                let s = ch.sampler.value();
                let sampler = a
                    .samplers
                    .get(s)
                    .ok_or_else(|| self.malformed(&place, format!("sampler {s} does not exist")))?;
                let target = ch.target.node.value();
                if target >= root.nodes.len() {
                    return Err(self.malformed(
                        place,
                        format!(
                            "targets node {target}, which does not exist ({} nodes)",
                            root.nodes.len()
                        ),
                    ));
                }
                let property = match ch.target.path {
                    Checked::Valid(P::MorphTargetWeights) => {
                        self.warn(format!("{place}: morph-target weights ignored"));
                        continue;
                    }
                    Checked::Valid(p) => p,
                    Checked::Invalid => return Err(self.malformed(place, "invalid target path")),
                };
                let Some(node) = node_ids.get(target).copied().flatten() else {
                    self.warn(format!(
                        "{place}: targets node {target}, which is not in the loaded scene; ignored"
                    ));
                    continue;
                };
                let (interpolation, times) = self.sampler_keys(sampler, &place)?;
                let (input, output) = (sampler.input.value(), sampler.output.value());
                let what = format!("{place} output");
                let values = match property {
                    P::Translation => ChannelValues::Translation(
                        self.read_vecs::<3>(output, &what)?
                            .into_iter()
                            .map(Vec3::from)
                            .collect(),
                    ),
                    P::Scale => ChannelValues::Scale(
                        self.read_vecs::<3>(output, &what)?
                            .into_iter()
                            .map(Vec3::from)
                            .collect(),
                    ),
                    P::Rotation => ChannelValues::Rotation(
                        self.read_vecs::<4>(output, &what)?
                            .into_iter()
                            .map(Vec4::from)
                            .collect(),
                    ),
                    P::MorphTargetWeights => continue,
                };
                let channel = Channel {
                    node,
                    times,
                    values,
                    interpolation,
                };
                channel.validate().map_err(|m| {
                    self.malformed(format!("{place} (accessors {input}/{output})"), m)
                })?;
                targeted.push(node);
                channels.push(channel);
            }
            let properties = self.pointer_channels(ai, &name)?;
            if channels.is_empty() && properties.is_empty() {
                self.warn(format!(
                    "animation {ai} '{}': no usable channel; skipped",
                    excerpt(&name)
                ));
                continue;
            }
            self.builder.animation(Animation {
                name,
                channels,
                properties,
            });
        }
        Ok(targeted)
    }
}
