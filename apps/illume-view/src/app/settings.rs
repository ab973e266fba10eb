//! The settings panel: the technique's table as editable fields with their
//! documentation, each saying before it applies whether a change rebuilds.

use super::{Actions, App};
use crate::renderer::{Command, Shown};
use egui::Key;
use illume_engine::TechniqueKind;
use illume_engine::settings_doc::Applies;

impl App {
    /// The technique's settings as editable fields, each with its documentation
    /// (meaning, unit, range, default) as a tooltip. An edited field says what applying
    /// it will do — at the next frame, or a rebuild of the technique — before Enter
    /// applies it as `--set TABLE.KEY=VALUE`.
    pub(super) fn settings(&mut self, ui: &mut egui::Ui, shown: &Shown, actions: &mut Actions) {
        if self.settings_for != shown.settings_toml {
            self.settings_for = shown.settings_toml.clone();
            self.settings_rows = setting_rows(shown.technique, &shown.settings_toml)
                .into_iter()
                .map(|r| {
                    let v = r.value.clone();
                    (r, v)
                })
                .collect();
        }
        ui.label("Hover a name for its meaning, unit and range; Enter applies.");
        if let Some((_, notice)) = &self.rebuilding {
            ui.colored_label(egui::Color32::from_rgb(255, 170, 60), notice.as_str());
        }
        let table = shown.technique.name();
        for (row, text) in &mut self.settings_rows {
            ui.horizontal(|ui| {
                ui.label(row.label.as_str())
                    .on_hover_text(row.tooltip.as_str());
                if let Some(choices) = &row.choices {
                    // A drop-down applies its choice at once (the notice below says
                    // whether that rebuilt the technique).
                    let before = text.clone();
                    egui::ComboBox::from_id_salt(("setting", row.key.as_str()))
                        .selected_text(text.as_str())
                        .show_ui(ui, |ui| {
                            for c in choices {
                                ui.selectable_value(text, c.clone(), c.as_str());
                            }
                        })
                        .response
                        .on_hover_text(row.tooltip.as_str());
                    if *text != before {
                        actions
                            .commands
                            .push(Command::Set(format!("{table}.{}={}", row.key, text)));
                    }
                    return;
                }
                let r = ui
                    .add(egui::TextEdit::singleline(text).desired_width(f32::INFINITY))
                    .on_hover_text(row.tooltip.as_str());
                if r.lost_focus() && ui.input(|i| i.key_pressed(Key::Enter)) {
                    actions.commands.push(Command::Set(format!(
                        "{table}.{}={}",
                        row.key,
                        text.trim()
                    )));
                }
            });
            if let Some(notice) = pending_notice(shown.technique, row, text) {
                let colour = match row.applies {
                    Applies::Rebuild => egui::Color32::from_rgb(255, 170, 60),
                    Applies::PerFrame => egui::Color32::LIGHT_GREEN,
                };
                ui.colored_label(colour, notice);
            }
        }
    }
}

/// One row of the settings panel: a field of the technique's table.
#[derive(Clone, Debug)]
pub(super) struct SettingRow {
    /// The key in the technique's table.
    key: String,
    /// The current value as TOML text.
    value: String,
    /// The key and its unit.
    label: String,
    /// Meaning, unit, range, default and what a change does.
    tooltip: String,
    /// Whether a change applies at the next frame or rebuilds the technique.
    applies: Applies,
    /// The values a drop-down offers (a boolean's two, an enum's as its doc lists
    /// them); None: edited as text.
    choices: Option<Vec<String>>,
}

/// The settings panel's rows for `technique`, whose table is `settings_toml`: every
/// field but sub-tables, in the settings struct's order, with its documentation
/// (`illume_engine::settings_doc`).
fn setting_rows(technique: TechniqueKind, settings_toml: &str) -> Vec<SettingRow> {
    let Ok(table) = settings_toml.parse::<toml::Table>() else {
        return Vec::new();
    };
    let docs = technique.settings_docs();
    let mut keys: Vec<&String> = docs
        .iter()
        .map(|d| &d.key)
        .filter(|k| table.contains_key(*k))
        .collect();
    keys.extend(table.keys().filter(|k| !docs.iter().any(|d| &d.key == *k)));
    keys.into_iter()
        .filter(|k| !table[*k].is_table())
        .map(|k| {
            let doc = docs.iter().find(|d| &d.key == k);
            let value = match &table[k] {
                toml::Value::String(s) => s.clone(),
                v => v.to_string(),
            };
            let choices = match &table[k] {
                toml::Value::Boolean(_) => Some(vec!["true".to_owned(), "false".to_owned()]),
                toml::Value::String(_) => doc
                    .and_then(|d| d.range.as_deref())
                    .filter(|r| r.contains(" | "))
                    .map(|r| r.split(" | ").map(|v| v.trim().to_owned()).collect()),
                _ => None,
            };
            SettingRow {
                key: k.clone(),
                value,
                label: match doc.and_then(|d| d.unit.as_deref()) {
                    Some(u) => format!("{k} [{u}]"),
                    None => k.clone(),
                },
                tooltip: doc.map_or_else(|| format!("{k}: undocumented"), |d| d.tooltip(technique)),
                applies: doc.map_or(Applies::Rebuild, |d| d.applies),
                choices,
            }
        })
        .collect()
}

