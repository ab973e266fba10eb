//! Selective photon tracing's headline measurements in kind of the paper's §7, printed
//! as tables (recorded in BENCHMARKS.md):
//!
//! * `fig5` — relevant photons (those whose path changed) found as groups are
//!   re-traced after the sphere of `builtin:cornell-spot` moves, for N_g = 72 (this
//!   one-light scene's default), 288 (the paper's ROOM) and 10 080, the sphere lit directly (in the spot's
//!   cone) or only indirectly (outside it), priority order beside random order;
//! * `fig7` — the same for R = 8, 16, 32, 64 at an equal pool;
//! * `room` — Fig. 5 (N_g = 288 and 10 080) and Fig. 7 (R = 8 … 64) on `builtin:room`
//!   (ROOM in kind: four spot lights, ≈ 12 400 elements) with the paper's pool of
//!   1 152 000 photons, the table pushed 0.6 m (issue 34 goal 3);
//! * `house` — the same on `builtin:house` (HOUSE in kind: three rooms, two spot lights,
//!   ≈ 377 900 elements) with its pool of 1 728 000 photons and N_g = 144 (2^4·3^2);
//! * `pool` — recovery against pool size (N_p = 125 … 2000 at N_g = 72, R = 16);
//! * `costs` — pool fill, full update after the move, restart vs re-trace after a light
//!   move, memory per element;
//! * `elements` — the element mesh on Dabrovic Sponza (66 k triangles) and
//!   `builtin:cornell-spot` for `element_max_side` off (default), 1/32, 1/64 and 1/128, with
//!   `min_photons_per_element` 16: elements,
//!   grid sides, hanging vertices, the scaled pool, memory and the display's cost per
//!   element (issue 34).
//!
//! `cargo bench -p illume-selective [-- fig5|fig7|room|house|pool|costs|elements]`

use illume_core::{Affine3A, Vec3};
use illume_scene::{Edit, InstanceId, LightId};
use illume_selective::{GroupOrder, Selective, SelectiveSettings};
use illume_transport::{Technique, World};
use std::time::Instant;

fn instance(world: &World, name: &str) -> InstanceId {
    InstanceId(
        world
            .scene
            .instances
            .iter()
            .position(|i| i.name == name)
            .unwrap_or_else(|| panic!("{} has no instance {name}", world.scene.source))
            as u32,
    )
}

fn base(factors: Vec<[u32; 2]>, pilots: u32, ratio: u32, order: GroupOrder) -> SelectiveSettings {
    SelectiveSettings {
        group_factors: factors,
        pilots_per_group: pilots,
        ratio,
        order,
        warm_up: false,
        ..SelectiveSettings::deterministic()
    }
}

/// What moves: a built-in scene and the instance in it.
#[derive(Clone, Copy)]
struct Mover {
    scene: &'static str,
    instance: &'static str,
}

/// `builtin:cornell-spot`'s sphere.
const SPHERE: Mover = Mover {
    scene: "cornell-spot",
    instance: "sphere",
};

/// `builtin:room`'s table (ROOM in kind).
const TABLE: Mover = Mover {
    scene: "room",
    instance: "table",
};

/// The sphere moved from `from` to `to` (world offsets from its place in the scene).
fn moved_world(from: Vec3, to: Vec3) -> (World, World, Vec<illume_scene::SceneChange>) {
    moved(SPHERE, from, to)
}

/// `mover` moved from `from` to `to` (world offsets from its place in the scene).
fn moved(mover: Mover, from: Vec3, to: Vec3) -> (World, World, Vec<illume_scene::SceneChange>) {
    let mut old = World::new(illume_scene::builtin::load(mover.scene).unwrap());
    let s = instance(&old, mover.instance);
    let at = old.scene.instances[s.index()].world_from_object;
    old.apply_edit(&Edit::SetInstanceTransform {
        instance: s,
        world_from_object: Affine3A::from_translation(from) * at,
    })
    .unwrap();
    let mut new = old.with_scene(old.scene.clone());
    let changes = new
        .apply_edit(&Edit::SetInstanceTransform {
            instance: s,
            world_from_object: Affine3A::from_translation(to) * at,
        })
        .unwrap();
    (old, new, changes)
}

