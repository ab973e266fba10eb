//! glTF and GLB cases: one valid document (a triangle, a camera, a point light, an
//! animation; its data in `tri.bin`) broken one way per case.

use crate::corpus::{Case, Expect, error, warning};
use serde_json::{Value, json};

/// Byte layout of `tri.bin`: positions, indices, key times, key translations.
const POSITIONS: usize = 0;
const INDICES: usize = 36;
const TIMES: usize = 44;
const BIN_LEN: usize = 76;

/// The buffer of the base document.
pub fn bin() -> Vec<u8> {
    let mut b = Vec::with_capacity(BIN_LEN);
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]] {
        for x in v {
            b.extend_from_slice(&x.to_le_bytes());
        }
    }
    for i in [0u16, 1, 2] {
        b.extend_from_slice(&i.to_le_bytes());
    }
    b.extend_from_slice(&[0, 0]);
    for t in [0.0f32, 1.0] {
        b.extend_from_slice(&t.to_le_bytes());
    }
    for v in [[0.0f32, 0.0, 0.0], [0.0, 0.5, 0.0]] {
        for x in v {
            b.extend_from_slice(&x.to_le_bytes());
        }
    }
    assert_eq!(b.len(), BIN_LEN);
    b
}

/// `tri.bin` with the f32 at byte `at` replaced.
fn bin_with(at: usize, value: f32) -> Vec<u8> {
    let mut b = bin();
    b[at..at + 4].copy_from_slice(&value.to_le_bytes());
    b
}

/// The valid base document.
pub fn doc() -> Value {
    json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "intensity": 1.0, "color": [1.0, 1.0, 1.0]}
        ]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [
            {"name": "tri", "mesh": 0},
            {"name": "cam", "camera": 0, "translation": [0.3, 0.3, 2.0]},
            {"name": "lamp", "translation": [0.3, 0.3, 1.0],
             "extensions": {"KHR_lights_punctual": {"light": 0}}}
        ],
        "cameras": [{"type": "perspective",
                     "perspective": {"yfov": 0.8, "znear": 0.01, "zfar": 100.0}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "material": 0}]}],
        "materials": [{"name": "grey",
                       "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0],
                                                "metallicFactor": 0.0}}],
        "buffers": [{"uri": "tri.bin", "byteLength": BIN_LEN}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 6},
            {"buffer": 0, "byteOffset": 44, "byteLength": 8},
            {"buffer": 0, "byteOffset": 52, "byteLength": 24}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 0.0]},
            {"bufferView": 1, "componentType": 5123, "count": 3, "type": "SCALAR"},
            {"bufferView": 2, "componentType": 5126, "count": 2, "type": "SCALAR",
             "min": [0.0], "max": [1.0]},
            {"bufferView": 3, "componentType": 5126, "count": 2, "type": "VEC3"}
        ],
        "animations": [{"name": "slide",
                        "channels": [{"sampler": 0, "target": {"node": 0, "path": "translation"}}],
                        "samplers": [{"input": 2, "output": 3, "interpolation": "LINEAR"}]}]
    })
}

/// Two f32 keys (2, 2), (−1, −1) and (0.5, 0.5) as base64 data URIs.
const TWO_TWO: &str = "AAAAQAAAAEA=";
const MINUS_ONES: &str = "AACAvwAAgL8=";
const HALVES: &str = "AAAAPwAAAD8=";

/// Makes animation 0's channel a `KHR_animation_pointer` channel on `pointer` whose
/// two scalar keys (at the base's times 0 and 1) come from `keys` (a data URI buffer).
fn animate_scalar(d: &mut Value, pointer: &str, keys: &str) {
    d["extensionsUsed"] = json!(["KHR_lights_punctual", "KHR_animation_pointer"]);
    d["buffers"].as_array_mut().expect("buffers").push(
        json!({"uri": format!("data:application/octet-stream;base64,{keys}"), "byteLength": 8}),
    );
    d["bufferViews"]
        .as_array_mut()
        .expect("views")
        .push(json!({"buffer": 1, "byteOffset": 0, "byteLength": 8}));
    d["accessors"]
        .as_array_mut()
        .expect("accessors")
        .push(json!({"bufferView": 4, "componentType": 5126, "count": 2, "type": "SCALAR"}));
    d["animations"][0]["samplers"][0]["output"] = json!(4);
    d["animations"][0]["channels"][0] = json!({"sampler": 0, "target": {"path": "pointer",
        "extensions": {"KHR_animation_pointer": {"pointer": pointer}}}});
}

/// The base document changed by `edit`, as `.gltf` text.
fn edited(edit: impl FnOnce(&mut Value)) -> Vec<u8> {
    let mut d = doc();
    edit(&mut d);
    serde_json::to_vec_pretty(&d).expect("JSON")
}

/// A `.gltf` case: `x.gltf` (the base with `edit`) beside the valid `tri.bin`.
fn gltf(name: &str, edit: impl FnOnce(&mut Value), expect: Expect) -> Case {
    Case::new("gltf", name)
        .file("x.gltf", edited(edit))
        .file("tri.bin", bin())
        .scene("x.gltf", expect)
}

/// A `.gltf` case whose `tri.bin` is `bin`.
fn gltf_bin(name: &str, bin: Vec<u8>, expect: Expect) -> Case {
    Case::new("gltf", name)
        .file("x.gltf", edited(|_| {}))
        .file("tri.bin", bin)
        .scene("x.gltf", expect)
}

