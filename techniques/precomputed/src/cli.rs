//! `illume precompute`: the offline part of `precomputed` (Bahnsen et al. 2012) — render
//! a day's indirect-light keys (or one shard of them, or of one adaptive level), merge
//! shards, describe a file. The registration's offline command
//! ([`illume_transport::Registration::OFFLINE`]): the CLI mounts it, and what it needs of
//! the app (configuration layers, scene loading, progress bars) comes through the
//! [`OfflineHost`].

use crate::file::PcFile;
use crate::settings::{Colour, PrecomputedSettings, ScheduleKind};
use crate::shard::{Shard, merge_level, precompute_level, precompute_shard};
use clap::{Args, FromArgMatches, Subcommand};
use illume_transport::{OfflineCommand, OfflineError, OfflineHost};
use std::path::PathBuf;
use std::time::Instant;

type Result<T> = std::result::Result<T, OfflineError>;

/// `illume precompute`, as the registration hands it to the CLI.
pub const OFFLINE: OfflineCommand = OfflineCommand {
    name: "precompute",
    command,
    run: run_matches,
};

/// The command as the CLI shows it, its `about` included.
#[derive(Subcommand)]
enum Mounted {
    /// Precompute a day of indirect light for the technique `precomputed` (or one shard
    /// of it with --shard K/N); `merge` shards; `info` describes a .illumepc file.
    Precompute(PrecomputeArgs),
}

/// The `precompute` subcommand.
fn command() -> clap::Command {
    let holder = Mounted::augment_subcommands(clap::Command::new("illume"));
    holder
        .find_subcommand("precompute")
        .cloned()
        .expect("Mounted declares `precompute`")
}

/// Runs the `precompute` subcommand given its matches.
fn run_matches(matches: &clap::ArgMatches, host: &dyn OfflineHost) -> Result<()> {
    run(PrecomputeArgs::from_arg_matches(matches)?, host)
}

/// An error with what was being done.
#[derive(Debug, thiserror::Error)]
#[error("{what}")]
struct Doing {
    what: String,
    #[source]
    source: std::io::Error,
}

/// `std::fs::create_dir_all(dir)`, its error saying which directory.
fn create_dir(dir: &std::path::Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|source| {
        Box::new(Doing {
            what: format!("creating {}", dir.display()),
            source,
        }) as OfflineError
    })
}

/// `illume precompute SCENE … --output FILE`, or `merge` / `info`.
#[derive(Args)]
#[command(
    args_conflicts_with_subcommands = true,
    after_help = "Sharding over machines (docs/techniques/precomputed.md, scripts/slurm/):
  uniform:  illume precompute SCENE --schedule uniform --shard K/N -o partK.illumepc   (K = 0…N−1)
            illume precompute merge part*.illumepc -o day.illumepc
  adaptive, level by level (level L's keys depend on the images of the levels before):
            illume precompute SCENE --level 0 --shard K/N -o l0_K.illumepc
            illume precompute merge l0_*.illumepc -o levels0.illumepc
            illume precompute SCENE --level 1 --previous levels0.illumepc --shard K/N -o l1_K.illumepc
            illume precompute merge l1_*.illumepc --previous levels0.illumepc -o levels1.illumepc
            … until a merge reports the schedule complete: it then writes the PCA file
            (`illume precompute info FILE` says `kind pca`). The result equals the
            unsharded run bit for bit."
)]
struct PrecomputeArgs {
    #[command(subcommand)]
    action: Option<Action>,
    #[command(flatten)]
    run: RunArgs,
}

#[derive(Subcommand)]
enum Action {
    /// Check that shard files agree, gather their keys and run the PCA (an adaptive
    /// level: write the merged levels so far, or the PCA file once no interval is left
    /// to split).
    Merge(MergeArgs),
    /// Describe a .illumepc file: keys, keys per hour, variance curve; --dump writes EXRs.
    Info(InfoArgs),
}

