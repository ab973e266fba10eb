//! The G-buffer: the primary hit of every pixel, which direct lighting and every
//! technique's indirect light shade.

use crate::camera::CameraRays;
use crate::mip::UvFootprint;
use crate::raster::VisibilityBuffer;
use crate::surface::SurfaceHit;
use crate::world::World;
use illume_core::{Rgb, Vec2, Vec3};
use rayon::prelude::*;

/// How the rasterized G-buffer reads base-colour textures and normal maps.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum TextureFilter {
    /// One bilinear lookup at the pixel centre's texture coordinates, as a ray through
    /// the centre reads them ([`GBuffer::render`]): minified textures alias (moiré,
    /// shimmering under a moving camera), and each pixel's lookup is a cache miss where
    /// a texel is smaller than a pixel.
    #[default]
    Bilinear,
    /// Trilinear mip-mapping by the pixel's footprint ([`crate::mip`]): the same lookup
    /// as `Bilinear` where a texel covers the pixel or more; where the pixel covers more
    /// than a texel, the texture's mean over the footprint (a blend of the two nearest
    /// box-filtered levels) — what many jittered samples per pixel average to, without
    /// the aliasing, at a fraction of the cost.
    Trilinear,
}

/// What a pixel sees.
#[derive(Clone, Copy, Debug)]
pub struct GBufferPixel {
    /// The primary hit (position, normals, albedo, instance, depth `t`).
    pub hit: SurfaceHit,
    /// Unit direction from the hit towards the camera.
    pub to_camera: Vec3,
}

impl GBufferPixel {
    /// The albedo an irradiance-storing technique displays this pixel's indirect light
    /// with, `A/π · E`: with `directional`, the surface's directional albedo towards the
    /// camera ([`SurfaceHit::uniform_albedo`]: exact for light arriving uniformly, beyond
    /// the papers); without, the base colour ρ (the papers' ρ/π · E on every surface).
    /// The two are the same bits on a Lambertian surface.
    #[inline]
    pub fn display_albedo(&self, directional: bool) -> Rgb {
        if directional {
            self.hit.uniform_albedo(self.to_camera)
        } else {
            self.hit.albedo
        }
    }
}

/// Primary hits of a `width × height` image (row-major, row 0 at the top); `None` where
/// the pixel sees nothing.
#[derive(Clone, Debug)]
pub struct GBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// One entry per pixel.
    pub pixels: Vec<Option<GBufferPixel>>,
    /// Pixels the last [`GBuffer::rasterize_into`] kept from the frame before (their
    /// surface could not have changed); 0 after [`GBuffer::render`].
    pub reused_pixels: u64,
    /// Where in each pixel the primary hits were sampled, in `[0, 1)²` (0.5, 0.5 = the
    /// centre): the offset of [`GBuffer::render`] or [`GBuffer::rasterize_into_at`].
    pub offset: Vec2,
    /// The rasterizer's last visibility buffer, kept for its allocation.
    pub(crate) visibility: VisibilityBuffer,
    /// What the pixels were built from, to tell which ones the next frame may keep.
    pub(crate) built_from: BuildState,
}

/// The scene state a G-buffer was built from: camera, image size, every instance's
/// transform and mask, and every material. Meshes and textures never change after
/// loading.
#[derive(Clone, Debug, Default)]
pub(crate) struct BuildState {
    camera: Option<illume_scene::Camera>,
    size: (u32, u32),
    instances: Vec<(illume_core::Affine3A, u32)>,
    materials: Vec<illume_scene::Material>,
    filter: TextureFilter,
    offset: Vec2,
}

impl BuildState {
    /// The state of `world` for a `width × height` image.
    pub(crate) fn of(
        world: &World,
        width: u32,
        height: u32,
        filter: TextureFilter,
        offset: Vec2,
    ) -> Self {
        let scene = &world.scene;
        Self {
            camera: Some(scene.camera.clone()),
            size: (width, height),
            instances: scene
                .instances
                .iter()
                .map(|i| (i.world_from_object, i.mask))
                .collect(),
            materials: scene.materials.clone(),
            filter,
            offset,
        }
    }

