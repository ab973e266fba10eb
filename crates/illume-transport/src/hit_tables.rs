//! Tables derived from a scene that make photon hit records cheap: per-instance frames
//! (transform and normal cofactor matrix) and base-colour textures packed to 8-bit sRGB
//! indices, with box-filtered copies for photons ([`HitTables`]).

use crate::mip::{MipChain, UvFootprint};
use illume_core::{Affine3A, Mat3A, Rgb, Vec2, Vec3, Vec3A};
use illume_scene::{InstanceId, MeshId, Scene, Texture, TextureId, WrapMode};
use rayon::prelude::*;
use std::sync::Arc;

/// An instance's transforms for hit records: its `world_from_object` and the cofactor
/// matrix that carries object-space normals (cross products) to world space.
#[derive(Clone, Copy, Debug)]
pub struct InstanceFrame {
    /// Object to world.
    pub world_from_object: Affine3A,
    /// cof(M) = det(M)·M⁻ᵀ of the linear part M: `cof(M)·(a×b) = (M·a)×(M·b)`.
    pub normal_from_object: Mat3A,
    /// Sign of det(M): 1, or −1 for a mirroring transform.
    pub det_sign: f32,
    /// True when M is the identity (normals need no transform).
    pub linear_identity: bool,
}

impl InstanceFrame {
    /// The frame of `world_from_object`.
    pub fn new(world_from_object: &Affine3A) -> Self {
        let m = &world_from_object.matrix3;
        let (c0, c1, c2) = (m.x_axis, m.y_axis, m.z_axis);
        let normal_from_object = Mat3A::from_cols(c1.cross(c2), c2.cross(c0), c0.cross(c1));
        Self {
            world_from_object: *world_from_object,
            normal_from_object,
            det_sign: c0.dot(c1.cross(c2)).signum(),
            linear_identity: *m == Mat3A::IDENTITY,
        }
    }

    /// `cof(M)·n` (unnormalised).
    #[inline]
    pub fn normal(&self, n: Vec3) -> Vec3 {
        if self.linear_identity {
            n
        } else {
            (self.normal_from_object * Vec3A::from(n)).into()
        }
    }
}

/// Tables derived from a scene that make [`PhotonHit`](crate::surface::PhotonHit)s cheap: each instance's
/// [`InstanceFrame`] (no cofactor matrix per hit), and each texture packed as one 8-bit
/// index per channel into its 256 decoded values — sRGB for colour, code/255 for data
/// such as normal maps (a quarter of the memory of `f32` texels, so far fewer cache
/// misses for scattered photon lookups and the G-buffer's normal maps) — whenever that
/// reproduces every texel exactly: always for textures decoded from 8-bit images; other
/// textures are sampled as they are.
///
/// Cloning copies the instance frames only: the packed textures never change once
/// packed and are shared (`Arc`) between clones, so a second world (another time) does
/// not copy them.
#[derive(Clone, Debug, Default)]
pub struct HitTables {
    frames: Vec<InstanceFrame>,
    textures: Vec<Option<Arc<PackedTexture>>>,
    /// Copies of `textures` box-filtered to at most [`PHOTON_TEXTURE_SIDE`] texels a
    /// side (`None` where the texture is no larger, or not packed).
    filtered: Vec<Option<Arc<PackedTexture>>>,
    /// Mip chains for footprint-filtered lookups ([`HitTables::sample_footprint`]) of the
    /// textures some material uses as base colour or normal map; `None` for the others
    /// and for one-texel textures (lookups then read the texture itself).
    mips: Vec<Option<Arc<MipChain>>>,
    /// Per mesh, one bit a triangle, set where a corner's normal is not the facet's: the
    /// curved regions, where [`SurfaceHit::smooth_point`](crate::SurfaceHit::smooth_point)
    /// can lift a point ([`World::shadow_ray`](crate::World::shadow_ray) skips the
    /// others without reading their corners: normal-mapped walls are flat).
    curved: Vec<Arc<Vec<u64>>>,
}