/// Rendering the keys.
#[derive(Args)]
struct RunArgs {
    /// Scene file (.gltf, .glb, .obj, .ply) or builtin:NAME (builtin:sun-room).
    scene: Option<PathBuf>,
    /// Latitude [degrees, north positive] (default: the scene's [sun], else 55.49).
    #[arg(long, allow_negative_numbers = true)]
    latitude: Option<f64>,
    /// Longitude [degrees, east positive] (default: the scene's [sun], else 9.47).
    #[arg(long, allow_negative_numbers = true)]
    longitude: Option<f64>,
    /// Date YYYY-MM-DD (default: the scene's [sun], else 2026-06-21).
    #[arg(long)]
    date: Option<String>,
    /// First clock hour [hours] (default 0).
    #[arg(long)]
    from: Option<f64>,
    /// Last clock hour [hours] (default 24).
    #[arg(long)]
    to: Option<f64>,
    /// screen (default: the fixed camera), cube (the camera may turn in place) or atlas
    /// (lightmap and probes: any camera; `--set precomputed.atlas_density=…`).
    #[arg(long)]
    domain: Option<String>,
    /// adaptive (default) or uniform.
    #[arg(long)]
    schedule: Option<String>,
    /// Key interval (uniform) or smallest interval (adaptive) [minutes] (default 5).
    #[arg(long)]
    step_min: Option<f64>,
    /// Samples per pixel of each key (default 256).
    #[arg(long)]
    spp: Option<u32>,
    /// PCA components k (default 10).
    #[arg(long)]
    components: Option<usize>,
    /// per-channel (default) or joint.
    #[arg(long)]
    colour: Option<String>,
    /// Image width [pixels] (default: the [render] table's).
    #[arg(long)]
    width: Option<u32>,
    /// Image height [pixels].
    #[arg(long)]
    height: Option<u32>,
    /// Render only the keys with index mod N = K into a partial file (merge them with
    /// `illume precompute merge`). The adaptive schedule shards one level at a time:
    /// give --level too.
    #[arg(long)]
    shard: Option<Shard>,
    /// Camera position X,Y,Z [m] (with --look-at), as in render: a `screen` or `cube`
    /// file holds this camera's view.
    #[arg(long, value_parser = illume_core::parse_point, requires = "look_at", allow_hyphen_values = true)]
    look_from: Option<illume_core::Vec3>,
    /// Point the camera looks at, X,Y,Z [m] (with --look-from).
    #[arg(long, value_parser = illume_core::parse_point, requires = "look_from", allow_hyphen_values = true)]
    look_at: Option<illume_core::Vec3>,
    /// A uniform sky of radiance R,G,B [W/(m²·sr)] at sky scale 1, replacing the
    /// scene's (render with the same --sky: the file's scene fingerprint holds it).
    #[arg(long, value_parser = illume_core::parse_radiance, value_name = "R,G,B", allow_hyphen_values = true)]
    sky: Option<illume_core::Vec3>,
    /// Adaptive schedule: render only level L's keys (0: the three first keys; L ≥ 1:
    /// the middles of the intervals the levels before split, found from --previous),
    /// into a partial file (all of them, or shard K/N's with --shard).
    #[arg(long, value_name = "L")]
    level: Option<u32>,
    /// With --level L ≥ 1: the merged file of levels 0…L−1 (what `precompute merge`
    /// wrote for level L−1). Must come from the same scene and settings.
    #[arg(long, value_name = "FILE", requires = "level")]
    previous: Option<PathBuf>,
    /// Take the sky images from FILE (another .illumepc of the same scene, --sky, image
    /// size, layout, spp and seed) instead of rendering them: the sky does not depend on
    /// the hours, and it costs about 1.3 keys (Sponza's atlas, 512 spp). Checked; what
    /// differs is named.
    /// Not with --shard or --level (shard 0 renders the sky there).
    #[arg(long, value_name = "FILE", conflicts_with_all = ["level", "shard"])]
    sky_from: Option<PathBuf>,
    /// Extra settings, as in render: `--set precomputed.KEY=VALUE`.
    #[arg(long = "set", value_name = "TABLE.KEY=VALUE")]
    sets: Vec<String>,
    /// Output file (.illumepc).
    #[arg(long, short)]
    output: Option<PathBuf>,
}

