//! Irradiance records (§3, Eq. 1–4): what a record holds, how it is computed from a
//! stratified hemisphere of gather rays, and how records are weighted (Ward's Eq. 2),
//! selected (Eq. 3) and interpolated (Eq. 1 with the gradient-corrected contribution of
//! Eq. 4).
//!
//! **The gather.** A record at p with normal n traces one ray per cell of an M×N grid
//! over the hemisphere (M strata in θ, N in φ; §6 uses 64×64). The θ strata are
//! cosine-weighted — stratum j spans sin²θ ∈ [j/M, (j+1)/M], so every cell has the same
//! projected solid angle π/(MN) — and each ray leaves from a jittered point of its cell.
//! A ray's radiance comes from [`illume_transport::path::continue_path`] at what it hits
//! ([`Incoming`] says which bounces count). From the cells' radiance L_jk and hit
//! distances r_jk:
//!
//! * irradiance E = π/(MN)·Σ L_jk;
//! * R_k, the harmonic mean distance MN/Σ 1/r_jk (escaping rays count 1/r = 0), clamped
//!   (see [`RecordSettings`]);
//! * the rotation gradient ∇_r = ∫ L(ω)(n × ω) dω, with L constant over each cell and
//!   the cell integrals of n × ω taken exactly (Ward & Heckbert 1992 weight each ray by
//!   tan θ instead, whose variance is unbounded near the horizon): it is exactly zero
//!   for uniform radiance and gives E(n') ≈ E + (n × n')·∇_r for a small turn of the
//!   normal, the form Eq. 4 uses;
//! * the translation gradient ∇_p by Ward & Heckbert 1992 ("Irradiance gradients",
//!   EGWR): moving p by δ in the tangent plane moves each wall between two cells by
//!   an angle that depends on the distance to the nearer of the two surfaces seen,
//!   and the projected solid angle that changes hands carries the two cells' radiance
//!   difference. Walls between θ strata contribute along the cell's azimuth u_k with
//!   weight (2π/N)·sinθ cos²θ / min(r), walls between φ columns along the wall's
//!   perpendicular with weight (sin θ₊ − sin θ₋)/min(r).
//!
//! Gradients are per colour channel ([`RgbGradient`]) and lie in the tangent plane.
//!
//! **Randomness.** A gather is a pure function of (seed, record key, cell): cell c draws
//! its jitter and then its path from `Pcg32::new(mix64(seed ^ mix64(key)), c)`, so a
//! record is the same whatever the thread count, and a replacement traced with its
//! predecessor's key sees the same directions and random numbers.

use crate::RadianceCacheError;
use illume_accel::Hit;
use illume_core::sampling::{Pcg32, SampleStream, mix64};
use illume_core::{Frame, PI, Ray, Rgb, Vec3, offset_ray_origin};
use illume_scene::InstanceId;
use illume_transport::World;
use illume_transport::path::{PathRadiance, PathSettings, continue_path};
use std::ops::{Add, AddAssign, Mul, Sub};

/// A gradient per colour channel: `self.0[c]` is the gradient of channel c (a vector in
/// world space; its unit is the quantity's per metre for translation, per radian for
/// rotation).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct RgbGradient(pub [Vec3; 3]);

impl RgbGradient {
    /// Zero in every channel.
    pub const ZERO: Self = Self([Vec3::ZERO; 3]);

    /// The change per channel along `v`: (∇_R·v, ∇_G·v, ∇_B·v).
    #[inline]
    pub fn dot(&self, v: Vec3) -> Rgb {
        Rgb::new(self.0[0].dot(v), self.0[1].dot(v), self.0[2].dot(v))
    }

    /// Adds `direction · values[c]` to channel c.
    #[inline]
    pub fn add_scaled(&mut self, direction: Vec3, values: Rgb) {
        for c in 0..3 {
            self.0[c] += direction * values[c];
        }
    }