/// [`HitTables::curved`]'s bits of `mesh`: a triangle is flat when each corner's normal
/// is its facet's normal (either side) to within 1e-6 in cosine; degenerate triangles
/// count as curved.
fn curved_bits(mesh: &illume_scene::Mesh) -> Vec<u64> {
    let mut bits = vec![0u64; mesh.indices.len().div_ceil(64)];
    if mesh.normals.is_empty() {
        return bits;
    }
    for (t, corners) in mesh.indices.iter().enumerate() {
        let [p0, p1, p2] = corners.map(|i| mesh.positions[i as usize]);
        let facet = (p1 - p0).cross(p2 - p0).normalize_or_zero();
        let flat = facet != Vec3::ZERO
            && corners.iter().all(|&i| {
                let n = mesh.normals[i as usize].normalize_or_zero();
                n.dot(facet).abs() >= 1.0 - 1e-6
            });
        if !flat {
            bits[t / 64] |= 1 << (t % 64);
        }
    }
    bits
}

/// Longest side, in texels, of the texture copies photons read with
/// [`PhotonPathSettings::filtered_textures`](crate::photon::PhotonPathSettings).
///
/// A photon's albedo only matters averaged over the many photons that a VSL or a
/// photon-map lookup gathers, over regions far larger than a texel; a box-filtered
/// copy keeps each region's mean albedo and fits in cache. Full-resolution textures
/// (Sponza's are 11 MB) cost photon tracing a cache miss per impact: 128 texels a side,
/// read one texel per impact, made Sponza's photon impacts 1.3× as fast (`BENCHMARKS.md`).
pub const PHOTON_TEXTURE_SIDE: u32 = 128;

/// A texture as packed 8-bit indices `[r, g, b, 0]` into `lut`: [`SRGB8_LUT`] for
/// colour textures, [`LINEAR8_LUT`] for data textures (normal maps, decoded as code/255).
#[derive(Clone, Debug)]
struct PackedTexture {
    width: u32,
    height: u32,
    texels: Vec<[u8; 4]>,
    wrap_u: WrapMode,
    wrap_v: WrapMode,
    /// The 256 values the codes stand for.
    lut: &'static [f32; 256],
}

/// The 256 linear values of 8-bit sRGB codes, computed as the image loaders compute them.
static SRGB8_LUT: std::sync::LazyLock<[f32; 256]> = std::sync::LazyLock::new(|| {
    std::array::from_fn(|i| illume_core::image::srgb_decode(i as f32 / 255.0))
});

/// The 256 values of 8-bit data codes (`code / 255`), computed as the image loaders
/// compute them for textures that are not colour (normal and metal-roughness maps).
static LINEAR8_LUT: std::sync::LazyLock<[f32; 256]> =
    std::sync::LazyLock::new(|| std::array::from_fn(|i| i as f32 / 255.0));

/// For each of the 2¹⁶ high halves `h` of an f32 bit pattern, the first code whose
/// [`SRGB8_LUT`] value has a bit pattern ≥ `h << 16` (256 if none). Non-negative floats
/// order like their bit patterns and a bucket spans at most a couple of codes, so
/// finding a texel's code is one lookup and a step or two instead of a binary search
/// per channel (`BENCHMARKS.md`, `HitTables::new` on Sponza).
static SRGB8_BUCKETS: std::sync::LazyLock<Box<[u16]>> = std::sync::LazyLock::new(|| {
    let lut = &*SRGB8_LUT;
    (0u32..1 << 16)
        .map(|h| lut.partition_point(|x| x.to_bits() < h << 16) as u16)
        .collect()
});

impl HitTables {
    /// Tables for `scene` at its current time.
    pub fn new(scene: &Scene) -> Self {
        let mut tables = Self::default();
        tables.update(scene);
        tables
    }

