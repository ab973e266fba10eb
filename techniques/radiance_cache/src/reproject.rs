//! The next-frame estimate of a record's incoming radiance (§4.3, §5, Fig. 7–8): the
//! points a record's gather rays hit at frame t are moved to frame t + 1 and splatted
//! back into the record's hemisphere grid, giving E(t + 1) and the gradients at t + 1
//! without tracing the hemisphere again.
//!
//! For each cell of the gather ([`HemisphereGather::trace_keeping_paths`]):
//! 1. **Move the hit.** The hit (instance, triangle, barycentrics) is evaluated in the
//!    next frame's [`World`] (`next`): its instance's `world_from_object` at t + 1 gives
//!    the point's new position. Hits on instances that did not move keep their cell and
//!    direction exactly (no rounding can move them to a neighbour).
//! 2. **Its light at t + 1.** The light it reflects once (direct light, with shadows) is
//!    recomputed in `next` from the random stream the path used at t, so an unchanged
//!    point gives the same value bit for bit and a change shows as change, not noise;
//!    the light it reflects more than once is carried over from t (the paper's
//!    multi-bounce part).
//! 3. **Splat with a depth test.** The point lands in the cell its new direction from
//!    the record falls in (points that sink below the record's tangent plane are
//!    dropped); where several land in one cell, the nearest wins (the Z-buffer), and a
//!    count per cell is kept (the paper's stencil). Rays that left the scene stay in
//!    their cell at infinite distance, behind any point that lands there.
//!    A point that moved can leave gaps where its surface now spreads over more cells
//!    than it has points (coming nearer, or sliding over its background): a cell whose
//!    entry did not move, between moved points nearer than it on both sides (along θ or
//!    φ, within 2 cells), is made a hole too.
//! 4. **Fill the holes.** Cells no point landed in take the mean of their filled 3×3
//!    neighbours (φ wraps around, θ does not), pass after pass, at most
//!    `max_fill_passes` times; cells still empty then take the grid's mean.
//!
//! The grid is a [`HemisphereGather`] over the record's frame and strata (each cell keeps
//! its direction at t), so E(t + 1), ∇_r(t + 1) and ∇_p(t + 1) come from the same code
//! as a traced record's.

use crate::record::{CellPath, GatherCell, HemisphereGather, Incoming, RecordSettings};
use illume_core::{PI, Ray, Rgb, Vec3};
use illume_transport::World;
use illume_transport::path::{PathRadiance, PathSettings, continue_path};

/// A record's reprojected next-frame grid, with what the splat left empty.
#[derive(Clone, Debug)]
pub struct Reprojection {
    /// The grid at t + 1 (radiance and distance per cell), over the record's frame.
    pub gather: HemisphereGather,
    /// Cells no point landed in (the holes of Fig. 7d).
    pub holes: u32,
    /// Per cell (θ-stratum major), true for the holes.
    pub hole_cells: Vec<bool>,
    /// Holes still empty after `max_fill_passes` passes, given the grid's mean.
    pub unfilled: u32,
}

/// The cell (θ stratum major) of the unit local direction `l` (normal = +Z) in an M×N
/// cosine-stratified grid, or `None` below the tangent plane.
fn cell_of(l: Vec3, m: u32, n: u32) -> Option<usize> {
    if l.z <= 0.0 || !l.is_finite() {
        return None;
    }
    let sin2 = (1.0 - l.z * l.z).max(0.0);
    let j = ((sin2 * m as f32) as u32).min(m - 1);
    let mut phi = l.y.atan2(l.x);
    if phi < 0.0 {
        phi += 2.0 * PI;
    }
    let k = ((phi / (2.0 * PI) * n as f32) as u32).min(n - 1);
    Some((j * n + k) as usize)
}

