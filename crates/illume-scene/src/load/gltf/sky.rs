//! The sky in the document's root `extras.illume_sky`.

use crate::load::LoadError;
use crate::model::Sky;
use ::gltf::json;
use illume_core::Rgb;
use std::path::Path;

/// The sky declared in the document's root `extras` (no standard glTF extension holds
/// a renderable sky), exactly one of `{"illume_sky": {"radiance": [R, G, B]}}`
/// [W/(m²·sr)] or `{"illume_sky": {"equirect": "FILE", "scale": S, "rotation_deg": A}}`
/// (FILE relative to the glTF, linear `.exr`/`.hdr`; S defaults to 1, A to 0). Anything
/// else under `illume_sky` is an error naming the field.
pub(super) fn sky_from_extras(path: &Path, root: &json::Root) -> Result<Option<Sky>, LoadError> {
    let Some(raw) = &root.extras else {
        return Ok(None);
    };
    let place = "extras.illume_sky";
    let value: serde_json::Value = serde_json::from_str(raw.get())
        .map_err(|e| LoadError::malformed(path, "extras", e.to_string()))?;
    let Some(sky) = value.get("illume_sky") else {
        return Ok(None);
    };
    let Some(table) = sky.as_object() else {
        return Err(LoadError::malformed(path, place, "must be an object"));
    };
    const KEYS: [&str; 4] = ["radiance", "equirect", "scale", "rotation_deg"];
    if let Some(key) = table.keys().find(|k| !KEYS.contains(&k.as_str())) {
        return Err(LoadError::malformed(
            path,
            place,
            format!("unknown key '{key}' (have: {})", KEYS.join(", ")),
        ));
    }
    let number = |key: &str, default: f32| -> Result<f32, LoadError> {
        match table.get(key) {
            None => Ok(default),
            Some(v) => v
                .as_f64()
                .map(|v| v as f32)
                .filter(|v| v.is_finite())
                .ok_or_else(|| {
                    LoadError::malformed(path, format!("{place}.{key}"), "must be a finite number")
                }),
        }
    };
    match (table.get("radiance"), table.get("equirect")) {
        (Some(_), Some(_)) => Err(LoadError::malformed(
            path,
            place,
            "give exactly one of `radiance` and `equirect`",
        )),
        (None, None) => Err(LoadError::malformed(
            path,
            place,
            "needs `radiance` [R, G, B] or `equirect` \"FILE\"",
        )),
        (Some(radiance), None) => {
            if table.contains_key("scale") || table.contains_key("rotation_deg") {
                return Err(LoadError::malformed(
                    path,
                    place,
                    "`scale` and `rotation_deg` belong to `equirect`",
                ));
            }
            let bad = || {
                LoadError::malformed(
                    path,
                    format!("{place}.radiance"),
                    "must be three finite numbers ≥ 0 [W/(m²·sr)]",
                )
            };
            let list = radiance.as_array().ok_or_else(bad)?;
            let c: Vec<f32> = list
                .iter()
                .filter_map(|v| v.as_f64())
                .map(|v| v as f32)
                .collect();
            if list.len() != 3 || c.len() != 3 || c.iter().any(|v| !v.is_finite() || *v < 0.0) {
                return Err(bad());
            }
            Ok(Some(Sky::Uniform {
                radiance: Rgb::new(c[0], c[1], c[2]),
            }))
        }
        (None, Some(file)) => {
            let file = file.as_str().ok_or_else(|| {
                LoadError::malformed(path, format!("{place}.equirect"), "must be a file name")
            })?;
            let scale = number("scale", 1.0)?;
            let rotation = number("rotation_deg", 0.0)?;
            let folder = path.parent().unwrap_or(Path::new("."));
            crate::load::load_envmap(&folder.join(file), scale, rotation)
                .map(Some)
                .map_err(|e| LoadError::malformed(path, format!("{place}.equirect"), e.to_string()))
        }
    }
}
