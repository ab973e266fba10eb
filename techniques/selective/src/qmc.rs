//! Quasi-Monte Carlo photon paths (§4.1, Eqs. 1–2) and the group size N_g (§4.2,
//! Eqs. 3–5).
//!
//! Photon `i` follows the scrambled Halton point `i`; its dimensions are read in the
//! order the paper gives them bases (§4.1): dimension 0 (base 2) chooses the light and,
//! remapped, is the first emission coordinate; the light's other emission coordinates
//! take the next bases (a point or spot light reads one more, an area light three);
//! then every bounce reads two, the roulette number remapped into the first direction
//! coordinate ([`PhotonPathSettings::remap_roulette`]). So for a point light bases 2, 3
//! are the emission direction and 5, 7 the first bounce — the paper's Φ₂…Φ₇.
//!
//! **Light choice.** Lights are *units* — a scene light, an emissive object (all its
//! triangles), the sky — chosen by CDF inversion of dimension 0 over `C = 2^k₂` equal
//! cells (k₂ the exponent of base 2 in N_g), each unit owning a whole number of cells
//! in proportion to its power (at least one). Photons `i` and `i + m·N_g` share their
//! first k₂ binary digits (Eq. 3), so they fall in the same cell and leave the same
//! unit — the coherence §7 buys with 2^(3+⌈log₂ L⌉). The unit's share is rounded to
//! cells, so its photons carry power/(cells/C): unbiased, not equal-power. Within a
//! unit, an emitter (an emissive triangle) is chosen by CDF inversion of the remapped
//! number, remapped again into the first emission coordinate.
//!
//! [`PhotonPathSettings::remap_roulette`]: illume_transport::photon::PhotonPathSettings

use illume_core::sampling::{HaltonScramble, HaltonStream, ONE_MINUS_EPSILON};
use illume_core::{Rgb, Vec2};
use illume_transport::lights::{Emitter, LightSet};
use illume_transport::photon::PhotonPath;
use std::hash::{Hash, Hasher};

/// Halton dimensions with a base of their own ([`PRIMES`]); deeper dimensions are
/// pseudo-random, so N_g can only be factored over these bases.
pub const MAPPED_DIMENSIONS: usize = 64;

/// N_g = Π bᵏ (Eq. 5), with the exponent of each base.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct GroupFactors {
    factors: Vec<(u32, u32)>,
    groups: u64,
}

impl GroupFactors {
    /// N_g from `[base, exponent]` pairs (bases among the first
    /// [`MAPPED_DIMENSIONS`] primes; checked by the settings).
    pub fn new(factors: &[[u32; 2]]) -> Self {
        let factors: Vec<(u32, u32)> = factors
            .iter()
            .filter(|f| f[1] > 0)
            .map(|f| (f[0], f[1]))
            .collect();
        let groups = factors
            .iter()
            .map(|&(b, k)| (b as u64).pow(k))
            .product::<u64>();
        Self { factors, groups }
    }

    /// The paper's default for `units` light units (§7): 2^(3+⌈log₂ L⌉)·3².
    pub fn paper_default(units: usize) -> Self {
        let log2 = (units.max(1) as u64).next_power_of_two().trailing_zeros();
        Self::new(&[[2, 3 + log2], [3, 2]])
    }

    /// N_g.
    pub fn groups(&self) -> u64 {
        self.groups
    }

    /// The exponent k_b of `base` (0 when N_g has no such factor).
    pub fn exponent(&self, base: u32) -> u32 {
        self.factors.iter().find(|f| f.0 == base).map_or(0, |f| f.1)
    }

    /// The `(base, exponent)` pairs.
    pub fn factors(&self) -> &[(u32, u32)] {
        &self.factors
    }
}

impl std::fmt::Display for GroupFactors {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let parts: Vec<String> = self
            .factors
            .iter()
            .map(|(b, k)| format!("{b}^{k}"))
            .collect();
        write!(f, "{} = {}", self.groups, parts.join("·"))
    }
}

/// The sample stream of photon `index`: the scrambled Halton point, dimension by
/// dimension.
#[inline]
pub fn photon_stream(index: u64, scramble: &HaltonScramble) -> HaltonStream<'_> {
    HaltonStream::scrambled(index, scramble)
}

/// What a light unit is in the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum UnitKey {
    /// A scene light (point, spot, directional).
    Light(u32),
    /// An emissive instance (all its emissive triangles).
    Instance(u32),
    /// The sky.
    Sky,
}

/// One light unit: its emitters, cells and a signature of everything its photons
/// depend on.
#[derive(Clone, Debug)]
pub struct LightUnit {
    /// What it is.
    pub key: UnitKey,
    /// Indices into [`LightSet::emitters`] (the sky: the emitter count).
    pub emitters: Vec<u32>,
    /// Cumulative selection weights of `emitters`, ending at 1.
    cdf: Vec<f64>,
    /// First cell.
    pub first_cell: u32,
    /// Cells owned (0 for a unit without power).
    pub cells: u32,
    /// Power \[W\] (channel sum over emitters).
    pub power: f64,
    /// Hash of every emitter's geometry and emission: equal signatures, equal photons.
    pub signature: u64,
}

