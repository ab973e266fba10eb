//! Binned surface-area-heuristic (SAH) construction of a binary BVH over boxes, shared by
//! the mesh level (boxes of triangles) and the instance level (world boxes of instances).
//!
//! The binary tree is an intermediate form: [`crate::wide`] collapses it into the
//! eight-wide nodes that traversal uses.

use illume_core::{Aabb, Vec3A};

/// Number of SAH bins per axis.
const BINS: usize = 32;
/// Depth after which splits fall back to the object median, so the tree depth (and so the
/// traversal stack) stays bounded even for adversarial inputs.
const MEDIAN_DEPTH: u32 = 40;
/// Hard limit on the depth of the binary tree (object-median splits halve the count, so
/// `MEDIAN_DEPTH + 32` levels suffice for any `u32` primitive count).
pub(crate) const MAX_DEPTH: usize = MEDIAN_DEPTH as usize + 34;

/// Build parameters.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BuildParams {
    /// Cost of visiting an interior node, relative to one primitive test.
    pub traversal_cost: f32,
    /// Largest number of primitives in a leaf (larger sets are always split).
    pub max_leaf: usize,
    /// Primitives tested together (4 for triangle packets): a leaf of `n` costs
    /// `⌈n / block⌉` tests.
    pub block: u32,
}

impl BuildParams {
    /// Test cost of `n` primitives.
    #[inline]
    fn leaf_cost(&self, n: u32) -> f32 {
        n.div_ceil(self.block) as f32
    }
}

/// A node of the binary build tree: a leaf holds `count > 0` primitives starting at
/// `first` in the build's primitive order; an interior node's children are `left` and
/// `left + 1`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct BinaryNode {
    /// Bounds of everything below.
    pub bounds: Aabb,
    /// First child (interior) or first primitive (leaf).
    pub first: u32,
    /// Primitive count, 0 for an interior node.
    pub count: u32,
}

/// A binary BVH: `nodes[0]` is the root; `order[i]` is the input index of the `i`-th
/// primitive in leaf order.
pub(crate) struct BinaryBvh {
    /// Nodes, root first; children are allocated in adjacent pairs.
    pub nodes: Vec<BinaryNode>,
    /// Primitive permutation.
    pub order: Vec<u32>,
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    count: u32,
}

impl Default for Bin {
    fn default() -> Self {
        Self {
            bounds: Aabb::EMPTY,
            count: 0,
        }
    }
}

