//! The record lookup: an octree over the records' spheres of influence (WRC88), the
//! CPU counterpart of §5's splatting, answering "which records' spheres contain p".
//!
//! A record k is usable at p only within distance a·R_k of p_k (Eq. 2–3: the distance
//! term alone reaches a there), so its sphere of influence, centre p_k and radius
//! a·R_k, bounds where it can matter. Each sphere is stored in the deepest node whose
//! cube contains its centre and whose half-size is at least its radius (so a sphere
//! reaches at most half a cube beyond its node: the loose octree of WRC88). Every node
//! also keeps the box of all spheres below it, and a query descends only into nodes
//! whose box contains the point, so the answer is exact: the same set as testing every
//! sphere ([`sphere_contains`]), which [`Octree::validate`] and the tests check.
//!
//! Records come and go (replacement, deletion): [`Octree::insert`] grows the root
//! cube when a centre lies outside it (records keep their world positions, even when
//! the objects they were made on leave the scene's first bounds), and
//! [`Octree::remove`] frees nodes left without records or children and re-tightens the
//! boxes above. Freed nodes wait in a free list for the next insertion; every node
//! reachable from the root holds records or has children.

use crate::RadianceCacheError;
use illume_core::{Aabb, Vec3};

const NONE: u32 = u32::MAX;

/// Depth below the root beyond which spheres are not pushed further (only spheres of
/// radius below 2⁻⁴⁰ of the root's size reach it).
pub const MAX_DEPTH: u32 = 40;

/// True when `p` lies in the closed sphere (`center`, `radius`): the definition the
/// octree answers for.
#[inline]
pub fn sphere_contains(center: Vec3, radius: f32, p: Vec3) -> bool {
    (p - center).length_squared() <= radius * radius
}

/// The box stored for a sphere: its bounding box, padded by a relative 10⁻⁵ so that
/// every point [`sphere_contains`] accepts lies inside despite rounding.
#[inline]
fn sphere_box(center: Vec3, radius: f32) -> Aabb {
    let pad = radius * (1.0 + 1e-5) + 1e-6 * (1.0 + center.abs().max_element());
    Aabb::new(center - pad, center + pad)
}

#[derive(Clone, Copy, Debug)]
struct Entry {
    center: Vec3,
    radius: f32,
    node: u32,
}

#[derive(Clone, Debug)]
struct Node {
    center: Vec3,
    half: f32,
    /// Box of every sphere stored in this node and below.
    bounds: Aabb,
    parent: u32,
    children: [u32; 8],
    items: Vec<u32>,
}

impl Node {
    fn new(center: Vec3, half: f32, parent: u32) -> Self {
        Self {
            center,
            half,
            bounds: Aabb::EMPTY,
            parent,
            children: [NONE; 8],
            items: Vec::new(),
        }
    }

    fn cube_contains(&self, p: Vec3) -> bool {
        (p - self.center).abs().max_element() <= self.half
    }

    /// [`Node::cube_contains`] up to the rounding of centres computed by halving.
    fn cube_contains_loosely(&self, p: Vec3) -> bool {
        let slack = 1e-5 * (self.half + self.center.abs().max_element());
        (p - self.center).abs().max_element() <= self.half + slack
    }

    fn is_empty(&self) -> bool {
        self.items.is_empty() && self.children.iter().all(|&c| c == NONE)
    }
}

/// The octant of `p` about `center`: bit k set when p is at or beyond the centre on
/// axis k.
#[inline]
fn octant(center: Vec3, p: Vec3) -> usize {
    (p.x >= center.x) as usize
        | ((p.y >= center.y) as usize) << 1
        | ((p.z >= center.z) as usize) << 2
}

/// The centre of octant `o` of the cube (`center`, `half`).
#[inline]
fn octant_center(center: Vec3, half: f32, o: usize) -> Vec3 {
    let q = half * 0.5;
    center
        + Vec3::new(
            if o & 1 != 0 { q } else { -q },
            if o & 2 != 0 { q } else { -q },
            if o & 4 != 0 { q } else { -q },
        )
}

/// An octree over spheres of influence, keyed by record ids (`u32`, dense: storage per
/// id up to the largest inserted).
#[derive(Clone, Debug, Default)]
pub struct Octree {
    nodes: Vec<Node>,
    free: Vec<u32>,
    root: Option<u32>,
    entries: Vec<Option<Entry>>,
    len: usize,
}

impl Octree {
    /// An empty octree.
    pub fn new() -> Self {
        Self::default()
    }

    /// Spheres stored.
    pub fn len(&self) -> usize {
        self.len
    }