    /// Brings the instance frames up to date with the scene's transforms and packs
    /// textures added since the last call (textures never change in place).
    pub fn update(&mut self, scene: &Scene) {
        // Meshes, like textures, are only ever added, never changed in place.
        let meshes = self.curved.len().min(scene.meshes.len());
        self.curved.truncate(meshes);
        self.curved.extend(
            scene.meshes[meshes..]
                .iter()
                .map(|m| Arc::new(curved_bits(m))),
        );
        self.frames.clear();
        self.frames.extend(
            scene
                .instances
                .iter()
                .map(|i| InstanceFrame::new(&i.world_from_object)),
        );
        let known = self.textures.len().min(scene.textures.len());
        self.textures.truncate(known);
        self.textures.extend(
            scene.textures[known..]
                .iter()
                .map(|t| PackedTexture::new(t).map(Arc::new)),
        );
        self.filtered.truncate(known);
        let added = self.textures[known..]
            .iter()
            .map(|t| {
                t.as_ref()
                    .and_then(|t| t.box_filtered(PHOTON_TEXTURE_SIDE))
                    .map(Arc::new)
            })
            .collect::<Vec<_>>();
        self.filtered.extend(added);
        // Mip chains only for the textures the G-buffer filters (base colour and normal
        // maps of some material): a chain costs a third more than its texture in 16-byte
        // texels (≈ 90 MB for one 4096² texture), wasted on emissive and
        // metal-roughness maps. A material added later that filters an older texture gets
        // its chain then.
        self.mips.truncate(known);
        self.mips.resize(scene.textures.len(), None);
        let mut filtered_by_gbuffer = vec![false; scene.textures.len()];
        for m in &scene.materials {
            for t in [m.base_color_texture, m.normal_texture]
                .into_iter()
                .flatten()
            {
                if let Some(f) = filtered_by_gbuffer.get_mut(t.index()) {
                    *f = true;
                }
            }
        }
        let missing: Vec<usize> = (0..scene.textures.len())
            .filter(|&i| filtered_by_gbuffer[i] && self.mips[i].is_none())
            .collect();
        let chains: Vec<_> = missing
            .iter()
            .map(|&i| MipChain::new(&scene.textures[i]).map(Arc::new))
            .collect();
        for (i, chain) in missing.into_iter().zip(chains) {
            self.mips[i] = chain;
        }
    }

    /// The frame of `instance` (whose transform is `world_from_object`); computed on the
    /// spot for an instance the tables do not know. Contract: the tables were updated
    /// after the scene's last transform change ([`World`](crate::World) does this).
    #[inline]
    pub fn frame(&self, instance: InstanceId, world_from_object: &Affine3A) -> InstanceFrame {
        match self.frames.get(instance.index()) {
            Some(f) => *f,
            None => InstanceFrame::new(world_from_object),
        }
    }

    /// False when `triangle` of `mesh` is flat (its corners' normals are the facet's:
    /// no point of it can be lifted to a smooth surface); true otherwise, and for a mesh
    /// the tables do not know.
    #[inline]
    pub fn is_curved(&self, mesh: MeshId, triangle: u32) -> bool {
        let t = triangle as usize;
        self.curved
            .get(mesh.index())
            .and_then(|bits| bits.get(t / 64))
            .is_none_or(|word| word >> (t % 64) & 1 == 1)
    }

    /// Bilinear lookup of scene texture `texture` at `uv`, equal bit for bit to
    /// [`Texture::sample`](illume_scene::Texture::sample).
    #[inline]
    pub fn sample(&self, scene: &Scene, texture: TextureId, uv: Vec2) -> Rgb {
        match self.textures.get(texture.index()) {
            Some(Some(packed)) => packed.sample(uv),
            _ => scene.textures[texture.index()].sample(uv),
        }
    }
    /// Trilinear mip-mapped lookup of scene texture `texture` at `uv` for a pixel whose
    /// texture coordinates change by `footprint` to its neighbours (see [`crate::mip`]):
    /// exactly [`HitTables::sample`] where the footprint is at most one texel.
    #[inline]
    pub fn sample_footprint(
        &self,
        scene: &Scene,
        texture: TextureId,
        uv: Vec2,
        footprint: &UvFootprint,
    ) -> Rgb {
        let level0 = |uv| self.sample(scene, texture, uv);
        match self.mips.get(texture.index()) {
            Some(Some(chain)) => chain.sample(uv, chain.lod(footprint), level0),
            _ => level0(uv),
        }
    }