/// Moves `gather` (traced at `position` in `now`, with `paths` from
/// [`HemisphereGather::trace_keeping_paths`] under the same `settings`) to the frame of
/// `next` (see the module docs).
pub fn reproject(
    now: &World,
    next: &World,
    position: Vec3,
    gather: &HemisphereGather,
    paths: &[CellPath],
    settings: &RecordSettings,
    max_fill_passes: u32,
) -> Reprojection {
    let (m, n) = gather.strata();
    let frame = *gather.frame();
    let count = gather.cells().len();
    let mut radiance = vec![Rgb::ZERO; count];
    let mut depth = vec![f32::INFINITY; count];
    let mut hits = vec![0u32; count];
    // The entry of each cell came from a point that moved.
    let mut moved_entry = vec![false; count];
    let direct_only = PathSettings {
        max_depth: 1,
        ..settings.path
    };
    for (i, (cell, path)) in gather.cells().iter().zip(paths).enumerate() {
        let Some(hit) = path.hit else {
            // Left the scene: the same direction, behind anything that lands here.
            if hits[i] == 0 {
                radiance[i] = match settings.incoming {
                    Incoming::Reflected => Rgb::ZERO,
                    Incoming::All => next.lights.sky_radiance(cell.direction),
                };
            }
            hits[i] += 1;
            continue;
        };
        let index = hit.instance.index();
        let (Some(before), Some(after)) = (
            now.scene.instances.get(index),
            next.scene.instances.get(index),
        ) else {
            continue;
        };
        if after.mask & illume_scene::MASK_DEFAULT == 0 || after.mesh != before.mesh {
            continue;
        }
        let moved = after.world_from_object != before.world_from_object;
        let (target, direction, distance) = if !moved {
            (i, cell.direction, hit.t)
        } else {
            let moved = next.surface(&Ray::new(position, cell.direction), &hit);
            let d = moved.position - position;
            let distance = d.length();
            if !(distance > 0.0 && distance.is_finite()) {
                continue;
            }
            let direction = d / distance;
            match cell_of(frame.to_local(direction), m, n) {
                Some(target) => (target, direction, distance),
                None => continue,
            }
        };
        let occupied = hits[target] > 0;
        hits[target] += 1;
        if occupied && distance >= depth[target] {
            continue;
        }
        let mut at = hit;
        at.t = distance;
        let surface = next.surface(&Ray::new(position, direction), &at);
        let emission = surface.emission;
        let mut out = PathRadiance::default();
        let mut stream = path.stream.clone();
        continue_path(
            next,
            surface,
            -direction,
            &mut stream,
            &direct_only,
            &mut out,
        );
        let mut l = out.direct + path.multiple;
        if settings.incoming == Incoming::All {
            l += emission;
        }
        radiance[target] = l;
        depth[target] = distance;
        moved_entry[target] = moved;
    }
    open_gaps(&mut hits, &depth, &moved_entry, m, n);
    let hole_cells: Vec<bool> = hits.iter().map(|&h| h == 0).collect();
    let (holes, unfilled) = fill_holes(&mut radiance, &mut depth, &hits, m, n, max_fill_passes);
    let cells = gather
        .cells()
        .iter()
        .zip(radiance.into_iter().zip(depth))
        .map(|(c, (radiance, distance_m))| GatherCell {
            direction: c.direction,
            radiance,
            distance_m,
        })
        .collect();
    Reprojection {
        gather: HemisphereGather::from_cells(frame, m, n, cells),
        holes,
        hole_cells,
        unfilled,
    }
}

/// How far (in cells, along θ or φ) [`open_gaps`] looks for moved points on either side.
const GAP_REACH: i64 = 2;

/// Turns into holes the cells a moved surface spread its points over without landing in:
/// a cell whose entry did not move (or left the scene) and has, on both sides along θ
/// or along φ within [`GAP_REACH`] cells, entries of moved points nearer than its own.
/// A moving surface coming nearer covers more cells than it has points; without this,
/// the static background (or the sky) would show through the gaps between them, where
/// the surface now is. Such cells are filled from their neighbours like any hole.
fn open_gaps(hits: &mut [u32], depth: &[f32], moved: &[bool], m: u32, n: u32) {
    let (m, n) = (m as i64, n as i64);
    let nearer_moved = |j: i64, k: i64, than: f32| {
        if !(0..m).contains(&j) {
            return false;
        }
        let o = (j * n + k.rem_euclid(n)) as usize;
        hits[o] > 0 && moved[o] && depth[o] < than
    };
    let mut gaps = Vec::new();
    for j in 0..m {
        for k in 0..n {
            let i = (j * n + k) as usize;
            if hits[i] == 0 || moved[i] {
                continue;
            }
            let d = depth[i];
            let side =
                |dj: i64, dk: i64| (1..=GAP_REACH).any(|r| nearer_moved(j + dj * r, k + dk * r, d));
            if (side(0, -1) && side(0, 1)) || (side(-1, 0) && side(1, 0)) {
                gaps.push(i);
            }
        }
    }
    for i in gaps {
        hits[i] = 0;
    }
}

