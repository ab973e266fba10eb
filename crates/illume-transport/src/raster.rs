//! Primary visibility by rasterization: a CPU visibility buffer of (depth, instance,
//! triangle) per pixel, from which [`GBuffer::rasterize`](crate::GBuffer::rasterize)
//! (in [`crate::gbuffer`]) builds the same G-buffer that ray casting
//! ([`GBuffer::render`](crate::GBuffer::render)) builds, far cheaper.
//!
//! Photon streaming (Meneveaux & Bridault 2008) rasterizes its G-buffer; we do it on the
//! CPU. The projection is exactly [`CameraRays`](crate::CameraRays)'s: vertical field of view `yfov_rad`,
//! aspect `width / height`, pixel (x, y) sampled at its centre (x + 0.5, y + 0.5), y = 0 at
//! the top, camera looking down −Z. Every instance visible to
//! [`MASK_DEFAULT`] is drawn; back faces are not culled (a
//! one-sided material still occludes, as it does for rays).
//!
//! # Pipeline
//!
//! 1. Vertices go to clip space `(x, y, w)` once per instance per frame through
//!    `clip_from_object = clip_from_world · world_from_object` (in parallel for big meshes);
//!    `w` is the view depth, so `1/w` is affine in screen space and is the depth we test
//!    (no far plane).
//! 2. Triangle setup, in parallel over chunks of triangles: triangles wholly outside one
//!    frustum plane are dropped; those crossing the near plane ([`NEAR_W`]) or the guard
//!    band (|x|, |y| ≤ [`GUARD_BAND`]·w) are clipped in homogeneous space
//!    (Sutherland–Hodgman) and fanned. Corners snap to 1/[`SUBPIXELS`] pixel; edges are
//!    exact 64-bit integer functions with the top-left fill rule, so triangles sharing an
//!    edge cover each pixel centre exactly once.
//! 3. Binning: each screen triangle is listed in every strip of [`STRIP_ROWS`] full-width
//!    rows it overlaps, in scene order (instance, then triangle); each setup job bins its
//!    own triangles, and a strip reads the jobs' lists in job order.
//! 4. Strips are rasterized in parallel (rayon), each into its own rows of the buffer:
//!    the nearer `1/w` wins, the first drawn on an exact tie.
//!
//! # Cost
//!
//! The visibility buffer is a small part of a G-buffer build; most of the rest is the
//! per-pixel surface (camera ray, one-triangle test, attribute interpolation) and
//! touching the pixels' memory. Measurements: `BENCHMARKS.md`, "G-buffer"
//! (`cargo bench -p illume-transport --bench gbuffer`).
//!
//! Strips rather than square tiles: a strip is a contiguous run of the row-major output,
//! so workers write the final buffer directly, and 16 rows × 1280 pixels of state stays in
//! L2.
//!
//! The same setup, binning and strips render shadow-map depth from a light
//! (`illume_render::shadow_map`): a viewport is any perspective projection (spot lights, cube
//! faces) or an orthographic one (directional lights), whose depth attribute is `1/w` or,
//! orthographically, a plane of world position.

use glam::{Affine3A, DVec4, Vec2, Vec3, Vec4};
use illume_scene::{InstanceId, MASK_DEFAULT, MeshCutout, Scene};
use rayon::prelude::*;

/// Nearest view depth drawn \[m\]: geometry closer to the camera plane than this is clipped
/// away (rays from the camera would still see it). A tenth of a millimetre.
pub const NEAR_W: f64 = 1e-4;

/// Guard band in NDC units: triangles reaching further than `|x|, |y| > GUARD_BAND · w`
/// are clipped, which bounds snapped screen coordinates (and keeps the 64-bit edge
/// functions exact) for images up to 2¹⁴ pixels on a side.
pub const GUARD_BAND: f64 = 2.0;

/// Sub-pixel precision of snapped corners (positions are multiples of `1/SUBPIXELS`).
pub const SUBPIXELS: i64 = 256;

/// Rows per strip, the unit of binning and of parallel rasterization.
pub const STRIP_ROWS: u32 = 16;

/// Bounding-box width \[pixels\] from which a triangle's rows are found by division rather
/// than by stepping.
const SPAN_MIN_WIDTH: i32 = 8;

/// Triangles per parallel setup job. Small enough that a scene of a few thousand
/// triangles (the Cornell box: 2 188) still splits over two threads; on Sponza the 260
/// jobs' strip lists cost nothing measurable (BENCHMARKS.md, "passes").
const SETUP_CHUNK: usize = 256;

/// Vertices per parallel transform job (smaller meshes are transformed in one go).
const TRANSFORM_CHUNK: usize = 8192;

/// What one pixel centre sees: the nearest triangle and its reciprocal view depth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct VisibilitySample {
    /// `1/w` at the pixel centre (w = view depth \[m\]; larger is nearer); 0 when empty.
    pub inverse_depth: f32,
    /// The instance, `u32::MAX` when the pixel sees nothing.
    pub instance: u32,
    /// Triangle index within the instance's mesh.
    pub triangle: u32,
}

impl VisibilitySample {
    /// A pixel that sees nothing.
    pub const EMPTY: Self = Self {
        inverse_depth: 0.0,
        instance: u32::MAX,
        triangle: u32::MAX,
    };

    /// `(instance, triangle)` seen, `None` when empty.
    #[inline]
    pub fn visible(&self) -> Option<(InstanceId, u32)> {
        (self.instance != u32::MAX).then_some((InstanceId(self.instance), self.triangle))
    }
}

