//! Scene data types: typed ids, meshes, materials, textures, lights, camera, nodes,
//! instances, and the [`Scene`] that owns them.

use crate::animation::{Animation, Trs};
use illume_core::{Aabb, Affine3A, PI, Rgb, Vec2, Vec3};
use std::sync::Arc;

macro_rules! typed_id {
    ($(#[$m:meta])* $name:ident) => {
        $(#[$m])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
        pub struct $name(pub u32);
        impl $name {
            /// The id as a `usize` index into its scene array.
            #[inline]
            pub fn index(self) -> usize {
                self.0 as usize
            }
        }
    };
}

typed_id!(
    /// Index of a [`Mesh`] in [`Scene::meshes`].
    MeshId
);
typed_id!(
    /// Index of a [`Material`] in [`Scene::materials`].
    MaterialId
);
typed_id!(
    /// Index of a [`Texture`] in [`Scene::textures`].
    TextureId
);
typed_id!(
    /// Index of an [`Instance`] in [`Scene::instances`].
    InstanceId
);
typed_id!(
    /// Index of a [`Light`] in [`Scene::lights`].
    LightId
);
typed_id!(
    /// Index of a [`Node`] in [`Scene::nodes`].
    NodeId
);

/// A triangle mesh in object space. Positions in metres; normals and UVs per vertex,
/// either empty or one per position; one material per triangle.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    /// Name from the file (glTF mesh name, OBJ object/group), for messages.
    pub name: String,
    /// Vertex positions, object space.
    pub positions: Vec<Vec3>,
    /// Unit shading normals per vertex, or empty (flat shading from the geometric normal).
    pub normals: Vec<Vec3>,
    /// Texture coordinates per vertex, or empty.
    pub uvs: Vec<Vec2>,
    /// Tangents per vertex for normal maps: xyz the unit tangent (direction of +u), w
    /// the bitangent sign (bitangent = w · normal × tangent), or empty.
    pub tangents: Vec<illume_core::Vec4>,
    /// Vertex indices of each triangle (counter-clockwise = front face).
    pub indices: Vec<[u32; 3]>,
    /// Material of each triangle (same length as `indices`).
    pub triangle_materials: Vec<MaterialId>,
}

impl Mesh {
    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.indices.len()
    }

    /// Object-space corner positions of triangle `t`.
    #[inline]
    pub fn triangle(&self, t: usize) -> [Vec3; 3] {
        let [a, b, c] = self.indices[t];
        [
            self.positions[a as usize],
            self.positions[b as usize],
            self.positions[c as usize],
        ]
    }

    /// Object-space bounds.
    pub fn bounds(&self) -> Aabb {
        Aabb::from_points(self.positions.iter().copied())
    }

    /// Checks the invariants (index ranges, attribute lengths, finite values);
    /// the message says what is wrong.
    pub fn validate(&self, material_count: usize) -> Result<(), String> {
        let n = self.positions.len();
        if !self.normals.is_empty() && self.normals.len() != n {
            return Err(format!(
                "{} normals for {} positions",
                self.normals.len(),
                n
            ));
        }
        if !self.uvs.is_empty() && self.uvs.len() != n {
            return Err(format!("{} UVs for {} positions", self.uvs.len(), n));
        }
        if !self.tangents.is_empty() && self.tangents.len() != n {
            return Err(format!(
                "{} tangents for {} positions",
                self.tangents.len(),
                n
            ));
        }
        if self.triangle_materials.len() != self.indices.len() {
            return Err(format!(
                "{} triangle materials for {} triangles",
                self.triangle_materials.len(),
                self.indices.len()
            ));
        }
        if let Some((i, p)) = self
            .positions
            .iter()
            .enumerate()
            .find(|(_, p)| !p.is_finite())
        {
            return Err(format!("position {i} is not finite: {p}"));
        }
        if let Some((t, tri)) = self
            .indices
            .iter()
            .enumerate()
            .find(|(_, tri)| tri.iter().any(|&v| v as usize >= n))
        {
            return Err(format!(
                "triangle {t} has vertex index {tri:?} out of range 0..{n}"
            ));
        }
        if let Some((t, m)) = self
            .triangle_materials
            .iter()
            .enumerate()
            .find(|(_, m)| m.index() >= material_count)
        {
            return Err(format!(
                "triangle {t} uses material {} of {material_count}",
                m.0
            ));
        }
        Ok(())
    }
}

/// How texture coordinates outside [0, 1] are mapped.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Default)]
pub enum WrapMode {
    /// Tile (glTF REPEAT, the default everywhere).
    #[default]
    Repeat,
    /// Clamp to the edge texel.
    Clamp,
    /// Tile with every other copy mirrored.
    Mirror,
}

impl WrapMode {
    /// Texel index `i` of a row or column of `n` texels, wrapped into `0..n` (the
    /// integer division only when `i` lies outside).
    #[inline]
    pub fn wrap(self, i: i64, n: u32) -> usize {
        let n = i64::from(n);
        if (0..n).contains(&i) {
            return i as usize;
        }
        let r = match self {
            WrapMode::Repeat => i.rem_euclid(n),
            WrapMode::Clamp => i.clamp(0, n - 1),
            WrapMode::Mirror => {
                let m = i.rem_euclid(2 * n);
                if m < n { m } else { 2 * n - 1 - m }
            }
        };
        r as usize
    }

