//! The selection's gizmo, drawn over the viewport at the selection's pivot: three axis
//! handles that move it along world X, Y and Z, and three rings that turn it about those
//! axes through the pivot. A drag on a handle becomes the edit the keys make
//! ([`Command::MoveSelected`](crate::renderer::Command::MoveSelected), applied through
//! `Engine::apply_edit`).

use glam::{Affine3A, Quat, Vec2, Vec3};

/// Handle length on screen \[points\].
const HANDLE_POINTS: f32 = 70.0;
/// A pointer within this distance of a handle grabs it \[points\].
const GRAB_POINTS: f32 = 7.0;
/// Points on the ring's polyline.
const RING_SEGMENTS: usize = 48;

/// The camera and where its image is drawn: projects world points to the screen.
#[derive(Clone, Copy, Debug)]
pub struct View {
    /// The camera's placement (looking down −Z, +Y up).
    pub world_from_camera: Affine3A,
    /// Vertical field of view \[rad\].
    pub yfov_rad: f32,
    /// The image's top-left corner on the screen \[points\].
    pub origin: Vec2,
    /// The image's size on the screen \[points\].
    pub size: Vec2,
}

impl View {
    fn tan_half_y(&self) -> f32 {
        (self.yfov_rad * 0.5).tan()
    }

    fn aspect(&self) -> f32 {
        self.size.x / self.size.y.max(1e-6)
    }

    /// The screen point \[points\] of world point `p` and its depth \[m\] in front of the
    /// camera; None when `p` is not in front of it.
    pub fn project(&self, p: Vec3) -> Option<(Vec2, f32)> {
        let c = self.world_from_camera.inverse().transform_point3(p);
        let depth = -c.z;
        if depth <= 1e-4 {
            return None;
        }
        let t = self.tan_half_y();
        let ndc = Vec2::new(c.x / (depth * t * self.aspect()), c.y / (depth * t));
        let uv = Vec2::new((ndc.x + 1.0) * 0.5, (1.0 - ndc.y) * 0.5);
        Some((self.origin + uv * self.size, depth))
    }

    /// The camera ray (origin, unit direction) through screen point `s` \[points\], as
    /// `CameraRays` traces it.
    pub fn ray(&self, s: Vec2) -> (Vec3, Vec3) {
        let uv = (s - self.origin) / self.size;
        let t = self.tan_half_y();
        let d = Vec3::new(
            (uv.x * 2.0 - 1.0) * t * self.aspect(),
            (1.0 - uv.y * 2.0) * t,
            -1.0,
        );
        (
            Vec3::from(self.world_from_camera.translation),
            self.world_from_camera.transform_vector3(d).normalize(),
        )
    }
}

/// A part of the gizmo.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Handle {
    /// Move along world axis 0 (X), 1 (Y) or 2 (Z).
    Axis(usize),
    /// Turn about world axis 0 (X), 1 (Y: the vertical) or 2 (Z) through the pivot.
    Turn(usize),
}

/// World axis `i` (0: X, 1: Y, 2: Z).
fn axis(i: usize) -> Vec3 {
    [Vec3::X, Vec3::Y, Vec3::Z][i]
}

/// Two unit vectors `(v, u)` spanning the plane normal to world axis `i`, ordered so
/// that a right-handed turn by +θ about the axis adds θ to `atan2(p·u, p·v)`: (Y, Z)
/// for X, (Z, X) for Y (the horizontal ring's `atan2(x, z)`) and (X, Y) for Z.
fn ring_basis(i: usize) -> (Vec3, Vec3) {
    match i {
        0 => (Vec3::Y, Vec3::Z),
        1 => (Vec3::Z, Vec3::X),
        _ => (Vec3::X, Vec3::Y),
    }
}

/// The gizmo of one frame: its handles on the screen.
#[derive(Clone, Debug)]
pub struct Gizmo {
    view: View,
    pivot: Vec3,
    /// The pivot on the screen \[points\].
    pub centre: Vec2,
    /// The handles' length in the world \[m\] (they keep a constant size on screen).
    pub length_m: f32,
    /// Each axis handle's far end on the screen \[points\] (None: behind the camera).
    pub axes: [Option<Vec2>; 3],
    /// The rings about X, Y and Z (radius `0.6 × length_m` in the plane normal to each
    /// axis) on the screen; points behind the camera left out.
    pub rings: [Vec<Vec2>; 3],
}

impl Gizmo {
    /// The gizmo at `pivot` \[m, world\]; None when the pivot is not in front of the camera.
    pub fn new(view: View, pivot: Vec3) -> Option<Self> {
        let (centre, depth) = view.project(pivot)?;
        // Metres per point at the pivot's depth.
        let m_per_point = depth * 2.0 * view.tan_half_y() / view.size.y.max(1.0);
        let length_m = HANDLE_POINTS * m_per_point;
        let axes =
            [Vec3::X, Vec3::Y, Vec3::Z].map(|a| view.project(pivot + a * length_m).map(|(s, _)| s));
        let rings = [0, 1, 2].map(|k| {
            let (v, u) = ring_basis(k);
            (0..=RING_SEGMENTS)
                .filter_map(|i| {
                    let a = i as f32 / RING_SEGMENTS as f32 * std::f32::consts::TAU;
                    let p = pivot + (u * a.sin() + v * a.cos()) * (0.6 * length_m);
                    view.project(p).map(|(s, _)| s)
                })
                .collect()
        });
        Some(Self {
            view,
            pivot,
            centre,
            length_m,
            axes,
            rings,
        })
    }