/// How an update went: the fraction of all relevant photons found after 10, 25, 50 %
/// of the groups, the seconds to find 90 % of them, the relevant total, and the curve
/// (seconds since the edit, fraction found) after each group.
struct Recovery {
    at: [f64; 3],
    t90: f64,
    total: u64,
    curve: Vec<(f64, f64)>,
}

fn recovery(settings: &SelectiveSettings, from: Vec3, to: Vec3) -> Recovery {
    recovery_of(SPHERE, settings, from, to)
}

fn recovery_of(mover: Mover, settings: &SelectiveSettings, from: Vec3, to: Vec3) -> Recovery {
    let (old, new, changes) = moved(mover, from, to);
    let mut sel = Selective::for_world(&old, settings.clone()).unwrap();
    sel.converge(&old);
    sel.scene_changed(&new, &changes);
    let n_g = sel.layout().groups;
    let mut found = Vec::with_capacity(n_g as usize);
    let mut times = Vec::with_capacity(n_g as usize);
    let t0 = Instant::now();
    let start = sel.counters().photons_invalid;
    while sel.stale_groups() > 0 {
        sel.step(&new);
        found.push(sel.counters().photons_invalid - start);
        times.push(t0.elapsed().as_secs_f64());
    }
    let total = *found.last().unwrap_or(&0);
    let fraction = |f: u64| f as f64 / total.max(1) as f64;
    let at = |f: f64| {
        let k = ((n_g as f64 * f).ceil() as usize).clamp(1, found.len()) - 1;
        fraction(found[k])
    };
    let t90 = found
        .iter()
        .position(|&f| f as f64 >= 0.9 * total as f64)
        .map_or(f64::NAN, |k| times[k]);
    let curve = std::iter::once((0.0, 0.0))
        .chain(times.iter().zip(&found).map(|(&t, &f)| (t, fraction(f))))
        .collect();
    Recovery {
        at: [at(0.10), at(0.25), at(0.50)],
        t90,
        total,
        curve,
    }
}

/// Where the recovery plots go: `target/selective-bench/` of the workspace.
fn plot_dir() -> std::path::PathBuf {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../target/selective-bench");
    std::fs::create_dir_all(&dir).expect("the plot folder can be made");
    dir
}

fn plot(name: &str, title: &str, series: Vec<illume_metrics::report::Series>) {
    let path = plot_dir().join(name);
    illume_metrics::report::plot_lines(
        &path,
        title,
        "seconds since the edit (2 threads)",
        "fraction of relevant photons re-traced",
        &series,
    )
    .expect("the plot is written");
    println!("(plot: {})", path.display());
}