    /// `(wrap(i, n), wrap(i + 1, n))`, the two texels a bilinear lookup reads along one
    /// axis, equal to two [`WrapMode::wrap`] calls but with one integer division at most
    /// (none inside the row).
    #[inline]
    pub fn wrap_pair(self, i: i64, n: u32) -> (usize, usize) {
        let n64 = i64::from(n);
        if i >= 0 && i < n64 - 1 {
            return (i as usize, i as usize + 1);
        }
        match self {
            WrapMode::Repeat => {
                let a = self.wrap(i, n);
                (a, if a + 1 == n as usize { 0 } else { a + 1 })
            }
            WrapMode::Clamp | WrapMode::Mirror => (self.wrap(i, n), self.wrap(i + 1, n)),
        }
    }
}

/// An RGB texture, linear values (sRGB base-colour images are decoded on load).
#[derive(Clone, Debug)]
pub struct Texture {
    /// File or glTF image name, for messages.
    pub name: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Row-major linear RGB texels, row 0 = top of the image (UV v = 0).
    pub texels: Vec<Rgb>,
    /// Wrapping in u.
    pub wrap_u: WrapMode,
    /// Wrapping in v.
    pub wrap_v: WrapMode,
    /// Row-major opacity per texel, 0 = transparent … 255 = opaque, laid out like
    /// `texels`; empty when the image has no alpha channel or is opaque everywhere.
    /// Read by alpha-mask (cut-out) materials only.
    pub alpha: Vec<u8>,
}

impl Texture {
    /// Memory of the texels \[bytes\]: 12 a texel (linear RGB) plus the alpha bytes.
    pub fn memory_bytes(&self) -> u64 {
        (self.texels.len() * std::mem::size_of::<Rgb>() + self.alpha.len()) as u64
    }

    /// An opaque `width`×`height` texture, repeating in both directions, whose texel
    /// `(x, y)` (row `y` from the top) is `f(x, y)`.
    pub fn from_fn(name: &str, width: u32, height: u32, f: impl Fn(u32, u32) -> Rgb) -> Self {
        Self {
            name: name.into(),
            width,
            height,
            texels: (0..height)
                .flat_map(|y| (0..width).map(move |x| (x, y)))
                .map(|(x, y)| f(x, y))
                .collect(),
            wrap_u: WrapMode::Repeat,
            wrap_v: WrapMode::Repeat,
            alpha: vec![],
        }
    }

    /// Bilinear lookup of the opacity in [0, 1] at `uv` (1 for a texture without alpha).
    pub fn sample_alpha(&self, uv: Vec2) -> f32 {
        if self.alpha.len() != self.texels.len() || self.alpha.is_empty() {
            return 1.0;
        }
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let t = |ix: i64, iy: i64| {
            let cx = self.wrap_u.wrap(ix, self.width);
            let cy = self.wrap_v.wrap(iy, self.height);
            f32::from(self.alpha[cy * self.width as usize + cx])
        };
        let (ix, iy) = (x0 as i64, y0 as i64);
        let top = t(ix, iy) * (1.0 - fx) + t(ix + 1, iy) * fx;
        let bottom = t(ix, iy + 1) * (1.0 - fx) + t(ix + 1, iy + 1) * fx;
        (top * (1.0 - fy) + bottom * fy) / 255.0
    }

    /// Bilinear lookup at `uv` (glTF convention: v = 0 at the top row).
    pub fn sample(&self, uv: Vec2) -> Rgb {
        if self.texels.is_empty() {
            return Rgb::ONE;
        }
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let (cx0, cx1) = self.wrap_u.wrap_pair(x0 as i64, self.width);
        let (cy0, cy1) = self.wrap_v.wrap_pair(y0 as i64, self.height);
        let w = self.width as usize;
        let t = &self.texels;
        let top = t[cy0 * w + cx0] * (1.0 - fx) + t[cy0 * w + cx1] * fx;
        let bottom = t[cy1 * w + cx0] * (1.0 - fx) + t[cy1 * w + cx1] * fx;
        top * (1.0 - fy) + bottom * fy
    }

    /// Mean texel value (used for photon albedo estimates and power).
    pub fn average(&self) -> Rgb {
        if self.texels.is_empty() {
            return Rgb::ONE;
        }
        self.texels.iter().copied().sum::<Rgb>() / self.texels.len() as f32
    }
}

/// A texture-coordinate transform (glTF `KHR_texture_transform`):
/// `uv' = offset + R(rotation) · (scale ⊙ uv)` with `R(θ)·(x, y) = (x cosθ − y sinθ,
/// x sinθ + y cosθ)`, the extension's matrix.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct UvTransform {
    /// Offset of the UV origin.
    pub offset: Vec2,
    /// Rotation \[rad\].
    pub rotation: f32,
    /// Scale per component.
    pub scale: Vec2,
}

impl UvTransform {
    /// The transformed coordinates.
    #[inline]
    pub fn apply(&self, uv: Vec2) -> Vec2 {
        let s = uv * self.scale;
        let (sin, cos) = self.rotation.sin_cos();
        self.offset + Vec2::new(s.x * cos - s.y * sin, s.x * sin + s.y * cos)
    }

    /// `uv` through `transform`, unchanged for `None`.
    #[inline]
    pub fn apply_opt(transform: &Option<UvTransform>, uv: Vec2) -> Vec2 {
        match transform {
            Some(t) => t.apply(uv),
            None => uv,
        }
    }

    /// True when every value is finite.
    pub fn is_finite(&self) -> bool {
        self.offset.is_finite() && self.rotation.is_finite() && self.scale.is_finite()
    }
}

