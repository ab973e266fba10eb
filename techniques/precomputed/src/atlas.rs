//! The `atlas` domain (Bahnsen et al. §3.1, Fig. 4: "the general case"): a world-space
//! lightmap of the static geometry, and beyond the paper a probe grid for dynamic objects.
//!
//! # Lightmap
//! Every static instance gets unique lightmap coordinates of its own, made here from
//! the world-space triangles (the scene's texture coordinates repeat and overlap, so they
//! cannot hold light):
//! - **Charts**: triangles that share an edge (corners welded by position) and lie in one
//!   plane (normals within [`PLANAR_COS`] of the chart's first triangle and on its
//!   plane) form a chart, projected onto that plane with no distortion. Curved meshes
//!   therefore get one chart per triangle (simple and exact; it costs texels on dense
//!   curved meshes: at least one per triangle).
//! - **Sides**: one-sided materials are lit on their front only; a double-sided material
//!   (every OBJ/PLY material) gets a second chart for its back, so light on the two sides
//!   of a thin wall never mixes.
//! - **Scale**: `density` texels per metre, the same everywhere.
//! - **Packing**: each chart's rectangle is turned to its smallest area among its edges'
//!   directions, then rectangles are packed in shelves, tallest first. No gutter is needed:
//!   lookups clamp to their own chart's rectangle, so bilinear filtering never reads a
//!   neighbour chart.
//!
//! A texel holds the *albedo-free* outgoing radiance of the surface: a white Lambertian
//! surface at the texel's point (albedo 1), lit by the key's light (light reflected ≥ 2
//! times with the texel's own reflection counted, as a screen key's). The run time
//! multiplies it by the pixel's own albedo, so textures keep their full resolution.
//! Texels whose centre falls outside their chart's triangles take the nearest point on
//! them; texels inside other geometry (a floor under a wall) are found by tracing a few
//! rays (most of them hit back faces) and take the value of the nearest valid texel of
//! their chart, so no dark rim bleeds in at contact edges.
//!
//! # Probes (beyond the paper)
//! A regular grid of points over the static scene's bounds, `spacing` metres apart. Each
//! holds the same albedo-free radiance for six normals (±X, ±Y, ±Z: an "ambient cube"),
//! stored after the lightmap's texels in the same key image, so the PCA compresses them
//! with everything else. A dynamic object's pixel interpolates the eight probes around
//! it (trilinear; probes inside geometry left out) and weighs the six directions by its
//! normal's squared components.
//!
//! Why by hand: the packages that make lightmap coordinates (xatlas and its bindings)
//! are C++ builds with unmaintained Rust bindings; planar charts and shelf packing are a
//! few hundred lines, deterministic, and enough for architectural scenes.

use crate::PrecomputedError;
use illume_core::{Rgb, Vec2, Vec3};
use illume_scene::{InstanceId, Scene};
use std::collections::HashMap;

/// Two triangles are in one chart when their normals' cosine is at least this (≈ 1.8°).
pub const PLANAR_COS: f32 = 0.9995;

/// Most texels (lightmap and probes) an atlas may have.
pub const MAX_TEXELS: u64 = 1 << 26;

/// Slot value of an unmapped side.
const UNMAPPED: u32 = u32::MAX;

/// One mapped triangle side: its corners' lightmap coordinates \[texels\] and its chart's
/// rectangle (lookups clamp to it).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Slot {
    /// Corner coordinates in texels (texel (i, j)'s centre is at (i + 0.5, j + 0.5)).
    pub uv: [Vec2; 3],
    /// The chart's rectangle: `[x0, y0, x1, y1]` in texels.
    pub rect: [u32; 4],
}

/// The probe grid.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ProbeGrid {
    /// Position of probe (0, 0, 0) \[m\].
    pub origin: Vec3,
    /// Distance between neighbours \[m\].
    pub spacing: f32,
    /// Probes along x, y, z.
    pub dims: [u32; 3],
}

impl ProbeGrid {
    /// Number of probes.
    pub fn count(&self) -> usize {
        self.dims.iter().map(|&d| d as usize).product()
    }

