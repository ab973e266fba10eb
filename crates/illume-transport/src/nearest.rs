//! Exact nearest-point queries over a fixed set of points, for any technique that
//! assigns surface points to their nearest representative: photon streaming's photon
//! impacts to VSLs, and (to come) radiance-cache records and selective photon tracing's
//! mesh elements.
//!
//! * [`NearestIndex`] — O(1) queries for points inside a box (an object's bounds)
//!   through a grid of per-cell candidate lists, with a k-d tree for the rest.
//! * [`KdTree`] — a static 3-d tree, O(log n) queries anywhere.
//!
//! Both return the nearest point's id and squared distance; of equally near points, the
//! lowest id (so results do not depend on build order).

use illume_core::{Aabb, Vec3, Vec4};

/// Exact nearest-point queries in O(1) for points inside a box (the object's bounds): a
/// uniform grid whose every cell lists the only points that can be nearest to any
/// position in it (those whose distance to the cell is at most the smallest distance,
/// over all points, to the cell's farthest corner). Outside the box, or with too many
/// points for the grid, a k-d tree answers.
///
/// Cells are small (about `CELLS_PER_POINT` per point), so a cell lists a handful of
/// points, stored four to a `CandidateChunk` and measured four at once; this lookup
/// runs once per photon impact.
#[derive(Clone, Debug, Default)]
pub struct NearestIndex {
    kd: KdTree,
    grid: Option<CandidateGrid>,
}

#[derive(Clone, Debug)]
struct CandidateGrid {
    bounds: Aabb,
    res: [u32; 3],
    inv_cell: Vec3,
    /// Chunks of cell `c` are `chunks[offsets[c]..offsets[c + 1]]`.
    offsets: Vec<u32>,
    chunks: Vec<CandidateChunk>,
}

/// Up to four candidate points as structure of arrays (one 64-byte line); unused lanes
/// lie at infinity with id `u32::MAX`, so they never win.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
struct CandidateChunk {
    x: [f32; 4],
    y: [f32; 4],
    z: [f32; 4],
    /// Point ids as `f32` bit patterns (moved through lane selects untouched).
    id_bits: [f32; 4],
}

/// Largest point count that gets a grid (its build costs cells × points).
const GRID_MAX_POINTS: usize = 4096;

/// Grid cells per indexed point. Higher: fewer candidates per cell (faster queries) at
/// the cost of memory and build time (cells × points distance tests). With 100 VSLs,
/// 8 cells a point left ~10 candidates a cell and 64 about 3 (on the benchmark scenes).
const CELLS_PER_POINT: usize = 64;

/// Bound on cells × points of a grid build (a few tens of milliseconds).
const GRID_BUILD_BUDGET: usize = 1 << 25;

impl NearestIndex {
    /// Index over `(point, id)` pairs for queries mostly inside `bounds`.
    pub fn new(items: Vec<(Vec3, u32)>, bounds: Aabb) -> Self {
        let grid = (!items.is_empty() && items.len() <= GRID_MAX_POINTS && !bounds.is_empty())
            .then(|| CandidateGrid::new(&items, bounds));
        Self {
            kd: KdTree::new(items),
            grid,
        }
    }

