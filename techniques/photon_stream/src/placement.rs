//! VSL placement (§0.4.2, Figure 4, Algorithm 1) and the per-object nearest-VSL index.
//!
//! 1. The VSL count N_v is shared among objects (instances) by world surface area;
//!    each object gets `max(1, ⌈(1 + oversampling)·N_v·A_o/A⌉)` candidates.
//! 2. Each candidate picks a triangle of its object with probability ∝ area and a
//!    uniform point on it after the triangle is shrunk about its centroid by
//!    `triangle_scale` (points stay off edges).
//! 3. Algorithm 1 removes, until N_v remain, the candidate with the smallest
//!    (d_min1, d_min2): d_min1 finds the closest pair, d_min2 picks which of the two
//!    sits in the denser neighbourhood. Each VSL keeps its two nearest neighbours, so a
//!    removal only rescans the VSLs that had the removed one as a neighbour: O(n) per
//!    removal instead of O(n²). The last VSL of an object is never removed.
//! 4. Each VSL's represented area A_s is its share of its object's area: the object's
//!    surface is sampled uniformly and every sample is assigned to its VSL by the same
//!    rule that assigns photons (below), so A_s is the area of its cell.
//!
//! **Cells follow orientation (beyond the paper).** A point of the surface belongs to the
//! nearest VSL of its object *in its orientation class*: the dominant axis and sign of
//! the object-space geometric normal (±X, ±Y, ±Z), the VSL's class being its triangle's;
//! only when the object has no VSL of that class does the nearest VSL of any class take
//! it. The paper's rule (nearest VSL of the object) makes cells of a one-mesh building
//! straddle floor, walls, column bases and arch undersides: flux landing on the lit
//! floor then leaves from a VSL with a wall's normal, and a cell's mean exitance mixes
//! bright and dark, hidden and exposed surface (a final gather over such cells read
//! Sponza's indirect light 22 % too dark with 3200 cells; `BENCHMARKS.md`).
//!
//! VSLs live in object space (they move with their object); distances in Algorithm 1
//! are measured in world space at construction time.

use illume_core::sampling::{AliasTable, Pcg32, SampleStream, mix64, uniform_triangle};
use illume_core::{Aabb, Vec3, transform_normal};
use illume_scene::{InstanceId, Scene};
use illume_transport::nearest::NearestIndex;
use rayon::prelude::*;

/// One virtual surface light (§0.4.1): a surface element attached to an object.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Vsl {
    /// The object (instance) it is attached to.
    pub instance: InstanceId,
    /// Centre in the object's space [m, object units].
    pub position_object: Vec3,
    /// Unit normal in object space (the front face's side; the back side is `−normal`).
    pub normal_object: Vec3,
    /// World area of the surface it represents \[m²\] (its Voronoi cell on the object).
    pub area_m2: f32,
}

/// All VSLs of a scene, grouped by instance, with nearest-neighbour indices per
/// instance in object space (built once: VSLs never move relative to their object).
#[derive(Clone, Debug)]
pub struct VslSet {
    vsls: Vec<Vsl>,
    /// `first[i]..first[i + 1]` are the VSLs of instance `i`.
    first: Vec<u32>,
    /// Orientation class of each VSL (its triangle's; from its normal for sets built
    /// without a scene).
    classes: Vec<u8>,
    /// Per instance, all its VSLs.
    trees: Vec<NearestIndex>,
    /// Per instance, its VSLs of each orientation class.
    class_trees: Vec<[NearestIndex; CLASSES]>,
    /// Per instance, per triangle of its mesh: the triangle's orientation class (empty
    /// for sets built without a scene: cells are then the paper's).
    triangle_class: Vec<Vec<u8>>,
    /// Per instance, per triangle of its mesh: the VSL whose cell holds the whole
    /// triangle, or [`NO_OWNER`] when the triangle straddles a cell boundary (empty for
    /// sets built without a scene).
    triangle_owner: Vec<Vec<u32>>,
}

/// No single VSL is nearest to the whole triangle.
const NO_OWNER: u32 = u32::MAX;

/// Orientation classes: ±X, ±Y, ±Z.
const CLASSES: usize = 6;

