//! Wavefront OBJ + MTL loader.
//!
//! Hand-written line parser rather than `tobj`: `tobj` 4 does resolve negative indices
//! against the vertices read so far and splits on any whitespace, but its errors carry
//! no line number (`FaceVertexOutOfBounds`, `PositionParseError` say neither where nor
//! which index), it silently drops MTL keywords it does not know (`Ke` ends up in
//! `unknown_param` as a string), and a missing texture is not its concern. The OBJ subset
//! a renderer needs is a few dozen lines, and owning it gives every error a line number.
//!
//! What is read:
//!
//! * `v x y z` (extra `w`/colour values ignored), `vt u [v]`, `vn x y z`, `f` with
//!   `v`, `v/vt`, `v//vn`, `v/vt/vn` corners; positive indices are 1-based absolute,
//!   negative ones are relative to the vertices read *so far* (both must refer to an
//!   element already read); polygons are fan-triangulated;
//! * `mtllib` (relative to the OBJ's folder; a library that is missing, not a regular
//!   file or binary data is a warning and its materials become the default material),
//!   `usemtl` (an unknown name is a warning and the default material);
//! * MTL: `newmtl`, `Kd` (albedo, ≥ 0, clamped to ≤ 1), `Ke` (emitted radiance
//!   [W/(m²·sr)], ≥ 0), `Ks`/`Ns` (mapped onto the metallic-roughness model: `Ks` = 0 stays
//!   exactly Lambertian; otherwise base = Kd + Ks, metallic = lum(Ks)/lum(Kd + Ks),
//!   GGX α = √(2/(Ns + 2)), roughness = √α; Kd + Ks > 1 is scaled down with a warning;
//!   transmission (`illum` 4, 6, 7, 9) is rendered opaque with a warning), `map_Kd` (an sRGB image
//!   relative to the MTL's folder, multiplied by `Kd` as the MTL spec says; `-clamp on`
//!   selects clamped wrapping, other options are skipped), `map_Ks` (sRGB, × `Ks`) and
//!   `map_Ns` (linear, × `Ns`) baked per texel into a metallic-roughness texture with
//!   the formulas above (the base colour keeps the untextured Kd + Ks, with a warning),
//!   `d` (or `Tr` = 1 − d) and `map_d` (its alpha channel, else its first channel) as an
//!   alpha mask with cutoff ½ (`d` < 1 alone warns: there is no partial transparency),
//!   `bump`/`map_bump` (with `-bm`) turned into a tangent-space normal map by central
//!   differences (a white texel [`BUMP_TEXELS`] texels above a black one; meshes without
//!   `vn` then get face normals per corner, MikkTSpace the tangents). Images are any
//!   format the `image` crate reads (PNG, JPEG, TGA, BMP, GIF, WebP, PNM). A texture file
//!   that cannot be read or decoded is a warning naming the OBJ, the MTL and its line,
//!   and the file (the material keeps its factors), an error when loading is strict
//!   ([`crate::LoadOptions`]); other keywords are ignored.
//!
//! Result: **one illume [`Mesh`] per OBJ file** (groups `o`/`g` are not split; each
//! triangle keeps its own material), placed once by a root node at the identity, every
//! material two-sided. Vertices are shared between faces with the same `v/vt/vn` triple.
//! When some corners have normals and others not, the ones without get their face's
//! geometric normal (flat shading there); when no corner has a normal the mesh has none.
//! OBJ's `vt` has v = 0 at the bottom of the image; it is flipped to illume's
//! top-row convention (v' = 1 − v). Points/lines (`p`, `l`) and free-form geometry are
//! ignored with a warning. Line continuations (`\`) are not supported.

use super::{
    LoadError, check_texture_budget, decode_coverage_texture, decode_texture,
    default_camera_for_bounds, excerpt, normal_map_from_height, read_file, read_referenced_file,
};
use crate::animation::Trs;
use crate::builtin::SceneBuilder;
use crate::model::{Material, MaterialId, Mesh, Scene, Texture, TextureId, WrapMode};
use illume_core::{Rgb, Vec2, Vec3};
use std::collections::{BTreeSet, HashMap};
use std::path::{Path, PathBuf};