#[derive(Args)]
struct MergeArgs {
    /// The shard files (all N of one step: the uniform schedule, or one adaptive level).
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// Adaptive level L ≥ 1: the merged file of levels 0…L−1 the shards were given.
    /// The merge writes the levels 0…L file, or the final PCA file when no interval is
    /// left to split.
    #[arg(long, value_name = "FILE")]
    previous: Option<PathBuf>,
    /// Output file (.illumepc).
    #[arg(long, short)]
    output: PathBuf,
}

#[derive(Args)]
struct InfoArgs {
    /// The .illumepc file.
    file: PathBuf,
    /// Write each key as restored from the file, and the sky images, as EXR into DIR.
    #[arg(long)]
    dump: Option<PathBuf>,
    /// Also measure the mean HDR-FLIP between neighbouring lit keys as restored (noise
    /// between keys shows as change; slow for large files: one FLIP per key).
    #[arg(long)]
    flip: bool,
    /// Write the plots into DIR: `variance.svg` (captured variance vs k, Fig. 5) and
    /// `keys_per_hour.svg` (Fig. 6).
    #[arg(long)]
    plot: Option<PathBuf>,
}

/// Runs `illume precompute`.
fn run(a: PrecomputeArgs, host: &dyn OfflineHost) -> Result<()> {
    match a.action {
        Some(Action::Merge(m)) => run_merge(m, host),
        Some(Action::Info(i)) => run_info(i),
        None => run_precompute(a.run, host),
    }
}

