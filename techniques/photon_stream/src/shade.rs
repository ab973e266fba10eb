//! Shading with VSLs (§0.4.1, §0.6, §0.7.3).
//!
//! Indirect radiance at a G-buffer point x with albedo ρ(x) and normal n (ρ is the
//! directional albedo towards the camera on glossy receivers with `directional_albedo`,
//! beyond the paper: [`illume_transport::GBufferPixel::display_albedo`]):
//!
//! ```text
//! L(x) = ρ(x)/π · Σ_s Φ_s · cosθ_i · cosθ' / (π r² + A_s)
//! ```
//!
//! Φ_s is the flux leaving VSL s on the side facing x, θ_i the angle at x, θ' the angle
//! at the VSL, r the distance. Far from the VSL this is the paper's Φ_s·R(x)·cosθ_i
//! cosθ'/(π r²). **Near-VSL singularity:** the denominator π r² + A_s is the exact
//! on-axis form factor of a uniformly emitting disk of area A_s (irradiance at height h
//! is Φ/(π h² + A)), so a point on or next to the VSL receives the VSL's exitance
//! Φ_s/A_s at most, never infinity. `falloff = "inverse_square"` (the `paper` preset)
//! drops A_s: the paper's point light, unbounded next to a VSL.
//!
//! **Culling (§0.7.3, CPU form).** The screen is cut into tiles; for each tile the world
//! box of its G-buffer points is computed, and a VSL is kept if its influence sphere of
//! radius r_ε = sqrt(Φ_s·R_max/(π ε)) (R_max = the tile's largest ρ/π) meets the box and
//! the box is not entirely behind the VSL's emitting side(s) (cosθ' ≤ 0 everywhere).
//! The kept VSLs are evaluated over the tile's pixels in a branch-free loop over
//! structure-of-arrays data that the compiler vectorises. The culling is in
//! [`crate::cull`].
//!
//! **Visibility (beyond the paper).** Optionally a shadow ray tests each VSL (or a
//! subset chosen ∝ contribution) from each pixel, removing Figure 7's over-illumination
//! ([`crate::visibility`]).
//!
//! **Stride (beyond the paper).** Optionally the sum is evaluated on a grid of pixels
//! and interpolated between them ([`crate::interpolate`]).
//!
//! **Near field (beyond the paper, [`crate::near_field`],
//! [`near_field_rays`](PhotonStreamSettings::near_field_rays) > 0).** A VSL stands for
//! its Voronoi cell at one point and one normal. Far away that is a good approximation;
//! close to the cell it is not: a point on a wall a few centimetres above the floor sees
//! the floor at grazing angles, its nearest floor VSLs lie tens of centimetres away, and
//! their cosθ' ≈ h/r is near zero — while the true floor, a uniformly bright half-plane,
//! would give it half of the floor's exitance whatever h. Every edge and corner comes
//! out dark. The estimator therefore splits the integral over the surfaces around x by
//! distance with a window w(r) = smoothstep over r² from (s·ℓ/2)² to (s·ℓ)², ℓ = √A of
//! the VSL involved, s = `near_field_scale`:
//!
//! ```text
//! L(x) = ρ(x)/π · [ Σ_s w(r_s) Φ_s V_s cosθ_i cosθ'/(π r_s² + A_s)
//!                 + (π/N) Σ_k (1 − w(r_k)) Φ_{s(y_k)} / (π A_{s(y_k)}) ]
//! ```
//!
//! with N cosine-distributed rays from x hitting y_k at distance r_k, s(y_k) the VSL the
//! photons landing at y_k are assigned to, on the side facing x (its cell's mean
//! exitance). The gathered part needs no visibility test (the rays find the first
//! surface) and has no singularity (a ray's weight is bounded). **Remaining bias:** the
//! gathered exitance is the cell's mean, not its value at y (light gradients inside a
//! cell near x are averaged); w is evaluated at the VSL's centre on one side and at the
//! hit on the other, so the two parts overlap or leave a gap of order ℓ in the window's
//! transition band; far VSLs keep one normal and one point per cell. Noise: the rays of
//! a pixel follow a rank-1 lattice shifted per pixel (the same shifts every frame, so
//! the residual noise does not shimmer), small where the surroundings' exitance is
//! smooth.