/// The orientation class of a (geometric, object-space) normal: its dominant axis and
/// that axis's sign, +X, −X, +Y, −Y, +Z, −Z → 0…5.
pub fn orientation_class(n: Vec3) -> u8 {
    let a = n.abs();
    let axis = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    (2 * axis + usize::from(n[axis] < 0.0)) as u8
}

/// The orientation class of triangle `t` of `mesh` (its geometric normal's).
fn triangle_class(mesh: &illume_scene::Mesh, t: usize) -> u8 {
    let [a, b, c] = mesh.triangle(t);
    orientation_class((b - a).cross(c - a))
}

/// For each triangle of `mesh` (of orientation class `classes[t]`), the VSL whose cell
/// holds all of its points, if one does. Whether point o or v is nearer to x is the sign
/// of an affine function of x, `|x − o|² − |x − v|²`, so over a triangle it is smallest
/// at a corner: a triangle whose three corners have the same nearest VSL v of its class,
/// each with a margin over its second nearest, lies inside v's cell. The margin
/// (relative to the mesh's coordinate magnitude) keeps rounding in the per-impact
/// distances from ever choosing another VSL inside such a triangle, so the answer equals
/// the search's. A triangle whose class has no VSL gets none (the search falls back).
fn triangle_owners(
    mesh: &illume_scene::Mesh,
    classes: &[u8],
    trees: &[NearestIndex; CLASSES],
) -> Vec<u32> {
    let b = mesh.bounds();
    let magnitude = b.min.abs().max(b.max.abs()).max_element();
    let margin = 1e-4 * magnitude * magnitude;
    mesh.indices
        .iter()
        .zip(classes)
        .map(|(tri, &c)| {
            let tree = &trees[c as usize];
            let mut owner = NO_OWNER;
            for (k, &v) in tri.iter().enumerate() {
                let Some((id, d1, d2)) = tree.two_nearest(mesh.positions[v as usize]) else {
                    return NO_OWNER;
                };
                if d2 - d1 <= margin || (k > 0 && id != owner) {
                    return NO_OWNER;
                }
                owner = id;
            }
            owner
        })
        .collect()
}

/// Inputs of placement.
#[derive(Clone, Copy, Debug)]
pub struct PlacementSettings {
    /// N_v.
    pub vsl_count: u32,
    /// Extra candidates as a fraction of N_v (0.10 in the paper).
    pub oversampling: f32,
    /// Triangle shrink factor about the centroid, in (0, 1].
    pub triangle_scale: f32,
    /// Seed.
    pub seed: u64,
    /// Cells by orientation class (module doc; beyond the paper) when true, else the
    /// paper's nearest VSL of the object.
    pub oriented_cells: bool,
}

struct Candidate {
    instance: u32,
    class: u8,
    position_object: Vec3,
    normal_object: Vec3,
    position_world: Vec3,
}

/// World area of every triangle of instance `i`.
fn world_triangle_areas(scene: &Scene, i: usize) -> Vec<f32> {
    let inst = &scene.instances[i];
    let mesh = &scene.meshes[inst.mesh.index()];
    (0..mesh.triangle_count())
        .map(|t| {
            let [a, b, c] = mesh
                .triangle(t)
                .map(|p| inst.world_from_object.transform_point3(p));
            0.5 * (b - a).cross(c - a).length()
        })
        .collect()
}

/// A uniform point of triangle `t` shrunk by `scale` about its centroid, with the
/// object-space normal there (shading normal on the geometric normal's side).
fn point_on_triangle(
    mesh: &illume_scene::Mesh,
    t: usize,
    scale: f32,
    u: illume_core::Vec2,
) -> (Vec3, Vec3) {
    let [p0, p1, p2] = mesh.triangle(t);
    let b = uniform_triangle(u);
    let (b0, b1, b2) = (1.0 - b.x - b.y, b.x, b.y);
    // Shrinking the triangle about its centroid = pulling barycentrics towards 1/3.
    let third = 1.0 / 3.0;
    let (b0, b1, b2) = (
        third + scale * (b0 - third),
        third + scale * (b1 - third),
        third + scale * (b2 - third),
    );
    let p = p0 * b0 + p1 * b1 + p2 * b2;
    let ng = (p1 - p0).cross(p2 - p0).normalize_or(Vec3::Y);
    let n = if mesh.normals.is_empty() {
        ng
    } else {
        let [i0, i1, i2] = mesh.indices[t].map(|i| i as usize);
        let n = (mesh.normals[i0] * b0 + mesh.normals[i1] * b1 + mesh.normals[i2] * b2)
            .normalize_or(ng);
        if n.dot(ng) < 0.0 { -n } else { n }
    };
    (p, n)
}