/// The light units of a light set and their cells (see the module doc).
#[derive(Clone, Debug)]
pub struct LightCells {
    units: Vec<LightUnit>,
    /// Owner unit of every cell.
    owner: Vec<u32>,
    /// Emission maps by emitter index ([`crate::emission`]); empty: uniform emission.
    maps: crate::emission::EmissionMaps,
}

fn weight(power: Rgb) -> f64 {
    (power.x as f64 + power.y as f64 + power.z as f64).max(0.0)
}

fn hash_f32s<H: Hasher>(h: &mut H, xs: &[f32]) {
    for x in xs {
        x.to_bits().hash(h);
    }
}

fn emitter_signature<H: Hasher>(h: &mut H, e: &Emitter) {
    match e {
        Emitter::Point {
            light,
            position,
            intensity,
        } => {
            (0u8, light.0).hash(h);
            hash_f32s(h, &position.to_array());
            hash_f32s(h, &intensity.to_array());
        }
        Emitter::Spot {
            light,
            position,
            axis,
            intensity,
            cos_inner,
            cos_outer,
        } => {
            (1u8, light.0).hash(h);
            hash_f32s(h, &position.to_array());
            hash_f32s(h, &axis.to_array());
            hash_f32s(h, &intensity.to_array());
            hash_f32s(h, &[*cos_inner, *cos_outer]);
        }
        Emitter::Directional {
            light,
            direction,
            irradiance,
        } => {
            (2u8, light.0).hash(h);
            hash_f32s(h, &direction.to_array());
            hash_f32s(h, &irradiance.to_array());
        }
        Emitter::Triangle {
            instance,
            triangle,
            corners,
            radiance,
            double_sided,
            texture,
            ..
        } => {
            (3u8, instance.0, *triangle, *double_sided).hash(h);
            for c in corners {
                hash_f32s(h, &c.to_array());
            }
            hash_f32s(h, &radiance.to_array());
            texture
                .as_ref()
                .map(|(t, _)| std::sync::Arc::as_ptr(t) as usize)
                .hash(h);
        }
    }
}

impl LightCells {
    /// The units of `lights` over `2^k` cells, `k = max(k₂, ⌈log₂ units⌉)`.
    pub fn new(lights: &LightSet, k2: u32) -> Self {
        let mut units: Vec<LightUnit> = Vec::new();
        let mut index = std::collections::HashMap::new();
        let n = lights.emitters().len();
        let powers = lights.powers();
        let mut push = |key: UnitKey, e: u32, p: Rgb, units: &mut Vec<LightUnit>| {
            let u = *index.entry(key).or_insert_with(|| {
                units.push(LightUnit {
                    key,
                    emitters: Vec::new(),
                    cdf: Vec::new(),
                    first_cell: 0,
                    cells: 0,
                    power: 0.0,
                    signature: 0,
                });
                units.len() - 1
            });
            units[u].emitters.push(e);
            units[u].cdf.push(weight(p));
            units[u].power += weight(p);
        };
        for (i, e) in lights.emitters().iter().enumerate() {
            let key = match e {
                Emitter::Point { light, .. }
                | Emitter::Spot { light, .. }
                | Emitter::Directional { light, .. } => UnitKey::Light(light.0),
                Emitter::Triangle { instance, .. } => UnitKey::Instance(instance.0),
            };
            push(key, i as u32, powers[i], &mut units);
        }
        if weight(lights.sky_power()) > 0.0 {
            push(UnitKey::Sky, n as u32, lights.sky_power(), &mut units);
        }
        for u in &mut units {
            let mut h = std::collections::hash_map::DefaultHasher::new();
            u.key.hash(&mut h);
            for &e in &u.emitters {
                match lights.emitters().get(e as usize) {
                    Some(em) => emitter_signature(&mut h, em),
                    None => {
                        // The sky: its power and kind (a changed sky changes power).
                        hash_f32s(&mut h, &lights.sky_power().to_array());
                    }
                }
            }
            u.signature = h.finish();
            // Weights → cumulative fractions.
            let total: f64 = u.cdf.iter().sum();
            let mut acc = 0.0;
            for w in &mut u.cdf {
                acc += if total > 0.0 { *w / total } else { 0.0 };
                *w = acc;
            }
            if let Some(last) = u.cdf.last_mut() {
                *last = 1.0;
            }
        }
        let live = units.iter().filter(|u| u.power > 0.0).count();
        let k = k2.max((live.max(1) as u64).next_power_of_two().trailing_zeros());
        let cells = 1u64 << k.min(30);
        // Largest remainder with at least one cell per unit with power.
        let total: f64 = units.iter().map(|u| u.power).sum();
        let mut assigned = 0u64;
        let mut rema: Vec<(f64, usize)> = Vec::new();
        for (i, u) in units.iter_mut().enumerate() {
            if u.power > 0.0 {
                let share = u.power / total * cells as f64;
                let c = (share.floor() as u64).max(1);
                u.cells = c as u32;
                assigned += c;
                rema.push((share - share.floor(), i));
            }
        }
        rema.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
        let mut r = 0;
        while assigned < cells && !rema.is_empty() {
            units[rema[r % rema.len()].1].cells += 1;
            assigned += 1;
            r += 1;
        }
        while assigned > cells {
            // Minimum-one cells overshot: take from the largest.
            let i = (0..units.len())
                .max_by_key(|&i| units[i].cells)
                .unwrap_or(0);
            units[i].cells -= 1;
            assigned -= 1;
        }
        let mut owner = Vec::with_capacity(cells as usize);
        for (i, u) in units.iter_mut().enumerate() {
            u.first_cell = owner.len() as u32;
            owner.extend(std::iter::repeat_n(i as u32, u.cells as usize));
        }
        Self {
            units,
            owner,
            maps: Default::default(),
        }
    }

