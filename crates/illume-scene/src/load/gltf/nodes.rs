//! The node hierarchy: the scene's roots, the forest check, the depth-first walk that
//! places instances, node transforms, and the camera.

use super::Ctx;
use crate::animation::Trs;
use crate::load::{LoadError, excerpt};
use crate::model::NodeId;
use ::gltf::json;
use illume_core::{Affine3A, Mat4, Quat, Vec3};
use json::validation::Checked;

impl Ctx<'_> {
    /// Root nodes of the scene to load: `scene`, else scene 0, else every node that is
    /// nobody's child.
    pub(super) fn scene_roots(&self) -> Result<Vec<usize>, LoadError> {
        let chosen = self
            .root
            .scene
            .map(|s| s.value())
            .or(if self.root.scenes.is_empty() {
                None
            } else {
                Some(0)
            });
        match chosen {
            Some(s) => {
                let scene =
                    self.root.scenes.get(s).ok_or_else(|| {
                        self.malformed("scene", format!("scene {s} does not exist"))
                    })?;
                Ok(scene.nodes.iter().map(|n| n.value()).collect())
            }
            None => {
                let mut is_child = vec![false; self.root.nodes.len()];
                for n in &self.root.nodes {
                    for c in n.children.iter().flatten() {
                        if let Some(flag) = is_child.get_mut(c.value()) {
                            *flag = true;
                        }
                    }
                }
                Ok((0..self.root.nodes.len())
                    .filter(|&i| !is_child[i])
                    .collect())
            }
        }
    }

    /// The whole document's node hierarchy (reachable from the scene or not) must be a
    /// forest, as glTF requires: every child exists, no node has two parents and no node
    /// is its own ancestor. The error names the node.
    pub(super) fn check_hierarchy(&self) -> Result<(), LoadError> {
        let n = self.root.nodes.len();
        let mut parent: Vec<Option<usize>> = vec![None; n];
        for (p, node) in self.root.nodes.iter().enumerate() {
            for c in node.children.iter().flatten().map(|c| c.value()) {
                let Some(slot) = parent.get_mut(c) else {
                    return Err(self.malformed(
                        format!("node {p}"),
                        format!("child {c} does not exist ({n} nodes)"),
                    ));
                };
                if let Some(first) = slot.replace(p) {
                    return Err(self.malformed(
                        format!("node {c}"),
                        format!(
                            "is a child of node {first} and of node {p} (a node has at most one parent)"
                        ),
                    ));
                }
            }
        }
        // One parent each: follow parents from every node, each node walked once.
        let mut walked_from = vec![usize::MAX; n];
        let mut done = vec![false; n];
        for start in 0..n {
            let mut at = start;
            while !done[at] {
                if walked_from[at] == start {
                    return Err(self.malformed(
                        format!("node {at}"),
                        "is its own ancestor (a cycle in the node hierarchy)",
                    ));
                }
                walked_from[at] = start;
                match parent[at] {
                    Some(p) => at = p,
                    None => break,
                }
            }
            let mut at = start;
            while walked_from[at] == start && !done[at] {
                done[at] = true;
                match parent[at] {
                    Some(p) => at = p,
                    None => break,
                }
            }
        }
        Ok(())
    }

    /// Depth-first order of the nodes under `roots` as `(node, parent)`; parents come
    /// before their children. A node reached twice is an error.
    pub(super) fn walk(&self, roots: &[usize]) -> Result<Vec<(usize, Option<usize>)>, LoadError> {
        let mut seen = vec![false; self.root.nodes.len()];
        let mut order = Vec::new();
        let mut stack: Vec<(usize, Option<usize>)> =
            roots.iter().rev().map(|&r| (r, None)).collect();
        while let Some((n, parent)) = stack.pop() {
            let place = format!("node {n}");
            let node = self
                .root
                .nodes
                .get(n)
                .ok_or_else(|| self.malformed(&place, "does not exist"))?;
            if std::mem::replace(&mut seen[n], true) {
                return Err(self.malformed(
                    place,
                    "reached twice in the hierarchy (a cycle, two parents or a repeated root)",
                ));
            }
            order.push((n, parent));
            for c in node.children.iter().flatten().rev() {
                stack.push((c.value(), Some(n)));
            }
        }
        Ok(order)
    }

    /// The local transform of node `g`; non-finite values are an error.
    pub(super) fn node_trs(&self, g: usize) -> Result<Trs, LoadError> {
        let node = &self.root.nodes[g];
        let place = format!("node {g} '{}'", excerpt(node.name.as_deref().unwrap_or("")));
        if let Some(m) = node.matrix {
            if m.iter().any(|x| !x.is_finite()) {
                return Err(self.malformed(place, format!("matrix is not finite: {m:?}")));
            }
            let trs = Trs::from_affine(&Affine3A::from_mat4(Mat4::from_cols_array(&m)));
            if !trs.is_finite() {
                return Err(self.malformed(
                    place,
                    "matrix cannot be decomposed into translation, rotation and scale",
                ));
            }
            return Ok(trs);
        }
        let t = node.translation.unwrap_or([0.0; 3]);
        let r = node.rotation.map(|q| q.0).unwrap_or([0.0, 0.0, 0.0, 1.0]);
        let s = node.scale.unwrap_or([1.0; 3]);
        if t.iter().chain(&r).chain(&s).any(|x| !x.is_finite()) {
            return Err(self.malformed(
                place,
                format!("transform is not finite: translation {t:?}, rotation {r:?}, scale {s:?}"),
            ));
        }
        let q = Quat::from_array(r);
        if q.length_squared() == 0.0 {
            return Err(self.malformed(place, "rotation quaternion is zero"));
        }
        Ok(Trs {
            translation: Vec3::from(t),
            rotation: q.normalize(),
            scale: Vec3::from(s),
        })
    }

    /// Sets the camera from the lowest-index scene node with a perspective camera.
    pub(super) fn camera(
        &mut self,
        order: &[(usize, Option<usize>)],
        node_ids: &[Option<NodeId>],
    ) -> Result<(), LoadError> {
        use json::camera::Type;
        let root = self.root;
        let mut with_camera: Vec<usize> = order
            .iter()
            .map(|&(g, _)| g)
            .filter(|&g| root.nodes[g].camera.is_some())
            .collect();
        with_camera.sort_unstable();
        for g in with_camera {
            let Some(c) = root.nodes[g].camera.map(|c| c.value()) else {
                continue;
            };
            let place = format!("node {g} camera {c}");
            let cam = root
                .cameras
                .get(c)
                .ok_or_else(|| self.malformed(&place, "camera does not exist"))?;
            match (&cam.type_, &cam.perspective) {
                (Checked::Valid(Type::Perspective), Some(p)) => {
                    if !(p.yfov.is_finite() && p.yfov > 0.0 && p.yfov < std::f32::consts::PI) {
                        return Err(
                            self.malformed(place, format!("yfov {} is not in (0, π)", p.yfov))
                        );
                    }
                    // illume clips nothing and takes the aspect ratio from the image, but a
                    // camera the glTF specification forbids is a broken file.
                    if !(p.znear.is_finite() && p.znear > 0.0) {
                        return Err(self.malformed(
                            place,
                            format!("znear {} must be finite and > 0", p.znear),
                        ));
                    }
                    if let Some(zfar) = p.zfar
                        && (zfar.is_nan() || zfar <= p.znear)
                    {
                        return Err(self.malformed(
                            place,
                            format!("zfar {zfar} must be greater than znear {}", p.znear),
                        ));
                    }
                    if let Some(a) = p.aspect_ratio
                        && !(a.is_finite() && a > 0.0)
                    {
                        return Err(self
                            .malformed(place, format!("aspectRatio {a} must be finite and > 0")));
                    }
                    let Some(node) = node_ids.get(g).copied().flatten() else {
                        continue;
                    };
                    let name = cam.name.clone().unwrap_or_else(|| format!("camera {c}"));
                    self.builder.camera(&name, p.yfov, node);
                    self.camera_set = true;
                    return Ok(());
                }
                _ => self.warn(format!("{place}: not a perspective camera, ignored")),
            }
        }
        Ok(())
    }
}