    /// The largest length over the channels.
    pub fn max_length(&self) -> f32 {
        self.0.iter().map(|g| g.length()).fold(0.0, f32::max)
    }
}

impl Add for RgbGradient {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self(std::array::from_fn(|c| self.0[c] + o.0[c]))
    }
}

impl AddAssign for RgbGradient {
    fn add_assign(&mut self, o: Self) {
        *self = *self + o;
    }
}

impl Sub for RgbGradient {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self(std::array::from_fn(|c| self.0[c] - o.0[c]))
    }
}

impl Mul<f32> for RgbGradient {
    type Output = Self;
    fn mul(self, s: f32) -> Self {
        Self(self.0.map(|g| g * s))
    }
}

/// What Eq. 4 extrapolates from: the irradiance E \[W/m²\] with its rotation gradient
/// ∇_r \[W/(m²·rad)\] and translation gradient ∇_p \[W/m³\]. The same triple, per frame,
/// is a record's temporal gradient (∇ᵗ_E, ∇ᵗ_∇r, ∇ᵗ_∇p of Eq. 16).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct IrradianceValue {
    /// E (RGB).
    pub irradiance: Rgb,
    /// ∇_r per channel.
    pub rotation_gradient: RgbGradient,
    /// ∇_p per channel.
    pub translation_gradient: RgbGradient,
}

impl IrradianceValue {
    /// Zero.
    pub const ZERO: Self = Self {
        irradiance: Rgb::ZERO,
        rotation_gradient: RgbGradient::ZERO,
        translation_gradient: RgbGradient::ZERO,
    };

    /// Eq. 4: E + (n_k × n)·∇_r + (p − p_k)·∇_p, given `normal_turn` = n_k × n and
    /// `offset` = p − p_k. Not clamped (the sum over records is, in
    /// [`WeightedSum::result`]).
    #[inline]
    pub fn extrapolate(&self, offset: Vec3, normal_turn: Vec3) -> Rgb {
        self.irradiance
            + self.rotation_gradient.dot(normal_turn)
            + self.translation_gradient.dot(offset)
    }
}

impl Add for IrradianceValue {
    type Output = Self;
    fn add(self, o: Self) -> Self {
        Self {
            irradiance: self.irradiance + o.irradiance,
            rotation_gradient: self.rotation_gradient + o.rotation_gradient,
            translation_gradient: self.translation_gradient + o.translation_gradient,
        }
    }
}

impl Sub for IrradianceValue {
    type Output = Self;
    fn sub(self, o: Self) -> Self {
        Self {
            irradiance: self.irradiance - o.irradiance,
            rotation_gradient: self.rotation_gradient - o.rotation_gradient,
            translation_gradient: self.translation_gradient - o.translation_gradient,
        }
    }
}

impl Mul<f32> for IrradianceValue {
    type Output = Self;
    fn mul(self, s: f32) -> Self {
        Self {
            irradiance: self.irradiance * s,
            rotation_gradient: self.rotation_gradient * s,
            translation_gradient: self.translation_gradient * s,
        }
    }
}

/// Which light a gather ray counts.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Incoming {
    /// Light reflected at least once at the surface the ray hits (`continue_path`'s
    /// `direct + indirect`): what the technique caches, since the renderer adds direct
    /// light (emitters and the sky seen from the shaded point) itself. E·ρ/π is then
    /// the indirect light of a Lambertian point.
    #[default]
    Reflected,
    /// Everything arriving: also emission and sky seen directly along the ray (for
    /// analytic checks against closed-form irradiance).
    All,
}

