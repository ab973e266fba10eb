//! Triangle pre-splitting (Karras & Aila 2013, "Fast Parallel Construction of
//! High-Quality Bounding Volume Hierarchies", §4; Ernst & Greiner 2007, "Early Split
//! Clipping"): before the SAH build, the boxes of triangles that fill their box badly —
//! long, thin, diagonal triangles such as Sponza's floor strips and arches — are cut into
//! several tighter boxes, each a *reference* to the same triangle. The build then sees
//! small boxes where it would have seen one large one, and rays stop entering leaves
//! whose box the triangle barely touches.
//!
//! A triangle can then sit in several leaves. Its hits are the same wherever it is
//! tested (the leaf stores the whole triangle), so closest hits do not change; only
//! memory and build time grow with the number of references.
//!
//! Written by hand: this is the build's own step, tied to its box type and budget, and no
//! crate offers it apart from a whole BVH builder.

use illume_core::{Aabb, Vec3};

/// Most references one triangle may become.
const MAX_FRAGMENTS: u32 = 64;

/// References `(box, triangle index)` of `triangles` (each given by its corners) after
/// splitting: at most about `budget · triangles.len()` extra references, handed out in
/// proportion to the cube root of each triangle's wasted box area (its box's surface
/// area minus the least area boxes around it could have, that of its three axis
/// projections), as Karras & Aila do. A triangle whose share is below one extra
/// reference keeps its one box. Cuts follow the planes of a power-of-two grid over all
/// the triangles' box, the planes the build's own splits tend to use. Every reference's
/// box lies inside its triangle's box, and together they cover the triangle (each is a
/// little larger than the clipped part it bounds).
pub(crate) fn split_references(triangles: &[[Vec3; 3]], budget: f32) -> (Vec<Aabb>, Vec<u32>) {
    let n = triangles.len();
    let boxes: Vec<Aabb> = triangles.iter().map(|&c| Aabb::from_points(c)).collect();
    let waste: Vec<f64> = triangles
        .iter()
        .zip(&boxes)
        .map(|(c, b)| {
            let cross = (c[1] - c[0]).cross(c[2] - c[0]);
            // Surface area of the ideal cover: twice the sum of the projected areas.
            let ideal = cross.abs().element_sum();
            let w = f64::from(b.surface_area() - ideal).cbrt();
            if w.is_finite() { w.max(0.0) } else { 0.0 }
        })
        .collect();
    let total: f64 = waste.iter().sum();
    let root = boxes.iter().fold(Aabb::EMPTY, |a, b| a.union(*b));
    let extra = f64::from(budget.max(0.0)) * n as f64;
    let mut out_boxes = Vec::with_capacity(n + extra as usize + 1);
    let mut out_tris = Vec::with_capacity(n + extra as usize + 1);
    for (t, corners) in triangles.iter().enumerate() {
        let share = if total > 0.0 {
            extra * waste[t] / total
        } else {
            0.0
        };
        let fragments = (1 + share as u32).min(MAX_FRAGMENTS);
        let before = out_boxes.len();
        split(
            corners,
            boxes[t],
            &boxes[t],
            &root,
            fragments,
            &mut out_boxes,
        );
        out_tris.extend(std::iter::repeat_n(t as u32, out_boxes.len() - before));
    }
    (out_boxes, out_tris)
}

/// Pushes `fragments` boxes (or fewer, where a cut leaves one side empty) that together
/// cover the part of the triangle `corners` inside `region`, each within `whole` (the
/// triangle's own box); cuts follow `root`'s power-of-two grid.
fn split(
    corners: &[Vec3; 3],
    region: Aabb,
    whole: &Aabb,
    root: &Aabb,
    fragments: u32,
    out: &mut Vec<Aabb>,
) {
    if fragments <= 1 {
        out.push(region);
        return;
    }
    let extent = region.max - region.min;
    let axis = if extent.x >= extent.y && extent.x >= extent.z {
        0
    } else if extent.y >= extent.z {
        1
    } else {
        2
    };
    let cut = grid_plane(
        region.min[axis],
        region.max[axis],
        root.min[axis],
        root.max[axis],
    );
    let side = |below| {
        clipped_bounds(corners, axis, cut, below)
            .map(|b| meet(&grown(b, whole), &region))
            .filter(|b| !b.is_empty())
    };
    match (side(true), side(false)) {
        (Some(l), Some(r)) => {
            let (al, ar) = (l.surface_area(), r.surface_area());
            let share = if al + ar > 0.0 { al / (al + ar) } else { 0.5 };
            let nl = ((fragments as f32 * share).round() as u32).clamp(1, fragments - 1);
            split(corners, l, whole, root, nl, out);
            split(corners, r, whole, root, fragments - nl, out);
        }
        // Rounding left one side empty: the region is kept whole.
        _ => out.push(region),
    }
}

/// The coarsest plane of the root's power-of-two grid strictly inside `(lo, hi)` (the
/// planes a spatial-median split of the root would use), else the midpoint.
fn grid_plane(lo: f32, hi: f32, root_lo: f32, root_hi: f32) -> f32 {
    let mut cell = root_hi - root_lo;
    for _ in 0..24 {
        cell *= 0.5;
        let k = ((lo - root_lo) / cell).floor() + 1.0;
        let plane = root_lo + k * cell;
        if plane > lo && plane < hi {
            return plane;
        }
    }
    0.5 * (lo + hi)
}

