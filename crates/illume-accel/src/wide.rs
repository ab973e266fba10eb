//! The eight-wide BVH that traversal walks: each 256-byte node (four cache lines) holds the
//! boxes of its up to eight children in structure-of-arrays form, so one ray is tested
//! against eight boxes at once (one 8-lane AVX2 test or two 4-lane ones, see
//! [`crate::kernel`]), and children are visited nearest first.
//!
//! A child reference ([`Item`]) is either an interior node or a leaf (a run of
//! primitives in the owner's primitive array), encoded in one `u32`.

use crate::build::{BinaryBvh, BinaryNode, MAX_DEPTH};
use crate::kernel::BoxKernel;
use illume_core::{Aabb, Vec3, Vec3A};
use std::cell::RefCell;

/// Children per node.
pub(crate) const WIDTH: usize = 8;
/// Largest primitive count of a leaf (fits the 4-bit count of [`Item`]).
pub(crate) const MAX_LEAF: usize = 16;
/// Traversal stack entries: each level of the tree pushes at most `WIDTH - 1`.
pub(crate) const STACK_SIZE: usize = (WIDTH - 1) * MAX_DEPTH + 1;
/// Relative widening of a box's exit distance that makes the slab test conservative
/// under rounding (2γ₃ with γₙ = nε/(1 − nε), ε = 2⁻²⁴; Ize 2013, pbrt-v4 §6.8.2).
pub(crate) const EXIT_SCALE: f32 =
    1.0 + 2.0 * 3.0 * f32::EPSILON * 0.5 / (1.0 - 3.0 * f32::EPSILON * 0.5);

/// A child reference: bit 31 set = leaf with primitives `first .. first + count`
/// (`first` in bits 4..31, `count − 1` in bits 0..4); clear = interior node index.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct Item(pub u32);

impl Item {
    const LEAF: u32 = 1 << 31;
    /// Largest primitive index a leaf can start at (one less than the 27-bit maximum,
    /// so that no leaf encodes as [`Item::NONE`], which also marks unused slots).
    pub const MAX_FIRST: u32 = (1 << 27) - 2;
    /// The reference to nothing (an empty tree's root).
    pub const NONE: Item = Item(u32::MAX);

    fn leaf(first: u32, count: u32) -> Self {
        assert!(
            first <= Self::MAX_FIRST,
            "BVH leaf starts at primitive {first}, beyond the limit {}",
            Self::MAX_FIRST
        );
        assert!(
            (1..=MAX_LEAF as u32).contains(&count),
            "BVH leaf of {count} primitives (1..={MAX_LEAF})"
        );
        Item(Self::LEAF | first << 4 | (count - 1))
    }

    /// True for a leaf.
    #[inline(always)]
    pub fn is_leaf(self) -> bool {
        self.0 & Self::LEAF != 0
    }

    /// Primitive range of a leaf.
    #[inline(always)]
    pub fn leaf_range(self) -> std::ops::Range<usize> {
        let first = ((self.0 & !Self::LEAF) >> 4) as usize;
        first..first + (self.0 & 15) as usize + 1
    }

    /// Node index of an interior node.
    #[inline(always)]
    pub fn node(self) -> usize {
        self.0 as usize
    }
}

/// Eight children's boxes (structure of arrays: `bounds[k][i]` is coordinate `k` of child
/// `i`, with `k` = min x, min y, min z, max x, max y, max z), references and masks. An
/// unused slot has an empty box (min = +∞, max = −∞) and mask 0, so it never hits.
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct WideNode {
    /// Child boxes, structure of arrays.
    pub bounds: [[f32; WIDTH]; 6],
    /// Child references ([`Item`] bits).
    pub children: [u32; WIDTH],
    /// Union of the instance masks below each child (all ones in a mesh BVH).
    pub masks: [u32; WIDTH],
}

const _: () = assert!(std::mem::size_of::<WideNode>() == 256);

impl WideNode {
    const EMPTY: WideNode = WideNode {
        bounds: [
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
            [f32::NEG_INFINITY; WIDTH],
        ],
        children: [u32::MAX; WIDTH],
        masks: [0; WIDTH],
    };

    /// Box of child slot `i`.
    pub fn child_bounds(&self, i: usize) -> Aabb {
        let b = &self.bounds;
        Aabb::new(
            Vec3::new(b[0][i], b[1][i], b[2][i]),
            Vec3::new(b[3][i], b[4][i], b[5][i]),
        )
    }

    /// Number of used slots (they come first).
    pub fn child_count(&self) -> usize {
        self.children
            .iter()
            .take_while(|&&c| c != Item::NONE.0)
            .count()
    }
}

