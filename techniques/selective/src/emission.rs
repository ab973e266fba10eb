//! Where the sun's photons start (beyond the paper; issue 34 goal 2, `emission_map`).
//!
//! A directional light emits over the disk of the scene's bounding sphere
//! ([`illume_transport::LightSet`]): in an open model most of that disk lies over roofs
//! and outer walls whose photons leave the scene after their first hit, and only the
//! first hit is not stored (the renderer draws direct light). In Dabrovic Sponza under
//! the 13:00 sun 0.028 impacts were stored per photon traced (0.44 per element at the
//! default pool): the elements the camera sees were nearly empty. With the map: 0.355.
//!
//! An emission map spends the photons where they are stored. The disk's sample square
//! (the two emission coordinates, mapped to the disk by an area-preserving map) is cut
//! into [`SIDE`]² cells; before the first photon, [`PILOTS_PER_CELL`] photons per cell
//! are traced uniformly and each cell's importance is the energy its photons stored
//! (luminance, relative to what each carried at its start), moved half-way to its 3 × 3
//! neighbourhood's mean ([`BLUR`]).
//! Photons then start in a cell with density `p` ∝ importance + [`FLOOR`]·mean (never
//! zero, so every path the uniform emission could take remains possible) and carry
//! their flux divided by `p` (relative to uniform): the estimate stays unbiased, only
//! its variance moves — down where impacts are stored, up (rarely met, heavier photons)
//! where they almost never are. The warp is the inverse of the piecewise-constant
//! density's CDF (rows, then the column within the row): monotonic in each coordinate,
//! so a group's photons, which share a tight box of Halton coordinates, still start
//! close together (the coherence §4.2 relies on).
//!
//! The maps are built when the technique starts and kept by every later snapshot:
//! re-tracing a photon must start it where it started before, and a map rebuilt at each
//! change would move every photon. They are rebuilt only when the solution restarts (a
//! light change that re-traces everything anyway) and a directional light has turned by
//! more than [`REBUILD_DEG`] since its map was made, or has none (the sun rose). Between
//! rebuilds a map may fit less well; it stays unbiased.

use crate::fill::run_to_its_end;
use crate::qmc::photon_stream;
use illume_core::sampling::{HaltonScramble, ONE_MINUS_EPSILON, SampleStream};
use illume_core::{Vec2, Vec3, luminance};
use illume_transport::World;
use illume_transport::lights::{Emitter, LightSet};
use illume_transport::photon::{PhotonPath, PhotonPathSettings};
use rayon::prelude::*;
use std::sync::Arc;

/// Cells per side of the emission map.
pub const SIDE: u32 = 32;

/// Photons traced per cell to measure its importance. Measured on Dabrovic Sponza under
/// the 13:00 sun (`scenarios/selective_sponza.toml`, with [`BLUR`]): 32 against 16
/// lowered the frame's relMSE and HDR-FLIP a little (the map's own noise: at a yield of
/// ≈ 3 % most cells' 16 pilots store nothing), for ≈ 0.4 s more warm-up.
pub const PILOTS_PER_CELL: u32 = 32;

/// Share of a cell's importance taken from the mean of its 3 × 3 neighbourhood instead
/// of its own pilots: a cell beside productive ones whose few pilots happened to store
/// nothing would otherwise sit at the [`FLOOR`] and start rare photons of ≈ 100× the
/// typical flux, seen as bright blotches. Measured on Sponza together with 32 pilots a
/// cell (four seeds): relMSE 0.182 → 0.126 at seed 0, HDR-FLIP −0.006 on average.
pub const BLUR: f64 = 0.5;

/// Every cell's density is at least this fraction of the mean importance's (relative):
/// cells whose pilots stored nothing keep a share.
pub const FLOOR: f64 = 0.1;

/// A directional light that turned by more than this since its map was made gets a new
/// one at the next restart \[degrees\].
pub const REBUILD_DEG: f32 = 2.0;

/// First photon index of the map's pilots: far above any pool (whose indices stay
/// below `MAX_POOL` = 2³²), so their Halton points are not the pool's.
const PILOT_INDEX_BASE: u64 = 1 << 40;

/// A piecewise-constant density over the unit square of an emitter's two emission
/// coordinates, and its inverse CDF (module docs).
#[derive(Clone, Debug, PartialEq)]
pub struct EmissionMap {
    /// Relative density per cell (row-major, rows along the second coordinate); their
    /// mean is 1.
    density: Vec<f32>,
    /// Cumulative share of each row, ending at 1.
    row_cdf: Vec<f64>,
    /// Cumulative share of each cell within its row, each row ending at 1.
    cell_cdf: Vec<f64>,
}