fn run_precompute(a: RunArgs, host: &dyn OfflineHost) -> Result<()> {
    let scene_path = a
        .scene
        .clone()
        .ok_or("illume precompute: give a SCENE (or the subcommand merge / info)")?;
    let output = a
        .output
        .clone()
        .ok_or("illume precompute: give --output FILE")?;
    // Before hours of rendering: the output must be new or an earlier .illumepc, in a
    // folder that exists (created here if need be).
    crate::file::prepare_output(&output)?;
    let configured = host.settings(&a.sets)?;
    let (render_width, render_height) = configured.image_size;
    let mut s: PrecomputedSettings = *configured
        .settings
        .downcast()
        .expect("the host hands over this technique's settings");
    let width = a.width.unwrap_or(render_width);
    let height = a.height.unwrap_or(render_height);
    illume_render::check_image_size(width, height).map_err(|m| format!("--width/--height: {m}"))?;
    if let Some(v) = a.from {
        s.from_h = v;
    }
    if let Some(v) = a.to {
        s.to_h = v;
    }
    if let Some(v) = a.step_min {
        s.step_min = v;
    }
    if let Some(v) = a.spp {
        s.spp = v;
    }
    if let Some(v) = a.components {
        s.components = v;
    }
    if let Some(d) = &a.domain {
        s.domain = toml::Value::String(d.clone())
            .try_into()
            .map_err(|_| format!("--domain {d}: expected screen, cube or atlas"))?;
    }
    if let Some(v) = &a.schedule {
        s.schedule = match v.as_str() {
            "uniform" => ScheduleKind::Uniform,
            "adaptive" => ScheduleKind::Adaptive,
            _ => return Err(format!("--schedule {v}: expected adaptive or uniform").into()),
        };
    }
    if let Some(v) = &a.colour {
        s.colour = match v.as_str() {
            "per-channel" => Colour::PerChannel,
            "joint" => Colour::Joint,
            _ => return Err(format!("--colour {v}: expected per-channel or joint").into()),
        };
    }
    s.validate()?;
    let mut scene = host.load_scene(&scene_path)?;
    // The sun: the scene's [sun] with the flags on top (or the defaults).
    let mut sun = scene
        .sun
        .as_ref()
        .map(|p| p.settings.clone())
        .unwrap_or_default();
    if let Some(v) = a.latitude {
        sun.latitude_deg = v;
    }
    if let Some(v) = a.longitude {
        sun.longitude_deg = v;
    }
    if let Some(v) = &a.date {
        sun.date = v.clone();
    }
    if let Some(path) = scene.sun.take() {
        scene.sky = path.sky_base;
    }
    if let (Some(eye), Some(target)) = (a.look_from, a.look_at) {
        illume_scene::builtin::look_from(&mut scene, eye, target)
            .map_err(|m| format!("--look-from/--look-at: {m}"))?;
    }
    if let Some(radiance) = a.sky {
        scene.sky = Some(illume_scene::Sky::Uniform { radiance });
    }
    // The loader checked the scene; --sky changed it: the same checks as `render` makes,
    // on the sky at scale 1 (before the sun scales it: at night it would pass as 0). A
    // sky of 3e38 is a total power beyond any scene's.
    scene.validate().map_err(|m| {
        format!(
            "{}{}: {m}",
            scene.source,
            if a.sky.is_some() { " with --sky" } else { "" }
        )
    })?;
    scene.attach_sun(sun)?;
    let world = illume_transport::World::new(scene);
    let previous = match &a.previous {
        Some(p) => Some((p.clone(), PcFile::read(p)?)),
        None => None,
    };
    let sky_from = match &a.sky_from {
        Some(p) => {
            eprintln!(
                "precomputed sky: from {} (checked before the keys)",
                p.display()
            );
            Some((p.clone(), PcFile::read(p)?))
        }
        None => None,
    };
    let size = (width, height);
    // Every key is held for the PCA (a shard's until it is written): refuse, before
    // rendering any, keys that this machine cannot hold.
    let key_size = crate::domain::Layout::new(&world, &s, size)?.image_size();
    let span_keys = crate::file::most_keys(&s);
    let held = match (a.level, a.shard) {
        (None, Some(shard)) => span_keys.div_ceil(shard.count.max(1) as usize),
        _ => span_keys,
    };
    crate::file::check_keys_memory(held, key_size.0, key_size.1)
        .map_err(|m| format!("{}: {m}", output.display()))?;
    let start = Instant::now();
    let mut bars = host.progress("precomputed PCA");
    let file = match (s.schedule, a.level, a.shard) {
        (ScheduleKind::Uniform, Some(_), _) => {
            return Err(
                "--level is for the adaptive schedule; uniform keys shard with --shard K/N alone"
                    .into(),
            );
        }
        (ScheduleKind::Adaptive, None, Some(_)) => {
            return Err(
                "--shard with the adaptive schedule needs --level L: level L's keys depend on \
                 the images of the levels before, so it shards one level at a time (--level 0, \
                 merge, --level 1 --previous MERGED, … see `illume precompute --help`)"
                    .into(),
            );
        }
        (_, Some(level), shard) => precompute_level(
            &world,
            &s,
            size,
            level,
            previous.as_ref().map(|(p, f)| (p.as_path(), f)),
            shard.unwrap_or_default(),
            &mut *bars,
        )?,
        (_, None, Some(shard)) => precompute_shard(&world, &s, size, shard, &mut *bars)?,
        (_, None, None) => crate::precompute::precompute_with_sky(
            &world,
            &s,
            size,
            sky_from.as_ref().map(|(p, f)| (p.as_path(), f)),
            &mut *bars,
        )?,
    };
    bars.finish();
    file.write(&output)?;
    let bytes = std::fs::metadata(&output).map(|m| m.len()).unwrap_or(0);
    eprintln!(
        "{}: {} keys ({} dark), {:.1} s, {:.1} MB{}",
        output.display(),
        file.header.keys.len(),
        file.header.keys.iter().filter(|k| k.dark).count(),
        start.elapsed().as_secs_f64(),
        bytes as f64 / 1e6,
        match (a.level, a.shard) {
            (Some(l), sh) => format!(", level {l}, shard {}", sh.unwrap_or_default()),
            (None, Some(sh)) => format!(", shard {sh}"),
            (None, None) => String::new(),
        }
    );
    Ok(())
}

