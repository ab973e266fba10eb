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

mod accessors;
mod animations;
mod buffers;
mod lights;
mod materials;
mod meshes;
mod nodes;
mod sky;

use super::{LoadError, default_camera_for_bounds, excerpt, read_file};
use crate::builtin::SceneBuilder;
use crate::model::{LightId, MaterialId, MeshId, NodeId, Scene, TextureId};
use ::gltf::json;
use animations::{PointerChannel, split_pointer_channels};
use buffers::{check_glb_header, load_buffers};
use json::validation::{Checked, Validate};
use sky::sky_from_extras;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

/// Extensions a file may list in `extensionsRequired`.
pub const SUPPORTED_REQUIRED_EXTENSIONS: [&str; 4] = [
    "KHR_lights_punctual",
    "KHR_materials_emissive_strength",
    "KHR_animation_pointer",
    "KHR_texture_transform",
];

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
    /// [`crate::LoadOptions::max_texture_bytes`], resolved.
    texture_limit: u64,
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

/// Loads the glTF document (`.gltf` or `.glb`) at `path` (see the module docs); with
/// `strict`, a missing or undecodable image is an error instead of a warning.
pub(super) fn load(path: &Path, strict: bool, texture_limit: u64) -> Result<Scene, LoadError> {
    let bytes = read_file(path)?;
    let is_glb = bytes.starts_with(b"glTF");
    if is_glb {
        check_glb_header(path, &bytes)?;
    }
    let (bytes, pointers) = split_pointer_channels(path, bytes, is_glb)?;
    let document = ::gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| {
        LoadError::malformed(
            path,
            if is_glb { "GLB container" } else { "JSON" },
            e.to_string(),
        )
    })?;
    let root = document.document.as_json();
    check_document(path, root)?;
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
        texture_limit,
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

/// The document's checks before conversion: `asset.version` 2.x, only supported
/// `extensionsRequired`, attribute accessors that exist (on which the `gltf` crate's
/// validation would panic), then that validation, reported with its JSON paths.
fn check_document(path: &Path, root: &json::Root) -> Result<(), LoadError> {
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
    Ok(())
}

impl Ctx<'_> {
    pub(super) fn malformed(
        &self,
        place: impl Into<String>,
        message: impl Into<String>,
    ) -> LoadError {
        LoadError::malformed(self.path, place, message)
    }

    pub(super) fn warn(&mut self, w: String) {
        let msg = format!("{}: {w}", self.path.display());
        self.builder.warn(msg);
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
}
