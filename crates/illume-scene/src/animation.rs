//! Keyframe animation with glTF 2.0 semantics: channels drive a node's translation,
//! rotation or scale with `STEP`, `LINEAR` (slerp for rotations) or `CUBICSPLINE`
//! (Hermite with in/out tangents) interpolation. Before the first key the first value
//! holds; after the last key the last value holds.

use crate::model::{LightId, MaterialId, NodeId};
use illume_core::{Affine3A, Quat, Vec3, Vec4};

/// A transform as translation, rotation and (possibly non-uniform) scale; the matrix is
/// `T · R · S` as in glTF.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    /// Translation \[m\].
    pub translation: Vec3,
    /// Unit rotation quaternion.
    pub rotation: Quat,
    /// Scale per axis.
    pub scale: Vec3,
}

impl Default for Trs {
    fn default() -> Self {
        Self::IDENTITY
    }
}

impl Trs {
    /// No translation, rotation or scale.
    pub const IDENTITY: Trs = Trs {
        translation: Vec3::ZERO,
        rotation: Quat::IDENTITY,
        scale: Vec3::ONE,
    };

    /// A pure translation.
    pub fn from_translation(t: Vec3) -> Self {
        Self {
            translation: t,
            ..Self::IDENTITY
        }
    }

    /// The affine matrix `T · R · S`.
    pub fn to_affine(&self) -> Affine3A {
        Affine3A::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }

    /// Decomposes an affine matrix (exact for matrices without shear).
    pub fn from_affine(m: &Affine3A) -> Self {
        let (scale, rotation, translation) = m.to_scale_rotation_translation();
        Self {
            translation,
            rotation,
            scale,
        }
    }

    /// True when every component is finite.
    pub fn is_finite(&self) -> bool {
        self.translation.is_finite() && self.rotation.is_finite() && self.scale.is_finite()
    }
}

/// glTF interpolation modes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolation {
    /// Hold the previous key's value.
    Step,
    /// Linear (rotations: spherical linear).
    Linear,
    /// Cubic Hermite spline with per-key in/out tangents.
    CubicSpline,
}

/// Keyed values of one channel. For `CubicSpline`, each key has three entries
/// (in-tangent, value, out-tangent) in that order, as in glTF.
#[derive(Clone, Debug, PartialEq)]
pub enum ChannelValues {
    /// Translations \[m\].
    Translation(Vec<Vec3>),
    /// Rotations as quaternions `(x, y, z, w)`.
    Rotation(Vec<Vec4>),
    /// Scales.
    Scale(Vec<Vec3>),
}

/// One animated property of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The node it drives.
    pub node: NodeId,
    /// Key times \[s\], strictly increasing.
    pub times: Vec<f32>,
    /// Key values (see [`ChannelValues`]).
    pub values: ChannelValues,
    /// How values between keys are found.
    pub interpolation: Interpolation,
}

/// A light or material value an animation drives (glTF `KHR_animation_pointer`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PropertyTarget {
    /// A light's scalar intensity; its radiometric quantity is `colour × value`.
    LightIntensity {
        /// Which light.
        light: LightId,
        /// The light's colour from the file.
        colour: illume_core::Rgb,
    },
    /// A light's colour (RGB); its radiometric quantity is `value × intensity`.
    LightColour {
        /// Which light.
        light: LightId,
        /// The light's scalar intensity from the file.
        intensity: f32,
    },
    /// A spot light's inner cone half-angle \[rad\].
    SpotInnerCone {
        /// Which light.
        light: LightId,
    },
    /// A spot light's outer cone half-angle \[rad\].
    SpotOuterCone {
        /// Which light.
        light: LightId,
    },
    /// A material's base colour (RGBA; alpha ignored).
    BaseColour {
        /// Which material.
        material: MaterialId,
    },
    /// A material's emissive factor (RGB), times its emissive strength.
    Emissive {
        /// Which material.
        material: MaterialId,
        /// `KHR_materials_emissive_strength` from the file.
        strength: f32,
    },
    /// A material's metallic factor.
    Metallic {
        /// Which material.
        material: MaterialId,
    },
    /// A material's roughness factor.
    Roughness {
        /// Which material.
        material: MaterialId,
    },
}

impl PropertyTarget {
    /// Components per key (1 scalar, 3 RGB, 4 RGBA).
    pub fn components(&self) -> usize {
        match self {
            PropertyTarget::LightColour { .. } | PropertyTarget::Emissive { .. } => 3,
            PropertyTarget::BaseColour { .. } => 4,
            _ => 1,
        }
    }