    /// Position of probe `i` (x fastest, then y, then z).
    pub fn position(&self, i: usize) -> Vec3 {
        let [nx, ny, _] = self.dims.map(|d| d as usize);
        let (x, y, z) = (i % nx, (i / nx) % ny, i / (nx * ny));
        self.origin + Vec3::new(x as f32, y as f32, z as f32) * self.spacing
    }

    /// The grid over `bounds` with probes `spacing` apart (at least 2 per axis, at most
    /// 256), centred on the box.
    fn over(bounds: illume_core::Aabb, spacing: f32) -> Self {
        let extent = (bounds.max - bounds.min).max(Vec3::ZERO);
        let n = |e: f32| ((e / spacing).floor() as u32 + 1).clamp(2, 256);
        let dims = [n(extent.x), n(extent.y), n(extent.z)];
        let span = Vec3::new(
            (dims[0] - 1) as f32,
            (dims[1] - 1) as f32,
            (dims[2] - 1) as f32,
        ) * spacing;
        Self {
            origin: (bounds.min + bounds.max) * 0.5 - span * 0.5,
            spacing,
            dims,
        }
    }
}

/// What a lightmap or probe lookup interpolates: a texel's value, or several values
/// read with one set of weights (the run time reads the sky's direct share beside the
/// light, [`crate::lookup`]).
pub trait Texel:
    Copy + std::ops::Add<Output = Self> + std::ops::AddAssign + std::ops::Mul<f32, Output = Self>
{
    /// No light.
    const ZERO: Self;
}

impl Texel for Rgb {
    const ZERO: Self = Rgb::ZERO;
}

/// The six normals of a probe, in the order its values are stored.
pub const PROBE_AXES: [Vec3; 6] = [
    Vec3::X,
    Vec3::NEG_X,
    Vec3::Y,
    Vec3::NEG_Y,
    Vec3::Z,
    Vec3::NEG_Z,
];

/// What a lightmap texel samples: a point on a triangle side.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TexelPoint {
    /// The instance.
    pub instance: InstanceId,
    /// Triangle in the instance's mesh.
    pub triangle: u32,
    /// 0: front, 1: back.
    pub side: u8,
    /// Barycentrics (b1, b2) of the point.
    pub barycentrics: Vec2,
}

/// A lightmap layout for a static scene, and its probe grid.
#[derive(Clone, Debug, PartialEq)]
pub struct Atlas {
    /// Lightmap width \[texels\].
    pub width: u32,
    /// Lightmap height \[texels\].
    pub height: u32,
    /// Texels per metre.
    pub density: f32,
    /// First slot of each instance (2 per triangle: front, back); `UNMAPPED` for
    /// dynamic or hidden instances.
    instance_base: Vec<u32>,
    /// Slot index of each (instance, triangle, side), or `UNMAPPED`.
    slot_index: Vec<u32>,
    /// The mapped sides.
    slots: Vec<Slot>,
    /// What each lightmap texel samples (`None`: no chart covers it).
    points: Vec<Option<TexelPoint>>,
    /// The probe grid.
    pub probes: ProbeGrid,
}

/// A triangle side waiting for a chart.
struct Face {
    instance: usize,
    triangle: u32,
    side: u8,
    corners: [Vec3; 3],
    normal: Vec3,
    welded: [u32; 3],
}

