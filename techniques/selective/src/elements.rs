//! Mesh elements: the buckets photons are counted in (§1, §3) and the Gouraud display
//! of their irradiance (§6).
//!
//! Every triangle is split into a k×k barycentric grid of k² equal sub-triangles. k is
//! a power of two chosen from the triangle's object-space area and a target element
//! area ([`grid_sides`]; the target from `element_count` over the scene's area, and no
//! larger than a fixed fraction of the scene's size, see [`Elements::with_max_side`], so
//! large triangles are split even on a model of many triangles). A grid cell `(i, j)` (i along b₁, j along b₂, i + j <
//! k) holds a lower sub-triangle and, when i + j < k − 1, an upper one; element `e =
//! j(2k − j) + 2i + upper` within the triangle. Instances of one mesh share its grid but
//! each has its own accumulators (elements live in object space and move with their
//! object).
//!
//! **Display.** Element-grid vertices of one mesh at the same object-space point whose
//! triangles' normals lie within `smoothing_angle_deg` are welded into one display
//! vertex; its irradiance is the area-weighted mean of the elements around it,
//! Σ Φ / (N·Σ A), and a pixel interpolates its element's three corners (the paper's
//! Gouraud shading of the mesh).
//!
//! **Gather over neighbouring elements** (beyond the paper, issue 34 goal 2). Where the
//! elements around a display vertex hold few photon impacts (a finely tessellated object
//! whose triangles are each one element, or a dimly lit region), the plain mean of its
//! own elements is mostly noise. With [`Gather`] on, such a vertex gathers flux and area
//! from the rings of display vertices around it, one ring per pass (each pass adds every
//! vertex's neighbours' sums of the previous pass to its own, a binomial-like kernel that
//! weighs the vertex most), until the gathered elements hold `impacts` impacts or
//! `max_rings` rings are reached: a density estimate whose support adapts to the photon
//! density, as a k-nearest-neighbour estimate does. Rings follow the welded display mesh,
//! so they stay on one instance and never cross a crease sharper than
//! `smoothing_angle_deg`. The estimate is a ratio Σ w·Φ / (N·Σ w·A): a constant
//! irradiance stays exact.
//!
//! **No T-junction seams.** Two triangles that share an edge may have different k.
//! Because every k is a power of two, the coarser side's grid vertices along the edge
//! are also the finer side's; the finer side's other edge vertices ("hanging"
//! vertices) are displayed as the linear interpolation of the two coarse vertices
//! around them. Both sides then show the same piecewise-linear irradiance along the
//! edge: the displayed indirect light is continuous across every shared edge of a
//! smoothing group (tested), as on a conforming mesh.

use illume_core::{Affine3A, Rgb, Vec2, Vec3};
use illume_scene::{Mesh, Scene};
use illume_transport::flux::Quanta;
use rayon::prelude::*;
use std::collections::HashMap;

/// Quantized object-space position.
type PosKey = [i64; 3];

/// The triangles and local edge numbers on each edge (its end points' keys, ordered).
type EdgeSides = HashMap<(PosKey, PosKey), Vec<(usize, usize)>>;

/// Largest grid side k per triangle (k² elements).
pub const MAX_K: u32 = 256;

/// Elements and display vertices of one mesh.
#[derive(Clone, Debug, Default)]
pub struct MeshGrid {
    /// Grid side per triangle.
    pub k: Vec<u32>,
    /// First element of each triangle (prefix sums of k²), then the total.
    pub first_element: Vec<u32>,
    /// First grid vertex of each triangle in `vertex_ids` ((k+1)(k+2)/2 each).
    first_grid_vertex: Vec<u32>,
    /// Welded display vertex of every triangle's grid vertex.
    vertex_ids: Vec<u32>,
    /// Display vertices.
    pub vertex_count: u32,
    /// Hanging display vertices: `(vertex, a, b, w)`, shown as `(1 − w)·a + w·b`.
    pub hanging: Vec<(u32, u32, u32, f32)>,
    /// Neighbours of each display vertex (those sharing an element with it) in
    /// `neighbours[neighbour_first[v] .. neighbour_first[v + 1]]`; empty until
    /// [`Elements::set_gather`] turns the gather on.
    neighbour_first: Vec<u32>,
    neighbours: Vec<u32>,
}