/// "No texture coordinate / normal" marker in a [`Corner`].
const NONE: u32 = u32::MAX;

/// One face corner: 0-based indices into the position/uv/normal arrays.
#[derive(Clone, Copy)]
struct Corner {
    v: u32,
    vt: u32,
    vn: u32,
}

/// Parser state for one OBJ file.
struct ObjReader<'a> {
    path: &'a Path,
    builder: SceneBuilder,
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    normals: Vec<Vec3>,
    triangles: Vec<[Corner; 3]>,
    triangle_materials: Vec<MaterialId>,
    materials: HashMap<String, MaterialId>,
    /// Decoded textures by file and use.
    textures: HashMap<(PathBuf, TextureUse), TextureId>,
    /// Missing or undecodable textures are errors rather than warnings.
    strict: bool,
    /// [`crate::LoadOptions::max_texture_bytes`], resolved.
    texture_limit: u64,
    default_material: Option<MaterialId>,
    current: Option<MaterialId>,
    ignored: BTreeSet<String>,
    unknown_materials: BTreeSet<String>,
}

pub(super) fn load(path: &Path, strict: bool, texture_limit: u64) -> Result<Scene, LoadError> {
    let bytes = read_file(path)?;
    if let Some((place, message)) = binary_data(&bytes, "OBJ") {
        return Err(LoadError::malformed(path, place, message));
    }
    let text = String::from_utf8_lossy(&bytes);
    let mut r = ObjReader {
        path,
        builder: SceneBuilder::new(),
        positions: Vec::new(),
        uvs: Vec::new(),
        normals: Vec::new(),
        triangles: Vec::new(),
        triangle_materials: Vec::new(),
        materials: HashMap::new(),
        textures: HashMap::new(),
        strict,
        texture_limit,
        default_material: None,
        current: None,
        ignored: BTreeSet::new(),
        unknown_materials: BTreeSet::new(),
    };
    for (i, raw) in text.split('\n').enumerate() {
        r.line(i + 1, raw)?;
    }
    if !r.ignored.is_empty() {
        let list = r.ignored.iter().cloned().collect::<Vec<_>>().join(", ");
        r.builder.warn(format!(
            "{}: ignored OBJ statements: {list}",
            path.display()
        ));
    }
    if !r.unknown_materials.is_empty() {
        let list = r
            .unknown_materials
            .iter()
            .cloned()
            .collect::<Vec<_>>()
            .join(", ");
        r.builder.warn(format!(
            "{}: unknown materials (default material used): {list}",
            path.display()
        ));
    }
    let name = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "obj".into());
    let bumped = r.triangle_materials.iter().any(|m| {
        r.builder.scene().materials[m.index()]
            .normal_texture
            .is_some()
    });
    // Bump maps need a shading frame: without `vn`, every corner gets its face's normal.
    let mut mesh = r.build_mesh(&name, bumped);
    if mesh.indices.is_empty() {
        r.builder.warn(format!("{}: no faces", path.display()));
    }
    if bumped {
        if mesh.uvs.is_empty() {
            r.builder.warn(format!(
                "{}: bump maps need texture coordinates (vt); not applied",
                path.display()
            ));
        } else if !super::tangents::generate(&mut mesh) {
            r.builder.warn(format!(
                "{}: MikkTSpace found no tangents; bump maps are not applied",
                path.display()
            ));
        }
    }
    let mut b = r.builder;
    let mesh = b.mesh(mesh);
    b.placed(&name, mesh, Trs::IDENTITY, false);
    let mut scene = b.finish(&path.to_string_lossy());
    default_camera_for_bounds(&mut scene);
    Ok(scene)
}

/// `Some((place, message))` when `bytes` are binary data rather than text of `format`
/// (OBJ, MTL): a NUL byte, or mostly bytes that are not UTF-8 text.
fn binary_data(bytes: &[u8], format: &str) -> Option<(String, String)> {
    if let Some(at) = bytes.iter().position(|&b| b == 0) {
        return Some((
            format!("byte {at}"),
            format!("binary data (a NUL byte) in what should be a text {format} file"),
        ));
    }
    if std::str::from_utf8(bytes).is_err() {
        let bad = bytes.iter().filter(|&&b| b >= 0x80).count();
        if bad * 10 > bytes.len() {
            return Some((
                "file".into(),
                format!("mostly non-text bytes: not a text {format} file"),
            ));
        }
    }
    None
}