fn run_merge(m: MergeArgs, host: &dyn OfflineHost) -> Result<()> {
    crate::file::prepare_output(&m.output)?;
    let parts = m
        .parts
        .iter()
        .map(|p| Ok((p.clone(), PcFile::read(p)?)))
        .collect::<Result<Vec<_>>>()?;
    let previous = match &m.previous {
        Some(p) => Some((p.clone(), PcFile::read(p)?)),
        None => None,
    };
    if let Some((path, first)) = parts.first() {
        let h = &first.header;
        crate::file::check_keys_memory(h.keys.len(), h.width, h.height)
            .map_err(|m| format!("{}: {m}", path.display()))?;
    }
    let start = Instant::now();
    let mut spinner = host.progress("precomputed PCA");
    let file = merge_level(&parts, previous.as_ref().map(|(p, f)| (p.as_path(), f)))?;
    spinner.finish();
    file.write(&m.output)?;
    if file.header.kind == "levels" {
        let level = file.header.keys.iter().map(|k| k.level).max().unwrap_or(0);
        eprintln!(
            "{}: merged {} shards: levels 0–{level}, {} keys; next: --level {} --previous {}",
            m.output.display(),
            parts.len(),
            file.header.keys.len(),
            level + 1,
            m.output.display()
        );
    } else {
        eprintln!(
            "{}: merged {} shards, {} keys, k = {}, PCA {:.2} s",
            m.output.display(),
            parts.len(),
            file.header.keys.len(),
            file.header.components,
            start.elapsed().as_secs_f64()
        );
    }
    Ok(())
}

fn run_info(i: InfoArgs) -> Result<()> {
    let start = Instant::now();
    let file = PcFile::read(&i.file)?;
    let load_s = start.elapsed().as_secs_f64();
    let h = &file.header;
    let bytes = std::fs::metadata(&i.file).map(|m| m.len()).unwrap_or(0);
    println!(
        "file        {} ({:.2} MB, read in {load_s:.3} s)",
        i.file.display(),
        bytes as f64 / 1e6
    );
    let top_level = h.keys.iter().map(|k| k.level).max().unwrap_or(0);
    match h.kind.as_str() {
        "levels" => println!(
            "kind        levels (adaptive levels 0–{top_level} merged; next: --level {})",
            top_level + 1
        ),
        _ => println!(
            "kind        {} (shard {}/{})",
            h.kind, h.shard[0], h.shard[1]
        ),
    }
    println!(
        "scene       {} (fingerprint {})",
        h.scene_source, h.scene_fingerprint
    );
    println!("domain      {} {}×{}", h.domain, h.width, h.height);
    if let Some(a) = &h.atlas {
        println!(
            "atlas       {}×{} lightmap at {} texels/m, {}×{}×{} probes {} m apart",
            a.lightmap[0],
            a.lightmap[1],
            a.density,
            a.probe_dims[0],
            a.probe_dims[1],
            a.probe_dims[2],
            a.probe_spacing
        );
    }
    println!("exposure    {}", h.exposure);
    let dark = h.keys.iter().filter(|k| k.dark).count();
    println!(
        "keys        {} ({} dark, {} in the PCA)",
        h.keys.len(),
        dark,
        h.keys.len() - dark
    );
    // Keys per clock hour (Fig. 6).
    let mut per_hour = std::collections::BTreeMap::<i64, usize>::new();
    for k in h.keys.iter().filter(|k| !k.dark) {
        *per_hour.entry(k.hours.floor() as i64).or_default() += 1;
    }
    let line: Vec<String> = per_hour
        .iter()
        .map(|(hr, n)| format!("{hr:02}h:{n}"))
        .collect();
    println!("keys/hour   {}", line.join(" "));
    println!("components  {} ({})", h.components, h.colour);
    for (g, eig) in h.eigenvalues.iter().enumerate() {
        let curve: Vec<String> = [1, 2, 5, 10, 20]
            .iter()
            .filter(|&&k| k <= eig.len())
            .map(|&k| {
                format!(
                    "k={k}: {:.2} %",
                    100.0 * crate::pca::variance_captured(eig, k)
                )
            })
            .collect();
        println!("variance[{g}] {}", curve.join(", "));
    }
    if let Some(c) = file.compression() {
        println!(
            "compression {:.1} % of the bytes (raw keys {:.2} MB, stored {:.2} MB); \
             {:.1} % of the keys' values (the paper's measure: components, coefficients \
             and means against the lit keys; the sky's images stored beside, as its \
             skylight image)",
            100.0 * c.of_bytes(),
            c.raw_bytes / 1e6,
            c.stored_bytes / 1e6,
            100.0 * c.of_key_values()
        );
    }
    if i.flip && h.kind == "pca" {
        match flip_between_keys(&file)? {
            Some((mean, max, pairs)) => println!(
                "between keys HDR-FLIP mean {mean:.4}, max {max:.4} ({pairs} pairs of \
                 neighbouring lit keys, restored at k = {})",
                h.components
            ),
            None => println!("between keys (fewer than two lit keys)"),
        }
    }
    if let Some(dir) = &i.dump {
        dump(&file, dir)?;
    }
    if let Some(dir) = &i.plot {
        create_dir(dir)?;
        let names = ["r", "g", "b"];
        let series: Vec<illume_metrics::report::Series> = h
            .eigenvalues
            .iter()
            .enumerate()
            .map(|(g, eig)| illume_metrics::report::Series {
                name: if h.eigenvalues.len() == 1 {
                    "rgb".into()
                } else {
                    names.get(g).copied().unwrap_or("?").into()
                },
                points: (1..=eig.len().min(40))
                    .map(|k| (k as f64, 100.0 * crate::pca::variance_captured(eig, k)))
                    .collect(),
            })
            .collect();
        illume_metrics::report::plot_lines(
            &dir.join("variance.svg"),
            "variance captured by the first k eigenvectors",
            "k",
            "variance [%]",
            &series,
        )?;
        let bars: Vec<illume_metrics::report::Bar> = (0..24)
            .map(|hr| illume_metrics::report::Bar {
                label: format!("{hr:02}"),
                value: per_hour.get(&hr).copied().unwrap_or(0) as f64,
            })
            .collect();
        // Beside the sun's elevation at each hour's middle (issue 36 goal 2: keys follow
        // the light), when the file's `[sun]` table is one the sun model reads.
        let path = dir.join("keys_per_hour.svg");
        let title = "keys per clock hour";
        match sun_elevations(&h.sun) {
            Some(values) => illume_metrics::report::plot_bars_and_line(
                &path,
                title,
                "keys",
                &bars,
                &illume_metrics::report::BarLine {
                    name: "sun elevation".into(),
                    y_label: "sun elevation [degrees]".into(),
                    values,
                },
            )?,
            None => illume_metrics::report::plot_bars(&path, title, "keys", &bars)?,
        }
        eprintln!(
            "wrote variance.svg and keys_per_hour.svg into {}",
            dir.display()
        );
    }
    Ok(())
}