impl Atlas {
    /// The layout of `scene`'s static instances at `density` texels per metre, and a
    /// probe grid `probe_spacing` metres apart over their bounds.
    pub fn build(
        scene: &Scene,
        density: f32,
        probe_spacing: f32,
    ) -> Result<Self, PrecomputedError> {
        let bad = |field: &'static str, reason: String| PrecomputedError::InvalidSetting {
            field,
            reason,
        };
        if !(density.is_finite() && density > 0.0) {
            return Err(bad("atlas_density", "must be > 0 texels per metre".into()));
        }
        if !(probe_spacing.is_finite() && probe_spacing > 0.0) {
            return Err(bad("probe_spacing", "must be > 0 metres".into()));
        }
        // Faces of every mapped side, with corners welded by position.
        let mut faces = Vec::new();
        let mut weld: HashMap<[u32; 3], u32> = HashMap::new();
        let mut bounds = illume_core::Aabb::EMPTY;
        let mut instance_base = vec![UNMAPPED; scene.instances.len()];
        let mut slot_count = 0u64;
        for (i, inst) in scene.instances.iter().enumerate() {
            if inst.dynamic || inst.mask == 0 {
                continue;
            }
            let mesh = &scene.meshes[inst.mesh.index()];
            instance_base[i] = slot_count as u32;
            slot_count += 2 * mesh.triangle_count() as u64;
            if slot_count >= UNMAPPED as u64 {
                return Err(bad(
                    "atlas_density",
                    "the scene has too many triangles".into(),
                ));
            }
            let m = &inst.world_from_object;
            let mirror = m.matrix3.determinant() < 0.0;
            for t in 0..mesh.triangle_count() {
                let corners = mesh.triangle(t).map(|p| m.transform_point3(p));
                for c in corners {
                    bounds = bounds.grow(c);
                }
                let mut normal = (corners[1] - corners[0])
                    .cross(corners[2] - corners[0])
                    .normalize_or_zero();
                if mirror {
                    normal = -normal;
                }
                let welded = corners.map(|c| {
                    let key = c.to_array().map(|x| (x * 1e4).round() as i64 as u32);
                    let next = weld.len() as u32;
                    *weld.entry(key).or_insert(next)
                });
                let material = &scene.materials[mesh.triangle_materials[t].index()];
                let sides = if material.double_sided { 2 } else { 1 };
                for side in 0..sides {
                    faces.push(Face {
                        instance: i,
                        triangle: t as u32,
                        side,
                        corners,
                        normal: if side == 0 { normal } else { -normal },
                        welded,
                    });
                }
            }
        }
        let charts = charts(&faces);
        // Each chart's rectangle, in the orientation of least area.
        let mut placed: Vec<ChartRect> = charts
            .iter()
            .map(|chart| chart_rectangle(&faces, chart, density))
            .collect();
        // Sizes in checked arithmetic (issue 38): a density high enough makes a chart's
        // side saturate at u32::MAX, and the packing's sums would wrap.
        let too_many = |what: String| {
            bad(
                "atlas_density",
                format!(
                    "{density} texels/m makes {what}, more than the atlas's {MAX_TEXELS} texels: lower atlas_density"
                ),
            )
        };
        let mut area = 0u64;
        for (_, w, h) in &placed {
            let chart = u64::from(*w) * u64::from(*h);
            area = area
                .checked_add(chart)
                .filter(|&a| chart <= MAX_TEXELS && a <= MAX_TEXELS)
                .ok_or_else(|| {
                    too_many(if chart > MAX_TEXELS {
                        format!("a chart of {w}×{h} texels")
                    } else {
                        format!("charts of more than {MAX_TEXELS} texels in all")
                    })
                })?;
        }
        let widest = placed.iter().map(|(_, w, _)| *w).max().unwrap_or(1);
        let width = ((area as f64 * 1.15).sqrt().ceil() as u32)
            .max(widest)
            .max(1);
        // Shelf packing, tallest first (ties by width, then chart order: deterministic).
        let mut order: Vec<usize> = (0..placed.len()).collect();
        order.sort_by_key(|&c| {
            (
                std::cmp::Reverse(placed[c].2),
                std::cmp::Reverse(placed[c].1),
                c,
            )
        });
        let (mut x, mut y, mut shelf) = (0u32, 0u32, 0u32);
        let mut origin = vec![(0u32, 0u32); placed.len()];
        let overflow = || too_many("a lightmap wider or taller than 2³² texels".into());
        for &c in &order {
            let (_, w, h) = placed[c];
            if x.checked_add(w).is_none_or(|right| right > width) {
                y = y.checked_add(shelf).ok_or_else(overflow)?;
                x = 0;
                shelf = 0;
            }
            origin[c] = (x, y);
            x = x.checked_add(w).ok_or_else(overflow)?;
            shelf = shelf.max(h);
            y.checked_add(shelf).ok_or_else(overflow)?;
        }
        let height = (y + shelf).max(1);
        let texels = width as u64 * height as u64;
        let probes = ProbeGrid::over(bounds, probe_spacing);
        let total = texels + 6 * probes.count() as u64;
        if total > MAX_TEXELS {
            return Err(bad(
                "atlas_density",
                format!(
                    "the atlas would need {total} texels ({width}×{height} lightmap, {} probes), more than {MAX_TEXELS}: lower atlas_density or raise probe_spacing",
                    probes.count()
                ),
            ));
        }
        // Slots, and what each texel samples.
        let mut slot_index = vec![UNMAPPED; slot_count as usize];
        let mut slots = Vec::with_capacity(faces.len());
        let mut points = vec![None; texels as usize];
        for (c, (members, w, h)) in placed.iter_mut().enumerate() {
            let (x0, y0) = origin[c];
            let shift = Vec2::new(x0 as f32, y0 as f32);
            let rect = [x0, y0, x0 + *w, y0 + *h];
            for (f, uv) in members.iter_mut() {
                for p in uv.iter_mut() {
                    *p += shift;
                }
                let face = &faces[*f];
                let s = instance_base[face.instance] as usize
                    + 2 * face.triangle as usize
                    + face.side as usize;
                slot_index[s] = slots.len() as u32;
                slots.push(Slot { uv: *uv, rect });
            }
            fill_chart(&faces, members, rect, width, &mut points);
        }
        Ok(Self {
            width,
            height,
            density,
            instance_base,
            slot_index,
            slots,
            points,
            probes,
        })
    }

    /// Lightmap texels (width × height).
    pub fn lightmap_texels(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// Values of one key: the lightmap's texels, then 6 per probe, padded to whole rows.
    pub fn image_size(&self) -> (u32, u32) {
        let probe_values = 6 * self.probes.count();
        let rows = probe_values.div_ceil(self.width as usize) as u32;
        (self.width, self.height + rows)
    }

    /// What texel `i` samples (`None`: no chart covers it).
    pub fn point(&self, i: usize) -> Option<TexelPoint> {
        self.points[i]
    }

    /// Mapped triangle sides.
    pub fn slot_count(&self) -> usize {
        self.slots.len()
    }

    /// A checksum of the layout (every slot's coordinates and rectangle, the sizes and
    /// the probe grid): a file's atlas must be the one its scene gives today.
    pub fn checksum(&self) -> u64 {
        let mut bytes = Vec::with_capacity(self.slots.len() * 40 + 64);
        for v in [self.width, self.height] {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        for s in &self.slots {
            for p in s.uv {
                bytes.extend_from_slice(&p.x.to_le_bytes());
                bytes.extend_from_slice(&p.y.to_le_bytes());
            }
            for r in s.rect {
                bytes.extend_from_slice(&r.to_le_bytes());
            }
        }
        for &i in &self.slot_index {
            bytes.extend_from_slice(&i.to_le_bytes());
        }
        let g = &self.probes;
        for v in g.origin.to_array().into_iter().chain([g.spacing]) {
            bytes.extend_from_slice(&v.to_le_bytes());
        }
        for d in g.dims {
            bytes.extend_from_slice(&d.to_le_bytes());
        }
        crate::file::fnv1a64(&bytes)
    }

    /// Whether `instance` is in the lightmap (static and shown).
    pub fn maps(&self, instance: InstanceId) -> bool {
        self.instance_base
            .get(instance.index())
            .is_some_and(|&b| b != UNMAPPED)
    }

    /// The mapped side hit by a pixel: `instance`'s `triangle`, on its back when `back`
    /// (only double-sided materials have one).
    pub fn slot(&self, instance: InstanceId, triangle: u32, back: bool) -> Option<&Slot> {
        let base = *self.instance_base.get(instance.index())?;
        if base == UNMAPPED {
            return None;
        }
        let i = *self
            .slot_index
            .get(base as usize + 2 * triangle as usize + back as usize)?;
        self.slots.get(i as usize)
    }

    /// Bilinear lookup of `values` (the lightmap's texels, row-major) at barycentrics
    /// `b` of `slot`, clamped to the slot's chart.
    pub fn lookup<T: Texel>(&self, values: &[T], slot: &Slot, b: Vec2) -> T {
        let uv = slot.uv[0] * (1.0 - b.x - b.y) + slot.uv[1] * b.x + slot.uv[2] * b.y;
        let [x0, y0, x1, y1] = slot.rect.map(|v| v as f32);
        let x = uv.x.clamp(x0 + 0.5, x1 - 0.5) - 0.5;
        let y = uv.y.clamp(y0 + 0.5, y1 - 0.5) - 0.5;
        let (fx, fy) = (x.floor(), y.floor());
        let (tx, ty) = (x - fx, y - fy);
        let (ix, iy) = (fx as usize, fy as usize);
        let jx = (ix + 1).min(slot.rect[2] as usize - 1);
        let jy = (iy + 1).min(slot.rect[3] as usize - 1);
        let w = self.width as usize;
        let at = |x: usize, y: usize| values[y * w + x];
        (at(ix, iy) * (1.0 - tx) + at(jx, iy) * tx) * (1.0 - ty)
            + (at(ix, jy) * (1.0 - tx) + at(jx, jy) * tx) * ty
    }

    /// The probes' interpolated albedo-free radiance at `position` for unit normal
    /// `normal`: `probe_values` holds 6 per probe, `valid` one flag per probe. Black when
    /// no probe around `position` is valid.
    pub fn probe_lookup<T: Texel>(
        &self,
        probe_values: &[T],
        valid: &[f32],
        position: Vec3,
        normal: Vec3,
    ) -> T {
        let g = &self.probes;
        let local = (position - g.origin) / g.spacing;
        let max = Vec3::new(
            (g.dims[0] - 1) as f32,
            (g.dims[1] - 1) as f32,
            (g.dims[2] - 1) as f32,
        );
        let local = local.clamp(Vec3::ZERO, max);
        let base = local.floor().min(max - Vec3::ONE).max(Vec3::ZERO);
        let t = local - base;
        let [bx, by, bz] = base.to_array().map(|v| v as usize);
        let (nx, ny) = (g.dims[0] as usize, g.dims[1] as usize);
        // Ambient cube weights: the squared components of the normal, by sign.
        let n2 = normal * normal;
        let axis_w = [
            if normal.x > 0.0 { n2.x } else { 0.0 },
            if normal.x < 0.0 { n2.x } else { 0.0 },
            if normal.y > 0.0 { n2.y } else { 0.0 },
            if normal.y < 0.0 { n2.y } else { 0.0 },
            if normal.z > 0.0 { n2.z } else { 0.0 },
            if normal.z < 0.0 { n2.z } else { 0.0 },
        ];
        let mut sum = T::ZERO;
        let mut weight = 0.0;
        for corner in 0..8 {
            let (dx, dy, dz) = (corner & 1, (corner >> 1) & 1, (corner >> 2) & 1);
            let w = (if dx == 1 { t.x } else { 1.0 - t.x })
                * (if dy == 1 { t.y } else { 1.0 - t.y })
                * (if dz == 1 { t.z } else { 1.0 - t.z });
            let p = (bx + dx) + nx * ((by + dy) + ny * (bz + dz));
            if w <= 0.0 || valid.get(p).copied().unwrap_or(0.0) < 0.5 {
                continue;
            }
            let mut v = T::ZERO;
            for (a, aw) in axis_w.iter().enumerate() {
                v += probe_values[6 * p + a] * *aw;
            }
            sum += v * w;
            weight += w;
        }
        if weight > 0.0 {
            sum * (1.0 / weight)
        } else {
            T::ZERO
        }
    }
}

/// Groups faces into planar, edge-connected charts (each a list of face indices).
fn charts(faces: &[Face]) -> Vec<Vec<usize>> {
    // Faces by welded edge, per side (a front and a back never share a chart).
    let mut by_edge: HashMap<(u32, u32, u8), Vec<usize>> = HashMap::new();
    for (f, face) in faces.iter().enumerate() {
        for e in 0..3 {
            let (a, b) = (face.welded[e], face.welded[(e + 1) % 3]);
            by_edge
                .entry((a.min(b), a.max(b), face.side))
                .or_default()
                .push(f);
        }
    }
    let mut chart_of = vec![usize::MAX; faces.len()];
    let mut out = Vec::new();
    for seed in 0..faces.len() {
        if chart_of[seed] != usize::MAX {
            continue;
        }
        let id = out.len();
        let (n, p) = (faces[seed].normal, faces[seed].corners[0]);
        let planar = n != Vec3::ZERO;
        let scale = 1e-4 * (1.0 + p.abs().max_element());
        let mut members = vec![seed];
        chart_of[seed] = id;
        let mut next = 0;
        while planar && next < members.len() {
            let f = members[next];
            next += 1;
            let face = &faces[f];
            for e in 0..3 {
                let (a, b) = (face.welded[e], face.welded[(e + 1) % 3]);
                for &g in &by_edge[&(a.min(b), a.max(b), face.side)] {
                    let other = &faces[g];
                    if chart_of[g] != usize::MAX
                        || other.normal.dot(n) < PLANAR_COS
                        || other.corners.iter().any(|c| (*c - p).dot(n).abs() > scale)
                    {
                        continue;
                    }
                    chart_of[g] = id;
                    members.push(g);
                }
            }
        }
        out.push(members);
    }
    out
}

/// A chart's faces (face index, corners in texels) and its rectangle's width and height.
type ChartRect = (Vec<(usize, [Vec2; 3])>, u32, u32);

/// A chart's faces in chart-local texel coordinates, and its rectangle's size.
fn chart_rectangle(faces: &[Face], chart: &[usize], density: f32) -> ChartRect {
    let first = &faces[chart[0]];
    let n = if first.normal == Vec3::ZERO {
        Vec3::Z
    } else {
        first.normal
    };
    // Candidate axes: the directions of the first faces' edges (a rectangle aligned with
    // an edge of the hull is often the smallest; exact for rectangles).
    let mut best: Option<(f32, Vec3, Vec3)> = None;
    for &f in chart.iter().take(16) {
        let c = faces[f].corners;
        for e in 0..3 {
            let d = c[(e + 1) % 3] - c[e];
            let u = (d - n * d.dot(n)).normalize_or_zero();
            if u == Vec3::ZERO {
                continue;
            }
            let v = n.cross(u);
            let (mut lo, mut hi) = (Vec2::splat(f32::INFINITY), Vec2::splat(f32::NEG_INFINITY));
            for &g in chart {
                for p in faces[g].corners {
                    let q = Vec2::new(p.dot(u), p.dot(v));
                    lo = lo.min(q);
                    hi = hi.max(q);
                }
            }
            let area = (hi - lo).x * (hi - lo).y;
            if best.is_none_or(|(a, _, _)| area < a) {
                best = Some((area, u, v));
            }
        }
    }
    let (u, v) = match best {
        Some((_, u, v)) => (u, v),
        None => {
            let f = illume_core::Frame::from_normal(n);
            (f.s, f.t)
        }
    };
    let mut lo = Vec2::splat(f32::INFINITY);
    let mut hi = Vec2::splat(f32::NEG_INFINITY);
    for &g in chart {
        for p in faces[g].corners {
            let q = Vec2::new(p.dot(u), p.dot(v));
            lo = lo.min(q);
            hi = hi.max(q);
        }
    }
    let size = ((hi - lo) * density).max(Vec2::ZERO);
    let w = (size.x.ceil() as u32).max(1);
    let h = (size.y.ceil() as u32).max(1);
    let members = chart
        .iter()
        .map(|&g| {
            let uv = faces[g]
                .corners
                .map(|p| (Vec2::new(p.dot(u), p.dot(v)) - lo) * density);
            (g, uv)
        })
        .collect();
    (members, w, h)
}

/// Barycentrics (b1, b2) of `p` in the 2-D triangle `t` (None if degenerate).
fn barycentrics(t: &[Vec2; 3], p: Vec2) -> Option<Vec2> {
    let (e1, e2, d) = (t[1] - t[0], t[2] - t[0], p - t[0]);
    let det = e1.perp_dot(e2);
    if det.abs() < 1e-12 {
        return None;
    }
    Some(Vec2::new(d.perp_dot(e2) / det, e1.perp_dot(d) / det))
}

/// The point of 2-D triangle `t` nearest `p`, as barycentrics.
fn nearest_barycentrics(t: &[Vec2; 3], p: Vec2) -> Vec2 {
    if let Some(b) = barycentrics(t, p)
        && b.x >= 0.0
        && b.y >= 0.0
        && b.x + b.y <= 1.0
    {
        return b;
    }
    // Nearest point on each edge; corners' barycentrics are (0,0), (1,0), (0,1).
    let corner_b = [Vec2::ZERO, Vec2::X, Vec2::Y];
    let mut best = (f32::INFINITY, Vec2::ZERO);
    for e in 0..3 {
        let (a, b) = (t[e], t[(e + 1) % 3]);
        let ab = b - a;
        let len2 = ab.length_squared();
        let s = if len2 > 0.0 {
            ((p - a).dot(ab) / len2).clamp(0.0, 1.0)
        } else {
            0.0
        };
        let d = (a + ab * s - p).length_squared();
        if d < best.0 {
            best = (d, corner_b[e] * (1.0 - s) + corner_b[(e + 1) % 3] * s);
        }
    }
    best.1
}

/// Fills the texels of one chart's rectangle: covered texels sample the face under their
/// centre, the others the nearest point of the chart's faces.
fn fill_chart(
    faces: &[Face],
    members: &[(usize, [Vec2; 3])],
    rect: [u32; 4],
    width: u32,
    points: &mut [Option<TexelPoint>],
) {
    let point = |f: usize, b: Vec2| {
        let face = &faces[f];
        Some(TexelPoint {
            instance: InstanceId(face.instance as u32),
            triangle: face.triangle,
            side: face.side,
            barycentrics: b,
        })
    };
    let at = |x: u32, y: u32| (y * width + x) as usize;
    // Cover: each face rasterises the texel centres inside it.
    for &(f, uv) in members {
        let lo = uv[0].min(uv[1]).min(uv[2]);
        let hi = uv[0].max(uv[1]).max(uv[2]);
        let x_lo = (lo.x - 0.5).ceil().max(rect[0] as f32) as u32;
        let y_lo = (lo.y - 0.5).ceil().max(rect[1] as f32) as u32;
        let x_hi = ((hi.x - 0.5).floor() as i64).min(rect[2] as i64 - 1);
        let y_hi = ((hi.y - 0.5).floor() as i64).min(rect[3] as i64 - 1);
        for y in y_lo as i64..=y_hi {
            for x in x_lo as i64..=x_hi {
                let c = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
                if let Some(b) = barycentrics(&uv, c)
                    && b.x >= 0.0
                    && b.y >= 0.0
                    && b.x + b.y <= 1.0
                {
                    points[at(x as u32, y as u32)] = point(f, b);
                }
            }
        }
    }
    // The rest of the rectangle: the nearest point of the nearest face.
    for y in rect[1]..rect[3] {
        for x in rect[0]..rect[2] {
            if points[at(x, y)].is_some() {
                continue;
            }
            let c = Vec2::new(x as f32 + 0.5, y as f32 + 0.5);
            let mut best = (f32::INFINITY, None);
            for &(f, uv) in members {
                let b = nearest_barycentrics(&uv, c);
                let q = uv[0] * (1.0 - b.x - b.y) + uv[1] * b.x + uv[2] * b.y;
                let d = (q - c).length_squared();
                if d < best.0 {
                    best = (d, point(f, b));
                }
            }
            points[at(x, y)] = best.1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Issue 38: densities whose lightmap sizes overflowed u32 (a chart's side saturates
    /// at 2³² − 1 texels from about 1e9 texels/m in this 4.4 m room, and the packing's
    /// sums wrapped or panicked) are refused, naming the setting and the value.
    #[test]
    fn huge_densities_are_refused_not_overflowed() {
        let scene = illume_scene::builtin::load("sun-room").unwrap();
        for density in [1e4f32, 1e9, 1e30, f32::MAX] {
            let e = Atlas::build(&scene, density, 0.5)
                .expect_err("beyond the texel cap")
                .to_string();
            assert!(
                e.contains("precomputed.atlas_density")
                    && e.contains(&format!("{density} texels/m"))
                    && e.contains(&MAX_TEXELS.to_string()),
                "{density}: {e}"
            );
        }
    }

    #[test]
    fn a_quad_is_one_chart_at_the_density_asked() {
        let scene = illume_scene::builtin::load("sun-room").unwrap();
        let atlas = Atlas::build(&scene, 10.0, 0.5).unwrap();
        // The floor slab's top face (4.4 m square: 44 texels) is one chart: its two
        // triangles map to one rectangle of 44×44 texels.
        let floor = scene
            .instances
            .iter()
            .position(|i| i.name == "floor")
            .unwrap();
        let mesh = &scene.meshes[scene.instances[floor].mesh.index()];
        let up: Vec<u32> = (0..mesh.triangle_count() as u32)
            .filter(|&t| {
                let [a, b, c] = mesh.triangle(t as usize);
                (b - a).cross(c - a).y > 0.0
            })
            .collect();
        assert_eq!(up.len(), 2);
        let id = InstanceId(floor as u32);
        let s0 = atlas.slot(id, up[0], false).unwrap();
        let s1 = atlas.slot(id, up[1], false).unwrap();
        assert_eq!(s0.rect, s1.rect, "one chart");
        let r = s0.rect;
        assert_eq!((r[2] - r[0], r[3] - r[1]), (44, 44));
        // One-sided material: no back side. Dynamic box: unmapped.
        assert!(atlas.slot(id, up[0], true).is_none());
        let boxed = scene.instances.iter().position(|i| i.dynamic).unwrap();
        assert!(atlas.slot(InstanceId(boxed as u32), 0, false).is_none());
        // Every texel of every chart samples a point; charts never overlap.
        let mut owner = vec![usize::MAX; atlas.lightmap_texels()];
        for (i, s) in atlas.slots.iter().enumerate() {
            for y in s.rect[1]..s.rect[3] {
                for x in s.rect[0]..s.rect[2] {
                    let t = (y * atlas.width + x) as usize;
                    assert!(atlas.point(t).is_some());
                    let chart = atlas.slots.iter().position(|o| o.rect == s.rect).unwrap();
                    assert!(owner[t] == usize::MAX || owner[t] == chart, "slot {i}");
                    owner[t] = chart;
                }
            }
        }
    }

    #[test]
    fn lookups_interpolate_inside_their_chart() {
        let scene = illume_scene::builtin::load("sun-room").unwrap();
        let atlas = Atlas::build(&scene, 8.0, 0.5).unwrap();
        // A linear ramp in x over the lightmap is reproduced exactly inside a chart.
        let values: Vec<Rgb> = (0..atlas.lightmap_texels())
            .map(|i| Rgb::splat((i % atlas.width as usize) as f32 + 0.5))
            .collect();
        let s = &atlas.slots[0];
        let b = Vec2::new(0.3, 0.3);
        let uv = s.uv[0] * 0.4 + s.uv[1] * 0.3 + s.uv[2] * 0.3;
        let expect = uv.x.clamp(s.rect[0] as f32 + 0.5, s.rect[2] as f32 - 0.5);
        let got = atlas.lookup(&values, s, b);
        assert!((got.x - expect).abs() < 1e-3, "{} vs {expect}", got.x);
    }

    #[test]
    fn probes_weigh_directions_by_the_normal() {
        let scene = illume_scene::builtin::load("sun-room").unwrap();
        let atlas = Atlas::build(&scene, 4.0, 1.0).unwrap();
        let n = atlas.probes.count();
        // Every probe: +X holds 1, every other direction 0.
        let values: Vec<Rgb> = (0..6 * n)
            .map(|i| if i % 6 == 0 { Rgb::ONE } else { Rgb::ZERO })
            .collect();
        let valid = vec![1.0; n];
        let p = atlas.probes.position(n / 2) + Vec3::splat(0.3);
        let x = atlas.probe_lookup(&values, &valid, p, Vec3::X);
        let diag = atlas.probe_lookup(&values, &valid, p, Vec3::new(1.0, 1.0, 0.0).normalize());
        let away = atlas.probe_lookup(&values, &valid, p, Vec3::NEG_X);
        assert!((x.x - 1.0).abs() < 1e-5 && (diag.x - 0.5).abs() < 1e-5 && away.x == 0.0);
        // No valid probe: black.
        let none = atlas.probe_lookup(&values, &vec![0.0; n], p, Vec3::X);
        assert_eq!(none, Rgb::ZERO);
    }
}