/// The text of a line without its comment and surrounding whitespace.
fn strip_comment(raw: &str) -> &str {
    raw.split('#').next().unwrap_or("").trim()
}

/// The rest of a (comment-stripped, trimmed) line after its keyword.
fn after_keyword(text: &str) -> &str {
    text.split_once(char::is_whitespace)
        .map(|(_, rest)| rest.trim())
        .unwrap_or("")
}

/// Parses `n` floats from `tokens`; fewer than `min` present, a non-number or a
/// non-finite value is an error message.
fn floats<const N: usize>(
    tokens: &mut std::str::SplitWhitespace<'_>,
    min: usize,
    what: &str,
) -> Result<[f32; N], String> {
    let mut out = [0.0f32; N];
    for (k, slot) in out.iter_mut().enumerate() {
        match tokens.next() {
            Some(t) => {
                let x: f32 = t
                    .parse()
                    .map_err(|_| format!("{what}: '{}' is not a number", excerpt(t)))?;
                if !x.is_finite() {
                    return Err(format!("{what}: value '{}' is not finite", excerpt(t)));
                }
                *slot = x;
            }
            None if k < min => return Err(format!("{what}: expected {min} numbers, found {k}")),
            None => break,
        }
    }
    Ok(out)
}

/// An MTL colour statement's value (`Kd`, `Ke`, `Ks`): one number (grey, as the MTL
/// spec says) or three, each finite and ≥ 0; `text` is the whole statement.
fn colour(
    tokens: &mut std::str::SplitWhitespace<'_>,
    text: &str,
    what: &str,
) -> Result<Rgb, String> {
    let [r, g, b] = floats::<3>(tokens, 1, what)?;
    let c = if text.split_whitespace().count() == 2 {
        Rgb::splat(r)
    } else {
        Rgb::new(r, g, b)
    };
    if c.min_element() < 0.0 {
        return Err(format!("{what} {c} must be ≥ 0"));
    }
    Ok(c)
}

/// Resolves a 1-based (positive) or relative (negative) OBJ index against `count`
/// elements read so far; the error says which and why.
fn resolve(token: &str, count: usize, what: &str) -> Result<u32, String> {
    let i: i64 = token
        .parse()
        .map_err(|_| format!("face {what} index '{}' is not an integer", excerpt(token)))?;
    let resolved = if i > 0 { i - 1 } else { count as i64 + i };
    if i == 0 || resolved < 0 || resolved >= count as i64 {
        return Err(format!(
            "face {what} index {i} out of range ({count} {what}s read so far)"
        ));
    }
    u32::try_from(resolved).map_err(|_| format!("face {what} index {i} too large"))
}

