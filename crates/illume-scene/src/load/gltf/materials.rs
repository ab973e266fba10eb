//! Materials and textures: metallic-roughness factors, texture slots (with
//! `KHR_texture_transform`, samplers' wrap modes), image decoding, the default material
//! and the warnings for material extensions illume does not read.

use super::Ctx;
use super::buffers::{decode_data_uri, decode_uri_path};
use crate::load::{LoadError, check_texture_budget, decode_texture, excerpt, read_referenced_file};
use crate::model::{Material, MaterialId, TextureId, UvTransform, WrapMode};
use ::gltf::json;
use illume_core::{Rgb, Vec2};
use json::extensions::texture::TextureTransform;
use json::validation::Checked;

/// What a material looks like when the named extension, which illume does not read, is
/// ignored (for the warning).
pub(super) fn unsupported_material_extension_effect(name: &str) -> &'static str {
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

/// Largest `KHR_texture_transform` offset or scale component accepted (a texture repeated
/// 10⁴ times per unit of texture coordinate still has f32 precision to address a texel).
pub(super) const MAX_UV_TRANSFORM: f32 = 1e4;

/// A `KHR_texture_transform` as illume's [`UvTransform`] and its `texCoord` override.
pub(super) fn transform_of(t: Option<&TextureTransform>) -> (Option<UvTransform>, Option<u32>) {
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
pub(super) enum ImageFailure {
    /// The document is wrong (a missing texture or image index, a bad data URI): an error.
    Document(LoadError),
    /// The image file is missing or does not decode: a warning unless loading is strict.
    Image(LoadError),
}

/// Material `m`'s `KHR_materials_emissive_strength` (1 without it).
pub(super) fn emissive_strength(m: &json::Material) -> f32 {
    m.extensions
        .as_ref()
        .and_then(|e| e.emissive_strength.as_ref())
        .map(|s| s.emissive_strength.0)
        .unwrap_or(1.0)
}

pub(super) fn wrap_mode(m: &Checked<json::texture::WrappingMode>) -> WrapMode {
    use json::texture::WrappingMode as W;
    match m {
        Checked::Valid(W::ClampToEdge) => WrapMode::Clamp,
        Checked::Valid(W::MirroredRepeat) => WrapMode::Mirror,
        _ => WrapMode::Repeat,
    }
}

impl Ctx<'_> {
    pub(super) fn convert_materials(&mut self) -> Result<(), LoadError> {
        for (i, m) in self.root.materials.iter().enumerate() {
            let material = self.material(i, m)?;
            let id = self.builder.material(material);
            self.materials.push(id);
        }
        Ok(())
    }

    /// glTF material `i` (`m`) as illume's, checked (see the module docs), with a
    /// warning for each extension illume does not read.
    fn material(&mut self, i: usize, m: &json::Material) -> Result<Material, LoadError> {
        let name = m.name.clone().unwrap_or_else(|| format!("material {i}"));
        let pbr = &m.pbr_metallic_roughness;
        let [r, g, b, alpha] = pbr.base_color_factor.0;
        let strength = emissive_strength(m);
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
        let (normal_texture, normal_transform, normal_scale) =
            self.normal_slot(m.normal_texture.as_ref(), &user)?;
        self.warn_unread_extensions(m, &user);
        let alpha_cutoff = self.alpha_cutoff(m, &user)?;
        if !(alpha.is_finite() && (0.0..=1.0).contains(&alpha)) {
            return Err(self.malformed(
                &user,
                format!("baseColorFactor alpha {alpha} is not in [0, 1]"),
            ));
        }
        Ok(Material {
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
        })
    }

    /// The normal map slot (`normalTexture`) of the material named `user`: texture,
    /// transform and scale; `(None, None, 1)` without one.
    fn normal_slot(
        &mut self,
        info: Option<&json::material::NormalTexture>,
        user: &str,
    ) -> Result<(Option<TextureId>, Option<UvTransform>, f32), LoadError> {
        Ok(match info {
            Some(info) => {
                if !info.scale.is_finite() {
                    return Err(self.malformed(user, "normalTexture.scale is not finite"));
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
                        return Err(self
                            .malformed(user, format!("normalTexture KHR_texture_transform: {e}")));
                    }
                    None => None,
                };
                let (texture, transform) = self.texture_slot(
                    info.index.value(),
                    info.tex_coord,
                    transform_of(parsed.as_ref()),
                    user,
                    "normalTexture",
                    false,
                )?;
                (texture, transform, info.scale)
            }
            None => (None, None, 1.0),
        })
    }

    /// Material extensions illume does not read: one warning each, saying what the
    /// material is rendered as instead.
    fn warn_unread_extensions(&mut self, m: &json::Material, user: &str) {
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
    }

    /// The alpha cut-off of material `m` (named `user`): `None` for OPAQUE, MASK's
    /// `alphaCutoff` (0.5 by default), BLEND as MASK at 0.5 with a warning.
    fn alpha_cutoff(&mut self, m: &json::Material, user: &str) -> Result<Option<f32>, LoadError> {
        Ok(match m.alpha_mode {
            Checked::Valid(json::material::AlphaMode::Opaque) => None,
            Checked::Valid(json::material::AlphaMode::Mask) => {
                let cutoff = m.alpha_cutoff.map_or(0.5, |c| c.0);
                if !(cutoff.is_finite() && cutoff >= 0.0) {
                    return Err(self.malformed(
                        user,
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
                return Err(self.malformed(user, "alphaMode is not OPAQUE, MASK or BLEND"));
            }
        })
    }

    /// [`Ctx::texture_slot`] for a slot given as a glTF texture info (all but the normal
    /// map), `(None, None)` without one.
    pub(super) fn info_slot(
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
    pub(super) fn texture_slot(
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
        // Finite but absurd: at 1e38 the texture coordinates overflow into NaN (an all-NaN
        // image); beyond MAX_UV_TRANSFORM an f32 texture coordinate keeps no sub-texel
        // precision at all.
        if let Some(t) = transform {
            for (what, v) in [("offset", t.offset), ("scale", t.scale)] {
                if v.abs().max_element() > MAX_UV_TRANSFORM {
                    return Err(self.malformed(
                        user,
                        format!(
                            "{slot}: KHR_texture_transform {what} [{}, {}] is beyond ±{MAX_UV_TRANSFORM:e} (texture coordinates would lose all precision)",
                            v.x, v.y
                        ),
                    ));
                }
            }
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
    pub(super) fn texture(
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
    pub(super) fn decoded_texture(
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
        // Memory is not the file's fault: an error strict or not.
        check_texture_budget(self.builder.texture_bytes(), &tex, self.texture_limit).map_err(
            |m| ImageFailure::Document(self.malformed(&place, format!("'{shown}': {m}"))),
        )?;
        let id = self.builder.texture(tex);
        self.textures
            .insert((image_index, wrap_u as u8, wrap_v as u8, srgb), id);
        Ok(id)
    }

    pub(super) fn default_material(&mut self) -> MaterialId {
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
}