/// How records are computed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RecordSettings {
    /// M, strata in θ (cosine-weighted). At least 1; the translation gradient needs 2.
    pub theta_strata: u32,
    /// N, strata in φ. At least 1; the gradients need 3.
    pub phi_strata: u32,
    /// Smallest R_k \[m\]. Also the smallest distance the translation gradient divides
    /// by: a surface nearer than this is finer detail than the cache resolves, and
    /// dividing by its distance would let one ray dominate the gradient.
    pub r_min_m: f32,
    /// Largest R_k \[m\] (rays that escape make R_k infinite). When smaller than
    /// `r_min_m`, it wins.
    pub r_max_m: f32,
    /// Also clamp R_k to E/|∇_p E| (the smallest over channels with E > 0), before the
    /// `r_min_m` clamp (see the settings' `gradient_limit`).
    pub gradient_limit: bool,
    /// Jitter each ray within its cell (true) or aim it at the cell's centre (false, a
    /// deterministic grid for tests and reprojection).
    pub jitter: bool,
    /// Which light the gather counts.
    pub incoming: Incoming,
    /// Path length of the gather rays' paths.
    pub path: PathSettings,
    /// Seed of the jitter and the paths.
    pub seed: u64,
}

impl Default for RecordSettings {
    /// A 64×64 jittered grid of reflected light, R_k in [1 mm, 1 km], gradient limit on.
    fn default() -> Self {
        Self {
            theta_strata: 64,
            phi_strata: 64,
            r_min_m: 1e-3,
            r_max_m: 1e3,
            gradient_limit: true,
            jitter: true,
            incoming: Incoming::Reflected,
            path: PathSettings::default(),
            seed: 0,
        }
    }
}

/// One cell of a gather: the direction its ray took, the radiance it brought back and
/// the distance to what it hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GatherCell {
    /// Unit direction of the ray (world space).
    pub direction: Vec3,
    /// Radiance arriving along it \[W/(m²·sr)\].
    pub radiance: Rgb,
    /// Distance to the surface hit \[m\]; infinite when the ray left the scene.
    pub distance_m: f32,
}

/// What one gather ray found, for moving it to the next frame (§4.3): its first hit,
/// the random stream its path started from, and the light reflected there once
/// (`direct`, recomputed at the next frame) and more than once (`multiple`, carried
/// over).
#[derive(Clone, Debug)]
pub struct CellPath {
    /// The first hit (instance, triangle, barycentrics, distance); `None` when the ray
    /// left the scene.
    pub hit: Option<Hit>,
    /// The cell's random stream as the path at the hit started drawing from it.
    pub stream: Pcg32,
    /// Light reflected once at the hit towards the record \[W/(m²·sr)\].
    pub direct: Rgb,
    /// Light reflected two or more times \[W/(m²·sr)\].
    pub multiple: Rgb,
}

impl CellPath {
    fn escaped() -> Self {
        Self {
            hit: None,
            stream: Pcg32::new(0, 0),
            direct: Rgb::ZERO,
            multiple: Rgb::ZERO,
        }
    }
}

/// The gather rays of one record: an M×N grid of [`GatherCell`]s over the hemisphere
/// of a normal, θ-stratum major (cell (j, k) at `j·N + k`).
#[derive(Clone, Debug, PartialEq)]
pub struct HemisphereGather {
    frame: Frame,
    theta_strata: u32,
    phi_strata: u32,
    cells: Vec<GatherCell>,
}

/// The random stream of cell `cell` of the record with key `key`.
#[inline]
pub fn cell_stream(seed: u64, key: u64, cell: u32) -> Pcg32 {
    Pcg32::new(mix64(seed ^ mix64(key)), cell as u64)
}

/// The local frame of a record's hemisphere, or why there is none.
fn record_frame(position: Vec3, normal: Vec3) -> Result<Frame, RadianceCacheError> {
    let bad = |reason| RadianceCacheError::BadRecordPoint {
        position,
        normal,
        reason,
    };
    if !position.is_finite() {
        return Err(bad("the position is not finite"));
    }
    let n = normal.normalize_or_zero();
    if !n.is_finite() || n == Vec3::ZERO {
        return Err(bad("the normal has no direction"));
    }
    Ok(Frame::from_normal(n))
}