impl ObjReader<'_> {
    fn err(&self, line: usize, message: String) -> LoadError {
        LoadError::malformed(self.path, format!("line {line}"), message)
    }

    fn line(&mut self, n: usize, raw: &str) -> Result<(), LoadError> {
        let text = strip_comment(raw);
        let mut tokens = text.split_whitespace();
        let Some(keyword) = tokens.next() else {
            return Ok(());
        };
        match keyword {
            "v" => {
                let [x, y, z] =
                    floats::<3>(&mut tokens, 3, "vertex position").map_err(|m| self.err(n, m))?;
                self.positions.push(Vec3::new(x, y, z));
            }
            "vt" => {
                let [u, v] = floats::<2>(&mut tokens, 1, "texture coordinate")
                    .map_err(|m| self.err(n, m))?;
                self.uvs.push(Vec2::new(u, 1.0 - v));
            }
            "vn" => {
                let [x, y, z] =
                    floats::<3>(&mut tokens, 3, "normal").map_err(|m| self.err(n, m))?;
                self.normals.push(Vec3::new(x, y, z));
            }
            "f" => self.face(n, tokens)?,
            "usemtl" => {
                let name = after_keyword(text);
                self.current = Some(match self.materials.get(name) {
                    Some(&m) => m,
                    None => {
                        self.unknown_materials.insert(excerpt(name));
                        self.default_material()
                    }
                });
            }
            "mtllib" => self.mtllib(n, after_keyword(text))?,
            "o" | "g" | "s" => {}
            other => {
                self.ignored.insert(excerpt(other));
            }
        }
        Ok(())
    }

    fn face(&mut self, n: usize, tokens: std::str::SplitWhitespace<'_>) -> Result<(), LoadError> {
        let mut corners = Vec::with_capacity(4);
        for t in tokens {
            let mut parts = t.split('/');
            let v = parts.next().unwrap_or("");
            let vt = parts.next().unwrap_or("");
            let vn = parts.next().unwrap_or("");
            let v = resolve(v, self.positions.len(), "position").map_err(|m| self.err(n, m))?;
            let vt = if vt.is_empty() {
                NONE
            } else {
                resolve(vt, self.uvs.len(), "texture coordinate").map_err(|m| self.err(n, m))?
            };
            let vn = if vn.is_empty() {
                NONE
            } else {
                resolve(vn, self.normals.len(), "normal").map_err(|m| self.err(n, m))?
            };
            corners.push(Corner { v, vt, vn });
        }
        if corners.len() < 3 {
            return Err(self.err(
                n,
                format!("face has {} corners, needs at least 3", corners.len()),
            ));
        }
        let material = match self.current {
            Some(m) => m,
            None => self.default_material(),
        };
        for k in 1..corners.len() - 1 {
            self.triangles
                .push([corners[0], corners[k], corners[k + 1]]);
            self.triangle_materials.push(material);
        }
        Ok(())
    }

    fn default_material(&mut self) -> MaterialId {
        match self.default_material {
            Some(m) => m,
            None => {
                let m = self.builder.material(Material::default());
                self.default_material = Some(m);
                m
            }
        }
    }

    /// Loads the libraries named on an `mtllib` line: the whole rest of the line when
    /// such a file exists (names with spaces), else each whitespace-separated name.
    fn mtllib(&mut self, line: usize, rest: &str) -> Result<(), LoadError> {
        let folder = self.path.parent().unwrap_or(Path::new("."));
        let whole = folder.join(rest.replace('\\', "/"));
        let names: Vec<String> = if whole.is_file() {
            vec![rest.to_string()]
        } else {
            rest.split_whitespace().map(str::to_string).collect()
        };
        for name in names {
            let mtl_path = folder.join(name.replace('\\', "/"));
            let problem = match illume_core::files::read_regular(&mtl_path, super::MAX_FILE_BYTES) {
                Ok(bytes) => match binary_data(&bytes, "MTL") {
                    None => {
                        self.parse_mtl(&mtl_path, &String::from_utf8_lossy(&bytes))?;
                        continue;
                    }
                    Some((place, message)) => format!("{place}: {message}"),
                },
                Err(e) => e.to_string(),
            };
            let shown = mtl_path.to_string_lossy();
            let shown = if shown.len() > super::MAX_PATH_BYTES {
                excerpt(&shown)
            } else {
                shown.into_owned()
            };
            self.builder.warn(format!(
                "{}: line {line}: material library '{shown}' not readable ({problem}); its materials use the default material",
                self.path.display(),
            ));
        }
        Ok(())
    }

    fn parse_mtl(&mut self, mtl_path: &Path, text: &str) -> Result<(), LoadError> {
        let obj_path = self.path;
        let err = |line: usize, message: String| {
            LoadError::malformed(obj_path, mtl_place(mtl_path, line), message)
        };
        let mut current: Option<Material> = None;
        // `Ks`, `Ns` and whether it transmits (`illum`) of `current`.
        let mut phong = Phong::default();
        let mut finished: Vec<(Material, Phong)> = Vec::new();
        for (i, raw) in text.split('\n').enumerate() {
            let n = i + 1;
            let text = strip_comment(raw);
            let mut tokens = text.split_whitespace();
            let Some(keyword) = tokens.next() else {
                continue;
            };
            let keyword = keyword.to_ascii_lowercase();
            if keyword == "newmtl" {
                if let Some(m) = current.take() {
                    finished.push((m, std::mem::take(&mut phong)));
                }
                let name = after_keyword(text).to_string();
                current = Some(Material {
                    name,
                    ..Material::default()
                });
                continue;
            }
            let Some(m) = current.as_mut() else {
                continue; // statements before the first newmtl have nothing to apply to
            };
            match keyword.as_str() {
                "kd" => {
                    let c = colour(&mut tokens, text, "Kd").map_err(|e| err(n, e))?;
                    // Above 1 is common in exported files: clamped.
                    m.base_color = c.min(Rgb::ONE);
                }
                "ke" => {
                    m.emission = colour(&mut tokens, text, "Ke").map_err(|e| err(n, e))?;
                }
                "ns" => {
                    let [ns] = floats::<1>(&mut tokens, 1, "Ns").map_err(|e| err(n, e))?;
                    if !(ns.is_finite() && ns >= 0.0) {
                        return Err(err(n, format!("Ns {ns} must be finite and ≥ 0")));
                    }
                    phong.ns = Some(ns);
                }
                "ks" => {
                    phong.ks = colour(&mut tokens, text, "Ks").map_err(|e| err(n, e))?;
                }
                "illum" => {
                    // 4, 6, 7, 9: the MTL illumination models with transparency or
                    // refraction (`Tf` alone is often the 1 1 1 default, and 5 is a
                    // Fresnel mirror).
                    if let Some(Ok(i)) = tokens.next().map(str::parse::<u32>) {
                        phong.transmits = matches!(i, 4 | 6 | 7 | 9);
                    }
                }
                "d" | "tr" => {
                    let [v] = floats::<1>(&mut tokens, 1, &keyword).map_err(|e| err(n, e))?;
                    if !(0.0..=1.0).contains(&v) {
                        return Err(err(n, format!("{keyword} {v} is not in [0, 1]")));
                    }
                    // `Tr` is the transparency 1 − d (some exporters write it instead).
                    phong.d = Some(if keyword == "d" { v } else { 1.0 - v });
                }
                "map_kd" | "map_ks" | "map_ns" | "map_d" | "map_bump" | "bump" => {
                    let spec = texture_file(tokens);
                    if spec.file.is_empty() {
                        return Err(err(n, format!("{keyword} without a file name")));
                    }
                    let folder = mtl_path.parent().unwrap_or(Path::new("."));
                    let tex_path = folder.join(spec.file.replace('\\', "/"));
                    let usage = match keyword.as_str() {
                        "map_kd" | "map_ks" => TextureUse::Colour,
                        "map_ns" => TextureUse::Scalar,
                        "map_d" => TextureUse::Coverage,
                        _ => TextureUse::Bump(spec.bump_multiplier.to_bits()),
                    };
                    // Named as written (`map_Kd`), not lower-cased.
                    let written = text.split_whitespace().next().unwrap_or(&keyword);
                    let id = self.texture(mtl_path, n, written, &tex_path, spec.wrap, usage)?;
                    match keyword.as_str() {
                        "map_kd" => m.base_color_texture = id,
                        "map_ks" => phong.ks_texture = id,
                        "map_ns" => phong.ns_texture = id,
                        "map_d" => phong.d_texture = id,
                        _ => m.normal_texture = id,
                    }
                }
                _ => {}
            }
        }
        if let Some(m) = current.take() {
            finished.push((m, phong));
        }
        for (mut m, phong) in finished {
            let textures = &self.builder.scene().textures;
            let texture =
                |t: Option<TextureId>| t.map(|t| std::sync::Arc::clone(&textures[t.index()]));
            let (warning, baked) = phong.apply(
                &mut m,
                texture(phong.ks_texture).as_deref(),
                texture(phong.ns_texture).as_deref(),
            );
            if let Some(baked) = baked {
                m.metallic_roughness_texture = Some(self.builder.texture(baked));
            }
            if let Some(warning) = warning {
                self.builder.warn(format!(
                    "{}: material '{}': {warning}",
                    mtl_path.display(),
                    excerpt(&m.name)
                ));
            }
            let name = m.name.clone();
            let id = self.builder.material(m);
            // The first definition of a name wins, as in most loaders.
            self.materials.entry(name).or_insert(id);
        }
        Ok(())
    }

    /// The texture at `tex_path` read for `usage` (decoded once per file and use),
    /// named by statement `keyword` of `mtl_path` line `line`. A file that cannot be read
    /// or decoded is a warning and `None` (the material keeps its factors), or with
    /// `strict` an error; both name the OBJ, the MTL line and the file.
    fn texture(
        &mut self,
        mtl_path: &Path,
        line: usize,
        keyword: &str,
        tex_path: &Path,
        wrap: WrapMode,
        usage: TextureUse,
    ) -> Result<Option<TextureId>, LoadError> {
        if let Some(&id) = self.textures.get(&(tex_path.into(), usage)) {
            return Ok(Some(id));
        }
        let place = format!("{} ({keyword})", mtl_place(mtl_path, line));
        let decoded = match read_referenced_file(self.path, &place, tex_path) {
            Err(e) => Err(e),
            Ok(bytes) => {
                let name = tex_path.to_string_lossy().into_owned();
                match usage {
                    TextureUse::Colour => decode_texture(&bytes, name, wrap, wrap, true),
                    TextureUse::Scalar => decode_texture(&bytes, name, wrap, wrap, false),
                    TextureUse::Coverage => decode_coverage_texture(&bytes, name, wrap, wrap),
                    TextureUse::Bump(bm) => decode_texture(&bytes, name, wrap, wrap, false)
                        .map(|h| normal_map_from_height(&h, BUMP_TEXELS * f32::from_bits(bm))),
                }
                .map_err(|e| {
                    LoadError::malformed(
                        self.path,
                        place.clone(),
                        format!("texture '{}' cannot be decoded: {e}", tex_path.display()),
                    )
                })
            }
        };
        match decoded {
            Ok(texture) => {
                // Memory is not the file's fault: an error strict or not.
                check_texture_budget(self.builder.texture_bytes(), &texture, self.texture_limit)
                    .map_err(|m| {
                        LoadError::malformed(
                            self.path,
                            place.clone(),
                            format!("texture '{}': {m}", tex_path.display()),
                        )
                    })?;
                let id = self.builder.texture(texture);
                self.textures.insert((tex_path.into(), usage), id);
                Ok(Some(id))
            }
            Err(e) if self.strict => Err(e),
            Err(e) => {
                self.builder
                    .warn(format!("{e} (the material is rendered without it)"));
                Ok(None)
            }
        }
    }

    /// Turns the triangles into one mesh, sharing vertices with equal `v/vt/vn`.
    /// With `normals`, the mesh has normals even when no corner has one (then each
    /// corner carries its face's normal).
    fn build_mesh(&self, name: &str, normals: bool) -> Mesh {
        let has_uv = self.triangles.iter().flatten().any(|c| c.vt != NONE);
        let has_normal = normals || self.triangles.iter().flatten().any(|c| c.vn != NONE);
        let mut mesh = Mesh {
            name: name.into(),
            ..Default::default()
        };
        let mut map: HashMap<(u32, u32, u64), u32> = HashMap::with_capacity(self.positions.len());
        for (t, tri) in self.triangles.iter().enumerate() {
            let p = tri.map(|c| self.positions[c.v as usize]);
            let flat = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or(Vec3::Y);
            let mut idx = [0u32; 3];
            for (k, c) in tri.iter().enumerate() {
                // Corners without a normal are not shared across faces: they carry their
                // face's normal.
                let normal_key = if c.vn != NONE {
                    c.vn as u64
                } else {
                    (1u64 << 32) + t as u64
                };
                let key = (c.v, c.vt, if has_normal { normal_key } else { 0 });
                idx[k] = *map.entry(key).or_insert_with(|| {
                    mesh.positions.push(self.positions[c.v as usize]);
                    if has_uv {
                        mesh.uvs.push(if c.vt != NONE {
                            self.uvs[c.vt as usize]
                        } else {
                            Vec2::ZERO
                        });
                    }
                    if has_normal {
                        mesh.normals.push(if c.vn != NONE {
                            self.normals[c.vn as usize].normalize_or(flat)
                        } else {
                            flat
                        });
                    }
                    mesh.positions.len() as u32 - 1
                });
            }
            mesh.indices.push(idx);
        }
        mesh.triangle_materials = self.triangle_materials.clone();
        mesh
    }
}