/// Index of grid vertex `(a, b)` (a along b₁, b along b₂, a + b ≤ k) in its triangle.
#[inline]
fn grid_vertex(k: u32, a: u32, b: u32) -> u32 {
    b * (k + 1) - b * (b.saturating_sub(1)) / 2 + a
}

/// The element of barycentrics `b = (b₁, b₂)` in a k-grid, and the point's weights on
/// the element's three grid corners with their `(a, b)` coordinates.
#[inline]
pub fn locate(k: u32, b: Vec2) -> (u32, [(u32, u32, f32); 3]) {
    let kf = k as f32;
    let x = (b.x * kf).clamp(0.0, kf);
    let y = (b.y * kf).clamp(0.0, kf);
    let j = (y as u32).min(k - 1);
    let i = (x as u32).min(k - 1 - j);
    let fx = x - i as f32;
    let fy = y - j as f32;
    let upper = fx + fy > 1.0 && i + j + 1 < k;
    let e = j * (2 * k - j) + 2 * i + upper as u32;
    let corners = if upper {
        [
            (i + 1, j, 1.0 - fy),
            (i + 1, j + 1, fx + fy - 1.0),
            (i, j + 1, 1.0 - fx),
        ]
    } else {
        [(i, j, 1.0 - fx - fy), (i + 1, j, fx), (i, j + 1, fy)]
    };
    (e, corners)
}

/// The barycentric centre of element `e` of a k-grid (the inverse of [`locate`]).
pub fn element_centre(k: u32, e: u32) -> Vec2 {
    // Row j holds 2(k − j) − 1 elements starting at j(2k − j).
    let mut j = 0;
    while j + 1 < k && (j + 1) * (2 * k - (j + 1)) <= e {
        j += 1;
    }
    let r = e - j * (2 * k - j);
    let (i, upper) = (r / 2, r % 2 == 1);
    let kf = k as f32;
    if upper {
        Vec2::new((i as f32 + 2.0 / 3.0) / kf, (j as f32 + 2.0 / 3.0) / kf)
    } else {
        Vec2::new((i as f32 + 1.0 / 3.0) / kf, (j as f32 + 1.0 / 3.0) / kf)
    }
}

/// The three grid corners of element `e` of a k-grid.
fn element_corners(k: u32, e: u32) -> [(u32, u32); 3] {
    let c = element_centre(k, e);
    let (_, corners) = locate(k, c);
    corners.map(|(a, b, _)| (a, b))
}

/// Power-of-two grid sides for triangles of areas `areas` and a target element area
/// `target`: each triangle gets one of the two powers of two around √(area/target)
/// (1 … [`MAX_K`]), the one that keeps the running count of elements closest to the
/// running Σ area/target (error diffusion in triangle order), so a mesh holds about
/// area/target elements although sides are powers of two. Triangles smaller than the
/// target get k = 1 and carry no error forward.
pub fn grid_sides(areas: &[f64], target: f64) -> Vec<u32> {
    let mut debt = 0.0f64;
    areas
        .iter()
        .map(|&a| {
            let want = if target > 0.0 && a > 0.0 {
                a / target
            } else {
                0.0
            };
            if want.is_nan() || want <= 1.0 {
                return 1;
            }
            let max = (MAX_K as f64).powi(2);
            if want >= max {
                return MAX_K;
            }
            let lo = 1u32 << ((want.log2() * 0.5).floor() as u32).min(MAX_K.trailing_zeros());
            let hi = (lo * 2).min(MAX_K);
            let (r_lo, r_hi) = (
                debt + want - (lo as f64).powi(2),
                debt + want - (hi as f64).powi(2),
            );
            let (k, r) = if r_lo.abs() <= r_hi.abs() {
                (lo, r_lo)
            } else {
                (hi, r_hi)
            };
            debt = r;
            k
        })
        .collect()
}

