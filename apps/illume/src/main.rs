//! `illume` — the command line of the illume global-illumination engine.
//!
//! * `illume render SCENE` — one image (reference path tracer or a technique);
//! * `illume info SCENE` — what a scene holds (triangles, instances, lights and power);
//! * `illume compare A B` — image metrics between two images or two frame folders;
//! * `illume animate SCENE` — an animation: numbered frames, a preview, a per-frame CSV;
//! * `illume demo` — photon streaming on `builtin:cornell-spot` in real time.
//! * `illume bench SCENARIO.toml` — run a benchmark scenario and write its report.
//! * `illume convert IN.exr OUT.png [--exposure EV]` — a linear image tone-mapped as
//!   `render` writes PNGs.
//! * `illume precompute SCENE --output FILE` — a day of precomputed indirect light
//!   (`--shard K/N` for one shard, `--level L` for one adaptive level; `precompute
//!   merge`, `precompute info`).
//!
//! Offline work splits over machines with `--shard K/N` (item i goes to shard i mod N):
//! precompute keys, `animate` frames (gathered by `animate --collect N`), `bench`'s
//! converged references; `scripts/slurm/` submits them as job arrays.
//! * `illume view SCENE` — an interactive window (default feature `view`).
//!
//! SCENE is a file (`.gltf`, `.glb`, `.obj`, `.ply`) or `builtin:NAME`
//! (`builtin:cornell-spot`, `builtin:cube-in-box`, `builtin:furnace`).

// The doc comments of the clap argument structs are the `--help` text: units in brackets
// there (`[pixels]`) are for people, not intra-doc links, and escaping them would show the
// backslashes in the help.
#![allow(rustdoc::broken_intra_doc_links, rustdoc::invalid_html_tags)]

mod animate;
mod bench;
mod compare;
mod convert;
mod frames;
mod info;
mod offline;
mod progress;
mod render;
mod setup;
#[cfg(feature = "view")]
mod view;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

/// Frames allocate several images of megabytes each; the system allocator hands such
/// blocks back to the kernel on free, and touching them again next frame costs a page
/// fault per 4 KiB, a measurable share of a frame at 800×600 (`BENCHMARKS.md`).
/// mimalloc keeps them mapped for reuse.
#[global_allocator]
static ALLOCATOR: mimalloc::MiMalloc = mimalloc::MiMalloc;

/// illume: global illumination for dynamic scenes.
#[derive(Parser)]
#[command(name = "illume", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render one image of a scene.
    Render(render::RenderArgs),
    /// Describe a scene: geometry, lights and their power, animations, bounds.
    Info(info::InfoArgs),
    /// Render an animation: numbered PNG (and EXR) frames, a GIF/MP4 preview, a
    /// per-frame CSV of timings and counters.
    Animate(animate::AnimateArgs),
    /// The main demo: photon streaming on builtin:cornell-spot with the sphere and the
    /// spot light moving, in real time; writes out/demo/ and prints frames per second.
    Demo(animate::DemoArgs),
    /// Compare two images (EXR/PNG) or two folders of frames with image metrics (and, for
    /// two images, their per-channel means).
    Compare(compare::CompareArgs),
    /// Run a benchmark scenario: techniques vs the converged reference, report and plots.
    Bench(bench::BenchArgs),
    /// Turn a linear image (EXR) into a PNG with render's exposure and tone curve.
    Convert(convert::ConvertArgs),
    // The techniques' offline commands (`illume precompute`, …) come next: `main` mounts
    // them from their registrations (`offline::mount`).
    /// Open a window on a scene: the engine's frames as they render, camera and scene
    /// edits, techniques and the reference one toggle away (docs/viewer.md).
    #[cfg(feature = "view")]
    #[command(display_order = 900)]
    View(view::ViewArgs),
}

fn main() {
    default_sigpipe();
    progress::install_logger();
    let matches = command().get_matches();
    let result = match matches
        .subcommand()
        .and_then(|(name, sub)| offline::run(name, sub))
    {
        Some(result) => result,
        None => run(Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())),
    };
    if let Err(e) = result {
        eprintln!("error: {}", error_message(&e));
        std::process::exit(1);
    }
}

/// The whole command line: the app's commands, the techniques' offline commands, and a
/// first `--help` line that names every one of them (made from the list itself, so that
/// a new command cannot be missing from it).
fn command() -> clap::Command {
    let cli = offline::mount(Cli::command());
    let names: Vec<String> = cli
        .get_subcommands()
        .map(|c| c.get_name().to_owned())
        .collect();
    cli.about(format!("The illume command line: {}.", names.join(", ")))
}

/// Runs one of the app's own commands.
fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Render(a) => render::run(a),
        Command::Info(a) => info::run(a),
        Command::Compare(a) => compare::run(a),
        Command::Animate(a) => animate::run(a),
        Command::Demo(a) => animate::demo(a),
        Command::Bench(a) => bench::run_bench(a),
        Command::Convert(a) => convert::run(a),
        #[cfg(feature = "view")]
        Command::View(a) => view::run(a),
    }
}

/// Output piped into a command that stops reading (`illume compare … | head -1`) ends
/// the process quietly, as it does for other Unix tools. Rust ignores SIGPIPE by
/// default, so a write to a closed pipe fails with EPIPE, and `println!` panics on it.
fn default_sigpipe() {
    #[cfg(unix)]
    #[expect(unsafe_code, reason = "restoring the default SIGPIPE action")]
    // SAFETY: `signal` only changes this process's disposition of SIGPIPE to the
    // default; it runs first thing in `main`, before any thread or Rust state that a
    // signal could interrupt, and SIG_DFL runs no handler code.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

/// The error and its causes, each once: a cause whose text its error already shows (a
/// file error that quotes its I/O error) is not repeated.
fn error_message(e: &anyhow::Error) -> String {
    let mut message = e.to_string();
    for cause in e.chain().skip(1) {
        let text = cause.to_string();
        if !message.contains(&text) {
            message.push_str(": ");
            message.push_str(&text);
        }
    }
    message
}