fn fig5() {
    println!(
        "\n## fig5: relevant photons found vs groups re-traced (cornell-spot, sphere moved 0.3 m)"
    );
    println!(
        "| N_g | sphere | order | found @10 % | @25 % | @50 % of groups | s to 90 % | relevant |"
    );
    println!("|---|---|---|---:|---:|---:|---:|---:|");
    // Under the spot (lit directly) and in the corner away from the cone (indirectly).
    let cases = [
        ("direct", Vec3::ZERO, Vec3::new(0.3, 0.0, 0.0)),
        (
            "indirect",
            Vec3::new(-0.55, 0.0, 0.6),
            Vec3::new(-0.55, 0.0, 0.3),
        ),
    ];
    for (lit, from, to) in cases {
        let mut series = Vec::new();
        // Pools of N_g · N_p · 16 photons: 1 152 000 for N_g = 72 and 288; 1 290 240 for
        // N_g = 10 080 (N_p = 8 is the nearest whole number, 12 % more photons).
        for (name, factors, pilots) in [
            ("72 (2^3·3^2)", vec![[2, 3], [3, 2]], 1000),
            ("288 (2^5·3^2)", vec![[2, 5], [3, 2]], 250),
            ("10 080", vec![[2, 5], [3, 2], [5, 1], [7, 1]], 8),
        ] {
            for order in [GroupOrder::Priority, GroupOrder::Random] {
                let s = base(factors.clone(), pilots, 16, order);
                let r = recovery(&s, from, to);
                println!(
                    "| {name} | {lit} | {order:?} | {:.2} | {:.2} | {:.2} | {:.2} | {} |",
                    r.at[0], r.at[1], r.at[2], r.t90, r.total
                );
                series.push(illume_metrics::report::Series {
                    name: format!("N_g = {name}, {order:?}"),
                    points: r.curve,
                });
            }
        }
        plot(
            &format!("fig5_{lit}.svg"),
            &format!("Fig. 5 in kind: sphere lit {lit}ly, moved 0.3 m"),
            series,
        );
    }
}

fn fig7() {
    println!(
        "\n## fig7: pilot ratio R at an equal pool (N_g = 72, N = 1 152 000, sphere lit directly)"
    );
    println!("| R | N_p | pilots | found @10 % | @25 % | @50 % of groups | s to 90 % |");
    println!("|---:|---:|---:|---:|---:|---:|---:|");
    let mut series = Vec::new();
    for ratio in [8u32, 16, 32, 64] {
        let pilots = 16_000 / ratio;
        let s = base(vec![[2, 3], [3, 2]], pilots, ratio, GroupOrder::Priority);
        let r = recovery(&s, Vec3::ZERO, Vec3::new(0.3, 0.0, 0.0));
        println!(
            "| {ratio} | {pilots} | {:.2} % | {:.2} | {:.2} | {:.2} | {:.2} |",
            100.0 / ratio as f64,
            r.at[0],
            r.at[1],
            r.at[2],
            r.t90
        );
        series.push(illume_metrics::report::Series {
            name: format!("R = {ratio} ({:.2} % pilots)", 100.0 / ratio as f64),
            points: r.curve,
        });
    }
    plot(
        "fig7.svg",
        "Fig. 7 in kind: pilot ratio at an equal pool (N = 1 152 000)",
        series,
    );
}

/// A paper scene in kind for Fig. 5 and Fig. 7: the scene and its mover, the paper's
/// factorisation and pool, and the element count the paper gives.
struct PaperScene {
    /// Section name and plot prefix (`room`, `house`).
    name: &'static str,
    /// What the section's title says the scene is.
    title: &'static str,
    mover: Mover,
    /// The paper's N_g factorisation and its name.
    factors: &'static [[u32; 2]],
    groups_label: &'static str,
    /// The paper's pool N = N_g·N_p·16.
    pool: u64,
    /// Mesh elements (`element_count`).
    elements: u32,
}