/// Per-pixel nearest triangle of a `width × height` image (row-major, row 0 at the top).
#[derive(Clone, Debug)]
pub struct VisibilityBuffer {
    /// Width in pixels.
    pub width: u32,
    /// Height in pixels.
    pub height: u32,
    /// One sample per pixel.
    pub pixels: Vec<VisibilitySample>,
    /// Where in each pixel the sample lies, in `[0, 1)²` (0.5, 0.5 = the centre, what
    /// [`VisibilityBuffer::render`] takes): [`VisibilityBuffer::render_into`] shifts the
    /// projection by the offset's distance from the centre, so that the pixel centres
    /// the rasterizer samples see what the camera sees at `(x, y) + offset`.
    pub offset: Vec2,
}

impl VisibilityBuffer {
    /// Rasterizes every instance of `scene` visible to `MASK_DEFAULT` from the scene's
    /// camera, sampling pixel centres. Contract: a pixel holds the triangle whose plane is
    /// nearest along the pixel-centre camera ray among the triangles covering that centre
    /// (after snapping corners to 1/[`SUBPIXELS`] pixel and clipping at [`NEAR_W`]).
    pub fn render(scene: &Scene, width: u32, height: u32) -> Self {
        let mut buffer = Self {
            width,
            height,
            pixels: Vec::new(),
            offset: Vec2::splat(0.5),
        };
        buffer.render_into(scene);
        buffer
    }

    /// A 0 × 0 buffer.
    pub(crate) fn empty() -> Self {
        Self {
            width: 0,
            height: 0,
            pixels: Vec::new(),
            offset: Vec2::splat(0.5),
        }
    }

    /// [`VisibilityBuffer::render`] into this buffer's size, reusing its allocation.
    pub fn render_into(&mut self, scene: &Scene) {
        let (width, height) = (self.width, self.height);
        // Cleared strip by strip below, on every core (one thread clearing 5.8 MB at
        // 800×600 left the other idle).
        self.pixels
            .resize((width * height) as usize, VisibilitySample::EMPTY);
        if width == 0 || height == 0 {
            return;
        }
        let viewport = Viewport::for_camera(scene, width, height, self.offset);
        let setup = setup_scene(scene, &viewport);
        self.pixels
            .par_chunks_mut((width * STRIP_ROWS) as usize)
            // One strip a task: left to itself, rayon splits the strips into a few runs
            // a thread, and a run of dense strips (a floor under arcades) became the
            // long pole (Sponza's strips kept two threads 1.60× busy; one a task, 1.90×).
            .with_max_len(1)
            .enumerate()
            .for_each(|(strip, out)| {
                let rows = strip as i32 * STRIP_ROWS as i32
                    ..((strip as i32 + 1) * STRIP_ROWS as i32).min(height as i32);
                out.fill(VisibilitySample::EMPTY);
                for tri in setup.strip(strip) {
                    tri.rasterize(rows.clone(), |x, y, z| {
                        let px = &mut out[((y - rows.start) as u32 * width + x as u32) as usize];
                        if z > px.inverse_depth && (!tri.cut || setup.keeps(tri, x, y)) {
                            *px = VisibilitySample {
                                inverse_depth: z,
                                instance: tri.instance,
                                triangle: tri.triangle,
                            };
                        }
                    });
                }
            });
    }

    /// The sample of pixel (x, y).
    #[inline]
    pub fn get(&self, x: u32, y: u32) -> &VisibilitySample {
        &self.pixels[(y * self.width + x) as usize]
    }
}

/// The image and the projection shared by every triangle of a frame: the camera's, or a
/// light's for shadow maps (perspective for spot lights and cube faces, orthographic for
/// directional lights).
pub struct Viewport {
    width: u32,
    height: u32,
    /// Maps world points to clip space `(x, y, w)`: `x/w`, `y/w` are NDC (−1..1 across
    /// the image, +y up) and `w` is the view depth (1 everywhere for an orthographic view).
    clip_from_world: Affine3A,
    /// The plane `z = depth_plane.xyz · p + depth_plane.w` whose ratio `z/w` is the depth
    /// attribute the rasterizer interpolates and compares (larger is nearer). `(0, 0, 0, 1)`
    /// for perspective views: the attribute is `1/w`. An orthographic view has `w = 1`, so
    /// it needs the plane to carry its depth.
    depth_plane: Vec4,
}

impl Viewport {
    /// A viewport whose clip space is world space (for tests that place clip points).
    #[cfg(test)]
    fn new(width: u32, height: u32) -> Self {
        Self::perspective(width, height, Affine3A::IDENTITY)
    }

    /// A `width × height` perspective view: `clip_from_world` maps world points to
    /// `(x, y, w)` with `w` the view depth; the attribute compared is `1/w`.
    pub fn perspective(width: u32, height: u32, clip_from_world: Affine3A) -> Self {
        Self {
            width,
            height,
            clip_from_world,
            depth_plane: Vec4::W,
        }
    }

    /// A `width × height` orthographic view: `clip_from_world` maps world points to
    /// `(x, y, 1)`, and the attribute compared is `depth_plane · (p, 1)` (larger is nearer).
    pub fn orthographic(
        width: u32,
        height: u32,
        clip_from_world: Affine3A,
        depth_plane: Vec4,
    ) -> Self {
        Self {
            width,
            height,
            clip_from_world,
            depth_plane,
        }
    }

