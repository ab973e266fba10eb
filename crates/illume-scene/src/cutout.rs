//! Alpha masks (cut-outs): where a surface with [`Material::alpha_cutoff`] is not there.
//!
//! A [`MeshCutout`] answers, for a point of one mesh's triangle given by barycentrics,
//! whether the surface is there. The tracer keeps one per mesh whose materials cut out
//! (rays, shadow rays and photons pass through holes), and the rasterizer builds them per
//! view (G-buffers and shadow maps), so both see the same holes.
//!
//! glTF 2.0 `alphaMode: MASK`: the surface is there where
//! `alpha × texture alpha ≥ alphaCutoff` (texture alpha bilinearly filtered at the
//! point's texture coordinates); with `alphaMode: BLEND` the loaders set a cutoff of 0.5
//! and warn (illume has no partial transparency).

use crate::{Material, Mesh, MeshId, Scene, Texture, UvTransform};
use illume_core::Vec2;
use std::sync::Arc;

/// One cut-out material as the test needs it.
#[derive(Clone, Debug)]
struct AlphaTest {
    /// Opacity factor.
    alpha: f32,
    /// Cutoff: the surface is there where opacity ≥ cutoff.
    cutoff: f32,
    /// Texture whose alpha multiplies the factor.
    texture: Option<Arc<Texture>>,
    /// Transform of the texture coordinates the texture is read at.
    transform: Option<UvTransform>,
}

/// Which points of one mesh's triangles are there (see the module documentation).
#[derive(Clone, Debug)]
pub struct MeshCutout {
    /// The mesh (its texture coordinates and triangle order).
    mesh: Arc<Mesh>,
    /// Per triangle, its index in `tests`, or [`MeshCutout::OPAQUE`].
    test_of_triangle: Vec<u32>,
    /// The cut-out materials the mesh uses.
    tests: Vec<AlphaTest>,
}

impl MeshCutout {
    /// Marks a triangle that is opaque everywhere.
    const OPAQUE: u32 = u32::MAX;

    /// The cut-outs of mesh `mesh` of `scene` with its current materials; `None` when no
    /// triangle of the mesh can have a hole (no cut-out material, or one whose factor
    /// alone passes and that has no texture with alpha).
    pub fn new(scene: &Scene, mesh: MeshId) -> Option<Self> {
        let mesh = scene.meshes.get(mesh.index())?;
        scene.materials.iter().find(|m| m.alpha_cutoff.is_some())?;
        let mut test_of_material = vec![None::<u32>; scene.materials.len()];
        let mut tests = Vec::new();
        let mut any = false;
        for (i, m) in scene.materials.iter().enumerate() {
            if let Some(test) = alpha_test(scene, m) {
                test_of_material[i] = Some(tests.len() as u32);
                tests.push(test);
            }
        }
        if tests.is_empty() {
            return None;
        }
        let test_of_triangle: Vec<u32> = mesh
            .triangle_materials
            .iter()
            .map(
                |m| match test_of_material.get(m.index()).copied().flatten() {
                    Some(t) => {
                        any = true;
                        t
                    }
                    None => Self::OPAQUE,
                },
            )
            .collect();
        any.then(|| Self {
            mesh: Arc::clone(mesh),
            test_of_triangle,
            tests,
        })
    }

    /// [`MeshCutout::new`] for every mesh of `scene`, indexed like `scene.meshes`; one
    /// pass over the materials when none cuts out (the rasterizer asks once per view).
    pub fn all(scene: &Scene) -> Vec<Option<Self>> {
        if scene.materials.iter().all(|m| m.alpha_cutoff.is_none()) {
            return vec![None; scene.meshes.len()];
        }
        (0..scene.meshes.len())
            .map(|m| Self::new(scene, MeshId(m as u32)))
            .collect()
    }

    /// True when triangle `triangle` may have holes (its material cuts out).
    #[inline]
    pub fn is_tested(&self, triangle: u32) -> bool {
        self.test_of_triangle
            .get(triangle as usize)
            .is_some_and(|&t| t != Self::OPAQUE)
    }

    /// True when the surface of triangle `triangle` is there at barycentrics `b`
    /// (weights of its second and third corners, as in `Hit::barycentrics`).
    #[inline]
    pub fn keeps(&self, triangle: u32, b: Vec2) -> bool {
        let Some(&t) = self.test_of_triangle.get(triangle as usize) else {
            return true;
        };
        let Some(test) = self.tests.get(t as usize) else {
            return true;
        };
        let mut alpha = test.alpha;
        if let Some(texture) = &test.texture
            && !self.mesh.uvs.is_empty()
        {
            let [i0, i1, i2] = self.mesh.indices[triangle as usize].map(|i| i as usize);
            let uv = self.mesh.uvs[i0] * (1.0 - b.x - b.y)
                + self.mesh.uvs[i1] * b.x
                + self.mesh.uvs[i2] * b.y;
            let uv = test.transform.map_or(uv, |t| t.apply(uv));
            alpha *= texture.sample_alpha(uv);
        }
        alpha >= test.cutoff
    }
}