/// Fig. 5 and Fig. 7 on `scene` (the table pushed 0.6 m), with the paper's pool and its
/// N_g beside 10 080 (Fig. 5), and R = 8 … 64 at that N_g and an equal pool (Fig. 7).
fn paper_figures(scene: &PaperScene) {
    println!(
        "\n## {}: Fig. 5 and Fig. 7 on builtin:{} ({}), the table pushed 0.6 m",
        scene.name, scene.mover.scene, scene.title
    );
    println!(
        "| N_g | R | N_p | pool | order | found @10 % | @25 % | @50 % of groups | s to 90 % | all groups [s] | relevant |"
    );
    println!("|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|");
    let to = Vec3::new(0.6, 0.0, 0.0);
    let run = |name: &str, factors: Vec<[u32; 2]>, pilots: u32, ratio: u32, order| {
        let s = SelectiveSettings {
            element_count: scene.elements,
            // The paper's pool, not one grown to 16 photons an element.
            min_photons_per_element: 0,
            min_impacts_per_element: 0,
            ..base(factors, pilots, ratio, order)
        };
        let r = recovery_of(scene.mover, &s, Vec3::ZERO, to);
        let groups: u64 = s
            .group_factors
            .iter()
            .map(|f| (f[0] as u64).pow(f[1]))
            .product();
        println!(
            "| {name} | {ratio} | {pilots} | {} | {order:?} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {} |",
            groups * (pilots * ratio) as u64,
            r.at[0],
            r.at[1],
            r.at[2],
            r.t90,
            r.curve.last().map_or(f64::NAN, |c| c.0),
            r.total
        );
        r.curve
    };
    let groups: u64 = scene
        .factors
        .iter()
        .map(|f| (f[0] as u64).pow(f[1]))
        .product();
    // N_p for `g` groups at R: the whole number that keeps the pool at most the paper's
    // (ROOM: 10 080 groups N_p = 7, 1 128 960 photons; R = 64 N_p = 62, 1 142 784).
    let pilots = |g: u64, ratio: u32| (scene.pool / (g * ratio as u64)) as u32;
    // Fig. 5: the paper's N_g and 10 080 (2^5·3^2·5·7), priority and random order.
    let mut series = Vec::new();
    for (name, factors) in [
        (scene.groups_label, scene.factors.to_vec()),
        ("10 080", vec![[2, 5], [3, 2], [5, 1], [7, 1]]),
    ] {
        let g: u64 = factors.iter().map(|f| (f[0] as u64).pow(f[1])).product();
        for order in [GroupOrder::Priority, GroupOrder::Random] {
            series.push(illume_metrics::report::Series {
                name: format!("N_g = {name}, {order:?}"),
                points: run(name, factors.clone(), pilots(g, 16), 16, order),
            });
        }
    }
    plot(
        &format!("{}_fig5.svg", scene.name),
        &format!(
            "Fig. 5 on {} in kind: the table pushed 0.6 m (N = {})",
            scene.name.to_uppercase(),
            scene.pool
        ),
        series,
    );
    // Fig. 7: R = 8 … 64 at the paper's N_g and an equal pool.
    let mut series = Vec::new();
    for ratio in [8u32, 16, 32, 64] {
        series.push(illume_metrics::report::Series {
            name: format!("R = {ratio} ({:.2} % pilots)", 100.0 / ratio as f64),
            points: run(
                scene.groups_label,
                scene.factors.to_vec(),
                pilots(groups, ratio),
                ratio,
                GroupOrder::Priority,
            ),
        });
    }
    plot(
        &format!("{}_fig7.svg", scene.name),
        &format!(
            "Fig. 7 on {} in kind: pilot ratio at N_g = {} (N = {})",
            scene.name.to_uppercase(),
            scene.groups_label,
            scene.pool
        ),
        series,
    );
}

/// ROOM in kind (`builtin:room`: four spot lights, ≈ 12 400 elements, N_g = 2^5·3^2,
/// 1 152 000 photons).
const ROOM: PaperScene = PaperScene {
    name: "room",
    title: "four spot lights",
    mover: TABLE,
    factors: &[[2, 5], [3, 2]],
    groups_label: "288 (2^5·3^2)",
    pool: 1_152_000,
    elements: 12_400,
};

/// HOUSE in kind (`builtin:house`: three rooms, two spot lights, ≈ 377 900 elements,
/// N_g = 2^4·3^2, 1 728 000 photons).
const HOUSE: PaperScene = PaperScene {
    name: "house",
    title: "three rooms, two spot lights",
    mover: Mover {
        scene: "house",
        instance: "table",
    },
    factors: &[[2, 4], [3, 2]],
    groups_label: "144 (2^4·3^2)",
    pool: 1_728_000,
    elements: 377_900,
};

