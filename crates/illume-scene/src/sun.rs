//! The sun over one day at one place: NOAA's solar position (after Meeus, *Astronomical
//! Algorithms*), a clear-sky irradiance from the air mass, and the `[sun]` table that lets
//! [`Scene::set_time`](crate::Scene::set_time) drive a directional light with them.
//!
//! Bahnsen et al. 2012 (§3.1 "Tips and tricks") move a light "along a path resembling the
//! sun's passing on a chosen day", intensity animated at sunrise and sunset, and give no
//! formula; this module is ours.
//!
//! **Axes.** +Y is up (the zenith), **north is −Z and east is +X** (so south is +Z, and the
//! scene's right-handed frame is east–up–south). Azimuth is measured from north, clockwise
//! seen from above (east = 90°), as in NOAA's and NREL's tables.
//!
//! **Clock.** Scene time t \[s\] maps to the local clock time
//! `hours = start_h + t / seconds_per_hour`, on the table's `date`, at `utc_offset_h` hours
//! from UTC (Denmark in summer: +2).
//!
//! ```
//! use illume_scene::sun::{SunSettings, solar_position};
//! let s = SunSettings::default(); // Koldinghus, 21 June
//! let p = solar_position(&s, 13.5).unwrap(); // about solar noon there (CEST)
//! assert!(p.elevation_deg > 55.0 && p.elevation_deg < 59.0);
//! ```

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

/// The `[sun]` table: where, when and how bright. Defaults: Koldinghus castle, Kolding,
/// Denmark (55.49° N, 9.47° E), 21 June 2026 (the paper names no day: our choice), Danish
/// summer time (UTC+2), scene time 0 at midnight and one scene second per clock second
/// (`seconds_per_hour = 3600`), so a day lasts 86 400 s.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, default)]
pub struct SunSettings {
    /// Latitude \[degrees\], north positive. Default 55.49 (Koldinghus).
    pub latitude_deg: f64,
    /// Longitude \[degrees\], east positive. Default 9.47 (Koldinghus).
    pub longitude_deg: f64,
    /// Calendar date `YYYY-MM-DD` (Gregorian). Default `2026-06-21`.
    pub date: String,
    /// Local clock offset from UTC \[hours\]: +2 for Danish summer time (default), −7 for
    /// Colorado in winter.
    pub utc_offset_h: f64,
    /// Clock time \[hours\] at scene time 0. Default 0 (midnight).
    pub start_h: f64,
    /// Scene seconds per clock hour. Default 3600 (real time); 1 plays a day in 24 s.
    pub seconds_per_hour: f64,
    /// Multiplies the clear-sky direct-normal irradiance \[W/m²\] of [`clear_sky_irradiance`]
    /// to give the light's irradiance in scene units. Default 1 (radiometric W/m²).
    pub scale: f32,
    /// Linear RGB colour the irradiance is multiplied by. Default white.
    pub colour: [f32; 3],
    /// Name of the directional light the sun drives (created if the scene has none of that
    /// name). Default `sun`.
    pub light: String,
}

impl Default for SunSettings {
    fn default() -> Self {
        Self {
            latitude_deg: 55.49,
            longitude_deg: 9.47,
            date: "2026-06-21".into(),
            utc_offset_h: 2.0,
            start_h: 0.0,
            seconds_per_hour: 3600.0,
            scale: 1.0,
            colour: [1.0, 1.0, 1.0],
            light: "sun".into(),
        }
    }
}

/// Why a `[sun]` table cannot be used; the message names the field.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SunError {
    /// `date` is not `YYYY-MM-DD` with a valid month and day.
    #[error("[sun] date {0:?} is not a date YYYY-MM-DD")]
    Date(String),
    /// A number is out of its range.
    #[error("[sun] {field} = {value} is out of range ({range})")]
    Range {
        /// The field.
        field: &'static str,
        /// Its value.
        value: f64,
        /// The allowed range, in words.
        range: &'static str,
    },
    /// `light` names a light that is not directional.
    #[error("[sun] light {0:?} exists but is not a directional light")]
    NotDirectional(String),
}

