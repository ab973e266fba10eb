//! Traversal kernels: the same tree walk, triangle tests and visiting order, with the
//! eight-box test of a node written for different instruction sets. The AVX2 kernel is
//! chosen at run time (`is_x86_feature_detected!`) and the whole query (instance level,
//! mesh level, triangle packets) is compiled for AVX2 inside it; the portable kernel runs
//! everywhere and is the reference the others are tested against.
//!
//! Every kernel tests triangles with the same IEEE operations in the same order (no fused
//! multiply-add), so a triangle's hit is the same bit for bit in every kernel. Box tests
//! differ in one rounding: the portable kernel computes a plane's distance as a multiply,
//! then a subtract; the AVX2 kernel fuses them (`vfmsub`, one rounding), so an entry
//! distance can differ by an ulp. Both tests are conservative (exit distances widened by
//! 2γ₃), so both kernels find the same closest hit; the one possible difference is which
//! of two triangles wins when their hit distances are equal, or within that ulp of a box
//! face's entry distance (ties go to the first triangle found, and the order children are
//! visited in rests on the entry distances). The random-ray test of every kernel
//! (`every_kernel_gives_identical_hits`) finds no such ray.
//!
//! Everything an AVX2 entry point calls must inline into it to run as AVX2 code: a
//! closure handed to a library function (`Iterator::any`, `array::map`, …) may stay out of
//! line, is then compiled without AVX2, and every intrinsic in it becomes a function call.
//! The query paths therefore use plain loops, and the intrinsics are called directly.
//!
//! `unsafe` is confined to this module: the AVX2 intrinsics of the box and triangle tests
//! and the calls of the AVX2 entry points, each with the argument that makes it sound. All
//! rest on one invariant: an [`Avx2`] value exists only on a CPU with AVX2, because its one
//! field is private to this module and only [`Avx2::detect`] makes one.
#![expect(
    unsafe_code,
    reason = "run-time selected AVX2 kernel: std::arch loads/stores and calls of #[target_feature] functions, each proven sound below"
)]

use crate::Tracer;
use crate::blas::TrianglePacket;
use crate::tracer::Closest;
use crate::wide::{EXIT_SCALE, PreparedRay, StackEntry, WIDTH, WideNode};
use illume_core::{Ray, Vec4};
use std::sync::OnceLock;

/// A traversal kernel: the instruction set a [`Tracer`]'s queries run in. Every kernel
/// returns the same hits bit for bit, except possibly which of two triangles at equal
/// distance wins (see the module documentation); they differ in speed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TraversalKernel {
    /// Two 4-lane box tests per node through `glam` (SSE2 on x86-64): runs on every CPU.
    Portable,
    /// One 8-lane AVX2 box test per node (with fused multiply-subtract), the whole query
    /// compiled for AVX2 and FMA: x86-64 CPUs with both, detected at run time.
    Avx2,
}

/// The environment variable that forces a kernel for every new [`Tracer`]: `portable` or
/// `avx2` (for tests and measurements).
pub const KERNEL_ENV: &str = "ILLUME_ACCEL_KERNEL";

impl TraversalKernel {
    /// Every kernel, available on this CPU or not.
    pub const ALL: [TraversalKernel; 2] = [TraversalKernel::Portable, TraversalKernel::Avx2];

    /// The kernel's name as [`KERNEL_ENV`] spells it.
    pub fn name(self) -> &'static str {
        match self {
            TraversalKernel::Portable => "portable",
            TraversalKernel::Avx2 => "avx2",
        }
    }

    /// True when this CPU can run the kernel.
    pub fn is_available(self) -> bool {
        Kernel::new(self).is_some()
    }

    /// The kernels this CPU can run, portable first.
    pub fn available() -> Vec<TraversalKernel> {
        Self::ALL.into_iter().filter(|k| k.is_available()).collect()
    }

    /// The kernel a new [`Tracer`] uses: the one named by [`KERNEL_ENV`] when it is set,
    /// else the fastest available (AVX2 where present). Panics when the variable names an
    /// unknown kernel or one this CPU cannot run (a forced choice is never ignored).
    pub fn default_for_this_cpu() -> TraversalKernel {
        static CHOICE: OnceLock<TraversalKernel> = OnceLock::new();
        *CHOICE.get_or_init(|| match std::env::var(KERNEL_ENV) {
            Ok(name) => {
                let kernel = Self::ALL
                    .into_iter()
                    .find(|k| k.name() == name.trim())
                    .unwrap_or_else(|| {
                        panic!("{KERNEL_ENV}={name}: unknown kernel (portable, avx2)")
                    });
                assert!(
                    kernel.is_available(),
                    "{KERNEL_ENV}={name}: this CPU cannot run that kernel"
                );
                kernel
            }
            Err(_) => *Self::available()
                .last()
                .unwrap_or(&TraversalKernel::Portable),
        })
    }
}

