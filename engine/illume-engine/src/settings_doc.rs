//! What each field of a technique's settings table means, for tools that show the
//! settings (the viewer's panel): its documentation, unit, range, default, and whether a
//! change needs the technique rebuilt.
//!
//! The text is the settings struct's own field docs — each technique's `settings.rs`
//! exposes its source as `settings::SOURCE` — so a field documented in the tuning guide
//! is documented in every tool, and no tool holds a technique's fields. The unit is the
//! doc's bracketed unit (`\[pixels\]`, `[W/(m²·sr)]`) or the name's suffix (`_ms`,
//! `_deg`, STYLE.md's naming convention); the range is the doc's stated range (`in (0,
//! 1]`, `1–8`, `≥ 2`) or, for an enum, its values.
//!
//! ```
//! use illume_engine::{TechniqueKind, settings_doc::Applies};
//! let docs = TechniqueKind::PhotonStream.settings_docs();
//! let vsl = docs.iter().find(|d| d.key == "vsl_count").unwrap();
//! assert_eq!(vsl.applies, Applies::Rebuild);
//! assert!(vsl.doc.contains("virtual surface lights"));
//! ```

use crate::{Config, TechniqueKind};

/// How a change of one setting reaches a running engine.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Applies {
    /// Read through the frame budget (`TechniqueSettings::default_budget`,
    /// [`Engine::set_budget`](crate::Engine::set_budget)): the running technique takes
    /// the new value at its next frame, its state kept.
    PerFrame,
    /// Read when the technique is built: a change rebuilds it, and its state (photon
    /// pool, VSLs, caches, precomputed data) starts again.
    Rebuild,
}

/// One field of a technique's settings table.
#[derive(Clone, Debug, PartialEq)]
pub struct SettingDoc {
    /// The key in the technique's table (`--set TABLE.KEY=VALUE`).
    pub key: String,
    /// The field's documentation, as plain text (links and escapes removed).
    pub doc: String,
    /// The unit (`pixels`, `ms`, `W/(m²·sr)`), when the doc or the name gives one.
    pub unit: Option<String>,
    /// The accepted values as the doc states them (`in (0, 1]`, `1–8`), or an enum's
    /// values (`streaming | deterministic`).
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
        use illume_photon_stream::settings as ps;
        use illume_precomputed::settings as pc;
        use illume_radiance_cache::settings as rc;
        use illume_reference::settings as rf;
        use illume_selective::settings as se;
        let (source, name, per_frame): (&str, &str, &[&str]) = match self {
            TechniqueKind::Reference => (rf::SOURCE, "ReferenceSettings", rf::PER_FRAME_FIELDS),
            TechniqueKind::PhotonStream => {
                (ps::SOURCE, "PhotonStreamSettings", ps::PER_FRAME_FIELDS)
            }
            TechniqueKind::Selective => (se::SOURCE, "SelectiveSettings", se::PER_FRAME_FIELDS),
            TechniqueKind::RadianceCache => {
                (rc::SOURCE, "RadianceCacheSettings", rc::PER_FRAME_FIELDS)
            }
            TechniqueKind::Precomputed => (pc::SOURCE, "PrecomputedSettings", pc::PER_FRAME_FIELDS),
        };
        let defaults = toml::Value::try_from(Config::default())
            .ok()
            .and_then(|v| v.get(self.name()).cloned());
        parse_fields(source, name)
            .into_iter()
            .map(|f| {
                let range = enum_values(source, &f.ty).or_else(|| stated_range(&f.doc));
                SettingDoc {
                    unit: stated_unit(&f.doc).or_else(|| suffix_unit(&f.key)),
                    range,
                    default: defaults.as_ref().and_then(|d| d.get(&f.key).cloned()),
                    applies: if per_frame.contains(&f.key.as_str()) {
                        Applies::PerFrame
                    } else {
                        Applies::Rebuild
                    },
                    doc: plain(&f.doc),
                    key: f.key,
                }
            })
            .collect()
    }
}

/// A field of a struct as written in the source.
struct Field {
    key: String,
    ty: String,
    doc: String,
}

/// The `pub` fields of `pub struct NAME { … }` in `source`, with their `///` docs.
/// Fields marked `#[serde(skip)]` are left out (they are not in the table).
fn parse_fields(source: &str, name: &str) -> Vec<Field> {
    let mut fields = Vec::new();
    let mut lines = source
        .lines()
        .skip_while(|l| !l.trim_start().starts_with(&format!("pub struct {name} {{")));
    lines.next();
    let (mut doc, mut skip) = (String::new(), false);
    for line in lines {
        let l = line.trim();
        if l == "}" {
            break;
        }
        if let Some(d) = l.strip_prefix("///") {
            doc.push_str(d.trim());
            doc.push(' ');
        } else if l.starts_with("#[") {
            skip |= l.contains("serde(skip");
        } else if let Some(rest) = l.strip_prefix("pub ")
            && let Some((key, ty)) = rest.split_once(':')
        {
            if !skip {
                fields.push(Field {
                    key: key.trim().to_owned(),
                    ty: ty.trim().trim_end_matches(',').trim().to_owned(),
                    doc: doc.trim().to_owned(),
                });
            }
            doc.clear();
            skip = false;
        }
    }
    fields
}