    /// The id of the point nearest to `q` and its squared distance; of equally near
    /// points, the lowest id.
    #[inline]
    pub fn nearest(&self, q: Vec3) -> Option<(u32, f32)> {
        if let Some(g) = &self.grid
            && g.bounds.contains(q)
        {
            let c = ((q - g.bounds.min) * g.inv_cell)
                .as_uvec3()
                .min(illume_core::UVec3::from(g.res) - 1);
            let cell = ((c.z * g.res[1] + c.y) * g.res[0] + c.x) as usize;
            let chunks = &g.chunks[g.offsets[cell] as usize..g.offsets[cell + 1] as usize];
            let (qx, qy, qz) = (Vec4::splat(q.x), Vec4::splat(q.y), Vec4::splat(q.z));
            let mut best_d = Vec4::INFINITY;
            let mut best_id = Vec4::splat(f32::from_bits(u32::MAX));
            // Each lane sees its candidates in increasing id order, so a strict `<`
            // keeps the lowest id of a tie within a lane; lanes are merged below.
            for ch in chunks {
                let dx = Vec4::from_array(ch.x) - qx;
                let dy = Vec4::from_array(ch.y) - qy;
                let dz = Vec4::from_array(ch.z) - qz;
                // Same operations, in the same order, as `Vec3::distance_squared`.
                let d = dx * dx + dy * dy + dz * dz;
                let closer = d.cmplt(best_d);
                best_d = Vec4::select(closer, d, best_d);
                best_id = Vec4::select(closer, Vec4::from_array(ch.id_bits), best_id);
            }
            // Lexicographic (distance, id) minimum of the lanes without branches: squared
            // distances are non-negative, so their bit patterns order like the values.
            let (d, id) = (best_d.to_array(), best_id.to_array());
            let key = |l: usize| (u64::from(d[l].to_bits()) << 32) | u64::from(id[l].to_bits());
            let k = key(0).min(key(1)).min(key(2).min(key(3)));
            let best = (k as u32, f32::from_bits((k >> 32) as u32));
            return Some(best);
        }
        self.kd.nearest(q)
    }

    /// [`KdTree::two_nearest`] over the same points.
    pub fn two_nearest(&self, q: Vec3) -> Option<(u32, f32, f32)> {
        self.kd.two_nearest(q)
    }
}

impl CandidateGrid {
    fn new(items: &[(Vec3, u32)], bounds: Aabb) -> Self {
        let e = bounds.extent();
        let pad = 1e-4 * (1.0 + e.max_element());
        let bounds = Aabb::new(bounds.min - pad, bounds.max + pad);
        let e = bounds.extent();
        let cells_wanted = (CELLS_PER_POINT * items.len())
            .min(GRID_BUILD_BUDGET / items.len())
            .clamp(64, 1 << 18) as f32;
        let cell = (e.x * e.y * e.z / cells_wanted)
            .cbrt()
            .max(e.max_element() / 64.0);
        let res = [0, 1, 2].map(|a| ((e[a] / cell).ceil() as u32).clamp(1, 64));
        let size = Vec3::new(
            e.x / res[0] as f32,
            e.y / res[1] as f32,
            e.z / res[2] as f32,
        );
        let mut items = items.to_vec();
        items.sort_by_key(|&(_, id)| id); // lanes rely on increasing ids
        let mut offsets = vec![0u32];
        let mut chunks = Vec::new();
        let mut cell_items = Vec::new();
        for z in 0..res[2] {
            for y in 0..res[1] {
                for x in 0..res[0] {
                    let lo = bounds.min + size * Vec3::new(x as f32, y as f32, z as f32);
                    let hi = lo + size;
                    let far2 = |p: Vec3| (p - lo).abs().max((p - hi).abs()).length_squared();
                    let near2 = |p: Vec3| (p.clamp(lo, hi) - p).length_squared();
                    let bound = items
                        .iter()
                        .map(|(p, _)| far2(*p))
                        .fold(f32::INFINITY, f32::min);
                    // A relative margin covers rounding in the distances.
                    let bound = bound * (1.0 + 1e-5) + 1e-12;
                    cell_items.clear();
                    cell_items.extend(items.iter().filter(|(p, _)| near2(*p) <= bound));
                    chunks.extend(cell_items.chunks(4).map(|four| {
                        let mut ch = CandidateChunk {
                            x: [f32::INFINITY; 4],
                            y: [f32::INFINITY; 4],
                            z: [f32::INFINITY; 4],
                            id_bits: [f32::from_bits(u32::MAX); 4],
                        };
                        for (lane, (p, id)) in four.iter().enumerate() {
                            (ch.x[lane], ch.y[lane], ch.z[lane]) = (p.x, p.y, p.z);
                            ch.id_bits[lane] = f32::from_bits(*id);
                        }
                        ch
                    }));
                    offsets.push(chunks.len() as u32);
                }
            }
        }
        Self {
            bounds,
            res,
            inv_cell: Vec3::ONE / size,
            offsets,
            chunks,
        }
    }
}