    /// For each instance of `next`, true when pixels seeing it may keep their surface
    /// from a build at `self`: same camera, size and materials, and the instance has not
    /// moved nor changed its mask. Empty when nothing may be kept.
    pub(crate) fn unchanged_instances(&self, next: &Self) -> Vec<bool> {
        if self.camera.is_none()
            || self.camera != next.camera
            || self.size != next.size
            || self.materials != next.materials
            || self.filter != next.filter
            || self.offset != next.offset
            || self.instances.len() != next.instances.len()
        {
            return Vec::new();
        }
        self.instances
            .iter()
            .zip(&next.instances)
            .map(|(a, b)| a == b)
            .collect()
    }
}

impl GBuffer {
    /// Traces one primary ray per pixel through `offset` within the pixel (0.5, 0.5 =
    /// centre), in parallel. This is the reference for primary visibility;
    /// [`GBuffer::rasterize`] gives the same hits far cheaper but only at the pixel centre
    /// (offset 0.5, 0.5), so sub-pixel jitter needs this path.
    pub fn render(world: &World, width: u32, height: u32, offset: Vec2) -> Self {
        let cam = CameraRays::new(&world.scene.camera, width, height);
        let pixels = (0..width * height)
            .into_par_iter()
            .with_min_len(64)
            .map(|i| {
                let ray = cam.ray(i % width, i / width, offset);
                world
                    .trace(&ray, illume_scene::MASK_DEFAULT)
                    .map(|hit| GBufferPixel {
                        hit,
                        to_camera: -ray.dir,
                    })
            })
            .collect();
        Self {
            width,
            height,
            pixels,
            reused_pixels: 0,
            offset,
            visibility: VisibilityBuffer::empty(),
            built_from: BuildState::default(),
        }
    }

    /// A 0 × 0 G-buffer: an allocation for [`GBuffer::rasterize_into`] to fill.
    pub fn empty() -> Self {
        Self {
            width: 0,
            height: 0,
            pixels: Vec::new(),
            reused_pixels: 0,
            offset: Vec2::splat(0.5),
            visibility: VisibilityBuffer::empty(),
            built_from: BuildState::default(),
        }
    }

    /// The entry of pixel (x, y).
    pub fn get(&self, x: u32, y: u32) -> Option<&GBufferPixel> {
        self.pixels[(y * self.width + x) as usize].as_ref()
    }

    /// The rasterizer's visibility buffer this G-buffer was built from: each pixel's
    /// instance, triangle and `1/w` at its sample in 12 bytes, cheaper to read than the
    /// entries when that is all a pass needs. It covers what the rasterizer saw: a pixel
    /// next to a silhouette that a BVH ray filled is empty there. `None` for a G-buffer
    /// of rays ([`GBuffer::render`]).
    pub fn visibility(&self) -> Option<&VisibilityBuffer> {
        let v = &self.visibility;
        (v.width == self.width && v.height == self.height && !v.pixels.is_empty()).then_some(v)
    }
}

/// Rebuilds primary hits from a visibility buffer without the BVH: per-triangle data is
/// set up once per run of pixels that see the same triangle (neighbouring pixels mostly
/// do), so a pixel costs a ray–plane intersection, two dot products for barycentrics and
/// the interpolation of its attributes.
///
/// The result matches [`SurfaceHit::new`] for the same ray and triangle up to f32
/// rounding (≈ 1e-6 relative): the same formulas, but in world space with the triangle's
/// vertices transformed once instead of the ray transformed per pixel. Pixels whose
/// centre ray misses the rasterized triangle by more than [`PrimarySurfaces::EDGE_SLACK`]
/// in barycentric terms (snapped edges, edge-on triangles) take a full BVH ray instead.
pub(crate) struct PrimarySurfaces<'a> {
    world: &'a World,
    camera: CameraRays,
    /// Each instance's frame (its cofactor normal matrix), computed once per frame. The
    /// determinant's sign is left out: interpolated normals are flipped to the geometric
    /// normal's side anyway.
    frames: Vec<crate::hit_tables::InstanceFrame>,
    /// How textures are read.
    filter: TextureFilter,
    /// The change of the unnormalised centre direction from one row to the next.
    row_step: Vec3,
}