    /// The quantity it animates, as messages name it.
    pub fn quantity(&self) -> &'static str {
        match self {
            PropertyTarget::LightIntensity { .. } => "light intensity",
            PropertyTarget::LightColour { .. } => "light colour",
            PropertyTarget::SpotInnerCone { .. } => "spot inner cone angle",
            PropertyTarget::SpotOuterCone { .. } => "spot outer cone angle",
            PropertyTarget::BaseColour { .. } => "baseColorFactor",
            PropertyTarget::Emissive { .. } => "emissiveFactor",
            PropertyTarget::Metallic { .. } => "metallicFactor",
            PropertyTarget::Roughness { .. } => "roughnessFactor",
        }
    }
}

/// One animated light or material value.
#[derive(Clone, Debug, PartialEq)]
pub struct PropertyChannel {
    /// What it drives.
    pub target: PropertyTarget,
    /// Key times \[s\], strictly increasing.
    pub times: Vec<f32>,
    /// Key values, [`PropertyTarget::components`] per key (three keys' worth per key
    /// for `CubicSpline`: in-tangent, value, out-tangent).
    pub values: Vec<f32>,
    /// How values between keys are found.
    pub interpolation: Interpolation,
}

impl PropertyChannel {
    /// The value at time `t` (components as [`PropertyTarget::components`], zero-padded).
    pub fn sample(&self, t: f32) -> Vec4 {
        let c = self.target.components();
        let key = |k: usize| {
            let mut v = [0.0f32; 4];
            v[..c].copy_from_slice(&self.values[k * c..(k + 1) * c]);
            Vec4::from_array(v)
        };
        let n = self.times.len();
        let keys: Vec<Vec4> = (0..self.values.len() / c).map(key).collect();
        debug_assert!(keys.len() >= n);
        let (i, u, dt) = locate(&self.times, t);
        let last = i + 1 >= n;
        match self.interpolation {
            Interpolation::CubicSpline => {
                if last || u == 0.0 {
                    keys[3 * i + 1]
                } else {
                    hermite(
                        keys[3 * i + 1],
                        keys[3 * i + 2],
                        keys[3 * (i + 1) + 1],
                        keys[3 * (i + 1)],
                        u,
                        dt,
                    )
                }
            }
            Interpolation::Step => keys[i],
            Interpolation::Linear => {
                if last {
                    keys[i]
                } else {
                    keys[i].lerp(keys[i + 1], u)
                }
            }
        }
    }

    /// Checks keys and values; the message says what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.times.len();
        let per_key = check_keys(&self.times, self.interpolation)?;
        let want = n * per_key * self.target.components();
        if self.values.len() != want {
            return Err(format!(
                "{} output values for {n} keys (want {want})",
                self.values.len()
            ));
        }
        if self.values.iter().any(|v| !v.is_finite()) {
            return Err("output values are not finite".into());
        }
        // The range the same value has when it is static (issue 38: animated values
        // outside it were clamped where a static one is a load error). CUBICSPLINE keys
        // are (in-tangent, value, out-tangent): only values are quantities.
        use PropertyTarget as P;
        let (low, high, range) = match self.target {
            P::LightIntensity { .. } | P::LightColour { .. } | P::Emissive { .. } => {
                (0.0, f32::INFINITY, "≥ 0")
            }
            P::BaseColour { .. } | P::Metallic { .. } | P::Roughness { .. } => {
                (0.0, 1.0, "in [0, 1]")
            }
            P::SpotInnerCone { .. } | P::SpotOuterCone { .. } => {
                (0.0, std::f32::consts::FRAC_PI_2, "in [0, π/2]")
            }
        };
        let c = self.target.components();
        for (k, key) in self.values.chunks_exact(c).enumerate() {
            let is_value = match self.interpolation {
                Interpolation::CubicSpline => k % 3 == 1,
                _ => true,
            };
            if let Some(v) = key.iter().find(|v| !(low..=high).contains(*v))
                && is_value
            {
                let key_index = match self.interpolation {
                    Interpolation::CubicSpline => k / 3,
                    _ => k,
                };
                return Err(format!(
                    "key {key_index}: {} {v} is not {range} (as the static value must be)",
                    self.target.quantity()
                ));
            }
        }
        Ok(())
    }
}

/// A named set of channels played together.
#[derive(Clone, Debug, PartialEq)]
pub struct Animation {
    /// Name from the file.
    pub name: String,
    /// Channels driving node transforms.
    pub channels: Vec<Channel>,
    /// Channels driving light and material values.
    pub properties: Vec<PropertyChannel>,
}

impl Animation {
    /// Time of the last key over all channels \[s\].
    pub fn duration(&self) -> f64 {
        self.channels
            .iter()
            .filter_map(|c| c.times.last())
            .chain(self.properties.iter().filter_map(|c| c.times.last()))
            .fold(0.0f32, |a, &b| a.max(b)) as f64
    }