/// A static 3-d tree over points (implicit: the median of each range is the node).
#[derive(Clone, Debug, Default)]
pub struct KdTree {
    points: Vec<Vec3>,
    ids: Vec<u32>,
    axes: Vec<u8>,
}

impl KdTree {
    /// Builds the tree over `(point, id)` pairs.
    pub fn new(mut items: Vec<(Vec3, u32)>) -> Self {
        let mut axes = vec![0u8; items.len()];
        build(&mut items, &mut axes);
        let (points, ids) = items.into_iter().unzip();
        Self { points, ids, axes }
    }

    /// The id of the point nearest to `q` and its squared distance.
    #[inline]
    pub fn nearest(&self, q: Vec3) -> Option<(u32, f32)> {
        if self.points.is_empty() {
            return None;
        }
        let mut best = Nearest([(0, f32::INFINITY)]);
        self.visit(0, self.points.len(), q, &mut best);
        let [(i, d)] = best.0;
        Some((self.ids[i], d))
    }

    /// The id of the point nearest to `q` (of equally near points, the lowest id), its
    /// squared distance, and the squared distance of the second nearest (∞ when there
    /// is one point).
    pub fn two_nearest(&self, q: Vec3) -> Option<(u32, f32, f32)> {
        if self.points.is_empty() {
            return None;
        }
        let mut best = Nearest([(0, f32::INFINITY); 2]);
        self.visit(0, self.points.len(), q, &mut best);
        let [(i, d1), (_, d2)] = best.0;
        Some((self.ids[i], d1, d2))
    }

    /// Offers the points of `lo..hi` to `best`, near side first, skipping a far side
    /// that lies beyond `best`'s radius.
    fn visit<const K: usize>(&self, lo: usize, hi: usize, q: Vec3, best: &mut Nearest<K>) {
        if lo >= hi {
            return;
        }
        let mid = lo + (hi - lo) / 2;
        let p = self.points[mid];
        best.offer(mid, p.distance_squared(q), &self.ids);
        let axis = self.axes[mid] as usize;
        let diff = q[axis] - p[axis];
        let (near, far) = if diff < 0.0 {
            ((lo, mid), (mid + 1, hi))
        } else {
            ((mid + 1, hi), (lo, mid))
        };
        self.visit(near.0, near.1, q, best);
        if diff * diff <= best.radius() {
            self.visit(far.0, far.1, q, best);
        }
    }
}

/// The K nearest points found so far, nearest first, as (index into the tree's arrays,
/// squared distance); of equally near points the lowest id comes first.
struct Nearest<const K: usize>([(usize, f32); K]);

impl<const K: usize> Nearest<K> {
    #[inline]
    fn offer(&mut self, i: usize, d: f32, ids: &[u32]) {
        let b = &mut self.0;
        if d > b[K - 1].1 || (d == b[K - 1].1 && ids[i] >= ids[b[K - 1].0]) {
            return;
        }
        let mut k = K - 1;
        while k > 0 && (d < b[k - 1].1 || (d == b[k - 1].1 && ids[i] < ids[b[k - 1].0])) {
            b[k] = b[k - 1];
            k -= 1;
        }
        b[k] = (i, d);
    }

    /// The squared distance within which points can still enter.
    #[inline]
    fn radius(&self) -> f32 {
        self.0[K - 1].1
    }
}

