//! `KHR_lights_punctual` lights, radiometric (see DESIGN.md "Conventions").

use super::Ctx;
use crate::load::{LoadError, excerpt};
use crate::model::{LightKind, NodeId};
use ::gltf::json;
use illume_core::Rgb;
use json::validation::Checked;

impl Ctx<'_> {
    /// Adds the `KHR_lights_punctual` light of glTF node `g`, if any, at `node`.
    pub(super) fn light(
        &mut self,
        g: usize,
        node_name: &str,
        node: NodeId,
    ) -> Result<(), LoadError> {
        use json::extensions::scene::khr_lights_punctual::Type;
        let root = self.root;
        let Some(index) = root.nodes[g]
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .map(|l| l.light.value())
        else {
            return Ok(());
        };
        let place = format!("node {g} '{}' light {index}", excerpt(node_name));
        let light = root
            .extensions
            .as_ref()
            .and_then(|e| e.khr_lights_punctual.as_ref())
            .and_then(|l| l.lights.get(index))
            .ok_or_else(|| self.malformed(&place, "light does not exist"))?;
        let colour = Rgb::from(light.color);
        let value = colour * light.intensity;
        if !value.is_finite() || value.min_element() < 0.0 {
            return Err(self.malformed(
                place,
                format!("intensity × colour {value} is not finite and non-negative"),
            ));
        }
        if let Some(range) = light.range {
            self.warn(format!(
                "{place}: range {range} ignored (pure inverse-square falloff)"
            ));
        }
        let kind = match light.type_ {
            Checked::Valid(Type::Point) => LightKind::Point { intensity: value },
            Checked::Valid(Type::Directional) => LightKind::Directional { irradiance: value },
            Checked::Valid(Type::Spot) => {
                let spot = light.spot.as_ref().ok_or_else(|| {
                    self.malformed(&place, "spot light without 'spot' cone angles")
                })?;
                let (inner, outer) = (spot.inner_cone_angle, spot.outer_cone_angle);
                if !(inner.is_finite()
                    && outer.is_finite()
                    && 0.0 <= inner
                    && inner < outer
                    && outer <= std::f32::consts::FRAC_PI_2)
                {
                    return Err(self.malformed(place, format!("spot cone angles inner {inner}, outer {outer} must satisfy 0 ≤ inner < outer ≤ π/2")));
                }
                LightKind::Spot {
                    intensity: value,
                    inner_cone_rad: inner,
                    outer_cone_rad: outer,
                }
            }
            Checked::Invalid => return Err(self.malformed(place, "invalid light type")),
        };
        let name = light.name.clone().unwrap_or_else(|| node_name.to_string());
        let id = self.builder.light(&name, kind, node);
        self.light_ids.entry(index).or_default().push(id);
        Ok(())
    }
}
