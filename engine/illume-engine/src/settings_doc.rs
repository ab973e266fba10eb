//! What each field of a technique's settings table means, for tools that show the
//! settings (the viewer's panel): its documentation, unit, range, default, and whether a
//! change needs the technique rebuilt.
//!
//! Each field is declared once, in the technique's settings struct (`#[derive(Settings)]`,
//! crate `illume-settings-derive`): its `///` doc, unit, range, default and whether it
//! applies per frame. This module reads the table that declaration generates
//! ([`SettingsTable`](illume_transport::SettingsTable)), so a field documented in the
//! tuning guide is documented in every tool, and no tool holds a technique's fields.
//!
//! ```
//! use illume_engine::{TechniqueKind, settings_doc::Applies};
//! let docs = TechniqueKind::PhotonStream.settings_docs();
//! let vsl = docs.iter().find(|d| d.key == "vsl_count").unwrap();
//! assert_eq!(vsl.applies, Applies::Rebuild);
//! assert!(vsl.doc.contains("virtual surface lights"));
//! ```

use crate::{Config, TechniqueKind};
pub use illume_transport::Applies;

/// One field of a technique's settings table.
#[derive(Clone, Debug, PartialEq)]
pub struct SettingDoc {
    /// The key in the technique's table (`--set TABLE.KEY=VALUE`).
    pub key: String,
    /// The field's documentation, as plain text (links and escapes removed).
    pub doc: String,
    /// The unit (`pixels`, `ms`, `W/(m²·sr)`), declared or carried by the name's suffix.
    pub unit: Option<String>,
    /// The accepted values as declared (`(0, 1]`, `1–8`), or an enum's values
    /// (`streaming | deterministic`).
    pub range: Option<String>,
    /// The default value (None for an optional field that is unset by default).
    pub default: Option<toml::Value>,
    /// Whether a change applies at the next frame or rebuilds the technique.
    pub applies: Applies,
}

impl SettingDoc {
    /// The text of a tooltip: the doc, then unit, range, default and what a change does.
    pub fn tooltip(&self, technique: TechniqueKind) -> String {
        let mut t = self.doc.clone();
        t.push('\n');
        if let Some(u) = &self.unit {
            t += &format!("\nunit: {u}");
        }
        if let Some(r) = &self.range {
            t += &format!("\nrange: {r}");
        }
        t += &format!(
            "\ndefault: {}",
            self.default
                .as_ref()
                .map_or_else(|| "none".to_owned(), |v| v.to_string())
        );
        t += &format!("\nchange: {}", self.applies_text(technique));
        t
    }

    /// What a change of this setting does, in words.
    pub fn applies_text(&self, technique: TechniqueKind) -> String {
        match self.applies {
            Applies::PerFrame => "applies at the next frame (no rebuild)".to_owned(),
            Applies::Rebuild => format!("rebuilds {technique} (its state starts again)"),
        }
    }
}