impl SunSettings {
    /// Checks every field; the error names the first bad one.
    pub fn validate(&self) -> Result<(), SunError> {
        parse_date(&self.date)?;
        let checks: [(&'static str, f64, bool, &'static str); 6] = [
            (
                "latitude_deg",
                self.latitude_deg,
                (-90.0..=90.0).contains(&self.latitude_deg),
                "−90 to 90",
            ),
            (
                "longitude_deg",
                self.longitude_deg,
                (-180.0..=180.0).contains(&self.longitude_deg),
                "−180 to 180",
            ),
            (
                "utc_offset_h",
                self.utc_offset_h,
                (-14.0..=14.0).contains(&self.utc_offset_h),
                "−14 to 14",
            ),
            ("start_h", self.start_h, self.start_h.is_finite(), "finite"),
            (
                "seconds_per_hour",
                self.seconds_per_hour,
                self.seconds_per_hour.is_finite() && self.seconds_per_hour > 0.0,
                "> 0",
            ),
            (
                "scale",
                self.scale as f64,
                self.scale.is_finite() && self.scale >= 0.0,
                "≥ 0",
            ),
        ];
        for (field, value, ok, range) in checks {
            if !ok {
                return Err(SunError::Range {
                    field,
                    value,
                    range,
                });
            }
        }
        if self.colour.iter().any(|c| !c.is_finite() || *c < 0.0) {
            return Err(SunError::Range {
                field: "colour",
                value: self.colour.iter().copied().fold(f32::NAN, f32::min) as f64,
                range: "three finite numbers ≥ 0",
            });
        }
        Ok(())
    }

    /// Local clock time \[hours\] at scene time `t` \[s\].
    pub fn clock_hours(&self, t: f64) -> f64 {
        self.start_h + t / self.seconds_per_hour
    }

    /// Scene time \[s\] at local clock time `hours` (the inverse of [`Self::clock_hours`]).
    pub fn scene_time(&self, hours: f64) -> f64 {
        (hours - self.start_h) * self.seconds_per_hour
    }
}

/// Parses `YYYY-MM-DD`.
pub fn parse_date(date: &str) -> Result<(i32, u32, u32), SunError> {
    let bad = || SunError::Date(date.to_string());
    let mut parts = date.trim().splitn(3, '-');
    let y: i32 = parts.next().and_then(|p| p.parse().ok()).ok_or_else(bad)?;
    let m: u32 = parts.next().and_then(|p| p.parse().ok()).ok_or_else(bad)?;
    let d: u32 = parts.next().and_then(|p| p.parse().ok()).ok_or_else(bad)?;
    let leap = (y % 4 == 0 && y % 100 != 0) || y % 400 == 0;
    let days = [
        31,
        if leap { 29 } else { 28 },
        31,
        30,
        31,
        30,
        31,
        31,
        30,
        31,
        30,
        31,
    ];
    if !(1..=12).contains(&m) || d == 0 || d > days[(m - 1) as usize] {
        return Err(bad());
    }
    Ok((y, m, d))
}

/// Julian day number at 0 h UT of a Gregorian date (Meeus, ch. 7).
pub fn julian_day(year: i32, month: u32, day: u32) -> f64 {
    let (mut y, mut m) = (year as f64, month as f64);
    if month <= 2 {
        y -= 1.0;
        m += 12.0;
    }
    let a = (y / 100.0).floor();
    let b = 2.0 - a + (a / 4.0).floor();
    (365.25 * (y + 4716.0)).floor() + (30.6001 * (m + 1.0)).floor() + day as f64 + b - 1524.5
}

/// Where the sun is, seen from the table's place.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolarPosition {
    /// Geometric elevation above the horizon \[degrees\] (no refraction).
    pub elevation_deg: f64,
    /// Azimuth from north, clockwise seen from above \[degrees\], in [0, 360).
    pub azimuth_deg: f64,
}

