//! Mip-mapped texture lookups by pixel footprint, for the rasterized G-buffer
//! ([`TextureFilter::Trilinear`](crate::gbuffer::TextureFilter)).
//!
//! A pixel whose footprint covers many texels and reads one bilinear sample at its
//! centre aliases (a minified checkerboard shows moiré instead of its mean grey) and
//! costs a cache miss per pixel, since neighbouring pixels read texels far apart. A mip
//! chain holds the texture box-filtered to half the size per level, down to one texel;
//! a lookup picks the level whose texels match the pixel's footprint
//! (`lod = log₂` of the longer of the footprint's two sides in texels, the isotropic
//! rule of OpenGL's specification, §8.14) and blends the two nearest levels, each read
//! bilinearly (trilinear filtering). Where the footprint is at most one texel
//! (`lod ≤ 0`: magnification), the lookup is the texture's plain bilinear one, bit for
//! bit.

use crate::hit_tables::floor_i64;
use illume_core::{Rgb, Vec2, Vec4};
use illume_scene::{Texture, WrapMode};
use rayon::prelude::*;

/// The change of a pixel's texture coordinates to its right-hand and to its lower
/// neighbour (ray differentials of the pixel-centre camera rays, on the hit's triangle).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct UvFootprint {
    /// `uv(x + 1, y) − uv(x, y)`.
    pub duv_dx: Vec2,
    /// `uv(x, y + 1) − uv(x, y)`.
    pub duv_dy: Vec2,
}

impl UvFootprint {
    /// The level of detail for a `width × height` texture: `log₂` of the longer of the
    /// footprint's sides measured in texels, ≤ 0 exactly where that side is at most one
    /// texel. The logarithm is the exponent-and-mantissa approximation GPUs use (exact
    /// at powers of two, linear between them, within 0.09 of `log₂`); a footprint that is
    /// not finite (a neighbouring ray parallel to the surface) gets the coarsest level.
    #[inline]
    pub fn lod(&self, width: u32, height: u32) -> f32 {
        self.lod_for_size(Vec2::new(width as f32, height as f32))
    }

    /// [`UvFootprint::lod`] for a texture of `size = (width, height)` texels, as floats.
    #[inline]
    pub(crate) fn lod_for_size(&self, size: Vec2) -> f32 {
        let (x, y) = (self.duv_dx * size, self.duv_dy * size);
        0.5 * log2_approx(x.length_squared().max(y.length_squared()))
    }

    /// The footprint in the coordinates of an affine texture transform `apply` (the
    /// derivatives of `apply` at `uv`).
    #[inline]
    pub fn through(&self, uv: Vec2, apply: impl Fn(Vec2) -> Vec2) -> Self {
        let at = apply(uv);
        Self {
            duv_dx: apply(uv + self.duv_dx) - at,
            duv_dy: apply(uv + self.duv_dy) - at,
        }
    }
}

/// `log₂ x` for `x ≥ 0`, piecewise linear between powers of two (where it is exact):
/// the float's bits read as a fixed-point number. Monotonic; 0 → −127; +∞ and NaN →
/// about 128.
#[inline(always)]
fn log2_approx(x: f32) -> f32 {
    x.to_bits() as f32 * (1.0 / (1u32 << 23) as f32) - 127.0
}

/// One level of a [`MipChain`]: linear RGB texels (fourth lane 0, for aligned SIMD
/// arithmetic), row-major, wrapped like the texture.
#[derive(Clone, Debug)]
pub(crate) struct MipLevel {
    width: u32,
    height: u32,
    /// `(width, height)` as floats.
    size: Vec2,
    texels: Vec<Vec4>,
}

/// A texture's mip levels 1, 2, … down to one texel (level 0 is the texture itself):
/// level k + 1 is level k box-filtered to half its size in each direction (rounded
/// down, at least 1), each texel the area-weighted mean of the texels it covers, so
/// every level keeps the texture's mean up to f32 rounding.
#[derive(Clone, Debug)]
pub(crate) struct MipChain {
    /// The texture's own size (level 0), for the level of detail, and as floats.
    size0: (u32, u32),
    size0_f32: Vec2,
    levels: Vec<MipLevel>,
    wrap_u: WrapMode,
    wrap_v: WrapMode,
}