impl TechniqueKind {
    /// The documentation of every field of the technique's settings table, in the
    /// struct's order.
    pub fn settings_docs(self) -> Vec<SettingDoc> {
        let defaults = toml::Value::try_from(Config::default())
            .ok()
            .and_then(|v| v.get(self.name()).cloned());
        self.setting_fields()
            .iter()
            .map(|f| SettingDoc {
                key: f.key.to_owned(),
                doc: f.doc.to_owned(),
                unit: f.unit.map(str::to_owned),
                range: f.range.map(str::to_owned),
                default: defaults.as_ref().and_then(|d| d.get(f.key).cloned()),
                applies: f.applies,
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every key of every technique's table (as serialized from the defaults) has a
    /// doc, and every documented field is in the table or optional.
    #[test]
    fn every_field_of_every_table_is_documented() {
        let config = toml::Value::try_from(Config::default()).unwrap();
        for &kind in TechniqueKind::ALL {
            let table = config.get(kind.name()).and_then(|t| t.as_table()).unwrap();
            let docs = kind.settings_docs();
            for key in table.keys() {
                let d = docs
                    .iter()
                    .find(|d| &d.key == key)
                    .unwrap_or_else(|| panic!("{kind}.{key} has no field doc"));
                assert!(d.doc.len() > 20, "{kind}.{key}: doc too short: {:?}", d.doc);
                assert!(!d.doc.contains('`'), "{kind}.{key}: {:?}", d.doc);
            }
            for d in &docs {
                assert!(
                    table.contains_key(&d.key) || d.default.is_none(),
                    "{kind}.{} is documented but not in the table",
                    d.key
                );
            }
        }
    }

    #[test]
    fn units_ranges_and_rebuilds_are_declared_with_the_fields() {
        let docs = TechniqueKind::PhotonStream.settings_docs();
        let get = |k: &str| docs.iter().find(|d| d.key == k).unwrap().clone();
        assert_eq!(get("vsl_count").applies, Applies::Rebuild);
        assert_eq!(get("vsl_count").default, Some(toml::Value::Integer(100)));
        assert_eq!(get("photons_per_frame").applies, Applies::PerFrame);
        assert_eq!(get("tile_size").unit.as_deref(), Some("pixels"));
        assert_eq!(get("epsilon").unit.as_deref(), Some("W/(m²·sr)"));
        assert_eq!(get("triangle_scale").range.as_deref(), Some("(0, 1]"));
        assert_eq!(get("shading_stride").range.as_deref(), Some("1–8"));
        assert_eq!(
            get("on_change").range.as_deref(),
            Some("age_out | flush"),
            "an enum's values"
        );
        assert!(get("mode").doc.contains("StreamMode::Streaming"));
        let tip = get("vsl_count").tooltip(TechniqueKind::PhotonStream);
        assert!(tip.contains("rebuilds photon_stream"), "{tip}");
        let sel = TechniqueKind::Selective.settings_docs();
        let get = |k: &str| sel.iter().find(|d| d.key == k).unwrap().clone();
        assert_eq!(get("smoothing_angle_deg").unit.as_deref(), Some("degrees"));
        assert_eq!(get("frame_budget_ms").unit.as_deref(), Some("ms"));
        assert_eq!(get("frame_budget_ms").applies, Applies::PerFrame);
        assert_eq!(get("pilots_per_group").range.as_deref(), Some("≥ 2"));
        let pc = TechniqueKind::Precomputed.settings_docs();
        let colour = pc.iter().find(|d| d.key == "colour").unwrap();
        assert_eq!(colour.range.as_deref(), Some("per-channel | joint"));
    }

    /// Each per-frame field moves the budget under some pacing: a change reaches the
    /// technique through `Engine::set_budget` alone.
    #[test]
    fn per_frame_fields_feed_the_budget() {
        use illume_transport::Pacing;
        let pacings = [
            Pacing::RealTime,
            Pacing::FixedWork {
                work_per_frame: None,
            },
        ];
        for &kind in TechniqueKind::ALL {
            for d in kind.settings_docs() {
                if d.applies != Applies::PerFrame {
                    continue;
                }
                let budget = |pacing: Pacing, v: i64| {
                    let mut config = Config {
                        technique: kind,
                        ..Default::default()
                    };
                    config.technique_settings_mut().pace(pacing);
                    let mut value = toml::Value::try_from(&config).unwrap();
                    let table = value
                        .get_mut(kind.name())
                        .and_then(|t| t.as_table_mut())
                        .unwrap();
                    let typed = match table.get(&d.key) {
                        Some(toml::Value::Float(_)) => toml::Value::Float(v as f64),
                        Some(_) => toml::Value::Integer(v),
                        None => panic!("{kind}.{} is not in the table", d.key),
                    };
                    table.insert(d.key.clone(), typed);
                    let config: Config = value.try_into().unwrap();
                    config.budget()
                };
                let moved = pacings.iter().any(|&p| budget(p, 3) != budget(p, 7));
                assert!(moved, "{kind}.{} is per-frame but moves no budget", d.key);
            }
        }
    }
}