    /// Applies every channel at time `t` to the nodes' local transforms in `locals`.
    pub fn apply(&self, t: f64, locals: &mut [Trs]) {
        for c in &self.channels {
            let trs = &mut locals[c.node.index()];
            c.apply(t as f32, trs);
        }
    }
}

/// Checks that `times` are keys (at least one, finite, strictly increasing) and returns
/// the values per key of `interpolation` (3 for `CubicSpline`: in-tangent, value,
/// out-tangent; else 1).
fn check_keys(times: &[f32], interpolation: Interpolation) -> Result<usize, String> {
    if times.is_empty() {
        return Err("channel has no keys".into());
    }
    if times
        .windows(2)
        .any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
        || times.iter().any(|t| !t.is_finite())
    {
        return Err("key times are not finite and strictly increasing".into());
    }
    Ok(if interpolation == Interpolation::CubicSpline {
        3
    } else {
        1
    })
}

/// Where `t` falls among the keys: `(i, u, dt)` with `t` between key `i` and `i + 1`,
/// `u ∈ [0, 1]` the fraction and `dt` the interval length; `i` is the last key (u = 0)
/// beyond the end.
fn locate(times: &[f32], t: f32) -> (usize, f32, f32) {
    let n = times.len();
    // NaN compares false everywhere: treat it as before the first key (no panic).
    if n == 1 || t <= times[0] || t.is_nan() {
        return (0, 0.0, 0.0);
    }
    if t >= times[n - 1] {
        return (n - 1, 0.0, 0.0);
    }
    let i = times.partition_point(|&k| k <= t) - 1;
    let dt = times[i + 1] - times[i];
    let u = if dt > 0.0 { (t - times[i]) / dt } else { 0.0 };
    (i, u, dt)
}

fn hermite<T>(p0: T, m0: T, p1: T, m1: T, u: f32, dt: f32) -> T
where
    T: std::ops::Mul<f32, Output = T> + std::ops::Add<Output = T>,
{
    let u2 = u * u;
    let u3 = u2 * u;
    p0 * (2.0 * u3 - 3.0 * u2 + 1.0)
        + m0 * (dt * (u3 - 2.0 * u2 + u))
        + p1 * (-2.0 * u3 + 3.0 * u2)
        + m1 * (dt * (u3 - u2))
}

fn sample_vec3(times: &[f32], v: &[Vec3], interp: Interpolation, t: f32) -> Vec3 {
    let (i, u, dt) = locate(times, t);
    let last = i + 1 >= times.len();
    match interp {
        Interpolation::CubicSpline => {
            if last || u == 0.0 {
                return v[3 * i + 1];
            }
            hermite(
                v[3 * i + 1],
                v[3 * i + 2],
                v[3 * (i + 1) + 1],
                v[3 * (i + 1)],
                u,
                dt,
            )
        }
        Interpolation::Step => v[i],
        Interpolation::Linear => {
            if last {
                v[i]
            } else {
                v[i].lerp(v[i + 1], u)
            }
        }
    }
}

fn sample_quat(times: &[f32], v: &[Vec4], interp: Interpolation, t: f32) -> Quat {
    let (i, u, dt) = locate(times, t);
    let last = i + 1 >= times.len();
    let q = |x: Vec4| Quat::from_vec4(x);
    let r = match interp {
        Interpolation::CubicSpline => {
            if last || u == 0.0 {
                q(v[3 * i + 1])
            } else {
                q(hermite(
                    v[3 * i + 1],
                    v[3 * i + 2],
                    v[3 * (i + 1) + 1],
                    v[3 * (i + 1)],
                    u,
                    dt,
                ))
            }
        }
        Interpolation::Step => q(v[i]),
        Interpolation::Linear => {
            if last {
                q(v[i])
            } else {
                q(v[i]).normalize().slerp(q(v[i + 1]).normalize(), u)
            }
        }
    };
    r.normalize()
}

impl Channel {
    /// Writes this channel's value at time `t` into `trs`.
    pub fn apply(&self, t: f32, trs: &mut Trs) {
        if self.times.is_empty() {
            return;
        }
        match &self.values {
            ChannelValues::Translation(v) => {
                trs.translation = sample_vec3(&self.times, v, self.interpolation, t)
            }
            ChannelValues::Scale(v) => {
                trs.scale = sample_vec3(&self.times, v, self.interpolation, t)
            }
            ChannelValues::Rotation(v) => {
                trs.rotation = sample_quat(&self.times, v, self.interpolation, t)
            }
        }
    }