/// [`Tracer::set_kernel`] was asked for a kernel this CPU cannot run.
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
#[error("traversal kernel {0:?} is not available on this CPU")]
pub struct KernelUnavailable(pub TraversalKernel);

/// A kernel this CPU can run: holding one proves the instruction set is present.
#[derive(Clone, Copy, Debug)]
pub(crate) enum Kernel {
    /// [`TraversalKernel::Portable`].
    Portable(Portable),
    /// [`TraversalKernel::Avx2`].
    #[cfg(target_arch = "x86_64")]
    Avx2(Avx2),
}

impl Kernel {
    /// The kernel `kind`, if this CPU can run it.
    pub fn new(kind: TraversalKernel) -> Option<Kernel> {
        match kind {
            TraversalKernel::Portable => Some(Kernel::Portable(Portable)),
            #[cfg(target_arch = "x86_64")]
            TraversalKernel::Avx2 => Avx2::detect().map(Kernel::Avx2),
            #[cfg(not(target_arch = "x86_64"))]
            TraversalKernel::Avx2 => None,
        }
    }

    /// Which kernel this is.
    pub fn kind(self) -> TraversalKernel {
        match self {
            Kernel::Portable(_) => TraversalKernel::Portable,
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2(_) => TraversalKernel::Avx2,
        }
    }
}

/// The box test of one wide node and the triangle test of a leaf's packets.
pub(crate) trait BoxKernel: Copy {
    /// True when [`BoxKernel::intersect_packet`] tests a packet's eight lanes in one
    /// pass: leaves then use it (else they test packets in 4-lane halves, with
    /// `TrianglePacket::intersect_half`).
    const WIDE_PACKETS: bool;

    /// All eight lanes of `packet` at once: per lane the hit distance, barycentrics `b1`
    /// and `b2`, and the bits of lanes hit with `t` in `(ray.t_min, t_max)`: lane for lane
    /// the results of `TrianglePacket::intersect_half`.
    fn intersect_packet(self, packet: &TrianglePacket, ray: &PreparedRay, t_max: f32)
    -> PacketHits;

    /// Entry distances of the child boxes of `node` and a bit mask of the children hit
    /// within `(ray.t_min, t_max)` (and, when `MASKED`, whose mask meets `mask`). Unused
    /// slots (empty boxes) never hit.
    fn hit_boxes<const MASKED: bool>(
        self,
        ray: &PreparedRay,
        node: &WideNode,
        t_max: f32,
        mask: u32,
    ) -> ([f32; WIDTH], u32);
}

/// Clears the bits of children whose mask misses `mask`.
#[inline(always)]
fn mask_bits(node: &WideNode, mut bits: u32, mask: u32) -> u32 {
    for (i, m) in node.masks.iter().enumerate() {
        if m & mask == 0 {
            bits &= !(1 << i);
        }
    }
    bits
}

/// A packet's hits: `(t, b1, b2, lane bits)`, eight lanes each.
pub(crate) type PacketHits = ([f32; 8], [f32; 8], [f32; 8], u32);

/// The portable kernel: two 4-lane halves per node and per triangle packet.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Portable;

impl BoxKernel for Portable {
    const WIDE_PACKETS: bool = false;

    #[inline(always)]
    fn intersect_packet(
        self,
        packet: &TrianglePacket,
        ray: &PreparedRay,
        t_max: f32,
    ) -> PacketHits {
        let mut out = ([0.0; 8], [0.0; 8], [0.0; 8], 0);
        for half in 0..2 {
            let (t, b1, b2, bits) = packet.intersect_half(half, ray, t_max);
            let lanes = 4 * half..4 * half + 4;
            t.write_to_slice(&mut out.0[lanes.clone()]);
            b1.write_to_slice(&mut out.1[lanes.clone()]);
            b2.write_to_slice(&mut out.2[lanes]);
            out.3 |= bits << (4 * half);
        }
        out
    }