use crate::interpolate::interpolate;
use crate::near_field::{NearField, add_near_field};
use crate::placement::VslSet;
use crate::settings::{PhotonStreamSettings, VisibilityMode};
use crate::visibility::shadowed_sums;
use illume_core::image::RgbImage;
use illume_core::{Aabb, INV_PI, PI, Rgb, Vec3};
use illume_transport::{GBuffer, GBufferPixel, World};
use rayon::prelude::*;

pub use crate::cull::cull;

/// The VSL field in world space for one frame.
#[derive(Clone, Debug, Default)]
pub struct VslField {
    /// World positions.
    pub positions: Vec<Vec3>,
    /// Unit world normals (front side).
    pub normals: Vec<Vec3>,
    /// Flux leaving the front side \[W\].
    pub front_w: Vec<Rgb>,
    /// Flux leaving the back side \[W\].
    pub back_w: Vec<Rgb>,
    /// Represented area A_s \[m²\].
    pub area_m2: Vec<f32>,
    /// The paper's point-light falloff, π r² ([`VslFalloff::InverseSquare`]); false:
    /// the disk's π r² + A_s ([`VslFalloff::Disk`]).
    ///
    /// [`VslFalloff::InverseSquare`]: crate::settings::VslFalloff::InverseSquare
    /// [`VslFalloff::Disk`]: crate::settings::VslFalloff::Disk
    pub inverse_square: bool,
}

impl VslField {
    /// Number of VSLs.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// True when there is none.
    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// The area term of VSL `s`'s falloff denominator π r² + A: A_s, or 0 for the
    /// paper's point lights.
    #[inline]
    pub fn disk_area(&self, s: usize) -> f32 {
        if self.inverse_square {
            0.0
        } else {
            self.area_m2[s]
        }
    }

    /// Unoccluded contribution weight (without Φ and ρ/π) of VSL `s` to a point, and
    /// whether the point sees its front side.
    #[inline]
    pub fn geometry(&self, s: usize, x: Vec3, n: Vec3) -> (f32, bool) {
        let d = self.positions[s] - x;
        let dd = d.length_squared().max(1e-20);
        let ci = n.dot(d).max(0.0);
        let cs = -self.normals[s].dot(d);
        (
            ci * cs.abs() / (dd * (PI * dd + self.disk_area(s))),
            cs > 0.0,
        )
    }
}

/// The far-field weight w of the near-field split (module doc): 0 for squared distances
/// up to `scale2`·A/4, 1 from `scale2`·A on, a smoothstep in r² between; 0 everywhere
/// for an infinite scale (everything gathered).
#[inline(always)]
pub fn far_weight(d2: f32, area_m2: f32, scale2: f32) -> f32 {
    let hi = (scale2 * area_m2).max(1e-30);
    let t = ((d2 / hi - 0.25) * (4.0 / 3.0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The inputs of one shading pass, shared by its tiles.
#[derive(Clone, Copy)]
pub(crate) struct ShadePass<'a> {
    pub(crate) world: &'a World,
    pub(crate) gbuffer: &'a GBuffer,
    pub(crate) field: &'a VslField,
    /// The near-field gather's inputs; `None` without a near field.
    pub(crate) near: Option<NearField<'a>>,
    pub(crate) settings: &'a PhotonStreamSettings,
    /// Decorrelates stochastic visibility between frames.
    pub(crate) frame_seed: u64,
}

/// Counters of one shading pass.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ShadeStats {
    /// Tiles with at least one G-buffer point.
    pub tiles: u64,
    /// Σ over those tiles of the VSLs kept by culling.
    pub vsls_kept: u64,
    /// VSL evaluations (pixels × kept VSLs).
    pub evaluations: u64,
    /// Shadow rays traced (visibility mode).
    pub shadow_rays: u64,
    /// Near-field gather rays traced.
    pub near_rays: u64,
    /// Pixels whose value was interpolated from shaded neighbours
    /// ([`PhotonStreamSettings::shading_stride`] > 1).
    pub interpolated: u64,
    /// Pixels between the shaded ones that had no neighbour on the same surface and
    /// were shaded exactly.
    pub fallbacks: u64,
}

impl ShadeStats {
    /// Mean VSLs per non-empty tile after culling.
    pub fn vsls_per_tile(&self) -> f64 {
        if self.tiles == 0 {
            0.0
        } else {
            self.vsls_kept as f64 / self.tiles as f64
        }
    }

    fn merge(self, o: Self) -> Self {
        Self {
            tiles: self.tiles + o.tiles,
            vsls_kept: self.vsls_kept + o.vsls_kept,
            evaluations: self.evaluations + o.evaluations,
            shadow_rays: self.shadow_rays + o.shadow_rays,
            near_rays: self.near_rays + o.near_rays,
            interpolated: self.interpolated + o.interpolated,
            fallbacks: self.fallbacks + o.fallbacks,
        }
    }
}

/// Pixels of one tile in structure-of-arrays form.
#[derive(Default)]
struct TilePixels {
    index: Vec<u32>,
    px: Vec<f32>,
    py: Vec<f32>,
    pz: Vec<f32>,
    nx: Vec<f32>,
    ny: Vec<f32>,
    nz: Vec<f32>,
    r: Vec<f32>,
    g: Vec<f32>,
    b: Vec<f32>,
    /// The VSLs culling kept for the tile.
    kept: Vec<u32>,
}

/// One VSL as the shading loop reads it.
struct VslTerm {
    p: Vec3,
    n: Vec3,
    front: Rgb,
    back: Rgb,
    area: f32,
    /// The falloff denominator's area term (A_s, or 0 for the paper's point lights).
    disk_area: f32,
    /// The near-field window's squared scale; 0 when there is no near field (w = 1).
    scale2: f32,
}

/// A tile's pixel positions and normals, structure of arrays (equal lengths).
struct TileSoa<'a> {
    px: &'a [f32],
    py: &'a [f32],
    pz: &'a [f32],
    nx: &'a [f32],
    ny: &'a [f32],
    nz: &'a [f32],
}