/// One nearest-VSL index per object: object `i` holds VSLs `first[i]..first[i + 1]`
/// (sorted by object) in its object space, over the box `bounds_of(i)`.
fn object_indices(
    vsls: &[Vsl],
    first: &[u32],
    bounds_of: impl Fn(usize) -> Aabb,
) -> Vec<NearestIndex> {
    (0..first.len() - 1)
        .map(|i| {
            let r = first[i] as usize..first[i + 1] as usize;
            NearestIndex::new(
                vsls[r.clone()]
                    .iter()
                    .zip(r)
                    .map(|(v, g)| (v.position_object, g as u32))
                    .collect(),
                bounds_of(i),
            )
        })
        .collect()
}

/// [`object_indices`] split by orientation class (`classes[g]` of VSL `g`), class `c`
/// of object `i` over the box `bounds_of(i, c)`.
fn class_indices(
    vsls: &[Vsl],
    classes: &[u8],
    first: &[u32],
    bounds_of: impl Fn(usize, usize) -> Aabb,
) -> Vec<[NearestIndex; CLASSES]> {
    (0..first.len() - 1)
        .map(|i| {
            let mut items: [Vec<(Vec3, u32)>; CLASSES] = Default::default();
            for g in first[i] as usize..first[i + 1] as usize {
                items[classes[g] as usize].push((vsls[g].position_object, g as u32));
            }
            let mut c = 0;
            items.map(|it| {
                let index = NearestIndex::new(it, bounds_of(i, c));
                c += 1;
                index
            })
        })
        .collect()
}

/// Algorithm 1's first step: `(1 + oversampling) · vsl_count` candidates spread over
/// the instances in proportion to their area (`object_area`, at least one each with
/// area), uniformly over each one's triangles (`areas`).
fn candidates(
    scene: &Scene,
    settings: &PlacementSettings,
    areas: &[Vec<f32>],
    object_area: &[f64],
) -> Vec<Candidate> {
    let total: f64 = object_area.iter().sum();
    let mut candidates = Vec::new();
    let mut rng = Pcg32::new(settings.seed, 0x7a5c_e11e);
    for (i, inst) in scene.instances.iter().enumerate() {
        let Some(table) = AliasTable::new(&areas[i]) else {
            continue;
        };
        let share = object_area[i] / total;
        let count = ((1.0 + settings.oversampling as f64) * settings.vsl_count as f64 * share)
            .ceil()
            .max(1.0) as usize;
        let mesh = &scene.meshes[inst.mesh.index()];
        for _ in 0..count {
            let (t, _) = table.sample(rng.next_1d());
            let (p, n) = point_on_triangle(mesh, t, settings.triangle_scale, rng.next_2d());
            candidates.push(Candidate {
                instance: i as u32,
                class: triangle_class(mesh, t),
                position_object: p,
                normal_object: n,
                position_world: inst.world_from_object.transform_point3(p),
            });
        }
    }
    candidates
}

impl VslSet {
    /// Places VSLs on every instance of `scene` at its current time (§0.4.2). Instances
    /// without area get none; every other instance gets at least one.
    pub fn place(scene: &Scene, settings: &PlacementSettings) -> Self {
        let areas: Vec<Vec<f32>> = (0..scene.instances.len())
            .map(|i| world_triangle_areas(scene, i))
            .collect();
        let object_area: Vec<f64> = areas
            .iter()
            .map(|a| a.iter().map(|&x| x as f64).sum())
            .collect();
        let objects_with_area = object_area.iter().filter(|&&a| a > 0.0).count();
        let candidates = candidates(scene, settings, &areas, &object_area);
        let positions: Vec<Vec3> = candidates.iter().map(|c| c.position_world).collect();
        let objects: Vec<u32> = candidates.iter().map(|c| c.instance).collect();
        let target = (settings.vsl_count as usize).max(objects_with_area);
        let keep = remove_closest(&positions, &objects, target).keep;
        let mut kept: Vec<Candidate> = candidates
            .into_iter()
            .zip(keep)
            .filter_map(|(c, k)| k.then_some(c))
            .collect();
        kept.sort_by_key(|c| c.instance); // stable: placement order within an object
        let mut set = Self::indexed(scene, &kept, settings.oriented_cells);
        set.assign_areas(scene, settings, &areas, &object_area);
        set
    }