/// The grid vertex `(a, b)` at step `m` (0 … k) along edge `edge` of a k-grid: edge 0
/// runs from corner 0 to corner 1, edge 1 from corner 1 to corner 2, edge 2 from corner 2
/// to corner 0.
#[inline]
fn edge_vertex(k: u32, edge: usize, m: u32) -> (u32, u32) {
    match edge {
        0 => (m, 0),
        1 => (k - m, m),
        _ => (0, k - m),
    }
}

fn object_area(mesh: &Mesh, t: usize) -> f32 {
    let [a, b, c] = mesh.indices[t].map(|i| mesh.positions[i as usize]);
    0.5 * (b - a).cross(c - a).length()
}

impl MeshGrid {
    /// The grid of `mesh` for a target element area `target` (object space), with
    /// display vertices welded within `cos_smooth`.
    fn new(mesh: &Mesh, target: f64, cos_smooth: f32) -> Self {
        let n = mesh.indices.len();
        let mut k = Vec::with_capacity(n);
        let mut first_element = Vec::with_capacity(n + 1);
        let mut first_grid_vertex = Vec::with_capacity(n + 1);
        let (mut elements, mut grid) = (0u32, 0u32);
        let areas: Vec<f64> = (0..n).map(|t| object_area(mesh, t) as f64).collect();
        for side in grid_sides(&areas, target) {
            k.push(side);
            first_element.push(elements);
            first_grid_vertex.push(grid);
            elements = elements.saturating_add(side * side);
            grid = grid.saturating_add((side + 1) * (side + 2) / 2);
        }
        first_element.push(elements);
        first_grid_vertex.push(grid);
        // Weld grid vertices: quantized object-space position, then normal clusters.
        let (lo, hi) = mesh.positions.iter().fold(
            (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
            |(l, h), p| (l.min(*p), h.max(*p)),
        );
        let cell = ((hi - lo).length() as f64 * 1e-5).max(1e-12);
        let mut clusters: HashMap<[i64; 3], Vec<(u32, Vec3)>> = HashMap::new();
        let mut vertex_ids = Vec::with_capacity(grid as usize);
        let mut vertex_count = 0u32;
        for (tri, &side) in mesh.indices.iter().zip(&k) {
            let [p0, p1, p2] = tri.map(|i| mesh.positions[i as usize]);
            let normal = (p1 - p0).cross(p2 - p0).normalize_or_zero();
            for b in 0..=side {
                for a in 0..=(side - b) {
                    let p = p0
                        + (p1 - p0) * (a as f32 / side as f32)
                        + (p2 - p0) * (b as f32 / side as f32);
                    let key = [p.x, p.y, p.z].map(|c| (c as f64 / cell).round() as i64);
                    let list = clusters.entry(key).or_default();
                    let found = if normal == Vec3::ZERO {
                        None
                    } else {
                        list.iter()
                            .find(|(_, n)| n.dot(normal) >= cos_smooth)
                            .map(|c| c.0)
                    };
                    let id = found.unwrap_or_else(|| {
                        let id = vertex_count;
                        vertex_count += 1;
                        list.push((id, normal));
                        id
                    });
                    vertex_ids.push(id);
                }
            }
        }
        let mut grid = Self {
            k,
            first_element,
            first_grid_vertex,
            vertex_ids,
            vertex_count,
            hanging: Vec::new(),
            neighbour_first: Vec::new(),
            neighbours: Vec::new(),
        };
        grid.hanging = grid.hanging_vertices(mesh, cell, cos_smooth);
        grid
    }

    /// The constraints that make the display continuous across edges shared by
    /// triangles of different k (see the module docs): every grid vertex of the finer
    /// side that the coarsest side within `cos_smooth` does not have.
    fn hanging_vertices(
        &self,
        mesh: &Mesh,
        cell: f64,
        cos_smooth: f32,
    ) -> Vec<(u32, u32, u32, f32)> {
        let key = |p: Vec3| [p.x, p.y, p.z].map(|c| (c as f64 / cell).round() as i64);
        let mut edges: EdgeSides = HashMap::new();
        let mut normals = Vec::with_capacity(mesh.indices.len());
        if self.k.iter().all(|&k| k == self.k[0]) {
            return Vec::new();
        }
        for (t, tri) in mesh.indices.iter().enumerate() {
            let p = tri.map(|i| mesh.positions[i as usize]);
            normals.push((p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero());
            for e in 0..3 {
                let (a, b) = (key(p[e]), key(p[(e + 1) % 3]));
                edges
                    .entry(if a <= b { (a, b) } else { (b, a) })
                    .or_default()
                    .push((t, e));
            }
        }
        let mut out = Vec::new();
        for sides in edges.values().filter(|s| s.len() > 1) {
            for &(t, e) in sides {
                let kf = self.k[t];
                let kc = sides
                    .iter()
                    .filter(|&&(u, _)| normals[u].dot(normals[t]) >= cos_smooth)
                    .map(|&(u, _)| self.k[u])
                    .min()
                    .unwrap_or(kf);
                if kc >= kf {
                    continue;
                }
                let r = kf / kc;
                let id = |m: u32| {
                    let (a, b) = edge_vertex(kf, e, m);
                    self.vertex(t, a, b)
                };
                for m in (1..kf).filter(|m| m % r != 0) {
                    let m0 = m - m % r;
                    out.push((id(m), id(m0), id(m0 + r), (m % r) as f32 / r as f32));
                }
            }
        }
        out.sort_unstable_by_key(|h| h.0);
        out.dedup_by_key(|h| h.0);
        out
    }

    /// Builds the display vertices' adjacency (vertices sharing an element), once.
    fn build_neighbours(&mut self) {
        if !self.neighbour_first.is_empty() {
            return;
        }
        let mut pairs: Vec<(u32, u32)> = Vec::new();
        for (t, &k) in self.k.iter().enumerate() {
            for e in 0..k * k {
                let v = element_corners(k, e).map(|(a, b)| self.vertex(t, a, b));
                for (i, j) in [(0, 1), (1, 2), (2, 0)] {
                    if v[i] != v[j] {
                        pairs.push((v[i], v[j]));
                        pairs.push((v[j], v[i]));
                    }
                }
            }
        }
        pairs.sort_unstable();
        pairs.dedup();
        let mut first = vec![0u32; self.vertex_count as usize + 1];
        for &(a, _) in &pairs {
            first[a as usize + 1] += 1;
        }
        for v in 0..self.vertex_count as usize {
            first[v + 1] += first[v];
        }
        self.neighbours = pairs.into_iter().map(|(_, b)| b).collect();
        self.neighbour_first = first;
    }

    /// The display vertices sharing an element with `v` (empty before
    /// [`Elements::set_gather`]).
    pub fn neighbours(&self, v: u32) -> &[u32] {
        match (
            self.neighbour_first.get(v as usize),
            self.neighbour_first.get(v as usize + 1),
        ) {
            (Some(&a), Some(&b)) => &self.neighbours[a as usize..b as usize],
            _ => &[],
        }
    }

    /// Elements of the mesh.
    pub fn element_count(&self) -> u32 {
        *self.first_element.last().unwrap_or(&0)
    }

    /// Display vertex of grid vertex `(a, b)` of triangle `t`.
    #[inline]
    fn vertex(&self, t: usize, a: u32, b: u32) -> u32 {
        self.vertex_ids[(self.first_grid_vertex[t] + grid_vertex(self.k[t], a, b)) as usize]
    }
}

/// Every mesh's grid and every instance's accumulator range.
#[derive(Clone, Debug)]
pub struct Elements {
    /// Per mesh.
    pub grids: Vec<MeshGrid>,
    /// First accumulator of each instance, then the total.
    pub instance_first: Vec<u32>,
    /// First display vertex of each instance, then the total.
    instance_first_vertex: Vec<u32>,
    /// The density estimate over neighbouring elements (off unless set).
    gather: Gather,
}

/// The display's density estimate over neighbouring elements (module docs; beyond the
/// paper, issue 34): a display vertex whose elements hold fewer than `impacts` photon
/// impacts gathers rings of neighbouring display vertices, up to `max_rings`.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Gather {
    /// Impacts a vertex's estimate should rest on; 0: off (each vertex the mean of its
    /// own elements, the paper's Gouraud display).
    pub impacts: u32,
    /// Most rings gathered.
    pub max_rings: u32,
}

impl Gather {
    /// True when the gather changes the display.
    pub fn is_on(&self) -> bool {
        self.impacts > 0 && self.max_rings > 0
    }
}

impl Elements {
    /// Grids for about `element_count` elements over the scene's instances (by object
    /// space area), display vertices welded within `smoothing_angle_deg`.
    pub fn new(scene: &Scene, element_count: u32, smoothing_angle_deg: f32) -> Self {
        Self::with_max_side(scene, element_count, smoothing_angle_deg, 0.0)
    }