/// The sun's elevation \[degrees\] at the middle of each clock hour 0–23 for a file's
/// `[sun]` table; `None` when the table does not describe a sun the model can place.
fn sun_elevations(sun: &toml::Table) -> Option<Vec<f64>> {
    let settings: illume_scene::sun::SunSettings = sun.clone().try_into().ok()?;
    (0..24)
        .map(|hr| {
            illume_scene::sun::solar_position(&settings, hr as f64 + 0.5)
                .ok()
                .map(|p| p.elevation_deg)
        })
        .collect()
}

/// Key `t` as restored from a `pca` file: mean + Σ images · coefficients, clamped at 0.
fn restored_key(file: &PcFile, t: usize) -> Result<illume_core::image::RgbImage> {
    use illume_core::Rgb;
    use illume_core::image::RgbImage;
    let h = &file.header;
    let pixels = h.width as usize * h.height as usize;
    let keys = h.keys.len();
    let k = h.components as usize;
    let joint = h.colour == "joint";
    let names: &[&str] = if joint { &["rgb"] } else { &["r", "g", "b"] };
    let section = |name: &str| {
        file.section(name)
            .map(|s| s.values.as_slice())
            .ok_or_else(|| format!("{}: section {name} missing", h.scene_source))
    };
    let mut px = vec![Rgb::ZERO; pixels];
    for (g, name) in names.iter().enumerate() {
        let mean = section(&format!("mean.{name}"))?;
        let temporal = section(&format!("temporal.{name}"))?;
        let images = section(&format!("images.{name}"))?;
        let rows = if joint { 3 * pixels } else { pixels };
        for r in 0..rows {
            let mut v = mean.get(t).copied().unwrap_or(0.0);
            for c in 0..k {
                v += images.get(c * rows + r).copied().unwrap_or(0.0)
                    * temporal.get(c * keys + t).copied().unwrap_or(0.0);
            }
            let (p, ch) = if joint { (r / 3, r % 3) } else { (r, g) };
            px[p][ch] = v.max(0.0);
        }
    }
    Ok(RgbImage::from_vec(h.width, h.height, px).ok_or("image size")?)
}