/// A GLB container: header, JSON chunk (space-padded), optional BIN chunk
/// (zero-padded).
pub fn glb(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let mut json = json.to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut body = Vec::new();
    body.extend_from_slice(&(json.len() as u32).to_le_bytes());
    body.extend_from_slice(b"JSON");
    body.extend_from_slice(&json);
    if let Some(bin) = bin {
        let mut bin = bin.to_vec();
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        body.extend_from_slice(&(bin.len() as u32).to_le_bytes());
        body.extend_from_slice(b"BIN\0");
        body.extend_from_slice(&bin);
    }
    let mut out = Vec::new();
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&((12 + body.len()) as u32).to_le_bytes());
    out.extend_from_slice(&body);
    out
}

/// The base document as a valid GLB (its buffer is the BIN chunk).
fn valid_glb() -> Vec<u8> {
    let json = edited(|d| d["buffers"][0] = json!({"byteLength": BIN_LEN}));
    glb(&json, Some(&bin()))
}

/// A GLB case: `x.glb` is the valid GLB changed by `edit`.
fn glb_case(name: &str, edit: impl FnOnce(&mut Vec<u8>), expect: Expect) -> Case {
    let mut bytes = valid_glb();
    edit(&mut bytes);
    Case::new("glb", name)
        .file("x.glb", bytes)
        .scene("x.glb", expect)
}

fn set_u32(b: &mut [u8], at: usize, v: u32) {
    b[at..at + 4].copy_from_slice(&v.to_le_bytes());
}