fn pool() {
    println!(
        "\n## pool: recovery against pool size (N_g = 72, R = 16, sphere moved 0.3 m, lit directly)"
    );
    println!("| N_p | pool | fill [s] | s to 90 % | all groups current [s] | relevant |");
    println!("|---:|---:|---:|---:|---:|---:|");
    for pilots in [125u32, 250, 500, 1000, 2000] {
        let s = base(Vec::new(), pilots, 16, GroupOrder::Priority);
        let (old, new, changes) = moved_world(Vec3::ZERO, Vec3::new(0.3, 0.0, 0.0));
        let mut sel = Selective::for_world(&old, s.clone()).unwrap();
        let t = Instant::now();
        sel.converge(&old);
        let fill = t.elapsed().as_secs_f64();
        drop(sel);
        let r = recovery(&s, Vec3::ZERO, Vec3::new(0.3, 0.0, 0.0));
        let (t90, total) = (r.t90, r.total);
        let mut sel = Selective::for_world(&old, s).unwrap();
        sel.converge(&old);
        sel.scene_changed(&new, &changes);
        let t = Instant::now();
        sel.converge(&new);
        println!(
            "| {pilots} | {} | {fill:.3} | {t90:.3} | {:.3} | {total} |",
            sel.layout().pool(),
            t.elapsed().as_secs_f64()
        );
    }
}

fn costs() {
    println!(
        "\n## costs (cornell-spot, N_g = 72, N_p = 1000, R = 16: 1 152 000 photons, 12 400 elements)"
    );
    let s = base(Vec::new(), 1000, 16, GroupOrder::Priority);
    let (old, new, changes) = moved_world(Vec3::ZERO, Vec3::new(0.3, 0.0, 0.0));
    let t = Instant::now();
    let mut sel = Selective::for_world(&old, s.clone()).unwrap();
    sel.converge(&old);
    let fill = t.elapsed().as_secs_f64();
    let rays_fill = sel.counters().rays;
    sel.scene_changed(&new, &changes);
    let before = sel.counters();
    let t = Instant::now();
    sel.converge(&new);
    let update = t.elapsed().as_secs_f64();
    let after = sel.counters();
    let invalid = after.photons_invalid - before.photons_invalid;
    let per_photon_fill = rays_fill as f64 / sel.layout().pool() as f64;
    println!("| what | value |");
    println!("|---|---:|");
    println!(
        "| fill the pool | {fill:.3} s ({:.2} M photons/s) |",
        sel.layout().pool() as f64 / fill / 1e6
    );
    println!(
        "| update after the sphere move (all {} groups) | {update:.3} s = {:.2} × a fill |",
        sel.layout().groups,
        update / fill
    );
    println!(
        "| photons found invalid | {invalid} ({:.2} %) |",
        100.0 * invalid as f64 / sel.layout().pool() as f64
    );
    println!(
        "| rays per pool photon: fill / update | {per_photon_fill:.2} / {:.2} |",
        (after.rays - before.rays) as f64 / sel.layout().pool() as f64
    );
    println!(
        "| memory: accumulators per element | {} B (+ display grid) |",
        2 * std::mem::size_of::<illume_transport::flux::Quanta>()
    );
    // Light move: re-trace (restart_fraction 1) vs restart (default).
    for (name, fraction) in [("re-trace", 1.0f32), ("restart", 0.5)] {
        let settings = SelectiveSettings {
            restart_fraction: fraction,
            ..s.clone()
        };
        let mut w = World::new(illume_scene::builtin::load("cornell-spot").unwrap());
        let mut sel = Selective::for_world(&w, settings).unwrap();
        sel.converge(&w);
        let node = w.scene.lights[0].node;
        let at = w.scene.nodes[node.index()].world_from_node;
        let changes = w
            .apply_edit(&Edit::SetLightTransform {
                light: LightId(0),
                world_from_light: Affine3A::from_translation(Vec3::new(0.2, 0.0, 0.0)) * at,
            })
            .unwrap();
        let t = Instant::now();
        sel.scene_changed(&w, &changes);
        sel.converge(&w);
        println!(
            "| light moved, {name} until current | {:.3} s |",
            t.elapsed().as_secs_f64()
        );
    }
}

