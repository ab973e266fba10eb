//! Math types and unit conventions: glam re-exports, [`Ray`], [`Aabb`], orthonormal
//! [`Frame`], [`Rgb`] colour helpers.
//!
//! Geometry is `f32` (metres); time is `f64` (seconds). Colour is linear Rec.709 RGB
//! stored in a `Vec3` ([`Rgb`]): the same arithmetic serves both, and every API names
//! which quantity (radiance, flux, irradiance, albedo) an `Rgb` carries.

pub use glam::{Affine3A, Mat3, Mat3A, Mat4, Quat, UVec2, UVec3, Vec2, Vec3, Vec3A, Vec4};

/// Linear Rec.709 RGB. The physical quantity (radiance W/(m²·sr), flux W, irradiance
/// W/m², albedo) is named by the field or function that holds it.
pub type Rgb = Vec3;

/// Rec.709 luminance weights of a linear RGB value.
#[inline]
pub fn luminance(c: Rgb) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Arithmetic mean of the three channels (used for power-proportional choices, where
/// every channel of a radiometric quantity counts alike).
#[inline]
pub fn channel_mean(c: Rgb) -> f32 {
    (c.x + c.y + c.z) / 3.0
}

/// π as `f32`.
pub const PI: f32 = std::f32::consts::PI;
/// 1/π as `f32`.
pub const INV_PI: f32 = std::f32::consts::FRAC_1_PI;

/// A ray `origin + t·dir` for `t` in `[t_min, t_max]`. `dir` need not be normalised for
/// intersection, but every ray made by illume's kernels is unit length, so `t` is metres.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    /// Ray origin (world space unless a function says otherwise).
    pub origin: Vec3,
    /// Ray direction.
    pub dir: Vec3,
    /// Smallest accepted hit distance.
    pub t_min: f32,
    /// Largest accepted hit distance.
    pub t_max: f32,
}

impl Ray {
    /// A ray over `[0, ∞)`.
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        Self {
            origin,
            dir,
            t_min: 0.0,
            t_max: f32::INFINITY,
        }
    }

    /// A ray over `[0, t_max]`.
    #[inline]
    pub fn segment(origin: Vec3, dir: Vec3, t_max: f32) -> Self {
        Self {
            origin,
            dir,
            t_min: 0.0,
            t_max,
        }
    }

    /// The point at distance `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// Offsets a surface point along its geometric normal so a ray leaving it in direction
/// `dir` does not re-hit the same surface. The offset scales with the point's magnitude
/// (float spacing grows with distance from the origin).
#[inline]
pub fn offset_ray_origin(p: Vec3, geometric_normal: Vec3, dir: Vec3) -> Vec3 {
    let scale = 1e-4 * (1.0 + p.abs().max_element());
    let n = if geometric_normal.dot(dir) >= 0.0 {
        geometric_normal
    } else {
        -geometric_normal
    };
    p + n * scale
}

/// Axis-aligned bounding box. An empty box has `min > max` and absorbs any union.
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Default for Aabb {
    fn default() -> Self {
        Self::EMPTY
    }
}

impl Aabb {
    /// The empty box (identity of [`Aabb::union`]).
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// Box from two corners.
    #[inline]
    pub fn new(min: Vec3, max: Vec3) -> Self {
        Self { min, max }
    }

    /// Smallest box containing all `points`.
    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Self {
        points.into_iter().fold(Self::EMPTY, |b, p| b.grow(p))
    }