    #[inline(always)]
    fn hit_boxes<const MASKED: bool>(
        self,
        ray: &PreparedRay,
        node: &WideNode,
        t_max: f32,
        mask: u32,
    ) -> ([f32; WIDTH], u32) {
        let b = &node.bounds;
        let [nx, ny, nz] = ray.near;
        let [fx, fy, fz] = ray.far;
        let [ix, iy, iz] = ray.inv_dir.map(Vec4::splat);
        let [ox, oy, oz] = ray.origin_inv.map(Vec4::splat);
        let (t_min, t_max) = (Vec4::splat(ray.t_min), Vec4::splat(t_max));
        let mut dist = [0.0; WIDTH];
        let mut bits = 0;
        for half in 0..WIDTH / 4 {
            let lanes = 4 * half..4 * half + 4;
            let plane =
                |row: usize, inv: Vec4, o: Vec4| Vec4::from_slice(&b[row][lanes.clone()]) * inv - o;
            let t_near = plane(nx, ix, ox)
                .max(plane(ny, iy, oy))
                .max(plane(nz, iz, oz).max(t_min));
            let t_far = plane(fx, ix, ox)
                .min(plane(fy, iy, oy))
                .min(plane(fz, iz, oz).min(t_max))
                * EXIT_SCALE;
            t_near.write_to_slice(&mut dist[lanes.clone()]);
            bits |= t_near.cmple(t_far).bitmask() << (4 * half);
        }
        if MASKED {
            bits = mask_bits(node, bits, mask);
        }
        (dist, bits)
    }
}

/// The AVX2 kernel. A value exists only when the CPU has AVX2 and FMA ([`Avx2::detect`]).
#[cfg(target_arch = "x86_64")]
#[derive(Clone, Copy, Debug)]
pub(crate) struct Avx2(());

#[cfg(target_arch = "x86_64")]
impl Avx2 {
    /// The kernel, when this CPU has AVX2 and FMA.
    fn detect() -> Option<Avx2> {
        (is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")).then_some(Avx2(()))
    }
}

#[cfg(target_arch = "x86_64")]
impl BoxKernel for Avx2 {
    const WIDE_PACKETS: bool = true;

