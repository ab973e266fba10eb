//! Animations: node TRS channels, and `KHR_animation_pointer` channels (taken out of
//! the JSON before the `gltf` crate reads it) on light and material properties.

use super::Ctx;
use super::materials::emissive_strength;
use crate::animation::{
    Animation, Channel, ChannelValues, Interpolation, PropertyChannel, PropertyTarget,
};
use crate::load::{LoadError, excerpt};
use crate::model::NodeId;
use ::gltf::json;
use illume_core::{Rgb, Vec3, Vec4};
use json::validation::Checked;
use std::path::Path;

/// An animation channel whose target is a JSON pointer (`KHR_animation_pointer`).
#[derive(Clone, Debug)]
pub(super) struct PointerChannel {
    animation: usize,
    channel: usize,
    sampler: usize,
    pointer: String,
}

/// Takes the `KHR_animation_pointer` channels (target path `"pointer"`) out of the
/// document's JSON, returning the document without them (re-encoded, GLB container
/// rebuilt) and the channels. A document without such channels comes back unchanged;
/// one whose JSON does not parse too (the `gltf` crate reports that error).
pub(super) fn split_pointer_channels(
    path: &Path,
    bytes: Vec<u8>,
    is_glb: bool,
) -> Result<(Vec<u8>, Vec<PointerChannel>), LoadError> {
    let word = |b: &[u8], at: usize| {
        b.get(at..at + 4)
            .map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]) as usize)
    };
    let json_range = if is_glb {
        match (word(&bytes, 12), bytes.get(16..20)) {
            (Some(len), Some(b"JSON")) if 20 + len <= bytes.len() => 20..20 + len,
            _ => return Ok((bytes, Vec::new())),
        }
    } else {
        0..bytes.len()
    };
    let Ok(mut doc) = serde_json::from_slice::<serde_json::Value>(&bytes[json_range.clone()])
    else {
        return Ok((bytes, Vec::new()));
    };
    check_index_widths(path, &doc, &mut String::new())?;
    let mut found = Vec::new();
    if let Some(animations) = doc.get_mut("animations").and_then(|a| a.as_array_mut()) {
        for (ai, a) in animations.iter_mut().enumerate() {
            let Some(channels) = a.get_mut("channels").and_then(|c| c.as_array_mut()) else {
                continue;
            };
            let mut ci = 0;
            channels.retain(|c| {
                let target = &c["target"];
                let keep = target["path"] != "pointer";
                if !keep {
                    found.push(PointerChannel {
                        animation: ai,
                        channel: ci,
                        sampler: c["sampler"].as_u64().unwrap_or(u64::MAX) as usize,
                        pointer: target["extensions"]["KHR_animation_pointer"]["pointer"]
                            .as_str()
                            .unwrap_or("")
                            .to_owned(),
                    });
                }
                ci += 1;
                keep
            });
        }
    }
    if found.is_empty() {
        return Ok((bytes, found));
    }
    let Ok(mut json) = serde_json::to_vec(&doc) else {
        return Ok((bytes, Vec::new()));
    };
    if !is_glb {
        return Ok((json, found));
    }
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let rest = &bytes[json_range.end..];
    let mut out = Vec::with_capacity(20 + json.len() + rest.len());
    out.extend_from_slice(&bytes[0..8]);
    out.extend_from_slice(&((20 + json.len() + rest.len()) as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(rest);
    Ok((out, found))
}

/// The JSON keys whose values are indices into the document's arrays (glTF 2.0's
/// `glTFid`s and `texCoord`), and the arrays of them.
const INDEX_KEYS: &[&str] = &[
    "index",
    "source",
    "sampler",
    "texCoord",
    "material",
    "mesh",
    "camera",
    "node",
    "scene",
    "skin",
    "bufferView",
    "buffer",
    "indices",
    "input",
    "output",
    "light",
    "skeleton",
];
const INDEX_ARRAYS: &[&str] = &["nodes", "children", "joints", "scenes"];

/// Refuses an index that does not fit the 32 bits the `gltf` crate stores it in (issue
/// 38: a texture index of 2³² wrapped to texture 0), naming its JSON path and value.
fn check_index_widths(
    path: &Path,
    value: &serde_json::Value,
    at: &mut String,
) -> Result<(), LoadError> {
    use serde_json::Value;
    let wide = |v: &Value| v.as_u64().is_some_and(|n| n > u64::from(u32::MAX));
    match value {
        Value::Object(map) => {
            for (key, v) in map {
                let len = at.len();
                if !at.is_empty() {
                    at.push('.');
                }
                at.push_str(key);
                let bad = if INDEX_KEYS.contains(&key.as_str()) {
                    wide(v).then(|| at.clone())
                } else if INDEX_ARRAYS.contains(&key.as_str()) {
                    v.as_array()
                        .and_then(|a| a.iter().position(wide))
                        .map(|i| format!("{at}[{i}]"))
                } else {
                    None
                };
                if let Some(place) = bad {
                    let shown = if place.ends_with(']') {
                        v.as_array()
                            .and_then(|a| a.iter().find(|x| wide(x)).cloned())
                            .unwrap_or_default()
                    } else {
                        v.clone()
                    };
                    return Err(LoadError::malformed(
                        path,
                        place,
                        format!("index {shown} is beyond 4294967295 (2³² − 1)"),
                    ));
                }
                // Attribute maps (`attributes`, morph `targets`) hold indices by any name.
                if (key == "attributes" || key == "targets")
                    && let Some((name, v)) =
                        v.as_object().and_then(|m| m.iter().find(|(_, x)| wide(x)))
                {
                    return Err(LoadError::malformed(
                        path,
                        format!("{at}.{name}"),
                        format!("index {v} is beyond 4294967295 (2³² − 1)"),
                    ));
                }
                check_index_widths(path, v, at)?;
                at.truncate(len);
            }
        }
        Value::Array(items) => {
            for (i, v) in items.iter().enumerate() {
                let len = at.len();
                at.push_str(&format!("[{i}]"));
                check_index_widths(path, v, at)?;
                at.truncate(len);
            }
        }
        _ => {}
    }
    Ok(())
}

impl Ctx<'_> {
    /// Converts every animation; returns the illume nodes any channel targets.
    /// An animation sampler's interpolation and key times (its input accessor, SCALAR).
    pub(super) fn sampler_keys(
        &self,
        sampler: &json::animation::Sampler,
        place: &str,
    ) -> Result<(Interpolation, Vec<f32>), LoadError> {
        use json::animation::Interpolation as I;
        let interpolation = match sampler.interpolation {
            Checked::Valid(I::Linear) => Interpolation::Linear,
            Checked::Valid(I::Step) => Interpolation::Step,
            Checked::Valid(I::CubicSpline) => Interpolation::CubicSpline,
            Checked::Invalid => return Err(self.malformed(place, "invalid interpolation")),
        };
        let input = sampler.input.value();
        let what = format!("{place} input");
        self.check_component_type(input, &what, &[json::accessor::ComponentType::F32], "FLOAT")?;
        let (times, comps) = self.read_accessor(input, &what)?;
        if comps != 1 {
            return Err(self.malformed(
                format!("accessor {input} ({place} input)"),
                "key times must be SCALAR",
            ));
        }
        Ok((interpolation, times.into_iter().map(|t| t as f32).collect()))
    }

    /// The `KHR_animation_pointer` channels of animation `ai`: light intensity, colour and
    /// spot cone angles, material base colour, emissive factor, metallic and roughness.
    /// Other pointers are warnings (ignored); bad samplers and accessors are errors.
    pub(super) fn pointer_channels(
        &mut self,
        ai: usize,
        name: &str,
    ) -> Result<Vec<PropertyChannel>, LoadError> {
        let root = self.root;
        let mut out = Vec::new();
        let pointers: Vec<PointerChannel> = self
            .pointers
            .iter()
            .filter(|p| p.animation == ai)
            .cloned()
            .collect();
        for p in pointers {
            let place = format!(
                "animation {ai} '{}' channel {} (pointer '{}')",
                excerpt(name),
                p.channel,
                excerpt(&p.pointer)
            );
            let Some(targets) = self.pointer_targets(&p.pointer, &place)? else {
                continue;
            };
            let a = &root.animations[ai];
            let sampler = a.samplers.get(p.sampler).ok_or_else(|| {
                self.malformed(&place, format!("sampler {} does not exist", p.sampler))
            })?;
            let (interpolation, times) = self.sampler_keys(sampler, &place)?;
            let (input, output) = (sampler.input.value(), sampler.output.value());
            let (values, _) = self.read_accessor(output, &format!("{place} output"))?;
            for target in targets {
                let channel = PropertyChannel {
                    target,
                    times: times.clone(),
                    values: values.iter().map(|&v| v as f32).collect(),
                    interpolation,
                };
                channel.validate().map_err(|m| {
                    self.malformed(format!("{place} (accessors {input}/{output})"), m)
                })?;
                out.push(channel);
            }
        }
        Ok(out)
    }

    /// The properties `KHR_animation_pointer` `pointer` (of the channel at `place`)
    /// animates: a light's (one target per illume light made from it) or a material's;
    /// `None`, with a warning, for a property or target illume does not animate.
    fn pointer_targets(
        &mut self,
        pointer: &str,
        place: &str,
    ) -> Result<Option<Vec<PropertyTarget>>, LoadError> {
        let parts: Vec<&str> = pointer.trim_start_matches('/').split('/').collect();
        match parts[..] {
            [
                "extensions",
                "KHR_lights_punctual",
                "lights",
                i,
                ref rest @ ..,
            ] => self.light_targets(i, rest, place),
            ["materials", m, ref rest @ ..] => self.material_targets(m, rest, place),
            _ => {
                self.warn(format!("{place}: unsupported pointer target; ignored"));
                Ok(None)
            }
        }
    }

    /// [`Ctx::pointer_targets`] for property `rest` of light `i`.
    fn light_targets(
        &mut self,
        i: &str,
        rest: &[&str],
        place: &str,
    ) -> Result<Option<Vec<PropertyTarget>>, LoadError> {
        let index = |s: &str| s.parse::<usize>().ok();
        let lights = self
            .root
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref());
        let Some(l) = index(i).and_then(|i| lights.and_then(|ls| ls.lights.get(i))) else {
            return Err(self.malformed(place, "the light does not exist"));
        };
        let ids = self
            .light_ids
            .get(&index(i).unwrap_or(0))
            .cloned()
            .unwrap_or_default();
        let mut targets = Vec::new();
        for light in ids {
            match rest {
                ["intensity"] => targets.push(PropertyTarget::LightIntensity {
                    light,
                    colour: Rgb::from(l.color),
                }),
                ["color"] => targets.push(PropertyTarget::LightColour {
                    light,
                    intensity: l.intensity,
                }),
                ["spot", "innerConeAngle"] => targets.push(PropertyTarget::SpotInnerCone { light }),
                ["spot", "outerConeAngle"] => targets.push(PropertyTarget::SpotOuterCone { light }),
                _ => {}
            }
        }
        if !matches!(
            rest,
            ["intensity"] | ["color"] | ["spot", "innerConeAngle"] | ["spot", "outerConeAngle"]
        ) {
            self.warn(format!(
                "{place}: this light property is not animated; ignored"
            ));
            return Ok(None);
        }
        Ok(Some(targets))
    }

    /// [`Ctx::pointer_targets`] for property `rest` of material `m`.
    fn material_targets(
        &mut self,
        m: &str,
        rest: &[&str],
        place: &str,
    ) -> Result<Option<Vec<PropertyTarget>>, LoadError> {
        let root = self.root;
        let Some((gm, &material)) = m
            .parse::<usize>()
            .ok()
            .and_then(|m| Some((root.materials.get(m)?, self.materials.get(m)?)))
        else {
            return Err(self.malformed(place, "the material does not exist"));
        };
        let strength = emissive_strength(gm);
        let target = match rest {
            ["pbrMetallicRoughness", "baseColorFactor"] => PropertyTarget::BaseColour { material },
            ["pbrMetallicRoughness", "metallicFactor"] => PropertyTarget::Metallic { material },
            ["pbrMetallicRoughness", "roughnessFactor"] => PropertyTarget::Roughness { material },
            ["emissiveFactor"] => PropertyTarget::Emissive { material, strength },
            _ => {
                self.warn(format!(
                    "{place}: this material property is not animated; ignored"
                ));
                return Ok(None);
            }
        };
        Ok(Some(vec![target]))
    }

    pub(super) fn animations(
        &mut self,
        node_ids: &[Option<NodeId>],
    ) -> Result<Vec<NodeId>, LoadError> {
        use json::animation::Property as P;
        let root = self.root;
        let mut targeted = Vec::new();
        for (ai, a) in root.animations.iter().enumerate() {
            let name = a.name.clone().unwrap_or_else(|| format!("animation {ai}"));
            let mut channels = Vec::new();
            for (ci, ch) in a.channels.iter().enumerate() {
                let place = format!("animation {ai} '{}' channel {ci}", excerpt(&name));
                let s = ch.sampler.value();
                let sampler = a
                    .samplers
                    .get(s)
                    .ok_or_else(|| self.malformed(&place, format!("sampler {s} does not exist")))?;
                let target = ch.target.node.value();
                if target >= root.nodes.len() {
                    return Err(self.malformed(
                        place,
                        format!(
                            "targets node {target}, which does not exist ({} nodes)",
                            root.nodes.len()
                        ),
                    ));
                }
                let property = match ch.target.path {
                    Checked::Valid(P::MorphTargetWeights) => {
                        self.warn(format!("{place}: morph-target weights ignored"));
                        continue;
                    }
                    Checked::Valid(p) => p,
                    Checked::Invalid => return Err(self.malformed(place, "invalid target path")),
                };
                let Some(node) = node_ids.get(target).copied().flatten() else {
                    self.warn(format!(
                        "{place}: targets node {target}, which is not in the loaded scene; ignored"
                    ));
                    continue;
                };
                let (interpolation, times) = self.sampler_keys(sampler, &place)?;
                let (input, output) = (sampler.input.value(), sampler.output.value());
                let what = format!("{place} output");
                let values = match property {
                    P::Translation => ChannelValues::Translation(
                        self.read_vecs::<3>(output, &what)?
                            .into_iter()
                            .map(Vec3::from)
                            .collect(),
                    ),
                    P::Scale => ChannelValues::Scale(
                        self.read_vecs::<3>(output, &what)?
                            .into_iter()
                            .map(Vec3::from)
                            .collect(),
                    ),
                    P::Rotation => ChannelValues::Rotation(
                        self.read_vecs::<4>(output, &what)?
                            .into_iter()
                            .map(Vec4::from)
                            .collect(),
                    ),
                    P::MorphTargetWeights => continue,
                };
                let channel = Channel {
                    node,
                    times,
                    values,
                    interpolation,
                };
                channel.validate().map_err(|m| {
                    self.malformed(format!("{place} (accessors {input}/{output})"), m)
                })?;
                targeted.push(node);
                channels.push(channel);
            }
            let properties = self.pointer_channels(ai, &name)?;
            if channels.is_empty() && properties.is_empty() {
                self.warn(format!(
                    "animation {ai} '{}': no usable channel; skipped",
                    excerpt(&name)
                ));
                continue;
            }
            self.builder.animation(Animation {
                name,
                channels,
                properties,
            });
        }
        Ok(targeted)
    }
}
