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

/// A primitive's box during the build, kept in the build's order (so binning reads
/// memory in sequence rather than through the permutation).
#[derive(Clone, Copy)]
struct Ref {
    lo: Vec3A,
    hi: Vec3A,
}

impl Ref {
    /// The centroid doubled (min + max): the factor 2 does not change any split.
    #[inline(always)]
    fn centroid(&self) -> Vec3A {
        self.lo + self.hi
    }
}

/// Box bounds and centroid bounds of a set of references, with its count.
#[derive(Clone, Copy)]
struct Bin {
    lo: Vec3A,
    hi: Vec3A,
    clo: Vec3A,
    chi: Vec3A,
    count: u32,
}

impl Default for Bin {
    fn default() -> Self {
        Self {
            lo: Vec3A::splat(f32::INFINITY),
            hi: Vec3A::splat(f32::NEG_INFINITY),
            clo: Vec3A::splat(f32::INFINITY),
            chi: Vec3A::splat(f32::NEG_INFINITY),
            count: 0,
        }
    }
}

impl Bin {
    #[inline(always)]
    fn add(&mut self, r: &Ref, c: Vec3A) {
        self.lo = self.lo.min(r.lo);
        self.hi = self.hi.max(r.hi);
        self.clo = self.clo.min(c);
        self.chi = self.chi.max(c);
        self.count += 1;
    }

    #[inline(always)]
    fn merge(&mut self, o: &Bin) {
        self.lo = self.lo.min(o.lo);
        self.hi = self.hi.max(o.hi);
        self.clo = self.clo.min(o.clo);
        self.chi = self.chi.max(o.chi);
        self.count += o.count;
    }

    fn of(refs: &[Ref]) -> Bin {
        let mut b = Bin::default();
        for r in refs {
            b.add(r, r.centroid());
        }
        b
    }

    #[inline(always)]
    fn bounds(&self) -> Aabb {
        Aabb::new(self.lo.into(), self.hi.into())
    }
}

/// Builds a binary BVH over `boxes` (none may be empty). An empty input gives an empty tree.
/// `owner[i]` names the primitive box `i` belongs to (pre-split references of one
/// triangle share it; empty: every box is its own): a node whose boxes belong to few
/// enough primitives becomes a leaf of those primitives when that is cheaper than a split.
///
/// Binned SAH (Wald 2007): each node bins its references' centroids on all three axes in
/// one pass over its references, kept contiguous in build order; the bins also give the
/// children's box and centroid bounds, so a node reads its references once to bin them
/// and once to partition them. Below a node of [`PARALLEL_MIN`] or more references the
/// two subtrees are built in parallel (rayon) into disjoint slots of one node array.
pub(crate) fn build_binary(boxes: &[Aabb], owner: &[u32], params: BuildParams) -> BinaryBvh {
    let n = boxes.len();
    let mut order: Vec<u32> = (0..n as u32).collect();
    if n == 0 {
        return BinaryBvh {
            nodes: Vec::new(),
            order,
        };
    }
    let mut refs: Vec<Ref> = boxes
        .iter()
        .map(|b| Ref {
            lo: b.min.into(),
            hi: b.max.into(),
        })
        .collect();
    let all = Bin::of(&refs);
    let ctx = Context { owner, params };
    // A subtree over c references has at most 2c − 1 nodes: each subtree gets that many
    // slots, so parallel subtrees write disjoint parts of one array. Slots a subtree
    // leaves unused stay empty interior-looking nodes no link points to.
    let mut nodes = vec![leaf(Aabb::EMPTY, 0, 0); 2 * n - 1];
    let (root, rest) = nodes.split_at_mut(1);
    ctx.subtree(Span {
        refs: &mut refs,
        order: &mut order,
        base: 0,
        depth: 0,
        known: Some(all),
        root: &mut root[0],
        rest,
        rest_base: 1,
    });
    BinaryBvh { nodes, order }
}

/// Ranges of at least this many references split their two halves between threads.
const PARALLEL_MIN: usize = 4096;

/// What a node becomes.
enum Decision {
    Leaf,
    /// Children `[..mid]` and `[mid..]` of the (partitioned) range, with their bins when
    /// the split gives them.
    Split {
        mid: usize,
        children: Option<(Bin, Bin)>,
    },
}

/// The build's inputs shared by every node.
struct Context<'a> {
    owner: &'a [u32],
    params: BuildParams,
}

/// A subtree to build: references `refs` (the first is number `base` of the build order;
/// `order` alike) at `depth`, with their bins when known; its root goes into `root`, its
/// other nodes into `rest` (2·len − 2 slots, the first at index `rest_base` of the whole
/// node array).
struct Span<'a> {
    refs: &'a mut [Ref],
    order: &'a mut [u32],
    base: usize,
    depth: u32,
    known: Option<Bin>,
    root: &'a mut BinaryNode,
    rest: &'a mut [BinaryNode],
    rest_base: usize,
}