/// Builds a binary BVH over `boxes` (none may be empty). An empty input gives an empty tree.
pub(crate) fn build_binary(boxes: &[Aabb], params: BuildParams) -> BinaryBvh {
    let n = boxes.len();
    let mut order: Vec<u32> = (0..n as u32).collect();
    if n == 0 {
        return BinaryBvh {
            nodes: Vec::new(),
            order,
        };
    }
    // Centroids doubled (min + max): the factor 2 does not change any split.
    let centroids: Vec<Vec3A> = boxes.iter().map(|b| Vec3A::from(b.min + b.max)).collect();
    let mut nodes = Vec::with_capacity(2 * n);
    nodes.push(BinaryNode {
        bounds: Aabb::EMPTY,
        first: 0,
        count: n as u32,
    });
    // (node index, start, end, depth)
    let mut work = vec![(0usize, 0usize, n, 0u32)];
    while let Some((node, start, end, depth)) = work.pop() {
        let prims = &mut order[start..end];
        let bounds = prims
            .iter()
            .fold(Aabb::EMPTY, |b, &p| b.union(boxes[p as usize]));
        nodes[node].bounds = bounds;
        let count = prims.len();
        let make_leaf = |nodes: &mut Vec<BinaryNode>| {
            nodes[node].first = start as u32;
            nodes[node].count = count as u32;
        };
        if count <= 1 {
            make_leaf(&mut nodes);
            continue;
        }
        let (cmin, cmax) = prims.iter().fold(
            (Vec3A::splat(f32::INFINITY), Vec3A::splat(f32::NEG_INFINITY)),
            |(lo, hi), &p| {
                let c = centroids[p as usize];
                (lo.min(c), hi.max(c))
            },
        );
        let extent = cmax - cmin;
        let split = if depth >= MEDIAN_DEPTH || extent.max_element() <= 0.0 {
            None
        } else {
            best_binned_split(
                prims,
                boxes,
                &centroids,
                cmin,
                extent,
                bounds.surface_area(),
                params,
            )
        };
        let mid = match split {
            Some((axis, bin, cost)) => {
                if cost >= params.leaf_cost(count as u32) && count <= params.max_leaf {
                    make_leaf(&mut nodes);
                    continue;
                }
                let scale = BINS as f32 / extent[axis];
                let left_count = partition(prims, |p| {
                    bin_of(centroids[p as usize][axis], cmin[axis], scale) <= bin
                });
                if left_count == 0 || left_count == count {
                    count / 2
                } else {
                    left_count
                }
            }
            None => {
                if count <= params.max_leaf {
                    make_leaf(&mut nodes);
                    continue;
                }
                // Object median along the widest centroid axis.
                let axis = extent.max_position();
                let mid = count / 2;
                prims.select_nth_unstable_by(mid, |&a, &b| {
                    centroids[a as usize][axis].total_cmp(&centroids[b as usize][axis])
                });
                mid
            }
        };
        let left = nodes.len();
        nodes.push(BinaryNode {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        nodes.push(BinaryNode {
            bounds: Aabb::EMPTY,
            first: 0,
            count: 0,
        });
        nodes[node].first = left as u32;
        nodes[node].count = 0;
        work.push((left + 1, start + mid, end, depth + 1));
        work.push((left, start, start + mid, depth + 1));
    }
    BinaryBvh { nodes, order }
}

#[inline]
fn bin_of(c: f32, cmin: f32, scale: f32) -> usize {
    (((c - cmin) * scale) as usize).min(BINS - 1)
}

/// Best split as (axis, last bin of the left side, SAH cost in units of a primitive test).
fn best_binned_split(
    prims: &[u32],
    boxes: &[Aabb],
    centroids: &[Vec3A],
    cmin: Vec3A,
    extent: Vec3A,
    parent_area: f32,
    params: BuildParams,
) -> Option<(usize, usize, f32)> {
    let mut best: Option<(usize, usize, f32)> = None;
    for axis in 0..3 {
        if extent[axis] <= 0.0 {
            continue;
        }
        let scale = BINS as f32 / extent[axis];
        let mut bins = [Bin::default(); BINS];
        for &p in prims {
            let b = &mut bins[bin_of(centroids[p as usize][axis], cmin[axis], scale)];
            b.bounds = b.bounds.union(boxes[p as usize]);
            b.count += 1;
        }
        // Sweep from the right: area·count of bins (i+1)..BINS.
        let mut right_cost = [0.0f32; BINS];
        let mut acc = Bin::default();
        for i in (1..BINS).rev() {
            acc.bounds = acc.bounds.union(bins[i].bounds);
            acc.count += bins[i].count;
            right_cost[i - 1] = acc.bounds.surface_area() * params.leaf_cost(acc.count);
        }
        let mut acc = Bin::default();
        for i in 0..BINS - 1 {
            acc.bounds = acc.bounds.union(bins[i].bounds);
            acc.count += bins[i].count;
            if acc.count == 0 || acc.count as usize == prims.len() {
                continue;
            }
            let cost = params.traversal_cost
                + (acc.bounds.surface_area() * params.leaf_cost(acc.count) + right_cost[i])
                    / parent_area.max(f32::MIN_POSITIVE);
            if best.is_none_or(|(_, _, c)| cost < c) {
                best = Some((axis, i, cost));
            }
        }
    }
    best
}

/// Reorders `prims` so those satisfying `left` come first; returns their count.
fn partition(prims: &mut [u32], left: impl Fn(u32) -> bool) -> usize {
    let mut i = 0;
    let mut j = prims.len();
    while i < j {
        if left(prims[i]) {
            i += 1;
        } else {
            j -= 1;
            prims.swap(i, j);
        }
    }
    i
}