    /// True when no sphere is stored.
    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Nodes in use (reachable from the root).
    pub fn node_count(&self) -> usize {
        self.nodes.len() - self.free.len()
    }

    /// The sphere of record `id`, if stored: (centre, radius).
    pub fn sphere(&self, id: u32) -> Option<(Vec3, f32)> {
        self.entries
            .get(id as usize)
            .and_then(|e| e.as_ref())
            .map(|e| (e.center, e.radius))
    }

    fn alloc(&mut self, node: Node) -> u32 {
        match self.free.pop() {
            Some(i) => {
                self.nodes[i as usize] = node;
                i
            }
            None => {
                self.nodes.push(node);
                self.nodes.len() as u32 - 1
            }
        }
    }

    /// Stores (or moves) the sphere of record `id`: centre `center`, radius `radius` \[m\]
    /// (a·R_k). Errors on a non-finite centre or radius or a negative radius.
    pub fn insert(&mut self, id: u32, center: Vec3, radius: f32) -> Result<(), RadianceCacheError> {
        if !(center.is_finite() && radius.is_finite() && radius >= 0.0) {
            return Err(RadianceCacheError::BadSphere { id, center, radius });
        }
        self.remove(id);
        let root = match self.root {
            Some(r) => r,
            None => {
                let half = (2.0 * radius).max(1e-3 * (1.0 + center.abs().max_element()));
                let r = self.alloc(Node::new(center, half, NONE));
                self.root = Some(r);
                r
            }
        };
        let root = self.grow_to(root, center);
        // Descend while the child cube is still at least as large as the sphere.
        let mut node = root;
        for _ in 0..MAX_DEPTH {
            let (c, half) = (
                self.nodes[node as usize].center,
                self.nodes[node as usize].half,
            );
            let child_half = 0.5 * half;
            if child_half < radius {
                break;
            }
            let o = octant(c, center);
            let child = match self.nodes[node as usize].children[o] {
                NONE => {
                    let new = self.alloc(Node::new(octant_center(c, half, o), child_half, node));
                    self.nodes[node as usize].children[o] = new;
                    new
                }
                child => child,
            };
            node = child;
        }
        self.nodes[node as usize].items.push(id);
        if self.entries.len() <= id as usize {
            self.entries.resize(id as usize + 1, None);
        }
        self.entries[id as usize] = Some(Entry {
            center,
            radius,
            node,
        });
        self.len += 1;
        let b = sphere_box(center, radius);
        let mut n = node;
        while n != NONE {
            let node = &mut self.nodes[n as usize];
            node.bounds = node.bounds.union(b);
            n = node.parent;
        }
        Ok(())
    }

    /// Doubles the root cube towards `p` until it contains `p`; returns the root.
    fn grow_to(&mut self, mut root: u32, p: Vec3) -> u32 {
        while !self.nodes[root as usize].cube_contains(p) {
            let (c, half, bounds) = {
                let r = &self.nodes[root as usize];
                (r.center, r.half, r.bounds)
            };
            let step = Vec3::new(
                if p.x >= c.x { half } else { -half },
                if p.y >= c.y { half } else { -half },
                if p.z >= c.z { half } else { -half },
            );
            let mut new = Node::new(c + step, 2.0 * half, NONE);
            new.bounds = bounds;
            let new_center = new.center;
            let index = self.alloc(new);
            let slot = octant(new_center, c);
            self.nodes[index as usize].children[slot] = root;
            self.nodes[root as usize].parent = index;
            // The old root may hold spheres larger than its half-size (the root holds
            // anything); as a child it may not: they move up to the new root.
            let items = std::mem::take(&mut self.nodes[root as usize].items);
            let (keep, lift): (Vec<u32>, Vec<u32>) = items
                .into_iter()
                .partition(|&id| self.entries[id as usize].is_some_and(|e| e.radius <= half));
            for &id in &lift {
                if let Some(e) = self.entries[id as usize].as_mut() {
                    e.node = index;
                }
            }
            self.nodes[root as usize].items = keep;
            self.nodes[index as usize].items = lift;
            if self.nodes[root as usize].is_empty() {
                self.nodes[index as usize].children[slot] = NONE;
                self.free.push(root);
            } else {
                self.nodes[root as usize].bounds = self.tight_bounds(root);
            }
            root = index;
        }
        self.root = Some(root);
        root
    }