/// The place of line `line` of material library `mtl_path`, for errors reported against
/// the OBJ file.
fn mtl_place(mtl_path: &Path, line: usize) -> String {
    format!("material library {} line {line}", mtl_path.display())
}

/// Splits the arguments of a `map_*` statement into the file name (the tokens left
/// after the options, joined by single spaces) and the wrap mode (`-clamp on` →
/// [`WrapMode::Clamp`]).
fn texture_file(tokens: std::str::SplitWhitespace<'_>) -> TextureSpec {
    let tokens: Vec<&str> = tokens.collect();
    let mut wrap = WrapMode::Repeat;
    let mut bump_multiplier = 1.0f32;
    let mut rest = Vec::new();
    let mut i = 0;
    while i < tokens.len() {
        let t = tokens[i];
        if t.starts_with('-') && t.len() > 1 && t.parse::<f32>().is_err() {
            // An option: skip its arguments (numbers or on/off).
            if t.eq_ignore_ascii_case("-clamp")
                && tokens
                    .get(i + 1)
                    .is_some_and(|a| a.eq_ignore_ascii_case("on"))
            {
                wrap = WrapMode::Clamp;
            }
            if t.eq_ignore_ascii_case("-bm")
                && let Some(v) = tokens.get(i + 1).and_then(|a| a.parse::<f32>().ok())
                && v.is_finite()
            {
                bump_multiplier = v;
            }
            i += 1;
            while i < tokens.len() && i + 1 < tokens.len() && is_option_argument(tokens[i]) {
                i += 1;
            }
            continue;
        }
        rest.push(t);
        i += 1;
    }
    TextureSpec {
        file: rest.join(" "),
        wrap,
        bump_multiplier,
    }
}