/// The test of material `m`, `None` when it never cuts anything out.
fn alpha_test(scene: &Scene, m: &Material) -> Option<AlphaTest> {
    let cutoff = m.alpha_cutoff?;
    let texture = m
        .alpha_texture
        .and_then(|t| scene.textures.get(t.index()))
        .filter(|t| !t.alpha.is_empty())
        .cloned();
    // Without a texture the factor decides everywhere; a factor of 0 makes a fully cut
    // surface, which still needs the test.
    if texture.is_none() && m.alpha >= cutoff {
        return None;
    }
    let transform = if m.alpha_texture == m.base_color_texture {
        m.base_color_transform
    } else {
        None
    };
    Some(AlphaTest {
        alpha: m.alpha,
        cutoff,
        texture,
        transform,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::builtin::SceneBuilder;
    use crate::{Trs, WrapMode};
    use illume_core::{Rgb, Vec3};

    /// A quad of two triangles with UVs over [0, 1]², material 0, and a 2×1 texture whose
    /// left texel is opaque and right texel transparent.
    fn quad_scene(cutoff: Option<f32>, alpha: f32) -> Scene {
        let mut b = SceneBuilder::new();
        let tex = b.texture(Texture {
            name: "half".into(),
            width: 2,
            height: 1,
            texels: vec![Rgb::ONE; 2],
            wrap_u: WrapMode::Clamp,
            wrap_v: WrapMode::Clamp,
            alpha: vec![255, 0],
        });
        let m = b.material(Material {
            base_color_texture: Some(tex),
            alpha_texture: Some(tex),
            alpha_cutoff: cutoff,
            alpha,
            ..Material::default()
        });
        let mesh = b.mesh(Mesh {
            name: "quad".into(),
            positions: vec![
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(1.0, 0.0, 0.0),
                Vec3::new(1.0, 1.0, 0.0),
                Vec3::new(0.0, 1.0, 0.0),
            ],
            normals: vec![],
            uvs: vec![
                Vec2::new(0.0, 0.0),
                Vec2::new(1.0, 0.0),
                Vec2::new(1.0, 1.0),
                Vec2::new(0.0, 1.0),
            ],
            tangents: vec![],
            indices: vec![[0, 1, 2], [0, 2, 3]],
            triangle_materials: vec![m, m],
        });
        b.placed("quad", mesh, Trs::default(), false);
        b.finish("test")
    }

    #[test]
    fn a_mask_keeps_the_opaque_texels_and_cuts_the_others() {
        let scene = quad_scene(Some(0.5), 1.0);
        let cut = MeshCutout::new(&scene, MeshId(0)).expect("the material cuts out");
        assert!(cut.is_tested(0) && cut.is_tested(1));
        // Triangle 0 = corners (0,0), (1,0), (1,1): b = (b1, b2) weights of (1,0), (1,1).
        // u = b1 + b2; the texture's alpha falls from 1 at u ≤ 0.25 to 0 at u ≥ 0.75.
        assert!(cut.keeps(0, Vec2::new(0.1, 0.05)));
        assert!(!cut.keeps(0, Vec2::new(0.6, 0.3)));
        // The cutoff 0.5 is reached half-way, at u = 0.5.
        assert!(cut.keeps(0, Vec2::new(0.45, 0.0)));
        assert!(!cut.keeps(0, Vec2::new(0.55, 0.0)));
    }

    #[test]
    fn opaque_materials_and_passing_factors_need_no_test() {
        assert!(MeshCutout::new(&quad_scene(None, 1.0), MeshId(0)).is_none());
        let mut scene = quad_scene(Some(0.5), 1.0);
        scene.textures[0] = Arc::new(Texture {
            alpha: vec![],
            ..(*scene.textures[0]).clone()
        });
        assert!(MeshCutout::new(&scene, MeshId(0)).is_none());
        // A factor below the cutoff cuts every point, texture or not.
        scene.materials[0].alpha = 0.25;
        let cut = MeshCutout::new(&scene, MeshId(0)).expect("factor below the cutoff");
        assert!(!cut.keeps(1, Vec2::new(0.2, 0.2)));
    }
}