/// Mean HDR-FLIP between neighbouring lit keys as restored from a `pca` file (the
/// earlier key the reference), and the largest: noise between keys shows here as change.
/// `None` with fewer than two lit keys.
fn flip_between_keys(file: &PcFile) -> Result<Option<(f64, f64, usize)>> {
    let lit: Vec<usize> = (0..file.header.keys.len())
        .filter(|&t| !file.header.keys[t].dark)
        .collect();
    let mut flips = Vec::new();
    let mut previous = None;
    for &t in &lit {
        let key = restored_key(file, t)?;
        if let Some(before) = &previous {
            let flip = illume_metrics::hdr_flip(before, &key, &Default::default())?;
            flips.push(flip.map.mean());
        }
        previous = Some(key);
    }
    if flips.is_empty() {
        return Ok(None);
    }
    let mean = flips.iter().sum::<f64>() / flips.len() as f64;
    let max = flips.iter().copied().fold(0.0, f64::max);
    Ok(Some((mean, max, flips.len())))
}

/// Restored keys ([`restored_key`]) and the sky (and its direct share) as EXR.
fn dump(file: &PcFile, dir: &std::path::Path) -> Result<()> {
    use illume_core::Rgb;
    use illume_core::image::RgbImage;
    create_dir(dir)?;
    let h = &file.header;
    for t in 0..h.keys.len() {
        let img = restored_key(file, t)?;
        let path = dir.join(format!("key_{t:03}_{:05.2}h.exr", h.keys[t].hours));
        img.write(&path, &Default::default())?;
    }
    for (name, out) in [
        ("sky", "sky.exr"),
        (crate::precompute::SKY_DIRECT, "sky_direct.exr"),
    ] {
        let Some(sky) = file.section(name) else {
            continue;
        };
        let px = sky
            .values
            .chunks_exact(3)
            .map(|c| Rgb::new(c[0], c[1], c[2]))
            .collect();
        let img = RgbImage::from_vec(h.width, h.height, px).ok_or("image size")?;
        img.write(&dir.join(out), &Default::default())?;
    }
    eprintln!(
        "wrote {} keys and the sky into {}",
        h.keys.len(),
        dir.display()
    );
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The plot's elevation line: the default sun (Koldinghus, 21 June, UTC+2) peaks at
    /// 90° − 55.49° + 23.44° ≈ 57.9° shortly after 13:00 local time and is below the
    /// horizon at midnight; a table the sun model does not read gives no line.
    #[test]
    fn the_suns_elevation_per_hour_follows_the_files_sun() {
        let table: toml::Table =
            toml::Table::try_from(illume_scene::sun::SunSettings::default()).unwrap();
        let e = sun_elevations(&table).unwrap();
        assert_eq!(e.len(), 24);
        let (peak_hour, peak) = e
            .iter()
            .enumerate()
            .fold((0, f64::MIN), |b, (h, &v)| if v > b.1 { (h, v) } else { b });
        assert_eq!(peak_hour, 13, "{e:?}");
        assert!((peak - 57.9).abs() < 1.0, "{peak}");
        assert!(e[0] < 0.0 && e[23] < 0.0, "{e:?}");
        let mut bad = table.clone();
        bad.insert("date".into(), toml::Value::String("not a date".into()));
        assert!(sun_elevations(&bad).is_none());
        bad = table;
        bad.insert("no_such_key".into(), toml::Value::Integer(1));
        assert!(sun_elevations(&bad).is_none());
    }
}