/// A texture statement's file and the options illume reads.
struct TextureSpec {
    /// File name (relative to the MTL's folder).
    file: String,
    /// `-clamp on` → clamped, else repeating.
    wrap: WrapMode,
    /// `-bm` bump multiplier (1 by default).
    bump_multiplier: f32,
}

/// How an MTL texture file is decoded (a file used two ways is decoded twice).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum TextureUse {
    /// sRGB colour (`map_Kd`, `map_Ks`).
    Colour,
    /// Linear scalar data (`map_Ns`).
    Scalar,
    /// Opacity (`map_d`): the alpha channel, else the first channel.
    Coverage,
    /// Heights (`bump`, `map_bump`) turned into a normal map; the bits of the `-bm`
    /// multiplier.
    Bump(u32),
}

/// Height of a white bump-map texel over a black one, in texels (times `-bm`): a step
/// from black to white between neighbouring texels tilts the normal by
/// atan(BUMP_TEXELS / 2) ≈ 45°. MTL gives bump heights no unit; this choice renders
/// Dabrovic Sponza's bump maps as visible relief without exaggerating them.
const BUMP_TEXELS: f32 = 2.0;

/// True for option arguments (`0.5`, `on`, `off`, a channel letter of `-imfchan`).
fn is_option_argument(t: &str) -> bool {
    t.parse::<f32>().is_ok()
        || matches!(
            t.to_ascii_lowercase().as_str(),
            "on" | "off" | "r" | "g" | "b" | "m" | "l" | "z"
        )
}