/// The world-space data of one triangle, shared by the pixels that see it.
#[derive(Clone, Copy, Debug)]
pub(crate) struct TriangleSetup {
    instance: u32,
    mesh: illume_scene::MeshId,
    triangle: u32,
    /// Unit front-face normal.
    geometric_normal: Vec3,
    /// Dual vectors: `b1 = (p − p0)·dual1`, `b2 = (p − p0)·dual2` for p on the plane.
    dual1: Vec3,
    dual2: Vec3,
    /// The camera's signed height over the plane, `n·(p0 − origin)`.
    height: f32,
    /// A corner: barycentrics are measured from it (close to the hit, so precise far
    /// from the camera, unlike sums of large terms measured from the camera).
    p0: Vec3,
    /// World shading normals at the corners (not normalised); `None` without normals or
    /// where the three are equal (then `flat_normal` is every pixel's).
    normals: Option<[Vec3; 3]>,
    /// The shading normal of a triangle without `normals`: its corners' common normal,
    /// normalised once, else the geometric normal.
    flat_normal: Vec3,
    uvs: Option<[Vec2; 3]>,
    /// The normal map and its tangent frame, for normal-mapped triangles.
    normal_map: Option<NormalMap>,
    material: illume_scene::MaterialId,
    /// The camera sees the front face.
    front_face: bool,
    reflects: bool,
    /// Albedo when untextured (the texture is sampled per pixel otherwise).
    albedo: Rgb,
    metallic: f32,
    roughness: f32,
    /// Metallic and roughness come from a texture (sampled per pixel).
    metal_rough_textured: bool,
    textured: bool,
    emission: Rgb,
    /// False for degenerate triangles (pixels then take a BVH ray).
    usable: bool,
}

/// A triangle's normal map: the texture, world tangents at the corners (not
/// normalised) and the bitangent sign.
#[derive(Clone, Copy, Debug)]
pub(crate) struct NormalMap {
    texture: illume_scene::TextureId,
    tangents: [Vec3; 3],
    sign: f32,
}

impl<'a> PrimarySurfaces<'a> {
    /// Barycentric slack accepted before a pixel falls back to a BVH ray. Zero: a
    /// centre the rasterizer gave to a triangle whose exact plane hit lies outside it
    /// (snapping moves edges by ≤ 1/256 pixel) is decided by the BVH, as ray casting
    /// would; such pixels are a few per thousand at most.
    pub(crate) const EDGE_SLACK: f32 = 0.0;

    pub(crate) fn new(
        world: &'a World,
        width: u32,
        height: u32,
        filter: TextureFilter,
        offset: Vec2,
    ) -> Self {
        let frames = world
            .scene
            .instances
            .iter()
            .map(|inst| crate::hit_tables::InstanceFrame::new(&inst.world_from_object))
            .collect();
        let camera = CameraRays::new(&world.scene.camera, width, height).with_offset(offset);
        Self {
            world,
            camera,
            frames,
            filter,
            row_step: camera.row_step(),
        }
    }

    /// The centre rays of image row `y`.
    #[inline]
    pub(crate) fn row(&self, y: u32) -> crate::camera::RowRays {
        self.camera.row(y)
    }