    /// `TrianglePacket::intersect_half` on both halves in one 8-lane pass, with the same
    /// operations in the same order (no fused multiply-add), so the same results bit for
    /// bit; the comparisons are the same ordered ones (false on NaN).
    #[inline(always)]
    fn intersect_packet(
        self,
        packet: &TrianglePacket,
        ray: &PreparedRay,
        t_max: f32,
    ) -> PacketHits {
        use std::arch::x86_64::*;
        let mut out = ([0.0f32; 8], [0.0f32; 8], [0.0f32; 8], 0);
        // SAFETY: `self` exists only if `Avx2::detect` found AVX2 on this CPU, so every
        // AVX/AVX2 intrinsic below may run. Each load reads `packet.coords[k]`, a
        // `[f32; 8]` (32 readable bytes); each store writes one of `out`'s `[f32; 8]`s (32
        // writable bytes); `loadu`/`storeu` need no alignment.
        unsafe {
            let c = |k: usize| _mm256_loadu_ps(packet.coords[k].as_ptr());
            let (e1x, e1y, e1z) = (c(3), c(4), c(5));
            let (e2x, e2y, e2z) = (c(6), c(7), c(8));
            let (dx, dy, dz) = (
                _mm256_set1_ps(ray.dir.x),
                _mm256_set1_ps(ray.dir.y),
                _mm256_set1_ps(ray.dir.z),
            );
            let mul = |x, y| _mm256_mul_ps(x, y);
            let sub = |x, y| _mm256_sub_ps(x, y);
            let add = |x, y| _mm256_add_ps(x, y);
            let px = sub(mul(dy, e2z), mul(dz, e2y));
            let py = sub(mul(dz, e2x), mul(dx, e2z));
            let pz = sub(mul(dx, e2y), mul(dy, e2x));
            let det = add(add(mul(e1x, px), mul(e1y, py)), mul(e1z, pz));
            let inv_det = _mm256_div_ps(_mm256_set1_ps(1.0), det);
            let (ox, oy, oz) = (
                _mm256_set1_ps(ray.origin.x),
                _mm256_set1_ps(ray.origin.y),
                _mm256_set1_ps(ray.origin.z),
            );
            let (tx, ty, tz) = (sub(ox, c(0)), sub(oy, c(1)), sub(oz, c(2)));
            let b1 = mul(add(add(mul(tx, px), mul(ty, py)), mul(tz, pz)), inv_det);
            let abs_det = _mm256_and_ps(det, _mm256_castsi256_ps(_mm256_set1_epi32(i32::MAX)));
            let first = _mm256_and_ps(
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_GE_OS>(abs_det, _mm256_set1_ps(f32::MIN_POSITIVE)),
                    _mm256_cmp_ps::<_CMP_GE_OS>(b1, _mm256_setzero_ps()),
                ),
                _mm256_cmp_ps::<_CMP_LE_OS>(b1, _mm256_set1_ps(1.0)),
            );
            if _mm256_movemask_ps(first) == 0 {
                // As in `TrianglePacket::intersect_half`: most packets miss on `b1`.
                return out;
            }
            let qx = sub(mul(ty, e1z), mul(tz, e1y));
            let qy = sub(mul(tz, e1x), mul(tx, e1z));
            let qz = sub(mul(tx, e1y), mul(ty, e1x));
            let b2 = mul(add(add(mul(dx, qx), mul(dy, qy)), mul(dz, qz)), inv_det);
            let t = mul(add(add(mul(e2x, qx), mul(e2y, qy)), mul(e2z, qz)), inv_det);
            let valid = _mm256_and_ps(
                _mm256_and_ps(
                    _mm256_and_ps(first, _mm256_cmp_ps::<_CMP_GE_OS>(b2, _mm256_setzero_ps())),
                    _mm256_cmp_ps::<_CMP_LE_OS>(add(b1, b2), _mm256_set1_ps(1.0)),
                ),
                _mm256_and_ps(
                    _mm256_cmp_ps::<_CMP_GT_OS>(t, _mm256_set1_ps(ray.t_min)),
                    _mm256_cmp_ps::<_CMP_LT_OS>(t, _mm256_set1_ps(t_max)),
                ),
            );
            out.3 = _mm256_movemask_ps(valid) as u32;
            _mm256_storeu_ps(out.0.as_mut_ptr(), t);
            _mm256_storeu_ps(out.1.as_mut_ptr(), b1);
            _mm256_storeu_ps(out.2.as_mut_ptr(), b2);
        }
        out
    }

    /// [`Portable::hit_boxes`] in one 8-lane pass, with each plane's multiply and
    /// subtract fused (`_mm256_fmsub_ps`, one rounding instead of two) and otherwise the
    /// same operations in the same order: `_mm256_max_ps(a, b)`/`_mm256_min_ps` return
    /// `b` when either is NaN, as `Vec4::max`/`min` (`_mm_max_ps`) do, and the
    /// comparison is the same ordered `≤`.
    ///
    /// Not a `#[target_feature]` function itself (those cannot be forced inline): it is
    /// inlined into the AVX2 entry points ([`closest_avx2`], [`occluded_avx2`]), where
    /// the intrinsics inline in turn.
    #[inline(always)]
    fn hit_boxes<const MASKED: bool>(
        self,
        ray: &PreparedRay,
        node: &WideNode,
        t_max: f32,
        mask: u32,
    ) -> ([f32; WIDTH], u32) {
        use std::arch::x86_64::*;
        const _: () = assert!(WIDTH == 8);
        let b = &node.bounds;
        let [nx, ny, nz] = ray.near;
        let [fx, fy, fz] = ray.far;
        let mut dist = [0.0f32; WIDTH];
        // SAFETY: `self` exists only if `Avx2::detect` found AVX2 and FMA on this CPU, so
        // every AVX/AVX2/FMA intrinsic below may run. Each load reads `b[row]`, a `[f32; 8]` (32
        // readable bytes), and the store writes `dist`, a `[f32; 8]` (32 writable bytes);
        // `loadu`/`storeu` have no alignment requirement.
        let bits = unsafe {
            let plane = |row: usize, axis: usize| {
                _mm256_fmsub_ps(
                    _mm256_loadu_ps(b[row].as_ptr()),
                    _mm256_set1_ps(ray.inv_dir[axis]),
                    _mm256_set1_ps(ray.origin_inv[axis]),
                )
            };
            let t_near = _mm256_max_ps(
                _mm256_max_ps(plane(nx, 0), plane(ny, 1)),
                _mm256_max_ps(plane(nz, 2), _mm256_set1_ps(ray.t_min)),
            );
            let t_far = _mm256_mul_ps(
                _mm256_min_ps(
                    _mm256_min_ps(plane(fx, 0), plane(fy, 1)),
                    _mm256_min_ps(plane(fz, 2), _mm256_set1_ps(t_max)),
                ),
                _mm256_set1_ps(EXIT_SCALE),
            );
            _mm256_storeu_ps(dist.as_mut_ptr(), t_near);
            _mm256_movemask_ps(_mm256_cmp_ps::<_CMP_LE_OS>(t_near, t_far)) as u32
        };
        (
            dist,
            if MASKED {
                mask_bits(node, bits, mask)
            } else {
                bits
            },
        )
    }
}