    /// These cells with emission maps `maps` (emitter index, map): photons of those
    /// emitters start by the map ([`crate::emission`]).
    pub fn with_maps(mut self, maps: crate::emission::EmissionMaps) -> Self {
        self.maps = maps;
        self
    }

    /// The emission maps.
    pub fn maps(&self) -> &crate::emission::EmissionMaps {
        &self.maps
    }

    /// The units.
    pub fn units(&self) -> &[LightUnit] {
        &self.units
    }

    /// Number of cells C.
    pub fn cell_count(&self) -> u32 {
        self.owner.len() as u32
    }

    /// True when both assign the same cells to the same units (then a photon's unit
    /// depends only on its index).
    pub fn same_layout(&self, other: &LightCells) -> bool {
        self.owner == other.owner
            && self
                .units
                .iter()
                .zip(&other.units)
                .all(|(a, b)| a.key == b.key && a.cells == b.cells)
    }

    /// The unit, emitter and selection probability for dimension-0 value `u` in
    /// `[0, 1)`, and `u` remapped into `[0, 1)` within the chosen emitter (the first
    /// emission coordinate). None without lights.
    pub fn pick(&self, u: f64) -> Option<(u32, u32, f32, f32)> {
        let c = self.owner.len();
        if c == 0 {
            return None;
        }
        let x = u * c as f64;
        let cell = (x as usize).min(c - 1);
        let unit_index = self.owner[cell];
        let unit = &self.units[unit_index as usize];
        let mut v = (x - unit.first_cell as f64) / unit.cells as f64;
        v = v.clamp(0.0, 1.0);
        let j = unit
            .cdf
            .partition_point(|&f| f <= v)
            .min(unit.cdf.len() - 1);
        let lo = if j == 0 { 0.0 } else { unit.cdf[j - 1] };
        let width = unit.cdf[j] - lo;
        let rest = if width > 0.0 { (v - lo) / width } else { 0.5 };
        let pmf = unit.cells as f64 / c as f64 * width;
        Some((
            unit_index,
            unit.emitters[j],
            pmf as f32,
            (rest as f32).clamp(0.0, ONE_MINUS_EPSILON),
        ))
    }
}

/// A photon leaving `lights` for Halton stream `s` (dimension 0 chooses the unit and
/// emitter by `cells`; only the emission coordinates the emitter uses are drawn). Returns
/// the path and its unit; None without lights or when the emitter emits nothing there.
pub fn emit(
    lights: &LightSet,
    cells: &LightCells,
    s: &mut HaltonStream<'_>,
) -> Option<(PhotonPath, u32)> {
    use illume_core::sampling::SampleStream;
    let (unit, emitter, pmf, first) = cells.pick(s.next_f64())?;
    let (uses_pos, uses_dir) = lights.emission_coordinates(emitter as usize);
    let (u_pos, u_dir) = match (uses_pos, uses_dir) {
        (true, true) => {
            let p = Vec2::new(first, s.next_1d());
            (p, s.next_2d())
        }
        (true, false) => (Vec2::new(first, s.next_1d()), Vec2::splat(0.5)),
        _ => (Vec2::splat(0.5), Vec2::new(first, s.next_1d())),
    };
    // An emission map moves the start and divides the flux by its density (unbiased).
    let map = uses_pos.then(|| cells.maps.of(emitter)).flatten();
    let (u_pos, density) = match map {
        Some(m) => m.warp(u_pos),
        None => (u_pos, 1.0),
    };
    let mut e = lights.emit_from(emitter as usize, pmf, u_pos, u_dir, s)?;
    if density != 1.0 {
        e.flux /= density;
    }
    Some((PhotonPath::emitted(e), unit))
}