impl HemisphereGather {
    /// Traces the gather of a record at `position` with `normal` in `world`: each
    /// cell's ray leaves from just off `position` (the point need not lie on a surface)
    /// and its radiance is [`continue_path`]'s at the first hit (see [`Incoming`]).
    /// `key` names the record's random streams. Errors when the point or the normal is
    /// not usable.
    pub fn trace(
        world: &World,
        position: Vec3,
        normal: Vec3,
        key: u64,
        settings: &RecordSettings,
    ) -> Result<Self, RadianceCacheError> {
        Self::trace_cells(world, position, normal, key, settings, None)
    }

    /// [`HemisphereGather::trace`], also returning what each cell's ray found (its first
    /// hit, the random stream its path started from, its light split by bounces): what
    /// the §4.3 reprojection moves to the next frame ([`crate::reproject`]). The gather
    /// is the same as [`HemisphereGather::trace`]'s, bit for bit.
    pub fn trace_keeping_paths(
        world: &World,
        position: Vec3,
        normal: Vec3,
        key: u64,
        settings: &RecordSettings,
    ) -> Result<(Self, Vec<CellPath>), RadianceCacheError> {
        let mut paths = Vec::with_capacity((settings.theta_strata * settings.phi_strata) as usize);
        let gather = Self::trace_cells(world, position, normal, key, settings, Some(&mut paths))?;
        Ok((gather, paths))
    }

    fn trace_cells(
        world: &World,
        position: Vec3,
        normal: Vec3,
        key: u64,
        settings: &RecordSettings,
        mut keep: Option<&mut Vec<CellPath>>,
    ) -> Result<Self, RadianceCacheError> {
        let frame = record_frame(position, normal)?;
        Ok(Self::gather(frame, settings, key, |direction, stream| {
            let ray = Ray::new(offset_ray_origin(position, frame.n, direction), direction);
            match world.trace(&ray, illume_scene::MASK_DEFAULT) {
                None => {
                    let sky = match settings.incoming {
                        Incoming::Reflected => Rgb::ZERO,
                        Incoming::All => world.lights.sky_radiance(direction),
                    };
                    if let Some(keep) = keep.as_deref_mut() {
                        keep.push(CellPath::escaped());
                    }
                    (sky, f32::INFINITY)
                }
                Some(hit) => {
                    let (emission, t) = (hit.emission, hit.t);
                    let first = Hit {
                        t,
                        instance: hit.instance,
                        triangle: hit.triangle,
                        barycentrics: hit.barycentrics,
                    };
                    let start = keep.is_some().then(|| stream.clone());
                    let mut out = PathRadiance::default();
                    continue_path(world, hit, -direction, stream, &settings.path, &mut out);
                    if let (Some(keep), Some(stream)) = (keep.as_deref_mut(), start) {
                        keep.push(CellPath {
                            hit: Some(first),
                            stream,
                            direct: out.direct,
                            multiple: out.indirect,
                        });
                    }
                    let reflected = out.direct + out.indirect;
                    let radiance = match settings.incoming {
                        Incoming::Reflected => reflected,
                        Incoming::All => reflected + emission,
                    };
                    (radiance, t)
                }
            }
        }))
    }

    /// A gather over `frame` with `cells` given (θ-stratum major, `theta_strata ×
    /// phi_strata` of them), for grids assembled elsewhere (the reprojection's).
    pub(crate) fn from_cells(
        frame: Frame,
        theta_strata: u32,
        phi_strata: u32,
        cells: Vec<GatherCell>,
    ) -> Self {
        debug_assert_eq!(cells.len(), (theta_strata * phi_strata) as usize);
        Self {
            frame,
            theta_strata,
            phi_strata,
            cells,
        }
    }

    /// A gather whose radiance and distances come from `sample(direction)` (world
    /// direction → (radiance, distance \[m\], infinite for none)) instead of rays: the
    /// same grid and jitter as [`HemisphereGather::trace`], for synthetic radiance
    /// fields and for reusing rays traced elsewhere.
    pub fn from_fn(
        normal: Vec3,
        settings: &RecordSettings,
        key: u64,
        mut sample: impl FnMut(Vec3) -> (Rgb, f32),
    ) -> Result<Self, RadianceCacheError> {
        let frame = record_frame(Vec3::ZERO, normal)?;
        Ok(Self::gather(frame, settings, key, |d, _| sample(d)))
    }

