//! Colour spaces used by FLIP (Andersson et al. 2020): linear Rec.709 RGB,
//! CIE XYZ (D65), the opponent space YCxCz (a linearised CIELAB) in which the
//! contrast-sensitivity filters are applied, and CIELAB with the Hunt adjustment in which
//! colour differences are measured with HyAB.

use glam::Vec3;

/// D65 reference white in XYZ, as FLIP uses it.
const D65_WHITE: Vec3 = Vec3::new(0.950_428_5, 1.0, 1.088_900_4);
/// Its inverse, per component.
const INV_D65_WHITE: Vec3 = Vec3::new(1.052_156_9, 1.0, 0.918_357_7);

/// Rec.709 luminance of a linear RGB value.
#[inline]
pub(crate) fn luminance(rgb: Vec3) -> f32 {
    0.2126 * rgb.x + 0.7152 * rgb.y + 0.0722 * rgb.z
}

/// Linear Rec.709 RGB → CIE XYZ (D65). The matrix is the exact rational form of the
/// sRGB primaries that FLIP uses.
#[inline]
pub(crate) fn xyz_from_linear_rgb(c: Vec3) -> Vec3 {
    Vec3::new(
        (10_135_552.0 / 24_577_794.0) * c.x
            + (8_788_810.0 / 24_577_794.0) * c.y
            + (4_435_075.0 / 24_577_794.0) * c.z,
        (2_613_072.0 / 12_288_897.0) * c.x
            + (8_788_810.0 / 12_288_897.0) * c.y
            + (887_015.0 / 12_288_897.0) * c.z,
        (1_425_312.0 / 73_733_382.0) * c.x
            + (8_788_810.0 / 73_733_382.0) * c.y
            + (70_074_185.0 / 73_733_382.0) * c.z,
    )
}

/// CIE XYZ (D65) → linear Rec.709 RGB.
#[inline]
pub(crate) fn linear_rgb_from_xyz(c: Vec3) -> Vec3 {
    Vec3::new(
        3.241_003_3 * c.x - 1.537_398_9 * c.y - 0.498_615_87 * c.z,
        -0.969_224_33 * c.x + 1.875_930_1 * c.y + 0.041_554_224 * c.z,
        0.055_639_423 * c.x - 0.204_011_2 * c.y + 1.057_148_9 * c.z,
    )
}

/// CIE XYZ → YCxCz: CIELAB without the cube root, so that filtering in it is linear
/// (FLIP paper, spatial filtering).
#[inline]
pub(crate) fn ycxcz_from_xyz(c: Vec3) -> Vec3 {
    let n = c * INV_D65_WHITE;
    Vec3::new(116.0 * n.y - 16.0, 500.0 * (n.x - n.y), 200.0 * (n.y - n.z))
}

/// YCxCz → CIE XYZ, the inverse of [`ycxcz_from_xyz`].
#[inline]
pub(crate) fn xyz_from_ycxcz(c: Vec3) -> Vec3 {
    let y = (c.x + 16.0) / 116.0;
    let cx = c.y / 500.0;
    let cz = c.z / 200.0;
    Vec3::new(y + cx, y, y - cz) * D65_WHITE
}

/// CIE XYZ → CIELAB (D65 white).
#[inline]
pub(crate) fn lab_from_xyz(c: Vec3) -> Vec3 {
    const DELTA: f32 = 6.0 / 29.0;
    let f = |t: f32| {
        if t > DELTA * DELTA * DELTA {
            t.powf(1.0 / 3.0)
        } else {
            t / (3.0 * DELTA * DELTA) + 4.0 / 29.0
        }
    };
    let n = c * INV_D65_WHITE;
    let (fx, fy, fz) = (f(n.x), f(n.y), f(n.z));
    Vec3::new(116.0 * fy - 16.0, 500.0 * (fx - fy), 200.0 * (fy - fz))
}

/// The Hunt effect: chroma scaled by 0.01·L*, so that dark colours differ less
/// (FLIP paper, colour pipeline).
#[inline]
pub(crate) fn hunt_adjusted(lab: Vec3) -> Vec3 {
    Vec3::new(lab.x, 0.01 * lab.x * lab.y, 0.01 * lab.x * lab.z)
}

/// HyAB distance: city-block in lightness plus Euclidean in (a, b) (Abasi et al. 2020;
/// FLIP paper, colour pipeline).
#[inline]
pub(crate) fn hyab(a: Vec3, b: Vec3) -> f32 {
    let da = a.y - b.y;
    let db = a.z - b.z;
    (a.x - b.x).abs() + (da * da + db * db).sqrt()
}

/// The Hunt-adjusted CIELAB colour of a linear RGB value.
#[inline]
pub(crate) fn hunt_lab_from_linear_rgb(c: Vec3) -> Vec3 {
    hunt_adjusted(lab_from_xyz(xyz_from_linear_rgb(c)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn xyz_round_trips_through_rgb() {
        let c = Vec3::new(0.2, 0.5, 0.9);
        let back = linear_rgb_from_xyz(xyz_from_linear_rgb(c));
        assert!((back - c).abs().max_element() < 1e-5, "{back}");
    }

    #[test]
    fn ycxcz_round_trips_and_white_is_neutral() {
        let white = ycxcz_from_xyz(xyz_from_linear_rgb(Vec3::ONE));
        assert!(
            (white.x - 100.0).abs() < 1e-3 && white.y.abs() < 1e-3 && white.z.abs() < 1e-3,
            "{white}"
        );
        let c = Vec3::new(0.3, 0.7, 0.1);
        let back = xyz_from_ycxcz(ycxcz_from_xyz(c));
        assert!((back - c).abs().max_element() < 1e-5);
    }

    #[test]
    fn lab_of_white_is_100_0_0() {
        let lab = lab_from_xyz(xyz_from_linear_rgb(Vec3::ONE));
        assert!(
            (lab - Vec3::new(100.0, 0.0, 0.0)).abs().max_element() < 1e-3,
            "{lab}"
        );
    }
}
