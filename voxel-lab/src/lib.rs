//! The lab of the voxel OIT renderer: scenes (TOML files, generated terrain), headless
//! rendering, every technique measured against the exact reference, charts and reports.
//! It has no window: the demo's window and the integration tests both build on it.
//!
//! Modules depend on each other one way:
//! - the model: [`error`] (what can go wrong, [`Error`]), [`files`] (result files written in one checked call), [`limits`] (the
//!   documented caps on a run), [`progress`], [`random`]
//!   (random scenes as scene-file text), [`overlaps`] (which pixels show two of a game's
//!   objects that interpenetrate), [`edges`] (which pixels lie on quad edges),
//!   [`content`] (what the ray march needs of a game's particles and entities),
//!   [`raymarch`] (the CPU ray-march reference),
//!   [`summary`], [`metrics`], [`scene`], [`headless`];
//! - the runs, which use the model: [`eval`] (every scene × technique against the
//!   reference), [`stability`] (sweeps and flicker);
//! - the report, which reads what the runs produced: [`distribution`] (errors over random
//!   scenes, where each technique fails), [`charts`], [`costs`] (what each technique asked
//!   of the GPU), [`report`];
//! - [`evaluate`] here, which runs everything and writes every file;
//! - [`stream`]: the streaming flight (`demo stream`), which draws its own chart;
//! - [`gallery`]: one scene under every technique with its error maps (`demo gallery`);
//! - [`backends`]: every technique on Vulkan, GL and WebGL2's limits (`demo backends`).

#![warn(missing_docs)]

pub mod backends;
pub mod charts;
pub mod content;
pub mod costs;
pub mod distribution;
pub mod edges;
pub mod error;
pub mod eval;
pub mod far;
pub mod files;
pub mod gallery;
pub mod headless;
pub mod limits;
pub mod metrics;
pub mod overlaps;
pub mod progress;
pub mod random;
pub mod raymarch;
pub mod report;
pub mod scene;
pub mod stability;
pub mod stream;
pub mod summary;

pub use error::{Error, Result};
pub use summary::{EvalOptions, Summary};

/// `e` and its sources, joined by ": " (what a user needs to see of a renderer error).
pub fn chain(e: &dyn std::error::Error) -> String {
    let mut s = e.to_string();
    let mut source = e.source();
    while let Some(inner) = source {
        s += &format!(": {inner}");
        source = inner.source();
    }
    s
}

/// Runs the evaluation `opts` asks for and writes every file into `opts.out`:
/// `summary.json`, `reference_checks.json`, heat maps, the speed-against-accuracy chart,
/// the stability sweeps (when asked), `report.md` and `costs.md` (what each technique's
/// frame asked of the GPU, [`costs`]). On random scenes
/// ([`EvalOptions::random`]) no heat maps, but `distribution.json`, `scenes.json`,
/// `worst/` and the distribution charts.
///
/// Fails before rendering anything when `opts` asks for more than [`limits`] allows, a
/// scene file is broken or asks for a size past the caps ([`EvalOptions::validate`]).
pub fn evaluate(ctx: &voxel_render::GpuContext, opts: &EvalOptions) -> Result<Summary> {
    opts.validate()?;
    let out = &opts.out;
    let summary = eval::run_suite(ctx, opts)?;
    summary::write_json(&out.join("summary.json"), &summary.records)?;
    summary::write_json(
        &out.join("reference_checks.json"),
        &summary.reference_checks,
    )?;
    let distribution = opts
        .random
        .map(|set| (set, distribution::compute(&summary, set)));
    match &distribution {
        Some((set, d)) => {
            summary::write_json(&out.join("distribution.json"), d)?;
            summary::write_json(&out.join("scenes.json"), &d.scenes)?;
            distribution::write_worst(out, *set, d, opts)?;
            report::random_charts(out, &summary, d, opts)?;
        }
        // Without FLIP there is no accuracy axis to chart.
        None if opts.checks.flip => report::chart(out, &summary, opts)?,
        None => {}
    }
    if distribution.is_none() {
        costs::write(out, &summary, opts)?;
    }
    let stability = if opts.stability {
        let st = stability::run(ctx, opts)?;
        report::stability_charts(out, &st)?;
        Some(st)
    } else {
        None
    };
    report::write(
        out,
        &summary,
        distribution.as_ref().map(|(_, d)| d),
        stability.as_ref(),
        opts,
    )?;
    Ok(summary)
}
