//! Images as NumPy arrays: EXR/PNG files, and the metrics of `illume compare`.

use crate::{detached, value_error};
use illume_core::Vec3;
use illume_core::image::{RgbImage, ToneMap, auto_exposure_ev};
use illume_metrics::{Metric, compare_images};
use numpy::{PyArray3, PyArrayMethods, PyReadonlyArray3, PyUntypedArrayMethods};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;

/// `image` as a float32 (height, width, 3) array.
pub(crate) fn to_array<'py>(py: Python<'py>, image: &RgbImage) -> Bound<'py, PyArray3<f32>> {
    let data: Vec<f32> = image.pixels().iter().flat_map(|p| p.to_array()).collect();
    let shape = [image.height() as usize, image.width() as usize, 3];
    numpy::PyArray1::from_vec(py, data)
        .reshape(shape)
        .expect("width × height × 3 values")
}

/// The argument `name`, a float32 (height, width, 3) array, as an image; ValueError
/// naming the argument when its shape is not that. (The Python wrappers convert other
/// float dtypes and name the dtype when it is no float.)
pub(crate) fn from_array(name: &str, array: &PyReadonlyArray3<'_, f32>) -> PyResult<RgbImage> {
    let shape = array.shape();
    if shape[2] != 3 || shape[0] == 0 || shape[1] == 0 {
        return Err(value_error(format!(
            "{name}: shape {shape:?}, expected (height, width, 3) with height, width ≥ 1"
        )));
    }
    let (height, width) = (shape[0], shape[1]);
    let too_big = |n: usize| u32::try_from(n).is_err();
    if too_big(height) || too_big(width) {
        return Err(value_error(format!("{name}: shape {shape:?} is too large")));
    }
    let view = array.as_array();
    let pixels: Vec<Vec3> = view
        .outer_iter()
        .flat_map(|row| {
            row.outer_iter()
                .map(|p| Vec3::new(p[0], p[1], p[2]))
                .collect::<Vec<_>>()
        })
        .collect();
    Ok(RgbImage::from_vec(width as u32, height as u32, pixels).expect("width × height pixels"))
}

/// Image metrics of `test` against `reference` (float32 (height, width, 3) arrays of
/// radiance), as `illume compare` computes them: `metrics` is a list of names or one
/// comma-separated string of `rmse`, `relmse`, `psnr`, `ssim`, `flip`, `hdr-flip`
/// (default: all). Returns a dict from metric name to value.
#[pyfunction]
#[pyo3(signature = (reference, test, metrics=None))]
pub fn compare<'py>(
    py: Python<'py>,
    reference: PyReadonlyArray3<'py, f32>,
    test: PyReadonlyArray3<'py, f32>,
    metrics: Option<Vec<String>>,
) -> PyResult<Bound<'py, PyDict>> {
    let metrics: Vec<Metric> = match metrics {
        None => Metric::ALL.to_vec(),
        Some(list) => {
            illume_metrics::compare::parse_metric_list(&list.join(",")).map_err(value_error)?
        }
    };
    let r = from_array("reference", &reference)?;
    let t = from_array("test", &test)?;
    let values = detached(py, move || {
        compare_images(&r, &t, &metrics).map_err(value_error)
    })?;
    let d = PyDict::new(py);
    for (m, v) in values {
        d.set_item(m.name(), v)?;
    }
    Ok(d)
}

/// Reads an image file: `.exr` or `.hdr` (linear radiance), `.png` or `.jpg` (sRGB
/// decoded to linear), as float32 (height, width, 3). ValueError names the file.
#[pyfunction]
pub fn read_image(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyArray3<f32>>> {
    let image = detached(py, move || RgbImage::read(&path).map_err(value_error))?;
    Ok(to_array(py, &image))
}

/// Writes a float32 (height, width, 3) radiance array: `.exr` as it is, `.png`
/// tone-mapped as `illume render` writes it (automatic exposure plus `exposure` stops,
/// or `exposure` alone with `exposure_mode="fixed"`). The file is written whole or not
/// at all (a temporary file renamed).
#[pyfunction]
#[pyo3(signature = (path, image, exposure=0.0, exposure_mode="auto"))]
pub fn write_image(
    py: Python<'_>,
    path: PathBuf,
    image: PyReadonlyArray3<'_, f32>,
    exposure: f32,
    exposure_mode: &str,
) -> PyResult<()> {
    if !(exposure.is_finite() && exposure.abs() <= 64.0) {
        return Err(value_error(format!(
            "exposure={exposure}: must be finite and within ±64 stops"
        )));
    }
    let image = from_array("image", &image)?;
    let auto = match exposure_mode {
        "auto" => true,
        "fixed" => false,
        other => {
            return Err(value_error(format!(
                "exposure_mode='{other}': expected 'auto' or 'fixed'"
            )));
        }
    };
    detached(py, move || {
        let base = if auto {
            auto_exposure_ev(&image).unwrap_or(0.0)
        } else {
            0.0
        };
        let tone = ToneMap {
            exposure_ev: base + exposure,
            ..Default::default()
        };
        image.write(&path, &tone).map_err(value_error)
    })
}