    /// Sets up triangle `triangle` of `instance` as seen from the camera.
    pub(crate) fn setup(&self, instance: u32, triangle: u32) -> TriangleSetup {
        let origin = self.camera.origin();
        let scene = &self.world.scene;
        let inst = &scene.instances[instance as usize];
        let mesh = &scene.meshes[inst.mesh.index()];
        let t = triangle as usize;
        let idx = mesh.indices[t].map(|i| i as usize);
        let m = &inst.world_from_object;
        let [p0, p1, p2] = idx.map(|i| m.transform_point3(mesh.positions[i]));
        let (e1, e2) = (p1 - p0, p2 - p0);
        let n = e1.cross(e2);
        let nn = n.length_squared();
        // Emission-textured triangles take the exact per-pixel path (`SurfaceHit::new`
        // through a BVH ray) rather than this setup's interpolation.
        let tm = &scene.materials[mesh.triangle_materials[t].index()];
        let per_pixel = tm.emissive_texture.is_some();
        let usable = nn > 0.0 && nn.is_finite() && !per_pixel;
        // A mirroring instance keeps its object-space front (see `SurfaceHit::new`); the
        // duals below stay on the unflipped cross product.
        let geometric_normal = (n * self.frames[instance as usize].det_sign).normalize_or(Vec3::Y);
        let front_face = (p0 - origin).dot(geometric_normal) < 0.0;
        let frame = &self.frames[instance as usize];
        let normals =
            (!mesh.normals.is_empty()).then(|| idx.map(|i| frame.normal(mesh.normals[i])));
        let uvs = (!mesh.uvs.is_empty()).then(|| idx.map(|i| mesh.uvs[i]));
        // World tangents (a linear map: transforming the corners transforms every
        // interpolated tangent) for normal maps, as `SurfaceHit::new` reads them.
        let normal_map = match tm.normal_texture {
            Some(tex) if !mesh.tangents.is_empty() && normals.is_some() => Some(NormalMap {
                texture: tex,
                tangents: idx.map(|i| m.transform_vector3(mesh.tangents[i].truncate())),
                sign: if mesh.tangents[idx[0]].w < 0.0 {
                    -1.0
                } else {
                    1.0
                },
            }),
            _ => None,
        };
        // Flat-shaded triangles (three equal corner normals: walls, floors, most of an
        // interior) skip the per-pixel interpolation and its square root.
        let (normals, flat_normal) = match normals {
            Some([n0, n1, n2]) if n0 == n1 && n1 == n2 => (None, n0.normalize_or(geometric_normal)),
            corners => (corners, geometric_normal),
        };
        let material = mesh.triangle_materials[t];
        let mat = &scene.materials[material.index()];
        let reflects = front_face || mat.double_sided;
        let textured = reflects && mat.base_color_texture.is_some();
        let (dual1, dual2) = (e2.cross(n) / nn, n.cross(e1) / nn);
        TriangleSetup {
            instance,
            mesh: inst.mesh,
            triangle,
            geometric_normal,
            dual1,
            dual2,
            height: geometric_normal.dot(p0 - origin),
            p0,
            normals,
            flat_normal,
            uvs,
            normal_map,
            material,
            front_face,
            reflects,
            albedo: if reflects { mat.base_color } else { Rgb::ZERO },
            metallic: mat.metallic,
            roughness: mat.roughness,
            metal_rough_textured: mat.metallic_roughness_texture.is_some(),
            textured,
            emission: if reflects { mat.emission } else { Rgb::ZERO },
            usable,
        }
    }

    /// The G-buffer entry of a pixel whose centre ray (unnormalised direction `d` from
    /// the camera, `step_x` its change to the next pixel of the row) sees `tri` per the
    /// rasterizer, or a BVH ray's answer when the ray does not actually hit it.
    #[inline]
    pub(crate) fn pixel(&self, d: Vec3, step_x: Vec3, tri: &TriangleSetup) -> Option<GBufferPixel> {
        self.on_triangle(d, step_x, tri)
            .or_else(|| self.traced(&illume_core::Ray::new(self.camera.origin(), d.normalize())))
    }

    /// The BVH's answer for `ray`.
    pub(crate) fn traced(&self, ray: &illume_core::Ray) -> Option<GBufferPixel> {
        self.world
            .trace(ray, illume_scene::MASK_DEFAULT)
            .map(|hit| GBufferPixel {
                hit,
                to_camera: -ray.dir,
            })
    }

