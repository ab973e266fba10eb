//! Ray–triangle intersection.

use illume_core::{Ray, Vec2, Vec3};

/// Möller–Trumbore intersection. Returns `(t, b1, b2)` for a hit with `t` in
/// `(ray.t_min, t_max)`; both faces are hit (culling is the caller's business).
#[inline]
pub fn intersect_triangle(
    ray: &Ray,
    t_max: f32,
    p0: Vec3,
    p1: Vec3,
    p2: Vec3,
) -> Option<(f32, Vec2)> {
    let e1 = p1 - p0;
    let e2 = p2 - p0;
    let pvec = ray.dir.cross(e2);
    let det = e1.dot(pvec);
    if det.abs() < f32::MIN_POSITIVE {
        return None;
    }
    let inv_det = 1.0 / det;
    let tvec = ray.origin - p0;
    let b1 = tvec.dot(pvec) * inv_det;
    if !(0.0..=1.0).contains(&b1) {
        return None;
    }
    let qvec = tvec.cross(e1);
    let b2 = ray.dir.dot(qvec) * inv_det;
    if b2 < 0.0 || b1 + b2 > 1.0 {
        return None;
    }
    let t = e2.dot(qvec) * inv_det;
    (t > ray.t_min && t < t_max).then_some((t, Vec2::new(b1, b2)))
}