    /// The set of VSLs `kept` (sorted by instance, areas 0) with its per-object and
    /// per-class nearest-VSL indices and each triangle's owner. Without `oriented`
    /// cells every triangle and VSL is of one class, 0: the class index is then the
    /// object's, and a cell the paper's.
    fn indexed(scene: &Scene, kept: &[Candidate], oriented: bool) -> Self {
        let class_of = |c: u8| if oriented { c } else { 0 };
        let mut first = vec![0u32; scene.instances.len() + 1];
        for c in kept {
            first[c.instance as usize + 1] += 1;
        }
        for i in 0..scene.instances.len() {
            first[i + 1] += first[i];
        }
        let vsls: Vec<Vsl> = kept
            .iter()
            .map(|c| Vsl {
                instance: InstanceId(c.instance),
                position_object: c.position_object,
                normal_object: c.normal_object,
                area_m2: 0.0,
            })
            .collect();
        let mesh_of = |i: usize| &scene.meshes[scene.instances[i].mesh.index()];
        // Any-class indices answer only the rare point whose class has no VSL on its
        // object (and `nearest`): a k-d tree alone (an empty box builds no grid).
        let trees = object_indices(&vsls, &first, |_| Aabb::EMPTY);
        let classes: Vec<u8> = kept.iter().map(|c| class_of(c.class)).collect();
        let triangle_class: Vec<Vec<u8>> = (0..scene.instances.len())
            .map(|i| {
                let mesh = mesh_of(i);
                (0..mesh.triangle_count())
                    .map(|t| class_of(triangle_class(mesh, t)))
                    .collect()
            })
            .collect();
        // A class's grid spans the triangles of that class only: its queries come from
        // them, and a box around the whole object would list far more candidates per
        // cell (a wall's VSLs seen from across the room).
        let class_bounds: Vec<[Aabb; CLASSES]> = (0..scene.instances.len())
            .map(|i| {
                let mesh = mesh_of(i);
                let mut b = [Aabb::EMPTY; CLASSES];
                for (t, &c) in triangle_class[i].iter().enumerate() {
                    for p in mesh.triangle(t) {
                        b[c as usize] = b[c as usize].grow(p);
                    }
                }
                b
            })
            .collect();
        let class_trees = class_indices(&vsls, &classes, &first, |i, c| class_bounds[i][c]);
        let triangle_owner: Vec<Vec<u32>> = (0..scene.instances.len())
            .map(|i| triangle_owners(mesh_of(i), &triangle_class[i], &class_trees[i]))
            .collect();
        Self {
            vsls,
            first,
            classes,
            trees,
            class_trees,
            triangle_class,
            triangle_owner,
        }
    }

    /// A_s of every VSL: the object's area split among its cells by assigning uniform
    /// samples with the photons' rule (`areas`: each instance's world triangle areas,
    /// `object_area` their sums).
    fn assign_areas(
        &mut self,
        scene: &Scene,
        settings: &PlacementSettings,
        areas: &[Vec<f32>],
        object_area: &[f64],
    ) {
        let set = self;
        for (i, inst) in scene.instances.iter().enumerate() {
            let (lo, hi) = (set.first[i] as usize, set.first[i + 1] as usize);
            let Some(table) = AliasTable::new(&areas[i]) else {
                continue;
            };
            let mesh = &scene.meshes[inst.mesh.index()];
            let samples = 256 * (hi - lo);
            // In chunks with their own PCG streams: the same counts whatever the threads.
            const CHUNK: usize = 4096;
            let set_ref = &*set;
            let counts = (0..samples.div_ceil(CHUNK))
                .into_par_iter()
                .map(|k| {
                    let mut rng = Pcg32::new(
                        mix64(settings.seed ^ 0xa_5a4e),
                        ((i as u64) << 32) | k as u64,
                    );
                    let mut counts = vec![0u32; hi - lo];
                    for _ in 0..CHUNK.min(samples - k * CHUNK) {
                        let (t, _) = table.sample(rng.next_1d());
                        let (p, _) = point_on_triangle(mesh, t, 1.0, rng.next_2d());
                        if let Some(g) = set_ref.nearest_on(InstanceId(i as u32), t as u32, p) {
                            counts[g as usize - lo] += 1;
                        }
                    }
                    counts
                })
                .reduce(
                    || vec![0u32; hi - lo],
                    |mut a, b| {
                        a.iter_mut().zip(b).for_each(|(x, y)| *x += y);
                        a
                    },
                );
            for (k, c) in counts.iter().enumerate() {
                // At least one sample's worth, so no VSL claims zero area.
                set.vsls[lo + k].area_m2 =
                    (object_area[i] * (*c).max(1) as f64 / samples as f64) as f32;
            }
        }
    }