    /// The surface where the camera ray with unnormalised direction `d` meets `tri`,
    /// `None` when it misses. Worked with `d` as is — the hit is `o + s·d` for the
    /// triangle's (per-triangle) camera height over its plane — so normalising `d` for
    /// `to_camera` and `t` is off the chain of dependent divisions and square roots.
    #[inline]
    fn on_triangle(&self, d: Vec3, step_x: Vec3, tri: &TriangleSetup) -> Option<GBufferPixel> {
        if !tri.usable {
            return None;
        }
        let ng = tri.geometric_normal;
        let s = tri.height / ng.dot(d);
        if !(s > 0.0 && s.is_finite()) {
            return None;
        }
        let origin = self.camera.origin();
        let position = origin + d * s;
        let e = position - tri.p0;
        let (b1, b2) = (e.dot(tri.dual1), e.dot(tri.dual2));
        let b0 = 1.0 - b1 - b2;
        let slack = -Self::EDGE_SLACK;
        if b0 < slack || b1 < slack || b2 < slack {
            return None;
        }
        let len = d.length();
        let dir = d / len;
        let t = s * len;
        let mut shading_normal = match tri.normals {
            Some([n0, n1, n2]) => {
                let n = (n0 * b0 + n1 * b1 + n2 * b2).normalize_or_zero();
                if n == Vec3::ZERO { ng } else { n }
            }
            None => tri.flat_normal,
        };
        let uv = match tri.uvs {
            Some([u0, u1, u2]) => u0 * b0 + u1 * b1 + u2 * b2,
            None => Vec2::ZERO,
        };
        // The footprint: texture coordinates where the neighbouring pixels' centre rays
        // meet the triangle's plane (ray differentials), for textured triangles only.
        let footprint = match tri.uvs {
            Some([u0, u1, u2])
                if self.filter == TextureFilter::Trilinear
                    && (tri.textured || tri.normal_map.is_some()) =>
            {
                let uv_along = |dd: Vec3| {
                    let e = origin + dd * (tri.height / ng.dot(dd)) - tri.p0;
                    let (c1, c2) = (e.dot(tri.dual1), e.dot(tri.dual2));
                    u0 * (1.0 - c1 - c2) + u1 * c1 + u2 * c2
                };
                Some(UvFootprint {
                    duv_dx: uv_along(d + step_x) - uv,
                    duv_dy: uv_along(d + self.row_step) - uv,
                })
            }
            _ => None,
        };
        let scene = &self.world.scene;
        let tables = &self.world.hit_tables;
        // Normal map and base colour read at the same coordinates (no texture transform
        // or the same one): one filtered lookup of both, bit for bit the two lookups.
        let pair = match (&footprint, &tri.normal_map) {
            (Some(f), Some(map)) if tri.textured => {
                let mat = &scene.materials[tri.material.index()];
                match mat.base_color_texture {
                    Some(base) if mat.base_color_transform == mat.normal_transform => {
                        let f = f.through(uv, |uv| mat.normal_uv(uv));
                        let textures = [map.texture, base];
                        Some(tables.sample_footprint_pair(scene, textures, mat.normal_uv(uv), &f))
                    }
                    _ => None,
                }
            }
            _ => None,
        };
        if let Some(map) = &tri.normal_map {
            let [t0, t1, t2] = map.tangents;
            let mat = &scene.materials[tri.material.index()];
            shading_normal = crate::surface::normal_mapped_with(
                mat,
                shading_normal,
                t0 * b0 + t1 * b1 + t2 * b2,
                map.sign,
                || match (&pair, &footprint) {
                    (Some((normal, _)), _) => *normal,
                    (None, Some(f)) => {
                        let at = mat.normal_uv(uv);
                        let f = f.through(uv, |uv| mat.normal_uv(uv));
                        tables.sample_footprint(scene, map.texture, at, &f)
                    }
                    (None, None) => scene.textures[map.texture.index()].sample(mat.normal_uv(uv)),
                },
            );
        }
        if shading_normal.dot(ng) < 0.0 {
            shading_normal = -shading_normal;
        }
        let albedo = match (tri.textured, &footprint, pair) {
            (false, _, _) => tri.albedo,
            (true, _, Some((_, base))) => scene.materials[tri.material.index()].base_color * base,
            (true, Some(f), None) => self.world.albedo_footprint(tri.material, uv, f),
            (true, None, None) => self.world.albedo(tri.material, uv),
        };
        let (metallic, roughness) = if tri.metal_rough_textured {
            self.world.scene.metal_rough(tri.material, uv)
        } else {
            (tri.metallic, tri.roughness)
        };
        Some(GBufferPixel {
            hit: SurfaceHit {
                position,
                geometric_normal: ng,
                shading_normal,
                uv,
                instance: illume_scene::InstanceId(tri.instance),
                mesh: tri.mesh,
                triangle: tri.triangle,
                barycentrics: Vec2::new(b1, b2),
                material: tri.material,
                albedo,
                metallic,
                roughness,
                emission: tri.emission,
                front_face: tri.front_face,
                reflects: tri.reflects,
                t,
            },
            to_camera: -dir,
        })
    }
}