    /// `(sample_footprint(a, …), sample_footprint(b, …))` at the same `uv` and
    /// `footprint`, bit for bit: a material's normal map and base colour usually share
    /// their texture size, wrap modes and coordinates, and then the level of detail,
    /// texel positions and weights are found once for both.
    #[inline]
    pub fn sample_footprint_pair(
        &self,
        scene: &Scene,
        [a, b]: [TextureId; 2],
        uv: Vec2,
        footprint: &UvFootprint,
    ) -> (Rgb, Rgb) {
        match (self.mips.get(a.index()), self.mips.get(b.index())) {
            (Some(Some(ca)), Some(Some(cb))) if ca.same_layout(cb) => {
                ca.sample_pair(cb, uv, ca.lod(footprint), |uv| {
                    (self.sample(scene, a, uv), self.sample(scene, b, uv))
                })
            }
            _ => (
                self.sample_footprint(scene, a, uv, footprint),
                self.sample_footprint(scene, b, uv, footprint),
            ),
        }
    }

    /// The texel at `uv` of the texture's copy box-filtered to at most
    /// [`PHOTON_TEXTURE_SIDE`] texels a side, unfiltered (a filtered texel is already
    /// the mean of the area it covers, so a uniform `uv` over that area reads its mean);
    /// [`HitTables::sample`] when the texture is no larger. Same mean, coarser detail,
    /// one texel read from a cache-resident copy.
    #[inline]
    pub fn sample_filtered(&self, scene: &Scene, texture: TextureId, uv: Vec2) -> Rgb {
        match self.filtered.get(texture.index()) {
            Some(Some(small)) => small.sample_nearest(uv),
            _ => self.sample(scene, texture, uv),
        }
    }
}

impl PackedTexture {
    /// Packs `texture` when every channel of every texel is one of [`SRGB8_LUT`], or
    /// else one of [`LINEAR8_LUT`] (normal maps: 12-byte texels become 4-byte ones, read
    /// back bit for bit).
    fn new(texture: &Texture) -> Option<Self> {
        let srgb = &*SRGB8_LUT;
        let buckets = &*SRGB8_BUCKETS;
        // The first code at or above `v`'s bucket, then up to `v`: a code or two.
        let srgb_code = |v: f32| -> Option<u8> {
            let bits = v.to_bits();
            let mut k = usize::from(buckets[(bits >> 16) as usize]);
            while k < 256 && srgb[k].to_bits() < bits {
                k += 1;
            }
            (k < 256 && srgb[k].to_bits() == bits).then_some(k as u8)
        };
        let linear = &*LINEAR8_LUT;
        let linear_code = |v: f32| -> Option<u8> {
            let k = (v * 255.0).round();
            (0.0..=255.0).contains(&k).then_some(())?;
            (linear[k as usize].to_bits() == v.to_bits()).then_some(k as u8)
        };
        let pack = |code: &(dyn Fn(f32) -> Option<u8> + Sync)| -> Option<Vec<[u8; 4]>> {
            texture
                .texels
                .par_iter()
                .map(|t| Some([code(t.x)?, code(t.y)?, code(t.z)?, 0]))
                .collect::<Option<Vec<_>>>()
                .filter(|t| !t.is_empty())
        };
        let (texels, lut) = match pack(&srgb_code) {
            Some(t) => (t, srgb),
            None => (pack(&linear_code)?, linear),
        };
        Some(Self {
            width: texture.width,
            height: texture.height,
            texels,
            wrap_u: texture.wrap_u,
            wrap_v: texture.wrap_v,
            lut,
        })
    }

