//! No black pixels at silhouettes (issue 35 goal 5): where the interpolated normal of a
//! smooth-shaded mesh faces away from a camera that sees the triangle's front, the
//! specular part is evaluated about the normal bent towards the camera.

use illume_radiance_cache::RadianceCacheSettings;

/// `builtin:glossy-box` at 320×240 (its gold sphere is a metal: no diffuse part, and the
/// renderer's direct light is zero at such pixels too): every reflecting pixel gets
/// indirect light. Before the bend, 4 pixels of the sphere's silhouette were black.
/// Records of 8×8 rays: only where the light is evaluated matters here, not its noise.
#[test]
fn a_glossy_silhouette_has_no_black_pixels() {
    let (w, h) = (320, 240);
    let settings = RadianceCacheSettings {
        theta_strata: 8,
        phi_strata: 8,
        traced_rays: 2,
        ..RadianceCacheSettings::default()
    };
    let (g, img) = crate::common::still_indirect("glossy-box", (w, h), settings);
    let (mut facing_away, mut black) = (0, Vec::new());
    for (i, (px, out)) in g.pixels.iter().zip(img.pixels()).enumerate() {
        let Some(px) = px else { continue };
        if !px.hit.reflects {
            continue;
        }
        let n = if px.hit.front_face {
            px.hit.shading_normal
        } else {
            -px.hit.shading_normal
        };
        facing_away += usize::from(n.dot(px.to_camera) <= 0.0);
        if out.max_element() <= 0.0 {
            black.push((i as u32 % w, i as u32 / w));
        }
    }
    assert!(
        facing_away > 0,
        "no pixel's shading normal faces away from the camera: the case is not exercised"
    );
    assert!(black.is_empty(), "black pixels at {black:?}");
}