impl TriangleSetup {
    /// True when this is the setup of `(instance, triangle)`.
    #[inline]
    pub(crate) fn is(&self, instance: u32, triangle: u32) -> bool {
        self.instance == instance && self.triangle == triangle
    }
}

impl GBuffer {
    /// The G-buffer of [`GBuffer::render`] at pixel centres (offset 0.5, 0.5 only),
    /// with primary visibility from the [`VisibilityBuffer`] rasterizer instead of a BVH
    /// ray per pixel.
    ///
    /// Each pixel intersects its centre ray with the plane of the triangle the rasterizer
    /// found, in world space, and interpolates that triangle's attributes (set up once per
    /// run of pixels seeing the same triangle): the [`SurfaceHit`]
    /// [`GBuffer::render`] builds for the same triangle, up to f32 rounding. Where the ray
    /// misses the chosen triangle (an edge moved by snapping, an edge-on triangle), and on
    /// empty pixels next to covered ones (silhouettes against the background), a full BVH
    /// ray decides.
    pub fn rasterize(world: &World, width: u32, height: u32) -> Self {
        Self::rasterize_with(world, width, height, TextureFilter::Bilinear)
    }

    /// [`GBuffer::rasterize`] with textures read through `filter` (the plain
    /// rasterization reads them as [`TextureFilter::Bilinear`], like rays).
    pub fn rasterize_with(world: &World, width: u32, height: u32, filter: TextureFilter) -> Self {
        let mut g = Self::empty();
        g.rasterize_into_with(world, width, height, filter);
        g
    }

    /// [`GBuffer::rasterize`] into this buffer, reusing its pixel allocation (a fresh
    /// 800×600 G-buffer is 48 MB whose first touch costs page faults every frame) and
    /// its pixels where nothing they depend on changed: with the same camera, image size
    /// and materials as the previous build, a pixel that sees the same triangle of an
    /// instance that has not moved keeps its surface (counted in
    /// [`GBuffer::reused_pixels`]). The result is bit-identical to a fresh build; only
    /// the pixels of moving objects (where they are and where they were) cost anything.
    pub fn rasterize_into(&mut self, world: &World, width: u32, height: u32) {
        self.rasterize_into_with(world, width, height, TextureFilter::Bilinear);
    }

    /// [`GBuffer::rasterize_into`] with textures read through `filter`; pixels are kept
    /// from the previous build only when it used the same filter.
    pub fn rasterize_into_with(
        &mut self,
        world: &World,
        width: u32,
        height: u32,
        filter: TextureFilter,
    ) {
        self.rasterize_into_at(world, width, height, filter, Vec2::splat(0.5));
    }