impl MipChain {
    /// The chain of `texture`; `None` for a texture of one texel or none.
    pub(crate) fn new(texture: &Texture) -> Option<Self> {
        let (mut w, mut h) = (texture.width, texture.height);
        if texture.texels.len() != (w as usize) * (h as usize) || w * h <= 1 {
            return None;
        }
        let mut levels: Vec<MipLevel> = Vec::new();
        let mut source = texture.texels.clone();
        while w > 1 || h > 1 {
            let (nw, nh) = ((w / 2).max(1), (h / 2).max(1));
            let texels = downsample(&source, w, h, nw, nh);
            levels.push(MipLevel {
                width: nw,
                height: nh,
                size: Vec2::new(nw as f32, nh as f32),
                texels: texels.iter().map(|t| t.extend(0.0)).collect(),
            });
            source = texels;
            (w, h) = (nw, nh);
        }
        Some(Self {
            size0: (texture.width, texture.height),
            size0_f32: Vec2::new(texture.width as f32, texture.height as f32),
            levels,
            wrap_u: texture.wrap_u,
            wrap_v: texture.wrap_v,
        })
    }

    /// Number of levels below the texture itself.
    #[cfg(test)]
    pub(crate) fn len(&self) -> usize {
        self.levels.len()
    }

    /// The texels of level `k` (1-based: level 1 is the first halving).
    #[cfg(test)]
    pub(crate) fn level(&self, k: usize) -> Vec<Rgb> {
        self.levels[k - 1]
            .texels
            .iter()
            .map(|t| t.truncate())
            .collect()
    }

    /// True when `other` has this chain's texture size and wrap modes: a lookup at the
    /// same `uv` and level of detail then reads the same texel positions with the same
    /// weights in both ([`MipChain::sample_pair`]).
    #[inline]
    pub(crate) fn same_layout(&self, other: &Self) -> bool {
        // Level k's size follows from level 0's: equal sizes, equal chains.
        self.size0 == other.size0 && self.wrap_u == other.wrap_u && self.wrap_v == other.wrap_v
    }

    /// The level of detail of `footprint` for this texture ([`UvFootprint::lod`]).
    #[inline]
    pub(crate) fn lod(&self, footprint: &UvFootprint) -> f32 {
        footprint.lod_for_size(self.size0_f32)
    }

    /// Trilinear lookup at `uv` for level of detail `lod`, `level0` reading the texture
    /// itself bilinearly; exactly `level0(uv)` where `lod ≤ 0` or is NaN, the one-texel
    /// level beyond the chain's end.
    #[inline]
    pub(crate) fn sample(&self, uv: Vec2, lod: f32, level0: impl Fn(Vec2) -> Rgb) -> Rgb {
        let Some((k, f)) = self.split_lod(lod) else {
            return level0(uv);
        };
        match (k, f > 0.0) {
            (0, false) => level0(uv),
            (0, true) => level0(uv)
                .extend(0.0)
                .lerp(self.blend(0, &self.taps(0, uv)), f)
                .truncate(),
            (_, false) => self.blend(k - 1, &self.taps(k - 1, uv)).truncate(),
            (_, true) => self
                .blend(k - 1, &self.taps(k - 1, uv))
                .lerp(self.blend(k, &self.taps(k, uv)), f)
                .truncate(),
        }
    }

    /// [`MipChain::sample`] of this chain and of `other` (whose layout is the same,
    /// [`MipChain::same_layout`]) at the same `uv` and `lod`, bit for bit, with the
    /// level, texel positions and weights found once for both.
    #[inline]
    pub(crate) fn sample_pair(
        &self,
        other: &Self,
        uv: Vec2,
        lod: f32,
        level0: impl Fn(Vec2) -> (Rgb, Rgb),
    ) -> (Rgb, Rgb) {
        debug_assert!(self.same_layout(other));
        let Some((k, f)) = self.split_lod(lod) else {
            return level0(uv);
        };
        let both = |i: usize, taps: &Taps| (self.blend(i, taps), other.blend(i, taps));
        let lerp = |(a, b): (Vec4, Vec4), (c, d): (Vec4, Vec4)| {
            (a.lerp(c, f).truncate(), b.lerp(d, f).truncate())
        };
        match (k, f > 0.0) {
            (0, false) => level0(uv),
            (0, true) => {
                let (a, b) = level0(uv);
                lerp((a.extend(0.0), b.extend(0.0)), both(0, &self.taps(0, uv)))
            }
            (_, false) => {
                let (a, b) = both(k - 1, &self.taps(k - 1, uv));
                (a.truncate(), b.truncate())
            }
            (_, true) => lerp(
                both(k - 1, &self.taps(k - 1, uv)),
                both(k, &self.taps(k, uv)),
            ),
        }
    }

    /// `lod` as the level `k` at or below it and the blend `f` towards level `k + 1`
    /// (`k = 0` is the texture itself), clamped to the chain's end; `None` for
    /// `lod ≤ 0` or NaN (the texture itself).
    #[inline(always)]
    fn split_lod(&self, lod: f32) -> Option<(usize, f32)> {
        if lod.is_nan() || lod <= 0.0 {
            return None;
        }
        let top = self.levels.len() as f32;
        let lod = lod.min(top);
        // lod ∈ (0, top] < 2³¹: the cast truncates.
        let k = lod as i32 as usize;
        Some((k, lod - k as f32))
    }