fn build(items: &mut [(Vec3, u32)], axes: &mut [u8]) {
    if items.len() <= 1 {
        return;
    }
    let bounds = illume_core::Aabb::from_points(items.iter().map(|i| i.0));
    let e = bounds.extent();
    let axis = if e.x >= e.y && e.x >= e.z {
        0
    } else if e.y >= e.z {
        1
    } else {
        2
    };
    let mid = items.len() / 2;
    items.select_nth_unstable_by(mid, |a, b| a.0[axis].total_cmp(&b.0[axis]));
    axes[mid] = axis as u8;
    let (left, right) = items.split_at_mut(mid);
    let (left_axes, right_axes) = axes.split_at_mut(mid);
    build(left, left_axes);
    build(&mut right[1..], &mut right_axes[1..]);
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::sampling::{Pcg32, SampleStream};

    #[test]
    fn two_nearest_matches_linear_scan() {
        let mut rng = Pcg32::new(5, 6);
        let pts: Vec<(Vec3, u32)> = (0..200)
            .map(|i| (Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d()), i))
            .collect();
        let tree = KdTree::new(pts.clone());
        for _ in 0..500 {
            let q = Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d()) * 1.4 - 0.2;
            let mut d: Vec<(f32, u32)> = pts
                .iter()
                .map(|(p, i)| (p.distance_squared(q), *i))
                .collect();
            d.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            assert_eq!(tree.two_nearest(q), Some((d[0].1, d[0].0, d[1].0)));
        }
        assert_eq!(
            KdTree::new(vec![(Vec3::ONE, 7)]).two_nearest(Vec3::ZERO),
            Some((7, 3.0, f32::INFINITY))
        );
        assert_eq!(KdTree::new(Vec::new()).two_nearest(Vec3::ZERO), None);
    }

    #[test]
    fn kd_tree_matches_linear_scan() {
        let mut rng = Pcg32::new(3, 4);
        let pts: Vec<(Vec3, u32)> = (0..300)
            .map(|i| {
                (
                    Vec3::new(rng.next_1d(), rng.next_1d() * 0.1, rng.next_1d() * 3.0),
                    i,
                )
            })
            .collect();
        let tree = KdTree::new(pts.clone());
        for _ in 0..2000 {
            let q = Vec3::new(
                rng.next_1d() * 1.4 - 0.2,
                rng.next_1d() - 0.5,
                rng.next_1d() * 3.5 - 0.2,
            );
            let (id, d) = tree.nearest(q).unwrap();
            let best = pts
                .iter()
                .map(|(p, _)| p.distance_squared(q))
                .fold(f32::INFINITY, f32::min);
            assert_eq!(d, best);
            assert_eq!(pts[id as usize].0.distance_squared(q), best);
        }
        assert!(KdTree::new(vec![]).nearest(Vec3::ZERO).is_none());
    }

    #[test]
    fn candidate_grid_matches_linear_scan_inside_and_outside_its_box() {
        let mut rng = Pcg32::new(8, 9);
        // Points on two faces of a box (surface-like, as VSLs are).
        let pts: Vec<(Vec3, u32)> = (0..150)
            .map(|i| {
                let (a, b) = (rng.next_1d() * 2.0 - 1.0, rng.next_1d() * 2.0);
                (
                    if i % 2 == 0 {
                        Vec3::new(a, 0.0, b - 1.0)
                    } else {
                        Vec3::new(-1.0, b, a)
                    },
                    i,
                )
            })
            .collect();
        let bounds = Aabb::new(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 2.0, 1.0));
        let index = NearestIndex::new(pts.clone(), bounds);
        assert!(index.grid.is_some());
        for k in 0..20_000 {
            let spread = if k % 4 == 0 { 3.0 } else { 1.0 }; // some queries outside the box
            let q = Vec3::new(
                (rng.next_1d() * 2.0 - 1.0) * spread,
                rng.next_1d() * 2.0 * spread,
                (rng.next_1d() * 2.0 - 1.0) * spread,
            );
            let (id, d) = index.nearest(q).unwrap();
            let best = pts
                .iter()
                .map(|(p, _)| p.distance_squared(q))
                .fold(f32::INFINITY, f32::min);
            assert_eq!(d, best, "query {q}");
            assert_eq!(pts[id as usize].0.distance_squared(q), best);
        }
    }
}
