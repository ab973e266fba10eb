//! The mesh level: one BVH per mesh, built once in object space, with the mesh's
//! triangles copied in leaf order (corner plus two edges, eight triangles to a packet) so
//! a leaf is one contiguous run of packets.

use crate::BvhSettings;
use crate::build::{BinaryBvh, BuildParams, build_binary};
use crate::kernel::BoxKernel;
use crate::split::split_references;
use crate::wide::{MAX_LEAF, PreparedRay, StackEntry, WideBvh, traverse};

use illume_core::{Aabb, Vec2, Vec3, Vec4};
use illume_scene::{Mesh, MeshCutout};

/// Triangles per packet.
pub(crate) const LANES: usize = 8;

/// Up to eight triangles ready for Möller–Trumbore (320 bytes: five cache lines, aligned
/// to start a line), tested together in one 8-lane pass
/// (AVX2) or two 4-lane halves (portable): corners `v0`, edges `e1 = v1 − v0` and
/// `e2 = v2 − v0` (structure of arrays), and each lane's triangle index in the mesh. Used
/// lanes come first; an unused lane has zero edges (it never hits) and index
/// [`TrianglePacket::UNUSED`].
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub(crate) struct TrianglePacket {
    /// `[v0.x, v0.y, v0.z, e1.x, e1.y, e1.z, e2.x, e2.y, e2.z]`, one array lane per triangle.
    pub coords: [[f32; LANES]; 9],
    /// Mesh triangle index per lane.
    pub index: [u32; LANES],
}

const _: () = assert!(std::mem::size_of::<TrianglePacket>() == 320);

impl TrianglePacket {
    /// Index of an unused lane.
    pub const UNUSED: u32 = u32::MAX;

    /// Packs up to eight triangles given as `(index, corners)`.
    fn new(tris: &[(u32, [Vec3; 3])]) -> Self {
        debug_assert!(!tris.is_empty() && tris.len() <= LANES);
        let mut p = TrianglePacket {
            coords: [[0.0; LANES]; 9],
            index: [Self::UNUSED; LANES],
        };
        for (lane, &(index, [v0, v1, v2])) in tris.iter().enumerate() {
            let (e1, e2) = (v1 - v0, v2 - v0);
            for (k, value) in [v0.x, v0.y, v0.z, e1.x, e1.y, e1.z, e2.x, e2.y, e2.z]
                .into_iter()
                .enumerate()
            {
                p.coords[k][lane] = value;
            }
            p.index[lane] = index;
        }
        p
    }

    /// Used lanes as `(mesh triangle index, corners)`; corners are rebuilt from the edges,
    /// so within rounding of the mesh's.
    pub fn triangles(&self) -> impl Iterator<Item = (u32, [Vec3; 3])> + '_ {
        (0..LANES)
            .filter(|&l| self.index[l] != Self::UNUSED)
            .map(|l| {
                let c = |k: usize| {
                    Vec3::new(
                        self.coords[k][l],
                        self.coords[k + 1][l],
                        self.coords[k + 2][l],
                    )
                };
                let (v0, e1, e2) = (c(0), c(3), c(6));
                (self.index[l], [v0, v0 + e1, v0 + e2])
            })
    }

    /// Number of 4-lane halves with a used lane (1 or 2).
    #[inline(always)]
    pub(crate) fn halves(&self) -> usize {
        1 + usize::from(self.index[4] != Self::UNUSED)
    }

    /// Per lane of half `half` (lanes `4·half .. 4·half + 4`): hit distance (valid where
    /// the returned bit is set), barycentrics `b1`, `b2`; bit `i` marks lane `4·half + i`
    /// hit with `t` in `(ray.t_min, t_max)`. The arithmetic and the acceptance on edges
    /// are those of [`crate::triangle::intersect_triangle`].
    #[inline(always)]
    pub(crate) fn intersect_half(
        &self,
        half: usize,
        ray: &PreparedRay,
        t_max: f32,
    ) -> (Vec4, Vec4, Vec4, u32) {
        let lanes = 4 * half..4 * half + 4;
        let c = |k: usize| Vec4::from_slice(&self.coords[k][lanes.clone()]);
        let (e1x, e1y, e1z) = (c(3), c(4), c(5));
        let (e2x, e2y, e2z) = (c(6), c(7), c(8));
        let [dx, dy, dz] = ray.dir.to_array().map(Vec4::splat);
        // pvec = dir × e2
        let px = dy * e2z - dz * e2y;
        let py = dz * e2x - dx * e2z;
        let pz = dx * e2y - dy * e2x;
        let det = e1x * px + e1y * py + e1z * pz;
        let inv_det = Vec4::ONE / det;
        let [ox, oy, oz] = ray.origin.to_array().map(Vec4::splat);
        let (tx, ty, tz) = (ox - c(0), oy - c(1), oz - c(2));
        let b1 = (tx * px + ty * py + tz * pz) * inv_det;
        let first = det.abs().cmpge(Vec4::splat(f32::MIN_POSITIVE))
            & b1.cmpge(Vec4::ZERO)
            & b1.cmple(Vec4::ONE);
        if !first.any() {
            // Most packets a ray meets miss on the first barycentric: skip the rest.
            return (Vec4::ZERO, Vec4::ZERO, Vec4::ZERO, 0);
        }
        // qvec = tvec × e1
        let qx = ty * e1z - tz * e1y;
        let qy = tz * e1x - tx * e1z;
        let qz = tx * e1y - ty * e1x;
        let b2 = (dx * qx + dy * qy + dz * qz) * inv_det;
        let t = (e2x * qx + e2y * qy + e2z * qz) * inv_det;
        let valid = first
            & b2.cmpge(Vec4::ZERO)
            & (b1 + b2).cmple(Vec4::ONE)
            & t.cmpgt(Vec4::splat(ray.t_min))
            & t.cmplt(Vec4::splat(t_max));
        (t, b1, b2, valid.bitmask())
    }
}