    /// A copy box-filtered to at most `side` texels a side: each texel is the
    /// area-weighted mean of the linear values of the texels it covers, stored as the
    /// nearest code of the same table. `None` when the texture already fits.
    fn box_filtered(&self, side: u32) -> Option<Self> {
        if self.width <= side && self.height <= side {
            return None;
        }
        let lut = self.lut;
        let (w, h) = (self.width.min(side), self.height.min(side));
        let (wx, wy) = (box_weights(self.width, w), box_weights(self.height, h));
        // Horizontal pass: every source row to `w` linear texels.
        let rows: Vec<Rgb> = (0..self.height as usize)
            .into_par_iter()
            .flat_map_iter(|y| {
                let row = &self.texels[y * self.width as usize..][..self.width as usize];
                wx.iter().map(move |taps| {
                    taps.iter().fold(Rgb::ZERO, |acc, &(j, a)| {
                        let [r, g, b, _] = row[j];
                        acc + Rgb::new(lut[r as usize], lut[g as usize], lut[b as usize]) * a
                    })
                })
            })
            .collect();
        let code = |v: f32| -> u8 {
            let k = lut.partition_point(|&x| x < v).min(255);
            if k > 0 && v - lut[k - 1] <= lut[k] - v {
                (k - 1) as u8
            } else {
                k as u8
            }
        };
        // Vertical pass, then back to codes.
        let texels = (0..h as usize)
            .flat_map(|y| (0..w as usize).map(move |x| (x, y)))
            .map(|(x, y)| {
                let v = wy[y]
                    .iter()
                    .fold(Rgb::ZERO, |acc, &(j, a)| acc + rows[j * w as usize + x] * a);
                [code(v.x), code(v.y), code(v.z), 0]
            })
            .collect();
        Some(Self {
            width: w,
            height: h,
            texels,
            wrap_u: self.wrap_u,
            wrap_v: self.wrap_v,
            lut,
        })
    }

    /// The texel containing `uv` (wrapped as [`Texture::sample`] wraps).
    #[inline]
    fn sample_nearest(&self, uv: Vec2) -> Rgb {
        let lut = self.lut;
        let x = self
            .wrap_u
            .wrap(floor_i64(uv.x * self.width as f32), self.width);
        let y = self
            .wrap_v
            .wrap(floor_i64(uv.y * self.height as f32), self.height);
        let [r, g, b, _] = self.texels[y * self.width as usize + x];
        Rgb::new(lut[r as usize], lut[g as usize], lut[b as usize])
    }

    /// [`Texture::sample`]'s arithmetic on the decoded texels.
    #[inline]
    fn sample(&self, uv: Vec2) -> Rgb {
        let lut = self.lut;
        let x = uv.x * self.width as f32 - 0.5;
        let y = uv.y * self.height as f32 - 0.5;
        let (ix, iy) = (floor_i64(x), floor_i64(y));
        let (x0, y0) = (ix as f32, iy as f32);
        let (fx, fy) = (x - x0, y - y0);
        let (cx0, cx1) = crate::mip::wrap_pair(self.wrap_u, ix, self.width);
        let (cy0, cy1) = crate::mip::wrap_pair(self.wrap_v, iy, self.height);
        let (r0, r1) = (cy0 * self.width as usize, cy1 * self.width as usize);
        let t = |i: usize| {
            let [r, g, b, _] = self.texels[i];
            Rgb::new(lut[r as usize], lut[g as usize], lut[b as usize])
        };
        let top = t(r0 + cx0) * (1.0 - fx) + t(r0 + cx1) * fx;
        let bottom = t(r1 + cx0) * (1.0 - fx) + t(r1 + cx1) * fx;
        top * (1.0 - fy) + bottom * fy
    }
}

/// For each of `dst` texels spanning the same extent as `src`, the source texels it
/// overlaps and the fraction of its width each covers (the fractions sum to 1).
pub(crate) fn box_weights(src: u32, dst: u32) -> Vec<Vec<(usize, f32)>> {
    let scale = src as f64 / dst as f64;
    (0..dst)
        .map(|i| {
            let (a, b) = (i as f64 * scale, (i + 1) as f64 * scale);
            (a.floor() as usize..(b.ceil() as usize).min(src as usize))
                .map(|j| {
                    (
                        j,
                        ((b.min(j as f64 + 1.0) - a.max(j as f64)) / scale) as f32,
                    )
                })
                .filter(|&(_, f)| f > 0.0)
                .collect()
        })
        .collect()
}