    /// This box grown to contain `p`.
    #[inline]
    pub fn grow(self, p: Vec3) -> Self {
        Self {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    /// Smallest box containing both.
    #[inline]
    pub fn union(self, o: Aabb) -> Self {
        Self {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// True when the box contains no point.
    #[inline]
    pub fn is_empty(&self) -> bool {
        self.min.x > self.max.x || self.min.y > self.max.y || self.min.z > self.max.z
    }

    /// Size along each axis (zero for an empty box).
    #[inline]
    pub fn extent(&self) -> Vec3 {
        if self.is_empty() {
            Vec3::ZERO
        } else {
            self.max - self.min
        }
    }

    /// Centre point.
    #[inline]
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// The eight corners; corner `i` takes `max` on axis k where bit k of `i` is set.
    #[inline]
    pub fn corners(&self) -> [Vec3; 8] {
        std::array::from_fn(|i| {
            Vec3::select(
                glam::BVec3::new(i & 1 != 0, i & 2 != 0, i & 4 != 0),
                self.max,
                self.min,
            )
        })
    }

    /// Surface area (zero for an empty box).
    #[inline]
    pub fn surface_area(&self) -> f32 {
        let e = self.extent();
        2.0 * (e.x * e.y + e.y * e.z + e.z * e.x)
    }

    /// Does the box contain `p` (boundary included)?
    #[inline]
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }

    /// Does the box contain `o` entirely, with tolerance `eps`?
    #[inline]
    pub fn contains_box(&self, o: &Aabb, eps: f32) -> bool {
        o.is_empty() || (o.min.cmpge(self.min - eps).all() && o.max.cmple(self.max + eps).all())
    }

    /// The box of this box's eight corners after an affine transform.
    pub fn transformed(&self, m: &Affine3A) -> Aabb {
        if self.is_empty() {
            return *self;
        }
        // Arvo's method: per-axis min/max of the linear part's contributions.
        let t = Vec3::from(m.translation);
        let mut min = t;
        let mut max = t;
        let cols = [
            Vec3::from(m.matrix3.x_axis),
            Vec3::from(m.matrix3.y_axis),
            Vec3::from(m.matrix3.z_axis),
        ];
        for (i, col) in cols.iter().enumerate() {
            let a = *col * self.min[i];
            let b = *col * self.max[i];
            min += a.min(b);
            max += a.max(b);
        }
        Aabb { min, max }
    }

    /// Radius of the bounding sphere about the centre.
    #[inline]
    pub fn bounding_radius(&self) -> f32 {
        self.extent().length() * 0.5
    }
}

/// An orthonormal frame (tangent, bitangent, normal) for moving directions between world
/// space and a local space where the normal is +Z.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Frame {
    /// First tangent.
    pub s: Vec3,
    /// Second tangent.
    pub t: Vec3,
    /// Normal (local +Z).
    pub n: Vec3,
}

impl Frame {
    /// A frame around unit normal `n` (Duff et al. 2017, branchless ONB).
    #[inline]
    pub fn from_normal(n: Vec3) -> Self {
        let sign = 1.0f32.copysign(n.z);
        let a = -1.0 / (sign + n.z);
        let b = n.x * n.y * a;
        let s = Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x);
        let t = Vec3::new(b, sign + n.y * n.y * a, -n.y);
        Self { s, t, n }
    }

    /// Local direction (normal = +Z) to world.
    #[inline]
    pub fn to_world(&self, v: Vec3) -> Vec3 {
        self.s * v.x + self.t * v.y + self.n * v.z
    }

    /// World direction to local (normal = +Z).
    #[inline]
    pub fn to_local(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.s), v.dot(self.t), v.dot(self.n))
    }
}

/// True when every component of the transform is finite.
pub fn affine_is_finite(m: &Affine3A) -> bool {
    m.matrix3.is_finite() && m.translation.is_finite()
}

/// Transforms a normal by the inverse transpose of `world_from_object`'s linear part and
/// normalises it. Uses the cofactor matrix (det · inverse transpose: three cross products,
/// no division), with the determinant's sign restored so mirroring transforms give the
/// same direction as the inverse transpose.
#[inline]
pub fn transform_normal(world_from_object: &Affine3A, n: Vec3) -> Vec3 {
    let m = &world_from_object.matrix3;
    let (c0, c1, c2) = (m.x_axis, m.y_axis, m.z_axis);
    let (k0, k1, k2) = (c1.cross(c2), c2.cross(c0), c0.cross(c1));
    let det = c0.dot(k0);
    let v = (k0 * n.x + k1 * n.y + k2 * n.z) * det.signum();
    Vec3::from(v).normalize_or_zero()
}

/// `X,Y,Z` as a point (a command-line value): three finite numbers, else a message
/// quoting `s`.
pub fn parse_point(s: &str) -> Result<Vec3, String> {
    let v: Vec<f32> = s
        .split(',')
        .map(|c| c.trim().parse::<f32>())
        .collect::<Result<_, _>>()
        .map_err(|e| format!("'{s}': {e} (expected X,Y,Z)"))?;
    match v[..] {
        [x, y, z] if x.is_finite() && y.is_finite() && z.is_finite() => Ok(Vec3::new(x, y, z)),
        _ => Err(format!("'{s}': expected three finite numbers X,Y,Z")),
    }
}