    /// [`Elements::new`], with elements no wider than `max_side` times the diagonal of
    /// the scene's world-space bounding box (0: no bound): the target element area is
    /// the smaller of the scene's area over `element_count` and that side squared.
    pub fn with_max_side(
        scene: &Scene,
        element_count: u32,
        smoothing_angle_deg: f32,
        max_side: f32,
    ) -> Self {
        let mesh_area: Vec<f64> = scene
            .meshes
            .iter()
            .map(|m| (0..m.indices.len()).map(|t| object_area(m, t) as f64).sum())
            .collect();
        let total: f64 = scene
            .instances
            .iter()
            .map(|i| mesh_area[i.mesh.index()])
            .sum();
        let mut target = total / element_count.max(1) as f64;
        if max_side > 0.0 {
            let side = max_side as f64 * scene_diagonal(scene);
            if side > 0.0 {
                target = target.min(side * side);
            }
        }
        let cos_smooth = smoothing_angle_deg.to_radians().cos() - 1e-6;
        let grids: Vec<MeshGrid> = scene
            .meshes
            .iter()
            .map(|m| MeshGrid::new(m, target, cos_smooth))
            .collect();
        let mut instance_first = Vec::with_capacity(scene.instances.len() + 1);
        let mut instance_first_vertex = Vec::with_capacity(scene.instances.len() + 1);
        let (mut e, mut v) = (0u32, 0u32);
        for inst in &scene.instances {
            instance_first.push(e);
            instance_first_vertex.push(v);
            let g = &grids[inst.mesh.index()];
            e = e.saturating_add(g.element_count());
            v = v.saturating_add(g.vertex_count);
        }
        instance_first.push(e);
        instance_first_vertex.push(v);
        Self {
            grids,
            instance_first,
            instance_first_vertex,
            gather: Gather::default(),
        }
    }