    fn gather(
        frame: Frame,
        settings: &RecordSettings,
        key: u64,
        mut radiance: impl FnMut(Vec3, &mut Pcg32) -> (Rgb, f32),
    ) -> Self {
        let (m, n) = (settings.theta_strata.max(1), settings.phi_strata.max(1));
        let mut cells = Vec::with_capacity((m * n) as usize);
        for j in 0..m {
            for k in 0..n {
                let cell = j * n + k;
                let mut stream = cell_stream(settings.seed, key, cell);
                let (u, v) = if settings.jitter {
                    (stream.next_1d(), stream.next_1d())
                } else {
                    (0.5, 0.5)
                };
                let sin2 = ((j as f32 + u) / m as f32).min(1.0);
                let (sin_theta, cos_theta) = (sin2.sqrt(), (1.0 - sin2).max(0.0).sqrt());
                let phi = 2.0 * PI * (k as f32 + v) / n as f32;
                let local = Vec3::new(sin_theta * phi.cos(), sin_theta * phi.sin(), cos_theta);
                let direction = frame.to_world(local).normalize();
                let (radiance, distance_m) = radiance(direction, &mut stream);
                cells.push(GatherCell {
                    direction,
                    radiance,
                    distance_m,
                });
            }
        }
        Self {
            frame,
            theta_strata: m,
            phi_strata: n,
            cells,
        }
    }

    /// The record's normal.
    pub fn normal(&self) -> Vec3 {
        self.frame.n
    }

    /// The local frame the grid is laid out in (normal = +Z, φ measured from `s`).
    pub fn frame(&self) -> &Frame {
        &self.frame
    }

    /// (M, N): strata in θ and in φ.
    pub fn strata(&self) -> (u32, u32) {
        (self.theta_strata, self.phi_strata)
    }

    /// The cells, θ-stratum major.
    pub fn cells(&self) -> &[GatherCell] {
        &self.cells
    }

    #[inline]
    fn cell(&self, j: u32, k: u32) -> &GatherCell {
        &self.cells[(j * self.phi_strata + k) as usize]
    }

    /// E = π/(MN)·Σ L_jk \[W/m²\].
    pub fn irradiance(&self) -> Rgb {
        // Summed in f64: 4096 f32 terms would lose up to a few 10⁻⁴ of the total.
        let mut sum = [0.0f64; 3];
        for cell in &self.cells {
            for (s, v) in sum.iter_mut().zip(cell.radiance.to_array()) {
                *s += v as f64;
            }
        }
        let scale = std::f64::consts::PI / self.cells.len() as f64;
        Rgb::new(
            (sum[0] * scale) as f32,
            (sum[1] * scale) as f32,
            (sum[2] * scale) as f32,
        )
    }

    /// MN/Σ 1/r_jk \[m\]: infinite when every ray escaped, zero when one hit at
    /// distance zero.
    pub fn harmonic_mean_distance(&self) -> f32 {
        let inverse: f64 = self.cells.iter().map(|c| 1.0 / c.distance_m as f64).sum();
        (self.cells.len() as f64 / inverse) as f32
    }