    /// The viewport of `scene`'s camera, with [`CameraRays`](crate::CameraRays)'s projection,
    /// shifted so that pixel centres sample the camera's image at `(x, y) + offset`
    /// (`offset` = (0.5, 0.5): unshifted).
    pub(crate) fn for_camera(scene: &Scene, width: u32, height: u32, offset: Vec2) -> Self {
        let camera = &scene.camera;
        let tan_half_y = (camera.yfov_rad * 0.5).tan();
        let aspect = width as f32 / height.max(1) as f32;
        // A point at screen x + offset.x must land on the centre x + 0.5: screen x is
        // (x_c/w + 1)·W/2, so x_c gains −kx·w with kx = (offset.x − 0.5)·2/W; screen y is
        // (1 − y_c/w)·H/2, so y_c gains ky·w. Here w = −z_view.
        let kx = (offset.x - 0.5) * 2.0 / width.max(1) as f32;
        let ky = (offset.y - 0.5) * 2.0 / height.max(1) as f32;
        let clip_from_view = Affine3A::from_mat3(glam::Mat3::from_cols(
            Vec3::new(1.0 / (tan_half_y * aspect), 0.0, 0.0),
            Vec3::new(0.0, 1.0 / tan_half_y, 0.0),
            Vec3::new(kx, -ky, -1.0),
        ));
        Self::perspective(
            width,
            height,
            clip_from_view * camera.world_from_camera.inverse(),
        )
    }

    /// Screen position in pixels (y down) of a clip-space point with `w > 0`.
    #[inline]
    fn to_screen(&self, clip: DVec4) -> (f64, f64) {
        let inv_w = 1.0 / clip.z;
        (
            (clip.x * inv_w + 1.0) * 0.5 * self.width as f64,
            (1.0 - clip.y * inv_w) * 0.5 * self.height as f64,
        )
    }
}

/// A screen-space triangle ready to rasterize: three integer edge functions with the
/// fill rule folded in, a pixel bounding box, and the plane of `1/w`.
#[derive(Clone, Copy, Debug)]
struct ScreenTriangle {
    /// Edge functions `E(X, Y) = a·X + b·Y + c` in sub-pixel units; a sample is inside
    /// when all three are ≥ 0 (the top-left rule is a −1 in `c` of other edges).
    a: [i64; 3],
    b: [i64; 3],
    c: [i64; 3],
    /// Inclusive pixel bounds whose centres may be inside, clamped to the image.
    x0: i32,
    x1: i32,
    y0: i32,
    y1: i32,
    /// The depth attribute (`1/w` in perspective views, see [`Viewport::depth_plane`]) at
    /// the centre of pixel (x0, y0) and its change per pixel in x and y.
    z0: f32,
    dzdx: f32,
    dzdy: f32,
    /// Scene instance and mesh triangle.
    instance: u32,
    triangle: u32,
    /// True when the triangle's material has alpha-mask holes: each covered pixel
    /// centre is then tested ([`SceneSetup::keeps`]).
    cut: bool,
}

impl ScreenTriangle {
    /// Sets up the triangle with snapped screen corners `(x, y)` (sub-pixel units) and
    /// depth attributes (`1/w` values in perspective views); `None` when it has no area or
    /// covers no pixel centre of the image.
    fn new(
        corners: [(i64, i64); 3],
        inverse_depths: [f64; 3],
        viewport: &Viewport,
        instance: u32,
        triangle: u32,
    ) -> Option<Self> {
        let [p0, mut p1, mut p2] = corners;
        let [z0, mut z1, mut z2] = inverse_depths;
        let area = (p1.0 - p0.0) * (p2.1 - p0.1) - (p1.1 - p0.1) * (p2.0 - p0.0);
        if area == 0 {
            return None;
        }
        if area < 0 {
            // Back faces are drawn too: orient counter-clockwise on screen (y down).
            std::mem::swap(&mut p1, &mut p2);
            std::mem::swap(&mut z1, &mut z2);
        }
        let s = SUBPIXELS;
        let half = s / 2;
        // Pixel x has its centre at X = x·s + s/2.
        let first = |v: i64| (v - half).div_euclid(s) + i64::from((v - half).rem_euclid(s) != 0);
        let last = |v: i64| (v - half).div_euclid(s);
        let (minx, maxx) = (p0.0.min(p1.0).min(p2.0), p0.0.max(p1.0).max(p2.0));
        let (miny, maxy) = (p0.1.min(p1.1).min(p2.1), p0.1.max(p1.1).max(p2.1));
        let x0 = first(minx).max(0);
        let x1 = last(maxx).min(viewport.width as i64 - 1);
        let y0 = first(miny).max(0);
        let y1 = last(maxy).min(viewport.height as i64 - 1);
        if x0 > x1 || y0 > y1 {
            return None;
        }
        let mut a = [0; 3];
        let mut b = [0; 3];
        let mut c = [0; 3];
        for (k, (from, to)) in [(p0, p1), (p1, p2), (p2, p0)].into_iter().enumerate() {
            let (dx, dy) = (to.0 - from.0, to.1 - from.1);
            a[k] = -dy;
            b[k] = dx;
            c[k] = dy * from.0 - dx * from.1;
            // Top-left rule (y down, interior on the left of a→b turning clockwise):
            // a left edge goes up, a top edge goes right; others exclude their samples.
            let top_left = dy < 0 || (dy == 0 && dx > 0);
            if !top_left {
                c[k] -= 1;
            }
        }
        // Plane of the depth attribute (1/w) through the snapped corners, in pixels.
        let sf = s as f64;
        let q = |p: (i64, i64), z: f64| glam::DVec3::new(p.0 as f64 / sf, p.1 as f64 / sf, z);
        let (q0, q1, q2) = (q(p0, z0), q(p1, z1), q(p2, z2));
        let n = (q1 - q0).cross(q2 - q0);
        let (dzdx, dzdy) = (-n.x / n.z, -n.y / n.z);
        let centre = (x0 as f64 + 0.5, y0 as f64 + 0.5);
        let z_start = q0.z + dzdx * (centre.0 - q0.x) + dzdy * (centre.1 - q0.y);
        Some(Self {
            a,
            b,
            c,
            x0: x0 as i32,
            x1: x1 as i32,
            y0: y0 as i32,
            y1: y1 as i32,
            z0: z_start as f32,
            dzdx: dzdx as f32,
            dzdy: dzdy as f32,
            instance,
            triangle,
            cut: false,
        })
    }