    /// Turns the density estimate over neighbouring elements on (or off, `impacts` 0):
    /// it applies to displays made with impact counts ([`Elements::display_with_noise`]).
    /// Builds each mesh's vertex adjacency the first time.
    pub fn set_gather(&mut self, gather: Gather) {
        if gather.is_on() {
            for g in &mut self.grids {
                g.build_neighbours();
            }
        }
        self.gather = gather;
    }

    /// The density estimate over neighbouring elements in use.
    pub fn gather(&self) -> Gather {
        self.gather
    }

    /// Total elements (accumulators hold a front and a back side each).
    pub fn len(&self) -> usize {
        *self.instance_first.last().unwrap_or(&0) as usize
    }

    /// True without elements.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Instances the elements were built for.
    pub fn instances(&self) -> usize {
        self.instance_first.len() - 1
    }

    /// The accumulator of the point at barycentrics `b` of triangle `t` of `instance`
    /// (whose mesh is `mesh`).
    #[inline]
    pub fn element(&self, instance: usize, mesh: usize, t: usize, b: Vec2) -> u32 {
        let g = &self.grids[mesh];
        let (e, _) = locate(g.k[t], b);
        self.instance_first[instance] + g.first_element[t] + e
    }

    /// Per-vertex irradiance of every instance from the accumulators (`front`/`back`
    /// per element, in quanta of `quantum_w` watts) for `photons` photons.
    pub fn display(
        &self,
        scene: &Scene,
        accumulators: &[[Quanta; 2]],
        quantum_w: f64,
        photons: u64,
    ) -> Display {
        self.display_with(scene, accumulators, None, quantum_w, photons)
    }