/// A surface material: the glTF 2.0 metallic-roughness model (its BRDF is
/// `illume_transport::metal_rough`). `metallic = 0`, `roughness = 1` is exactly
/// Lambertian with albedo `base_color` — the default, and every OBJ material.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Name from the file.
    pub name: String,
    /// Base colour (linear RGB, each channel in [0, 1]), multiplied by the texture: the
    /// diffuse albedo ρ of a dielectric, the Fresnel reflectance at normal incidence of a
    /// metal.
    pub base_color: Rgb,
    /// Optional base-colour texture (linear after decoding), multiplied into `base_color`.
    pub base_color_texture: Option<TextureId>,
    /// Transform of the texture coordinates the base-colour texture is read at.
    pub base_color_transform: Option<UvTransform>,
    /// Transform of the texture coordinates the metallic-roughness texture is read at.
    pub metallic_roughness_transform: Option<UvTransform>,
    /// Transform of the texture coordinates the normal map is read at.
    pub normal_transform: Option<UvTransform>,
    /// Transform of the texture coordinates the emissive texture is read at.
    pub emissive_transform: Option<UvTransform>,
    /// Emitted radiance Le [W/(m²·sr)], from the front face only.
    pub emission: Rgb,
    /// Optional emissive texture (linear after sRGB decoding), multiplied into
    /// `emission`.
    pub emissive_texture: Option<TextureId>,
    /// 0 = dielectric, 1 = metal (glTF `metallicFactor`), in [0, 1].
    pub metallic: f32,
    /// Perceptual roughness (glTF `roughnessFactor`), in [0, 1]; GGX α = roughness².
    pub roughness: f32,
    /// Optional glTF metallic-roughness texture (linear): its blue channel multiplies
    /// `metallic`, its green channel `roughness`.
    pub metallic_roughness_texture: Option<TextureId>,
    /// Optional tangent-space normal map (linear, glTF convention: +x along +u, +y along
    /// +v of the tangent frame, +z the surface normal), used where the mesh has tangents.
    pub normal_texture: Option<TextureId>,
    /// Scale of the normal map's x and y (glTF `normalTexture.scale`). Default 1.
    pub normal_scale: f32,
    /// When false (glTF `doubleSided: false`), a back face neither reflects nor emits:
    /// light arriving there is absorbed.
    pub double_sided: bool,
    /// Opacity factor (glTF `baseColorFactor`'s alpha, MTL `d`), in [0, 1]; read only
    /// when `alpha_cutoff` is set.
    pub alpha: f32,
    /// Texture whose alpha channel multiplies `alpha` (glTF: the base-colour texture,
    /// read at its coordinates; MTL: `map_d`), read only when `alpha_cutoff` is set.
    pub alpha_texture: Option<TextureId>,
    /// Alpha mask (glTF `alphaMode: MASK`, `alphaCutoff`): where the opacity is below
    /// the cutoff the surface is not there at all: rays, shadows, photons and the
    /// rasterizer pass through it (a cut-out: leaves, chains, fences). `None`: opaque.
    /// Cut-outs are fixed when the tracer builds a mesh's BVH (animating `alpha` has no
    /// effect on them).
    pub alpha_cutoff: Option<f32>,
}

impl Default for Material {
    fn default() -> Self {
        Self {
            name: "default".into(),
            base_color: Rgb::splat(0.8),
            base_color_texture: None,
            base_color_transform: None,
            metallic_roughness_transform: None,
            normal_transform: None,
            emissive_transform: None,
            emission: Rgb::ZERO,
            emissive_texture: None,
            metallic: 0.0,
            roughness: 1.0,
            metallic_roughness_texture: None,
            normal_texture: None,
            normal_scale: 1.0,
            double_sided: true,
            alpha: 1.0,
            alpha_texture: None,
            alpha_cutoff: None,
        }
    }
}

impl Material {
    /// True when the material is exactly Lambertian everywhere (metallic 0, roughness 1,
    /// no metallic-roughness texture).
    pub fn is_lambertian(&self) -> bool {
        self.metallic <= 0.0 && self.roughness >= 1.0 && self.metallic_roughness_texture.is_none()
    }

    /// The texture coordinates the base-colour texture is read at for mesh coordinates
    /// `uv` (unchanged without a transform).
    #[inline]
    pub fn base_color_uv(&self, uv: Vec2) -> Vec2 {
        UvTransform::apply_opt(&self.base_color_transform, uv)
    }

    /// The texture coordinates the metallic-roughness texture is read at.
    #[inline]
    pub fn metallic_roughness_uv(&self, uv: Vec2) -> Vec2 {
        UvTransform::apply_opt(&self.metallic_roughness_transform, uv)
    }

    /// The texture coordinates the normal map is read at.
    #[inline]
    pub fn normal_uv(&self, uv: Vec2) -> Vec2 {
        UvTransform::apply_opt(&self.normal_transform, uv)
    }

    /// The texture coordinates the emissive texture is read at.
    #[inline]
    pub fn emissive_uv(&self, uv: Vec2) -> Vec2 {
        UvTransform::apply_opt(&self.emissive_transform, uv)
    }

    /// True when the material emits light.
    pub fn is_emissive(&self) -> bool {
        self.emission.max_element() > 0.0
    }
}

/// Kinds of analytic (non-surface) light. Emissive triangles are area lights through
/// their [`Material::emission`] and are not listed here.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    /// Isotropic point light; `intensity` is radiant intensity [W/sr] per channel.
    Point {
        /// Radiant intensity I [W/sr].
        intensity: Rgb,
    },
    /// Spot light shining down the light's local −Z with glTF's smooth falloff
    /// `clamp((cosθ − cos outer)/(cos inner − cos outer), 0, 1)²`.
    Spot {
        /// Radiant intensity on the axis [W/sr].
        intensity: Rgb,
        /// Inner cone half-angle \[rad\]: full intensity inside.
        inner_cone_rad: f32,
        /// Outer cone half-angle \[rad\]: zero outside.
        outer_cone_rad: f32,
    },
    /// Distant light shining down the light's local −Z; `irradiance` [W/m²] on a surface
    /// facing it.
    Directional {
        /// Irradiance E on a perpendicular surface [W/m²].
        irradiance: Rgb,
    },
}