    /// ∇_r = ∫ L(ω)(n × ω) dω with L constant over each cell: Σ L_jk·∫_cell n × ω dω,
    /// the cell integral being (∫ sin²θ dθ over the stratum)·2 sin(Δφ/2)·v(φ_k), v the
    /// tangent direction a quarter turn from the cell's centre azimuth φ_k.
    pub fn rotation_gradient(&self) -> RgbGradient {
        let (m, n) = (self.theta_strata, self.phi_strata);
        let d_phi = 2.0 * PI / n as f32;
        let chord = 2.0 * (0.5 * d_phi).sin();
        // ∫ sin²θ dθ = θ/2 − sin 2θ/4, between the stratum's bounds.
        let antiderivative = |sin2: f32| {
            let theta = sin2.clamp(0.0, 1.0).sqrt().asin();
            0.5 * theta - 0.25 * (2.0 * theta).sin()
        };
        let stratum: Vec<f32> = (0..m)
            .map(|j| {
                antiderivative((j + 1) as f32 / m as f32) - antiderivative(j as f32 / m as f32)
            })
            .collect();
        let mut g = RgbGradient::ZERO;
        for k in 0..n {
            let phi = d_phi * (k as f32 + 0.5);
            let v = self.frame.to_world(Vec3::new(-phi.sin(), phi.cos(), 0.0));
            let column: Rgb = (0..m)
                .map(|j| self.cell(j, k).radiance * stratum[j as usize])
                .sum();
            g.add_scaled(v, column * chord);
        }
        g
    }

    /// ∇_p by Ward & Heckbert 1992 (see the module doc), distances clamped below at
    /// `min_distance_m`.
    pub fn translation_gradient(&self, min_distance_m: f32) -> RgbGradient {
        let (m, n) = (self.theta_strata, self.phi_strata);
        let d_phi = 2.0 * PI / n as f32;
        let floor = min_distance_m.max(f32::MIN_POSITIVE);
        let nearer = |a: &GatherCell, b: &GatherCell| a.distance_m.min(b.distance_m).max(floor);
        let sin_bound = |j: u32| (j as f32 / m as f32).sqrt();
        let mut g = RgbGradient::ZERO;
        for k in 0..n {
            // Walls between θ strata j − 1 and j of column k, along the column's azimuth.
            let phi = d_phi * (k as f32 + 0.5);
            let u = self.frame.to_world(Vec3::new(phi.cos(), phi.sin(), 0.0));
            let mut theta_walls = Rgb::ZERO;
            for j in 1..m {
                let (below, above) = (self.cell(j - 1, k), self.cell(j, k));
                let sin2 = j as f32 / m as f32;
                let weight = sin2.sqrt() * (1.0 - sin2) / nearer(below, above);
                theta_walls += (above.radiance - below.radiance) * weight;
            }
            g.add_scaled(u, theta_walls * d_phi);
            // Walls between columns k − 1 and k, along the wall's perpendicular.
            let k_prev = (k + n - 1) % n;
            let wall = d_phi * k as f32;
            let v = self.frame.to_world(Vec3::new(-wall.sin(), wall.cos(), 0.0));
            let mut phi_walls = Rgb::ZERO;
            for j in 0..m {
                let (prev, this) = (self.cell(j, k_prev), self.cell(j, k));
                let weight = (sin_bound(j + 1) - sin_bound(j)) / nearer(prev, this);
                phi_walls += (this.radiance - prev.radiance) * weight;
            }
            g.add_scaled(v, phi_walls);
        }
        g
    }
}

/// An irradiance record (§3): a point's irradiance with its gradients, valid around
/// its position (Ward's weight) and over its lifespan (§4.2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IrradianceRecord {
    /// p_k, world space \[m\]. Fixed for the record's life, even on a moving object
    /// (§4.2, Fig. 6).
    pub position: Vec3,
    /// n_k, unit.
    pub normal: Vec3,
    /// E_k with ∇_r and ∇_p at the record's frame.
    pub value: IrradianceValue,
    /// R_k \[m\], the harmonic mean distance after the clamps.
    pub harmonic_distance_m: f32,
    /// Temporal gradient per frame (∇ᵗ_E, ∇ᵗ_∇r, ∇ᵗ_∇p, Eq. 16); zero without one
    /// (the `reuse` mode).
    pub temporal_gradient: IrradianceValue,
    /// t_k, the frame the record was computed at.
    pub frame: u32,
    /// Frames it is valid for, counting its own (Eq. 10, Eq. 12): frames
    /// t_k..t_k + lifespan.
    pub lifespan_frames: u32,
    /// The instance the record's point lies on, if any.
    pub instance: Option<InstanceId>,
}