impl SolarPosition {
    /// Geometric zenith angle \[degrees\] = 90° − elevation.
    pub fn zenith_deg(&self) -> f64 {
        90.0 - self.elevation_deg
    }

    /// Unit world vector pointing **toward** the sun (north −Z, east +X, up +Y).
    pub fn to_sun(&self) -> Vec3 {
        let (el, az) = (
            self.elevation_deg.to_radians(),
            self.azimuth_deg.to_radians(),
        );
        Vec3::new(
            (az.sin() * el.cos()) as f32,
            el.sin() as f32,
            (-az.cos() * el.cos()) as f32,
        )
    }
}

/// NOAA's solar position (the algorithm of NOAA's solar calculator spreadsheets, after
/// Meeus) at local clock time `hours` on the table's date; accurate to about 0.01° for
/// years 1800–2100. No atmospheric refraction.
pub fn solar_position(sun: &SunSettings, hours: f64) -> Result<SolarPosition, SunError> {
    let (y, m, d) = parse_date(&sun.date)?;
    Ok(solar_position_at(
        julian_day(y, m, d) + (hours - sun.utc_offset_h) / 24.0,
        sun.latitude_deg,
        sun.longitude_deg,
    ))
}

/// NOAA's solar position at Julian day `jd` (UT) for latitude/longitude in degrees
/// (north and east positive).
pub fn solar_position_at(jd: f64, latitude_deg: f64, longitude_deg: f64) -> SolarPosition {
    let jc = (jd - 2_451_545.0) / 36_525.0;
    let l0 = (280.46646 + jc * (36000.76983 + jc * 0.0003032)).rem_euclid(360.0);
    let m = 357.52911 + jc * (35999.05029 - 0.0001537 * jc);
    let e = 0.016708634 - jc * (0.000042037 + 0.0000001267 * jc);
    let mr = m.to_radians();
    let centre = mr.sin() * (1.914602 - jc * (0.004817 + 0.000014 * jc))
        + (2.0 * mr).sin() * (0.019993 - 0.000101 * jc)
        + (3.0 * mr).sin() * 0.000289;
    let true_long = l0 + centre;
    let omega = (125.04 - 1934.136 * jc).to_radians();
    let apparent_long = true_long - 0.00569 - 0.00478 * omega.sin();
    let mean_obliquity =
        23.0 + (26.0 + (21.448 - jc * (46.815 + jc * (0.00059 - jc * 0.001813))) / 60.0) / 60.0;
    let obliquity = (mean_obliquity + 0.00256 * omega.cos()).to_radians();
    let declination = (obliquity.sin() * apparent_long.to_radians().sin()).asin();
    let v = (obliquity / 2.0).tan().powi(2);
    let l0r = l0.to_radians();
    let equation_of_time_min = 4.0
        * (v * (2.0 * l0r).sin() - 2.0 * e * mr.sin() + 4.0 * e * v * mr.sin() * (2.0 * l0r).cos()
            - 0.5 * v * v * (4.0 * l0r).sin()
            - 1.25 * e * e * (2.0 * mr).sin())
        .to_degrees();
    // Minutes past UT midnight of this Julian day.
    let ut_min = ((jd + 0.5).fract()) * 1440.0;
    let true_solar_min = (ut_min + equation_of_time_min + 4.0 * longitude_deg).rem_euclid(1440.0);
    let hour_angle = true_solar_min / 4.0 - 180.0;
    let lat = latitude_deg.to_radians();
    let ha = hour_angle.to_radians();
    let cos_zenith =
        (lat.sin() * declination.sin() + lat.cos() * declination.cos() * ha.cos()).clamp(-1.0, 1.0);
    let zenith = cos_zenith.acos();
    let denominator = lat.cos() * zenith.sin();
    let azimuth_deg = if denominator.abs() < 1e-12 {
        // At a pole or with the sun at the zenith the azimuth is undefined: take south.
        180.0
    } else {
        let c = ((lat.sin() * cos_zenith - declination.sin()) / denominator).clamp(-1.0, 1.0);
        let a = c.acos().to_degrees();
        if hour_angle > 0.0 {
            (a + 180.0).rem_euclid(360.0)
        } else {
            (540.0 - a).rem_euclid(360.0)
        }
    };
    SolarPosition {
        elevation_deg: 90.0 - zenith.to_degrees(),
        azimuth_deg,
    }
}

