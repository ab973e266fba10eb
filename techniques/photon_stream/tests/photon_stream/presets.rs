//! `--preset paper` is the paper (issue 35): every setting documented as beyond the paper
//! is switched off by it, and the two estimator choices it makes — point-light falloff
//! and nearest-VSL cells — compute what §0.4.1 and Algorithm 2 say.

use crate::common::sixty_vsls;
use illume_core::Vec3;
use illume_core::sampling::{Pcg32, SampleStream, uniform_triangle};
use illume_photon_stream::PhotonStreamSettings;
use illume_photon_stream::placement::VslSet;
use illume_photon_stream::settings::{VisibilityMode, VslCells, VslFalloff};
use illume_photon_stream::shade::VslField;
use illume_scene::InstanceId;

/// The settings by which this implementation departs from the paper, and the value that
/// is the paper's. A setting documented as "beyond the paper" that is missing here fails
/// `the_paper_preset_switches_every_deviation_off`.
fn paper_values(s: &PhotonStreamSettings) -> Vec<(&'static str, bool)> {
    vec![
        ("falloff", s.falloff == VslFalloff::InverseSquare),
        ("cells", s.cells == VslCells::Nearest),
        ("shading_stride", s.shading_stride == 1),
        ("near_field_rays", s.near_field_rays == 0),
        ("near_field_scale", s.near_field_rays == 0), // used only with a near field
        ("visibility", s.visibility == VisibilityMode::Off),
        ("visibility_rays", s.visibility == VisibilityMode::Off), // used only with it
        ("filtered_textures", !s.filtered_textures),
        ("rest_when_settled", !s.rest_when_settled),
        ("turnover_frames", s.turnover_frames == 0),
        ("gather_direct", !s.gather_direct),
        ("smooth_frames", s.smooth_frames == 0),
        ("directional_albedo", !s.directional_albedo),
    ]
}

#[test]
fn the_paper_preset_switches_every_deviation_off() {
    let paper = illume_agreement::assert_paper_preset(paper_values);
    paper.validate().unwrap();
    // And the default keeps the improvements (each measured in BENCHMARKS.md).
    let default = PhotonStreamSettings::default();
    assert_eq!(default.falloff, VslFalloff::Disk);
    assert_eq!(default.cells, VslCells::Oriented);
    assert!(default.shading_stride > 1);
}

/// One VSL of area `a` at height `r` above a point, facing it: the unoccluded weight is
/// 1/(π r²) with the paper's point light and 1/(π r² + A) with the disk (both without
/// Φ and ρ/π; the cosines are 1).
#[test]
fn the_falloff_is_the_papers_point_light_or_the_disk() {
    for (r, a) in [(0.05f32, 0.01f32), (0.3, 0.04), (2.0, 0.5)] {
        let mut field = VslField {
            positions: vec![Vec3::new(0.0, r, 0.0)],
            normals: vec![Vec3::NEG_Y],
            front_w: vec![illume_core::Rgb::ONE],
            back_w: vec![illume_core::Rgb::ZERO],
            area_m2: vec![a],
            inverse_square: false,
        };
        let disk = field.geometry(0, Vec3::ZERO, Vec3::Y).0;
        field.inverse_square = true;
        let point = field.geometry(0, Vec3::ZERO, Vec3::Y).0;
        let pi = std::f32::consts::PI;
        let close = |x: f32, want: f32| ((x - want) / want).abs() < 1e-5;
        assert!(
            close(disk, 1.0 / (pi * r * r + a)),
            "disk at r = {r}: {disk}"
        );
        assert!(
            close(point, 1.0 / (pi * r * r)),
            "point at r = {r}: {point}"
        );
    }
}

/// With `cells = nearest`, every impact goes to the closest VSL of its object (Algorithm
/// 2), whatever the orientation of the surface it hit; with `oriented` (the default)
/// some floor impacts near a wall go to a floor VSL that is not the closest.
#[test]
fn nearest_cells_give_every_impact_to_the_closest_vsl_of_its_object() {
    let scene = illume_scene::builtin::load("cornell-spot").unwrap();
    let (paper, oriented) = (sixty_vsls(&scene, false), sixty_vsls(&scene, true));
    let mut rng = Pcg32::new(3, 4);
    let (mut samples, mut oriented_differs) = (0, 0);
    for (i, inst) in scene.instances.iter().enumerate() {
        let id = InstanceId(i as u32);
        let mesh = &scene.meshes[inst.mesh.index()];
        for t in 0..mesh.triangle_count() {
            let [a, b, c] = mesh.triangle(t);
            for _ in 0..50 {
                let u = uniform_triangle(rng.next_2d());
                let p = a * (1.0 - u.x - u.y) + b * u.x + c * u.y;
                let closest = |set: &VslSet| {
                    set.vsls()
                        .iter()
                        .enumerate()
                        .filter(|(_, v)| v.instance == id)
                        .map(|(g, v)| (v.position_object.distance_squared(p), g as u32))
                        .min_by(|x, y| x.0.total_cmp(&y.0).then(x.1.cmp(&y.1)))
                        .map(|(_, g)| g)
                };
                assert_eq!(
                    paper.nearest_on(id, t as u32, p),
                    closest(&paper),
                    "instance {i} triangle {t} at {p}"
                );
                samples += 1;
                oriented_differs +=
                    usize::from(oriented.nearest_on(id, t as u32, p) != closest(&oriented));
            }
        }
    }
    assert!(samples > 1000, "{samples} samples");
    assert!(
        oriented_differs > 0,
        "the oriented rule should differ from the nearest somewhere in the box"
    );
}
