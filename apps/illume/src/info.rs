//! `illume info`.

use anyhow::Result;
use clap::Args;
use illume_core::channel_mean;
use illume_scene::{LightKind, excerpt};
use std::path::PathBuf;

/// Arguments of `illume info`.
#[derive(Args)]
pub struct InfoArgs {
    /// Scene file (.gltf, .glb, .obj, .ply) or builtin:NAME.
    pub scene: PathBuf,
    /// How a glTF file's light intensities and emission are read (as in `render`).
    #[arg(long, value_enum, default_value_t = crate::setup::Units::Radiometric)]
    pub units: crate::setup::Units,
}

/// Runs `illume info`.
pub fn run(a: InfoArgs) -> Result<()> {
    let options = illume_scene::LoadOptions {
        units: a.units.load(),
        ..Default::default()
    };
    let scene = crate::render::load_scene_with(&a.scene, None, 0.0, false, &options)?;
    let b = scene.bounds();
    println!("scene        {}", scene.source);
    println!(
        "triangles    {} in {} meshes ({} instanced)",
        scene
            .meshes
            .iter()
            .map(|m| m.triangle_count())
            .sum::<usize>(),
        scene.meshes.len(),
        scene.instanced_triangle_count()
    );
    println!(
        "instances    {} ({} dynamic)",
        scene.instances.len(),
        scene.instances.iter().filter(|i| i.dynamic).count()
    );
    println!(
        "materials    {} ({} emissive), textures {}",
        scene.materials.len(),
        scene.materials.iter().filter(|m| m.is_emissive()).count(),
        scene.textures.len()
    );
    // Names come from the file: each is cut to an excerpt.
    let specular: Vec<String> = scene
        .materials
        .iter()
        .filter(|m| !m.is_lambertian())
        .map(|m| excerpt(&m.name))
        .collect();
    if specular.is_empty() {
        println!("surfaces     all Lambertian");
    } else {
        println!(
            "surfaces     {} of {} materials have a specular part (metallic/roughness): {}",
            specular.len(),
            scene.materials.len(),
            specular.join(", ")
        );
        println!(
            "             note: photons (photon_stream, selective) scatter by these BRDFs, but their \
             indirect light leaves a glossy surface as from a Lambertian one (glossy reflections \
             of indirect light are approximated); radiance_cache and the reference render them"
        );
    }
    let cut: Vec<String> = scene
        .materials
        .iter()
        .filter_map(|m| Some(format!("{} (cutoff {})", excerpt(&m.name), m.alpha_cutoff?)))
        .collect();
    if !cut.is_empty() {
        println!(
            "cut-outs     {} alpha-masked: {}",
            cut.len(),
            cut.join(", ")
        );
    }
    let bumped = scene
        .materials
        .iter()
        .filter(|m| m.normal_texture.is_some())
        .count();
    if bumped > 0 {
        println!("normal maps  {bumped} materials");
    }
    match &scene.sky {
        None => println!("sky          none (escaping rays see black)"),
        Some(illume_scene::Sky::Uniform { radiance }) => println!(
            "sky          uniform, L = ({:.3}, {:.3}, {:.3}) W/(m²·sr)",
            radiance.x, radiance.y, radiance.z
        ),
        Some(illume_scene::Sky::Equirect(map)) => println!(
            "sky          environment map {} ({}×{}, rotated {:.1}°), ∫L dω mean {:.3} W/m²",
            map.name,
            map.width,
            map.height,
            map.rotation_deg,
            channel_mean(map.integral())
        ),
    }
    println!(
        "bounds       ({:.3}, {:.3}, {:.3}) .. ({:.3}, {:.3}, {:.3}) m",
        b.min.x, b.min.y, b.min.z, b.max.x, b.max.y, b.max.z
    );
    let r = b.bounding_radius();
    println!("lights       {}", scene.lights.len());
    println!("units        {}", a.units.describe(&a.scene));
    for l in &scene.lights {
        let p = l.power(r);
        let kind = match l.kind {
            LightKind::Point { intensity } => format!(
                "point, I = ({:.3}, {:.3}, {:.3}) W/sr",
                intensity.x, intensity.y, intensity.z
            ),
            LightKind::Spot {
                intensity,
                inner_cone_rad,
                outer_cone_rad,
            } => format!(
                "spot, I = ({:.3}, {:.3}, {:.3}) W/sr, cones {:.1}°/{:.1}°",
                intensity.x,
                intensity.y,
                intensity.z,
                inner_cone_rad.to_degrees(),
                outer_cone_rad.to_degrees()
            ),
            LightKind::Directional { irradiance } => format!(
                "directional, E = ({:.3}, {:.3}, {:.3}) W/m²",
                irradiance.x, irradiance.y, irradiance.z
            ),
        };
        let pos = l.position();
        println!(
            "  {:<12} {kind}; at ({:.2}, {:.2}, {:.2}); power ({:.3}, {:.3}, {:.3}) W",
            excerpt(&l.name),
            pos.x,
            pos.y,
            pos.z,
            p.x,
            p.y,
            p.z
        );
    }
    let e = scene.emissive_power();
    println!("emissive     power ({:.3}, {:.3}, {:.3}) W", e.x, e.y, e.z);
    if scene.sky.is_some() {
        let k = scene.sky_power(r);
        println!(
            "sky power    ({:.3}, {:.3}, {:.3}) W through the scene's bounding sphere",
            k.x, k.y, k.z
        );
    }
    let t = scene.total_power();
    println!(
        "total power  ({:.3}, {:.3}, {:.3}) W (mean {:.3} W)",
        t.x,
        t.y,
        t.z,
        channel_mean(t)
    );
    println!("animations   {}", scene.animations.len());
    for (i, an) in scene.animations.iter().enumerate() {
        let active = if scene.active_animation == Some(i) {
            " (active)"
        } else {
            ""
        };
        println!(
            "  {:<12} {:.3} s, {} channels{active}",
            excerpt(&an.name),
            an.duration(),
            an.channels.len() + an.properties.len()
        );
        let mut nodes: Vec<String> = an
            .channels
            .iter()
            .map(|c| excerpt(&scene.nodes[c.node.index()].name))
            .collect();
        nodes.dedup();
        if !nodes.is_empty() {
            println!("               moves {}", nodes.join(", "));
        }
        for p in &an.properties {
            use illume_scene::PropertyTarget as P;
            let light = |l: illume_scene::LightId| excerpt(&scene.lights[l.index()].name);
            let material = |m: illume_scene::MaterialId| excerpt(&scene.materials[m.index()].name);
            let what = match p.target {
                P::LightIntensity { light: l, .. } => format!("light '{}' intensity", light(l)),
                P::LightColour { light: l, .. } => format!("light '{}' colour", light(l)),
                P::SpotInnerCone { light: l } => format!("light '{}' inner cone", light(l)),
                P::SpotOuterCone { light: l } => format!("light '{}' outer cone", light(l)),
                P::BaseColour { material: m } => format!("material '{}' base colour", material(m)),
                P::Emissive { material: m, .. } => format!("material '{}' emission", material(m)),
                P::Metallic { material: m } => format!("material '{}' metallic", material(m)),
                P::Roughness { material: m } => format!("material '{}' roughness", material(m)),
            };
            println!("               drives {what}");
        }
    }
    let c = &scene.camera;
    let cp = c.world_from_camera.translation;
    println!(
        "camera       '{}' at ({:.2}, {:.2}, {:.2}), vertical fov {:.1}°",
        excerpt(&c.name),
        cp.x,
        cp.y,
        cp.z,
        c.yfov_rad.to_degrees()
    );
    if !scene.warnings.is_empty() {
        println!("warnings     {}", scene.warnings.len());
    }
    Ok(())
}