/// An analytic light placed by a node.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    /// Name from the file.
    pub name: String,
    /// What kind of light and its radiometric quantity.
    pub kind: LightKind,
    /// The node that places it (position = node origin, direction = node −Z).
    pub node: NodeId,
    /// Cached world transform of `node` at the scene's current time.
    pub world_from_light: Affine3A,
}

impl Light {
    /// World position (meaningless for directional lights).
    pub fn position(&self) -> Vec3 {
        self.world_from_light.translation.into()
    }

    /// Unit world direction the light shines in (spot and directional: local −Z).
    pub fn direction(&self) -> Vec3 {
        self.world_from_light
            .transform_vector3(-Vec3::Z)
            .normalize_or(-Vec3::Y)
    }

    /// Radiant power Φ \[W\] per channel. Directional lights need the radius of the
    /// scene's bounding sphere (their power is the irradiance through its disk).
    pub fn power(&self, scene_radius: f32) -> Rgb {
        match self.kind {
            LightKind::Point { intensity } => intensity * 4.0 * PI,
            LightKind::Spot {
                intensity,
                inner_cone_rad,
                outer_cone_rad,
            } => intensity * spot_solid_angle(inner_cone_rad, outer_cone_rad),
            LightKind::Directional { irradiance } => irradiance * PI * scene_radius * scene_radius,
        }
    }
}

/// glTF spot falloff at `cos_theta` from the axis.
#[inline]
pub fn spot_falloff(cos_theta: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    let d = (cos_inner - cos_outer).max(1e-6);
    let x = ((cos_theta - cos_outer) / d).clamp(0.0, 1.0);
    x * x
}

/// ∫ falloff dω over the sphere for a glTF spot (steradians): 2π(1 − cos_inner) for the
/// full-intensity core plus 2π(cos_inner − cos_outer)/3 for the squared linear ramp in cosθ.
pub fn spot_solid_angle(inner_cone_rad: f32, outer_cone_rad: f32) -> f32 {
    let ci = inner_cone_rad.cos();
    let co = outer_cone_rad.cos();
    2.0 * PI * (1.0 - ci) + 2.0 * PI * (ci - co).max(0.0) / 3.0
}

/// A perspective camera placed by a node, looking down its local −Z, +Y up.
#[derive(Clone, Debug, PartialEq)]
pub struct Camera {
    /// Name from the file.
    pub name: String,
    /// Vertical field of view \[rad\] (glTF `yfov`); the aspect comes from the output size.
    pub yfov_rad: f32,
    /// The node that places it.
    pub node: NodeId,
    /// Cached world transform of `node` at the scene's current time.
    pub world_from_camera: Affine3A,
}

/// A node of the transform hierarchy. Animations drive `local`.
#[derive(Clone, Debug, PartialEq)]
pub struct Node {
    /// Name from the file.
    pub name: String,
    /// Parent node, `None` for a root. Parents always have smaller indices.
    pub parent: Option<NodeId>,
    /// Transform relative to the parent, as translation/rotation/scale.
    pub local: Trs,
    /// Cached world transform at the scene's current time.
    pub world_from_node: Affine3A,
}

/// Largest light power accepted per channel \[W\] (a scene is refused beyond it): far
/// above any physical source, low enough that the transport's products stay finite.
pub const MAX_POWER_W: f32 = 1e30;

/// Largest world coordinate accepted \[m\] (a scene reaching beyond it is refused):
/// squares and cross products of coordinates and their differences stay finite in f32
/// (≈ 3.4·10³⁸), which a vertex at 3·10³⁸ m would overflow into a silently black image.
pub const MAX_COORDINATE_M: f32 = 1e18;

/// `p` (a power per channel, a point) for messages, each component in scientific
/// notation when large (1.571e36, not 37 digits).
fn format_large(p: Vec3) -> String {
    let one = |v: f32| {
        if v.abs() >= 1e6 {
            format!("{v:.3e}")
        } else {
            format!("{v}")
        }
    };
    format!("[{}, {}, {}]", one(p.x), one(p.y), one(p.z))
}

/// Bit in [`Instance::mask`] that every ordinary instance carries.
pub const MASK_DEFAULT: u32 = 1;

/// One placement of a mesh in the world.
#[derive(Clone, Debug, PartialEq)]
pub struct Instance {
    /// Name from the file (node name).
    pub name: String,
    /// The mesh it places.
    pub mesh: MeshId,
    /// The node that places it.
    pub node: NodeId,
    /// Cached world transform of `node` at the scene's current time.
    pub world_from_object: Affine3A,
    /// True when an animation or the user may move it (techniques may precompute less
    /// for dynamic instances).
    pub dynamic: bool,
    /// Visibility bits: a ray sees this instance when `ray_mask & mask != 0`. Ordinary
    /// instances carry [`MASK_DEFAULT`]; techniques may add copies (e.g. selective photon
    /// tracing's phantoms) with other bits.
    pub mask: u32,
}