/// A binary tree whose leaves index triangle packets, with its SAH cost.
struct PackedTree {
    bin: BinaryBvh,
    packets: Vec<TrianglePacket>,
    /// Expected cost of a ray through the root: Σ over nodes of (area ÷ root area) ×
    /// (node cost for an interior node, packets for a leaf).
    sah: f32,
}

impl PackedTree {
    /// The binary SAH tree over `boxes` (references to the triangles `owner` names, or one
    /// box per triangle when `owner` is empty), its leaves repacked into whole packets. A
    /// triangle whose references land twice in one leaf is stored there once.
    fn build(corners: &[[Vec3; 3]], boxes: &[Aabb], owner: &[u32], params: BuildParams) -> Self {
        let mut bin = build_binary(boxes, owner, params);
        let triangle = |r: u32| {
            if owner.is_empty() {
                r
            } else {
                owner[r as usize]
            }
        };
        let mut packets = Vec::with_capacity(boxes.len() / 6 + 1);
        let mut tris: Vec<(u32, [Vec3; 3])> = Vec::with_capacity(4 * MAX_LEAF);
        for node in bin.nodes.iter_mut().filter(|n| n.count > 0) {
            tris.clear();
            for &r in &bin.order[node.first as usize..(node.first + node.count) as usize] {
                let t = triangle(r);
                if !tris.iter().any(|&(u, _)| u == t) {
                    tris.push((t, corners[t as usize]));
                }
            }
            let first = packets.len() as u32;
            packets.extend(tris.chunks(LANES).map(TrianglePacket::new));
            node.first = first;
            node.count = packets.len() as u32 - first;
        }
        let root = bin.nodes.first().map_or(0.0, |n| n.bounds.surface_area());
        let sah = if root > 0.0 {
            bin.nodes
                .iter()
                .map(|n| {
                    let cost = if n.count > 0 {
                        n.count as f32
                    } else {
                        params.traversal_cost
                    };
                    n.bounds.surface_area() / root * cost
                })
                .sum()
        } else {
            0.0
        };
        Self { bin, packets, sah }
    }
}

/// One mesh's BVH, in the mesh's object space.
#[derive(Clone, Debug)]
pub(crate) struct Blas {
    /// The tree; leaves index `packets`.
    pub bvh: WideBvh,
    /// Triangles in leaf order, eight to a packet (a leaf is a run of whole packets).
    pub packets: Vec<TrianglePacket>,
    /// Number of mesh triangles.
    pub triangle_count: usize,
    /// Holes of the mesh's alpha-masked triangles, `None` when it has none: a hit in a
    /// hole is no hit.
    pub cutout: Option<MeshCutout>,
}