/// Relative optical air mass at geometric elevation `elevation_deg` (Kasten & Young 1989:
/// `1 / (cos z + 0.50572 (96.07995° − z)^−1.6364)`, z the zenith angle in degrees); 1 at
/// the zenith, about 38 at the horizon. Infinite below the horizon.
pub fn air_mass(elevation_deg: f64) -> f64 {
    if elevation_deg <= 0.0 {
        return f64::INFINITY;
    }
    let z = 90.0 - elevation_deg;
    1.0 / (z.to_radians().cos() + 0.50572 * (96.07995 - z).powf(-1.6364))
}

/// Clear-sky direct-normal irradiance \[W/m²\] at geometric elevation `elevation_deg`:
/// Meinel & Meinel (1976), `1353 · 0.7^(AM^0.678)` with AM from [`air_mass`]; 947 W/m² at
/// the zenith, 20 W/m² just above the horizon, **exactly 0 at and below it** (the sun's
/// light and shadows go off at sunset, as the paper's animated intensity does).
pub fn clear_sky_irradiance(elevation_deg: f64) -> f64 {
    if elevation_deg <= 0.0 {
        return 0.0;
    }
    1353.0 * 0.7f64.powf(air_mass(elevation_deg).powf(0.678))
}

/// The scale s(t) of a precomputed sky image (Bahnsen et al. §2: "a precomputed image for
/// the skylight, which we scale depending on the position of the sun"): `sin(elevation)`
/// clamped to [0, 1]. Diffuse horizontal irradiance of a sky with a fixed angular
/// distribution grows roughly with the sine of the sun's elevation (the CIE overcast
/// sky's illuminance is nearly proportional to it), and the sky goes dark at sunset.
pub fn sky_scale(elevation_deg: f64) -> f32 {
    elevation_deg.to_radians().sin().clamp(0.0, 1.0) as f32
}

/// The sun's state at one scene time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SunState {
    /// Where the sun is.
    pub position: SolarPosition,
    /// Irradiance on a surface facing the sun, in scene units (colour × scale × clear sky).
    pub irradiance: illume_core::Rgb,
    /// Rotation of the light's node: its local −Z shines away from the sun.
    pub rotation: Quat,
    /// [`sky_scale`] at this elevation.
    pub sky_scale: f32,
}