    /// The VSLs, grouped by instance.
    pub fn vsls(&self) -> &[Vsl] {
        &self.vsls
    }

    /// The orientation class of VSL `g` (module doc).
    pub fn class_of(&self, g: usize) -> u8 {
        self.classes[g]
    }

    /// Number of VSLs.
    pub fn len(&self) -> usize {
        self.vsls.len()
    }

    /// True when there is none.
    pub fn is_empty(&self) -> bool {
        self.vsls.is_empty()
    }

    /// Number of VSLs attached to `instance`.
    pub fn count_on(&self, instance: InstanceId) -> usize {
        let i = instance.index();
        (self.first[i + 1] - self.first[i]) as usize
    }

    /// The VSL of `instance` nearest to `position_object` (object space) whatever its
    /// orientation class, by the per-object index; `None` if the instance has no VSL.
    /// Photons and gather hits use [`VslSet::nearest_on`].
    #[inline]
    pub fn nearest(&self, instance: InstanceId, position_object: Vec3) -> Option<u32> {
        self.trees
            .get(instance.index())?
            .nearest(position_object)
            .map(|(g, _)| g)
    }

    /// The VSL whose cell holds `position_object`, a point of triangle `triangle` of
    /// `instance`'s mesh (module doc: the nearest VSL of the triangle's orientation
    /// class, else the nearest of any class). Found without a search when one cell
    /// holds the whole triangle (most triangles of finely tessellated objects; this
    /// runs per photon impact). For a set built without a scene it is
    /// [`VslSet::nearest`].
    #[inline]
    pub fn nearest_on(
        &self,
        instance: InstanceId,
        triangle: u32,
        position_object: Vec3,
    ) -> Option<u32> {
        let i = instance.index();
        if let Some(&owner) = self
            .triangle_owner
            .get(i)
            .and_then(|t| t.get(triangle as usize))
            && owner != NO_OWNER
        {
            return Some(owner);
        }
        if let Some(&class) = self
            .triangle_class
            .get(i)
            .and_then(|t| t.get(triangle as usize))
            && let Some((g, _)) = self.class_trees[i][class as usize].nearest(position_object)
        {
            return Some(g);
        }
        self.nearest(instance, position_object)
    }

    /// World positions and unit normals of every VSL for the scene's current transforms.
    pub fn world_frames(&self, scene: &Scene) -> (Vec<Vec3>, Vec<Vec3>) {
        self.vsls
            .iter()
            .map(|v| {
                let m = &scene.instances[v.instance.index()].world_from_object;
                (
                    m.transform_point3(v.position_object),
                    transform_normal(m, v.normal_object),
                )
            })
            .unzip()
    }
}

/// Result of [`remove_closest`].
#[derive(Clone, Debug, PartialEq)]
pub struct Removal {
    /// `keep[i]`: point `i` survived.
    pub keep: Vec<bool>,
    /// Removed points in removal order.
    pub order: Vec<usize>,
}

/// Two nearest alive neighbours of `i` by linear scan: (d1², n1, d2², n2).
fn two_nearest(points: &[Vec3], alive: &[bool], i: usize) -> (f32, u32, f32, u32) {
    let (mut d1, mut n1, mut d2, mut n2) = (f32::INFINITY, u32::MAX, f32::INFINITY, u32::MAX);
    for (j, p) in points.iter().enumerate() {
        if j == i || !alive[j] {
            continue;
        }
        let d = p.distance_squared(points[i]);
        if d < d1 {
            (d2, n2) = (d1, n1);
            (d1, n1) = (d, j as u32);
        } else if d < d2 {
            (d2, n2) = (d, j as u32);
        }
    }
    (d1, n1, d2, n2)
}

