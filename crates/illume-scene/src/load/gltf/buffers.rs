//! The document's bytes: the GLB container's header, and the buffers (GLB binary chunk,
//! data URIs, files beside the document).

use crate::load::{LoadError, read_referenced_file};
use ::gltf::json;
use std::path::Path;

/// Checks the 12-byte GLB header before the `gltf` crate reads it (it subtracts 12 from
/// the declared length without checking, which overflows on a corrupt header).
pub(super) fn check_glb_header(path: &Path, bytes: &[u8]) -> Result<(), LoadError> {
    let place = "GLB header";
    let word = |at: usize| {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let (Some(version), Some(length)) = (word(4), word(8)) else {
        return Err(LoadError::malformed(
            path,
            place,
            format!(
                "file has {} bytes, the header needs 12 (truncated)",
                bytes.len()
            ),
        ));
    };
    if version != 2 {
        return Err(LoadError::unsupported(
            path,
            place,
            format!("GLB version {version} (only 2)"),
        ));
    }
    if length < 20 {
        return Err(LoadError::malformed(
            path,
            place,
            format!("declared length {length} is too small for a JSON chunk"),
        ));
    }
    if length as usize > bytes.len() {
        return Err(LoadError::malformed(
            path,
            place,
            format!(
                "declared length {length} but the file has {} bytes (truncated)",
                bytes.len()
            ),
        ));
    }
    Ok(())
}

/// Reads every buffer: the GLB binary chunk, a data URI or a file next to the glTF.
pub(super) fn load_buffers(
    path: &Path,
    folder: &Path,
    root: &json::Root,
    blob: Option<&[u8]>,
) -> Result<Vec<Vec<u8>>, LoadError> {
    let mut out = Vec::with_capacity(root.buffers.len());
    for (i, b) in root.buffers.iter().enumerate() {
        let place = format!("buffer {i}");
        let data = match b.uri.as_deref() {
            None => blob
                .ok_or_else(|| {
                    LoadError::malformed(path, &place, "no uri and no GLB binary chunk")
                })?
                .to_vec(),
            Some(uri) if uri.starts_with("data:") => {
                decode_data_uri(uri).map_err(|m| LoadError::malformed(path, &place, m))?
            }
            Some(uri) => read_referenced_file(path, &place, &folder.join(decode_uri_path(uri)))?,
        };
        let need = b.byte_length.0;
        if (data.len() as u64) < need {
            return Err(LoadError::malformed(
                path,
                place,
                format!(
                    "has {} bytes but byteLength is {need} (truncated?)",
                    data.len()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// Decodes `data:[<media type>][;base64],<data>`.
pub(super) fn decode_data_uri(uri: &str) -> Result<Vec<u8>, String> {
    let (header, data) = uri.split_once(',').ok_or("data URI without ','")?;
    if header.ends_with(";base64") {
        base64::decode(data.trim()).map_err(|e| format!("bad base64 in data URI: {e}"))
    } else {
        Ok(urlencoding::decode_binary(data.as_bytes()).into_owned())
    }
}

/// A relative URI as a file path (percent-decoded).
pub(super) fn decode_uri_path(uri: &str) -> String {
    urlencoding::decode(uri)
        .map(|s| s.into_owned())
        .unwrap_or_else(|_| uri.to_string())
}