/// Adds one VSL's unshadowed contribution (without ρ/π) to every pixel of a tile, using
/// AVX2+FMA when the CPU has them (checked once at run time), else the baseline ISA.
fn accumulate(v: &VslTerm, t: &TileSoa, r: &mut [f32], g: &mut [f32], b: &mut [f32]) {
    #[cfg(target_arch = "x86_64")]
    {
        static AVX2_FMA: std::sync::OnceLock<bool> = std::sync::OnceLock::new();
        let avx2_fma = *AVX2_FMA
            .get_or_init(|| is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma"));
        if avx2_fma {
            #[expect(
                unsafe_code,
                reason = "calling a target_feature function after detecting the feature"
            )]
            // SAFETY: `accumulate_avx2` only requires the CPU to support AVX2 and FMA,
            // which `is_x86_feature_detected!` just confirmed; it has no other
            // precondition (safe code inside, slices bounds-checked).
            unsafe {
                accumulate_avx2(v, t, r, g, b)
            };
            return;
        }
    }
    accumulate_portable(v, t, r, g, b);
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn accumulate_avx2(v: &VslTerm, t: &TileSoa, r: &mut [f32], g: &mut [f32], b: &mut [f32]) {
    accumulate_portable(v, t, r, g, b);
}

/// Branch-free over the tile's pixels (vectorised by the compiler); one-sided VSLs
/// (no back-side power, the common case) skip the side selection, and without a near
/// field the window is left out.
#[inline(always)]
fn accumulate_portable(v: &VslTerm, t: &TileSoa, r: &mut [f32], g: &mut [f32], b: &mut [f32]) {
    if v.scale2 > 0.0 {
        accumulate_loop::<true>(v, t, r, g, b);
    } else {
        accumulate_loop::<false>(v, t, r, g, b);
    }
}