    /// Calls `covered(x, y, attribute)` for every pixel of `rows` whose centre is inside
    /// (the attribute is `1/w` in perspective views), row by row, left to right.
    #[inline]
    fn rasterize(&self, rows: std::ops::Range<i32>, mut covered: impl FnMut(i32, i32, f32)) {
        self.rasterize_runs(rows, |y, run, z_row| {
            for x in run {
                covered(x, y, z_row + self.dzdx * (x - self.x0) as f32);
            }
        });
    }

    /// Calls `run(y, xs, z_row)` for every row of `rows` with pixels inside: `xs` are
    /// those pixels (a row of a triangle is one run) and the attribute at pixel x is
    /// `z_row + dzdx · (x − x0)`.
    #[inline]
    fn rasterize_runs(
        &self,
        rows: std::ops::Range<i32>,
        mut run: impl FnMut(i32, std::ops::RangeInclusive<i32>, f32),
    ) {
        let s = SUBPIXELS;
        let y_start = self.y0.max(rows.start);
        let y_end = self.y1.min(rows.end - 1);
        let step = [self.a[0] * s, self.a[1] * s, self.a[2] * s];
        let sx = self.x0 as i64 * s + s / 2;
        // Wide triangles get each row's run from its three edges solved for x instead of
        // stepping from the bounding box's edge (shadow maps see walls and floors spanning
        // the whole map); narrow ones step, which is cheaper than solving.
        let wide = self.x1 - self.x0 >= SPAN_MIN_WIDTH;
        for y in y_start..=y_end {
            let sy = y as i64 * s + s / 2;
            let mut e = [0, 1, 2].map(|k| self.a[k] * sx + self.b[k] * sy + self.c[k]);
            let z_row = self.z0 + self.dzdy * (y - self.y0) as f32;
            if wide {
                if let Some(xs) = self.row_run(e, step) {
                    run(y, xs, z_row);
                }
                continue;
            }
            let mut first = None;
            let mut last = self.x1;
            for x in self.x0..=self.x1 {
                if (e[0] | e[1] | e[2]) >= 0 {
                    first.get_or_insert(x);
                } else if first.is_some() {
                    last = x - 1;
                    break;
                }
                e[0] += step[0];
                e[1] += step[1];
                e[2] += step[2];
            }
            if let Some(first) = first {
                run(y, first..=last, z_row);
            }
        }
    }

    /// The pixels of one row inside all three edges, given the edge functions `e` at
    /// pixel `x0` and their change per pixel `step`: edge k holds where
    /// `e[k] + step[k]·i ≥ 0` (i = x − x0), a half-line whose end a float division
    /// estimates and exact integer tests then settle.
    #[inline]
    fn row_run(&self, e: [i64; 3], step: [i64; 3]) -> Option<std::ops::RangeInclusive<i32>> {
        let (mut lo, mut hi) = (0i64, (self.x1 - self.x0) as i64);
        for k in 0..3 {
            let (b, a) = (e[k], step[k]);
            let inside = |i: i64| b + a * i >= 0;
            // Where the boundary −b/a lies, within the current run.
            let estimate = || (-(b as f64) / a as f64).clamp(lo as f64, hi as f64) as i64;
            if a > 0 {
                // Inside from some i on: find the smallest i in [lo, hi] inside.
                if !inside(hi) {
                    return None;
                }
                if !inside(lo) {
                    let mut i = estimate();
                    while !inside(i) {
                        i += 1;
                    }
                    while inside(i - 1) {
                        i -= 1;
                    }
                    lo = i;
                }
            } else if a < 0 {
                // Inside up to some i: find the largest i in [lo, hi] inside.
                if !inside(lo) {
                    return None;
                }
                if !inside(hi) {
                    let mut i = estimate();
                    while !inside(i) {
                        i -= 1;
                    }
                    while inside(i + 1) {
                        i += 1;
                    }
                    hi = i;
                }
            } else if b < 0 {
                return None;
            }
        }
        Some(self.x0 + lo as i32..=self.x0 + hi as i32)
    }
}

/// Every screen triangle of a view, binned by strip, and what testing alpha-mask holes
/// needs.
struct SceneSetup<'s> {
    /// Screen triangles in scene order (instance, then triangle), as the parallel setup
    /// jobs made them, each job's binned by strip on its own thread (no serial binning
    /// or concatenation of the whole list).
    jobs: Vec<SetupJob>,
    /// The scene.
    scene: &'s Scene,
    /// Clip points `(x, y, w, z)` of each scene instance's vertices (empty when the
    /// instance is not drawn or has no holes).
    clip_of_instance: Vec<Vec<Vec4>>,
    /// Alpha-mask holes of each scene mesh (`None`: none).
    cutouts: Vec<Option<MeshCutout>>,
    /// Image size in pixels.
    width: f64,
    height: f64,
}

/// One setup job's screen triangles (in scene order) and their strip bins.
struct SetupJob {
    triangles: Vec<ScreenTriangle>,
    bins: StripBins,
}

