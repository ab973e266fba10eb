//! `illume bench`: runs a scenario file and writes its report (see `docs/bench.md`).

use crate::progress;
use anyhow::{Context, Result};
use clap::Args;
use illume_bench::{RunOptions, Scenario, references_shard, run, write_report};
use illume_core::Shard;
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `illume bench`.
#[derive(Args)]
pub struct BenchArgs {
    /// The scenario file (.toml), e.g. scenarios/moving_sphere.toml.
    pub scenario: PathBuf,
    /// Report folder [default: out/bench/<scenario name>].
    #[arg(long, short)]
    pub output: Option<PathBuf>,
    /// Converged-reference cache folder.
    #[arg(long, default_value = "out/cache")]
    pub cache: PathBuf,
    /// Also write every frame of every series as PNG under OUTPUT/frames/.
    #[arg(long)]
    pub save_frames: bool,
    /// Only render shard K of N's share of the converged references into --cache (the
    /// distinct references in frame order, those with number mod N = K) and stop: no
    /// technique runs, no report. After the N shards, the plain `illume bench` finds
    /// them all in the cache (scripts/slurm/bench_refs.sbatch).
    #[arg(long, value_name = "K/N", conflicts_with = "save_frames")]
    pub shard: Option<Shard>,
    /// Run the scenario at toy sizes instead (at most 32 pixels wide, 4-spp references,
    /// the first, last and edited frames only; each technique's work that does not scale with the pixels cut, e.g. rays per radiance record): a check
    /// that its command runs end to end in seconds, whose numbers mean nothing. CI runs
    /// every shipped scenario this way.
    #[arg(long)]
    pub miniature: bool,
}

/// Runs `illume bench`.
pub fn run_bench(a: BenchArgs) -> Result<()> {
    let t0 = Instant::now();
    let mut scenario = Scenario::load(&a.scenario)?;
    if a.miniature {
        scenario = scenario.miniature();
        eprintln!(
            "miniature: {}×{}, {} frames, references at {} spp — a check that the scenario runs; its numbers mean nothing",
            scenario.width,
            scenario.height,
            scenario.frame_times().len(),
            scenario.reference.spp
        );
    }
    let mut options = RunOptions::for_scenario(&scenario);
    if let Some(o) = a.output {
        options.output_dir = o;
    }
    options.cache_dir = a.cache;
    options.save_frames = a.save_frames;
    if let Some(shard) = a.shard {
        let mut bars = progress::Bars::default();
        let done = references_shard(&scenario, &options, shard, &mut bars)
            .with_context(|| format!("{} (shard {shard})", a.scenario.display()))?;
        bars.finish();
        eprintln!(
            "shard {shard}: {} of {} distinct converged references ({} rendered, {} already cached) in {} ({:.1} s)",
            done.mine,
            done.distinct,
            done.cache_renders,
            done.cache_hits,
            options.cache_dir.display(),
            t0.elapsed().as_secs_f64()
        );
        return Ok(());
    }
    let command: Vec<String> = std::env::args().collect();
    options
        .notes
        .push(format!("Command: `{}`", command.join(" ")));
    if a.miniature {
        options.notes.push(
            "**Miniature run** (`--miniature`): toy sizes, a check that the scenario runs; its numbers mean nothing.".into(),
        );
    }
    let mut bars = progress::Bars::default();
    let outcome = run(&scenario, &options, &mut bars)
        .with_context(|| format!("running {}", a.scenario.display()))?;
    bars.finish();
    let files = write_report(&scenario, &outcome, &options)?;
    for s in &outcome.summaries {
        let metrics: Vec<String> = s
            .metrics
            .iter()
            .map(|(m, mean, _)| format!("{m} {mean:.4}"))
            .collect();
        eprintln!(
            "{:<40} median {:8.2} ms/frame  mean {}",
            s.series,
            s.median_frame_ms,
            metrics.join(", ")
        );
    }
    let noise = outcome.reference_noise_summary();
    if !noise.is_empty() {
        let metrics: Vec<String> = noise
            .iter()
            .map(|(m, mean, _, _)| format!("{m} {mean:.4}"))
            .collect();
        eprintln!(
            "{:<40} between its halves ({} spp each): mean {}",
            "converged reference",
            scenario.reference.spp / 2,
            metrics.join(", ")
        );
    }
    eprintln!(
        "wrote {} and {} ({} plots) in {:.1} s",
        files.report_md.display(),
        files.results_csv.display(),
        files.plots.len(),
        t0.elapsed().as_secs_f64()
    );
    Ok(())
}