    /// [`GBuffer::rasterize_into_with`] sampling each pixel at `offset` in `[0, 1)²`
    /// instead of its centre (0.5, 0.5): the projection is shifted by the offset's
    /// distance from the centre ([`VisibilityBuffer::offset`]) and the rays follow, so the
    /// hits are [`GBuffer::render`]'s at `offset` up to the rasterizer's contract. Pixels
    /// are kept from the previous build only when it used the same offset. Jittered
    /// frames (still refinement) average such buffers over offsets spread in the pixel.
    pub fn rasterize_into_at(
        &mut self,
        world: &World,
        width: u32,
        height: u32,
        filter: TextureFilter,
        offset: Vec2,
    ) {
        let n = (width * height) as usize;
        let next = BuildState::of(world, width, height, filter, offset);
        let unchanged = self.built_from.unchanged_instances(&next);
        let nothing_moved = !unchanged.is_empty() && unchanged.iter().all(|&u| u);
        self.built_from = next;
        if nothing_moved && self.pixels.len() == n {
            // Same camera, size, materials and instances: the same G-buffer.
            self.reused_pixels = n as u64;
            return;
        }
        let vis = &mut self.visibility;
        vis.width = width;
        vis.height = height;
        vis.offset = offset;
        vis.render_into(&world.scene);
        self.width = width;
        self.height = height;
        self.offset = offset;
        if self.pixels.len() != n {
            self.pixels.clear();
            self.pixels.resize(n, None);
        }
        if n == 0 {
            return;
        }
        let surfaces = PrimarySurfaces::new(world, width, height, filter, offset);
        let vis = &self.visibility;
        let w = width as usize;
        self.reused_pixels = self
            .pixels
            .par_chunks_mut(w * SURFACE_ROWS as usize)
            // One job a task, as the rasterizer's strips: rayon's own splitting left a
            // few long runs of rows a thread, and textured rows cost unevenly.
            .with_max_len(1)
            .enumerate()
            .map(|(chunk, out)| {
                let mut current: Option<TriangleSetup> = None;
                let mut reused = 0u64;
                for (r, row) in out.chunks_mut(w).enumerate() {
                    let y = chunk as u32 * SURFACE_ROWS + r as u32;
                    let samples = &vis.pixels[y as usize * w..][..w];
                    let rays = surfaces.row(y);
                    for (x, (px, sample)) in row.iter_mut().zip(samples).enumerate() {
                        let x = x as u32;
                        match sample.visible() {
                            Some((instance, triangle)) => {
                                // Same camera, same static triangle: same surface.
                                let keep = unchanged.get(instance.index()) == Some(&true)
                                    && px.as_ref().is_some_and(|p| {
                                        p.hit.instance == instance && p.hit.triangle == triangle
                                    });
                                if keep {
                                    reused += 1;
                                    continue;
                                }
                                if !current.as_ref().is_some_and(|t| t.is(instance.0, triangle)) {
                                    current = Some(surfaces.setup(instance.0, triangle));
                                }
                                let tri = current.as_ref().expect("set up above");
                                *px = surfaces.pixel(rays.direction(x), rays.step(), tri);
                            }
                            None if next_to_covered(vis, x, y) => {
                                *px = surfaces.traced(&rays.ray(x))
                            }
                            None => *px = None,
                        }
                    }
                }
                reused
            })
            .sum();
    }
}

/// Image rows per parallel job when building surfaces from the visibility buffer.
const SURFACE_ROWS: u32 = 4;

/// True when a 4-neighbour of empty pixel (x, y) is covered.
fn next_to_covered(vis: &VisibilityBuffer, x: u32, y: u32) -> bool {
    let covered = |x: u32, y: u32| vis.get(x, y).instance != u32::MAX;
    (x > 0 && covered(x - 1, y))
        || (x + 1 < vis.width && covered(x + 1, y))
        || (y > 0 && covered(x, y - 1))
        || (y + 1 < vis.height && covered(x, y + 1))
}