    /// Removes record `id`'s sphere; false when it was not stored.
    pub fn remove(&mut self, id: u32) -> bool {
        let Some(entry) = self.entries.get_mut(id as usize).and_then(|e| e.take()) else {
            return false;
        };
        self.len -= 1;
        let items = &mut self.nodes[entry.node as usize].items;
        if let Some(i) = items.iter().position(|&x| x == id) {
            items.swap_remove(i);
        }
        // Free emptied nodes and re-tighten boxes up to the root.
        let mut n = entry.node;
        while n != NONE {
            let parent = self.nodes[n as usize].parent;
            if self.nodes[n as usize].is_empty() {
                if parent == NONE {
                    self.root = None;
                } else {
                    let slot = self.nodes[parent as usize]
                        .children
                        .iter()
                        .position(|&c| c == n);
                    if let Some(slot) = slot {
                        self.nodes[parent as usize].children[slot] = NONE;
                    }
                }
                self.free.push(n);
            } else {
                self.nodes[n as usize].bounds = self.tight_bounds(n);
            }
            n = parent;
        }
        if self.root.is_none() {
            self.nodes.clear();
            self.free.clear();
        }
        true
    }

    /// The box of node `n`'s own spheres and its children's boxes.
    fn tight_bounds(&self, n: u32) -> Aabb {
        let node = &self.nodes[n as usize];
        let own = node.items.iter().fold(Aabb::EMPTY, |b, &id| {
            let e = self.entries[id as usize].expect("stored item has an entry");
            b.union(sphere_box(e.center, e.radius))
        });
        node.children
            .iter()
            .filter(|&&c| c != NONE)
            .fold(own, |b, &c| b.union(self.nodes[c as usize].bounds))
    }