impl Context<'_> {
    /// Builds `span`. Large spans build their two halves in parallel (rayon); the tree is
    /// the same whatever the thread count.
    fn subtree(&self, span: Span<'_>) {
        if span.refs.len() < PARALLEL_MIN {
            return self.sequential(span);
        }
        let Span {
            refs,
            order,
            base,
            depth,
            known,
            root,
            rest,
            rest_base,
        } = span;
        let all = known.unwrap_or_else(|| Bin::of(refs));
        let mut scratch = [[Bin::default(); BINS]; 3];
        let mut owners = Vec::new();
        let decision = self.decide(refs, order, depth, &all, &mut scratch, &mut owners);
        let Decision::Split { mid, children } = decision else {
            *root = leaf(all.bounds(), base, refs.len());
            return;
        };
        *root = BinaryNode {
            bounds: all.bounds(),
            first: rest_base as u32,
            count: 0,
        };
        let (l, r) = children.map_or((None, None), |(l, r)| (Some(l), Some(r)));
        let (refs_l, refs_r) = refs.split_at_mut(mid);
        let (order_l, order_r) = order.split_at_mut(mid);
        // The children as a pair, then the left subtree's slots, then the right's.
        let (pair, rest) = rest.split_at_mut(2);
        let (rest_l, rest_r) = rest.split_at_mut(2 * mid - 2);
        let (root_l, root_r) = pair.split_at_mut(1);
        let left = Span {
            refs: refs_l,
            order: order_l,
            base,
            depth: depth + 1,
            known: l,
            root: &mut root_l[0],
            rest: rest_l,
            rest_base: rest_base + 2,
        };
        let right = Span {
            refs: refs_r,
            order: order_r,
            base: base + mid,
            depth: depth + 1,
            known: r,
            root: &mut root_r[0],
            rest: rest_r,
            rest_base: rest_base + 2 * mid,
        };
        rayon::join(|| self.subtree(left), || self.subtree(right));
    }

    /// [`Context::subtree`] on this thread.
    fn sequential(&self, span: Span<'_>) {
        let (refs, order, base, rest_base) = (span.refs, span.order, span.base, span.rest_base);
        let (root, rest) = (span.root, span.rest);
        let n = refs.len();
        // (slot in `rest`, None for the root; start, end, depth, bins when known)
        let mut work = vec![(None, 0usize, n, span.depth, span.known)];
        let mut next = 0usize;
        let mut owners: Vec<u32> = Vec::new();
        let mut scratch = [[Bin::default(); BINS]; 3];
        while let Some((slot, start, end, depth, known)) = work.pop() {
            let range = &mut refs[start..end];
            let all = known.unwrap_or_else(|| Bin::of(range));
            let decision = self.decide(
                range,
                &mut order[start..end],
                depth,
                &all,
                &mut scratch,
                &mut owners,
            );
            let node = match decision {
                Decision::Leaf => leaf(all.bounds(), base + start, end - start),
                Decision::Split { mid, children } => {
                    let left = next;
                    next += 2;
                    let (l, r) = children.map_or((None, None), |(l, r)| (Some(l), Some(r)));
                    work.push((Some(left + 1), start + mid, end, depth + 1, r));
                    work.push((Some(left), start, start + mid, depth + 1, l));
                    BinaryNode {
                        bounds: all.bounds(),
                        first: (rest_base + left) as u32,
                        count: 0,
                    }
                }
            };
            match slot {
                None => *root = node,
                Some(i) => rest[i] = node,
            }
        }
    }

    /// Decides a node over `range` (all of whose references `all` bins), partitioning the
    /// range (and `order` alike) when it splits.
    fn decide(
        &self,
        range: &mut [Ref],
        order: &mut [u32],
        depth: u32,
        all: &Bin,
        scratch: &mut [[Bin; BINS]; 3],
        owners: &mut Vec<u32>,
    ) -> Decision {
        let params = self.params;
        let count = range.len();
        if count <= 1 {
            return Decision::Leaf;
        }
        let bounds = all.bounds();
        let (cmin, cmax) = (all.clo, all.chi);
        let extent = cmax - cmin;
        // Primitives the node's boxes belong to (counted for small nodes only).
        let owned = if self.owner.is_empty() || count > 4 * params.max_leaf {
            count
        } else {
            owners.clear();
            owners.extend(order.iter().map(|&p| self.owner[p as usize]));
            owners.sort_unstable();
            owners.dedup();
            owners.len()
        };
        let split = if depth >= MEDIAN_DEPTH || extent.max_element() <= 0.0 {
            None
        } else {
            best_binned_split(
                range,
                cmin,
                extent,
                bounds.surface_area(),
                params,
                bins_for(count),
                scratch,
            )
        };
        match split {
            Some((axis, bin, cost, left, right)) => {
                if cost >= params.leaf_cost(owned as u32) && owned <= params.max_leaf {
                    return Decision::Leaf;
                }
                let nb = bins_for(count);
                let scale = nb as f32 / extent[axis];
                let left_count = partition(range, order, |r| {
                    bin_of(r.centroid()[axis], cmin[axis], scale, nb) <= bin
                });
                if left_count == 0 || left_count == count {
                    Decision::Split {
                        mid: count / 2,
                        children: None,
                    }
                } else {
                    Decision::Split {
                        mid: left_count,
                        children: Some((left, right)),
                    }
                }
            }
            None => {
                if owned <= params.max_leaf {
                    return Decision::Leaf;
                }
                // Object median along the widest centroid axis.
                let axis = extent.max_position();
                let mid = count / 2;
                let mut perm: Vec<u32> = (0..count as u32).collect();
                perm.select_nth_unstable_by(mid, |&a, &b| {
                    range[a as usize].centroid()[axis]
                        .total_cmp(&range[b as usize].centroid()[axis])
                });
                let moved_refs: Vec<Ref> = perm.iter().map(|&i| range[i as usize]).collect();
                let moved_order: Vec<u32> = perm.iter().map(|&i| order[i as usize]).collect();
                range.copy_from_slice(&moved_refs);
                order.copy_from_slice(&moved_order);
                Decision::Split {
                    mid,
                    children: None,
                }
            }
        }
    }
}