    /// [`Elements::display`] with each vertex's noise ([`Display::noise`]) from the
    /// impacts per element side `counts`: an element of flux Φ from n impacts has a
    /// variance of about Φ²/n (n impacts of similar power, each present or not), the
    /// elements around a vertex are independent, so the vertex's irradiance
    /// Σ Φ / (N·Σ A) has a variance of Σ (Φ²/n) / (N·Σ A)², in luminance.
    pub fn display_with_noise(
        &self,
        scene: &Scene,
        accumulators: &[[Quanta; 2]],
        counts: &[[i64; 2]],
        quantum_w: f64,
        photons: u64,
    ) -> Display {
        self.display_with(scene, accumulators, Some(counts), quantum_w, photons)
    }

    fn display_with(
        &self,
        scene: &Scene,
        accumulators: &[[Quanta; 2]],
        counts: Option<&[[i64; 2]]>,
        quantum_w: f64,
        photons: u64,
    ) -> Display {
        let vertices = *self.instance_first_vertex.last().unwrap_or(&0) as usize;
        let mut flux = vec![[[0.0f64; 3]; 2]; vertices];
        let mut area = vec![0.0f64; vertices];
        let mut var = vec![[0.0f64; 2]; if counts.is_some() { vertices } else { 0 }];
        let gather = counts.is_some() && self.gather.is_on();
        let mut impacts = vec![[0.0f64; 2]; if gather { vertices } else { 0 }];
        let scale = if photons > 0 {
            quantum_w / photons as f64
        } else {
            0.0
        };
        // The noise of an element without impacts is that of one impact, not zero: else
        // a vertex whose elements lost their one or two impacts would pass as a real
        // change and drop to black at once, while the same impacts arriving were held
        // back as noise (a one-sided gate that flickers and darkens).
        let one_impact = counts.map_or(0.0, |c| mean_impact(accumulators, c) * scale);
        for (ii, inst) in scene.instances.iter().enumerate().take(self.instances()) {
            if inst.mask == 0 {
                continue;
            }
            let mesh = &scene.meshes[inst.mesh.index()];
            let g = &self.grids[inst.mesh.index()];
            let v0 = self.instance_first_vertex[ii] as usize;
            let a0 = self.instance_first[ii] as usize;
            for t in 0..mesh.indices.len() {
                let k = g.k[t];
                let elems = k * k;
                let a_e = world_area(mesh, t, &inst.world_from_object) as f64 / elems as f64;
                for e in 0..elems {
                    let index = a0 + (g.first_element[t] + e) as usize;
                    let acc = &accumulators[index];
                    let element_var = counts.map(|c| {
                        [0, 1].map(|s| {
                            let n = c[index][s];
                            if n <= 0 {
                                one_impact * one_impact
                            } else {
                                let y = luminance_f64(acc[s].0) * scale;
                                y * y / n as f64
                            }
                        })
                    });
                    for (a, b) in element_corners(k, e) {
                        let v = v0 + g.vertex(t, a, b) as usize;
                        area[v] += a_e;
                        for (f, q) in flux[v].iter_mut().zip(acc) {
                            for (fc, qc) in f.iter_mut().zip(q.0) {
                                *fc += qc as f64 * scale;
                            }
                        }
                        if let Some(ev) = element_var {
                            var[v][0] += ev[0];
                            var[v][1] += ev[1];
                        }
                        if let (true, Some(c)) = (gather, counts) {
                            impacts[v][0] += c[index][0].max(0) as f64;
                            impacts[v][1] += c[index][1].max(0) as f64;
                        }
                    }
                }
            }
        }
        // Per vertex and side: the area the flux is spread over, and the noise's scale
        // (√ of own impacts over gathered impacts; 1 without the gather).
        let mut side_area: Vec<[f64; 2]> = area.iter().map(|&a| [a, a]).collect();
        let mut noise_scale = vec![[1.0f64; 2]; if gather { vertices } else { 0 }];
        if gather {
            for (ii, inst) in scene.instances.iter().enumerate().take(self.instances()) {
                let range = self.instance_first_vertex[ii] as usize
                    ..self.instance_first_vertex[ii + 1] as usize;
                if inst.mask == 0 || range.is_empty() {
                    continue;
                }
                let g = &self.grids[inst.mesh.index()];
                let own: Vec<[f64; 2]> = impacts[range.clone()].to_vec();
                for side in 0..2 {
                    gather_rings(
                        g,
                        self.gather,
                        side,
                        &mut flux[range.clone()],
                        &mut side_area[range.clone()],
                        &mut impacts[range.clone()],
                    );
                }
                for ((s, o), n) in noise_scale[range.clone()]
                    .iter_mut()
                    .zip(&own)
                    .zip(&impacts[range])
                {
                    *s = [0, 1].map(|k| (o[k].max(1.0) / n[k].max(1.0)).sqrt());
                }
            }
        }
        let mut irradiance: Vec<[Rgb; 2]> = flux
            .iter()
            .zip(&side_area)
            .map(|(f, a)| {
                let e = |s: usize| {
                    let a = a[s];
                    if a > 0.0 {
                        Rgb::new(
                            (f[s][0] / a) as f32,
                            (f[s][1] / a) as f32,
                            (f[s][2] / a) as f32,
                        )
                    } else {
                        Rgb::ZERO
                    }
                };
                [e(0), e(1)]
            })
            .collect();
        let mut noise: Vec<[f32; 2]> = var
            .iter()
            .zip(&area)
            .enumerate()
            .map(|(i, (v, &a))| {
                [0, 1].map(|s| {
                    if a > 0.0 {
                        let scale = noise_scale.get(i).map_or(1.0, |n| n[s]);
                        (v[s].sqrt() / a * scale) as f32
                    } else {
                        0.0
                    }
                })
            })
            .collect();
        for (ii, inst) in scene.instances.iter().enumerate().take(self.instances()) {
            let v0 = self.instance_first_vertex[ii] as usize;
            for &(v, a, b, w) in &self.grids[inst.mesh.index()].hanging {
                let (ea, eb) = (irradiance[v0 + a as usize], irradiance[v0 + b as usize]);
                irradiance[v0 + v as usize] = [0, 1].map(|s| ea[s] * (1.0 - w) + eb[s] * w);
                if !noise.is_empty() {
                    let (na, nb) = (noise[v0 + a as usize], noise[v0 + b as usize]);
                    noise[v0 + v as usize] = [0, 1].map(|s| na[s] * (1.0 - w) + nb[s] * w);
                }
            }
        }
        Display { irradiance, noise }
    }