/// Evaluates the sun at scene time `t` \[s\].
pub fn evaluate(sun: &SunSettings, t: f64) -> Result<SunState, SunError> {
    let position = solar_position(sun, sun.clock_hours(t))?;
    let e = clear_sky_irradiance(position.elevation_deg) as f32 * sun.scale;
    let shine = -position.to_sun();
    Ok(SunState {
        position,
        irradiance: illume_core::Rgb::new(sun.colour[0], sun.colour[1], sun.colour[2]) * e,
        rotation: Quat::from_rotation_arc(-Vec3::Z, shine),
        sky_scale: sky_scale(position.elevation_deg),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// NREL SPA's published example (Reda & Andreas 2008, Table A4.1): 17 October 2003,
    /// 12:30:30 local at UTC−7, 39.742476° N, 105.1786° W: geometric zenith 50.12795°,
    /// azimuth 194.34024°.
    #[test]
    fn matches_the_spa_example() {
        let s = SunSettings {
            latitude_deg: 39.742476,
            longitude_deg: -105.1786,
            date: "2003-10-17".into(),
            utc_offset_h: -7.0,
            ..Default::default()
        };
        let p = solar_position(&s, 12.0 + 30.0 / 60.0 + 30.0 / 3600.0).unwrap();
        assert!(
            (p.zenith_deg() - 50.12795).abs() < 0.05,
            "zenith {}",
            p.zenith_deg()
        );
        assert!(
            (p.azimuth_deg - 194.34024).abs() < 0.05,
            "azimuth {}",
            p.azimuth_deg
        );
    }

    /// At an equinox, at true solar noon, the sun stands 90° − φ high.
    #[test]
    fn equinox_noon_elevation_is_ninety_minus_latitude() {
        for lat in [-60.0, -30.0, 0.0, 20.0, 55.49, 70.0] {
            let s = SunSettings {
                latitude_deg: lat,
                longitude_deg: 0.0,
                date: "2026-03-20".into(),
                utc_offset_h: 0.0,
                ..Default::default()
            };
            // Highest elevation over the day, searched by the minute (the equation of
            // time shifts noon by minutes).
            let best = (0..1440)
                .map(|m| solar_position(&s, m as f64 / 60.0).unwrap().elevation_deg)
                .fold(f64::MIN, f64::max);
            let expected = 90.0 - f64::abs(lat);
            assert!(
                (best - expected).abs() < 0.5,
                "lat {lat}: {best} vs {expected}"
            );
        }
    }

    #[test]
    fn no_light_below_the_horizon() {
        let s = SunSettings::default();
        // Koldinghus at 01:00 CEST on 21 June: below the horizon.
        let night = evaluate(&s, s.scene_time(1.0)).unwrap();
        assert!(night.position.elevation_deg < 0.0);
        assert_eq!(night.irradiance, illume_core::Rgb::ZERO);
        assert_eq!(night.sky_scale, 0.0);
        let noon = evaluate(&s, s.scene_time(13.5)).unwrap();
        assert!(noon.irradiance.x > 800.0, "{:?}", noon.irradiance);
        // The light shines down and toward the north (sun in the south, +Z).
        let shine = noon.rotation * -Vec3::Z;
        assert!(shine.y < -0.8 && shine.z < 0.0, "{shine}");
        assert_eq!(clear_sky_irradiance(-0.001), 0.0);
        assert!((clear_sky_irradiance(90.0) - 947.0).abs() < 1.0);
    }

    #[test]
    fn set_time_emits_light_changed() {
        let mut scene = crate::Scene::default();
        let s = SunSettings::default();
        let light = scene.attach_sun(s.clone()).unwrap();
        let changes = scene.set_time(s.scene_time(12.0));
        let changed = changes.iter().find_map(|c| match c {
            crate::SceneChange::LightChanged { light: l, from, to } if *l == light => {
                Some((from.clone(), to.clone()))
            }
            _ => None,
        });
        let (from, to) = changed.expect("the sun's light changed");
        assert_eq!(
            from.kind,
            crate::LightKind::Directional {
                irradiance: illume_core::Rgb::ZERO
            }
        );
        let crate::LightKind::Directional { irradiance } = to.kind else {
            panic!("not directional");
        };
        assert!(irradiance.x > 500.0);
        let expected = -evaluate(&s, s.scene_time(12.0)).unwrap().position.to_sun();
        assert!(to.direction().abs_diff_eq(expected, 1e-5));
        // The same time again changes no light.
        let again = scene.set_time(s.scene_time(12.0));
        assert!(
            !again
                .iter()
                .any(|c| matches!(c, crate::SceneChange::LightChanged { .. })),
            "{again:?}"
        );
    }

    #[test]
    fn bad_tables_name_the_field() {
        let bad_date = SunSettings {
            date: "2026-02-30".into(),
            ..Default::default()
        };
        assert!(matches!(bad_date.validate(), Err(SunError::Date(_))));
        let bad_lat = SunSettings {
            latitude_deg: 95.0,
            ..Default::default()
        };
        assert!(
            bad_lat
                .validate()
                .unwrap_err()
                .to_string()
                .contains("latitude_deg")
        );
    }
}