/// Every glTF and GLB case.
pub fn cases() -> Vec<Case> {
    let f = "x.gltf";
    let mut c = vec![
        // Baseline: the unbroken document loads and renders.
        gltf("valid", |_| {}, Expect::Success),
        // --- JSON ---
        Case::new("gltf", "json_syntax_error")
            .file(
                "x.gltf",
                &b"{\"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [,]\n}"[..],
            )
            .scene("x.gltf", error(&[f, "JSON", "line 2"])),
        Case::new("gltf", "empty_file")
            .file("x.gltf", Vec::new())
            .scene("x.gltf", error(&[f, "JSON"])),
        Case::new("gltf", "json_array_at_root")
            .file("x.gltf", &b"[1, 2, 3]"[..])
            .scene("x.gltf", error(&[f, "JSON"])),
        Case::new("gltf", "json_nan_literal")
            .file(
                "x.gltf",
                String::from_utf8(edited(|_| {}))
                    .unwrap()
                    .replace("[\n        0.3,", "[\n        NaN,"),
            )
            .file("tri.bin", bin())
            .scene("x.gltf", error(&[f, "JSON"])),
        Case::new("gltf", "json_deeply_nested")
            .file(
                "x.gltf",
                format!(
                    "{{\"asset\": {{\"version\": \"2.0\"}}, \"extras\": {}{}}}",
                    "[".repeat(100_000),
                    "]".repeat(100_000)
                ),
            )
            .scene("x.gltf", error(&[f, "extras", "recursion limit"])),
        Case::new("gltf", "json_deeply_nested_extension")
            .file(
                "x.gltf",
                format!(
                    "{{\"asset\": {{\"version\": \"2.0\"}}, \"extensions\": {{\"X\": {}{}}}}}",
                    "[".repeat(100_000),
                    "]".repeat(100_000)
                ),
            )
            .scene("x.gltf", error(&[f, "JSON", "recursion limit"])),
        gltf(
            "nodes_is_a_string",
            |d| d["nodes"] = json!("many"),
            error(&[f, "JSON", "nodes"]),
        ),
        gltf(
            "translation_is_a_string",
            |d| d["nodes"][1]["translation"] = json!("up"),
            error(&[f, "JSON"]),
        ),
        gltf(
            "asset_missing",
            |d| {
                d.as_object_mut().unwrap().remove("asset");
            },
            error(&[f, "asset"]),
        ),
        gltf(
            "asset_version_1",
            |d| d["asset"]["version"] = json!("1.0"),
            error(&[f, "asset.version", "1.0"]),
        ),
        gltf(
            "extension_required_unknown",
            |d| d["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]),
            error(&[f, "extensionsRequired[0]", "KHR_draco_mesh_compression"]),
        ),
        // --- accessors ---
        gltf(
            "position_accessor_out_of_range",
            |d| d["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(99),
            error(&[f, "mesh 0 primitive 0", "accessor 99"]),
        ),
        gltf(
            "indices_accessor_out_of_range",
            |d| d["meshes"][0]["primitives"][0]["indices"] = json!(99),
            error(&[f, "indices"]),
        ),
        gltf(
            "accessor_component_type_invalid",
            |d| d["accessors"][0]["componentType"] = json!(5130),
            error(&[f, "accessors[0]", "componentType"]),
        ),
        gltf(
            "position_component_type_byte",
            |d| d["accessors"][0]["componentType"] = json!(5121),
            error(&[f, "accessor 0", "POSITION", "componentType"]),
        ),
        gltf(
            "position_type_mat4",
            |d| d["accessors"][0]["type"] = json!("MAT4"),
            error(&[f, "accessor 0"]),
        ),
        gltf(
            "accessor_type_unknown",
            |d| d["accessors"][0]["type"] = json!("VEC7"),
            error(&[f, "accessors[0]", "type"]),
        ),
        gltf(
            "indices_type_vec3",
            |d| {
                d["accessors"][1]["type"] = json!("VEC3");
                d["accessors"][1]["count"] = json!(1);
            },
            error(&[f, "accessor 1", "SCALAR"]),
        ),
        gltf(
            "accessor_count_beyond_buffer_view",
            |d| d["accessors"][0]["count"] = json!(1000),
            error(&[f, "accessor 0", "bufferView 0"]),
        ),
        gltf(
            "accessor_count_u32_max",
            |d| d["accessors"][0]["count"] = json!(u32::MAX),
            error(&[f, "accessor 0"]),
        ),
        gltf(
            "accessor_count_zero",
            |d| {
                d["accessors"][0]["count"] = json!(0);
                d["accessors"][1]["count"] = json!(0);
            },
            error(&[f, "accessor 0", "count 0"]),
        ),
        gltf(
            "accessor_byte_offset_past_view",
            |d| d["accessors"][0]["byteOffset"] = json!(4_000_000_000u64),
            error(&[f, "accessor 0"]),
        ),
        gltf(
            "accessor_without_view_huge_count",
            |d| {
                let a = d["accessors"][0].as_object_mut().unwrap();
                a.remove("bufferView");
                a.insert("count".into(), json!(4_000_000_000u64));
            },
            error(&[f, "accessors[0]"]),
        ),
        gltf_bin(
            "index_value_out_of_range",
            {
                let mut b = bin();
                b[INDICES + 4..INDICES + 6].copy_from_slice(&7u16.to_le_bytes());
                b
            },
            error(&[f, "accessor 1", "index 2 = 7", "out of range"]),
        ),
        gltf(
            "indices_not_a_multiple_of_three",
            |d| {
                d["accessors"][1]["count"] = json!(2);
            },
            error(&[f, "mesh 0", "multiple of 3"]),
        ),
        gltf(
            "sparse_accessor",
            |d| {
                d["accessors"][0]["sparse"] = json!({"count": 1,
                    "indices": {"bufferView": 1, "componentType": 5123},
                    "values": {"bufferView": 0}})
            },
            error(&[f, "accessor 0", "sparse"]),
        ),
        gltf(
            "no_position",
            |d| d["meshes"][0]["primitives"][0]["attributes"] = json!({"NORMAL": 0}),
            error(&[f, "meshes[0].primitives[0]", "POSITION"]),
        ),
        gltf(
            "normal_count_mismatch",
            |d| d["meshes"][0]["primitives"][0]["attributes"]["NORMAL"] = json!(3),
            error(&[f, "NORMAL", "normals for 3 positions"]),
        ),
        gltf(
            "primitive_mode_points",
            |d| d["meshes"][0]["primitives"][0]["mode"] = json!(0),
            error(&[f, "mesh 0", "TRIANGLES"]),
        ),
        gltf(
            "primitive_mode_invalid",
            |d| d["meshes"][0]["primitives"][0]["mode"] = json!(42),
            error(&[f, "mode"]),
        ),
        gltf(
            "mesh_out_of_range",
            |d| d["nodes"][0]["mesh"] = json!(7),
            error(&[f, "nodes[0].mesh"]),
        ),
        gltf(
            "material_out_of_range",
            |d| d["meshes"][0]["primitives"][0]["material"] = json!(7),
            error(&[f, "material"]),
        ),
        // --- buffer views and buffers ---
        gltf(
            "buffer_view_past_buffer",
            |d| d["bufferViews"][0]["byteLength"] = json!(1000),
            error(&[f, "bufferView 0", "buffer 0"]),
        ),
        gltf(
            "buffer_view_offset_u64_max",
            |d| d["bufferViews"][0]["byteOffset"] = json!(u64::MAX),
            error(&[f, "bufferView"]),
        ),
        gltf(
            "buffer_view_stride_too_small",
            |d| d["bufferViews"][0]["byteStride"] = json!(2),
            error(&[f, "byteStride"]),
        ),
        gltf(
            "buffer_view_buffer_out_of_range",
            |d| d["bufferViews"][0]["buffer"] = json!(3),
            error(&[f, "bufferViews[0].buffer"]),
        ),
        gltf(
            "buffer_byte_length_beyond_file",
            |d| d["buffers"][0]["byteLength"] = json!(100_000),
            error(&[f, "buffer 0", "truncated"]),
        ),
        gltf(
            "buffer_byte_length_u64_max",
            |d| d["buffers"][0]["byteLength"] = json!(u64::MAX),
            error(&[f, "buffer 0"]),
        ),
        Case::new("gltf", "buffer_file_missing")
            .file("x.gltf", edited(|_| {}))
            .scene("x.gltf", error(&[f, "buffer 0", "tri.bin"])),
        Case::new("gltf", "buffer_is_a_folder")
            .file("x.gltf", edited(|_| {}))
            .dir("tri.bin")
            .scene("x.gltf", error(&[f, "buffer 0", "tri.bin"])),
        Case::new("gltf", "buffer_is_a_pipe")
            .file("x.gltf", edited(|_| {}))
            .fifo("tri.bin")
            .scene(
                "x.gltf",
                error(&[f, "buffer 0", "tri.bin", "not a regular file"]),
            ),
        gltf(
            "buffer_is_dev_zero",
            |d| d["buffers"][0]["uri"] = json!("/dev/zero"),
            error(&[f, "buffer 0", "/dev/zero", "not a regular file"]),
        ),
        gltf(
            "buffer_uri_percent_garbage",
            |d| d["buffers"][0]["uri"] = json!("%ff%fe%00.bin"),
            error(&[f, "buffer 0"]),
        ),
        gltf(
            "buffer_uri_one_megabyte",
            |d| d["buffers"][0]["uri"] = json!("b".repeat(1 << 20)),
            error(&[f, "buffer 0", "file name"]),
        ),
        gltf(
            "data_uri_bad_base64",
            |d| d["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,@@@@!!"),
            error(&[f, "buffer 0", "base64"]),
        ),
        gltf(
            "data_uri_without_comma",
            |d| d["buffers"][0]["uri"] = json!("data:application/octet-stream;base64"),
            error(&[f, "buffer 0", "data URI"]),
        ),
        gltf(
            "data_uri_too_short",
            |d| d["buffers"][0]["uri"] = json!("data:application/octet-stream;base64,AAAA"),
            error(&[f, "buffer 0", "truncated"]),
        ),
        gltf(
            "no_buffer_uri_outside_glb",
            |d| d["buffers"][0] = json!({"byteLength": BIN_LEN}),
            error(&[f, "buffer 0", "no uri"]),
        ),
        // --- binary data ---
        gltf_bin(
            "position_nan",
            bin_with(POSITIONS, f32::NAN),
            error(&[f, "accessor 0", "not finite"]),
        ),
        gltf_bin(
            "position_infinite",
            bin_with(POSITIONS + 4, f32::INFINITY),
            error(&[f, "accessor 0", "not finite"]),
        ),
        gltf_bin(
            "position_huge",
            bin_with(POSITIONS, 3e38),
            error(&[f, "instance 0", "beyond", "1e18"]),
        ),
        // --- node hierarchy ---
        gltf(
            "hierarchy_cycle",
            |d| {
                d["nodes"][0]["children"] = json!([1]);
                d["nodes"][1]["children"] = json!([0]);
                d["scenes"][0]["nodes"] = json!([0, 2]);
            },
            error(&[f, "node 0", "cycle"]),
        ),
        gltf(
            "node_is_its_own_child",
            |d| d["nodes"][0]["children"] = json!([0]),
            error(&[f, "node 0", "cycle"]),
        ),
        gltf(
            "node_with_two_parents",
            |d| {
                d["nodes"][1]["children"] = json!([0]);
                d["nodes"][2]["children"] = json!([0]);
                d["scenes"][0]["nodes"] = json!([1, 2]);
            },
            error(&[f, "node 0", "one parent"]),
        ),
        gltf(
            "cycle_without_a_scene",
            |d| {
                let o = d.as_object_mut().unwrap();
                o.remove("scene");
                o.remove("scenes");
                d["nodes"][0]["children"] = json!([1]);
                d["nodes"][1]["children"] = json!([0]);
            },
            error(&[f, "node 0", "cycle"]),
        ),
        gltf(
            "root_listed_twice",
            |d| d["scenes"][0]["nodes"] = json!([0, 1, 2, 0]),
            error(&[f, "node 0", "reached twice"]),
        ),
        gltf(
            "child_out_of_range",
            |d| d["nodes"][0]["children"] = json!([42]),
            error(&[f, "nodes[0].children"]),
        ),
        gltf(
            "scene_node_out_of_range",
            |d| d["scenes"][0]["nodes"] = json!([0, 1, 2, 9]),
            error(&[f, "scenes[0].nodes"]),
        ),
        gltf(
            "default_scene_out_of_range",
            |d| d["scene"] = json!(5),
            error(&[f, "scene"]),
        ),
        gltf(
            "empty_scene",
            |d| d["scenes"][0]["nodes"] = json!([]),
            Expect::Success,
        ),
        // --- numbers in transforms ---
        gltf(
            "translation_1e39",
            |d| d["nodes"][0]["translation"] = json!([1e39, 0.0, 0.0]),
            error(&[f, "node 0", "not finite"]),
        ),
        gltf(
            "scale_minus_1e39",
            |d| d["nodes"][0]["scale"] = json!([1.0, -1e39, 1.0]),
            error(&[f, "node 0", "not finite"]),
        ),
        gltf(
            "rotation_zero_quaternion",
            |d| d["nodes"][0]["rotation"] = json!([0.0, 0.0, 0.0, 0.0]),
            error(&[f, "node 0", "quaternion"]),
        ),
        gltf(
            "rotation_1e39",
            |d| d["nodes"][0]["rotation"] = json!([1e39, 0.0, 0.0, 1.0]),
            error(&[f, "node 0"]),
        ),
        gltf(
            "matrix_1e39",
            |d| {
                d["nodes"][0]["matrix"] = json!([
                    1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1e39, 0.0, 0.0, 1.0
                ])
            },
            error(&[f, "node 0", "matrix"]),
        ),
        gltf(
            "matrix_all_zero",
            |d| d["nodes"][0]["matrix"] = json!(vec![0.0; 16]),
            error(&[f, "node 0"]),
        ),
        gltf(
            "mesh_node_scale_zero",
            |d| d["nodes"][0]["scale"] = json!([0.0, 0.0, 0.0]),
            // Scaling to zero hides an object (animations do it): accepted.
            Expect::Success,
        ),
        gltf(
            "translation_3e38",
            |d| d["nodes"][0]["translation"] = json!([3e38, 0.0, 0.0]),
            error(&[f, "instance 0", "beyond", "1e18"]),
        ),
        gltf(
            "mirrored_node",
            |d| d["nodes"][0]["scale"] = json!([-1.0, 1.0, 1.0]),
            Expect::Success,
        ),
        // --- cameras ---
        gltf(
            "camera_node_scale_zero",
            |d| d["nodes"][1]["scale"] = json!([0.0, 0.0, 0.0]),
            error(&[f, "camera", "node 1"]),
        ),
        gltf(
            "camera_yfov_zero",
            |d| d["cameras"][0]["perspective"]["yfov"] = json!(0.0),
            error(&[f, "camera 0", "yfov"]),
        ),
        gltf(
            "camera_yfov_pi",
            |d| d["cameras"][0]["perspective"]["yfov"] = json!(std::f64::consts::PI),
            error(&[f, "camera 0", "yfov"]),
        ),
        gltf(
            "camera_yfov_1e39",
            |d| d["cameras"][0]["perspective"]["yfov"] = json!(1e39),
            error(&[f, "camera 0", "yfov"]),
        ),
        gltf(
            "camera_znear_zero",
            |d| d["cameras"][0]["perspective"]["znear"] = json!(0.0),
            error(&[f, "camera 0", "znear"]),
        ),
        gltf(
            "camera_znear_negative",
            |d| d["cameras"][0]["perspective"]["znear"] = json!(-1.0),
            error(&[f, "camera 0", "znear"]),
        ),
        gltf(
            "camera_zfar_below_znear",
            |d| d["cameras"][0]["perspective"]["zfar"] = json!(0.001),
            error(&[f, "camera 0", "zfar"]),
        ),
        gltf(
            "camera_aspect_ratio_zero",
            |d| d["cameras"][0]["perspective"]["aspectRatio"] = json!(0.0),
            error(&[f, "camera 0", "aspectRatio"]),
        ),
        gltf(
            "camera_without_perspective",
            |d| {
                d["cameras"][0]
                    .as_object_mut()
                    .unwrap()
                    .remove("perspective");
            },
            error(&[f, "cameras[0]"]),
        ),
        gltf(
            "camera_orthographic",
            |d| {
                d["cameras"][0] = json!({"type": "orthographic",
                    "orthographic": {"xmag": 1.0, "ymag": 1.0, "znear": 0.01, "zfar": 100.0}})
            },
            warning(&[f, "camera 0", "perspective"]),
        ),
        gltf(
            "camera_out_of_range",
            |d| d["nodes"][1]["camera"] = json!(4),
            error(&[f, "nodes[1].camera"]),
        ),
        gltf(
            "camera_looking_from_1e38",
            |d| d["nodes"][1]["translation"] = json!([1e38, 0.0, 0.0]),
            error(&[f, "camera", "beyond", "1e18"]),
        ),
        // --- materials ---
        gltf(
            "base_color_1e39",
            |d| {
                d["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] =
                    json!([1e39, 0.5, 0.5, 1.0])
            },
            error(&[f, "material 0", "baseColorFactor"]),
        ),
        gltf(
            "base_color_negative",
            |d| {
                d["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] =
                    json!([-0.5, 0.5, 0.5, 1.0])
            },
            error(&[f, "material 0", "baseColorFactor"]),
        ),
        gltf(
            "base_color_above_one",
            |d| {
                d["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] =
                    json!([2.0, 0.5, 0.5, 1.0])
            },
            error(&[f, "material 0", "baseColorFactor"]),
        ),
        gltf(
            "base_color_alpha_2",
            |d| {
                d["materials"][0]["pbrMetallicRoughness"]["baseColorFactor"] =
                    json!([0.5, 0.5, 0.5, 2.0])
            },
            error(&[f, "material 0", "alpha"]),
        ),
        gltf(
            "emissive_1e39",
            |d| d["materials"][0]["emissiveFactor"] = json!([1e39, 0.0, 0.0]),
            error(&[f, "material 0", "emissive"]),
        ),
        gltf(
            "emissive_negative",
            |d| d["materials"][0]["emissiveFactor"] = json!([-1.0, 0.0, 0.0]),
            error(&[f, "material 0", "emissive"]),
        ),
        gltf(
            "emissive_strength_1e39",
            |d| {
                d["extensionsUsed"] =
                    json!(["KHR_lights_punctual", "KHR_materials_emissive_strength"]);
                d["materials"][0]["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
                d["materials"][0]["extensions"] =
                    json!({"KHR_materials_emissive_strength": {"emissiveStrength": 1e39}});
            },
            error(&[f, "material 0", "emissive"]),
        ),
        gltf(
            "emissive_strength_1e36",
            |d| {
                d["extensionsUsed"] =
                    json!(["KHR_lights_punctual", "KHR_materials_emissive_strength"]);
                d["materials"][0]["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
                d["materials"][0]["extensions"] =
                    json!({"KHR_materials_emissive_strength": {"emissiveStrength": 1e36}});
            },
            error(&[f, "light power", "1.571e36", "1e30"]),
        ),
        gltf(
            "emissive_strength_negative",
            |d| {
                d["extensionsUsed"] =
                    json!(["KHR_lights_punctual", "KHR_materials_emissive_strength"]);
                d["materials"][0]["emissiveFactor"] = json!([1.0, 1.0, 1.0]);
                d["materials"][0]["extensions"] =
                    json!({"KHR_materials_emissive_strength": {"emissiveStrength": -5.0}});
            },
            error(&[f, "material 0", "emissive"]),
        ),
        gltf(
            "metallic_2",
            |d| d["materials"][0]["pbrMetallicRoughness"]["metallicFactor"] = json!(2.0),
            error(&[f, "material 0", "metallicFactor"]),
        ),
        gltf(
            "roughness_1e39",
            |d| d["materials"][0]["pbrMetallicRoughness"]["roughnessFactor"] = json!(1e39),
            error(&[f, "material 0", "roughnessFactor"]),
        ),
        gltf(
            "alpha_cutoff_negative",
            |d| {
                d["materials"][0]["alphaMode"] = json!("MASK");
                d["materials"][0]["alphaCutoff"] = json!(-1.0);
            },
            error(&[f, "material 0", "alphaCutoff"]),
        ),
        gltf(
            "alpha_mode_unknown",
            |d| d["materials"][0]["alphaMode"] = json!("GLASS"),
            error(&[f, "alphaMode"]),
        ),
        gltf(
            "alpha_mode_blend",
            |d| d["materials"][0]["alphaMode"] = json!("BLEND"),
            warning(&[f, "material 0", "BLEND"]),
        ),
        gltf(
            "normal_texture_scale_1e39",
            |d| {
                d["images"] = json!([{"uri": "missing.png"}]);
                d["textures"] = json!([{"source": 0}]);
                d["materials"][0]["normalTexture"] = json!({"index": 0, "scale": 1e39});
            },
            error(&[f, "material 0", "scale"]),
        ),
        gltf(
            "texture_transform_scale_1e39",
            |d| {
                d["extensionsUsed"] = json!(["KHR_lights_punctual", "KHR_texture_transform"]);
                d["images"] = json!([{"uri": "missing.png"}]);
                d["textures"] = json!([{"source": 0}]);
                d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0,
                    "extensions": {"KHR_texture_transform": {"scale": [1e39, 1.0]}}});
            },
            error(&[f, "material 0", "KHR_texture_transform"]),
        ),
        gltf(
            "texture_out_of_range",
            |d| d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 3}),
            error(&[f, "texture"]),
        ),
        gltf(
            "image_out_of_range",
            |d| {
                d["textures"] = json!([{"source": 5}]);
                d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0})
            },
            error(&[f, "textures[0].source"]),
        ),
        gltf(
            "image_without_uri_or_view",
            |d| {
                d["images"] = json!([{"name": "nothing"}]);
                d["textures"] = json!([{"source": 0}]);
                d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0})
            },
            error(&[f, "image 0"]),
        ),
        gltf(
            "image_buffer_view_out_of_range",
            |d| {
                d["images"] = json!([{"bufferView": 9, "mimeType": "image/png"}]);
                d["textures"] = json!([{"source": 0}]);
                d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0})
            },
            error(&[f, "images[0].bufferView"]),
        ),
        // --- lights ---
        gltf(
            "light_intensity_1e39",
            |d| d["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = json!(1e39),
            error(&[f, "light 0"]),
        ),
        gltf(
            "light_intensity_2e37",
            |d| d["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = json!(2e37),
            error(&[f, "light 0"]),
        ),
        gltf(
            "light_intensity_negative",
            |d| d["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = json!(-1.0),
            error(&[f, "light 0"]),
        ),
        gltf(
            "light_colour_1e39",
            |d| {
                d["extensions"]["KHR_lights_punctual"]["lights"][0]["color"] =
                    json!([1e39, 1.0, 1.0])
            },
            error(&[f, "light 0"]),
        ),
        gltf(
            "light_type_unknown",
            |d| d["extensions"]["KHR_lights_punctual"]["lights"][0]["type"] = json!("laser"),
            error(&[f, "type"]),
        ),
        gltf(
            "light_out_of_range",
            |d| d["nodes"][2]["extensions"]["KHR_lights_punctual"]["light"] = json!(8),
            error(&[f, "light"]),
        ),
        gltf(
            "spot_inner_above_outer",
            |d| {
                d["extensions"]["KHR_lights_punctual"]["lights"][0] = json!({"type": "spot",
                    "intensity": 1.0, "spot": {"innerConeAngle": 0.6, "outerConeAngle": 0.3}})
            },
            error(&[f, "light 0", "cone"]),
        ),
        gltf(
            "spot_outer_above_half_pi",
            |d| {
                d["extensions"]["KHR_lights_punctual"]["lights"][0] = json!({"type": "spot",
                    "intensity": 1.0, "spot": {"innerConeAngle": 0.1, "outerConeAngle": 3.0}})
            },
            error(&[f, "light 0", "cone"]),
        ),
        gltf(
            "light_range",
            |d| d["extensions"]["KHR_lights_punctual"]["lights"][0]["range"] = json!(5.0),
            warning(&[f, "light 0", "range"]),
        ),
        // A point light has no orientation: its node's scale does not matter.
        gltf(
            "point_light_node_scale_zero",
            |d| d["nodes"][2]["scale"] = json!([0.0, 0.0, 0.0]),
            Expect::Success,
        ),
        gltf(
            "spot_light_node_scale_zero",
            |d| {
                d["nodes"][2]["scale"] = json!([0.0, 0.0, 0.0]);
                d["extensions"]["KHR_lights_punctual"]["lights"][0] = json!({"type": "spot",
                    "intensity": 1.0, "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.3}});
            },
            error(&[f, "light 0", "lamp", "no direction"]),
        ),
        // --- animations ---
        gltf(
            "animation_count_mismatch",
            |d| d["accessors"][3]["count"] = json!(1),
            error(&[f, "animation 0", "channel 0"]),
        ),
        gltf_bin(
            "animation_times_decreasing",
            bin_with(TIMES + 4, -1.0),
            error(&[f, "animation 0", "channel 0"]),
        ),
        gltf_bin(
            "animation_times_equal",
            bin_with(TIMES + 4, 0.0),
            error(&[f, "animation 0", "channel 0"]),
        ),
        gltf_bin(
            "animation_time_nan",
            bin_with(TIMES + 4, f32::NAN),
            error(&[f, "accessor 2", "not finite"]),
        ),
        // glTF asks for times ≥ 0; earlier ones are well defined and accepted.
        gltf_bin(
            "animation_time_negative",
            bin_with(TIMES, -5.0),
            Expect::Success,
        ),
        gltf_bin(
            "animation_value_nan",
            bin_with(52, f32::NAN),
            error(&[f, "accessor 3", "not finite"]),
        ),
        gltf(
            "animation_sampler_out_of_range",
            |d| d["animations"][0]["channels"][0]["sampler"] = json!(4),
            error(&[f, "animations[0].channels[0].sampler"]),
        ),
        gltf(
            "animation_target_node_out_of_range",
            |d| d["animations"][0]["channels"][0]["target"]["node"] = json!(40),
            error(&[f, "animation 0", "node 40", "does not exist"]),
        ),
        gltf(
            "animation_interpolation_unknown",
            |d| d["animations"][0]["samplers"][0]["interpolation"] = json!("SMOOTH"),
            error(&[f, "interpolation"]),
        ),
        gltf(
            "animation_cubic_spline_count",
            |d| d["animations"][0]["samplers"][0]["interpolation"] = json!("CUBICSPLINE"),
            error(&[f, "animation 0", "channel 0"]),
        ),
        gltf(
            "animation_input_vec3",
            |d| d["animations"][0]["samplers"][0]["input"] = json!(3),
            error(&[f, "animation 0", "SCALAR"]),
        ),
        gltf(
            "animation_rotation_output_vec3",
            |d| d["animations"][0]["channels"][0]["target"]["path"] = json!("rotation"),
            error(&[f, "animation 0", "components"]),
        ),
        gltf(
            "animation_path_unknown",
            |d| d["animations"][0]["channels"][0]["target"]["path"] = json!("colour"),
            error(&[f, "path"]),
        ),
        gltf(
            "animation_input_accessor_out_of_range",
            |d| d["animations"][0]["samplers"][0]["input"] = json!(77),
            error(&[f, "animations[0].samplers[0].input"]),
        ),
        gltf(
            "animation_pointer_to_missing_light",
            |d| {
                d["extensionsUsed"] = json!(["KHR_lights_punctual", "KHR_animation_pointer"]);
                d["animations"][0]["channels"][0] = json!({"sampler": 0, "target": {"path": "pointer",
                    "extensions": {"KHR_animation_pointer":
                        {"pointer": "/extensions/KHR_lights_punctual/lights/9/intensity"}}}});
                d["accessors"][3]["type"] = json!("SCALAR");
            },
            error(&[f, "animation 0", "light"]),
        ),
        gltf(
            "animation_pointer_unsupported",
            |d| {
                d["extensionsUsed"] = json!(["KHR_lights_punctual", "KHR_animation_pointer"]);
                d["animations"][0]["channels"][0] = json!({"sampler": 0, "target": {"path": "pointer",
                    "extensions": {"KHR_animation_pointer": {"pointer": "/cameras/0/perspective/yfov"}}}});
            },
            warning(&[f, "animation 0", "pointer"]),
        ),
        gltf(
            "animation_pointer_garbage",
            |d| {
                d["animations"][0]["channels"][0] =
                    json!({"sampler": "x", "target": {"path": "pointer"}});
            },
            warning(&[f, "animation 0", "pointer"]),
        ),
        // --- issue 38: values that rendered wrong without a word ---
        gltf(
            "texture_transform_offset_1e38",
            |d| {
                d["extensionsUsed"] = json!(["KHR_lights_punctual", "KHR_texture_transform"]);
                d["images"] = json!([{"uri": "missing.png"}]);
                d["textures"] = json!([{"source": 0}]);
                d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0,
                    "extensions": {"KHR_texture_transform": {"offset": [1e38, 0.0]}}});
            },
            error(&[f, "material 0", "KHR_texture_transform offset", "1e38"]),
        ),
        gltf(
            "texture_transform_scale_1e20",
            |d| {
                d["extensionsUsed"] = json!(["KHR_lights_punctual", "KHR_texture_transform"]);
                d["images"] = json!([{"uri": "missing.png"}]);
                d["textures"] = json!([{"source": 0}]);
                d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] = json!({"index": 0,
                    "extensions": {"KHR_texture_transform": {"scale": [1.0, -1e20]}}});
            },
            error(&[f, "material 0", "KHR_texture_transform scale"]),
        ),
        gltf(
            "texture_index_2_pow_32",
            |d| {
                d["images"] = json!([{"uri": "missing.png"}]);
                d["textures"] = json!([{"source": 0}]);
                d["materials"][0]["pbrMetallicRoughness"]["baseColorTexture"] =
                    json!({"index": 4_294_967_296u64});
            },
            error(&[f, "baseColorTexture.index", "4294967296"]),
        ),
        gltf(
            "mesh_index_2_pow_32_plus_1",
            |d| d["nodes"][0]["mesh"] = json!(4_294_967_297u64),
            error(&[f, "nodes[0].mesh", "4294967297"]),
        ),
        gltf(
            "animated_metallic_2",
            |d| {
                animate_scalar(
                    d,
                    "/materials/0/pbrMetallicRoughness/metallicFactor",
                    TWO_TWO,
                )
            },
            error(&[f, "animation 0", "metallicFactor 2", "[0, 1]"]),
        ),
        gltf(
            "animated_light_intensity_negative",
            |d| {
                animate_scalar(
                    d,
                    "/extensions/KHR_lights_punctual/lights/0/intensity",
                    MINUS_ONES,
                )
            },
            error(&[f, "animation 0", "light intensity -1", "≥ 0"]),
        ),
        gltf(
            "animated_roughness_valid",
            |d| {
                animate_scalar(
                    d,
                    "/materials/0/pbrMetallicRoughness/roughnessFactor",
                    HALVES,
                )
            },
            Expect::Success,
        ),
        // --- long names are cut in messages ---
        gltf(
            "huge_node_name_in_an_error",
            |d| {
                d["nodes"][0]["name"] = json!("n".repeat(1 << 20));
                d["nodes"][0]["translation"] = json!([1e39, 0.0, 0.0]);
            },
            error(&[f, "node 0", "not finite"]),
        ),
        gltf(
            "huge_material_name_in_a_warning",
            |d| {
                d["materials"][0]["name"] = json!("m".repeat(1 << 20));
                d["materials"][0]["alphaMode"] = json!("BLEND");
            },
            warning(&[f, "material 0", "BLEND"]),
        ),
    ];
    // --- GLB containers ---
    let g = "x.glb";
    c.extend([
        glb_case("valid", |_| {}, Expect::Success),
        glb_case(
            "bad_magic",
            |b| b[0..4].copy_from_slice(b"glTX"),
            error(&[g]),
        ),
        glb_case(
            "version_1",
            |b| set_u32(b, 4, 1),
            error(&[g, "GLB header", "version 1"]),
        ),
        glb_case(
            "length_beyond_file",
            |b| set_u32(b, 8, 1_000_000),
            error(&[g, "GLB header", "truncated"]),
        ),
        glb_case(
            "length_too_small",
            |b| set_u32(b, 8, 12),
            error(&[g, "GLB header"]),
        ),
        glb_case(
            "header_only",
            |b| b.truncate(8),
            error(&[g, "GLB header", "truncated"]),
        ),
        glb_case(
            "json_chunk_length_beyond_file",
            |b| set_u32(b, 12, 1_000_000),
            error(&[g, "GLB"]),
        ),
        glb_case(
            "json_chunk_length_u32_max",
            |b| set_u32(b, 12, u32::MAX),
            error(&[g, "GLB"]),
        ),
        glb_case(
            "json_chunk_type_wrong",
            |b| b[16..20].copy_from_slice(b"JSOX"),
            error(&[g, "GLB"]),
        ),
        glb_case(
            "bin_chunk_length_beyond_file",
            |b| {
                let json_len = u32::from_le_bytes([b[12], b[13], b[14], b[15]]) as usize;
                set_u32(b, 20 + json_len, 1_000_000);
            },
            error(&[g, "GLB"]),
        ),
        glb_case(
            "truncated_bin_chunk",
            |b| {
                let n = b.len() - 40;
                b.truncate(n);
                set_u32(b, 8, n as u32);
            },
            error(&[g, "GLB"]),
        ),
        glb_case(
            "truncated_json_chunk",
            |b| {
                b.truncate(60);
                set_u32(b, 8, 60);
            },
            error(&[g, "GLB"]),
        ),
        Case::new("glb", "no_bin_chunk")
            .file(
                "x.glb",
                glb(
                    &edited(|d| d["buffers"][0] = json!({"byteLength": BIN_LEN})),
                    None,
                ),
            )
            .scene("x.glb", error(&[g, "buffer 0"])),
        Case::new("glb", "json_chunk_not_json")
            .file("x.glb", glb(b"\xff\xfe binary junk \x00\x01", Some(&bin())))
            .scene("x.glb", error(&[g, "GLB"])),
        Case::new("glb", "bin_chunk_shorter_than_buffer")
            .file(
                "x.glb",
                glb(
                    &edited(|d| d["buffers"][0] = json!({"byteLength": BIN_LEN})),
                    Some(&bin()[..20]),
                ),
            )
            .scene("x.glb", error(&[g, "buffer 0"])),
    ]);
    c
}