/// The Phong terms of an MTL material, mapped onto the metallic-roughness model.
#[derive(Clone, Copy, Debug, Default)]
struct Phong {
    /// Specular colour `Ks` (zero: Lambertian).
    ks: Rgb,
    /// Specular exponent `Ns`.
    ns: Option<f32>,
    /// The material asks for transmission (`illum` 4, 6, 7 or 9), which illume lacks.
    transmits: bool,
    /// Opacity `d` (or 1 − `Tr`).
    d: Option<f32>,
    /// `map_Ks`, `map_Ns`, `map_d`.
    ks_texture: Option<TextureId>,
    ns_texture: Option<TextureId>,
    d_texture: Option<TextureId>,
}

/// GGX roughness √α for Phong exponent `ns`, with α = √(2/(Ns + 2)).
fn roughness_of_exponent(ns: f32) -> f32 {
    (2.0 / (ns.max(0.0) + 2.0)).sqrt().sqrt().clamp(0.0, 1.0)
}

impl Phong {
    /// Maps `Kd` (the material's base colour) and `Ks`/`Ns` onto metallic-roughness: with
    /// `Ks` = 0 the material stays exactly Lambertian. Otherwise the glTF mix's diffuse
    /// part (1 − m)·base and specular part m·base match `Kd` and `Ks`:
    /// base = Kd + Ks, metallic m = lum(Ks)/lum(Kd + Ks); the Phong exponent becomes GGX
    /// α = √(2/(Ns + 2)) (Walter et al. 2007's Phong–Beckmann correspondence), roughness
    /// = √α. Kd + Ks above 1 is scaled down to 1. `map_Ks` (`ks_map`) and `map_Ns`
    /// (`ns_map`, multiplying Ns) are baked, per texel of `map_Ns` (else of `map_Ks`),
    /// into a metallic-roughness texture with the same formulas (the base colour keeps
    /// the untextured Kd + Ks: an approximation, warned). `d` < 1 or `map_d` make an alpha
    /// mask with cutoff ½. Returns a warning for what was approximated, and the baked
    /// texture.
    fn apply(
        &self,
        m: &mut Material,
        ks_map: Option<&Texture>,
        ns_map: Option<&Texture>,
    ) -> (Option<String>, Option<Texture>) {
        let mut warnings = Vec::new();
        let d = self.d.unwrap_or(1.0);
        if self.transmits {
            warnings
                .push("transmission (illum 4, 6, 7, 9) is not supported: rendered opaque".into());
        } else if self.d_texture.is_some() || d < 1.0 {
            m.alpha = d;
            m.alpha_texture = self.d_texture;
            m.alpha_cutoff = Some(0.5);
            if self.d_texture.is_none() {
                let what = if d >= 0.5 { "opaque" } else { "invisible" };
                warnings.push(format!(
                    "d = {d} (partial transparency) is rendered as an alpha mask with cutoff 0.5: {what}"
                ));
            }
        }
        if self.ks.max_element() <= 0.0 {
            return ((!warnings.is_empty()).then(|| warnings.join("; ")), None);
        }
        let mut sum = m.base_color + self.ks;
        let mut ks = self.ks;
        if sum.max_element() > 1.0 {
            let k = 1.0 / sum.max_element();
            warnings.push(format!("Kd + Ks = {sum} exceeds 1: both scaled by {k:.3}"));
            sum *= k;
            ks *= k;
        }
        let kd = sum - ks;
        let metallic_of = |ks: Rgb| {
            let total = illume_core::luminance(kd + ks);
            if total > 0.0 {
                (illume_core::luminance(ks) / total).clamp(0.0, 1.0)
            } else {
                0.0
            }
        };
        let ns = self.ns.unwrap_or(0.0);
        m.base_color = sum.clamp(Rgb::ZERO, Rgb::ONE);
        m.metallic = metallic_of(ks);
        m.roughness = roughness_of_exponent(ns);
        let baked = ns_map.or(ks_map).map(|grid| {
            if ks_map.is_some() {
                warnings.push(
                    "map_Ks varies the metallic part only (the base colour keeps Kd + Ks)".into(),
                );
            }
            let (w, h) = (grid.width, grid.height);
            let texels = (0..h)
                .flat_map(|y| (0..w).map(move |x| (x, y)))
                .map(|(x, y)| {
                    let uv = Vec2::new((x as f32 + 0.5) / w as f32, (y as f32 + 0.5) / h as f32);
                    let ks_here = ks_map.map_or(ks, |t| ks * t.sample(uv));
                    let ns_here = ns_map.map_or(ns, |t| ns * t.sample(uv).x);
                    Rgb::new(0.0, roughness_of_exponent(ns_here), metallic_of(ks_here))
                })
                .collect();
            // The texture carries the values: factors of 1.
            m.metallic = 1.0;
            m.roughness = 1.0;
            Texture {
                name: format!("{} (metallic-roughness from map_Ks/map_Ns)", grid.name),
                width: w,
                height: h,
                texels,
                wrap_u: grid.wrap_u,
                wrap_v: grid.wrap_v,
                alpha: Vec::new(),
            }
        });
        ((!warnings.is_empty()).then(|| warnings.join("; ")), baked)
    }
}