/// Fills the cells with `hits == 0` (see the module docs, step 4): the radiance of a
/// hole becomes the mean of its filled 3×3 neighbours and its distance their smallest.
/// Returns (holes, holes left for the grid's mean).
fn fill_holes(
    radiance: &mut [Rgb],
    depth: &mut [f32],
    hits: &[u32],
    m: u32,
    n: u32,
    max_passes: u32,
) -> (u32, u32) {
    let mut filled: Vec<bool> = hits.iter().map(|&h| h > 0).collect();
    let holes = filled.iter().filter(|f| !**f).count() as u32;
    if holes == 0 {
        return (0, 0);
    }
    let (m, n) = (m as i64, n as i64);
    let mut left = holes;
    for _ in 0..max_passes {
        let mut fills = Vec::new();
        for j in 0..m {
            for k in 0..n {
                let i = (j * n + k) as usize;
                if filled[i] {
                    continue;
                }
                let (mut sum, mut near, mut count) = (Rgb::ZERO, f32::INFINITY, 0u32);
                for dj in -1..=1 {
                    let jj = j + dj;
                    if !(0..m).contains(&jj) {
                        continue;
                    }
                    for dk in -1..=1 {
                        let kk = (k + dk).rem_euclid(n);
                        let o = (jj * n + kk) as usize;
                        if filled[o] {
                            sum += radiance[o];
                            near = near.min(depth[o]);
                            count += 1;
                        }
                    }
                }
                if count > 0 {
                    fills.push((i, sum * (1.0 / count as f32), near));
                }
            }
        }
        if fills.is_empty() {
            break;
        }
        left -= fills.len() as u32;
        for (i, l, d) in fills {
            radiance[i] = l;
            depth[i] = d;
            filled[i] = true;
        }
        if left == 0 {
            return (holes, 0);
        }
    }
    // What the passes did not reach takes the mean of the grid's filled cells.
    let (mut sum, mut count) = (Rgb::ZERO, 0u32);
    for (l, f) in radiance.iter().zip(&filled) {
        if *f {
            sum += *l;
            count += 1;
        }
    }
    let mean = if count > 0 {
        sum * (1.0 / count as f32)
    } else {
        Rgb::ZERO
    };
    for (l, f) in radiance.iter_mut().zip(&filled) {
        if !*f {
            *l = mean;
        }
    }
    (holes, left)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cells_of_directions_match_the_grid_layout() {
        let (m, n) = (8, 12);
        for j in 0..m {
            for k in 0..n {
                let sin2 = (j as f32 + 0.5) / m as f32;
                let phi = 2.0 * PI * (k as f32 + 0.5) / n as f32;
                let s = sin2.sqrt();
                let l = Vec3::new(s * phi.cos(), s * phi.sin(), (1.0 - sin2).sqrt());
                assert_eq!(cell_of(l, m, n), Some((j * n + k) as usize));
            }
        }
        assert_eq!(cell_of(Vec3::new(1.0, 0.0, -0.1).normalize(), m, n), None);
    }

    #[test]
    fn holes_take_their_neighbours_mean_and_then_the_grid_mean() {
        // 3×4 grid, one filled cell of radiance 2 at (0, 0): its neighbours fill in the
        // first pass (φ wraps: (0, 3) and (1, 3) are neighbours).
        let (m, n) = (3u32, 4u32);
        let mut l = vec![Rgb::ZERO; 12];
        let mut d = vec![f32::INFINITY; 12];
        let mut hits = vec![0u32; 12];
        l[0] = Rgb::splat(2.0);
        d[0] = 5.0;
        hits[0] = 1;
        let (holes, left) = fill_holes(&mut l, &mut d, &hits, m, n, 1);
        assert_eq!(holes, 11);
        // Filled in pass 1: (0,1), (0,3), (1,0), (1,1), (1,3); 6 left for the mean.
        assert_eq!(left, 6);
        for i in [1, 3, 4, 5, 7] {
            assert_eq!(l[i], Rgb::splat(2.0), "cell {i}");
            assert_eq!(d[i], 5.0);
        }
        assert!(l.iter().all(|x| *x == Rgb::splat(2.0)));
    }
}