impl SceneSetup<'_> {
    /// The screen triangles overlapping strip `s`, in scene order (jobs in order, each
    /// job's triangles in order): the order the depth test breaks exact ties by.
    fn strip(&self, s: usize) -> impl Iterator<Item = &ScreenTriangle> {
        self.jobs.iter().flat_map(move |job| {
            job.bins
                .strip(s)
                .iter()
                .map(|&t| &job.triangles[t as usize])
        })
    }

    /// True when the surface of cut triangle `tri` is there at the centre of pixel
    /// (x, y): the point of the (unclipped) triangle that projects there, found by solving
    /// for its barycentrics in clip space (`x − sx·w = 0`, `y − sy·w = 0` hold for the
    /// affine combination of the corners), which holds for perspective and orthographic
    /// views alike.
    fn keeps(&self, tri: &ScreenTriangle, x: i32, y: i32) -> bool {
        let instance = &self.scene.instances[tri.instance as usize];
        let Some(cutout) = &self.cutouts[instance.mesh.index()] else {
            return true;
        };
        let clip = &self.clip_of_instance[tri.instance as usize];
        let mesh = &self.scene.meshes[instance.mesh.index()];
        let [c0, c1, c2] = mesh.indices[tri.triangle as usize].map(|v| clip[v as usize].as_dvec4());
        let sx = (x as f64 + 0.5) / self.width * 2.0 - 1.0;
        let sy = 1.0 - (y as f64 + 0.5) / self.height * 2.0;
        let a = [c0, c1, c2].map(|c| c.x - sx * c.z);
        let b = [c0, c1, c2].map(|c| c.y - sy * c.z);
        let (a1, a2) = (a[1] - a[0], a[2] - a[0]);
        let (b1, b2) = (b[1] - b[0], b[2] - b[0]);
        let det = a1 * b2 - a2 * b1;
        if det == 0.0 {
            return true;
        }
        let l1 = (-a[0] * b2 + a2 * b[0]) / det;
        let l2 = (-a1 * b[0] + a[0] * b1) / det;
        cutout.keeps(tri.triangle, glam::Vec2::new(l1 as f32, l2 as f32))
    }
}

/// Clip-space corners of every triangle of `scene`'s default-mask instances, set up for
/// rasterization, in scene order.
fn setup_scene<'s>(scene: &'s Scene, viewport: &Viewport) -> SceneSetup<'s> {
    let strips = viewport.height.div_ceil(STRIP_ROWS) as usize;
    let cutouts = MeshCutout::all(scene);
    // Instances transformed side by side (a small mesh's vertices in one go, a large one's
    // in parallel chunks below).
    let instances: Vec<(usize, Vec<Vec4>)> = scene
        .instances
        .par_iter()
        .enumerate()
        .filter(|(_, inst)| inst.mask & MASK_DEFAULT != 0)
        .map(|(i, inst)| {
            let mesh = &scene.meshes[inst.mesh.index()];
            let clip_from_object = viewport.clip_from_world * inst.world_from_object;
            // The depth plane in object space: n·(M p + t) + c = (Mᵀn)·p + (n·t + c).
            let n = viewport.depth_plane.truncate();
            let m = inst.world_from_object;
            let object_plane = Vec4::from((
                m.matrix3.transpose() * glam::Vec3A::from(n),
                n.dot(m.translation.into()) + viewport.depth_plane.w,
            ));
            // Clip point (x, y, w) with the depth plane's value in the fourth component.
            let transform = |p: &Vec3| {
                clip_from_object
                    .transform_point3(*p)
                    .extend(object_plane.truncate().dot(*p) + object_plane.w)
            };
            let clip = if mesh.positions.len() > TRANSFORM_CHUNK {
                mesh.positions
                    .par_iter()
                    .with_min_len(TRANSFORM_CHUNK)
                    .map(transform)
                    .collect()
            } else {
                mesh.positions.iter().map(transform).collect()
            };
            (i, clip)
        })
        .collect();
    let jobs: Vec<(usize, std::ops::Range<usize>)> = instances
        .iter()
        .enumerate()
        .flat_map(|(k, (i, _))| {
            let n = scene.meshes[scene.instances[*i].mesh.index()].triangle_count();
            (0..n.div_ceil(SETUP_CHUNK))
                .map(move |c| (k, c * SETUP_CHUNK..((c + 1) * SETUP_CHUNK).min(n)))
        })
        .collect();
    let per_job: Vec<SetupJob> = jobs
        .par_iter()
        .map(|(k, range)| {
            let (i, clip) = &instances[*k];
            let mesh_id = scene.instances[*i].mesh.index();
            let mesh = &scene.meshes[mesh_id];
            let cutout = cutouts[mesh_id].as_ref();
            let mut out = Vec::new();
            for t in range.clone() {
                let [a, b, c] = mesh.indices[t].map(|v| clip[v as usize]);
                let first = out.len();
                setup_triangle([a, b, c], viewport, *i as u32, t as u32, &mut out);
                if cutout.is_some_and(|c| c.is_tested(t as u32)) {
                    for tri in &mut out[first..] {
                        tri.cut = true;
                    }
                }
            }
            let bins = bin_by_strip(&out, strips);
            SetupJob {
                triangles: out,
                bins,
            }
        })
        .collect();
    let mut clip_of_instance = vec![Vec::new(); scene.instances.len()];
    for (i, clip) in instances {
        if cutouts[scene.instances[i].mesh.index()].is_some() {
            clip_of_instance[i] = clip;
        }
    }
    SceneSetup {
        jobs: per_job,
        scene,
        clip_of_instance,
        cutouts,
        width: viewport.width as f64,
        height: viewport.height as f64,
    }
}