/// What applying `edited` to `row` will do, said before it is applied (None when the
/// text is the current value).
fn pending_notice(technique: TechniqueKind, row: &SettingRow, edited: &str) -> Option<String> {
    (edited.trim() != row.value).then(|| match row.applies {
        Applies::Rebuild => format!(
            "⟳ Enter rebuilds {technique}: its state (photons, caches, placements) starts again"
        ),
        Applies::PerFrame => "Enter applies it at the next frame (no rebuild)".to_owned(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn default_table(kind: TechniqueKind) -> String {
        let config = illume_engine::Config {
            technique: kind,
            ..Default::default()
        };
        let value = toml::Value::try_from(&config).unwrap();
        toml::to_string(value.get(kind.name()).unwrap()).unwrap()
    }

    /// Every field of every technique's table has a row whose tooltip carries its doc,
    /// default and what a change does; units show in the label.
    #[test]
    fn every_setting_has_a_documented_tooltip() {
        for &kind in TechniqueKind::ALL {
            let text = default_table(kind);
            let table: toml::Table = text.parse().unwrap();
            let rows = setting_rows(kind, &text);
            for key in table.keys() {
                let row = rows
                    .iter()
                    .find(|r| &r.key == key)
                    .unwrap_or_else(|| panic!("{kind}.{key} has no row"));
                assert!(
                    !row.tooltip.contains("undocumented") && row.tooltip.len() > 60,
                    "{kind}.{key}: {}",
                    row.tooltip
                );
                assert!(row.tooltip.contains("default: "), "{}", row.tooltip);
                assert!(row.tooltip.contains("change: "), "{}", row.tooltip);
            }
        }
        let rows = setting_rows(
            TechniqueKind::PhotonStream,
            &default_table(TechniqueKind::PhotonStream),
        );
        let tile = rows.iter().find(|r| r.key == "tile_size").unwrap();
        assert_eq!(tile.label, "tile_size [pixels]");
        let stride = rows.iter().find(|r| r.key == "shading_stride").unwrap();
        assert!(stride.tooltip.contains("range: 1–8"), "{}", stride.tooltip);
    }

    /// Editing `photon_stream.vsl_count` says it rebuilds before it is applied; a
    /// per-frame field says it does not; an unchanged field says nothing.
    #[test]
    fn a_change_that_rebuilds_says_so_before_it_is_applied() {
        let kind = TechniqueKind::PhotonStream;
        let rows = setting_rows(kind, &default_table(kind));
        let row = |k: &str| rows.iter().find(|r| r.key == k).unwrap();
        let vsl = row("vsl_count");
        assert_eq!(vsl.value, "100");
        assert_eq!(pending_notice(kind, vsl, "100"), None);
        let notice = pending_notice(kind, vsl, "200").expect("a notice");
        assert!(notice.contains("rebuilds photon_stream"), "{notice}");
        let per_frame = pending_notice(kind, row("photons_per_frame"), "5000").unwrap();
        assert!(per_frame.contains("no rebuild"), "{per_frame}");
        // The render thread takes the same decision from the same docs.
        use crate::renderer::setting_applies;
        assert_eq!(
            setting_applies(kind, "photon_stream.vsl_count=200"),
            Applies::Rebuild
        );
        assert_eq!(
            setting_applies(kind, "photon_stream.photons_per_frame=5000"),
            Applies::PerFrame
        );
        assert_eq!(
            setting_applies(TechniqueKind::Reference, "reference.spp_per_frame=8"),
            Applies::PerFrame
        );
    }

    /// Enum settings offer their documented values in a drop-down, booleans true and
    /// false, numbers stay text; every enum's current value is one of its choices.
    #[test]
    fn enums_and_booleans_are_chosen_from_a_list() {
        let kind = TechniqueKind::RadianceCache;
        let rows = setting_rows(kind, &default_table(kind));
        let row = |k: &str| rows.iter().find(|r| r.key == k).unwrap();
        assert_eq!(
            row("temporal").choices.as_deref(),
            Some(
                &[
                    "per_frame".to_owned(),
                    "reuse".to_owned(),
                    "extrapolated".to_owned(),
                    "interpolated".to_owned()
                ][..]
            )
        );
        assert_eq!(row("deletion").choices.as_ref().map(Vec::len), Some(2));
        assert_eq!(row("theta_strata").choices, None);
        for &kind in TechniqueKind::ALL {
            for r in setting_rows(kind, &default_table(kind)) {
                if let Some(c) = &r.choices {
                    assert!(
                        c.contains(&r.value),
                        "{kind}.{}: {} not in {c:?}",
                        r.key,
                        r.value
                    );
                }
            }
        }
    }
}