/// Light arriving from every direction in which a ray leaves the scene (below the
/// horizon too): escaping rays see it, surfaces are lit by it, photons are emitted from
/// it.
#[derive(Clone, Debug, PartialEq)]
pub enum Sky {
    /// The same radiance [W/(m²·sr)] from every direction.
    Uniform {
        /// Radiance per channel, finite and ≥ 0.
        radiance: Rgb,
    },
    /// An equirectangular environment map ([`EnvMap`], its mapping fixed there).
    Equirect(Arc<EnvMap>),
}

impl Sky {
    /// Radiance seen looking along unit `dir` (arriving from that direction).
    #[inline]
    pub fn radiance(&self, dir: Vec3) -> Rgb {
        match self {
            Sky::Uniform { radiance } => *radiance,
            Sky::Equirect(map) => map.lookup(map.uv(dir)),
        }
    }

    /// Checks the values; the message names the field.
    pub fn validate(&self) -> Result<(), String> {
        match self {
            Sky::Uniform { radiance } => {
                if !radiance.is_finite() || radiance.min_element() < 0.0 {
                    return Err(format!(
                        "sky radiance {radiance} must be three finite numbers ≥ 0"
                    ));
                }
            }
            Sky::Equirect(map) => map.validate()?,
        }
        Ok(())
    }

    /// ∫ L dω over the sphere [W/(m²)] per channel (4π·L for a uniform sky).
    pub fn integral(&self) -> Rgb {
        match self {
            Sky::Uniform { radiance } => *radiance * (4.0 * PI),
            Sky::Equirect(map) => map.integral(),
        }
    }
}

/// An equirectangular environment map: linear RGB radiance [W/(m²·sr)] (already
/// multiplied by its scale), rotated by `rotation_deg` about +Y.
///
/// The mapping is fixed: for a world direction d,
/// `u = 0.5 + (atan2(d.x, −d.z) + A·π/180) / 2π` (columns left to right, wrapping) and
/// `v = acos(d.y) / π` (row 0 at the top is +Y, clamped). With A = 0, u = 0.5 looks along
/// −Z, 0.75 along +X, 0.25 along −X, both edges along +Z; seen from inside the image is not
/// mirrored. Texel (i, j) is centred at ((i + ½)/W, (j + ½)/H) and looked up bilinearly. A
/// positive A turns the sky by the right-hand rule about +Y (+X toward −Z).
#[derive(Clone, Debug, PartialEq)]
pub struct EnvMap {
    /// File name, for messages.
    pub name: String,
    /// Width in texels.
    pub width: u32,
    /// Height in texels.
    pub height: u32,
    /// Row-major texels, row 0 at the top (+Y); the radiance is `scale` × texel. Shared:
    /// the sun's scaled skies of a day are one image (issue 38: a deep copy per time of
    /// day held 400 MB more for an 8192 × 4096 map).
    pub texels: std::sync::Arc<Vec<Rgb>>,
    /// Factor on every texel (the sun's sky scale; 1 as loaded).
    pub scale: f32,
    /// Rotation about +Y \[degrees\].
    pub rotation_deg: f32,
    /// The texels' importance-sampling table, built by the first light set that needs it
    /// and shared with `texels` (`Default::default()` when making a map).
    pub sampling: EnvSampling,
}

/// The importance-sampling table of an [`EnvMap`]'s texels (over texels, so the same for
/// any positive `scale`): built once, by the first light set that needs it, and shared by
/// every copy of the map — the sun's scaled skies and every light set (a world's refresh
/// and its snapshots). Issue 38: a table per light set (12 bytes a texel) held several
/// at once. The texels of a map are never changed after it is made, so the cache cannot
/// go stale; as a cache it takes no part in comparisons and prints as its state only.
#[derive(Clone, Default)]
pub struct EnvSampling(Arc<std::sync::OnceLock<Option<illume_core::sampling::AliasTable>>>);

impl EnvSampling {
    /// The table, built by `build` on first use (`None`: nothing to sample, e.g. black).
    pub fn get_or_build(
        &self,
        build: impl FnOnce() -> Option<illume_core::sampling::AliasTable>,
    ) -> Option<&illume_core::sampling::AliasTable> {
        self.0.get_or_init(build).as_ref()
    }
}

impl PartialEq for EnvSampling {
    /// Always equal: a cache derived from the texels, which are compared.
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for EnvSampling {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("EnvSampling")
    }
}

impl EnvMap {
    /// Texture coordinates of world direction `dir` (unit).
    #[inline]
    pub fn uv(&self, dir: Vec3) -> Vec2 {
        let phi = dir.x.atan2(-dir.z) + self.rotation_deg.to_radians();
        let u = (0.5 + phi / (2.0 * PI)).rem_euclid(1.0);
        let v = dir.y.clamp(-1.0, 1.0).acos() / PI;
        Vec2::new(u, v)
    }

    /// The unit world direction of texture coordinates `uv` (inverse of [`EnvMap::uv`]).
    #[inline]
    pub fn direction(&self, uv: Vec2) -> Vec3 {
        let phi = (uv.x - 0.5) * 2.0 * PI - self.rotation_deg.to_radians();
        let theta = uv.y * PI;
        let (st, ct) = theta.sin_cos();
        let (sp, cp) = phi.sin_cos();
        Vec3::new(st * sp, ct, -st * cp)
    }