    /// Checks key counts and ordering; the message says what is wrong.
    pub fn validate(&self) -> Result<(), String> {
        let n = self.times.len();
        let per_key = check_keys(&self.times, self.interpolation)?;
        let (len, finite) = match &self.values {
            ChannelValues::Translation(v) | ChannelValues::Scale(v) => {
                (v.len(), v.iter().all(|x| x.is_finite()))
            }
            ChannelValues::Rotation(v) => (v.len(), v.iter().all(|x| x.is_finite())),
        };
        if len != n * per_key {
            return Err(format!(
                "{len} values for {n} keys (expected {})",
                n * per_key
            ));
        }
        if !finite {
            return Err("a key value is not finite".into());
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chan(values: ChannelValues, times: Vec<f32>, interpolation: Interpolation) -> Channel {
        Channel {
            node: NodeId(0),
            times,
            values,
            interpolation,
        }
    }

    #[test]
    fn linear_translation_interpolates_and_clamps() {
        let c = chan(
            ChannelValues::Translation(vec![Vec3::ZERO, Vec3::new(2.0, 0.0, 0.0)]),
            vec![1.0, 2.0],
            Interpolation::Linear,
        );
        let mut trs = Trs::IDENTITY;
        for (t, x) in [
            (0.0, 0.0),
            (1.0, 0.0),
            (1.25, 0.5),
            (1.5, 1.0),
            (2.0, 2.0),
            (9.0, 2.0),
        ] {
            c.apply(t, &mut trs);
            assert!((trs.translation.x - x).abs() < 1e-6, "t={t}");
        }
    }

    #[test]
    fn step_holds_previous_key() {
        let c = chan(
            ChannelValues::Scale(vec![Vec3::ONE, Vec3::splat(3.0)]),
            vec![0.0, 1.0],
            Interpolation::Step,
        );
        let mut trs = Trs::IDENTITY;
        c.apply(0.999, &mut trs);
        assert_eq!(trs.scale, Vec3::ONE);
        c.apply(1.0, &mut trs);
        assert_eq!(trs.scale, Vec3::splat(3.0));
    }

    #[test]
    fn cubic_spline_matches_hermite_by_hand() {
        // Keys at t=0 (p=0, out-tangent 1) and t=2 (p=1, in-tangent 0); 1D in x.
        let v = vec![
            Vec3::ZERO,
            Vec3::ZERO,
            Vec3::X, // key 0: in, value, out
            Vec3::ZERO,
            Vec3::X,
            Vec3::ZERO, // key 1
        ];
        let c = chan(
            ChannelValues::Translation(v),
            vec![0.0, 2.0],
            Interpolation::CubicSpline,
        );
        let mut trs = Trs::IDENTITY;
        c.apply(1.0, &mut trs);
        // u = 0.5, dt = 2: h00 = .5, h10 = .125, h01 = .5, h11 = -.125 → 0 + 2·.125·1 + .5·1 + 0 = 0.75
        assert!(
            (trs.translation.x - 0.75).abs() < 1e-6,
            "{}",
            trs.translation.x
        );
    }

    #[test]
    fn rotation_slerps_at_constant_speed() {
        let q0 = Quat::IDENTITY;
        let q1 = Quat::from_rotation_y(std::f32::consts::FRAC_PI_2);
        let c = chan(
            ChannelValues::Rotation(vec![Vec4::from(q0), Vec4::from(q1)]),
            vec![0.0, 1.0],
            Interpolation::Linear,
        );
        let mut trs = Trs::IDENTITY;
        c.apply(0.5, &mut trs);
        assert!(
            trs.rotation
                .angle_between(Quat::from_rotation_y(std::f32::consts::FRAC_PI_4))
                < 1e-5
        );
    }

    #[test]
    fn validate_rejects_bad_channels() {
        let bad_count = chan(
            ChannelValues::Translation(vec![Vec3::ZERO]),
            vec![0.0, 1.0],
            Interpolation::Linear,
        );
        assert!(bad_count.validate().is_err());
        let bad_order = chan(
            ChannelValues::Translation(vec![Vec3::ZERO; 2]),
            vec![1.0, 0.5],
            Interpolation::Linear,
        );
        assert!(bad_order.validate().is_err());
        let nan = chan(
            ChannelValues::Translation(vec![Vec3::NAN; 2]),
            vec![0.0, 1.0],
            Interpolation::Linear,
        );
        assert!(nan.validate().is_err());
    }
}

#[cfg(test)]
mod nan_tests {
    /// A NaN time evaluates like a time before the first key instead of panicking.
    #[test]
    fn nan_time_does_not_panic() {
        let mut s = crate::builtin::load("cornell-spot").unwrap();
        let at_zero: Vec<_> = s.instances.iter().map(|i| i.world_from_object).collect();
        s.set_time(1.0);
        s.set_time(f64::NAN);
        let at_nan: Vec<_> = s.instances.iter().map(|i| i.world_from_object).collect();
        assert_eq!(at_nan, at_zero);
    }
}
