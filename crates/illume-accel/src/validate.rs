//! Structural checks of a [`Tracer`]: every node box contains its children, the leaves
//! holding a triangle cover it (a split triangle is in several), every instance is
//! referenced exactly once, and masks cover what lies below them.

use crate::Tracer;
use crate::blas::Blas;
use crate::tracer::tolerance;
use crate::wide::{self, Item, WideBvh};
use illume_core::Aabb;

impl Tracer {
    /// Checks the structure's invariants (bounds contain children, every triangle is
    /// covered by the boxes of the leaves holding it, every instance referenced once);
    /// the message says what is broken.
    pub fn validate(&self) -> Result<(), String> {
        for (m, blas) in self.blases.iter().enumerate() {
            validate_blas(blas).map_err(|e| format!("mesh {m} BVH: {e}"))?;
        }
        let mut seen = vec![0u32; self.instances.len()];
        validate_tree(&self.tlas, &mut |range, bounds, mask, place| {
            for (k, inst) in self.instances[range.clone()].iter().enumerate() {
                seen[range.start + k] += 1;
                if !bounds.contains_box(&inst.world_bounds, tolerance(bounds)) {
                    return Err(format!("{place}: box {bounds:?} does not contain instance {} box {:?}", inst.id.0, inst.world_bounds));
                }
                let blas_world = self.blases[inst.mesh as usize].bounds().transformed(&inst.world_from_object);
                if !inst.world_bounds.contains_box(&blas_world, tolerance(&blas_world)) {
                    return Err(format!("{place}: instance {} box {:?} does not contain its mesh BVH's world box {blas_world:?}", inst.id.0, inst.world_bounds));
                }
                if inst.mask & !mask != 0 {
                    return Err(format!("{place}: mask {mask:#x} lacks bits of instance {} mask {:#x}", inst.id.0, inst.mask));
                }
            }
            Ok(())
        })
        .map_err(|e| format!("instance level: {e}"))?;
        if let Some(i) = seen.iter().position(|&c| c != 1) {
            return Err(format!(
                "instance level: instance record {i} (instance {}) referenced {} times",
                self.instances[i].id.0, seen[i]
            ));
        }
        Ok(())
    }
}