    /// Bilinear lookup at `uv` (u wraps, v clamps).
    pub fn lookup(&self, uv: Vec2) -> Rgb {
        let (w, h) = (self.width as i64, self.height as i64);
        let x = uv.x * self.width as f32 - 0.5;
        let y = (uv.y * self.height as f32 - 0.5).clamp(0.0, (h - 1) as f32);
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = (x - x0, y - y0);
        let texel = |ix: i64, iy: i64| {
            let cx = ix.rem_euclid(w) as usize;
            let cy = iy.clamp(0, h - 1) as usize;
            self.texels[cy * self.width as usize + cx]
        };
        let (ix, iy) = (x0 as i64, y0 as i64);
        let top = texel(ix, iy) * (1.0 - fx) + texel(ix + 1, iy) * fx;
        let bottom = texel(ix, iy + 1) * (1.0 - fx) + texel(ix + 1, iy + 1) * fx;
        (top * (1.0 - fy) + bottom * fy) * self.scale
    }

    /// Solid angle of a texel of row `j` \[sr\]: (2π/W)·(π/H)·sin θ at the row centre.
    #[inline]
    pub fn texel_solid_angle(&self, j: u32) -> f32 {
        let theta = (j as f32 + 0.5) / self.height as f32 * PI;
        2.0 * PI * PI / (self.width as f32 * self.height as f32) * theta.sin()
    }

    /// ∫ L dω over the sphere, by texels.
    pub fn integral(&self) -> Rgb {
        let mut sum = Rgb::ZERO;
        for j in 0..self.height {
            let row = &self.texels[(j * self.width) as usize..((j + 1) * self.width) as usize];
            sum += row.iter().copied().sum::<Rgb>() * self.texel_solid_angle(j);
        }
        sum * self.scale
    }

    /// Checks size and values; the message names the map.
    pub fn validate(&self) -> Result<(), String> {
        if self.width == 0 || self.height == 0 {
            return Err(format!("environment map {}: empty image", self.name));
        }
        if self.texels.len() != (self.width * self.height) as usize {
            return Err(format!("environment map {}: texel count", self.name));
        }
        if let Some(i) = self
            .texels
            .iter()
            .position(|t| !t.is_finite() || t.min_element() < 0.0)
        {
            return Err(format!(
                "environment map {}: texel ({}, {}) is {} (must be finite and ≥ 0)",
                self.name,
                i as u32 % self.width,
                i as u32 / self.width,
                self.texels[i]
            ));
        }
        if !self.rotation_deg.is_finite() {
            return Err(format!(
                "environment map {}: rotation is not finite",
                self.name
            ));
        }
        if !self.scale.is_finite() || self.scale < 0.0 {
            return Err(format!(
                "environment map {}: scale {} must be finite and ≥ 0",
                self.name, self.scale
            ));
        }
        Ok(())
    }
}

/// A whole scene at one time.
#[derive(Clone, Debug, Default)]
pub struct Scene {
    /// Where it came from (file path or `builtin:NAME`), for messages.
    pub source: String,
    /// Meshes in object space, shared (never changed in place once added), so cloning a
    /// scene — a second world at another time — copies no vertex data.
    pub meshes: Vec<Arc<Mesh>>,
    /// Materials.
    pub materials: Vec<Material>,
    /// Textures, shared like the meshes.
    pub textures: Vec<Arc<Texture>>,
    /// Transform hierarchy (parents before children).
    pub nodes: Vec<Node>,
    /// Mesh placements.
    pub instances: Vec<Instance>,
    /// Analytic lights.
    pub lights: Vec<Light>,
    /// The sky, if any: what rays leaving the scene see (none: black).
    pub sky: Option<Sky>,
    /// The camera used for rendering.
    pub camera: Camera,
    /// Animations; [`Scene::active_animation`] selects the one that plays.
    pub animations: Vec<Animation>,
    /// Index of the animation [`Scene::set_time`] plays, if any.
    pub active_animation: Option<usize>,
    /// Current time \[s\].
    pub time: f64,
    /// Non-fatal problems found while loading (unsupported features ignored, defaults used).
    pub warnings: Vec<String>,
    /// The sun path ([`crate::sun`]) that [`Scene::set_time`] applies to one directional
    /// light, if the scene has a `[sun]` table (attached by [`Scene::attach_sun`]).
    pub sun: Option<SunPath>,
}

/// A `[sun]` table bound to the directional light it drives.
#[derive(Clone, Debug, PartialEq)]
pub struct SunPath {
    /// Where, when and how bright.
    pub settings: crate::sun::SunSettings,
    /// The directional light it drives (its node is a root node the sun owns).
    pub light: LightId,
    /// The scene's sky when the sun was attached: [`Scene::set_time`] sets the sky to it
    /// scaled by [`crate::sun::sky_scale`] (a fixed angular distribution, so a sky image
    /// rendered once scales exactly; Bahnsen et al. §2).
    pub sky_base: Option<Sky>,
}

impl Default for Camera {
    fn default() -> Self {
        Self {
            name: "camera".into(),
            yfov_rad: 40f32.to_radians(),
            node: NodeId(0),
            world_from_camera: Affine3A::IDENTITY,
        }
    }
}

impl Scene {
    /// World-space bounds of every instance at the current time (removed instances,
    /// mask 0, excluded).
    pub fn bounds(&self) -> Aabb {
        self.instances
            .iter()
            .filter(|i| i.mask != 0)
            .map(|i| {
                self.meshes[i.mesh.index()]
                    .bounds()
                    .transformed(&i.world_from_object)
            })
            .fold(Aabb::EMPTY, Aabb::union)
    }

    /// Total triangles over all instances.
    pub fn instanced_triangle_count(&self) -> usize {
        self.instances
            .iter()
            .map(|i| self.meshes[i.mesh.index()].triangle_count())
            .sum()
    }

    /// Albedo ρ of `material` at `uv` (texture × factor).
    pub fn albedo(&self, material: MaterialId, uv: Vec2) -> Rgb {
        let m = &self.materials[material.index()];
        match m.base_color_texture {
            Some(t) => m.base_color * self.textures[t.index()].sample(m.base_color_uv(uv)),
            None => m.base_color,
        }
    }