/// Clips clip-space triangle `clip` (points `(x, y, w, z)`, `z/w` the depth attribute)
/// against the near plane and the guard band, snaps it, and appends its screen triangles
/// (one, or a fan after clipping) to `out`.
fn setup_triangle(
    clip: [Vec4; 3],
    viewport: &Viewport,
    instance: u32,
    triangle: u32,
    out: &mut Vec<ScreenTriangle>,
) {
    let [p0, p1, p2] = clip.map(|p| p.as_dvec4());
    // Entirely outside one plane of the view frustum (or behind the near plane): unseen.
    let outside = |f: &dyn Fn(DVec4) -> bool| f(p0) && f(p1) && f(p2);
    if outside(&|p| p.z < NEAR_W)
        || outside(&|p| p.x > p.z)
        || outside(&|p| p.x < -p.z)
        || outside(&|p| p.y > p.z)
        || outside(&|p| p.y < -p.z)
    {
        return;
    }
    let inside_all = [p0, p1, p2]
        .iter()
        .all(|&p| p.z >= NEAR_W && p.x.abs() <= GUARD_BAND * p.z && p.y.abs() <= GUARD_BAND * p.z);
    let snap = |p: DVec4| {
        let (x, y) = viewport.to_screen(p);
        let s = SUBPIXELS as f64;
        (
            (((x * s).round()) as i64, ((y * s).round()) as i64),
            p.w / p.z,
        )
    };
    let mut emit = |a: ((i64, i64), f64), b: ((i64, i64), f64), c: ((i64, i64), f64)| {
        if let Some(t) = ScreenTriangle::new(
            [a.0, b.0, c.0],
            [a.1, b.1, c.1],
            viewport,
            instance,
            triangle,
        ) {
            out.push(t);
        }
    };
    if inside_all {
        // Most triangles: no clipping, no polygon (setup runs for every triangle of the
        // scene, once per view).
        emit(snap(p0), snap(p1), snap(p2));
        return;
    }
    let mut polygon = Polygon::new([p0, p1, p2]);
    // Distance to each plane, ≥ 0 inside.
    let planes: [fn(DVec4) -> f64; 5] = [
        |p| p.z - NEAR_W,
        |p| GUARD_BAND * p.z - p.x,
        |p| GUARD_BAND * p.z + p.x,
        |p| GUARD_BAND * p.z - p.y,
        |p| GUARD_BAND * p.z + p.y,
    ];
    for plane in planes {
        polygon = polygon.clipped(plane);
        if polygon.len < 3 {
            return;
        }
    }
    let first = snap(polygon.points[0]);
    for k in 1..polygon.len - 1 {
        emit(first, snap(polygon.points[k]), snap(polygon.points[k + 1]));
    }
}

/// A convex polygon of up to 8 clip-space points `(x, y, w, z)` (a triangle clipped by
/// five planes).
#[derive(Clone, Copy)]
struct Polygon {
    points: [DVec4; 8],
    len: usize,
}

impl Polygon {
    fn new(triangle: [DVec4; 3]) -> Self {
        let mut points = [DVec4::ZERO; 8];
        points[..3].copy_from_slice(&triangle);
        Self { points, len: 3 }
    }

    /// The part where `distance ≥ 0` (Sutherland–Hodgman against one plane).
    fn clipped(&self, distance: fn(DVec4) -> f64) -> Self {
        let mut out = Self {
            points: [DVec4::ZERO; 8],
            len: 0,
        };
        let mut push = |p: DVec4| {
            if out.len < out.points.len() {
                out.points[out.len] = p;
                out.len += 1;
            }
        };
        for i in 0..self.len {
            let (a, b) = (self.points[i], self.points[(i + 1) % self.len]);
            let (da, db) = (distance(a), distance(b));
            if da >= 0.0 {
                push(a);
            }
            if (da >= 0.0) != (db >= 0.0) {
                push(a + (b - a) * (da / (da - db)));
            }
        }
        out
    }
}

/// Screen triangles listed per strip, in setup order.
struct StripBins {
    /// `start[s]..start[s + 1]` indexes `triangles` for strip `s`.
    start: Vec<u32>,
    triangles: Vec<u32>,
}

impl StripBins {
    fn strip(&self, s: usize) -> &[u32] {
        &self.triangles[self.start[s] as usize..self.start[s + 1] as usize]
    }
}

/// Counting sort of triangles into the strips their pixel rows overlap (stable).
fn bin_by_strip(triangles: &[ScreenTriangle], strips: usize) -> StripBins {
    let range = |t: &ScreenTriangle| {
        (t.y0 as u32 / STRIP_ROWS) as usize..=(t.y1 as u32 / STRIP_ROWS) as usize
    };
    let mut start = vec![0u32; strips + 1];
    for t in triangles {
        for s in range(t) {
            start[s + 1] += 1;
        }
    }
    for s in 0..strips {
        start[s + 1] += start[s];
    }
    let mut fill = start.clone();
    let mut list = vec![0u32; start[strips] as usize];
    for (i, t) in triangles.iter().enumerate() {
        for s in range(t) {
            list[fill[s] as usize] = i as u32;
            fill[s] += 1;
        }
    }
    StripBins {
        start,
        triangles: list,
    }
}

/// What a shadow map stores per texel, from the rasterizer's depth attribute.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoredDepth {
    /// Perspective views: the attribute is `1/w`; store `w`.
    ViewDepth,
    /// Orthographic views whose depth plane gives `−depth`; store `depth`.
    NegatedAttribute,
}