impl IrradianceRecord {
    /// The record a gather gives: E, ∇_r and ∇_p from the cells, R_k clamped as
    /// `settings` say, at frame `frame` with a lifespan of one frame and no temporal
    /// gradient (the temporal module sets both). `position` is the gather's origin.
    pub fn from_gather(
        position: Vec3,
        gather: &HemisphereGather,
        frame: u32,
        instance: Option<InstanceId>,
        settings: &RecordSettings,
    ) -> Self {
        let irradiance = gather.irradiance();
        let translation_gradient = gather.translation_gradient(settings.r_min_m);
        let mut r = gather.harmonic_mean_distance();
        if settings.gradient_limit {
            for c in 0..3 {
                let slope = translation_gradient.0[c].length();
                if irradiance[c] > 0.0 && slope > 0.0 {
                    r = r.min(irradiance[c] / slope);
                }
            }
        }
        // max then min (not clamp): misordered bounds must not panic; r_max wins.
        let harmonic_distance_m = r.max(settings.r_min_m).min(settings.r_max_m);
        Self {
            position,
            normal: gather.normal(),
            value: IrradianceValue {
                irradiance,
                rotation_gradient: gather.rotation_gradient(),
                translation_gradient,
            },
            harmonic_distance_m,
            temporal_gradient: IrradianceValue::ZERO,
            frame,
            lifespan_frames: 1,
            instance,
        }
    }

    /// Traces the gather at `position` with `normal` in `world` and makes the record
    /// ([`HemisphereGather::trace`], [`IrradianceRecord::from_gather`]).
    pub fn compute(
        world: &World,
        position: Vec3,
        normal: Vec3,
        frame: u32,
        instance: Option<InstanceId>,
        key: u64,
        settings: &RecordSettings,
    ) -> Result<Self, RadianceCacheError> {
        let gather = HemisphereGather::trace(world, position, normal, key, settings)?;
        Ok(Self::from_gather(
            position, &gather, frame, instance, settings,
        ))
    }

    /// Radius of the sphere of influence, a·R_k \[m\]: no point farther away can have
    /// w_k ≥ 1/a.
    #[inline]
    pub fn influence_radius_m(&self, accuracy: f32) -> f32 {
        accuracy * self.harmonic_distance_m
    }

    /// 1/w_k(p) of Eq. 2: ‖p − p_k‖/R_k + √(1 − n·n_k) (the root's argument clamped at
    /// zero against rounding).
    #[inline]
    pub fn ward_error(&self, p: Vec3, n: Vec3) -> f32 {
        ward_error(p, n, self.position, self.normal, self.harmonic_distance_m)
    }

    /// Eq. 4 at `p` with normal `n`: E_k + (n_k × n)·∇_r + (p − p_k)·∇_p.
    #[inline]
    pub fn contribution(&self, p: Vec3, n: Vec3) -> Rgb {
        self.value
            .extrapolate(p - self.position, self.normal.cross(n))
    }
}

/// 1/w of Eq. 2 for a record at `record_position` with `record_normal` and harmonic mean
/// distance `r_k`, seen from `p` with normal `n`.
#[inline]
pub fn ward_error(p: Vec3, n: Vec3, record_position: Vec3, record_normal: Vec3, r_k: f32) -> f32 {
    (p - record_position).length() / r_k + (1.0 - n.dot(record_normal)).max(0.0).sqrt()
}

/// Eq. 2: w_k(p) = 1/(‖p − p_k‖/R_k + √(1 − n·n_k)); infinite at the record itself.
#[inline]
pub fn ward_weight(p: Vec3, n: Vec3, record_position: Vec3, record_normal: Vec3, r_k: f32) -> f32 {
    1.0 / ward_error(p, n, record_position, record_normal, r_k)
}

