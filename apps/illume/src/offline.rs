//! The techniques' offline commands (`illume precompute`, …): each registration's
//! [`OfflineCommand`](illume_transport::OfflineCommand), mounted under `illume` and run
//! with this app as its [`OfflineHost`]. No technique is named here.

use illume_engine::{Config, ConfigLayers, TechniqueKind};
use illume_transport::{OfflineError, OfflineHost, OfflineProgress, OfflineSettings};

/// `cli` with every registered technique's offline command mounted, after the app's own
/// commands in `--help`.
pub fn mount(mut cli: clap::Command) -> clap::Command {
    let mut order = cli.get_subcommands().count();
    for kind in TechniqueKind::ALL {
        if let Some(offline) = kind.offline() {
            cli = cli.subcommand((offline.command)().display_order(order));
            order += 1;
        }
    }
    cli
}

/// Runs the offline command that `name` names with its `matches`; None when no
/// technique has a command of that name.
pub fn run(name: &str, matches: &clap::ArgMatches) -> Option<anyhow::Result<()>> {
    TechniqueKind::ALL.iter().find_map(|&kind| {
        let offline = kind.offline().filter(|o| o.name == name)?;
        Some((offline.run)(matches, &Host { kind }).map_err(anyhow::Error::from_boxed))
    })
}

/// The app, as an offline command of technique `kind` sees it.
struct Host {
    kind: TechniqueKind,
}

impl OfflineHost for Host {
    fn settings(&self, sets: &[String]) -> Result<OfflineSettings, OfflineError> {
        let config = Config::layered(&ConfigLayers {
            technique: Some(self.kind),
            sets,
            ..Default::default()
        })?;
        let image_size = (config.render.width, config.render.height);
        Ok(OfflineSettings {
            settings: config.into_settings(self.kind),
            image_size,
        })
    }

    fn load_scene(&self, path: &std::path::Path) -> Result<illume_scene::Scene, OfflineError> {
        crate::render::load_scene_with(path, None, 0.0, false, &Default::default())
            .map_err(Into::into)
    }

    fn progress(&self, what: &str) -> Box<dyn OfflineProgress> {
        Box::new(crate::progress::Bars::with_spinner(what))
    }
}

impl OfflineProgress for crate::progress::Bars {
    fn finish(&mut self) {
        crate::progress::Bars::finish(self);
    }
}