    /// Calls `f` with the id of every record whose sphere contains `p`
    /// ([`sphere_contains`]), in no particular order.
    pub fn for_each_containing(&self, p: Vec3, mut f: impl FnMut(u32)) {
        let Some(root) = self.root else { return };
        let mut stack = Vec::with_capacity(64);
        stack.push(root);
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n as usize];
            if !node.bounds.contains(p) {
                continue;
            }
            for &id in &node.items {
                if let Some(e) = self.entries[id as usize]
                    && sphere_contains(e.center, e.radius, p)
                {
                    f(id);
                }
            }
            stack.extend(node.children.iter().copied().filter(|&c| c != NONE));
        }
    }

    /// The ids of every record whose sphere contains `p`, sorted.
    pub fn containing(&self, p: Vec3) -> Vec<u32> {
        let mut ids = Vec::new();
        self.for_each_containing(p, |id| ids.push(id));
        ids.sort_unstable();
        ids
    }

    /// Checks the structure; the message names the first broken node or record:
    /// every stored sphere is reachable exactly once, from the node its entry names;
    /// each node's cube contains its spheres' centres and is the right octant of its
    /// parent's (both up to the rounding of halved centres); non-root nodes are at
    /// least as large as their spheres; each node's box contains its spheres' boxes
    /// and its children's boxes; every reachable node holds spheres or has children;
    /// every node is either reachable or free.
    pub fn validate(&self) -> Result<(), String> {
        let Some(root) = self.root else {
            if self.len != 0 || self.entries.iter().any(|e| e.is_some()) {
                return Err(format!("no root but {} spheres stored", self.len));
            }
            return Ok(());
        };
        let mut seen = vec![0u32; self.entries.len()];
        let mut visited = vec![false; self.nodes.len()];
        let mut stack = vec![root];
        if self.nodes[root as usize].parent != NONE {
            return Err(format!("root node {root} has a parent"));
        }
        while let Some(n) = stack.pop() {
            let Some(node) = self.nodes.get(n as usize) else {
                return Err(format!("node {n} does not exist"));
            };
            if std::mem::replace(&mut visited[n as usize], true) {
                return Err(format!("node {n} is reached twice"));
            }
            if node.is_empty() {
                return Err(format!("node {n} holds no sphere and has no child"));
            }
            for &id in &node.items {
                let Some(Some(e)) = self.entries.get(id as usize) else {
                    return Err(format!("node {n} holds record {id}, which is not stored"));
                };
                seen[id as usize] += 1;
                if e.node != n {
                    return Err(format!(
                        "record {id} is held by node {n} but its entry names node {}",
                        e.node
                    ));
                }
                if !node.cube_contains_loosely(e.center) {
                    return Err(format!(
                        "node {n}: record {id}'s centre {} lies outside the cube",
                        e.center
                    ));
                }
                if n != root && e.radius > node.half {
                    return Err(format!(
                        "node {n}: record {id}'s radius {} exceeds the half-size {}",
                        e.radius, node.half
                    ));
                }
                if !node
                    .bounds
                    .contains_box(&sphere_box(e.center, e.radius), 0.0)
                {
                    return Err(format!(
                        "node {n}: the box {:?} does not contain record {id}'s sphere",
                        node.bounds
                    ));
                }
            }
            for (o, &c) in node.children.iter().enumerate() {
                if c == NONE {
                    continue;
                }
                let Some(child) = self.nodes.get(c as usize) else {
                    return Err(format!("node {n}: child {c} does not exist"));
                };
                if child.parent != n {
                    return Err(format!("node {c}'s parent is {}, not {n}", child.parent));
                }
                let expected = octant_center(node.center, node.half, o);
                let slack = 1e-5 * (node.half + node.center.abs().max_element());
                if (child.center - expected).abs().max_element() > slack
                    || child.half != 0.5 * node.half
                {
                    return Err(format!("node {c} is not octant {o} of node {n}"));
                }
                if !node.bounds.contains_box(&child.bounds, 0.0) {
                    return Err(format!(
                        "node {n}: the box does not contain child {c}'s box"
                    ));
                }
                stack.push(c);
            }
        }
        for (id, e) in self.entries.iter().enumerate() {
            let count = seen[id];
            match e {
                Some(_) if count != 1 => {
                    return Err(format!("record {id} is held {count} times"));
                }
                None if count != 0 => {
                    return Err(format!("removed record {id} is still held"));
                }
                _ => {}
            }
        }
        let stored = self.entries.iter().filter(|e| e.is_some()).count();
        if stored != self.len {
            return Err(format!(
                "{stored} spheres stored but the count says {}",
                self.len
            ));
        }
        for &f in &self.free {
            if visited.get(f as usize).copied().unwrap_or(true) {
                return Err(format!("free node {f} is reachable or does not exist"));
            }
        }
        let reachable = visited.iter().filter(|&&v| v).count();
        if reachable + self.free.len() != self.nodes.len() {
            return Err(format!(
                "{} nodes, of which {reachable} reachable and {} free: the rest are lost",
                self.nodes.len(),
                self.free.len()
            ));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample_tree() -> Octree {
        let mut t = Octree::new();
        for i in 0..200u32 {
            let f = i as f32;
            let c = Vec3::new(
                (f * 0.37).sin() * 3.0,
                (f * 0.11).cos() * 2.0,
                (f * 0.73).sin(),
            );
            t.insert(i, c, 0.01 + 0.2 * ((f * 0.29).sin().abs()))
                .unwrap();
        }
        t
    }

    #[test]
    fn validate_names_what_is_broken() {
        let t = sample_tree();
        t.validate().unwrap();
        // A node box shrunk: a sphere sticks out.
        let mut bad = t.clone();
        let n = bad.entries[17].unwrap().node as usize;
        bad.nodes[n].bounds.max.x -= 0.5;
        let e = bad.validate().unwrap_err();
        assert!(e.contains("does not contain"), "{e}");
        // A record lost from a node that holds others.
        let mut bad = t.clone();
        let id = (0..200u32)
            .find(|&id| {
                bad.nodes[bad.entries[id as usize].unwrap().node as usize]
                    .items
                    .len()
                    > 1
            })
            .expect("some node holds two records");
        let n = bad.entries[id as usize].unwrap().node as usize;
        bad.nodes[n].items.retain(|&x| x != id);
        let e = bad.validate().unwrap_err();
        assert!(e.contains(&format!("record {id} is held 0 times")), "{e}");
        // An empty leaf hung under the root.
        let mut bad = t.clone();
        let root = bad.root.unwrap();
        let slot = bad.nodes[root as usize]
            .children
            .iter()
            .position(|&c| c == NONE);
        if let Some(slot) = slot {
            let (c, h) = (
                bad.nodes[root as usize].center,
                bad.nodes[root as usize].half,
            );
            let leaf = bad.alloc(Node::new(octant_center(c, h, slot), 0.5 * h, root));
            bad.nodes[root as usize].children[slot] = leaf;
            let e = bad.validate().unwrap_err();
            assert!(e.contains("holds no sphere"), "{e}");
        }
        // A node dropped from the tree without being freed.
        let mut bad = t.clone();
        bad.nodes.push(Node::new(Vec3::ZERO, 1.0, NONE));
        let e = bad.validate().unwrap_err();
        assert!(e.contains("lost"), "{e}");
    }

    #[test]
    fn removing_everything_frees_every_node() {
        let mut t = sample_tree();
        for i in (0..200).step_by(2) {
            assert!(t.remove(i));
            assert!(!t.remove(i));
        }
        t.validate().unwrap();
        for i in (1..200).step_by(2) {
            t.remove(i);
        }
        t.validate().unwrap();
        assert!(t.is_empty());
        assert_eq!(t.node_count(), 0);
    }
}