    /// Emitted radiance of `material` at texture coordinates `uv` (factor × emissive
    /// texture).
    pub fn emission(&self, material: MaterialId, uv: Vec2) -> Rgb {
        let m = &self.materials[material.index()];
        match m.emissive_texture {
            Some(t) => m.emission * self.textures[t.index()].sample(m.emissive_uv(uv)),
            None => m.emission,
        }
    }

    /// `(metallic, roughness)` of `material` at texture coordinates `uv` (factors ×
    /// the metallic-roughness texture's blue and green channels).
    pub fn metal_rough(&self, material: MaterialId, uv: Vec2) -> (f32, f32) {
        let m = &self.materials[material.index()];
        match m.metallic_roughness_texture {
            Some(t) => {
                let texel = self.textures[t.index()].sample(m.metallic_roughness_uv(uv));
                (m.metallic * texel.z, m.roughness * texel.y)
            }
            None => (m.metallic, m.roughness),
        }
    }

    /// Duration of the active animation \[s\] (0 without one).
    pub fn animation_duration(&self) -> f64 {
        self.active_animation
            .map(|a| self.animations[a].duration())
            .unwrap_or(0.0)
    }

    /// Total emitted power of emissive triangles \[W\] per channel: Σ π·Le·A (one-sided).
    pub fn emissive_power(&self) -> Rgb {
        let mut total = Rgb::ZERO;
        for inst in &self.instances {
            let mesh = &self.meshes[inst.mesh.index()];
            for (t, m) in mesh.triangle_materials.iter().enumerate() {
                let mat = &self.materials[m.index()];
                if mat.is_emissive() {
                    let [a, b, c] = mesh
                        .triangle(t)
                        .map(|p| inst.world_from_object.transform_point3(p));
                    // A textured emitter counts with the texture's mean (an estimate).
                    let texture = mat
                        .emissive_texture
                        .map_or(Rgb::ONE, |t| self.textures[t.index()].average());
                    total += mat.emission * texture * PI * 0.5 * (b - a).cross(c - a).length();
                }
            }
        }
        total
    }

    /// Total power of all lights \[W\] per channel, analytic, emissive and the sky.
    pub fn total_power(&self) -> Rgb {
        let r = self.bounds().bounding_radius();
        self.lights.iter().map(|l| l.power(r)).sum::<Rgb>()
            + self.emissive_power()
            + self.sky_power(r)
    }

    /// Power \[W\] per channel the sky sends through the scene's bounding sphere of
    /// radius `scene_radius`: radiance from every direction through a disk of area πR²
    /// facing it, `∫L dω · πR²` (`L·4π·πR²` for a uniform sky); 0 without a sky.
    pub fn sky_power(&self, scene_radius: f32) -> Rgb {
        match &self.sky {
            Some(sky) => sky.integral() * (PI * scene_radius * scene_radius),
            None => Rgb::ZERO,
        }
    }

    /// Every instance's world bounds, every light's position and the camera's lie within
    /// ±[`MAX_COORDINATE_M`]; the message names the first item beyond.
    fn check_extent(&self) -> Result<(), String> {
        use crate::load::excerpt;
        let beyond = |p: Vec3| !p.is_finite() || p.abs().max_element() > MAX_COORDINATE_M;
        for (i, inst) in self.instances.iter().enumerate() {
            let Some(mesh) = self.meshes.get(inst.mesh.index()) else {
                continue; // reported by validate
            };
            let b = mesh.bounds().transformed(&inst.world_from_object);
            if !b.is_empty() && (beyond(b.min) || beyond(b.max)) {
                return Err(format!(
                    "instance {i} '{}': its world bounds {} … {} reach beyond ±{MAX_COORDINATE_M:e} m",
                    excerpt(&inst.name),
                    format_large(b.min),
                    format_large(b.max)
                ));
            }
        }
        for (i, l) in self.lights.iter().enumerate() {
            if !matches!(l.kind, LightKind::Directional { .. }) && beyond(l.position()) {
                return Err(format!(
                    "light {i} '{}': its position {} is beyond ±{MAX_COORDINATE_M:e} m",
                    excerpt(&l.name),
                    format_large(l.position())
                ));
            }
        }
        let eye = Vec3::from(self.camera.world_from_camera.translation);
        if beyond(eye) {
            return Err(format!(
                "camera '{}': its position {} is beyond ±{MAX_COORDINATE_M:e} m",
                excerpt(&self.camera.name),
                format_large(eye)
            ));
        }
        Ok(())
    }