/// Depth rendering for shadow maps: every default-mask instance of `scene` seen through
/// `viewport` (back faces too, as shadow rays see them), keeping per texel the nearest
/// depth attribute and storing it as `stored`; texels that see nothing get
/// `f32::INFINITY`. `depth` is resized to the viewport (row-major, row 0 at the top) and
/// its allocation reused. Same setup, binning and parallel strips as
/// [`VisibilityBuffer::render`], so the same pixel-centre coverage rules hold.
pub fn rasterize_depth(
    scene: &Scene,
    viewport: &Viewport,
    depth: &mut Vec<f32>,
    stored: StoredDepth,
) {
    let (width, height) = (viewport.width, viewport.height);
    // Every texel is initialised by its strip below.
    depth.resize((width * height) as usize, f32::NEG_INFINITY);
    if width == 0 || height == 0 {
        return;
    }
    let setup = setup_scene(scene, viewport);
    depth
        .par_chunks_mut((width * STRIP_ROWS) as usize)
        .with_max_len(1)
        .enumerate()
        .for_each(|(strip, out)| {
            out.fill(f32::NEG_INFINITY);
            let rows = strip as i32 * STRIP_ROWS as i32
                ..((strip as i32 + 1) * STRIP_ROWS as i32).min(height as i32);
            for tri in setup.strip(strip) {
                tri.rasterize_runs(rows.clone(), |y, xs, z_row| {
                    let row = (y - rows.start) as usize * width as usize;
                    let (start, end) = (*xs.start() as usize, *xs.end() as usize);
                    // A plain slice loop: the compiler vectorizes it.
                    let z_start = z_row + tri.dzdx * (start as i32 - tri.x0) as f32;
                    let texels = out[row + start..=row + end].iter_mut().enumerate();
                    if tri.cut {
                        for (i, texel) in texels {
                            if setup.keeps(tri, start as i32 + i as i32, y) {
                                *texel = texel.max(z_start + tri.dzdx * i as f32);
                            }
                        }
                    } else {
                        for (i, texel) in texels {
                            *texel = texel.max(z_start + tri.dzdx * i as f32);
                        }
                    }
                });
            }
            // Convert while the strip is still in cache; −∞ (empty) becomes +∞ both ways.
            match stored {
                StoredDepth::ViewDepth => {
                    for texel in out.iter_mut() {
                        *texel = if *texel > 0.0 {
                            1.0 / *texel
                        } else {
                            f32::INFINITY
                        };
                    }
                }
                StoredDepth::NegatedAttribute => {
                    for texel in out.iter_mut() {
                        *texel = -*texel;
                    }
                }
            }
        });
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A viewport whose clip space is the identity (tests give clip points directly).
    fn viewport(width: u32, height: u32) -> Viewport {
        Viewport::new(width, height)
    }

    /// Clip points `(x, y, w)` of a perspective view with their depth numerator 1.
    fn perspective(triangle: [Vec3; 3]) -> [Vec4; 3] {
        triangle.map(|p| p.extend(1.0))
    }

    /// How often each pixel is covered by `triangles` (clip space), via the real setup.
    fn coverage(width: u32, height: u32, triangles: &[[Vec3; 3]]) -> Vec<u32> {
        let vp = viewport(width, height);
        let mut screen = Vec::new();
        for (i, t) in triangles.iter().enumerate() {
            setup_triangle(perspective(*t), &vp, 0, i as u32, &mut screen);
        }
        let mut count = vec![0u32; (width * height) as usize];
        for t in &screen {
            t.rasterize(0..height as i32, |x, y, _| {
                count[(y as u32 * width + x as u32) as usize] += 1
            });
        }
        count
    }

    /// Clip-space point of screen position (sx, sy) in a `w × h` image at depth `w_clip`.
    fn at_screen(sx: f32, sy: f32, width: u32, height: u32, w_clip: f32) -> Vec3 {
        let ndc_x = sx / width as f32 * 2.0 - 1.0;
        let ndc_y = 1.0 - sy / height as f32 * 2.0;
        Vec3::new(ndc_x * w_clip, ndc_y * w_clip, w_clip)
    }

    #[test]
    fn shared_edges_cover_every_pixel_exactly_once() {
        // A square split along its diagonal, corners on pixel centres, so the diagonal and
        // the four sides pass exactly through sample points.
        let (w, h) = (32, 32);
        let p = |x: f32, y: f32| at_screen(x, y, w, h, 2.0);
        let (a, b, c, d) = (p(4.5, 4.5), p(20.5, 4.5), p(20.5, 20.5), p(4.5, 20.5));
        for tris in [[[a, b, c], [a, c, d]], [[a, c, b], [c, a, d]]] {
            let count = coverage(w, h, &tris);
            for y in 0..h {
                for x in 0..w {
                    let n = count[(y * w + x) as usize];
                    // Top-left rule: the top and left sides are in, bottom and right out.
                    let inside = (4..20).contains(&x) && (4..20).contains(&y);
                    assert_eq!(n, u32::from(inside), "pixel ({x}, {y}) covered {n} times");
                }
            }
        }
        // A fan of eight triangles around a centre on a sample: every pixel once.
        let centre = p(16.5, 16.5);
        let ring: Vec<Vec3> = (0..8)
            .map(|k| {
                let phi = k as f32 * std::f32::consts::TAU / 8.0;
                p(16.5 + 9.0 * phi.cos(), 16.5 + 9.0 * phi.sin())
            })
            .collect();
        let fan: Vec<[Vec3; 3]> = (0..8)
            .map(|k| [centre, ring[k], ring[(k + 1) % 8]])
            .collect();
        let count = coverage(w, h, &fan);
        assert!(count.iter().all(|&n| n <= 1), "a pixel is covered twice");
        assert_eq!(
            count[(16 * w + 16) as usize],
            1,
            "the shared centre is covered once"
        );
        assert!(count.iter().filter(|&&n| n == 1).count() > 200);
    }

    #[test]
    fn a_triangle_through_the_near_plane_covers_what_rays_see() {
        // A triangle with one corner behind the camera (w < 0): its screen image is
        // unbounded; clipping must keep exactly the part in front. Compare with rays
        // from the eye (view direction (ndc_x, ndc_y, 1) in this clip space).
        let (w, h) = (64u32, 48u32);
        let tri = [
            Vec3::new(-0.5, -0.4, 1.0),
            Vec3::new(0.6, -0.3, 2.0),
            Vec3::new(0.1, 0.5, -1.5),
        ];
        let count = coverage(w, h, &[tri]);
        let ray = |x: u32, y: u32| {
            let ndc_x = (x as f32 + 0.5) / w as f32 * 2.0 - 1.0;
            let ndc_y = 1.0 - (y as f32 + 0.5) / h as f32 * 2.0;
            illume_core::Ray::new(Vec3::ZERO, Vec3::new(ndc_x, ndc_y, 1.0))
        };
        let (mut agree, mut covered) = (0, 0);
        for y in 0..h {
            for x in 0..w {
                let r = ray(x, y);
                let hit = illume_accel::triangle::intersect_triangle(
                    &r,
                    f32::INFINITY,
                    tri[0],
                    tri[1],
                    tri[2],
                )
                .is_some();
                let n = count[(y * w + x) as usize];
                assert!(n <= 1);
                covered += n;
                if (n == 1) == hit {
                    agree += 1;
                } else {
                    // Only samples within a hair of an edge may differ.
                    let wide = |s: f32| {
                        [(-s, 0.0), (s, 0.0), (0.0, -s), (0.0, s)]
                            .iter()
                            .any(|&(dx, dy)| {
                                let mut r2 = r;
                                r2.dir.x += dx;
                                r2.dir.y += dy;
                                illume_accel::triangle::intersect_triangle(
                                    &r2,
                                    f32::INFINITY,
                                    tri[0],
                                    tri[1],
                                    tri[2],
                                )
                                .is_some()
                                    != hit
                            })
                    };
                    assert!(wide(0.01), "pixel ({x}, {y}): raster {n}, ray {hit}");
                }
            }
        }
        assert!(
            covered > 300,
            "the clipped triangle covers much of the image: {covered}"
        );
        assert!(
            agree as f32 >= 0.995 * (w * h) as f32,
            "{agree} of {}",
            w * h
        );
        // The same triangle wholly behind the camera covers nothing.
        let behind = tri.map(|p| Vec3::new(p.x, p.y, -p.z.abs() - 0.5));
        assert!(coverage(w, h, &[behind]).iter().all(|&n| n == 0));
    }

    #[test]
    fn nearer_triangle_wins_whatever_the_order() {
        let scene_free = |order: [usize; 2]| {
            let (w, h) = (16u32, 16u32);
            let vp = viewport(w, h);
            let near = [
                Vec3::new(-1.0, -1.0, 1.0),
                Vec3::new(3.0, -1.0, 1.0),
                Vec3::new(-1.0, 3.0, 1.0),
            ];
            let far = near.map(|p| p * 3.0);
            let tris = [near, far];
            let mut screen = Vec::new();
            for i in order {
                setup_triangle(perspective(tris[i]), &vp, i as u32, 0, &mut screen);
            }
            let mut best = vec![(0.0f32, u32::MAX); (w * h) as usize];
            for t in &screen {
                t.rasterize(0..h as i32, |x, y, z| {
                    let b = &mut best[(y as u32 * w + x as u32) as usize];
                    if z > b.0 {
                        *b = (z, t.instance);
                    }
                });
            }
            best
        };
        for order in [[0, 1], [1, 0]] {
            let best = scene_free(order);
            assert!(
                best.iter().all(|&(z, i)| i == 0 && (z - 1.0).abs() < 1e-5),
                "{order:?}"
            );
        }
    }

    #[test]
    fn row_runs_cover_exactly_the_pixels_whose_centres_are_inside() {
        // Random triangles, many wide enough for the divided runs: the pixels reported
        // are exactly those where all three edge functions are ≥ 0.
        let (w, h) = (96u32, 64u32);
        let vp = viewport(w, h);
        let mut rng = illume_core::sampling::Pcg32::new(3, 0);
        let mut checked = 0;
        for _ in 0..300 {
            let mut p = || {
                at_screen(
                    illume_core::sampling::SampleStream::next_1d(&mut rng) * 140.0 - 20.0,
                    illume_core::sampling::SampleStream::next_1d(&mut rng) * 100.0 - 20.0,
                    w,
                    h,
                    1.0 + illume_core::sampling::SampleStream::next_1d(&mut rng),
                )
            };
            let tri = [p(), p(), p()];
            let mut screen = Vec::new();
            setup_triangle(perspective(tri), &vp, 0, 0, &mut screen);
            for t in &screen {
                let mut got = Vec::new();
                t.rasterize(0..h as i32, |x, y, _| got.push((x, y)));
                let mut expected = Vec::new();
                for y in t.y0..=t.y1 {
                    for x in t.x0..=t.x1 {
                        let (sx, sy) = (
                            x as i64 * SUBPIXELS + SUBPIXELS / 2,
                            y as i64 * SUBPIXELS + SUBPIXELS / 2,
                        );
                        if (0..3).all(|k| t.a[k] * sx + t.b[k] * sy + t.c[k] >= 0) {
                            expected.push((x, y));
                        }
                    }
                }
                assert_eq!(got, expected);
                checked += got.len();
            }
        }
        assert!(checked > 10_000, "{checked}");
    }

    #[test]
    fn clipping_keeps_convex_polygons_small() {
        // A triangle crossing every plane at once still yields a valid fan.
        let tri = [
            Vec3::new(-50.0, -50.0, 0.5),
            Vec3::new(50.0, -10.0, -3.0),
            Vec3::new(0.0, 80.0, 4.0),
        ];
        let mut out = Vec::new();
        setup_triangle(perspective(tri), &viewport(40, 30), 0, 0, &mut out);
        assert!(!out.is_empty() && out.len() <= 6);
    }
}