#[inline(always)]
fn accumulate_loop<const WINDOW: bool>(
    v: &VslTerm,
    t: &TileSoa,
    r: &mut [f32],
    g: &mut [f32],
    b: &mut [f32],
) {
    let m = r.len();
    let (px, py, pz, nx, ny, nz) = (
        &t.px[..m],
        &t.py[..m],
        &t.pz[..m],
        &t.nx[..m],
        &t.ny[..m],
        &t.nz[..m],
    );
    let (g, b) = (&mut g[..m], &mut b[..m]);
    let (p, n, f, bk, area, scale2) = (v.p, v.n, v.front, v.back, v.area, v.scale2);
    let disk_area = v.disk_area;
    let window = |dd: f32| {
        if WINDOW {
            far_weight(dd, area, scale2)
        } else {
            1.0
        }
    };
    if bk == Rgb::ZERO {
        for i in 0..m {
            let dx = p.x - px[i];
            let dy = p.y - py[i];
            let dz = p.z - pz[i];
            let dd = (dx * dx + dy * dy + dz * dz).max(1e-20);
            let ci = (nx[i] * dx + ny[i] * dy + nz[i] * dz).max(0.0);
            let cs = (-(n.x * dx + n.y * dy + n.z * dz)).max(0.0);
            let wgt = ci * cs / (dd * (PI * dd + disk_area)) * window(dd);
            r[i] += wgt * f.x;
            g[i] += wgt * f.y;
            b[i] += wgt * f.z;
        }
    } else {
        for i in 0..m {
            let dx = p.x - px[i];
            let dy = p.y - py[i];
            let dz = p.z - pz[i];
            let dd = (dx * dx + dy * dy + dz * dz).max(1e-20);
            let ci = (nx[i] * dx + ny[i] * dy + nz[i] * dz).max(0.0);
            let cs = -(n.x * dx + n.y * dy + n.z * dz);
            let wgt = ci * cs.abs() / (dd * (PI * dd + disk_area)) * window(dd);
            let front = cs > 0.0;
            r[i] += wgt * if front { f.x } else { bk.x };
            g[i] += wgt * if front { f.y } else { bk.y };
            b[i] += wgt * if front { f.z } else { bk.z };
        }
    }
}

/// Indirect radiance of every G-buffer pixel from `field` (see the module doc).
/// `frame_seed` decorrelates stochastic visibility between frames.
/// `vsls` are the VSLs `field` was made from (the near-field gather finds a hit's cell
/// with them).
pub fn shade(
    world: &World,
    gbuffer: &GBuffer,
    field: &VslField,
    vsls: &VslSet,
    settings: &PhotonStreamSettings,
    frame_seed: u64,
) -> (RgbImage, ShadeStats) {
    let near = (settings.near_field_rays > 0).then_some(NearField {
        vsls,
        rays: settings.near_field_rays,
        scale2: settings.near_field_scale * settings.near_field_scale,
        direct: settings.gather_direct,
        filtered_textures: settings.filtered_textures,
    });
    let (w, h) = (gbuffer.width, gbuffer.height);
    let n = (w * h) as usize;
    let stride = settings.shading_stride.max(1);
    // Σ_s Φ_s·G_s per shaded pixel, without ρ/π (multiplied in at the end so that texture
    // detail stays at full resolution whatever the stride).
    let grid = Include::Grid(stride);
    let pass = ShadePass {
        world,
        gbuffer,
        field,
        near,
        settings,
        frame_seed,
    };
    let run = |include: &Include, store: &mut dyn FnMut(u32, Rgb)| gather(&pass, include, store);
    if stride == 1 {
        let mut gathered = zeros(n);
        let stats = run(&grid, &mut |i, c| gathered[i as usize] = c);
        return (
            radiance(gbuffer, &gathered, settings.directional_albedo),
            stats,
        );
    }
    // One entry per grid cell (a quarter of the image's at stride 2): the pass writes and
    // the interpolation reads a buffer that stays in cache.
    let aw = w.div_ceil(stride);
    let mut on_grid = vec![Rgb::ZERO; (aw * h.div_ceil(stride)) as usize];
    let mut stats = run(&grid, &mut |i, c| {
        let (x, y) = (i % w, i / w);
        on_grid[((y / stride) * aw + x / stride) as usize] = c;
    });
    let (mut img, interpolated, missing) = interpolate(
        gbuffer,
        &on_grid,
        stride,
        world.scene.camera.yfov_rad,
        settings.directional_albedo,
    );
    stats.interpolated = interpolated;
    stats.fallbacks = missing.len() as u64;
    if !missing.is_empty() {
        let mut mask = vec![false; n];
        for &i in &missing {
            mask[i as usize] = true;
        }
        let pixels = img.pixels_mut();
        let rest = run(&Include::Mask(&mask), &mut |i, c| {
            if let Some(p) = &gbuffer.pixels[i as usize] {
                pixels[i as usize] = p.display_albedo(settings.directional_albedo) * INV_PI * c;
            }
        });
        stats = stats.merge(ShadeStats { tiles: 0, ..rest });
    }
    (img, stats)
}