impl Blas {
    /// Builds the BVH of `mesh` (binned SAH, then collapsed to eight-wide nodes), whose
    /// alpha-masked triangles have the holes of `cutout`.
    ///
    /// With a split budget (see [`BvhSettings::split_budget`]), two trees are built, one
    /// after the other (each in parallel inside): one over the triangles, one over
    /// pre-split references
    /// ([`crate::split`]); the one the surface area heuristic expects to be cheaper to
    /// traverse is kept. Splitting pays where long diagonal triangles cross a large mesh
    /// (Sponza's floors and arches) and costs where the pieces of a few large triangles
    /// join the boxes of their small neighbours (a Cornell box's walls around its
    /// spheres); the heuristic tells the two apart.
    pub fn build(mesh: &Mesh, cutout: Option<MeshCutout>, settings: &BvhSettings) -> Blas {
        let corners: Vec<[Vec3; 3]> = (0..mesh.triangle_count())
            .map(|t| mesh.triangle(t))
            .collect();
        let params = BuildParams {
            traversal_cost: settings.node_cost,
            max_leaf: settings.max_leaf_triangles.clamp(1, 4 * MAX_LEAF),
            block: if settings.packet_aware_sah { 4 } else { 1 },
        };
        let plain = || {
            let boxes: Vec<Aabb> = corners.iter().map(|&c| Aabb::from_points(c)).collect();
            PackedTree::build(&corners, &boxes, &[], params)
        };
        let split = || {
            let (boxes, owner) = split_references(&corners, settings.split_budget);
            // No reference made: the same tree as without splitting.
            (boxes.len() > corners.len())
                .then(|| PackedTree::build(&corners, &boxes, &owner, params))
        };
        let tree = if settings.split_budget > 0.0 {
            // One after the other: each build is parallel inside, and two at once
            // contend for the cores and the memory bus.
            match (plain(), split()) {
                (plain, Some(split)) if split.sah < plain.sah => split,
                (plain, _) => plain,
            }
        } else {
            plain()
        };
        let bvh = WideBvh::from_binary(&tree.bin, &|_, _| u32::MAX);
        Blas {
            bvh,
            packets: tree.packets,
            triangle_count: mesh.triangle_count(),
            cutout,
        }
    }

    /// Triangle slots used in the leaves: the triangle count, or more where pre-split
    /// triangles sit in several leaves.
    pub fn stored_triangles(&self) -> usize {
        self.packets
            .iter()
            .map(|p| {
                p.index
                    .iter()
                    .filter(|&&i| i != TrianglePacket::UNUSED)
                    .count()
            })
            .sum()
    }

    /// Object-space bounds.
    pub fn bounds(&self) -> Aabb {
        self.bvh.bounds
    }

    /// Bytes used by nodes and triangles.
    pub fn memory_bytes(&self) -> usize {
        self.bvh.memory_bytes() + self.packets.len() * std::mem::size_of::<TrianglePacket>()
    }

    /// Object-space hit point and unnormalised front normal of lane `lane` of packet
    /// `packet` at barycentrics `b`: `v0 + b1·e1 + b2·e2` and `e1 × e2`.
    #[inline]
    pub fn geometry(&self, packet: u32, lane: u32, b: Vec2) -> (Vec3, Vec3) {
        let c = &self.packets[packet as usize].coords;
        let l = lane as usize;
        let v0 = Vec3::new(c[0][l], c[1][l], c[2][l]);
        let e1 = Vec3::new(c[3][l], c[4][l], c[5][l]);
        let e2 = Vec3::new(c[6][l], c[7][l], c[8][l]);
        (v0 + e1 * b.x + e2 * b.y, e1.cross(e2))
    }

    /// Closest hit `(t, triangle index, barycentrics, packet index, lane)` with
    /// `t < t_max`.
    #[inline(always)]
    pub fn intersect<K: BoxKernel>(
        &self,
        k: K,
        ray: &PreparedRay,
        t_max: f32,
        stack: &mut [StackEntry],
    ) -> Option<(f32, u32, Vec2, u32, u32)> {
        // Meshes without holes pay nothing for them: the test is compiled out.
        if self.cutout.is_some() {
            self.intersect_with::<K, true>(k, ray, t_max, stack)
        } else {
            self.intersect_with::<K, false>(k, ray, t_max, stack)
        }
    }

    /// [`Blas::intersect`], testing alpha-mask holes when `CUT`.
    #[inline(always)]
    fn intersect_with<K: BoxKernel, const CUT: bool>(
        &self,
        k: K,
        ray: &PreparedRay,
        t_max: f32,
        stack: &mut [StackEntry],
    ) -> Option<(f32, u32, Vec2, u32, u32)> {
        let mut best = None;
        traverse::<K, false>(
            k,
            &self.bvh,
            ray,
            t_max,
            u32::MAX,
            stack,
            #[inline(always)]
            |range, t_max, _| {
                let packets = &self.packets[range.clone()];
                for (p, packet) in packets.iter().enumerate() {
                    if K::WIDE_PACKETS {
                        // All eight lanes in one pass; the closest lane, ties to the lower
                        // lane, is the hit the two halves tested in turn would give.
                        let (t, b1, b2, mut bits) = k.intersect_packet(packet, ray, *t_max);
                        if CUT && bits != 0 {
                            bits = self.keep_packet_lanes(packet, bits, &b1, &b2);
                        }
                        if bits != 0 {
                            let lane = closest_lane(&t, bits);
                            *t_max = t[lane];
                            best = Some((
                                t[lane],
                                packet.index[lane],
                                Vec2::new(b1[lane], b2[lane]),
                                (range.start + p) as u32,
                                lane as u32,
                            ));
                        }
                        continue;
                    }
                    for half in 0..packet.halves() {
                        let (t, b1, b2, mut bits) = packet.intersect_half(half, ray, *t_max);
                        if CUT && bits != 0 {
                            bits = self.keep_lanes(packet, half, bits, b1, b2);
                        }
                        if bits != 0 {
                            let t = t.to_array();
                            let lane = closest_lane(&t, bits);
                            *t_max = t[lane];
                            best = Some((
                                t[lane],
                                packet.index[4 * half + lane],
                                Vec2::new(b1.to_array()[lane], b2.to_array()[lane]),
                                (range.start + p) as u32,
                                (4 * half + lane) as u32,
                            ));
                        }
                    }
                }
                false
            },
        );
        best
    }