fn validate_blas(blas: &Blas) -> Result<(), String> {
    let n = blas.triangle_count;
    let mut packet_refs = vec![0u32; blas.packets.len()];
    // Boxes of the leaves holding each triangle (pre-splitting puts a triangle in one or
    // more leaves, each box covering a part of it).
    let mut leaf_boxes: Vec<Vec<(usize, Aabb)>> = vec![Vec::new(); n];
    let mut corners_of: Vec<Option<[illume_core::Vec3; 3]>> = vec![None; n];
    validate_tree(&blas.bvh, &mut |range, bounds, _, place| {
        for (k, packet) in blas.packets[range.clone()].iter().enumerate() {
            packet_refs[range.start + k] += 1;
            for (index, corners) in packet.triangles() {
                let Some(boxes) = leaf_boxes.get_mut(index as usize) else {
                    return Err(format!(
                        "{place}: triangle index {index} out of range 0..{n}"
                    ));
                };
                // A leaf is known by its first packet.
                if boxes.iter().any(|&(leaf, _)| leaf == range.start) {
                    return Err(format!(
                        "{place}: triangle {index} stored twice in one leaf"
                    ));
                }
                boxes.push((range.start, *bounds));
                match corners_of[index as usize] {
                    None => corners_of[index as usize] = Some(corners),
                    Some(c) if c == corners => {}
                    Some(c) => {
                        return Err(format!(
                            "{place}: triangle {index} stored as {corners:?} here and {c:?} elsewhere"
                        ));
                    }
                }
            }
        }
        Ok(())
    })?;
    if let Some(i) = packet_refs.iter().position(|&c| c != 1) {
        return Err(format!(
            "triangle packet {i} is in {} leaves",
            packet_refs[i]
        ));
    }
    for (t, boxes) in leaf_boxes.iter().enumerate() {
        let Some(c) = corners_of[t] else {
            return Err(format!("mesh triangle {t} is in no leaf"));
        };
        // The leaves' boxes must cover the triangle: its corners, edge points and a
        // lattice of inner points each lie in one of them.
        const STEPS: usize = 8;
        let tol = tolerance(&Aabb::from_points(c));
        for i in 0..=STEPS {
            for j in 0..=STEPS - i {
                let (u, v) = (i as f32 / STEPS as f32, j as f32 / STEPS as f32);
                let p = c[0] + (c[1] - c[0]) * u + (c[2] - c[0]) * v;
                if !boxes
                    .iter()
                    .any(|(_, b)| b.contains_box(&Aabb::new(p, p), tol))
                {
                    return Err(format!(
                        "mesh triangle {t} {c:?}: point {p:?} lies in none of its {} leaf boxes {boxes:?}",
                        boxes.len()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Checks one leaf: `(primitive range, box and mask its parent holds, where)`.
type LeafCheck<'a> = dyn FnMut(std::ops::Range<usize>, &Aabb, u32, &str) -> Result<(), String> + 'a;

/// Walks every node of `bvh` checking that each node's child boxes lie inside the box
/// its parent holds for it and that unused slots are empty; calls
/// `leaf(range, box, mask, place)` for every leaf with the box and mask its parent holds.
fn validate_tree(bvh: &WideBvh, leaf: &mut LeafCheck<'_>) -> Result<(), String> {
    if bvh.root == Item::NONE {
        return if bvh.nodes.is_empty() {
            Ok(())
        } else {
            Err(format!("empty tree has {} nodes", bvh.nodes.len()))
        };
    }
    let mut visits = vec![0u32; bvh.nodes.len()];
    // (reference, box the parent holds for it, mask the parent holds for it, parent description)
    let mut work = vec![(bvh.root, bvh.bounds, u32::MAX, "root".to_string())];
    while let Some((item, bounds, mask, place)) = work.pop() {
        if item.is_leaf() {
            leaf(
                item.leaf_range(),
                &bounds,
                mask,
                &format!("leaf {:?} under {place}", item.leaf_range()),
            )?;
            continue;
        }
        let index = item.node();
        let node = bvh.nodes.get(index).ok_or_else(|| {
            format!(
                "{place}: child node {index} out of range 0..{}",
                bvh.nodes.len()
            )
        })?;
        visits[index] += 1;
        if visits[index] > 1 {
            return Err(format!("node {index} is referenced more than once"));
        }
        let count = node.child_count();
        if count < 2 {
            return Err(format!("node {index} has {count} children"));
        }
        for slot in 0..wide::WIDTH {
            let b = node.child_bounds(slot);
            if slot >= count {
                if !b.is_empty() || node.masks[slot] != 0 {
                    return Err(format!(
                        "node {index} slot {slot}: unused slot is not empty"
                    ));
                }
                continue;
            }
            if !bounds.contains_box(&b, tolerance(&b)) {
                return Err(format!(
                    "node {index} slot {slot}: child box {b:?} is outside the node's box {bounds:?}"
                ));
            }
            if node.masks[slot] & !mask != 0 {
                return Err(format!(
                    "node {index} slot {slot}: mask {:#x} has bits the parent's {mask:#x} lacks",
                    node.masks[slot]
                ));
            }
            work.push((
                Item(node.children[slot]),
                b,
                node.masks[slot],
                format!("node {index} slot {slot}"),
            ));
        }
    }
    if let Some(i) = visits.iter().position(|&v| v == 0) {
        return Err(format!("node {i} is unreachable"));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::Arc;

    #[test]
    fn validate_names_the_broken_node() {
        let scene = illume_scene::builtin::load("cornell-spot").unwrap();
        let mut tracer = Tracer::new(&scene);
        assert_eq!(tracer.validate(), Ok(()));
        // Shrink one child box of the sphere's root node: its triangles stick out.
        let sphere = scene
            .instances
            .iter()
            .position(|i| i.name == "sphere")
            .unwrap();
        let mesh = scene.instances[sphere].mesh.index();
        let blas = Arc::get_mut(&mut tracer.blases[mesh]).expect("not shared");
        blas.bvh.nodes[0].bounds[3][1] -= 0.05;
        let err = tracer.validate().unwrap_err();
        assert!(err.starts_with(&format!("mesh {mesh} BVH:")), "{err}");
        assert!(
            err.contains("outside the node's box") || err.contains("does not contain triangle"),
            "{err}"
        );
        // A packet lane pointing at another triangle's index is caught too.
        let mut tracer = Tracer::new(&scene);
        let first = tracer.blases[mesh].packets[0].index[0];
        Arc::get_mut(&mut tracer.blases[mesh])
            .expect("not shared")
            .packets[1]
            .index[0] = first;
        let err = tracer.validate().unwrap_err();
        assert!(err.contains("stored as"), "{err}");
        // An instance box that no longer covers its mesh.
        let mut tracer = Tracer::new(&scene);
        tracer.instances[0].world_bounds.max.y -= 0.5;
        let err = tracer.validate().unwrap_err();
        assert!(err.starts_with("instance level:"), "{err}");
    }
}
