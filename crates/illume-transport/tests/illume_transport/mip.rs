//! Trilinear mip-mapping in the rasterized G-buffer (`TextureFilter::Trilinear`): a
//! minified checkerboard reads as its mean grey instead of aliasing, and a magnified
//! one reads exactly what the bilinear G-buffer (and rays) read.

use illume_core::{Rgb, Vec2, Vec3};
use illume_scene::builtin::{SceneBuilder, quad};
use illume_scene::{Material, Mesh, Texture, Trs};
use illume_transport::{GBuffer, TextureFilter, World};

/// A 2 m square facing +y, seen from 3 m straight above, textured with a 64 × 64
/// checkerboard of one-texel black and white checks repeated `repeats` times across it
/// (base colour 1, so the albedo is the texture's value).
fn checkerboard_floor(repeats: f32) -> World {
    let mut b = SceneBuilder::new();
    let side = 64;
    let tex = b.texture(Texture::from_fn("checks", side, side, |x, y| {
        Rgb::splat(((x + y) % 2) as f32)
    }));
    let m = b.material(Material {
        base_color: Rgb::ONE,
        base_color_texture: Some(tex),
        ..Default::default()
    });
    // Facing +y (z × x), texture coordinates scaled to repeat the checks.
    let mut floor = quad(Vec3::ZERO, Vec3::Z, Vec3::X, m);
    floor.uvs.iter_mut().for_each(|uv| *uv *= repeats);
    let mesh = b.mesh(Mesh {
        name: "floor".into(),
        ..floor
    });
    b.placed("floor", mesh, Trs::IDENTITY, false);
    b.camera_looking_down(3.0, 40f32.to_radians());
    let scene = b.finish("test:checkerboard");
    scene.validate().unwrap();
    World::new(scene)
}

/// Albedos (red channel) of the pixels that see the floor.
fn albedos(g: &GBuffer) -> Vec<f32> {
    g.pixels.iter().flatten().map(|p| p.hit.albedo.x).collect()
}

#[test]
fn a_minified_checkerboard_renders_as_its_mean_grey() {
    // 64 × 50 repeats of 64 texels across ~110 pixels: ~30 texels per pixel.
    let world = checkerboard_floor(50.0);
    let (w, h) = (160, 120);
    let bilinear = albedos(&GBuffer::rasterize(&world, w, h));
    let trilinear = albedos(&GBuffer::rasterize_with(
        &world,
        w,
        h,
        TextureFilter::Trilinear,
    ));
    assert_eq!(bilinear.len(), trilinear.len());
    assert!(trilinear.len() > 5000, "{}", trilinear.len());
    // Mip-mapped: every pixel within a hair of the mean 0.5.
    let worst = trilinear
        .iter()
        .map(|a| (a - 0.5).abs())
        .fold(0.0f32, f32::max);
    assert!(
        worst < 0.02,
        "mip-mapped albedo strays {worst} from the mean"
    );
    // Point-sampled: aliasing, pixels off the mean by (1 − 2fx)(1 − 2fy)/2 for their
    // fractional texel positions fx, fy — more than 0.1 for about half of them (the test
    // can fail: were the G-buffer to filter without being asked, or mip-mapping to do
    // nothing, one of the two assertions would).
    let aliased = bilinear.iter().filter(|a| (*a - 0.5).abs() > 0.1).count();
    assert!(
        aliased as f64 > 0.3 * bilinear.len() as f64,
        "{aliased} of {} bilinear pixels aliased",
        bilinear.len()
    );
}

#[test]
fn a_magnified_texture_reads_the_bilinear_values_exactly() {
    // One repeat of 64 texels across ~110 pixels: a texel covers more than a pixel.
    let world = checkerboard_floor(1.0);
    let (w, h) = (160, 120);
    let bilinear = GBuffer::rasterize(&world, w, h);
    let trilinear = GBuffer::rasterize_with(&world, w, h, TextureFilter::Trilinear);
    let rays = GBuffer::render(&world, w, h, Vec2::splat(0.5));
    let mut seen = 0;
    for ((a, b), r) in trilinear
        .pixels
        .iter()
        .zip(&bilinear.pixels)
        .zip(&rays.pixels)
    {
        if let (Some(a), Some(b)) = (a, b) {
            assert_eq!(a.hit.albedo, b.hit.albedo);
            assert_eq!(a.hit.position, b.hit.position);
            if let Some(r) = r {
                assert!((a.hit.albedo - r.hit.albedo).abs().max_element() < 1e-3);
            }
            seen += 1;
        }
    }
    assert!(seen > 5000, "{seen}");
}

#[test]
fn a_buffer_switching_filters_matches_a_fresh_build() {
    // Pixels kept from a build with another filter would hold the other filter's
    // albedo: the incremental build must rebuild them.
    let world = checkerboard_floor(50.0);
    let (w, h) = (96, 72);
    let mut g = GBuffer::rasterize(&world, w, h);
    g.rasterize_into_with(&world, w, h, TextureFilter::Trilinear);
    let fresh = GBuffer::rasterize_with(&world, w, h, TextureFilter::Trilinear);
    for (a, b) in g.pixels.iter().zip(&fresh.pixels) {
        assert_eq!(a.map(|p| p.hit.albedo), b.map(|p| p.hit.albedo));
    }
    assert_eq!(g.reused_pixels, 0);
}