impl EmissionMap {
    /// The map of cell `importance` (row-major, [`SIDE`]² values ≥ 0): density ∝
    /// importance + [`FLOOR`]·mean. `None` when nothing was stored anywhere (the uniform
    /// emission is then as good as any).
    pub fn from_importance(importance: &[f64]) -> Option<Self> {
        let n = (SIDE * SIDE) as usize;
        if importance.len() != n || importance.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return None;
        }
        let mean = importance.iter().sum::<f64>() / n as f64;
        if mean <= 0.0 {
            return None;
        }
        let weight: Vec<f64> = importance.iter().map(|v| v + FLOOR * mean).collect();
        let total: f64 = weight.iter().sum();
        let density = weight
            .iter()
            .map(|w| (w / total * n as f64) as f32)
            .collect();
        let side = SIDE as usize;
        let mut row_cdf = Vec::with_capacity(side);
        let mut cell_cdf = Vec::with_capacity(n);
        let mut acc = 0.0;
        for row in weight.chunks(side) {
            let row_total: f64 = row.iter().sum();
            acc += row_total / total;
            row_cdf.push(acc);
            let mut c = 0.0;
            for w in row {
                c += w / row_total;
                cell_cdf.push(c);
            }
            if let Some(last) = cell_cdf.last_mut() {
                *last = 1.0;
            }
        }
        if let Some(last) = row_cdf.last_mut() {
            *last = 1.0;
        }
        Some(Self {
            density,
            row_cdf,
            cell_cdf,
        })
    }

    /// `u` (uniform on the unit square) warped to the map's density, and that density
    /// (relative to uniform) at the result: a photon started there carries its flux
    /// divided by it.
    pub fn warp(&self, u: Vec2) -> (Vec2, f32) {
        let side = SIDE as usize;
        let (row, fy) = invert(&self.row_cdf, u.y as f64);
        let (col, fx) = invert(&self.cell_cdf[row * side..(row + 1) * side], u.x as f64);
        let at = Vec2::new(
            ((col as f64 + fx) / side as f64) as f32,
            ((row as f64 + fy) / side as f64) as f32,
        )
        .clamp(Vec2::ZERO, Vec2::splat(ONE_MINUS_EPSILON));
        (at, self.density[row * side + col])
    }

    /// The relative density of cell (column, row).
    pub fn density(&self, column: u32, row: u32) -> f32 {
        self.density[(row * SIDE + column) as usize]
    }
}

/// The bin of `u` in the cumulative `cdf` and `u`'s fraction within it.
fn invert(cdf: &[f64], u: f64) -> (usize, f64) {
    let i = cdf.partition_point(|&c| c <= u).min(cdf.len() - 1);
    let lo = if i == 0 { 0.0 } else { cdf[i - 1] };
    let width = cdf[i] - lo;
    let f = if width > 0.0 { (u - lo) / width } else { 0.5 };
    (i, f.clamp(0.0, 1.0))
}

/// The emission maps of a light set's directional lights, and the directions they
/// were made for (a light whose pilots stored nothing has a direction and no map).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EmissionMaps {
    /// Emitter index and its map.
    pub maps: Vec<(u32, Arc<EmissionMap>)>,
    /// Emitter index and the direction its light travelled in when its map was made.
    pub built_for: Vec<(u32, Vec3)>,
}

impl EmissionMaps {
    /// The map of emitter `i`, if it has one.
    pub fn of(&self, i: u32) -> Option<&EmissionMap> {
        self.maps.iter().find(|(e, _)| *e == i).map(|(_, m)| &**m)
    }

    /// True when every directional light of `lights` with power was mapped in its
    /// present direction (within [`REBUILD_DEG`]).
    pub fn fit(&self, lights: &LightSet) -> bool {
        let cos = REBUILD_DEG.to_radians().cos();
        lights
            .emitters()
            .iter()
            .zip(lights.powers())
            .enumerate()
            .all(|(i, (e, power))| match e {
                Emitter::Directional { direction, .. } if power.max_element() > 0.0 => self
                    .built_for
                    .iter()
                    .any(|(j, d)| *j == i as u32 && d.dot(*direction) >= cos),
                _ => true,
            })
    }
}

/// The emission maps of `world`'s directional lights (module docs), from pilot photons
/// traced with `path` settings.
pub fn build_maps(
    world: &World,
    path: &PhotonPathSettings,
    scramble: &HaltonScramble,
) -> EmissionMaps {
    let lights = &world.lights;
    let mut maps = EmissionMaps::default();
    for (i, e) in lights.emitters().iter().enumerate() {
        let Emitter::Directional { direction, .. } = e else {
            continue;
        };
        if lights.powers()[i].max_element() <= 0.0 {
            continue;
        }
        maps.built_for.push((i as u32, *direction));
        let cells = SIDE * SIDE;
        let importance: Vec<f64> = (0..cells)
            .into_par_iter()
            .map(|cell| {
                let (column, row) = (cell % SIDE, cell / SIDE);
                let mut stored = 0.0;
                world.tracer.scoped(|tracer| {
                    for k in 0..PILOTS_PER_CELL {
                        let index = PILOT_INDEX_BASE
                            + (i as u64) * u64::from(cells * PILOTS_PER_CELL)
                            + u64::from(cell * PILOTS_PER_CELL + k);
                        let mut s = photon_stream(index, scramble);
                        let jitter = s.next_2d();
                        let u = Vec2::new(
                            (column as f32 + jitter.x) / SIDE as f32,
                            (row as f32 + jitter.y) / SIDE as f32,
                        );
                        let Some(sample) = lights.emit_from(i, 1.0, u, Vec2::splat(0.5), &mut s)
                        else {
                            continue;
                        };
                        let flux = luminance(sample.flux).max(f32::MIN_POSITIVE) as f64;
                        let p = PhotonPath::emitted(sample);
                        // Stored energy relative to the photon's start.
                        run_to_its_end(world, tracer, path, p, &mut s, |f| {
                            stored += luminance(f) as f64 / flux;
                        });
                    }
                });
                stored
            })
            .collect();
        if let Some(map) = EmissionMap::from_importance(&blurred(&importance)) {
            maps.maps.push((i as u32, Arc::new(map)));
        }
    }
    maps
}

