//! Meshes: `TRIANGLES` primitives concatenated into one illume mesh per glTF mesh, with
//! their attributes, per-triangle materials, cut-outs and tangents.

use super::Ctx;
use crate::load::{LoadError, excerpt};
use crate::model::{MaterialId, Mesh, MeshId};
use ::gltf::json;
use illume_core::{Vec2, Vec3};
use json::validation::Checked;

/// One primitive's vertices and triangles, read and checked.
struct Primitive {
    positions: Vec<Vec3>,
    /// Unit normals; zero (flat shading) when the primitive has none.
    normals: Vec<Vec3>,
    /// Whether the file gave the normals.
    has_normals: bool,
    uvs: Vec<Vec2>,
    /// Vertex indices, three per triangle.
    indices: Vec<u32>,
    material: MaterialId,
}

impl Ctx<'_> {
    /// The illume mesh of glTF mesh `index`, converted on first use.
    pub(super) fn mesh(&mut self, index: usize) -> Result<MeshId, LoadError> {
        if let Some(&id) = self.meshes.get(&index) {
            return Ok(id);
        }
        let root = self.root;
        let gm = root
            .meshes
            .get(index)
            .ok_or_else(|| self.malformed(format!("mesh {index}"), "does not exist"))?;
        let name = gm.name.clone().unwrap_or_else(|| format!("mesh {index}"));
        let mut mesh = Mesh {
            name: name.clone(),
            ..Default::default()
        };
        let shown = excerpt(&name);
        let mut with_normals = 0;
        let mut prim_normals: Vec<Vec<Vec3>> = Vec::new();
        for (p, prim) in gm.primitives.iter().enumerate() {
            let place = format!("mesh {index} '{shown}' primitive {p}");
            let prim = self.primitive(prim, &place)?;
            with_normals += prim.has_normals as usize;
            let base = mesh.positions.len() as u32;
            mesh.positions.extend(prim.positions);
            mesh.uvs.extend(prim.uvs);
            prim_normals.push(prim.normals);
            for t in prim.indices.chunks_exact(3) {
                mesh.indices.push([base + t[0], base + t[1], base + t[2]]);
                mesh.triangle_materials.push(prim.material);
            }
        }
        // Each primitive keeps its own attributes: with normals smooth, without flat
        // (zero normals select the geometric normal).
        if with_normals > 0 {
            mesh.normals = prim_normals.into_iter().flatten().collect();
        }
        self.tangents_for_normal_maps(&mut mesh, &format!("mesh {index} '{shown}'"));
        let id = self.builder.mesh(mesh);
        self.meshes.insert(index, id);
        Ok(id)
    }

    /// Primitive `prim` (at `place`, for messages): its mode, attributes, indices and
    /// material, checked in that order.
    fn primitive(
        &mut self,
        prim: &json::mesh::Primitive,
        place: &str,
    ) -> Result<Primitive, LoadError> {
        use json::accessor::ComponentType as C;
        use json::mesh::{Mode, Semantic};
        match prim.mode {
            Checked::Valid(Mode::Triangles) => {}
            Checked::Valid(other) => {
                return Err(LoadError::unsupported(
                    self.path,
                    place,
                    format!("primitive mode {other:?} (only TRIANGLES)"),
                ));
            }
            Checked::Invalid => return Err(self.malformed(place, "invalid primitive mode")),
        }
        if prim.targets.as_ref().is_some_and(|t| !t.is_empty()) {
            self.warn(format!("{place}: morph targets ignored"));
        }
        let attr = |s: Semantic| prim.attributes.get(&Checked::Valid(s)).map(|a| a.value());
        let pos_acc = attr(Semantic::Positions)
            .ok_or_else(|| self.malformed(place, "no POSITION attribute"))?;
        self.check_component_type(pos_acc, &format!("{place} POSITION"), &[C::F32], "FLOAT")?;
        let positions: Vec<Vec3> = self
            .read_vecs::<3>(pos_acc, &format!("{place} POSITION"))?
            .into_iter()
            .map(Vec3::from)
            .collect();
        let n = positions.len();
        let normals = match attr(Semantic::Normals) {
            Some(a) => Some(self.primitive_normals(a, place, n)?),
            None => None,
        };
        // The set the primitive's material reads its textures at.
        let set = prim
            .material
            .and_then(|m| self.uv_sets.get(&m.value()).copied())
            .unwrap_or(0);
        let uvs: Vec<Vec2> = match attr(Semantic::TexCoords(set)) {
            Some(a) => self.primitive_uvs(a, place, set, n)?,
            None => vec![Vec2::ZERO; n],
        };
        let indices: Vec<u32> = match prim.indices {
            Some(a) => self.primitive_indices(a.value(), place, n)?,
            None => (0..n as u32).collect(),
        };
        if !indices.len().is_multiple_of(3) {
            return Err(self.malformed(
                place,
                format!("{} indices is not a multiple of 3", indices.len()),
            ));
        }
        let material = match prim.material {
            Some(m) => *self.materials.get(m.value()).ok_or_else(|| {
                self.malformed(place, format!("material {} does not exist", m.value()))
            })?,
            None => self.default_material(),
        };
        Ok(Primitive {
            has_normals: normals.is_some(),
            // Zero normals mark flat shading (the geometric normal is used where the
            // interpolated normal is zero), used when another primitive has normals.
            normals: normals.unwrap_or_else(|| vec![Vec3::ZERO; n]),
            positions,
            uvs,
            indices,
            material,
        })
    }

    /// The NORMAL accessor `a` of the primitive at `place` with `n` positions, unit.
    fn primitive_normals(&self, a: usize, place: &str, n: usize) -> Result<Vec<Vec3>, LoadError> {
        use json::accessor::ComponentType as C;
        self.check_component_type(a, &format!("{place} NORMAL"), &[C::F32], "FLOAT")?;
        let v: Vec<Vec3> = self
            .read_vecs::<3>(a, &format!("{place} NORMAL"))?
            .into_iter()
            .map(|x| Vec3::from(x).normalize_or(Vec3::Y))
            .collect();
        if v.len() != n {
            return Err(self.malformed(
                format!("accessor {a} ({place} NORMAL)"),
                format!("{} normals for {n} positions", v.len()),
            ));
        }
        Ok(v)
    }

    /// The TEXCOORD_`set` accessor `a` of the primitive at `place` with `n` positions.
    fn primitive_uvs(
        &self,
        a: usize,
        place: &str,
        set: u32,
        n: usize,
    ) -> Result<Vec<Vec2>, LoadError> {
        use json::accessor::ComponentType as C;
        self.check_component_type(
            a,
            &format!("{place} TEXCOORD_{set}"),
            &[C::F32, C::U8, C::U16],
            "FLOAT, UNSIGNED_BYTE, UNSIGNED_SHORT",
        )?;
        let v: Vec<Vec2> = self
            .read_vecs::<2>(a, &format!("{place} TEXCOORD_{set}"))?
            .into_iter()
            .map(Vec2::from)
            .collect();
        if v.len() != n {
            return Err(self.malformed(
                format!("accessor {a} ({place} TEXCOORD_{set})"),
                format!("{} UVs for {n} positions", v.len()),
            ));
        }
        Ok(v)
    }

    /// The index accessor `a` of the primitive at `place`: SCALAR unsigned integers,
    /// each below `n` (the vertices).
    fn primitive_indices(&self, a: usize, place: &str, n: usize) -> Result<Vec<u32>, LoadError> {
        use json::accessor::ComponentType as C;
        let what = format!("{place} indices");
        self.check_component_type(
            a,
            &what,
            &[C::U8, C::U16, C::U32],
            "UNSIGNED_BYTE, UNSIGNED_SHORT, UNSIGNED_INT",
        )?;
        let (v, comps) = self.read_accessor(a, &what)?;
        if comps != 1 {
            return Err(self.malformed(format!("accessor {a} ({what})"), "indices must be SCALAR"));
        }
        let mut out = Vec::with_capacity(v.len());
        for (k, &i) in v.iter().enumerate() {
            if i < 0.0 || i >= n as f64 || i.fract() != 0.0 {
                return Err(self.malformed(
                    format!("accessor {a} ({what})"),
                    format!("index {k} = {i} out of range ({n} vertices)"),
                ));
            }
            out.push(i as u32);
        }
        Ok(out)
    }

    /// MikkTSpace tangents for `mesh` (named `shown` in warnings) when a material of
    /// its triangles has a normal map; a warning when they cannot be made.
    fn tangents_for_normal_maps(&mut self, mesh: &mut Mesh, shown: &str) {
        let normal_mapped = mesh.triangle_materials.iter().any(|m| {
            self.builder.scene().materials[m.index()]
                .normal_texture
                .is_some()
        });
        if normal_mapped {
            if mesh.normals.is_empty() || mesh.uvs.is_empty() {
                self.warn(format!(
                    "{shown}: a normal map needs normals and TEXCOORD_0; it is not applied"
                ));
            } else if !crate::load::tangents::generate(mesh) {
                self.warn(format!(
                    "{shown}: MikkTSpace found no tangents; the normal map is not applied"
                ));
            }
        }
    }
}