/// Algorithm 1: removes points until `target` remain (or no removable point is left),
/// each time the one with the smallest `(d_min1, d_min2)`; a point that is the last of
/// its object (`objects[i]`) is never removed. Ties go to the lower index.
pub fn remove_closest(points: &[Vec3], objects: &[u32], target: usize) -> Removal {
    let n = points.len();
    assert_eq!(n, objects.len(), "one object id per point");
    let mut alive = vec![true; n];
    let mut per_object = std::collections::HashMap::<u32, usize>::new();
    for &o in objects {
        *per_object.entry(o).or_default() += 1;
    }
    let mut near: Vec<(f32, u32, f32, u32)> =
        (0..n).map(|i| two_nearest(points, &alive, i)).collect();
    let mut remaining = n;
    let mut order = Vec::new();
    while remaining > target {
        let mut best: Option<usize> = None;
        for i in 0..n {
            if !alive[i] || per_object[&objects[i]] <= 1 {
                continue;
            }
            let better = match best {
                None => true,
                Some(b) => (near[i].0, near[i].2) < (near[b].0, near[b].2),
            };
            if better {
                best = Some(i);
            }
        }
        let Some(k) = best else { break };
        alive[k] = false;
        remaining -= 1;
        order.push(k);
        *per_object.get_mut(&objects[k]).expect("counted") -= 1;
        for i in 0..n {
            if alive[i] && (near[i].1 == k as u32 || near[i].3 == k as u32) {
                near[i] = two_nearest(points, &alive, i);
            }
        }
    }
    Removal { keep: alive, order }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn whole_triangle_owners_give_the_nearest_vsl() {
        let scene = illume_scene::builtin::load("cornell-spot").unwrap();
        let set = VslSet::place(
            &scene,
            &PlacementSettings {
                vsl_count: 60,
                oversampling: 0.1,
                triangle_scale: 0.9,
                seed: 5,
                oriented_cells: true,
            },
        );
        let mut rng = Pcg32::new(6, 7);
        let mut owned = 0;
        for (i, inst) in scene.instances.iter().enumerate() {
            let id = InstanceId(i as u32);
            let mesh = &scene.meshes[inst.mesh.index()];
            for t in 0..mesh.triangle_count() {
                owned += usize::from(set.triangle_owner[i][t] != NO_OWNER);
                let [a, b, c] = mesh.triangle(t);
                for _ in 0..200 {
                    let u = uniform_triangle(rng.next_2d());
                    let p = a * (1.0 - u.x - u.y) + b * u.x + c * u.y;
                    // The rule by brute force: nearest of the triangle's class, else of
                    // any class; ties to the lowest id.
                    let class = triangle_class(mesh, t);
                    let on = |want: Option<u8>| {
                        set.vsls()
                            .iter()
                            .enumerate()
                            .filter(|(g, v)| {
                                v.instance == id && want.is_none_or(|c| set.classes[*g] == c)
                            })
                            .map(|(g, v)| (v.position_object.distance_squared(p), g as u32))
                            .min_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)))
                            .map(|(_, g)| g)
                    };
                    let expected = on(Some(class)).or_else(|| on(None));
                    assert_eq!(
                        set.nearest_on(id, t as u32, p),
                        expected,
                        "instance {i} triangle {t}"
                    );
                }
            }
        }
        assert!(owned > 0, "some triangle lies inside one VSL's cell");
    }

    #[test]
    fn orientation_classes_are_dominant_axis_and_sign() {
        assert_eq!(orientation_class(Vec3::new(0.9, 0.1, -0.3)), 0);
        assert_eq!(orientation_class(Vec3::new(-0.9, 0.1, -0.3)), 1);
        assert_eq!(orientation_class(Vec3::Y), 2);
        assert_eq!(orientation_class(Vec3::new(0.1, -2.0, 0.0)), 3);
        assert_eq!(orientation_class(Vec3::new(0.0, 0.5, 0.7)), 4);
        assert_eq!(orientation_class(Vec3::NEG_Z), 5);
    }
}
