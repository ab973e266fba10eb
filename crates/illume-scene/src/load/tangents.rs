//! MikkTSpace tangents for normal-mapped meshes (the `bevy_mikktspace` port of the
//! reference implementation, as glTF asks for when a file has no `TANGENT`).

use crate::model::Mesh;
use illume_core::{Vec3, Vec4};

struct Faces<'a> {
    mesh: &'a Mesh,
    /// Per vertex: the sum of the tangents generated for its face corners, and the sign.
    sums: Vec<(Vec3, f32)>,
}

impl bevy_mikktspace::Geometry for Faces<'_> {
    fn num_faces(&self) -> usize {
        self.mesh.indices.len()
    }
    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }
    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.positions[self.mesh.indices[face][vert] as usize].to_array()
    }
    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.mesh.normals[self.mesh.indices[face][vert] as usize].to_array()
    }
    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.mesh.uvs[self.mesh.indices[face][vert] as usize].to_array()
    }
    fn set_tangent_encoded(&mut self, tangent: [f32; 4], face: usize, vert: usize) {
        let v = self.mesh.indices[face][vert] as usize;
        let (sum, sign) = &mut self.sums[v];
        *sum += Vec3::new(tangent[0], tangent[1], tangent[2]);
        *sign = tangent[3];
    }
}

/// Fills `mesh.tangents` (the mesh needs normals and UVs). Corners of one vertex that
/// MikkTSpace gives different tangents (UV seams shared by one vertex) get their mean.
/// False when MikkTSpace fails.
pub(crate) fn generate(mesh: &mut Mesh) -> bool {
    let mut faces = Faces {
        mesh,
        sums: vec![(Vec3::ZERO, 1.0); mesh.positions.len()],
    };
    if !bevy_mikktspace::generate_tangents(&mut faces) {
        return false;
    }
    let tangents = faces
        .sums
        .iter()
        .map(|(t, sign)| {
            t.normalize_or(Vec3::X)
                .extend(if *sign < 0.0 { -1.0 } else { 1.0 })
        })
        .collect::<Vec<Vec4>>();
    mesh.tangents = tangents;
    true
}