    /// The handle under screen point `p` \[points\]: axes first, then the rings (Y, X,
    /// Z).
    pub fn hit(&self, p: Vec2) -> Option<Handle> {
        let near = |a: Vec2, b: Vec2| segment_distance(p, a, b) < GRAB_POINTS;
        (0..3)
            .find(|&i| self.axes[i].is_some_and(|end| near(self.centre, end)))
            .map(Handle::Axis)
            .or_else(|| {
                [1, 0, 2]
                    .into_iter()
                    .find(|&k| self.rings[k].windows(2).any(|w| near(w[0], w[1])))
                    .map(Handle::Turn)
            })
    }

    /// The move a pointer drag from `from` to `to` \[points\] on `handle` asks for: a
    /// world translation \[m\] and a rotation about the pivot.
    pub fn drag(&self, handle: Handle, from: Vec2, to: Vec2) -> (Vec3, Quat) {
        match handle {
            Handle::Axis(i) => {
                let per_metre = self.axes[i].map_or(Vec2::ZERO, |end| end - self.centre)
                    / self.length_m.max(1e-9);
                (
                    drag_translation(axis(i), per_metre, to - from),
                    Quat::IDENTITY,
                )
            }
            Handle::Turn(k) => (
                Vec3::ZERO,
                Quat::from_axis_angle(axis(k), self.turn(k, from, to)),
            ),
        }
    }

    /// The turn about world axis `k` that carries the pointer's point on the plane
    /// through the pivot normal to that axis from `from` to `to` \[rad, in (−π, π]\]; 0
    /// when the plane is seen edge-on.
    fn turn(&self, k: usize, from: Vec2, to: Vec2) -> f32 {
        let n = axis(k);
        let (v, u) = ring_basis(k);
        let on_plane = |s: Vec2| {
            let (o, d) = self.view.ray(s);
            let dn = d.dot(n);
            if dn.abs() < 1e-4 {
                return None;
            }
            let t = (self.pivot - o).dot(n) / dn;
            (t > 0.0).then(|| o + d * t - self.pivot)
        };
        match (on_plane(from), on_plane(to)) {
            (Some(a), Some(b)) => {
                // A rotation by θ about the axis adds θ to atan2(p·u, p·v).
                let d = b.dot(u).atan2(b.dot(v)) - a.dot(u).atan2(a.dot(v));
                (d + std::f32::consts::PI).rem_euclid(std::f32::consts::TAU) - std::f32::consts::PI
            }
            _ => 0.0,
        }
    }
}

/// The translation \[m\] along unit `axis` that a pointer drag of `drag` \[points\] asks
/// for, where `per_metre` is the screen motion \[points\] of one metre along the axis: the
/// drag's component along the axis's screen direction, in metres. 0 when the axis points
/// at the viewer (no screen direction).
pub fn drag_translation(axis: Vec3, per_metre: Vec2, drag: Vec2) -> Vec3 {
    let len2 = per_metre.length_squared();
    if len2 < 1e-6 {
        return Vec3::ZERO;
    }
    axis * (drag.dot(per_metre) / len2)
}