    /// Checks every cross-reference and value; the message names the offending item.
    /// Among the values: world coordinates within ±[`MAX_COORDINATE_M`], base colours in
    /// [0, 1], spot and directional lights whose node gives them a direction, powers up
    /// to [`MAX_POWER_W`]. Names quoted from the input are cut to a short excerpt.
    pub fn validate(&self) -> Result<(), String> {
        use crate::load::excerpt;
        if let Some(sky) = &self.sky {
            sky.validate()?;
        }
        self.check_extent()?;
        let cam = &self.camera.world_from_camera;
        let det = cam.matrix3.determinant();
        if !illume_core::affine_is_finite(cam) || !det.is_finite() || det.abs() < 1e-12 {
            let node = self
                .nodes
                .get(self.camera.node.index())
                .map_or(String::new(), |n| {
                    format!(" (node {} '{}')", self.camera.node.0, excerpt(&n.name))
                });
            return Err(format!(
                "camera '{}'{node}: its transform is degenerate (zero scale or not finite)",
                excerpt(&self.camera.name)
            ));
        }
        if !(self.camera.yfov_rad.is_finite()
            && self.camera.yfov_rad > 0.0
            && self.camera.yfov_rad < PI)
        {
            return Err(format!(
                "camera '{}': vertical field of view {} rad is not in (0, π)",
                excerpt(&self.camera.name),
                self.camera.yfov_rad
            ));
        }
        for (i, m) in self.meshes.iter().enumerate() {
            m.validate(self.materials.len())
                .map_err(|e| format!("mesh {i} '{}': {e}", excerpt(&m.name)))?;
        }
        for (i, m) in self.materials.iter().enumerate() {
            let name = excerpt(&m.name);
            // An albedo outside [0, 1] creates or destroys energy (negative radiance).
            if !(m.base_color.min_element() >= 0.0 && m.base_color.max_element() <= 1.0) {
                return Err(format!(
                    "material {i} '{name}': base colour {} is not in [0, 1]",
                    m.base_color
                ));
            }
            if !m.emission.is_finite() || m.emission.min_element() < 0.0 {
                return Err(format!(
                    "material {i} '{name}': emission {} is not finite and ≥ 0",
                    m.emission
                ));
            }
            for (field, v) in [("metallic", m.metallic), ("roughness", m.roughness)] {
                if !(0.0..=1.0).contains(&v) {
                    return Err(format!("material {i} '{name}': {field} {v} outside [0, 1]"));
                }
            }
            for (slot, texture) in [
                ("base-colour", m.base_color_texture),
                ("emissive", m.emissive_texture),
                ("normal", m.normal_texture),
                ("metallic-roughness", m.metallic_roughness_texture),
                ("alpha", m.alpha_texture),
            ] {
                if let Some(t) = texture
                    && t.index() >= self.textures.len()
                {
                    return Err(format!(
                        "material {i} '{name}': {slot} texture {} of {}",
                        t.0,
                        self.textures.len()
                    ));
                }
            }
            if let Some(c) = m.alpha_cutoff
                && !(c.is_finite() && (0.0..=1.0).contains(&m.alpha))
            {
                return Err(format!(
                    "material {i} '{name}': alpha {} or alpha cutoff {c} not finite or alpha outside [0, 1]",
                    m.alpha
                ));
            }
        }
        for (i, n) in self.nodes.iter().enumerate() {
            if let Some(p) = n.parent
                && p.index() >= i
            {
                return Err(format!(
                    "node {i} '{}': parent {} does not come first",
                    excerpt(&n.name),
                    p.0
                ));
            }
            if !n.local.is_finite() {
                return Err(format!(
                    "node {i} '{}': transform is not finite",
                    excerpt(&n.name)
                ));
            }
        }
        for (i, inst) in self.instances.iter().enumerate() {
            if inst.mesh.index() >= self.meshes.len() || inst.node.index() >= self.nodes.len() {
                return Err(format!(
                    "instance {i} '{}': mesh or node out of range",
                    excerpt(&inst.name)
                ));
            }
        }
        for (i, l) in self.lights.iter().enumerate() {
            let aimed = !matches!(l.kind, LightKind::Point { .. });
            let forward = l.world_from_light.transform_vector3(-Vec3::Z);
            if aimed && !(forward.is_finite() && forward.length_squared() > 1e-24) {
                return Err(format!(
                    "light {i} '{}': its node's transform is degenerate (zero scale), so it has no direction",
                    excerpt(&l.name)
                ));
            }
            if l.node.index() >= self.nodes.len() {
                return Err(format!(
                    "light {i} '{}': node out of range",
                    excerpt(&l.name)
                ));
            }
        }
        // Powers are bounded so that every product of the transport (power × pdf ratios
        // × throughput, summed over pixels) stays finite in f32.
        let radius = self.bounds().bounding_radius();
        for (i, l) in self.lights.iter().enumerate() {
            let p = l.power(if radius.is_finite() { radius } else { 0.0 });
            if !p.is_finite() || p.min_element() < 0.0 || p.max_element() > MAX_POWER_W {
                return Err(format!(
                    "light {i} '{}': its power {} W is not finite, non-negative and at most {MAX_POWER_W:e} W",
                    excerpt(&l.name),
                    format_large(p)
                ));
            }
        }
        let total = self.total_power();
        if !total.is_finite() || total.max_element() > MAX_POWER_W {
            return Err(format!(
                "the scene's total light power {} W exceeds {MAX_POWER_W:e} W (lights, emissive surfaces and sky together)",
                format_large(total)
            ));
        }
        // A sun path scales its sky with the time of day (0 at night): the sky at scale
        // 1 is what the day reaches, checked as the sky itself is.
        if let Some(base) = self.sun.as_ref().and_then(|s| s.sky_base.as_ref()) {
            base.validate()?;
            let r = self.bounds().bounding_radius();
            let day = total - self.sky_power(r) + base.integral() * (PI * r * r);
            if !day.is_finite() || day.max_element() > MAX_POWER_W {
                return Err(format!(
                    "the scene's total light power with its sun path's sky at full day {} W exceeds {MAX_POWER_W:e} W (lights, emissive surfaces and sky together)",
                    format_large(day)
                ));
            }
        }
        for (i, a) in self.animations.iter().enumerate() {
            for c in &a.channels {
                if c.node.index() >= self.nodes.len() {
                    return Err(format!(
                        "animation {i} '{}': channel targets missing node {}",
                        excerpt(&a.name),
                        c.node.0
                    ));
                }
            }
        }
        Ok(())
    }
}