/// The values of `pub enum TY` in `source` as the table spells them (its serde
/// `rename_all`), joined with ` | `; None when `ty` is no enum of the file.
fn enum_values(source: &str, ty: &str) -> Option<String> {
    let lines: Vec<&str> = source.lines().collect();
    let start = lines
        .iter()
        .position(|l| l.trim_start().starts_with(&format!("pub enum {ty} {{")))?;
    let rename = lines[..start]
        .iter()
        .rev()
        .take_while(|l| l.trim_start().starts_with('#'))
        .find_map(|l| l.split_once("rename_all = \"").map(|(_, r)| r))
        .and_then(|r| r.split('"').next())
        .unwrap_or("");
    let values: Vec<String> = lines[start + 1..]
        .iter()
        .map(|l| l.trim())
        .take_while(|l| *l != "}")
        .filter(|l| !l.starts_with("//") && !l.starts_with('#'))
        .filter_map(|l| {
            let v = l.trim_end_matches(',');
            (!v.is_empty() && v.chars().all(|c| c.is_ascii_alphanumeric()))
                .then(|| spell(v, rename))
        })
        .collect();
    (!values.is_empty()).then(|| values.join(" | "))
}

/// A variant name as serde's `rename_all` spells it.
fn spell(variant: &str, rename: &str) -> String {
    let sep = match rename {
        "snake_case" => "_",
        "kebab-case" => "-",
        "lowercase" => "",
        _ => return variant.to_owned(),
    };
    let mut out = String::new();
    for (i, c) in variant.chars().enumerate() {
        if c.is_uppercase() && i > 0 {
            out.push_str(sep);
        }
        out.extend(c.to_lowercase());
    }
    out
}

/// The first bracketed unit of a doc: `\[pixels\]` or `[W/(m²·sr)]` (not a link, not a
/// range such as `[0, 1]`).
fn stated_unit(doc: &str) -> Option<String> {
    let text = doc.replace("\\[", "[").replace("\\]", "]");
    let mut rest = text.as_str();
    while let Some(open) = rest.find('[') {
        let after = &rest[open + 1..];
        let close = matching_bracket(after)?;
        let inside = &after[..close];
        let link = after[close + 1..].starts_with('(') || inside.contains('`');
        let range = inside.contains(',') || inside.starts_with(|c: char| c.is_ascii_digit());
        if !link && !range && !inside.is_empty() {
            return Some(inside.to_owned());
        }
        rest = &after[close + 1..];
    }
    None
}

/// The index of the `]` closing a bracket opened just before `s` (nested pairs skipped).
fn matching_bracket(s: &str) -> Option<usize> {
    let mut depth = 0;
    for (i, c) in s.char_indices() {
        match c {
            '[' => depth += 1,
            ']' if depth == 0 => return Some(i),
            ']' => depth -= 1,
            _ => {}
        }
    }
    None
}

/// The unit a field's name carries (STYLE.md: `budget_ms`, `radius_m`).
fn suffix_unit(key: &str) -> Option<String> {
    let units = [
        ("_ms", "ms"),
        ("_s", "s"),
        ("_m", "m"),
        ("_deg", "degrees"),
        ("_rad", "radians"),
        ("_min", "minutes"),
        ("_h", "hours"),
        ("_frames", "frames"),
        ("_fraction", "fraction"),
    ];
    units
        .iter()
        .find(|(s, _)| key.ends_with(s))
        .map(|(_, u)| (*u).to_owned())
}

/// The range a doc states: `in (0, 1]`, `in [0, 10]`, `1–8`, `≥ 2`, `at least 1`.
fn stated_range(doc: &str) -> Option<String> {
    let text = plain(doc);
    for opener in ["in (", "in [", "In (", "In ["] {
        if let Some(i) = text.find(opener) {
            let s = &text[i + 3..];
            if let Some(end) = s.find([']', ')']) {
                let r = &s[..=end];
                if r.contains(',') {
                    return Some(r.to_owned());
                }
            }
        }
    }
    // `a–b` with digits on both sides (spaces inside numbers allowed: `1–100 000`).
    let chars: Vec<char> = text.chars().collect();
    for (i, &c) in chars.iter().enumerate() {
        if c == '–'
            && i > 0
            && chars[i - 1].is_ascii_digit()
            && chars.get(i + 1).is_some_and(|c| c.is_ascii_digit())
        {
            let start = chars[..i]
                .iter()
                .rposition(|c| !(c.is_ascii_digit() || *c == '.'))
                .map_or(0, |p| p + 1);
            let mut end = i + 1;
            while end < chars.len()
                && (chars[end].is_ascii_digit()
                    || chars[end] == '.'
                    || (chars[end] == ' '
                        && chars.get(end + 1).is_some_and(|c| c.is_ascii_digit())
                        && chars.get(end + 4).is_none_or(|c| !c.is_ascii_digit())))
            {
                end += 1;
            }
            return Some(chars[start..end].iter().collect());
        }
    }
    for lead in ["≥ ", "at least "] {
        if let Some(i) = text.find(lead) {
            let n: String = text[i + lead.len()..]
                .chars()
                .take_while(|c| c.is_ascii_digit() || *c == '.')
                .collect();
            if !n.is_empty() {
                return Some(format!("≥ {n}"));
            }
        }
    }
    None
}

/// A doc comment as plain text: intra-doc links by their text, backticks and escapes
/// removed.
fn plain(doc: &str) -> String {
    let mut out = String::with_capacity(doc.len());
    let mut rest = doc;
    while let Some(i) = rest.find("[`") {
        out.push_str(&rest[..i]);
        let after = &rest[i + 2..];
        let Some(end) = after.find("`]") else {
            out.push_str(&rest[i..]);
            rest = "";
            break;
        };
        out.push_str(&after[..end]);
        rest = &after[end + 2..];
        // `[text](path)`: drop the path.
        if rest.starts_with('(')
            && let Some(close) = rest.find(')')
        {
            rest = &rest[close + 1..];
        }
    }
    out.push_str(rest);
    out.replace("\\[", "[").replace("\\]", "]").replace('`', "")
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
    fn units_ranges_and_rebuilds_are_read_from_the_docs() {
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