    /// [`Blas::keep_lanes`] for all eight lanes of `packet` tested together.
    #[cold]
    fn keep_packet_lanes(
        &self,
        packet: &TrianglePacket,
        bits: u32,
        b1: &[f32; LANES],
        b2: &[f32; LANES],
    ) -> u32 {
        let half = |h: usize| {
            let lanes = 4 * h..4 * h + 4;
            self.keep_lanes(
                packet,
                h,
                (bits >> (4 * h)) & 15,
                Vec4::from_slice(&b1[lanes.clone()]),
                Vec4::from_slice(&b2[lanes]),
            ) << (4 * h)
        };
        half(0) | half(1)
    }

    /// True when `packet` has a hit with `t < t_max` (not in a hole, when `CUT`), tested
    /// in 4-lane halves.
    #[inline(always)]
    fn packet_occludes<const CUT: bool>(
        &self,
        packet: &TrianglePacket,
        ray: &PreparedRay,
        t_max: f32,
    ) -> bool {
        for half in 0..packet.halves() {
            let (_, b1, b2, bits) = packet.intersect_half(half, ray, t_max);
            if bits != 0 && (!CUT || self.keep_lanes(packet, half, bits, b1, b2) != 0) {
                return true;
            }
        }
        false
    }

    /// The lanes of `bits` (hits of half `half` of `packet` at barycentrics `b1`, `b2`)
    /// that are not in a hole of the cut-out.
    #[cold]
    fn keep_lanes(
        &self,
        packet: &TrianglePacket,
        half: usize,
        mut bits: u32,
        b1: Vec4,
        b2: Vec4,
    ) -> u32 {
        let Some(cutout) = &self.cutout else {
            return bits;
        };
        let (b1, b2) = (b1.to_array(), b2.to_array());
        let mut rest = bits;
        while rest != 0 {
            let lane = rest.trailing_zeros() as usize;
            rest &= rest - 1;
            let triangle = packet.index[4 * half + lane];
            if cutout.is_tested(triangle) && !cutout.keeps(triangle, Vec2::new(b1[lane], b2[lane]))
            {
                bits &= !(1 << lane);
            }
        }
        bits
    }

    /// True when any triangle is hit with `t < t_max`.
    #[inline(always)]
    pub fn occluded<K: BoxKernel>(
        &self,
        k: K,
        ray: &PreparedRay,
        t_max: f32,
        stack: &mut [StackEntry],
    ) -> bool {
        if self.cutout.is_some() {
            self.occluded_with::<K, true>(k, ray, t_max, stack)
        } else {
            self.occluded_with::<K, false>(k, ray, t_max, stack)
        }
    }

    /// [`Blas::occluded`], testing alpha-mask holes when `CUT`.
    #[inline(always)]
    fn occluded_with<K: BoxKernel, const CUT: bool>(
        &self,
        k: K,
        ray: &PreparedRay,
        t_max: f32,
        stack: &mut [StackEntry],
    ) -> bool {
        let mut hit = false;
        traverse::<K, false>(
            k,
            &self.bvh,
            ray,
            t_max,
            u32::MAX,
            stack,
            #[inline(always)]
            |range, t_max, _| {
                // Loops, not `Iterator::any`: see `Tracer::occluded_in`.
                for packet in &self.packets[range] {
                    let occludes = if K::WIDE_PACKETS {
                        let (_, b1, b2, bits) = k.intersect_packet(packet, ray, *t_max);
                        bits != 0 && (!CUT || self.keep_packet_lanes(packet, bits, &b1, &b2) != 0)
                    } else {
                        self.packet_occludes::<CUT>(packet, ray, *t_max)
                    };
                    if occludes {
                        hit = true;
                        return true;
                    }
                }
                false
            },
        );
        hit
    }
}

/// The lane of `bits` (at least one set) with the smallest `t`; ties go to the lower lane.
#[inline(always)]
fn closest_lane(t: &[f32], mut bits: u32) -> usize {
    let mut lane = bits.trailing_zeros() as usize;
    bits &= bits - 1;
    while bits != 0 {
        let l = bits.trailing_zeros() as usize;
        bits &= bits - 1;
        if t[l] < t[lane] {
            lane = l;
        }
    }
    lane
}