/// A usable record's weight in Eq. 1 at a point where Ward's error is `ward_error`
/// (≤ `accuracy`): Ward's w_k = 1/ε (Eq. 2), or with `smooth`, 1/ε − 1/a, which falls to
/// zero at the edge of the record's sphere of use instead of jumping there from 1/a to
/// nothing (where neighbouring records' values differ, Ward's jump draws the sphere's
/// circle on the image). Both are infinite at ε = 0 (the record's own value) and keep
/// the records' order; a point at the very edge keeps a weight of 1e-6/a, so a record
/// that serves it alone still does.
#[inline]
pub fn interpolation_weight(ward_error: f32, accuracy: f32, smooth: bool) -> f32 {
    let ward = 1.0 / ward_error;
    if smooth {
        (ward - 1.0 / accuracy).max(1e-6 / accuracy)
    } else {
        ward
    }
}

/// Eq. 3 as it should read (the paper prints w_k ≥ a; compare Eq. 10): a record is in
/// the usable set S_r(p) when w_k(p) ≥ 1/a, tested as 1/w_k ≤ a so that the infinite
/// weight at the record itself needs no special case. False for NaN.
#[inline]
pub fn usable(ward_error: f32, accuracy: f32) -> bool {
    ward_error <= accuracy
}

/// The weighted average of Eq. 1, accumulated one record at a time. Records with an
/// infinite weight (the point is the record's) win outright: the result is their mean.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WeightedSum {
    sum: Rgb,
    weights: f32,
    exact_sum: Rgb,
    exact_count: u32,
}

impl WeightedSum {
    /// Adds a record's `contribution` with weight `w_k` (Eq. 2).
    #[inline]
    pub fn add(&mut self, weight: f32, contribution: Rgb) {
        if weight.is_infinite() {
            self.exact_sum += contribution;
            self.exact_count += 1;
        } else if weight > 0.0 {
            self.sum += contribution * weight;
            self.weights += weight;
        }
    }

    /// True when no record was added with a positive weight.
    pub fn is_empty(&self) -> bool {
        self.exact_count == 0 && self.weights <= 0.0
    }

    /// Eq. 1, clamped at zero per channel (the gradients of Eq. 4 may extrapolate below
    /// zero); `None` when no record was added (the caller makes a new one).
    pub fn result(&self) -> Option<Rgb> {
        let e = if self.exact_count > 0 {
            self.exact_sum / self.exact_count as f32
        } else if self.weights > 0.0 {
            self.sum / self.weights
        } else {
            return None;
        };
        Some(e.max(Rgb::ZERO))
    }
}

/// Eq. 1 over the usable records among `records` (Eq. 3 with accuracy `accuracy`),
/// each weighted by Eq. 2 and contributing `contribution(record)` (records for which it
/// gives `None` are left out), at `p` with unit normal `n`: the irradiance \[W/m²\], or
/// `None` when no record is usable.
pub fn interpolate_by<'a>(
    records: impl IntoIterator<Item = &'a IrradianceRecord>,
    p: Vec3,
    n: Vec3,
    accuracy: f32,
    mut contribution: impl FnMut(&IrradianceRecord) -> Option<Rgb>,
) -> Option<Rgb> {
    let mut sum = WeightedSum::default();
    for r in records {
        let error = r.ward_error(p, n);
        if usable(error, accuracy)
            && let Some(c) = contribution(r)
        {
            sum.add(1.0 / error, c);
        }
    }
    sum.result()
}

/// Eq. 1 with the contributions of Eq. 4 ([`interpolate_by`]). Records' lifespans are
/// not looked at (see [`crate::temporal::interpolate_at`] for frames).
pub fn interpolate<'a>(
    records: impl IntoIterator<Item = &'a IrradianceRecord>,
    p: Vec3,
    n: Vec3,
    accuracy: f32,
) -> Option<Rgb> {
    interpolate_by(records, p, n, accuracy, |r| Some(r.contribution(p, n)))
}