    /// Where the bilinear lookup at `uv` reads in `levels[i]`: texel centres at
    /// half-integers as in [`Texture::sample`] (whose arithmetic it follows).
    #[inline(always)]
    fn taps(&self, i: usize, uv: Vec2) -> Taps {
        let l = &self.levels[i];
        let p = uv * l.size - Vec2::splat(0.5);
        let (ix, iy) = (floor_i64(p.x), floor_i64(p.y));
        let (cx0, cx1) = wrap_pair(self.wrap_u, ix, l.width);
        let (cy0, cy1) = wrap_pair(self.wrap_v, iy, l.height);
        let w = l.width as usize;
        Taps {
            rows: [cy0 * w, cy1 * w],
            columns: [cx0, cx1],
            fx: p.x - ix as f32,
            fy: p.y - iy as f32,
        }
    }

    /// The bilinear blend of `levels[i]`'s texels at `taps`.
    #[inline(always)]
    fn blend(&self, i: usize, taps: &Taps) -> Vec4 {
        let t = &self.levels[i].texels;
        let ([r0, r1], [cx0, cx1]) = (taps.rows, taps.columns);
        let top = t[r0 + cx0].lerp(t[r0 + cx1], taps.fx);
        let bottom = t[r1 + cx0].lerp(t[r1 + cx1], taps.fx);
        top.lerp(bottom, taps.fy)
    }
}

/// The four texels a bilinear lookup reads in one level (row offsets and columns) and
/// its fractions between them.
#[derive(Clone, Copy, Debug)]
struct Taps {
    rows: [usize; 2],
    columns: [usize; 2],
    fx: f32,
    fy: f32,
}

/// `(mode.wrap(i, n), mode.wrap(i + 1, n))` ([`WrapMode::wrap_pair`]), with the
/// interior of the texture and repeating textures answered inline (tiled floors and
/// walls read outside [0, 1] for a third of their lookups).
#[inline(always)]
pub(crate) fn wrap_pair(mode: WrapMode, i: i64, n: u32) -> (usize, usize) {
    // `0 ≤ i < n − 1` in one unsigned comparison (a negative `i` is above any `n`).
    if (i as u64) < u64::from(n).wrapping_sub(1) {
        return (i as usize, i as usize + 1);
    }
    if mode == WrapMode::Repeat {
        // `n ≥ 1` (`max` tells the compiler so: no division-by-zero check).
        let a = i.rem_euclid(i64::from(n.max(1))) as usize;
        return (a, if a + 1 == n as usize { 0 } else { a + 1 });
    }
    mode.wrap_pair(i, n)
}