/// `n` black pixels, written (and first touched) on every core: a frame's buffers are
/// megabytes, whose zeroing on one thread left the other core idle.
pub(crate) fn zeros(n: usize) -> Vec<Rgb> {
    (0..n)
        .into_par_iter()
        .with_min_len(4096)
        .map(|_| Rgb::ZERO)
        .collect()
}

/// Radiance ρ/π · Σ Φ·G of every pixel (ρ: the display albedo, directional or not).
fn radiance(gbuffer: &GBuffer, gathered: &[Rgb], directional: bool) -> RgbImage {
    let pixels = gbuffer
        .pixels
        .par_iter()
        .zip(gathered.par_iter())
        .with_min_len(1024)
        .map(|(px, e)| {
            px.as_ref()
                .map_or(Rgb::ZERO, |p| p.display_albedo(directional) * INV_PI * *e)
        })
        .collect();
    RgbImage::from_vec(gbuffer.width, gbuffer.height, pixels).expect("one value per pixel")
}

/// True for G-buffer points that receive indirect light (reflecting, non-black).
#[inline]
pub(crate) fn shades(p: &GBufferPixel) -> bool {
    p.hit.reflects && p.hit.albedo != Rgb::ZERO
}

/// Which pixels a shading pass evaluates.
enum Include<'a> {
    /// Pixels on the grid `stride` apart (every pixel for 1).
    Grid(u32),
    /// Pixels whose mask entry is set.
    Mask(&'a [bool]),
}

impl Include<'_> {
    #[inline]
    fn contains(&self, x: u32, y: u32, i: u32) -> bool {
        match *self {
            Include::Grid(s) => x.is_multiple_of(s) && y.is_multiple_of(s),
            Include::Mask(m) => m[i as usize],
        }
    }
}

/// Shades the pixels `include` selects, tile by tile, handing each pixel's Σ Φ·G to
/// `store` (pixel index, value).
fn gather(pass: &ShadePass, include: &Include, store: &mut dyn FnMut(u32, Rgb)) -> ShadeStats {
    let (w, h) = (pass.gbuffer.width, pass.gbuffer.height);
    let t = pass.settings.tile_size;
    let (tx, ty) = (w.div_ceil(t), h.div_ceil(t));
    let results: Vec<(Vec<(u32, Rgb)>, ShadeStats)> = (0..tx * ty)
        .into_par_iter()
        .map_init(TilePixels::default, |tile, k| {
            let (x0, y0) = ((k % tx) * t, (k / tx) * t);
            let rect = TileRect {
                x0,
                y0,
                x1: (x0 + t).min(w),
                y1: (y0 + t).min(h),
            };
            shade_tile(pass, rect, include, tile)
        })
        .collect();
    let mut stats = ShadeStats::default();
    for (px, s) in results {
        for (i, c) in px {
            store(i, c);
        }
        stats = stats.merge(s);
    }
    stats
}

/// A tile of the screen: pixels `x0..x1` × `y0..y1`.
#[derive(Clone, Copy)]
struct TileRect {
    x0: u32,
    y0: u32,
    x1: u32,
    y1: u32,
}

/// Σ Φ·G (before ρ/π) of the pixels of tile `rect` that `include` selects, in pixel
/// order, and the tile's counters; `tile` is the thread's scratch.
fn shade_tile(
    pass: &ShadePass,
    rect: TileRect,
    include: &Include,
    tile: &mut TilePixels,
) -> (Vec<(u32, Rgb)>, ShadeStats) {
    let mut stats = ShadeStats::default();
    let Some((bounds, max_albedo)) = tile.collect(
        pass.gbuffer,
        rect,
        include,
        pass.settings.directional_albedo,
    ) else {
        return (Vec::new(), stats);
    };
    let m = tile.index.len();
    let (settings, near) = (pass.settings, pass.near);
    cull(
        pass.field,
        &bounds,
        max_albedo * INV_PI,
        settings.epsilon,
        near.map_or(0.0, |nf| nf.scale2),
        &mut tile.kept,
    );
    stats.tiles = 1;
    stats.vsls_kept = tile.kept.len() as u64;
    stats.evaluations = (tile.kept.len() * m) as u64;
    let mut out: Vec<(u32, Rgb)> = match settings.visibility {
        VisibilityMode::Off => tile.unshadowed_sums(pass.field, near),
        VisibilityMode::All | VisibilityMode::Stochastic => {
            shadowed_sums(pass, &tile.index, &tile.kept, &mut stats.shadow_rays)
        }
    };
    if let Some(nf) = near {
        stats.near_rays = add_near_field(
            pass.world,
            pass.gbuffer,
            pass.field,
            nf,
            settings.seed,
            &mut out,
        );
    }
    (out, stats)
}