    /// Irradiance \[W/m²\] at barycentrics `b` of triangle `t` of `instance` (mesh `mesh`)
    /// on its front (`front`) or back side, interpolated from `display`.
    #[inline]
    pub fn irradiance(
        &self,
        display: &Display,
        instance: usize,
        mesh: usize,
        t: usize,
        b: Vec2,
        front: bool,
    ) -> Rgb {
        if instance >= self.instances() {
            return Rgb::ZERO;
        }
        let g = &self.grids[mesh];
        let (_, corners) = locate(g.k[t], b);
        let v0 = self.instance_first_vertex[instance] as usize;
        let side = if front { 0 } else { 1 };
        corners.iter().fold(Rgb::ZERO, |acc, &(a, bb, w)| {
            acc + display.irradiance[v0 + g.vertex(t, a, bb) as usize][side] * w
        })
    }
}

/// The density estimate over neighbouring elements of one instance's display vertices
/// (module docs) on side `side`: a vertex whose `impacts` fall short of
/// `gather.impacts` takes its sums after the first pass (ring) that reaches them, or
/// after `gather.max_rings`. `flux`, `area` and `impacts` hold the vertices' own sums on
/// entry and the gathered ones on return. A side without impacts is left alone.
fn gather_rings(
    grid: &MeshGrid,
    gather: Gather,
    side: usize,
    flux: &mut [[[f64; 3]; 2]],
    area: &mut [[f64; 2]],
    impacts: &mut [[f64; 2]],
) {
    let target = gather.impacts as f64;
    let n = flux.len().min(grid.vertex_count as usize);
    let mut pending: Vec<bool> = (0..n).map(|v| impacts[v][side] < target).collect();
    if !pending.iter().any(|&p| p) || impacts.iter().all(|c| c[side] <= 0.0) {
        return;
    }
    // Flux (3), area and impacts.
    let mut current: Vec<[f64; 5]> = (0..n)
        .map(|v| {
            let f = flux[v][side];
            [f[0], f[1], f[2], area[v][side], impacts[v][side]]
        })
        .collect();
    for ring in 1..=gather.max_rings {
        let next: Vec<[f64; 5]> = current
            .par_iter()
            .enumerate()
            .map(|(v, own)| {
                let mut sum = *own;
                for &u in grid.neighbours(v as u32) {
                    if let Some(other) = current.get(u as usize) {
                        for (a, b) in sum.iter_mut().zip(other) {
                            *a += b;
                        }
                    }
                }
                sum
            })
            .collect();
        let mut left = false;
        for (v, p) in pending.iter_mut().enumerate() {
            if !*p {
                continue;
            }
            let x = &next[v];
            if x[4] >= target || ring == gather.max_rings {
                flux[v][side] = [x[0], x[1], x[2]];
                area[v][side] = x[3];
                impacts[v][side] = x[4];
                *p = false;
            } else {
                left = true;
            }
        }
        if !left {
            break;
        }
        current = next;
    }
}

/// The diagonal of the world-space bounding box of `scene`'s instances \[m\].
pub fn scene_diagonal(scene: &Scene) -> f64 {
    let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
    for inst in &scene.instances {
        for p in &scene.meshes[inst.mesh.index()].positions {
            let w = inst.world_from_object.transform_point3(*p);
            lo = lo.min(w);
            hi = hi.max(w);
        }
    }
    if lo.x <= hi.x {
        (hi - lo).length() as f64
    } else {
        0.0
    }
}

/// World-space area of triangle `t` of `mesh` placed by `world_from_object`.
pub fn world_area(mesh: &Mesh, t: usize, world_from_object: &Affine3A) -> f32 {
    let [a, b, c] =
        mesh.indices[t].map(|i| world_from_object.transform_point3(mesh.positions[i as usize]));
    0.5 * (b - a).cross(c - a).length()
}

/// Luminance (Rec. 709) of integer RGB quanta.
#[inline]
fn luminance_f64(q: [i64; 3]) -> f64 {
    0.2126 * q[0] as f64 + 0.7152 * q[1] as f64 + 0.0722 * q[2] as f64
}

/// Per display vertex, front and back irradiance \[W/m²\].
#[derive(Clone, Debug, Default)]
pub struct Display {
    /// `[front, back]` per vertex, instances one after another.
    pub irradiance: Vec<[Rgb; 2]>,
    /// `[front, back]` standard deviation of each vertex's luminance irradiance
    /// \[W/m²\] from the impacts per element ([`Elements::display_with_noise`]); empty
    /// from [`Elements::display`].
    pub noise: Vec<[f32; 2]>,
}
/// The mean luminance an impact carries (photon-energy units, before the display's
/// scale): the luminance of every side's accumulated energy over its impacts, for sides
/// with impacts; 0 when there are none.
fn mean_impact(accumulators: &[[Quanta; 2]], counts: &[[i64; 2]]) -> f64 {
    let (mut energy, mut impacts) = (0.0f64, 0i64);
    for (acc, c) in accumulators.iter().zip(counts) {
        for s in 0..2 {
            if c[s] > 0 {
                energy += luminance_f64(acc[s].0).max(0.0);
                impacts += c[s];
            }
        }
    }
    if impacts > 0 {
        energy / impacts as f64
    } else {
        0.0
    }
}