/// `R,G,B` as a radiance [W/(m²·sr)] (a command-line value): three finite numbers ≥ 0,
/// else a message quoting `s`.
pub fn parse_radiance(s: &str) -> Result<Vec3, String> {
    let v =
        parse_point(s).map_err(|_| format!("'{s}': expected three finite numbers R,G,B ≥ 0"))?;
    if v.min_element() < 0.0 {
        return Err(format!("'{s}': radiance must be ≥ 0"));
    }
    Ok(v)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_corners_are_the_eight_min_max_combinations() {
        let b = Aabb {
            min: Vec3::new(-1.0, 2.0, 3.0),
            max: Vec3::new(4.0, 5.0, 6.0),
        };
        let c = b.corners();
        assert_eq!(c[0], b.min);
        assert_eq!(c[7], b.max);
        assert_eq!(c[1], Vec3::new(4.0, 2.0, 3.0));
        assert_eq!(c[6], Vec3::new(-1.0, 5.0, 6.0));
        for (i, p) in c.iter().enumerate() {
            assert!(c[..i].iter().all(|q| q != p), "corner {i} repeated");
        }
    }

    #[test]
    fn frame_is_orthonormal_for_many_normals() {
        for i in 0..1000 {
            let a = i as f32 * 0.37;
            let b = i as f32 * 0.11 - 50.0;
            let n = Vec3::new(a.cos() * b.sin(), a.sin() * b.sin(), b.cos()).normalize();
            let f = Frame::from_normal(n);
            assert!((f.s.length() - 1.0).abs() < 1e-4);
            assert!((f.t.length() - 1.0).abs() < 1e-4);
            assert!(
                f.s.dot(f.t).abs() < 1e-4 && f.s.dot(n).abs() < 1e-4 && f.t.dot(n).abs() < 1e-4
            );
            let v = Vec3::new(0.3, -0.5, 0.8);
            assert!((f.to_local(f.to_world(v)) - v).length() < 1e-5);
        }
    }

    #[test]
    fn normal_transform_matches_inverse_transpose() {
        for (k, scale) in [
            Vec3::new(2.0, 0.5, 1.0),
            Vec3::new(-1.0, 3.0, 0.2),
            Vec3::splat(0.01),
        ]
        .into_iter()
        .enumerate()
        {
            let m = Affine3A::from_scale_rotation_translation(
                scale,
                Quat::from_euler(glam::EulerRot::XYZ, 0.3 * k as f32, 1.1, -0.4),
                Vec3::new(5.0, -1.0, 0.0),
            );
            for n in [Vec3::X, Vec3::new(0.3, -0.5, 0.8).normalize(), Vec3::Z] {
                let expected = (m.matrix3.inverse().transpose() * Vec3A::from(n)).normalize();
                let got = transform_normal(&m, n);
                assert!(
                    (Vec3::from(expected) - got).length() < 1e-5,
                    "{expected} vs {got}"
                );
            }
        }
    }

    #[test]
    fn transformed_box_contains_transformed_corners() {
        let b = Aabb::new(Vec3::new(-1.0, 0.0, 2.0), Vec3::new(1.0, 3.0, 2.5));
        let m = Affine3A::from_scale_rotation_translation(
            Vec3::new(2.0, 0.5, 1.0),
            Quat::from_euler(glam::EulerRot::XYZ, 0.3, 1.1, -0.4),
            Vec3::new(5.0, -1.0, 0.0),
        );
        let tb = b.transformed(&m);
        for i in 0..8 {
            let c = Vec3::new(
                if i & 1 == 0 { b.min.x } else { b.max.x },
                if i & 2 == 0 { b.min.y } else { b.max.y },
                if i & 4 == 0 { b.min.z } else { b.max.z },
            );
            let p = m.transform_point3(c);
            assert!(
                tb.contains(p) || (tb.min - 1e-4).cmple(p).all() && p.cmple(tb.max + 1e-4).all()
            );
        }
    }
}