/// `x.floor() as i64` without the libm call (x86-64's baseline has no SSE4.1 `roundss`):
/// exact for every f32 — above 2²³ in magnitude an f32 is already an integer — and 0
/// for NaN, as the cast gives.
#[inline(always)]
pub(crate) fn floor_i64(x: f32) -> i64 {
    let i = x as i64;
    if (i as f32) > x {
        i.saturating_sub(1)
    } else {
        i
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::sampling::{Pcg32, SampleStream, mix64};

    /// A texture of sRGB-8 values (so it packs), `w`×`h`, from `f(x, y)` codes.
    fn srgb8_texture(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) -> Texture {
        let lut = &*SRGB8_LUT;
        Texture::from_fn("test", w, h, |x, y| f(x, y).map(|c| lut[c as usize]).into())
    }

    fn mean(t: &PackedTexture) -> Rgb {
        let lut = &*SRGB8_LUT;
        let sum = t.texels.iter().fold(Rgb::ZERO, |acc, [r, g, b, _]| {
            acc + Rgb::new(lut[*r as usize], lut[*g as usize], lut[*b as usize])
        });
        sum / t.texels.len() as f32
    }

    #[test]
    fn mip_chains_only_for_textures_the_gbuffer_filters() {
        use illume_scene::Material;
        use illume_scene::builtin::SceneBuilder;
        let mut b = SceneBuilder::new();
        let albedo = b.texture(srgb8_texture(16, 16, |x, y| [x as u8, y as u8, 7]));
        let emissive = b.texture(srgb8_texture(16, 16, |x, _| [x as u8, 1, 2]));
        b.material(Material {
            base_color_texture: Some(albedo),
            emissive_texture: Some(emissive),
            ..Default::default()
        });
        let mut scene = b.finish("test:mips");
        let mut tables = HitTables::new(&scene);
        assert!(tables.mips[albedo.index()].is_some());
        assert!(
            tables.mips[emissive.index()].is_none(),
            "emissive map got a chain"
        );
        // A material added later that filters the older texture gets its chain.
        scene.materials.push(Material {
            normal_texture: Some(emissive),
            ..Default::default()
        });
        tables.update(&scene);
        assert!(tables.mips[emissive.index()].is_some());
    }

    #[test]
    fn paired_footprint_lookups_equal_the_two_lookups_bit_for_bit() {
        use illume_scene::Material;
        use illume_scene::builtin::SceneBuilder;
        let mut rng = Pcg32::new(5, 6);
        let mut b = SceneBuilder::new();
        // A packed sRGB base colour and an unpacked (f32) normal map of the same size
        // and wraps (the shared path), and a normal map one texel narrower (not shared).
        let mut base = srgb8_texture(37, 21, |x, y| {
            [(x * 7) as u8, (y * 11) as u8, (x ^ y) as u8]
        });
        base.wrap_v = WrapMode::Mirror;
        let f32_map = |w: u32| {
            let mut t = Texture::from_fn("n", w, 21, |x, y| {
                Rgb::new(x as f32 * 0.0173 + 0.01, y as f32 * 0.029 + 0.001, 0.5)
            });
            t.wrap_v = WrapMode::Mirror;
            t
        };
        let (base, normal, narrow) = (
            b.texture(base),
            b.texture(f32_map(37)),
            b.texture(f32_map(36)),
        );
        for n in [normal, narrow] {
            b.material(Material {
                base_color_texture: Some(base),
                normal_texture: Some(n),
                ..Default::default()
            });
        }
        let scene = b.finish("test:pairs");
        let tables = HitTables::new(&scene);
        let chain = |t: TextureId| tables.mips[t.index()].as_ref().expect("chain");
        assert!(
            tables.textures[base.index()].is_some() && tables.textures[normal.index()].is_none()
        );
        assert!(chain(normal).same_layout(chain(base)));
        assert!(!chain(narrow).same_layout(chain(base)));
        let bits = |c: Rgb| c.to_array().map(f32::to_bits);
        let mut levels = [0usize; 3];
        for i in 0..20_000 {
            let uv = Vec2::new(rng.next_1d() * 8.0 - 4.0, rng.next_1d() * 8.0 - 4.0);
            // Footprints from a fraction of a texel (level 0) to beyond the chain.
            let scale = 2f32.powf(rng.next_1d() * 14.0 - 8.0) / 37.0;
            let footprint = UvFootprint {
                duv_dx: Vec2::new(rng.next_1d() - 0.5, rng.next_1d() - 0.5) * scale,
                duv_dy: Vec2::new(rng.next_1d() - 0.5, rng.next_1d() - 0.5) * scale,
            };
            let lod = chain(base).lod(&footprint);
            levels[usize::from(lod > 0.0) + usize::from(lod > 1.0)] += 1;
            for n in [normal, narrow] {
                let (a, b) = tables.sample_footprint_pair(&scene, [n, base], uv, &footprint);
                let a0 = tables.sample_footprint(&scene, n, uv, &footprint);
                let b0 = tables.sample_footprint(&scene, base, uv, &footprint);
                assert_eq!(
                    (bits(a), bits(b)),
                    (bits(a0), bits(b0)),
                    "{i}: {uv} lod {lod}"
                );
            }
        }
        // Every branch was taken: magnified, between level 0 and 1, deeper levels.
        assert!(levels.iter().all(|&n| n > 1000), "{levels:?}");
    }

    #[test]
    fn every_srgb8_code_packs_to_itself_and_nothing_else_packs() {
        let all = srgb8_texture(256, 1, |x, _| [x as u8, 255 - x as u8, (x * 7 % 256) as u8]);
        let packed = PackedTexture::new(&all).expect("all 256 codes pack");
        for (x, t) in packed.texels.iter().enumerate() {
            assert_eq!(*t, [x as u8, 255 - x as u8, (x * 7 % 256) as u8, 0]);
        }
        // A value between two codes, one above 1 and NaN keep the texture unpacked.
        for bad in [0.5f32, 1.0001, f32::NAN, -0.0001] {
            let mut t = all.clone();
            t.texels[17].y = bad;
            assert!(PackedTexture::new(&t).is_none(), "{bad} packed");
        }
    }

    #[test]
    fn box_weights_cover_each_source_texel_once() {
        for (src, dst) in [(1000u32, 128u32), (129, 128), (1024, 128), (7, 3)] {
            let w = box_weights(src, dst);
            let mut coverage = vec![0.0f64; src as usize];
            for taps in &w {
                let sum: f32 = taps.iter().map(|t| t.1).sum();
                assert!(
                    (sum - 1.0).abs() < 1e-5,
                    "{src}->{dst}: weights sum to {sum}"
                );
                for &(j, f) in taps {
                    coverage[j] += f as f64 * src as f64 / dst as f64;
                }
            }
            // Every source texel counts exactly once in total.
            assert!(
                coverage.iter().all(|c| (c - 1.0).abs() < 1e-4),
                "{src}->{dst}"
            );
        }
    }

    #[test]
    fn filtered_textures_keep_the_mean_and_constants() {
        // Noise-like content, sizes that do not divide: the mean survives to within the
        // 8-bit re-encoding (half a code step, at most 0.0045 in linear units).
        let noisy = srgb8_texture(1000, 301, |x, y| {
            let h = mix64(u64::from(x) << 32 | u64::from(y));
            [h as u8, (h >> 8) as u8, (h >> 16) as u8]
        });
        let full = PackedTexture::new(&noisy).expect("sRGB-8 packs");
        let small = full
            .box_filtered(PHOTON_TEXTURE_SIDE)
            .expect("larger than the cap");
        assert_eq!((small.width, small.height), (128, 128));
        let (a, b) = (mean(&full), mean(&small));
        assert!((a - b).abs().max_element() < 2e-3, "means {a} vs {b}");
        // A constant texture stays that constant, code for code.
        let flat = srgb8_texture(640, 477, |_, _| [200, 17, 90]);
        let small = PackedTexture::new(&flat)
            .unwrap()
            .box_filtered(PHOTON_TEXTURE_SIDE)
            .unwrap();
        assert!(small.texels.iter().all(|&t| t == [200, 17, 90, 0]));
        // Small textures are not copied.
        let tiny = srgb8_texture(128, 64, |_, _| [1, 2, 3]);
        assert!(
            PackedTexture::new(&tiny)
                .unwrap()
                .box_filtered(128)
                .is_none()
        );
        // A white/black step halves where a filtered texel straddles it, and stays
        // sharp elsewhere: the filter is local.
        let step = srgb8_texture(256, 4, |x, _| if x < 129 { [255; 3] } else { [0; 3] });
        let small = PackedTexture::new(&step)
            .unwrap()
            .box_filtered(128)
            .unwrap();
        let lut = &*SRGB8_LUT;
        let row: Vec<f32> = small.texels[..128]
            .iter()
            .map(|t| lut[t[0] as usize])
            .collect();
        assert_eq!((row[0], row[63], row[65], row[127]), (1.0, 1.0, 0.0, 0.0));
        assert!((row[64] - 0.5).abs() < 5e-3, "straddling texel {}", row[64]);
        // Photons read the texel containing uv, wrapped.
        let at = |u: f32| small.sample_nearest(Vec2::new(u, 0.3)).x;
        assert_eq!(at(64.5 / 128.0), row[64]);
        assert_eq!(at(63.99 / 128.0), 1.0);
        assert_eq!(at(1.0 + 0.5 / 128.0), 1.0);
        assert_eq!(at(-0.5 / 128.0), 0.0);
    }

    #[test]
    fn floor_i64_is_floor_then_cast() {
        let specials = [
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            1.5,
            -1.5,
            8388607.5,
            -8388607.5,
            1e10,
            -1e10,
            1e30,
            -1e30,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::NAN,
            f32::EPSILON,
            -f32::EPSILON,
            f32::MIN_POSITIVE,
        ];
        let mut rng = Pcg32::new(3, 4);
        let random = (0..100_000).map(|_| (rng.next_1d() - 0.5) * 4096.0);
        for x in specials.into_iter().chain(random) {
            assert_eq!(floor_i64(x), x.floor() as i64, "x = {x}");
        }
    }

    #[test]
    fn packed_textures_sample_bit_for_bit_like_their_source() {
        let mut rng = Pcg32::new(1, 2);
        // Colour (sRGB codes) and data (code/255: normal maps) textures.
        for (lut, wrap_u, wrap_v) in [
            (&*SRGB8_LUT, WrapMode::Repeat, WrapMode::Repeat),
            (&*SRGB8_LUT, WrapMode::Clamp, WrapMode::Mirror),
            (&*LINEAR8_LUT, WrapMode::Mirror, WrapMode::Clamp),
            (&*LINEAR8_LUT, WrapMode::Repeat, WrapMode::Repeat),
        ] {
            let (width, height) = (7u32, 5u32);
            let mut code = || lut[(rng.next_1d() * 256.0) as usize % 256];
            let texture = Texture {
                name: "t".into(),
                width,
                height,
                texels: (0..width * height)
                    .map(|_| Rgb::new(code(), code(), code()))
                    .collect(),
                wrap_u,
                wrap_v,
                alpha: vec![],
            };
            let packed = PackedTexture::new(&texture).expect("8-bit texels pack");
            assert!(std::ptr::eq(packed.lut, lut), "packed with the other table");
            for _ in 0..5000 {
                let uv = Vec2::new(rng.next_1d() * 6.0 - 3.0, rng.next_1d() * 6.0 - 3.0);
                let (a, b) = (packed.sample(uv), texture.sample(uv));
                assert_eq!(
                    a.to_array().map(f32::to_bits),
                    b.to_array().map(f32::to_bits)
                );
            }
        }
        // A texel that is no 8-bit sRGB value keeps the texture unpacked.
        let odd = Texture {
            name: "odd".into(),
            width: 1,
            height: 1,
            texels: vec![Rgb::splat(0.123_456_7)],
            wrap_u: WrapMode::Repeat,
            wrap_v: WrapMode::Repeat,
            alpha: vec![],
        };
        assert!(PackedTexture::new(&odd).is_none());
    }
}