/// An eight-wide BVH: the root reference, its box, and the nodes.
#[derive(Clone, Debug)]
pub(crate) struct WideBvh {
    /// Root reference ([`Item::NONE`] for an empty tree).
    pub root: Item,
    /// Box of everything.
    pub bounds: Aabb,
    /// Interior nodes.
    pub nodes: Vec<WideNode>,
}

impl WideBvh {
    /// Collapses a binary BVH; `leaf_mask(first, count)` gives a leaf's mask.
    pub fn from_binary(bin: &BinaryBvh, leaf_mask: &dyn Fn(u32, u32) -> u32) -> WideBvh {
        let Some(root) = bin.nodes.first() else {
            return WideBvh {
                root: Item::NONE,
                bounds: Aabb::EMPTY,
                nodes: Vec::new(),
            };
        };
        let mut nodes = Vec::with_capacity(bin.nodes.len() / 2 + 1);
        let root_item = if root.count > 0 {
            Item::leaf(root.first, root.count)
        } else {
            let mut mask = 0;
            nodes.push(WideNode::EMPTY);
            collapse(bin, 0, &mut nodes, 0, leaf_mask, &mut mask);
            Item(0)
        };
        WideBvh {
            root: root_item,
            bounds: root.bounds,
            nodes,
        }
    }

    /// Bytes used by the nodes.
    pub fn memory_bytes(&self) -> usize {
        self.nodes.len() * std::mem::size_of::<WideNode>()
    }
}

/// Writes the wide node for binary interior node `b` into the `reserved` slot of `out`
/// (and, recursively, its subtree) and ORs the subtree's mask into `mask`.
fn collapse(
    bin: &BinaryBvh,
    b: usize,
    out: &mut Vec<WideNode>,
    reserved: usize,
    leaf_mask: &dyn Fn(u32, u32) -> u32,
    mask: &mut u32,
) {
    let node: &BinaryNode = &bin.nodes[b];
    debug_assert_eq!(node.count, 0);
    let mut kids: Vec<usize> = vec![node.first as usize, node.first as usize + 1];
    // Open the interior child of largest area until eight children or only leaves remain.
    while kids.len() < WIDTH {
        let interior = kids
            .iter()
            .enumerate()
            .filter(|(_, k)| bin.nodes[**k].count == 0);
        let Some((i, _)) = interior.max_by(|a, b| {
            bin.nodes[*a.1]
                .bounds
                .surface_area()
                .total_cmp(&bin.nodes[*b.1].bounds.surface_area())
        }) else {
            break;
        };
        let k = kids.swap_remove(i);
        kids.push(bin.nodes[k].first as usize);
        kids.push(bin.nodes[k].first as usize + 1);
    }
    // Siblings' nodes sit side by side (allocated before any of their subtrees).
    let index = reserved;
    let mut first_interior = out.len();
    out.extend(
        kids.iter()
            .filter(|&&k| bin.nodes[k].count == 0)
            .map(|_| WideNode::EMPTY),
    );
    let mut wide = WideNode::EMPTY;
    for (i, &k) in kids.iter().enumerate() {
        let kid = &bin.nodes[k];
        let (item, m) = if kid.count > 0 {
            (
                Item::leaf(kid.first, kid.count).0,
                leaf_mask(kid.first, kid.count),
            )
        } else {
            let slot = first_interior;
            first_interior += 1;
            let mut m = 0;
            collapse(bin, k, out, slot, leaf_mask, &mut m);
            (slot as u32, m)
        };
        wide.children[i] = item;
        wide.masks[i] = m;
        *mask |= m;
        for axis in 0..3 {
            wide.bounds[axis][i] = kid.bounds.min[axis];
            wide.bounds[axis + 3][i] = kid.bounds.max[axis];
        }
    }
    out[index] = wide;
}

/// A ray prepared for box tests: origin, direction, robust reciprocal direction, and for
/// each axis which of a box's min/max planes is entered first.
#[derive(Clone, Copy, Debug)]
pub(crate) struct PreparedRay {
    /// Origin.
    pub origin: Vec3A,
    /// Direction.
    pub dir: Vec3A,
    /// `1 / dir`, with zero components replaced by tiny ones of the same sign.
    pub inv_dir: [f32; 3],
    /// `origin · inv_dir`, so a plane distance is one multiply-subtract.
    pub origin_inv: [f32; 3],
    /// Row of [`WideNode::bounds`] holding the entry plane per axis.
    pub near: [usize; 3],
    /// Row of [`WideNode::bounds`] holding the exit plane per axis.
    pub far: [usize; 3],
    /// Smallest accepted distance.
    pub t_min: f32,
}