/// A leaf over references `first..first + count` of the build order.
fn leaf(bounds: Aabb, first: usize, count: usize) -> BinaryNode {
    BinaryNode {
        bounds,
        first: first as u32,
        count: count as u32,
    }
}

#[inline(always)]
fn bin_of(c: f32, cmin: f32, scale: f32, bins: usize) -> usize {
    (((c - cmin) * scale) as usize).min(bins - 1)
}

/// Bins for a node of `count` references: [`BINS`], or fewer for small nodes, whose
/// fixed cost (clearing and sweeping the bins) would otherwise dominate the build.
#[inline]
fn bins_for(count: usize) -> usize {
    count.clamp(4, BINS)
}

/// The best split as (axis, last bin of the left side, SAH cost in units of a primitive
/// test, left side's bins, right side's bins).
fn best_binned_split(
    refs: &[Ref],
    cmin: Vec3A,
    extent: Vec3A,
    parent_area: f32,
    params: BuildParams,
    nb: usize,
    all: &mut [[Bin; BINS]; 3],
) -> Option<(usize, usize, f32, Bin, Bin)> {
    // Axes without extent bin everything into bin 0 and are skipped below.
    let scale = Vec3A::select(
        extent.cmpgt(Vec3A::ZERO),
        Vec3A::splat(nb as f32) / extent,
        Vec3A::ZERO,
    );
    let [b0, b1, b2] = all;
    let (b0, b1, b2) = (&mut b0[..nb], &mut b1[..nb], &mut b2[..nb]);
    for b in b0.iter_mut().chain(b1.iter_mut()).chain(b2.iter_mut()) {
        *b = Bin::default();
    }
    for r in refs {
        let c = r.centroid();
        let t = (c - cmin) * scale;
        b0[(t.x as usize).min(nb - 1)].add(r, c);
        b1[(t.y as usize).min(nb - 1)].add(r, c);
        b2[(t.z as usize).min(nb - 1)].add(r, c);
    }
    let bins = [&all[0][..nb], &all[1][..nb], &all[2][..nb]];
    let mut best: Option<(usize, usize, f32)> = None;
    for (axis, bins) in bins.iter().enumerate() {
        if extent[axis] <= 0.0 {
            continue;
        }
        // Sweep from the right: area·count of bins (i+1)..BINS.
        let mut right_cost = [0.0f32; BINS];
        let mut acc = Bin::default();
        for i in (1..nb).rev() {
            acc.merge(&bins[i]);
            right_cost[i - 1] = acc.bounds().surface_area() * params.leaf_cost(acc.count);
        }
        let mut acc = Bin::default();
        for i in 0..nb - 1 {
            acc.merge(&bins[i]);
            if acc.count == 0 || acc.count as usize == refs.len() {
                continue;
            }
            let cost = params.traversal_cost
                + (acc.bounds().surface_area() * params.leaf_cost(acc.count) + right_cost[i])
                    / parent_area.max(f32::MIN_POSITIVE);
            if best.is_none_or(|(_, _, c)| cost < c) {
                best = Some((axis, i, cost));
            }
        }
    }
    best.map(|(axis, bin, cost)| {
        let mut left = Bin::default();
        let mut right = Bin::default();
        for (i, b) in bins[axis].iter().enumerate() {
            if i <= bin {
                left.merge(b);
            } else {
                right.merge(b);
            }
        }
        (axis, bin, cost, left, right)
    })
}

/// Reorders `refs` (and `order` alike) so those satisfying `left` come first; returns
/// their count.
fn partition(refs: &mut [Ref], order: &mut [u32], left: impl Fn(&Ref) -> bool) -> usize {
    let mut i = 0;
    let mut j = refs.len();
    while i < j {
        if left(&refs[i]) {
            i += 1;
        } else {
            j -= 1;
            refs.swap(i, j);
            order.swap(i, j);
        }
    }
    i
}