/// `importance` (row-major, [`SIDE`]²) with each cell's value moved [`BLUR`] of the way
/// to the mean of its 3 × 3 neighbourhood (fewer cells at the square's edge).
fn blurred(importance: &[f64]) -> Vec<f64> {
    let side = SIDE as usize;
    (0..importance.len())
        .map(|c| {
            let (x, y) = (c % side, c / side);
            let (mut sum, mut n) = (0.0, 0.0);
            for v in y.saturating_sub(1)..(y + 2).min(side) {
                for u in x.saturating_sub(1)..(x + 2).min(side) {
                    sum += importance[v * side + u];
                    n += 1.0;
                }
            }
            (1.0 - BLUR) * importance[c] + BLUR * sum / n
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_map_warps_uniform_points_to_its_density() {
        // Importance in one column block: cells 0..8 of every row 1, the rest 0.
        let n = (SIDE * SIDE) as usize;
        let importance: Vec<f64> = (0..n)
            .map(|c| if (c as u32 % SIDE) < 8 { 1.0 } else { 0.0 })
            .collect();
        let map = EmissionMap::from_importance(&importance).unwrap();
        // Mean 0.25; weights 1.025 inside, 0.025 outside: densities relative to uniform.
        let (inside, outside) = (1.025 / (0.25 * 1.025 + 0.75 * 0.025), 0.025 / 0.275);
        assert!((map.density(0, 0) as f64 - inside).abs() < 1e-4);
        assert!((map.density(20, 5) as f64 - outside).abs() < 1e-4);
        // A uniform grid of points lands in the first 8 columns in the density's share,
        // and the weights 1/p average to 1 over the square (unbiased emission). The grid
        // is fine along u.x (4 096 points a row), where an outer cell takes only 0.28 %
        // of a row: a coarse grid would count its points a whole point off.
        let (mx, my) = (4096, 64);
        let (mut share, mut mean_weight) = (0.0, 0.0);
        for a in 0..mx {
            for b in 0..my {
                let u = Vec2::new((a as f32 + 0.5) / mx as f32, (b as f32 + 0.5) / my as f32);
                let (w, p) = map.warp(u);
                assert!(w.x >= 0.0 && w.x < 1.0 && w.y >= 0.0 && w.y < 1.0);
                let col = (w.x * SIDE as f32) as u32;
                let row = (w.y * SIDE as f32) as u32;
                assert_eq!(p, map.density(col.min(SIDE - 1), row.min(SIDE - 1)));
                if col < 8 {
                    share += 1.0;
                }
                mean_weight += 1.0 / p as f64;
            }
        }
        let total = (mx * my) as f64;
        let want = 0.25 * inside;
        assert!(
            (share / total - want).abs() < 0.01,
            "share {}",
            share / total
        );
        // E[1/p] over the warped points = Σ cells (p/N)·(1/p) = 1.
        assert!(
            (mean_weight / total - 1.0).abs() < 0.01,
            "{}",
            mean_weight / total
        );
    }

    #[test]
    fn the_blur_keeps_the_total_inside_and_reaches_the_neighbours_only() {
        let n = (SIDE * SIDE) as usize;
        let mut importance = vec![0.0; n];
        let centre = (10 * SIDE + 10) as usize;
        importance[centre] = 9.0;
        let b = blurred(&importance);
        // Own share 1 − BLUR plus BLUR / 9 of itself; each of the 8 neighbours BLUR / 9.
        assert!((b[centre] - (9.0 * (1.0 - BLUR) + BLUR)).abs() < 1e-12);
        assert!((b[centre + 1] - BLUR).abs() < 1e-12);
        assert!((b[centre + SIDE as usize + 1] - BLUR).abs() < 1e-12);
        assert_eq!(b[centre + 2], 0.0);
        // Away from the square's edge the total is kept.
        assert!((b.iter().sum::<f64>() - 9.0).abs() < 1e-9);
    }

    #[test]
    fn nothing_stored_gives_no_map() {
        let n = (SIDE * SIDE) as usize;
        assert!(EmissionMap::from_importance(&vec![0.0; n]).is_none());
        assert!(EmissionMap::from_importance(&[1.0; 3]).is_none());
        let mut bad = vec![1.0; n];
        bad[5] = f64::NAN;
        assert!(EmissionMap::from_importance(&bad).is_none());
    }
}