impl PreparedRay {
    /// Prepares `origin + t·dir`, `t ≥ t_min`.
    #[inline]
    pub fn new(origin: Vec3A, dir: Vec3A, t_min: f32) -> Self {
        // A zero component would make 0·∞ = NaN at a slab; replacing components below
        // 1e-20 in magnitude keeps every product finite for coordinates up to 1e18.
        let safe = |d: f32| {
            if d.abs() < 1e-20 {
                1e-20f32.copysign(d)
            } else {
                d
            }
        };
        let inv_dir = [1.0 / safe(dir.x), 1.0 / safe(dir.y), 1.0 / safe(dir.z)];
        let origin_inv = [
            origin.x * inv_dir[0],
            origin.y * inv_dir[1],
            origin.z * inv_dir[2],
        ];
        let near = [0, 1, 2].map(|a| if inv_dir[a] >= 0.0 { a } else { a + 3 });
        let far = near.map(|k| if k < 3 { k + 3 } else { k - 3 });
        Self {
            origin,
            dir,
            inv_dir,
            origin_inv,
            near,
            far,
            t_min,
        }
    }

    /// The same ray from `origin + offset`.
    #[inline]
    pub fn translated(&self, offset: Vec3A) -> Self {
        let origin = self.origin + offset;
        let origin_inv = [
            origin.x * self.inv_dir[0],
            origin.y * self.inv_dir[1],
            origin.z * self.inv_dir[2],
        ];
        Self {
            origin,
            origin_inv,
            ..*self
        }
    }
}

/// Entries of a traversal stack: (child reference, entry distance).
pub(crate) type StackEntry = (u32, f32);

thread_local! {
    /// Each thread's traversal stack, kept between queries (clearing a fresh one per ray
    /// would cost more than a small scene's whole query).
    static STACK: RefCell<Vec<StackEntry>> = RefCell::new(new_stack());
}

/// A traversal stack big enough for one tree walk plus, below it, one more (the
/// instance level walks a mesh BVH from its leaves).
pub(crate) fn new_stack() -> Vec<StackEntry> {
    vec![(0, 0.0); 2 * STACK_SIZE]
}

/// Runs `f` with a stack big enough for one tree walk plus, below it, one more (the
/// instance level walks a mesh BVH from its leaves).
#[inline]
pub(crate) fn with_stack<R>(f: impl FnOnce(&mut [StackEntry]) -> R) -> R {
    STACK.with(|stack| match stack.try_borrow_mut() {
        Ok(mut stack) => f(&mut stack),
        // Only reached if a query runs inside another on the same thread.
        Err(_) => f(&mut new_stack()),
    })
}

/// Walks `bvh` nearest child first with the box tests of `kernel`, using `stack` (at
/// least `STACK_SIZE` entries).
/// `leaf(range, t_max, free_stack)` tests a leaf's primitives, lowers `t_max` on a
/// closer hit, and returns true to stop the walk (any-hit queries); `free_stack` is the
/// unused rest of `stack`, for a nested walk. Returns the final `t_max`.
#[inline(always)]
pub(crate) fn traverse<K: BoxKernel, const MASKED: bool>(
    kernel: K,
    bvh: &WideBvh,
    ray: &PreparedRay,
    mut t_max: f32,
    mask: u32,
    stack: &mut [StackEntry],
    mut leaf: impl FnMut(std::ops::Range<usize>, &mut f32, &mut [StackEntry]) -> bool,
) -> f32 {
    if bvh.root == Item::NONE {
        return t_max;
    }
    let mut sp = 0usize;
    let mut current = bvh.root;
    loop {
        if current.is_leaf() {
            if leaf(current.leaf_range(), &mut t_max, &mut stack[sp..]) {
                return t_max;
            }
        } else {
            let node = &bvh.nodes[current.node()];
            let (dist, mut bits) = kernel.hit_boxes::<MASKED>(ray, node, t_max, mask);
            if bits == 0 {
                // Nothing hit: fall through to pop.
            } else if bits & (bits - 1) == 0 {
                // One child hit (the common case deep in the tree): visit it directly.
                current = Item(node.children[bits.trailing_zeros() as usize]);
                continue;
            } else {
                // Insert the hit children into the stack sorted farthest first (an
                // insertion sort in place: ties keep slot order), then visit the nearest.
                let base = sp;
                while bits != 0 {
                    let i = bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    let entry = (node.children[i], dist[i]);
                    let mut j = sp;
                    while j > base && stack[j - 1].1 < entry.1 {
                        stack[j] = stack[j - 1];
                        j -= 1;
                    }
                    stack[j] = entry;
                    sp += 1;
                }
                sp -= 1;
                current = Item(stack[sp].0);
                continue;
            }
        }
        // Pop the next child still nearer than the closest hit.
        loop {
            if sp == 0 {
                return t_max;
            }
            sp -= 1;
            let (item, d) = stack[sp];
            if d <= t_max {
                current = Item(item);
                break;
            }
        }
    }
}