impl TilePixels {
    /// Gathers the pixels of `rect` that `include` selects and that receive indirect
    /// light; returns their world box and largest display albedo channel (`directional`
    /// as [`GBufferPixel::display_albedo`]), `None` when there is none.
    fn collect(
        &mut self,
        gbuffer: &GBuffer,
        rect: TileRect,
        include: &Include,
        directional: bool,
    ) -> Option<(Aabb, f32)> {
        let tp = self;
        for v in [
            &mut tp.px, &mut tp.py, &mut tp.pz, &mut tp.nx, &mut tp.ny, &mut tp.nz,
        ] {
            v.clear();
        }
        tp.index.clear();
        let mut bounds = Aabb::EMPTY;
        let mut max_albedo = 0.0f32;
        // A grid pass visits only its rows and columns (the G-buffer is large: touching
        // pixels it will not shade costs memory traffic).
        let step = match include {
            Include::Grid(s) => *s,
            Include::Mask(_) => 1,
        };
        let first = |v: u32| v.next_multiple_of(step);
        for y in (first(rect.y0)..rect.y1).step_by(step as usize) {
            for x in (first(rect.x0)..rect.x1).step_by(step as usize) {
                let i = y * gbuffer.width + x;
                if !include.contains(x, y, i) {
                    continue;
                }
                let Some(px) = &gbuffer.pixels[i as usize] else {
                    continue;
                };
                if !px.hit.reflects || px.hit.albedo == Rgb::ZERO {
                    continue;
                }
                let p = px.hit.position;
                let n = px.hit.facing_normal();
                tp.index.push(i);
                tp.px.push(p.x);
                tp.py.push(p.y);
                tp.pz.push(p.z);
                tp.nx.push(n.x);
                tp.ny.push(n.y);
                tp.nz.push(n.z);
                bounds = bounds.grow(p);
                max_albedo = max_albedo.max(px.display_albedo(directional).max_element());
            }
        }
        (!tp.index.is_empty()).then_some((bounds, max_albedo))
    }

    /// Σ Φ·G of the collected pixels over the culled VSLs, without visibility, in pixel
    /// order: the branch-free structure-of-arrays loop ([`accumulate`]).
    fn unshadowed_sums(&mut self, field: &VslField, near: Option<NearField>) -> Vec<(u32, Rgb)> {
        let tp = self;
        let m = tp.index.len();
        for v in [&mut tp.r, &mut tp.g, &mut tp.b] {
            v.clear();
            v.resize(m, 0.0);
        }
        let (r, g, b) = (&mut tp.r[..m], &mut tp.g[..m], &mut tp.b[..m]);
        let (px, py, pz) = (&tp.px[..m], &tp.py[..m], &tp.pz[..m]);
        let (nx, ny, nz) = (&tp.nx[..m], &tp.ny[..m], &tp.nz[..m]);
        let pixels = TileSoa {
            px,
            py,
            pz,
            nx,
            ny,
            nz,
        };
        for &s in tp.kept.iter() {
            let s = s as usize;
            let vsl = VslTerm {
                p: field.positions[s],
                n: field.normals[s],
                front: field.front_w[s],
                back: field.back_w[s],
                area: field.area_m2[s],
                disk_area: field.disk_area(s),
                scale2: near.map_or(0.0, |nf| nf.scale2),
            };
            accumulate(&vsl, &pixels, r, g, b);
        }
        (0..m)
            .map(|i| (tp.index[i], Rgb::new(tp.r[i], tp.g[i], tp.b[i])))
            .collect()
    }
}