/// Bounds of the triangle's part on one side of the plane `p[axis] = cut` (`below`: the
/// side `≤ cut`), None when it has none.
fn clipped_bounds(corners: &[Vec3; 3], axis: usize, cut: f32, below: bool) -> Option<Aabb> {
    let inside = |p: Vec3| {
        if below {
            p[axis] <= cut
        } else {
            p[axis] >= cut
        }
    };
    let mut b = Aabb::EMPTY;
    for i in 0..3 {
        let (a, c) = (corners[i], corners[(i + 1) % 3]);
        if inside(a) {
            b = b.grow(a);
        }
        let (da, dc) = (a[axis] - cut, c[axis] - cut);
        if (da < 0.0 && dc > 0.0) || (da > 0.0 && dc < 0.0) {
            let mut p = a + (c - a) * (da / (da - dc));
            p[axis] = cut;
            b = b.grow(p);
        }
    }
    (!b.is_empty()).then_some(b)
}

/// `b` grown by a few ulps of the triangle's scale (the clipped corners are rounded), kept
/// within the triangle's box `whole`.
fn grown(b: Aabb, whole: &Aabb) -> Aabb {
    let scale = whole
        .min
        .abs()
        .max(whole.max.abs())
        .max_element()
        .max(1e-30);
    let e = Vec3::splat(4.0 * f32::EPSILON * scale);
    meet(
        &Aabb {
            min: b.min - e,
            max: b.max + e,
        },
        whole,
    )
}

/// The intersection of two boxes (empty when they do not meet).
fn meet(a: &Aabb, b: &Aabb) -> Aabb {
    Aabb {
        min: a.min.max(b.min),
        max: a.max.min(b.max),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use illume_core::sampling::{Pcg32, SampleStream};

    /// The boxes of triangle `t`'s references.
    fn references_of<'a>(boxes: &'a [Aabb], refs: &[u32], t: usize) -> Vec<&'a Aabb> {
        boxes
            .iter()
            .zip(refs)
            .filter(|(_, r)| **r == t as u32)
            .map(|(b, _)| b)
            .collect()
    }

    fn random_triangles(n: usize, seed: u64) -> Vec<[Vec3; 3]> {
        let mut rng = Pcg32::new(seed, 3);
        let mut p = || Vec3::new(rng.next_1d(), rng.next_1d(), rng.next_1d()) * 10.0 - 5.0;
        (0..n).map(|_| [p(), p(), p()]).collect()
    }

    #[test]
    fn references_cover_their_triangles_and_stay_inside_their_boxes() {
        let tris = random_triangles(300, 1);
        let (boxes, refs) = split_references(&tris, 1.0);
        assert!(boxes.len() > 450, "{} references", boxes.len());
        assert!(boxes.len() <= 600 + 1, "{} references", boxes.len());
        let mut rng = Pcg32::new(9, 9);
        for (t, c) in tris.iter().enumerate() {
            let whole = Aabb::from_points(*c);
            let mine = references_of(&boxes, &refs, t);
            assert!(!mine.is_empty());
            for b in &mine {
                assert!(
                    whole.contains_box(b, 0.0),
                    "triangle {t}: {b:?} outside {whole:?}"
                );
            }
            // Points of the triangle, corners and edges included, lie in some reference
            // (to the rounding of the point's own arithmetic).
            for k in 0..200 {
                let (mut u, mut v) = (rng.next_1d(), rng.next_1d());
                if k < 3 {
                    (u, v) = [(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)][k];
                } else if u + v > 1.0 {
                    (u, v) = (1.0 - u, 1.0 - v);
                }
                let p = c[0] + (c[1] - c[0]) * u + (c[2] - c[0]) * v;
                assert!(
                    mine.iter().any(|b| b.contains_box(&Aabb::new(p, p), 1e-5)),
                    "triangle {t} {c:?}: point {p:?} in none of {} references {mine:?}",
                    mine.len()
                );
            }
        }
    }

    #[test]
    fn degenerate_triangles_keep_covering_boxes() {
        // A point, a needle along a diagonal (no area, a large box), a flat sliver.
        let point = [Vec3::ONE; 3];
        let needle = [Vec3::ZERO, Vec3::splat(5.0), Vec3::splat(2.5)];
        let flat = [
            Vec3::ZERO,
            Vec3::new(4.0, 0.0, 0.0),
            Vec3::new(4.0, 0.0, 0.0),
        ];
        let tris = [point, needle, flat];
        let (boxes, refs) = split_references(&tris, 4.0);
        for (t, c) in tris.iter().enumerate() {
            let mine = references_of(&boxes, &refs, t);
            assert!(!mine.is_empty(), "triangle {t} lost");
            for k in 0..=20 {
                let p = c[0] + (c[1] - c[0]) * (k as f32 / 20.0);
                assert!(
                    mine.iter().any(|b| b.contains_box(&Aabb::new(p, p), 1e-5)),
                    "triangle {t}: {p:?} uncovered"
                );
            }
        }
        assert!(
            refs.iter().filter(|&&r| r == 1).count() > 1,
            "the needle is split"
        );
    }

    #[test]
    fn slivers_get_the_splits() {
        // A right triangle in the z = 0 plane with legs on the axes wastes half its box
        // area, a diagonal sliver far more: the sliver gets the splits.
        let flat = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let sliver = [
            Vec3::ZERO,
            Vec3::new(10.0, 10.0, 10.0),
            Vec3::new(10.1, 10.0, 10.0),
        ];
        let (_, refs) = split_references(&[flat, sliver], 2.0);
        let count = |t| refs.iter().filter(|&&r| r == t).count();
        assert_eq!(count(0), 1);
        assert!(count(1) >= 3, "{}", count(1));
    }
}