fn main() {
    let args: Vec<String> = std::env::args()
        .skip(1)
        .filter(|a| !a.starts_with("--"))
        .collect();
    let want = |name: &str| args.is_empty() || args.iter().any(|a| a == name);
    println!(
        "machine: {} threads available",
        std::thread::available_parallelism().map_or(0, |n| n.get())
    );
    if want("fig5") {
        fig5();
    }
    if want("fig7") {
        fig7();
    }
    if want("room") {
        paper_figures(&ROOM);
    }
    if want("house") {
        paper_figures(&HOUSE);
    }
    if want("pool") {
        pool();
    }
    if want("costs") {
        costs();
    }
    if want("elements") {
        elements();
    }
}

fn elements() {
    println!(
        "\n## elements: the element mesh by `element_max_side` (element_count 12 400, min_photons_per_element 16)"
    );
    println!(
        "| scene | max side | triangles | elements | split triangles | largest k | hanging vertices | pool (N_p) | photons / element | memory [MB] | build [s] | display [ms] | display per element [ns] |"
    );
    println!("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|");
    let sponza = illume_scene::shared_scenes_dir().join("dabrovic_sponza/sponza.obj");
    let scenes = [
        (
            "cornell-spot",
            illume_scene::builtin::load("cornell-spot").unwrap(),
        ),
        (
            "Dabrovic Sponza",
            illume_scene::load::load_scene(&sponza).unwrap(),
        ),
    ];
    for (name, mut scene) in scenes {
        scene.set_time(0.0);
        let world = World::new(scene);
        for max_side in [0.0f32, 1.0 / 32.0, 1.0 / 64.0, 1.0 / 128.0] {
            let settings = SelectiveSettings {
                element_max_side: max_side,
                min_photons_per_element: 16,
                min_impacts_per_element: 0,
                ..SelectiveSettings::deterministic()
            };
            let t = Instant::now();
            let sel = Selective::for_world(&world, settings).unwrap();
            let build = t.elapsed().as_secs_f64();
            let el = sel.elements();
            let triangles: usize = el.grids.iter().map(|g| g.k.len()).sum();
            let split: usize = el
                .grids
                .iter()
                .map(|g| g.k.iter().filter(|&&k| k > 1).count())
                .sum();
            let kmax = el
                .grids
                .iter()
                .flat_map(|g| g.k.iter().copied())
                .max()
                .unwrap_or(1);
            let hanging: usize = el.grids.iter().map(|g| g.hanging.len()).sum();
            let vertices: usize = el.grids.iter().map(|g| g.vertex_count as usize).sum();
            let memory = el.len() * 2 * std::mem::size_of::<illume_transport::flux::Quanta>()
                + vertices * (2 * std::mem::size_of::<illume_core::Rgb>() + 4);
            let reps = 5;
            let t = Instant::now();
            for _ in 0..reps {
                std::hint::black_box(sel.display(&world));
            }
            let display = t.elapsed().as_secs_f64() / reps as f64;
            println!(
                "| {name} | {} | {triangles} | {} | {split} | {kmax} | {hanging} | {} ({}) | {:.0} | {:.1} | {build:.2} | {:.1} | {:.0} |",
                if max_side > 0.0 {
                    format!("1/{:.0}", 1.0 / max_side)
                } else {
                    "off".into()
                },
                el.len(),
                sel.layout().pool(),
                sel.layout().pilots,
                sel.layout().pool() as f64 / el.len() as f64,
                memory as f64 / 1e6,
                display * 1e3,
                display * 1e9 / el.len() as f64,
            );
        }
    }
}