/// `source` (`w × h`) box-filtered to `nw × nh`: area-weighted means, separably.
fn downsample(source: &[Rgb], w: u32, h: u32, nw: u32, nh: u32) -> Vec<Rgb> {
    let (wx, wy) = (
        crate::hit_tables::box_weights(w, nw),
        crate::hit_tables::box_weights(h, nh),
    );
    let rows: Vec<Rgb> = source
        .par_chunks(w as usize)
        .flat_map_iter(|row| {
            wx.iter()
                .map(move |taps| taps.iter().fold(Rgb::ZERO, |acc, &(j, a)| acc + row[j] * a))
        })
        .collect();
    (0..nh as usize)
        .into_par_iter()
        .flat_map_iter(|y| {
            let (rows, taps) = (&rows, &wy[y]);
            (0..nw as usize).map(move |x| {
                taps.iter().fold(Rgb::ZERO, |acc, &(j, a)| {
                    acc + rows[j * nw as usize + x] * a
                })
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn texture(w: u32, h: u32, f: impl Fn(u32, u32) -> Rgb) -> Texture {
        Texture::from_fn("test", w, h, f)
    }

    fn mean(t: &[Rgb]) -> Rgb {
        t.iter().copied().sum::<Rgb>() / t.len() as f32
    }

    #[test]
    fn every_level_keeps_the_texture_mean() {
        // Sizes that halve unevenly (odd sides, non-square) and noisy content.
        for (w, h) in [(64u32, 64u32), (37, 10), (1, 9), (300, 7)] {
            let tex = texture(w, h, |x, y| {
                let k = (x * 7919 + y * 104_729) % 97;
                Rgb::new(k as f32 / 97.0, ((x ^ y) % 5) as f32 / 4.0, 0.25)
            });
            let chain = MipChain::new(&tex).expect("more than one texel");
            let m0 = mean(&tex.texels);
            let last = chain.level(chain.len());
            assert_eq!(last.len(), 1, "{w}x{h}: the chain ends at one texel");
            for k in 1..=chain.len() {
                let m = mean(&chain.level(k));
                assert!(
                    (m - m0).abs().max_element() < 1e-5,
                    "{w}x{h} level {k}: mean {m} against {m0}"
                );
            }
        }
        assert!(MipChain::new(&texture(1, 1, |_, _| Rgb::ONE)).is_none());
    }

    #[test]
    fn the_approximate_log2_is_exact_at_powers_of_two_and_close_between() {
        for k in -20..=20 {
            assert_eq!(log2_approx(2f32.powi(k)), k as f32);
        }
        let mut previous = f32::NEG_INFINITY;
        for i in 1..10_000 {
            let x = i as f32 * 0.013;
            let l = log2_approx(x);
            assert!((l - x.log2()).abs() < 0.09, "{x}: {l} against {}", x.log2());
            assert!(l >= previous, "not monotonic at {x}");
            previous = l;
        }
        assert!(log2_approx(f32::INFINITY) >= 128.0);
        assert!(log2_approx(0.0) <= -127.0);
    }

    #[test]
    fn inline_wrapping_equals_the_wrap_modes() {
        for mode in [WrapMode::Repeat, WrapMode::Clamp, WrapMode::Mirror] {
            for n in [1u32, 2, 3, 7, 64, 477] {
                let n64 = i64::from(n);
                let far = [i64::MIN, i64::MIN + 1, -(1 << 40), 1 << 40, i64::MAX - 1];
                for i in (-3 * n64 - 2..3 * n64 + 2).chain(far) {
                    assert_eq!(
                        wrap_pair(mode, i, n),
                        mode.wrap_pair(i, n),
                        "{mode:?} i {i} n {n}"
                    );
                }
            }
        }
    }

    #[test]
    fn magnified_lookups_equal_the_plain_bilinear_one() {
        let tex = texture(16, 8, |x, y| Rgb::new(x as f32, y as f32, (x * y) as f32));
        let chain = MipChain::new(&tex).expect("chain");
        for (i, uv) in [(0.1f32, 0.2f32), (0.97, 0.5), (-0.3, 1.7)]
            .into_iter()
            .enumerate()
        {
            let uv = Vec2::from(uv);
            for lod in [0.0, -2.0, f32::NAN, f32::NEG_INFINITY] {
                assert_eq!(
                    chain.sample(uv, lod, |uv| tex.sample(uv)),
                    tex.sample(uv),
                    "{i}"
                );
            }
        }
        // A footprint of one texel or less is lod ≤ 0.
        let f = UvFootprint {
            duv_dx: Vec2::new(1.0 / 16.0, 0.0),
            duv_dy: Vec2::new(0.0, 0.5 / 8.0),
        };
        assert_eq!(f.lod(16, 8), 0.0);
    }

    #[test]
    fn a_minified_checkerboard_reads_its_mean_grey() {
        // One-texel checks: a pixel covering 8×8 texels must see the mean (0.5), where
        // a bilinear lookup at the pixel centre reads 0 or 1 (aliasing).
        let tex = texture(256, 256, |x, y| Rgb::splat(((x + y) % 2) as f32));
        let chain = MipChain::new(&tex).expect("chain");
        let f = UvFootprint {
            duv_dx: Vec2::new(8.0 / 256.0, 0.0),
            duv_dy: Vec2::new(0.0, 8.0 / 256.0),
        };
        let lod = f.lod(256, 256);
        assert!((lod - 3.0).abs() < 1e-6, "{lod}");
        let mut worst = 0.0f32;
        let mut aliased = 0;
        for i in 0..100 {
            let uv = Vec2::new(
                (i as f32 * 0.618_034).fract(),
                (i as f32 * 0.414_214).fract(),
            );
            let v = chain.sample(uv, lod, |uv| tex.sample(uv));
            worst = worst.max((v - Rgb::splat(0.5)).abs().max_element());
            let point = tex.sample(Vec2::new(
                (uv.x * 256.0).floor() / 256.0 + 0.5 / 256.0,
                (uv.y * 256.0).floor() / 256.0 + 0.5 / 256.0,
            ));
            aliased += usize::from((point - Rgb::splat(0.5)).abs().max_element() > 0.4);
        }
        assert!(worst < 1e-5, "mip lookups stray from the mean by {worst}");
        assert_eq!(aliased, 100, "texel-centre lookups see black or white");
        // Between levels the blend stays on the mean too; beyond the chain, the last level.
        assert!(
            (chain.sample(Vec2::splat(0.3), 2.5, |uv| tex.sample(uv)) - Rgb::splat(0.5))
                .abs()
                .max_element()
                < 1e-5
        );
        assert_eq!(
            chain.sample(Vec2::splat(0.3), 100.0, |uv| tex.sample(uv)),
            chain.level(chain.len())[0]
        );
    }
}