/// Distance from `p` to the segment `a`–`b`.
fn segment_distance(p: Vec2, a: Vec2, b: Vec2) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_squared().max(1e-12)).clamp(0.0, 1.0);
    (a + ab * t - p).length()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The camera 4 m from the origin on +Z, raised 2 m, looking at the origin; an
    /// 800×600-point image.
    fn view() -> View {
        View {
            world_from_camera: Affine3A::look_at_rh(Vec3::new(0.0, 2.0, 4.0), Vec3::ZERO, Vec3::Y)
                .inverse(),
            yfov_rad: 45f32.to_radians(),
            origin: Vec2::new(10.0, 20.0),
            size: Vec2::new(800.0, 600.0),
        }
    }

    #[test]
    fn projection_matches_the_camera_rays() {
        let v = view();
        let (centre, depth) = v.project(Vec3::ZERO).unwrap();
        assert!(
            (centre - Vec2::new(410.0, 320.0)).length() < 1e-3,
            "{centre}"
        );
        assert!((depth - 20f32.sqrt()).abs() < 1e-4);
        for p in [Vec3::new(0.5, 0.3, -0.2), Vec3::new(-1.0, 0.0, 1.0)] {
            let (s, _) = v.project(p).unwrap();
            let (o, d) = v.ray(s);
            let along = (p - o).normalize();
            assert!(along.dot(d) > 1.0 - 1e-6, "ray through {s} misses {p}");
        }
        assert!(v.project(Vec3::new(0.0, 2.0, 6.0)).is_none(), "behind");
    }

    #[test]
    fn dragging_an_axis_handle_moves_along_that_axis_by_the_dragged_length() {
        let g = Gizmo::new(view(), Vec3::ZERO).unwrap();
        let x_end = g.axes[0].unwrap();
        // The X handle points right on screen; dragging its full length moves one handle
        // length along +X, nothing along Y or Z.
        assert!(x_end.x > g.centre.x + 60.0 && (x_end.y - g.centre.y).abs() < 1e-3);
        assert_eq!(g.hit(g.centre.lerp(x_end, 0.7)), Some(Handle::Axis(0)));
        let (t, turn) = g.drag(Handle::Axis(0), g.centre, x_end);
        assert!(
            (t - Vec3::X * g.length_m).length() < 1e-3 * g.length_m,
            "{t}"
        );
        assert_eq!(turn, Quat::IDENTITY);
        // A drag across the axis's screen direction does not move the object.
        let across = (x_end - g.centre).perp();
        let (t, _) = g.drag(Handle::Axis(0), g.centre, g.centre + across);
        assert!(t.length() < 1e-6, "{t}");
        // Y handle: dragging up moves up; half the length, half the move.
        let y_end = g.axes[1].unwrap();
        assert!(y_end.y < g.centre.y);
        let (t, _) = g.drag(Handle::Axis(1), g.centre, g.centre.lerp(y_end, 0.5));
        assert!(
            (t - Vec3::Y * 0.5 * g.length_m).length() < 1e-3 * g.length_m,
            "{t}"
        );
        // The drag maps linearly: twice the drag, twice the move.
        let d = Vec2::new(13.0, -4.0);
        let a = drag_translation(Vec3::Z, Vec2::new(3.0, 40.0), d);
        let b = drag_translation(Vec3::Z, Vec2::new(3.0, 40.0), 2.0 * d);
        assert!((b - 2.0 * a).length() < 1e-6 && a.x == 0.0 && a.y == 0.0);
        assert_eq!(
            drag_translation(Vec3::Z, Vec2::ZERO, d),
            Vec3::ZERO,
            "an axis seen end-on does not move"
        );
    }

    /// The signed angle of the rotation `q` about world axis `k` (q must be one).
    fn angle_about(q: Quat, k: usize) -> f32 {
        let (a, angle) = q.to_axis_angle();
        if angle.abs() < 1e-7 {
            return 0.0;
        }
        angle * a.dot(axis(k)).signum()
    }

    #[test]
    fn dragging_along_a_ring_turns_about_its_axis_by_the_angle_swept() {
        // A pivot off the origin, seen from a corner so that no ring is edge-on.
        let v = View {
            world_from_camera: Affine3A::look_at_rh(
                Vec3::new(3.0, 2.5, 4.0),
                Vec3::new(0.2, 0.1, -0.3),
                Vec3::Y,
            )
            .inverse(),
            ..view()
        };
        let pivot = Vec3::new(0.2, 0.1, -0.3);
        let g = Gizmo::new(v, pivot).unwrap();
        let r = 0.6 * g.length_m;
        for k in 0..3 {
            let (bv, bu) = ring_basis(k);
            let world = |a: f32| pivot + (bu * a.sin() + bv * a.cos()) * r;
            let at = |a: f32| g.view.project(world(a)).unwrap().0;
            // The rotation the drag asks for carries the ring's point to the other.
            let (t, q) = g.drag(Handle::Turn(k), at(0.2), at(0.2 + 0.5));
            assert_eq!(t, Vec3::ZERO);
            assert!((angle_about(q, k) - 0.5).abs() < 1e-3, "axis {k}: {q}");
            let moved = pivot + q * (world(0.2) - pivot);
            assert!(
                (moved - world(0.7)).length() < 1e-3 * r,
                "axis {k}: {moved}"
            );
            let (_, back) = g.drag(Handle::Turn(k), at(0.7), at(0.2));
            assert!((angle_about(back, k) + 0.5).abs() < 1e-3, "axis {k}");
            // Across ±π the shorter way round.
            let (_, wrap) = g.drag(Handle::Turn(k), at(3.0), at(-3.0));
            assert!(
                (angle_about(wrap, k) - (std::f32::consts::TAU - 6.0)).abs() < 1e-3,
                "axis {k}: {wrap}"
            );
        }
        // Each ring is grabbed where it is drawn, away from the others' crossings.
        let on_ring = |k: usize| {
            g.rings[k]
                .iter()
                .copied()
                .find(|&p| {
                    (0..3).all(|j| {
                        j == k
                            || g.rings[j]
                                .windows(2)
                                .all(|w| segment_distance(p, w[0], w[1]) > GRAB_POINTS + 0.5)
                    }) && (0..3).all(|j| {
                        g.axes[j]
                            .is_none_or(|e| segment_distance(p, g.centre, e) > GRAB_POINTS + 0.5)
                    })
                })
                .unwrap_or_else(|| panic!("ring {k} has no point of its own"))
        };
        for k in 0..3 {
            assert_eq!(g.hit(on_ring(k)), Some(Handle::Turn(k)));
        }
        assert_eq!(g.hit(g.centre + Vec2::new(300.0, 250.0)), None);
    }
}