/// Closest hit of `ray` with `tracer`, in the tracer's kernel.
#[inline]
pub(crate) fn closest(
    tracer: &Tracer,
    ray: &Ray,
    mask: u32,
    stack: &mut [StackEntry],
) -> Option<Closest> {
    match tracer.kernel {
        Kernel::Portable(k) => tracer.closest_in(k, ray, mask, stack),
        #[cfg(target_arch = "x86_64")]
        // SAFETY: a `Kernel::Avx2` holds an `Avx2`, which exists only on CPUs with AVX2 and
        // FMA, the one requirement of `closest_avx2`.
        Kernel::Avx2(k) => unsafe { closest_avx2(tracer, k, ray, mask, stack) },
    }
}

/// Occlusion of `ray` in `tracer`, in the tracer's kernel.
#[inline]
pub(crate) fn occluded(tracer: &Tracer, ray: &Ray, mask: u32, stack: &mut [StackEntry]) -> bool {
    match tracer.kernel {
        Kernel::Portable(k) => tracer.occluded_in(k, ray, mask, stack),
        #[cfg(target_arch = "x86_64")]
        // SAFETY: as in `closest`: the `Avx2` value proves the CPU has AVX2 and FMA.
        Kernel::Avx2(k) => unsafe { occluded_avx2(tracer, k, ray, mask, stack) },
    }
}

/// [`Tracer::closest_in`] compiled for AVX2 and FMA (everything it calls is inlined into
/// it; Rust never contracts a separate multiply and add into an FMA, so only the box
/// test's explicit `_mm256_fmsub_ps` fuses).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn closest_avx2(
    tracer: &Tracer,
    k: Avx2,
    ray: &Ray,
    mask: u32,
    stack: &mut [StackEntry],
) -> Option<Closest> {
    tracer.closest_in(k, ray, mask, stack)
}

/// [`Tracer::occluded_in`] compiled for AVX2 and FMA.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn occluded_avx2(tracer: &Tracer, k: Avx2, ray: &Ray, mask: u32, stack: &mut [StackEntry]) -> bool {
    tracer.occluded_in(k, ray, mask, stack)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_portable_kernel_is_always_available_and_avx2_where_detected() {
        let available = TraversalKernel::available();
        assert_eq!(available[0], TraversalKernel::Portable);
        #[cfg(target_arch = "x86_64")]
        assert_eq!(
            available.contains(&TraversalKernel::Avx2),
            is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")
        );
        assert!(available.contains(&TraversalKernel::default_for_this_cpu()));
        for k in TraversalKernel::ALL {
            assert_eq!(
                Kernel::new(k).map(Kernel::kind),
                k.is_available().then_some(k)
            );
        }
    }

    #[test]
    fn set_kernel_switches_or_refuses() {
        let scene = illume_scene::builtin::load("cornell-spot").unwrap();
        let mut tracer = Tracer::new(&scene);
        for k in TraversalKernel::ALL {
            let before = tracer.kernel();
            match tracer.set_kernel(k) {
                Ok(()) => assert_eq!(tracer.kernel(), k),
                Err(e) => {
                    assert_eq!(e, KernelUnavailable(k));
                    assert_eq!(tracer.kernel(), before, "a refused kernel changes nothing");
                }
            }
        }
    }
}
